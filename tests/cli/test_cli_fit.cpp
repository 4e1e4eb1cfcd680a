// End-to-end tests of `burnish fit`.
#include "cli_run.h"

#include <burnish/core/util/files.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
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

class CliFit : public ::testing::Test {
protected:
    void SetUp() override {
        m_dir = fs::temp_directory_path() / ("burnish_cli_fit_" + std::to_string(::getpid()) + "_" +
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

size_t lineCount(const std::string& s) {
    return static_cast<size_t>(std::count(s.begin(), s.end(), '\n'));
}

TEST_F(CliFit, AllJsonParsesAndHoldsEveryFit) {
    const RunResult r = run("fit all --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    std::vector<std::string> names;
    for (const auto& f : j.at("fits")) {
        names.push_back(f.at("name"));
        EXPECT_TRUE(f.contains("domain") && f.contains("metric") && f.contains("note") &&
                    f.contains("parameters"));
        EXPECT_TRUE(f.at("fittedError").contains("rms"));
    }
    for (const char* n :
         {"sg-offset", "fresnel-sg", "fresnel-sg-quadratic", "blinn-phong-ratio", "kv-cone", "diffuse-aa"})
        EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
}

TEST_F(CliFit, SgOffsetPrintsPublishedMeanAndDomain) {
    const RunResult r = run("fit sg-offset");
    ASSERT_EQ(r.code, 0) << r.err;
    // The fitted mean 0.775364 prints as 0.775364, next to the published 0.775.
    EXPECT_NE(r.out.find("0.7753"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("domain:"), std::string::npos);
    EXPECT_NE(r.out.find("c in [0, 1]"), std::string::npos);
    EXPECT_NE(r.out.find("note:"), std::string::npos);
}

TEST_F(CliFit, ExponentChangesTheFresnelFit) {
    const RunResult five = run("fit fresnel-sg --json");
    const RunResult seven = run("fit fresnel-sg --exponent 7 --json");
    ASSERT_EQ(five.code, 0) << five.err;
    ASSERT_EQ(seven.code, 0) << seven.err;
    const double k5 = nlohmann::json::parse(five.out)["fits"][0]["parameters"][0]["fitted"];
    const double k7 = nlohmann::json::parse(seven.out)["fits"][0]["parameters"][0]["fitted"];
    // The best offsets for p = 5 and 7 are 0.7875 and 0.7779.
    constexpr double kDistinct = 1e-3;
    EXPECT_GT(std::abs(k5 - k7), kDistinct);
}

TEST_F(CliFit, OutWritesTheSameBytesAsStdout) {
    const fs::path file = m_dir / "fit.json";
    const RunResult toFile = run("fit diffuse-aa --json --out \"" + file.string() + "\"");
    ASSERT_EQ(toFile.code, 0) << toFile.err;
    EXPECT_TRUE(toFile.out.empty());
    const RunResult toStdout = run("fit diffuse-aa --json");
    EXPECT_EQ(slurp(file), toStdout.out);
}

TEST_F(CliFit, OptionForAnotherFitIsOneLineErrorExitOne) {
    const RunResult r = run("fit sg-offset --exponent 7");
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("burnish: error: ", 0), 0u) << r.err;
    EXPECT_TRUE(r.out.empty());
}

TEST_F(CliFit, OutOfRangeValueIsOneLineErrorExitOne) {
    const RunResult r = run("fit fresnel-sg --exponent -1");
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("burnish: error: ", 0), 0u) << r.err;
}

TEST_F(CliFit, ParseErrorsAreOneLineAndNonZero) {
    // CLI11 parse errors: main.cpp returns CLI11's own code (non-zero) with one line.
    for (const char* args : {"fit sg-offset --bogus", "fit nonsense", "fit"}) {
        const RunResult r = run(args);
        EXPECT_NE(r.code, 0) << args;
        EXPECT_EQ(lineCount(r.err), 1u) << args << ": " << r.err;
        EXPECT_EQ(r.err.rfind("burnish: error: ", 0), 0u) << r.err;
    }
}

} // namespace
