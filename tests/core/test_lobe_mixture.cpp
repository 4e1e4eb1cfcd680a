// The lobe-mixture fit (prefilter/lobe_mixture.h): it recovers the clusters of normals a footprint
// holds, keeps their energy, stays finite at the extremes, is deterministic, agrees with LEAN for
// one lobe, and on a real map errs less than LEAN against the ground truth.
#include <burnish/core/eval/evaluate.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/methods.h>

#include "box_pyramid_of.h"
#include "normal_map_of.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <vector>

using namespace burnish;

namespace {

using test::mapOf;

using test::build;
using test::Built;

bool allFinite(const LobeMixture& m, double minVariance) {
    for (int i = 0; i < m.count; ++i) {
        const auto& l = m.lobes[size_t(i)];
        const auto c = l.covariance(minVariance);
        const glm::dvec2 b = l.mean();
        if (!(std::isfinite(l.w) && std::isfinite(b.x) && std::isfinite(b.y) && std::isfinite(c[0]) &&
              std::isfinite(c[1]) && std::isfinite(c[2]) && c[0] * c[1] - c[2] * c[2] > 0.0))
            return false;
    }
    return true;
}

} // namespace

TEST(LobeMixture, TwoTiltCheckerGivesTwoLobesWithBothTiltsAndWeights) {
    const double t = std::tan(0.3);
    // A checker of two tilts about y, 3 of 4 texels one way: weights 3/4 and 1/4.
    auto b = build(mapOf(8, 8, [&](int x, int y) {
        return ((x + y) % 4 == 0) ? glm::vec3(float(-t), 0.0f, 1.0f) : glm::vec3(float(t), 0.0f, 1.0f);
    }));
    const double s = 1024.0;
    const MixturePyramid two = MixturePyramid::build(b.pyramid, s, 2);
    const LobeMixture& m = two.at(3, 0, 0); // the whole 8×8 map
    ASSERT_EQ(m.count, 2);
    // Canonical order: the −x tilt first.
    EXPECT_NEAR(m.lobes[0].mean().x, -t, 1e-6);
    EXPECT_NEAR(m.lobes[1].mean().x, t, 1e-6);
    EXPECT_NEAR(m.lobes[0].w / m.totalWeight(), 0.25, 1e-12);
    EXPECT_NEAR(m.lobes[1].w / m.totalWeight(), 0.75, 1e-12);
    // Each lobe is as narrow as the base lobe (two or more lobes: 1/(s + 2)): no spread between the two
    // tilts leaks in.
    for (int i = 0; i < 2; ++i) {
        const auto c = m.lobes[size_t(i)].covariance(two.minVariance());
        EXPECT_NEAR(c[0], 1.0 / (s + 2.0), 1e-9);
        EXPECT_NEAR(c[1], 1.0 / (s + 2.0), 1e-9);
    }
    // One lobe holds both: its x variance carries the spread of the tilts (as LEAN's).
    const MixturePyramid one = MixturePyramid::build(b.pyramid, s, 1);
    const auto c1 = one.at(3, 0, 0).lobes[0].covariance(one.minVariance());
    const double mean = 0.75 * t - 0.25 * t;
    EXPECT_NEAR(c1[0], t * t - mean * mean + 1.0 / s, 1e-7); // slopes are the pyramid's floats
}

TEST(LobeMixture, GroovesGiveAnAnisotropicLobeAlongTheGrooveNormal) {
    std::mt19937 rng(7);
    std::normal_distribution<double> g(0.0, 0.2);
    auto b = build(mapOf(16, 16, [&](int, int) { return glm::vec3(float(g(rng)), 0.0f, 1.0f); }));
    const MixturePyramid one = MixturePyramid::build(b.pyramid, 512.0, 1);
    const auto c = one.at(4, 0, 0).lobes[0].covariance(one.minVariance());
    EXPECT_GT(c[0], 20.0 * c[1]); // slopes vary in x only
    EXPECT_NEAR(c[1], 1.0 / 512.0, 1e-12);
}

TEST(LobeMixture, BaseLobePeaksAsTheBlinnPhongLobeFromTwoLobes) {
    // The normalised Blinn-Phong lobe peaks at (s + 2)/2π. Two or more lobes give each finest normal the
    // Gaussian of that peak; one lobe keeps LEAN's, s/2π (3 % low at s = 64).
    for (const double s : {1.0, 64.0, 256.0, 1e6}) {
        const glm::dvec3 n(0.0, 0.0, 1.0);
        const double blinnPhongPeak = (s + 2.0) / (2.0 * kPi<double>);
        for (int k = 2; k <= kMaxMixtureLobes; ++k) {
            const double v = mixtureBaseVariance(s, k);
            EXPECT_NEAR(slopeGaussianNdf(n, {0.0, 0.0}, {v, v, 0.0}) / blinnPhongPeak, 1.0, 1e-12) << s;
        }
        const double lean = slopeInverseBasePower(s);
        EXPECT_EQ(mixtureBaseVariance(s, 1), lean);
        EXPECT_NEAR(slopeGaussianNdf(n, {0.0, 0.0}, {lean, lean, 0.0}) / blinnPhongPeak, s / (s + 2.0),
                    1e-12);
    }
}

