// Spherical-Gaussian approximations of cosine-power lobes: the GLSL twin of
// core/include/burnish/core/shading/spherical_gaussian.h (the fitted offset curve stays on the CPU; pass
// its value for the material's power as x).
#include "common_math.glsl"

// Lagarde 2012, "Spherical Gaussian approximation for Blinn-Phong, Phong and Fresnel": plain SG
// (Wang et al. 2009), the mean best fit over powers 3..15, and the large-power limit of the fit.
const float kSgOffsetPlain = 0.0;
const float kSgOffsetLagarde = 0.775;
const float kSgOffsetLimit = 0.75;

// Lagarde 2012 (after Wang et al. 2009): c^n ≈ exp((n + x)(c − 1)), 0 for c <= 0
float sgLobe(float c, float n, float x) {
    if (!(c > 0.0)) return 0.0;
    float k = clampPower(n) + x;
    return exp(max(k, 0.0) * (min(c, 1.0) - 1.0));
}

// Lagarde 2012, GPU form: exp2(A·c − A), A = (n + x)/ln 2 ("ModifiedSpecularPower"). Written as
// A·(c − 1): the same value, but A·c − A in float cancels away the exponent at high powers
// (A = 1.4e9 rounds A·c to a multiple of 128), while c − 1 is exact for c >= 0.5.
float sgLobeExp2(float c, float modifiedPower) {
    if (!(c > 0.0)) return 0.0;
    // A clamped like every power: NaN and negative → 0 (a negative A would raise the lobe above 1).
    float A = modifiedPower > 0.0 ? min(modifiedPower, kMaxPower / kLn2) : 0.0;
    return exp2(A * (min(c, 1.0) - 1.0));
}
