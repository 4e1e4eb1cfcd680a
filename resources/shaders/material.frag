// The material pass: a prefiltering method's lobe read from its baked textures, shaded the way an
// engine would (NDF × Fresnel × visibility / 4 in the π light units of core's punctualRadiance,
// Lambert diffuse), into an HDR target. Features are switched by the numbered defines of
// render/src/features.cpp; a feature that is off has no define and none of its code, uniforms or
// samplers here. With UBERSHADER 1 everything is compiled in and switched by uniforms.
#include "common_math.glsl"
#include "brdf_ndf.glsl"
#include "brdf_fresnel.glsl"
#include "brdf_visibility.glsl"
#include "geometric_aa.glsl"
#include "gloss.glsl"
#include "methods.glsl"
#include "common_color.glsl"

#ifndef UBERSHADER
#define UBERSHADER 0
#endif
// DISPLAY_OUTPUT 1: write the display value (displayFromHdr with uExposure) instead of HDR.
#ifndef DISPLAY_OUTPUT
#define DISPLAY_OUTPUT 0
#endif
#if DISPLAY_OUTPUT
uniform float uExposure;
#endif

#if UBERSHADER
// Every switch becomes a uniform; the #if tests below see a value no switch has, so each branch
// is compiled in and chosen at run time.
#define METHOD (-1)
#define NDF (-1)
#define FRESNEL (-1)
#define VISIBILITY (-1)
#define SPECULAR_AA (-1)
#define DEBUG_VIEW (-1)
#define ENVIRONMENT (-1)
uniform int uMethod;
uniform int uNdf;
uniform int uFresnel;
uniform int uVisibility;
uniform int uSpecularAa;
uniform int uDebugView;
uniform int uPointLightCount;
uniform bool uHasAmbient;
uniform bool uHasNormalMap;
uniform bool uHasDetailMap;
uniform bool uHasGlossMap;
uniform bool uHasSpecularMap;
uniform bool uHasDiffuse;
uniform bool uHasDiffuseAa;
uniform int uEnvironmentKind; // int(EnvironmentKind)
#define IS_METHOD(m) (uMethod == (m))
#define IS_NDF(m) (uNdf == (m))
#define IS_FRESNEL(m) (uFresnel == (m))
#define IS_VISIBILITY(m) (uVisibility == (m))
#define IS_SPECULAR_AA(m) (uSpecularAa == (m))
#define IS_DEBUG(m) (uDebugView == (m))
#define IS_ENVIRONMENT(m) (uEnvironmentKind == (m))
#define UBER_ON(flag) (flag)
#else
#define IS_METHOD(m) (METHOD == (m))
#define IS_NDF(m) (NDF == (m))
#define IS_FRESNEL(m) (FRESNEL == (m))
#define IS_VISIBILITY(m) (VISIBILITY == (m))
#define IS_SPECULAR_AA(m) (SPECULAR_AA == (m))
#define IS_DEBUG(m) (DEBUG_VIEW == (m))
#define IS_ENVIRONMENT(m) (ENVIRONMENT == (m))
#define UBER_ON(flag) true
#endif

// The environment's code, uniforms and sampler exist only in the programs that light with it.
#if ENVIRONMENT == ENVIRONMENT_PREFILTERED || ENVIRONMENT == ENVIRONMENT_FIS || UBERSHADER
#define HAS_ENVIRONMENT_MAP 1
#include "env_lighting.glsl"
#endif

in vec3 vWorldPosition;
in vec3 vNormal;
in vec4 vTangent;
in vec2 vUv;

layout(location = 0) out vec4 fragColor;

uniform vec3 uCameraPosition;
uniform vec3 uLightDirection; // towards the light, unit
uniform vec3 uLightColor;     // colour × intensity, in the "game light units" of punctualRadiance
#if defined(POINT_LIGHTS)
uniform vec3 uPointLightPosition[POINT_LIGHTS];
uniform vec3 uPointLightColor[POINT_LIGHTS]; // colour × intensity at distance 1
#endif
#if defined(HAS_AMBIENT)
uniform vec3 uAmbient; // constant radiance from every direction
#endif

#if defined(HAS_SPECULAR_MAP)
uniform sampler2D uSpecularMap; // linear F0 per texel
#endif
#if !defined(HAS_SPECULAR_MAP) || UBERSHADER
uniform vec3 uSpecularColor; // linear F0
#endif
#if defined(HAS_DIFFUSE)
uniform vec3 uAlbedo; // linear diffuse albedo
#endif

// The authored (base) power where no gloss texture carries it.
uniform float uBasePower;

