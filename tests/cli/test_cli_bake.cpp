// End to end: `burnish bake` run as a process on a small synthetic normal map written by the test.
#include <burnish/core/bake/presets.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/util/files.h>

#include "temp_dir.h"

#include "cli_run.h"
#include "normal_map_files.h"
#include <OpenImageIO/imageio.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <thread>
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
    burnish::test::writeSineNormalMap(path, size);
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
    EXPECT_EQ(evaluation["brdf"], "ggx");           // godot's engine shades GGX
    EXPECT_EQ(job["method"], "fitted");             // the roughness presets' default
    EXPECT_EQ(evaluation["costs"].size(), 7u);      // every GGX method (godot), the mixture's GGX form too
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
        m << R"({"version": 1, "jobs": [
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
        m << R"({"version": 1, "jobs": [{"input": "one.png", "out": "o", "preset": "unity", "metalic": 1}]})";
    }
    r = runBurnish("bake --manifest " + quote((dir / "typo.json").string()));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("unknown field 'metalic'"), std::string::npos) << r.err;
}

// Every job of a manifest is checked before the first writes anything: two jobs writing one file,
// a job whose input is not a readable image, a NUL in a string, an output outside --out-root, an
// empty --out-root (which would hold every folder).
TEST(CliBake, ManifestJobsAreAllCheckedBeforeTheFirstRuns) {
    TempDir dir;
    writeNormalMap(dir / "one.png");
    std::ofstream(dir / "garbage.png") << "\x89PNG\r\n\x1a\n this is no image";
    auto write = [&](const char* name, const std::string& text) { std::ofstream(dir / name) << text; };
    write("clash.json", R"({"version": 1, "jobs": [{"input": "one.png", "out": "out1", "preset": "godot"},
                                   {"input": "one.png", "out": "out1", "preset": "gltf"}]})");
    write("garbage.json", R"({"version": 1, "jobs": [{"input": "one.png", "out": "out1", "preset": "godot"},
                                     {"input": "garbage.png", "out": "out2", "preset": "godot"}]})");
    write("missing.json", R"({"version": 1, "jobs": [{"input": "one.png", "out": "out1", "preset": "godot"},
                                     {"input": "gone.png", "out": "out2", "preset": "godot"}]})");
    write("nul.json",
          R"({"version": 1, "jobs": [{"input": "one.png", "out": "out1\u0000/etc", "preset": "godot"}]})");
    // Two jobs writing one set through a linked folder (issue 45, point 5: both ran, the second
    // replacing the first).
    fs::create_directories(dir / "real");
    fs::create_directory_symlink(dir / "real", dir / "link");
    write("linked.json", R"({"version": 1, "jobs": [{"input": "one.png", "out": "real/x", "preset": "godot"},
                                   {"input": "one.png", "out": "link/x", "preset": "godot", "force": true}]})");
    write("away.json", R"({"version": 1, "jobs": [{"input": "one.png", "out": "inside/a", "preset": "godot"},
                                  {"input": "one.png", "out": "../away", "preset": "godot"}]})");
    for (const auto& [manifest, needle] : std::vector<std::pair<std::string, std::string>>{
             {"clash.json", "which job 1 writes too"},
             {"linked.json", "which job 1 writes too"},
             {"garbage.json", "garbage.png"},
             {"missing.json", "does not exist"},
             {"nul.json", "NUL"},
             {"away.json --out-root " + quote((dir / "inside").string()), "outside --out-root"},
             {"away.json --out-root ''", "--out-root: an empty value"}}) {
        SCOPED_TRACE(manifest);
        const auto r =
            runBurnish("bake --manifest " + quote((dir / manifest.substr(0, manifest.find(' '))).string()) +
                       (manifest.find(' ') == std::string::npos ? "" : manifest.substr(manifest.find(' '))));
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(countLines(r.err), 1) << r.err;
        EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir / "out1"));
        EXPECT_FALSE(fs::exists(dir / "real" / "x"));
        EXPECT_FALSE(fs::exists(dir / "inside"));
        EXPECT_FALSE(fs::exists(dir.path().parent_path() / "away"));
    }
    // Inside the root, both jobs run; a single job is held to --out-root too.
    write("inside.json",
          R"({"version": 1, "jobs": [{"input": "one.png", "out": "inside/a", "preset": "godot"},
                                    {"input": "one.png", "out": "inside/b/../c", "preset": "godot"}]})");
    auto ok = runBurnish("bake --manifest " + quote((dir / "inside.json").string()) + " --out-root " +
                         quote((dir / "inside").string()));
    EXPECT_EQ(ok.exitCode, 0) << ok.err;
    EXPECT_TRUE(fs::exists(dir / "inside" / "c" / "bake.json"));
    auto single =
        runBurnish("bake " + quote((dir / "one.png").string()) + " --preset godot --out " +
                   quote((dir / "elsewhere").string()) + " --out-root " + quote((dir / "inside").string()));
    EXPECT_NE(single.exitCode, 0);
    EXPECT_NE(single.err.find("outside --out-root"), std::string::npos) << single.err;
    EXPECT_FALSE(fs::exists(dir / "elsewhere"));
}

