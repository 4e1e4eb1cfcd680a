// End to end: `burnish bake` run as a process on a small synthetic normal map written by the test.
#include <burnish/core/atomic_file.h>
#include <burnish/core/presets.h>

#include "temp_dir.h"

#include "cli_run.h"
#include <OpenImageIO/imageio.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace {

namespace fs = std::filesystem;
using burnish::test::TempDir;

using RunResult = burnish::test::CliResult;
using burnish::test::runBurnish;

std::string quote(const std::string& s) {
    return burnish::test::shellQuote(s);
}
int countLines(const std::string& s) {
    return burnish::test::lineCount(s);
}

// A 32x32 8-bit RGB tangent-space normal map with bumps (unsigned encoding, +Y green).
void writeNormalMap(const fs::path& path, int size = 32) {
    std::vector<unsigned char> pixels(size_t(size) * size_t(size) * 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float nx = 0.4f * std::sin(6.2831853f * 3.0f * float(x) / float(size));
            const float ny = 0.3f * std::cos(6.2831853f * 2.0f * float(y) / float(size));
            const float len = std::sqrt(nx * nx + ny * ny + 1.0f);
            const float n[3] = {nx / len, ny / len, 1.0f / len};
            for (int c = 0; c < 3; ++c)
                pixels[(size_t(y) * size_t(size) + size_t(x)) * 3 + size_t(c)] =
                    static_cast<unsigned char>(std::lround((0.5f * n[c] + 0.5f) * 255.0f));
        }
    auto out = OIIO::ImageOutput::create(path.string());
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path.string(), OIIO::ImageSpec(size, size, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
    ASSERT_TRUE(out->close());
}

// Random colours: not a plausible normal map (many texels point below the surface).
void writeNoise(const fs::path& path) {
    std::vector<unsigned char> pixels(32 * 32 * 3);
    unsigned state = 12345u;
    for (auto& p : pixels) {
        state = state * 1664525u + 1013904223u; // LCG: a fixed, portable sequence
        p = static_cast<unsigned char>(state >> 24);
    }
    auto out = OIIO::ImageOutput::create(path.string());
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path.string(), OIIO::ImageSpec(32, 32, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
    ASSERT_TRUE(out->close());
}

std::vector<std::string> listFolder(const fs::path& dir) {
    std::vector<std::string> names;
    if (!fs::exists(dir)) return names;
    for (const auto& e : fs::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

// 32x32 down to 1x1.
constexpr int kMipCount = 6;

TEST(CliBake, EveryPresetWritesItsFiles) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    for (const auto& preset : burnish::builtinPresets()) {
        SCOPED_TRACE(preset.name);
        const fs::path out = dir / preset.name;
        const auto r = runBurnish("bake " + quote((dir / "bumps.png").string()) + " --preset " + preset.name +
                                  " --out " + quote(out.string()));
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_TRUE(r.err.empty()) << r.err;
        const std::string ext(burnish::exportFormatExtension(preset.format));
        const bool perMip = preset.format == burnish::ExportFormat::Png8 ||
                            preset.format == burnish::ExportFormat::Png16 ||
                            preset.format == burnish::ExportFormat::Tga;
        std::vector<std::string> expected{"bake.json"};
        for (const auto& f : preset.files) {
            expected.push_back("bumps_" + f.name + "." + ext);
            if (perMip)
                for (int k = 1; k < kMipCount; ++k)
                    expected.push_back("bumps_" + f.name + "_mip" + std::to_string(k) + "." + ext);
        }
        std::sort(expected.begin(), expected.end());
        EXPECT_EQ(listFolder(out), expected);
        const auto manifest = nlohmann::json::parse(burnish::readFile(out / "bake.json").value());
        EXPECT_EQ(manifest["preset"]["name"], preset.name);
        EXPECT_EQ(manifest["method"], std::string(burnish::methodName(preset.method)));
        EXPECT_EQ(manifest["stats"]["mipCount"], kMipCount);
    }
}

TEST(CliBake, UnknownNamesAreOneLineListingTheKnownOnes) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    const std::string in = quote((dir / "bumps.png").string());
    const std::string out = " --out " + quote((dir / "out").string());
    struct Case {
        std::string args;
        std::string expected;
    };
    for (const Case& c :
         {Case{"--preset halo", "unknown preset 'halo' (known: blackops"},
          Case{"--preset gltf --method magic", "unknown method 'magic' (known: naive"},
          Case{"--preset gltf --format webp", "unknown format 'webp' (known: png8"},
          Case{"--preset gltf --format dds --compression bc7", "unknown DDS compression 'bc7'"},
          Case{"--preset gltf --compression bc4", "applies to --format dds only"},
          Case{"--preset lean --method vmf", "methods that fit: lean"},
          Case{"--preset unreal --metallic 1", "stores no metallic channel"},
          Case{"--preset gltf --kernel sinc", "--kernel 'sinc' is not known (known: box, tent, gaussian)"},
          Case{"--preset lean --format png8", "need 16-bit or float storage"}}) {
        SCOPED_TRACE(c.args);
        const auto r = runBurnish("bake " + in + out + " " + c.args);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(countLines(r.err), 1) << r.err;
        EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
    }
    // Nothing was written by any of the failed runs.
    EXPECT_TRUE(listFolder(dir / "out").empty());
}

TEST(CliBake, UnreadableOrImplausibleInputFails) {
    TempDir dir;
    auto r = runBurnish("bake " + quote((dir / "missing.png").string()) + " --preset gltf --out " +
                        quote((dir / "o").string()));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(countLines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("missing.png"), std::string::npos) << r.err;

    writeNoise(dir / "noise.png");
    r = runBurnish("bake " + quote((dir / "noise.png").string()) + " --preset gltf --out " +
                   quote((dir / "o").string()));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(countLines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("noise.png"), std::string::npos) << r.err;
    EXPECT_TRUE(listFolder(dir / "o").empty());

    r = runBurnish("bake " + quote((dir / "noise.png").string()) +
                   " --preset gltf --allow-implausible --out " + quote((dir / "o").string()));
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir / "o" / "bake.json"));
}

