// A Ninja build file for many bake jobs (`burnish bake --manifest M --ninja FILE`): one build
// statement per job, running that job as one `burnish bake` command, with the job's exact outputs
// (named by export's plan, nothing baked) and its inputs (maps, preset file, manifest).
#pragma once

#include <burnish/core/jobs/bake_job.h>
#include <burnish/core/util/result.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace burnish {

/// `text` as one word of a /bin/sh command line (single-quoted; ninja and sbatch scripts run sh).
std::string shellQuoted(const std::string& text);

/// The `burnish bake` command line (argv, `exe` first) that runs one resolved job on its own: every
/// option spelled out as resolved, file paths absolute, --force so a rebuild replaces the previous
/// outputs, --shaded-fit and --report when the spec asks for them. Options whose absence means "each file's
/// own choice" or "none" (compression, metallic, mips, gloss, detail) stay absent when the spec leaves them
/// out.
std::vector<std::string> bakeJobCommand(const std::string& exe, const BakeJob& job);

/// Every file a job will write (absolute paths: the export's files, bake.json, the report's files),
/// from its input's header and the export's plan, without baking. Errors: an unreadable input
/// header, an invalid plan.
Result<std::vector<std::string>> plannedBakeOutputs(const BakeJob& job);

/// Checks resolved jobs before the first one writes anything, reading only file headers: every
/// input (normal map, gloss, detail) opens as an image with a plausible header (a normal map has 2
/// to 4 channels), each job's plan (its files, bake.json, report files) is valid, no two jobs write
/// one file, and with `outRoot` every job's output folder lies inside it (links resolved).
/// Errors: "manifest job N (input): ..." (`fromManifest`; N is numbers[i] when given, for a
/// selection of a manifest's jobs, else i + 1), otherwise the reason alone.
Status checkBakeJobs(const std::vector<BakeJob>& jobs,
                     const std::optional<std::filesystem::path>& outRoot = {}, bool fromManifest = true,
                     const std::vector<size_t>& numbers = {});

/// Writes (atomically, replacing any previous file) a Ninja build file at `path` with one
/// `burnish_bake` build statement per job (restat, so unchanged outputs stop the rebuild), run by
/// `exe`. `manifest` is the file the jobs came from: each job depends on it. Reads each input's
/// extent, bakes nothing. Returns {"ninja": path, "jobs": count, "outputs": [absolute paths]}.
/// Errors ("manifest job N (input): ..."): an unreadable input, two jobs writing one file, a path
/// Ninja cannot express (a line break); "--ninja: ..." when the file cannot be written.
Result<nlohmann::json> writeBakeNinja(const std::vector<BakeJob>& jobs, const std::string& manifest,
                                      const std::string& path, const std::string& exe);

} // namespace burnish
