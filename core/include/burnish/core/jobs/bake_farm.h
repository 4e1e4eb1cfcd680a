// Baking a library in many processes, on one machine or a farm: whether a set on disk is the one its
// job would bake now (bake.json's input and option hashes), a manifest's jobs in chunks, each job's
// outcome in a status folder, one summary of a whole manifest, and the Slurm job array that bakes it
// (`burnish bake --manifest M --slurm DIR`; README, "Bake a library on a farm").
#pragma once

#include <burnish/core/jobs/bake_job.h>
#include <burnish/core/util/result.h>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace burnish {

/// FNV-1a 64 of each file a job reads, as bake.json's inputs.fnv1a64 records them: {"normalMap",
/// "glossMap", "detailMap", "preset"}, 16 hex digits each, null where the job reads no such file (a
/// built-in sample, no gloss or detail map, a built-in preset). Errors: a file that cannot be read.
Result<nlohmann::json> bakeInputHashes(const BakeJob& job);

/// FNV-1a 64 of the job's command line (bakeJobCommand) less the program, its output folder and
/// --force, as bake.json's options.fnv1a64: equal for two jobs that bake the same inputs the same
/// way, wherever they write.
std::string bakeOptionsHash(const BakeJob& job);

enum class BakeSetState { Current, Stale, Missing };
std::string_view bakeSetStateName(BakeSetState state);

struct BakeSetCheck {
    BakeSetState state = BakeSetState::Missing;
    std::string reason; // why it is not current ("" when current)
};

/// Whether job.spec.out holds the set the job would bake now: a bake.json that parses, records the
/// job's options hash and the hashes its inputs have now, and names files that are all there.
/// Missing: no bake.json. Stale: any other difference, with the first reason found ("its normal map
/// changed since it was baked", "it was baked with other options", "its file X is missing", ...).
BakeSetCheck checkBakeSet(const BakeJob& job);

/// Job numbers 1..jobs in `tasks` runs of consecutive numbers ([first, last], 1-based), their sizes
/// differing by at most one; one run per job when jobs <= tasks. Empty when jobs or tasks is 0.
std::vector<std::pair<std::size_t, std::size_t>> bakeChunks(std::size_t jobs, std::size_t tasks);

/// A list of job numbers as `--only` takes it ("3", "1-5,9,12-13") → 0-based indices, ascending,
/// each once. Errors: an empty or malformed list, a number outside 1..jobs, a range running backwards.
Result<std::vector<std::size_t>> parseJobList(std::string_view list, std::size_t jobs);

/// One job's outcome, written by the process that ran it into a status folder (`--status-dir`):
/// <dir>/job-<number>.json, atomically, replacing the previous outcome. `status` holds at least
/// "state" ("baked", "current" or "failed") and, when failed, "error".
Status writeBakeStatus(const std::filesystem::path& dir, std::size_t jobNumber, const nlohmann::json& status);
/// The outcome writeBakeStatus left for a job; nullopt when there is none or it does not parse.
std::optional<nlohmann::json> readBakeStatus(const std::filesystem::path& dir, std::size_t jobNumber);

/// Every job of a manifest checked against its set on disk: `jobs` is each spec resolved now (an
/// error where it no longer resolves: its input gone), `statusDir` where the bakes left their
/// outcomes, `chunks` the array tasks' job runs (bakeChunks) when a Slurm plan baked them.
/// {"manifest", "jobs": count, "counts": {"current", "failed", "stale", "missing"}, "sets": [one per
/// job not current: {"job", "input", "out", "state", "reason", "task"?}], "rerunTasks": [tasks
/// holding a set not current]}. A set not current whose last outcome is "failed" is failed, with
/// that error as its reason; one that does not resolve is failed with the resolution's error.
nlohmann::json summarizeBakeSets(const std::string& manifest, const std::vector<BakeJobSpec>& specs,
                                 const std::vector<Result<BakeJob>>& jobs,
                                 const std::optional<std::filesystem::path>& statusDir,
                                 const std::vector<std::pair<std::size_t, std::size_t>>& chunks);

