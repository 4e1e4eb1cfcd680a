// Colour encodings: the exact sRGB transfer functions (IEC 61966-2-1), the gamma 2.0 and 2.2
// approximations that engines and the reference texts use in their place, 8-bit helpers, and a
// linear RGB triple with its Rec. 709 luminance.
// Every function here accepts any input: values are clamped to [0, 1] and NaN becomes 0, so no
// NaN or Inf can leave them.
#pragma once

#include <burnish/core/util/numeric.h>
#include <burnish/core/util/result.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string_view>

namespace burnish {

/// sRGB-encoded value in [0, 1] → linear value in [0, 1].
// IEC 61966-2-1: v <= 0.04045 ? v/12.92 : ((v + 0.055)/1.055)^2.4
// The two pieces meet within 2.3e-9 at the knee, with the power piece above: the function is
// monotone as written.
template <class T> inline T srgbToLinear(T v) {
    v = saturate(v);
    if (v <= T(0.04045)) return v / T(12.92);
    return std::pow((v + T(0.055)) / T(1.055), T(2.4));
}

/// Linear value in [0, 1] → sRGB-encoded value in [0, 1].
// IEC 61966-2-1: L <= 0.0031308 ? 12.92·L : 1.055·L^(1/2.4) − 0.055
template <class T> inline T linearToSrgb(T L) {
    L = saturate(L);
    // The standard's rounded constants leave the power piece 2.9e-8 below the linear piece at the
    // knee (0.04044991 vs 0.04044994); max() keeps the encoding monotone and moves no result by more
    // than that step, 1/136000 of an 8-bit code.
    constexpr T kKnee = T(0.0031308);
    if (L <= kKnee) return T(12.92) * L;
    // 1.055 − 0.055 rounds to 1 − ulp in binary: white must encode to exactly 1.
    if (L >= T(1)) return T(1);
    return std::max(T(1.055) * std::pow(L, T(1) / T(2.4)) - T(0.055), T(12.92) * kKnee);
}

/// 8-bit sRGB code → linear value in [0, 1] (exact transfer function, double precision).
inline double srgb8ToLinear(std::uint8_t code) {
    return srgbToLinear(double(code) / 255.0);
}

/// Linear value → nearest 8-bit sRGB code (round to nearest; NaN and values <= 0 give 0, >= 1 give
/// 255). srgb8ToLinear followed by this returns the same code for all 256 codes.
inline std::uint8_t linearToSrgb8(double L) {
    return static_cast<std::uint8_t>(std::lround(linearToSrgb(L) * 255.0));
}

/// The gamma-2.0 approximation (Lazarov 2011: Black Ops "used gamma 2.0, mix of shader & GPU
/// conversion"): encoded v → linear v², and back with √L. Inputs clamped as above.
template <class T> inline T gamma20ToLinear(T v) {
    v = saturate(v);
    return v * v;
}
template <class T> inline T linearToGamma20(T L) {
    return std::sqrt(saturate(L));
}

/// The gamma-2.2 approximation: encoded v → linear v^2.2, and back with L^(1/2.2). The linear
/// numbers quoted in Lagarde's specular chart (sRGB 40 → 0.017, 155 → 0.33) are this curve's,
/// not the exact sRGB decode (0.0212, 0.328).
template <class T> inline T gamma22ToLinear(T v) {
    return std::pow(saturate(v), T(2.2));
}
template <class T> inline T linearToGamma22(T L) {
    return std::pow(saturate(L), T(1) / T(2.2));
}

/// A linear-light RGB triple (not sRGB-encoded). Channels are whatever the producer put there;
/// functions that need [0, 1] clamp.
struct LinearRgb {
    double r = 0.0;
    double g = 0.0;
    double b = 0.0;

    static constexpr LinearRgb grey(double v) { return {v, v, v}; }
    friend constexpr bool operator==(const LinearRgb&, const LinearRgb&) = default;
};

/// An 8-bit sRGB-encoded triple.
struct Srgb8 {
    std::uint8_t r = 0;
    std::uint8_t g = 0;
    std::uint8_t b = 0;

    friend constexpr bool operator==(const Srgb8&, const Srgb8&) = default;
};

/// Relative luminance of linear Rec. 709 / sRGB primaries.
// ITU-R BT.709 (as used by IEC 61966-2-1): Y = 0.2126 R + 0.7152 G + 0.0722 B
constexpr double luminance(const LinearRgb& c) {
    return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
}

/// A linear colour as typed: "R,G,B", or one value for a grey, each a whole number, finite, in [0, 1].
/// Errors name `option` and the field ("--check '0.5,x': 'x' is not a number").
Result<LinearRgb> parseLinearRgb(std::string_view text, std::string_view option);

/// Each channel through linearToSrgb8.
inline Srgb8 toSrgb8(const LinearRgb& c) {
    return {linearToSrgb8(c.r), linearToSrgb8(c.g), linearToSrgb8(c.b)};
}

/// Each channel through srgb8ToLinear.
inline LinearRgb toLinear(const Srgb8& c) {
    return {srgb8ToLinear(c.r), srgb8ToLinear(c.g), srgb8ToLinear(c.b)};
}

} // namespace burnish
