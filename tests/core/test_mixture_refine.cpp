// The mixture fitted to the shaded ground truth (prefilter/mixture_refine.h): it never raises a texel's
// training error, keeps the texel's weight and a covariance above the base lobe's, stays finite at
// the extremes, is deterministic, trains on pairs evaluate does not measure, and on a real map errs
// less than the moment fit on evaluate's own pairs, aligned and between texels.
#include <burnish/core/eval/evaluate.h>
#include <burnish/core/jobs/bake_job.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/mixture_refine.h>

#include "box_pyramid_of.h"
#include "normal_map_of.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>

using namespace burnish;

namespace {

using test::mapOf;

using test::build;
using test::Built;

// The top-left size×size texels of a test map.
NormalMap cropOf(const std::string& name, int size) {
    auto map = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/" + name);
    EXPECT_TRUE(map) << map.error();
    return mapOf(size, size, [&](int x, int y) { return map->at(x, y); });
}

double objective(const LobeMixture& m, const std::vector<DirectionPair>& dirs,
                 const std::vector<double>& truth, double v) {
    const DecodedMixture d = decodeMixture(m, v);
    double sum = 0.0, total = 0.0;
    for (size_t i = 0; i < dirs.size(); ++i) {
        const double e = mixtureValue(d, dirs[i].l, dirs[i].h) - truth[i];
        sum += e * e;
        total += e;
    }
    // The fit's objective: the pairs' squared errors and the energy's.
    const double energy = kShadedFitEnergyWeight * total / std::sqrt(double(dirs.size()));
    return sum + energy * energy;
}

// Every lobe finite, its variances at least the base variance v, and the texel's weight `total`.
void expectSound(const LobeMixture& m, double v, double total) {
    double w = 0.0;
    for (int i = 0; i < m.count; ++i) {
        const LobeMoments& l = m.lobes[size_t(i)];
        if (l.w == 0.0) continue;
        w += l.w;
        const glm::dvec2 b = l.mean();
        const auto c = l.covariance(0.0);
        ASSERT_TRUE(std::isfinite(b.x) && std::isfinite(b.y) && std::isfinite(c[0]) && std::isfinite(c[1]) &&
                    std::isfinite(c[2]));
        // M − bbᵀ cancels: a few ulps of |b|² on top of the floor.
        const double slack = 1e-9 * v + 1e-13 * (1.0 + glm::dot(b, b));
        EXPECT_GE(c[0], v - slack);
        EXPECT_GE(c[1], v - slack);
    }
    EXPECT_NEAR(w, total, 1e-9 * total);
}

struct Rows {
    std::vector<double> aligned, between; // per mip 1..4
};

Rows evaluateMixture(const NormalMap& map, double s, bool shaded) {
    EvaluateOptions o;
    o.basePowers = {s};
    o.methods = {Method::Mixture};
    o.mixtureLobes = {3};
    o.firstMip = 1;
    o.lastMip = 4;
    o.betweenTexels = true;
    o.params.mixtureShadedFit = shaded;
    auto r = evaluateMethods(map, o);
    EXPECT_TRUE(r) << r.error();
    Rows rows{std::vector<double>(5, -1.0), std::vector<double>(5, -1.0)};
    for (const MipError& e : r->errors)
        (e.betweenTexels ? rows.between : rows.aligned)[size_t(e.mip)] = e.relativeL1;
    return rows;
}

} // namespace

TEST(ShadedFit, TrainingPairsAreNotEvaluatesPairsAndLightTheSurface) {
    const auto training = shadedFitDirections();
    EXPECT_GE(training.size(), 120u);
    const double minLz = std::sin(3.0 * 3.14159265358979 / 180.0);
    for (const DirectionPair& t : training) {
        EXPECT_GE(t.l.z, minLz - 1e-12);
        EXPECT_NEAR(glm::length(t.l), 1.0, 1e-12);
        EXPECT_NEAR(glm::length(t.h), 1.0, 1e-12);
        // h halves l and v.
        EXPECT_LT(glm::length(glm::normalize(t.l + t.v) - t.h), 1e-9);
    }
    for (const EvaluateOptions& o : {EvaluateOptions{}, [] {
                                         EvaluateOptions dense;
                                         dense.halfAnglesDeg.clear();
                                         for (int a = 0; a <= 40; ++a)
                                             dense.halfAnglesDeg.push_back(a);
                                         dense.azimuths = 16;
                                         return dense;
                                     }()})
        for (const DirectionPair& e : evaluationDirections(o))
            for (const DirectionPair& t : training)
                EXPECT_GT(glm::length(e.h - t.h) + glm::length(e.l - t.l), 1e-3);
}

TEST(ShadedFit, NeverRaisesTheTrainingErrorAndKeepsTheWeight) {
    auto b = build(cropOf("trak-rust1_nm.png", 128));
    const auto dirs = shadedFitDirections();
    int lowered = 0, texels = 0;
    for (const double s : {64.0, 1024.0}) {
        const MixturePyramid mp = MixturePyramid::build(b.pyramid, s, 3, 4);
        for (int level : {2, 4}) {
            const PyramidLevel& l = b.pyramid.level(level);
            for (int y = 0; y < l.height; y += 3)
                for (int x = 0; x < l.width; x += 3) {
                    const LobeMixture fitted = mp.at(level, x, y);
                    std::vector<double> truth;
                    for (const DirectionPair& d : dirs)
                        truth.push_back(groundTruthTexel(b.pyramid, level, x, y, s, d));
                    const LobeMixture refined = refineMixtureToTruth(fitted, dirs, truth, mp.minVariance());
                    const double before = objective(fitted, dirs, truth, mp.minVariance());
                    const double after = objective(refined, dirs, truth, mp.minVariance());
                    EXPECT_LE(after, before * (1.0 + 1e-12)) << "s " << s << " level " << level;
                    expectSound(refined, mp.minVariance(), fitted.totalWeight());
                    lowered += after < 0.9 * before;
                    ++texels;
                }
        }
    }
    // The refinement does something on most texels of a real map.
    EXPECT_GT(lowered, texels / 2) << lowered << " of " << texels;
}

