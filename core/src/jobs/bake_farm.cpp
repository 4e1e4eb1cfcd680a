#include <burnish/core/jobs/bake_farm.h>

#include <burnish/core/io/image.h>
#include <burnish/core/jobs/bake_ninja.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/hash.h>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <set>
#include <utility>

namespace burnish {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

constexpr std::string_view kBakeJson = "bake.json";

/// The input files a job reads, by bake.json's names for them, with words for a message.
struct InputFile {
    const char* key;
    const char* words;
};
constexpr InputFile kInputFiles[] = {{"normalMap", "normal map"},
                                     {"glossMap", "gloss map"},
                                     {"detailMap", "detail map"},
                                     {"preset", "preset file"}};

Result<Json> hashOf(const std::string& path, std::string_view what) {
    const auto hash = fileFnv1a64(path);
    if (!hash) return Error{std::string(what) + ": " + hash.error()};
    return Json(hashHex(*hash));
}

/// Whether `text` can stand in an #SBATCH line as one value: Slurm splits those lines at white
/// space, reads quotes and expands '%' in file names.
bool sbatchSafe(std::string_view text) {
    return std::none_of(text.begin(), text.end(), [](char c) {
        return std::isspace(static_cast<unsigned char>(c)) || c == '%' || c == '"' || c == '\'' ||
               c == '\\' || static_cast<unsigned char>(c) < 0x20;
    });
}

/// A size as sbatch --mem reads it: digits with an optional unit K, M, G or T.
bool slurmSize(std::string_view text) {
    if (text.empty()) return false;
    size_t digits = 0;
    while (digits < text.size() && std::isdigit(static_cast<unsigned char>(text[digits])))
        ++digits;
    if (digits == 0 || text.size() - digits > 1) return false;
    return digits == text.size() || std::string_view("KMGT").find(text.back()) != std::string_view::npos;
}

std::string chunkText(const std::pair<size_t, size_t>& chunk) {
    return chunk.first == chunk.second ? std::to_string(chunk.first)
                                       : fmt::format("{}-{}", chunk.first, chunk.second);
}

/// Numbers as a compact list ("1-3,7").
std::string listText(const std::vector<size_t>& numbers) {
    std::string text;
    for (size_t i = 0; i < numbers.size();) {
        size_t j = i;
        while (j + 1 < numbers.size() && numbers[j + 1] == numbers[j] + 1)
            ++j;
        text += (text.empty() ? "" : ",") + chunkText({numbers[i], numbers[j]});
        i = j + 1;
    }
    return text;
}

} // namespace

Result<Json> bakeInputHashes(const BakeJob& job) {
    Json hashes = Json::object();
    for (const auto& f : kInputFiles)
        hashes[f.key] = nullptr;
    if (!isSampleBakeInput(job.spec.input)) {
        auto h = hashOf(job.spec.input, "normal map");
        if (!h) return Error{h.error()};
        hashes["normalMap"] = *h;
    }
    // An in-memory gloss stands in for the file, which is then not read (bake.json hashes its values).
    if (job.spec.gloss && !job.spec.authoredGloss) {
        auto h = hashOf(*job.spec.gloss, "--gloss");
        if (!h) return Error{h.error()};
        hashes["glossMap"] = *h;
    }
    if (job.spec.detail) {
        auto h = hashOf(*job.spec.detail, "--detail");
        if (!h) return Error{h.error()};
        hashes["detailMap"] = *h;
    }
    if (job.preset.origin != "built-in") {
        auto h = hashOf(job.preset.origin, "--preset");
        if (!h) return Error{h.error()};
        hashes["preset"] = *h;
    }
    return hashes;
}

std::string bakeOptionsHash(const BakeJob& job) {
    const auto args = bakeJobCommand("", job);
    std::uint64_t hash = kFnv1a64Basis;
    for (size_t i = 1; i < args.size(); ++i) {
        if (args[i] == "--out") {
            ++i;
            continue;
        }
        if (args[i] == "--force") continue;
        hash = fnv1a64(args[i].data(), args[i].size(), hash);
        hash = fnv1a64("", 1, hash); // the NUL between words: "a b" and "ab" differ
    }
    return hashHex(hash);
}