TEST(LobeMixture, FlatMapGivesTheBasePowerForEveryK) {
    for (const double s : {1.0, 256.0, 1e6}) {
        auto b = build(mapOf(16, 16, [](int, int) { return glm::vec3(0.0f, 0.0f, 1.0f); }));
        for (int k = 1; k <= kMaxMixtureLobes; ++k) {
            const MixturePyramid mp = MixturePyramid::build(b.pyramid, s, k);
            // One lobe is LEAN's, of variance 1/s; two or more lobes carry 1/(s + 2).
            const double v = k == 1 ? 1.0 / s : 1.0 / (s + 2.0);
            for (int level = 1; level < mp.levelCount(); ++level) {
                const LobeMixture& m = mp.at(level, 0, 0);
                for (int i = 0; i < m.count; ++i) {
                    const auto c = m.lobes[size_t(i)].covariance(mp.minVariance());
                    EXPECT_NEAR(c[0] / v, 1.0, 1e-12) << "s " << s << " k " << k << " level " << level;
                    EXPECT_NEAR(c[1] / v, 1.0, 1e-12);
                    EXPECT_EQ(c[2], 0.0);
                    EXPECT_EQ(m.lobes[size_t(i)].mean().x, 0.0);
                }
                // Equal lobes cost nothing to merge, and every K holds the base lobe's NDF.
                const glm::dvec3 h = glm::normalize(glm::dvec3(0.01, 0.02, 1.0));
                EXPECT_NEAR(mixtureNdf(m, h, mp.minVariance()), slopeGaussianNdf(h, {0.0, 0.0}, {v, v, 0.0}),
                            1e-9 * slopeGaussianNdf(h, {0.0, 0.0}, {v, v, 0.0}) + 1e-300);
            }
        }
    }
}

TEST(LobeMixture, OneLobeAgreesWithLean) {
    auto map = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png");
    ASSERT_TRUE(map) << map.error();
    auto b = build(std::move(map).value());
    const double s = 256.0;
    const MixturePyramid one = MixturePyramid::build(b.pyramid, s, 1, 4);
    double worst = 0.0;
    for (int level = 1; level <= 4; ++level) {
        const PyramidLevel& l = b.pyramid.level(level);
        for (int y = 0; y < l.height; y += 7)
            for (int x = 0; x < l.width; x += 5) {
                const TexelLobe lean = methodLobe(Method::Lean, b.pyramid.boxMoments(level, x, y), s);
                const LobeMoments m = one.at(level, x, y).lobes[0];
                const auto c = m.covariance(one.minVariance());
                worst = std::max({worst, std::abs(m.mean().x - lean.slopeMean.x),
                                  std::abs(m.mean().y - lean.slopeMean.y),
                                  std::abs(c[0] - lean.slopeCov[0]) / lean.slopeCov[0],
                                  std::abs(c[1] - lean.slopeCov[1]) / lean.slopeCov[1]});
            }
    }
    // The pyramid sums in float, the mixture in double.
    EXPECT_LT(worst, 1e-4);
}

TEST(LobeMixture, SteepOutliersKeepTheirEnergyWithoutDraggingTheLobe) {
    // 255 flat normals and one within a degree of the horizon in one 16×16 footprint.
    auto b = build(mapOf(16, 16, [](int x, int y) {
        return x == 3 && y == 5 ? glm::vec3(1.0f, 0.0f, 0.005f) : glm::vec3(0.0f, 0.0f, 1.0f);
    }));
    const double s = 1024.0;
    const TexelLobe lean = methodLobe(Method::Lean, b.pyramid.boxMoments(4, 0, 0), s);
    EXPECT_GT(lean.slopeCov[0], 10.0); // LEAN's variance takes 100²/256 from the outlier
    const double outlierSlope =
        double(LobeMoments::ofNormal(glm::normalize(glm::vec3(1.0f, 0.0f, 0.005f)), 1.0 / s).mean().x);
    for (int k = 1; k <= kMaxMixtureLobes; ++k) {
        const MixturePyramid mp = MixturePyramid::build(b.pyramid, s, k);
        const LobeMixture& m = mp.at(4, 0, 0);
        EXPECT_DOUBLE_EQ(m.totalWeight(), 256.0);
        ASSERT_TRUE(allFinite(m, mp.minVariance()));
        const auto c = m.lobes[0].covariance(mp.minVariance());
        if (k == 1) {
            // One lobe is LEAN's, dragged alike.
            EXPECT_NEAR(c[0], lean.slopeCov[0], 1e-4 * lean.slopeCov[0]);
            continue;
        }
        // With a second lobe the outlier keeps a lobe of its own, as steep as it is (its energy where it
        // reflects), and the flat lobe keeps the base lobe's variance and a flat mean.
        ASSERT_EQ(m.count, 2) << "k " << k;
        EXPECT_EQ(m.lobes[0].w, 255.0) << "k " << k;
        EXPECT_LT(c[0], 1.001 / (s + 2.0)) << "k " << k;
        EXPECT_LT(std::abs(m.lobes[0].mean().x), 1e-6) << "k " << k;
        EXPECT_EQ(m.lobes[1].w, 1.0) << "k " << k;
        EXPECT_NEAR(m.lobes[1].mean().x, outlierSlope, 1e-6 * outlierSlope) << "k " << k;
    }
}

