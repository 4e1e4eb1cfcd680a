// core's shared helpers (util/): the one [0, 1] clamp, the roughness floor, the radical inverse,
// the error accumulator and the sample grids.
#include <burnish/core/util/error_accumulator.h>
#include <burnish/core/util/grid.h>
#include <burnish/core/util/low_discrepancy.h>
#include <burnish/core/util/numeric.h>
#include <burnish/core/util/simd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

using namespace burnish;

TEST(Util, SaturateMapsNanAndInfinitiesIntoTheUnitInterval) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(saturate(std::nan("")), 0.0);
    EXPECT_EQ(saturate(inf), 1.0);
    EXPECT_EQ(saturate(-inf), 0.0);
    EXPECT_EQ(saturate(0.25), 0.25);
    EXPECT_EQ(saturate(1.5), 1.0);
    EXPECT_EQ(saturate(-0.5), 0.0);
    // −0 becomes +0: a stored channel never holds a negative zero.
    EXPECT_FALSE(std::signbit(saturate(-0.0)));
    EXPECT_EQ(saturate(std::numeric_limits<float>::quiet_NaN()), 0.0f);
    EXPECT_EQ(saturate(2.0f), 1.0f);
}

TEST(Util, MinRoughnessIsTheRoughnessOfTheLargestPower) {
    EXPECT_EQ(kMinRoughness, std::sqrt(2.0 / (kMaxPower + 2.0)));
    EXPECT_GT(kMinRoughness, 0.0);
}

TEST(Util, RadicalInverseOfBaseTwoByBitsEqualsTheDigitLoop) {
    for (std::uint32_t i = 0; i < 70000; ++i)
        ASSERT_EQ(radicalInverse2(i), radicalInverse(i, 2)) << i;
    for (std::uint32_t i : {0xFFFFFFFFu, 0x80000000u, 0x12345678u})
        EXPECT_EQ(radicalInverse2(i), radicalInverse(i, 2)) << i;
    EXPECT_EQ(radicalInverse(1, 3), 1.0 / 3.0);
    // 5 is 12 in base 3, mirrored 0.21: 2/3 + 1/9.
    EXPECT_NEAR(radicalInverse(5, 3), 2.0 / 3.0 + 1.0 / 9.0, 1e-15);
    EXPECT_EQ(radicalInverse2(1), 0.5);
    EXPECT_EQ(radicalInverse2(3), 0.75);
}

TEST(Util, ErrorAccumulatorSamplesAndDomains) {
    ErrorAccumulator samples;
    samples.add(1.0, 1.5);
    samples.add(2.0, 1.0);
    samples.add(0.0, 0.25);         // no relative error where exact is 0
    samples.add(1.0, std::nan("")); // counted apart
    const ErrorMetrics m = samples.metrics();
    EXPECT_EQ(m.samples, 3u);
    EXPECT_EQ(samples.nonFinite(), 1u);
    EXPECT_EQ(m.maxAbs, 1.0);
    ASSERT_TRUE(m.maxRel);
    EXPECT_EQ(*m.maxRel, 0.5);
    EXPECT_EQ(m.rms, std::sqrt((0.25 + 1.0 + 0.0625) / 3.0));

    // Two quadrature domains: the mean over domains of (Σ w e²)/measure.
    ErrorAccumulator domains;
    domains.addDomain({0.5, 0.5}, {1.0, -3.0}, 1.0).addDomain({2.0}, {0.5}, 2.0);
    const ErrorMetrics d = domains.metrics();
    EXPECT_EQ(d.maxAbs, 3.0);
    EXPECT_EQ(d.rms, std::sqrt(((0.5 * 1.0 + 0.5 * 9.0) / 1.0 + (2.0 * 0.25) / 2.0) / 2.0));
    EXPECT_FALSE(d.maxRel);
    EXPECT_EQ(ErrorAccumulator{}.metrics().rms, 0.0);
}