std::string_view bakeSetStateName(BakeSetState state) {
    switch (state) {
    case BakeSetState::Current:
        return "current";
    case BakeSetState::Stale:
        return "stale";
    case BakeSetState::Missing:
        return "missing";
    }
    return "missing";
}

BakeSetCheck checkBakeSet(const BakeJob& job) {
    const fs::path out = job.spec.out;
    const fs::path index = out / kBakeJson;
    std::error_code ec;
    if (!fs::exists(index, ec)) return {BakeSetState::Missing, "no bake.json in '" + out.string() + "'"};
    const auto text = readFile(index);
    if (!text) return {BakeSetState::Stale, "its bake.json cannot be read: " + text.error()};
    Json record;
    try {
        record = Json::parse(*text);
    } catch (const Json::exception& e) {
        return {BakeSetState::Stale, std::string("its bake.json does not parse: ") + e.what()};
    }
    const Json* options = record.is_object() ? &record["options"] : nullptr;
    const Json* recorded =
        record.is_object() && record["inputs"].is_object() ? &record["inputs"]["fnv1a64"] : nullptr;
    if (!options || !options->is_object() || !options->contains("fnv1a64") || !recorded ||
        !recorded->is_object())
        return {BakeSetState::Stale, "its bake.json records no input and option hashes (an older Burnish "
                                     "baked it)"};
    if ((*options)["fnv1a64"] != bakeOptionsHash(job))
        return {BakeSetState::Stale, "it was baked from another input path or with other options"};
    const auto now = bakeInputHashes(job);
    if (!now) return {BakeSetState::Stale, "its input cannot be read now: " + now.error()};
    for (const auto& f : kInputFiles)
        if (recorded->value(f.key, Json()) != (*now)[f.key])
            return {BakeSetState::Stale, fmt::format("its {} changed since it was baked", f.words)};
    std::vector<std::string> files;
    if (record["files"].is_array())
        for (const Json& f : record["files"])
            if (f.is_object() && f["paths"].is_array())
                for (const Json& p : f["paths"])
                    if (p.is_string()) files.push_back(p.get<std::string>());
    if (record["detail"].is_object() && record["detail"]["file"].is_string())
        files.push_back(record["detail"]["file"].get<std::string>());
    if (job.spec.report)
        for (const auto f : kBakeReportFiles)
            files.push_back((fs::path(kBakeReportFolder) / f).string());
    for (const auto& f : files)
        if (!fs::is_regular_file(out / f, ec))
            return {BakeSetState::Stale, "its file '" + f + "' is missing"};
    return {BakeSetState::Current, ""};
}

std::vector<std::pair<size_t, size_t>> bakeChunks(size_t jobs, size_t tasks) {
    std::vector<std::pair<size_t, size_t>> chunks;
    if (jobs == 0 || tasks == 0) return chunks;
    const size_t n = std::min(jobs, tasks);
    const size_t base = jobs / n;
    const size_t extra = jobs % n;
    size_t first = 1;
    for (size_t k = 0; k < n; ++k) {
        const size_t size = base + (k < extra ? 1 : 0);
        chunks.emplace_back(first, first + size - 1);
        first += size;
    }
    return chunks;
}

Result<std::vector<size_t>> parseJobList(std::string_view list, size_t jobs) {
    const std::string quoted = "--only '" + std::string(list) + "'";
    if (list.empty()) return Error{"--only: an empty list (give job numbers such as 1-5,9)"};
    std::set<size_t> picked;
    auto number = [&](std::string_view text) -> Result<size_t> {
        size_t value = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (text.empty() || ec != std::errc() || end != text.data() + text.size())
            return Error{quoted + ": '" + std::string(text) + "' is not a job number"};
        if (value < 1 || value > jobs)
            return Error{fmt::format("{}: job {} is not in the manifest's 1-{}", quoted, value, jobs)};
        return value;
    };
    size_t start = 0;
    while (start <= list.size()) {
        const size_t comma = std::min(list.find(',', start), list.size());
        const std::string_view item = list.substr(start, comma - start);
        const size_t dash = item.find('-');
        const auto first = number(item.substr(0, dash));
        if (!first) return Error{first.error()};
        size_t last = *first;
        if (dash != std::string_view::npos) {
            const auto end = number(item.substr(dash + 1));
            if (!end) return Error{end.error()};
            if (*end < *first)
                return Error{quoted + ": the range '" + std::string(item) + "' runs backwards"};
            last = *end;
        }
        for (size_t n = *first; n <= last; ++n)
            picked.insert(n - 1);
        start = comma + 1;
    }
    return std::vector<size_t>(picked.begin(), picked.end());
}

