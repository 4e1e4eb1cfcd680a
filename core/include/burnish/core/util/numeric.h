// Constants and guarded elementary functions shared by every shading formula.
// Everything here is header-only and templated on the float type so the same code
// serves double-precision references and float kernels that the compiler can vectorize.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

namespace burnish {

template <class T> inline constexpr T kPi = T(3.141592653589793238462643383279502884L);
template <class T> inline constexpr T kInvPi = T(0.318309886183790671537767526745028724L);
template <class T> inline constexpr T kLn2 = T(0.693147180559945309417232121458176568L);

/// Degrees to radians, deg·π/180 (evaluate's direction sets and the shaded fit's training pairs).
inline double radians(double deg) {
    return deg * kPi<double> / 180.0;
}

/// Largest specular power any Burnish function produces or accepts; larger inputs are clamped.
/// 1e9 keeps the normalized Blinn-Phong peak (n+2)/(2π) ≈ 1.6e8 far from float overflow and
/// its reciprocal (a variance of 1e-9) a normal float.
inline constexpr double kMaxPower = 1e9;
/// Smallest variance: the variance of kMaxPower under the 1/n convention.
inline constexpr double kMinVariance = 1.0 / kMaxPower;
/// Cosines below this are treated as this value in divisions (visibility terms, Beckmann):
/// bounds 1/cos at 1e6 while changing no result that has a visible effect.
inline constexpr double kMinCosine = 1e-6;

/// Clamps to [0, 1]: NaN becomes 0 (so a NaN cosine or channel value can never travel further),
/// +Inf 1, −Inf and −0 become 0. Selects, no branches: loops of it vectorise. The one [0, 1] clamp
/// of core (bake and paint rows, gloss channels, cube coordinates, colour encodings).
template <class T> constexpr T saturate(T x) {
    return x > T(0) ? (x < T(1) ? x : T(1)) : T(0);
}

/// Smallest GGX alpha / Beckmann m: the roughness of kMaxPower under α² = m² = 2/(n+2)
/// (the lower bound of beckmannNdf's m, ggxNdf's alpha and the gloss encodings' roughness).
// Lazarov 2011: m = sqrt(2/(n+2))
inline const double kMinRoughness = std::sqrt(2.0 / (kMaxPower + 2.0));

/// Clamps a power to [0, kMaxPower]; NaN becomes 0.
template <class T> constexpr T clampPower(T n) {
    return n > T(0) ? std::min(n, T(kMaxPower)) : T(0); // NaN fails n > 0
}

/// max(c, 0)^n evaluated as exp(n·log c), the overflow- and NaN-free form of pow for lobes:
/// returns 1 for n == 0 (the limit, also at c == 0), 0 for c <= 0 and n > 0, and never NaN.
template <class T> inline T powCos(T c, T n) {
    n = clampPower(n);
    if (n == T(0)) return T(1);
    if (!(c > T(0))) return T(0);
    if (c >= T(1)) return T(1);
    return std::exp(n * std::log(c));
}

/// x^p for x in [0, 1] and p >= 0 (Fresnel-style powers), never NaN: 0^0 = 1, 0^p = 0.
template <class T> inline T powUnit(T x, T p) {
    return powCos(x, p);
}

/// log2(x) for a positive, normal, finite double, without branches or calls so that loops over it
/// vectorise. x = m·2^e with m in [√½, √2); log2(m) = (2/ln 2)·atanh(s), s = (m − 1)/(m + 1),
/// |s| <= 0.1716, by its odd series to s^15: the truncation is below 2e-14, so the result is
/// within 2e-14 of std::log2 (tested) and exact at powers of two. Zero, negative, subnormal,
/// infinite and NaN inputs give meaningless (finite or not) values: clamp x first.
/// D is double, or a vector of doubles (GCC vector extensions, e.g. simd::Double4) with U its
/// vector of 64-bit unsigned integers: the same IEEE operations lane by lane, so a lane's result is
/// the double's bit for bit. Always inlined: called out of line from a target_clones copy, its
/// vector instance gave other bits (see the -Wpsabi note in simd.h).
template <class D, class U = std::uint64_t> [[gnu::always_inline]] inline D log2Positive(D x) {
    const U bits = std::bit_cast<U>(x);
    // The biased exponent as a double, exactly: OR it into 2^52's mantissa and subtract 2^52.
    const D biased = std::bit_cast<D>((bits >> 52) | 0x4330000000000000ull) - 0x1p52;
    const U mBits = (bits & 0x000fffffffffffffull) | 0x3ff0000000000000ull; // m in [1, 2)
    // m >= √2 is halved and the exponent raised by one, with masks rather than selects: GCC's
    // if-conversion gave up on the selects and left evaluate's loops over this unvectorised. Halving
    // m in [1, 2) is one off its exponent field, and e + 0.0 is e: the same bits as the selects.
    U high;
    if constexpr (std::is_same_v<U, std::uint64_t>)
        high = U(0) - U(std::bit_cast<D>(mBits) > 1.4142135623730951);
    else
        high = (U)(std::bit_cast<D>(mBits) > 1.4142135623730951); // lanes of all ones or zeros
    const D m = std::bit_cast<D>(mBits - (high & 0x0010000000000000ull));
    const D e = (biased + std::bit_cast<D>(high & 0x3ff0000000000000ull)) - 1023.0;
    const D s = (m - 1.0) / (m + 1.0), s2 = s * s;
    // Horner from 1/15 down to 1, written out as expNonPositive's: a loop over the coefficients here
    // also kept the loops around log2Positive from vectorising (seen with objdump).
    D series = D{} + 1.0 / 15;
    series = 1.0 / 13 + s2 * series;
    series = 1.0 / 11 + s2 * series;
    series = 1.0 / 9 + s2 * series;
    series = 1.0 / 7 + s2 * series;
    series = 1.0 / 5 + s2 * series;
    series = 1.0 / 3 + s2 * series;
    series = 1.0 + s2 * series;
    return e + (2.0 / kLn2<double>)*s * series;
}

/// Below this, expNonPositive returns 0: e^x < 2^-1021, where a result would soon be subnormal.
inline constexpr double kExpFlushBelow = -707.0;

/// e^x for x <= 0 (x > 0 is taken as 0), without branches or calls so that loops over it
/// vectorise, and without subnormal results: x < kExpFlushBelow gives 0 (x86 takes about a
/// hundred cycles for an operation that makes or reads a subnormal, and libm's exp makes them for
/// x in (−745, −708)). x = k·ln2 + r, |r| <= ln2/2, k rounded by adding 1.5·2^52 (its low bits
/// then hold k), ln2 in two parts so r is exact (Cody & Waite 1980); e^r by its Taylor series to
/// r^13, whose truncation is below 5e-18; then 2^k from its bits. Within 1e-15 relative of
/// std::exp (tested). NaN gives a meaningless finite value: clamp first.
[[gnu::always_inline]] inline double expNonPositive(double x) {
    constexpr double kLog2e = 1.4426950408889634;
    constexpr double kLn2Hi = 0x1.62e42fefa3800p-1; // ln 2 to 43 bits: k·kLn2Hi is exact
    constexpr double kLn2Lo = 0x1.ef35793c76730p-45;
    constexpr double kShift = 0x1.8p52;
    const bool flush = !(x >= kExpFlushBelow); // NaN too
    x = flush ? 0.0 : std::min(x, 0.0);
    const double t = x * kLog2e + kShift;
    const double k = t - kShift; // round(x·log2e), exactly, in [−1021, 0]
    const double r = (x - k * kLn2Hi) - k * kLn2Lo;
    // Horner from 1/13! down to 1/0!, written out so that the loop it sits in vectorises.
    double p = 1.0 / 6227020800.0;
    p = 1.0 / 479001600.0 + r * p;
    p = 1.0 / 39916800.0 + r * p;
    p = 1.0 / 3628800.0 + r * p;
    p = 1.0 / 362880.0 + r * p;
    p = 1.0 / 40320.0 + r * p;
    p = 1.0 / 5040.0 + r * p;
    p = 1.0 / 720.0 + r * p;
    p = 1.0 / 120.0 + r * p;
    p = 1.0 / 24.0 + r * p;
    p = 1.0 / 6.0 + r * p;
    p = 0.5 + r * p;
    p = 1.0 + r * p;
    p = 1.0 + r * p;
    // t's low bits are k + 2^51 (two's complement in the mantissa): 2^k's bits are (k + 1023) << 52.
    const std::int64_t ki = std::bit_cast<std::int64_t>(t) - std::bit_cast<std::int64_t>(kShift);
    const double scale = std::bit_cast<double>(std::uint64_t(ki + 1023) << 52);
    return flush ? 0.0 : p * scale;
}

/// max(c, 0)^p as powCos computes it (p clamped by the caller, p = 0 gives 1, c >= 1 gives 1), without
/// branches or calls (log2Positive, expNonPositive), so loops over it vectorise; results below e^-707
/// are 0.
[[gnu::always_inline]] inline double powCosFast(double c, double p) {
    const double lg = kLn2<double> * log2Positive(std::max(c, std::numeric_limits<double>::min()));
    const double v = expNonPositive(p * lg);
    return (c > 0.0 || p == 0.0) ? v : 0.0;
}

/// True when x is neither NaN nor infinite.
template <class T> constexpr bool isFinite(T x) {
    return std::isfinite(x);
}

} // namespace burnish
