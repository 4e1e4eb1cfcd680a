// Golden images of the scene renderer: each method on the sphere, the plane at a grazing angle, the
// supersampled reference, two debug views and the design's extremes, rendered headless at 64×64 and
// compared with tests/render/golden/*.png under a threshold triple (tests/support/image_compare.h).
// On a failure the expected, actual and diff PNGs are written to $BURNISH_GOLDEN_DIFF_DIR, or to
// golden-diff/ in the test's working folder, and the failure message names them.
//
// Regenerate the goldens after an intended change of the renderer's output:
//     BURNISH_UPDATE_GOLDENS=1 build/tests/render/burnish_render_tests --gtest_filter='Golden*'
// and look at every changed PNG before committing it.
//
// Thresholds. The goldens are made on Mesa llvmpipe, the machine type CI runs, which is
// deterministic run to run; what can differ between two llvmpipe machines (LLVM version, vector
// width, FMA contraction) is the rounding of float shading, which moves an 8-bit sRGB value by one
// or two codes, and only rarely flips a pixel at the edge of a highlight. Hence:
//  - a pixel fails when a channel moves by more than 3/255: above one or two codes of rounding;
//  - the image fails when more than 0.5% of its pixels fail (20 of 4096): a few highlight-edge
//    pixels, never a region;
//  - any pixel moving by more than half the range fails the image at once: a NaN turned black, a
//    missing highlight, a changed debug ramp.
// NVIDIA or other GPUs differ by more than rounding (their derivatives and texture filtering are
// not llvmpipe's); the goldens are not meant for them.
#include <burnish/core/prefilter/sample_maps.h>
#include <burnish/core/util/files.h>
#include <burnish/render/context.h>
#include <burnish/render/renderer.h>

#include "image_compare.h"
#include "temp_dir.h"

#include "renderer_fixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace burnish;
using namespace burnish::render;
using burnish::test::ImageThresholds;
using burnish::test::RgbaImage;

// Small enough that the goldens stay a few kilobytes each and the suite fast on llvmpipe.
constexpr int kGoldenSize = 64;
// Samples per pixel of the reference golden: enough for a smooth image, few enough to be quick.
constexpr int kGoldenReferenceSamples = 8;
// The normal map is 64² on a 64-pixel sphere: magnified, so its bumps are several pixels wide and a
// highlight edge rarely falls on a pixel by rounding alone.
constexpr int kGoldenMapSize = 64;

// See the file header.
const ImageThresholds kGoldenThresholds{3.0f / 255.0f, 0.005, 0.5f};

fs::path goldenDir() {
    return fs::path(BURNISH_SOURCE_DIR) / "tests" / "render" / "golden";
}

fs::path diffDir() {
    if (const char* dir = std::getenv("BURNISH_GOLDEN_DIFF_DIR"); dir && *dir) return dir;
    return fs::current_path() / "golden-diff";
}

bool updating() {
    const char* update = std::getenv("BURNISH_UPDATE_GOLDENS");
    return update && std::string(update) == "1";
}

class GoldenTest : public burnish::test::RendererFixture {
protected:
    // The display image of a scene (or of its reference), after checking that the HDR image the
    // display one is made from holds no NaN or Inf.
    static RgbaImage render(const Scene& scene, int referenceSamples = 0) {
        const Status set = renderer().setScene(scene);
        EXPECT_TRUE(set.ok()) << set.error();
        auto hdr = referenceSamples > 0 ? renderer().renderReference(kGoldenSize, kGoldenSize,
                                                                     referenceSamples, ImageKind::Hdr)
                                        : renderer().renderToImage(kGoldenSize, kGoldenSize, ImageKind::Hdr);
        EXPECT_TRUE(hdr.ok()) << hdr.error();
        if (hdr) {
            size_t nonFinite = 0;
            for (float v : *hdr)
                nonFinite += std::isfinite(v) ? 0 : 1;
            EXPECT_EQ(nonFinite, 0u) << "non-finite HDR values";
        }
        auto display =
            referenceSamples > 0
                ? renderer().renderReference(kGoldenSize, kGoldenSize, referenceSamples, ImageKind::Display)
                : renderer().renderToImage(kGoldenSize, kGoldenSize, ImageKind::Display);
        EXPECT_TRUE(display.ok()) << display.error();
        return RgbaImage{kGoldenSize, kGoldenSize,
                         display ? std::move(display).value() : std::vector<float>{}};
    }

