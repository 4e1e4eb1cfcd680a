// sRGB transfer functions, their gamma approximations, 8-bit helpers and luminance.
#include <burnish/core/shading/color.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace burnish;

namespace {

// Reference decodes of 8-bit codes, computed independently (Python, IEC 61966-2-1 formula in
// double precision) and written to 6 significant digits: compare within half a unit of the 6th.
constexpr double kSixDigitTolerance = 5e-6;
// A float transfer function evaluated with float pow differs from the double one by a few ulps
// of float near 1 (ulp(1) = 1.2e-7).
constexpr double kFloatTolerance = 1e-6;
// The IEC constants are rounded, so the two pieces do not meet exactly at the knee: the decode
// jumps by 2.3e-9 and the raw encode by 2.9e-8. Anything larger would be a wrong constant.
constexpr double kKneeJumpTolerance = 3e-8;

double nan() {
    return std::numeric_limits<double>::quiet_NaN();
}
double inf() {
    return std::numeric_limits<double>::infinity();
}

} // namespace

TEST(Srgb, AllEightBitCodesRoundTripExactly) {
    for (int code = 0; code < 256; ++code) {
        const auto c = static_cast<std::uint8_t>(code);
        EXPECT_EQ(linearToSrgb8(srgb8ToLinear(c)), c) << "code " << code;
    }
}

TEST(Srgb, FloatVersionMatchesDoubleAndRoundTrips) {
    for (int code = 0; code < 256; ++code) {
        const float v = float(code) / 255.0f;
        const double exact = srgbToLinear(double(code) / 255.0);
        EXPECT_NEAR(srgbToLinear(v), exact, kFloatTolerance) << "code " << code;
        EXPECT_EQ(std::lround(linearToSrgb(srgbToLinear(v)) * 255.0f), code) << "code " << code;
    }
}

TEST(Srgb, KnownPoints) {
    // 187: Lagarde's middle grey ("not 128 but 187"): half the light, linear ~0.5.
    EXPECT_NEAR(srgb8ToLinear(187), 0.496933, kSixDigitTolerance);
    EXPECT_NEAR(srgb8ToLinear(128), 0.215861, kSixDigitTolerance);
    // Lagarde's chart end points.
    EXPECT_NEAR(srgb8ToLinear(40), 0.0212190, kSixDigitTolerance);
    EXPECT_NEAR(srgb8ToLinear(75), 0.0703601, kSixDigitTolerance);
    EXPECT_NEAR(srgb8ToLinear(155), 0.327778, kSixDigitTolerance);
    EXPECT_EQ(srgb8ToLinear(0), 0.0);
    EXPECT_EQ(srgb8ToLinear(255), 1.0);
    // The linear segment: code 10 is below the 0.04045 knee.
    EXPECT_DOUBLE_EQ(srgb8ToLinear(10), 10.0 / 255.0 / 12.92);
}

// Lagarde's chart prints 40..75 → 0.017..0.067 and 155 → 0.33. Those are the gamma-2.2 decode, not
// the sRGB one: gamma 2.2 reproduces each printed number to within one unit of its last printed
// digit, while the exact decode misses 0.017 and 0.067 by several units (0.0212, 0.0704).
TEST(Srgb, LagardePrintedRangeIsTheGamma22Decode) {
    struct Printed {
        int code;
        double value;
        double lastDigit; // one unit of the last digit printed in the text
    };
    const Printed printed[] = {{40, 0.017, 0.001}, {75, 0.067, 0.001}, {155, 0.33, 0.01}};
    for (const auto& p : printed) {
        EXPECT_NEAR(gamma22ToLinear(p.code / 255.0), p.value, p.lastDigit) << "code " << p.code;
    }
    EXPECT_GT(std::abs(srgb8ToLinear(40) - 0.017), 4 * printed[0].lastDigit);
    EXPECT_GT(std::abs(srgb8ToLinear(75) - 0.067), 3 * printed[1].lastDigit);
    // At 155 both curves round to the printed 0.33.
    EXPECT_NEAR(srgb8ToLinear(155), 0.33, printed[2].lastDigit);
}

