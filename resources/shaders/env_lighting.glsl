// Environment lighting: the prefiltered radiance lookup (the mip read for a lobe's power follows
// core's prefilter rule exactly), SH9 irradiance for diffuse, and filtered importance sampling (FIS)
// of the box-filtered source chain at shading time. The GLSL twin of core's environment.h
// (mipForGloss, prefilterPowers inverted), sh.h (shBasis, shIrradiance) and env_sampling.h
// (hammersley, sampleLobe, lobePdfH, fisLod, tangentFrame, filteredImportanceSample), same names.
// material.frag includes this file only for the Prefiltered and FIS environments.
#include "common_math.glsl"
#include "brdf_ndf.glsl"
#include "gloss.glsl"

// int(burnish::LobeModel): the lobe each mip of the prefiltered cube was filtered with.
#define LOBE_MODEL_PHONG 0
#define LOBE_MODEL_BLINN_PHONG 1
// int(burnish::SampleDistribution).
#define SAMPLE_PHONG 0
#define SAMPLE_BLINN_PHONG 1
#define SAMPLE_BECKMANN 2
#define SAMPLE_GGX 3
#define SAMPLE_LEAN 4
// How the prefilter chose the power per mip (core's PrefilterOptions): topPower·powerDrop^m, or the
// gloss encoding's power at g = 1 − m/(mips − 1).
#define ENV_MIP_RULE_DROP 0
#define ENV_MIP_RULE_ENCODING 1

// env_sampling.h's kMaxFisSamples: the most taps one estimate takes.
const int kMaxFisSamples = 4096;

// The radiance cube: prefiltered (one cosine-power lobe per mip) for ENVIRONMENT_PREFILTERED, the
// box-filtered source chain for ENVIRONMENT_FIS.
uniform samplerCube uEnvironment;
uniform float uEnvironmentMips;     // levels of uEnvironment
uniform float uEnvironmentFaceSize; // level 0's face size
uniform mat3 uEnvironmentRotation;  // world direction → environment direction (rotation about +y)
uniform float uEnvironmentIntensity;
uniform vec3 uEnvironmentSh[9]; // SH9 of the radiance (core's Sh9 order), not yet scaled by intensity
uniform int uEnvironmentLobe;   // LOBE_MODEL_*
uniform int uEnvironmentMipRule;
uniform float uEnvironmentTopPower;
uniform float uEnvironmentPowerDrop;
uniform int uEnvironmentGlossKind; // the encoding of ENV_MIP_RULE_ENCODING (GLOSS_KIND_*)
uniform float uEnvironmentGlossMinPower;
uniform float uEnvironmentGlossMaxPower;
uniform int uEnvironmentSamples; // FIS taps per pixel

// ---------------------------------------------------------------------------------------------
// Prefiltered lookup.

// Lazarov 2011, "Physically Based Lighting in Call of Duty: Black Ops": texCUBElod(uv, float4(R, nMips − gloss·nMips)),
// with the last mip at g = 0: (1 − g)·(mips − 1)
float mipForGloss(float g, float mips) {
    return (1.0 - saturate(g)) * max(mips - 1.0, 0.0);
}

// GlossEncoding::increasesWithPower: the gloss-like encodings store g, the roughness-like 1 − g.
bool glossIncreasesWithPower(int kind) {
    return kind == GLOSS_KIND_LOG_POWER || kind == GLOSS_KIND_SMOOTHNESS;
}

