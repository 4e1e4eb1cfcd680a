#include <burnish/core/bake/detail.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace burnish;

namespace {

// Float vector arithmetic in reorientedBlend: unit length and agreement to a few float ulps.
constexpr float kVectorTolerance = 1e-6f;

double channel(const BakedTexture& t, int mip, int x, int y, int c) {
    const auto& m = t.mips[size_t(mip)];
    return m.texels[(size_t(y) * size_t(m.width) + size_t(x)) * 4 + size_t(c)] * t.decode[size_t(c)].scale +
           t.decode[size_t(c)].bias;
}

NormalMap bumpy(int size, float sigma, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0.0f, sigma);
    std::vector<glm::vec3> n(static_cast<size_t>(size) * static_cast<size_t>(size));
    for (auto& v : n)
        v = glm::normalize(glm::vec3(g(rng), g(rng), 1.0f));
    return makeNormalMap(size, size, n);
}

} // namespace

TEST(Detail, ReorientedBlendIdentities) {
    const glm::vec3 flat(0, 0, 1);
    const glm::vec3 b = glm::normalize(glm::vec3(0.3f, -0.2f, 1.0f));
    const glm::vec3 d = glm::normalize(glm::vec3(-0.1f, 0.4f, 1.0f));
    const glm::vec3 bd = reorientedBlend(b, flat);
    const glm::vec3 fd = reorientedBlend(flat, d);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(bd[i], b[i], kVectorTolerance); // a flat detail keeps the base
        EXPECT_NEAR(fd[i], d[i], kVectorTolerance); // a flat base gives the detail
    }
    const glm::vec3 r = reorientedBlend(b, d);
    EXPECT_NEAR(glm::length(r), 1.0f, kVectorTolerance);
    // RNM rotates the detail by the rotation taking +z to the base: the angle between the result
    // and the base equals the detail's angle from +z.
    EXPECT_NEAR(glm::dot(r, b), d.z, 1e-5f);
    // A base below the horizon has no frame: no NaN.
    const glm::vec3 down = reorientedBlend(glm::vec3(0, 0, -1), d);
    EXPECT_TRUE(std::isfinite(down.x) && std::isfinite(down.y) && std::isfinite(down.z));
}

TEST(Detail, VarianceAddsAsInversePower) {
    EXPECT_NEAR(addVarianceToPower(100.0, 0.0), 100.0, 1e-9);
    EXPECT_NEAR(addVarianceToPower(100.0, 0.01), 1.0 / (0.01 + 0.01), 1e-9);
    EXPECT_NEAR(addVarianceToPower(1e6, 0.5), 1.0 / (1e-6 + 0.5), 1e-9);
    EXPECT_TRUE(std::isfinite(addVarianceToPower(0.0, 0.0)));
    EXPECT_TRUE(std::isfinite(addVarianceToPower(1e9, std::numeric_limits<double>::quiet_NaN())));
    EXPECT_LE(addVarianceToPower(1e9, 0.0), kMaxPower);
}

TEST(Detail, BakedVarianceFadesToTheConstantAndNormalsToFlat) {
    const NormalMap map = bumpy(64, 0.2f, 3);
    DetailOptions options;
    options.fadeStartMip = 2;
    options.fadeEndMip = 4;
    options.pyramid.kernel = FilterKernel::Box; // mip 0 is then the map itself
    auto out = bakeDetail(map, options);
    ASSERT_TRUE(out.ok()) << out.error();
    const BakedTexture& t = out->texture;
    EXPECT_EQ(t.mips.size(), 7u);
    EXPECT_GT(out->constantVariance, 0.02); // slopes of σ = 0.2 per axis: σ² ≈ 0.04 per axis
    // Mip 0 keeps the detail's own normal.
    const glm::vec3 n0 = map.at(5, 5);
    EXPECT_NEAR(channel(t, 0, 5, 5, 0), n0.x, 1e-6);
    EXPECT_NEAR(channel(t, 0, 5, 5, 3), 0.0, 1e-6); // one normal: no spread
    // From the fade end on: flat normal, constant variance (within 8-bit-free float storage).
    for (int k = 4; k < 7; ++k) {
        EXPECT_NEAR(channel(t, k, 0, 0, 0), 0.0, 1e-6);
        EXPECT_NEAR(channel(t, k, 0, 0, 1), 0.0, 1e-6);
        EXPECT_NEAR(channel(t, k, 0, 0, 3), out->constantVariance, 1e-6 * t.decode[3].scale);
    }
    // Mid-fade (mip 3): halfway between the map's own normal/variance and flat/the constant.
    const auto pyramid = NormalPyramid::build(std::make_shared<const NormalMap>(map), options.pyramid);
    const NormalMoments m3 = pyramid.boxMoments(3, 2, 1);
    EXPECT_NEAR(channel(t, 3, 2, 1, 0), 0.5 * m3.meanDirection().x, 1e-6);
    EXPECT_NEAR(channel(t, 3, 2, 1, 3), 0.5 * toksvigVariance(m3.lengthNa()) + 0.5 * out->constantVariance,
                1e-6 * t.decode[3].scale);
}

