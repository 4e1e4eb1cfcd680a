// End to end: a manifest baked in parts (`--only`), resumed (`--skip-current`), past a failed job
// (`--keep-going`, `--status-dir`), checked (`--check`), and its Slurm plan's task script run by bash
// without Slurm, as a task would run it (tests/slurm runs the same plan under a real Slurm).
#include <burnish/core/util/files.h>

#include "cli_run.h"
#include "normal_map_files.h"
#include "temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <sys/stat.h>

namespace {

namespace fs = std::filesystem;
using burnish::test::runBurnish;
using burnish::test::shellQuote;
using burnish::test::TempDir;
using Json = nlohmann::json;

void writeText(const fs::path& path, const std::string& text) {
    std::ofstream f(path);
    f << text;
}

/// A library of four jobs in `dir`: maps a.png, b.png, c.png (c.png cut short after its header when
/// `cut`), and a fourth job baking a.png for another preset.
fs::path writeLibrary(const TempDir& dir, bool cut) {
    burnish::test::writeSineNormalMap(dir / "a.png", 32);
    burnish::test::writeSineNormalMap(dir / "b.png", 32, 0.3f);
    burnish::test::writeSineNormalMap(dir / "c.png", 64, 0.6f);
    if (cut) fs::resize_file(dir / "c.png", fs::file_size(dir / "c.png") / 2);
    writeText(dir / "library.json", R"({"version": 1, "jobs": [
        {"input": "a.png", "out": "out/a"},
        {"input": "b.png", "out": "out/b"},
        {"input": "c.png", "out": "out/c"},
        {"input": "a.png", "out": "out/a-unreal", "preset": "unreal"}]})");
    return dir / "library.json";
}

/// Each bake.json's inode and modification time: what a skipped set keeps.
std::map<std::string, std::pair<ino_t, long>> stamps(const fs::path& out) {
    std::map<std::string, std::pair<ino_t, long>> s;
    for (const auto& e : fs::directory_iterator(out)) {
        struct stat st {};
        if (::stat((e.path() / "bake.json").c_str(), &st) == 0)
            s[e.path().filename().string()] = {st.st_ino, long(st.st_mtim.tv_nsec) + long(st.st_mtim.tv_sec)};
    }
    return s;
}

} // namespace

TEST(CliFarm, OnlyBakesTheNamedJobs) {
    TempDir dir;
    const std::string manifest = shellQuote(writeLibrary(dir, false).string());
    const auto r = runBurnish("bake --manifest " + manifest + " --preset blackops --only 2,4");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out/a"));
    EXPECT_TRUE(fs::exists(dir / "out/b/bake.json"));
    EXPECT_FALSE(fs::exists(dir / "out/c"));
    EXPECT_TRUE(fs::exists(dir / "out/a-unreal/bake.json"));
    for (const char* bad : {"0", "5", "3-2", "x"}) {
        const auto refused = runBurnish("bake --manifest " + manifest + " --only " + bad);
        EXPECT_EQ(refused.exitCode, 1) << bad;
        EXPECT_NE(refused.err.find("--only"), std::string::npos) << refused.err;
    }
    const auto noManifest = runBurnish("bake " + shellQuote((dir / "a.png").string()) + " --only 1");
    EXPECT_EQ(noManifest.exitCode, 1);
    EXPECT_NE(noManifest.err.find("need --manifest"), std::string::npos) << noManifest.err;
}

TEST(CliFarm, KeepGoingBakesTheOtherJobsNamesTheFailedOneAndARerunSkipsWhatIsCurrent) {
    TempDir dir;
    const std::string manifest = shellQuote(writeLibrary(dir, true).string());
    const std::string status = shellQuote((dir / "status").string());
    const std::string resume = "bake --manifest " + manifest +
                               " --preset blackops --force --skip-current "
                               "--keep-going --status-dir " +
                               status;
    // Without --keep-going the first failure stops the run.
    const auto stop = runBurnish("bake --manifest " + manifest + " --preset blackops");
    EXPECT_EQ(stop.exitCode, 1);
    EXPECT_NE(stop.err.find("manifest job 3"), std::string::npos) << stop.err;

    const auto first = runBurnish(resume);
    EXPECT_EQ(first.exitCode, 1);
    EXPECT_NE(first.err.find("manifest job 3"), std::string::npos) << first.err;
    EXPECT_NE(first.err.find("1 of 4 jobs failed (job 3"), std::string::npos) << first.err;
    for (const char* set : {"a", "b", "a-unreal"})
        EXPECT_TRUE(fs::exists(dir / "out" / set / "bake.json")) << set;
    EXPECT_FALSE(fs::exists(dir / "out/c/bake.json"));
    const auto failed = Json::parse(burnish::readFile(dir / "status/job-3.json").value());
    EXPECT_EQ(failed["state"], "failed");
    EXPECT_NE(failed["error"].get<std::string>().find("c.png"), std::string::npos) << failed;
    EXPECT_EQ(Json::parse(burnish::readFile(dir / "status/job-1.json").value())["state"], "baked");

    // --check: one failed (its error from the status folder), exit status 1.
    const auto check = runBurnish("bake --manifest " + manifest + " --preset blackops --check --status-dir " +
                                  status + " --json");
    EXPECT_EQ(check.exitCode, 1) << check.err;
    const auto summary = Json::parse(check.out);
    EXPECT_EQ(summary["counts"]["current"], 3);
    EXPECT_EQ(summary["counts"]["failed"], 1);
    EXPECT_EQ(summary["sets"][0]["job"], 3);
    EXPECT_EQ(summary["sets"][0]["reason"], failed["error"]);
    // The same options are needed to call a set current: another default preset makes the sets that
    // take it stale (job 4 names its own preset).
    const auto other = runBurnish("bake --manifest " + manifest + " --preset godot --check");
    EXPECT_NE(other.out.find("4 sets: 1 current, 2 stale, 1 not baked"), std::string::npos) << other.out;
    EXPECT_NE(other.out.find("with other options"), std::string::npos) << other.out;

    // The input mended, a rerun bakes job 3 alone and leaves the others as they were.
    const auto before = stamps(dir / "out");
    burnish::test::writeSineNormalMap(dir / "c.png", 64, 0.6f);
    const auto second = runBurnish(resume);
    ASSERT_EQ(second.exitCode, 0) << second.err;
    EXPECT_NE(second.out.find("out/c: preset blackops"), std::string::npos) << second.out;
    auto after = stamps(dir / "out");
    after.erase("c");
    EXPECT_EQ(before, after);
    const auto done = runBurnish("bake --manifest " + manifest + " --preset blackops --check");
    EXPECT_EQ(done.exitCode, 0) << done.out;
    EXPECT_NE(done.out.find("4 sets: 4 current"), std::string::npos) << done.out;
}

