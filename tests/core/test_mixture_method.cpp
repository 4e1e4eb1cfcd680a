// The lobe mixture as a method: its bake (textures, K = 1 as LEAN, flat maps, extremes, odd sizes,
// threads), the filtering its premultiplied moments are made for, evaluate's rows per K, and the
// mixture preset with its --lobes rule.
#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/eval/evaluate.h>
#include <burnish/core/io/image.h>
#include <burnish/core/jobs/bake_job.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/methods.h>

#include "normal_map_of.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Imath/half.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <utility>

using namespace burnish;
namespace fs = std::filesystem;

namespace {

using test::mapOf;

// Normals tilted one way on black squares and the other on white (a two-cluster footprint).
NormalMap checker(int size, float tilt) {
    return mapOf(size, size, [tilt](int x, int y) {
        return ((x + y) % 2) ? glm::vec3(tilt, 0.0f, 1.0f) : glm::vec3(-tilt, 0.3f * tilt, 1.0f);
    });
}

BakeOutput bakeMixture(const NormalMap& map, int lobes, double s = 256.0) {
    BakeOptions o;
    o.method = Method::Mixture;
    o.basePower = s;
    o.params.mixtureLobes = lobes;
    auto out = bake(map, o);
    EXPECT_TRUE(out) << out.error();
    return std::move(out).value();
}

// A stored texel's channels decoded (value = stored·scale + bias).
std::vector<double> decoded(const BakedTexture& t, int mip, size_t texel) {
    std::vector<double> v;
    for (int c = 0; c < t.channels; ++c)
        v.push_back(double(t.mips[size_t(mip)].texels[texel * size_t(t.channels) + size_t(c)]) *
                        t.decode[size_t(c)].scale +
                    t.decode[size_t(c)].bias);
    return v;
}

// The mixture a shader reads from stored (filtered) values: per lobe (w, w·b, w·M) back as LobeMoments.
LobeMixture storedMixture(const BakeOutput& out, int lobes, int mip, size_t texel) {
    const auto w = decoded(*out.find(TextureRole::MixtureWeights), mip, texel);
    const auto cross = decoded(*out.find(TextureRole::MixtureCross), mip, texel);
    LobeMixture m;
    for (int i = 0; i < lobes; ++i) {
        const auto l = decoded(*out.find(TextureRole(int(TextureRole::MixtureLobe0) + i)), mip, texel);
        LobeMoments lm;
        lm.w = w[size_t(i)];
        lm.bx = l[0], lm.by = l[1], lm.mxx = l[2], lm.myy = l[3], lm.mxy = cross[size_t(i)];
        if (lm.w > 0.0) m.lobes[size_t(m.count++)] = lm;
    }
    return m;
}

bool finiteUnit(const BakeOutput& out) {
    for (const auto& t : out.textures)
        for (const auto& mip : t.mips)
            for (float v : mip.texels)
                if (!(v >= 0.0f && v <= 1.0f)) return false;
    return true;
}

} // namespace

TEST(MixtureMethod, BakesKLobeTexturesBesideTheWeightsAndCrossMoments) {
    const NormalMap map = checker(32, 0.4f);
    for (int k = 1; k <= kMaxMixtureLobes; ++k) {
        const BakeOutput out = bakeMixture(map, k);
        int lobeTextures = 0;
        for (const auto& t : out.textures)
            lobeTextures += isMixtureLobeRole(t.role) ? 1 : 0;
        EXPECT_EQ(lobeTextures, k);
        EXPECT_TRUE(out.find(TextureRole::MixtureWeights));
        EXPECT_TRUE(out.find(TextureRole::MixtureCross));
        EXPECT_EQ(out.find(TextureRole::MixtureWeights)->mips.size(), 6u);
        EXPECT_TRUE(finiteUnit(out));
        EXPECT_EQ(methodStorage(Method::Mixture, {100.0, k}).textureFetches, k + 2);
        // The weights of every texel of every level sum to 1.
        const auto& weights = *out.find(TextureRole::MixtureWeights);
        for (size_t mip = 0; mip < weights.mips.size(); ++mip)
            for (size_t t = 0; t < weights.mips[mip].texels.size() / 4; ++t) {
                const auto w = decoded(weights, int(mip), t);
                EXPECT_NEAR(w[0] + w[1] + w[2] + w[3], 1.0, 1e-6) << "k " << k << " mip " << mip;
            }
    }
}

