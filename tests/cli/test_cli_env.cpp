// End-to-end tests of `burnish env`: the procedural studio and an equirect EXR in, DDS/EXR/SH/JSON
// out, the brute-force report, normalization, and one-line errors.
#include "cli_run.h"
#include "temp_dir.h"

#include <burnish/core/env/cube.h>
#include <burnish/core/env/cube_dds.h>
#include <burnish/core/io/image.h>
#include <burnish/core/shading/color.h>
#include <burnish/core/util/files.h>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using burnish::test::runBurnish;
using burnish::test::shellQuote;
using burnish::test::TempDir;

// Half keeps 11 significant bits (relative rounding 2^-11), plus the prefilter's float sums.
constexpr double kHalfRelative = 1.0 / 1024.0;

/// A constant equirectangular float EXR written with OpenImageIO.
void writeConstantEquirect(const fs::path& path, float value) {
    const int w = 32, h = 16;
    std::vector<float> pixels(size_t(w * h * 3), value);
    auto out = OIIO::ImageOutput::create(path.string());
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::FLOAT);
    ASSERT_TRUE(out->open(path.string(), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()));
    ASSERT_TRUE(out->close());
}

TEST(CliEnv, StudioWritesEveryFileAndJson) {
    TempDir dir;
    const auto r = runBurnish("env --out " + shellQuote((dir / "out").string()) + " --face-size 16 --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("faceSize"), 16);
    ASSERT_EQ(j.at("mips").size(), 5u); // 16, 8, 4, 2, 1
    EXPECT_EQ(j.at("mips")[0].at("power"), 2048.0);
    EXPECT_EQ(j.at("mips")[1].at("power"), 512.0);
    for (const char* f : {"radiance.dds", "irradiance.dds", "sh.json", "env.json", "radiance_m0_px.exr",
                          "radiance_m4_nz.exr", "irradiance_py.exr"})
        EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
    const auto sh = nlohmann::json::parse(burnish::readFile(dir / "out" / "sh.json").value());
    EXPECT_EQ(sh.at("coefficients").size(), 9u);
    const auto dds = burnish::decodeCubeDds(burnish::readFile(dir / "out" / "radiance.dds").value());
    ASSERT_TRUE(dds) << dds.error();
    EXPECT_EQ(dds->mipCount(), 5);
}

TEST(CliEnv, ConstantEquirectGivesConstantRadianceAndNormalizesToOne) {
    TempDir dir;
    const fs::path in = dir / "sky.exr";
    writeConstantEquirect(in, 2.5f);
    const std::string out = (dir / "out").string();
    auto r = runBurnish("env " + shellQuote(in.string()) + " --out " + shellQuote(out) +
                        " --face-size 8 --format dds --lobe blinn-phong --gloss-encoding exp2");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "radiance_m0_px.exr")); // dds only
    auto cube = burnish::decodeCubeDds(burnish::readFile(dir / "out" / "radiance.dds").value());
    ASSERT_TRUE(cube) << cube.error();
    for (const auto& level : cube->levels)
        for (const auto& face : level.faces)
            for (float v : face)
                ASSERT_NEAR(v, 2.5, kHalfRelative * 2.5);
    // --normalize-diffuse divides by the average diffuse lighting (2.5): everything becomes 1.
    r = runBurnish("env " + shellQuote(in.string()) + " --out " + shellQuote(out) +
                   " --face-size 8 --format dds --normalize-diffuse --force");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    cube = burnish::decodeCubeDds(burnish::readFile(dir / "out" / "irradiance.dds").value());
    ASSERT_TRUE(cube);
    for (const auto& face : cube->levels[0].faces)
        for (float v : face)
            ASSERT_NEAR(v, 1.0, kHalfRelative);
}

