// Extreme inputs: every public function of ndf.h, fresnel.h, visibility.h, spherical_gaussian.h,
// geometric_aa.h and gloss.h is evaluated over powers, cosines, mean-normal lengths, roughnesses and
// variances at and beyond the ends of their ranges, in float and double: every result must be
// finite. Then half-float and 8-bit storage of gloss and variance.
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/shading/fresnel.h>
#include <burnish/core/shading/geometric_aa.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/spherical_gaussian.h>
#include <burnish/core/shading/visibility.h>

#include <Imath/half.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace burnish {
namespace {

template <class T> const std::vector<T>& powers() {
    static const std::vector<T> values{T(0),
                                       T(1e-6),
                                       T(1),
                                       T(2),
                                       T(8192),
                                       T(1e6),
                                       T(1e9),
                                       T(-1),
                                       T(-1e9),
                                       std::numeric_limits<T>::quiet_NaN(),
                                       std::numeric_limits<T>::infinity()};
    return values;
}

template <class T> const std::vector<T>& cosines() {
    // 1e-30: a cosine whose square and fourth power underflow float (denormal / zero).
    static const std::vector<T> values{T(-1), T(0), T(1e-30), T(1e-7), T(1) - T(1e-7), T(1)};
    return values;
}

template <class T> const std::vector<T>& lengths() {
    static const std::vector<T> values{T(0), T(1e-9), T(1) - T(1e-9), T(1)};
    return values;
}

// Roughness (Beckmann m, GGX α): the bridges of every power, and raw values at and past the ends.
template <class T> std::vector<T> roughnesses() {
    std::vector<T> values{T(0),
                          T(1e-9),
                          T(1),
                          T(2),
                          T(1e9),
                          T(-1),
                          std::numeric_limits<T>::quiet_NaN(),
                          std::numeric_limits<T>::infinity()};
    for (const T n : powers<T>())
        values.push_back(beckmannRoughnessFromPower(n));
    return values;
}

// Specular colours and gloss values in [0, 1], with their ends.
template <class T> const std::vector<T>& units() {
    static const std::vector<T> values{T(0), T(1e-7), T(0.04), T(0.5), T(1) - T(1e-7), T(1)};
    return values;
}

template <class T> std::string describe(std::initializer_list<T> args) {
    std::ostringstream s;
    s.precision(9);
    s << (sizeof(T) == 4 ? "float(" : "double(");
    for (const T a : args)
        s << a << " ";
    s << ")";
    return s.str();
}

#define EXPECT_FINITE(expr, ...)                                                                             \
    EXPECT_TRUE(std::isfinite(static_cast<double>(expr)))                                                    \
        << #expr << " = " << (expr) << " at " << describe<T>({__VA_ARGS__})

template <class T> void sweepNdf() {
    for (const T n : powers<T>()) {
        EXPECT_FINITE(blinnPhongNdfNorm(n), n);
        EXPECT_FINITE(phongLobeNorm(n), n);
        EXPECT_FINITE(phongBrdfNorm(n), n);
        EXPECT_FINITE(blinnPhongLobeNorm(n), n);
        EXPECT_FINITE(blinnPhongBrdfNorm(n), n);
        EXPECT_FINITE(blinnPhongBrdfNormApprox(n), n);
        EXPECT_FINITE(beckmannRoughnessFromPower(n), n);
        EXPECT_FINITE(ggxAlphaFromPower(n), n);
        for (const T c : cosines<T>())
            EXPECT_FINITE(blinnPhongNdf(c, n), c, n);
    }
    for (const T m : roughnesses<T>()) {
        EXPECT_FINITE(powerFromBeckmannRoughness(m), m);
        EXPECT_FINITE(powerFromGgxAlpha(m), m);
        for (const T c : cosines<T>()) {
            EXPECT_FINITE(beckmannNdf(c, m), c, m);
            EXPECT_FINITE(ggxNdf(c, m), c, m);
        }
    }
    EXPECT_FINITE(lambertBrdf<T>());
    for (const T c : cosines<T>()) {
        // The largest BRDF value core produces (the normalized peak at kMaxPower) times a unit light.
        const T peak = blinnPhongNdf(T(1), T(kMaxPower));
        EXPECT_FINITE(punctualRadiance(peak, T(1), c), c);
        EXPECT_FINITE(punctualRadiance(lambertBrdf<T>(), T(1), c), c);
    }
}

template <class T> void sweepFresnel() {
    for (const T c : units<T>()) {
        EXPECT_FINITE(iorFromF0(c), c);
        for (const T x : cosines<T>()) {
            EXPECT_FINITE(fresnelSchlick(c, x), c, x);
            EXPECT_FINITE(fresnelSchlickSg(c, x), c, x);
            EXPECT_FINITE(fresnelSchlickSgQuadratic(c, x), c, x);
            EXPECT_FINITE(fresnelDielectric(c, x), c, x);
            for (const T p : powers<T>())
                EXPECT_FINITE(fresnelSchlickPow(c, x, p), c, x, p);
            for (const T g : units<T>())
                EXPECT_FINITE(fresnelGlossy(c, x, g), c, x, g);
        }
    }
}

template <class T> void sweepVisibility() {
    EXPECT_FINITE(visibilityNone<T>());
    for (const T n : powers<T>())
        EXPECT_FINITE(schlickSmithA(n), n);
    for (const T l : cosines<T>()) {
        EXPECT_FINITE(visibilityKelemen(l), l);
        for (const T v : cosines<T>()) {
            for (const T n : powers<T>())
                EXPECT_FINITE(visibilitySchlickSmith(l, v, n), l, v, n);
            for (const T m : roughnesses<T>()) {
                EXPECT_FINITE(visibilitySmithBeckmann(l, v, m), l, v, m);
                EXPECT_FINITE(visibilitySmithGgxCorrelated(l, v, m), l, v, m);
            }
            for (const T h : cosines<T>())
                for (const T vh : cosines<T>())
                    EXPECT_FINITE(visibilityCookTorrance(l, v, h, vh), l, v, h, vh);
        }
        for (const T m : roughnesses<T>())
            EXPECT_FINITE(smithBeckmannG1(l, m), l, m);
    }
}

template <class T> void sweepSphericalGaussian() {
    for (const T c : cosines<T>()) {
        for (const T n : powers<T>()) {
            for (const T x : {T(kSgOffsetPlain), T(kSgOffsetLagarde), T(kSgOffsetLimit)})
                EXPECT_FINITE(sgLobe(c, n, x), c, n, x);
            // The exp2 form takes the power already divided by ln 2.
            EXPECT_FINITE(sgLobeExp2(c, n), c, n);
            EXPECT_FINITE(sgLobeExp2(c, n / kLn2<T>), c, n);
        }
    }
}

template <class T> void sweepGeometricAa() {
    for (const T len : lengths<T>()) {
        EXPECT_FINITE(coneCosFromNormalLength(len), len);
        for (const T a : cosines<T>())
            EXPECT_FINITE(diffuseAaCurve(a, len), a, len);
    }
    for (const T n : powers<T>()) {
        EXPECT_FINITE(kvConeAngleFromPower(n), n);
        // Angles: the angles of every power, and the power list itself as raw angles.
        EXPECT_FINITE(kvPowerFromConeAngle(kvConeAngleFromPower(n)), n);
        EXPECT_FINITE(kvPowerFromConeAngle(n), n);
        // Curvature is sqrt(1 − n·n') in [0, 1]; also past both ends.
        for (const T curvature : {T(-1), T(0), T(1e-7), T(1), T(2)})
            EXPECT_FINITE(kvCurvatureAdjustedPower(n, curvature), n, curvature);
    }
}

TEST(Extremes, FloatKernelsStayFinite) {
    using T = float;
    sweepNdf<T>();
    sweepFresnel<T>();
    sweepVisibility<T>();
    sweepSphericalGaussian<T>();
    sweepGeometricAa<T>();
}

TEST(Extremes, DoubleKernelsStayFinite) {
    using T = double;
    sweepNdf<T>();
    sweepFresnel<T>();
    sweepVisibility<T>();
    sweepSphericalGaussian<T>();
    sweepGeometricAa<T>();
}

TEST(Extremes, DoubleOnlyFunctionsStayFinite) {
    using T = double;
    // diffuseConeIntegral: light cosines × cone cosines from every |Na|, and NaN.
    const T nan = std::numeric_limits<T>::quiet_NaN();
    std::vector<T> cones{nan, T(-1), T(2)};
    for (const T len : lengths<T>())
        cones.push_back(coneCosFromNormalLength(len));
    std::vector<T> lights = cosines<T>();
    lights.push_back(nan);
    for (const T a : lights)
        for (const T c : cones)
            EXPECT_FINITE(diffuseConeIntegral(a, c), a, c);

    const SgOffsetCurve empty;
    const SgOffsetCurve curve({1.0, 100.0}, {0.5, 0.75});
    for (const T n : powers<T>()) {
        EXPECT_FINITE(empty(n), n);
        EXPECT_FINITE(curve(n), n);
    }
}

std::vector<GlossEncoding> allEncodings() {
    std::vector<GlossEncoding> encodings;
    for (const auto& name : GlossEncoding::presetNames())
        encodings.push_back(GlossEncoding::fromName(name).value());
    encodings.push_back(GlossEncoding::logRange(1e-6, kMaxPower).value());
    return encodings;
}

const VarianceConvention kConventions[] = {VarianceConvention::InversePower,
                                           VarianceConvention::InversePowerPlusOne,
                                           VarianceConvention::InversePowerPlusTwo};

TEST(Extremes, GlossFunctionsStayFinite) {
    using T = double;
    const T nan = std::numeric_limits<T>::quiet_NaN();
    const T inf = std::numeric_limits<T>::infinity();
    std::vector<T> stored = units<T>();
    stored.insert(stored.end(), {nan, T(-1), T(2), inf, -inf});
    std::vector<T> variances = powers<T>(); // variance exactly 0, tiny, huge, NaN, negative, inf
    std::vector<T> lens = lengths<T>();
    lens.insert(lens.end(), {nan, T(-1), T(2)});

    for (const auto& e : allEncodings()) {
        EXPECT_FINITE(e.minPower());
        EXPECT_FINITE(e.maxPower());
        for (const T v : stored) {
            EXPECT_FINITE(e.power(v), v);
            for (const T var : variances)
                EXPECT_FINITE(varianceToGloss(v, var, e), v, var);
        }
        for (const T n : powers<T>())
            EXPECT_FINITE(e.value(n), n);
    }
    for (const auto conv : kConventions) {
        for (const T n : powers<T>())
            EXPECT_FINITE(varianceFromPower(n, conv), n);
        for (const T v : variances) {
            EXPECT_FINITE(powerFromVariance(v, conv), v);
            EXPECT_GE(powerFromVariance(v, conv), 0.0);
        }
    }
    for (const T len : lens) {
        EXPECT_FINITE(toksvigVariance(len), len);
        for (const T s : powers<T>()) {
            EXPECT_FINITE(toksvigFactor(len, s), len, s);
            EXPECT_FINITE(toksvigPower(len, s), len, s);
        }
    }
    for (const T ft : stored)
        for (const T fixedS : powers<T>())
            for (const T s : powers<T>())
                EXPECT_FINITE(convertToksvigFactor(ft, fixedS, s), ft, fixedS, s);
    for (const T v : variances)
        EXPECT_FINITE(encodeLogVariance(v), v);
    for (const T g : stored)
        EXPECT_FINITE(decodeLogVariance(g), g);
}

// ---------------------------------------------------------------------------------------------
// Storage: half floats and 8-bit channels.

// Every one of the 65536 half bit patterns (NaN, ±inf, denormals and negatives included).
std::vector<float> allHalfValues() {
    std::vector<float> values;
    values.reserve(1 << 16);
    for (uint32_t bits = 0; bits < (1u << 16); ++bits) {
        Imath::half h;
        h.setBits(static_cast<uint16_t>(bits));
        values.push_back(static_cast<float>(h));
    }
    return values;
}

TEST(Extremes, HalfStoredGlossDecodesToFinitePowers) {
    const auto halves = allHalfValues();
    for (const auto& e : allEncodings()) {
        for (const float h : halves) {
            const double n = e.power(h);
            ASSERT_TRUE(std::isfinite(n)) << e.name() << " half " << h;
            ASSERT_GE(n, 0.0) << e.name() << " half " << h;
        }
        // And each encoding's own values, stored as half and read back.
        for (int i = 0; i <= 1000; ++i) {
            const double v = e.value(e.power(i / 1000.0));
            const Imath::half stored(static_cast<float>(v));
            EXPECT_TRUE(std::isfinite(e.power(static_cast<float>(stored)))) << e.name() << " v = " << v;
        }
    }
}

TEST(Extremes, HalfStoredVarianceDecodesToFinitePowers) {
    const auto halves = allHalfValues();
    for (const auto conv : kConventions) {
        for (const float h : halves) {
            const double n = powerFromVariance(h, conv);
            ASSERT_TRUE(std::isfinite(n)) << "half " << h;
            ASSERT_GE(n, 0.0) << "half " << h;
            ASSERT_TRUE(std::isfinite(varianceToGloss(0.5, h, GlossEncoding::blackOps()))) << "half " << h;
        }
        // Variances of every power, through half: 1/kMaxPower underflows half (its smallest denormal
        // is 6e-8) to 0, which must read back as the largest power, not as infinity.
        for (const double n : powers<double>()) {
            const Imath::half stored(static_cast<float>(varianceFromPower(n, conv)));
            EXPECT_TRUE(std::isfinite(powerFromVariance(static_cast<float>(stored), conv))) << "n = " << n;
        }
    }
    for (const float h : halves) {
        ASSERT_TRUE(std::isfinite(toksvigVariance(h))) << "half |Na| " << h;
        ASSERT_TRUE(std::isfinite(toksvigPower(h, 8192.0))) << "half |Na| " << h;
        ASSERT_TRUE(std::isfinite(decodeLogVariance(h))) << "half g " << h;
    }
}

TEST(Extremes, EightBitGlossDecodesToFiniteMonotonicPowers) {
    for (const auto& e : allEncodings()) {
        double previous = e.power(0.0);
        for (int code = 0; code <= 255; ++code) {
            // round(g·255)/255, the value an 8-bit channel reads back.
            const double g = std::round(code / 255.0 * 255.0) / 255.0;
            const double n = e.power(g);
            ASSERT_TRUE(std::isfinite(n)) << e.name() << " code " << code;
            if (e.increasesWithPower())
                EXPECT_GE(n, previous) << e.name() << " code " << code;
            else
                EXPECT_LE(n, previous) << e.name() << " code " << code;
            previous = n;
        }
        // Quantizing any gloss to 8 bits and back stays finite, for every encoding's whole range.
        for (int i = 0; i <= 1000; ++i) {
            const double g = std::round(i / 1000.0 * 255.0) / 255.0;
            EXPECT_TRUE(std::isfinite(e.power(g))) << e.name();
        }
    }
}

TEST(Extremes, PowerThroughHalfLogVarianceIsFiniteAndMonotonic) {
    // power → per-axis slope variance (1/(n+2)) → log-space value (Baker & Hill 2012) → half → back.
    double previous = -1.0;
    for (int i = 0; i <= 1500; ++i) {
        const double n = std::pow(10.0, -6.0 + i / 100.0); // 1e-6 .. 1e9
        const double sigma2 = varianceFromPower(n, VarianceConvention::InversePowerPlusTwo);
        const Imath::half stored(static_cast<float>(encodeLogVariance(sigma2)));
        const double back = powerFromVariance(decodeLogVariance(static_cast<float>(stored)),
                                              VarianceConvention::InversePowerPlusTwo);
        ASSERT_TRUE(std::isfinite(back)) << "n = " << n;
        EXPECT_GE(back, previous) << "n = " << n;
        previous = back;
    }
    // The encoding covers Σ in [2^-13, 1]: the highest power that survives is 2^13 − 2.
    constexpr double kExact = 1e-9;
    EXPECT_NEAR(previous, 8192.0 - 2.0, kExact);
}

} // namespace
} // namespace burnish
