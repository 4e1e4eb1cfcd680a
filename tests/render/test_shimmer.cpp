// The shimmer metric (render/shimmer.h): its arithmetic, its zero for a still camera, and the
// texts' claim that prefiltering calms the highlights of a bumpy surface seen from a distance.
//
// Measured here (HDR luminance, the bumpy sample at 128² on the sphere in a 128² frame, about a
// texel per pixel, a metal of constant F0 at power 2048, 8 frames of 0.5°; `burnish render
// --sample bumpy --sample-size 128 --size 128x128 --metal --specular 0.9 --fresnel none --power 2048
// --sequence 8 --reference 4 --method M`): naive 0.103, Toksvig 0.052, Toksvig map 0.057,
// variance-to-gloss 0.048, LEAN 0.057, CLEAN 0.056, vMF 0.057, so naive moves 1.8–2.2× more
// highlight energy between frames than every baked method (1.6–1.9× at 64² map and frame). The
// claim depends on the scale: with the same map in a 96² frame (1.4 texels per pixel) all seven
// measured within 0.035–0.041, so the test keeps the map and frame sizes equal.
//
// The issue also expects naive to shimmer more than the supersampled reference. That holds only
// where the reference has converged and naive aliases: a face-on-ish plane at ~9 texels per pixel
// (NaiveShimmersMoreThanTheReferenceAtDistance, with the numbers and the regimes where it fails).
// A reference shimmer must be read against its noise floor (ShimmerOptions::estimateReferenceNoise):
// where thousands of finest texels fall in a pixel, N jittered samples land on new glints every
// frame and the measured "shimmer" is Monte Carlo noise (ReferenceShimmerIsNoiseWhereItIsNotConverged).
#include <burnish/core/prefilter/sample_maps.h>
#include <burnish/render/context.h>
#include <burnish/render/renderer.h>
#include <burnish/render/shimmer.h>

#include "renderer_fixture.h"
#include <glm/geometric.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace burnish;
using namespace burnish::render;

// Under AddressSanitizer (GCC and Clang define __SANITIZE_ADDRESS__ / __has_feature) everything is
// several times slower; the claims hold at the smaller size too (fewer pixels, same texel ratio).
#if defined(__SANITIZE_ADDRESS__)
constexpr int kFrameSize = 64;
#else
constexpr int kFrameSize = 128;
#endif
// About a texel per pixel: the map as wide as the frame (see the file header).
constexpr int kMapSize = kFrameSize;
constexpr int kFrames = 8;
constexpr float kDegreesPerFrame = 0.5f; // a slow orbit: the surface slides ~0.5 pixel per frame
// The reference is not part of the method claims; a few samples keep the suite fast.
constexpr int kReferenceSamples = 4;

class ShimmerTest : public burnish::test::RendererFixture {};

// The bumpy sample on the sphere, about texel for pixel, as a metal with a constant F0: only the
// specular lobe is drawn, so the methods differ in nothing else.
Scene bumpyMetal() {
    Scene scene;
    scene.material.normalMap =
        std::make_shared<const NormalMap>(makeSampleNormalMap(SampleMapKind::Bumpy, kMapSize));
    scene.material.metal = true;
    scene.material.specularColor = glm::vec3(0.9f);
    scene.material.fresnel = FresnelTerm::None;
    scene.material.basePower = 2048.0;
    return scene;
}

ShimmerOptions orbit() {
    ShimmerOptions o;
    o.frames = kFrames;
    o.degreesPerFrame = kDegreesPerFrame;
    o.width = kFrameSize;
    o.height = kFrameSize;
    o.referenceSamples = kReferenceSamples;
    return o;
}

TEST(ShimmerMetric, LuminanceUsesRec709Weights) {
    // Float arithmetic of three products: a few ulps of values of order 1.
    constexpr float kTolerance = 1e-6f;
    const auto Y = frameLuminance({1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1, 1, 0});
    ASSERT_EQ(Y.size(), 4u);
    EXPECT_NEAR(Y[0], 0.2126f, kTolerance);
    EXPECT_NEAR(Y[1], 0.7152f, kTolerance);
    EXPECT_NEAR(Y[2], 0.0722f, kTolerance);
    EXPECT_NEAR(Y[3], 1.0f, kTolerance); // the weights sum to one; alpha is ignored
}

