// SH9 irradiance: exact for a constant environment, equal to the brute-force integral where the
// environment is itself of order ≤ 2, within Ramamoorthi & Hanrahan's bound on the studio, never
// negative or NaN next to a sun; the irradiance cube and the average-diffuse normalization.
#include <burnish/core/env/sh.h>

#include <burnish/core/env/sampling.h>

#include <burnish/core/util/numeric.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>

namespace burnish {
namespace {

using glm::dvec3;

constexpr int kFace = 16;
constexpr unsigned kDirections = 64;
// The basis constants are printed to 6 digits (0.282095 for 0.28209479...): c00·Y00 is off by ~2e-6.
constexpr double kShConstantRounding = 1e-5;

template <class F> CubeMap cubeOf(int size, const F& radiance) {
    CubeMap cube = CubeMap::zeros(size, 1);
    for (int f = 0; f < kCubeFaces; ++f)
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const dvec3 L = radiance(texelDirection(f, size, x, y));
                float* t = cube.levels[0].texel(f, x, y);
                for (int c = 0; c < 3; ++c)
                    t[c] = float(L[c]);
            }
    return cube;
}

TEST(Sh9, ConstantEnvironmentGivesExactIrradiance) {
    const dvec3 L(0.5, 2.0, 8.0);
    const CubeMap cube = cubeOf(kFace, [&](const dvec3&) { return L; });
    const Sh9 sh = projectSh9(cube);
    // Only the constant band is non-zero (the higher bands integrate to 0 over the exact texel areas).
    constexpr double kZeroBand = 1e-6;
    for (size_t k = 1; k < 9; ++k)
        EXPECT_NEAR(glm::length(sh.coefficients[k]), 0.0, kZeroBand * glm::length(L)) << k;
    // The brute-force sum of cos·Ω over texel centres is πL up to the horizon's cut through texels
    // (measured 0.1% at 16²).
    constexpr double kBruteForceDiscretization = 0.005;
    for (unsigned i = 0; i < kDirections; ++i) {
        const dvec3 n = sphereDirection(i, kDirections);
        const dvec3 E = shIrradiance(sh, n);
        const dvec3 brute = bruteForceIrradiance(cube, n);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(E[c], kPi<double> * L[c], kShConstantRounding * kPi<double> * L[c]);
            EXPECT_NEAR(brute[c], kPi<double> * L[c], kBruteForceDiscretization * kPi<double> * L[c]);
        }
    }
    // The irradiance cube stores E/π: the radiance itself.
    const auto irr = irradianceCube(sh, 8);
    ASSERT_TRUE(irr) << irr.error();
    for (const auto& face : irr->levels[0].faces)
        for (size_t i = 0; i < face.size(); ++i)
            EXPECT_NEAR(face[i], L[int(i % 3)], kShConstantRounding * L[int(i % 3)]);
}

TEST(Sh9, MatchesBruteForceForAnOrderTwoEnvironment) {
    // L = 1 + 0.5y + 0.3xz + 0.2(x² − y²) (min 0.15 > 0) lies in the span of the nine basis functions,
    // so the SH irradiance is exact and differs from the brute-force sum only by the cube's
    // discretization (measured 0.2% at 16²).
    constexpr double kDiscretization = 0.01;
    const CubeMap cube = cubeOf(kFace, [](const dvec3& d) {
        return dvec3(1.0 + 0.5 * d.y + 0.3 * d.x * d.z + 0.2 * (d.x * d.x - d.y * d.y));
    });
    const Sh9 sh = projectSh9(cube);
    for (unsigned i = 0; i < kDirections; ++i) {
        const dvec3 n = sphereDirection(i, kDirections);
        const dvec3 brute = bruteForceIrradiance(cube, n);
        EXPECT_NEAR(shIrradiance(sh, n).x, brute.x, kDiscretization * brute.x) << i;
    }
}

