#include <burnish/core/bake/bake.h>

#include <burnish/core/shading/ndf.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

using namespace burnish;

namespace {

NormalMap gaussianField(int size, double sigmaX, double sigmaY, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> gx(0.0, sigmaX), gy(0.0, sigmaY);
    std::vector<glm::vec3> n(static_cast<size_t>(size) * static_cast<size_t>(size));
    for (auto& v : n)
        v = glm::vec3(glm::normalize(glm::dvec3(gx(rng), gy(rng), 1.0)));
    return makeNormalMap(size, size, std::move(n));
}

double decode(const BakedTexture& t, int mip, int x, int y, int c) {
    const auto& m = t.mips[size_t(mip)];
    const double stored =
        m.texels[(size_t(y) * size_t(m.width) + size_t(x)) * size_t(t.channels) + size_t(c)];
    return stored * t.decode[size_t(c)].scale + t.decode[size_t(c)].bias;
}

double meanGlossPower(const BakeOutput& out, const GlossEncoding& enc, int mip) {
    const BakedTexture* g = out.find(TextureRole::Gloss);
    double sum = 0;
    const auto& m = g->mips[size_t(mip)];
    for (float v : m.texels)
        sum += enc.power(v);
    return sum / double(m.texels.size());
}

// A gloss value stored as float in [0,1] and decoded through the encoding: the power comes back to
// float precision of the stored log-space value (1e-6 of 13·ln 2 ≈ 1e-5 relative).
constexpr double kGlossRoundTrip = 1e-4;

} // namespace

TEST(Bake, FlatMapGivesTheBasePowerBackAtEveryMip) {
    for (Method method : {Method::Naive, Method::Toksvig, Method::VarianceToGloss, Method::Vmf}) {
        BakeOptions options;
        options.method = method;
        options.basePower = 700.0;
        const NormalMap flat = makeNormalMap(16, 16, std::vector<glm::vec3>(256, glm::vec3(0, 0, 1)));
        auto out = bake(flat, options);
        ASSERT_TRUE(out.ok()) << out.error();
        EXPECT_EQ(out->stats.mipCount, 5);
        for (int k = 0; k < 5; ++k)
            EXPECT_NEAR(meanGlossPower(*out, options.encoding, k) / 700.0, 1.0, kGlossRoundTrip)
                << methodName(method) << " mip " << k;
    }
}

TEST(Bake, EightBitFlatMapBakesToTheBasePower) {
    // (128,128,255) decodes to one slightly tilted direction everywhere: no spread, no roughness.
    Image image;
    image.width = image.height = 8;
    image.channels = 3;
    for (int i = 0; i < 64; ++i)
        image.pixels.insert(image.pixels.end(), {128 / 255.f, 128 / 255.f, 1.0f});
    auto map = decodeNormalMap(image);
    ASSERT_TRUE(map.ok());
    BakeOptions options;
    options.basePower = 4096.0;
    auto out = bake(*map, options);
    ASSERT_TRUE(out.ok());
    for (int k = 0; k < out->stats.mipCount; ++k)
        EXPECT_NEAR(meanGlossPower(*out, options.encoding, k) / 4096.0, 1.0, kGlossRoundTrip);
}