TEST(ShimmerMetric, MeanAbsoluteChangeOverTheMask) {
    constexpr double kTolerance = 1e-12; // sums of a few exact binary fractions
    const std::vector<float> a{0.0f, 1.0f, 0.5f, 0.25f};
    const std::vector<float> b{1.0f, 0.0f, 0.5f, 0.75f};
    auto all = meanAbsoluteChange(a, b);
    ASSERT_TRUE(all.ok());
    EXPECT_NEAR(*all, (1.0 + 1.0 + 0.0 + 0.5) / 4.0, kTolerance);
    auto masked = meanAbsoluteChange(a, b, {0, 0, 1, 1});
    ASSERT_TRUE(masked.ok());
    EXPECT_NEAR(*masked, 0.25, kTolerance);
    auto none = meanAbsoluteChange(a, b, {0, 0, 0, 0});
    ASSERT_TRUE(none.ok());
    EXPECT_EQ(*none, 0.0);
    EXPECT_FALSE(meanAbsoluteChange(a, {1.0f}).ok());
    EXPECT_FALSE(meanAbsoluteChange(a, b, {1, 1}).ok());
}

TEST(ShimmerMetric, ErosionDropsTheSilhouette) {
    // A 5×5 mask with a 3×3 block in the middle: only its centre has all four neighbours in.
    std::vector<std::uint8_t> mask(25, 0);
    for (int y = 1; y <= 3; ++y)
        for (int x = 1; x <= 3; ++x)
            mask[size_t(y * 5 + x)] = 1;
    const auto eroded = erodeMask(mask, 5, 5);
    int in = 0;
    for (std::uint8_t m : eroded)
        in += m;
    EXPECT_EQ(in, 1);
    EXPECT_EQ(eroded[12], 1);
    // A full mask loses its border row and column.
    const auto full = erodeMask(std::vector<std::uint8_t>(25, 1), 5, 5);
    in = 0;
    for (std::uint8_t m : full)
        in += m;
    EXPECT_EQ(in, 9);
}

TEST_F(ShimmerTest, BadOptionsAreErrors) {
    const Scene scene = bumpyMetal();
    ShimmerOptions o = orbit();
    o.frames = 1;
    EXPECT_FALSE(measureShimmer(renderer(), scene, o).ok());
    o = orbit();
    o.degreesPerFrame = NAN;
    EXPECT_FALSE(measureShimmer(renderer(), scene, o).ok());
    o = orbit();
    o.referenceSamples = 0;
    EXPECT_FALSE(measureShimmer(renderer(), scene, o).ok());
    // The noise floor splits the samples in two halves of linear radiance.
    o = orbit();
    o.estimateReferenceNoise = true;
    o.referenceSamples = 1;
    EXPECT_FALSE(measureShimmer(renderer(), scene, o).ok());
    o.referenceSamples = 4;
    o.space = ImageKind::Display;
    EXPECT_FALSE(measureShimmer(renderer(), scene, o).ok());
    // A sphere far away covers no pixel after the silhouette is dropped.
    Scene far = scene;
    far.camera.distance = 1e4f;
    EXPECT_FALSE(measureShimmer(renderer(), far, orbit()).ok());
}

// A still camera: both sequences are the same frame repeated (the renderer is deterministic and
// the reference's jitter is the same Halton set every frame), so the shimmer is exactly zero.
TEST_F(ShimmerTest, StillCameraDoesNotShimmer) {
    ShimmerOptions o = orbit();
    o.frames = 3;
    o.degreesPerFrame = 0.0f;
    int calls = 0;
    o.onFrame = [&](const ShimmerFrame& f) {
        EXPECT_EQ(f.index, calls++);
        ASSERT_NE(f.method, nullptr);
        EXPECT_EQ(f.method->size(), size_t(kFrameSize) * kFrameSize * 4);
    };
    auto report = measureShimmer(renderer(), bumpyMetal(), o);
    ASSERT_TRUE(report.ok()) << report.error();
    EXPECT_EQ(calls, 3);
    EXPECT_EQ(report->methodDeltas.size(), 2u);
    EXPECT_EQ(report->methodMean, 0.0);
    EXPECT_EQ(report->referenceMean, 0.0);
    // The mask: the sphere covers a good part of the frame, not all of it.
    EXPECT_GT(report->measuredPixels, kFrameSize * kFrameSize / 4);
    EXPECT_LT(report->measuredPixels, kFrameSize * kFrameSize);
    // A still reference gives a finite ratio.
    EXPECT_TRUE(std::isfinite(report->ratio));
}

