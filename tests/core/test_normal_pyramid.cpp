#include <burnish/core/prefilter/normal_pyramid.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

using namespace burnish;

namespace {

// Moments are stored in float: relative accuracy of a few float ulps of the combined values.
constexpr double kMomentTolerance = 2e-6;

std::shared_ptr<const NormalMap> shared(NormalMap map) {
    return std::make_shared<const NormalMap>(std::move(map));
}

std::vector<glm::vec3> randomNormals(int count, float spread, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0.0f, spread);
    std::vector<glm::vec3> n(static_cast<size_t>(count));
    for (auto& v : n)
        v = glm::normalize(glm::vec3(g(rng), g(rng), 1.0f));
    return n;
}

// Direct double-precision moments of the finest normals in [x0,x1)×[y0,y1).
struct Direct {
    glm::dvec3 mean{0.0};
    double projectedVariance = 0.0;
    glm::dvec2 slope{0.0};
    double m[3] = {0, 0, 0};
};

Direct direct(const NormalMap& map, int x0, int x1, int y0, int y1) {
    Direct d;
    double count = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const glm::dvec3 n = map.at(x, y);
            d.mean += n;
            const glm::dvec2 b(n.x / std::max(n.z, double(kMinSlopeZ)),
                               n.y / std::max(n.z, double(kMinSlopeZ)));
            d.slope += b;
            d.m[0] += b.x * b.x;
            d.m[1] += b.y * b.y;
            d.m[2] += b.x * b.y;
            count += 1;
        }
    d.mean /= count;
    d.slope /= count;
    for (double& v : d.m)
        v /= count;
    const glm::dvec3 nHat = glm::normalize(d.mean);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const double c = glm::dot(glm::dvec3(map.at(x, y)), nHat);
            d.projectedVariance += 1.0 - c * c;
        }
    d.projectedVariance /= count;
    return d;
}

} // namespace

TEST(NormalPyramid, LevelSizesFollowTheMipRule) {
    auto map = shared(makeNormalMap(5, 3, std::vector<glm::vec3>(15, glm::vec3(0, 0, 1))));
    auto pyramid = NormalPyramid::build(map, {BorderMode::Wrap, FilterKernel::Box});
    ASSERT_EQ(pyramid.levelCount(), 3); // 5×3 → 2×1 → 1×1
    EXPECT_EQ(pyramid.level(1).width, 2);
    EXPECT_EQ(pyramid.level(1).height, 1);
    EXPECT_EQ(pyramid.level(2).width, 1);
    // Every finest texel counted exactly once at every level.
    for (int k = 0; k < pyramid.levelCount(); ++k) {
        int total = 0;
        for (int y = 0; y < pyramid.level(k).height; ++y)
            for (int x = 0; x < pyramid.level(k).width; ++x)
                total += pyramid.footprintCount(k, x, y);
        EXPECT_EQ(total, 15) << "level " << k;
    }
}

TEST(NormalPyramid, OneByOneMapHasOneLevel) {
    auto pyramid = NormalPyramid::build(shared(makeNormalMap(1, 1, {glm::vec3(0.1f, 0, 1)})));
    EXPECT_EQ(pyramid.levelCount(), 1);
    EXPECT_FLOAT_EQ(pyramid.moments(0, 0, 0).projectedVariance(), 0.0f);
}

TEST(NormalPyramid, BoxMomentsMatchDirectSumsOverAlignedBlocks) {
    const int size = 32;
    auto map = shared(makeNormalMap(size, size, randomNormals(size * size, 0.3f, 1)));
    auto pyramid = NormalPyramid::build(map, {BorderMode::Wrap, FilterKernel::Box});
    for (int k = 1; k < pyramid.levelCount(); ++k) {
        const int block = 1 << k;
        for (int y = 0; y < pyramid.level(k).height; y += 3)
            for (int x = 0; x < pyramid.level(k).width; x += 3) {
                const Direct d = direct(*map, x * block, (x + 1) * block, y * block, (y + 1) * block);
                const NormalMoments m = pyramid.boxMoments(k, x, y);
                for (int i = 0; i < 3; ++i)
                    EXPECT_NEAR(m.mean[i], d.mean[i], kMomentTolerance);
                EXPECT_NEAR(m.projectedVariance(), d.projectedVariance, kMomentTolerance);
                const auto M = m.slopeSecondMoments();
                for (int i = 0; i < 3; ++i)
                    EXPECT_NEAR(M[size_t(i)], d.m[i], kMomentTolerance * 10);
                EXPECT_NEAR(m.slope.x, d.slope.x, kMomentTolerance);
            }
    }
}