TEST(CliBake, ExistingOutputsNeedForce) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    const std::string args = "bake " + quote((dir / "bumps.png").string()) + " --preset godot --out " +
                             quote((dir / "o").string());
    ASSERT_EQ(runBurnish(args).exitCode, 0);
    const auto before = burnish::readFile(dir / "o" / "bumps_roughness.png").value();
    const auto again = runBurnish(args + " --power 20");
    EXPECT_NE(again.exitCode, 0);
    EXPECT_EQ(countLines(again.err), 1) << again.err;
    EXPECT_NE(again.err.find("--force"), std::string::npos) << again.err;
    EXPECT_EQ(burnish::readFile(dir / "o" / "bumps_roughness.png").value(), before);
    const auto forced = runBurnish(args + " --power 20 --force");
    EXPECT_EQ(forced.exitCode, 0) << forced.err;
    EXPECT_NE(burnish::readFile(dir / "o" / "bumps_roughness.png").value(), before);
}

TEST(CliBake, SameInputsGiveSameBytes) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    for (const char* preset : {"exp2", "lean", "unity"}) {
        for (const char* out : {"a", "b"}) {
            const auto r = runBurnish("bake " + quote((dir / "bumps.png").string()) + " --preset " + preset +
                                      " --out " + quote((dir / out / preset).string()));
            ASSERT_EQ(r.exitCode, 0) << r.err;
        }
        for (const auto& name : listFolder(dir / "a" / preset))
            EXPECT_EQ(burnish::readFile(dir / "a" / preset / name).value(),
                      burnish::readFile(dir / "b" / preset / name).value())
                << preset << "/" << name;
    }
}

