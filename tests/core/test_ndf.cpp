// NDFs and normalization factors of ndf.h, checked by numerical integration (white furnace), and the
// bridges between Blinn-Phong power and Beckmann / GGX roughness.
#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/quadrature.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace burnish {
namespace {

// integrateHemisphere runs each panel to a relative tolerance of 1e-10; 1e-9 relative on the whole
// integral leaves a factor 10 for the sum of the panels and the round-off of the integrand.
constexpr double kNormTolerance = 1e-9;
// The white-furnace tolerance: the brief asks for 1e-6 or tighter; the quadrature reaches ~1e-10,
// so 1e-8 still catches any wrong factor (the smallest plausible mistake, n+1 for n+2 at
// n = 1e4, is 1e-4).
constexpr double kFurnaceTolerance = 1e-8;

const std::vector<double> kNormPowers{0.0, 1.0, 2.0, 8.0, 64.0, 1000.0, 1e4, 1e6};

// Angular width of a cosine-power lobe: cos^n θ ≈ exp(−nθ²/2), so θ ~ 1/√(n+1).
double lobeWidth(double n) {
    return 1.0 / std::sqrt(n + 1.0);
}

// ---------------------------------------------------------------------------------------------
// Normalization factors: K · (stated integral) = 1.

TEST(NdfNormalization, BlinnPhongNdf) {
    for (const double n : kNormPowers) {
        const double I = integrateHemisphere([&](double c) { return powCos(c, n) * c; }, lobeWidth(n));
        EXPECT_NEAR(blinnPhongNdfNorm(n) * I, 1.0, kNormTolerance) << "n = " << n;
    }
}

TEST(NdfNormalization, PhongLobe) {
    for (const double n : kNormPowers) {
        // With l = n the reflected vector is n, so r·v = cosθ_o.
        const double I = integrateHemisphere([&](double c) { return powCos(c, n); }, lobeWidth(n));
        EXPECT_NEAR(phongLobeNorm(n) * I, 1.0, kNormTolerance) << "n = " << n;
    }
}

TEST(NdfNormalization, PhongBrdf) {
    for (const double n : kNormPowers) {
        const double I = integrateHemisphere([&](double c) { return powCos(c, n) * c; }, lobeWidth(n));
        EXPECT_NEAR(phongBrdfNorm(n) * I, 1.0, kNormTolerance) << "n = " << n;
    }
}

// With l = n, the half vector of v at polar angle θ lies at θ/2: n·h = cos(θ/2) = √((1 + cosθ)/2).
double cosHalf(double c) {
    return std::sqrt(std::max(0.0, (1.0 + c) / 2.0));
}

TEST(NdfNormalization, BlinnPhongLobe) {
    for (const double n : kNormPowers) {
        // The lobe in θ_o is twice as wide as in θ_h.
        const double I =
            integrateHemisphere([&](double c) { return powCos(cosHalf(c), n); }, 2.0 * lobeWidth(n));
        EXPECT_NEAR(blinnPhongLobeNorm(n) * I, 1.0, kNormTolerance) << "n = " << n;
    }
}

TEST(NdfNormalization, BlinnPhongBrdf) {
    for (const double n : kNormPowers) {
        const double I =
            integrateHemisphere([&](double c) { return powCos(cosHalf(c), n) * c; }, 2.0 * lobeWidth(n));
        EXPECT_NEAR(blinnPhongBrdfNorm(n) * I, 1.0, kNormTolerance) << "n = " << n;
    }
}

TEST(NdfNormalization, HoffmanSloanApproximationConverges) {
    // ratio − 1 = (2n − 8 + 2^(−n/2)(n + 8)) / ((n + 2)(n + 4)), which is ≤ 2/n for n ≥ 1 and
    // tends to 2/n: the (n+8)/(8π) factor is exact in the limit and 2/n off for finite n.
    double maxRatioError = 0.0;
    double argMax = 0.0;
    for (int i = 0; i <= 600; ++i) {
        const double n = std::pow(10.0, i / 100.0); // 1 .. 1e6, 100 per decade
        const double ratio = blinnPhongBrdfNormApprox(n) / blinnPhongBrdfNorm(n);
        EXPECT_LE(std::abs(ratio - 1.0), 2.0 / n) << "n = " << n;
        if (n <= 1e4 && std::abs(ratio - 1.0) > maxRatioError) {
            maxRatioError = std::abs(ratio - 1.0);
            argMax = n;
        }
    }
    std::printf("[measured] max |(n+8)/(8π) / exact − 1| over n in [1, 1e4]: %.5f at n = %.2f\n",
                maxRatioError, argMax);
    // Measured 0.07520 at n ≈ 8.7 on this grid (100 powers per decade). Bounds on both sides,
    // ±0.0002 around it (the grid's resolution near the maximum is far finer), so a changed factor is
    // caught: the approximation is within 7.6% everywhere but not exact.
    constexpr double kMaxRatioErrorUpper = 0.0754;
    constexpr double kMaxRatioErrorLower = 0.0750;
    EXPECT_LT(maxRatioError, kMaxRatioErrorUpper);
    EXPECT_GT(maxRatioError, kMaxRatioErrorLower);
    // And at high power the ratio is 1 to within the 2/n bound, 2e-6 at n = 1e6.
    constexpr double kHighPowerRatioTolerance = 2.1e-6;
    EXPECT_NEAR(blinnPhongBrdfNormApprox(1e6) / blinnPhongBrdfNorm(1e6), 1.0, kHighPowerRatioTolerance);
}

// ---------------------------------------------------------------------------------------------
// White furnace: each NDF integrates to 1 in projected solid angle.

std::vector<double> furnacePowers() {
    std::vector<double> powers;
    for (int i = 0; i <= 16; ++i)
        powers.push_back(std::pow(10.0, i / 4.0)); // 1 .. 1e4, 17 powers
    return powers;
}

TEST(WhiteFurnace, BlinnPhong) {
    const auto powers = furnacePowers();
    ASSERT_GE(powers.size(), 12u);
    ASSERT_EQ(powers.back(), 1e4);
    for (const double n : powers) {
        const double I = integrateHemisphere([&](double c) { return blinnPhongNdf(c, n) * c; }, lobeWidth(n));
        EXPECT_NEAR(I, 1.0, kFurnaceTolerance) << "n = " << n;
    }
}

TEST(WhiteFurnace, Beckmann) {
    for (const double n : furnacePowers()) {
        const double m = beckmannRoughnessFromPower(n);
        const double I = integrateHemisphere([&](double c) { return beckmannNdf(c, m) * c; }, lobeWidth(n));
        EXPECT_NEAR(I, 1.0, kFurnaceTolerance) << "n = " << n;
    }
}

TEST(WhiteFurnace, Ggx) {
    for (const double n : furnacePowers()) {
        const double alpha = ggxAlphaFromPower(n);
        // GGX's tails fall as θ^-4, not like a Gaussian; the geometric breakpoints from the width
        // out to π/2 resolve them.
        const double I = integrateHemisphere([&](double c) { return ggxNdf(c, alpha) * c; }, lobeWidth(n));
        EXPECT_NEAR(I, 1.0, kFurnaceTolerance) << "n = " << n;
    }
}

TEST(WhiteFurnace, StiffLobesAtTheClampedExtremes) {
    // Powers far above any texture's range still integrate to 1: the formulas hold up to kMaxPower.
    for (const double n : {1e6, 1e8}) {
        const double w = lobeWidth(n);
        EXPECT_NEAR(integrateHemisphere([&](double c) { return blinnPhongNdf(c, n) * c; }, w), 1.0,
                    kFurnaceTolerance);
        const double m = beckmannRoughnessFromPower(n);
        EXPECT_NEAR(integrateHemisphere([&](double c) { return beckmannNdf(c, m) * c; }, w), 1.0,
                    kFurnaceTolerance);
    }
}

// ---------------------------------------------------------------------------------------------
// Bridges.

// Round trips through a square root and a reciprocal: a few ulps relative, 1e-12 is generous.
constexpr double kRoundTripTolerance = 1e-12;

TEST(NdfBridges, BeckmannRoughnessRoundTrip) {
    for (const double n : {0.5, 1.0, 8.0, 100.0, 8192.0, 1e6, 1e8}) {
        const double m = beckmannRoughnessFromPower(n);
        EXPECT_NEAR(m, std::sqrt(2.0 / (n + 2.0)), kRoundTripTolerance * m);
        EXPECT_NEAR(powerFromBeckmannRoughness(m) / n, 1.0, kRoundTripTolerance) << "n = " << n;
    }
    // m → 0 is a mirror: the largest power; a huge m is the flattest lobe, power 0.
    EXPECT_EQ(powerFromBeckmannRoughness(0.0), kMaxPower);
    EXPECT_EQ(powerFromBeckmannRoughness(10.0), 0.0);
}

TEST(NdfBridges, GgxAlphaRoundTrip) {
    for (const double n : {0.5, 1.0, 8.0, 100.0, 8192.0, 1e6, 1e8}) {
        const double alpha = ggxAlphaFromPower(n);
        EXPECT_NEAR(alpha * alpha, 2.0 / (n + 2.0), kRoundTripTolerance * alpha * alpha);
        EXPECT_NEAR(powerFromGgxAlpha(alpha) / n, 1.0, kRoundTripTolerance) << "n = " << n;
    }
}

TEST(NdfBridges, GgxMatchesBlinnPhongPeak) {
    // With α² = 2/(n+2), GGX's peak 1/(πα²) equals Blinn-Phong's (n+2)/(2π).
    constexpr double kPeakTolerance = 1e-12; // the same expression rearranged: round-off only
    for (const double n : {1.0, 64.0, 8192.0}) {
        EXPECT_NEAR(ggxNdf(1.0, ggxAlphaFromPower(n)) / blinnPhongNdf(1.0, n), 1.0, kPeakTolerance);
    }
}

TEST(NdfBridges, BeckmannAndBlinnPhongAgreeAtHighPower) {
    const double n = 1000.0;
    const double m = beckmannRoughnessFromPower(n);
    const double peak = blinnPhongNdf(1.0, n);
    // At the peak both are (n+2)/(2π) = 1/(πm²) exactly, to round-off.
    constexpr double kPeakTolerance = 1e-12;
    EXPECT_NEAR(beckmannNdf(1.0, m) / peak, 1.0, kPeakTolerance);

    // RMS of the difference relative to the peak, over the lobe θ in [0, 3/√n] (3 "sigmas").
    const int samples = 1000;
    double sum2 = 0.0;
    double maxDiff = 0.0;
    for (int i = 0; i <= samples; ++i) {
        const double theta = 3.0 / std::sqrt(n) * i / samples;
        const double c = std::cos(theta);
        const double d = (beckmannNdf(c, m) - blinnPhongNdf(c, n)) / peak;
        sum2 += d * d;
        maxDiff = std::max(maxDiff, std::abs(d));
    }
    const double rms = std::sqrt(sum2 / (samples + 1));
    std::printf("[measured] Beckmann vs Blinn-Phong at n = 1000: RMS %.3e, max %.3e (relative to the peak)\n",
                rms, maxDiff);
    // Measured RMS 2.53e-4 and max 4.61e-4 of the peak; the bounds add ~10% as a regression guard.
    // The lobes are "very similar" (Lazarov 2011), and the difference shrinks like 1/n.
    constexpr double kRmsBound = 2.8e-4;
    constexpr double kMaxBound = 5.1e-4;
    EXPECT_LT(rms, kRmsBound);
    EXPECT_LT(maxDiff, kMaxBound);

    // At n = 8 they differ visibly: the agreement is a high-power property, not an identity.
    constexpr double kLowPowerMinDifference = 1e-2;
    const double m8 = beckmannRoughnessFromPower(8.0);
    const double c8 = std::cos(0.5);
    EXPECT_GT(std::abs(beckmannNdf(c8, m8) - blinnPhongNdf(c8, 8.0)) / blinnPhongNdf(1.0, 8.0),
              kLowPowerMinDifference);
}

TEST(Lambert, UnitAlbedoIntegratesToOne) {
    // ∫ f cosθ dω = (1/π)·π = 1 for a white Lambert surface.
    EXPECT_NEAR(integrateHemisphere([](double c) { return lambertBrdf<double>() * c; }), 1.0, kNormTolerance);
    // "Game light units": a white Lambert surface facing a unit light shows 1.
    constexpr double kExact = 1e-15;
    EXPECT_NEAR(punctualRadiance(lambertBrdf<double>(), 1.0, 1.0), 1.0, kExact);
    EXPECT_EQ(punctualRadiance(lambertBrdf<double>(), 1.0, -0.5), 0.0);
}

} // namespace
} // namespace burnish
