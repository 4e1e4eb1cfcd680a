// The cube's face frames, area element, texel fetches and face-size check shared by env/cube.cpp and
// env/prefilter.cpp (private to core).
#pragma once

#include <burnish/core/env/cube.h>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace burnish::cubeface {

using glm::dvec3;

/// The face's frame: direction = axis + sc·u + tc·v for sc, tc ∈ [−1, 1].
// OpenGL 4.6, table 8.19 (cube map face selection), inverted
struct FaceFrame {
    dvec3 axis, u, v;
};
inline constexpr std::array<FaceFrame, kCubeFaces> kFrames{{
    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},  // +X: sc = −z, tc = −y
    {{-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},  // −X: sc = +z, tc = −y
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},    // +Y: sc = +x, tc = +z
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},  // −Y: sc = +x, tc = −z
    {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}},   // +Z: sc = +x, tc = −y
    {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}}, // −Z: sc = −x, tc = −y
}};

inline dvec3 facePoint(int face, double sc, double tc) {
    const FaceFrame& f = kFrames[size_t(face)];
    return f.axis + sc * f.u + tc * f.v;
}

/// Finite and non-negative, or 0.
inline float sanitize(float x, std::uint64_t& replaced) {
    if (std::isfinite(x) && x >= 0.0f) return x;
    ++replaced;
    return 0.0f;
}

// Integral of the face's area element from the face centre to (x, y).
// Driscoll 2012 / cmft: ∫∫ (1 + x² + y²)^(−3/2) dx dy = atan2(xy, sqrt(x² + y² + 1))
inline double areaElement(double x, double y) {
    return std::atan2(x * y, std::sqrt(x * x + y * y + 1.0));
}

/// A texel's solid angle from the area element at its corners (x0, y0), (x0, y1), (x1, y0), (x1, y1).
inline double solidAngleFromCorners(double a00, double a01, double a10, double a11) {
    return a00 - a01 - a10 + a11;
}

inline glm::dvec3 fetch(const CubeLevel& level, int face, int x, int y) {
    const float* p = level.texel(face, x, y);
    return {p[0], p[1], p[2]};
}

/// Texel (x, y) of `face`, where x or y may lie one texel beyond the face: read from the face the
/// texel centre's direction falls on.
inline glm::dvec3 fetchSeamless(const CubeLevel& level, int face, int x, int y) {
    const int n = level.size;
    if (x >= 0 && y >= 0 && x < n && y < n) return fetch(level, face, x, y);
    const double sc = 2.0 * (x + 0.5) / n - 1.0;
    const double tc = 2.0 * (y + 0.5) / n - 1.0;
    const CubeCoord c = cubeCoord(facePoint(face, sc, tc));
    const int xi = std::clamp(int(c.s * n), 0, n - 1);
    const int yi = std::clamp(int(c.t * n), 0, n - 1);
    return fetch(level, c.face, xi, yi);
}

inline Status checkFaceSize(int faceSize) {
    // 65536 texels per side would already be 100 GiB of float faces; 16384 keeps a chain below 8 GiB.
    constexpr int kMaxFaceSize = 16384;
    if (!isPowerOfTwo(faceSize) || faceSize > kMaxFaceSize)
        return Error{
            fmt::format("cube face size {} must be a power of two in [1, {}]", faceSize, kMaxFaceSize)};
    return {};
}

} // namespace burnish::cubeface