// An empty value is an error in one line, never the option's default, for every command's options (the
// four the reliability sweep found exiting 0, and --out).
TEST(CliBake, EmptyValuesAreErrorsNotTheDefault) {
    TempDir dir;
    writeNormalMap(dir / "one.png");
    const std::string map = quote((dir / "one.png").string()), out = quote((dir / "out").string());
    for (const auto& [args, option] : std::vector<std::pair<std::string, std::string>>{
             {"bake " + map + " --preset gltf --mips '' --out " + out, "--mips"},
             {"bake " + map + " --preset gltf --gloss '' --out " + out, "--gloss"},
             {"render " + map + " --yaw '' --out " + quote((dir / "out" / "r.png").string()), "--yaw"},
             {"env " + map + " --mips '' --out " + out, "--mips"},
             {"bake " + map + " --preset gltf --out ''", "--out"}}) {
        SCOPED_TRACE(args);
        const auto r = runBurnish(args);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(countLines(r.err), 1) << r.err;
        EXPECT_NE(r.err.find(option + ": an empty value"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir / "out"));
    }
}

// Every level of a file as OpenImageIO decodes it (float values, bit-exact for float storage).
std::vector<std::vector<float>> readLevels(const fs::path& path) {
    std::vector<std::vector<float>> levels;
    // The fourth channel is data (variance, gloss): read it unassociated, as an engine does.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path.string(), &config);
    if (!in) return levels;
    for (int k = 0; in->seek_subimage(0, k); ++k) {
        const OIIO::ImageSpec& s = in->spec();
        std::vector<float> v(size_t(s.width) * size_t(s.height) * size_t(s.nchannels));
        if (!in->read_image(0, k, 0, s.nchannels, OIIO::TypeDesc::FLOAT, v.data())) break;
        levels.push_back(std::move(v));
    }
    return levels;
}

// The bytes after a DDS file's header (magic + 124-byte header, + 20 for a DX10 extension).
std::string ddsPayload(const std::string& bytes) {
    constexpr size_t kHeader = 4 + 124;
    constexpr size_t kFourCcOffset = 84;
    constexpr size_t kDx10Header = 20;
    if (bytes.size() < kHeader) return {};
    const bool dx10 = bytes.compare(kFourCcOffset, 4, "DX10") == 0;
    return bytes.substr(kHeader + (dx10 ? kDx10Header : 0));
}