// The texts' claim: the baked methods widen the lobe by the normals' variance, so their highlights
// move less light from frame to frame than naive's narrow, aliased ones.
TEST_F(ShimmerTest, BakedMethodsShimmerLessThanNaive) {
    // Naive must exceed each baked method by this factor: measured 1.80× (LEAN, vMF) to 2.15×
    // (variance-to-gloss) at 128², 1.63–1.90× at 64²; 1.3 keeps "clearly less" with room for the
    // differences between llvmpipe builds.
    constexpr double kMinNaiveOverBaked = 1.3;
    Scene scene = bumpyMetal();
    // Power 2048 is past the Toksvig map's fixed power (100): it converts, as Hill 2011 does.
    std::map<Method, double> shimmer;
    for (Method m : {Method::Naive, Method::Toksvig, Method::ToksvigMap, Method::VarianceToGloss,
                     Method::Lean, Method::Clean, Method::Vmf}) {
        scene.material.method = m;
        auto report = measureShimmer(renderer(), scene, orbit());
        ASSERT_TRUE(report.ok()) << report.error();
        shimmer[m] = report->methodMean;
        std::cout << methodName(m) << ": mean |dY| " << report->methodMean << " (reference "
                  << report->referenceMean << ", ratio " << report->ratio << ")\n";
    }
    EXPECT_GT(shimmer[Method::Naive], 0.0);
    for (const auto& [m, value] : shimmer) {
        if (m == Method::Naive) continue;
        EXPECT_GT(shimmer[Method::Naive], kMinNaiveOverBaked * value)
            << methodName(m) << " shimmers " << value << ", naive " << shimmer[Method::Naive];
    }
}

// The bumpy sample seen from a distance: on the plane, viewed from 60° above at distance 3, with the
// map tiled so that a pixel covers about 9 finest texels across (80 per pixel) and a 32-texel bump
// about 4 pixels: the finest octaves are far below a pixel, the bumps still visible. The light is
// the camera's direction mirrored in the plane, so the flat-mirror highlight sits on the target.
Scene distantBumpyPlane(double power) {
    Scene scene = bumpyMetal();
    scene.mesh = MeshKind::Plane;
    scene.camera.pitchDegrees = 60.0f;
    // The plane's UVs repeat once per unit and a frame sees 2.2 units across at the target, so 4
    // repeats of the kMapSize² map (as wide as the frame) give 4·2.2 ≈ 9 texels per pixel across
    // at any frame size, and the same bumps per pixel.
    scene.material.uvScale = 4.0f;
    scene.material.basePower = power;
    const glm::vec3 toCamera = glm::normalize(scene.camera.position() - scene.camera.target);
    scene.light.direction = glm::vec3(-toCamera.x, toCamera.y, -toCamera.z);
    return scene;
}

// The reference's noise floor is what its shimmer is made of where the truth is far from converged:
// the sphere with the map tiled 256 times (about 85 texels per pixel across) at power 512. There,
// glints cover about 1% of the surface, so N samples over thousands of texels per pixel land on a
// new random set of them every frame, and the mean |ΔY| between frames is sampling noise.
// Measured (referenceMean / referenceNoise): N = 16: 0.299 / 0.269, 64: 0.173 / 0.166, 256: 0.089 /
// 0.089, 1024: 0.044 — falling like 1/√N, while naive's (a smooth too-shiny highlight) is 0.003–0.016.
TEST_F(ShimmerTest, ReferenceShimmerIsNoiseWhereItIsNotConverged) {
    // Noise-dominated: the reference's shimmer is within this fraction of its noise floor (measured
    // 1.11× at 16 samples, 1.04× at 64; the floor is an estimate from one split of the samples).
    constexpr double kMaxShimmerOverNoise = 1.3;
    // Quadrupling the samples must cut the noise at least this much (1/√N gives 2; measured 1.61
    // at 128² and the Halton set's stratification only adds to it): 1.3 leaves room and still fails
    // if the samples did not reduce the noise.
    constexpr double kMinNoiseDrop = 1.3;
    Scene scene = bumpyMetal();
    scene.material.basePower = 512.0;
    // The map is as wide as the frame, so the tiling fixes the texels per pixel at any frame size.
    scene.material.uvScale = 256.0f;
    ShimmerOptions o = orbit();
    o.frames = 4;
    o.estimateReferenceNoise = true;
    std::vector<double> noise;
    for (int samples : {16, 64}) {
        o.referenceSamples = samples;
        auto report = measureShimmer(renderer(), scene, o);
        ASSERT_TRUE(report.ok()) << report.error();
        std::cout << samples << " samples: reference " << report->referenceMean << ", noise floor "
                  << report->referenceNoise << ", naive " << report->methodMean << "\n";
        ASSERT_EQ(report->referenceNoiseDeltas.size(), size_t(o.frames - 1)); // one per delta
        EXPECT_GT(report->referenceNoise, 0.0);
        EXPECT_LT(report->referenceMean, kMaxShimmerOverNoise * report->referenceNoise);
        noise.push_back(report->referenceNoise);
    }
    EXPECT_GT(noise[0], kMinNoiseDrop * noise[1]);
}