// The squared-error cost: 0 for equal lobes, the same bits either way round (the reduction reads a
// merged lobe's row both ways), never negative, and finite from one finest texel to a 4096² footprint,
// from power 1 to 10^6 and from flat to steep slopes (±100, the slope limit), correlated lobes too.
TEST(LobeMixture, SquaredErrorCostIsFiniteSymmetricAndZeroForEqualLobes) {
    const auto lobe = [](double w, glm::dvec2 b, double vx, double vy, double c) {
        return LobeMoments{
            w, w * b.x, w * b.y, w * (vx + b.x * b.x), w * (vy + b.y * b.y), w * (c + b.x * b.y)};
    };
    int cases = 0;
    for (const double s : {1.0, 64.0, 1e6}) {
        const double v = mixtureBaseVariance(s, 3);
        for (const double wa : {1.0, 16.0, 16777216.0})
            for (const double wb : {1.0, 4096.0})
                for (const glm::dvec2 ba : {glm::dvec2(0.0), glm::dvec2(100.0, -100.0), glm::dvec2(0.3, 0.1)})
                    for (const glm::dvec2 bb :
                         {glm::dvec2(0.0), glm::dvec2(-100.0, 100.0), glm::dvec2(0.3, 0.2)}) {
                        const LobeMoments a = lobe(wa, ba, v, 4.0 * v, 1.9 * v);
                        const LobeMoments b = lobe(wb, bb, 9.0 * v, v, -0.5 * v);
                        const double ab = iseMergeCost(a, b, v), ba2 = iseMergeCost(b, a, v);
                        ASSERT_TRUE(std::isfinite(ab)) << s << " " << wa << " " << wb;
                        EXPECT_GE(ab, 0.0);
                        EXPECT_EQ(std::memcmp(&ab, &ba2, sizeof ab), 0) << s << " " << wa << " " << wb;
                        EXPECT_EQ(iseMergeCost(a, a, v), 0.0) << s << " " << wa;
                        ++cases;
                    }
    }
    EXPECT_EQ(cases, 162);
}

// Slots go by the expected log-likelihood of each child lobe's normals, its weight times its lobe's:
// a texel's heavy lobe takes the slot of the parent lobe it matches even where a light broad lobe of
// scattered normals would rather have that slot. The parent (the top, 1×1) holds a flat lobe in slot 0
// and a bevel at slope 0.4 in slot 1, equally heavy; the child holds a heavy flat lobe and a light broad
// one centred at −0.1. Unweighted, the broad lobe's preference (31 for slot 0) outvotes the flat
// lobe's (21), which would move the texel's main lobe into the bevel's slot; filtering with its
// neighbours would then merge it with their bevels.
TEST(LobeMixture, AHeavyLobeTakesTheSlotItMatchesBeforeALightBroadOne) {
    auto b = build(mapOf(4, 2, [](int, int) { return glm::vec3(0.0f, 0.0f, 1.0f); }));
    const double s = 256.0;
    const auto lobe = [](double w, glm::dvec2 m, double v) {
        return LobeMoments{w, w * m.x, w * m.y, w * (v + m.x * m.x), w * (v + m.y * m.y), w * m.x * m.y};
    };
    const double v = mixtureBaseVariance(s, 2);
    const MixturePyramid mp = MixturePyramid::build(b.pyramid, s, 2, -1, nullptr, [&](MixturePyramid& p) {
        LobeMixture top;
        top.count = 2;
        top.lobes[0] = lobe(4.0, {0.0, 0.0}, v);
        top.lobes[1] = lobe(4.0, {0.4, 0.0}, v);
        p.replace(2, 0, 0, top);
        LobeMixture child;
        child.count = 2;
        child.lobes[0] = lobe(0.4, {-0.1, 0.0}, 0.1); // canonical order: by mean x
        child.lobes[1] = lobe(3.6, {0.0, 0.0}, v);
        p.replace(1, 0, 0, child);
        LobeMixture bevel;
        bevel.count = 1;
        bevel.lobes[0] = lobe(4.0, {0.4, 0.0}, v);
        p.replace(1, 1, 0, bevel);
    });
    const LobeMixture& m = mp.at(1, 0, 0);
    ASSERT_EQ(m.count, 2);
    EXPECT_EQ(m.lobes[0].w, 3.6); // the flat lobe in the flat slot
    EXPECT_EQ(m.lobes[1].w, 0.4);
    EXPECT_EQ(mp.at(1, 1, 0).lobes[1].w, 4.0); // the neighbour's bevel in the bevel slot
}

