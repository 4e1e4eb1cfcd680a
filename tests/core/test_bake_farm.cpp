// A library baked in parts (bake_farm.h): whether a set on disk is current, job lists and chunks, the
// summary of a manifest, and the Slurm plan's scripts, run here by bash with a stand-in program.
#include <burnish/core/jobs/bake_farm.h>

#include <burnish/core/util/files.h>
#include <burnish/core/util/hash.h>

#include "normal_map_files.h"
#include "temp_dir.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace burnish {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string readText(const fs::path& path) {
    const auto text = readFile(path);
    return text ? *text : std::string();
}

/// A resolved job baking `input` into `out` with the blackops preset (quick, one gloss file).
BakeJob jobOf(const fs::path& input, const fs::path& out, double power = 256.0) {
    BakeJobSpec spec;
    spec.input = input.string();
    spec.out = out.string();
    spec.preset = "blackops";
    spec.power = power;
    spec.force = true;
    auto job = resolveBakeJob(spec);
    EXPECT_TRUE(job) << job.error();
    return job ? *job : BakeJob{};
}

/// Runs `command` through /bin/sh; its exit code and stdout.
std::pair<int, std::string> shell(const std::string& command) {
    std::string out;
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) return {-1, out};
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0)
        out.append(buffer, n);
    const int status = ::pclose(pipe);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(BakeFarm, ChunksCoverEveryJobOnceInRunsDifferingByAtMostOne) {
    for (size_t jobs : {1u, 2u, 7u, 20u, 21u, 1000u, 2501u})
        for (size_t tasks : {1u, 3u, 5u, 20u, 1000u}) {
            const auto chunks = bakeChunks(jobs, tasks);
            ASSERT_EQ(chunks.size(), std::min(jobs, tasks)) << jobs << " jobs, " << tasks << " tasks";
            size_t next = 1;
            size_t smallest = jobs;
            size_t largest = 0;
            for (const auto& [first, last] : chunks) {
                EXPECT_EQ(first, next);
                ASSERT_GE(last, first);
                smallest = std::min(smallest, last - first + 1);
                largest = std::max(largest, last - first + 1);
                next = last + 1;
            }
            EXPECT_EQ(next, jobs + 1);
            EXPECT_LE(largest - smallest, 1u);
        }
    EXPECT_TRUE(bakeChunks(0, 5).empty());
    EXPECT_TRUE(bakeChunks(5, 0).empty());
}

TEST(BakeFarm, JobListsReadRangesAndRefuseWhatIsNotOne) {
    const auto list = parseJobList("9,1-3,2,12-12", 12);
    ASSERT_TRUE(list) << list.error();
    EXPECT_EQ(*list, (std::vector<size_t>{0, 1, 2, 8, 11}));
    for (const char* bad :
         {"", "0", "13", "3-1", "a", "1-", "-2", ",", "1,,2", "1 ", "2-x", "99999999999999999999"}) {
        const auto r = parseJobList(bad, 12);
        EXPECT_FALSE(r) << "'" << bad << "' was read";
        if (!r) {
            EXPECT_NE(r.error().find("--only"), std::string::npos) << r.error();
        }
    }
    EXPECT_NE(parseJobList("13", 12).error().find("not in the manifest's 1-12"), std::string::npos);
}

TEST(BakeFarm, ASetIsCurrentUntilItsInputOptionsOrFilesChange) {
    test::TempDir dir;
    const fs::path map = dir / "map.png";
    test::writeSineNormalMap(map, 32);
    const BakeJob job = jobOf(map, dir / "out");
    EXPECT_EQ(checkBakeSet(job).state, BakeSetState::Missing);

    ASSERT_TRUE(runBakeJob(job));
    const BakeSetCheck baked = checkBakeSet(job);
    EXPECT_EQ(baked.state, BakeSetState::Current) << baked.reason;
    // bake.json records what the check compares.
    const Json record = Json::parse(readText(dir / "out" / "bake.json"));
    EXPECT_EQ(record["options"]["fnv1a64"], bakeOptionsHash(job));
    EXPECT_EQ(record["inputs"]["fnv1a64"], *bakeInputHashes(job));
    EXPECT_TRUE(record["inputs"]["fnv1a64"]["glossMap"].is_null());

    // Other options: stale; the job as baked is still current.
    const BakeSetCheck otherPower = checkBakeSet(jobOf(map, dir / "out", 300.0));
    EXPECT_EQ(otherPower.state, BakeSetState::Stale);
    EXPECT_NE(otherPower.reason.find("other options"), std::string::npos) << otherPower.reason;

    // Another map at the same path: stale, named.
    test::writeSineNormalMap(map, 32, 0.5f);
    const BakeSetCheck otherMap = checkBakeSet(job);
    EXPECT_EQ(otherMap.state, BakeSetState::Stale);
    EXPECT_NE(otherMap.reason.find("normal map changed"), std::string::npos) << otherMap.reason;
    ASSERT_TRUE(runBakeJob(job));
    EXPECT_EQ(checkBakeSet(job).state, BakeSetState::Current);

    // A file of the set gone: stale, named.
    const std::string file = record["files"][1]["paths"][0];
    fs::remove(dir / "out" / file);
    const BakeSetCheck gone = checkBakeSet(job);
    EXPECT_EQ(gone.state, BakeSetState::Stale);
    EXPECT_NE(gone.reason.find(file), std::string::npos) << gone.reason;

    // A bake.json that does not parse, or one from before the hashes were recorded.
    ASSERT_TRUE(writeFileAtomic(dir / "out" / "bake.json", "{\"files\": [", Overwrite::Allow));
    EXPECT_NE(checkBakeSet(job).reason.find("does not parse"), std::string::npos);
    Json older = record;
    older["options"].erase("fnv1a64");
    ASSERT_TRUE(writeFileAtomic(dir / "out" / "bake.json", older.dump(), Overwrite::Allow));
    EXPECT_NE(checkBakeSet(job).reason.find("older Burnish"), std::string::npos);
}