TEST(Bake, GaussianSlopeFieldBakesItsVariance) {
    // Slopes with σ = 0.1 per axis: normals' projected variance ≈ 2σ² (for small σ). At the top
    // mip the footprint is the whole map, so variance-to-gloss must give 1/(v + 1/(s+1)) − 1 with
    // v the sample variance, and LEAN's M − BBᵀ must be σ² per axis (sample of 4096 → ±3%).
    const double sigma = 0.1;
    const NormalMap map = gaussianField(64, sigma, sigma, 3);
    BakeOptions options;
    options.pyramid.kernel = FilterKernel::Box;
    options.basePower = 1e4;
    options.method = Method::Lean;
    auto lean = bake(map, options);
    ASSERT_TRUE(lean.ok());
    const int top = lean->stats.mipCount - 1;
    const BakedTexture* M = lean->find(TextureRole::LeanM);
    const BakedTexture* B = lean->find(TextureRole::LeanB);
    ASSERT_TRUE(M && B);
    const double bx = decode(*B, top, 0, 0, 0), by = decode(*B, top, 0, 0, 1);
    const double varX = decode(*M, top, 0, 0, 0) - 1.0 / 1e4 - bx * bx;
    const double varY = decode(*M, top, 0, 0, 1) - 1.0 / 1e4 - by * by;
    constexpr double kSampleTolerance =
        0.06; // 4096 samples: relative std of a variance ≈ sqrt(2/4096) = 2.2%
    EXPECT_NEAR(varX / (sigma * sigma), 1.0, kSampleTolerance);
    EXPECT_NEAR(varY / (sigma * sigma), 1.0, kSampleTolerance);

    options.method = Method::VarianceToGloss;
    auto v2g = bake(map, options);
    ASSERT_TRUE(v2g.ok());
    const double p = meanGlossPower(*v2g, options.encoding, top);
    // v ≈ 2σ²/(1+σ²)-ish for slope σ; invert the method's formula to recover v.
    const double v = 1.0 / (p + 1.0) - 1.0 / (1e4 + 1.0);
    EXPECT_NEAR(v / (2 * sigma * sigma), 1.0, 0.08);
}

TEST(Bake, GroovedMapIsAnisotropicOnlyForLean) {
    // Grooves along y: normals tilt in x only (alternating ±0.3 slope by column).
    std::vector<glm::vec3> n;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            n.push_back(glm::normalize(glm::vec3((x % 2) ? 0.3f : -0.3f, 0.0f, 1.0f)));
    const NormalMap map = makeNormalMap(16, 16, n);
    BakeOptions options;
    options.basePower = 1e4;
    options.pyramid.kernel = FilterKernel::Box;
    options.method = Method::Lean;
    auto lean = bake(map, options);
    ASSERT_TRUE(lean.ok());
    const BakedTexture* M = lean->find(TextureRole::LeanM);
    const double mxx = decode(*M, 1, 0, 0, 0), myy = decode(*M, 1, 0, 0, 1);
    EXPECT_NEAR(mxx, 0.09 + 1e-4, 1e-3);
    EXPECT_NEAR(myy, 1e-4, 1e-4);
    const BakedTexture* compact = lean->find(TextureRole::LeanGloss);
    EXPECT_LT(decode(*compact, 1, 0, 0, 0), decode(*compact, 1, 0, 0, 1)); // rougher along x

    options.method = Method::Clean;
    auto clean = bake(map, options);
    ASSERT_TRUE(clean.ok());
    const double avg = decode(*clean->find(TextureRole::Clean), 1, 0, 0, 2);
    EXPECT_NEAR(avg, 0.5 * (0.09 + 2e-4), 1e-3); // one isotropic value: the mean of both axes
}

TEST(Bake, BimodalCheckerOfTwoTiltsRoughensAndKeepsTheMeanNormal) {
    std::vector<glm::vec3> n;
    const glm::vec3 a = glm::normalize(glm::vec3(0.4f, 0.1f, 1.0f)),
                    b = glm::normalize(glm::vec3(-0.4f, 0.1f, 1.0f));
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            n.push_back(((x + y) % 2) ? a : b);
    BakeOptions options;
    options.pyramid.kernel = FilterKernel::Box;
    options.basePower = 2048;
    auto out = bake(makeNormalMap(8, 8, n), options);
    ASSERT_TRUE(out.ok());
    const BakedTexture* normal = out->find(TextureRole::Normal);
    // Mean of the two tilts points along (0, 0.1, 1) renormalized.
    const glm::dvec3 expected = glm::normalize(glm::dvec3(a + b));
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(decode(*normal, 1, 0, 0, c), expected[c], 1e-6);
    EXPECT_LT(meanGlossPower(*out, options.encoding, 1), 20.0); // ±21.8° tilts: far rougher than 2048
    EXPECT_NEAR(meanGlossPower(*out, options.encoding, 0) / 2048.0, 1.0,
                kGlossRoundTrip); // box: mip 0 untouched
}

