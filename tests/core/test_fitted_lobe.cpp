// The GGX specular term, evaluate's GGX truth and the fitted one-lobe roughness.
#include "random_normals.h"

#include <burnish/core/bake/bake.h>
#include <burnish/core/eval/evaluate.h>
#include <burnish/core/prefilter/fitted_lobe.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/shading/ggx_specular.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/visibility.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

using namespace burnish;

namespace {

// A map whose footprints mix a flat majority with a few steep normals: the case where one lobe widened
// by the variance flattens the core (grout, treads, bevels).
NormalMap flatWithSteepNormals(int size, double steepShare, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto flat = test::gaussianSlopes(size * size, 0.03, seed + 1);
    for (auto& n : flat)
        if (u(rng) < steepShare) {
            const double phi = 6.283185307179586 * u(rng), tilt = 0.6 + 0.4 * u(rng);
            n = glm::vec3(glm::normalize(
                glm::dvec3(std::sin(tilt) * std::cos(phi), std::sin(tilt) * std::sin(phi), std::cos(tilt))));
        }
    return makeNormalMap(size, size, std::move(flat));
}

double rowError(const EvaluationResult& r, Method m, int mip, bool floor = false) {
    for (const MipError& e : r.errors)
        if (e.method == m && e.mip == mip && e.floor == floor && !e.betweenTexels) return e.relativeL1;
    return -1.0;
}

} // namespace

TEST(GgxSpecular, IsTheNdfTimesTheVisibilityOverFourTimesTheCosine) {
    for (double alpha : {kMinRoughness, 0.01, 0.088, 0.3, 0.7, 1.0})
        for (double noh : {0.01, 0.5, 0.9, 0.999, 1.0})
            for (double nol : {1e-3, 0.2, 0.8, 1.0})
                for (double nov : {-0.3, 1e-3, 0.5, 1.0}) {
                    const double expected = ggxNdf(noh, alpha) *
                                            visibilitySmithGgxCorrelated(nol, nov, alpha) / 4.0 *
                                            saturate(nol);
                    EXPECT_NEAR(ggxSpecularTerm(noh, nol, nov, alpha), expected, 1e-12 * expected)
                        << alpha << " " << noh << " " << nol << " " << nov;
                }
}

TEST(GgxSpecular, FiniteAndZeroBehindForEveryInput) {
    const double nan = std::numeric_limits<double>::quiet_NaN(),
                 inf = std::numeric_limits<double>::infinity();
    for (double a : {nan, -1.0, 0.0, 1e-9, 0.5, 1.0, 5.0, inf})
        for (double c : {nan, -1.0, 0.0, 1e-7, 0.5, 1.0, 2.0, inf})
            for (double l : {nan, -0.5, 0.0, 1e-7, 1.0, inf})
                for (double v : {nan, -0.5, 0.0, 1.0, inf}) {
                    const double x = ggxSpecularTerm(c, l, v, a);
                    EXPECT_TRUE(std::isfinite(x) && x >= 0.0) << a << " " << c << " " << l << " " << v;
                    if (!(c > 0.0) || !(l > 0.0)) {
                        EXPECT_EQ(x, 0.0) << a << " " << c << " " << l << " " << v;
                    }
                    EXPECT_TRUE(std::isfinite(ggxSpecularTerm(float(c), float(l), float(v), float(a))));
                }
}