Status writeBakeStatus(const fs::path& dir, size_t jobNumber, const Json& status) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return Error{"--status-dir: cannot create '" + dir.string() + "': " + ec.message()};
    const Status s =
        writeFileAtomic(dir / fmt::format("job-{}.json", jobNumber), status.dump(2) + "\n", Overwrite::Allow);
    if (!s) return Error{"--status-dir: " + s.error()};
    return {};
}

std::optional<Json> readBakeStatus(const fs::path& dir, size_t jobNumber) {
    const fs::path path = dir / fmt::format("job-{}.json", jobNumber);
    std::error_code ec;
    if (!fs::exists(path, ec)) return std::nullopt;
    const auto text = readFile(path);
    if (!text) return std::nullopt;
    try {
        Json status = Json::parse(*text);
        if (status.is_object()) return status;
    } catch (const Json::exception&) {
    }
    return std::nullopt;
}

Json summarizeBakeSets(const std::string& manifest, const std::vector<BakeJobSpec>& specs,
                       const std::vector<Result<BakeJob>>& jobs, const std::optional<fs::path>& statusDir,
                       const std::vector<std::pair<size_t, size_t>>& chunks) {
    Json counts = {{"current", 0}, {"failed", 0}, {"stale", 0}, {"missing", 0}};
    Json sets = Json::array();
    std::set<size_t> rerunTasks;
    std::vector<size_t> rerunJobs;
    for (size_t i = 0; i < jobs.size() && i < specs.size(); ++i) {
        const size_t number = i + 1;
        Json entry = {{"job", number}, {"input", specs[i].input}, {"out", specs[i].out}};
        if (!jobs[i]) {
            entry["state"] = "failed";
            entry["reason"] = jobs[i].error();
        } else {
            const BakeSetCheck check = checkBakeSet(*jobs[i]);
            if (check.state == BakeSetState::Current) {
                counts["current"] = counts["current"].get<int>() + 1;
                continue;
            }
            const auto status = statusDir ? readBakeStatus(*statusDir, number) : std::nullopt;
            if (status && status->value("state", "") == "failed") {
                entry["state"] = "failed";
                entry["reason"] = status->value("error", "failed (no error recorded)");
            } else {
                entry["state"] = std::string(bakeSetStateName(check.state));
                entry["reason"] = check.reason;
            }
        }
        const std::string state = entry["state"];
        counts[state] = counts[state].get<int>() + 1;
        for (size_t k = 0; k < chunks.size(); ++k)
            if (chunks[k].first <= number && number <= chunks[k].second) {
                entry["task"] = k;
                rerunTasks.insert(k);
            }
        rerunJobs.push_back(number);
        sets.push_back(std::move(entry));
    }
    return Json{{"schema", "burnish-bake-summary"},
                {"version", 1},
                {"manifest", manifest},
                {"jobs", jobs.size()},
                {"counts", counts},
                {"sets", sets},
                {"rerunJobs", listText(rerunJobs)},
                {"rerunTasks", listText(std::vector<size_t>(rerunTasks.begin(), rerunTasks.end()))}};
}

