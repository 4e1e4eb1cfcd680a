// End to end: `burnish bake --manifest M --ninja FILE` writes a Ninja build file; `ninja` runs it
// (when the binary is installed), produces the bytes of a direct bake, and does nothing the second
// time.
#include <burnish/core/util/files.h>

#include "cli_run.h"
#include "normal_map_files.h"
#include "temp_dir.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using burnish::test::runBurnish;
using burnish::test::shellQuote;
using burnish::test::TempDir;

// A size×size 8-bit normal map of sines; `phase` makes a different map of the same size.
void writeNormalMap(const fs::path& path, int size, float phase = 0.0f) {
    burnish::test::writeSineNormalMap(path, size, phase);
}

void writeText(const fs::path& path, const std::string& text) {
    std::ofstream f(path);
    f << text;
}

// Two jobs: one with a detail map and PNG files per level, one DDS with a short chain.
std::string manifestText(const std::string& out1, const std::string& out2) {
    return R"({"version": 1, "jobs": [
        {"input": "one.png", "out": ")" +
           out1 + R"(", "preset": "godot", "detail": "detail.png", "detail-fade": "1:2"},
        {"input": "two.png", "out": ")" +
           out2 + R"(", "preset": "blackops", "power": 300, "mips": 3}
    ]})";
}

std::vector<std::string> filesUnder(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.is_regular_file()) names.push_back(fs::relative(e.path(), dir).string());
    std::sort(names.begin(), names.end());
    return names;
}

struct Shell {
    int exitCode = -1;
    std::string out;
};

// Runs a shell command, stdout and stderr together.
Shell shell(const std::string& command) {
    Shell r;
    FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return r;
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0)
        r.out.append(buffer, n);
    const int status = ::pclose(pipe);
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

bool haveNinja() {
    return shell("command -v ninja").exitCode == 0;
}

} // namespace