// The methods whose lobes live in slope space and carry the authored power in their moments.
#define STATIC_SLOPE_METHOD (METHOD == METHOD_LEAN || METHOD == METHOD_CLEAN || METHOD == METHOD_MIXTURE)
#define IS_SLOPE_METHOD (IS_METHOD(METHOD_LEAN) || IS_METHOD(METHOD_CLEAN) || IS_METHOD(METHOD_MIXTURE))

#if defined(HAS_NORMAL_MAP)
// The baked "normal" texture (every method but LEAN/CLEAN/mixture reads it); in the reference, the
// finest normals themselves. Every baked texture arrives decoded (the renderer applies core's
// ChannelDecode, stored·scale + bias, as it uploads): its values are physical.
#if UBERSHADER || !STATIC_SLOPE_METHOD
uniform sampler2D uNormalMap;
#endif
// The normal map's finest size, for the mip-level view and the slope methods' derivatives.
uniform vec2 uNormalMapSize;
// The "gloss" texture: the adjusted lobe of variance-to-gloss, vMF and the fitted lobe, or the authored gloss map.
// LEAN and CLEAN carry the authored gloss as 1/s inside their moments: they never read it.
#if UBERSHADER || METHOD == METHOD_VARIANCE_TO_GLOSS || METHOD == METHOD_VMF || METHOD == METHOD_FITTED
#define READS_GLOSS_TEXTURE 1
#elif defined(HAS_GLOSS_MAP) && !STATIC_SLOPE_METHOD
#define READS_GLOSS_TEXTURE 1
#endif
#if defined(READS_GLOSS_TEXTURE)
uniform sampler2D uGlossMap;
// The gloss encoding (core's GlossEncoding): int(GlossKind) and, for LogPower, its nMin and nMax.
uniform int uGlossKind;
uniform float uGlossMinPower;
uniform float uGlossMaxPower;
#endif
#if UBERSHADER || METHOD == METHOD_TOKSVIG_MAP
uniform sampler2D uToksvigMap;
uniform float uToksvigFixedPower; // the power the Toksvig factor was baked for
#endif
#if UBERSHADER || METHOD == METHOD_LEAN
uniform sampler2D uLeanB;
uniform sampler2D uLeanM;
#endif
#if UBERSHADER || METHOD == METHOD_CLEAN
uniform sampler2D uClean;
#endif
#if UBERSHADER || METHOD == METHOD_MIXTURE
// The mixture's textures (method table rows mixture-weights, mixture-lobe0..3, mixture-cross):
// uMixtureLobes of the lobe samplers are bound.
uniform int uMixtureLobes;
// The specialised program is compiled for its K (MIXTURE_LOBES, set by the renderer), so its loops
// over the lobes unroll to exactly K and the unused lobes' code and fetches are gone.
#if !UBERSHADER && defined(MIXTURE_LOBES)
#define MIXTURE_LOBE_COUNT MIXTURE_LOBES
#else
#define MIXTURE_LOBE_COUNT clamp(uMixtureLobes, 1, kMaxMixtureLobes)
#endif
uniform float uMixtureMinVariance; // the narrowest authored lobe's base variance (mixtureBaseVariance)
uniform sampler2D uMixtureWeights;
uniform sampler2D uMixtureLobe0;
uniform sampler2D uMixtureLobe1;
uniform sampler2D uMixtureLobe2;
uniform sampler2D uMixtureLobe3;
uniform sampler2D uMixtureCross;
#if defined(MIXTURE_STOCHASTIC)
// Filtering after shading (MaterialSettings::mixtureFiltering): the pass's sample index and the
// mixture textures' level count.
uniform int uStochasticSample;
uniform int uMixtureLevels;
#endif
#endif
#if defined(HAS_DETAIL_MAP)
uniform sampler2D uDetailMap; // core's bakeDetail: [x, y, 0, variance]
uniform float uDetailUvScale; // detail tiling relative to the base map
#endif
#endif

// A texture read: the hardware's trilinear filter, or the finest level for the reference.
vec4 sampleMap(sampler2D map, vec2 uv) {
#if defined(REFERENCE_MODE)
    return textureLod(map, uv, 0.0);
#else
    return texture(map, uv);
#endif
}

// v/|v|, or `fallback` for a zero (or non-finite) vector, so normalize never divides by zero.
vec3 safeNormalize(vec3 v, vec3 fallback) {
    float len2 = dot(v, v);
    return (len2 > 1e-30 && !isinf(len2)) ? v * inversesqrt(len2) : fallback;
}