// The anisotropic term: the isotropic one when α_t = α_b in an orthonormal frame; swapping the axes and
// their roughnesses changes nothing; the highlight reaches further along the rougher axis; and its NDF,
// recovered by dividing out the visibility and the cosine at l = v = h, holds projected area 1 (∫ D n·h dω
// = 1, by a midpoint rule over the hemisphere) for a lobe 4× longer than wide.
TEST(GgxSpecular, AnisotropicTermIsTheIsotropicOneWhenRoundAndKeepsItsArea) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    auto unitAbove = [&] {
        glm::dvec3 x(u(rng), u(rng), std::abs(u(rng)) + 0.05);
        return glm::normalize(x);
    };
    for (int i = 0; i < 2000; ++i) {
        const glm::dvec3 n = unitAbove(), l = unitAbove(), v = unitAbove();
        // (Behind the normal the isotropic form clamps n·v inside its square root, the anisotropic one
        // only outside it, as the engines write them; they agree where n·v > 0.)
        if (glm::dot(n, v) <= 0.0) continue;
        const glm::dvec3 h = glm::normalize(l + v);
        glm::dvec3 t = glm::normalize(glm::cross(n, glm::dvec3(u(rng), u(rng), u(rng))));
        const glm::dvec3 b = glm::cross(n, t);
        const double alpha = std::exp(3.0 * u(rng) - 3.0), other = std::exp(3.0 * u(rng) - 3.0);
        auto term = [&](const glm::dvec3& T, const glm::dvec3& B, double at, double ab) {
            return ggxAnisotropicSpecularTerm(glm::dot(n, h), glm::dot(T, h), glm::dot(B, h), glm::dot(n, l),
                                              glm::dot(T, l), glm::dot(B, l), glm::dot(n, v), glm::dot(T, v),
                                              glm::dot(B, v), at, ab);
        };
        const double iso = ggxSpecularTerm(glm::dot(n, h), glm::dot(n, l), glm::dot(n, v), alpha);
        EXPECT_NEAR(term(t, b, alpha, alpha), iso, 1e-9 * iso + 1e-300) << i;
        EXPECT_NEAR(term(t, b, alpha, other), term(b, -t, other, alpha), 1e-12 * term(t, b, alpha, other))
            << i;
    }
    // Along the rougher axis the lobe reaches further: h tilted 10° towards t against towards b.
    const glm::dvec3 n(0, 0, 1), t(1, 0, 0), b(0, 1, 0);
    auto at = [&](const glm::dvec3& h, double aT, double aB) {
        return ggxAnisotropicSpecularTerm(h.z, h.x, h.y, h.z, h.x, h.y, h.z, h.x, h.y, aT, aB);
    };
    const double s10 = std::sin(0.1745), c10 = std::cos(0.1745);
    EXPECT_GT(at({s10, 0, c10}, 0.4, 0.1), 10.0 * at({0, s10, c10}, 0.4, 0.1));
    // ∫ D(h) n·h dω_h = 1 with D = term / (V·n·l) at l = v = h (where V = 1/(4 (n·h)² |(α_t t·h, α_b b·h,
    // n·h)|)).
    const double aT = 0.4, aB = 0.1;
    const int steps = 2000;
    double area = 0.0;
    for (int i = 0; i < steps; ++i) {
        const double theta = (i + 0.5) / steps * 0.5 * kPi<double>;
        for (int j = 0; j < steps; ++j) {
            const double phi = (j + 0.5) / steps * 2.0 * kPi<double>;
            const glm::dvec3 h(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                               std::cos(theta));
            const double g = std::sqrt(aT * aT * h.x * h.x + aB * aB * h.y * h.y + h.z * h.z);
            const double V = 0.5 / (2.0 * h.z * g);
            const double D = at(h, aT, aB) / (V * h.z);
            area += D * h.z * std::sin(theta) * (0.5 * kPi<double> / steps) * (2.0 * kPi<double> / steps);
        }
    }
    EXPECT_NEAR(area, 1.0, 2e-3);
}

TEST(GgxSpecular, AnisotropicTermIsFiniteForEveryInput) {
    const double nan = std::numeric_limits<double>::quiet_NaN(),
                 inf = std::numeric_limits<double>::infinity();
    const std::vector<double> dots{nan, -1.0, 0.0, 1e-7, 0.5, 1.0, inf};
    for (double a : {nan, 0.0, 0.3, 1.0, inf})
        for (double c : dots)
            for (double x : dots)
                for (double lv : dots) {
                    const double value = ggxAnisotropicSpecularTerm(c, x, x, lv, x, -x, lv, -x, x, a, 0.2);
                    EXPECT_TRUE(std::isfinite(value) && value >= 0.0)
                        << a << " " << c << " " << x << " " << lv;
                    if (!(c > 0.0) || !(lv > 0.0)) {
                        EXPECT_EQ(value, 0.0);
                    }
                    const float f =
                        ggxAnisotropicSpecularTerm(float(c), float(x), float(x), float(lv), float(x),
                                                   float(-x), float(lv), float(-x), float(x), float(a), 0.2f);
                    EXPECT_TRUE(std::isfinite(f) && f >= 0.0f);
                }
}

