// Normal distribution functions, lobe and BRDF normalization factors, and the bridges between
// Blinn-Phong powers and microfacet roughness. Header-only: the same inline code is the
// double-precision reference and the float kernel the approximation report times.
//
// Conventions: NoH = n·h, the cosine between the (macro or micro) normal and the half vector.
// Powers n are clamped to [0, kMaxPower]; cosines outside [0, 1] give a zero lobe. No function
// here returns NaN or Inf for any input, including NaN powers (treated as 0).
#pragma once

#include <burnish/core/util/numeric.h>

#include <string_view>

namespace burnish {

// ---------------------------------------------------------------------------------------------
// Normalization factors (each makes a stated integral equal to 1 when l = n).

/// Blinn-Phong NDF normalization: ∫ D(h)(n·h) dω_h = 1 over the hemisphere.
// Lazarov 2011, "Physically Based Lighting in Call of Duty: Black Ops": D_P = (n+2)/(2π) (n·h)^n
template <class T> inline T blinnPhongNdfNorm(T n) {
    return (clampPower(n) + T(2)) / (T(2) * kPi<T>);
}

/// Phong lobe (r·v)^n normalization: ∫ K (r·v)^n dω_o = 1 with l = n.
// Lagarde 2011, "Adopting a physically based shading model": (n+1)/(2π)
template <class T> inline T phongLobeNorm(T n) {
    return (clampPower(n) + T(1)) / (T(2) * kPi<T>);
}

/// Phong BRDF (r·v)^n (n·l) normalization: ∫ K (r·v)^n cosθ_o dω_o = 1 with l = n.
// Lagarde 2011, "Adopting a physically based shading model": (n+2)/(2π)
template <class T> inline T phongBrdfNorm(T n) {
    return (clampPower(n) + T(2)) / (T(2) * kPi<T>);
}

/// Blinn-Phong lobe (n·h)^n normalization: ∫ K (n·h)^n dω_o = 1 with l = n.
// Lagarde 2011, "Adopting a physically based shading model": (n+2)/(4π(2−2^(−n/2)))
template <class T> inline T blinnPhongLobeNorm(T n) {
    n = clampPower(n);
    return (n + T(2)) / (T(4) * kPi<T> * (T(2) - std::exp2(-n / T(2))));
}

/// Blinn-Phong BRDF (n·h)^n (n·l) normalization: ∫ K (n·h)^n cosθ_o dω_o = 1 with l = n.
// Lagarde 2011, "Adopting a physically based shading model": (n+2)(n+4)/(8π(2^(−n/2)+n))
template <class T> inline T blinnPhongBrdfNorm(T n) {
    n = clampPower(n);
    // Split so the product never overflows float at n = kMaxPower.
    return ((n + T(2)) / (T(8) * kPi<T>)) * ((n + T(4)) / (std::exp2(-n / T(2)) + n));
}

/// The cheap approximation of blinnPhongBrdfNorm.
// Akenine-Möller, Haines, Hoffman, "Real-Time Rendering" 3rd ed., via Lagarde 2011: (n+8)/(8π)
template <class T> inline T blinnPhongBrdfNormApprox(T n) {
    return (clampPower(n) + T(8)) / (T(8) * kPi<T>);
}

// ---------------------------------------------------------------------------------------------
// NDFs. Each integrates to 1 in projected solid angle: ∫ D(h)(n·h) dω_h = 1.

/// Normalized Blinn-Phong NDF.
// Lazarov 2011: D_P(h) = (n+2)/(2π) (n·h)^n
template <class T> inline T blinnPhongNdf(T NoH, T n) {
    return blinnPhongNdfNorm(n) * powCos(NoH, n);
}

/// Beckmann NDF with RMS slope m (m clamped to at least sqrt(2/(kMaxPower+2))).
// Lazarov 2011 (after Beckmann 1963): D_B(h) = exp(((n·h)²−1)/(m²(n·h)²)) / (π m² (n·h)⁴)
template <class T> inline T beckmannNdf(T NoH, T m) {
    const T mMin = T(kMinRoughness);
    m = (m > mMin) ? m : mMin;
    if (!(NoH > T(0))) return T(0);
    // kMinCosine (numeric.h) in the divisions: below it m²c² and c⁴ underflow float to 0 and logD
    // became −inf + inf = NaN; D there is exp(−1/(m²c²))-small for every m a power maps to.
    NoH = std::clamp(NoH, T(kMinCosine), T(1));
    const T c2 = NoH * NoH;
    const T m2 = m * m;
    // Evaluated as one exponential so the 0·∞ of exp(-∞)/c⁴ at grazing NoH never happens.
    const T logD = (c2 - T(1)) / (m2 * c2) - std::log(kPi<T> * m2 * c2 * c2);
    return std::exp(std::min(logD, T(80)));
}

/// GGX / Trowbridge-Reitz NDF with alpha (alpha clamped like Beckmann's m).
// Walter et al. 2007, "Microfacet Models for Refraction": D = α² / (π((n·h)²(α²−1)+1)²)
template <class T> inline T ggxNdf(T NoH, T alpha) {
    const T aMin = T(kMinRoughness);
    // Upper bound 1/aMin ≈ 2.2e4: a flatter lobe than any power describes, and it keeps α² and d² finite
    // in float (α = +inf would give inf/inf).
    alpha = (alpha > aMin) ? std::min(alpha, T(1) / aMin) : aMin;
    if (!(NoH > T(0))) return T(0);
    NoH = std::min(NoH, T(1));
    const T a2 = alpha * alpha;
    // (n·h)²(α²−1)+1 written as 1−c²+c²α² = sin²+c²α², which stays > 0 and exact near c = 1.
    const T s2 = (T(1) - NoH) * (T(1) + NoH);
    const T d = s2 + NoH * NoH * a2;
    return a2 / (kPi<T> * d * d);
}

/// Lambert diffuse BRDF for unit albedo.
// Lagarde 2012, "PI or not to PI in game lighting equation": f = c_diff/π
template <class T> inline T lambertBrdf() {
    return kInvPi<T>;
}

/// Radiance reflected from a punctual light in "game light units": the light colour is what a white
/// Lambert surface facing the light shows, so the π of the Lambert BRDF cancels.
// Lagarde 2012, "PI or not to PI": L_o = π f(l, v) c_light (n·l)
template <class T> inline T punctualRadiance(T brdf, T lightColor, T NoL) {
    return kPi<T> * brdf * lightColor * saturate(NoL);
}

// ---------------------------------------------------------------------------------------------
// Bridges between Blinn-Phong power and microfacet roughness.

/// Beckmann RMS slope matching Blinn-Phong power n.
// Lazarov 2011: m = sqrt(2/(n+2))
template <class T> inline T beckmannRoughnessFromPower(T n) {
    return std::sqrt(T(2) / (clampPower(n) + T(2)));
}

/// Inverse of beckmannRoughnessFromPower: n = 2/m² − 2, clamped to [0, kMaxPower].
template <class T> inline T powerFromBeckmannRoughness(T m) {
    const T m2 = m * m;
    return m2 > T(0) ? clampPower(T(2) / m2 - T(2)) : T(kMaxPower);
}

/// GGX alpha matching Blinn-Phong power n (the usual bridge α² = 2/(n+2), the same as Beckmann's m).
// Walter et al. 2007; Karis 2013 ("Real Shading in Unreal Engine 4", α = roughness²)
template <class T> inline T ggxAlphaFromPower(T n) {
    return beckmannRoughnessFromPower(n);
}

/// Inverse of ggxAlphaFromPower.
template <class T> inline T powerFromGgxAlpha(T alpha) {
    return powerFromBeckmannRoughness(alpha);
}

// ---------------------------------------------------------------------------------------------
// The term as a choice (render's feature set, the command line, evaluate and fit name it).

/// The NDF term a shader evaluates (the functions above).
enum class NdfTerm { BlinnPhong, Beckmann, Ggx };
/// The term's name on the command line, in projects and in reports.
inline std::string_view ndfTermName(NdfTerm term) {
    switch (term) {
    case NdfTerm::BlinnPhong:
        return "blinn-phong";
    case NdfTerm::Beckmann:
        return "beckmann";
    case NdfTerm::Ggx:
        return "ggx";
    }
    return "blinn-phong";
}

} // namespace burnish