TEST(CliBake, MipsWritesTheFirstLevelsOfAFullBake) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    constexpr int kShort = 3;
    // png16: one file per level; exr-half: one MIP-mapped file; dds: the chain in one file (bc5, bc4).
    for (const char* format : {"png16", "exr-half", "dds"}) {
        SCOPED_TRACE(format);
        const std::string common =
            "bake " + quote((dir / "bumps.png").string()) + " --preset godot --format " + format + " --out ";
        const fs::path full = dir / (std::string(format) + "-full");
        const fs::path part = dir / (std::string(format) + "-3");
        ASSERT_EQ(runBurnish(common + quote(full.string())).exitCode, 0);
        const auto r = runBurnish(common + quote(part.string()) + " --mips " + std::to_string(kShort));
        ASSERT_EQ(r.exitCode, 0) << r.err;
        const auto manifest = nlohmann::json::parse(burnish::readFile(part / "bake.json").value());
        EXPECT_EQ(manifest["stats"]["mipCount"], kShort);
        EXPECT_EQ(manifest["options"]["mips"], kShort);
        for (const auto& file : manifest["files"]) {
            const std::string name = file["name"];
            EXPECT_EQ(file["mips"].size(), size_t(kShort)) << name;
            const auto& paths = file["paths"];
            if (std::string(format) == "png16") {
                ASSERT_EQ(paths.size(), size_t(kShort)) << name;
                for (const auto& p : paths) // level k of the short bake is level k of the full one
                    EXPECT_EQ(burnish::readFile(part / p.get<std::string>()).value(),
                              burnish::readFile(full / p.get<std::string>()).value())
                        << p;
                EXPECT_TRUE(fs::exists(full / ("bumps_" + name + "_mip3.png")));
                EXPECT_FALSE(fs::exists(part / ("bumps_" + name + "_mip3.png")));
                continue;
            }
            ASSERT_EQ(paths.size(), 1u);
            const std::string file0 = paths[0];
            const auto shortLevels = readLevels(part / file0);
            const auto fullLevels = readLevels(full / file0);
            ASSERT_EQ(shortLevels.size(), size_t(kShort)) << file0;
            ASSERT_EQ(fullLevels.size(), size_t(kMipCount)) << file0;
            for (int k = 0; k < kShort; ++k)
                EXPECT_EQ(shortLevels[size_t(k)], fullLevels[size_t(k)]) << file0 << " level " << k;
            if (std::string(format) == "dds") {
                // Same compressed blocks: the short file's data is a prefix of the full file's.
                const std::string a = ddsPayload(burnish::readFile(part / file0).value());
                const std::string b = ddsPayload(burnish::readFile(full / file0).value());
                ASSERT_FALSE(a.empty());
                ASSERT_LT(a.size(), b.size());
                EXPECT_EQ(a, b.substr(0, a.size())) << file0;
            }
        }
    }
}

TEST(CliBake, MipsBeyondTheChainAreClampedWithANote) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    const std::string base = "bake " + quote((dir / "bumps.png").string()) + " --preset godot --out ";
    const auto r = runBurnish(base + quote((dir / "o").string()) + " --mips 40 --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto job = nlohmann::json::parse(r.out)["jobs"][0];
    EXPECT_EQ(job["mipCount"], kMipCount);
    EXPECT_EQ(job["mipsRequested"], 40);
    ASSERT_EQ(job["notes"].size(), 1u);
    EXPECT_NE(job["notes"][0].get<std::string>().find("--mips 40 exceeds the 6-level chain"),
              std::string::npos)
        << job["notes"];

    const auto zero = runBurnish(base + quote((dir / "z").string()) + " --mips 0");
    EXPECT_NE(zero.exitCode, 0);
    EXPECT_EQ(countLines(zero.err), 1) << zero.err;
    EXPECT_NE(zero.err.find("--mips 0 must be at least 1"), std::string::npos) << zero.err;
}

// Grooves along x: columns alternate between slopes +kGrooveSlope and -kGrooveSlope (8-bit RGB).
constexpr float kGrooveSlope = 0.5f;
void writeGrooves(const fs::path& path, int size) {
    burnish::test::writeNormals8(path, size, size, [](int x, int, float n[3]) {
        n[0] = x % 2 ? kGrooveSlope : -kGrooveSlope;
        n[1] = 0.0f;
        n[2] = 1.0f;
    });
}