TEST(FittedLobe, NeverWorseThanTheBaseOrVmfAndTheFloorIsNoWorse) {
    // Random footprints' truths under the GGX truth, at evaluate's pairs.
    const auto dirs = directionPairs({});
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 200; ++trial) {
        const double s = std::pow(10.0, 1.0 + 5.0 * u(rng));
        const auto normals = test::gaussianSlopes(16, 0.02 + 0.5 * u(rng), unsigned(trial));
        glm::dvec3 mean(0.0);
        for (const auto& n : normals)
            mean += glm::dvec3(n);
        const glm::dvec3 nbar = glm::normalize(mean);
        std::vector<double> truth(dirs.size(), 0.0), noh, nol, nov;
        for (size_t d = 0; d < dirs.size(); ++d) {
            for (const auto& n : normals)
                truth[d] += isotropicLobeShading(Brdf::Ggx, glm::dot(glm::dvec3(n), dirs[d].h),
                                                 glm::dot(glm::dvec3(n), dirs[d].l),
                                                 glm::dot(glm::dvec3(n), dirs[d].v), s) /
                            double(normals.size());
            noh.push_back(glm::dot(nbar, dirs[d].h));
            nol.push_back(glm::dot(nbar, dirs[d].l));
            nov.push_back(glm::dot(nbar, dirs[d].v));
        }
        const double aBase = ggxAlphaFromPower(s);
        const double aVmf = ggxAlphaFromPower(1.0 / (1.0 / s + 1.0 / vmfKappa(glm::length(mean) / 16.0)));
        auto E = [&](double a) {
            return fitTexelError(Brdf::Ggx, truth.data(), noh.data(), nol.data(), nov.data(), dirs.size(), a);
        };
        const double fit = fitTexelAlpha(Brdf::Ggx, truth.data(), noh.data(), nol.data(), nov.data(),
                                         dirs.size(), aBase, aVmf, false);
        const double floor = fitTexelAlpha(Brdf::Ggx, truth.data(), noh.data(), nol.data(), nov.data(),
                                           dirs.size(), aBase, aVmf, true);
        ASSERT_TRUE(std::isfinite(fit) && fit > 0.0 && fit <= 1.0) << fit << " " << aBase << " " << aVmf;
        // The fit compares in eight-lane sums: the same figure as E's plain sum to rounding.
        const double slack = 1e-12 * E(aBase);
        EXPECT_LE(E(fit), E(aBase) + slack) << trial;
        EXPECT_LE(E(fit), E(aVmf) + slack) << trial;
        EXPECT_LE(E(floor), E(fit) * 1.02 + slack) << trial; // the dense search finds at least as good
    }
}

TEST(FittedLobe, FlatMapKeepsTheBasePowerAndTheFitIsTheSameOnAnyThreadCount) {
    const NormalMap flat = makeNormalMap(16, 16, std::vector<glm::vec3>(256, glm::vec3(0.0f, 0.0f, 1.0f)));
    const auto pyramid =
        NormalPyramid::build(std::shared_ptr<const NormalMap>(&flat, [](const NormalMap*) {}));
    const FittedPyramid f =
        FittedPyramid::build(pyramid, [](int, int, int) { return 256.0; }, nullptr, 256.0, -1, {});
    for (int k = 1; k < f.levelCount(); ++k)
        EXPECT_NEAR(f.power(k, 0, 0), 256.0, 1e-3) << k;

    const NormalMap map = flatWithSteepNormals(64, 0.08, 3);
    const auto shared = std::shared_ptr<const NormalMap>(&map, [](const NormalMap*) {});
    const auto p = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Tent});
    auto fitAll = [&] {
        return FittedPyramid::build(p, [](int, int, int) { return 256.0; }, nullptr, 256.0, -1, {});
    };
    const FittedPyramid many = fitAll();
    std::optional<FittedPyramid> one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one.emplace(fitAll());
    }
    for (int k = 1; k < many.levelCount(); ++k)
        for (int y = 0; y < p.level(k).height; ++y)
            for (int x = 0; x < p.level(k).width; ++x) {
                ASSERT_EQ(many.power(k, x, y), one->power(k, x, y)) << k << " " << x << " " << y;
                ASSERT_TRUE(std::isfinite(many.power(k, x, y)) && many.power(k, x, y) > 0.0);
            }
}

TEST(FittedLobe, BeatsNaiveAndVmfWhereAFewSteepNormalsCarryTheVarianceAndSitsOnTheFloor) {
    const NormalMap map = flatWithSteepNormals(128, 0.05, 5);
    EvaluateOptions options;
    options.brdf = Brdf::Ggx;
    options.methods = {Method::Naive, Method::Vmf, Method::Fitted};
    options.basePowers = {256.0};
    options.lastMip = 6;
    options.floor = true;
    auto result = evaluateMethods(map, options);
    ASSERT_TRUE(result.ok()) << result.error();
    for (int mip = 1; mip <= 6; ++mip) {
        const double fitted = rowError(*result, Method::Fitted, mip),
                     floor = rowError(*result, Method::Fitted, mip, true);
        EXPECT_LE(fitted, rowError(*result, Method::Naive, mip) + 1e-12) << mip;
        EXPECT_LE(fitted, rowError(*result, Method::Vmf, mip) + 1e-12) << mip;
        EXPECT_LE(fitted, 1.02 * floor) << mip;
        EXPECT_GT(floor, 0.0);
    }
    // Where the footprint holds many steep normals, vMF widens the one lobe past the flat core.
    EXPECT_LT(rowError(*result, Method::Fitted, 6), 0.75 * rowError(*result, Method::Vmf, 6));
}