#if defined(READS_GLOSS_TEXTURE)
// GlossEncoding::power (core/gloss.h) for the stored value v.
float glossEncodingPower(float v) {
    return glossToPower(v, uGlossKind, uGlossMinPower, uGlossMaxPower);
}
#endif

#if defined(HAS_DETAIL_MAP)
// The twins of core/detail.h (no other snippet holds them).
// Barré-Brisebois & Hill 2012, "Blending in Detail":
// t = b + (0,0,1), u = d·(−1,−1,1), r = t·(t·u)/t.z − u
vec3 reorientedBlend(vec3 base, vec3 detail) {
    vec3 t = vec3(base.xy, base.z + 1.0);
    vec3 u = vec3(-detail.xy, detail.z);
    // A base at or below the horizon has no frame to rotate into (core returns the detail).
    if (!(t.z > 1e-6)) return safeNormalize(detail, vec3(0.0, 0.0, 1.0));
    return safeNormalize(t * (dot(t, u) / t.z) - u, base);
}

// Baker & Hill 2012, "Rock-Solid Shading", detail normal maps: 1/s' = 1/s + σ²
float addVarianceToPower(float s, float sigma2) {
    float v = 1.0 / max(clampPower(s), 1.0 / kMaxPower) + max(sigma2, 0.0);
    return clampPower(1.0 / max(v, kMinVariance));
}
#endif

// The lobe a texel's method reconstructs (core's TexelLobe): the normal n̄ in tangent space, the
// isotropic power, or for LEAN/CLEAN the slope-space Gaussian (mean B, covariance xx, yy, xy).
struct Lobe {
    vec3 n;
    float power;
    bool slope;
    vec2 B;
    vec3 cov;
    float lenNa; // |Na| for diffuse AA (1 = a flat footprint)
    // The mixture's lobes as filtered premultiplied moments (its B and cov above are the moment-
    // matched single lobe, LEAN's, for the terms that need one lobe: visibility, environment).
    int mixtureLobes; // 0: not a mixture
    vec4 mixtureWeights;
    vec4 mixtureLobe[kMaxMixtureLobes];
    vec4 mixtureCross;
    float mixtureMinVariance;
};

// Variance added to a slope lobe on both axes (specular AA, detail maps): a mixture adds it to every
// lobe, w·v on its premultiplied w·M diagonal.
void addSlopeVariance(inout Lobe lobe, float v) {
    lobe.cov.xy += vec2(v);
    for (int i = 0; i < kMaxMixtureLobes; ++i)
        lobe.mixtureLobe[i].zw += vec2(lobe.mixtureWeights[i] * v);
}

// Variance below which a slope covariance is treated as this: kMinVariance, the variance of
// kMaxPower, keeps det Σ > 0 and 1/det finite.
vec3 guardCovariance(vec3 cov) {
    float xx = max(cov.x, kMinVariance);
    float yy = max(cov.y, kMinVariance);
    // |ρ| < 1 strictly: 16-bit storage of M can make M − BBᵀ a hair indefinite.
    float limit = 0.999 * sqrt(xx * yy);
    return vec3(xx, yy, clamp(cov.z, -limit, limit));
}

