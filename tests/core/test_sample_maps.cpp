#include <burnish/core/prefilter/sample_maps.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>

namespace burnish {
namespace {

struct SlopeStats {
    double meanSx2 = 0.0;
    double meanSy2 = 0.0;
    double lenMean = 0.0; // |mean normal| over the whole map
};

SlopeStats slopeStats(const NormalMap& map) {
    SlopeStats stats;
    glm::dvec3 sum(0.0);
    for (const glm::vec3& n : map.normals) {
        stats.meanSx2 += double(n.x / n.z) * double(n.x / n.z);
        stats.meanSy2 += double(n.y / n.z) * double(n.y / n.z);
        sum += glm::dvec3(n);
    }
    const double count = static_cast<double>(map.normals.size());
    stats.meanSx2 /= count;
    stats.meanSy2 /= count;
    stats.lenMean = glm::length(sum / count);
    return stats;
}

// Normals are normalized in float: 1 ± a few float ULPs.
constexpr double kUnitTolerance = 1e-5;

TEST(SampleMaps, EveryKindIsUnitUpFacingAndDeterministic) {
    for (SampleMapKind kind : allSampleMaps()) {
        const NormalMap a = makeSampleNormalMap(kind, 64);
        const NormalMap b = makeSampleNormalMap(kind, 64);
        ASSERT_EQ(a.width, 64);
        ASSERT_EQ(a.height, 64);
        ASSERT_EQ(a.normals.size(), b.normals.size());
        for (size_t i = 0; i < a.normals.size(); ++i) {
            ASSERT_EQ(a.normals[i], b.normals[i]) << sampleMapName(kind);
            ASSERT_NEAR(glm::length(a.normals[i]), 1.0f, kUnitTolerance);
            ASSERT_GT(a.normals[i].z, 0.0f);
        }
    }
}

TEST(SampleMaps, EveryKindIsRoughEnoughToAliasWhenMinified) {
    // A map whose whole-map mean normal is this short has a Toksvig variance (1−|Na|)/|Na| of at
    // least ~0.01: a base power above 100 loses most of its peak when the map shrinks to a texel.
    constexpr double kMaxMeanLength = 0.99;
    for (SampleMapKind kind : allSampleMaps()) {
        const SlopeStats stats = slopeStats(makeSampleNormalMap(kind, 256));
        EXPECT_LT(stats.lenMean, kMaxMeanLength) << sampleMapName(kind);
    }
}

TEST(SampleMaps, BrushedIsAnisotropicAcrossItsGrooves) {
    // Grooves run along x, so slopes across them (y) dominate; hammered dents are round.
    constexpr double kAnisotropyRatio = 5.0;
    constexpr double kIsotropyRatio = 1.5;
    const SlopeStats brushed = slopeStats(makeSampleNormalMap(SampleMapKind::Brushed, 256));
    EXPECT_GT(brushed.meanSy2, kAnisotropyRatio * brushed.meanSx2);
    const SlopeStats hammered = slopeStats(makeSampleNormalMap(SampleMapKind::Hammered, 256));
    EXPECT_LT(hammered.meanSy2, kIsotropyRatio * hammered.meanSx2);
    EXPECT_LT(hammered.meanSx2, kIsotropyRatio * hammered.meanSy2);
}

TEST(SampleMaps, TilesWithoutASeam) {
    // The step across the wrap seam is no larger than the largest step inside the map.
    for (SampleMapKind kind : allSampleMaps()) {
        const NormalMap map = makeSampleNormalMap(kind, 128);
        float inside = 0.0f;
        float seam = 0.0f;
        for (int y = 0; y < map.height; ++y) {
            for (int x = 0; x + 1 < map.width; ++x) {
                inside = std::max(inside, glm::length(map.at(x + 1, y) - map.at(x, y)));
            }
            seam = std::max(seam, glm::length(map.at(0, y) - map.at(map.width - 1, y)));
        }
        EXPECT_LE(seam, inside) << sampleMapName(kind);
    }
}

TEST(SampleMaps, TinySizesAndNamesWork) {
    for (SampleMapKind kind : allSampleMaps()) {
        const NormalMap one = makeSampleNormalMap(kind, 1);
        ASSERT_EQ(one.normals.size(), 1u);
        // A 1×1 map wraps onto itself: its central differences vanish and it is flat.
        EXPECT_EQ(one.normals[0], glm::vec3(0.0f, 0.0f, 1.0f));
        const auto parsed = sampleMapFromName(sampleMapName(kind));
        ASSERT_TRUE(parsed.ok());
        EXPECT_EQ(*parsed, kind);
    }
    const auto bad = sampleMapFromName("velvet");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().find("hammered"), std::string::npos);
}

} // namespace
} // namespace burnish