TEST(NormalPyramid, NonPowerOfTwoFootprintsAreExact) {
    const int w = 7, h = 5;
    auto map = shared(makeNormalMap(w, h, randomNormals(w * h, 0.4f, 2)));
    auto pyramid = NormalPyramid::build(map, {BorderMode::Clamp, FilterKernel::Box});
    const int top = pyramid.levelCount() - 1;
    const Direct d = direct(*map, 0, w, 0, h);
    EXPECT_NEAR(pyramid.boxMoments(top, 0, 0).projectedVariance(), d.projectedVariance, kMomentTolerance);
    for (int k = 0; k <= top; ++k) {
        const auto& l = pyramid.level(k);
        for (int y = 0; y < l.height; ++y)
            for (int x = 0; x < l.width; ++x) {
                const Direct dd = direct(*map, l.xStart[size_t(x)], l.xStart[size_t(x) + 1],
                                         l.yStart[size_t(y)], l.yStart[size_t(y) + 1]);
                EXPECT_NEAR(pyramid.boxMoments(k, x, y).projectedVariance(), dd.projectedVariance,
                            kMomentTolerance);
            }
    }
}

TEST(NormalPyramid, TinyVarianceSurvivesBesideAUnitMean) {
    // Two directions 1e-4 rad apart: projected variance ≈ (5e-5)² = 2.5e-9, far below float's
    // resolution of 1 − (n·n̄)² computed naively (~1e-7). Central moments keep it.
    const float a = 5e-5f;
    std::vector<glm::vec3> n;
    for (int i = 0; i < 64; ++i)
        n.push_back(glm::normalize(glm::vec3((i % 2) ? a : -a, 0.0f, 1.0f)));
    auto pyramid =
        NormalPyramid::build(shared(makeNormalMap(8, 8, n)), {BorderMode::Wrap, FilterKernel::Box});
    const float v = pyramid.boxMoments(pyramid.levelCount() - 1, 0, 0).projectedVariance();
    EXPECT_NEAR(v, double(a) * a, 0.05 * double(a) * a);
}

TEST(NormalPyramid, RowFilterKeepsTinyVariancesBesideATiltedMean) {
    // forEachMomentRow sums in float about each texel's own normal; a tent-filtered variance of
    // ~1e-9 next to |Na| = 1 (tilted 0.5 rad, so no component is 0) must keep ~1e-6 relative
    // accuracy against the double-precision per-texel path. A float sum of raw moments would
    // lose it entirely (float resolves 1 − 1e-9 as 1).
    constexpr double kTinyRelativeTolerance = 1e-4;
    std::mt19937 rng(7);
    std::normal_distribution<double> g(0.0, 3e-5);
    std::vector<glm::vec3> n(64 * 32);
    for (auto& v : n)
        v = glm::vec3(glm::normalize(glm::dvec3(std::sin(0.5) + g(rng), g(rng), std::cos(0.5))));
    const auto pyramid =
        NormalPyramid::build(shared(makeNormalMap(64, 32, n)), {BorderMode::Wrap, FilterKernel::Tent});
    pyramid.forEachMomentRow(0, [&](int y, const NormalMoments* row) {
        for (int x = 0; x < 64; ++x) {
            const NormalMoments d = pyramid.moments(0, x, y);
            ASSERT_GT(d.projectedVariance(), 1e-10f);
            EXPECT_NEAR(row[x].projectedVariance(), d.projectedVariance(),
                        kTinyRelativeTolerance * d.projectedVariance());
            EXPECT_NEAR(row[x].slopeCov[0], d.slopeCov[0], kTinyRelativeTolerance * d.slopeCov[0]);
        }
    });
}