TEST(Bake, OddSizesNanTexelsAndTwoChannelMapsBake) {
    Image image;
    image.width = 3;
    image.height = 5;
    image.channels = 2;
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.35f, 0.65f);
    for (int i = 0; i < 15; ++i)
        image.pixels.insert(image.pixels.end(), {u(rng), u(rng)});
    image.pixels[4] = std::numeric_limits<float>::quiet_NaN();
    auto map = decodeNormalMap(image);
    ASSERT_TRUE(map.ok()) << map.error();
    EXPECT_EQ(map->diagnostics.nonFiniteTexels, 1u);
    for (Method m : allMethods()) {
        BakeOptions options;
        options.method = m;
        auto out = bake(*map, options);
        ASSERT_TRUE(out.ok()) << methodName(m) << ": " << out.error();
        EXPECT_EQ(out->stats.mipCount, 3); // 3×5 → 1×2 → 1×1
        for (const auto& t : out->textures)
            for (const auto& mip : t.mips)
                for (float v : mip.texels)
                    EXPECT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 1.0f) << roleName(t.role);
    }
}

TEST(Bake, AuthoredGlossIsAveragedAsVariance) {
    // Half the texels at power 8192, half at 8: the mip-1 base power is the harmonic mean
    // 1/((1/8192 + 1/8)/2) ≈ 15.98, not the gloss mean (which would give sqrt(8192·8) = 256).
    const NormalMap flat = makeNormalMap(2, 2, std::vector<glm::vec3>(4, glm::vec3(0, 0, 1)));
    BakeOptions options;
    options.method = Method::Naive;
    options.pyramid.kernel = FilterKernel::Box;
    const auto& enc = options.encoding;
    options.authoredGloss = std::vector<float>{float(enc.value(8192)), float(enc.value(8)),
                                               float(enc.value(8)), float(enc.value(8192))};
    auto out = bake(flat, options);
    ASSERT_TRUE(out.ok());
    EXPECT_NEAR(meanGlossPower(*out, enc, 1), 2.0 / (1.0 / 8192 + 1.0 / 8), 1e-2);

    options.authoredGloss = std::vector<float>{0.5f};
    EXPECT_FALSE(bake(flat, options).ok()); // wrong size
    options.authoredGloss = std::vector<float>(4, std::numeric_limits<float>::quiet_NaN());
    EXPECT_FALSE(bake(flat, options).ok());
}

TEST(Bake, IsDeterministic) {
    const NormalMap map = gaussianField(32, 0.2, 0.1, 8);
    for (Method m : allMethods()) {
        BakeOptions options;
        options.method = m;
        auto a = bake(map, options);
        auto b = bake(map, options);
        ASSERT_TRUE(a.ok() && b.ok());
        for (size_t t = 0; t < a->textures.size(); ++t)
            for (size_t k = 0; k < a->textures[t].mips.size(); ++k)
                EXPECT_EQ(a->textures[t].mips[k].texels, b->textures[t].mips[k].texels);
    }
}

// A bake limited to some roles (what an export's files read) produces exactly those textures,
// each equal bit for bit to the same texture of a full bake; the others are absent.
TEST(Bake, RoleSubsetsProduceTheSameTexturesAsAFullBake) {
    const NormalMap map = gaussianField(32, 0.2, 0.1, 9);
    for (Method m : allMethods()) {
        BakeOptions options;
        options.method = m;
        auto full = bake(map, options);
        ASSERT_TRUE(full.ok());
        for (const auto& kept : full->textures) {
            options.roles = std::vector<TextureRole>{kept.role};
            auto part = bake(map, options);
            ASSERT_TRUE(part.ok());
            ASSERT_EQ(part->textures.size(), 1u) << methodName(m) << " " << roleName(kept.role);
            const BakedTexture& t = part->textures[0];
            EXPECT_EQ(t.role, kept.role);
            ASSERT_EQ(t.mips.size(), kept.mips.size());
            for (size_t k = 0; k < t.mips.size(); ++k)
                EXPECT_EQ(t.mips[k].texels, kept.mips[k].texels)
                    << methodName(m) << " " << roleName(kept.role) << " mip " << k;
        }
        options.roles = std::vector<TextureRole>{};
        auto none = bake(map, options);
        ASSERT_TRUE(none.ok());
        EXPECT_TRUE(none->textures.empty());
    }
}