// A heavy narrow lobe among lighter ones (a footprint of a noisy map: most normals in one cluster, a
// small cluster beside it, the rest strewn over steeper slopes). Reduced to 2..4 lobes by the squared
// error, the main lobe keeps its weight, mean and spread exactly (the highlight keeps its height) and
// the others gather among themselves. Runnalls' bound merges the small cluster into the main lobe
// first, which then holds 10 % more weight spread over about twice the variance.
TEST(LobeMixture, SquaredErrorKeepsTheMainLobeApartFromScatteredOnes) {
    const double v = 1.0 / 258.0;
    std::vector<LobeMoments> lobes;
    const auto add = [&](double w, glm::dvec2 b) {
        lobes.push_back({w, w * b.x, w * b.y, w * (v + b.x * b.x), w * (v + b.y * b.y), w * b.x * b.y});
    };
    add(200.0, {0.0, 0.0});
    add(20.0, {0.2, 0.0});
    for (int i = 0; i < 5; ++i) {
        const double angle = 2.0 * kPi<double> * (i + 0.5) / 5.0;
        add(20.0, {std::cos(angle), std::sin(angle)});
    }
    for (int k = 2; k <= kMaxMixtureLobes; ++k) {
        const LobeMixture ise = reduceLobes(lobes, k, v, MergeCriterion::SquaredError);
        ASSERT_EQ(ise.count, k);
        EXPECT_DOUBLE_EQ(ise.totalWeight(), 320.0);
        ASSERT_TRUE(allFinite(ise, v));
        int main = -1;
        for (int i = 0; i < ise.count; ++i)
            if (ise.lobes[size_t(i)].w == 200.0) main = i;
        ASSERT_GE(main, 0) << "k " << k;
        const auto c = ise.lobes[size_t(main)].covariance(v);
        EXPECT_EQ(ise.lobes[size_t(main)].mean(), glm::dvec2(0.0)) << "k " << k;
        EXPECT_NEAR(c[0], v, 1e-12) << "k " << k;
        EXPECT_NEAR(c[1], v, 1e-12) << "k " << k;

        const LobeMixture kl = reduceLobes(lobes, k, v, MergeCriterion::KullbackLeibler);
        ASSERT_EQ(kl.count, k);
        const LobeMoments* heaviest = &kl.lobes[0];
        for (int i = 1; i < kl.count; ++i)
            if (kl.lobes[size_t(i)].w > heaviest->w) heaviest = &kl.lobes[size_t(i)];
        EXPECT_EQ(heaviest->w, 220.0) << "k " << k;
        EXPECT_GT(heaviest->covariance(v)[0], 1.8 * v) << "k " << k;
    }
}

TEST(LobeMixture, ExtremesStayFinite) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (const auto& [w, h] : {std::pair{1, 1}, {3, 5}, {17, 9}}) {
        auto b = build(mapOf(w, h, [&](int x, int y) {
            if ((x + y) % 3 == 0) return glm::vec3(float(u(rng)), float(u(rng)), 0.0f); // on the horizon
            return glm::vec3(float(u(rng)), float(u(rng)), 0.3f);
        }));
        for (const double s : {1.0, 1e6}) {
            const MixturePyramid mp = MixturePyramid::build(b.pyramid, s, 3);
            EXPECT_EQ(mp.levelCount(), b.pyramid.levelCount());
            for (int level = 1; level < mp.levelCount(); ++level) {
                const PyramidLevel& l = b.pyramid.level(level);
                for (int y = 0; y < l.height; ++y)
                    for (int x = 0; x < l.width; ++x) {
                        const LobeMixture& m = mp.at(level, x, y);
                        ASSERT_TRUE(allFinite(m, mp.minVariance()));
                        EXPECT_EQ(m.totalWeight(), double(b.pyramid.footprintCount(level, x, y)));
                        for (const glm::dvec3 hv :
                             {glm::dvec3(0, 0, 1), glm::normalize(glm::dvec3(1, 0, 1e-3))})
                            EXPECT_TRUE(
                                std::isfinite(mixtureValue(m, glm::dvec3(0, 0, 1), hv, mp.minVariance())));
                    }
            }
        }
    }
    // A NaN normal counts as a flat one.
    const LobeMoments nan =
        LobeMoments::ofNormal(glm::vec3(std::nanf(""), 0.0f, 1.0f), mixtureBaseVariance(64.0, 3));
    EXPECT_EQ(nan.bx, 0.0);
    EXPECT_EQ(nan.mxx, 1.0 / 66.0);
}

