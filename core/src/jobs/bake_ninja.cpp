#include <burnish/core/jobs/bake_ninja.h>

#include <burnish/core/io/image.h>
#include <burnish/core/util/files.h>

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <map>
#include <utility>

namespace burnish {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string absolutePath(const std::string& p) {
    return fs::absolute(fs::path(p)).lexically_normal().string();
}

/// A job's input as a command names it: a file absolute, a built-in sample by its name.
std::string inputArgument(const std::string& input) {
    return isSampleBakeInput(input) ? input : absolutePath(input);
}

/// A path in a ninja build line: '$', ' ' and ':' are escaped with '$'; a line break or '|' (which
/// ends a path in Ninja's lexer, with no escape) cannot be written.
Result<std::string> ninjaPath(const std::string& p) {
    std::string out;
    for (char c : p) {
        if (c == '\n' || c == '\r')
            return Error{"path '" + p + "' holds a line break, which Ninja cannot express"};
        if (c == '|') return Error{"path '" + p + "' holds '|', which Ninja cannot express in a path"};
        if (c == '$' || c == ' ' || c == ':') out += '$';
        out += c;
    }
    return out;
}

/// A variable's value in a ninja file: only '$' needs escaping (ninja expands it); commands hold no
/// newline.
std::string ninjaValue(const std::string& v) {
    std::string out;
    for (char c : v)
        out += c == '$' ? std::string("$$") : std::string(1, c);
    return out;
}

struct NinjaJob {
    std::vector<std::string> outputs; // absolute
    std::vector<std::string> inputs;  // absolute
    std::string command;
    std::string description;
};

/// The extent of a job's input: read from its file's header, or the size a sample is baked at.
Result<std::pair<int, int>> inputExtent(const std::string& input) {
    if (isSampleBakeInput(input)) return std::pair{kSampleBakeSize, kSampleBakeSize};
    const auto header = readImageHeader(input);
    if (!header) return Error{header.error()};
    if (header->channels < 2)
        return Error{"'" + input + "' has 1 channel; a normal map needs 2 (RG) to 4 (RGBA)"};
    return std::pair{header->width, header->height};
}

/// What one job reads and writes, without baking: its outputs (plannedBakeOutputs), its inputs.
Result<NinjaJob> planNinjaJob(const std::string& exe, const BakeJob& job, const std::string& manifest) {
    auto outputs = plannedBakeOutputs(job);
    if (!outputs) return Error{outputs.error()};
    NinjaJob nj;
    nj.outputs = std::move(outputs).value();
    const fs::path out = absolutePath(job.spec.out);
    if (!isSampleBakeInput(job.spec.input)) nj.inputs.push_back(absolutePath(job.spec.input));
    if (job.spec.gloss) nj.inputs.push_back(absolutePath(*job.spec.gloss));
    if (job.spec.detail) nj.inputs.push_back(absolutePath(*job.spec.detail));
    if (job.preset.origin != "built-in") nj.inputs.push_back(absolutePath(job.preset.origin));
    nj.inputs.push_back(absolutePath(manifest));
    for (const auto& a : bakeJobCommand(exe, job))
        nj.command += (nj.command.empty() ? "" : " ") + shellQuoted(a);
    nj.description = "burnish bake " + fs::path(job.spec.input).filename().string() + " -> " + out.string();
    return nj;
}

/// Whether `path` lies inside `root` (both made absolute, links resolved as far as they exist).
bool inside(const fs::path& path, const fs::path& root) {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
    const fs::path r = fs::weakly_canonical(fs::absolute(root), ec);
    const auto [rootEnd, pathAt] = std::mismatch(r.begin(), r.end(), p.begin(), p.end());
    return rootEnd == r.end() || (std::next(rootEnd) == r.end() && rootEnd->empty());
}

} // namespace

Result<std::vector<std::string>> plannedBakeOutputs(const BakeJob& job) {
    const auto extent = inputExtent(job.spec.input);
    if (!extent) return Error{extent.error()};
    if (job.spec.gloss)
        if (const auto gloss = readImageHeader(*job.spec.gloss); !gloss)
            return Error{"--gloss: " + gloss.error()};
    BakeRecord record;
    auto shape = bakeJobShape(job, extent->first, extent->second, record);
    if (!shape) return Error{shape.error()};
    const auto plan = planExport(*shape, job.preset, job.exportOptions, record);
    if (!plan) return Error{plan.error()};
    std::vector<std::string> outputs;
    const fs::path out = absolutePath(job.spec.out);
    for (const auto& f : plan->files)
        for (const auto& p : f.paths)
            outputs.push_back((out / p).string());
    outputs.push_back((out / plan->manifestPath).string());
    if (job.spec.report)
        for (const auto f : kBakeReportFiles)
            outputs.push_back((out / kBakeReportFolder / f).string());
    return outputs;
}