TEST(Srgb, MonotoneOverTheWholeRangeAndAcrossTheKnee) {
    const auto checkMonotone = [](auto f, double from, double to, int steps) {
        double previous = f(from);
        for (int i = 1; i <= steps; ++i) {
            const double x = from + (to - from) * i / steps;
            const double y = f(x);
            ASSERT_GE(y, previous) << "at " << x;
            previous = y;
        }
    };
    const auto decode = [](double v) { return srgbToLinear(v); };
    const auto encode = [](double L) { return linearToSrgb(L); };
    const auto decodeF = [](double v) { return double(srgbToLinear(float(v))); };
    const auto encodeF = [](double L) { return double(linearToSrgb(float(L))); };
    checkMonotone(decode, 0.0, 1.0, 1000000);
    checkMonotone(encode, 0.0, 1.0, 1000000);
    checkMonotone(decodeF, 0.0, 1.0, 1000000);
    checkMonotone(encodeF, 0.0, 1.0, 1000000);
    // The knees, sampled far finer than the steps of the rounded constants (2.3e-9, 2.9e-8).
    checkMonotone(decode, 0.04045 - 1e-7, 0.04045 + 1e-7, 200000);
    checkMonotone(encode, 0.0031308 - 1e-8, 0.0031308 + 1e-8, 200000);
    checkMonotone(encodeF, 0.0031308 - 1e-6, 0.0031308 + 1e-6, 200000);
}

TEST(Srgb, PiecesMeetAtTheKnee) {
    const double below = srgbToLinear(0.04045);
    const double above = srgbToLinear(std::nextafter(0.04045, 1.0));
    EXPECT_NEAR(above, below, kKneeJumpTolerance);
    const double encBelow = linearToSrgb(0.0031308);
    const double encAbove = linearToSrgb(std::nextafter(0.0031308, 1.0));
    EXPECT_NEAR(encAbove, encBelow, kKneeJumpTolerance);
}

TEST(Srgb, NonFiniteAndOutOfRangeInputsClamp) {
    for (double bad : {nan(), -nan(), -1.0, -inf(), -1e-300}) {
        EXPECT_EQ(srgbToLinear(bad), 0.0) << bad;
        EXPECT_EQ(linearToSrgb(bad), 0.0) << bad;
        EXPECT_EQ(gamma20ToLinear(bad), 0.0) << bad;
        EXPECT_EQ(linearToGamma20(bad), 0.0) << bad;
        EXPECT_EQ(gamma22ToLinear(bad), 0.0) << bad;
        EXPECT_EQ(linearToGamma22(bad), 0.0) << bad;
        EXPECT_EQ(linearToSrgb8(bad), 0) << bad;
    }
    for (double big : {1.0 + 1e-12, 2.0, 1e300, inf()}) {
        EXPECT_EQ(srgbToLinear(big), 1.0) << big;
        EXPECT_EQ(linearToSrgb(big), 1.0) << big;
        EXPECT_EQ(gamma20ToLinear(big), 1.0) << big;
        EXPECT_EQ(linearToGamma20(big), 1.0) << big;
        EXPECT_EQ(gamma22ToLinear(big), 1.0) << big;
        EXPECT_EQ(linearToGamma22(big), 1.0) << big;
        EXPECT_EQ(linearToSrgb8(big), 255) << big;
    }
    EXPECT_EQ(srgbToLinear(std::numeric_limits<float>::quiet_NaN()), 0.0f);
    EXPECT_EQ(linearToSrgb(std::numeric_limits<float>::infinity()), 1.0f);
}

