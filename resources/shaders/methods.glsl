// What each prefiltering method's shader does with its stored values: the GLSL twin of
// core/include/burnish/core/prefilter/methods.h, core/src/prefilter/methods.cpp and the Toksvig functions of gloss.h.
// Every guard of core is here too: |Na| → 0, zero variance, det Σ → 0, h_z <= 0.
#include "common_math.glsl"
#include "brdf_ndf.glsl"

// int(burnish::Method), in the enum's order; chosen with `#if METHOD == METHOD_LEAN`.
#define METHOD_NAIVE 0
#define METHOD_TOKSVIG 1
#define METHOD_TOKSVIG_MAP 2
#define METHOD_VARIANCE_TO_GLOSS 3
#define METHOD_LEAN 4
#define METHOD_CLEAN 5
#define METHOD_VMF 6
#define METHOD_MIXTURE 7
#define METHOD_FITTED 8

// Base powers below this are treated as this, so 1/s stays finite (methods.cpp).
const float kMinBasePower = 1e-6;

// The base power as methodLobe uses it: clamped to [kMinBasePower, kMaxPower].
float methodBasePower(float s) {
    return max(clampPower(s), kMinBasePower);
}

// Toksvig 2004 via Baker & Hill 2012: σ² = (1 − |Na|)/|Na|, clamped to [0, 1/kMinVariance]
float toksvigVariance(float lenNa) {
    lenNa = saturate(lenNa);
    if (lenNa <= kMinVariance) return 1.0 / kMinVariance;
    return min((1.0 - lenNa) / lenNa, 1.0 / kMinVariance);
}

// Toksvig 2004 via Hill 2011: f_t = |Na| / (|Na| + s(1 − |Na|)); |Na| → 0 gives 0
float toksvigFactor(float lenNa, float s) {
    lenNa = saturate(lenNa);
    s = clampPower(s);
    float denom = lenNa + s * (1.0 - lenNa);
    // denom is 0 only for |Na| = 0 and s = 0: a power of 0 stays 0.
    return denom > 0.0 ? lenNa / denom : 1.0;
}

// f_t·s, never below 0 nor above s.
float toksvigPower(float lenNa, float s) {
    return clamp(toksvigFactor(lenNa, s) * clampPower(s), 0.0, clampPower(s));
}

// Hill 2011, "Specular Showdown in the Wild West": ft /= lerp(s/fixed_s, 1, ft)
float convertToksvigFactor(float ft, float fixedS, float s) {
    ft = saturate(ft);
    fixedS = max(clampPower(fixedS), kMinVariance); // keeps s/fixed_s finite
    float ratio = clampPower(s) / fixedS;
    float denom = ratio + (1.0 - ratio) * ft;
    return denom > 0.0 ? min(ft / denom, 1.0) : 1.0;
}

// Hill 2011: the baked Toksvig map's factor ft (for fixedS) converted to s; p = ft'·s
float toksvigMapPower(float ft, float fixedS, float s) {
    s = methodBasePower(s);
    return convertToksvigFactor(ft, fixedS, s) * s;
}

// Lazarov 2011: p = 1/(v + 1/(s+1)) − 1, for the projected variance v (zero variance keeps s)
float varianceToGlossPower(float v, float s) {
    s = methodBasePower(s);
    return clampPower(1.0 / (v + 1.0 / (s + 1.0)) - 1.0);
}

// Banerjee et al. 2005, "Clustering on the Unit Hypersphere using von Mises-Fisher Distributions":
// κ ≈ (3r − r³)/(1 − r²), clamped to [0, kMaxPower]
float vmfKappa(float r) {
    r = saturate(r);
    float oneMinusR2 = (1.0 - r) * (1.0 + r);
    // r = 1 (all normals equal) is the limit κ → ∞: the lobe keeps the base power.
    if (!(oneMinusR2 > 0.0)) return kMaxPower;
    return clamp(r * (3.0 - r * r) / oneMinusR2, 0.0, kMaxPower);
}

// Han et al. 2007, "Frequency Domain Normal Map Filtering": 1/p = 1/s + 1/κ
float vmfPower(float lenNa, float s) {
    s = methodBasePower(s);
    float kappa = vmfKappa(lenNa);
    return kappa > 0.0 ? clampPower(1.0 / (1.0 / s + 1.0 / kappa)) : 0.0;
}