// BakeOptions::cachedPyramid: a bake from bakePyramid's pyramid (every moment, the levels above the
// cap released) is the bake that builds its own, bit for bit, for every method with and without an
// authored gloss map; it is read, never released, so a second bake from it is the same again; a
// pyramid of another map, or one missing a level the bake computes, is refused.
TEST(Bake, ACachedPyramidBakesTheSameAndIsRefusedWhereItCannotServe) {
    const auto map = std::make_shared<const NormalMap>(gaussianField(64, 0.3, 0.15, 9));
    std::vector<float> gloss(map->texelCount());
    for (size_t i = 0; i < gloss.size(); ++i)
        gloss[i] = float(i % 7) / 7.0f;
    BakeOptions capped;
    capped.largestLevel = 16;
    const auto pyramid = bakePyramid(map, capped);
    EXPECT_TRUE(pyramid->level(1).box.empty()) << "32² is above the cap: released";
    EXPECT_FALSE(pyramid->level(2).box.empty());
    for (const Method m : allMethods())
        for (const bool authored : {false, true}) {
            BakeOptions options = capped;
            options.method = m;
            options.params.mixtureLobes = 3;
            if (authored) options.authoredGloss = gloss;
            const auto own = bake(*map, options);
            ASSERT_TRUE(own) << own.error();
            options.cachedPyramid = pyramid;
            std::vector<double> seen;
            options.progress = [&seen](double f) {
                seen.push_back(f);
                return true;
            };
            for (int run = 0; run < 2; ++run) {
                const auto cached = bake(*map, options);
                ASSERT_TRUE(cached) << cached.error();
                ASSERT_EQ(cached->textures.size(), own->textures.size());
                for (size_t t = 0; t < own->textures.size(); ++t)
                    for (size_t k = 0; k < own->textures[t].mips.size(); ++k)
                        EXPECT_EQ(cached->textures[t].mips[k].texels, own->textures[t].mips[k].texels)
                            << methodName(m) << " level " << k << " run " << run;
            }
            // The kept pyramid cost these bakes nothing: the first report is 0, not the pyramid's share.
            ASSERT_FALSE(seen.empty());
            EXPECT_EQ(seen.front(), 0.0);
            EXPECT_EQ(seen.back(), 1.0);
        }
    BakeOptions uncapped;
    uncapped.cachedPyramid = pyramid;
    const auto missing = bake(*map, uncapped);
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().find("released level 1"), std::string::npos) << missing.error();
    const NormalMap other = gaussianField(64, 0.3, 0.15, 10);
    BakeOptions elsewhere = capped;
    elsewhere.cachedPyramid = pyramid;
    const auto wrongMap = bake(other, elsewhere);
    ASSERT_FALSE(wrongMap);
    EXPECT_NE(wrongMap.error().find("another normal map"), std::string::npos) << wrongMap.error();
}