    // Compares with tests/render/golden/<name>.png, or rewrites it under BURNISH_UPDATE_GOLDENS=1.
    static void expectGolden(const std::string& name, const RgbaImage& actual) {
        ASSERT_EQ(actual.rgba.size(), size_t(kGoldenSize) * kGoldenSize * 4) << name << ": no image";
        const fs::path path = goldenDir() / (name + ".png");
        if (updating()) {
            const Status s = burnish::test::writeRgbaPng(path, actual);
            ASSERT_TRUE(s.ok()) << s.error();
            std::cout << "updated " << path << "\n";
            return;
        }
        auto expected = burnish::test::readRgbaImage(path);
        ASSERT_TRUE(expected.ok()) << name << ": " << expected.error()
                                   << " (make it with BURNISH_UPDATE_GOLDENS=1, see test_golden.cpp)";
        const auto result =
            burnish::test::compareAndReport(name, *expected, actual, kGoldenThresholds, diffDir());
        EXPECT_TRUE(result.passed) << result.message;
    }
};

Scene goldenScene() {
    Scene scene;
    scene.material.normalMap =
        std::make_shared<const NormalMap>(makeSampleNormalMap(SampleMapKind::Hammered, kGoldenMapSize));
    return scene;
}

TEST_F(GoldenTest, EachMethodOnTheSphere) {
    Scene scene = goldenScene();
    for (Method m : allMethods()) {
        scene.material.method = m;
        expectGolden("sphere-" + std::string(methodName(m)), render(scene));
    }
}

TEST_F(GoldenTest, PlaneAtAGrazingAngle) {
    Scene scene = goldenScene();
    scene.mesh = MeshKind::Plane;
    scene.camera.pitchDegrees = 4.0f; // the camera low over the plane: strong minification far off
    scene.camera.distance = 2.0f;
    scene.light.direction = {-0.5f, 0.1f, -0.86f}; // low light in front: a long highlight streak
    scene.material.method = Method::Lean;
    expectGolden("plane-grazing-lean", render(scene));
    scene.material.method = Method::Naive;
    expectGolden("plane-grazing-naive", render(scene));
}

TEST_F(GoldenTest, SupersampledReference) {
    expectGolden("sphere-reference", render(goldenScene(), kGoldenReferenceSamples));
}

TEST_F(GoldenTest, DebugViews) {
    Scene scene = goldenScene();
    scene.debugView = DebugView::Normals;
    expectGolden("debug-normals", render(scene));
    scene.debugView = DebugView::Variance;
    scene.material.method = Method::Toksvig;
    expectGolden("debug-variance-toksvig", render(scene));
}

// The design's extremes, each as a golden: power 10^6, a grazing view, zero-variance texels and a
// 1×1 texture. render() also checks that no NaN or Inf reaches the HDR image.
TEST_F(GoldenTest, Extremes) {
    Scene scene = goldenScene();
    scene.material.basePower = 1e6;
    scene.material.method = Method::Lean;
    expectGolden("extreme-power-1e6-lean", render(scene));

    scene = goldenScene();
    scene.mesh = MeshKind::Plane;
    scene.camera.pitchDegrees = 0.5f; // the camera almost on the horizon
    scene.light.direction = {0.0f, 0.02f, -1.0f};
    scene.material.method = Method::Clean;
    expectGolden("extreme-grazing-clean", render(scene));

    scene = goldenScene();
    scene.material.normalMap = std::make_shared<const NormalMap>(
        makeNormalMap(8, 8, std::vector<glm::vec3>(64, glm::vec3(0.0f, 0.0f, 1.0f))));
    scene.material.basePower = 1e6;
    scene.material.method = Method::VarianceToGloss;
    expectGolden("extreme-zero-variance", render(scene));

    scene = goldenScene();
    scene.material.normalMap = std::make_shared<const NormalMap>(
        makeNormalMap(1, 1, {glm::normalize(glm::vec3(0.3f, -0.2f, 1.0f))}));
    scene.material.method = Method::Toksvig;
    expectGolden("extreme-1x1-map", render(scene));
}

