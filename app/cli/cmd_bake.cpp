// `burnish bake`: a normal map (and an optional authored gloss map and detail normal map) through
// a prefiltering method into an engine preset's textures with their mip chains, plus bake.json.
// One job from the options, or many from a manifest; or, with --ninja, a Ninja build file that
// runs the manifest's jobs one `burnish bake` each. The job itself is core's (bake_job.h, the same
// as the studio's Bake & Export dialog; bake_ninja.h): this file holds the options and the output.
#include "command.h"
#include "common.h"

#include <burnish/core/bake/export.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/jobs/bake_farm.h>
#include <burnish/core/jobs/bake_job.h>
#include <burnish/core/jobs/bake_ninja.h>
#include <burnish/core/prefilter/methods.h>

#include <burnish/core/util/files.h>
#include <burnish/core/util/hash.h>
#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace burnish::cli {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string joined(const std::vector<std::string>& names) {
    std::string out;
    for (const auto& n : names)
        out += (out.empty() ? "" : ", ") + n;
    return out;
}

std::vector<std::string> methodNames() {
    std::vector<std::string> names;
    for (Method m : allMethods())
        names.emplace_back(methodName(m));
    return names;
}

std::vector<std::string> formatNames() {
    std::vector<std::string> names;
    for (ExportFormat f : allExportFormats())
        names.emplace_back(exportFormatName(f));
    return names;
}

std::vector<std::string> compressionNames() {
    std::vector<std::string> names;
    for (DdsCompression c : allDdsCompressions())
        names.emplace_back(ddsCompressionName(c));
    return names;
}

std::string helpFooter() {
    std::string text = "\nPresets (--preset NAME, or --preset FILE.json):\n";
    for (const auto& p : builtinPresets()) {
        std::vector<std::string> fits;
        for (Method m : compatibleMethods(p))
            fits.emplace_back(methodName(m));
        text += fmt::format("  {:<10} {}\n  {:<10}   default method {}, format {}, {} normals; methods: {}\n"
                            "  {:<10}   {}\n",
                            p.name, p.title, "", methodName(p.method), exportFormatName(p.format),
                            p.green == GreenConvention::DirectX ? "DirectX (-Y)" : "OpenGL (+Y)",
                            joined(fits), "", p.conversion);
    }
    for (const auto& e : builtinPresetErrors())
        text += "  (broken built-in: " + e + ")\n";
    text += "\nMethods (--method):\n";
    for (Method m : allMethods())
        text += fmt::format("  {:<18} {}\n", methodName(m), methodDescription(m));
    text +=
        "\nFormats (--format): " + joined(formatNames()) +
        "\n  png8/png16/tga write one file per mip (<stem>_<file>_mip<k>.<ext> for k >= 1); exr and tiff "
        "one\n"
        "  MIP-mapped file; dds the whole chain in one file.\n"
        "DDS compressions (--compression): bc4 (1 channel), bc5 (normal x, y), bc3 (RGB + alpha), rgba8.\n"
        "\nManifest (--manifest FILE): {\"version\": 1, \"jobs\": [{\"input\": \"a.png\", \"out\": \"dir\", "
        "\"preset\": "
        "\"unity\", ...}]}\n  any option by its long name; relative paths from the manifest's folder; "
        "options given "
        "on the\n  command line are every job's defaults. Output paths may be absolute or lead out of the "
        "manifest's\n  folder (../); --out-root DIR refuses any job whose output folder is not inside DIR.\n"
        "  Before the first job runs, every job is checked: its inputs open as images, its options resolve,\n"
        "  and no two jobs write the same file.\n"
        "\nEach output folder gets bake.json: every file's channels and decode rule (value = stored*scale + "
        "bias).\n"
        "--detail FILE adds <stem>_detail.<ext> ([x, y, 0, variance], its own mip chain) to every preset, "
        "and\n"
        "  bake.json's \"detail\" entry gives the constant variance a shader adds beyond the fade.\n"
        "--ninja FILE (with --manifest) writes a Ninja build file instead of baking: `ninja -f FILE -j N`\n"
        "  bakes the jobs in parallel and reruns only those whose inputs changed.\n"
        "A library in parts (with --manifest): --only 3-7,12 bakes those jobs; --skip-current leaves every\n"
        "  set whose bake.json records the job's options and its inputs' hashes as they are now;\n"
        "  --keep-going goes past a failed job; --check says which sets are current, failed, stale or not\n"
        "  baked. --slurm DIR writes DIR/burnish.sbatch (a Slurm job array, one run of jobs per task) and\n"
        "  DIR/burnish-check.sbatch (run after it: DIR/summary.json and summary.txt) and prints the sbatch\n"
        "  line that submits both (README, \"Bake a library on a farm\").\n";
    return text;
}