TEST(ShadedFit, ExtremesStayFinite) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (const auto& [w, h] : {std::pair{1, 1}, {3, 5}, {17, 9}, {32, 32}}) {
        auto b = build(mapOf(w, h, [&](int x, int y) {
            if ((x + y) % 3 == 0) return glm::vec3(float(u(rng)), float(u(rng)), 0.0f); // on the horizon
            if ((x * y) % 5 == 1) return glm::vec3(0.0f, 0.0f, 1.0f);
            return glm::vec3(float(u(rng)), float(u(rng)), 0.3f);
        }));
        for (const double s : {1.0, 1e6}) {
            const MixturePyramid mp = buildShadedMixture(b.pyramid, s, 3);
            EXPECT_EQ(mp.levelCount(), b.pyramid.levelCount());
            for (int level = 1; level < mp.levelCount(); ++level) {
                const PyramidLevel& l = b.pyramid.level(level);
                for (int y = 0; y < l.height; ++y)
                    for (int x = 0; x < l.width; ++x) {
                        const LobeMixture m = mp.at(level, x, y);
                        expectSound(m, mp.minVariance(), double(b.pyramid.footprintCount(level, x, y)));
                        for (const glm::dvec3 hv :
                             {glm::dvec3(0, 0, 1), glm::normalize(glm::dvec3(1, 0, 1e-3))})
                            EXPECT_TRUE(
                                std::isfinite(mixtureValue(m, glm::dvec3(0, 0, 1), hv, mp.minVariance())));
                    }
            }
        }
    }
}

TEST(ShadedFit, SameBitsOnOneThreadAndOnAll) {
    auto b = build(cropOf("trak-treadplate1_nm.png", 64));
    const MixturePyramid all = buildShadedMixture(b.pyramid, 256.0, 3);
    MixturePyramid one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = buildShadedMixture(b.pyramid, 256.0, 3);
    }
    EXPECT_TRUE(test::sameLobesBitForBit(all, one, b.pyramid, all.levelCount() - 1));
}

TEST(ShadedFit, ErrsLessThanTheMomentFitOnEvaluatesOwnPairs) {
    // Evaluate's default 48 pairs, none of which the fit trains on, on a 128² corner of the tread
    // plate at s = 256 (K = 3). Level 1 keeps its moment fit; from mip 2 up the shaded fit errs at
    // most 0.6 of the moment fit's aligned, and between texels at most 0.92 of it at every mip and 0.9
    // over mips 2-4 together. (Until the moment fit merged by the squared error above level 1 the bound
    // was 0.9 at every mip; the better moment fit leaves mip 3 at 0.911: 0.0933 against 0.1024.)
    const NormalMap map = cropOf("trak-treadplate1_nm.png", 128);
    const Rows fitted = evaluateMixture(map, 256.0, false);
    const Rows shaded = evaluateMixture(map, 256.0, true);
    // Level 1's lobes are the moment fit's (their slots follow the refined level 2, so the sum's order
    // may differ).
    EXPECT_NEAR(shaded.aligned[1], fitted.aligned[1], 1e-12);
    double shadedBetween = 0.0, fittedBetween = 0.0;
    for (int mip = 2; mip <= 4; ++mip) {
        std::printf("[measured] tread plate 128² s = 256 mip %d: moment fit %.4f (between %.4f), shaded fit "
                    "%.4f (between %.4f)\n",
                    mip, fitted.aligned[size_t(mip)], fitted.between[size_t(mip)],
                    shaded.aligned[size_t(mip)], shaded.between[size_t(mip)]);
        EXPECT_LT(shaded.aligned[size_t(mip)], 0.6 * fitted.aligned[size_t(mip)]) << "mip " << mip;
        EXPECT_LT(shaded.between[size_t(mip)], 0.92 * fitted.between[size_t(mip)]) << "mip " << mip;
        shadedBetween += shaded.between[size_t(mip)];
        fittedBetween += fitted.between[size_t(mip)];
    }
    EXPECT_LT(shadedBetween, 0.9 * fittedBetween);
}

TEST(ShadedFit, BakeJobTakesItForTheMixtureOnly) {
    BakeJobSpec spec;
    spec.input = std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png";
    spec.out = "unused";
    spec.preset = "mixture";
    spec.shadedFit = true;
    auto job = resolveBakeJob(spec);
    ASSERT_TRUE(job) << job.error();
    EXPECT_TRUE(job->bake.params.mixtureShadedFit);
    spec.preset = "lean";
    auto lean = resolveBakeJob(spec);
    ASSERT_FALSE(lean);
    EXPECT_NE(lean.error().find("--shaded-fit applies to --method mixture only"), std::string::npos)
        << lean.error();
}