TEST(MixtureMethod, OneLobeStoresLeansMoments) {
    auto loaded = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png");
    ASSERT_TRUE(loaded) << loaded.error();
    BakeOptions lean;
    lean.method = Method::Lean;
    lean.basePower = 300.0;
    auto leanOut = bake(*loaded, lean);
    ASSERT_TRUE(leanOut);
    const BakeOutput mix = bakeMixture(*loaded, 1, 300.0);
    const auto& b = *leanOut->find(TextureRole::LeanB);
    const auto& m = *leanOut->find(TextureRole::LeanM);
    const auto& lobe = *mix.find(TextureRole::MixtureLobe0);
    const auto& cross = *mix.find(TextureRole::MixtureCross);
    const auto& weights = *mix.find(TextureRole::MixtureWeights);
    ASSERT_EQ(lobe.mips.size(), b.mips.size());
    for (size_t k = 0; k < b.mips.size(); ++k)
        for (size_t t = 0; t < b.mips[k].texels.size() / 2; ++t) {
            // The same stored bits: B, M.xx, M.yy and M.xy at the same scales, weight 1.
            ASSERT_EQ(lobe.mips[k].texels[4 * t], b.mips[k].texels[2 * t]) << "mip " << k;
            ASSERT_EQ(lobe.mips[k].texels[4 * t + 1], b.mips[k].texels[2 * t + 1]);
            ASSERT_EQ(lobe.mips[k].texels[4 * t + 2], m.mips[k].texels[3 * t]);
            ASSERT_EQ(lobe.mips[k].texels[4 * t + 3], m.mips[k].texels[3 * t + 1]);
            ASSERT_EQ(cross.mips[k].texels[4 * t], m.mips[k].texels[3 * t + 2]);
            ASSERT_EQ(weights.mips[k].texels[4 * t], 1.0f);
        }
    EXPECT_EQ(lobe.decode[0].scale, b.decode[0].scale);
    EXPECT_EQ(lobe.decode[2].scale, m.decode[0].scale);
}

TEST(MixtureMethod, FlatMapStoresTheBasePowerForEveryK) {
    const NormalMap flat = mapOf(16, 16, [](int, int) { return glm::vec3(0.0f, 0.0f, 1.0f); });
    for (const double s : {1.0, 256.0, 1e6})
        for (int k = 1; k <= kMaxMixtureLobes; ++k) {
            const BakeOutput out = bakeMixture(flat, k, s);
            for (int mip = 0; mip < 5; ++mip) {
                const LobeMixture m = storedMixture(out, k, mip, 0);
                ASSERT_GE(m.count, 1);
                // K = 1 stores LEAN's variance 1/s, two or more lobes 1/(s + 2).
                const double v = k == 1 ? 1.0 / s : 1.0 / (s + 2.0);
                for (int i = 0; i < m.count; ++i) {
                    const auto c = m.lobes[size_t(i)].covariance(1e-300);
                    // Float storage of v · 1/sM: a float's rounding of the power.
                    EXPECT_NEAR(c[0] / v, 1.0, 1e-6) << "s " << s << " k " << k << " mip " << mip;
                    EXPECT_NEAR(c[1] / v, 1.0, 1e-6);
                    EXPECT_NEAR(c[2] / v, 0.0, 1e-6);
                    EXPECT_NEAR(m.lobes[size_t(i)].mean().x, 0.0, 1e-6);
                }
            }
        }
}

TEST(MixtureMethod, FlatMapStoresTheBasePowerIn8BitAndHalfFloat) {
    // What an 8-bit or half-float file keeps of a flat map's stored values: the power comes back
    // within the storage's step (1/255 of the moment scale for 8 bits, 2^-11 relative for half).
    const NormalMap flat = mapOf(8, 8, [](int, int) { return glm::vec3(0.0f, 0.0f, 1.0f); });
    const double s = 16.0;
    const BakeOutput out = bakeMixture(flat, 3, s);
    const auto& lobe = *out.find(TextureRole::MixtureLobe0);
    const float stored = lobe.mips[0].texels[2];
    const double scale = lobe.decode[2].scale;
    const double eight = std::round(double(stored) * 255.0) / 255.0 * scale;
    const double v = 1.0 / (s + 2.0); // three lobes' base variance
    EXPECT_NEAR(eight / v, 1.0, scale / v / 255.0);
    // Half keeps 11 significant bits of the stored value.
    const double asHalf = double(float(Imath::half(stored))) * scale;
    EXPECT_NEAR(asHalf / v, 1.0, 1.0 / 1024.0);
}

TEST(MixtureMethod, SteepOutliersNanTexelsAndOddSizesStayFinite) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {3, 5}, {17, 6}, {64, 64}}) {
        NormalMap map = mapOf(w, h, [&](int x, int y) {
            if ((x * 7 + y * 3) % 11 == 0) return glm::vec3(1.0f, 0.0f, 1e-7f); // near the horizon
            return glm::vec3(u(rng), u(rng), 0.2f + std::abs(u(rng)));
        });
        map.normals[0] = glm::vec3(std::numeric_limits<float>::quiet_NaN(), 0.0f, 1.0f);
        for (int k = 1; k <= kMaxMixtureLobes; ++k)
            for (const double s : {1.0, 1e6}) {
                const BakeOutput out = bakeMixture(map, k, s);
                EXPECT_TRUE(finiteUnit(out)) << w << "x" << h << " k " << k << " s " << s;
                const auto& weights = *out.find(TextureRole::MixtureWeights);
                EXPECT_EQ(weights.mips.back().width, 1);
                EXPECT_EQ(weights.mips.back().height, 1);
            }
    }
}

