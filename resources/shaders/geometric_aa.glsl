// Geometric anti-aliasing: the GLSL twin of the inline functions of
// core/include/burnish/core/shading/geometric_aa.h (diffuse cone of normals, Kaplanyan–Valient cone
// angles) and of core/include/burnish/core/shading/specular_aa.h (normal-based NDF filtering).
#include "common_math.glsl"
#include "brdf_ndf.glsl"

// Baker & Hill 2012, "Rock-Solid Shading": cos θ = 2|Na| − 1
float coneCosFromNormalLength(float lenNa) {
    return 2.0 * saturate(lenNa) - 1.0;
}

// Baker & Hill 2012: x0 = 0.373837·a, x1 = 0.66874·x
const float kDiffuseAaC0 = 0.373837;
const float kDiffuseAaC1 = 0.66874;
// |Na| below this is treated as this: the curve covers cones up to ≈ 25.8°.
const float kDiffuseAaMinLength = 0.95;

// Baker & Hill 2012: w = max(|Na|, 0.95); x = sqrt(1−w); n = c0·a + c1·x;
//                    w·(|c0·a| <= c1·x ? n²/x : saturate(a))   (the listing's precedence fixed)
float diffuseAaCurve(float cosAlpha, float lenNa, float c0, float c1) {
    float w = max(min(lenNa, 1.0), kDiffuseAaMinLength);
    float x = sqrt(1.0 - w);
    float x0 = c0 * cosAlpha;
    float x1 = c1 * x;
    float n = x0 + x1;
    // x == 0 (a flat footprint): take the branch that cannot divide by zero (its limit).
    if (x > 0.0 && abs(x0) <= x1) return w * (n * n / x);
    return w * saturate(cosAlpha);
}

float diffuseAaCurve(float cosAlpha, float lenNa) {
    return diffuseAaCurve(cosAlpha, lenNa, kDiffuseAaC0, kDiffuseAaC1);
}

// Baker & Hill 2012 (method of Kaplanyan & Valient): angle = 4.11893/sqrt(power); power = 16.9656/angle²
const float kKvAngleConstant = 4.11893;
const float kKvPowerConstant = 16.9656;

float kvConeAngleFromPower(float n, float k) {
    // kMinVariance keeps the square root away from 0 at n = 0 (angle ≈ 1.3e5, a flat lobe).
    return k / sqrt(max(clampPower(n), kMinVariance));
}

float kvConeAngleFromPower(float n) {
    return kvConeAngleFromPower(n, kKvAngleConstant);
}

float kvPowerFromConeAngle(float angle, float k2) {
    float a2 = angle * angle;
    return a2 > 0.0 ? clampPower(k2 / a2) : kMaxPower;
}

float kvPowerFromConeAngle(float angle) {
    return kvPowerFromConeAngle(angle, kKvPowerConstant);
}

// Baker & Hill 2012: angle = 4.11893/sqrt(power) + curvature; power = 16.9656/(angle²)
float kvCurvatureAdjustedPower(float n, float curvature) {
    return kvPowerFromConeAngle(kvConeAngleFromPower(n) + max(curvature, 0.0));
}

// Tokuyoshi & Kaplanyan 2019, "Improved Geometric Specular Antialiasing", §4: σ = 0.5 px, κ = 0.18
// (κ bounds the error of derivatives estimated on 2×2 quads).
const float kSpecularAaKernelVariance = 0.25;
const float kSpecularAaKappa = 0.18;

// Tokuyoshi & Kaplanyan 2019, Listing 2: kernelRoughness2 = min(2σ²(|dndu|² + |dndv|²), κ)
float specularAaKernelRoughness2(float dn2, float sigma2, float kappa) {
    float d2 = dn2 > 0.0 ? dn2 : 0.0; // NaN → no curvature
    float s2 = sigma2 > 0.0 ? sigma2 : 0.0;
    float k = kappa > 0.0 ? kappa : 0.0;
    return min(2.0 * s2 * d2, k);
}

float specularAaKernelRoughness2(float dn2) {
    return specularAaKernelRoughness2(dn2, kSpecularAaKernelVariance, kSpecularAaKappa);
}

float normalDerivative2(vec3 dndx, vec3 dndy) {
    return dot(dndx, dndx) + dot(dndy, dndy);
}

// Tokuyoshi & Kaplanyan 2019, eq. 1: ᾱ² = α² + min(2σ²(‖Δn_u‖² + ‖Δn_v‖²), κ), clamped to 1
float specularAaRoughness2(float alpha2, float dn2) {
    return saturate(saturate(alpha2) + specularAaKernelRoughness2(dn2));
}

float specularAaGgxAlpha(float alpha, vec3 dndx, vec3 dndy) {
    return sqrt(specularAaRoughness2(alpha * alpha, normalDerivative2(dndx, dndy)));
}

// Tokuyoshi & Kaplanyan 2019, §3: A = diag(α²) + 2Σ for the Beckmann NDF
float specularAaBeckmannM(float m, vec3 dndx, vec3 dndy) {
    return sqrt(specularAaRoughness2(m * m, normalDerivative2(dndx, dndy)));
}

float specularAaPower(float n, vec3 dndx, vec3 dndy) {
    float alpha2 = 2.0 / (clampPower(n) + 2.0);
    return powerFromGgxAlpha(sqrt(specularAaRoughness2(alpha2, normalDerivative2(dndx, dndy))));
}

// The same from the interpolated shading normal n itself, differentiated across the 2×2 quad.
float specularAaGgxAlpha(float alpha, vec3 n) {
    return specularAaGgxAlpha(alpha, dFdx(n), dFdy(n));
}

float specularAaBeckmannM(float m, vec3 n) {
    return specularAaBeckmannM(m, dFdx(n), dFdy(n));
}

float specularAaPower(float n, vec3 normal) {
    return specularAaPower(n, dFdx(normal), dFdy(normal));
}
