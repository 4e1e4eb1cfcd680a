// Four floats in one SSE/NEON register (GCC and Clang vector extensions) for core's inner loops
// (the environment prefilter, the pyramid's row filters), and eight in one AVX register or two SSE
// ones. Arithmetic is element-wise IEEE, so a lane's result equals the scalar one bit for bit, and a
// function compiled twice (target_clones, see BURNISH_AVX2_CLONES) gives the same bits in both copies.
#pragma once

#include <cstdint>
#include <cstring>

// GCC notes that a 32-byte vector passed by value has another ABI with AVX than without. Float8 and
// Double4 values pass only into always-inlined functions inside a target_clones copy, never through a
// call between code built for different targets. When a change made GCC emit log2Positive<Double4>
// out of line (with that note) and call it from the AVX2 copy, the mixture's 1×1 lobes of a 4096² map
// changed; inlined, they are the same bits. Every function taking these types is always inlined.
#if defined(__GNUC__) // GCC, and Clang (which defines __GNUC__ and has the same warning)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace burnish::simd {

using Float4 = float __attribute__((vector_size(16)));
using Int4 = int __attribute__((vector_size(16)));
using Float8 = float __attribute__((vector_size(32)));
using Int8 = int __attribute__((vector_size(32)));
using UInt8 = unsigned __attribute__((vector_size(32)));
/// Four doubles (one AVX register, two SSE ones) and their bits; a comparison gives an Int64x4 mask.
using Double4 = double __attribute__((vector_size(32)));
using UInt64x4 = std::uint64_t __attribute__((vector_size(32)));
using Int64x4 = std::int64_t __attribute__((vector_size(32)));

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
// An AVX2 copy of a function beside the default (SSE2) one, picked when the program loads on CPUs that
// have it. FMA is not enabled (it is not part of "avx2"), so no multiply-add is fused: both copies do
// the same IEEE operations lane by lane and give the same bits.
#define BURNISH_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
// An AVX-512 copy too, for loops of doubles (evaluate's lobe values). Core is built with
// -ffp-contract=off, so this copy fuses no multiply-add either: every copy, run, thread count and
// heap layout gives the same bits.
#define BURNISH_AVX512_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define BURNISH_AVX2_CLONES
#define BURNISH_AVX512_CLONES
#endif

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

/// 2^x lane by lane for x in [−125, 0], within 1.4e-7 (relative) of the exact value. Other x give
/// unspecified values (callers drop those lanes). No calls, no branches.
// Cephes exp2f (Moshier): 2^x = 2^k (1 + f P(f)), k = round(x), |f| <= 1/2; P by Estrin's scheme
// (a shorter chain of dependent operations than Horner's). Always inlined (see the -Wpsabi note above).
[[gnu::always_inline]] inline Float8 exp2NonPositive(Float8 x) {
    // Adding 1.5·2^23 rounds x to the nearest integer k, which lands in the sum's low mantissa bits.
    constexpr float kRound = 12582912.0f;
    constexpr unsigned kRoundBits = 0x4B400000u; // the bits of 1.5·2^23
    const Float8 t = x + kRound;
    const Float8 f = x - (t - kRound);
    UInt8 bits;
    std::memcpy(&bits, &t, sizeof t);
    // 2^k as a float: the biased exponent k + 127 in bits 23..30 (unsigned: no overflow out of range).
    bits = (bits - (kRoundBits - 127u)) << 23;
    Float8 scale;
    std::memcpy(&scale, &bits, sizeof scale);
    const Float8 f2 = f * f;
    const Float8 p = ((6.931472028550421e-1f + 2.402264791363012e-1f * f) +
                      f2 * (5.550332471162809e-2f + 9.618437357674640e-3f * f)) +
                     (f2 * f2) * (1.339887440266574e-3f + 1.535336188319500e-4f * f);
    return (1.0f + f * p) * scale;
}

} // namespace burnish::simd