TEST(NormalPyramid, FlatMapHasZeroVarianceAtEveryLevelAndKernel) {
    for (auto kernel : {FilterKernel::Box, FilterKernel::Tent, FilterKernel::Gaussian}) {
        auto pyramid = NormalPyramid::build(
            shared(makeNormalMap(16, 16, std::vector<glm::vec3>(256, glm::vec3(0, 0, 1)))),
            {BorderMode::Wrap, kernel});
        for (int k = 0; k < pyramid.levelCount(); ++k) {
            const NormalMoments m = pyramid.moments(k, 0, 0);
            EXPECT_EQ(m.projectedVariance(), 0.0f);
            EXPECT_FLOAT_EQ(m.lengthNa(), 1.0f);
        }
    }
}

TEST(NormalPyramid, TentKernelSpreadsVarianceToNeighboursAndWrapMatters) {
    // A single tilted texel at the left edge of an otherwise flat map.
    std::vector<glm::vec3> n(64, glm::vec3(0, 0, 1));
    n[8 * 3 + 0] = glm::normalize(glm::vec3(0.5f, 0, 1));
    auto mapPtr = shared(makeNormalMap(8, 8, n));
    auto wrap = NormalPyramid::build(mapPtr, {BorderMode::Wrap, FilterKernel::Tent});
    auto clamp = NormalPyramid::build(mapPtr, {BorderMode::Clamp, FilterKernel::Tent});
    auto box = NormalPyramid::build(mapPtr, {BorderMode::Wrap, FilterKernel::Box});
    EXPECT_EQ(box.moments(0, 1, 3).projectedVariance(), 0.0f);
    EXPECT_GT(wrap.moments(0, 1, 3).projectedVariance(), 0.0f);  // right neighbour sees it
    EXPECT_GT(wrap.moments(0, 7, 3).projectedVariance(), 0.0f);  // wraps to the right edge
    EXPECT_EQ(clamp.moments(0, 7, 3).projectedVariance(), 0.0f); // clamping does not
}

TEST(NormalPyramid, ToksvigRelationHoldsForNarrowSpreads) {
    // For small spreads, 1 − |Na| ≈ σ²/2 where σ² is the projected variance: Toksvig's estimate
    // (1 − |Na|)/|Na| and the projected variance agree to first order.
    auto pyramid = NormalPyramid::build(shared(makeNormalMap(64, 64, randomNormals(64 * 64, 0.05f, 3))),
                                        {BorderMode::Wrap, FilterKernel::Box});
    const NormalMoments m = pyramid.boxMoments(pyramid.levelCount() - 1, 0, 0);
    const double toksvig = 2.0 * (1.0 - m.lengthNa()) / m.lengthNa();
    EXPECT_NEAR(toksvig / m.projectedVariance(), 1.0, 0.02);
}

TEST(NormalPyramid, RowStreamingMatchesPerTexelFiltering) {
    // forEachMomentRow (separable, blocked, parallel) must give the moments of moments(k, x, y)
    // (the direct 2D weighted sum), for every kernel, border and level, odd sizes included.
    // Both sum in double and store float: agreement to a few float ulps.
    constexpr double kRowTolerance = 1e-6;
    auto map = shared(makeNormalMap(37, 21, randomNormals(37 * 21, 0.3f, 12)));
    for (auto kernel : {FilterKernel::Box, FilterKernel::Tent, FilterKernel::Gaussian})
        for (auto border : {BorderMode::Wrap, BorderMode::Clamp}) {
            const auto pyramid = NormalPyramid::build(map, {border, kernel});
            for (int k = 0; k < pyramid.levelCount(); ++k) {
                std::vector<int> rowsSeen(size_t(pyramid.level(k).height), 0);
                pyramid.forEachMomentRow(k, [&](int y, const NormalMoments* row) {
                    ++rowsSeen[size_t(y)];
                    for (int x = 0; x < pyramid.level(k).width; ++x) {
                        const NormalMoments d = pyramid.moments(k, x, y);
                        for (int i = 0; i < 3; ++i)
                            EXPECT_NEAR(row[x].mean[i], d.mean[i], kRowTolerance);
                        EXPECT_NEAR(row[x].projectedVariance(), d.projectedVariance(), kRowTolerance);
                        for (int i = 0; i < 3; ++i)
                            EXPECT_NEAR(row[x].slopeSecondMoments()[size_t(i)],
                                        d.slopeSecondMoments()[size_t(i)], kRowTolerance * 10);
                    }
                });
                for (int seen : rowsSeen)
                    EXPECT_EQ(seen, 1); // every row exactly once
            }
        }
}