TEST(MixtureMethod, SameBitsOnOneThreadAndOnAll) {
    auto loaded = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png");
    ASSERT_TRUE(loaded);
    const BakeOutput all = bakeMixture(*loaded, 3);
    BakeOutput one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = bakeMixture(*loaded, 3);
    }
    ASSERT_EQ(all.textures.size(), one.textures.size());
    for (size_t t = 0; t < all.textures.size(); ++t)
        for (size_t k = 0; k < all.textures[t].mips.size(); ++k)
            EXPECT_TRUE(all.textures[t].mips[k].texels == one.textures[t].mips[k].texels)
                << roleName(all.textures[t].role) << " mip " << k;
}

TEST(MixtureMethod, FilteringBetweenTexelsOfDifferentLobesKeepsEnergyAndStaysFinite) {
    // Bilinear filtering halfway between a two-lobe texel and a one-lobe texel (and every other
    // pair of a level) averages their stored values: the result decodes to a valid mixture whose
    // weights sum to 1 and whose NDF keeps its projected-area integral.
    NormalMap map = mapOf(64, 64, [](int x, int y) {
        if (x < 32) return ((x + y) % 2) ? glm::vec3(0.5f, 0.0f, 1.0f) : glm::vec3(-0.5f, 0.0f, 1.0f);
        return glm::vec3(0.0f, 0.2f, 1.0f);
    });
    const BakeOutput out = bakeMixture(map, 3, 128.0);
    const int mip = 2; // 16×16: the two halves meet between x = 7 and 8
    const int width = 16;
    auto lerp = [&](size_t a, size_t b) {
        BakeOutput mixed = out;
        for (auto& t : mixed.textures)
            if (t.mips.size() > size_t(mip))
                for (int c = 0; c < t.channels; ++c) {
                    auto& v = t.mips[size_t(mip)].texels;
                    v[a * size_t(t.channels) + size_t(c)] = 0.5f * (v[a * size_t(t.channels) + size_t(c)] +
                                                                    v[b * size_t(t.channels) + size_t(c)]);
                }
        return storedMixture(mixed, 3, mip, a);
    };
    const LobeMixture left = storedMixture(out, 3, mip, 7), right = storedMixture(out, 3, mip, 8);
    EXPECT_GE(left.count, 2);
    EXPECT_EQ(right.count, 1);
    const LobeMixture between = lerp(7, 8);
    EXPECT_NEAR(between.totalWeight(), 1.0, 1e-6);
    // ∫ D(h) (n·h) dω over the hemisphere, by a midpoint rule on (θ, φ).
    auto integral = [](const LobeMixture& m) {
        double sum = 0.0;
        const int nt = 400, np = 200;
        for (int i = 0; i < nt; ++i)
            for (int j = 0; j < np; ++j) {
                const double t = (i + 0.5) * (kPi<double> / 2) / nt, p = (j + 0.5) * 2 * kPi<double> / np;
                const glm::dvec3 h(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
                sum += mixtureNdf(m, h, 1.0 / 128.0) * h.z * std::sin(t) * (kPi<double> / 2 / nt) *
                       (2 * kPi<double> / np);
            }
        return sum;
    };
    EXPECT_NEAR(integral(between), 0.5 * (integral(left) + integral(right)), 1e-3);
    EXPECT_GT(integral(between), 0.9);
    for (int y = 0; y < width; ++y)
        for (int x = 0; x + 1 < width; ++x) {
            const LobeMixture m = lerp(size_t(y * width + x), size_t(y * width + x + 1));
            const glm::dvec3 h = glm::normalize(glm::dvec3(0.1, -0.05, 1.0));
            ASSERT_TRUE(std::isfinite(mixtureNdf(m, h, 1.0 / 128.0)));
        }
}

TEST(MixtureMethod, EvaluateReportsEveryKAndOneLobeIsLean) {
    auto loaded = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png");
    ASSERT_TRUE(loaded);
    EvaluateOptions o;
    o.basePowers = {256.0};
    o.methods = {Method::Lean, Method::Mixture};
    o.mixtureLobes = {1, 2, 3, 4};
    o.lastMip = 3;
    auto r = evaluateMethods(*loaded, o);
    ASSERT_TRUE(r) << r.error();
    ASSERT_EQ(r->errors.size(), 5u * 3u);
    auto find = [&](Method m, int lobes, int mip) {
        for (const auto& e : r->errors)
            if (e.method == m && e.lobes == lobes && e.mip == mip) return e;
        ADD_FAILURE() << "no row";
        return MipError{};
    };
    for (int mip = 1; mip <= 3; ++mip) {
        const MipError lean = find(Method::Lean, 0, mip), one = find(Method::Mixture, 1, mip);
        EXPECT_EQ(lean.relativeL1, one.relativeL1);
        EXPECT_EQ(lean.energyRatio, one.energyRatio);
        // More lobes, less error; from three lobes at most half of LEAN's where footprints hold
        // several clusters (mips 2 and up on this map); energy within 3 %.
        double previous = lean.relativeL1;
        for (int k = 2; k <= 4; ++k) {
            const MipError e = find(Method::Mixture, k, mip);
            EXPECT_LT(e.relativeL1, previous) << "k " << k << " mip " << mip;
            if (k >= 3 && mip >= 2) {
                EXPECT_LT(e.relativeL1, 0.5 * lean.relativeL1) << "k " << k << " mip " << mip;
            }
            EXPECT_NEAR(e.energyRatio, 1.0, 0.03);
            previous = e.relativeL1;
        }
    }
    EXPECT_EQ(variantLabel({Method::Mixture, FilterKernel::Box, 3}), "mixture-k3");
    // The mixture fits box footprints: no tent rows.
    o.kernels = {FilterKernel::Tent};
    o.methods = {Method::Mixture};
    EXPECT_FALSE(evaluateMethods(*loaded, o));
}

TEST(MixtureMethod, PresetStoresThreeLobesAndLobesRewritesItsLobeFiles) {
    const fs::path dir = fs::temp_directory_path() / ("burnish-mixture-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    BakeJobSpec spec;
    spec.input = std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png";
    spec.out = (dir / "set").string();
    spec.preset = "mixture";
    auto job = resolveBakeJob(spec);
    ASSERT_TRUE(job) << job.error();
    EXPECT_EQ(job->method, Method::Mixture);
    EXPECT_EQ(job->bake.params.mixtureLobes, 3);
    auto result = runBakeJob(*job);
    ASSERT_TRUE(result) << result.error();
    for (const char* name :
         {"mixture-weights", "mixture-lobe0", "mixture-lobe1", "mixture-lobe2", "mixture-cross"}) {
        const fs::path file = dir / "set" / (std::string("trak-rust1_nm_") + name + ".exr");
        ASSERT_TRUE(fs::exists(file)) << file;
        auto image = readImage(file);
        ASSERT_TRUE(image) << image.error();
        EXPECT_EQ(image->channels, 4);
    }
    // --lobes K rewrites the preset's lobe files to mixture-lobe0..K−1, where lobe files stood.
    for (int k : {1, 2, 4}) {
        spec.lobes = k;
        spec.out = (dir / ("k" + std::to_string(k))).string();
        auto other = resolveBakeJob(spec);
        ASSERT_TRUE(other) << other.error();
        EXPECT_EQ(other->bake.params.mixtureLobes, k);
        std::vector<std::string> names;
        for (const auto& f : other->preset.files)
            names.push_back(f.name);
        std::vector<std::string> want{"mixture-weights"};
        for (int i = 0; i < k; ++i)
            want.push_back("mixture-lobe" + std::to_string(i));
        want.push_back("mixture-cross");
        EXPECT_EQ(names, want) << "k " << k;
        ASSERT_TRUE(runBakeJob(*other)) << "k " << k;
        for (int i = 0; i < kMaxMixtureLobes; ++i)
            EXPECT_EQ(
                fs::exists(fs::path(spec.out) / ("trak-rust1_nm_mixture-lobe" + std::to_string(i) + ".exr")),
                i < k)
                << "k " << k << ", lobe " << i;
    }
    // A preset whose lobe files are laid out otherwise (here lobe 1's file renamed) must store K lobes.
    {
        std::ifstream in(std::string(BURNISH_SOURCE_DIR) + "/resources/presets/mixture.json");
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const std::string from = "\"name\": \"mixture-lobe1\"";
        const size_t at = text.find(from);
        ASSERT_NE(at, std::string::npos);
        text.replace(at, from.size(), "\"name\": \"second-lobe\"");
        fs::create_directories(dir);
        const fs::path custom = dir / "custom.json";
        std::ofstream(custom) << text;
        spec.preset = custom.string();
        spec.lobes = 3;
        ASSERT_TRUE(resolveBakeJob(spec)) << "its own count";
        spec.lobes = 4;
        auto four = resolveBakeJob(spec);
        ASSERT_FALSE(four);
        EXPECT_NE(four.error().find("stores 3 mixture lobes"), std::string::npos) << four.error();
    }
    spec.preset = "lean";
    spec.lobes = 2;
    auto notMixture = resolveBakeJob(spec);
    ASSERT_FALSE(notMixture);
    EXPECT_NE(notMixture.error().find("--method mixture only"), std::string::npos) << notMixture.error();
    // LEAN's preset fits neither the mixture nor the mixture's preset LEAN.
    EXPECT_FALSE(checkPresetMethod(*findPreset("lean"), Method::Mixture));
    EXPECT_FALSE(checkPresetMethod(*findPreset("mixture"), Method::Lean));
    fs::remove_all(dir);
}

namespace {

// The method's value for pair d at the corner shared by four texels of level `mip`: (x, y), (x+1, y),
// (x, y+1), (x+1, y+1), wrapping.
using CornerValue =
    std::function<double(int mip, const std::array<glm::ivec2, 4>& texels, const DirectionPair& d)>;

// Evaluate's between-texel rows of mips 1..2 of `r` (one method) against a brute-force sum: at each
// corner the truth is ¼ of each of the four footprints' mean at base power 64, the method's value
// `value`.
void expectBetweenTexelsBruteForce(const NormalPyramid& pyramid, const EvaluationResult& r,
                                   const CornerValue& value) {
    for (int mip = 1; mip <= 2; ++mip) {
        const PyramidLevel& level = pyramid.level(mip);
        double abs = 0.0, truthSum = 0.0, valueSum = 0.0;
        for (const DirectionPair& d : r.directions)
            for (int y = 0; y < level.height; ++y)
                for (int x = 0; x < level.width; ++x) {
                    std::array<glm::ivec2, 4> texels;
                    double truth = 0.0;
                    for (int c = 0; c < 4; ++c) {
                        texels[size_t(c)] = {(x + (c & 1)) % level.width, (y + (c >> 1)) % level.height};
                        truth += 0.25 * groundTruthTexel(pyramid, mip, texels[size_t(c)].x,
                                                         texels[size_t(c)].y, 64.0, d);
                    }
                    const double v = value(mip, texels, d);
                    abs += std::abs(v - truth);
                    truthSum += truth;
                    valueSum += v;
                }
        bool found = false;
        for (const MipError& e : r.errors)
            if (e.betweenTexels && e.mip == mip) {
                found = true;
                EXPECT_NEAR(e.relativeL1, abs / truthSum, 1e-9 * abs / truthSum) << "mip " << mip;
                EXPECT_NEAR(e.energyRatio, valueSum / truthSum, 1e-9) << "mip " << mip;
            }
        EXPECT_TRUE(found);
    }
}

} // namespace

TEST(MixtureMethod, BetweenTexelsAgreesWithABruteForceSumOnATinyMap) {
    // At each texel's corner the truth is ¼ of each of the four footprints' mean, the method's value
    // its lobe from the averaged moments (LEAN) or the averaged stored lobes (the mixture).
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-0.6f, 0.6f);
    const NormalMap map = mapOf(8, 8, [&](int, int) { return glm::vec3(u(rng), u(rng), 1.0f); });
    EvaluateOptions o;
    o.basePowers = {64.0};
    o.methods = {Method::Lean};
    o.firstMip = 1;
    o.lastMip = 2;
    o.betweenTexels = true;
    auto r = evaluateMethods(map, o);
    ASSERT_TRUE(r) << r.error();
    const auto shared = std::make_shared<NormalMap>(map);
    const NormalPyramid pyramid = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Box});
    // LEAN's lobe from the four texels' averaged moments.
    expectBetweenTexelsBruteForce(
        pyramid, *r, [&](int mip, const std::array<glm::ivec2, 4>& texels, const DirectionPair& d) {
            std::array<NormalMoments, 4> moments;
            for (size_t c = 0; c < 4; ++c)
                moments[c] = pyramid.boxMoments(mip, texels[c].x, texels[c].y);
            return methodValue(methodLobeBetween(Method::Lean, moments, {64.0, 64.0, 64.0, 64.0}, {}), d);
        });
    // The mixture between texels: finite, and K = 1 equal to LEAN there too.
    o.methods = {Method::Lean, Method::Mixture};
    o.mixtureLobes = {1, 3};
    auto m = evaluateMethods(map, o);
    ASSERT_TRUE(m) << m.error();
    for (int mip = 1; mip <= 2; ++mip) {
        double lean = -1, one = -2;
        for (const MipError& e : m->errors) {
            if (!e.betweenTexels || e.mip != mip) continue;
            EXPECT_TRUE(std::isfinite(e.relativeL1));
            EXPECT_TRUE(std::isfinite(e.energyRatio) && e.energyRatio > 0.0);
            if (e.method == Method::Lean) lean = e.relativeL1;
            if (e.method == Method::Mixture && e.lobes == 1) one = e.relativeL1;
        }
        EXPECT_EQ(lean, one) << "mip " << mip;
    }
}