// The approximations, measured against the exact decode over all 256 codes: the numbers an
// approximation report quotes. Bounds are the measured maxima rounded up in the last digit, so a
// change to either curve shows here.
TEST(Srgb, GammaApproximationErrors) {
    constexpr double kGamma22MaxError = 0.0086; // measured 0.00853 at code 191
    constexpr double kGamma20MaxError = 0.0425; // measured 0.04248 at code 168
    constexpr double kGamma20AtLeast = 0.04;    // gamma 2.0 is visibly off in the mid tones
    double max22 = 0, max20 = 0;
    int at22 = 0, at20 = 0;
    for (int code = 0; code < 256; ++code) {
        const double v = code / 255.0;
        const double exact = srgb8ToLinear(static_cast<std::uint8_t>(code));
        const double e22 = std::abs(gamma22ToLinear(v) - exact);
        const double e20 = std::abs(gamma20ToLinear(v) - exact);
        if (e22 > max22) max22 = e22, at22 = code;
        if (e20 > max20) max20 = e20, at20 = code;
    }
    EXPECT_LT(max22, kGamma22MaxError);
    EXPECT_EQ(at22, 191);
    EXPECT_LT(max20, kGamma20MaxError);
    EXPECT_GT(max20, kGamma20AtLeast);
    EXPECT_EQ(at20, 168);
    // Each approximation inverts itself exactly enough to round-trip every code.
    for (int code = 0; code < 256; ++code) {
        const double v = code / 255.0;
        EXPECT_EQ(std::lround(linearToGamma22(gamma22ToLinear(v)) * 255.0), code);
        EXPECT_EQ(std::lround(linearToGamma20(gamma20ToLinear(v)) * 255.0), code);
    }
}

TEST(Luminance, Rec709Weights) {
    constexpr double kSumTolerance = 1e-15; // the three weights are exact decimals summing to 1
    EXPECT_NEAR(luminance(LinearRgb::grey(1.0)), 1.0, kSumTolerance);
    EXPECT_NEAR(luminance(LinearRgb::grey(0.25)), 0.25, kSumTolerance);
    EXPECT_DOUBLE_EQ(luminance({1, 0, 0}), 0.2126);
    EXPECT_DOUBLE_EQ(luminance({0, 1, 0}), 0.7152);
    EXPECT_DOUBLE_EQ(luminance({0, 0, 1}), 0.0722);
}

TEST(Srgb8Triple, ConvertsEachChannel) {
    const LinearRgb gold{1.0, 0.782, 0.344};
    const Srgb8 code = toSrgb8(gold);
    EXPECT_EQ(code, (Srgb8{255, 229, 158}));
    const LinearRgb back = toLinear(code);
    EXPECT_EQ(back.r, srgb8ToLinear(255));
    EXPECT_EQ(back.g, srgb8ToLinear(229));
    EXPECT_EQ(back.b, srgb8ToLinear(158));
}

TEST(Color, ParseLinearRgbTakesATripleOrAGreyAndRefusesTheRest) {
    const auto triple = parseLinearRgb("0.56,0.57,0.58", "--specular");
    ASSERT_TRUE(triple) << triple.error();
    EXPECT_EQ(*triple, (LinearRgb{0.56, 0.57, 0.58}));
    const auto grey = parseLinearRgb("0.04", "--specular");
    ASSERT_TRUE(grey);
    EXPECT_EQ(*grey, LinearRgb::grey(0.04));
    for (const char* bad : {"", "red", "0.1,0.2", "0.1,0.2,0.3,0.4", "0.1,,0.3", "1.5,0,0", "-0.1", "nan",
                            "inf,0,0", "0.1,0.2,0.3x"}) {
        const auto r = parseLinearRgb(bad, "--specular");
        ASSERT_FALSE(r) << bad;
        EXPECT_EQ(r.error().rfind("--specular '", 0), 0u) << r.error();
    }
    EXPECT_NE(parseLinearRgb("1.5,0,0", "--albedo").error().find("outside the linear range [0, 1]"),
              std::string::npos);
}