TEST(LobeMixture, SameBitsOnOneThreadAndOnAll) {
    auto map = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png");
    ASSERT_TRUE(map) << map.error();
    auto b = build(std::move(map).value());
    const MixturePyramid all = MixturePyramid::build(b.pyramid, 256.0, 3, 3);
    MixturePyramid one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = MixturePyramid::build(b.pyramid, 256.0, 3, 3);
    }
    EXPECT_TRUE(test::sameLobesBitForBit(all, one, b.pyramid, 3));
}

// The reduction as its header states it, one cost call per pair per step (no cost matrix, no
// four-at-a-time costs): the cheapest pair (mergeCost or iseMergeCost) merges until k remain, and then while
// a pair costs nothing (Runnalls': at most 1e-9 of the total weight; the squared error, iseMergeCost: at most
// 1e-9 of the pair's overlaps with themselves, w²/(4π√det Σ)); ties to the lower indices; canonical order.
double selfOverlap(const LobeMoments& l, double minVariance) {
    const auto c = l.covariance(minVariance);
    return l.w * l.w / (4.0 * kPi<double> * std::sqrt(c[0] * c[1] - c[2] * c[2]));
}

LobeMixture referenceReduction(std::vector<LobeMoments> lobes, int k, double minVariance,
                               MergeCriterion criterion = MergeCriterion::KullbackLeibler) {
    const bool squared = criterion == MergeCriterion::SquaredError && k > 1;
    std::erase_if(lobes, [](const LobeMoments& l) { return !(l.w > 0.0); });
    double total = 0.0;
    for (const auto& l : lobes)
        total += l.w;
    const auto cost = [&](const LobeMoments& a, const LobeMoments& b) {
        return squared ? iseMergeCost(a, b, minVariance) : mergeCost(a, b, minVariance);
    };
    while (lobes.size() > 1) {
        size_t bi = 0, bj = 0;
        double best = std::numeric_limits<double>::infinity();
        for (size_t i = 0; i < lobes.size(); ++i)
            for (size_t j = i + 1; j < lobes.size(); ++j)
                if (const double c = cost(lobes[i], lobes[j]); c < best) best = c, bi = i, bj = j;
        const double negligible =
            squared ? 1e-9 * (selfOverlap(lobes[bi], minVariance) + selfOverlap(lobes[bj], minVariance))
                    : 1e-9 * total;
        if (lobes.size() <= size_t(k) && !(best <= negligible)) break;
        lobes[bi] += lobes[bj];
        lobes.erase(lobes.begin() + std::ptrdiff_t(bj));
    }
    std::sort(lobes.begin(), lobes.end(), [](const LobeMoments& a, const LobeMoments& b) {
        const glm::dvec2 ma = a.mean(), mb = b.mean();
        if (ma.x != mb.x) return ma.x < mb.x;
        if (ma.y != mb.y) return ma.y < mb.y;
        return a.w > b.w;
    });
    LobeMixture out;
    out.count = int(lobes.size());
    for (size_t i = 0; i < lobes.size(); ++i)
        out.lobes[i] = lobes[i];
    return out;
}