namespace {

// Between texels of test map `name` at base power s and mip `mip`, the K = 3 mixture's relative L1 must
// stay under `limit` times LEAN's (both printed).
void expectBetweenTexelsUnder(const std::string& name, double s, int mip, double limit) {
    auto map = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/" + name);
    ASSERT_TRUE(map) << map.error();
    EvaluateOptions o;
    o.basePowers = {s};
    o.methods = {Method::Lean, Method::Mixture};
    o.mixtureLobes = {3};
    o.firstMip = mip;
    o.lastMip = mip;
    o.betweenTexels = true;
    auto r = evaluateMethods(*map, o);
    ASSERT_TRUE(r) << r.error();
    double lean = -1.0, mixture = -1.0;
    for (const MipError& e : r->errors)
        if (e.betweenTexels) (e.method == Method::Lean ? lean : mixture) = e.relativeL1;
    ASSERT_GT(lean, 0.0);
    ASSERT_GE(mixture, 0.0);
    std::printf("[measured] %s s = %g mip %d between texels: relative L1 LEAN %.4f, mixture K=3 %.4f "
                "(%.3f of LEAN)\n",
                name.c_str(), s, mip, lean, mixture, mixture / lean);
    EXPECT_LT(mixture, limit * lean) << name << " s " << s << " mip " << mip;
}

} // namespace

