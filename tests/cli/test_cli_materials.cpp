// End to end: `burnish materials` run as a process.
#include <burnish/core/shading/color.h>
#include <burnish/core/shading/materials.h>
#include <burnish/core/util/files.h>

#include "cli_run.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace {

using RunResult = burnish::test::CliResult;
using burnish::test::runBurnish;

int countLines(const std::string& s) {
    return burnish::test::lineCount(s);
}

// The line of `text` that starts (after indentation) with `name` followed by a space.
std::string lineFor(const std::string& text, const std::string& name) {
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        const auto start = line.find_first_not_of(' ');
        if (start != std::string::npos && line.compare(start, name.size() + 1, name + " ") == 0) return line;
    }
    return {};
}

} // namespace

TEST(CliMaterials, ListsGoldWithItsValues) {
    const RunResult r = runBurnish("materials");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    const std::string gold = lineFor(r.out, "gold");
    ASSERT_FALSE(gold.empty()) << r.out;
    EXPECT_NE(gold.find("metal"), std::string::npos) << gold;
    EXPECT_NE(gold.find("1.000 0.782 0.344"), std::string::npos) << gold;
    const burnish::Srgb8 code = burnish::toSrgb8({1.0, 0.782, 0.344});
    const std::string codes =
        std::to_string(code.r) + " " + std::to_string(code.g) + " " + std::to_string(code.b);
    EXPECT_NE(gold.find(codes), std::string::npos) << gold;
    EXPECT_NE(gold.find("hoffman2015-metals"), std::string::npos) << gold;
    // The two ranges and the mid-grey note.
    EXPECT_NE(r.out.find("sRGB 40..75"), std::string::npos);
    EXPECT_NE(r.out.find("sRGB 155..255"), std::string::npos);
    EXPECT_NE(r.out.find("Mid grey: sRGB 187"), std::string::npos);
}

TEST(CliMaterials, JsonParsesAndHoldsEveryMaterial) {
    const RunResult r = runBurnish("materials --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    nlohmann::json j;
    ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << r.out;
    ASSERT_TRUE(j.contains("materials"));
    EXPECT_EQ(j["materials"].size(), burnish::builtinMaterialTable().materials.size());
    // The output is itself a valid table equal to the built-in one.
    const auto again = burnish::parseMaterialTable(r.out);
    ASSERT_TRUE(again.ok()) << again.error();
    EXPECT_EQ(again.value(), burnish::builtinMaterialTable());
}

TEST(CliMaterials, CorruptFileIsOneLineErrorAndNonZeroExit) {
    const auto path = std::filesystem::path(::testing::TempDir()) /
                      ("burnish_cli_corrupt_materials_" + std::to_string(::getpid()) + ".json");
    ASSERT_TRUE(burnish::writeFileAtomic(path, "{ \"version\": 1, \"materials\": [ {\"name\": ").ok());
    const RunResult r = runBurnish("materials --file " + burnish::test::shellQuote(path.string()));
    std::filesystem::remove(path);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(countLines(r.err), 1) << r.err;
    EXPECT_EQ(r.err.rfind("burnish: error:", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(path.string()), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST(CliMaterials, ValidFileReplacesTheBuiltinTable) {
    const auto path = std::filesystem::path(::testing::TempDir()) /
                      ("burnish_cli_small_materials_" + std::to_string(::getpid()) + ".json");
    burnish::MaterialTable table = burnish::builtinMaterialTable();
    table.materials.resize(1); // water only
    ASSERT_TRUE(burnish::writeFileAtomic(path, burnish::materialTableToJson(table)).ok());
    const RunResult r = runBurnish("materials --json --file " + burnish::test::shellQuote(path.string()));
    std::filesystem::remove(path);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["materials"].size(), 1u);
    EXPECT_EQ(j["materials"][0]["name"], "water");
}

TEST(CliMaterials, CheckClassifiesADielectric) {
    const RunResult r = runBurnish("materials --check 0.04");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(lineFor(r.out, "class").find("dielectric"), std::string::npos) << r.out;

    const RunResult j = runBurnish("materials --check 0.04 --json");
    ASSERT_EQ(j.exitCode, 0) << j.err;
    const auto parsed = nlohmann::json::parse(j.out);
    EXPECT_EQ(parsed["class"], "dielectric");
    EXPECT_EQ(parsed["insideChart"], true);
}

TEST(CliMaterials, CheckNamesGold) {
    const RunResult r = runBurnish("materials --check 1.0,0.782,0.344");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(lineFor(r.out, "class").find("metal"), std::string::npos) << r.out;
    // Gold is named, first under "nearest".
    std::istringstream in(r.out);
    std::string line;
    while (std::getline(in, line) && line.rfind("nearest", 0) != 0) {
    }
    ASSERT_TRUE(std::getline(in, line)) << r.out;
    EXPECT_EQ(line.substr(line.find_first_not_of(' '), 5), "gold ") << r.out;
}

TEST(CliMaterials, CheckSrgbAndTheGap) {
    // sRGB 255,229,158 is gold's chart colour.
    const RunResult gold = runBurnish("materials --check-srgb 255,229,158 --json");
    ASSERT_EQ(gold.exitCode, 0) << gold.err;
    const auto parsed = nlohmann::json::parse(gold.out);
    EXPECT_EQ(parsed["class"], "metal");
    EXPECT_EQ(parsed["nearest"][0]["name"], "gold");

    // sRGB 128 decodes to 0.216: between the ranges.
    const RunResult gap = runBurnish("materials --check-srgb 128");
    ASSERT_EQ(gap.exitCode, 0) << gap.err;
    EXPECT_NE(lineFor(gap.out, "class").find("implausible"), std::string::npos) << gap.out;
}

TEST(CliMaterials, BadCheckValuesAreOneLineErrors) {
    for (const char* args : {"materials --check 1.5", "materials --check 0.1,0.2", "materials --check abc",
                             "materials --check-srgb 256", "materials --check 0.04 --check-srgb 40"}) {
        const RunResult r = runBurnish(args);
        EXPECT_NE(r.exitCode, 0) << args;
        EXPECT_EQ(countLines(r.err), 1) << args << ": " << r.err;
        EXPECT_EQ(r.err.rfind("burnish: error:", 0), 0u) << args << ": " << r.err;
    }
}

TEST(CliMaterials, HelpDescribesEachOption) {
    const RunResult r = runBurnish("materials --help");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* option : {"--json", "--file", "--check ", "--check-srgb", "--nearest"})
        EXPECT_NE(r.out.find(option), std::string::npos) << option;
}
