// Gloss encodings (what a texture channel stores ↔ Blinn-Phong power): the GLSL twin of
// GlossEncoding::power/value and varianceToGloss in core/include/burnish/core/prefilter/gloss.h. kind is
// int(GlossKind); nMin and nMax are used by GLOSS_KIND_LOG_POWER only.
#include "common_math.glsl"
#include "brdf_ndf.glsl"

// int(burnish::GlossKind), in the enum's order.
#define GLOSS_KIND_LOG_POWER 0
#define GLOSS_KIND_GGX_ROUGHNESS 1
#define GLOSS_KIND_GGX_ALPHA 2
#define GLOSS_KIND_BECKMANN_M 3
#define GLOSS_KIND_SMOOTHNESS 4

// Power of a roughness α (GGX α or Beckmann m), α at least the roughness of kMaxPower (gloss.cpp).
float glossPowerFromAlpha(float alpha) {
    return powerFromGgxAlpha(max(alpha, kMinRoughness));
}

// Power for a stored value v (clamped to [0, 1]; NaN → 0), as GlossEncoding::power.
// LogPower: n = nMin·(nMax/nMin)^v (Lazarov 2011: 8192^g; Lagarde 2011: exp2(10g+1))
float glossToPower(float v, int kind, float nMin, float nMax) {
    v = saturate(v);
    if (kind == GLOSS_KIND_LOG_POWER) return clampPower(nMin * exp2(v * log2(nMax / nMin)));
    if (kind == GLOSS_KIND_GGX_ROUGHNESS) return glossPowerFromAlpha(v * v);
    if (kind == GLOSS_KIND_SMOOTHNESS) return glossPowerFromAlpha((1.0 - v) * (1.0 - v));
    return glossPowerFromAlpha(v); // GLOSS_KIND_GGX_ALPHA, GLOSS_KIND_BECKMANN_M
}

// Lowest and highest power of an encoding (GlossEncoding::minPower/maxPower).
float glossMinPower(int kind, float nMin) {
    return kind == GLOSS_KIND_LOG_POWER ? nMin : 0.0;
}

float glossMaxPower(int kind, float nMax) {
    return kind == GLOSS_KIND_LOG_POWER ? nMax : glossPowerFromAlpha(kMinRoughness);
}

// Stored value for a power (clamped to the encoding's range), as GlossEncoding::value.
float powerToGloss(float n, int kind, float nMin, float nMax) {
    n = clamp(clampPower(n), glossMinPower(kind, nMin), glossMaxPower(kind, nMax));
    if (kind == GLOSS_KIND_LOG_POWER) return saturate(log2(n / nMin) / log2(nMax / nMin));
    float alpha = ggxAlphaFromPower(n);
    if (kind == GLOSS_KIND_GGX_ROUGHNESS) return saturate(sqrt(alpha));
    if (kind == GLOSS_KIND_SMOOTHNESS) return saturate(1.0 - sqrt(alpha));
    return saturate(alpha); // GLOSS_KIND_GGX_ALPHA, GLOSS_KIND_BECKMANN_M
}

// Lazarov 2011: v' = v + 1/(n+1); v'' = clamp(v', 1/(nMax+1), 1/(nMin+1)); back to gloss
float varianceToGloss(float g, float v, int kind, float nMin, float nMax) {
    float n = glossToPower(g, kind, nMin, nMax);
    v = saturate(v); // the projected variance 1 − (n_i·n̄)² lies in [0, 1]
    float vSum = v + 1.0 / (n + 1.0);
    float vClamped =
        clamp(vSum, 1.0 / (glossMaxPower(kind, nMax) + 1.0), 1.0 / (glossMinPower(kind, nMin) + 1.0));
    return powerToGloss(1.0 / vClamped - 1.0, kind, nMin, nMax);
}