Status checkBakeJobs(const std::vector<BakeJob>& jobs, const std::optional<std::filesystem::path>& outRoot,
                     bool fromManifest, const std::vector<size_t>& numbers) {
    std::map<std::string, size_t> owner; // output -> job number
    for (size_t i = 0; i < jobs.size(); ++i) {
        const size_t number = i < numbers.size() ? numbers[i] : i + 1;
        const std::string at =
            fromManifest ? "manifest job " + std::to_string(number) + " (" + jobs[i].spec.input + "): " : "";
        if (outRoot && !inside(jobs[i].spec.out, *outRoot))
            return Error{at + "its output folder '" + jobs[i].spec.out + "' is outside --out-root '" +
                         outRoot->string() + "'"};
        auto nj = planNinjaJob("burnish", jobs[i], "manifest");
        if (!nj) return Error{at + nj.error()};
        for (const auto& o : nj->outputs) {
            // Compared as the files they are: links in the folders resolved (two jobs writing one
            // file through a linked folder were both run, the second replacing the first).
            std::error_code ec;
            const fs::path real = fs::weakly_canonical(fs::path(o), ec);
            const auto [it, fresh] = owner.emplace(ec ? o : real.string(), number);
            if (!fresh)
                return Error{at + "writes '" + o + "', which job " + std::to_string(it->second) +
                             " writes too"};
        }
    }
    return {};
}

std::string shellQuoted(const std::string& text) {
    std::string q = "'";
    for (char c : text)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

std::vector<std::string> bakeJobCommand(const std::string& exe, const BakeJob& job) {
    const BakeJobSpec& s = job.spec;
    std::vector<std::string> args{
        exe,
        "bake",
        inputArgument(s.input),
        "--out",
        absolutePath(s.out),
        "--preset",
        s.preset,
        "--method",
        std::string(methodName(job.method)),
        "--power",
        fmt::format("{}", job.bake.basePower),
        "--format",
        std::string(exportFormatName(job.exportOptions.format.value_or(job.preset.format))),
        "--kernel",
        std::string(kernelName(job.bake.pyramid.kernel)),
        "--border",
        s.border.value_or("wrap"),
        "--green",
        s.green.value_or("opengl"),
        "--layout",
        s.layout.value_or("auto"),
        "--encoding",
        s.encoding.value_or("auto"),
        "--force"};
    // Options whose absence means "each file's own choice" or "none" stay absent.
    if (s.gloss) args.insert(args.end(), {"--gloss", absolutePath(*s.gloss)});
    if (job.exportOptions.compression)
        args.insert(args.end(),
                    {"--compression", std::string(ddsCompressionName(*job.exportOptions.compression))});
    if (s.metallic) args.insert(args.end(), {"--metallic", fmt::format("{}", *s.metallic)});
    if (s.specular) args.insert(args.end(), {"--specular", *s.specular});
    if (s.materialClass) args.insert(args.end(), {"--material-class", *s.materialClass});
    if (s.mips) args.insert(args.end(), {"--mips", std::to_string(*s.mips)});
    if (s.lobes) args.insert(args.end(), {"--lobes", std::to_string(*s.lobes)});
    if (s.detail)
        args.insert(args.end(), {"--detail", absolutePath(*s.detail), "--detail-fade",
                                 fmt::format("{}:{}", job.detail.fadeStartMip, job.detail.fadeEndMip)});
    if (s.allowImplausible) args.emplace_back("--allow-implausible");
    if (s.allowEightBit) args.emplace_back("--allow-8bit");
    if (s.shadedFit) args.emplace_back("--shaded-fit");
    if (s.report) args.emplace_back("--report");
    return args;
}

Result<nlohmann::json> writeBakeNinja(const std::vector<BakeJob>& jobs, const std::string& manifest,
                                      const std::string& path, const std::string& exe) {
    std::string text = "# Generated by `burnish bake --manifest " + fs::path(manifest).filename().string() +
                       " --ninja`: one `burnish bake` per job.\n"
                       "# Run with `ninja -f " +
                       fs::path(path).filename().string() +
                       " -j N`; a job reruns when one of its inputs (maps, preset file, manifest) "
                       "changed.\n"
                       "ninja_required_version = 1.3\n\n"
                       "rule burnish_bake\n"
                       "  command = $cmd\n"
                       "  description = $desc\n"
                       "  restat = 1\n";
    // Two jobs writing one file would make ninja refuse the whole file.
    if (const Status s = checkBakeJobs(jobs); !s) return Error{s.error()};
    Json outputs = Json::array();
    for (size_t i = 0; i < jobs.size(); ++i) {
        const std::string at = "manifest job " + std::to_string(i + 1) + " (" + jobs[i].spec.input + "): ";
        auto nj = planNinjaJob(exe, jobs[i], manifest);
        if (!nj) return Error{at + nj.error()};
        std::string line = "\nbuild";
        for (const auto& o : nj->outputs) {
            const auto e = ninjaPath(o);
            if (!e) return Error{at + e.error()};
            line += " " + *e;
            outputs.push_back(o);
        }
        line += ": burnish_bake";
        for (const auto& in : nj->inputs) {
            const auto e = ninjaPath(in);
            if (!e) return Error{at + e.error()};
            line += " " + *e;
        }
        text += line + "\n  cmd = " + ninjaValue(nj->command) + "\n  desc = " + ninjaValue(nj->description) +
                "\n";
    }
    if (const Status s = writeFileAtomic(path, text, Overwrite::Allow); !s)
        return Error{"--ninja: " + s.error()};
    return Json{{"ninja", path}, {"jobs", jobs.size()}, {"outputs", outputs}};
}

} // namespace burnish
