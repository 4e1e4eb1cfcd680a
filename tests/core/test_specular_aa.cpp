// Normal-based NDF filtering for geometric specular AA (Tokuyoshi & Kaplanyan 2019), specular_aa.h.
#include <burnish/core/shading/specular_aa.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace burnish {
namespace {

using glm::dvec3;

// The functions are a handful of double operations: agreement with the formula to ~1e-15 relative.
constexpr double kFormulaTolerance = 1e-14;

TEST(SpecularAa, KernelRoughnessIsTwiceSigma2TimesDerivativesBelowKappa) {
    EXPECT_EQ(specularAaKernelRoughness2(0.0), 0.0);
    // d² = 0.1 px⁻²: 2·0.25·0.1 = 0.05 < κ.
    EXPECT_NEAR(specularAaKernelRoughness2(0.1), 2.0 * kSpecularAaKernelVariance * 0.1, kFormulaTolerance);
    // Far above κ/(2σ²) = 0.36 the kernel is clamped to κ.
    EXPECT_EQ(specularAaKernelRoughness2(10.0), kSpecularAaKappa);
    const dvec3 dndx(0.3, 0.0, 0.1);
    const dvec3 dndy(0.0, -0.2, 0.0);
    EXPECT_NEAR(normalDerivative2(dndx, dndy), 0.09 + 0.01 + 0.04, kFormulaTolerance);
}

TEST(SpecularAa, BadDerivativesAreNoCurvatureOrTheClamp) {
    EXPECT_EQ(specularAaKernelRoughness2(std::numeric_limits<double>::quiet_NaN()), 0.0);
    EXPECT_EQ(specularAaKernelRoughness2(-1.0), 0.0);
    EXPECT_EQ(specularAaKernelRoughness2(std::numeric_limits<double>::infinity()), kSpecularAaKappa);
    const dvec3 inf(std::numeric_limits<double>::infinity(), 0.0, 0.0);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const double alpha : {0.0, 1e-9, 0.5, 1.0, 100.0, nan, std::numeric_limits<double>::infinity()}) {
        EXPECT_TRUE(std::isfinite(specularAaGgxAlpha(alpha, inf, dvec3(0.0)))) << alpha;
        EXPECT_TRUE(std::isfinite(specularAaBeckmannM(alpha, dvec3(nan), dvec3(0.0)))) << alpha;
        EXPECT_TRUE(std::isfinite(specularAaPower(alpha * 1e9, inf, dvec3(nan)))) << alpha;
    }
}

TEST(SpecularAa, FlatSurfaceKeepsRoughnessAndRoughnessSaturatesAtOne) {
    const dvec3 zero(0.0);
    for (const double alpha : {1e-4, 0.1, 0.5, 0.9}) {
        EXPECT_NEAR(specularAaGgxAlpha(alpha, zero, zero), alpha, kFormulaTolerance * alpha);
        EXPECT_NEAR(specularAaBeckmannM(alpha, zero, zero), alpha, kFormulaTolerance * alpha);
    }
    // α = 1 plus any kernel is clamped back to 1 (Listing 2's saturate).
    EXPECT_EQ(specularAaGgxAlpha(1.0, dvec3(1.0, 0.0, 0.0), zero), 1.0);
    // Filtered α² = α² + kernel: α = 0.1, d² = 0.2 → 0.01 + 0.1.
    EXPECT_NEAR(specularAaGgxAlpha(0.1, dvec3(0.2, 0.4, 0.0), zero), std::sqrt(0.01 + 0.1),
                kFormulaTolerance);
}

TEST(SpecularAa, PowerNeverGrowsAndCurvatureCapsIt) {
    // The highest power a κ-clamped kernel leaves: α² >= κ, n = 2/α² − 2.
    const double cappedPower = 2.0 / kSpecularAaKappa - 2.0;
    // Conversions through α² = 2/(n+2) and back: relative round-off of a few ULPs of n.
    constexpr double kRoundTrip = 1e-9;
    for (const double n : {0.0, 1.0, 10.0, 1e3, 1e6, 1e9}) {
        for (const double d : {0.0, 1e-4, 1e-2, 0.3, 10.0}) {
            const double p = specularAaPower(n, dvec3(d, 0.0, 0.0), dvec3(0.0, d, 0.0));
            EXPECT_LE(p, n * (1.0 + kRoundTrip) + kRoundTrip) << n << " " << d;
            if (d >= 10.0) {
                EXPECT_LE(p, cappedPower * (1.0 + kRoundTrip)) << n;
            }
            if (d == 0.0) {
                EXPECT_NEAR(p, n, kRoundTrip * (n + 1.0));
            }
        }
    }
}

// The Beckmann NDF is a Gaussian in slope space with per-axis variance m²/2 (the slope density is
// exp(−|b|²/m²)/(πm²)); filtering it with the kernel — an isotropic slope Gaussian whose per-axis
// variance is half the kernel roughness² — is a convolution of two Gaussians, whose result must be
// the Beckmann slope density of the filtered m. Checked by direct 2D quadrature of the convolution.
TEST(SpecularAa, BeckmannFilteringEqualsSlopeSpaceConvolution) {
    const double m = 0.2;
    const dvec3 dndx(0.25, 0.0, 0.0);
    const dvec3 dndy(0.0, 0.15, 0.0);
    const double kernel2 = specularAaKernelRoughness2(normalDerivative2(dndx, dndy));
    ASSERT_GT(kernel2, 0.0);
    ASSERT_LT(kernel2, kSpecularAaKappa); // the unclamped regime, where the convolution argument holds
    const double mFiltered = specularAaBeckmannM(m, dndx, dndy);
    const double kernelVar = kernel2 / 2.0; // per-axis variance of the kernel in slope space
    const auto beckmannSlopePdf = [](double bx, double by, double mm) {
        return std::exp(-(bx * bx + by * by) / (mm * mm)) / (kPi<double> * mm * mm);
    };
    // Midpoint rule over ±8 kernel standard deviations; 400² cells resolve both Gaussians.
    constexpr int kCells = 400;
    const double halfWidth = 8.0 * std::sqrt(kernelVar);
    const double step = 2.0 * halfWidth / kCells;
    // Quadrature error of the midpoint rule on smooth Gaussians this finely sampled.
    constexpr double kQuadratureTolerance = 1e-6;
    for (const double bx : {0.0, 0.1, 0.3}) {
        const double by = 0.05;
        double conv = 0.0;
        for (int i = 0; i < kCells; ++i)
            for (int j = 0; j < kCells; ++j) {
                const double ux = -halfWidth + (i + 0.5) * step;
                const double uy = -halfWidth + (j + 0.5) * step;
                const double kernel =
                    std::exp(-(ux * ux + uy * uy) / (2.0 * kernelVar)) / (2.0 * kPi<double> * kernelVar);
                conv += kernel * beckmannSlopePdf(bx - ux, by - uy, m) * step * step;
            }
        const double expected = beckmannSlopePdf(bx, by, mFiltered);
        EXPECT_NEAR(conv, expected, kQuadratureTolerance * std::max(1.0, expected)) << "bx=" << bx;
    }
}

} // namespace
} // namespace burnish