Lobe materialLobe(vec2 uv) {
    Lobe lobe;
    lobe.n = vec3(0.0, 0.0, 1.0);
    lobe.power = clampPower(uBasePower);
    lobe.slope = false;
    lobe.B = vec2(0.0);
    lobe.cov = vec3(0.0);
    lobe.lenNa = 1.0;
    lobe.mixtureLobes = 0;
    lobe.mixtureWeights = vec4(0.0);
    for (int i = 0; i < kMaxMixtureLobes; ++i)
        lobe.mixtureLobe[i] = vec4(0.0);
    lobe.mixtureCross = vec4(0.0);
    lobe.mixtureMinVariance = kMinVariance;
#if defined(HAS_NORMAL_MAP)
    if (UBER_ON(uHasNormalMap)) {
        float s = clampPower(uBasePower);
#if defined(HAS_GLOSS_MAP) && defined(READS_GLOSS_TEXTURE)
        // The authored power per texel (the slope methods' lenNa below then uses the base power).
        if (UBER_ON(uHasGlossMap) && !(IS_METHOD(METHOD_VARIANCE_TO_GLOSS) || IS_METHOD(METHOD_VMF) || IS_METHOD(METHOD_FITTED) ||
                                       IS_SLOPE_METHOD))
            s = glossEncodingPower(sampleMap(uGlossMap, uv).r);
#endif
#if UBERSHADER || !STATIC_SLOPE_METHOD
        if (!IS_SLOPE_METHOD) {
            vec3 Na = sampleMap(uNormalMap, uv).xyz;
            lobe.n = safeNormalize(Na, vec3(0.0, 0.0, 1.0));
            lobe.power = s;
            if (IS_METHOD(METHOD_TOKSVIG)) {
                // The hardware's trilinear average of the unnormalized mean normals is Na of the
                // footprint: its length carries the variance.
                // Toksvig 2004 via Hill 2011: p = f_t·s, f_t = |Na|/(|Na| + s(1−|Na|))
                lobe.lenNa = saturate(length(Na));
                lobe.power = toksvigPower(lobe.lenNa, s);
            }
#if UBERSHADER || METHOD == METHOD_TOKSVIG_MAP
            if (IS_METHOD(METHOD_TOKSVIG_MAP)) {
                float ft = saturate(sampleMap(uToksvigMap, uv).r);
                // Hill 2011, "Specular Showdown in the Wild West": ft /= lerp(s/fixed_s, 1, ft)
                lobe.power = convertToksvigFactor(ft, uToksvigFixedPower, s) * s;
                // Toksvig 2004: f_t for the fixed power inverts to |Na| = ft·s0/(1 − ft + ft·s0)
                float s0 = uToksvigFixedPower;
                // 1e-6: the denominator is >= min(1, s0) > 0 for ft in [0, 1]; guards s0 = 0 only.
                lobe.lenNa = saturate(ft * s0 / max(1.0 - ft + ft * s0, 1e-6));
            }
#endif
#if defined(READS_GLOSS_TEXTURE)
            if (IS_METHOD(METHOD_VARIANCE_TO_GLOSS) || IS_METHOD(METHOD_VMF) || IS_METHOD(METHOD_FITTED))
                lobe.power = glossEncodingPower(sampleMap(uGlossMap, uv).r);
#endif
        }
#endif
#if UBERSHADER || METHOD == METHOD_LEAN
        if (IS_METHOD(METHOD_LEAN)) {
            vec2 B = sampleMap(uLeanB, uv).xy;
            vec3 M = sampleMap(uLeanM, uv).xyz;
            // Olano & Baker 2010, "LEAN Mapping": Σ = M − BBᵀ (1/s already on M's diagonal)
            lobe.slope = true;
            lobe.B = B;
            lobe.cov = guardCovariance(vec3(M.x - B.x * B.x, M.y - B.y * B.y, M.z - B.x * B.y));
        }
#endif
#if UBERSHADER || METHOD == METHOD_CLEAN
        if (IS_METHOD(METHOD_CLEAN)) {
            vec3 c = sampleMap(uClean, uv).xyz;
            // Baker 2011 via Baker & Hill 2012 (CLEAN): σ² = (M_xx + M_yy)/2 − |B|²/2 (1/s included)
            float sigma2 = c.z - 0.5 * dot(c.xy, c.xy);
            lobe.slope = true;
            lobe.B = c.xy;
            lobe.cov = guardCovariance(vec3(sigma2, sigma2, 0.0));
        }
#endif
#if UBERSHADER || METHOD == METHOD_MIXTURE
        if (IS_METHOD(METHOD_MIXTURE)) {
            // Premultiplied moments, filtered by the hardware: same-index lobes merge exactly (with
            // MIXTURE_STOCHASTIC one texel of the footprint, fetched unfiltered: see below).
            lobe.mixtureLobes = MIXTURE_LOBE_COUNT;
            lobe.mixtureMinVariance = max(uMixtureMinVariance, kMinVariance);
#if defined(MIXTURE_STOCHASTIC)
            // Filtering after shading: one texel of the trilinear footprint, picked with the
            // probability of its weight (stochasticTexel), fetched unfiltered; the renderer averages
            // the passes. The level of detail is the isotropic one of the GL specification.
            ivec2 size0 = textureSize(uMixtureWeights, 0);
            vec2 texels = uv * vec2(size0);
            float rho2 = max(dot(dFdx(texels), dFdx(texels)), dot(dFdy(texels), dFdy(texels)));
            ivec3 at = stochasticTexel(uv, 0.5 * log2(max(rho2, 1e-30)), size0, uMixtureLevels,
                                       stochasticNumbers(uvec3(uvec2(gl_FragCoord.xy), uint(uStochasticSample))));
#define MIXTURE_FETCH(map) texelFetch(map, at.xy, at.z)
#else
#define MIXTURE_FETCH(map) sampleMap(map, uv)
#endif
            lobe.mixtureWeights = MIXTURE_FETCH(uMixtureWeights);
            lobe.mixtureCross = MIXTURE_FETCH(uMixtureCross);
            lobe.mixtureLobe[0] = MIXTURE_FETCH(uMixtureLobe0);
            if (lobe.mixtureLobes > 1)
                lobe.mixtureLobe[1] = MIXTURE_FETCH(uMixtureLobe1);
            if (lobe.mixtureLobes > 2)
                lobe.mixtureLobe[2] = MIXTURE_FETCH(uMixtureLobe2);
            if (lobe.mixtureLobes > 3)
                lobe.mixtureLobe[3] = MIXTURE_FETCH(uMixtureLobe3);
            // Lobes above the count and lost weights carry nothing.
            for (int i = 0; i < kMaxMixtureLobes; ++i)
                if (i >= lobe.mixtureLobes) lobe.mixtureWeights[i] = 0.0;
            lobe.mixtureWeights = max(lobe.mixtureWeights, vec4(0.0));
            // The moment-matched single lobe (LEAN's): Σ of the sums.
            float total = dot(lobe.mixtureWeights, vec4(1.0));
            vec2 wb = vec2(0.0);
            vec3 wM = vec3(0.0);
            for (int i = 0; i < kMaxMixtureLobes; ++i) {
                if (i >= lobe.mixtureLobes) continue;
                wb += lobe.mixtureLobe[i].xy;
                wM += vec3(lobe.mixtureLobe[i].zw, lobe.mixtureCross[i]);
            }
            lobe.slope = true;
            lobe.B = mixtureLobeMean(total, wb);
            lobe.cov = guardCovariance(mixtureLobeCovariance(total, wb, wM, lobe.mixtureMinVariance));
        }
#endif
        if (lobe.slope) {
            // The slope methods' normal is the one whose slope is B (core's normalOfSlope).
            lobe.n = normalOfSlope(lobe.B);
            // The equal-variance isotropic power, 1/σ²_avg, for the terms that need a power.
            lobe.power = clampPower(2.0 / (lobe.cov.x + lobe.cov.y));
            // Toksvig 2004: |Na| = 1/(1 + σ²) is the inverse of σ² = (1 − |Na|)/|Na|
            lobe.lenNa = 1.0 / (1.0 + max(0.5 * (lobe.cov.x + lobe.cov.y) - 1.0 / max(s, 1e-6), 0.0));
        } else if (!IS_METHOD(METHOD_TOKSVIG) && !IS_METHOD(METHOD_TOKSVIG_MAP)) {
            // The variance the method added over the base lobe, as |Na| (same Toksvig relation).
            float added = max(1.0 / max(lobe.power, 1e-6) - 1.0 / max(s, 1e-6), 0.0);
            lobe.lenNa = 1.0 / (1.0 + added);
        }
#if defined(HAS_DETAIL_MAP)
        if (UBER_ON(uHasDetailMap)) {
            vec4 d = sampleMap(uDetailMap, uv * uDetailUvScale);
            vec3 detailN = vec3(d.xy, sqrt(max(1.0 - dot(d.xy, d.xy), 0.0)));
            float sigma2 = max(d.w, 0.0);
            if (lobe.slope) {
                // Olano & Baker 2010: layered LEAN maps add their slopes and their variances.
                vec2 detailSlope = detailN.xy / max(detailN.z, 0.01); // kMinSlopeZ of normal_pyramid.h
                lobe.B += detailSlope;
                // A mixture's lobes each move by the detail slope: w·b += w·d, w·M += w(b d + d b + d d).
                for (int i = 0; i < kMaxMixtureLobes; ++i) {
                    float w = lobe.mixtureWeights[i];
                    vec2 b = mixtureLobeMean(w, lobe.mixtureLobe[i].xy);
                    vec2 nb = b + detailSlope;
                    lobe.mixtureLobe[i].zw += w * (nb * nb - b * b);
                    lobe.mixtureCross[i] += w * (nb.x * nb.y - b.x * b.y);
                    lobe.mixtureLobe[i].xy += w * detailSlope;
                }
                addSlopeVariance(lobe, sigma2);
                lobe.n = normalOfSlope(lobe.B);
                lobe.power = clampPower(2.0 / (lobe.cov.x + lobe.cov.y));
            } else {
                lobe.n = reorientedBlend(lobe.n, detailN);
                lobe.power = addVarianceToPower(lobe.power, sigma2);
            }
        }
#endif
    }
#endif
    return lobe;
}