// The claim: on a bumpy normal map seen from a distance, naive Blinn-Phong shimmers clearly
// more than the supersampled reference, and the baked methods less than naive. It holds where the
// reference's shimmer is the truth's (converged: well above its noise floor) and naive's sharp lobe
// on mip-averaged normals aliases: ~9 texels per pixel on a face-on-ish plane.
//
// Measured on the plane of distantBumpyPlane (128², 5 frames of 0.5°, HDR, naive / reference mean
// |ΔY| with the noise floor in brackets):
//   power 512:  ~4 texels/px 1.40 / 1.13 (0.02 at 1024 spp); ~9 texels/px 1.46 / 1.02 (0.19 at 256),
//               1.01 (0.05 at 1024): 1.45×; ~17 texels/px 0.82 / 0.79 (0.10 at 1024): 1.04×.
//   power 2048: ~9 texels/px 2.81 / 1.31 (0.52 at 256): 2.1× (2.3× against the noise-free part).
// Where it does not hold, the converged reference shimmers MORE than naive: the sphere at 0.5–10
// texels per pixel (powers 64–2048, naive/reference 0.25–0.8 with noise under a fifth of the
// reference) — the trilinear mip, chosen by the sphere's denser v axis, blurs naive isotropically
// while the box-filtered truth keeps every glint; and from ~17 texels per pixel on, naive's
// mip-averaged normals are a flat mirror whose small highlight barely moves, while the truth's
// thousands of glints per pixel still sparkle and take 10⁴–10⁵ samples to converge.
TEST_F(ShimmerTest, NaiveShimmersMoreThanTheReferenceAtDistance) {
    // Measured 2.14× at 128² and power 2048 (see above), 3.3× in the 64² frame at 1024 samples
    // (noise floor 0.15 of 0.58); 1.5 keeps "clearly more" with room for
    // llvmpipe builds. The reference's residual noise only raises its shimmer, so this is conservative.
    constexpr double kMinNaiveOverReference = 1.5;
    // The reference is converged enough to stand for the truth when its noise floor is at most this
    // fraction of its shimmer (measured 0.40 at 256 samples; noise adds roughly in quadrature, so the
    // truth's own shimmer is still over 90% of the measured value).
    constexpr double kMaxNoiseFraction = 0.55;
    // The baked methods widen the lobe by the variance: measured variance-to-gloss 0.087 against
    // naive's 1.46 at power 512, far calmer; 1.3 as in BakedMethodsShimmerLessThanNaive.
    constexpr double kMinNaiveOverBaked = 1.3;
    Scene scene = distantBumpyPlane(2048.0);
    ShimmerOptions o = orbit();
    o.frames = 5;
    // 256 samples at 128²; four times as many in the 64² frame, the same count of shaded pixels
    // (the smaller map there has a larger noise floor: 0.45 of 0.66 at 256 samples).
    o.referenceSamples = 256 * (128 / kFrameSize) * (128 / kFrameSize);
    o.estimateReferenceNoise = true;
    scene.material.method = Method::Naive;
    auto naive = measureShimmer(renderer(), scene, o);
    ASSERT_TRUE(naive.ok()) << naive.error();
    std::cout << "naive " << naive->methodMean << ", reference " << naive->referenceMean << " (noise floor "
              << naive->referenceNoise << "), ratio " << naive->ratio << "\n";
    EXPECT_LT(naive->referenceNoise, kMaxNoiseFraction * naive->referenceMean);
    EXPECT_GT(naive->methodMean, kMinNaiveOverReference * naive->referenceMean);

    // The baked method only: the reference does not depend on the method, one sample suffices.
    scene.material.method = Method::VarianceToGloss;
    o.referenceSamples = 1;
    o.estimateReferenceNoise = false;
    auto baked = measureShimmer(renderer(), scene, o);
    ASSERT_TRUE(baked.ok()) << baked.error();
    std::cout << "variance-to-gloss " << baked->methodMean << "\n";
    EXPECT_GT(naive->methodMean, kMinNaiveOverBaked * baked->methodMean);
}