// The comparison can fail: a visibly changed image does, in each of the triple's ways, and the
// failure writes the three images it names.
TEST_F(GoldenTest, ComparisonFailsOnAVisiblyChangedImage) {
    const RgbaImage golden = render(goldenScene());
    ASSERT_FALSE(golden.rgba.empty());

    // Identical, and within rounding (every channel one 8-bit code up): passes.
    EXPECT_TRUE(burnish::test::compareImages(golden, golden, kGoldenThresholds).passed);
    RgbaImage rounded = golden;
    for (float& v : rounded.rgba)
        v = std::min(v + 1.0f / 255.0f, 1.0f);
    EXPECT_TRUE(burnish::test::compareImages(golden, rounded, kGoldenThresholds).passed);

    // A region changed by a tenth of the range: too many failing pixels, though none is a hard fail.
    constexpr int kBlock = 12; // 144 pixels, 3.5% of the image: far above the allowed 0.5%
    constexpr float kRegionChange = 0.1f;
    RgbaImage region = golden;
    for (int y = 20; y < 20 + kBlock; ++y)
        for (int x = 20; x < 20 + kBlock; ++x)
            for (int c = 0; c < 3; ++c) {
                float& v = region.rgba[(size_t(y) * kGoldenSize + size_t(x)) * 4 + size_t(c)];
                v = v > 0.5f ? v - kRegionChange : v + kRegionChange;
            }
    const auto regionResult = burnish::test::compareImages(golden, region, kGoldenThresholds);
    EXPECT_FALSE(regionResult.passed);
    EXPECT_EQ(regionResult.failingPixels, kBlock * kBlock);

    // One pixel turned from its value to the opposite end: within the fraction, but a hard fail.
    RgbaImage pixel = golden;
    float& v = pixel.rgba[(size_t(32) * kGoldenSize + 32) * 4 + 1];
    v = v > 0.5f ? 0.0f : 1.0f;
    const auto pixelResult = burnish::test::compareImages(golden, pixel, kGoldenThresholds);
    EXPECT_EQ(pixelResult.failingPixels, 1);
    EXPECT_FALSE(pixelResult.passed);

    // A NaN is the largest difference there is.
    RgbaImage nan = golden;
    nan.rgba[0] = NAN;
    EXPECT_FALSE(burnish::test::compareImages(golden, nan, kGoldenThresholds).passed);

    // Another size fails.
    EXPECT_FALSE(
        burnish::test::compareImages(golden, RgbaImage{1, 1, {0, 0, 0, 1}}, kGoldenThresholds).passed);

    // A renderer change that shows: a gold metal instead of the dielectric, against the golden file.
    Scene gold = goldenScene();
    gold.material.metal = true;
    gold.material.specularColor = glm::vec3(1.0f, 0.78f, 0.34f);
    burnish::test::TempDir dir;
    const auto expected = burnish::test::readRgbaImage(goldenDir() / "sphere-variance-to-gloss.png");
    ASSERT_TRUE(expected.ok()) << expected.error();
    const auto changed =
        burnish::test::compareAndReport("changed", *expected, render(gold), kGoldenThresholds, dir.path());
    EXPECT_FALSE(changed.passed);
    for (const char* file : {"changed-expected.png", "changed-actual.png", "changed-diff.png"}) {
        EXPECT_TRUE(fs::exists(dir / file)) << file;
        EXPECT_NE(changed.message.find(file), std::string::npos) << changed.message;
    }
    // The written expected image reads back as it was.
    const auto reread = burnish::test::readRgbaImage(dir / "changed-expected.png");
    ASSERT_TRUE(reread.ok()) << reread.error();
    EXPECT_TRUE(burnish::test::compareImages(*expected, *reread, ImageThresholds{0.0f, 0.0, 0.0f}).passed);
}

} // namespace