struct Shading {
    vec3 diffuse;
    vec3 specular;
};

vec3 fresnelTerm(vec3 F0, float VoH) {
    if (IS_FRESNEL(FRESNEL_SCHLICK)) return fresnelSchlick(F0, VoH);
    if (IS_FRESNEL(FRESNEL_SCHLICK_SG)) return fresnelSchlickSg(F0, VoH);
    if (IS_FRESNEL(FRESNEL_SCHLICK_SG_QUADRATIC)) return fresnelSchlickSgQuadratic(F0, VoH);
    return F0;
}

// The microfacet specular D·F·V/4 and Lambert diffuse for one light of radiance `radiance` from
// direction L, in the π light units: L_o = π f c_light (n·l) (Lagarde 2012).
void shadeLight(inout Shading sh, Lobe lobe, mat3 TBN, vec3 N, vec3 V, vec3 L, vec3 radiance, vec3 F0,
                vec3 albedo) {
    float NoL = dot(N, L);
    float NoV = dot(N, V);
    vec3 H = safeNormalize(L + V, N);
    float NoH = dot(N, H);
    float VoH = saturate(dot(V, H));
    float D;
    if (lobe.slope) {
        // Olano & Baker 2010: the slope-space Gaussian about B, h in the tangent frame.
        D = slopeGaussianNdf(transpose(TBN) * H, lobe.B, lobe.cov);
    } else if (IS_NDF(NDF_BECKMANN)) {
        D = beckmannNdf(NoH, beckmannRoughnessFromPower(lobe.power));
    } else if (IS_NDF(NDF_GGX)) {
        D = ggxNdf(NoH, ggxAlphaFromPower(lobe.power));
    } else {
        D = blinnPhongNdf(NoH, lobe.power);
    }
    float Vis = 1.0;
    if (IS_VISIBILITY(VISIBILITY_KELEMEN))
        Vis = visibilityKelemen(VoH);
    else if (IS_VISIBILITY(VISIBILITY_SCHLICK_SMITH))
        Vis = visibilitySchlickSmith(NoL, NoV, lobe.power);
    else if (IS_VISIBILITY(VISIBILITY_COOK_TORRANCE))
        Vis = visibilityCookTorrance(NoL, NoV, NoH, VoH);
    else if (IS_VISIBILITY(VISIBILITY_SMITH_BECKMANN))
        Vis = visibilitySmithBeckmann(NoL, NoV, beckmannRoughnessFromPower(lobe.power));
    else if (IS_VISIBILITY(VISIBILITY_SMITH_GGX_CORRELATED))
        Vis = visibilitySmithGgxCorrelated(NoL, NoV, ggxAlphaFromPower(lobe.power));
    vec3 F = fresnelTerm(F0, VoH);
    // D·(n·l): the mixture's lobes each with their own normal (core's mixtureValue), in tangent space.
    float DNoL = 0.0;
    if (lobe.mixtureLobes > 0) {
        mat3 toTangent = transpose(TBN);
        DNoL = mixtureValue(lobe.mixtureWeights, lobe.mixtureLobe, lobe.mixtureCross, lobe.mixtureLobes,
                            toTangent * L, toTangent * H, lobe.mixtureMinVariance);
    }
    // Lazarov 2011: f = D·F·V/4; Lagarde 2012: L_o = π f c_light (n·l)
    if (lobe.mixtureLobes > 0)
        sh.specular += kPi * (DNoL * Vis * 0.25) * F * radiance;
    else
        sh.specular += kPi * (D * Vis * 0.25) * F * radiance * saturate(NoL);
#if defined(HAS_DIFFUSE)
    if (UBER_ON(uHasDiffuse)) {
        float diffuseNoL = saturate(NoL);
#if defined(HAS_DIFFUSE_AA)
        // Baker & Hill 2012: the mean of max(0, n_i·l) over the footprint's cone of normals.
        if (UBER_ON(uHasDiffuseAa)) diffuseNoL = diffuseAaCurve(NoL, lobe.lenNa);
#endif
        // Lagarde 2012: π · (albedo/π) · c_light · (n·l); the specular's share (F) is not diffused.
        sh.diffuse += albedo * (vec3(1.0) - F) * radiance * diffuseNoL;
    }
#endif
}