TEST(CliBake, JsonSummaryParses) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    const auto r = runBurnish("bake " + quote((dir / "bumps.png").string()) +
                              " --preset gltf --metallic 1 --format exr-half --json --out " +
                              quote((dir / "o").string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["jobs"].size(), 1u);
    const auto& job = j["jobs"][0];
    EXPECT_EQ(job["preset"], "gltf");
    EXPECT_EQ(job["format"], "exr-half");
    EXPECT_EQ(job["mipCount"], kMipCount);
    ASSERT_EQ(job["files"].size(), 2u);
    for (const auto& f : job["files"])
        EXPECT_TRUE(fs::exists(f.get<std::string>())) << f;
    const auto manifest =
        nlohmann::json::parse(burnish::readFile(job["bakeJson"].get<std::string>()).value());
    EXPECT_EQ(manifest["files"][1]["channels"][2]["value"], 1.0); // B = metallic
}

TEST(CliBake, ReportWritesTheGroundTruthEvaluationBesideTheTextures) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    const auto r =
        runBurnish("bake " + quote((dir / "bumps.png").string()) +
                   " --preset godot --power 300 --report --json --out " + quote((dir / "o").string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto job = nlohmann::json::parse(r.out)["jobs"][0];
    ASSERT_TRUE(job.contains("report"));
    const auto evaluation =
        nlohmann::json::parse(burnish::readFile(dir / "o" / "report" / "evaluate.json").value());
    EXPECT_EQ(evaluation["base_powers"][0], 300.0); // the bake's power
    EXPECT_EQ(evaluation["costs"].size(), 7u);      // every method, not only the baked one
    EXPECT_TRUE(fs::exists(dir / "o" / "report" / "evaluate-error-per-mip.png"));
}

TEST(CliBake, ManifestRunsEveryJob) {
    TempDir dir;
    writeNormalMap(dir / "one.png");
    writeNormalMap(dir / "two.png", 16);
    {
        std::ofstream m(dir / "jobs.json");
        m << R"({"version": 1, "jobs": [
              {"input": "one.png", "out": "out1", "preset": "unity", "metallic": 0.5},
              {"input": "two.png", "out": "out2", "preset": "blackops", "method": "vmf", "power": 64}
            ]})";
    }
    const auto r = runBurnish("bake --manifest " + quote((dir / "jobs.json").string()) + " --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["jobs"].size(), 2u);
    EXPECT_EQ(j["jobs"][1]["method"], "vmf");
    EXPECT_TRUE(fs::exists(dir / "out1" / "one_metallic.png"));
    EXPECT_TRUE(fs::exists(dir / "out2" / "two_gloss.dds"));
    const auto bake2 = nlohmann::json::parse(burnish::readFile(dir / "out2" / "bake.json").value());
    EXPECT_EQ(bake2["options"]["power"], 64.0);
}

TEST(CliBake, BadManifestEntryFailsBeforeAnythingIsWritten) {
    TempDir dir;
    writeNormalMap(dir / "one.png");
    {
        std::ofstream m(dir / "jobs.json");
        m << R"({"jobs": [
              {"input": "one.png", "out": "out1", "preset": "unity"},
              {"input": "one.png", "out": "out2", "preset": "quake"}
            ]})";
    }
    auto r = runBurnish("bake --manifest " + quote((dir / "jobs.json").string()));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(countLines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("job 2"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("unknown preset 'quake'"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out1"));

    {
        std::ofstream m(dir / "typo.json");
        m << R"({"jobs": [{"input": "one.png", "out": "o", "preset": "unity", "metalic": 1}]})";
    }
    r = runBurnish("bake --manifest " + quote((dir / "typo.json").string()));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("unknown field 'metalic'"), std::string::npos) << r.err;
}

TEST(CliBake, HelpListsPresetsMethodsAndFormats) {
    const auto r = runBurnish("bake --help");
    EXPECT_EQ(r.exitCode, 0);
    for (const auto& name : burnish::builtinPresetNames())
        EXPECT_NE(r.out.find(name), std::string::npos) << name;
    for (const char* word :
         {"variance-to-gloss", "vmf", "exr-half", "tiff-float", "bc5", "--manifest", "--allow-8bit",
          "--green", "--layout", "--kernel", "--border", "--compression", "--gloss", "--power"})
        EXPECT_NE(r.out.find(word), std::string::npos) << word;
}

} // namespace
