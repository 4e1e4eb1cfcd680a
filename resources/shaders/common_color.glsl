// Colour encodings and the display tone curve: the GLSL twins of core/include/burnish/core/shading/color.h
// (srgbToLinear, linearToSrgb) and core/include/burnish/core/shading/tonemap.h (tonemapFilmic). Same names,
// same clamping: every function accepts any input and returns values in [0, 1].

// Clamps to [0, 1]; NaN becomes 0 (the comparison fails), as core's saturate (util/numeric.h).
float clamp01(float x) {
    return x > 0.0 ? min(x, 1.0) : 0.0;
}

vec3 clamp01(vec3 x) {
    return vec3(clamp01(x.r), clamp01(x.g), clamp01(x.b));
}

// sRGB-encoded value in [0, 1] → linear value in [0, 1].
// IEC 61966-2-1: v <= 0.04045 ? v/12.92 : ((v + 0.055)/1.055)^2.4
float srgbToLinear(float v) {
    v = clamp01(v);
    if (v <= 0.04045) return v / 12.92;
    return pow((v + 0.055) / 1.055, 2.4);
}

vec3 srgbToLinear(vec3 v) {
    return vec3(srgbToLinear(v.r), srgbToLinear(v.g), srgbToLinear(v.b));
}

// Linear value in [0, 1] → sRGB-encoded value in [0, 1].
// IEC 61966-2-1: L <= 0.0031308 ? 12.92·L : 1.055·L^(1/2.4) − 0.055
float linearToSrgb(float L) {
    L = clamp01(L);
    // The knee of the piecewise curve; below it the linear piece (pow(0, x) is avoided there).
    const float kKnee = 0.0031308;
    if (L <= kKnee) return 12.92 * L;
    // White encodes to exactly 1 (1.055 − 0.055 is not 1 in binary).
    if (L >= 1.0) return 1.0;
    // max(): the power piece dips 2.9e-8 below the linear piece at the knee; keeps it monotone.
    return max(1.055 * pow(L, 1.0 / 2.4) - 0.055, 12.92 * kKnee);
}

vec3 linearToSrgb(vec3 L) {
    return vec3(linearToSrgb(L.r), linearToSrgb(L.g), linearToSrgb(L.b));
}

// Filmic display curve: scene-linear HDR value (>= 0) → display-linear value in [0, 1].
// Narkowicz 2015, "ACES Filmic Tone Mapping Curve": x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)
float tonemapFilmic(float x) {
    // Negative and NaN inputs are black. The saturated curve reaches 1 at x ≈ 7.24 and stays
    // there, so clamping at 64 changes nothing and keeps x² far from float overflow.
    x = x > 0.0 ? min(x, 64.0) : 0.0;
    return clamp01((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14));
}

vec3 tonemapFilmic(vec3 x) {
    return vec3(tonemapFilmic(x.r), tonemapFilmic(x.g), tonemapFilmic(x.b));
}

// HDR → display, the one display transform (tonemap.frag's pass, and material.frag's fused output):
// exposure (a linear scale, 2^EV computed on the CPU), the filmic curve, the sRGB encoding.
vec3 displayFromHdr(vec3 hdr, float exposure) {
    return linearToSrgb(tonemapFilmic(hdr * exposure));
}