// PyramidOptions::boxMoments = false: the levels' extents and footprints of a full pyramid with no
// box moments. A mixture of K >= 2 lobes baking its own roles reads none (its bake builds such a
// pyramid, and takes one given), and bakes the same bits as from a full pyramid; a bake that reads
// moments (K = 1 is LEAN's) refuses it.
TEST(Bake, AMixtureBakesFromAPyramidOfFootprintsAlone) {
    const auto map = std::make_shared<const NormalMap>(gaussianField(48, 0.3, 0.15, 4));
    PyramidOptions geometry;
    geometry.boxMoments = false;
    const auto bare = std::make_shared<const NormalPyramid>(NormalPyramid::build(map, geometry));
    const auto full = std::make_shared<const NormalPyramid>(NormalPyramid::build(map, PyramidOptions{}));
    ASSERT_EQ(bare->levelCount(), full->levelCount());
    for (int k = 1; k < full->levelCount(); ++k) {
        const PyramidLevel &a = bare->level(k), &b = full->level(k);
        EXPECT_EQ(a.width, b.width);
        EXPECT_EQ(a.height, b.height);
        EXPECT_EQ(a.xStart, b.xStart);
        EXPECT_EQ(a.yStart, b.yStart);
        EXPECT_EQ(a.xChild, b.xChild);
        EXPECT_EQ(a.yChild, b.yChild);
        EXPECT_TRUE(a.box.empty());
        EXPECT_FALSE(b.box.empty());
    }
    for (int lobes = 1; lobes <= kMaxMixtureLobes; ++lobes) {
        BakeOptions options;
        options.method = Method::Mixture;
        options.params.mixtureLobes = lobes;
        // The mixture preset's files: no normal texture (that one reads the moments).
        options.roles = {TextureRole::MixtureWeights, TextureRole::MixtureLobe0, TextureRole::MixtureLobe1,
                         TextureRole::MixtureLobe2,   TextureRole::MixtureLobe3, TextureRole::MixtureCross};
        const auto own = bake(*map, options);
        ASSERT_TRUE(own) << own.error();
        options.cachedPyramid = full;
        const auto fromFull = bake(*map, options);
        options.cachedPyramid = bare;
        const auto fromBare = bake(*map, options);
        ASSERT_TRUE(fromFull) << fromFull.error();
        if (lobes == 1) {
            ASSERT_FALSE(fromBare);
            EXPECT_NE(fromBare.error().find("lacks moments"), std::string::npos) << fromBare.error();
            continue;
        }
        ASSERT_TRUE(fromBare) << fromBare.error();
        ASSERT_EQ(own->textures.size(), size_t(lobes + 2));
        for (size_t t = 0; t < own->textures.size(); ++t)
            for (size_t k = 0; k < own->textures[t].mips.size(); ++k) {
                EXPECT_EQ(fromFull->textures[t].mips[k].texels, own->textures[t].mips[k].texels) << lobes;
                EXPECT_EQ(fromBare->textures[t].mips[k].texels, own->textures[t].mips[k].texels) << lobes;
            }
    }
    BakeOptions lean;
    lean.method = Method::Lean;
    lean.cachedPyramid = bare;
    EXPECT_FALSE(bake(*map, lean));
    // With its normal texture, a mixture reads the moments.
    BakeOptions withNormal;
    withNormal.method = Method::Mixture;
    withNormal.params.mixtureLobes = 3;
    withNormal.cachedPyramid = bare;
    EXPECT_FALSE(bake(*map, withNormal));
}

// BakeOptions::progress: called once the pyramids are built and after each level, with fractions
// that grow to 1 (levels skipped by largestLevel count for nothing); the bake it watches is the same
// as one without it; returning false stops the bake with "cancelled" at once.
TEST(Bake, ProgressGrowsToOneAndFalseCancels) {
    const NormalMap map = gaussianField(64, 0.3, 0.15, 9);
    for (const Method m : {Method::VarianceToGloss, Method::Mixture}) {
        for (const int largest : {0, 16}) {
            BakeOptions options;
            options.method = m;
            options.params.mixtureLobes = 3;
            options.largestLevel = largest;
            const auto plain = bake(map, options);
            ASSERT_TRUE(plain) << plain.error();
            std::vector<double> seen;
            options.progress = [&seen](double f) {
                seen.push_back(f);
                return true;
            };
            const auto watched = bake(map, options);
            ASSERT_TRUE(watched) << watched.error();
            // The pyramids, then 7 levels (64² to 1²).
            ASSERT_EQ(seen.size(), 8u) << methodName(m);
            EXPECT_GT(seen.front(), 0.0);
            EXPECT_EQ(seen.back(), 1.0);
            for (size_t i = 1; i < seen.size(); ++i)
                EXPECT_GE(seen[i], seen[i - 1]);
            // 64² + 32² skipped: the pyramids (4096 texels) over 4096 + 16² + 8² + … + 1 ≈ 0.92.
            if (largest == 16) {
                EXPECT_NEAR(seen.front(), 4096.0 / (4096.0 + 341.0), 1e-12);
            }
            for (size_t t = 0; t < plain->textures.size(); ++t)
                for (size_t k = 0; k < plain->textures[t].mips.size(); ++k)
                    EXPECT_EQ(watched->textures[t].mips[k].texels, plain->textures[t].mips[k].texels);

            int calls = 0;
            options.progress = [&calls](double) { return ++calls < 3; };
            const auto stopped = bake(map, options);
            ASSERT_FALSE(stopped);
            EXPECT_EQ(stopped.error(), "cancelled");
            EXPECT_EQ(calls, 3) << "stopped at the first false";
        }
    }
}