/// The options of a library's bake in parts (--only, --slurm, --check...).
struct FarmOptions {
    std::string only;
    bool skipCurrent = false;
    bool keepGoing = false;
    std::string statusDir;
    int threads = 0;
    std::string slurm;
    size_t tasks = 0;
    std::string partition;
    std::string memPerTask;
    int cpusPerTask = 1;
    bool check = false;
    std::string manifestHash;
};

/// The running burnish binary, which build statements and Slurm tasks run.
Result<std::string> runningProgram(const std::string& option) {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (ec)
        return Error{option + ": cannot find the running burnish binary (/proc/self/exe): " + ec.message()};
    return exe.string();
}

/// The job options given on the command line (every manifest job's defaults), as they were given, for
/// the commands a Slurm plan runs: everything but the manifest, the output's form and the options of
/// the bake in parts, which the plan sets itself.
std::vector<std::string> jobDefaults(const CLI::App& cmd) {
    static const std::set<std::string> kNotDefaults = {
        "--manifest",     "--json",          "--ninja",      "--force",
        "--only",         "--skip-current",  "--keep-going", "--status-dir",
        "--threads",      "--slurm",         "--tasks",      "--partition",
        "--mem-per-task", "--cpus-per-task", "--check",      "--manifest-fnv1a64",
        "--help"};
    std::vector<std::string> args;
    for (const CLI::Option* o : cmd.get_options()) {
        if (o->count() == 0 || o->get_lnames().empty()) continue;
        const std::string name = "--" + o->get_lnames().front();
        if (kNotDefaults.count(name)) continue;
        if (o->get_type_size() == 0) {
            args.push_back(name);
            continue;
        }
        for (const auto& value : o->results())
            args.insert(args.end(), {name, value});
    }
    return args;
}