/// summarizeBakeSets's summary on one screen: counts, then at most `maxSets` sets not current (one
/// line each, the rest counted), then what to run next.
std::string bakeSummaryText(const nlohmann::json& summary, std::size_t maxSets = 12);

/// Slurm's largest array by default (MaxArraySize 1001: task ids 0..1000).
inline constexpr std::size_t kMaxSlurmTasks = 1000;

struct SlurmOptions {
    std::size_t tasks = 0;  // array tasks; 0: one per job, at most kMaxSlurmTasks
    std::string partition;  // "" = the cluster's default partition
    std::string memPerTask; // "" = the cluster's default, "auto" = Burnish's estimate, or 4000M, 8G...
    int cpusPerTask = 1;    // each task's bake threads
    /// Options given on the command line besides the manifest's (every job's defaults), passed on to
    /// each task and to the check as they were given.
    std::vector<std::string> defaults;
    std::filesystem::path workingFolder; // the tasks' --chdir: where relative default paths lead
};

/// The memory one job's bake needs at its peak (estimatedBakeBytes of bakeJobBytesPerTexel, plus its detail
/// map's), for the extent its input's header claims (a built-in sample's size for a sample): what the bake
/// checks against free memory before it reads anything, and what a Slurm task asks for.
struct BakeMemoryEstimate {
    std::uint64_t bytes = 0;
    int width = 0;
    int height = 0;
};
/// Errors: an input whose header cannot be read, a job whose plan fails.
/// Memory a --detail map adds per texel of it (measured: a 2048² detail over a 1024² godot bake raised
/// the peak from 39 MB to 323 MB, 68 bytes per detail texel; core/bench/command_memory.sh).
inline constexpr double kDetailBytesPerTexel = 72.0;
Result<BakeMemoryEstimate> estimatedJobBytes(const BakeJob& job);

/// The memory `--mem-per-task auto` asks for: the largest over the jobs of estimatedBakeBytes for
/// each job's input (read from its header; a task bakes its jobs one after another), in MiB rounded
/// up, at least kSlurmMinimumMiB. Errors: an input whose header cannot be read, a job whose plan fails.
Result<std::uint64_t> slurmMemoryMiB(const std::vector<BakeJob>& jobs);
/// The least a task asks for: a node's memory cgroup counts the task's page cache and the shell and
/// srun around it too, so a request of a small bake's own 20 MB would be killed by its first writes.
inline constexpr std::uint64_t kSlurmMinimumMiB = 256;

/// Writes a Slurm plan for a manifest's resolved jobs into `dir` (created): burnish.sbatch, a job
/// array whose task k runs `exe bake --manifest M --only <chunk k> --force --skip-current --keep-going
/// --status-dir DIR/status` (plus the defaults and --threads from the task's CPUs); burnish-check.sbatch,
/// `exe bake --manifest M --slurm DIR --check`, which writes DIR/summary.json and DIR/summary.txt;
/// plan.json (the manifest, its hash, the chunks, the resources); logs/ and status/. Returns
/// {"dir", "jobs", "tasks", "memPerTask", "submit": the shell line that submits both, the check
/// after every task ends however it ended}. Errors: a folder Slurm's #SBATCH lines cannot name
/// (white space, '%', quotes), an invalid --mem-per-task, an unreadable input (auto memory), a file
/// that cannot be written.
Result<nlohmann::json> writeSlurmPlan(const std::vector<BakeJob>& jobs, const std::string& manifest,
                                      const std::filesystem::path& dir, const std::string& exe,
                                      const SlurmOptions& options);

/// What writeSlurmPlan wrote into plan.json: the manifest's path and FNV-1a 64 ("manifest",
/// "manifestFnv1a64") and the chunks ("tasks": [{"task", "first", "last"}]). Errors: no plan there,
/// or one that does not parse.
struct SlurmPlan {
    std::string manifest;
    std::string manifestHash;
    std::vector<std::pair<std::size_t, std::size_t>> chunks;
};
Result<SlurmPlan> readSlurmPlan(const std::filesystem::path& dir);

} // namespace burnish