// The (fractional) mip whose prefilter power is n: the inverse of core's prefilterPowers, clamped to
// [0, mips − 1]. Encoding rule: v = value(n), g = v (or 1 − v), mip = mipForGloss(g). Drop rule:
// n_m = top·drop^m, so m = log(n/top)/log(drop).
// Lagarde 2011, "AMD Cubemapgen for physically based rendering": power drop per mip
float mipForPower(float n, float mips, int rule, float topPower, float powerDrop, int glossKind, float nMin,
                  float nMax) {
    float last = max(mips - 1.0, 0.0);
    if (rule == ENV_MIP_RULE_ENCODING) {
        bool increases = glossIncreasesWithPower(glossKind);
        float v = powerToGloss(n, glossKind, nMin, nMax);
        // The roughness encodings hold their top power (kMaxPower's roughness) over a small range of
        // values next to g = 1, where core's mip 0 was filtered: powerToGloss clamps n at the top
        // power, so every n at or above it gives exactly the top's value, read as g = 1.
        float vTop = powerToGloss(kMaxPower, glossKind, nMin, nMax);
        if (v == vTop) return 0.0;
        return mipForGloss(increases ? v : 1.0 - v, mips);
    }
    n = clampPower(n);
    // A chain that does not fall (drop >= 1) or has no top power has only its first mip to offer.
    if (!(powerDrop > 0.0 && powerDrop < 1.0) || !(topPower > 0.0)) return 0.0;
    if (!(n > 0.0)) return last; // power 0 (and below): the widest lobe
    // In log2 so n/top never under- or overflows.
    return clamp((log2(n) - log2(topPower)) / log2(powerDrop), 0.0, last);
}

// The power of the lobe about R that stands for a Blinn-Phong BRDF of power n: the Blinn-Phong
// lobe model is that lobe at normal incidence (n itself); a Phong lobe of a quarter of the power
// is close to it.
// Lagarde 2012, "Relationship between Phong and Blinn lighting model": n_phong ≈ n_blinn/4
float environmentLobePower(float n, int lobe) {
    return lobe == LOBE_MODEL_PHONG ? 0.25 * clampPower(n) : clampPower(n);
}

// The gloss of Lazarov's glossy Fresnel, which was fitted for Black Ops' encoding n = 8192^g:
// g = log2(n)/13, whatever the material's own encoding.
// Lazarov 2011: n = 8192^g
float environmentFresnelGloss(float n) {
    return saturate(log2(max(clampPower(n), 1.0)) / 13.0);
}

// Radiance of the prefiltered cube about world direction R for a Blinn-Phong power n.
vec3 environmentPrefiltered(vec3 R, float n) {
    float mip = mipForPower(environmentLobePower(n, uEnvironmentLobe), uEnvironmentMips, uEnvironmentMipRule,
                            uEnvironmentTopPower, uEnvironmentPowerDrop, uEnvironmentGlossKind,
                            uEnvironmentGlossMinPower, uEnvironmentGlossMaxPower);
    return uEnvironmentIntensity * textureLod(uEnvironment, uEnvironmentRotation * R, mip).rgb;
}

// ---------------------------------------------------------------------------------------------
// SH9 irradiance.

// Ramamoorthi & Hanrahan 2001, "An Efficient Representation for Irradiance Environment Maps", eq. 3:
// Y00 = 0.282095; Y1m = 0.488603 (y, z, x); Y2-2, Y2-1, Y21 = 1.092548 (xy, yz, xz);
// Y20 = 0.315392 (3z² − 1); Y22 = 0.546274 (x² − y²)
void shBasis(vec3 d, out float Y[9]) {
    float len2 = dot(d, d);
    // The zero (or a non-finite) vector reads as +z, as core.
    d = (len2 > 1e-30 && !isinf(len2)) ? d * inversesqrt(len2) : vec3(0.0, 0.0, 1.0);
    Y[0] = 0.282095;
    Y[1] = 0.488603 * d.y;
    Y[2] = 0.488603 * d.z;
    Y[3] = 0.488603 * d.x;
    Y[4] = 1.092548 * d.x * d.y;
    Y[5] = 1.092548 * d.y * d.z;
    Y[6] = 0.315392 * (3.0 * d.z * d.z - 1.0);
    Y[7] = 1.092548 * d.x * d.z;
    Y[8] = 0.546274 * (d.x * d.x - d.y * d.y);
}