/// `burnish bake --manifest M --check [--slurm DIR]`: every set against what its job would bake now.
int checkSets(const std::string& manifest, const std::vector<BakeJobSpec>& specs, const FarmOptions& farm,
              bool json) {
    std::vector<Result<BakeJob>> jobs;
    for (const auto& s : specs)
        jobs.push_back(resolveBakeJob(s));
    std::optional<fs::path> statusDir;
    if (!farm.statusDir.empty()) statusDir = fs::path(farm.statusDir);
    std::vector<std::pair<size_t, size_t>> chunks;
    Json warnings = Json::array();
    const fs::path folder = farm.slurm.empty() ? fs::path() : fs::absolute(farm.slurm).lexically_normal();
    if (!farm.slurm.empty()) {
        const auto plan = readSlurmPlan(folder);
        if (!plan) return fail(plan.error());
        chunks = plan->chunks;
        if (!statusDir) statusDir = folder / "status";
        const auto hash = fileFnv1a64(manifest);
        if (hash && hashHex(*hash) != plan->manifestHash)
            warnings.push_back("the manifest changed since this plan was written: its tasks bake other jobs "
                               "than the manifest's now (write the plan again with --slurm DIR)");
    }
    Json summary = summarizeBakeSets(manifest, specs, jobs, statusDir, chunks);
    summary["warnings"] = warnings;
    const std::string rerunJobs = summary["rerunJobs"];
    if (!farm.slurm.empty()) {
        summary["slurm"] = folder.string();
        summary["rerun"] = "Rerun the tasks holding them (sets already current are skipped), then this "
                           "check:\n  jid=$(sbatch "
                           "--parsable --array=" +
                           summary["rerunTasks"].get<std::string>() + " " +
                           shellQuoted((folder / "burnish.sbatch").string()) +
                           ") && sbatch --dependency=afterany:${jid%%;*} " +
                           shellQuoted((folder / "burnish-check.sbatch").string());
    } else if (!rerunJobs.empty()) {
        summary["rerun"] = "Rebake them: burnish bake --manifest " + shellQuoted(manifest) + " --only " +
                           rerunJobs + " --force --skip-current --keep-going";
    }
    std::string text = bakeSummaryText(summary);
    for (const auto& w : warnings)
        text += "warning: " + w.get<std::string>() + "\n";
    if (!farm.slurm.empty()) {
        for (const auto& [name, bytes] : {std::pair{folder / "summary.json", summary.dump(2) + "\n"},
                                          std::pair{folder / "summary.txt", text}})
            if (const Status s = writeFileAtomic(name, bytes, Overwrite::Allow); !s)
                return fail("--check: " + s.error());
    }
    if (json)
        std::printf("%s\n", summary.dump(2).c_str());
    else
        std::fputs(text.c_str(), stdout);
    return summary["counts"]["current"].get<size_t>() == specs.size() ? 0 : 1;
}

} // namespace

