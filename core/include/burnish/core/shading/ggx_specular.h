// The specular term engines that read glTF shade with (three.js, Filament, Godot, Unity and Unreal's
// GGX paths): GGX NDF, height-correlated Smith visibility and the cosine, for a unit light and F = 1.
// Header-only and branch-free (selects, no early returns), so evaluate's and the fitted lobe's loops
// over many normals vectorise; every input, NaN included, gives a finite value >= 0.
#pragma once

#include <burnish/core/util/numeric.h>

#include <algorithm>
#include <cmath>
#include <limits>

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

/// The anisotropic GGX term of KHR_materials_anisotropy (three.js's MeshPhysicalMaterial, the glTF sample
/// viewer): D_GGX,aniso · V_SmithGGXCorrelated,aniso · max(0, n·l), Fresnel 1, with α_t along the
/// tangent-plane direction t and α_b along b (each clamped as ggxSpecularAlpha), and the dot products of
/// h, l, v with (t, b, n) as the engine computes them (t and b in the geometric tangent plane, n the
/// shading normal: the frame need not be orthonormal). α_t = α_b with an orthonormal frame is
/// ggxSpecularTerm. Branch-free; 0 where n·h <= 0 or n·l <= 0, n·v clamped to [kMinCosine, 1].
// Khronos, KHR_materials_anisotropy: D = 1/(π α_t α_b ((t·h/α_t)² + (b·h/α_b)² + (n·h)²)²),
// V = 1/(2 (n·l |(α_t t·v, α_b b·v, n·v)| + n·v |(α_t t·l, α_b b·l, n·l)|))
template <class T>
inline T ggxAnisotropicSpecularTerm(T NoH, T ToH, T BoH, T NoL, T ToL, T BoL, T NoV, T ToV, T BoV, T alphaT,
                                    T alphaB) {
    const T at = ggxSpecularAlpha(alphaT), ab = ggxSpecularAlpha(alphaB);
    const T a2 = at * ab;
    const T c = NoH > T(0) ? std::min(NoH, T(1)) : T(0);
    // D = a2·w²/π with w = a2/|(α_b t·h, α_t b·h, a2 n·h)|²: a sum of squares, no cancellation near n·h = 1.
    const T x = ab * ToH, y = at * BoH, z = a2 * c;
    const T q = x * x + y * y + z * z;
    const T w = a2 / std::max(q, std::numeric_limits<T>::min());
    const T D = a2 * w * w / kPi<T>;
    const T l = NoL > T(kMinCosine) ? std::min(NoL, T(1)) : T(kMinCosine);
    const T v = NoV > T(kMinCosine) ? std::min(NoV, T(1)) : T(kMinCosine);
    const T gv = l * std::sqrt(at * at * ToV * ToV + ab * ab * BoV * BoV + v * v);
    const T gl = v * std::sqrt(at * at * ToL * ToL + ab * ab * BoL * BoL + l * l);
    const T value = D * (T(0.5) / (gv + gl)) * l;
    const bool finite = value < std::numeric_limits<T>::infinity(); // NaN (from NaN dot products) fails too
    return ((NoH > T(0)) & (NoL > T(0)) & finite) ? value : T(0);
}

} // namespace burnish