// Irradiance E(n) = Σ Â_l c_lm Y_lm(n), clamped at 0 (order 2 rings below 0 opposite a sun).
// Ramamoorthi & Hanrahan 2001, eq. 8: Â_0 = π, Â_1 = 2π/3, Â_2 = π/4
vec3 shIrradiance(vec3 c[9], vec3 n) {
    float Y[9];
    shBasis(n, Y);
    vec3 E = kPi * Y[0] * c[0];
    for (int k = 1; k < 4; ++k)
        E += (2.0 * kPi / 3.0) * Y[k] * c[k];
    for (int k = 4; k < 9; ++k)
        E += (0.25 * kPi) * Y[k] * c[k];
    return max(E, vec3(0.0));
}

// What a white Lambert surface of world normal N shows: E/π, times the intensity.
// Lagarde 2012, "PI or not to PI in game lighting equation": L_o = (c_diff/π) E
vec3 environmentDiffuse(vec3 N) {
    return uEnvironmentIntensity * kInvPi * shIrradiance(uEnvironmentSh, uEnvironmentRotation * N);
}

// ---------------------------------------------------------------------------------------------
// Filtered importance sampling.

// A lobe to sample (core's SpecularLobe): `power` for the isotropic ones; LEAN's slope mean and
// covariance (σxx, σyy, σxy) in the tangent frame.
struct SpecularLobe {
    int distribution; // SAMPLE_*
    float power;
    vec2 mean;
    vec3 cov;
};

struct LobeSample {
    vec3 h;     // tangent-frame half vector (for Phong the sampled l itself)
    float pdfH; // its density per steradian
};

// Van der Corput in base 2: the bits of i mirrored about the binary point.
float radicalInverse(uint i) {
    i = (i << 16u) | (i >> 16u);
    i = ((i & 0x55555555u) << 1u) | ((i & 0xAAAAAAAAu) >> 1u);
    i = ((i & 0x33333333u) << 2u) | ((i & 0xCCCCCCCCu) >> 2u);
    i = ((i & 0x0F0F0F0Fu) << 4u) | ((i & 0xF0F0F0F0u) >> 4u);
    i = ((i & 0x00FF00FFu) << 8u) | ((i & 0xFF00FF00u) >> 8u);
    return float(i) * 2.3283064365386963e-10; // 2^-32
}

// Hammersley & Handscomb 1964 via Colbert & Křivánek 2007, "GPU-Based Importance Sampling":
// (i/n, radical inverse of i)
vec2 hammersley(uint i, uint n) {
    return vec2(n > 0u ? float(i) / float(n) : 0.0, radicalInverse(i));
}

// Duff et al. 2017, "Building an Orthonormal Basis, Revisited", listing 3
void tangentFrame(vec3 N, out vec3 T, out vec3 B) {
    float s = N.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + N.z);
    float b = N.x * N.y * a;
    T = vec3(1.0 + s * N.x * N.x * a, s * b, -s * N.x);
    B = vec3(b, s + N.y * N.y * a, -N.y);
}

// Baker & Hill 2012, "Rock-Solid Shading": z_x = sqrt(−2 log ξ2) cos 2πξ1, z_y = sqrt(−2 log ξ2) sin 2πξ1
vec2 boxMuller(float u1, float u2) {
    // ξ2 = 1 − u2 ∈ (0, 1]; 1e-30 (above float's smallest normal) keeps log finite for u2 = 1 inputs.
    float r = sqrt(-2.0 * log(max(1.0 - u2, 1e-30)));
    return r * vec2(cos(2.0 * kPi * u1), sin(2.0 * kPi * u1));
}

// LEAN's Gaussian (core's leanParams): σ floored at the variance of kMaxPower, |ρ| below 1 so the
// Gaussian is proper. Returns (σx, σy, ρ, det Σ).
vec4 leanParams(vec3 cov) {
    float sxx = max(cov.x, kMinVariance), syy = max(cov.y, kMinVariance);
    float sx = sqrt(sxx), sy = sqrt(syy);
    float rho = clamp(cov.z / (sx * sy), -0.999, 0.999);
    return vec4(sx, sy, rho, sxx * syy * (1.0 - rho * rho));
}