TEST(CliEnv, ReportComparesEveryMipWithBruteForce) {
    // The prefilter at texel centres is within 1% of the brute-force integral (measured below 0.4%).
    constexpr double kPrefilterRms = 0.01;
    TempDir dir;
    const auto r = runBurnish("env --out " + shellQuote(dir.path().string()) +
                              " --face-size 16 --report --samples 32 --directions 16 --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto report = nlohmann::json::parse(burnish::readFile(dir / "report.json").value());
    ASSERT_EQ(report.at("mips").size(), 5u);
    for (const auto& row : report.at("mips")) {
        EXPECT_LT(row.at("relativeRms").get<double>(), kPrefilterRms);
        EXPECT_EQ(row.at("fisSamples"), 32);
        EXPECT_GE(row.at("referenceSeconds").get<double>(), 0.0);
    }
    EXPECT_TRUE(fs::exists(dir / "report.md"));
}

TEST(CliEnv, BadInputFailsWithOneLine) {
    TempDir dir;
    for (const std::string& args :
         {"env --out " + shellQuote(dir.path().string()) + " --face-size 12",
          "env /nonexistent/sky.exr --out " + shellQuote(dir.path().string()),
          "env --out " + shellQuote(dir.path().string()) + " --gloss-encoding nope",
          "env --out " + shellQuote(dir.path().string()) + " --face-size 8 --mips 9"}) {
        const auto r = runBurnish(args);
        EXPECT_NE(r.exitCode, 0) << args;
        EXPECT_EQ(burnish::test::lineCount(r.err), 1) << args << ": " << r.err;
        EXPECT_EQ(r.err.rfind("burnish: error:", 0), 0u) << r.err;
    }
}

// What is checked before any work: a bad --irradiance-size, --top-power or --power-drop is the
// error even when the input does not exist (it was found only after the whole prefilter ran, and
// --top-power 0 ran 45 times longer than the default).
TEST(CliEnv, OptionsAreCheckedBeforeAnyWork) {
    TempDir dir;
    for (const auto& [args, needle] : std::vector<std::pair<std::string, std::string>>{
             {"--irradiance-size 3", "--irradiance-size 3"},
             {"--irradiance-size 8192", "--irradiance-size 8192"},
             {"--top-power 0", "--top-power 0"},
             {"--top-power 0.5", "--top-power 0.5"},
             {"--power-drop 2", "--power-drop 2"},
             {"--power-drop 0", "--power-drop 0"}}) {
        const auto r =
            runBurnish("env /nonexistent/sky.exr --out " + shellQuote(dir.path().string()) + " " + args);
        EXPECT_NE(r.exitCode, 0) << args;
        EXPECT_EQ(burnish::test::lineCount(r.err), 1) << args << ": " << r.err;
        EXPECT_NE(r.err.find(needle), std::string::npos) << args << ": " << r.err;
    }
}

// Sources that are not plain radiance are said so: an 8-bit PNG is decoded from sRGB to linear
// with a warning; NaN, infinite and negative texels are replaced by 0 and values above half
// float's largest are counted, each with a warning on stderr and in the JSON summary; the outputs
// stay finite and within half float's range.
TEST(CliEnv, SuspectSourcesAreReportedAndConverted) {
    TempDir dir;
    const int w = 32, h = 16;
    std::vector<float> grey(size_t(w * h * 3), 0.5f);
    ASSERT_TRUE(
        burnish::writeImageAtomic(dir / "ldr.png", w, h, 3, grey, {burnish::StoredType::UInt8, {}, {}}));
    const auto ldr = runBurnish("env " + shellQuote((dir / "ldr.png").string()) +
                                " --face-size 8 --json --out " + shellQuote((dir / "ldr").string()));
    ASSERT_EQ(ldr.exitCode, 0) << ldr.err;
    EXPECT_NE(ldr.err.find("burnish: warning:"), std::string::npos) << ldr.err;
    EXPECT_NE(ldr.err.find("sRGB"), std::string::npos) << ldr.err;
    const auto ldrJson = nlohmann::json::parse(ldr.out);
    EXPECT_TRUE(ldrJson["srgbDecoded"].get<bool>());
    // 0.5 in 8 bits is code 128: sRGB-decoded radiance 0.2158.
    const auto face = burnish::readImage(dir / "ldr" / "irradiance_px.exr");
    ASSERT_TRUE(face) << face.error();
    EXPECT_NEAR(face->pixels[0], burnish::srgb8ToLinear(128), 0.01) << "irradiance of a constant sky";

    std::vector<float> wild(size_t(w * h * 3), 1.0f);
    wild[0] = std::numeric_limits<float>::quiet_NaN();
    wild[3] = -std::numeric_limits<float>::infinity();
    wild[6] = -2.0f;
    wild[300] = 1e30f;
    ASSERT_TRUE(
        burnish::writeImageAtomic(dir / "wild.exr", w, h, 3, wild, {burnish::StoredType::Float, {}, {}}));
    const auto r = runBurnish("env " + shellQuote((dir / "wild.exr").string()) +
                              " --face-size 8 --json --out " + shellQuote((dir / "wild").string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("3 NaN, infinite or negative values were replaced by 0"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("exceed 65504"), std::string::npos) << r.err;
    const auto json = nlohmann::json::parse(r.out);
    EXPECT_EQ(json["replacedTexels"], 3);
    EXPECT_GT(json["aboveHalfValues"].get<int>(), 0);
    EXPECT_FALSE(json["srgbDecoded"].get<bool>());
    EXPECT_EQ(json["warnings"].size(), 2u);
    for (const auto& e : fs::directory_iterator(dir / "wild")) {
        if (e.path().extension() != ".exr") continue;
        const auto image = burnish::readImage(e.path());
        ASSERT_TRUE(image) << image.error();
        for (float v : image->pixels)
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 65504.0f) << e.path() << " " << v;
    }
}

} // namespace