// The bake's reductions (a cost matrix, its rows four pairs at a time in AVX2 or SSE2, or a row's
// squared errors in vector lanes) give the reference's lobes bit for bit under either criterion: random
// clusters of 1 to 40 lobes (a level-1 footprint's normals, up to 3×3 children of 4 lobes), light lobes
// and equal lobes among them, every K.
TEST(LobeMixture, ReductionIsTheReferenceGreedyMergeBitForBit) {
    std::mt19937 rng(7);
    std::normal_distribution<double> slope(0.0, 0.4);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double minVariance = 1.0 / 256.0;
    int cases = 0;
    for (int trial = 0; trial < 600; ++trial) {
        const size_t n = 1 + size_t(trial % 40);
        std::vector<LobeMoments> lobes;
        const glm::dvec2 centre(slope(rng), slope(rng));
        for (size_t i = 0; i < n; ++i) {
            if (trial % 7 == 0 && i > 0 && unit(rng) < 0.3) {
                lobes.push_back(lobes.back()); // equal lobes
                continue;
            }
            const double w = trial % 3 == 0 && unit(rng) < 0.25 ? 0.005 * unit(rng) : 0.2 + unit(rng);
            const glm::dvec2 b = centre + glm::dvec2(slope(rng), slope(rng)) * (unit(rng) < 0.5 ? 0.1 : 1.0);
            const double vx = minVariance * (1.0 + 20.0 * unit(rng)),
                         vy = minVariance * (1.0 + 20.0 * unit(rng));
            const double c = 0.5 * std::sqrt(vx * vy) * (2.0 * unit(rng) - 1.0);
            LobeMoments l;
            l.w = w;
            l.bx = w * b.x, l.by = w * b.y;
            l.mxx = w * (vx + b.x * b.x), l.myy = w * (vy + b.y * b.y), l.mxy = w * (c + b.x * b.y);
            lobes.push_back(l);
        }
        for (MergeCriterion criterion : {MergeCriterion::KullbackLeibler, MergeCriterion::SquaredError})
            for (int k = 1; k <= kMaxMixtureLobes; ++k) {
                const LobeMixture got = reduceLobes(lobes, k, minVariance, criterion);
                const LobeMixture want = referenceReduction(lobes, k, minVariance, criterion);
                const int c = int(criterion);
                ASSERT_EQ(got.count, want.count) << "trial " << trial << ", k " << k << ", criterion " << c;
                ASSERT_EQ(std::memcmp(got.lobes.data(), want.lobes.data(), sizeof(got.lobes)), 0)
                    << "trial " << trial << ", k " << k << ", criterion " << c;
                ++cases;
            }
    }
    EXPECT_EQ(cases, 4800);
}

// A lobe count outside 1..kMaxMixtureLobes is clamped under either criterion: 12 scattered lobes asked
// for 0, −3, kMaxMixtureLobes + 1 or 9 lobes give the bits of 1 and of kMaxMixtureLobes (the squared
// error's reduction once merged only down to k, and its result overran the mixture's slots).
TEST(LobeMixture, LobeCountOutsideItsRangeIsClamped) {
    const double minVariance = 1.0 / 258.0;
    std::vector<LobeMoments> lobes;
    for (int i = 0; i < 12; ++i) {
        const double a = 0.7 * i;
        lobes.push_back(LobeMoments::ofNormal(
            glm::normalize(glm::vec3(0.4f * float(std::cos(a)), 0.4f * float(std::sin(a)), 1.0f)),
            minVariance));
    }
    for (MergeCriterion criterion : {MergeCriterion::KullbackLeibler, MergeCriterion::SquaredError}) {
        const LobeMixture one = reduceLobes(lobes, 1, minVariance, criterion);
        const LobeMixture most = reduceLobes(lobes, kMaxMixtureLobes, minVariance, criterion);
        ASSERT_EQ(one.count, 1);
        ASSERT_EQ(most.count, kMaxMixtureLobes);
        for (int k : {0, -3}) {
            const LobeMixture got = reduceLobes(lobes, k, minVariance, criterion);
            ASSERT_EQ(got.count, 1) << "k " << k;
            EXPECT_EQ(std::memcmp(got.lobes.data(), one.lobes.data(), sizeof(got.lobes)), 0) << "k " << k;
        }
        for (int k : {kMaxMixtureLobes + 1, 9}) {
            const LobeMixture got = reduceLobes(lobes, k, minVariance, criterion);
            ASSERT_EQ(got.count, kMaxMixtureLobes) << "k " << k;
            EXPECT_EQ(std::memcmp(got.lobes.data(), most.lobes.data(), sizeof(got.lobes)), 0) << "k " << k;
        }
    }
}