TEST(FittedLobe, GgxRefusesTheSlopeSpaceMethodsAndTheEnergySplit) {
    const NormalMap map = flatWithSteepNormals(16, 0.1, 2);
    EvaluateOptions options;
    options.brdf = Brdf::Ggx;
    options.methods = {Method::Naive, Method::Lean};
    auto r = evaluateMethods(map, options);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().find("no GGX form"), std::string::npos) << r.error();
    options.methods = {Method::Naive};
    options.energySplit = true;
    EXPECT_FALSE(evaluateMethods(map, options).ok());
}

TEST(FittedLobe, BakeStoresTheFitAboveMipZeroAndTheBasePowerAtIt) {
    const NormalMap map = flatWithSteepNormals(32, 0.1, 9);
    BakeOptions options;
    options.method = Method::Fitted;
    options.encoding = GlossEncoding::ggxRoughness();
    options.basePower = 256.0;
    options.pyramid = {BorderMode::Wrap, FilterKernel::Box};
    auto baked = bake(map, options);
    ASSERT_TRUE(baked.ok()) << baked.error();
    const BakedTexture* gloss = baked->find(TextureRole::Gloss);
    ASSERT_NE(gloss, nullptr);
    const auto shared = std::shared_ptr<const NormalMap>(&map, [](const NormalMap*) {});
    const NormalPyramid pyramid = NormalPyramid::build(shared, options.pyramid);
    FittedLobeOptions fit; // GGX: the encoding's engine
    const FittedPyramid fitted = FittedPyramid::build(
        pyramid, [](int, int, int) { return 256.0; }, nullptr, 256.0, -1, fit);
    const float base = float(options.encoding.value(256.0));
    EXPECT_NEAR(gloss->mips[0].texels[0], base, 1e-6);
    int differ = 0;
    for (int k = 1; k < int(gloss->mips.size()); ++k) {
        const TextureMip& mip = gloss->mips[size_t(k)];
        for (int y = 0; y < mip.height; ++y)
            for (int x = 0; x < mip.width; ++x) {
                const float stored = mip.texels[size_t(y) * size_t(mip.width) + size_t(x)];
                EXPECT_NEAR(stored, float(options.encoding.value(fitted.power(k, x, y))), 1e-6) << k;
                differ += std::abs(stored - base) > 1e-3f;
            }
    }
    EXPECT_GT(differ, 0); // the fit moved some texels off the base roughness
}

// The truth's finest normals: as texels they are truthValues of each texel's own normal; as the bilinear
// interpolant they agree with evaluate's brute-force definition (groundTruthTexel: the interpolant at
// 2×2 points per texel, computed from the sample's position) for every texel and pair, both border modes,
// on maps that are not powers of two, 1×1 and with normals at the horizon; a constant map is the same
// either way.
TEST(TruthNormals, TexelsAreTheTexelsAndBilinearIsTheInterpolantAtTwoByTwoPoints) {
    for (const auto& [w, h] : {std::pair{5, 3}, std::pair{1, 1}, std::pair{7, 1}}) {
        std::vector<glm::vec3> normals = test::gaussianSlopes(w * h, 0.5, unsigned(w * 10 + h));
        normals[0] = glm::normalize(glm::vec3(1.0f, 0.0f, 0.001f)); // at the horizon
        const NormalMap map = makeNormalMap(w, h, normals);
        const auto shared = std::shared_ptr<const NormalMap>(&map, [](const NormalMap*) {});
        for (const BorderMode border : {BorderMode::Wrap, BorderMode::Clamp}) {
            const NormalPyramid pyramid = NormalPyramid::build(shared, {border, FilterKernel::Box});
            for (const Brdf brdf : {Brdf::Ggx, Brdf::BlinnPhong})
                for (const TruthNormals how : {TruthNormals::Texels, TruthNormals::Bilinear}) {
                    TruthBand band(map, 0, h, how, border);
                    ASSERT_EQ(band.size(), size_t(w * h));
                    std::vector<double> values(band.size());
                    for (const DirectionPair& d : directionPairs({})) {
                        band.values(brdf, nullptr, 256.0, d, values.data());
                        for (int y = 0; y < h; ++y)
                            for (int x = 0; x < w; ++x) {
                                const double v = values[size_t(y * w + x)];
                                const double ref = groundTruthTexel(pyramid, 0, x, y, 256.0, d, brdf, how);
                                ASSERT_TRUE(std::isfinite(v));
                                EXPECT_NEAR(v, ref, 1e-12 * (1.0 + ref))
                                    << w << "x" << h << " " << truthNormalsName(how) << " " << brdfName(brdf)
                                    << " texel " << x << "," << y;
                            }
                    }
                }
        }
    }
    // A constant map: every sub-sample is the texel's normal (renormalized in double: the float normal's
    // length is 1 to 6e-8, which moves a power-512 lobe by up to 3e-5).
    const NormalMap flat =
        makeNormalMap(4, 4, std::vector<glm::vec3>(16, glm::normalize(glm::vec3(0.2f, -0.1f, 1.0f))));
    TruthBand texels(flat, 0, 4, TruthNormals::Texels, BorderMode::Wrap);
    TruthBand bilinear(flat, 0, 4, TruthNormals::Bilinear, BorderMode::Wrap);
    std::vector<double> a(16), b(16);
    for (const DirectionPair& d : directionPairs({})) {
        texels.values(Brdf::Ggx, nullptr, 512.0, d, a.data());
        bilinear.values(Brdf::Ggx, nullptr, 512.0, d, b.data());
        for (size_t i = 0; i < 16; ++i)
            EXPECT_NEAR(a[i], b[i], 1e-4 * a[i] + 1e-12);
    }
}

