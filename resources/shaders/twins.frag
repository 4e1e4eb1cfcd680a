// Evaluates one group of GLSL twins of core's shading math per pixel, for tests/render/test_twins.cpp:
// `#define TWIN <n>` picks the group; each pixel reads its arguments from two RGBA32F textures
// (uInputs, uInputs2, texelFetch at the pixel) and writes up to four results to an RGBA32F target.
#include "common_math.glsl"
#include "brdf_ndf.glsl"
#include "brdf_fresnel.glsl"
#include "brdf_visibility.glsl"
#include "brdf_sg.glsl"
#include "geometric_aa.glsl"
#include "gloss.glsl"
#include "methods.glsl"

#define TWIN_IDENTITY 0
#define TWIN_NUMERIC 1
#define TWIN_NDF_NORM_A 2
#define TWIN_NDF_NORM_B 3
#define TWIN_NDF 4
#define TWIN_NDF_BRIDGE 5
#define TWIN_FRESNEL_A 6
#define TWIN_FRESNEL_B 7
#define TWIN_FRESNEL_IOR 8
#define TWIN_VISIBILITY_A 9
#define TWIN_VISIBILITY_B 10
#define TWIN_SG 11
#define TWIN_GEOMETRIC_AA_A 12
#define TWIN_GEOMETRIC_AA_B 13
#define TWIN_SPECULAR_AA 14
#define TWIN_SPECULAR_AA_DERIVATIVES 15
#define TWIN_GLOSS 16
#define TWIN_TOKSVIG 17
#define TWIN_METHOD_POWERS 18
#define TWIN_LEAN_CLEAN 19
#define TWIN_SLOPE_NDF 20
#define TWIN_ISOTROPIC_NDF 21
#define TWIN_MIXTURE_LOBE 22
#define TWIN_MIXTURE_VALUE 23
#define TWIN_STOCHASTIC_TEXEL 24
#define TWIN_STOCHASTIC_NUMBERS 25
#define TWIN_GGX_SPECULAR 26
#define TWIN_GGX_ANISOTROPIC 27
// 30..38: the vec3 (RGB specular colour) overloads of brdf_fresnel.glsl, one per twin.
#define TWIN_FRESNEL_RGB_FIRST 30
#define TWIN_FRESNEL_RGB_LAST 38

#ifndef TWIN
#error "twins.frag needs TWIN defined"
#endif

uniform sampler2D uInputs;
uniform sampler2D uInputs2;

out vec4 fragColor;