TEST(CliFarm, ASlurmTaskScriptBakesItsChunkAndTheCheckWritesTheSummary) {
    TempDir dir;
    writeLibrary(dir, false);
    // The plan is written from the library's folder with a relative manifest and a default (the
    // preset) on the command line: each task runs there (--chdir) with the same default.
    const std::string at = "cd " + shellQuote(dir.path().string()) + " && ";
    const std::string exe = shellQuote(BURNISH_EXE);
    auto sh = [&](const std::string& command) {
        return std::system(("bash -c " + shellQuote(at + command) + " >/dev/null 2>&1").c_str());
    };
    ASSERT_EQ(sh(exe + " bake --manifest library.json --preset godot --slurm slurm --tasks 2"), 0);
    const std::string script = burnish::readFile(dir / "slurm/burnish.sbatch").value();
    EXPECT_NE(script.find("'--preset' 'godot'"), std::string::npos) << script;
    EXPECT_NE(script.find("#SBATCH --chdir=" + dir.path().string() + "\n"), std::string::npos) << script;

    // Task 1 (jobs 3-4) as Slurm would start it, from another folder.
    ASSERT_EQ(std::system(("cd / && SLURM_ARRAY_TASK_ID=1 SLURM_CPUS_PER_TASK=1 bash " +
                           shellQuote((dir / "slurm/burnish.sbatch").string()) + " >/dev/null 2>&1")
                              .c_str()),
              0);
    EXPECT_FALSE(fs::exists(dir / "out/a"));
    EXPECT_TRUE(fs::exists(dir / "out/c/bake.json"));
    const auto record = Json::parse(burnish::readFile(dir / "out/c/bake.json").value());
    EXPECT_EQ(record["preset"]["name"], "godot");
    EXPECT_EQ(record["inputs"]["normalMap"], "c.png"); // as a local bake from that folder records it

    // The check job: not every set is current (exit status 1), summary.json and summary.txt written.
    EXPECT_NE(std::system(("cd / && bash " + shellQuote((dir / "slurm/burnish-check.sbatch").string()) +
                           " >/dev/null 2>&1")
                              .c_str()),
              0);
    const auto summary = Json::parse(burnish::readFile(dir / "slurm/summary.json").value());
    EXPECT_EQ(summary["counts"]["current"], 2);
    EXPECT_EQ(summary["counts"]["missing"], 2);
    EXPECT_EQ(summary["rerunTasks"], "0");
    const std::string text = burnish::readFile(dir / "slurm/summary.txt").value();
    EXPECT_NE(text.find("--array=0 "), std::string::npos) << text;

    // A manifest edited after its plan was written: the tasks refuse to bake by stale numbers.
    writeText(dir / "library.json", R"({"version": 1, "jobs": [{"input": "b.png", "out": "out/b"}]})");
    const int refused = std::system(("cd / && SLURM_ARRAY_TASK_ID=0 bash " +
                                     shellQuote((dir / "slurm/burnish.sbatch").string()) + " >/dev/null 2>&1")
                                        .c_str());
    EXPECT_EQ(WEXITSTATUS(refused), 1);
    EXPECT_FALSE(fs::exists(dir / "out/a"));
}

TEST(CliFarm, RefusesCombinationsThatMeanNothing) {
    TempDir dir;
    const std::string manifest = shellQuote(writeLibrary(dir, false).string());
    const auto ninja = runBurnish("bake --manifest " + manifest + " --ninja x.ninja --slurm s");
    EXPECT_EQ(ninja.exitCode, 1);
    EXPECT_NE(ninja.err.find("--ninja"), std::string::npos) << ninja.err;
    const auto only = runBurnish("bake --manifest " + manifest + " --check --only 1");
    EXPECT_EQ(only.exitCode, 1);
    EXPECT_NE(only.err.find("--check checks every set"), std::string::npos) << only.err;
    const auto tasks = runBurnish("bake --manifest " + manifest + " --slurm " +
                                  shellQuote((dir / "s").string()) + " --tasks 1001");
    EXPECT_NE(tasks.exitCode, 0);
    const auto noPlan = runBurnish("bake --manifest " + manifest + " --slurm " +
                                   shellQuote((dir / "none").string()) + " --check");
    EXPECT_EQ(noPlan.exitCode, 1);
    EXPECT_NE(noPlan.err.find("no plan to check"), std::string::npos) << noPlan.err;
}
