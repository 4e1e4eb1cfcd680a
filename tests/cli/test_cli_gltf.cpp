// `burnish gltf` end to end: the summary it prints and its one-line refusals (the asset processing
// itself is tested in core's test_gltf.cpp; the third-party readers in CTest gltf_validator_ktx_parse).
#include <burnish/core/util/files.h>

#include "claiming_png.h"
#include "cli_run.h"
#include "temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace {

namespace fs = std::filesystem;
using burnish::test::runBurnish;

const fs::path kData = BURNISH_TEST_DATA_DIR;

TEST(CliGltf, ProcessesAnAssetAndPrintsWhatItWrote) {
    burnish::test::TempDir dir;
    fs::create_directories(dir.path() / "in");
    fs::copy_file(kData / "gltf" / "plane.gltf", dir.path() / "in" / "plane.gltf");
    fs::copy_file(kData / "trak-rust1_nm.png", dir.path() / "in" / "normal.png");
    const auto out = dir.path() / "out";
    const auto r =
        runBurnish("gltf " + burnish::test::shellQuote((dir.path() / "in" / "plane.gltf").string()) +
                   " --out " + burnish::test::shellQuote(out.string()) + " --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["method"], "fitted");
    ASSERT_EQ(summary["materials"].size(), 1u);
    EXPECT_EQ(summary["materials"][0]["mipCount"], 10);
    for (const auto& name : summary["written"])
        EXPECT_TRUE(fs::exists(out / name.get<std::string>())) << name;
    // Again without --force: refused, one line, the set untouched.
    const auto again =
        runBurnish("gltf " + burnish::test::shellQuote((dir.path() / "in" / "plane.gltf").string()) +
                   " --out " + burnish::test::shellQuote(out.string()));
    EXPECT_EQ(again.exitCode, 1);
    EXPECT_EQ(std::count(again.err.begin(), again.err.end(), '\n'), 1) << again.err;
}

// An asset whose normal map claims 16384² texels (a 200-byte file) is refused from the image's header by
// the bake's memory check, before it is decoded (it would be found cut short), under a 4 GB limit.
TEST(CliGltf, ANormalMapThatCannotFitIsRefusedBeforeDecoding) {
    burnish::test::TempDir dir;
    fs::create_directories(dir.path() / "in");
    fs::copy_file(kData / "gltf" / "plane.gltf", dir.path() / "in" / "plane.gltf");
    burnish::test::writeClaimingPng(dir.path() / "in" / "normal.png", 16384);
    const auto out = dir.path() / "out";
    const auto r =
        runBurnish("gltf " + burnish::test::shellQuote((dir.path() / "in" / "plane.gltf").string()) +
                       " --out " + burnish::test::shellQuote(out.string()),
                   "BURNISH_MEMORY_LIMIT=4G");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("baking a 16384x16384 map needs about"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("truncated"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "plane.gltf"));
}

TEST(CliGltf, RefusesWhatItCannotDoInOneLine) {
    burnish::test::TempDir dir;
    for (const std::string& args :
         {std::string("gltf"), std::string("gltf a.gltf"),
          std::string("gltf a.gltf --normal-map n.png --out o"),
          "gltf --normal-map " + (kData / "trak-rust1_nm.png").string() + " --specular red --out o",
          "gltf --normal-map " + (kData / "trak-rust1_nm.png").string() + " --roughness 2 --out " +
              (dir.path() / "o").string(),
          "gltf " + (dir.path() / "missing.gltf").string() + " --out " + (dir.path() / "o2").string(),
          std::string("gltf a.gltf --out o --coding bc7"),
          std::string("gltf a.gltf --out o --anisotropy maybe")}) {
        const auto r = runBurnish(args);
        EXPECT_NE(r.exitCode, 0) << args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
        EXPECT_TRUE(r.out.empty()) << args;
    }
    EXPECT_FALSE(fs::exists(dir.path() / "o"));
    EXPECT_FALSE(fs::exists(dir.path() / "o2"));
}

} // namespace
