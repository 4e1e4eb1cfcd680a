// Visibility terms V = G/((n·l)(n·v)), so the specular BRDF is F·V·D/4: the GLSL twin of
// core/include/burnish/core/shading/visibility.h. Dividing cosines are clamped to [kMinCosine, 1].
#include "common_math.glsl"
#include "brdf_ndf.glsl"

// Lazarov 2011
float visibilityNone() {
    return 1.0;
}

// Lazarov 2011 (after Kelemen & Szirmay-Kalos 2001): V = 4/((v+l)·(v+l)) = 1/(v·h)²
float visibilityKelemen(float VoH) {
    float c = max(saturate(VoH), kMinCosine);
    return 1.0 / (c * c);
}

// Lazarov 2011: a = m sqrt(2/π) = 1/sqrt(πn/4 + π/2)
float schlickSmithA(float n) {
    return 1.0 / sqrt(kPi / 4.0 * clampPower(n) + kPi / 2.0);
}

// Lazarov 2011: V = 1 / (((n·l)(1−a) + a)((n·v)(1−a) + a))
float visibilitySchlickSmith(float NoL, float NoV, float n) {
    float a = schlickSmithA(n);
    return 1.0 / ((saturate(NoL) * (1.0 - a) + a) * (saturate(NoV) * (1.0 - a) + a));
}

// Cook & Torrance 1982: G = min(1, 2(n·h)(n·v)/(v·h), 2(n·h)(n·l)/(v·h))
float visibilityCookTorrance(float NoL, float NoV, float NoH, float VoH) {
    NoL = max(saturate(NoL), kMinCosine);
    NoV = max(saturate(NoV), kMinCosine);
    NoH = saturate(NoH);
    VoH = max(saturate(VoH), kMinCosine);
    float G = min(1.0, min(2.0 * NoH * NoV / VoH, 2.0 * NoH * NoL / VoH));
    return G / (NoL * NoV);
}

// erf(x) for x >= 0 (GLSL has none), absolute error below 1.5e-7: smithBeckmannG1 adds it to
// 1 + exp(−a²)/(a√π) >= 1, so that is also its relative error there.
// Abramowitz & Stegun 1964, eq. 7.1.26
float erfNonNegative(float x) {
    float t = 1.0 / (1.0 + 0.3275911 * x);
    float poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    return 1.0 - poly * exp(-x * x);
}

// Walter et al. 2007, eq. 25 (as Smith G1 with a = cosθ/(m sinθ)): G1 = 2/(1 + erf(a) + exp(−a²)/(a√π))
float smithBeckmannG1(float NoX, float m) {
    NoX = max(saturate(NoX), kMinCosine);
    m = m > 1e-6 ? m : 1e-6; // also NaN → 1e-6, the smoothest, as core does
    float sinT = sqrt(max(0.0, 1.0 - NoX * NoX));
    if (sinT <= 0.0) return 1.0;
    float a = NoX / (m * sinT);
    if (a > 30.0) return 1.0; // erf(a) == 1 and exp(−a²) underflows: G1 is 1 to float precision
    return 2.0 / (1.0 + erfNonNegative(a) + exp(-a * a) / (a * sqrt(kPi)));
}

// Separable Smith visibility for Beckmann roughness m.
float visibilitySmithBeckmann(float NoL, float NoV, float m) {
    float l = max(saturate(NoL), kMinCosine);
    float v = max(saturate(NoV), kMinCosine);
    return smithBeckmannG1(l, m) * smithBeckmannG1(v, m) / (l * v);
}

// Heitz 2014, "Understanding the Masking-Shadowing Function", eq. 99 (times 4: V excludes the 1/4):
// V = 2/(n·l √((n·v)²(1−α²)+α²) + n·v √((n·l)²(1−α²)+α²))
float visibilitySmithGgxCorrelated(float NoL, float NoV, float alpha) {
    NoL = max(saturate(NoL), kMinCosine);
    NoV = max(saturate(NoV), kMinCosine);
    // α² clamped to [0, 1]; NaN → 0 (the smoothest, as ggxNdf does).
    float a2 = alpha * alpha > 0.0 ? min(alpha * alpha, 1.0) : 0.0;
    float gv = NoL * sqrt(NoV * NoV * (1.0 - a2) + a2);
    float gl = NoV * sqrt(NoL * NoL * (1.0 - a2) + a2);
    return 2.0 / (gv + gl);
}

// Twin of core/include/burnish/core/shading/ggx_specular.h: α clamped to [kMinRoughness, 1], NaN to
// kMinRoughness.
float ggxSpecularAlpha(float alpha) {
    return alpha > kMinRoughness ? min(alpha, 1.0) : kMinRoughness;
}

// The specular term glTF engines shade with, unit light, F = 1: D_GGX · V_SmithGGXCorrelated/4 · max(0, n·l).
// Khronos, glTF 2.0 specification, Appendix B.3.2: f_specular = F·D·V, V = G/(4|n·l||n·v|)
float ggxSpecularTerm(float NoH, float NoL, float NoV, float alpha) {
    float a = ggxSpecularAlpha(alpha);
    float a2 = a * a;
    float c = NoH > 0.0 ? min(NoH, 1.0) : 0.0;
    float d = (1.0 - c) * (1.0 + c) + c * c * a2;
    float D = a2 / (kPi * d * d);
    float l = NoL > kMinCosine ? min(NoL, 1.0) : kMinCosine;
    float v = NoV > kMinCosine ? min(NoV, 1.0) : kMinCosine;
    float gv = l * sqrt(v * v * (1.0 - a2) + a2);
    float gl = v * sqrt(l * l * (1.0 - a2) + a2);
    float value = D * (0.5 / (gv + gl)) * l;
    return (NoH > 0.0 && NoL > 0.0) ? value : 0.0;
}

// The anisotropic term of KHR_materials_anisotropy, unit light, F = 1: alpha_t along t, alpha_b along b,
// the dot products of h, l, v with (t, b, n) as the engine forms them.
// Khronos, KHR_materials_anisotropy: D = 1/(pi at ab ((t.h/at)^2 + (b.h/ab)^2 + (n.h)^2)^2),
// V = 1/(2 (n.l |(at t.v, ab b.v, n.v)| + n.v |(at t.l, ab b.l, n.l)|))
float ggxAnisotropicSpecularTerm(float NoH, float ToH, float BoH, float NoL, float ToL, float BoL, float NoV,
                                 float ToV, float BoV, float alphaT, float alphaB) {
    float at = ggxSpecularAlpha(alphaT), ab = ggxSpecularAlpha(alphaB);
    float a2 = at * ab;
    float c = NoH > 0.0 ? min(NoH, 1.0) : 0.0;
    float x = ab * ToH, y = at * BoH, z = a2 * c;
    float w = a2 / max(x * x + y * y + z * z, 1.175494e-38);
    float D = a2 * w * w / kPi;
    float l = NoL > kMinCosine ? min(NoL, 1.0) : kMinCosine;
    float v = NoV > kMinCosine ? min(NoV, 1.0) : kMinCosine;
    float gv = l * sqrt(at * at * ToV * ToV + ab * ab * BoV * BoV + v * v);
    float gl = v * sqrt(at * at * ToL * ToL + ab * ab * BoL * BoL + l * l);
    float value = D * (0.5 / (gv + gl)) * l;
    return (NoH > 0.0 && NoL > 0.0 && value < 3.4e38) ? value : 0.0;
}