// Four finest lobes of one power (a level-1 footprint), which the reduction decides in closed form
// (the closest pair merges) where it can, are still the reference's lobes bit for bit: powers 1 to
// 10^6, normals off an 8-bit grid (ties and near ties among the distances), steep normals at the
// slope limit, equal normals (two, or all four), near-equal ones, exact ties, and patterns at the
// correlation clamp, and groups of equal normals among distinct ones (two pairs, three and one, one
// pair). It also counts the footprints inside the closed forms' domains (a clear closest pair,
// u >= 1e-3; equal lobes among lobes u >= 1e-3 apart, three equal among them), so the sample cannot
// drift to fallbacks only.
TEST(LobeMixture, FourFinestLobesAreTheReferenceBitForBit) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    const double powers[] = {1.0, 8.0, 64.0, 256.0, 1024.0, 16384.0, 1e6};
    auto code8 = [](float v) {
        return float(std::lround((v * 0.5f + 0.5f) * 255.0f)) / 255.0f * 2.0f - 1.0f;
    };
    int cases = 0, distinctPairs = 0, equalGroups = 0, threeEqual = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const double s = powers[size_t(trial) % std::size(powers)];
        const int kind = (trial / int(std::size(powers))) % 10;
        const double spread = kind == 0 ? 0.02 : kind == 1 ? 0.3 : 1.0;
        std::array<glm::vec3, 4> normals;
        const glm::dvec2 centre(0.3 * gauss(rng), 0.3 * gauss(rng));
        for (size_t i = 0; i < 4; ++i) {
            glm::dvec2 b = centre + spread * glm::dvec2(gauss(rng), gauss(rng));
            if (kind == 3 && i == 3)
                b = glm::dvec2(80.0 * (unit(rng) - 0.5), 80.0 * (unit(rng) - 0.5)); // steep
            glm::vec3 n = glm::normalize(glm::vec3(float(b.x), float(b.y), 1.0f));
            if (kind == 2 || kind == 4) n = glm::vec3(code8(n.x), code8(n.y), code8(n.z)); // 8-bit
            if (kind == 4 && i == 2) n = normals[1];                                       // equal
            if (kind == 5 && i % 2 == 1) // near-equal pairs: the same normal one float ulp apart
                n = glm::vec3(std::nextafter(normals[i - 1].x, 2.0f), normals[i - 1].y, normals[i - 1].z);
            if (kind == 6 && i == 0 &&
                trial % 2) // steep: at high powers, merging equal lobes costs a rounding
                n = glm::normalize(
                    glm::vec3(float(80.0 * (unit(rng) - 0.5)), float(80.0 * (unit(rng) - 0.5)), 1.0f));
            if (kind == 6 && i > 0) n = normals[0]; // all four equal: a flat or upsampled footprint
            normals[i] = n;
        }
        if (kind >= 7) {
            // Equal lobes in groups, at positions that vary: two pairs, three and one (the three
            // steep at times, where merging the third costs a rounding), or one pair.
            std::array<size_t, 4> at{0, 1, 2, 3};
            std::shuffle(at.begin(), at.end(), rng);
            if (kind == 8 && trial % 2)
                normals[at[0]] = glm::normalize(
                    glm::vec3(float(80.0 * (unit(rng) - 0.5)), float(80.0 * (unit(rng) - 0.5)), 1.0f));
            if (kind == 7) normals[at[1]] = normals[at[0]], normals[at[3]] = normals[at[2]];
            if (kind == 8) normals[at[1]] = normals[at[2]] = normals[at[0]];
            if (kind == 9) normals[at[1]] = normals[at[0]];
        }
        if (trial % 3 == 0) {
            // Exact ties: two pairs at equal distances along different axes (a Pythagorean triple in
            // dyadic slopes, n.z = 1 so the slopes are exact), computed through different roundings.
            const std::array<glm::ivec3, 4> triples{{{3, 4, 5}, {5, 12, 13}, {8, 15, 17}, {7, 24, 25}}};
            const glm::ivec3 t = triples[size_t(trial / 3) % triples.size()];
            const float scale = std::ldexp(1.0f, -4 - (trial / 12) % 6), ox = float(trial % 7) / 8,
                        oy = -0.25f;
            normals = {glm::vec3(ox, oy, 1), glm::vec3(ox + scale * float(t.z), oy, 1),
                       glm::vec3(ox + scale * float(t.x), oy + scale * float(t.y), 1),
                       glm::vec3(ox - scale * float(t.y), oy - scale * float(t.x) * 3, 1)};
            if (trial % 2) std::swap(normals[1], normals[2]);
        }
        if (trial % 50 == 0) // a diagonal pair far apart: the merged correlation at its clamp
            normals = {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(30, 30, 1)),
                       glm::normalize(glm::vec3(-30, 31, 1)), glm::normalize(glm::vec3(31, -30, 1))};
        // The fit's floor: each lobe's base variance (that of K >= 2; K = 1 sums whatever it gets).
        const double minVariance = mixtureBaseVariance(s, kMaxMixtureLobes);
        std::vector<LobeMoments> lobes;
        for (const glm::vec3& n : normals)
            lobes.push_back(LobeMoments::ofNormal(n, minVariance));
        for (int k = 1; k <= kMaxMixtureLobes; ++k) {
            const LobeMixture got = reduceLobes(lobes, k, minVariance);
            const LobeMixture want = referenceReduction(lobes, k, minVariance);
            ASSERT_EQ(got.count, want.count) << "trial " << trial << ", s " << s << ", k " << k;
            ASSERT_EQ(std::memcmp(got.lobes.data(), want.lobes.data(), sizeof(got.lobes)), 0)
                << "trial " << trial << ", s " << s << ", k " << k;
            ++cases;
        }
        std::array<double, 6> d{};
        size_t p = 0;
        double apart = std::numeric_limits<double>::infinity(); // the closest unequal lobes
        bool equal = false;
        for (size_t i = 0; i < 4; ++i)
            for (size_t j = i + 1; j < 4; ++j) {
                d[p++] =
                    glm::distance(glm::dvec2(lobes[i].bx, lobes[i].by), glm::dvec2(lobes[j].bx, lobes[j].by));
                if (std::memcmp(&lobes[i], &lobes[j], sizeof(LobeMoments)) == 0)
                    equal = true;
                else
                    apart = std::min(apart, d[p - 1]);
            }
        std::sort(d.begin(), d.end());
        distinctPairs += d[0] * d[0] * s / 4 >= 1e-3 && d[1] > d[0] * (1 + 1e-9);
        const bool allEqual = apart == std::numeric_limits<double>::infinity();
        equalGroups += equal && !allEqual && apart * apart / (4.0 * minVariance) >= 1e-3;
        // Three equal lobes and one apart: the closed form computes the third merge's cost.
        threeEqual += kind == 8 && equal && !allEqual && apart * apart / (4.0 * minVariance) >= 1e-3;
    }
    EXPECT_EQ(cases, 16000);
    EXPECT_GT(distinctPairs, 1000); // footprints whose closest pair the closed form can decide
    EXPECT_GT(equalGroups, 500);    // footprints with equal lobes among clearly distinct ones
    EXPECT_GT(threeEqual, 100);     // three of them equal
}

