// Diffuse AA (the cone-of-normals integral and its LUT-free curve) and Kaplanyan–Valient cone-angle
// specular AA, from geometric_aa.h.
#include <burnish/core/shading/geometric_aa.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace burnish {
namespace {

// A brute-force estimate of the integral, straight from its definition in Baker & Hill 2012:
// ∫∫ max(UniformSampleCone(u, v, cos θc)·L, 0) du dv, by the midpoint rule on an N×N grid in (u, v).
// It shares nothing with diffuseConeIntegral's closed-form azimuth: it builds each normal as a vector.
double bruteForceCone(double cosAlpha, double cosCone, int N) {
    const double sinAlpha = std::sqrt(std::max(0.0, 1.0 - cosAlpha * cosAlpha));
    // Axis z, light in the xz plane.
    const double lx = sinAlpha;
    const double lz = cosAlpha;
    double sum = 0.0;
    for (int i = 0; i < N; ++i) {
        const double u = (i + 0.5) / N;
        // pbrt's UniformSampleCone: cosθ = (1 − u) + u·cosθc, uniform in solid angle.
        const double cosTheta = (1.0 - u) + u * cosCone;
        const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
        for (int j = 0; j < N; ++j) {
            const double phi = 2.0 * kPi<double> * (j + 0.5) / N;
            const double nx = sinTheta * std::cos(phi);
            sum += std::max(0.0, nx * lx + cosTheta * lz);
        }
    }
    return sum / (double(N) * N);
}

// |Na| of a uniform cone: the mean of cosθ over the cone, (1 + cosθc)/2.
double lengthFromConeCos(double cosCone) {
    return (1.0 + cosCone) / 2.0;
}

// The integral is computed to ~1e-9 (header); comparisons between two evaluations of it, or with
// a closed form, use 1e-8.
constexpr double kIntegralTolerance = 1e-8;

TEST(DiffuseConeIntegral, MatchesBruteForce) {
    // The brute-force midpoint rule on a 1024² grid errs by O(h²) where the terminator crosses the
    // cone (a kink in the integrand): measured max 1.46e-6 over these cases (printed below), at the
    // widest cones. 5e-6 is that error ×3.4, still 1000× below any visible difference.
    constexpr int kGrid = 1024;
    constexpr double kBruteForceTolerance = 5e-6;
    double maxError = 0.0;
    for (const double cosCone : {0.999, 0.9, 0.5, 0.0, -0.5}) {
        for (const double cosAlpha : {-0.9, -0.3, 0.0, 0.2, 0.5, 0.95}) {
            const double exact = diffuseConeIntegral(cosAlpha, cosCone);
            const double brute = bruteForceCone(cosAlpha, cosCone, kGrid);
            maxError = std::max(maxError, std::abs(exact - brute));
            EXPECT_NEAR(exact, brute, kBruteForceTolerance)
                << "cosAlpha = " << cosAlpha << " cosCone = " << cosCone;
        }
    }
    std::printf("[measured] max |diffuseConeIntegral − brute force (1024²)|: %.2e\n", maxError);
}

TEST(DiffuseConeIntegral, NoConeIsTheClampedCosine) {
    constexpr double kExact = 0.0;
    for (const double a : {-1.0, -0.5, 0.0, 0.3, 1.0})
        EXPECT_NEAR(diffuseConeIntegral(a, 1.0), saturate(a), kExact);
    // A cone of half-angle ~1.4e-6 rad (cos = 1 − 1e-12) differs from the limit by at most its
    // width: at a = 0 the mean is θc·(1/π)·(2/3) ≈ 3e-7.
    constexpr double kTinyConeTolerance = 1e-6;
    for (const double a : {-0.5, 0.0, 0.3, 1.0})
        EXPECT_NEAR(diffuseConeIntegral(a, 1.0 - 1e-12), saturate(a), kTinyConeTolerance) << "a = " << a;
}

TEST(DiffuseConeIntegral, FarFromTheTerminatorIsLengthTimesCosine) {
    for (const double cosCone : {0.99, 0.9, 0.7, 0.3}) {
        const double sinCone = std::sqrt(1.0 - cosCone * cosCone);
        // The cone's length |Na| and the header's inverse relation cos θc = 2|Na| − 1.
        const double lenNa = lengthFromConeCos(cosCone);
        EXPECT_NEAR(coneCosFromNormalLength(lenNa), cosCone, 1e-15);
        for (int i = 0; i <= 20; ++i) {
            const double a = -1.0 + 2.0 * i / 20.0;
            if (a >= sinCone) {
                // Every normal of the cone faces the light: the clamp never acts, the mean of n·l
                // is that of the mean normal.
                EXPECT_NEAR(diffuseConeIntegral(a, cosCone), lenNa * a, kIntegralTolerance) << "a = " << a;
            } else if (a <= -sinCone) {
                EXPECT_NEAR(diffuseConeIntegral(a, cosCone), 0.0, kIntegralTolerance) << "a = " << a;
            } else {
                // Across the terminator the clamp adds light.
                EXPECT_GT(diffuseConeIntegral(a, cosCone), std::max(lenNa * a, 0.0)) << "a = " << a;
            }
        }
    }
}

TEST(DiffuseConeIntegral, OddPartIsTheMeanNormal) {
    // max(0, x) − max(0, −x) = x, and I(−a) is the mean of max(0, −n·l): so I(a) − I(−a) is the
    // mean of n·l over the cone, |Na|·a, at every a and cone, through the terminator too.
    for (const double cosCone : {0.95, 0.5, 0.0, -0.6, -1.0}) {
        const double lenNa = lengthFromConeCos(cosCone);
        for (int i = 0; i <= 20; ++i) {
            const double a = -1.0 + 2.0 * i / 20.0;
            EXPECT_NEAR(diffuseConeIntegral(a, cosCone) - diffuseConeIntegral(-a, cosCone), lenNa * a,
                        kIntegralTolerance)
                << "a = " << a << " cosCone = " << cosCone;
        }
    }
    // The whole sphere (cosCone = −1): I = 1/4 for every light, the mean of max(0, cosθ) over the sphere.
    EXPECT_NEAR(diffuseConeIntegral(0.3, -1.0), 0.25, kIntegralTolerance);
}

TEST(DiffuseConeIntegral, MonotonicInTheLightCosine) {
    for (const double cosCone : {0.95, 0.5, -0.5}) {
        double previous = -1.0;
        for (int i = 0; i <= 200; ++i) {
            const double I = diffuseConeIntegral(-1.0 + i / 100.0, cosCone);
            EXPECT_GE(I, previous - kIntegralTolerance);
            previous = I;
        }
    }
}

TEST(DiffuseConeIntegral, ClampsItsInputs) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(diffuseConeIntegral(2.0, 0.9), diffuseConeIntegral(1.0, 0.9));
    EXPECT_EQ(diffuseConeIntegral(0.5, 3.0), 0.5);
    EXPECT_EQ(diffuseConeIntegral(0.5, -3.0), diffuseConeIntegral(0.5, -1.0));
    for (const double a : {nan, -1.0, 0.0, 1.0})
        for (const double c : {nan, -1.0, 0.0, 1.0})
            EXPECT_TRUE(std::isfinite(diffuseConeIntegral(a, c)));
}