// Olano & Baker 2010, "LEAN Mapping": Σ = M − BBᵀ + I/s, as vec3(xx, yy, xy). M − BBᵀ is a
// covariance, so its diagonal is clamped at 0: stored (16-bit) B and M can put it slightly below.
vec3 leanCovariance(vec2 B, vec3 M, float s) {
    float invS = 1.0 / methodBasePower(s);
    return vec3(max(M.x - B.x * B.x, 0.0) + invS, max(M.y - B.y * B.y, 0.0) + invS, M.z - B.x * B.y);
}

// Baker 2011, "Spectacular Specular: LEAN and CLEAN Specular Highlights": σ² = (M_xx + M_yy)/2 −
// |B|²/2 + 1/s, from the stored mean second moment mIso = (M_xx + M_yy)/2 (clamped at 0 like LEAN's).
float cleanVariance(vec2 B, float mIso, float s) {
    return max(mIso - 0.5 * dot(B, B), 0.0) + 1.0 / methodBasePower(s);
}

// The normal whose slope is B: normalize(B.x, B.y, 1).
vec3 normalOfSlope(vec2 B) {
    return normalize(vec3(B, 1.0));
}

// The largest slope-space Gaussian value: e^80, where float still has room for the shading's factors.
const float kMaxSlopeNdf = 5.5406223e34;

// Olano & Baker 2010, "LEAN Mapping": exp(−½ dᵀΣ⁻¹d)/(2π√detΣ) / h_z⁴ with d = h's slope − B, from
// h's slope h.xy/h_z and invNorm = 1/(2π h_z⁴) (slopeGaussianInvNorm), which every lobe at one h
// shares (mixtureValue computes them once for its K lobes).
float slopeGaussianNdfAtSlope(vec2 slope, float invNorm, vec2 mean, vec3 cov) {
    float det = cov.x * cov.y - cov.z * cov.z;
    float dx = slope.x - mean.x;
    float dy = slope.y - mean.y;
    // One inverse square root gives both 1/√detΣ and 1/detΣ (no division, no logarithm).
    float r = inversesqrt(det);
    float e = (dx * dx * cov.y + dy * dy * cov.x - 2.0 * dx * dy * cov.z) * (r * r);
    // exp(−e/2) <= 1 for a positive definite Σ, 1/√detΣ <= 2.3e10 for the guarded covariances every
    // method produces and invNorm <= 1.6e23: the product stays finite in float. kMaxSlopeNdf (e^80)
    // bounds what a broken Σ could give. A singular or broken Σ (det <= 0, NaN) gives no lobe (as
    // core): the comparisons fail. Selects, not early returns: a shader core pays for divergent
    // branches.
    float D = exp(-0.5 * e) * r * invNorm;
    return det > 0.0 && D > 0.0 ? min(D, kMaxSlopeNdf) : 0.0;
}

// 1/(2π h_z⁴) for slopeGaussianNdfAtSlope, h_z at least kMinCosine: that bounds 1/h_z at 1e6, where
// h_z⁴ (1e-24) is still a normal float; there the Gaussian of any Σ a method produces (|B| <= 100,
// Σ <= 1e6) is exp(−1e6)-small, 0 in core too.
float slopeGaussianInvNorm(float hz) {
    float hz2 = hz * hz;
    return 1.0 / (2.0 * kPi * hz2 * hz2);
}

float slopeGaussianNdf(vec3 h, vec2 mean, vec3 cov) {
    float hz = max(h.z, kMinCosine);
    float D = slopeGaussianNdfAtSlope(h.xy / hz, slopeGaussianInvNorm(hz), mean, cov);
    return h.z > 0.0 ? D : 0.0;
}

// The isotropic methods' NDF (methodNdf for a lobe with power p about normal): (p+2)/(2π)(n̄·h)^p
float isotropicLobeNdf(vec3 normal, float power, vec3 h) {
    return blinnPhongNdf(dot(normal, h), power);
}

// The lobe mixture (core/include/burnish/core/prefilter/lobe_mixture.h): up to 4 slope-space
// Gaussians per texel, stored as premultiplied raw moments (w, w·b, w·M) that filtering merges.
const int kMaxMixtureLobes = 4;
// Correlations stay inside (−kMaxCorrelation, kMaxCorrelation): det Σ stays positive in float.
const float kMaxCorrelation = 0.999;

// LobeMoments::mean: b = (w·b)/w, (0, 0) for an empty lobe
vec2 mixtureLobeMean(float w, vec2 wb) {
    return w > 0.0 ? wb * (1.0 / w) : vec2(0.0);
}

