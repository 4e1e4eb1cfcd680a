// Normal distribution functions, normalization factors and the power ↔ roughness bridges: the GLSL
// twin of core/include/burnish/core/shading/ndf.h. NoH = n·h; powers clamped to [0, kMaxPower]; cosines
// outside [0, 1] give a zero lobe; nothing here returns NaN or Inf.
#include "common_math.glsl"

// Smallest Beckmann m / GGX α: the roughness of kMaxPower under m² = 2/(n+2) (ndf.h).
const float kMinRoughness = sqrt(2.0 / (kMaxPower + 2.0));

// Lazarov 2011, "Physically Based Lighting in Call of Duty: Black Ops": D_P = (n+2)/(2π) (n·h)^n
float blinnPhongNdfNorm(float n) {
    return (clampPower(n) + 2.0) / (2.0 * kPi);
}

// Lagarde 2011, "Adopting a physically based shading model": (n+1)/(2π)
float phongLobeNorm(float n) {
    return (clampPower(n) + 1.0) / (2.0 * kPi);
}

// Lagarde 2011, "Adopting a physically based shading model": (n+2)/(2π)
float phongBrdfNorm(float n) {
    return (clampPower(n) + 2.0) / (2.0 * kPi);
}

// Lagarde 2011, "Adopting a physically based shading model": (n+2)/(4π(2−2^(−n/2)))
float blinnPhongLobeNorm(float n) {
    n = clampPower(n);
    return (n + 2.0) / (4.0 * kPi * (2.0 - exp2(-n / 2.0)));
}

// Lagarde 2011, "Adopting a physically based shading model": (n+2)(n+4)/(8π(2^(−n/2)+n))
float blinnPhongBrdfNorm(float n) {
    n = clampPower(n);
    // Split so the product never overflows float at n = kMaxPower.
    return ((n + 2.0) / (8.0 * kPi)) * ((n + 4.0) / (exp2(-n / 2.0) + n));
}

// Akenine-Möller, Haines, Hoffman, "Real-Time Rendering" 3rd ed., via Lagarde 2011: (n+8)/(8π)
float blinnPhongBrdfNormApprox(float n) {
    return (clampPower(n) + 8.0) / (8.0 * kPi);
}

// Lazarov 2011: D_P(h) = (n+2)/(2π) (n·h)^n
float blinnPhongNdf(float NoH, float n) {
    return blinnPhongNdfNorm(n) * powCos(NoH, n);
}

// Lazarov 2011 (after Beckmann 1963): D_B(h) = exp(((n·h)²−1)/(m²(n·h)²)) / (π m² (n·h)⁴)
float beckmannNdf(float NoH, float m) {
    m = (m > kMinRoughness) ? m : kMinRoughness;
    if (!(NoH > 0.0)) return 0.0;
    // kMinCosine in the divisions: below it m²c² and c⁴ underflow to 0 and logD became −inf + inf.
    NoH = clamp(NoH, kMinCosine, 1.0);
    float c2 = NoH * NoH;
    float m2 = m * m;
    // 1 − c² as (1−c)(1+c), the same value: float's c² − 1 keeps only ~3e-8 absolute, which 1/m²
    // (up to 5e8) would turn into an exponent error of ~15 at high powers.
    float s2 = (1.0 - NoH) * (1.0 + NoH);
    // One exponential, so the 0·∞ of exp(−∞)/c⁴ at grazing NoH never happens; 80 keeps exp finite.
    float logD = -s2 / (m2 * c2) - log(kPi * m2 * c2 * c2);
    return exp(min(logD, 80.0));
}

// Walter et al. 2007, "Microfacet Models for Refraction": D = α² / (π((n·h)²(α²−1)+1)²)
float ggxNdf(float NoH, float alpha) {
    // Upper bound 1/kMinRoughness ≈ 2.2e4 keeps α² and d² finite in float.
    alpha = (alpha > kMinRoughness) ? min(alpha, 1.0 / kMinRoughness) : kMinRoughness;
    if (!(NoH > 0.0)) return 0.0;
    NoH = min(NoH, 1.0);
    float a2 = alpha * alpha;
    // (n·h)²(α²−1)+1 written as sin²+c²α², which stays > 0 and exact near c = 1.
    float s2 = (1.0 - NoH) * (1.0 + NoH);
    float d = s2 + NoH * NoH * a2;
    return a2 / (kPi * d * d);
}

// Lagarde 2012, "PI or not to PI in game lighting equation": f = c_diff/π
float lambertBrdf() {
    return kInvPi;
}

// Lagarde 2012, "PI or not to PI": L_o = π f(l, v) c_light (n·l)
float punctualRadiance(float brdf, float lightColor, float NoL) {
    return kPi * brdf * lightColor * saturate(NoL);
}

// Lazarov 2011: m = sqrt(2/(n+2))
float beckmannRoughnessFromPower(float n) {
    return sqrt(2.0 / (clampPower(n) + 2.0));
}

// Inverse of beckmannRoughnessFromPower: n = 2/m² − 2, clamped to [0, kMaxPower]. Written as
// 2(1−m)(1+m)/m², the same value without float's cancellation of 2/m² − 2 near m = 1.
float powerFromBeckmannRoughness(float m) {
    float m2 = m * m;
    return m2 > 0.0 ? clampPower(2.0 * (1.0 - m) * (1.0 + m) / m2) : kMaxPower;
}

// Walter et al. 2007; Karis 2013 ("Real Shading in Unreal Engine 4", α = roughness²)
float ggxAlphaFromPower(float n) {
    return beckmannRoughnessFromPower(n);
}

float powerFromGgxAlpha(float alpha) {
    return powerFromBeckmannRoughness(alpha);
}