// What the bilinear truth is for: texel-scale noise is narrower on the interpolant an engine draws than
// on the texels, so the fit to it is sharper (here by a clear margin on every mip) and, judged by that
// truth, closer than the fit to the facets.
TEST(TruthNormals, TheFitToTheInterpolantIsSharperOnTexelNoiseAndBetterByItsTruth) {
    const NormalMap map = makeNormalMap(64, 64, test::gaussianSlopes(64 * 64, 0.05, 11));
    const auto shared = std::shared_ptr<const NormalMap>(&map, [](const NormalMap*) {});
    const NormalPyramid pyramid = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Box});
    const double s = 256.0;
    FittedLobeOptions texels, bilinear;
    texels.truthNormals = TruthNormals::Texels;
    bilinear.truthNormals = TruthNormals::Bilinear;
    EXPECT_EQ(FittedLobeOptions{}.truthNormals, std::nullopt);
    EXPECT_EQ(defaultTruthNormals(Brdf::Ggx), TruthNormals::Bilinear);
    EXPECT_EQ(defaultTruthNormals(Brdf::BlinnPhong), TruthNormals::Texels);
    auto base = [s](int, int, int) { return s; };
    const FittedPyramid onTexels = FittedPyramid::build(pyramid, base, nullptr, s, 4, texels);
    const FittedPyramid onBilinear = FittedPyramid::build(pyramid, base, nullptr, s, 4, bilinear);
    for (int k = 1; k <= 4; ++k) {
        double sumT = 0.0, sumB = 0.0;
        const PyramidLevel& level = pyramid.level(k);
        for (int y = 0; y < level.height; ++y)
            for (int x = 0; x < level.width; ++x)
                sumT += ggxAlphaFromPower(onTexels.power(k, x, y)),
                    sumB += ggxAlphaFromPower(onBilinear.power(k, x, y));
        EXPECT_LT(sumB, 0.9 * sumT) << "mip " << k;
    }
    EvaluateOptions options;
    options.brdf = Brdf::Ggx;
    options.methods = {Method::Naive, Method::Fitted};
    options.basePowers = {s};
    options.firstMip = 1;
    options.lastMip = 4;
    for (const TruthNormals how : {TruthNormals::Texels, TruthNormals::Bilinear}) {
        options.truthNormals = how;
        const auto r = evaluateMethods(map, options);
        ASSERT_TRUE(r) << r.error();
        for (int k = 1; k <= 4; ++k)
            EXPECT_LT(rowError(*r, Method::Fitted, k), rowError(*r, Method::Naive, k))
                << truthNormalsName(how);
    }
}

TEST(TruthNormals, NamesRoundTripAndTheEnergySplitWantsTexels) {
    for (const TruthNormals t : {TruthNormals::Texels, TruthNormals::Bilinear}) {
        TruthNormals back{};
        ASSERT_TRUE(truthNormalsFromName(truthNormalsName(t), back));
        EXPECT_EQ(back, t);
    }
    TruthNormals unused{};
    EXPECT_FALSE(truthNormalsFromName("bicubic", unused));
    const NormalMap map = makeNormalMap(8, 8, test::gaussianSlopes(64, 0.2, 3));
    EvaluateOptions options;
    options.energySplit = true;
    options.truthNormals = TruthNormals::Bilinear;
    const auto r = evaluateMethods(map, options);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("--truth-normals texels"), std::string::npos) << r.error();
}

namespace {

// Stripes of normals tilted ±tilt about the axis at `angle` in the tangent plane (ridges across it), on a
// faint noise: every footprint spreads its normals along `angle` only.
NormalMap stripes(int size, double angle, double tilt) {
    auto noise = test::gaussianSlopes(size * size, 0.01, 3);
    std::vector<glm::vec3> normals(noise.size());
    const glm::dvec2 dir(std::cos(angle), std::sin(angle));
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double side = (x + y) % 2 == 0 ? 1.0 : -1.0; // alternates along both axes
            const glm::dvec3 n(side * std::sin(tilt) * dir.x, side * std::sin(tilt) * dir.y, std::cos(tilt));
            normals[size_t(y * size + x)] =
                glm::normalize(glm::vec3(n) + 0.3f * (noise[size_t(y * size + x)] - glm::vec3(0, 0, 1)));
        }
    return makeNormalMap(size, size, std::move(normals));
}