static CommandRegistration registration(40, [](CLI::App& app) -> std::function<int()> {
    auto* cmd = app.add_subcommand(
        "bake", "Bake a normal map's prefiltered gloss/LEAN textures for an engine preset");
    auto spec = std::make_shared<BakeJobSpec>();
    auto manifest = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    auto ninja = std::make_shared<std::string>();
    auto outRoot = std::make_shared<std::string>();

    cmd->add_option("input", spec->input, "Tangent-space normal map (PNG, TGA, EXR, TIFF, DDS, ...)");
    cmd->add_option("--preset", spec->preset,
                    "Engine preset: a name listed below, or a preset FILE.json (default with --method "
                    "toksvig-map, lean, clean or mixture: that method's own preset)");
    cmd->add_option("--method", spec->method,
                    "Prefiltering method (default: the preset's): " + joined(methodNames()));
    cmd->add_option("--out", spec->out, "Output folder (created if missing)");
    cmd->add_option("--power", spec->power,
                    "Authored Blinn-Phong power when there is no --gloss map (default 1024)");
    cmd->add_option("--gloss", spec->gloss,
                    "Authored gloss map (first channel), in the preset's gloss encoding");
    cmd->add_option("--format", spec->format,
                    "Output format (default: the preset's): " + joined(formatNames()));
    cmd->add_option("--compression", spec->compression,
                    "DDS compression for every file (default: each file's preset choice): " +
                        joined(compressionNames()));
    cmd->add_option("--kernel", spec->kernel,
                    "Per-mip filter standing in for bilinear filtering: box, tent (default), gaussian");
    cmd->add_option("--border", spec->border, "Texture border: wrap (default) or clamp");
    cmd->add_option("--green", spec->green,
                    "Green convention of the INPUT map: opengl (+Y, default) or directx (-Y)");
    cmd->add_option("--layout", spec->layout,
                    "Input channels holding the normal: auto (default), rgb, rg (z rebuilt)");
    cmd->add_option("--encoding", spec->encoding,
                    "How the INPUT's stored values map to [-1, 1]: auto (default: integer files and float "
                    "files without negative finite values are unsigned, 2v-1), unsigned, or signed");
    cmd->add_option("--metallic", spec->metallic,
                    "Metalness in [0, 1] for presets with a metallic channel (gltf, unity)");
    cmd->add_option("--specular", spec->specular,
                    "Specular colour: a material of `burnish materials` (iron, gold, water...) or linear F0 "
                    "R,G,B (one value for a grey); bake.json's \"material\" records it in the preset "
                    "engine's own terms (glTF "
                    "KHR_materials_specular, Unreal Specular = F0/0.08, Godot/Filament 0.16 s^2, ...) with a "
                    "warning where the engine cannot hold it; sets --metallic from the class when not given");
    cmd->add_option("--material-class", spec->materialClass,
                    "metal or dielectric, for a --specular given as numbers (default: metal when --metallic "
                    ">= 0.5)");
    cmd->add_option("--lobes", spec->lobes,
                    "Mixture lobes per texel, 1..4 (--method mixture; default: as many as the preset stores, "
                    "3 in the mixture preset, whose lobe files mixture-lobe0..K-1 follow K; 1 is LEAN)");
    cmd->add_flag("--shaded-fit", spec->shadedFit,
                  "Fit the mixture's lobes to the shaded ground truth as well as to their moments (--method "
                  "mixture): a closer highlight on mips 2 and up, for final exports; the bake takes tens "
                  "of times longer (see README)");
    cmd->add_option("--mips", spec->mips,
                    "Mip levels written, N >= 1 (default all, down to 1x1; more than the chain holds is "
                    "clamped, with a note in the --json summary)");
    cmd->add_option("--detail", spec->detail,
                    "Detail normal map: baked into <stem>_detail.<ext> ([x, y, 0, variance], its own mips), "
                    "its constant variance into bake.json");
    cmd->add_option("--detail-fade", spec->detailFade,
                    "START:END mips of the detail map over which its normal fades to flat and its variance "
                    "to the constant (default 3:6)");
    cmd->add_flag("--force", spec->force, "Replace existing output files (still atomically, as a set)");
    cmd->add_flag("--allow-implausible", spec->allowImplausible,
                  "Bake an input that does not look like a tangent-space normal map");
    cmd->add_flag("--allow-8bit", spec->allowEightBit, "Store LEAN/CLEAN moments in 8-bit formats anyway");
    cmd->add_flag("--json", *json, "Print a machine-readable summary on stdout");
    cmd->add_option("--manifest", *manifest, "JSON file listing many jobs, run in order");
    cmd->add_option("--out-root", *outRoot,
                    "Refuse any job whose output folder is not inside DIR (links resolved); for manifests "
                    "from others")
        ->type_name("DIR");
    cmd->add_option("--ninja", *ninja,
                    "With --manifest: write a Ninja build file (one `burnish bake` per job) instead of "
                    "baking");
    cmd->add_flag("--report", spec->report,
                  "Also measure every method against the ground truth for this map and power (as burnish "
                  "evaluate, mips 1-4) and write the report into <out>/report/");
    // Built lazily: listing the presets parses them, which other subcommands need not pay for.
    cmd->footer([] { return helpFooter(); });

    auto farm = std::make_shared<FarmOptions>();
    auto* farmGroup = cmd->add_option_group("Library", "Baking a manifest in parts, resuming, on Slurm");
    farmGroup
        ->add_option("--only", farm->only, "With --manifest: bake only these jobs, by number (1-5,9,12-13)")
        ->type_name("LIST");
    farmGroup->add_flag("--skip-current", farm->skipCurrent,
                        "Skip every job whose output folder already holds its set as it would bake now "
                        "(bake.json records the same options and input hashes, its files are there)");
    farmGroup->add_flag("--keep-going", farm->keepGoing,
                        "Go on with the other jobs when one fails (exit status 1 at the end, the failed "
                        "jobs named)");
    farmGroup
        ->add_option("--status-dir", farm->statusDir,
                     "Write each job's outcome (baked, current, failed and its error) to "
                     "DIR/job-N.json")
        ->type_name("DIR");
    farmGroup->add_option("--threads", farm->threads, "Bake with at most N threads (default: every core)")
        ->check(CLI::Range(1, 4096));
    farmGroup
        ->add_option("--slurm", farm->slurm,
                     "With --manifest: write a Slurm job array baking it (DIR/burnish.sbatch) and a "
                     "check to run after it (DIR/burnish-check.sbatch), print how to submit them; "
                     "with --check: check the sets that plan bakes")
        ->type_name("DIR");
    farmGroup
        ->add_option("--tasks", farm->tasks,
                     "With --slurm: array tasks, each baking a run of consecutive jobs (default: one "
                     "per job, at most 1000)")
        ->check(CLI::Range(size_t(1), kMaxSlurmTasks));
    farmGroup->add_option("--partition", farm->partition, "With --slurm: the Slurm partition")
        ->type_name("NAME");
    farmGroup
        ->add_option("--mem-per-task", farm->memPerTask,
                     "With --slurm: memory each task asks for: auto (Burnish's own estimate for the "
                     "largest job) or a size as sbatch --mem reads it (4000M, 8G)")
        ->type_name("SIZE");
    farmGroup
        ->add_option("--cpus-per-task", farm->cpusPerTask,
                     "With --slurm: CPUs each task asks for and bakes with (default 1)")
        ->check(CLI::Range(1, 4096));
    farmGroup->add_flag("--check", farm->check,
                        "With --manifest: bake nothing; say which sets are current, failed (with the error "
                        "their bake left in --status-dir), stale or not baked; exit status 1 unless all are "
                        "current. With --slurm DIR: that plan's statuses, and DIR/summary.json and "
                        "DIR/summary.txt written");
    farmGroup
        ->add_option("--manifest-fnv1a64", farm->manifestHash,
                     "Refuse to run when the manifest's FNV-1a 64 is not this (the Slurm tasks' guard "
                     "against a manifest edited after its plan was written)")
        ->type_name("HEX");

    return [cmd, spec, manifest, json, ninja, outRoot, farm]() -> int {
        if (!builtinPresetErrors().empty()) return fail(builtinPresetErrors().front());
        const bool farmWork = !farm->only.empty() || farm->check || !farm->slurm.empty() ||
                              !farm->statusDir.empty() || !farm->manifestHash.empty();
        std::vector<BakeJobSpec> specs;
        if (!manifest->empty()) {
            if (!spec->input.empty()) return fail("give either an input map or --manifest, not both");
            auto read = readBakeManifest(*manifest, *spec);
            if (!read) return fail(read.error());
            specs = std::move(read.value());
        } else {
            if (!ninja->empty())
                return fail("--ninja needs --manifest FILE (the jobs to write build statements for)");
            if (farmWork)
                return fail("--only, --check, --slurm, --status-dir and --manifest-fnv1a64 need --manifest "
                            "FILE");
            if (spec->input.empty()) return fail("no input normal map given (see 'burnish bake --help')");
            specs.push_back(*spec);
        }
        if (!ninja->empty() && (!farm->slurm.empty() || farm->check || !farm->only.empty()))
            return fail("--ninja writes a build file for the whole manifest: give it without --slurm, "
                        "--check or --only");
        if (!farm->manifestHash.empty()) {
            const auto hash = fileFnv1a64(*manifest);
            if (!hash) return fail("--manifest: " + hash.error());
            if (hashHex(*hash) != farm->manifestHash)
                return fail("the manifest '" + *manifest +
                            "' changed since its Slurm plan was written "
                            "(FNV-1a 64 " +
                            hashHex(*hash) + ", the plan's " + farm->manifestHash +
                            "): write the plan again (--slurm DIR) and submit it");
        }
        std::optional<tbb::global_control> threads;
        if (farm->threads > 0)
            threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(farm->threads));
        std::optional<fs::path> root;
        if (!outRoot->empty()) root = fs::path(*outRoot);
        if (farm->check) {
            if (!farm->only.empty())
                return fail("--check checks every set of the manifest: give it without --only");
            return checkSets(*manifest, specs, *farm, *json);
        }

        std::vector<size_t> selected(specs.size());
        for (size_t i = 0; i < specs.size(); ++i)
            selected[i] = i;
        if (!farm->only.empty()) {
            auto picked = parseJobList(farm->only, specs.size());
            if (!picked) return fail(picked.error());
            selected = std::move(picked.value());
        }
        const bool numbered = !manifest->empty();
        auto at = [&](size_t i) {
            return numbered ? "manifest job " + std::to_string(i + 1) + " (" + specs[i].input + "): " : "";
        };
        // Every job is checked before the first one writes anything; with --keep-going a job that
        // fails its check is reported and the others go on.
        std::vector<BakeJob> jobs;
        std::vector<size_t> numbers;
        std::vector<std::pair<size_t, std::string>> failed;
        for (size_t i : selected) {
            auto job = resolveBakeJob(specs[i]);
            Status ok = job ? Status{} : Status{Error{job.error()}};
            if (ok && (numbered || root) && farm->keepGoing) ok = checkBakeJobs({*job}, root, false);
            if (!ok) {
                if (!farm->keepGoing) return fail(at(i) + ok.error());
                std::fprintf(stderr, "burnish: %s\n", printable(at(i) + ok.error()).c_str());
                failed.emplace_back(i, ok.error());
                continue;
            }
            jobs.push_back(std::move(job.value()));
            numbers.push_back(i + 1);
        }
        if (numbered || root)
            if (const Status s = checkBakeJobs(jobs, root, numbered, numbers); !s) return fail(s.error());
        if (!ninja->empty()) {
            // The build statements run this very binary.
            const auto exe = runningProgram("--ninja");
            if (!exe) return fail(exe.error());
            const auto written = writeBakeNinja(jobs, *manifest, *ninja, *exe);
            if (!written) return fail(written.error());
            if (*json)
                std::printf("%s\n", written->dump(2).c_str());
            else
                std::printf("%s: %zu build statements, %zu outputs; run ninja -f %s\n", ninja->c_str(),
                            jobs.size(), (*written)["outputs"].size(), ninja->c_str());
            return 0;
        }
        if (!farm->slurm.empty()) {
            if (!failed.empty()) return fail(at(failed.front().first) + failed.front().second);
            const auto exe = runningProgram("--slurm");
            if (!exe) return fail(exe.error());
            SlurmOptions options;
            options.tasks = farm->tasks;
            options.partition = farm->partition;
            options.memPerTask = farm->memPerTask;
            options.cpusPerTask = farm->cpusPerTask;
            options.defaults = jobDefaults(*cmd);
            options.workingFolder = fs::current_path();
            const auto written = writeSlurmPlan(jobs, *manifest, farm->slurm, *exe, options);
            if (!written) return fail(written.error());
            if (*json) {
                std::printf("%s\n", written->dump(2).c_str());
            } else {
                const Json& w = *written;
                std::printf(
                    "%s: %zu sets in %zu array tasks%s. Submit the array, then the check after it:\n"
                    "  %s\n",
                    w["dir"].get<std::string>().c_str(), w["jobs"].get<size_t>(), w["tasks"].get<size_t>(),
                    w["memPerTask"].is_null() ? ""
                                              : (", " + w["memPerTask"].get<std::string>() + " each").c_str(),
                    w["submit"].get<std::string>().c_str());
            }
            return 0;
        }

        ProgressBar progress;
        Json summaries = Json::array();
        const fs::path statusDir = farm->statusDir;
        auto report = [&](size_t number, const BakeJobSpec& job, Json status) {
            if (farm->statusDir.empty()) return;
            status["job"] = number;
            status["input"] = job.input;
            status["out"] = job.out;
            for (const char* name : {"SLURM_ARRAY_JOB_ID", "SLURM_ARRAY_TASK_ID", "SLURMD_NODENAME"})
                if (const char* v = std::getenv(name)) status[name] = v;
            if (const Status s = writeBakeStatus(statusDir, number, status); !s)
                std::fprintf(stderr, "burnish: warning: %s\n", printable(s.error()).c_str());
        };
        for (const auto& [i, error] : failed)
            report(i + 1, specs[i], {{"state", "failed"}, {"error", error}});
        for (size_t k = 0; k < jobs.size(); ++k) {
            const BakeJob& job = jobs[k];
            const size_t i = numbers[k] - 1;
            if (farm->skipCurrent && checkBakeSet(job).state == BakeSetState::Current) {
                report(i + 1, job.spec, {{"state", "current"}});
                if (*json)
                    summaries.push_back(
                        {{"input", job.spec.input}, {"out", job.spec.out}, {"skipped", "current"}});
                else
                    std::printf("%s -> %s: current, skipped\n", job.spec.input.c_str(), job.spec.out.c_str());
                std::fflush(stdout);
                continue;
            }
            const std::string name = fs::path(job.spec.input).filename().string();
            const std::string label =
                jobs.size() > 1 ? fmt::format("[{}/{}] {}", k + 1, jobs.size(), name) : name;
            progress.setLabel(label);
            auto run = runBakeJob(job, [&](double fraction, std::string_view stage) {
                progress.update(fraction, std::string(stage));
                return true;
            });
            progress.finish();
            if (!run) {
                report(i + 1, job.spec, {{"state", "failed"}, {"error", run.error()}});
                if (!farm->keepGoing) return fail(at(i) + run.error());
                std::fprintf(stderr, "burnish: %s\n", printable(at(i) + run.error()).c_str());
                failed.emplace_back(i, run.error());
                continue;
            }
            Json& summary = run.value().summary;
            report(i + 1, job.spec, {{"state", "baked"}, {"seconds", summary["seconds"]}});
            for (const auto& w : summary["warnings"])
                std::fprintf(stderr, "burnish: warning: %s\n", printable(w.get<std::string>()).c_str());
            if (!*json) {
                std::printf("%s -> %s: preset %s, method %s, %zu files + bake.json, %d mips, %.2f s\n",
                            job.spec.input.c_str(), job.spec.out.c_str(), job.preset.name.c_str(),
                            std::string(methodName(job.method)).c_str(), summary["files"].size(),
                            summary["mipCount"].get<int>(), summary["seconds"].get<double>());
                for (const auto& n : summary["notes"])
                    std::printf("  note: %s\n", n.get<std::string>().c_str());
                // In a log file (a Slurm task's) each line lands in order with the errors on stderr.
                std::fflush(stdout);
            }
            summaries.push_back(std::move(summary));
        }
        if (*json) {
            Json out = {{"jobs", summaries}};
            if (farm->keepGoing) {
                out["failed"] = Json::array();
                for (const auto& [i, error] : failed)
                    out["failed"].push_back({{"job", i + 1}, {"input", specs[i].input}, {"error", error}});
            }
            std::printf("%s\n", out.dump(2).c_str());
        }
        if (!failed.empty()) {
            std::vector<size_t> jobNumbers;
            for (const auto& f : failed)
                jobNumbers.push_back(f.first + 1);
            std::sort(jobNumbers.begin(), jobNumbers.end());
            std::string list;
            for (size_t n : jobNumbers)
                list += (list.empty() ? "" : ",") + std::to_string(n);
            return fail(fmt::format("{} of {} jobs failed ({} {}; each error above)", failed.size(),
                                    selected.size(), failed.size() == 1 ? "job" : "jobs", list));
        }
        return 0;
    };
});

} // namespace burnish::cli