TEST(MixtureMethod, BetweenTexelsSlotsFollowTheLevelAboveAsFiltered) {
    // Rendering samples between texels, where bilinear filtering merges the lobes of one slot of four
    // texels. On a diamond tread plate, whose diamonds straddle the texels of every level, slots
    // chosen against the level above as filtered at each texel's centre (not its one parent) keep one
    // cluster in one slot across parents: the mixture's error between texels at s = 256 is then
    // under 0.43 of LEAN's at mip 2 and 0.31 at mip 3 (measured 0.366 and 0.264; against the one
    // parent 0.494 and 0.366).
    expectBetweenTexelsUnder("trak-treadplate1_nm.png", 256.0, 2, 0.43);
    expectBetweenTexelsUnder("trak-treadplate1_nm.png", 256.0, 3, 0.31);
}

TEST(MixtureMethod, BetweenTexelsSlotsExplainWholeChildLobes) {
    // A child lobe takes the slot whose lobe explains it best as a whole, its spread too (expected
    // log-likelihood), not only its mean: a broad lobe then shares its slot with broad neighbours instead
    // of smearing a narrow cluster whose mean it happens to sit on. Between texels at mip 4 the mixture
    // (K = 3) errs 0.307 of LEAN's on the tread plate at s = 64 and 0.358 on rust at s = 1024; scored
    // by the mean alone 0.352 and 0.399.
    expectBetweenTexelsUnder("trak-treadplate1_nm.png", 64.0, 4, 0.33);
    expectBetweenTexelsUnder("trak-rust1_nm.png", 1024.0, 4, 0.38);
}

