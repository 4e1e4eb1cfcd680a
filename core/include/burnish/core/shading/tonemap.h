// Display tone curves: scene-linear HDR values to display-linear [0, 1], before the sRGB encoding.
// The GLSL twin is tonemapFilmic in resources/shaders/common_color.glsl.
#pragma once

#include <algorithm>

namespace burnish {

/// Filmic tone curve (the ACES RRT+ODT fit): scene-linear x >= 0 → display-linear [0, 1].
/// Monotone, tonemapFilmic(0) = 0; negative and NaN inputs give 0, +Inf and anything above ~7.24
/// give 1. Never NaN or Inf.
// Narkowicz 2015, "ACES Filmic Tone Mapping Curve": x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)
template <class T> T tonemapFilmic(T x) {
    // NaN fails the comparison: black, like negative light.
    if (!(x > T(0))) return T(0);
    // The saturated curve reaches 1 at x ≈ 7.24 and stays there: clamping at 64 changes no result
    // and keeps x² far from overflow (float) for huge inputs and Inf.
    x = std::min(x, T(64));
    const T y = (x * (T(2.51) * x + T(0.03))) / (x * (T(2.43) * x + T(0.59)) + T(0.14));
    return std::min(y, T(1));
}

} // namespace burnish