// A colour ramp (black → blue → green → yellow → red → white) for t in [0, 1].
vec3 heatRamp(float t) {
    t = saturate(t);
    vec3 c0 = vec3(0.0, 0.0, 0.0), c1 = vec3(0.0, 0.0, 1.0), c2 = vec3(0.0, 1.0, 0.0);
    vec3 c3 = vec3(1.0, 1.0, 0.0), c4 = vec3(1.0, 0.0, 0.0), c5 = vec3(1.0, 1.0, 1.0);
    float x = t * 5.0;
    if (x < 1.0) return mix(c0, c1, x);
    if (x < 2.0) return mix(c1, c2, x - 1.0);
    if (x < 3.0) return mix(c2, c3, x - 2.0);
    if (x < 4.0) return mix(c3, c4, x - 3.0);
    return mix(c4, c5, x - 4.0);
}

void main() {
    vec3 Ng = safeNormalize(vNormal, vec3(0.0, 0.0, 1.0));
    // Gram–Schmidt: the interpolated tangent is no longer exactly orthogonal to the normal.
    // A tangent parallel to the normal falls back to any axis not parallel to it.
    vec3 anyAxis = abs(Ng.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    vec3 T = safeNormalize(vTangent.xyz - Ng * dot(Ng, vTangent.xyz), anyAxis);
    vec3 Bt = vTangent.w * cross(Ng, T);
    mat3 TBN = mat3(T, Bt, Ng);

    Lobe lobe = materialLobe(vUv);
    vec3 N = safeNormalize(TBN * lobe.n, Ng);
    vec3 V = safeNormalize(uCameraPosition - vWorldPosition, Ng);

#if SPECULAR_AA == SPECULAR_AA_KAPLANYAN_VALIENT || UBERSHADER
    if (IS_SPECULAR_AA(SPECULAR_AA_KAPLANYAN_VALIENT)) {
        // Baker & Hill 2012 (Kaplanyan–Valient): dN = fwidth(N); curvature = sqrt(1 − n·n')
        vec3 dN = fwidth(N);
        vec3 bentN = safeNormalize(N + dN, N);
        float curvature = sqrt(saturate(1.0 - dot(bentN, N)));
        float p = kvCurvatureAdjustedPower(lobe.power, curvature);
        // The slope methods take the widening as added per-axis variance 1/p' − 1/p.
        if (lobe.slope) addSlopeVariance(lobe, max(1.0 / max(p, 1e-6) - 1.0 / max(lobe.power, 1e-6), 0.0));
        lobe.power = p;
    }
#endif
#if SPECULAR_AA == SPECULAR_AA_TOKUYOSHI_KAPLANYAN || UBERSHADER
    if (IS_SPECULAR_AA(SPECULAR_AA_TOKUYOSHI_KAPLANYAN)) {
        // Tokuyoshi & Kaplanyan 2019, "Improved Geometric Specular Antialiasing", eq. 1:
        // ᾱ² = α² + min(2σ²(‖Δn_u‖² + ‖Δn_v‖²), κ), with α² = 2/(p+2)
        vec3 du = dFdx(N);
        vec3 dv = dFdy(N);
        float p = specularAaPower(lobe.power, du, dv);
        // The slope Gaussian's per-axis variance is α²/2, so it takes half the kernel roughness.
        if (lobe.slope) addSlopeVariance(lobe, 0.5 * specularAaKernelRoughness2(normalDerivative2(du, dv)));
        lobe.power = p;
    }
#endif

    vec3 F0 = vec3(0.04);
#if defined(HAS_SPECULAR_MAP)
    if (UBER_ON(uHasSpecularMap)) F0 = saturate(sampleMap(uSpecularMap, vUv).rgb);
#if UBERSHADER
    else F0 = saturate(uSpecularColor);
#endif
#else
    F0 = saturate(uSpecularColor);
#endif
    vec3 albedo = vec3(0.0);
#if defined(HAS_DIFFUSE)
    albedo = IS_DEBUG(DEBUG_LIGHTING_ONLY) ? vec3(1.0) : saturate(uAlbedo);
#endif

    Shading sh;
    sh.diffuse = vec3(0.0);
    sh.specular = vec3(0.0);
    shadeLight(sh, lobe, TBN, N, V, safeNormalize(uLightDirection, Ng), uLightColor, F0, albedo);
#if defined(POINT_LIGHTS)
    for (int i = 0; i < POINT_LIGHTS; ++i) {
#if UBERSHADER
        if (i >= uPointLightCount) break;
#endif
        vec3 toLight = uPointLightPosition[i] - vWorldPosition;
        // Inverse-square falloff; 1e-4 (1 cm at unit scale) keeps a light inside the surface finite.
        float d2 = max(dot(toLight, toLight), 1e-4);
        shadeLight(sh, lobe, TBN, N, V, safeNormalize(toLight, Ng), uPointLightColor[i] / d2, F0, albedo);
    }
#endif
#if defined(HAS_AMBIENT)
    if (UBER_ON(uHasAmbient)) {
        // A constant environment: the specular lobe integrates to F0 in the white furnace, the
        // diffuse to the albedo times what the specular leaves.
        sh.specular += F0 * uAmbient;
#if defined(HAS_DIFFUSE)
        if (UBER_ON(uHasDiffuse)) sh.diffuse += albedo * (vec3(1.0) - F0) * uAmbient;
#endif
    }
#endif
#if defined(HAS_ENVIRONMENT_MAP)
    if (IS_ENVIRONMENT(ENVIRONMENT_PREFILTERED) || IS_ENVIRONMENT(ENVIRONMENT_FIS)) {
        // Lazarov 2011: the environment's specular is F_glossy × the lobe's mean radiance about R
        // (the value a prefiltered map stores), FRESNEL_NONE keeping F0 as for the lights.
        float NoV = saturate(dot(N, V));
        vec3 Fenv = IS_FRESNEL(FRESNEL_NONE) ? F0 : fresnelGlossy(F0, NoV, environmentFresnelGloss(lobe.power));
        vec3 Ls;
        if (IS_ENVIRONMENT(ENVIRONMENT_FIS)) {
            SpecularLobe sl;
            sl.power = lobe.power;
            sl.mean = lobe.B;
            sl.cov = lobe.cov;
            vec3 Tf, Bf;
            if (lobe.slope) {
                // The slope Gaussian lives in the surface's tangent frame about the geometric normal.
                sl.distribution = SAMPLE_LEAN;
                Ls = environmentFis(Ng, V, T, Bt, sl);
            } else {
                sl.distribution = IS_NDF(NDF_BECKMANN) ? SAMPLE_BECKMANN
                                  : IS_NDF(NDF_GGX)    ? SAMPLE_GGX
                                                       : SAMPLE_BLINN_PHONG;
                tangentFrame(N, Tf, Bf);
                Ls = environmentFis(N, V, Tf, Bf, sl);
            }
        } else {
            Ls = environmentPrefiltered(reflect(-V, N), lobe.power);
        }
        sh.specular += Fenv * Ls;
#if defined(HAS_DIFFUSE)
        // Lagarde 2012: the diffuse shows albedo·E/π of the SH irradiance; the specular's share is not diffused.
        if (UBER_ON(uHasDiffuse)) sh.diffuse += albedo * (vec3(1.0) - Fenv) * environmentDiffuse(N);
#endif
    }
#endif

    vec3 color = sh.diffuse + sh.specular;
    if (IS_DEBUG(DEBUG_DIFFUSE_ONLY)) color = sh.diffuse;
    if (IS_DEBUG(DEBUG_SPECULAR_ONLY)) color = sh.specular;
    // log2 of the power over the log2 of kMaxPower's decade range (≈ 30), grey.
    if (IS_DEBUG(DEBUG_POWER)) color = vec3(saturate(log2(max(lobe.power, 1.0)) / log2(kMaxPower)));
    if (IS_DEBUG(DEBUG_NORMALS)) color = N * 0.5 + 0.5;
    // The wrapped texture coordinate the texel lookups use, and b = 1 where the object covers the pixel
    // (the cleared background is 0): the studio's picking reads this back unclamped.
    if (IS_DEBUG(DEBUG_UV)) color = vec3(fract(vUv), 1.0);
    if (IS_DEBUG(DEBUG_VARIANCE)) {
        // Variance 1/p from kMinVariance (1e-9) to 1, as a ramp over its nine decades.
        float v = lobe.slope ? 0.5 * (lobe.cov.x + lobe.cov.y) : 1.0 / max(lobe.power, kMinVariance);
        color = heatRamp(saturate(log(max(v, kMinVariance)) / log(10.0) / 9.0 + 1.0));
    }
#if defined(HAS_NORMAL_MAP)
    if (IS_DEBUG(DEBUG_MIP_LEVEL)) {
        // The level the hardware picks: log2 of the larger texel footprint (GLSL 3.30 has no
        // textureQueryLod); 0 at magnification, ramp over 12 levels (a 4096² map).
        vec2 dx = dFdx(vUv * uNormalMapSize);
        vec2 dy = dFdy(vUv * uNormalMapSize);
        float lod = 0.5 * log2(max(max(dot(dx, dx), dot(dy, dy)), 1.0));
        color = heatRamp(lod / 12.0);
    }
#endif
#if DISPLAY_OUTPUT
    // The display pass fused into this one (the frame's view, no debug view): the same transform
    // tonemap.frag applies to the HDR target, without the target.
    fragColor = vec4(displayFromHdr(color, uExposure), 1.0);
#else
    fragColor = vec4(color, 1.0);
#endif
}