std::string bakeSummaryText(const Json& summary, size_t maxSets) {
    const Json& c = summary["counts"];
    std::string text =
        fmt::format("{}: {} sets: {} current", summary.value("manifest", std::string("manifest")),
                    summary.value("jobs", size_t(0)), c.value("current", 0));
    for (const char* state : {"failed", "stale", "missing"})
        if (c.value(state, 0) > 0)
            text += fmt::format(", {} {}", c.value(state, 0),
                                std::string_view(state) == "missing" ? "not baked" : state);
    text += "\n";
    const Json& sets = summary["sets"];
    for (size_t i = 0; i < sets.size() && i < maxSets; ++i) {
        const Json& s = sets[i];
        const std::string task = s.contains("task") ? fmt::format(" (task {})", s["task"].get<size_t>()) : "";
        const std::string state = s.value("state", "");
        text += fmt::format("  {:<9} job {}{}: {} -> {}\n            {}\n",
                            state == "missing" ? "not baked" : state, s.value("job", size_t(0)), task,
                            s.value("input", ""), s.value("out", ""), s.value("reason", ""));
    }
    if (sets.size() > maxSets)
        text += fmt::format("  ... and {} more (every set is in summary.json)\n", sets.size() - maxSets);
    if (summary.contains("rerun") && !sets.empty()) text += summary["rerun"].get<std::string>() + "\n";
    return text;
}

Result<BakeMemoryEstimate> estimatedJobBytes(const BakeJob& job) {
    BakeMemoryEstimate e{0, kSampleBakeSize, kSampleBakeSize};
    // OpenImageIO is loaded for a map core does not decode itself, or a file format it does not write.
    bool openImageIo = exportFormatUsesOpenImageIo(job.exportOptions.format.value_or(job.preset.format));
    bool coreDecoded = isSampleBakeInput(job.spec.input); // a sample is made in memory, not decoded
    if (!isSampleBakeInput(job.spec.input)) {
        const auto header = readImageHeader(job.spec.input);
        if (!header) return Error{header.error()};
        e.width = header->width;
        e.height = header->height;
        coreDecoded = decodedByCore(header->source.formatName, header->source.channelType);
        openImageIo = openImageIo || !coreDecoded;
    }
    const auto perTexel = bakeJobBytesPerTexel(job, e.width, e.height, coreDecoded);
    if (!perTexel) return Error{perTexel.error()};
    if (job.spec.gloss) {
        const auto gloss = readImageHeader(*job.spec.gloss);
        if (gloss)
            openImageIo = openImageIo || !decodedByCore(gloss->source.formatName, gloss->source.channelType);
    }
    std::uint64_t detailBytes = 0;
    if (job.spec.detail) {
        // The detail map is baked after the method's textures, which stay: its decoded normals, pyramid
        // and four-channel chain add about kDetailBytesPerTexel per detail texel.
        const auto detail = readImageHeader(*job.spec.detail);
        if (!detail) return Error{"--detail: " + detail.error()};
        detailBytes = std::uint64_t(kDetailBytesPerTexel * double(detail->width) * double(detail->height));
        openImageIo = openImageIo || !decodedByCore(detail->source.formatName, detail->source.channelType);
    }
    e.bytes = estimatedBakeBytes(*perTexel, e.width, e.height, openImageIo) + detailBytes;
    return e;
}

Result<std::uint64_t> slurmMemoryMiB(const std::vector<BakeJob>& jobs) {
    std::uint64_t most = 0;
    for (size_t i = 0; i < jobs.size(); ++i) {
        const auto need = estimatedJobBytes(jobs[i]);
        if (!need)
            return Error{fmt::format("manifest job {} ({}): {}", i + 1, jobs[i].spec.input, need.error())};
        most = std::max(most, need->bytes);
    }
    constexpr std::uint64_t kMiB = 1 << 20;
    return std::max(kSlurmMinimumMiB, (most + kMiB - 1) / kMiB);
}

