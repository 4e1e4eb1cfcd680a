// The specular term engines that read glTF shade with (three.js, Filament, Godot, Unity and Unreal's
// GGX paths): GGX NDF, height-correlated Smith visibility and the cosine, for a unit light and F = 1.
// Header-only and branch-free (selects, no early returns), so evaluate's and the fitted lobe's loops
// over many normals vectorise; every input, NaN included, gives a finite value >= 0.
#pragma once

#include <burnish/core/util/numeric.h>

#include <algorithm>
#include <cmath>

namespace burnish {

/// α as ggxSpecularTerm takes it: clamped to [kMinRoughness, 1] (the roughness of kMaxPower up to the
/// roughest a roughness texture stores), NaN to kMinRoughness.
template <class T> inline T ggxSpecularAlpha(T alpha) {
    const T aMin = T(kMinRoughness);
    return alpha > aMin ? std::min(alpha, T(1)) : aMin; // NaN → aMin, the sharpest
}

/// ggxSpecularTerm (below) for an α already clamped by ggxSpecularAlpha: for loops whose α is the same for
/// every element, which clamp it once outside (GCC does not vectorise a loop that clamps an invariant
/// inside).
template <class T> inline T ggxSpecularTermClamped(T NoH, T NoL, T NoV, T a) {
    const T a2 = a * a;
    // Selects that send NaN to the clamp's low end, so no NaN reaches the value.
    const T c = NoH > T(0) ? std::min(NoH, T(1)) : T(0);
    // ggxNdf's d = sin² + c²α², exact near c = 1.
    const T d = (T(1) - c) * (T(1) + c) + c * c * a2;
    const T D = a2 / (kPi<T> * d * d);
    const T l = NoL > T(kMinCosine) ? std::min(NoL, T(1)) : T(kMinCosine);
    const T v = NoV > T(kMinCosine) ? std::min(NoV, T(1)) : T(kMinCosine);
    const T gv = l * std::sqrt(v * v * (T(1) - a2) + a2);
    const T gl = v * std::sqrt(l * l * (T(1) - a2) + a2);
    const T value = D * (T(0.5) / (gv + gl)) * l;
    return ((NoH > T(0)) & (NoL > T(0))) ? value : T(0); // & not &&: no branch, so loops vectorise
}

/// D_GGX(n·h; α) · V_SmithGGXCorrelated(n·l, n·v; α)/4 · max(0, n·l): ggxNdf times
/// visibilitySmithGgxCorrelated/4 times the clamped cosine, α clamped to [kMinRoughness, 1]. 0 where
/// n·h <= 0 or n·l <= 0; n·v is clamped to [kMinCosine, 1] as the engines clamp it, so a normal facing
/// away from the viewer still reflects the light it faces.
// Khronos, glTF 2.0 specification, Appendix B.3.2: f_specular = F·D·V, V = G/(4|n·l||n·v|), Heitz 2014's
// height-correlated G
template <class T> inline T ggxSpecularTerm(T NoH, T NoL, T NoV, T alpha) {
    return ggxSpecularTermClamped(NoH, NoL, NoV, ggxSpecularAlpha(alpha));
}

} // namespace burnish
