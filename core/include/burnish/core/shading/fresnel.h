// Fresnel terms: Schlick in microfacet form, the glossy environment form, spherical-Gaussian
// approximations of (1−x)^5, and the exact dielectric Fresnel they approximate.
// c is the specular colour F0 (one channel, linear), x a cosine; x is clamped to [0, 1].
#pragma once

#include <burnish/core/util/numeric.h>

#include <string_view>

namespace burnish {

/// Schlick's Fresnel; in microfacet form x = h·l (or h·v), which needs no clamp for highlights.
// Lazarov 2011 (after Schlick 1994): F = c + (1−c)(1−x)^5
template <class T> inline T fresnelSchlick(T c, T x) {
    const T m = T(1) - saturate(x);
    const T m2 = m * m;
    return c + (T(1) - c) * (m2 * m2 * m);
}

/// Schlick's Fresnel with a general exponent p (p = 5 is Schlick's; 7 and others for the fitter).
template <class T> inline T fresnelSchlickPow(T c, T x, T p) {
    return c + (T(1) - c) * powUnit(T(1) - saturate(x), p);
}

/// The "Fresnel" for prefiltered environment maps: a fit to the hemispherical integral of the
/// whole specular BRDF; x = n·v and g the gloss in [0, 1].
// Lazarov 2011: F_glossy = c + (1−c)(1−x)^5 / (4−3g)
template <class T> inline T fresnelGlossy(T c, T x, T g) {
    const T m = T(1) - saturate(x);
    const T m2 = m * m;
    return c + (T(1) - c) * (m2 * m2 * m) / (T(4) - T(3) * saturate(g));
}

/// Single-term spherical-Gaussian Schlick: (1−x)^5 ≈ exp2(−k·x).
// Lagarde 2012, "Spherical Gaussian approximation for Blinn-Phong, Phong and Fresnel":
// k = (5 + 0.788)/ln 2 ≈ 8.35
inline constexpr double kFresnelSgK = 8.35;
template <class T> inline T fresnelSchlickSg(T c, T x, T k = T(kFresnelSgK)) {
    return c + (T(1) - c) * std::exp2(-k * saturate(x));
}

/// Quadratic-exponent spherical-Gaussian Schlick: (1−x)^5 ≈ exp2((a·x + b)·x).
// Lagarde 2012: a = −5.55473, b = −6.98316
inline constexpr double kFresnelSgQuadA = -5.55473;
inline constexpr double kFresnelSgQuadB = -6.98316;
template <class T>
inline T fresnelSchlickSgQuadratic(T c, T x, T a = T(kFresnelSgQuadA), T b = T(kFresnelSgQuadB)) {
    x = saturate(x);
    return c + (T(1) - c) * std::exp2((a * x + b) * x);
}

/// Refractive index of a dielectric (from air) whose normal-incidence reflectance is F0 in [0, 1).
// From F0 = ((η−1)/(η+1))²: η = (1+√F0)/(1−√F0)
template <class T> inline T iorFromF0(T F0) {
    const T s = std::sqrt(std::clamp(F0, T(0), T(0.999999)));
    return (T(1) + s) / (T(1) - s);
}

/// Exact unpolarized Fresnel reflectance of a dielectric interface (from air), for the F0 that
/// Schlick's form is parameterized by; x = cosine of the incidence angle.
// Born & Wolf, "Principles of Optics", §1.5 (Fresnel equations, mean of s and p)
template <class T> inline T fresnelDielectric(T F0, T x) {
    const T eta = iorFromF0(F0);
    const T ci = saturate(x);
    const T si2 = T(1) - ci * ci;
    const T ct = std::sqrt(std::max(T(0), T(1) - si2 / (eta * eta)));
    const T rs = (ci - eta * ct) / (ci + eta * ct);
    const T rp = (eta * ci - ct) / (eta * ci + ct);
    // ci = ct = 0 is impossible for eta >= 1 (ct >= sqrt(1 - 1/eta²) > 0 unless eta == 1, where
    // both numerators vanish too); guard the eta == 1 case to keep 0/0 out.
    if (!(ci + eta * ct > T(0))) return T(1);
    return saturate(T(0.5) * (rs * rs + rp * rp));
}

// ---------------------------------------------------------------------------------------------
// The term as a choice (render's feature set, the command line, evaluate and fit name it).

/// The Fresnel term a shader evaluates (the functions above); None uses F0 unchanged.
enum class FresnelTerm { None, Schlick, SchlickSg, SchlickSgQuadratic };
/// The term's name on the command line, in projects and in reports.
inline std::string_view fresnelTermName(FresnelTerm term) {
    switch (term) {
    case FresnelTerm::None:
        return "none";
    case FresnelTerm::Schlick:
        return "schlick";
    case FresnelTerm::SchlickSg:
        return "schlick-sg";
    case FresnelTerm::SchlickSgQuadratic:
        return "schlick-sg-quadratic";
    }
    return "none";
}

} // namespace burnish