TEST(CliBake, DetailMapIsAnExtraFileOfEveryPreset) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    constexpr int kDetailSize = 16; // tiles at its own resolution: 16x16 .. 1x1
    constexpr int kDetailLevels = 5;
    writeGrooves(dir / "grooves.png", kDetailSize);
    // The constant variance is Toksvig's (1 - |Na|)/|Na| of the whole decoded map's mean normal.
    const auto decodedGrooves = burnish::loadNormalMap(dir / "grooves.png");
    ASSERT_TRUE(decodedGrooves) << decodedGrooves.error();
    glm::dvec3 sum(0.0);
    for (int y = 0; y < kDetailSize; ++y)
        for (int x = 0; x < kDetailSize; ++x)
            sum += glm::dvec3(decodedGrooves->at(x, y));
    const double expectedVariance =
        burnish::toksvigVariance(glm::length(sum) / double(kDetailSize * kDetailSize));
    // Float moments against this double sum.
    constexpr double kMomentRounding = 1e-6;
    // Analytically |Na| = 1/sqrt(1 + slope^2) (x cancels), so the variance is sqrt(1 + slope^2) - 1;
    // 8-bit storage of the grooves moves it by 2.0% (measured): 3% keeps the bake honest.
    const double analyticVariance = std::sqrt(1.0 + double(kGrooveSlope) * kGrooveSlope) - 1.0;
    constexpr double kEightBitRelative = 0.03;
    EXPECT_NEAR(expectedVariance, analyticVariance, kEightBitRelative * analyticVariance);
    for (const auto& preset : burnish::builtinPresets()) {
        SCOPED_TRACE(preset.name);
        const fs::path out = dir / preset.name;
        const auto r = runBurnish("bake " + quote((dir / "bumps.png").string()) + " --preset " + preset.name +
                                  " --detail " + quote((dir / "grooves.png").string()) +
                                  " --detail-fade 1:3 --json --out " + quote(out.string()));
        ASSERT_EQ(r.exitCode, 0) << r.err;
        const std::string ext(burnish::exportFormatExtension(preset.format));
        const auto bakeJson = nlohmann::json::parse(burnish::readFile(out / "bake.json").value());
        const auto& detail = bakeJson["detail"];
        EXPECT_EQ(detail["file"], "bumps_detail." + ext);
        EXPECT_EQ(detail["fade"], nlohmann::json({1, 3}));
        EXPECT_NEAR(detail["constantVariance"].get<double>(), expectedVariance, kMomentRounding);
        EXPECT_EQ(bakeJson["inputs"]["detailMap"], (dir / "grooves.png").string());
        const auto& files = bakeJson["files"];
        ASSERT_EQ(files.size(), preset.files.size() + 1);
        const auto& df = files.back();
        EXPECT_EQ(df["name"], "detail");
        EXPECT_EQ(df["mips"].size(), size_t(kDetailLevels)); // its own chain, not the 32x32 map's 6
        EXPECT_EQ(df["mips"][0], nlohmann::json({kDetailSize, kDetailSize}));
        EXPECT_EQ(files[0]["mips"].size(), size_t(kMipCount));
        for (const auto& p : df["paths"])
            EXPECT_TRUE(fs::exists(out / p.get<std::string>())) << p;
        const auto summary = nlohmann::json::parse(r.out)["jobs"][0];
        EXPECT_EQ(summary["detail"]["constantVariance"], detail["constantVariance"]);
    }

    // The stored detail: mip 0 keeps the grooves' slopes; from the fade end (mip 3) on, the normal
    // is flat and the variance the constant. Read from 16-bit PNGs of the godot (OpenGL) preset, box
    // kernel (the tent would average each groove with its neighbours already at mip 0).
    const fs::path out = dir / "png16";
    ASSERT_EQ(runBurnish("bake " + quote((dir / "bumps.png").string()) +
                         " --preset godot --format png16 --kernel box --detail " +
                         quote((dir / "grooves.png").string()) + " --detail-fade 1:3 --out " +
                         quote(out.string()))
                  .exitCode,
              0);
    const auto bakeJson = nlohmann::json::parse(burnish::readFile(out / "bake.json").value());
    const auto& channels = bakeJson["files"].back()["channels"];
    auto decoded = [&](const std::vector<float>& texels, size_t t, int c) {
        return texels[t * 4 + size_t(c)] * channels[size_t(c)]["scale"].get<double>() +
               channels[size_t(c)]["bias"].get<double>();
    };
    // 16-bit storage: half a code of the [-1, 1] (scale 2) or variance range.
    const double kUint16Tolerance = 0.5 / 65535.0 * 2.0 + 1e-6;
    const double kEightBitSlope = 1.0 / 255.0; // the groove normals themselves were stored in 8 bits
    const auto mip0 = readLevels(out / "bumps_detail.png");
    ASSERT_EQ(mip0.size(), 1u);
    const double nx = double(kGrooveSlope) / std::sqrt(1.0 + double(kGrooveSlope) * kGrooveSlope);
    EXPECT_NEAR(std::abs(decoded(mip0[0], 0, 0)), nx, kEightBitSlope + kUint16Tolerance);
    const auto mip3 = readLevels(out / "bumps_detail_mip3.png");
    ASSERT_EQ(mip3.size(), 1u);
    const double constant = bakeJson["detail"]["constantVariance"];
    for (size_t t = 0; t < 4; ++t) { // 2x2 at mip 3
        EXPECT_NEAR(decoded(mip3[0], t, 0), 0.0, kUint16Tolerance);
        EXPECT_NEAR(decoded(mip3[0], t, 1), 0.0, kUint16Tolerance);
        EXPECT_NEAR(decoded(mip3[0], t, 3), constant, kUint16Tolerance * channels[3]["scale"].get<double>());
    }
}