// LobeMoments::covariance: Σ = (w·M)/w − bbᵀ (wM = xx, yy, xy), each variance at least minVariance
// (NaN too) and the correlation inside ±kMaxCorrelation; an empty lobe gets (min, min, 0).
vec3 mixtureLobeCovariance(float w, vec2 wb, vec3 wM, float minVariance) {
    if (!(w > 0.0)) return vec3(minVariance, minVariance, 0.0);
    // One reciprocal for the five quotients (mixtureLobeMean's too, once the compiler merges them).
    float r = 1.0 / w;
    vec2 b = wb * r;
    float xx = wM.x * r - b.x * b.x;
    float yy = wM.y * r - b.y * b.y;
    float xy = wM.z * r - b.x * b.y;
    xx = xx > minVariance ? xx : minVariance;
    yy = yy > minVariance ? yy : minVariance;
    float limit = kMaxCorrelation * sqrt(xx * yy);
    xy = isnan(xy) || isinf(xy) ? 0.0 : clamp(xy, -limit, limit);
    return vec3(xx, yy, xy);
}

// Runnalls 2007 (merge cost) on Olano & Baker 2010's lobes: the mixture's reflected value
// Σ_i (w_i/Σw) D_i(h) max(0, n_i·l), D_i the slope-space Gaussian of lobe i and n_i the normal of
// its mean slope (core's mixtureValue). lobe[i] = (w·b.x, w·b.y, w·M.xx, w·M.yy); cross[i] = w·M.xy.
float mixtureValue(vec4 weights, vec4 lobe[kMaxMixtureLobes], vec4 cross, int count, vec3 l, vec3 h,
                   float minVariance) {
    // No early return and no `continue`: each costs a shader core a divergent branch (on llvmpipe a
    // K = 1 mixture's frame took 23.5 ms with them, 13.4 ms without). An empty lobe's term is
    // w = 0 times a finite value (mixtureLobeCovariance's (min, min, 0) lobe): 0, as core's skip.
    // h's slope and the Gaussian's normalisation are the same for every lobe: computed once.
    float hz = max(h.z, kMinCosine);
    vec2 slope = h.xy / hz;
    float invNorm = slopeGaussianInvNorm(hz);
    float total = 0.0;
    for (int i = 0; i < count; ++i)
        total += max(weights[i], 0.0);
    float share = total > 0.0 ? 1.0 / total : 0.0;
    float sum = 0.0;
    for (int i = 0; i < count; ++i) {
        float w = max(weights[i], 0.0);
        vec2 b = mixtureLobeMean(w, lobe[i].xy);
        vec3 cov = mixtureLobeCovariance(w, lobe[i].xy, vec3(lobe[i].zw, cross[i]), minVariance);
        sum += w * share * slopeGaussianNdfAtSlope(slope, invNorm, b, cov) * max(0.0, dot(normalOfSlope(b), l));
    }
    return h.z > 0.0 ? sum : 0.0;
}

// MixtureFiltering::Stochastic, filtering after shading (core's stochasticTexel, lobe_mixture.h): of
// the texels that trilinear filtering of a texture of `levels` levels (level 0 size0 texels) blends at
// uv with level of detail lod, the one that three uniform numbers xi in [0, 1) pick, each with the
// probability of its filter weight; the texture repeats. Returns (x, y, level) for texelFetch.
// Pharr et al. 2024, "Filtering After Shading With Stochastic Texture Filtering": filter importance sampling
ivec3 stochasticTexel(vec2 uv, float lod, ivec2 size0, int levels, vec3 xi) {
    levels = max(levels, 1);
    float l = clamp(lod, 0.0, float(levels - 1));
    float fl = floor(l);
    int level = min(int(fl) + (xi.z < l - fl ? 1 : 0), levels - 1);
    ivec2 size = max(ivec2(size0.x >> level, size0.y >> level), ivec2(1));
    vec2 p = fract(uv) * vec2(size) - 0.5;
    vec2 base = floor(p);
    ivec2 at = ivec2(base) + ivec2(xi.x < p.x - base.x ? 1 : 0, xi.y < p.y - base.y ? 1 : 0);
    return ivec3((at + size) % size, level);
}

// Three uniform numbers in [0, 1) from a pixel and a sample index (core's stochasticNumbers): each
// word of the pcg3d hash of (x, y, sample), its top 24 bits.
// Jarzynski & Olano 2020, "Hash Functions for GPU Rendering": pcg3d
vec3 stochasticNumbers(uvec3 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> 16u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return vec3(v >> 8u) * (1.0 / 16777216.0);
}