// The truth of texel (x, y) of level k for every pair, and the cosines of its mean normal.
struct TexelTruth {
    std::vector<double> truth, noh, nol, nov;
    glm::dvec3 n;
};
TexelTruth texelTruth(const NormalPyramid& pyramid, int k, int x, int y, double s,
                      const std::vector<DirectionPair>& dirs) {
    TexelTruth t;
    t.n = glm::dvec3(pyramid.moments(k, x, y).meanDirection());
    for (const DirectionPair& d : dirs) {
        t.truth.push_back(groundTruthTexel(pyramid, k, x, y, s, d, Brdf::Ggx));
        t.noh.push_back(glm::dot(t.n, d.h)), t.nol.push_back(glm::dot(t.n, d.l)),
            t.nov.push_back(glm::dot(t.n, d.v));
    }
    return t;
}

} // namespace

// The anisotropic fit (KHR_materials_anisotropy's pair): on footprints whose normals spread along one
// direction it finds that direction, a lobe longer along it than across, and a clearly smaller error than
// the isotropic fit; it is never worse than the round lobes it starts from, never sharper than the base,
// and stays round on a flat map.
TEST(FittedLobe, AnisotropicFitFindsTheDirectionOfTheSpreadAndIsNeverWorse) {
    const auto dirs = directionPairs({});
    const double s = 256.0, aBase = ggxAlphaFromPower(s);
    for (const double angle : {0.0, 0.5 * kPi<double>, 0.3}) {
        const NormalMap map = stripes(16, angle, 0.12);
        const auto shared = std::shared_ptr<const NormalMap>(&map, [](const NormalMap*) {});
        const NormalPyramid pyramid = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Box});
        FittedLobeOptions options;
        options.anisotropic = true;
        options.truthNormals = TruthNormals::Texels;
        const FittedPyramid fitted = FittedPyramid::build(
            pyramid, [s](int, int, int) { return s; }, nullptr, s, 3, options);
        ASSERT_TRUE(fitted.hasAnisotropic());
        for (int k = 1; k <= 3; ++k)
            for (int y = 0; y < pyramid.level(k).height; y += 3)
                for (int x = 0; x < pyramid.level(k).width; x += 3) {
                    const AnisotropicLobe a = fitted.anisotropic(k, x, y);
                    const double aIso = ggxAlphaFromPower(fitted.power(k, x, y));
                    const TexelTruth t = texelTruth(pyramid, k, x, y, s, dirs);
                    const double eIso = fitTexelError(Brdf::Ggx, t.truth.data(), t.noh.data(), t.nol.data(),
                                                      t.nov.data(), dirs.size(), aIso);
                    const double eAniso = anisotropicFitError(t.truth.data(), dirs, t.n, a);
                    // (0.84-0.87 of the isotropic fit's error here: two clusters are not one long lobe)
                    EXPECT_LT(eAniso, 0.9 * eIso)
                        << "angle " << angle << " mip " << k << ": " << eAniso / eIso;
                    EXPECT_GE(a.alphaB, aBase * (1 - 1e-9));
                    EXPECT_GT(a.alphaT, 1.5 * a.alphaB);
                    EXPECT_GT(a.strength(), 0.1);
                    // Along the spread (θ and θ + π are one lobe; at mip 1 four normals leave the error flat
                    // within about ±12°: 0.21 rad with clang, 0.10 with GCC).
                    const double off = std::abs(std::remainder(a.angle - angle, kPi<double>));
                    EXPECT_LT(off, 0.25) << "angle " << angle << " fitted " << a.angle << " mip " << k;
                    EXPECT_LT(std::abs(std::remainder(principalAngle(pyramid.moments(k, x, y)) - angle,
                                                      kPi<double>)),
                              0.1);
                }
    }
    // Random footprints: never worse than the isotropic lobe it starts from.
    std::mt19937 rng(3);
    for (int i = 0; i < 40; ++i) {
        const NormalMap map = makeNormalMap(4, 4, test::gaussianSlopes(16, 0.05 + 0.02 * i, unsigned(i)));
        const auto shared = std::shared_ptr<const NormalMap>(&map, [](const NormalMap*) {});
        const NormalPyramid pyramid = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Box});
        const TexelTruth t = texelTruth(pyramid, 2, 0, 0, s, dirs);
        const double aIso = fitTexelAlpha(Brdf::Ggx, t.truth.data(), t.noh.data(), t.nol.data(), t.nov.data(),
                                          dirs.size(), aBase, aBase, false);
        const AnisotropicLobe a = fitTexelAnisotropic(t.truth.data(), dirs, t.n, aBase, aIso,
                                                      principalAngle(pyramid.moments(2, 0, 0)));
        // Never worse than the round lobes it starts from (the same family: the engine's anisotropic path
        // forms t and b in the geometric tangent plane, so about a tilted normal even a round lobe is not
        // the isotropic term).
        const double e = anisotropicFitError(t.truth.data(), dirs, t.n, a);
        EXPECT_LE(e, anisotropicFitError(t.truth.data(), dirs, t.n, {aIso, aIso, 0.0}) * (1 + 1e-12));
        EXPECT_LE(e, anisotropicFitError(t.truth.data(), dirs, t.n, {aBase, aBase, 0.0}) * (1 + 1e-12));
        EXPECT_GE(a.alphaT, a.alphaB);
        EXPECT_TRUE(a.angle >= 0.0 && a.angle < kPi<double>);
    }
    // A flat map stays round at the base roughness.
    const NormalMap flat = makeNormalMap(8, 8, std::vector<glm::vec3>(64, glm::vec3(0, 0, 1)));
    const auto shared = std::shared_ptr<const NormalMap>(&flat, [](const NormalMap*) {});
    const NormalPyramid pyramid = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Box});
    FittedLobeOptions options;
    options.anisotropic = true;
    const FittedPyramid fitted = FittedPyramid::build(
        pyramid, [s](int, int, int) { return s; }, nullptr, s, 3, options);
    for (int k = 1; k <= 3; ++k) {
        const AnisotropicLobe a = fitted.anisotropic(k, 0, 0);
        EXPECT_NEAR(a.alphaT, aBase, 1e-6);
        EXPECT_NEAR(a.alphaB, aBase, 1e-6);
        EXPECT_EQ(a.strength(), 0.0);
    }
}