TEST(BakeFarm, TheOptionsHashIgnoresWhereASetIsWrittenAndHowItIsForced) {
    test::TempDir dir;
    const fs::path map = dir / "map.png";
    test::writeSineNormalMap(map, 16);
    BakeJob a = jobOf(map, dir / "a");
    BakeJob b = jobOf(map, dir / "b");
    b.spec.force = false;
    EXPECT_EQ(bakeOptionsHash(a), bakeOptionsHash(b));
    EXPECT_NE(bakeOptionsHash(a), bakeOptionsHash(jobOf(map, dir / "a", 300.0)));
    BakeJob shaded = a;
    shaded.spec.shadedFit = true;
    EXPECT_NE(bakeOptionsHash(a), bakeOptionsHash(shaded));
}

TEST(BakeFarm, TheSummaryNamesEverySetNotCurrentWithItsErrorAndTask) {
    test::TempDir dir;
    test::writeSineNormalMap(dir / "map.png", 16);
    std::vector<BakeJobSpec> specs;
    std::vector<Result<BakeJob>> jobs;
    for (const char* out : {"one", "two", "three", "four"}) {
        specs.push_back(jobOf(dir / "map.png", dir / out).spec);
        jobs.emplace_back(jobOf(dir / "map.png", dir / out));
    }
    jobs[3] = Error{"cannot read image 'gone.png': no such file"};
    ASSERT_TRUE(runBakeJob(*jobs[0]));
    ASSERT_TRUE(writeBakeStatus(dir / "status", 2, {{"state", "failed"}, {"error", "the disk is full"}}));
    const auto chunks = bakeChunks(4, 2);

    const Json summary = summarizeBakeSets("library.json", specs, jobs, dir / "status", chunks);
    EXPECT_EQ(summary["counts"], Json({{"current", 1}, {"failed", 2}, {"stale", 0}, {"missing", 1}}));
    ASSERT_EQ(summary["sets"].size(), 3u);
    EXPECT_EQ(summary["sets"][0]["job"], 2);
    EXPECT_EQ(summary["sets"][0]["state"], "failed");
    EXPECT_EQ(summary["sets"][0]["reason"], "the disk is full");
    EXPECT_EQ(summary["sets"][0]["task"], 0);
    EXPECT_EQ(summary["sets"][1]["state"], "missing");
    EXPECT_EQ(summary["sets"][2]["reason"], "cannot read image 'gone.png': no such file");
    EXPECT_EQ(summary["rerunJobs"], "2-4");
    EXPECT_EQ(summary["rerunTasks"], "0-1");
    const std::string text = bakeSummaryText(summary);
    EXPECT_NE(text.find("4 sets: 1 current, 2 failed, 1 not baked"), std::string::npos) << text;
    EXPECT_NE(text.find("job 2 (task 0)"), std::string::npos) << text;
    EXPECT_EQ(bakeSummaryText(summary, 1).find("job 3"), std::string::npos);
    EXPECT_NE(bakeSummaryText(summary, 1).find("and 2 more"), std::string::npos);
}

