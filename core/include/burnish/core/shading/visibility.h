// Visibility terms in the factoring of Lazarov 2011: V = G(l,v,h) / ((n·l)(n·v)), so the
// microfacet specular BRDF is f = F · V · D / 4. Cosines are clamped to [kMinCosine, 1] where
// they divide, so V is finite at grazing angles; every function here is finite for all inputs.
#pragma once

#include <burnish/core/util/numeric.h>

#include <string_view>

namespace burnish {

/// No visibility term: G = (n·l)(n·v), V = 1.
// Lazarov 2011
template <class T> inline T visibilityNone() {
    return T(1);
}

/// Kelemen–Szirmay-Kalos approximation of the Cook–Torrance visibility.
// Lazarov 2011 (after Kelemen & Szirmay-Kalos 2001): V = 4/((v+l)·(v+l)) = 1/(v·h)²
template <class T> inline T visibilityKelemen(T VoH) {
    const T c = std::max(saturate(VoH), T(kMinCosine));
    return T(1) / (c * c);
}

/// The Schlick–Smith parameter for Blinn-Phong power n.
// Lazarov 2011: a = m sqrt(2/π) = 1/sqrt(πn/4 + π/2)
template <class T> inline T schlickSmithA(T n) {
    return T(1) / std::sqrt(kPi<T> / T(4) * clampPower(n) + kPi<T> / T(2));
}

/// Schlick's approximation of Smith's shadowing for a Blinn-Phong power n.
// Lazarov 2011: V = 1 / (((n·l)(1−a) + a)((n·v)(1−a) + a))
template <class T> inline T visibilitySchlickSmith(T NoL, T NoV, T n) {
    const T a = schlickSmithA(n);
    return T(1) / ((saturate(NoL) * (T(1) - a) + a) * (saturate(NoV) * (T(1) - a) + a));
}

/// Cook–Torrance geometric attenuation divided by (n·l)(n·v).
// Cook & Torrance 1982: G = min(1, 2(n·h)(n·v)/(v·h), 2(n·h)(n·l)/(v·h))
template <class T> inline T visibilityCookTorrance(T NoL, T NoV, T NoH, T VoH) {
    NoL = std::max(saturate(NoL), T(kMinCosine));
    NoV = std::max(saturate(NoV), T(kMinCosine));
    NoH = saturate(NoH);
    VoH = std::max(saturate(VoH), T(kMinCosine));
    const T G = std::min(T(1), std::min(T(2) * NoH * NoV / VoH, T(2) * NoH * NoL / VoH));
    return G / (NoL * NoV);
}

/// Exact Smith masking for the Beckmann NDF (one direction), the function Schlick–Smith fits.
// Walter et al. 2007, eq. 25 (as Smith G1 with a = cosθ/(m sinθ)): G1 = 2/(1 + erf(a) + exp(−a²)/(a√π))
template <class T> inline T smithBeckmannG1(T NoX, T m) {
    NoX = std::max(saturate(NoX), T(kMinCosine));
    m = m > T(1e-6) ? m : T(1e-6); // also NaN → 1e-6, the smoothest, as beckmannNdf does
    const T sinT = std::sqrt(std::max(T(0), T(1) - NoX * NoX));
    if (sinT <= T(0)) return T(1);
    const T a = NoX / (m * sinT);
    if (a > T(30)) return T(1); // erf(a) == 1 and exp(−a²) underflows: G1 is 1 to float precision
    return T(2) / (T(1) + std::erf(a) + std::exp(-a * a) / (a * std::sqrt(kPi<T>)));
}

/// Separable Smith visibility for Beckmann roughness m.
template <class T> inline T visibilitySmithBeckmann(T NoL, T NoV, T m) {
    const T l = std::max(saturate(NoL), T(kMinCosine));
    const T v = std::max(saturate(NoV), T(kMinCosine));
    return smithBeckmannG1(l, m) * smithBeckmannG1(v, m) / (l * v);
}

/// Height-correlated Smith visibility for GGX with alpha.
// Heitz 2014, "Understanding the Masking-Shadowing Function", eq. 99; Filament's V_SmithGGXCorrelated
// times 4 (Burnish's V excludes the 1/4 of the BRDF): V = 2/(n·l √((n·v)²(1−α²)+α²) + n·v √((n·l)²(1−α²)+α²))
template <class T> inline T visibilitySmithGgxCorrelated(T NoL, T NoV, T alpha) {
    NoL = std::max(saturate(NoL), T(kMinCosine));
    NoV = std::max(saturate(NoV), T(kMinCosine));
    // α² clamped to [0, 1]; NaN → 0 (the smoothest, as ggxNdf does) as saturate does).
    const T a2 = alpha * alpha > T(0) ? std::min(alpha * alpha, T(1)) : T(0);
    const T gv = NoL * std::sqrt(NoV * NoV * (T(1) - a2) + a2);
    const T gl = NoV * std::sqrt(NoL * NoL * (T(1) - a2) + a2);
    return T(2) / (gv + gl);
}

// ---------------------------------------------------------------------------------------------
// The term as a choice (render's feature set, the command line, evaluate and fit name it).

/// The visibility term a shader evaluates (the functions above).
enum class VisibilityTerm { None, Kelemen, SchlickSmith, CookTorrance, SmithBeckmann, SmithGgxCorrelated };
/// The term's name on the command line, in projects and in reports.
inline std::string_view visibilityTermName(VisibilityTerm term) {
    switch (term) {
    case VisibilityTerm::None:
        return "none";
    case VisibilityTerm::Kelemen:
        return "kelemen";
    case VisibilityTerm::SchlickSmith:
        return "schlick-smith";
    case VisibilityTerm::CookTorrance:
        return "cook-torrance";
    case VisibilityTerm::SmithBeckmann:
        return "smith-beckmann";
    case VisibilityTerm::SmithGgxCorrelated:
        return "smith-ggx-correlated";
    }
    return "none";
}

} // namespace burnish