// The density sampleLobe draws h with (tangent frame, per steradian).
float lobePdfH(SpecularLobe lobe, vec3 h) {
    float n = clampPower(lobe.power);
    float c = h.z;
    if (!(c > 0.0)) return 0.0;
    if (lobe.distribution == SAMPLE_PHONG) return phongLobeNorm(n) * powCos(c, n);
    if (lobe.distribution == SAMPLE_BLINN_PHONG) return blinnPhongNdf(c, n) * c;
    if (lobe.distribution == SAMPLE_BECKMANN) return beckmannNdf(c, beckmannRoughnessFromPower(n)) * c;
    if (lobe.distribution == SAMPLE_GGX) return ggxNdf(c, ggxAlphaFromPower(n)) * c;
    // Olano & Baker 2010, "LEAN Mapping": D(h) = P(slope)/cos⁴θ_h; the density of h is D cosθ_h
    vec4 p = leanParams(lobe.cov);
    float hz = max(c, kMinCosine); // slopes are h.xy/h.z: bounded at grazing h
    float x = h.x / hz - lobe.mean.x, y = h.y / hz - lobe.mean.y;
    float sxx = p.x * p.x, syy = p.y * p.y, sxy = p.z * p.x * p.y;
    float q = (syy * x * x - 2.0 * sxy * x * y + sxx * y * y) / p.w;
    // In log form: neither exp(−q/2) nor 1/h_z³ alone over- or underflows into 0·∞; 80 keeps exp finite.
    float logP = -0.5 * q - log(2.0 * kPi * sqrt(p.w)) - 3.0 * log(hz);
    return exp(min(logP, 80.0));
}

// Draws a tangent-frame half vector from the lobe for (u1, u2) ∈ [0, 1)².
LobeSample sampleLobe(SpecularLobe lobe, float u1, float u2) {
    float n = clampPower(lobe.power);
    float phi = 2.0 * kPi * u1;
    // log ξ with ξ = 1 − u2 ∈ (0, 1]; 1e-30 guards u2 = 1 inputs.
    float logXi = log(max(1.0 - u2, 1e-30));
    float cosTheta = 1.0;
    vec3 h;
    if (lobe.distribution == SAMPLE_PHONG) {
        // Lagarde 2011: the Phong lobe (n+1)/(2π) cos^n θ; its CDF inverts to cosθ = ξ^(1/(n+1))
        cosTheta = exp(logXi / (n + 1.0));
    } else if (lobe.distribution == SAMPLE_BLINN_PHONG) {
        // Lazarov 2011: D(h) cosθ_h = (n+2)/(2π) cos^(n+1) θ_h, so cosθ_h = ξ^(1/(n+2))
        cosTheta = exp(logXi / (n + 2.0));
    } else if (lobe.distribution == SAMPLE_GGX) {
        float alpha = ggxAlphaFromPower(n);
        // Walter et al. 2007, "Microfacet Models for Refraction", eq. 35: tan²θ_h = α² ξ/(1 − ξ), as cos²
        float u = min(u2, 0.99999994); // the float below 1: u2 = 1 would put h on the horizon
        cosTheta = sqrt(clamp((1.0 - u) / (1.0 + (alpha * alpha - 1.0) * u), 0.0, 1.0));
    } else {
        vec2 z = boxMuller(u1, u2);
        vec2 slope;
        if (lobe.distribution == SAMPLE_BECKMANN) {
            // Beckmann slopes are Gaussian with per-axis σ² = m²/2 = 1/(n+2)
            float m = beckmannRoughnessFromPower(n);
            slope = sqrt(0.5) * m * z;
        } else {
            // Baker & Hill 2012: h_x = σx z_x + μx, h_y = σy(ρ z_x + sqrt(1 − ρ²) z_y) + μy
            vec4 p = leanParams(lobe.cov);
            slope = vec2(p.x * z.x, p.y * (p.z * z.x + sqrt(1.0 - p.z * p.z) * z.y)) + lobe.mean;
        }
        h = normalize(vec3(slope, 1.0));
        LobeSample s;
        s.h = h;
        s.pdfH = lobePdfH(lobe, h);
        return s;
    }
    float sinTheta = sqrt(max(0.0, 1.0 - cosTheta * cosTheta));
    h = vec3(sinTheta * cos(phi), sinTheta * sin(phi), cosTheta);
    LobeSample s;
    s.h = h;
    s.pdfH = lobePdfH(lobe, h);
    return s;
}

