// End to end: `burnish render` run as a process (headless OpenGL on Mesa llvmpipe). Sizes are
// small so the software rasterizer keeps every case under a few seconds.
#include <burnish/core/io/image.h>
#include <burnish/core/prefilter/methods.h>

#include "cli_run.h"
#include "temp_dir.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

namespace {

using burnish::test::CliResult;
using burnish::test::lineCount;
// `burnish render` loads Mesa's OpenGL drivers, whose allocations LeakSanitizer cannot attribute
// (see BURNISH_GL_TEST_ENV in tests/CMakeLists.txt), so its runs go without leak checking. ctest
// runs each test in its own process: the setting reaches only this file's children.
CliResult runBurnish(const std::string& args) {
    ::setenv("ASAN_OPTIONS", "detect_leaks=0", 1);
    return burnish::test::runBurnish(args);
}
using burnish::test::shellQuote;
using burnish::test::TempDir;

// A pixel with a channel above this is lit (the background is exactly 0; 8-bit PNGs step by 1/255).
constexpr float kLit = 0.5f / 255.0f;
// At the default camera the sphere covers about a third of the frame: at least a tenth lit proves
// a material was drawn, not just a cleared frame.
constexpr double kMinLitFraction = 0.1;

struct PixelStats {
    size_t nonFinite = 0;
    double litFraction = 0.0;
};

PixelStats stats(const burnish::Image& image) {
    PixelStats s;
    size_t lit = 0;
    for (size_t p = 0; p < image.texelCount(); ++p) {
        bool any = false;
        for (int c = 0; c < std::min(image.channels, 3); ++c) {
            const float v = image.pixels[p * size_t(image.channels) + size_t(c)];
            if (!std::isfinite(v)) ++s.nonFinite;
            any = any || v > kLit;
        }
        lit += any ? 1 : 0;
    }
    s.litFraction = image.texelCount() ? double(lit) / double(image.texelCount()) : 0.0;
    return s;
}

// Exit code non-zero, nothing on stdout, and exactly one "burnish: error:" line naming `topic`.
void expectOneErrorLine(const CliResult& r, const std::string& topic) {
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(lineCount(r.err), 1) << r.err;
    EXPECT_EQ(r.err.rfind("burnish: error:", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(topic), std::string::npos) << r.err;
}

TEST(CliRender, WritesAPngOfTheRequestedSize) {
    TempDir dir;
    const auto out = dir / "sphere.png";
    const CliResult r =
        runBurnish("render --sample-size 32 --size 48x32 --method lean --out " + shellQuote(out.string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    auto image = burnish::readImage(out);
    ASSERT_TRUE(image.ok()) << image.error();
    EXPECT_EQ(image->width, 48);
    EXPECT_EQ(image->height, 32);
    EXPECT_EQ(image->source.bitsPerChannel, 8);
    const PixelStats s = stats(*image);
    EXPECT_EQ(s.nonFinite, 0u);
    EXPECT_GT(s.litFraction, kMinLitFraction);
}

TEST(CliRender, DrawsTheMixtureFilteredAfterShading) {
    // --mixture-filtering stochastic: finite and lit, and one pass draws another image than sixteen
    // averaged (each pass picks its own texels).
    TempDir dir;
    auto render = [&](int samples) {
        const auto out = dir / ("st" + std::to_string(samples) + ".exr");
        const CliResult r = runBurnish("render --sample-size 64 --size 64x64 --method mixture --uv-scale 4 "
                                       "--mixture-filtering stochastic --mixture-samples " +
                                       std::to_string(samples) + " --out " + shellQuote(out.string()));
        EXPECT_EQ(r.exitCode, 0) << r.err;
        auto image = burnish::readImage(out);
        EXPECT_TRUE(image.ok()) << image.error();
        return image.ok() ? *image : burnish::Image{};
    };
    const auto one = render(1), sixteen = render(16);
    for (const auto* image : {&one, &sixteen}) {
        const PixelStats s = stats(*image);
        EXPECT_EQ(s.nonFinite, 0u);
        EXPECT_GT(s.litFraction, kMinLitFraction);
    }
    ASSERT_EQ(one.pixels.size(), sixteen.pixels.size());
    EXPECT_NE(one.pixels, sixteen.pixels);
}

TEST(CliRender, WritesAFiniteHdrExr) {
    TempDir dir;
    const auto out = dir / "sphere.exr";
    // Power 10^6 and a 1×1 sample map: the extremes, where a NaN would show.
    const CliResult r =
        runBurnish("render --sample-size 1 --power 1e6 --size 40x24 --out " + shellQuote(out.string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    auto image = burnish::readImage(out);
    ASSERT_TRUE(image.ok()) << image.error();
    EXPECT_EQ(image->width, 40);
    EXPECT_EQ(image->height, 24);
    EXPECT_TRUE(image->source.isFloat);
    const PixelStats s = stats(*image);
    EXPECT_EQ(s.nonFinite, 0u);
    EXPECT_GT(s.litFraction, kMinLitFraction);
}

TEST(CliRender, WritesTheReferenceAndADebugView) {
    TempDir dir;
    const auto reference = dir / "reference.png";
    CliResult r = runBurnish("render --sample-size 32 --size 32x32 --reference 4 --out " +
                             shellQuote(reference.string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("reference, 4 samples"), std::string::npos) << r.out;
    auto image = burnish::readImage(reference);
    ASSERT_TRUE(image.ok()) << image.error();
    EXPECT_GT(stats(*image).litFraction, kMinLitFraction);

    const auto normals = dir / "normals.png";
    r = runBurnish("render --sample-size 32 --size 32x32 --debug normals --out " +
                   shellQuote(normals.string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    image = burnish::readImage(normals);
    ASSERT_TRUE(image.ok()) << image.error();
    EXPECT_GT(stats(*image).litFraction, kMinLitFraction);
}

TEST(CliRender, ExplainListsTheProgramsFeatures) {
    const CliResult r = runBurnish("render --sample-size 16 --method lean --ndf ggx --explain");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("method: lean"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ndf: ggx"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("METHOD METHOD_LEAN"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("HAS_NORMAL_MAP"), std::string::npos) << r.out;
    // A metal compiles the diffuse code out: the define is gone.
    const CliResult metal = runBurnish("render --sample-size 16 --material gold --explain");
    ASSERT_EQ(metal.exitCode, 0) << metal.err;
    EXPECT_NE(metal.out.find("metal only: yes"), std::string::npos) << metal.out;
    EXPECT_EQ(metal.out.find("HAS_DIFFUSE"), std::string::npos) << metal.out;
}

TEST(CliRender, BadInputsGiveOneErrorLine) {
    TempDir dir;
    const std::string out = " --sample-size 16 --out " + shellQuote((dir / "x.png").string());
    expectOneErrorLine(runBurnish("render --mesh cube" + out), "--mesh");
    expectOneErrorLine(runBurnish("render --mesh " + shellQuote((dir / "missing.obj").string()) + out),
                       "missing.obj");
    expectOneErrorLine(runBurnish("render --method shiny" + out), "--method");
    expectOneErrorLine(runBurnish("render --size 0x16" + out), "--size");
    expectOneErrorLine(runBurnish("render --size big" + out), "--size");
    expectOneErrorLine(runBurnish("render --debug sparkles" + out), "--debug");
    expectOneErrorLine(runBurnish("render --out " + shellQuote((dir / "x.jpg").string())), ".png or .exr");
    expectOneErrorLine(runBurnish("render"), "--out");
    expectOneErrorLine(runBurnish("render --power 100 --gloss 0.5" + out), "--gloss");
    expectOneErrorLine(
        runBurnish("render --out " + shellQuote((dir / "no" / "x.png").string()) + " --size 8x8"), "x.png");
    EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

TEST(CliRender, SequencePrintsTheShimmerTable) {
    TempDir dir;
    const auto frames = dir / "frames";
    const CliResult r = runBurnish("render --sample bumpy --sample-size 32 --sequence 3 --size 32x32 "
                                   "--reference 2 --method naive --frames-dir " +
                                   shellQuote(frames.string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("| frames | naive | reference |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| 0-1 |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| 1-2 |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| mean |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ratio (method / reference):"), std::string::npos) << r.out;
    // HDR frames (the shimmer's default space) as EXR.
    for (const char* f : {"frame-000-method.exr", "frame-000-reference.exr", "frame-002-method.exr",
                          "frame-002-reference.exr"})
        EXPECT_TRUE(std::filesystem::exists(frames / f)) << f;
}

TEST(CliRender, SequenceJsonParses) {
    constexpr int kFrames = 4;
    const CliResult r = runBurnish("render --sample-size 32 --sequence " + std::to_string(kFrames) +
                                   " --size 32x32 --reference 2 --orbit-degrees 2 --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << r.out;
    EXPECT_EQ(j.at("frames").get<int>(), kFrames);
    EXPECT_EQ(j.at("method").get<std::string>(), "variance-to-gloss");
    EXPECT_EQ(j.at("method_deltas").size(), size_t(kFrames - 1));
    EXPECT_EQ(j.at("reference_deltas").size(), size_t(kFrames - 1));
    EXPECT_GT(j.at("measured_pixels").get<int>(), 0);
    for (const char* key : {"method_mean", "reference_mean", "ratio"}) {
        const double v = j.at(key).get<double>();
        EXPECT_TRUE(std::isfinite(v) && v >= 0.0) << key << " = " << v;
    }
    // A 2° step turns the lit sphere: both sequences change.
    EXPECT_GT(j.at("method_mean").get<double>(), 0.0);
    EXPECT_GT(j.at("reference_mean").get<double>(), 0.0);
}

TEST(CliRender, ComparePrintsTheScreenErrorAgainstTheReference) {
    const std::string scene = "render --sample bumpy --sample-size 32 --size 32x32 --compare 4 ";
    const CliResult j = runBurnish(scene + "--method mixture --lobes 2 --kernel box --json");
    ASSERT_EQ(j.exitCode, 0) << j.err;
    const auto parsed = nlohmann::json::parse(j.out, nullptr, false);
    ASSERT_FALSE(parsed.is_discarded()) << j.out;
    EXPECT_EQ(parsed.at("method").get<std::string>(), "mixture-k2");
    EXPECT_EQ(parsed.at("reference_samples").get<int>(), 4);
    EXPECT_GT(parsed.at("measured_pixels").get<int>(), 0);
    for (const char* key : {"relative_l1", "energy_ratio", "reference_noise_l1"}) {
        const double v = parsed.at(key).get<double>();
        EXPECT_TRUE(std::isfinite(v) && v >= 0.0) << key << " = " << v;
    }
    EXPECT_GT(parsed.at("energy_ratio").get<double>(), 0.0);
    EXPECT_EQ(parsed.at("mixture_filtering").get<std::string>(), "moments");
    EXPECT_TRUE(parsed.at("mixture_samples").is_null());
    // Filtered after shading: recorded with its passes; LEAN (no mixture) records neither.
    const CliResult st =
        runBurnish(scene + "--method mixture --mixture-filtering stochastic --mixture-samples 3 --json");
    ASSERT_EQ(st.exitCode, 0) << st.err;
    const auto stochastic = nlohmann::json::parse(st.out, nullptr, false);
    ASSERT_FALSE(stochastic.is_discarded()) << st.out;
    EXPECT_EQ(stochastic.at("mixture_filtering").get<std::string>(), "stochastic");
    EXPECT_EQ(stochastic.at("mixture_samples").get<int>(), 3);
    const CliResult leanJson = runBurnish(scene + "--method lean --json");
    ASSERT_EQ(leanJson.exitCode, 0) << leanJson.err;
    const auto lean = nlohmann::json::parse(leanJson.out, nullptr, false);
    ASSERT_FALSE(lean.is_discarded()) << leanJson.out;
    EXPECT_TRUE(lean.at("mixture_filtering").is_null());
    const CliResult text = runBurnish(scene + "--method lean");
    ASSERT_EQ(text.exitCode, 0) << text.err;
    EXPECT_NE(text.out.find("relative L1 "), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("energy ratio "), std::string::npos) << text.out;
    // It renders its own images: --out and --reference are mistakes, one line each.
    TempDir dir;
    expectOneErrorLine(runBurnish(scene + "--out " + shellQuote((dir / "x.png").string())), "--compare");
    expectOneErrorLine(runBurnish(scene + "--reference 8"), "--compare");
    expectOneErrorLine(runBurnish(scene + "--sequence 3"), "--compare");
    expectOneErrorLine(runBurnish("render --sample-size 32 --size 32x32 --compare 1"), "--compare");
    expectOneErrorLine(runBurnish(scene + "--kernel wide"), "--kernel");
    EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

TEST(CliRender, BenchPrintsFiguresPerMethod) {
    const CliResult r = runBurnish("render --sample-size 16 --bench --size 32x32 --bench-frames 1 --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << r.out;
    ASSERT_EQ(j.at("methods").size(), burnish::allMethods().size());
    for (const auto& m : j.at("methods"))
        EXPECT_GT(m.at("median_ms").get<double>(), 0.0) << m.dump();
    EXPECT_GT(j.at("simple_scene").at("specialised_ms").get<double>(), 0.0);
    EXPECT_GT(j.at("simple_scene").at("ubershader_ms").get<double>(), 0.0);
    EXPECT_GT(j.at("peak_rss_mib").get<double>(), 0.0);
}

} // namespace
