// Diffuse anti-aliasing (cone of normals) and Kaplanyan–Valient cone-angle specular AA.
#pragma once

#include <burnish/core/util/numeric.h>

namespace burnish {

/// Cosine of the half-angle of the uniform cone of normals whose mean has length lenNa.
// Baker & Hill 2012, "Rock-Solid Shading": cos θ = 2|Na| − 1
template <class T> inline T coneCosFromNormalLength(T lenNa) {
    return T(2) * saturate(lenNa) - T(1);
}

/// Exact mean of max(0, n_i·l) over normals n_i uniform in the cone of half-angle acos(cosCone)
/// around an axis with axis·l = cosAlpha. This is the integral the diffuse-AA LUT and curve
/// approximate. Integrated in closed form over azimuth and by adaptive Gauss–Kronrod over the
/// polar angle; accurate to ~1e-9. cosCone = 1 gives saturate(cosAlpha).
// Baker & Hill 2012: ∫∫ max(UniformSampleCone(u, v, cos θ)·L, 0)
double diffuseConeIntegral(double cosAlpha, double cosCone);

/// Constants of the diffuse-AA curve fit.
// Baker & Hill 2012: x0 = 0.373837·a, x1 = 0.66874·x
inline constexpr double kDiffuseAaC0 = 0.373837;
inline constexpr double kDiffuseAaC1 = 0.66874;
/// |Na| below this is treated as this: the curve covers cones up to acos(2·0.95−1) ≈ 25.8°.
inline constexpr double kDiffuseAaMinLength = 0.95;

/// The LUT-free diffuse-AA curve, with the operator precedence of the published listing fixed
/// (it reads `w * (cond) ? a : b`, which multiplies the condition). cosAlpha = n̂a·l with the
/// renormalized mean normal, lenNa = |Na|. Returns the approximate mean of max(0, n_i·l); far
/// from the terminator it is |Na|·cosAlpha, the exact value there.
// Baker & Hill 2012: w = max(|Na|, 0.95); x = sqrt(1−w); n = c0·a + c1·x;
//                    w·(|c0·a| <= c1·x ? n²/x : saturate(a))
template <class T>
inline T diffuseAaCurve(T cosAlpha, T lenNa, T c0 = T(kDiffuseAaC0), T c1 = T(kDiffuseAaC1)) {
    const T w = std::max(std::min(lenNa, T(1)), T(kDiffuseAaMinLength));
    const T x = std::sqrt(T(1) - w);
    const T x0 = c0 * cosAlpha;
    const T x1 = c1 * x;
    const T n = x0 + x1;
    // x == 0 (a flat footprint) makes the tail zero-width: the condition is only true at a == 0,
    // where the limit is saturate(0) = 0; take the branch that cannot divide by zero.
    if (x > T(0) && std::abs(x0) <= x1) return w * (n * n / x);
    return w * saturate(cosAlpha);
}

/// Kaplanyan–Valient constants relating Blinn-Phong power to a highlight cone angle.
// Baker & Hill 2012 (method of Kaplanyan & Valient): angle = 4.11893/sqrt(power); power = 16.9656/angle²
inline constexpr double kKvAngleConstant = 4.11893;
inline constexpr double kKvPowerConstant = 16.9656;

/// Cone "angle" (in the curvature units of the published code) of the highlight of power n.
template <class T> inline T kvConeAngleFromPower(T n, T k = T(kKvAngleConstant)) {
    return k / std::sqrt(std::max(clampPower(n), T(kMinVariance)));
}

/// Power whose highlight cone has the given angle, clamped to [0, kMaxPower].
template <class T> inline T kvPowerFromConeAngle(T angle, T k2 = T(kKvPowerConstant)) {
    const T a2 = angle * angle;
    return a2 > T(0) ? clampPower(k2 / a2) : T(kMaxPower);
}

/// Power widened by a geometric curvature term (the optimised listing's sqrt(1 − n·n')).
// Baker & Hill 2012: angle = 4.11893/sqrt(power) + curvature; power = 16.9656/(angle²)
template <class T> inline T kvCurvatureAdjustedPower(T n, T curvature) {
    return kvPowerFromConeAngle(kvConeAngleFromPower(n) + std::max(curvature, T(0)));
}

} // namespace burnish