// ---------------------------------------------------------------------------------------------
// The LUT-free curve.

// The published constants satisfy 4·c0·c1 = 1 (what makes the x² tail meet the line with equal
// value and slope) to their printed 6 digits: measured |4·c0·c1 − 1| = 8.5e-7.
constexpr double kPublishedConstantRounding = 2e-6;

TEST(DiffuseAaCurve, ContinuousAtTheSwitchPoints) {
    EXPECT_NEAR(4.0 * kDiffuseAaC0 * kDiffuseAaC1, 1.0, kPublishedConstantRounding);
    for (const double w : {0.95, 0.97, 0.99, 0.999}) {
        const double x = std::sqrt(1.0 - w);
        // Upper switch: c0·a = c1·x; the tail n²/x meets the line saturate(a).
        const double aUp = kDiffuseAaC1 * x / kDiffuseAaC0;
        const double tailAtUp = w * std::pow(kDiffuseAaC0 * aUp + kDiffuseAaC1 * x, 2.0) / x;
        EXPECT_NEAR(tailAtUp, w * aUp, kPublishedConstantRounding * aUp);
        // Slopes: d/da of w·n²/x is w·2n·c0/x = w·4c0c1 at the switch; the line's is w.
        EXPECT_NEAR(w * 2.0 * (2.0 * kDiffuseAaC1 * x) * kDiffuseAaC0 / x, w, kPublishedConstantRounding);
        // And the function itself, sampled just either side: the jump is the slope times the step.
        const double h = 1e-7;
        const double jumpTolerance = 2.0 * h * w + kPublishedConstantRounding * aUp;
        EXPECT_NEAR(diffuseAaCurve(aUp + h, w), diffuseAaCurve(aUp - h, w), jumpTolerance);
        const double slopeLeft = (diffuseAaCurve(aUp - h, w) - diffuseAaCurve(aUp - 2.0 * h, w)) / h;
        const double slopeRight = (diffuseAaCurve(aUp + 2.0 * h, w) - diffuseAaCurve(aUp + h, w)) / h;
        // Finite differences of step 1e-7 carry ~1e-9/1e-7 round-off plus the slope change over 2h.
        constexpr double kSlopeTolerance = 1e-4;
        EXPECT_NEAR(slopeLeft, slopeRight, kSlopeTolerance) << "w = " << w;
        // Lower switch: c0·a = −c1·x, n = 0: the tail starts at 0 with slope 0, like saturate(a).
        const double aDown = -aUp;
        EXPECT_NEAR(diffuseAaCurve(aDown + h, w), 0.0, jumpTolerance);
        EXPECT_EQ(diffuseAaCurve(aDown - h, w), 0.0);
    }
}

