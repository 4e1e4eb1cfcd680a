// Constants and guarded elementary functions shared by every shading snippet: the GLSL twin of
// core/include/burnish/core/util/numeric.h (same names, same guards, float instead of double).

const float kPi = 3.14159265358979;
const float kInvPi = 0.318309886183791;
const float kLn2 = 0.693147180559945;

// Largest specular power any function produces or accepts (numeric.h: keeps (n+2)/(2π) and 1/n
// normal floats).
const float kMaxPower = 1e9;
// Smallest variance: the variance of kMaxPower under the 1/n convention.
const float kMinVariance = 1e-9;
// Cosines below this are treated as this in divisions: bounds 1/cos at 1e6 (numeric.h).
const float kMinCosine = 1e-6;

// Clamps to [0, 1]; NaN becomes 0 (a NaN fails x > 0), unlike GLSL's clamp, which may keep it.
float saturate(float x) {
    return x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0;
}

vec3 saturate(vec3 x) {
    return vec3(saturate(x.x), saturate(x.y), saturate(x.z));
}

// Clamps a power to [0, kMaxPower]; NaN becomes 0.
float clampPower(float n) {
    return n > 0.0 ? min(n, kMaxPower) : 0.0;
}

// True when x is neither NaN nor infinite.
bool isFinite(float x) {
    return !isnan(x) && !isinf(x);
}

// log(c) for c in (0, 1], accurate to a few float ULPs of the result also near c = 1, where GLSL
// allows log() an absolute error of 2^-21: times a power of 1e6 that would be an error of ~0.5 in
// n·log c. Above 0.75, c − 1 is exact (Sterbenz) and log(1+u) = 2 atanh(u/(2+u)) converges fast.
// Abramowitz & Stegun 1964, eq. 4.1.27: ln z = 2 (t + t³/3 + t⁵/5 + ...), t = (z−1)/(z+1)
float logCos(float c) {
    if (c > 0.75) {
        float u = c - 1.0;
        float t = u / (2.0 + u);
        float t2 = t * t;
        // |t| <= 1/7, so the first omitted term t^13/13 is below 1e-12 of t.
        return 2.0 * t *
               (1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0 + t2 * (1.0 / 9.0 + t2 / 11.0)))));
    }
    return log(c);
}

// max(c, 0)^n as exp(n·log c): 1 for n == 0 (also at c == 0), 0 for c <= 0 and n > 0, never NaN.
float powCos(float c, float n) {
    n = clampPower(n);
    if (n == 0.0) return 1.0;
    if (!(c > 0.0)) return 0.0;
    if (c >= 1.0) return 1.0;
    return exp(n * logCos(c));
}

// x^p for x in [0, 1] and p >= 0 (Fresnel-style powers), never NaN: 0^0 = 1, 0^p = 0.
float powUnit(float x, float p) {
    return powCos(x, p);
}