vec4 twin(vec4 a, vec4 b) {
#if TWIN == TWIN_IDENTITY
    return a + b; // the test fills uInputs2 with zeros: a round trip of uInputs
#elif TWIN == TWIN_NUMERIC
    return vec4(powCos(a.x, a.y), powUnit(a.x, a.y), saturate(a.z), clampPower(a.w));
#elif TWIN == TWIN_NDF_NORM_A
    return vec4(blinnPhongNdfNorm(a.x), phongLobeNorm(a.x), phongBrdfNorm(a.x), blinnPhongLobeNorm(a.x));
#elif TWIN == TWIN_NDF_NORM_B
    return vec4(blinnPhongBrdfNorm(a.x), blinnPhongBrdfNormApprox(a.x), beckmannRoughnessFromPower(a.x),
                ggxAlphaFromPower(a.x));
#elif TWIN == TWIN_NDF
    return vec4(blinnPhongNdf(a.x, a.y), beckmannNdf(a.x, a.z), ggxNdf(a.x, a.w), lambertBrdf());
#elif TWIN == TWIN_NDF_BRIDGE
    return vec4(powerFromBeckmannRoughness(a.x), powerFromGgxAlpha(a.x), punctualRadiance(a.y, a.z, a.w), 0.0);
#elif TWIN == TWIN_FRESNEL_A
    // a = (c, x, p, g)
    return vec4(fresnelSchlick(a.x, a.y), fresnelSchlickPow(a.x, a.y, a.z), fresnelGlossy(a.x, a.y, a.w),
                fresnelSchlickSg(a.x, a.y));
#elif TWIN == TWIN_FRESNEL_B
    // a = (c, x, k, qa), b.x = qb
    return vec4(fresnelSchlickSg(a.x, a.y, a.z), fresnelSchlickSgQuadratic(a.x, a.y),
                fresnelSchlickSgQuadratic(a.x, a.y, a.w, b.x), fresnelDielectric(a.x, a.y));
#elif TWIN == TWIN_FRESNEL_IOR
    return vec4(iorFromF0(a.x), 0.0, 0.0, 0.0);
#elif TWIN >= TWIN_FRESNEL_RGB_FIRST && TWIN <= TWIN_FRESNEL_RGB_LAST
    // a = (F0.rgb, x), b = (p, g, k, _) or, for the explicit quadratic, b = (qa, qb, _, _)
#if TWIN == TWIN_FRESNEL_RGB_FIRST + 0
    return vec4(fresnelSchlick(a.xyz, a.w), 0.0);
#elif TWIN == TWIN_FRESNEL_RGB_FIRST + 1
    return vec4(fresnelSchlickPow(a.xyz, a.w, b.x), 0.0);
#elif TWIN == TWIN_FRESNEL_RGB_FIRST + 2
    return vec4(fresnelGlossy(a.xyz, a.w, b.y), 0.0);
#elif TWIN == TWIN_FRESNEL_RGB_FIRST + 3
    return vec4(fresnelSchlickSg(a.xyz, a.w), 0.0);
#elif TWIN == TWIN_FRESNEL_RGB_FIRST + 4
    return vec4(fresnelSchlickSg(a.xyz, a.w, b.z), 0.0);
#elif TWIN == TWIN_FRESNEL_RGB_FIRST + 5
    return vec4(fresnelSchlickSgQuadratic(a.xyz, a.w), 0.0);
#elif TWIN == TWIN_FRESNEL_RGB_FIRST + 6
    return vec4(fresnelSchlickSgQuadratic(a.xyz, a.w, b.x, b.y), 0.0);
#elif TWIN == TWIN_FRESNEL_RGB_FIRST + 7
    return vec4(iorFromF0(a.xyz), 0.0);
#else
    return vec4(fresnelDielectric(a.xyz, a.w), 0.0);
#endif
#elif TWIN == TWIN_VISIBILITY_A
    // a = (NoL, NoV, n, VoH)
    return vec4(visibilityNone(), visibilityKelemen(a.w), schlickSmithA(a.z), visibilitySchlickSmith(a.x, a.y, a.z));
#elif TWIN == TWIN_VISIBILITY_B
    // a = (NoL, NoV, NoH, VoH), b = (m, alpha, _, _)
    return vec4(visibilityCookTorrance(a.x, a.y, a.z, a.w), smithBeckmannG1(a.x, b.x),
                visibilitySmithBeckmann(a.x, a.y, b.x), visibilitySmithGgxCorrelated(a.x, a.y, b.y));
#elif TWIN == TWIN_SG
    // a = (c, n, x, A)
    return vec4(sgLobe(a.x, a.y, a.z), sgLobeExp2(a.x, a.w), 0.0, 0.0);
#elif TWIN == TWIN_GEOMETRIC_AA_A
    // a = (lenNa, cosAlpha, n, curvature)
    return vec4(coneCosFromNormalLength(a.x), diffuseAaCurve(a.y, a.x), kvConeAngleFromPower(a.z),
                kvCurvatureAdjustedPower(a.z, a.w));
#elif TWIN == TWIN_GEOMETRIC_AA_B
    // a = (angle, n, c0, c1), b = (cosAlpha, lenNa, k, k2)
    return vec4(kvPowerFromConeAngle(a.x), diffuseAaCurve(b.x, b.y, a.z, a.w), kvConeAngleFromPower(a.y, b.z),
                kvPowerFromConeAngle(a.x, b.w));
#elif TWIN == TWIN_SPECULAR_AA
    // a = (dndx, alpha), b = (dndy, n)
    return vec4(specularAaGgxAlpha(a.w, a.xyz, b.xyz), specularAaBeckmannM(a.w, a.xyz, b.xyz),
                specularAaPower(b.w, a.xyz, b.xyz), specularAaKernelRoughness2(normalDerivative2(a.xyz, b.xyz)));
#elif TWIN == TWIN_SPECULAR_AA_DERIVATIVES
    // a = (gx, gy, gz, alpha), b.x = n, constant over each 2×2 quad: the normal field
    // (gx·x, gy·y, gz) has dFdx = (gx, 0, 0) and dFdy = (0, gy, 0) exactly (coarse or fine).
    vec3 normal = vec3(a.x * gl_FragCoord.x, a.y * gl_FragCoord.y, a.z);
    return vec4(specularAaGgxAlpha(a.w, normal), specularAaBeckmannM(a.w, normal), specularAaPower(b.x, normal),
                0.0);
#elif TWIN == TWIN_GLOSS
    // a = (v, n, g, variance), b = (kind, nMin, nMax, _)
    int kind = int(b.x);
    return vec4(glossToPower(a.x, kind, b.y, b.z), powerToGloss(a.y, kind, b.y, b.z),
                varianceToGloss(a.z, a.w, kind, b.y, b.z), 0.0);
#elif TWIN == TWIN_TOKSVIG
    // a = (lenNa, s, ft, fixedS)
    return vec4(toksvigVariance(a.x), toksvigFactor(a.x, a.y), toksvigPower(a.x, a.y),
                convertToksvigFactor(a.z, a.w, a.y));
#elif TWIN == TWIN_METHOD_POWERS
    // a = (lenNa, s, ft, fixedS), b.x = projected variance v
    return vec4(toksvigMapPower(a.z, a.w, a.y), varianceToGlossPower(b.x, a.y), vmfKappa(a.x), vmfPower(a.x, a.y));
#elif TWIN == TWIN_LEAN_CLEAN
    // a = (B, s, mIso), b = (M.xx, M.yy, M.xy, _)
    return vec4(leanCovariance(a.xy, b.xyz, a.z), cleanVariance(a.xy, a.w, a.z));
#elif TWIN == TWIN_SLOPE_NDF
    // a = (h, B.x), b = (B.y, cov.xx, cov.yy, cov.xy)
    return vec4(slopeGaussianNdf(a.xyz, vec2(a.w, b.x), b.yzw), 0.0, 0.0, 0.0);
#elif TWIN == TWIN_ISOTROPIC_NDF
    // a = (normal, power), b = (h, _); also the LEAN lobe normal of slope a.xy
    return vec4(isotropicLobeNdf(a.xyz, a.w, b.xyz), normalOfSlope(a.xy));
#elif TWIN == TWIN_MIXTURE_LOBE
    // a = (w, wb.x, wb.y, wM.xx), b = (wM.yy, wM.xy, minVariance, _): the lobe's covariance and mean.x
    // (mean.y is the channel-swapped case, a.yz = (wb.y, wb.x), in the test)
    return vec4(mixtureLobeCovariance(a.x, a.yz, vec3(a.w, b.x, b.y), b.z), mixtureLobeMean(a.x, a.yz).x);
#elif TWIN == TWIN_STOCHASTIC_TEXEL
    // a = (uv, lod, levels), b = (xi, size0.x + 4096·size0.y): the texel and level picked
    ivec3 t = stochasticTexel(a.xy, a.z, ivec2(int(b.w) % 4096, int(b.w) / 4096), int(a.w), b.xyz);
    return vec4(vec3(t), 0.0);
#elif TWIN == TWIN_GGX_SPECULAR
    // a = (NoH, NoL, NoV, alpha)
    return vec4(ggxSpecularTerm(a.x, a.y, a.z, a.w), ggxSpecularAlpha(a.w), 0.0, 0.0);
#elif TWIN == TWIN_GGX_ANISOTROPIC
    // a = (v.xy, l.xy), b = (n.xy, alpha_t, alpha_b): unit v and l above the plane, n = normalize(n.xy, 1),
    // the geometric frame t = x, b = y (not orthonormal to n, as an engine forms it), h = normalize(l + v).
    vec3 v = vec3(a.xy, sqrt(max(1.0 - dot(a.xy, a.xy), 0.0)));
    vec3 l = vec3(a.zw, sqrt(max(1.0 - dot(a.zw, a.zw), 0.0)));
    vec3 n = normalize(vec3(b.xy, 1.0));
    vec3 h = normalize(l + v);
    return vec4(ggxAnisotropicSpecularTerm(dot(n, h), h.x, h.y, dot(n, l), l.x, l.y, dot(n, v), v.x, v.y, b.z, b.w),
                0.0, 0.0, 0.0);
#elif TWIN == TWIN_STOCHASTIC_NUMBERS
    // a = (x, y, sample, _): the three numbers of pixel (x, y) and that sample
    return vec4(stochasticNumbers(uvec3(a.xyz)), 0.0);
#elif TWIN == TWIN_MIXTURE_VALUE
    // a = (l, t), b = (h, minVariance): a four-lobe mixture spread by t, built as the test builds it;
    // its value with all four lobes and with the first two.
    vec4 weights = vec4(0.1, 0.2, 0.3, 0.4);
    vec4 lobe[kMaxMixtureLobes];
    vec4 crossM;
    for (int i = 0; i < kMaxMixtureLobes; ++i) {
        float w = weights[i];
        vec2 m = a.w * vec2(float(i) - 1.5, 0.5 * float(i) - 0.7);
        float v = 0.01 * float(i + 1);
        lobe[i] = vec4(w * m, w * (v + m.x * m.x), w * (2.0 * v + m.y * m.y));
        crossM[i] = w * (0.3 * v + m.x * m.y);
    }
    return vec4(mixtureValue(weights, lobe, crossM, 4, a.xyz, b.xyz, b.w),
                mixtureValue(weights, lobe, crossM, 2, a.xyz, b.xyz, b.w), 0.0, 0.0);
#else
#error "unknown TWIN"
#endif
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    fragColor = twin(texelFetch(uInputs, pixel, 0), texelFetch(uInputs2, pixel, 0));
}
