// End to end: `burnish report approximations` run as a process.
#include "cli_run.h"

#include <OpenImageIO/imagebuf.h>
#include <burnish/core/util/files.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

struct RunResult {
    int code = -1;
    std::string out;
    std::string err;
};

// A file the command wrote ("" when it is missing, which the test's assertions then report).
std::string slurp(const fs::path& p) {
    auto text = burnish::readFile(p);
    return text ? text.value() : std::string();
}

/// Lines of a Markdown table body: "| <number> | ...".
size_t tableRows(const std::string& md) {
    static const std::regex row("^\\| [0-9]+ \\|");
    size_t n = 0;
    std::istringstream in(md);
    for (std::string line; std::getline(in, line);)
        if (std::regex_search(line, row)) ++n;
    return n;
}

bool hasNanOrInf(const std::string& s) {
    static const std::regex bad("\\b(nan|inf|infinity)\\b", std::regex::icase);
    return std::regex_search(s, bad);
}

// Every group the report must cover (the brief's list).
const std::set<std::string> kExpectedGroups = {"Normalization", "Blinn-Phong lobe", "Phong lobe",
                                               "Fresnel",       "Visibility",       "NDF bridges",
                                               "Diffuse AA",    "sRGB decode",      "sRGB encode"};

class CliReport : public ::testing::Test {
protected:
    void SetUp() override {
        m_dir = fs::temp_directory_path() / ("burnish_cli_report_" + std::to_string(::getpid()) + "_" +
                                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(m_dir);
    }
    void TearDown() override { fs::remove_all(m_dir); }

    RunResult run(const std::string& args) const {
        const auto r = burnish::test::runBurnish(args);
        return {r.exitCode, r.out, r.err};
    }

    fs::path m_dir;
};

TEST_F(CliReport, QuickApproximationsWritesThreeConsistentFiles) {
    const fs::path outDir = m_dir / "report" / "nested"; // created by the command
    const RunResult r = run("report approximations --quick --out \"" + outDir.string() + "\"");
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path md = outDir / "approximations.md";
    const fs::path json = outDir / "approximations.json";
    const fs::path png = outDir / "approximations.png";
    ASSERT_TRUE(fs::exists(md));
    ASSERT_TRUE(fs::exists(json));
    ASSERT_TRUE(fs::exists(png));

    const auto j = nlohmann::json::parse(slurp(json));
    EXPECT_TRUE(j.at("quick").get<bool>());
    std::set<std::string> groups;
    for (const auto& g : j.at("groups"))
        groups.insert(g.get<std::string>());
    EXPECT_EQ(groups, kExpectedGroups);
    std::set<std::string> entryGroups;
    for (const auto& a : j.at("approximations")) {
        entryGroups.insert(a.at("group").get<std::string>());
        EXPECT_TRUE(a.at("error").at("max_abs").is_number()) << a.at("id");
        EXPECT_TRUE(a.at("cost").at("ns_per_eval").is_number()) << a.at("id");
        EXPECT_GT(a.at("cost").at("ns_per_eval").get<double>(), 0.0) << a.at("id");
    }
    EXPECT_EQ(entryGroups, kExpectedGroups);

    const std::string mdText = slurp(md);
    EXPECT_EQ(tableRows(mdText), j.at("approximations").size());
    EXPECT_NE(mdText.find("Quick run"), std::string::npos);
    // stdout carries the same Markdown.
    EXPECT_EQ(tableRows(r.out), j.at("approximations").size());

    EXPECT_FALSE(hasNanOrInf(mdText));
    EXPECT_FALSE(hasNanOrInf(slurp(json)));
    EXPECT_FALSE(hasNanOrInf(r.out));

    OIIO::ImageBuf img(png.string());
    ASSERT_TRUE(img.read()) << img.geterror();
    EXPECT_GT(img.spec().width, 0);
    EXPECT_GT(img.spec().height, 0);
    // No temporaries left beside the outputs.
    size_t files = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(outDir))
        ++files;
    EXPECT_EQ(files, 3u);
}

TEST_F(CliReport, JsonFlagPrintsJsonOnStdout) {
    const RunResult r = run("report approximations --quick --json --out \"" + (m_dir / "j").string() + "\"");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out); // throws (fails the test) if stdout is not pure JSON
    EXPECT_EQ(j.at("report"), "approximations");
    EXPECT_FALSE(j.at("approximations").empty());
}

TEST_F(CliReport, MissingSubcommandAndUnwritableFolderFail) {
    EXPECT_NE(run("report").code, 0);
    // A regular file where the output folder should be: one clear error line, non-zero exit.
    const fs::path blocker = m_dir / "file";
    std::ofstream(blocker) << "x";
    const RunResult r = run("report approximations --quick --out \"" + (blocker / "sub").string() + "\"");
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find("burnish: error:"), std::string::npos) << r.err;
}

} // namespace