// Colbert & Křivánek 2007, "GPU-Based Importance Sampling", eq. 13:
// lod = 0.5 log2(Ω_s/Ω_p) + 1, Ω_s = 1/(N p), Ω_p = 4π/(6 w²), clamped to [0, mips − 1]
float fisLod(float pdfL, float samples, float faceSize, float mips) {
    float maxLod = max(mips, 1.0) - 1.0;
    if (!(pdfL > 0.0) || !(samples > 0.0) || !(faceSize > 0.0)) return maxLod;
    // Sums of log2 instead of the quotient: N·p reaches 1e30 for a mirror lobe.
    float log2OmegaP = log2(4.0 * kPi / 6.0) - 2.0 * log2(faceSize);
    float lod = 0.5 * (-log2(samples) - log2(pdfL) - log2OmegaP) + 1.0;
    return clamp(lod, 0.0, maxLod);
}

// FIS estimate of the lobe-weighted mean radiance: `samples` Hammersley points, trilinear
// mip-biased taps of `chain` (box-filtered mips of level-0 face size `faceSize`). N is the axis of
// the sampling frame (T, B, N) the lobe is given in (for Phong the frame's axis is the reflection of
// V about N, as core); taps under the surface (N·l <= 0) are dropped. `rotation` maps world
// directions to the cube's. Black when no tap is above the surface.
// Baker & Hill 2012, "Rock-Solid Shading": L_i = −reflect(V, H_i), mip biased by the sample density
vec3 filteredImportanceSample(samplerCube chain, mat3 rotation, float faceSize, float mips, vec3 N, vec3 V,
                              vec3 T, vec3 B, SpecularLobe lobe, int samples) {
    bool phong = lobe.distribution == SAMPLE_PHONG;
    vec3 axis = N;
    if (phong) {
        axis = normalize(2.0 * dot(N, V) * N - V);
        tangentFrame(axis, T, B);
    }
    vec3 Vt = vec3(dot(V, T), dot(V, B), dot(V, axis));
    int count = clamp(samples, 0, kMaxFisSamples);
    vec3 sum = vec3(0.0);
    float used = 0.0;
    for (int i = 0; i < count; ++i) {
        vec2 u = hammersley(uint(i), uint(count));
        LobeSample s = sampleLobe(lobe, u.x, u.y);
        vec3 lt;
        float pdfL;
        if (phong) {
            lt = s.h;
            pdfL = s.pdfH;
        } else {
            float VoH = dot(Vt, s.h);
            if (!(VoH > 0.0)) continue;
            // The Jacobian of h → l is 1/(4 v·h).
            lt = 2.0 * VoH * s.h - Vt;
            pdfL = s.pdfH / (4.0 * VoH);
        }
        vec3 l = lt.x * T + lt.y * B + lt.z * axis;
        if (!(dot(l, N) > 0.0)) continue;
        sum += textureLod(chain, rotation * l, fisLod(pdfL, float(count), faceSize, mips)).rgb;
        used += 1.0;
    }
    return used > 0.0 ? sum / used : vec3(0.0);
}

// FIS of uEnvironment (the box chain) for the lobe about the frame (T, B, N), times the intensity.
vec3 environmentFis(vec3 N, vec3 V, vec3 T, vec3 B, SpecularLobe lobe) {
    return uEnvironmentIntensity * filteredImportanceSample(uEnvironment, uEnvironmentRotation,
                                                            uEnvironmentFaceSize, uEnvironmentMips, N, V, T, B,
                                                            lobe, uEnvironmentSamples);
}