TEST(Util, GridsIncludeBothEndsExactly) {
    const auto lin = linSpaced(-1.0, 3.0, 5);
    EXPECT_EQ(lin, (std::vector<double>{-1.0, 0.0, 1.0, 2.0, 3.0}));
    EXPECT_EQ(linSpaced(2.0, 5.0, 1), std::vector<double>{2.0});
    const auto log = logSpaced(1.0, 1e4, 33);
    ASSERT_EQ(log.size(), 33u);
    EXPECT_EQ(log.front(), 1.0);
    EXPECT_EQ(log.back(), 1e4);
    for (size_t i = 1; i < log.size(); ++i)
        EXPECT_NEAR(log[i] / log[i - 1], std::pow(1e4, 1.0 / 32.0), 1e-12);
    EXPECT_EQ(logSpaced(3.0, 9.0, 1), std::vector<double>{3.0});
}

TEST(Util, Float4LanesMatchScalarArithmetic) {
    const float in[5] = {1.5f, -2.0f, std::numeric_limits<float>::quiet_NaN(), 4.0f, 9.0f};
    const simd::Float4 v = simd::load4(in + 1); // unaligned
    const simd::Float4 m = simd::max04(v);
    EXPECT_EQ(m[0], 0.0f);
    EXPECT_EQ(m[1], 0.0f); // NaN → 0
    EXPECT_EQ(m[2], 4.0f);
    EXPECT_EQ(m[3], 9.0f);
    EXPECT_EQ(simd::horizontalSum(simd::splat4(0.25f)), 1.0f);
    EXPECT_EQ(simd::horizontalSum(simd::Float4{1e8f, 1.0f, -1e8f, 1.0f}), (1e8f + 1.0f) + (-1e8f + 1.0f));
}

TEST(Util, ExpNonPositiveIsLibmsExpWithoutSubnormals) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(kExpFlushBelow, 0.0);
    double worst = 0.0;
    for (int i = 0; i < 200000; ++i) {
        const double x = i < 1000 ? -i * 1e-3 : u(rng);
        worst = std::max(worst, std::abs(expNonPositive(x) - std::exp(x)) / std::exp(x));
    }
    EXPECT_LT(worst, 1e-15);
    EXPECT_EQ(expNonPositive(0.0), 1.0);
    EXPECT_EQ(expNonPositive(-0.0), 1.0);
    EXPECT_EQ(expNonPositive(3.0), 1.0); // positive arguments are taken as 0
    EXPECT_NEAR(expNonPositive(kExpFlushBelow), std::exp(kExpFlushBelow), 1e-15 * std::exp(kExpFlushBelow));
    // Below the flush point 0, never a subnormal (libm gives subnormals down to −745).
    for (double x = kExpFlushBelow - 1e-9; x > -800.0; x -= 0.37)
        EXPECT_EQ(expNonPositive(x), 0.0) << x;
    EXPECT_EQ(expNonPositive(-std::numeric_limits<double>::infinity()), 0.0);
    EXPECT_EQ(expNonPositive(std::numeric_limits<double>::quiet_NaN()), 0.0);
    EXPECT_EQ(std::fpclassify(expNonPositive(-707.9)), FP_ZERO);
}

TEST(Util, Exp2OfNonPositiveFloat8IsWithinItsBound) {
    // Cephes exp2f's polynomial errs by 1.7e-8; float rounding of its evaluation adds about 1e-7.
    constexpr double kExp2Relative = 1.4e-7;
    double worst = 0.0;
    for (int i = 0; i <= 125 * 4096; i += 8) {
        simd::Float8 x;
        for (int k = 0; k < 8; ++k)
            x[k] = -float(std::min(i + k, 125 * 4096)) / 4096.0f;
        const simd::Float8 y = simd::exp2NonPositive(x);
        for (int k = 0; k < 8; ++k)
            worst = std::max(worst, std::abs(double(y[k]) / std::exp2(double(x[k])) - 1.0));
    }
    EXPECT_LT(worst, kExp2Relative);
    const simd::Float8 exact = simd::exp2NonPositive(simd::Float8{0.0f, -1.0f, -3.0f, -125.0f});
    EXPECT_EQ(exact[0], 1.0f); // exact at integers
    EXPECT_EQ(exact[1], 0.5f);
    EXPECT_EQ(exact[2], 0.125f);
    EXPECT_EQ(exact[3], std::ldexp(1.0f, -125));
}
