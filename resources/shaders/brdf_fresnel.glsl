// Fresnel terms: the GLSL twin of core/include/burnish/core/shading/fresnel.h, for one channel (float c)
// and for an RGB specular colour (vec3 c). c is F0 (linear), x a cosine clamped to [0, 1].
#include "common_math.glsl"

// Lagarde 2012, "Spherical Gaussian approximation for Blinn-Phong, Phong and Fresnel": k = 8.35
const float kFresnelSgK = 8.35;
// Lagarde 2012: a = −5.55473, b = −6.98316
const float kFresnelSgQuadA = -5.55473;
const float kFresnelSgQuadB = -6.98316;

// Lazarov 2011 (after Schlick 1994): F = c + (1−c)(1−x)^5
float fresnelSchlick(float c, float x) {
    float m = 1.0 - saturate(x);
    float m2 = m * m;
    return c + (1.0 - c) * (m2 * m2 * m);
}

vec3 fresnelSchlick(vec3 c, float x) {
    float m = 1.0 - saturate(x);
    float m2 = m * m;
    return c + (vec3(1.0) - c) * (m2 * m2 * m);
}

// Schlick with a general exponent p: F = c + (1−c)(1−x)^p
float fresnelSchlickPow(float c, float x, float p) {
    return c + (1.0 - c) * powUnit(1.0 - saturate(x), p);
}

vec3 fresnelSchlickPow(vec3 c, float x, float p) {
    return c + (vec3(1.0) - c) * powUnit(1.0 - saturate(x), p);
}

// Lazarov 2011: F_glossy = c + (1−c)(1−x)^5 / (4−3g)
float fresnelGlossy(float c, float x, float g) {
    float m = 1.0 - saturate(x);
    float m2 = m * m;
    return c + (1.0 - c) * (m2 * m2 * m) / (4.0 - 3.0 * saturate(g));
}

vec3 fresnelGlossy(vec3 c, float x, float g) {
    float m = 1.0 - saturate(x);
    float m2 = m * m;
    return c + (vec3(1.0) - c) * (m2 * m2 * m) / (4.0 - 3.0 * saturate(g));
}

// Lagarde 2012: (1−x)^5 ≈ exp2(−k·x)
float fresnelSchlickSg(float c, float x, float k) {
    return c + (1.0 - c) * exp2(-k * saturate(x));
}

float fresnelSchlickSg(float c, float x) {
    return fresnelSchlickSg(c, x, kFresnelSgK);
}

vec3 fresnelSchlickSg(vec3 c, float x, float k) {
    return c + (vec3(1.0) - c) * exp2(-k * saturate(x));
}

vec3 fresnelSchlickSg(vec3 c, float x) {
    return fresnelSchlickSg(c, x, kFresnelSgK);
}

// Lagarde 2012: (1−x)^5 ≈ exp2((a·x + b)·x)
float fresnelSchlickSgQuadratic(float c, float x, float a, float b) {
    x = saturate(x);
    return c + (1.0 - c) * exp2((a * x + b) * x);
}

float fresnelSchlickSgQuadratic(float c, float x) {
    return fresnelSchlickSgQuadratic(c, x, kFresnelSgQuadA, kFresnelSgQuadB);
}

vec3 fresnelSchlickSgQuadratic(vec3 c, float x, float a, float b) {
    x = saturate(x);
    return c + (vec3(1.0) - c) * exp2((a * x + b) * x);
}

vec3 fresnelSchlickSgQuadratic(vec3 c, float x) {
    return fresnelSchlickSgQuadratic(c, x, kFresnelSgQuadA, kFresnelSgQuadB);
}

// From F0 = ((η−1)/(η+1))²: η = (1+√F0)/(1−√F0), F0 clamped to [0, 0.999999] like core (η < 4e6).
// Float forms of the same values: η − 1 = 2(√F0 + F0)/(1 − F0), with 1 − F0 exact where 1 − √F0
// would lose its digits as F0 → 1 and η − 1 keeping its digits as F0 → 0. The upper clamp is
// applied to 1 − F0 (at least 1e-6): float has no 0.999999, and its nearest moves η there by 1.3%.
float iorMinusOneFromF0(float F0) {
    F0 = saturate(F0);
    float oneMinusF0 = max(1.0 - F0, 1e-6);
    float s = sqrt(min(F0, 1.0 - 1e-6));
    return 2.0 * (s + F0) / oneMinusF0;
}

float iorFromF0(float F0) {
    return 1.0 + iorMinusOneFromF0(F0);
}

vec3 iorFromF0(vec3 F0) {
    return vec3(iorFromF0(F0.x), iorFromF0(F0.y), iorFromF0(F0.z));
}

// Born & Wolf, "Principles of Optics", §1.5 (Fresnel equations, mean of s and p):
// rs = (cosθi − η cosθt)/(cosθi + η cosθt), rp = (η cosθi − cosθt)/(η cosθi + cosθt), with
// η cosθt = sqrt(η² − 1 + cos²θi). Both numerators are rewritten with η² − 1 = (η−1)(η+1) factored
// out, the same values without float's cancellation for F0 → 0 (η → 1):
// rs = −(η²−1)/(cosθi + η cosθt)², rp = (η²−1)((η²+1)cos²θi − 1)/(η² cosθi + η cosθt)².
float fresnelDielectric(float F0, float x) {
    float etaMinus1 = iorMinusOneFromF0(F0);
    float eta = 1.0 + etaMinus1;
    float eta2Minus1 = etaMinus1 * (eta + 1.0);
    float ci = saturate(x);
    float etaCt = sqrt(eta2Minus1 + ci * ci);
    // ci = η cosθt = 0 only for η == 1 (F0 = 0) at grazing incidence: keep the 0/0 out (core returns 1).
    if (!(ci + etaCt > 0.0)) return 1.0;
    float sumS = ci + etaCt;
    float rs = -eta2Minus1 / (sumS * sumS);
    float sumP = eta * eta * ci + etaCt;
    float rp = eta2Minus1 * ((eta * eta + 1.0) * ci * ci - 1.0) / (sumP * sumP);
    return saturate(0.5 * (rs * rs + rp * rp));
}

vec3 fresnelDielectric(vec3 F0, float x) {
    return vec3(fresnelDielectric(F0.x, x), fresnelDielectric(F0.y, x), fresnelDielectric(F0.z, x));
}
