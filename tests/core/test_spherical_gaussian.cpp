// Spherical-Gaussian lobes of spherical_gaussian.h: convergence to the cosine power, the exp2 GPU
// form, Lagarde's 0.775 offset, the normalized lobe's furnace integral, and SgOffsetCurve.
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/spherical_gaussian.h>
#include <burnish/core/util/quadrature.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace burnish {
namespace {

// Grid over c in [0, 1] for maxima and L2 norms: the lobes are smooth, 1e4 steps resolve them.
constexpr int kGridSteps = 10000;

double maxErrorAgainstPower(double n, double x) {
    double maxError = 0.0;
    for (int i = 0; i <= kGridSteps; ++i) {
        const double c = double(i) / kGridSteps;
        maxError = std::max(maxError, std::abs(sgLobe(c, n, x) - powCos(c, n)));
    }
    return maxError;
}

// L2 norm of sgLobe − c^n over c in [0, 1] (midpoint rule on the grid).
double l2ErrorAgainstPower(double n, double x) {
    double sum = 0.0;
    for (int i = 0; i < kGridSteps; ++i) {
        const double c = (i + 0.5) / kGridSteps;
        const double d = sgLobe(c, n, x) - powCos(c, n);
        sum += d * d;
    }
    return std::sqrt(sum / kGridSteps);
}

TEST(SphericalGaussian, PlainLobeConvergesToCosinePower) {
    // c^n = exp(n·log c) and exp(n(c − 1)) differ by exp(−nt)·nt²/2 near c = 1 − t: the maximum
    // error falls like 1/n (≈ 2e^(−2)/n = 0.27/n for large n; n·error is 0.37 at n = 1, 0.30 at 4).
    constexpr double kAsymptoticConstant = 0.28; // 2e^(−2) = 0.2707 plus a 3% margin
    double previous = 1.0;
    for (const double n : {1.0, 4.0, 16.0, 64.0, 256.0, 1024.0, 8192.0}) {
        const double e = maxErrorAgainstPower(n, kSgOffsetPlain);
        EXPECT_LT(e, previous) << "n = " << n; // shrinks with n
        if (n >= 16.0) {                       // the asymptotic regime
            EXPECT_LT(e * n, kAsymptoticConstant) << "n = " << n;
        }
        previous = e;
    }
    // The lobe is exact at the peak and zero behind the surface, like c^n.
    constexpr double kExact = 1e-15;
    EXPECT_NEAR(sgLobe(1.0, 100.0, kSgOffsetLagarde), 1.0, kExact);
    EXPECT_EQ(sgLobe(0.0, 100.0, kSgOffsetPlain), 0.0);
    EXPECT_EQ(sgLobe(-0.3, 100.0, kSgOffsetPlain), 0.0);
}

TEST(SphericalGaussian, Exp2FormEqualsLobe) {
    // exp2(A·c − A) with A = (n + x)/ln 2 is exp((n + x)(c − 1)) rearranged; the rearrangement
    // A·c − A loses ~A·ε absolute in the exponent, so relative 1e-12 holds up to n ~ 1e4.
    constexpr double kRelativeTolerance = 1e-12;
    for (const double n : {1.0, 10.0, 100.0, 2048.0}) {
        for (const double x : {kSgOffsetPlain, kSgOffsetLagarde, kSgOffsetLimit}) {
            const double A = (n + x) / std::log(2.0);
            for (int i = 1; i <= 100; ++i) {
                const double c = i / 100.0;
                const double expected = sgLobe(c, n, x);
                EXPECT_NEAR(sgLobeExp2(c, A), expected, kRelativeTolerance * expected)
                    << "n = " << n << " c = " << c;
            }
            EXPECT_EQ(sgLobeExp2(0.0, A), 0.0);
        }
    }
}

TEST(SphericalGaussian, LagardeOffsetBeatsPlainForLowPowers) {
    // Lagarde 2012: 0.775 is the mean best-fit offset over powers 3..15.
    for (int n = 3; n <= 15; ++n) {
        const double plain = l2ErrorAgainstPower(n, kSgOffsetPlain);
        const double lagarde = l2ErrorAgainstPower(n, kSgOffsetLagarde);
        EXPECT_LT(lagarde, plain) << "n = " << n;
        std::printf("[measured] n = %2d: L2 error x = 0: %.5f, x = 0.775: %.5f\n", n, plain, lagarde);
    }
}

TEST(SphericalGaussian, NormalizedLobeFurnace) {
    // The SG lobe normalized with Blinn-Phong's (n+2)/(2π) integrates in projected solid angle to
    //   (n+2)/(2π) · 2π ∫_0^1 e^(k(c−1)) c dc = (n+2)(k − 1 + e^(−k))/k²,   k = n + x,
    // which tends to 1 like 1 + (1 − x)/n: within 1/n of 1 for both published offsets (1 + 1/n
    // for x = 0, 1 + 0.225/n for x = 0.775). It is not 1 at low power: the SG lobe
    // is not itself normalized, the Blinn-Phong factor only approximately fits it.
    constexpr double kQuadratureTolerance = 1e-9; // integrateHemisphere's 1e-10 per panel, ×10
    for (const double x : {kSgOffsetPlain, kSgOffsetLagarde}) {
        for (const double n : {1.0, 3.0, 10.0, 100.0, 1e3, 1e4, 1e6}) {
            const double I =
                integrateHemisphere([&](double c) { return blinnPhongNdfNorm(n) * sgLobe(c, n, x) * c; },
                                    1.0 / std::sqrt(n + 1.0));
            const double k = n + x;
            const double closedForm = (n + 2.0) * (k - 1.0 + std::exp(-k)) / (k * k);
            EXPECT_NEAR(I, closedForm, kQuadratureTolerance) << "n = " << n << " x = " << x;
            EXPECT_LE(std::abs(I - 1.0), 1.0 / n) << "n = " << n << " x = " << x;
        }
    }
    // Lagarde's GPU normalization (ln2/8·A + 0.25) with A = n/ln 2 is (n + 2)/8, the (n+2)/(8π)
    // factor without the 1/π of "game units".
    constexpr double kExact = 1e-12;
    const double n = 100.0;
    const double A = n / std::log(2.0);
    EXPECT_NEAR(std::log(2.0) / 8.0 * A + 0.25, blinnPhongNdfNorm(n) * 2.0 * kPi<double> / 8.0, kExact);
}

TEST(SgOffsetCurve, InterpolatesInLogPowerAndHoldsEnds) {
    const SgOffsetCurve curve({1.0, 10.0, 1000.0}, {0.5, 0.8, 0.75});
    constexpr double kExact = 1e-14;
    // Nodes are reproduced.
    EXPECT_NEAR(curve(1.0), 0.5, kExact);
    EXPECT_NEAR(curve(10.0), 0.8, kExact);
    EXPECT_NEAR(curve(1000.0), 0.75, kExact);
    // Halfway in log n, not in n: √10 is the midpoint of [1, 10], 100 of [10, 1000].
    EXPECT_NEAR(curve(std::sqrt(10.0)), 0.65, kExact);
    EXPECT_NEAR(curve(100.0), 0.775, kExact);
    // A linear-in-n interpolation would give 0.5 + 0.3·(5.5 − 1)/9 = 0.65 at n = 5.5; log gives more.
    EXPECT_NEAR(curve(5.5), 0.5 + 0.3 * std::log(5.5) / std::log(10.0), kExact);
    // End values are held outside the nodes, also for NaN and 0.
    EXPECT_EQ(curve(0.5), 0.5);
    EXPECT_EQ(curve(0.0), 0.5);
    EXPECT_EQ(curve(std::nan("")), 0.5);
    EXPECT_EQ(curve(1e9), 0.75);
    // An empty curve is the large-power limit.
    EXPECT_EQ(SgOffsetCurve()(42.0), kSgOffsetLimit);
}

} // namespace
} // namespace burnish