Result<Json> writeSlurmPlan(const std::vector<BakeJob>& jobs, const std::string& manifest,
                            const fs::path& dir, const std::string& exe, const SlurmOptions& options) {
    if (jobs.empty()) return Error{"--slurm: the manifest has no jobs"};
    const fs::path folder = fs::absolute(dir).lexically_normal();
    const fs::path work = fs::absolute(options.workingFolder).lexically_normal();
    for (const fs::path& p : {folder, work})
        if (!sbatchSafe(p.string()))
            return Error{"--slurm: Slurm's #SBATCH lines cannot name the folder '" + p.string() +
                         "' (it holds white space, a quote, a backslash or '%'): choose another"};
    if (options.tasks > kMaxSlurmTasks)
        return Error{fmt::format("--tasks {}: Slurm arrays hold at most {} tasks by default (MaxArraySize); "
                                 "give fewer tasks, each bakes a run of sets",
                                 options.tasks, kMaxSlurmTasks)};
    if (options.cpusPerTask < 1) return Error{"--cpus-per-task must be at least 1"};
    if (!options.partition.empty() &&
        !std::all_of(options.partition.begin(), options.partition.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' ||
                   c == ',';
        }))
        return Error{"--partition '" + options.partition +
                     "': a partition name holds letters, digits, '_', "
                     "'-', '.' (',' between several)"};
    std::string mem;
    if (options.memPerTask == "auto") {
        const auto mib = slurmMemoryMiB(jobs);
        if (!mib) return Error{"--mem-per-task auto: " + mib.error()};
        mem = std::to_string(*mib) + "M";
    } else if (!options.memPerTask.empty()) {
        if (!slurmSize(options.memPerTask))
            return Error{"--mem-per-task '" + options.memPerTask +
                         "': give auto (Burnish's estimate) or a size as sbatch --mem reads it (4000M, 8G)"};
        mem = options.memPerTask;
    }
    const auto manifestHash = fileFnv1a64(manifest);
    if (!manifestHash) return Error{"--manifest: " + manifestHash.error()};
    const std::string manifestPath = fs::absolute(manifest).lexically_normal().string();
    const auto chunks = bakeChunks(jobs.size(), options.tasks ? options.tasks : kMaxSlurmTasks);

    std::error_code ec;
    for (const fs::path& p : {folder, folder / "logs", folder / "status"}) {
        fs::create_directories(p, ec);
        if (ec) return Error{"--slurm: cannot create '" + p.string() + "': " + ec.message()};
    }
    const std::string taskScript = (folder / "burnish.sbatch").string();
    const std::string checkScript = (folder / "burnish-check.sbatch").string();
    std::string defaults;
    for (const auto& d : options.defaults)
        defaults += " " + shellQuoted(d);
    const std::string submit = "jid=$(sbatch --parsable " + shellQuoted(taskScript) +
                               ") && sbatch --dependency=afterany:${jid%%;*} " + shellQuoted(checkScript);
    const std::string header = fmt::format(
        "#!/bin/bash\n"
        "# Written by `burnish bake --manifest {} --slurm {}`:\n"
        "# {} sets in {} array tasks, each task one `burnish bake --only` run of sets. Submit the array and\n"
        "# the check after it (the check runs however the tasks end):\n"
        "#   {}\n"
        "# A rerun skips every set already current, so rerunning a failed task alone is\n"
        "#   sbatch --array=K {}\n"
        "# Every node must see the manifest, its maps, the output folders and {}.\n",
        manifestPath, folder.string(), jobs.size(), chunks.size(), submit, shellQuoted(taskScript), exe);
    std::string resources = "#SBATCH --chdir=" + work.string() + "\n";
    // The script goes there itself too: run by hand (bash burnish.sbatch) it reads the same paths.
    const std::string cdLine = "cd " + shellQuoted(work.string()) + " || exit 2\n";
    if (!options.partition.empty()) resources += "#SBATCH --partition=" + options.partition + "\n";

    std::string task = header + "#SBATCH --job-name=burnish-bake\n" +
                       fmt::format("#SBATCH --array=0-{}\n", chunks.size() - 1) +
                       "#SBATCH --output=" + (folder / "logs" / "bake-%A_%a.out").string() + "\n" +
                       fmt::format("#SBATCH --cpus-per-task={}\n", options.cpusPerTask) +
                       (mem.empty() ? "" : "#SBATCH --mem=" + mem + "\n") + resources + "set -u\n" + cdLine +
                       "case \"${SLURM_ARRAY_TASK_ID:-}\" in\n";
    for (size_t k = 0; k < chunks.size(); ++k)
        task += fmt::format("  {}) only={} ;;\n", k, chunkText(chunks[k]));
    task += fmt::format("  *) echo \"burnish.sbatch: array task '${{SLURM_ARRAY_TASK_ID:-}}' is not one of "
                        "0-{} (submit this file with sbatch)\" >&2; exit 2 ;;\nesac\n",
                        chunks.size() - 1);
    // The manifest as the user named it, from the folder they named it in (--chdir): each job's paths
    // are then spelled as a local `burnish bake --manifest` spells them, and so is bake.json.
    task += "exec " + shellQuoted(exe) + " bake --manifest " + shellQuoted(manifest) + defaults +
            " --manifest-fnv1a64 " + hashHex(*manifestHash) +
            " --only \"$only\" --force --skip-current --keep-going --status-dir " +
            shellQuoted((folder / "status").string()) +
            fmt::format(" --threads \"${{SLURM_CPUS_PER_TASK:-{}}}\"\n", options.cpusPerTask);

    std::string check = header + "#SBATCH --job-name=burnish-check\n" +
                        "#SBATCH --output=" + (folder / "logs" / "check-%j.out").string() + "\n" +
                        "#SBATCH --cpus-per-task=1\n" + resources + cdLine + "exec " + shellQuoted(exe) +
                        " bake --manifest " + shellQuoted(manifest) + defaults + " --slurm " +
                        shellQuoted(folder.string()) + " --check\n";

    Json tasks = Json::array();
    for (size_t k = 0; k < chunks.size(); ++k)
        tasks.push_back({{"task", k}, {"first", chunks[k].first}, {"last", chunks[k].second}});
    const Json plan = {{"schema", "burnish-slurm-plan"},
                       {"version", 1},
                       {"manifest", manifestPath},
                       {"manifestFnv1a64", hashHex(*manifestHash)},
                       {"jobs", jobs.size()},
                       {"tasks", tasks},
                       {"memPerTask", mem.empty() ? Json(nullptr) : Json(mem)},
                       {"cpusPerTask", options.cpusPerTask},
                       {"partition", options.partition.empty() ? Json(nullptr) : Json(options.partition)},
                       {"defaults", options.defaults},
                       {"workingFolder", work.string()},
                       {"program", exe}};
    for (const auto& [path, text] :
         {std::pair{folder / "burnish.sbatch", task}, std::pair{folder / "burnish-check.sbatch", check},
          std::pair{folder / "plan.json", plan.dump(2) + "\n"}})
        if (const Status s = writeFileAtomic(path, text, Overwrite::Allow); !s)
            return Error{"--slurm: " + s.error()};
    return Json{{"dir", folder.string()},
                {"jobs", jobs.size()},
                {"tasks", chunks.size()},
                {"memPerTask", mem.empty() ? Json(nullptr) : Json(mem)},
                {"scripts", {taskScript, checkScript}},
                {"submit", submit}};
}

Result<SlurmPlan> readSlurmPlan(const fs::path& dir) {
    const fs::path path = dir / "plan.json";
    const auto text = readFile(path);
    if (!text) return Error{"--slurm: no plan to check (write one with --slurm DIR first): " + text.error()};
    try {
        const Json plan = Json::parse(*text);
        if (plan.value("schema", "") != "burnish-slurm-plan" || plan.value("version", 0) != 1)
            return Error{"--slurm: '" + path.string() + "' is not a Burnish Slurm plan (version 1)"};
        SlurmPlan out;
        out.manifest = plan.at("manifest").get<std::string>();
        out.manifestHash = plan.at("manifestFnv1a64").get<std::string>();
        for (const Json& t : plan.at("tasks"))
            out.chunks.emplace_back(t.at("first").get<size_t>(), t.at("last").get<size_t>());
        return out;
    } catch (const Json::exception& e) {
        return Error{"--slurm: '" + path.string() + "' does not parse as a plan: " + e.what()};
    }
}

} // namespace burnish