TEST(Sh9, StudioIrradianceIsWithinTheOrderTwoBound) {
    // The order-2 series replaces the kernel max(c, 0) by Σ_{l<=2} Â_l (2l+1)/(4π) P_l(c)
    // = 0.09375 + 0.5c + 0.46875c², which is off by at most 0.09375 (at c = 0; 1/16 at c = ±1): the
    // "9%" of Ramamoorthi & Hanrahan 2001. Since L >= 0, |E_SH(n) − E(n)| <= 0.09375 Σ L Ω at every n;
    // the cube's discretization adds a little (kDiscretization). A wrong constant in any band breaks the
    // order-2 test above; this one bounds the truncation on a studio with a small bright key light.
    constexpr double kKernelError = 0.09375;
    constexpr double kDiscretization = 0.01;
    const auto studio = proceduralStudioEnvironment(kFace);
    ASSERT_TRUE(studio);
    const Sh9 sh = projectSh9(*studio);
    double power = 0.0; // Σ L Ω (red)
    for (int f = 0; f < kCubeFaces; ++f)
        for (int y = 0; y < kFace; ++y)
            for (int x = 0; x < kFace; ++x)
                power += studio->levels[0].texel(f, x, y)[0] * texelSolidAngle(kFace, x, y);
    for (unsigned i = 0; i < kDirections; ++i) {
        const dvec3 n = sphereDirection(i, kDirections);
        const double brute = bruteForceIrradiance(*studio, n).x;
        EXPECT_NEAR(shIrradiance(sh, n).x, brute, (kKernelError + kDiscretization) * power) << i;
    }
}

TEST(Sh9, SunNextToDarknessStaysFiniteAndNonNegative) {
    // A 1e9 sun in a black sky: the order-2 series rings below zero on the far side; shIrradiance clamps.
    CubeMap cube = CubeMap::zeros(kFace, 1);
    float* t = cube.levels[0].texel(2, 7, 7);
    t[0] = t[1] = t[2] = 1e9f;
    const Sh9 sh = projectSh9(cube);
    for (unsigned i = 0; i < kDirections; ++i) {
        const dvec3 E = shIrradiance(sh, sphereDirection(i, kDirections));
        EXPECT_TRUE(std::isfinite(E.x) && E.x >= 0.0);
    }
    const auto irr = irradianceCube(sh, 4);
    ASSERT_TRUE(irr);
    for (const auto& face : irr->levels[0].faces)
        for (float v : face)
            EXPECT_TRUE(std::isfinite(v) && v >= 0.0f);
}

TEST(Sh9, NormalizationByAverageDiffuseMakesItOne) {
    // Lazarov 2011: after dividing by the average diffuse lighting, the mean of E/π over all normals is 1
    // per channel; the average equals the mean radiance Σ L Ω / 4π.
    constexpr double kMeanOverNormals = 0.01; // 64 normals average a smooth function to ~0.5%
    const auto studio = proceduralStudioEnvironment(kFace);
    ASSERT_TRUE(studio);
    CubeMap cube = *studio;
    Sh9 sh = projectSh9(cube);
    double meanRadiance = 0.0;
    for (int f = 0; f < kCubeFaces; ++f)
        for (int y = 0; y < kFace; ++y)
            for (int x = 0; x < kFace; ++x)
                meanRadiance +=
                    cube.levels[0].texel(f, x, y)[0] * texelSolidAngle(kFace, x, y) / (4 * kPi<double>);
    EXPECT_NEAR(averageDiffuse(sh).x, meanRadiance, kShConstantRounding * meanRadiance);
    const dvec3 divisor = normalizeByAverageDiffuse(cube, sh);
    EXPECT_NEAR(divisor.x, meanRadiance, kShConstantRounding * meanRadiance);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(averageDiffuse(sh)[c], 1.0, kShConstantRounding);
    double mean = 0.0;
    for (unsigned i = 0; i < kDirections; ++i)
        mean += shIrradiance(sh, sphereDirection(i, kDirections)).y / kPi<double> / kDirections;
    EXPECT_NEAR(mean, 1.0, kMeanOverNormals);
    // The cube was divided too: its mean radiance is now 1.
    EXPECT_NEAR(averageDiffuse(projectSh9(cube)).z, 1.0, kShConstantRounding);
}

TEST(Sh9, BlackChannelIsNotNormalized) {
    CubeMap cube = CubeMap::zeros(4, 1);
    for (auto& face : cube.levels[0].faces)
        for (size_t i = 0; i < face.size(); i += 3)
            face[i] = 2.0f; // red only
    Sh9 sh = projectSh9(cube);
    const dvec3 d = normalizeByAverageDiffuse(cube, sh);
    EXPECT_NEAR(d.x, 2.0, kShConstantRounding * 2.0);
    EXPECT_EQ(d.y, 1.0);
    EXPECT_EQ(d.z, 1.0);
    EXPECT_EQ(cube.levels[0].faces[0][1], 0.0f);
}

TEST(Sh9, JsonHoldsNineRgbCoefficients) {
    const nlohmann::json j = sh9Json(projectSh9(*proceduralStudioEnvironment(4)));
    ASSERT_EQ(j.at("coefficients").size(), 9u);
    EXPECT_EQ(j.at("coefficients")[0].size(), 3u);
    EXPECT_EQ(j.at("order"), 2);
}

} // namespace
} // namespace burnish