TEST(Detail, FlatDetailAddsNoVariance) {
    const NormalMap flat = makeNormalMap(8, 8, std::vector<glm::vec3>(64, glm::vec3(0, 0, 1)));
    auto out = bakeDetail(flat);
    ASSERT_TRUE(out.ok());
    EXPECT_EQ(out->constantVariance, 0.0);
    for (const auto& mip : out->texture.mips)
        for (size_t i = 3; i < mip.texels.size(); i += 4)
            EXPECT_EQ(mip.texels[i], 0.0f);
}

TEST(Detail, RejectsBadFadeRange) {
    const NormalMap flat = makeNormalMap(4, 4, std::vector<glm::vec3>(16, glm::vec3(0, 0, 1)));
    DetailOptions options;
    options.fadeStartMip = 5;
    options.fadeEndMip = 2;
    EXPECT_FALSE(bakeDetail(flat, options).ok());
}

TEST(Detail, ShortChainIsAPrefixOfTheFullOne) {
    const NormalMap map = bumpy(32, 0.3f, 7);
    DetailOptions options;
    auto full = bakeDetail(map, options);
    options.mipCount = 3;
    auto part = bakeDetail(map, options);
    ASSERT_TRUE(full.ok() && part.ok());
    ASSERT_EQ(full->texture.mips.size(), 6u);
    ASSERT_EQ(part->texture.mips.size(), 3u);
    EXPECT_EQ(part->constantVariance, full->constantVariance);
    EXPECT_EQ(part->texture.decode[3].scale, full->texture.decode[3].scale); // same variance scale
    for (size_t k = 0; k < 3; ++k)
        EXPECT_EQ(part->texture.mips[k].texels, full->texture.mips[k].texels) << "mip " << k;
    // More levels than the chain holds: the whole chain.
    options.mipCount = 40;
    EXPECT_EQ(bakeDetail(map, options)->texture.mips.size(), 6u);
    options.mipCount = -1;
    EXPECT_FALSE(bakeDetail(map, options).ok());
}

TEST(Detail, ShapeHasTheBakesRolesChannelsAndSizes) {
    const NormalMap map = makeNormalMap(12, 5, std::vector<glm::vec3>(60, glm::vec3(0, 0, 1)));
    DetailOptions options;
    options.mipCount = 3;
    auto baked = bakeDetail(map, options);
    auto shape = detailShape(12, 5, options);
    ASSERT_TRUE(baked.ok() && shape.ok());
    EXPECT_EQ(shape->role, baked->texture.role);
    EXPECT_EQ(shape->channels, baked->texture.channels);
    ASSERT_EQ(shape->decode.size(), baked->texture.decode.size());
    for (size_t c = 0; c < shape->decode.size(); ++c) {
        EXPECT_EQ(shape->decode[c].name, baked->texture.decode[c].name);
        EXPECT_EQ(shape->decode[c].scale, baked->texture.decode[c].scale);
        EXPECT_EQ(shape->decode[c].bias, baked->texture.decode[c].bias);
    }
    EXPECT_EQ(shape->description, baked->texture.description);
    EXPECT_EQ(shape->needsHighPrecision, baked->texture.needsHighPrecision);
    ASSERT_EQ(shape->mips.size(), baked->texture.mips.size()); // 12x5, 6x2, 3x1
    for (size_t k = 0; k < shape->mips.size(); ++k) {
        EXPECT_EQ(shape->mips[k].width, baked->texture.mips[k].width) << k;
        EXPECT_EQ(shape->mips[k].height, baked->texture.mips[k].height) << k;
        EXPECT_TRUE(shape->mips[k].texels.empty());
    }
    EXPECT_FALSE(detailShape(0, 4).ok());
    DetailOptions badFade;
    badFade.fadeStartMip = 5;
    badFade.fadeEndMip = 2;
    EXPECT_FALSE(detailShape(8, 8, badFade).ok()); // the options bakeDetail refuses
}
