// Gloss encodings and the power / variance / Toksvig conversions of gloss.h.
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/shading/ndf.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace burnish {
namespace {

// Closed forms evaluated two ways (pow vs exp2, a division rearranged): a few ulps.
constexpr double kFormulaTolerance = 1e-12;
// Fine grid of stored values for monotonicity and round trips: 2^16 steps, the resolution of a
// 16-bit channel.
constexpr int kFineSteps = 1 << 16;

std::vector<GlossEncoding> allEncodings() {
    std::vector<GlossEncoding> encodings;
    for (const auto& name : GlossEncoding::presetNames())
        encodings.push_back(GlossEncoding::fromName(name).value());
    encodings.push_back(GlossEncoding::logRange(0.5, 1e6).value());
    return encodings;
}

TEST(GlossPresets, BlackOps) {
    const auto e = GlossEncoding::blackOps();
    EXPECT_EQ(e.name(), "blackops");
    EXPECT_NEAR(e.power(0.0), 1.0, kFormulaTolerance);
    EXPECT_NEAR(e.power(1.0), 8192.0, kFormulaTolerance * 8192.0);
    EXPECT_NEAR(e.power(0.5), std::sqrt(8192.0), kFormulaTolerance * 100.0);
    for (int i = 0; i <= 100; ++i) {
        const double g = i / 100.0;
        // Lazarov 2011: n = 8192^g = 2^(13g).
        EXPECT_NEAR(e.power(g) / std::exp2(13.0 * g), 1.0, kFormulaTolerance) << "g = " << g;
    }
    EXPECT_EQ(e.minPower(), 1.0);
    EXPECT_EQ(e.maxPower(), 8192.0);
    EXPECT_TRUE(e.increasesWithPower());
}

TEST(GlossPresets, Exp2) {
    const auto e = GlossEncoding::exp2Range();
    EXPECT_NEAR(e.power(0.0), 2.0, kFormulaTolerance);
    EXPECT_NEAR(e.power(1.0), 2048.0, kFormulaTolerance * 2048.0);
    for (int i = 0; i <= 100; ++i) {
        const double g = i / 100.0;
        // Lagarde 2011: n = exp2(10g + 1).
        EXPECT_NEAR(e.power(g) / std::exp2(10.0 * g + 1.0), 1.0, kFormulaTolerance) << "g = " << g;
    }
}

TEST(GlossPresets, RoughnessKinds) {
    // GGX perceptual roughness r: α = r², n = 2/α² − 2.
    const auto r = GlossEncoding::ggxRoughness();
    EXPECT_NEAR(r.power(0.5), 2.0 / std::pow(0.25, 2.0) - 2.0, kFormulaTolerance * 30.0);
    EXPECT_NEAR(r.power(1.0), 0.0, kFormulaTolerance);
    EXPECT_EQ(r.power(0.0), kMaxPower);
    EXPECT_FALSE(r.increasesWithPower());
    // Smoothness s = 1 − r.
    const auto s = GlossEncoding::smoothness();
    EXPECT_NEAR(s.power(0.5), r.power(0.5), kFormulaTolerance * 30.0);
    EXPECT_NEAR(s.power(0.8), r.power(0.2), kFormulaTolerance * r.power(0.2));
    EXPECT_TRUE(s.increasesWithPower());
    // α and Beckmann m stored directly: n = 2/v² − 2.
    for (const auto& e : {GlossEncoding::ggxAlpha(), GlossEncoding::beckmann()}) {
        EXPECT_NEAR(e.power(0.5), 6.0, kFormulaTolerance);
        EXPECT_NEAR(e.power(0.5), powerFromBeckmannRoughness(0.5), kFormulaTolerance);
        EXPECT_FALSE(e.increasesWithPower());
    }
}

TEST(GlossNames, LogRangeParsing) {
    const auto blackOps = GlossEncoding::fromName("log:1:8192");
    ASSERT_TRUE(blackOps.ok()) << blackOps.error();
    const auto exp2 = GlossEncoding::fromName("log:2:2048");
    ASSERT_TRUE(exp2.ok()) << exp2.error();
    const auto custom = GlossEncoding::fromName("log:0.5:1e6");
    ASSERT_TRUE(custom.ok()) << custom.error();
    for (int i = 0; i <= 100; ++i) {
        const double g = i / 100.0;
        EXPECT_NEAR(blackOps->power(g) / GlossEncoding::blackOps().power(g), 1.0, kFormulaTolerance);
        EXPECT_NEAR(exp2->power(g) / GlossEncoding::exp2Range().power(g), 1.0, kFormulaTolerance);
    }
    EXPECT_NEAR(custom->minPower(), 0.5, 0.0);
    EXPECT_NEAR(custom->maxPower(), 1e6, 0.0);
    EXPECT_EQ(custom->name(), "log:0.5:1e+06");
}

TEST(GlossNames, LogRangeErrors) {
    for (const char* bad : {"log:", "log:1", "log:1:", "log::8", "log:a:8", "log:1:8x", "log:1:2:3",
                            "log:nan:8", "log:1:inf"}) {
        const auto r = GlossEncoding::fromName(bad);
        EXPECT_FALSE(r.ok()) << bad;
        EXPECT_NE(r.error().find("log:NMIN:NMAX"), std::string::npos) << r.error();
    }
    // Well-formed but out of domain: 0 < nMin < nMax <= kMaxPower.
    for (const char* bad : {"log:0:8", "log:-1:8", "log:8:8", "log:8:2", "log:1:1e10"}) {
        const auto r = GlossEncoding::fromName(bad);
        EXPECT_FALSE(r.ok()) << bad;
        EXPECT_NE(r.error().find("0 < n_min < n_max"), std::string::npos) << r.error();
    }
    EXPECT_FALSE(GlossEncoding::logRange(1.0, std::numeric_limits<double>::quiet_NaN()).ok());
    EXPECT_TRUE(GlossEncoding::logRange(1.0, kMaxPower).ok());
}

TEST(GlossNames, UnknownNameListsTheKnownOnes) {
    for (const char* bad : {"", "BlackOps", "ggx", "blackops ", "exp"}) {
        const auto r = GlossEncoding::fromName(bad);
        ASSERT_FALSE(r.ok()) << bad;
        EXPECT_NE(r.error().find("'" + std::string(bad) + "'"), std::string::npos) << r.error();
        for (const auto& known : GlossEncoding::presetNames())
            EXPECT_NE(r.error().find(known), std::string::npos) << known << " missing from: " << r.error();
        EXPECT_NE(r.error().find("log:NMIN:NMAX"), std::string::npos);
    }
    // Every listed name resolves, to an encoding of that name.
    for (const auto& known : GlossEncoding::presetNames()) {
        const auto r = GlossEncoding::fromName(known);
        ASSERT_TRUE(r.ok()) << known;
        EXPECT_EQ(r->name(), known);
        EXPECT_FALSE(r->formula().empty());
    }
}

TEST(GlossEncodings, StrictlyMonotonic) {
    for (const auto& e : allEncodings()) {
        double previous = e.power(0.0);
        for (int i = 1; i <= kFineSteps; ++i) {
            const double n = e.power(double(i) / kFineSteps);
            // Roughness kinds hold kMaxPower for the stored values whose roughness is below that of
            // kMaxPower (α < sqrt(2/(kMaxPower+2)) ≈ 4.5e-5): the only place the order is not strict.
            if (n == kMaxPower && previous == kMaxPower) continue;
            if (e.increasesWithPower())
                EXPECT_GT(n, previous) << e.name() << " v = " << double(i) / kFineSteps;
            else
                EXPECT_LT(n, previous) << e.name() << " v = " << double(i) / kFineSteps;
            previous = n;
        }
    }
}

TEST(GlossEncodings, RoundTripOverTheRange) {
    // value(power(v)) = v wherever the power is not clamped to kMaxPower. The inverse goes through a
    // log (log kinds) or two square roots and a reciprocal (roughness kinds): measured worst 2.2e-16
    // absolute (one ulp of 1) on this 2^16 grid; 1e-12 leaves room for other libm implementations
    // while catching any formula change (a 16-bit step is 1.5e-5).
    constexpr double kRoundTripTolerance = 1e-12;
    for (const auto& e : allEncodings()) {
        for (int i = 0; i <= kFineSteps; ++i) {
            const double v = double(i) / kFineSteps;
            const double n = e.power(v);
            if (n >= kMaxPower) continue;
            EXPECT_NEAR(e.value(n), v, kRoundTripTolerance) << e.name() << " v = " << v;
        }
        // The power range and the stored range correspond at their ends.
        EXPECT_NEAR(e.value(e.minPower()), e.increasesWithPower() ? 0.0 : 1.0, kRoundTripTolerance)
            << e.name();
        // Powers outside the range clamp to its ends; NaN is the lower end of the power range.
        EXPECT_EQ(e.value(1e12), e.value(e.maxPower())) << e.name();
        EXPECT_EQ(e.value(-3.0), e.value(e.minPower())) << e.name();
        EXPECT_EQ(e.value(std::numeric_limits<double>::quiet_NaN()), e.value(e.minPower())) << e.name();
        EXPECT_EQ(e.power(2.0), e.power(1.0)) << e.name();
        EXPECT_EQ(e.power(-1.0), e.power(0.0)) << e.name();
    }
}

// ---------------------------------------------------------------------------------------------
// Variance.

TEST(Variance, RoundTripPerConvention) {
    constexpr double kRoundTripTolerance = 1e-12; // relative: a reciprocal and an add
    for (const auto conv : {VarianceConvention::InversePower, VarianceConvention::InversePowerPlusOne,
                            VarianceConvention::InversePowerPlusTwo}) {
        for (const double n : {0.5, 1.0, 8.0, 1000.0, 1e6, 1e8}) {
            EXPECT_NEAR(powerFromVariance(varianceFromPower(n, conv), conv) / n, 1.0, kRoundTripTolerance)
                << n;
        }
        // v = 0 is a perfect mirror: the largest power.
        EXPECT_NEAR(powerFromVariance(0.0, conv), kMaxPower, kRoundTripTolerance * kMaxPower);
        EXPECT_NEAR(powerFromVariance(std::numeric_limits<double>::quiet_NaN(), conv), kMaxPower,
                    kRoundTripTolerance * kMaxPower);
        // A huge variance gives a power of (nearly) 0 and never a negative one: 1/v = 1e-12 under
        // the 1/n convention, 0 after the clamp under the others.
        constexpr double kHugeVariancePower = 1e-12;
        EXPECT_GE(powerFromVariance(1e12, conv), 0.0);
        EXPECT_LE(powerFromVariance(1e12, conv), kHugeVariancePower);
    }
    EXPECT_NEAR(varianceFromPower(9.0, VarianceConvention::InversePower), 1.0 / 9.0, kFormulaTolerance);
    EXPECT_NEAR(varianceFromPower(9.0, VarianceConvention::InversePowerPlusOne), 0.1, kFormulaTolerance);
    EXPECT_NEAR(varianceFromPower(8.0, VarianceConvention::InversePowerPlusTwo), 0.1, kFormulaTolerance);
    // The (n+2) convention is Beckmann's per-axis slope variance m²/2.
    const double m = beckmannRoughnessFromPower(30.0);
    EXPECT_NEAR(varianceFromPower(30.0, VarianceConvention::InversePowerPlusTwo), m * m / 2.0,
                kFormulaTolerance);
}

TEST(Toksvig, VarianceAndFactor) {
    for (const double lenNa : {0.1, 0.5, 0.9, 0.99}) {
        EXPECT_NEAR(toksvigVariance(lenNa), (1.0 - lenNa) / lenNa, kFormulaTolerance);
        for (const double s : {1.0, 16.0, 100.0, 8192.0}) {
            // Toksvig 2004 via Hill 2011: f_t = |Na| / (|Na| + s(1 − |Na|)).
            const double ft = lenNa / (lenNa + s * (1.0 - lenNa));
            EXPECT_NEAR(toksvigFactor(lenNa, s), ft, kFormulaTolerance);
            EXPECT_NEAR(toksvigPower(lenNa, s), ft * s, kFormulaTolerance * s);
            // Equivalently 1/p = 1/s + σ²: Toksvig's variance adds to the lobe's.
            EXPECT_NEAR(1.0 / toksvigPower(lenNa, s), 1.0 / s + toksvigVariance(lenNa),
                        kFormulaTolerance * 1e3);
        }
    }
    // |Na| = 1: no variance, the power is kept.
    EXPECT_EQ(toksvigVariance(1.0), 0.0);
    EXPECT_EQ(toksvigFactor(1.0, 100.0), 1.0);
    EXPECT_EQ(toksvigPower(1.0, 100.0), 100.0);
    // |Na| → 0: the variance reaches its clamp, the factor and the power go to 0.
    EXPECT_EQ(toksvigVariance(0.0), 1.0 / kMinVariance);
    EXPECT_EQ(toksvigFactor(0.0, 100.0), 0.0);
    EXPECT_EQ(toksvigPower(0.0, 100.0), 0.0);
    constexpr double kSmallLength = 1e-9;
    EXPECT_LT(toksvigFactor(kSmallLength, 100.0), 1e-10);
    EXPECT_LE(toksvigVariance(kSmallLength), 1.0 / kMinVariance);
}

TEST(Toksvig, ConvertBakedFactor) {
    // Hill 2011: a factor baked for power 100 converts to the factor computed directly at s.
    const double fixedS = 100.0;
    for (const double lenNa : {0.2, 0.6, 0.9, 0.999, 1.0}) {
        const double ftBaked = toksvigFactor(lenNa, fixedS);
        for (const double s : {1.0, 10.0, 100.0, 500.0, 8192.0}) {
            EXPECT_NEAR(convertToksvigFactor(ftBaked, fixedS, s), toksvigFactor(lenNa, s), kFormulaTolerance)
                << "|Na| = " << lenNa << " s = " << s;
        }
    }
}

TEST(Variance, LogVarianceRoundTrip) {
    // Baker & Hill 2012: g = log2(1/Σ)/13, Σ in [2^-13, 1].
    constexpr double kRoundTripTolerance = 1e-12;
    for (int i = 0; i <= 130; ++i) {
        const double sigma2 = std::exp2(-i / 10.0);
        EXPECT_NEAR(decodeLogVariance(encodeLogVariance(sigma2)) / sigma2, 1.0, kRoundTripTolerance)
            << sigma2;
        EXPECT_NEAR(encodeLogVariance(sigma2), i / 130.0, kRoundTripTolerance);
    }
    // Outside the range: clamped to its ends; 0 and NaN are the smallest variance.
    EXPECT_EQ(encodeLogVariance(2.0), 0.0);
    EXPECT_EQ(encodeLogVariance(1e-6), 1.0);
    EXPECT_EQ(encodeLogVariance(0.0), 1.0);
    EXPECT_EQ(encodeLogVariance(std::numeric_limits<double>::quiet_NaN()), 1.0);
    EXPECT_EQ(decodeLogVariance(1.0), std::exp2(-13.0));
}

TEST(Variance, LogVarianceEndsAreExactAndPositive) {
    // Σ = 1 is +0 (never −0, whose sign bit a float texture would keep), 2^-13 and below exactly 1,
    // an infinite variance 0.
    EXPECT_FALSE(std::signbit(encodeLogVariance(1.0)));
    EXPECT_EQ(encodeLogVariance(1.0), 0.0);
    EXPECT_EQ(encodeLogVariance(std::exp2(-13.0)), 1.0);
    EXPECT_EQ(encodeLogVariance(std::numeric_limits<double>::infinity()), 0.0);
    EXPECT_EQ(encodeLogVariance(-1.0), 1.0);
    EXPECT_EQ(encodeLogVariance(std::numeric_limits<double>::denorm_min()), 1.0);
}

TEST(GlossEncodings, ValuesOfARowMatchValue) {
    // The bake's row form is value() per power as a float, exactly: at and beyond the range's
    // ends, for negative powers and for a NaN power (0's value, not NaN). The log-power kinds are
    // also within 1e-14 of the closed form log(n/nMin)/log(nMax/nMin) and exact at both ends.
    std::vector<double> powers = {
        0.0,    1e-9,   0.5, 1.0, 2.0,  10.0, 100.0,
        2048.0, 8192.0, 1e5, 1e9, 1e12, -3.0, std::numeric_limits<double>::quiet_NaN()};
    for (int i = 0; i <= 4096; ++i)
        powers.push_back(std::exp2(i / 4096.0 * 14.0));
    for (const auto& name : GlossEncoding::presetNames()) {
        const auto encoding = GlossEncoding::fromName(name);
        ASSERT_TRUE(encoding) << name;
        std::vector<float> row(powers.size(), -1.0f);
        encoding->values(powers.data(), row.data(), powers.size());
        for (size_t i = 0; i < powers.size(); ++i) {
            const double expected = encoding->value(powers[i]);
            ASSERT_TRUE(std::isfinite(expected)) << name << " n = " << powers[i];
            EXPECT_EQ(row[i], float(expected)) << name << " n = " << powers[i];
        }
        if (encoding->kind() != GlossKind::LogPower) continue;
        const double lo = encoding->minPower(), hi = encoding->maxPower();
        EXPECT_EQ(encoding->value(lo), 0.0) << name;
        EXPECT_EQ(encoding->value(hi), 1.0) << name;
        for (int i = 0; i <= 1000; ++i) {
            const double n = lo * std::pow(hi / lo, i / 1000.0);
            EXPECT_NEAR(encoding->value(n), std::log(n / lo) / std::log(hi / lo), 1e-14)
                << name << " n = " << n;
        }
    }
}

TEST(Numeric, Log2PositiveMatchesStdLog2) {
    // Within 2e-14 of std::log2 over every binade a double holds and densely over [2^-13, 1] (the
    // log-variance range), exact at powers of two.
    double worst = 0.0;
    for (int e = -1022; e <= 1023; ++e)
        for (int i = 0; i < 64; ++i) {
            const double x = std::ldexp(1.0 + i / 64.0 + 1.0 / 4099.0, e);
            worst = std::max(worst, std::abs(log2Positive(x) - std::log2(x)));
        }
    for (int i = 0; i <= 1 << 20; ++i) {
        const double x = std::exp2(-13.0 * i / double(1 << 20)) * (1.0 + 1e-9 * (i % 7));
        worst = std::max(worst, std::abs(log2Positive(x) - std::log2(x)));
    }
    EXPECT_LT(worst, 2e-14);
    for (int e = -1022; e <= 1023; ++e)
        EXPECT_EQ(log2Positive(std::ldexp(1.0, e)), double(e)) << e;
    EXPECT_EQ(log2Positive(std::numeric_limits<double>::max()),
              std::log2(std::numeric_limits<double>::max()));
}

TEST(Variance, VarianceToGloss) {
    // v = 0 leaves the gloss unchanged: 1/(1/(n+1)) − 1 = n up to round-off, then value(n). Measured
    // worst 1.4e-16 over every encoding; 1e-12 as in the round trip above.
    constexpr double kUnchangedTolerance = 1e-12;
    for (const auto& e : allEncodings()) {
        for (int i = 0; i <= 100; ++i) {
            const double g = i / 100.0;
            if (e.power(g) >= kMaxPower) continue; // the clamped stored values are one power
            EXPECT_NEAR(varianceToGloss(g, 0.0, e), g, kUnchangedTolerance) << e.name() << " g = " << g;
        }
    }
    const auto blackOps = GlossEncoding::blackOps();
    for (int i = 0; i <= 20; ++i) {
        const double g = i / 20.0;
        double previous = varianceToGloss(g, 0.0, blackOps);
        for (const double v : {1e-5, 1e-4, 1e-3, 1e-2, 0.1, 0.5, 1.0}) {
            const double g2 = varianceToGloss(g, v, blackOps);
            // More variance never raises the gloss, and lowers it unless already at the bottom.
            if (previous > 0.0)
                EXPECT_LT(g2, previous) << "g = " << g << " v = " << v;
            else
                EXPECT_EQ(g2, 0.0);
            EXPECT_GE(g2, 0.0);
            EXPECT_LE(g2, 1.0);
            // Lazarov 2011: v' = v + 1/(n+1); v'' = clamp(v', 1/(nMax+1), 1/(nMin+1));
            //               g = log(1/v'' − 1)/log(nMax), for nMin = 1, nMax = 8192.
            const double n = std::pow(8192.0, g);
            const double v2 = std::clamp(v + 1.0 / (n + 1.0), 1.0 / 8193.0, 1.0 / 2.0);
            EXPECT_NEAR(g2, std::log(1.0 / v2 - 1.0) / std::log(8192.0), kFormulaTolerance) << "g = " << g;
            previous = g2;
        }
    }
    // Clamps to the encoding's range: huge variance is its lowest gloss, out-of-range input too.
    EXPECT_EQ(varianceToGloss(1.0, 1e6, blackOps), 0.0);
    EXPECT_NEAR(varianceToGloss(2.0, 0.0, blackOps), 1.0, kUnchangedTolerance);
    EXPECT_EQ(varianceToGloss(0.5, std::numeric_limits<double>::quiet_NaN(), blackOps),
              varianceToGloss(0.5, 0.0, blackOps));
    const auto exp2 = GlossEncoding::exp2Range();
    EXPECT_EQ(varianceToGloss(0.7, 1.0, exp2), 0.0);
    // A roughness encoding goes the other way: more variance, more roughness.
    const auto ggx = GlossEncoding::ggxRoughness();
    EXPECT_GT(varianceToGloss(0.3, 0.05, ggx), 0.3);
}

} // namespace
} // namespace burnish