TEST(DiffuseAaCurve, LinearFarFromTheTerminator) {
    for (const double lenNa : {0.95, 0.98, 0.999, 1.0}) {
        const double x = std::sqrt(1.0 - lenNa);
        for (int i = 0; i <= 40; ++i) {
            const double a = -1.0 + i / 20.0;
            if (std::abs(kDiffuseAaC0 * a) > kDiffuseAaC1 * x) {
                EXPECT_EQ(diffuseAaCurve(a, lenNa), lenNa * saturate(a)) << "a = " << a;
            }
        }
    }
    // |Na| below the supported range is treated as 0.95.
    EXPECT_EQ(diffuseAaCurve(0.9, 0.5), diffuseAaCurve(0.9, kDiffuseAaMinLength));
    // A flat footprint: the plain clamped cosine.
    EXPECT_EQ(diffuseAaCurve(0.0, 1.0), 0.0);
    EXPECT_EQ(diffuseAaCurve(0.4, 1.0), 0.4);
}

TEST(DiffuseAaCurve, CloseToTheExactIntegral) {
    double maxError = 0.0;
    double argA = 0.0;
    double argLen = 0.0;
    // |Na| every 0.002, a every 0.01 (both grids contain the maximum's neighbourhood, near a = 0).
    for (int i = 0; i <= 25; ++i) {
        const double lenNa = 0.95 + 0.05 * i / 25.0;
        const double cosCone = coneCosFromNormalLength(lenNa);
        for (int j = 0; j <= 200; ++j) {
            const double a = -1.0 + 2.0 * j / 200.0;
            const double e = std::abs(diffuseAaCurve(a, lenNa) - diffuseConeIntegral(a, cosCone));
            if (e > maxError) {
                maxError = e;
                argA = a;
                argLen = lenNa;
            }
        }
    }
    std::printf("[measured] max |diffuseAaCurve − diffuseConeIntegral| over |Na| in [0.95, 1], a in [−1, 1]: "
                "%.5f at a = %.3f, |Na| = %.3f\n",
                maxError, argA, argLen);
    // Measured maximum plus ~3% as a regression guard. "Pretty close to the focused LUT" (Baker &
    // Hill 2012): a few thousandths on a quantity of up to 1.
    // Measured 0.00234 at a = 0, |Na| = 0.976.
    constexpr double kCurveMaxError = 0.0024;
    EXPECT_LT(maxError, kCurveMaxError);
}

// ---------------------------------------------------------------------------------------------
// Kaplanyan–Valient.

TEST(KaplanyanValient, AngleAndPowerRoundTrip) {
    // The two published constants are k and k² each rounded to 6 significant figures:
    // 4.11893² = 16.96558..., published 16.9656; they agree to 1e-5 relative (half a unit in the
    // 6th digit of 16.9656 is 5e-5 absolute, 3e-6 relative).
    constexpr double kPublishedRelativeRounding = 3e-6;
    EXPECT_NEAR(kKvAngleConstant * kKvAngleConstant / kKvPowerConstant, 1.0, kPublishedRelativeRounding);
    // With the published pair the round trip is therefore exact to that rounding ...
    for (const double n : {1.0, 8.0, 100.0, 8192.0, 1e6}) {
        EXPECT_NEAR(kvPowerFromConeAngle(kvConeAngleFromPower(n)) / n, 1.0, kPublishedRelativeRounding) << n;
        // ... and with k² passed as the power constant, exact to round-off.
        constexpr double kRoundOff = 1e-14;
        const double k = kKvAngleConstant;
        EXPECT_NEAR(kvPowerFromConeAngle(kvConeAngleFromPower(n, k), k * k) / n, 1.0, kRoundOff) << n;
    }
    EXPECT_NEAR(kvConeAngleFromPower(16.0), kKvAngleConstant / 4.0, 1e-15);
}

TEST(KaplanyanValient, CurvatureWidens) {
    constexpr double kPublishedRelativeRounding = 3e-6; // see AngleAndPowerRoundTrip
    for (const double n : {8.0, 256.0, 8192.0}) {
        EXPECT_NEAR(kvCurvatureAdjustedPower(n, 0.0) / n, 1.0, kPublishedRelativeRounding);
        // Negative curvature is not a sharpening: it is clamped to 0.
        EXPECT_EQ(kvCurvatureAdjustedPower(n, -0.5), kvCurvatureAdjustedPower(n, 0.0));
        double previous = kvCurvatureAdjustedPower(n, 0.0);
        for (const double curvature : {0.001, 0.01, 0.1, 0.5, 1.0}) {
            const double p = kvCurvatureAdjustedPower(n, curvature);
            EXPECT_LT(p, previous) << "n = " << n << " curvature = " << curvature;
            // Baker & Hill 2012: angle = 4.11893/sqrt(power) + curvature; power = 16.9656/angle².
            const double angle = kKvAngleConstant / std::sqrt(n) + curvature;
            EXPECT_NEAR(p, kKvPowerConstant / (angle * angle), 1e-12 * p);
            previous = p;
        }
    }
    // A zero angle is a mirror: the largest power.
    EXPECT_EQ(kvPowerFromConeAngle(0.0), kMaxPower);
}

} // namespace
} // namespace burnish