TEST(MixtureMethod, DdsExportIsHalfFloatWithTheWholeChain) {
    // The mixture preset's DDS files are RGBA16F with a DX10 header (nvtt 2.0 writes neither): every
    // level, each stored value as a half, so the moments keep 11 bits of mantissa.
    const fs::path dir = fs::temp_directory_path() / ("burnish-mixture-dds-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    BakeJobSpec spec;
    spec.input = std::string(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png";
    spec.out = dir.string();
    spec.preset = "mixture";
    spec.format = "dds";
    auto job = resolveBakeJob(spec);
    ASSERT_TRUE(job) << job.error();
    ASSERT_TRUE(runBakeJob(*job));
    auto loaded = loadNormalMap(spec.input);
    ASSERT_TRUE(loaded);
    const BakeOutput baked = bakeMixture(*loaded, 3, job->bake.basePower);
    const BakedTexture& lobe = *baked.find(TextureRole::MixtureLobe1);
    std::ifstream in(dir / "trak-rust1_nm_mixture-lobe1.dds", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto u32 = [&](size_t at) {
        return std::uint32_t(std::uint8_t(bytes[at])) | std::uint32_t(std::uint8_t(bytes[at + 1])) << 8 |
               std::uint32_t(std::uint8_t(bytes[at + 2])) << 16 |
               std::uint32_t(std::uint8_t(bytes[at + 3])) << 24;
    };
    ASSERT_GT(bytes.size(), 148u);
    EXPECT_EQ(bytes.substr(0, 4), "DDS ");
    EXPECT_EQ(bytes.substr(84, 4), "DX10");
    EXPECT_EQ(u32(128), 10u); // DXGI_FORMAT_R16G16B16A16_FLOAT
    EXPECT_EQ(u32(16), std::uint32_t(loaded->width));
    EXPECT_EQ(u32(12), std::uint32_t(loaded->height));
    EXPECT_EQ(u32(28), std::uint32_t(lobe.mips.size()));
    size_t texels = 0;
    for (const auto& m : lobe.mips)
        texels += size_t(m.width) * size_t(m.height);
    EXPECT_EQ(bytes.size(), 148u + texels * 8u);
    // Mip 0 decodes to the bake's values within half precision.
    double worst = 0.0;
    for (size_t i = 0; i < lobe.mips[0].texels.size(); ++i) {
        Imath::half h;
        h.setBits(std::uint16_t(std::uint8_t(bytes[148 + 2 * i]) | std::uint8_t(bytes[149 + 2 * i]) << 8));
        worst = std::max(worst, std::abs(double(float(h)) - double(lobe.mips[0].texels[i])));
    }
    EXPECT_LT(worst, 1.0 / 2048.0);
    fs::remove_all(dir);
}

TEST(MixtureMethod, StochasticFilteringBetweenTexelsIsTheMeanOfTheFourTexelsShading) {
    // Filtering after shading (MixtureFiltering::Stochastic): at each corner the method's value is ¼ of
    // each of the four texels' own mixture values, summed by brute force here; the truth as above.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.7f, 0.7f);
    const NormalMap map = mapOf(8, 8, [&](int, int) { return glm::vec3(u(rng), u(rng), 1.0f); });
    EvaluateOptions o;
    o.basePowers = {64.0};
    o.methods = {Method::Mixture};
    o.mixtureLobes = {3};
    o.firstMip = 1;
    o.lastMip = 2;
    o.betweenTexels = true;
    o.mixtureFiltering = MixtureFiltering::Stochastic;
    auto r = evaluateMethods(map, o);
    ASSERT_TRUE(r) << r.error();
    const auto shared = std::make_shared<NormalMap>(map);
    const NormalPyramid pyramid = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Box});
    const MixturePyramid mixture = MixturePyramid::build(pyramid, 64.0, 3);
    expectBetweenTexelsBruteForce(
        pyramid, *r, [&](int mip, const std::array<glm::ivec2, 4>& texels, const DirectionPair& d) {
            double value = 0.0;
            for (const glm::ivec2& t : texels) {
                LobeMixture own;
                for (const LobeMoments& l : mixture.storedTexel(map, mip, t.x, t.y, 64.0))
                    if (l.w > 0.0) own.lobes[size_t(own.count++)] = l;
                value += 0.25 * mixtureValue(own, d.l, d.h, mixture.minVariance());
            }
            return value;
        });
}

TEST(MixtureMethod, StochasticFilteringBeatsMomentFilteringBetweenTexelsOnARealMap) {
    // The tread plate's bevels: slot-wise merging of the stored moments blurs them between texels;
    // shading each texel and averaging does not (K = 3, s = 256, mip 3; figures printed).
    auto map = loadNormalMap(std::string(BURNISH_TEST_DATA_DIR) + "/trak-treadplate1_nm.png");
    ASSERT_TRUE(map) << map.error();
    EvaluateOptions o;
    o.basePowers = {256.0};
    o.methods = {Method::Mixture};
    o.mixtureLobes = {3};
    o.firstMip = 3;
    o.lastMip = 3;
    o.betweenTexels = true;
    double aligned = -1.0;
    std::array<double, 2> between{-1.0, -1.0};
    for (const MixtureFiltering f : {MixtureFiltering::Moments, MixtureFiltering::Stochastic}) {
        o.mixtureFiltering = f;
        auto r = evaluateMethods(*map, o);
        ASSERT_TRUE(r) << r.error();
        for (const MipError& e : r->errors) {
            if (!e.betweenTexels)
                aligned = e.relativeL1;
            else
                between[size_t(f)] = e.relativeL1;
        }
    }
    std::printf(
        "[measured] trak-treadplate1 s = 256 mip 3, K = 3: aligned %.4f, between texels moments %.4f, "
        "stochastic %.4f\n",
        aligned, between[0], between[1]);
    ASSERT_GT(aligned, 0.0);
    EXPECT_LT(between[1], 0.6 * between[0]);
    EXPECT_LT(between[1], 1.5 * aligned);
}

TEST(MixtureMethod, StochasticTexelPicksEachTexelWithItsFilterWeight) {
    // Every pick of a fine grid of xi, counted: each texel of the trilinear footprint comes up with
    // its weight (bilinear weights in each of the two levels around lod, times the level's weight),
    // to the grid's resolution.
    constexpr int kGrid = 40;
    const glm::ivec2 size0(16, 8);
    const int levels = 5; // 16x8, 8x4, 4x2, 2x1, 1x1
    struct Case {
        glm::vec2 uv;
        float lod;
    };
    for (const Case& c : {Case{{0.3f, 0.55f}, 1.3f}, Case{{0.01f, 0.99f}, 0.6f}, Case{{-2.7f, 5.2f}, 2.5f},
                          Case{{0.5f, 0.5f}, -1.0f}, Case{{0.2f, 0.8f}, 9.0f}}) {
        std::map<std::array<int, 3>, double> expected, counted;
        const float l = std::clamp(c.lod, 0.0f, float(levels - 1));
        const int lower = int(std::floor(l));
        const double upper = l - float(lower);
        for (int level = lower; level <= std::min(lower + 1, levels - 1); ++level) {
            const double wl = level == lower ? 1.0 - upper : upper;
            const glm::ivec2 size = glm::max(glm::ivec2(size0.x >> level, size0.y >> level), glm::ivec2(1));
            const double px = (c.uv.x - std::floor(c.uv.x)) * size.x - 0.5,
                         py = (c.uv.y - std::floor(c.uv.y)) * size.y - 0.5;
            const double bx = std::floor(px), by = std::floor(py), fx = px - bx, fy = py - by;
            for (int j = 0; j < 2; ++j)
                for (int i = 0; i < 2; ++i) {
                    const int x = ((int(bx) + i) % size.x + size.x) % size.x;
                    const int y = ((int(by) + j) % size.y + size.y) % size.y;
                    expected[{x, y, level}] += wl * (i ? fx : 1.0 - fx) * (j ? fy : 1.0 - fy);
                }
        }
        for (int a = 0; a < kGrid; ++a)
            for (int b = 0; b < kGrid; ++b)
                for (int e = 0; e < kGrid; ++e) {
                    const glm::vec3 xi((float(a) + 0.5f) / kGrid, (float(b) + 0.5f) / kGrid,
                                       (float(e) + 0.5f) / kGrid);
                    const StochasticTexel t = stochasticTexel(c.uv, c.lod, size0, levels, xi);
                    counted[{t.x, t.y, t.level}] += 1.0 / (kGrid * kGrid * kGrid);
                }
        for (const auto& [texel, p] : counted)
            EXPECT_TRUE(expected.count(texel)) << "picked a texel outside the footprint: " << texel[0] << ", "
                                               << texel[1] << ", level " << texel[2];
        for (const auto& [texel, w] : expected)
            EXPECT_NEAR(counted[texel], w, 3.0 / kGrid)
                << "uv " << c.uv.x << ", " << c.uv.y << " lod " << c.lod << " texel " << texel[0] << ", "
                << texel[1] << ", level " << texel[2];
    }
    // A 1x1 texture, a NaN level of detail and non-finite uv pick a texel inside the texture.
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const StochasticTexel one = stochasticTexel({0.7f, 0.2f}, 3.0f, {1, 1}, 1, {0.9f, 0.9f, 0.9f});
    EXPECT_EQ(one.x, 0);
    EXPECT_EQ(one.y, 0);
    EXPECT_EQ(one.level, 0);
    const StochasticTexel odd = stochasticTexel({nan, inf}, nan, {5, 3}, 3, {0.5f, 0.5f, 0.5f});
    EXPECT_GE(odd.x, 0);
    EXPECT_LT(odd.x, 5);
    EXPECT_GE(odd.y, 0);
    EXPECT_LT(odd.y, 3);
    EXPECT_EQ(odd.level, 0);
}

TEST(MixtureMethod, StochasticNumbersAreUniformAndDifferPerPixelAndSample) {
    double sum = 0.0, sumSquares = 0.0;
    int n = 0;
    std::set<std::array<float, 3>> seen;
    for (unsigned y = 0; y < 32; ++y)
        for (unsigned x = 0; x < 32; ++x)
            for (unsigned s = 0; s < 4; ++s) {
                const glm::vec3 xi = stochasticNumbers({x, y, s});
                for (int i = 0; i < 3; ++i) {
                    ASSERT_GE(xi[i], 0.0f);
                    ASSERT_LT(xi[i], 1.0f);
                    sum += xi[i];
                    sumSquares += double(xi[i]) * xi[i];
                    ++n;
                }
                seen.insert({xi.x, xi.y, xi.z});
            }
    EXPECT_EQ(seen.size(), size_t(32 * 32 * 4)); // no two pixels or samples alike
    EXPECT_NEAR(sum / n, 0.5, 0.01);
    EXPECT_NEAR(sumSquares / n - (sum / n) * (sum / n), 1.0 / 12.0, 0.005); // a uniform's variance
    EXPECT_EQ(stochasticNumbers({3u, 4u, 5u}), stochasticNumbers({3u, 4u, 5u}));
}

TEST(MixtureMethod, MixtureFilteringNamesRoundTrip) {
    for (const MixtureFiltering f : {MixtureFiltering::Moments, MixtureFiltering::Stochastic})
        EXPECT_EQ(parseMixtureFiltering(mixtureFilteringName(f)), f);
    EXPECT_FALSE(parseMixtureFiltering("bilinear"));
}
