// Low-discrepancy sequences: the radical inverse (van der Corput) that the Hammersley directions of
// the environment's filtered importance sampling and the Halton jitter of the renderer's reference
// both use.
#pragma once

#include <cstdint>

namespace burnish {

/// Radical inverse of i in `base` (>= 2): the base-`base` digits of i mirrored about the point,
/// in [0, 1). Exact in double for base 2 (a sum of distinct powers of two).
// Halton 1960; Pharr, Jakob, Humphreys, "Physically Based Rendering" §8.6: Φ_b(i) = Σ d_k b^(−k−1)
inline double radicalInverse(std::uint32_t i, std::uint32_t base) {
    double f = 1.0, r = 0.0;
    for (; i > 0; i /= base) {
        f /= base;
        r += f * double(i % base);
    }
    return r;
}

/// radicalInverse(i, 2) by reversing the bits of i (the same value, bit for bit).
inline double radicalInverse2(std::uint32_t i) {
    i = (i << 16u) | (i >> 16u);
    i = ((i & 0x55555555u) << 1u) | ((i & 0xAAAAAAAAu) >> 1u);
    i = ((i & 0x33333333u) << 2u) | ((i & 0xCCCCCCCCu) >> 2u);
    i = ((i & 0x0F0F0F0Fu) << 4u) | ((i & 0xF0F0F0F0u) >> 4u);
    i = ((i & 0x00FF00FFu) << 8u) | ((i & 0xFF00FF00u) >> 8u);
    return double(i) * 2.3283064365386963e-10; // 2^-32
}

} // namespace burnish