// A still frame against the ground truth (measureImageError). A flat surface: the method's lobe is
// the reference's, so only the reference's own noise and the lobe's shape separate them.
TEST_F(ShimmerTest, FlatSurfaceMatchesItsReferenceOnTheScreen) {
    Scene scene = bumpyMetal();
    scene.material.normalMap.reset();
    scene.material.basePower = 64.0;
    scene.material.method = Method::Lean;
    ImageErrorOptions o;
    o.width = o.height = kFrameSize;
    o.referenceSamples = 16;
    auto report = measureImageError(renderer(), scene, o);
    ASSERT_TRUE(report.ok()) << report.error();
    std::cout << "flat: relative L1 " << report->relativeL1 << ", energy " << report->energyRatio
              << ", reference noise " << report->referenceNoiseL1 << "\n";
    EXPECT_GT(report->measuredPixels, kFrameSize * kFrameSize / 4);
    EXPECT_LT(report->relativeL1, 0.05);
    EXPECT_NEAR(report->energyRatio, 1.0, 0.03);
    EXPECT_TRUE(std::isfinite(report->referenceNoiseL1));
}

// The bumpy sample seen from a distance, where a pixel covers many finest texels: the baked LEAN lobe
// and the mixture stand far closer to the truth than naive's aliased, too narrow highlights, and the
// mixture keeps the energy.
TEST_F(ShimmerTest, BakedLobesErrLessThanNaiveOnTheScreenAtDistance) {
    Scene scene = distantBumpyPlane(512.0);
    ImageErrorOptions o;
    o.width = o.height = kFrameSize;
    o.referenceSamples = 64;
    std::map<Method, ImageErrorReport> r;
    for (Method m : {Method::Naive, Method::Lean, Method::Mixture}) {
        scene.material.method = m;
        auto report = measureImageError(renderer(), scene, o);
        ASSERT_TRUE(report.ok()) << report.error();
        std::cout << methodName(m) << ": relative L1 " << report->relativeL1 << ", energy "
                  << report->energyRatio << ", reference noise " << report->referenceNoiseL1 << "\n";
        r[m] = *report;
    }
    EXPECT_LT(r[Method::Lean].relativeL1, r[Method::Naive].relativeL1);
    EXPECT_LT(r[Method::Mixture].relativeL1, r[Method::Naive].relativeL1);
    EXPECT_NEAR(r[Method::Mixture].energyRatio, 1.0, 0.1);
    // The scene is the caller's again.
    EXPECT_EQ(renderer().scene().material.method, Method::Mixture);
}

TEST_F(ShimmerTest, ImageErrorBadOptionsAreErrors) {
    const Scene scene = bumpyMetal();
    ImageErrorOptions o;
    o.width = o.height = kFrameSize;
    o.referenceSamples = 1; // the noise estimate needs two halves
    EXPECT_FALSE(measureImageError(renderer(), scene, o).ok());
    o.referenceSamples = 4;
    o.width = 0;
    EXPECT_FALSE(measureImageError(renderer(), scene, o).ok());
    o.width = kFrameSize;
    Scene far = scene;
    far.camera.distance = 1e4f;
    auto none = measureImageError(renderer(), far, o);
    ASSERT_FALSE(none.ok());
    EXPECT_NE(none.error().find("covers no pixel"), std::string::npos) << none.error();
}

} // namespace