TEST(CliNinja, OneBuildStatementPerJobWithItsInputsAndOutputs) {
    TempDir dir;
    writeNormalMap(dir / "one.png", 32);
    writeNormalMap(dir / "two.png", 16);
    writeNormalMap(dir / "detail.png", 8);
    writeText(dir / "jobs.json", manifestText("out1", "out2"));
    const fs::path ninjaFile = dir / "bake.ninja";
    const auto r = runBurnish("bake --manifest " + shellQuote((dir / "jobs.json").string()) + " --ninja " +
                              shellQuote(ninjaFile.string()) + " --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // Nothing is baked: only the build file.
    EXPECT_FALSE(fs::exists(dir / "out1"));
    EXPECT_FALSE(fs::exists(dir / "out2"));
    const std::string text = burnish::readFile(ninjaFile).value();
    EXPECT_NE(text.find("rule burnish_bake"), std::string::npos);
    EXPECT_NE(text.find("restat = 1"), std::string::npos);
    EXPECT_NE(text.find("description = $desc"), std::string::npos);
    size_t builds = 0;
    for (size_t at = text.find("\nbuild "); at != std::string::npos; at = text.find("\nbuild ", at + 1))
        ++builds;
    EXPECT_EQ(builds, 2u);

    const auto summary = nlohmann::json::parse(r.out);
    std::vector<std::string> outputs;
    for (const auto& o : summary["outputs"])
        outputs.push_back(o.get<std::string>());
    // Job 1: godot PNG, 6 levels of normal and roughness, 4 of the 8x8 detail map, bake.json.
    // Job 2: blackops DDS (normal, gloss) with a 3-level chain, bake.json.
    EXPECT_EQ(outputs.size(), (2u * 6u + 4u + 1u) + (2u + 1u));
    for (const char* expected : {"out1/one_detail_mip3.png", "out1/one_roughness_mip5.png", "out1/bake.json",
                                 "out2/two_gloss.dds", "out2/bake.json"})
        EXPECT_NE(std::find(outputs.begin(), outputs.end(), (dir / expected).string()), outputs.end())
            << expected;
    // Inputs: the maps and the manifest, on job 1's build line.
    const std::string job1 = text.substr(text.find("\nbuild " + (dir / "out1").string()));
    const std::string line1 = job1.substr(0, job1.find('\n', 1));
    for (const char* input : {"one.png", "detail.png", "jobs.json"})
        EXPECT_NE(line1.find((dir / input).string()), std::string::npos) << input;
    // The command spells every option out and replaces the previous outputs.
    for (const char* option : {"'--method' 'variance-to-gloss'", "'--power' '1024'", "'--kernel' 'tent'",
                               "'--border' 'wrap'", "'--detail-fade' '1:2'", "'--force'"})
        EXPECT_NE(job1.find(option), std::string::npos) << option;
}

TEST(CliNinja, NinjaBakesWhatADirectBakeWritesAndRebuildsNothingTwice) {
    if (!haveNinja()) GTEST_SKIP() << "no ninja binary on PATH";
    TempDir dir;
    writeNormalMap(dir / "one.png", 32);
    writeNormalMap(dir / "two.png", 16);
    writeNormalMap(dir / "detail.png", 8);
    writeText(dir / "jobs.json", manifestText("ninja1", "ninja2"));
    writeText(dir / "direct.json", manifestText("direct1", "direct2"));
    const fs::path ninjaFile = dir / "bake.ninja";
    ASSERT_EQ(runBurnish("bake --manifest " + shellQuote((dir / "jobs.json").string()) + " --ninja " +
                         shellQuote(ninjaFile.string()))
                  .exitCode,
              0);
    const auto direct = runBurnish("bake --manifest " + shellQuote((dir / "direct.json").string()));
    ASSERT_EQ(direct.exitCode, 0) << direct.err;

    const std::string ninja =
        "cd " + shellQuote(dir.path().string()) + " && ninja -f " + shellQuote(ninjaFile.string()) + " -j 2";
    const Shell first = shell(ninja);
    ASSERT_EQ(first.exitCode, 0) << first.out;
    for (const auto& [built, baked] : {std::pair{"ninja1", "direct1"}, std::pair{"ninja2", "direct2"}}) {
        const auto names = filesUnder(dir / built);
        EXPECT_EQ(names, filesUnder(dir / baked)) << built;
        for (const auto& name : names) // bake.json included: it records no output folder
            EXPECT_EQ(burnish::readFile(dir / built / name).value(),
                      burnish::readFile(dir / baked / name).value())
                << built << "/" << name;
    }

    const Shell second = shell(ninja);
    EXPECT_EQ(second.exitCode, 0) << second.out;
    EXPECT_NE(second.out.find("ninja: no work to do"), std::string::npos) << second.out;

    // A changed input reruns its own job only. Its time stamp is set past every output's, so the
    // check does not depend on how long the bakes above took.
    writeNormalMap(dir / "two.png", 16, 1.0f);
    fs::last_write_time(dir / "two.png", fs::file_time_type::clock::now() + std::chrono::seconds(5));
    const Shell third = shell(ninja);
    EXPECT_EQ(third.exitCode, 0) << third.out;
    EXPECT_NE(third.out.find("[1/1]"), std::string::npos) << third.out;
    EXPECT_NE(third.out.find("two.png"), std::string::npos) << third.out;
}

TEST(CliNinja, RefusesWhatItCannotWrite) {
    TempDir dir;
    writeNormalMap(dir / "one.png", 16);
    // --ninja describes a manifest's jobs.
    auto r =
        runBurnish("bake " + shellQuote((dir / "one.png").string()) + " --preset godot --out " +
                   shellQuote((dir / "o").string()) + " --ninja " + shellQuote((dir / "b.ninja").string()));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("--ninja needs --manifest"), std::string::npos) << r.err;
    // Two jobs writing the same file would make ninja refuse the whole file.
    writeText(dir / "clash.json",
              R"({"version": 1, "jobs": [{"input": "one.png", "out": "o", "preset": "godot"},
                                              {"input": "one.png", "out": "o", "preset": "gltf"}]})");
    r = runBurnish("bake --manifest " + shellQuote((dir / "clash.json").string()) + " --ninja " +
                   shellQuote((dir / "b.ninja").string()));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(burnish::test::lineCount(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("job 2"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("which job 1 writes too"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "b.ninja"));
    // '|' ends a path in Ninja's syntax and has no escape: refused, not written broken.
    writeText(dir / "bar.json",
              R"({"version": 1, "jobs": [{"input": "one.png", "out": "a|b", "preset": "godot"}]})");
    r = runBurnish("bake --manifest " + shellQuote((dir / "bar.json").string()) + " --ninja " +
                   shellQuote((dir / "b.ninja").string()));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(burnish::test::lineCount(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("'|'"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "b.ninja"));
}