// evaluate's "fitted anisotropic" row is the anisotropic fit's lobes shaded by ggxAnisotropicSpecularTerm
// about each texel's mean normal in the geometric frame, against the same truth (a scalar recomputation
// here, to 1e-10), the round base lobe at mip 0; between texels the engine's filtered textures at each
// corner against the four footprints' mean truth (recomputed the same way); refused under Blinn-Phong.
TEST(FittedLobe, EvaluateRowsTheAnisotropicFitAsEnginesShadeIt) {
    const NormalMap map = stripes(16, 0.4, 0.15);
    EvaluateOptions options;
    options.brdf = Brdf::Ggx;
    options.truthNormals = TruthNormals::Texels;
    options.methods = {Method::Fitted};
    options.anisotropic = true;
    options.betweenTexels = true;
    options.basePowers = {256.0};
    options.firstMip = 0;
    options.lastMip = 3;
    const auto r = evaluateMethods(map, options);
    ASSERT_TRUE(r) << r.error();
    const auto shared = std::shared_ptr<const NormalMap>(&map, [](const NormalMap*) {});
    const NormalPyramid pyramid = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Box});
    FittedLobeOptions fit;
    fit.anisotropic = true;
    fit.truthNormals = TruthNormals::Texels;
    fit.directions = r->directions;
    const FittedPyramid fitted = FittedPyramid::build(
        pyramid, [](int, int, int) { return 256.0; }, nullptr, 256.0, 3, fit);
    int rows = 0;
    for (const MipError& e : r->errors) {
        if (!e.anisotropic) continue;
        EXPECT_EQ(variantLabel(variantOf(e)), "fitted anisotropic");
        EXPECT_TRUE(std::isfinite(e.relativeL1) && std::isfinite(e.energyRatio));
        ++rows;
        const PyramidLevel& level = pyramid.level(e.mip);
        const double a0 = ggxAlphaFromPower(256.0);
        auto lobeOf = [&](int x, int y) {
            return e.mip > 0 ? fitted.anisotropic(e.mip, x, y) : AnisotropicLobe{a0, a0, 0.0};
        };
        auto shade = [](const glm::dvec3& n, const AnisotropicLobe& a, const DirectionPair& d) {
            const glm::dvec3 t(std::cos(a.angle), std::sin(a.angle), 0.0), b(-t.y, t.x, 0.0);
            return ggxAnisotropicSpecularTerm(
                glm::dot(n, d.h), glm::dot(t, d.h), glm::dot(b, d.h), glm::dot(n, d.l), glm::dot(t, d.l),
                glm::dot(b, d.l), glm::dot(n, d.v), glm::dot(t, d.v), glm::dot(b, d.v), a.alphaT, a.alphaB);
        };
        double abs = 0.0, truth = 0.0;
        for (const DirectionPair& d : r->directions)
            for (int y = 0; y < level.height; ++y)
                for (int x = 0; x < level.width; ++x) {
                    glm::dvec3 n(pyramid.boxMoments(e.mip, x, y).meanDirection());
                    AnisotropicLobe a = lobeOf(x, y);
                    double gt = groundTruthTexel(pyramid, e.mip, x, y, 256.0, d, Brdf::Ggx);
                    if (e.betweenTexels) {
                        // The corner shared with the texels to the right and below (wrapping), the three
                        // textures filtered as the engine filters them: normals averaged and renormalized,
                        // r = √α_b averaged, directions averaged and normalized, strengths averaged.
                        glm::dvec3 sum(0.0);
                        glm::dvec2 dir(0.0);
                        double roughness = 0.0, k = 0.0;
                        gt = 0.0;
                        for (const auto& [dx, dy] : {std::pair{0, 0}, {1, 0}, {0, 1}, {1, 1}}) {
                            const int xi = (x + dx) % level.width, yi = (y + dy) % level.height;
                            const AnisotropicLobe c = lobeOf(xi, yi);
                            sum += glm::dvec3(pyramid.boxMoments(e.mip, xi, yi).meanDirection());
                            roughness += 0.25 * std::sqrt(c.alphaB), k += 0.25 * c.strength();
                            dir += glm::dvec2(std::cos(c.angle), std::sin(c.angle));
                            gt += 0.25 * groundTruthTexel(pyramid, e.mip, xi, yi, 256.0, d, Brdf::Ggx);
                        }
                        n = glm::normalize(sum);
                        const double alphaB = roughness * roughness;
                        a = {alphaB + (1.0 - alphaB) * k * k, alphaB, std::atan2(dir.y, dir.x)};
                    }
                    abs += std::abs(shade(n, a, d) - gt), truth += gt;
                }
        EXPECT_NEAR(e.relativeL1, abs / truth, 1e-10 * abs / truth)
            << "mip " << e.mip << (e.betweenTexels ? " between texels" : "");
    }
    EXPECT_EQ(rows, 8); // mips 0-3, at texels and between them
    options.brdf = Brdf::BlinnPhong;
    const auto refused = evaluateMethods(map, options);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().find("GGX"), std::string::npos) << refused.error();
}