TEST(CliBake, BadDetailOptionsAreOneLine) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    writeGrooves(dir / "grooves.png", 8);
    const std::string base = "bake " + quote((dir / "bumps.png").string()) + " --preset godot --out " +
                             quote((dir / "o").string()) + " ";
    for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
             {"--detail-fade 1:2", "--detail-fade needs a detail map"},
             {"--detail " + quote((dir / "grooves.png").string()) + " --detail-fade 5:2",
              "0 <= START <= END"},
             {"--detail " + quote((dir / "grooves.png").string()) + " --detail-fade x", "must be START:END"},
             {"--detail " + quote((dir / "missing.png").string()), "missing.png"}}) {
        SCOPED_TRACE(args);
        const auto r = runBurnish(base + args);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(countLines(r.err), 1) << r.err;
        EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    }
    EXPECT_TRUE(listFolder(dir / "o").empty());
}

TEST(CliBake, ReportWithAGlossMapUsesItsPowers) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    // A constant gloss of 0.5 in blackops' 8192^g: every texel's power is 8192^0.5.
    {
        std::vector<float> gloss(32 * 32, 0.5f);
        auto out = OIIO::ImageOutput::create((dir / "gloss.exr").string());
        ASSERT_TRUE(out);
        ASSERT_TRUE(
            out->open((dir / "gloss.exr").string(), OIIO::ImageSpec(32, 32, 1, OIIO::TypeDesc::FLOAT)));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, gloss.data()));
        ASSERT_TRUE(out->close());
    }
    const auto r = runBurnish("bake " + quote((dir / "bumps.png").string()) + " --preset blackops --gloss " +
                              quote((dir / "gloss.exr").string()) + " --report --json --out " +
                              quote((dir / "o").string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(nlohmann::json::parse(r.out)["jobs"][0]["warnings"].empty()) << r.out;
    const auto evaluation =
        nlohmann::json::parse(burnish::readFile(dir / "o" / "report" / "evaluate.json").value());
    // Powers decoded from float storage: 8192^0.5 to double rounding.
    constexpr double kPowerTolerance = 1e-9;
    EXPECT_NEAR(evaluation["authored_gloss"]["mean_power"].get<double>(), std::sqrt(8192.0),
                kPowerTolerance * std::sqrt(8192.0));
    EXPECT_NEAR(evaluation["base_powers"][0].get<double>(), std::sqrt(8192.0),
                kPowerTolerance * std::sqrt(8192.0));
}

TEST(CliBake, HelpListsPresetsMethodsAndFormats) {
    const auto r = runBurnish("bake --help");
    EXPECT_EQ(r.exitCode, 0);
    for (const auto& name : burnish::builtinPresetNames())
        EXPECT_NE(r.out.find(name), std::string::npos) << name;
    for (const char* word : {"variance-to-gloss", "vmf", "exr-half", "tiff-float", "bc5", "--manifest",
                             "--allow-8bit", "--green", "--layout", "--kernel", "--border", "--compression",
                             "--gloss", "--power", "--mips", "--detail", "--detail-fade", "--ninja"})
        EXPECT_NE(r.out.find(word), std::string::npos) << word;
}

// OpenImageIO is loaded on its first call (core/src/io/oiio_lazy): a PNG read and baked to PNG never
// loads it (core has its own PNG codec), an EXR export does and works through the loaded library.
TEST(CliBake, OpenImageIOLoadsOnlyWhenAFormatNeedsIt) {
    if (!BURNISH_LAZY_OIIO)
        GTEST_SKIP() << "this build links OpenImageIO (sanitizers: UBSan needs its typeinfo)";
    TempDir tmp;
    const fs::path dir = tmp.path();
    writeNormalMap(dir / "bumps.png");
    const std::string in = quote((dir / "bumps.png").string());
    // The dynamic loader names every library it opens on stderr.
    auto r = runBurnish("bake " + in + " --preset lean --format png16 --out " + quote((dir / "png").string()),
                        "LD_DEBUG=files");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err.find("libOpenImageIO.so"), std::string::npos);
    EXPECT_TRUE(fs::exists(dir / "png" / "bumps_lean-b.png"));

    r = runBurnish("bake " + in + " --preset lean --format exr-half --out " + quote((dir / "exr").string()),
                   "LD_DEBUG=files");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("libOpenImageIO.so"), std::string::npos);
    const fs::path exr = dir / "exr" / "bumps_lean-b.exr";
    ASSERT_TRUE(fs::exists(exr));
    auto file = OIIO::ImageInput::open(exr.string());
    ASSERT_TRUE(file) << OIIO::geterror();
    EXPECT_EQ(file->spec().width, 32);
    EXPECT_EQ(file->spec().format, OIIO::TypeDesc::HALF);
}

} // namespace