// A pyramid of a moment subset (what the bake builds for one method) holds, for the moments in
// the set, exactly the bits of the full pyramid, in the box levels and the filtered rows; the
// moments left out are NormalMoments' defaults. Sizes 37×29 (uneven footprints) and 64×64.
TEST(NormalPyramid, MomentSubsetsEqualTheFullPyramidBitForBit) {
    auto same = [](float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; };
    for (const auto& [w, h] : {std::pair{37, 29}, std::pair{64, 64}}) {
        const auto map = shared(makeNormalMap(w, h, randomNormals(w * h, 0.4f, 11)));
        for (const FilterKernel kernel : {FilterKernel::Box, FilterKernel::Tent, FilterKernel::Gaussian}) {
            const auto full = NormalPyramid::build(map, {BorderMode::Wrap, kernel, kMomentsAll});
            for (const unsigned set :
                 {unsigned(kMomentsMean), unsigned(kMomentsCov), unsigned(kMomentsSlope)}) {
                const auto part = NormalPyramid::build(map, {BorderMode::Wrap, kernel, set});
                ASSERT_EQ(part.levelCount(), full.levelCount());
                auto check = [&](const NormalMoments& a, const NormalMoments& b, int k, int x, int y,
                                 bool boxLevel0) {
                    SCOPED_TRACE(testing::Message()
                                 << "set " << set << " level " << k << " texel " << x << "," << y);
                    for (int c = 0; c < 3; ++c)
                        ASSERT_TRUE(same(a.mean[c], b.mean[c]));
                    for (int c = 0; c < 6; ++c)
                        ASSERT_TRUE((set & kMomentsCov) ? same(a.cov[size_t(c)], b.cov[size_t(c)])
                                                        : a.cov[size_t(c)] == 0.0f);
                    // Level 0's box moments come from the normal itself, slopes included.
                    const bool slopes = (set & kMomentsSlope) || boxLevel0;
                    for (int c = 0; c < 2; ++c)
                        ASSERT_TRUE(slopes ? same(a.slope[c], b.slope[c]) : a.slope[c] == 0.0f);
                    for (int c = 0; c < 3; ++c)
                        ASSERT_TRUE(slopes ? same(a.slopeCov[size_t(c)], b.slopeCov[size_t(c)])
                                           : a.slopeCov[size_t(c)] == 0.0f);
                };
                for (int k = 0; k < full.levelCount(); ++k) {
                    const PyramidLevel& l = full.level(k);
                    for (int y = 0; y < l.height; ++y)
                        for (int x = 0; x < l.width; ++x)
                            check(part.boxMoments(k, x, y), full.boxMoments(k, x, y), k, x, y, k == 0);
                    std::vector<std::vector<NormalMoments>> rowsFull(size_t(l.height)),
                        rowsPart(size_t(l.height));
                    full.forEachMomentRow(k, [&](int y, const NormalMoments* r) {
                        rowsFull[size_t(y)].assign(r, r + l.width);
                    });
                    part.forEachMomentRow(k, [&](int y, const NormalMoments* r) {
                        rowsPart[size_t(y)].assign(r, r + l.width);
                    });
                    for (int y = 0; y < l.height; ++y)
                        for (int x = 0; x < l.width; ++x)
                            check(rowsPart[size_t(y)][size_t(x)], rowsFull[size_t(y)][size_t(x)], k, x, y,
                                  kernel == FilterKernel::Box && k == 0);
                }
            }
        }
    }
}
