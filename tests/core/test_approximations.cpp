// The approximations report: its metrics on toy inputs with known answers, the Pareto flag, the
// measured entries (finite, plausible errors, positive costs), the glossy Fresnel reference
// against an independent integration, and the text outputs (never NaN/Inf).
#include <burnish/core/eval/approximations.h>
#include <burnish/core/shading/fresnel.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/visibility.h>
#include <burnish/core/util/report.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <regex>
#include <set>

namespace burnish {
namespace {

// Metrics are max/sqrt of sums of doubles: exact up to a few ulps of the values involved.
constexpr double kMetricTol = 1e-12;

TEST(ErrorAccumulator, ConstantOffsetGivesThatOffset) {
    // exact f(x) = x, approx x + 0.01 on x in [0.5, 1]: every error is 0.01.
    constexpr double kOffset = 0.01;
    ErrorAccumulator acc;
    for (int i = 0; i <= 100; ++i) {
        const double x = 0.5 + 0.5 * i / 100.0;
        acc.add(x, x + kOffset);
    }
    const ErrorMetrics m = acc.metrics();
    EXPECT_EQ(m.samples, 101u);
    EXPECT_NEAR(m.maxAbs, kOffset, kMetricTol);
    EXPECT_NEAR(m.rms, kOffset, kMetricTol);
    ASSERT_TRUE(m.maxRel.has_value());
    EXPECT_NEAR(*m.maxRel, kOffset / 0.5, kMetricTol); // largest at the smallest exact value
}

TEST(ErrorAccumulator, RelativeFloorExcludesTinyExactValues) {
    ErrorAccumulator acc;
    constexpr double kFloor = 1e-3;
    acc.add(1e-6, 2e-6, kFloor); // rel error 1, but below the floor
    acc.add(1.0, 1.1, kFloor);   // rel error 0.1
    const ErrorMetrics m = acc.metrics();
    ASSERT_TRUE(m.maxRel.has_value());
    EXPECT_NEAR(*m.maxRel, 0.1, kMetricTol);
    EXPECT_EQ(m.relSamples, 1u);

    ErrorAccumulator none;
    none.add(0.0, 0.5, kFloor);
    EXPECT_FALSE(none.metrics().maxRel.has_value()) << "no sample qualifies: max rel must be n/a";
}

TEST(ErrorAccumulator, NonFiniteSamplesAreCountedNotMixedIn) {
    ErrorAccumulator acc;
    acc.add(1.0, std::nan(""));
    acc.add(1.0, INFINITY);
    acc.add(1.0, 1.25);
    EXPECT_EQ(acc.nonFinite(), 2u);
    EXPECT_NEAR(acc.metrics().maxAbs, 0.25, kMetricTol);
}

TEST(Pareto, HandMadePoints) {
    const std::vector<ParetoPoint> pts = {
        {"a", 1.0, 0.5},          // cheapest: front
        {"a", 2.0, 0.1},          // most accurate: front
        {"a", 3.0, 0.3},          // dominated by (2, 0.1)
        {"a", 2.0, 0.1},          // a tie with point 1: neither dominates the other
        {"b", 10.0, 1.0},         // alone in its group: front, although group a dominates it
        {"a", std::nan(""), 0.0}, // NaN cost: never on the front, dominates nothing
        {"a", 0.5, INFINITY},     // Inf error: never on the front
    };
    const std::vector<bool> front = paretoFront(pts);
    const std::vector<bool> expected = {true, true, false, true, true, false, false};
    EXPECT_EQ(front, expected);
}

TEST(Pareto, EntriesUseTheirHeadlineMetric) {
    std::vector<ApproximationEntry> entries(2);
    for (auto& e : entries) {
        e.group = "g";
        e.metric = HeadlineMetric::MaxRel;
    }
    // Entry 0 is cheaper and better in max abs, but worse in the headline max rel: both on the front.
    entries[0].approxNs = 1.0, entries[0].error.maxAbs = 0.1, entries[0].error.maxRel = 0.9;
    entries[1].approxNs = 2.0, entries[1].error.maxAbs = 0.5, entries[1].error.maxRel = 0.2;
    markParetoFront(entries);
    EXPECT_TRUE(entries[0].pareto);
    EXPECT_TRUE(entries[1].pareto);
    entries[1].error.maxRel = 0.95; // now dominated by entry 0
    markParetoFront(entries);
    EXPECT_TRUE(entries[0].pareto);
    EXPECT_FALSE(entries[1].pareto);
    // Against a different exact form, entry 0 no longer competes with entry 1.
    entries[1].exact = "another reference";
    markParetoFront(entries);
    EXPECT_TRUE(entries[1].pareto);
}

TEST(Timing, PositiveFiniteAndCapped) {
    const auto& pairs = timedKernelPairs();
    ASSERT_FALSE(pairs.empty());
    constexpr size_t kInputs = 4096;
    constexpr int kReps = 3;
    for (const auto& pair : pairs) {
        if (pair.exactInputCap > 0 && pair.exactInputCap < 100) continue; // the glossy quadrature: slow
        const KernelTiming t = timeKernelPair(pair, kInputs, kReps);
        EXPECT_TRUE(std::isfinite(t.approxNs) && t.approxNs > 0.0) << pair.id;
        EXPECT_TRUE(std::isfinite(t.exactNs) && t.exactNs > 0.0) << pair.id;
        EXPECT_TRUE(std::isfinite(t.checksum)) << pair.id;
        EXPECT_EQ(t.approxInputs, kInputs) << pair.id;
        EXPECT_EQ(t.exactInputs, pair.exactInputCap > 0 ? std::min(kInputs, pair.exactInputCap) : kInputs)
            << pair.id;
    }
}

TEST(GlossyReference, SharpLobeAtNormalIncidenceConservesEnergy) {
    // g = 1 (n = 8192) seen head-on is nearly a mirror: ∫ f (n·l) dω → F·G → 1 for F = 1, and the
    // Fresnel part (1 − h·l)^5 vanishes with h·l ≈ 1. Tolerance: the lobe's residual width.
    constexpr double kMirrorTol = 1e-3;
    const GlossyEnvironmentMoments m = glossyEnvironmentReference(1.0, 1.0);
    EXPECT_NEAR(m.full, 1.0, kMirrorTol);
    EXPECT_NEAR(m.fresnel, 0.0, kMirrorTol);
    EXPECT_NEAR(m.at(0.04), 0.04 * m.full + 0.96 * m.fresnel, kMetricTol);
}

TEST(GlossyReference, MatchesBruteForceIntegrationOverLightDirections) {
    // An independent midpoint rule over l (not h, no arc trimming) for a smooth lobe.
    const double NoV = 0.5, g = 0.3;
    const double n = std::pow(8192.0, g);
    const double v[3] = {std::sqrt(1.0 - NoV * NoV), 0.0, NoV};
    constexpr int kSteps = 600;
    double full = 0.0, fres = 0.0;
    const double dT = 0.5 * kPi<double> / kSteps, dP = 2.0 * kPi<double> / kSteps;
    for (int i = 0; i < kSteps; ++i) {
        const double t = (i + 0.5) * dT;
        for (int j = 0; j < kSteps; ++j) {
            const double p = (j + 0.5) * dP;
            const double l[3] = {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
            double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
            const double len = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            for (double& c : h)
                c /= len;
            const double VoH = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
            const double f = blinnPhongNdf(h[2], n) * visibilitySchlickSmith(l[2], NoV, n) / 4.0;
            const double w = f * l[2] * std::sin(t) * dT * dP;
            full += w;
            fres += w * fresnelSchlick(0.0, VoH);
        }
    }
    // 600² midpoint samples of a smooth integrand (n ≈ 15): agreement to ~1e-4.
    constexpr double kBruteForceTol = 1e-3;
    const GlossyEnvironmentMoments m = glossyEnvironmentReference(NoV, g);
    EXPECT_NEAR(m.full, full, kBruteForceTol);
    EXPECT_NEAR(m.fresnel, fres, kBruteForceTol);
}

/// One quick measurement shared by the tests below (it takes a few seconds).
class MeasuredReport : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        ApproximationOptions o;
        o.quick = true;
        auto r = measureApproximations(o);
        ASSERT_TRUE(r.ok()) << r.error();
        s_report = new ApproximationReport(std::move(r).value());
    }
    static void TearDownTestSuite() {
        delete s_report;
        s_report = nullptr;
    }
    static const ApproximationEntry& entry(const std::string& id) {
        for (const auto& e : s_report->entries)
            if (e.id == id) return e;
        ADD_FAILURE() << "no entry " << id;
        static const ApproximationEntry none;
        return none;
    }
    static ApproximationReport* s_report;
};
ApproximationReport* MeasuredReport::s_report = nullptr;

TEST_F(MeasuredReport, EveryEntryIsFiniteTimedAndWrong) {
    ASSERT_NE(s_report, nullptr);
    EXPECT_TRUE(s_report->quick);
    EXPECT_EQ(s_report->entries.size(), timedKernelPairs().size())
        << "an entry without a kernel, or vice versa";
    for (const auto& e : s_report->entries) {
        EXPECT_TRUE(std::isfinite(e.error.maxAbs)) << e.id;
        EXPECT_TRUE(std::isfinite(e.error.rms)) << e.id;
        EXPECT_GT(e.error.samples, 0u) << e.id;
        // An approximation that equals its exact form would be a mislabelled entry.
        EXPECT_GT(e.error.maxAbs, 0.0) << e.id;
        EXPECT_LE(e.error.rms, e.error.maxAbs) << e.id;
        if (e.error.maxRel) {
            EXPECT_TRUE(std::isfinite(*e.error.maxRel)) << e.id;
        }
        EXPECT_TRUE(std::isfinite(e.headlineError())) << e.id;
        EXPECT_TRUE(std::isfinite(e.approxNs) && e.approxNs > 0.0) << e.id;
        EXPECT_TRUE(std::isfinite(e.exactNs) && e.exactNs > 0.0) << e.id;
        EXPECT_TRUE(std::isfinite(e.ratio())) << e.id;
    }
}

TEST_F(MeasuredReport, GroupsShareOneHeadlineMetricAndEachHasAFront) {
    std::map<std::string, std::set<HeadlineMetric>> metrics;
    std::map<std::string, int> onFront;
    for (const auto& e : s_report->entries) {
        metrics[e.group].insert(e.metric);
        onFront[e.group] += e.pareto ? 1 : 0;
    }
    EXPECT_EQ(metrics.size(), s_report->groups.size());
    for (const auto& [group, set] : metrics)
        EXPECT_EQ(set.size(), 1u) << group;
    for (const auto& [group, count] : onFront)
        EXPECT_GE(count, 1) << group;
}

TEST_F(MeasuredReport, KnownErrorBands) {
    // Schlick vs exact dielectric Fresnel for F0 in [0.02, 0.08]: Schlick undershoots at grazing
    // angles by a few hundredths (≈ 0.06 at F0 = 0.08); a band of [0.02, 0.1] catches a wrong
    // reference or an identical approximation.
    EXPECT_GT(entry("fresnel-schlick").error.maxAbs, 0.02);
    EXPECT_LT(entry("fresnel-schlick").error.maxAbs, 0.1);
    // Lagarde 2012 quotes exp2(−8.35) ≈ 0.003 at x = 1 and a visibly worse fit than the quadratic,
    // whose error at x = 1 is exp2(−12.54) ≈ 1.7e-4 and whose maximum stays below 1e-2.
    EXPECT_GT(entry("fresnel-sg").error.maxAbs, entry("fresnel-sg-quadratic").error.maxAbs);
    EXPECT_LT(entry("fresnel-sg-quadratic").error.maxAbs, 1e-2);
    EXPECT_GT(entry("fresnel-sg-quadratic").error.maxAbs, 1.6e-4);
    // The plain SG at n = 1 and c → 0+: exp(−1) against 0. The grid reaches c = e^−20.
    constexpr double kLobeEdgeTol = 1e-6;
    EXPECT_NEAR(entry("sg-blinn-x0").error.maxAbs, std::exp(-1.0), kLobeEdgeTol);
    // The offset moves the SG towards the lobe: x = 0.775 beats x = 0 in the max.
    EXPECT_LT(entry("sg-blinn-x0775").error.maxAbs, entry("sg-blinn-x0").error.maxAbs);
    // (n+8)/8π vs the exact BRDF normalization: the relative error peaks near n = 8 (≈ 0.075, not at
    // n = 1 where it is 0.024). Expected value from the published formulas written out here.
    double expectedNormRel = 0.0;
    for (int i = 0; i <= 100000; ++i) {
        const double n = std::pow(1e4, i / 100000.0);
        const double exact = (n + 2.0) * (n + 4.0) / (8.0 * kPi<double> * (std::exp2(-n / 2.0) + n));
        const double approx = (n + 8.0) / (8.0 * kPi<double>);
        expectedNormRel = std::max(expectedNormRel, std::abs(approx - exact) / exact);
    }
    // The quick grid has 501 log-spaced powers: the max it sees is within 1e-4 of the true one.
    constexpr double kNormGridTol = 1e-4;
    ASSERT_TRUE(entry("norm-blinn-phong-brdf").error.maxRel.has_value());
    EXPECT_NEAR(*entry("norm-blinn-phong-brdf").error.maxRel, expectedNormRel, kNormGridTol);
    // Gamma 2.2 decode vs sRGB: within 1e-2 everywhere (the well-known ≈ 0.0085 at v ≈ 0.2–0.3);
    // gamma 2.0 is several times worse.
    EXPECT_LT(entry("srgb-decode-gamma22").error.maxAbs, 1e-2);
    EXPECT_GT(entry("srgb-decode-gamma20").error.maxAbs, 3.0 * entry("srgb-decode-gamma22").error.maxAbs);
    // The glossy environment form is a coarse fit: tenths, not hundredths, and never above 1.
    EXPECT_GT(entry("fresnel-glossy").error.maxAbs, 0.1);
    EXPECT_LT(entry("fresnel-glossy").error.maxAbs, 1.0);
    // The diffuse-AA curve is a close fit of the cone integral over its stated |Na| range.
    EXPECT_LT(entry("diffuse-aa-curve").error.maxAbs, 1e-2);
    // Kelemen keeps Cook–Torrance within a factor of 2 (rel error <= 1 by construction of the
    // min() in G); no visibility term is off by up to 100 %.
    EXPECT_LE(entry("vis-kelemen").error.maxRel.value_or(INFINITY), 1.0);
    EXPECT_LT(entry("vis-kelemen").error.maxRel.value_or(INFINITY),
              entry("vis-none").error.maxRel.value_or(0.0));
}

TEST_F(MeasuredReport, MarkdownAndJsonListEveryEntryWithoutNanOrInf) {
    const std::string md = approximationsMarkdown(*s_report);
    const std::string json = approximationsJson(*s_report).dump();
    const std::regex bad("\\b(nan|inf|infinity)\\b", std::regex::icase);
    EXPECT_FALSE(std::regex_search(md, bad));
    EXPECT_FALSE(std::regex_search(json, bad));
    for (size_t i = 0; i < s_report->entries.size(); ++i)
        EXPECT_NE(md.find("| " + std::to_string(i + 1) + " | " + s_report->entries[i].group + " | "),
                  std::string::npos)
            << "no table row for " << s_report->entries[i].id;
    EXPECT_NE(md.find("Quick run"), std::string::npos) << "a quick run must say so";
}

TEST(ReportText, NonFiniteValuesAreNeverPrinted) {
    ApproximationReport r;
    ApproximationEntry e;
    e.id = "toy";
    e.group = "Toy";
    e.name = "toy";
    e.error.maxAbs = std::nan("");
    e.error.maxRel = INFINITY;
    e.error.rms = -INFINITY;
    e.approxNs = std::nan("");
    e.exactNs = 0.0; // ratio would divide by zero
    r.groups = {"Toy"};
    r.entries = {e};
    const std::regex bad("\\b(nan|inf|infinity)\\b", std::regex::icase);
    const std::string md = approximationsMarkdown(r);
    const std::string json = approximationsJson(r).dump();
    EXPECT_FALSE(std::regex_search(md, bad)) << md;
    EXPECT_FALSE(std::regex_search(json, bad)) << json;
    EXPECT_NE(md.find("n/a"), std::string::npos);
    EXPECT_TRUE(approximationsJson(r)["approximations"][0]["cost"]["ratio"].is_null());
    EXPECT_EQ(formatNumber(std::nan("")), "n/a");
    EXPECT_EQ(formatNumber(-INFINITY), "n/a");
    EXPECT_EQ(formatNumber(0.0123456), "0.0123");
}

TEST(ReportText, MarkdownTableEscapesPipes) {
    MarkdownTable t({"a", "b"}, {Align::Left, Align::Right});
    t.addRow({"x|y", "1"});
    t.addRow({"only one"});
    EXPECT_EQ(t.render(), "| a | b |\n| --- | ---: |\n| x\\|y | 1 |\n| only one |  |\n");
}

} // namespace
} // namespace burnish