TEST(CliBake, ShadedFitRefinesTheMixtureAndIsRecorded) {
    TempDir dir;
    writeNormalMap(dir / "bumps.png");
    const std::string common =
        "bake " + quote((dir / "bumps.png").string()) + " --preset mixture --power 256 --out ";
    ASSERT_EQ(runBurnish(common + quote((dir / "moments").string())).exitCode, 0);
    const auto r = runBurnish(common + quote((dir / "shaded").string()) + " --shaded-fit");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto manifest =
        nlohmann::json::parse(burnish::readFile((dir / "shaded" / "bake.json").string()).value());
    EXPECT_EQ(manifest["options"]["shadedFit"], true);
    const auto plain =
        nlohmann::json::parse(burnish::readFile((dir / "moments" / "bake.json").string()).value());
    EXPECT_EQ(plain["options"]["shadedFit"], false);
    // The lobes differ (mips 2 and up are refined); the set's files are the same.
    EXPECT_EQ(listFolder(dir / "moments"), listFolder(dir / "shaded"));
    EXPECT_NE(burnish::readFile((dir / "moments" / "bumps_mixture-lobe0.exr").string()).value(),
              burnish::readFile((dir / "shaded" / "bumps_mixture-lobe0.exr").string()).value());
    // Only the mixture has lobes to refine.
    const auto lean = runBurnish("bake " + quote((dir / "bumps.png").string()) +
                                 " --preset lean --shaded-fit --out " + quote((dir / "lean").string()));
    EXPECT_NE(lean.exitCode, 0);
    EXPECT_NE(lean.err.find("--shaded-fit applies to --method mixture only"), std::string::npos) << lean.err;
    EXPECT_FALSE(fs::exists(dir / "lean"));
}