TEST(LobeMixture, NdfKeepsItsEnergy) {
    // ∫ D(h) h_z dω_h = 1 for each lobe (the slope Gaussian's normalization), so for the mixture.
    const double t = std::tan(0.25);
    auto b = build(mapOf(4, 4, [&](int x, int) {
        return x % 2 ? glm::vec3(float(t), 0.0f, 1.0f) : glm::vec3(0.0f, float(-t), 1.0f);
    }));
    const MixturePyramid mp = MixturePyramid::build(b.pyramid, 64.0, 2);
    const LobeMixture& m = mp.at(2, 0, 0);
    ASSERT_EQ(m.count, 2);
    double sum = 0.0;
    const int n = 800;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
            const double theta = (i + 0.5) / n * (kPi<double> / 2),
                         phi = (j + 0.5) / (2 * n) * 2 * kPi<double>;
            const glm::dvec3 h(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                               std::cos(theta));
            sum += mixtureNdf(m, h, mp.minVariance()) * h.z * std::sin(theta) * (kPi<double> / 2 / n) *
                   (2 * kPi<double> / (2 * n));
        }
    EXPECT_NEAR(sum, 1.0, 2e-3);
}

TEST(LobeMixture, ErrsLessThanLeanOnARealMap) {
    // The evaluate metric (texture space, box footprints, the default 48 light/view pairs) at s = 256.
    auto map = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png");
    ASSERT_TRUE(map) << map.error();
    auto b = build(std::move(map).value());
    const double s = 256.0;
    const auto dirs = evaluationDirections(EvaluateOptions{});
    const MixturePyramid k3 = MixturePyramid::build(b.pyramid, s, 3, 3);
    for (int level : {2, 3}) {
        const PyramidLevel& l = b.pyramid.level(level);
        double truth = 0.0, leanAbs = 0.0, leanSum = 0.0, mixAbs = 0.0, mixSum = 0.0;
        for (int y = 0; y < l.height; y += 2)
            for (int x = 0; x < l.width; x += 2) {
                const TexelLobe lean = methodLobe(Method::Lean, b.pyramid.boxMoments(level, x, y), s);
                for (const DirectionPair& d : dirs) {
                    const double t = groundTruthTexel(b.pyramid, level, x, y, s, d);
                    const double vl = methodValue(lean, d);
                    const double vm = mixtureValue(k3.at(level, x, y), d.l, d.h, k3.minVariance());
                    truth += t;
                    leanAbs += std::abs(vl - t);
                    leanSum += vl;
                    mixAbs += std::abs(vm - t);
                    mixSum += vm;
                }
            }
        std::printf("[measured] trak-rust1 s = 256 mip %d: relative L1 LEAN %.4f, mixture K=3 %.4f; energy "
                    "LEAN %.4f, mixture %.4f\n",
                    level, leanAbs / truth, mixAbs / truth, leanSum / truth, mixSum / truth);
        EXPECT_LT(mixAbs, leanAbs) << "mip " << level;
        EXPECT_LT(std::abs(mixSum / truth - 1.0), std::abs(leanSum / truth - 1.0) + 0.01) << "mip " << level;
    }
}