// A viewer that draws from the first level no larger than N has the larger levels skipped: they
// keep their size and no texels, and every level baked is the full bake's, bit for bit, for every
// method, the mixture and an authored gloss map included.
TEST(Bake, LevelsLargerThanTheLargestAreSkippedAndTheRestAreTheFullBakes) {
    const NormalMap map = gaussianField(64, 0.3, 0.15, 9);
    std::vector<float> gloss(map.texelCount());
    for (size_t i = 0; i < gloss.size(); ++i)
        gloss[i] = float(i % 7) / 7.0f;
    for (const Method m : allMethods())
        for (const bool authored : {false, true}) {
            BakeOptions options;
            options.method = m;
            if (authored) options.authoredGloss = gloss;
            const auto full = bake(map, options);
            ASSERT_TRUE(full) << full.error();
            options.largestLevel = 16;
            const auto capped = bake(map, options);
            ASSERT_TRUE(capped) << capped.error();
            ASSERT_EQ(capped->textures.size(), full->textures.size());
            for (size_t t = 0; t < full->textures.size(); ++t) {
                const BakedTexture& a = full->textures[t];
                const BakedTexture& b = capped->textures[t];
                ASSERT_EQ(a.mips.size(), b.mips.size());
                for (size_t k = 0; k < a.mips.size(); ++k) {
                    EXPECT_EQ(b.mips[k].width, a.mips[k].width);
                    EXPECT_EQ(b.mips[k].height, a.mips[k].height);
                    if (k < 2) { // 64 and 32 are larger than 16
                        EXPECT_TRUE(b.mips[k].texels.empty()) << methodName(m) << " level " << k;
                        continue;
                    }
                    EXPECT_EQ(b.mips[k].texels, a.mips[k].texels) << methodName(m) << " level " << k;
                }
            }
        }
    // Never the last level, whatever the limit.
    BakeOptions tiny;
    tiny.largestLevel = 1;
    tiny.mipCount = 3;
    const auto three = bake(map, tiny);
    ASSERT_TRUE(three) << three.error();
    EXPECT_FALSE(three->textures.front().mips.back().texels.empty());
    EXPECT_TRUE(three->textures.front().mips.front().texels.empty());
}

// The eight-lane half conversion the bake stores half textures with gives halfCode's bits: for
// every 61st float bit pattern of [0, 1] (normal, denormal and zero halves, ties included), every
// pattern around the denormal and zero thresholds, −0, values outside [0, 1], infinities and NaN.
TEST(Bake, HalfCodesAreHalfCodeBitForBit) {
    std::vector<float> values;
    auto addBits = [&](std::uint32_t b) {
        float f;
        std::memcpy(&f, &b, sizeof f);
        values.push_back(f);
    };
    for (std::uint32_t b = 0; b <= 0x3f800000u; b += 61)
        addBits(b);
    for (const std::uint32_t edge : {0x33000000u, 0x38800000u, 0x387fe000u, 0x3f7ff000u})
        for (std::uint32_t b = edge - 4096; b <= edge + 4096; ++b)
            addBits(b);
    for (const float f :
         {-0.0f, -1e-30f, -2.0f, 1.0f, 1.0000001f, 3.5f, 70000.0f, std::numeric_limits<float>::infinity(),
          -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()})
        values.push_back(f);
    // An odd count: the last values take the scalar tail.
    values.push_back(0.5f);
    // Both paths: the F16C conversion (where the CPU has it) and the portable lanes.
    for (const auto convert : {&halfCodes, &portableHalfCodes}) {
        std::vector<std::uint16_t> bits(values.size());
        convert(values.data(), values.size(), bits.data());
        size_t mismatches = 0;
        for (size_t i = 0; i < values.size(); ++i)
            if (bits[i] != halfCode(values[i]).bits()) {
                if (++mismatches <= 5)
                    ADD_FAILURE() << "value " << values[i] << ": " << bits[i] << " against "
                                  << halfCode(values[i]).bits();
            }
        EXPECT_EQ(mismatches, 0u) << (convert == &halfCodes ? "halfCodes" : "portableHalfCodes");
    }
    EXPECT_GT(values.size(), 17'000'000u);
}