TEST(BakeFarm, TheSlurmPlanRunsEachTaskItsChunkAndRefusesWhatSlurmCannotRead) {
    test::TempDir dir;
    test::writeSineNormalMap(dir / "map.png", 64);
    std::vector<BakeJob> jobs;
    for (int i = 0; i < 7; ++i)
        jobs.push_back(jobOf(dir / "map.png", dir / ("out" + std::to_string(i))));
    const fs::path manifest = dir / "library.json";
    ASSERT_TRUE(writeFileAtomic(manifest, "{\"version\": 1, \"jobs\": []}", Overwrite::Allow));
    SlurmOptions options;
    options.tasks = 3;
    options.memPerTask = "auto";
    options.cpusPerTask = 2;
    options.defaults = {"--preset", "it's"};
    options.workingFolder = dir.path();
    // A stand-in program that prints its arguments, one per line.
    const fs::path echo = dir / "args.sh";
    ASSERT_TRUE(
        writeFileAtomic(echo, "#!/bin/sh\nfor a in \"$@\"; do echo \"$a\"; done\n", Overwrite::Allow));
    fs::permissions(echo, fs::perms::owner_all);

    const auto plan = writeSlurmPlan(jobs, manifest.string(), dir / "slurm", echo.string(), options);
    ASSERT_TRUE(plan) << plan.error();
    EXPECT_EQ((*plan)["tasks"], 3);
    const auto mib = slurmMemoryMiB(jobs);
    ASSERT_TRUE(mib);
    EXPECT_GE(*mib, kSlurmMinimumMiB); // small bakes ask for the floor
    EXPECT_EQ((*plan)["memPerTask"], std::to_string(*mib) + "M");
    const std::string script = readText(dir / "slurm" / "burnish.sbatch");
    for (const std::string& line :
         std::vector<std::string>{"#SBATCH --array=0-2\n", "#SBATCH --cpus-per-task=2\n",
                                  "#SBATCH --mem=" + std::to_string(*mib) + "M\n",
                                  "#SBATCH --chdir=" + dir.path().string() + "\n", "  1) only=4-5 ;;\n"})
        EXPECT_NE(script.find(line), std::string::npos) << line << "not in:\n" << script;

    // Task 1 runs its chunk with the plan's guard, flags and the defaults as given.
    const auto [code, args] = shell("cd / && SLURM_ARRAY_TASK_ID=1 SLURM_CPUS_PER_TASK=2 bash '" +
                                    (dir / "slurm" / "burnish.sbatch").string() + "'");
    EXPECT_EQ(code, 0);
    const std::string expected = "bake\n--manifest\n" + manifest.string() +
                                 "\n--preset\nit's\n--manifest-fnv1a64\n" + hashHex(*fileFnv1a64(manifest)) +
                                 "\n--only\n4-5\n--force\n--skip-current\n--keep-going\n--status-dir\n" +
                                 (dir / "slurm" / "status").string() + "\n--threads\n2\n";
    EXPECT_EQ(args, expected);
    EXPECT_EQ(
        shell("SLURM_ARRAY_TASK_ID=3 bash '" + (dir / "slurm" / "burnish.sbatch").string() + "' 2>&1").first,
        2);
    const auto [checkCode, checkArgs] =
        shell("bash '" + (dir / "slurm" / "burnish-check.sbatch").string() + "'");
    EXPECT_EQ(checkCode, 0);
    EXPECT_NE(checkArgs.find("--slurm\n" + (dir / "slurm").string() + "\n--check\n"), std::string::npos)
        << checkArgs;

    const auto read = readSlurmPlan(dir / "slurm");
    ASSERT_TRUE(read) << read.error();
    EXPECT_EQ(read->chunks, bakeChunks(7, 3));
    EXPECT_EQ(read->manifestHash, hashHex(*fileFnv1a64(manifest)));

    for (const std::string folder : {"with space", "per%cent", "quo\"te"}) { // NOLINT
        const auto refused = writeSlurmPlan(jobs, manifest.string(), dir / folder, echo.string(), options);
        ASSERT_FALSE(refused) << folder;
        EXPECT_NE(refused.error().find("#SBATCH"), std::string::npos) << refused.error();
        EXPECT_FALSE(fs::exists(dir / folder));
    }
    SlurmOptions bad = options;
    bad.memPerTask = "lots";
    EXPECT_NE(
        writeSlurmPlan(jobs, manifest.string(), dir / "m", echo.string(), bad).error().find("--mem-per-task"),
        std::string::npos);
    bad = options;
    bad.tasks = kMaxSlurmTasks + 1;
    EXPECT_NE(writeSlurmPlan(jobs, manifest.string(), dir / "m", echo.string(), bad).error().find("--tasks"),
              std::string::npos);
    bad = options;
    bad.partition = "gpu;rm";
    EXPECT_NE(
        writeSlurmPlan(jobs, manifest.string(), dir / "m", echo.string(), bad).error().find("--partition"),
        std::string::npos);
    EXPECT_FALSE(readSlurmPlan(dir / "m"));
}

} // namespace
} // namespace burnish