namespace {

// Two bakes of different maps with one stem into one folder at once (a resubmitted farm task and its slow
// original), each with --force, several times: the folder's writer lock (util/files.h FolderLock) runs them
// one after the other, so every time the folder holds exactly one of the two sets, each file byte for byte
// that map's bake alone, and bake.json naming that map. Before the lock, 6 runs in 45 left a mixed set.
// A file's bytes, or "" when it cannot be read.
std::string bytesOf(const fs::path& p) {
    auto r = burnish::readFile(p);
    return r ? *r : std::string();
}

TEST(CliBake, TwoBakesIntoOneFolderAtOnceLeaveOneWholeSet) {
    TempDir dir;
    fs::create_directories(dir / "a");
    fs::create_directories(dir / "b");
    writeNormalMap(dir / "a" / "map.png", 256);
    writeNormalMap(dir / "b" / "map.png", 512); // more mips: more files
    auto bake = [&](const std::string& which, const fs::path& out) {
        return runBurnish("bake " + quote((dir / which / "map.png").string()) +
                          " --preset gltf --format png16 --force --out " + quote(out.string()));
    };
    for (const std::string which : {"a", "b"}) {
        fs::create_directories(dir / ("ref-" + which));
        const auto r = bake(which, dir / ("ref-" + which));
        ASSERT_EQ(r.exitCode, 0) << r.err;
    }
    ASSERT_NE(listFolder(dir / "ref-a"), listFolder(dir / "ref-b"));
    // While another writer holds the folder (here this test), a bake into it waits and finishes after it.
    {
        fs::create_directories(dir / "held");
        auto held = burnish::FolderLock::acquire(dir / "held");
        ASSERT_TRUE(held && held->held());
        RunResult r;
        std::chrono::steady_clock::time_point finished;
        std::thread t([&] {
            r = bake("a", dir / "held");
            finished = std::chrono::steady_clock::now();
        });
        std::this_thread::sleep_for(std::chrono::milliseconds(1500)); // the bake alone takes ~0.3 s
        const auto released = std::chrono::steady_clock::now();
        { burnish::FolderLock gone = std::move(held).value(); }
        t.join();
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_GE(finished, released) << "the bake wrote into a folder another writer held";
        EXPECT_EQ(listFolder(dir / "held"), listFolder(dir / "ref-a"));
    }
    for (int round = 0; round < 4; ++round) {
        const fs::path out = dir / ("o" + std::to_string(round));
        fs::create_directories(out);
        RunResult ra, rb;
        std::thread ta([&] { ra = bake("a", out); }), tb([&] { rb = bake("b", out); });
        ta.join();
        tb.join();
        ASSERT_EQ(ra.exitCode, 0) << ra.err;
        ASSERT_EQ(rb.exitCode, 0) << rb.err;
        const std::vector<std::string> names = listFolder(out);
        const auto manifest = nlohmann::json::parse(bytesOf(out / "bake.json"), nullptr, false);
        ASSERT_FALSE(manifest.is_discarded()) << "round " << round;
        const std::string which = manifest.dump().find((dir / "a").string()) != std::string::npos ? "a" : "b";
        ASSERT_EQ(names, listFolder(dir / ("ref-" + which))) << "round " << round << ": a mixed set";
        for (const std::string& name : names) {
            if (name.find("bake.json") != std::string::npos) continue;
            EXPECT_EQ(bytesOf(out / name), bytesOf(dir / ("ref-" + which) / name))
                << "round " << round << " " << name;
        }
    }
}

} // namespace