namespace burnish {
namespace {

TEST(FittedLobe, FitErrorsSumTheIsotropicAndAnisotropicFitsPerLevel) {
    // A flat map: both fits are the base lobe about +z, where the engines' frame is the normal's: no error.
    const NormalMap flat = makeNormalMap(16, 16, std::vector<glm::vec3>(256, glm::vec3(0, 0, 1)));
    const NormalPyramid flatPyramid =
        NormalPyramid::build(std::shared_ptr<const NormalMap>(&flat, [](const NormalMap*) {}));
    FittedLobeOptions o;
    o.brdf = Brdf::Ggx;
    o.anisotropic = true;
    const FittedPyramid f = FittedPyramid::build(
        flatPyramid, [](int, int, int) { return 256.0; }, nullptr, 256.0, -1, o);
    for (int k = 1; k < f.levelCount(); ++k) {
        const auto e = f.fitErrors(k);
        EXPECT_GT(e.truth, 0.0);
        EXPECT_LT(e.isotropic, 1e-6 * e.truth) << k;
        EXPECT_LT(e.anisotropic, 1e-6 * e.truth) << k;
    }
    // Ridges along y: both fits err somewhere, every sum finite; without the anisotropic fit, no sums.
    std::vector<glm::vec3> ridges;
    for (int i = 0; i < 256; ++i)
        ridges.push_back(glm::normalize(glm::vec3(i % 2 ? 0.4f : -0.4f, 0.0f, 1.0f)));
    const NormalMap ridged = makeNormalMap(16, 16, ridges);
    const NormalPyramid pyramid =
        NormalPyramid::build(std::shared_ptr<const NormalMap>(&ridged, [](const NormalMap*) {}));
    const FittedPyramid r = FittedPyramid::build(
        pyramid, [](int, int, int) { return 256.0; }, nullptr, 256.0, -1, o);
    const auto e = r.fitErrors(2);
    EXPECT_TRUE(std::isfinite(e.isotropic) && std::isfinite(e.anisotropic));
    EXPECT_GT(e.isotropic, 0.01 * e.truth);
    o.anisotropic = false;
    const FittedPyramid iso = FittedPyramid::build(
        pyramid, [](int, int, int) { return 256.0; }, nullptr, 256.0, -1, o);
    EXPECT_EQ(iso.fitErrors(2).truth, 0.0);
}

} // namespace
} // namespace burnish
