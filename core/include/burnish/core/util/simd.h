// Four floats in one SSE/NEON register (GCC and Clang vector extensions) for core's inner loops
// (the environment prefilter, the pyramid's row filters). Arithmetic is element-wise IEEE, so a
// lane's result equals the scalar one bit for bit.
#pragma once

#include <cstring>

namespace burnish::simd {

using Float4 = float __attribute__((vector_size(16)));
using Int4 = int __attribute__((vector_size(16)));

/// Four floats from `p`, unaligned (runs may start at any texel).
inline Float4 load4(const float* p) {
    Float4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

/// `f` in every lane.
inline Float4 splat4(float f) {
    return Float4{f, f, f, f};
}

/// max(v, 0) lane by lane; a NaN lane gives 0.
inline Float4 max04(Float4 v) {
    return v > 0.0f ? v : Float4{};
}

/// (v0 + v1) + (v2 + v3): the order every caller relies on for its bits.
inline float horizontalSum(Float4 v) {
    return (v[0] + v[1]) + (v[2] + v[3]);
}

} // namespace burnish::simd
