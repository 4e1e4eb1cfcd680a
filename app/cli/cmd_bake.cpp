// `burnish bake`: a normal map (and an optional authored gloss map and detail normal map) through
// a prefiltering method into an engine preset's textures with their mip chains, plus bake.json.
// One job from the options, or many from a manifest; or, with --ninja, a Ninja build file that
// runs the manifest's jobs one `burnish bake` each.
#include "command.h"
#include "common.h"

#include <burnish/core/atomic_file.h>
#include <burnish/core/bake.h>
#include <burnish/core/detail.h>
#include <burnish/core/evaluate_report.h>
#include <burnish/core/export.h>
#include <burnish/core/image.h>
#include <burnish/core/normal_map.h>
#include <burnish/core/presets.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <charconv>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <unistd.h>
#include <vector>

namespace burnish::cli {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// One bake as the user described it (names not yet resolved).
struct JobSpec {
    std::string input;
    std::string out;
    std::string preset;
    std::optional<std::string> method;
    std::optional<double> power;
    std::optional<std::string> gloss;
    std::optional<std::string> format;
    std::optional<std::string> compression;
    std::optional<std::string> kernel;
    std::optional<std::string> border;
    std::optional<std::string> green;
    std::optional<std::string> layout;
    std::optional<double> metallic;
    std::optional<int> mips;
    std::optional<std::string> detail;
    std::optional<std::string> detailFade; // "START:END", in the detail map's mips
    bool force = false;
    bool allowImplausible = false;
    bool allowEightBit = false;
};

/// A job with every name resolved and checked: nothing of it is read or written yet.
struct Job {
    JobSpec spec;
    Preset preset;
    Method method = Method::VarianceToGloss;
    BakeOptions bake;
    NormalMapOptions normalMap;
    ExportOptions exportOptions;
    DetailOptions detail; // used when spec.detail is set
};

template <class T>
Result<T> choice(const char* option, const std::string& value,
                 std::initializer_list<std::pair<const char*, T>> choices) {
    std::string names;
    for (const auto& [name, v] : choices) {
        if (value == name) return v;
        names += (names.empty() ? "" : ", ") + std::string(name);
    }
    return Error{fmt::format("{} '{}' is not known (known: {})", option, value, names)};
}

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

Result<Job> resolve(const JobSpec& spec) {
    Job job;
    job.spec = spec;
    if (spec.input.empty()) return Error{"no input normal map given"};
    if (spec.out.empty()) return Error{"no output folder given (--out DIR)"};
    if (spec.preset.empty())
        return Error{"no preset given (--preset P; known: " + joined(builtinPresetNames()) + ")"};

    auto preset = findPreset(spec.preset);
    if (!preset) return Error{preset.error()};
    job.preset = std::move(preset.value());

    job.method = job.preset.method;
    if (spec.method) {
        const auto m = methodFromName(*spec.method);
        if (!m) return Error{"--method: " + m.error()};
        job.method = *m;
    }
    if (const Status s = checkPresetMethod(job.preset, job.method); !s) return Error{s.error()};

    if (spec.format) {
        const auto f = exportFormatFromName(*spec.format);
        if (!f) return Error{"--format: " + f.error()};
        job.exportOptions.format = *f;
    }
    if (spec.compression) {
        const auto c = ddsCompressionFromName(*spec.compression);
        if (!c) return Error{"--compression: " + c.error()};
        if (job.exportOptions.format.value_or(job.preset.format) != ExportFormat::Dds)
            return Error{
                "--compression " + *spec.compression + " applies to --format dds only (the format is " +
                std::string(exportFormatName(job.exportOptions.format.value_or(job.preset.format))) + ")"};
        job.exportOptions.compression = *c;
    }
    if (spec.metallic) {
        if (!job.preset.findParameter("metallic")) {
            std::vector<std::string> with;
            for (const auto& p : builtinPresets())
                if (p.findParameter("metallic")) with.push_back(p.name);
            return Error{"--metallic: preset '" + job.preset.name +
                         "' stores no metallic channel (presets with one: " + joined(with) + ")"};
        }
        job.exportOptions.parameters["metallic"] = *spec.metallic;
    }
    if (spec.power && !(*spec.power > 0.0 && *spec.power <= kMaxPower))
        return Error{fmt::format("--power {:g} must lie in (0, {:g}]", *spec.power, kMaxPower)};

    job.bake.method = job.method;
    job.bake.encoding = job.preset.encoding;
    if (spec.power) job.bake.basePower = *spec.power;
    if (spec.kernel) {
        const auto k = choice<FilterKernel>(
            "--kernel", *spec.kernel,
            {{"box", FilterKernel::Box}, {"tent", FilterKernel::Tent}, {"gaussian", FilterKernel::Gaussian}});
        if (!k) return Error{k.error()};
        job.bake.pyramid.kernel = *k;
    }
    if (spec.border) {
        const auto b = choice<BorderMode>("--border", *spec.border,
                                          {{"wrap", BorderMode::Wrap}, {"clamp", BorderMode::Clamp}});
        if (!b) return Error{b.error()};
        job.bake.pyramid.border = *b;
    }
    if (spec.green) {
        const auto g = choice<GreenConvention>(
            "--green", *spec.green,
            {{"opengl", GreenConvention::OpenGL}, {"directx", GreenConvention::DirectX}});
        if (!g) return Error{g.error()};
        job.normalMap.green = *g;
    }
    if (spec.layout) {
        const auto l = choice<NormalLayout>(
            "--layout", *spec.layout,
            {{"auto", NormalLayout::Auto}, {"rgb", NormalLayout::Rgb}, {"rg", NormalLayout::Rg}});
        if (!l) return Error{l.error()};
        job.normalMap.layout = *l;
    }
    if (spec.mips) {
        if (*spec.mips < 1) return Error{fmt::format("--mips {} must be at least 1", *spec.mips)};
        job.bake.mipCount = *spec.mips;
    }
    if (spec.detailFade && !spec.detail) return Error{"--detail-fade needs a detail map (--detail FILE)"};
    if (spec.detail) {
        if (spec.detail->empty()) return Error{"--detail: no file given"};
        job.detail.pyramid = job.bake.pyramid;
        job.detail.mipCount = job.bake.mipCount;
        if (spec.detailFade) {
            const std::string& f = *spec.detailFade;
            const auto colon = f.find(':');
            int start = -1, end = -1;
            const bool ok =
                colon != std::string::npos &&
                std::from_chars(f.data(), f.data() + colon, start).ptr == f.data() + colon &&
                std::from_chars(f.data() + colon + 1, f.data() + f.size(), end).ptr == f.data() + f.size();
            if (!ok || start < 0 || end < start)
                return Error{"--detail-fade '" + f +
                             "' must be START:END mips with 0 <= START <= END (e.g. 3:6)"};
            job.detail.fadeStartMip = start;
            job.detail.fadeEndMip = end;
        }
    }
    job.normalMap.allowImplausible = spec.allowImplausible;
    job.exportOptions.allowEightBit = spec.allowEightBit;
    job.exportOptions.overwrite = spec.force ? Overwrite::Allow : Overwrite::Refuse;
    job.exportOptions.stem = fs::path(spec.input).stem().string();
    if (job.exportOptions.stem.empty()) return Error{"input '" + spec.input + "' has no file name"};
    return job;
}

/// A one-line progress bar on stderr, drawn only when stderr is a terminal.
Result<Json> runJob(const Job& job, ProgressBar& progress, const std::string& label, bool report) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    constexpr int kSteps = 3;
    progress.setLabel(label);
    progress.update(0.0, "reading");
    const auto map = loadNormalMap(job.spec.input, job.normalMap);
    if (!map) return Error{map.error()};

    BakeOptions options = job.bake;
    if (job.spec.gloss) {
        const auto image = readImage(*job.spec.gloss);
        if (!image) return Error{"--gloss: " + image.error()};
        auto gloss = glossFromImage(*image, map->width, map->height);
        if (!gloss) return Error{"--gloss '" + *job.spec.gloss + "': " + gloss.error()};
        options.authoredGloss = std::move(gloss.value());
    }

    progress.update(double(1) / kSteps, "baking");
    auto baked = bake(*map, options);
    if (!baked) return Error{baked.error()};
    // What the summary should point out: a --mips beyond a chain, a fade beyond the detail's levels.
    Json notes = Json::array();
    if (job.spec.mips && *job.spec.mips > baked->stats.mipCount)
        notes.push_back(fmt::format("--mips {} exceeds the {}-level chain of a {}x{} map: {} levels written",
                                    *job.spec.mips, baked->stats.mipCount, map->width, map->height,
                                    baked->stats.mipCount));

    std::optional<DetailRecord> detailRecord;
    if (job.spec.detail) {
        const auto detailMap = loadNormalMap(*job.spec.detail, job.normalMap);
        if (!detailMap) return Error{"--detail: " + detailMap.error()};
        auto detail = bakeDetail(*detailMap, job.detail);
        if (!detail) return Error{"--detail '" + *job.spec.detail + "': " + detail.error()};
        const int levels = int(detail->texture.mips.size());
        if (job.spec.mips && *job.spec.mips > levels)
            notes.push_back(fmt::format("--mips {} exceeds the {}-level chain of the {}x{} detail map: {} "
                                        "detail levels written",
                                        *job.spec.mips, levels, detailMap->width, detailMap->height, levels));
        if (job.detail.fadeEndMip >= levels)
            notes.push_back(fmt::format("the detail fade ends at mip {}, beyond the detail map's {} stored "
                                        "levels: its last level is not fully faded to the constant variance",
                                        job.detail.fadeEndMip, levels));
        detailRecord = DetailRecord{*job.spec.detail, detail->constantVariance, job.detail.fadeStartMip,
                                    job.detail.fadeEndMip};
        baked.value().textures.push_back(std::move(detail.value().texture));
    }

    progress.update(double(2) / kSteps, "writing");
    std::error_code ec;
    fs::create_directories(job.spec.out, ec);
    if (ec) return Error{"cannot create output folder '" + job.spec.out + "': " + ec.message()};

    BakeRecord record;
    record.inputs = {{"normalMap", job.spec.input},
                     {"glossMap", job.spec.gloss ? Json(*job.spec.gloss) : Json(nullptr)},
                     {"detailMap", job.spec.detail ? Json(*job.spec.detail) : Json(nullptr)},
                     {"width", map->width},
                     {"height", map->height},
                     {"source",
                      {{"format", map->source.formatName},
                       {"channelType", map->source.channelType},
                       {"bitsPerChannel", map->source.bitsPerChannel}}}};
    const ExportFormat format = job.exportOptions.format.value_or(job.preset.format);
    record.options = {
        {"preset", job.spec.preset},
        {"method", std::string(methodName(job.method))},
        {"power", options.authoredGloss ? Json(nullptr) : Json(options.basePower)},
        {"format", std::string(exportFormatName(format))},
        {"compression", job.exportOptions.compression
                            ? Json(std::string(ddsCompressionName(*job.exportOptions.compression)))
                            : Json(nullptr)},
        {"kernel", job.spec.kernel.value_or("tent")},
        {"border", job.spec.border.value_or("wrap")},
        {"green", job.spec.green.value_or("opengl")},
        {"layout", job.spec.layout.value_or("auto")},
        {"mips", job.spec.mips ? Json(*job.spec.mips) : Json(nullptr)},
        {"allow8bit", job.spec.allowEightBit},
        {"allowImplausible", job.spec.allowImplausible}};
    if (detailRecord) record.options["detailFade"] = {detailRecord->fadeStartMip, detailRecord->fadeEndMip};
    record.diagnostics = map->diagnostics;
    record.detail = detailRecord;

    const auto exported = exportBake(*baked, job.preset, job.exportOptions, job.spec.out, record);
    if (!exported) {
        std::string message = exported.error();
        if (message.rfind("refusing to overwrite", 0) == 0) message += " (use --force to replace the set)";
        return Error{message};
    }
    progress.update(double(kSteps) / kSteps, "done");

    Json files = Json::array();
    for (const auto& f : exported->files)
        for (const auto& p : f.paths)
            files.push_back((fs::path(job.spec.out) / p).string());
    Json summary = {{"input", job.spec.input},
                    {"out", job.spec.out},
                    {"preset", job.preset.name},
                    {"method", std::string(methodName(job.method))},
                    {"format", std::string(exportFormatName(format))},
                    {"files", files},
                    {"bakeJson", (fs::path(job.spec.out) / exported->manifestPath).string()},
                    {"width", map->width},
                    {"height", map->height},
                    {"mipCount", baked->stats.mipCount},
                    {"mipsRequested", job.spec.mips ? Json(*job.spec.mips) : Json(nullptr)},
                    {"notes", notes},
                    {"glossClampedLow", baked->stats.glossClampedLow},
                    {"glossClampedHigh", baked->stats.glossClampedHigh},
                    {"pyramidSeconds", baked->stats.pyramidSeconds},
                    {"methodSeconds", baked->stats.methodSeconds},
                    {"seconds", std::chrono::duration<double>(Clock::now() - start).count()},
                    {"warnings", map->diagnostics.warnings}};
    if (detailRecord)
        summary["detail"] = {{"file", exported->manifest["detail"]["file"]},
                             {"constantVariance", detailRecord->constantVariance},
                             {"fade", {detailRecord->fadeStartMip, detailRecord->fadeEndMip}}};

    if (report) {
        // The ground-truth report for the same map, power and border: how far each method is from
        // the truth per mip, next to its cost (burnish evaluate, written into <out>/report).
        progress.update(double(kSteps) / kSteps, "evaluating");
        EvaluationReportOptions evaluation;
        evaluation.inputName = fs::path(job.spec.input).filename().string();
        evaluation.evaluate.basePowers = {options.basePower};
        evaluation.evaluate.border = options.pyramid.border;
        evaluation.evaluate.params = options.params;
        if (options.authoredGloss) {
            // The ground truth with each texel's authored power, decoded as the bake decodes it.
            std::vector<double> powers(options.authoredGloss->size());
            for (size_t i = 0; i < powers.size(); ++i)
                powers[i] = options.encoding.power((*options.authoredGloss)[i]);
            evaluation.evaluate.texelPowers = std::move(powers);
        }
        auto built = buildEvaluationReport(*map, evaluation);
        if (!built) return Error{"--report: " + built.error()};
        const fs::path dir = fs::path(job.spec.out) / "report";
        if (auto st = writeEvaluationReport(*built, dir); !st) return Error{"--report: " + st.error()};
        summary["report"] = (dir / "evaluate.md").string();
    }
    return summary;
}

// Manifest: {"version": 1, "jobs": [{"input": ..., "out": ..., <any option by its long name>}]}.
// Relative paths are relative to the manifest's folder; options on the command line are defaults.
Result<std::vector<JobSpec>> readManifest(const std::string& path, const JobSpec& defaults) {
    const auto text = readFile(path);
    if (!text) return Error{"--manifest: " + text.error()};
    Json root;
    try {
        root = Json::parse(*text);
    } catch (const Json::parse_error& e) {
        return Error{"manifest '" + path + "': invalid JSON: " + e.what()};
    }
    const std::string where = "manifest '" + path + "'";
    if (!root.is_object() || !root.contains("jobs") || !root["jobs"].is_array())
        return Error{where + ": expected an object with a \"jobs\" array"};
    for (const auto& [key, value] : root.items())
        if (key != "jobs" && key != "version")
            return Error{where + ": unknown field '" + key + "' (known: version, jobs)"};
    if (root.contains("version") && !(root["version"].is_number_integer() && root["version"].get<int>() == 1))
        return Error{where + ": version must be 1"};
    const fs::path base = fs::path(path).parent_path();
    auto rebase = [&](const std::string& p) {
        return fs::path(p).is_absolute() ? p : (base / p).lexically_normal().string();
    };

    std::vector<JobSpec> jobs;
    const auto& list = root["jobs"];
    if (list.empty()) return Error{where + ": \"jobs\" is empty"};
    for (size_t i = 0; i < list.size(); ++i) {
        const Json& j = list[i];
        const std::string at = where + " job " + std::to_string(i + 1);
        if (!j.is_object()) return Error{at + ": must be an object"};
        JobSpec spec = defaults;
        for (const auto& [key, value] : j.items()) {
            auto str = [&](std::string& dest) -> Status {
                if (!value.is_string()) return Error{at + ": '" + key + "' must be a string"};
                dest = value.get<std::string>();
                return {};
            };
            auto optStr = [&](std::optional<std::string>& dest) -> Status {
                if (!value.is_string()) return Error{at + ": '" + key + "' must be a string"};
                dest = value.get<std::string>();
                return {};
            };
            auto num = [&](std::optional<double>& dest) -> Status {
                if (!value.is_number()) return Error{at + ": '" + key + "' must be a number"};
                dest = value.get<double>();
                return {};
            };
            auto flag = [&](bool& dest) -> Status {
                if (!value.is_boolean()) return Error{at + ": '" + key + "' must be true or false"};
                dest = value.get<bool>();
                return {};
            };
            Status s;
            if (key == "input")
                s = str(spec.input);
            else if (key == "out")
                s = str(spec.out);
            else if (key == "preset")
                s = str(spec.preset);
            else if (key == "method")
                s = optStr(spec.method);
            else if (key == "power")
                s = num(spec.power);
            else if (key == "gloss")
                s = optStr(spec.gloss);
            else if (key == "format")
                s = optStr(spec.format);
            else if (key == "compression")
                s = optStr(spec.compression);
            else if (key == "kernel")
                s = optStr(spec.kernel);
            else if (key == "border")
                s = optStr(spec.border);
            else if (key == "green")
                s = optStr(spec.green);
            else if (key == "layout")
                s = optStr(spec.layout);
            else if (key == "metallic")
                s = num(spec.metallic);
            else if (key == "mips") {
                if (!value.is_number_integer())
                    s = Error{at + ": 'mips' must be an integer"};
                else
                    spec.mips = value.get<int>();
            } else if (key == "detail")
                s = optStr(spec.detail);
            else if (key == "detail-fade")
                s = optStr(spec.detailFade);
            else if (key == "force")
                s = flag(spec.force);
            else if (key == "allow-implausible")
                s = flag(spec.allowImplausible);
            else if (key == "allow-8bit")
                s = flag(spec.allowEightBit);
            else
                s = Error{at + ": unknown field '" + key +
                          "' (known: input, out, preset, method, power, gloss, format, compression, kernel, "
                          "border, "
                          "green, layout, metallic, mips, detail, detail-fade, force, allow-implausible, "
                          "allow-8bit)"};
            if (!s) return Error{s.error()};
        }
        if (j.contains("input")) spec.input = rebase(spec.input);
        if (j.contains("out")) spec.out = rebase(spec.out);
        if (j.contains("gloss") && spec.gloss) spec.gloss = rebase(*spec.gloss);
        if (j.contains("detail") && spec.detail) spec.detail = rebase(*spec.detail);
        if (j.contains("preset") && spec.preset.size() > 5 &&
            spec.preset.substr(spec.preset.size() - 5) == ".json")
            spec.preset = rebase(spec.preset);
        jobs.push_back(std::move(spec));
    }
    return jobs;
}

// --- Ninja build files --------------------------------------------------------------------------

std::string absolutePath(const std::string& p) {
    return fs::absolute(fs::path(p)).lexically_normal().string();
}

/// `text` quoted for /bin/sh (ninja runs commands through sh -c).
std::string shellQuote(const std::string& text) {
    std::string q = "'";
    for (char c : text)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// A path in a ninja build line: '$', ' ' and ':' are escaped with '$'; a newline cannot be written.
Result<std::string> ninjaPath(const std::string& p) {
    std::string out;
    for (char c : p) {
        if (c == '\n' || c == '\r')
            return Error{"path '" + p + "' holds a line break, which Ninja cannot express"};
        if (c == '$' || c == ' ' || c == ':') out += '$';
        out += c;
    }
    return out;
}

/// The whole-job `burnish bake` command line: every option spelled out, paths absolute, --force so a
/// rebuild replaces the outputs of the previous one.
std::vector<std::string> jobCommand(const std::string& exe, const Job& job, bool report) {
    const JobSpec& s = job.spec;
    std::vector<std::string> args{
        exe,
        "bake",
        absolutePath(s.input),
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
        s.kernel.value_or("tent"),
        "--border",
        s.border.value_or("wrap"),
        "--green",
        s.green.value_or("opengl"),
        "--layout",
        s.layout.value_or("auto"),
        "--force"};
    // Options whose absence means "each file's own choice" or "none" stay absent.
    if (s.gloss) args.insert(args.end(), {"--gloss", absolutePath(*s.gloss)});
    if (job.exportOptions.compression)
        args.insert(args.end(),
                    {"--compression", std::string(ddsCompressionName(*job.exportOptions.compression))});
    if (s.metallic) args.insert(args.end(), {"--metallic", fmt::format("{}", *s.metallic)});
    if (s.mips) args.insert(args.end(), {"--mips", std::to_string(*s.mips)});
    if (s.detail)
        args.insert(args.end(), {"--detail", absolutePath(*s.detail), "--detail-fade",
                                 fmt::format("{}:{}", job.detail.fadeStartMip, job.detail.fadeEndMip)});
    if (s.allowImplausible) args.emplace_back("--allow-implausible");
    if (s.allowEightBit) args.emplace_back("--allow-8bit");
    if (report) args.emplace_back("--report");
    return args;
}

struct NinjaJob {
    std::vector<std::string> outputs; // absolute
    std::vector<std::string> inputs;  // absolute
    std::string command;
    std::string description;
};

/// What one job reads and writes, without baking: the input's extent from its file, the file
/// names from export's plan.
Result<NinjaJob> planNinjaJob(const std::string& exe, const Job& job, const std::string& manifest,
                              bool report) {
    const auto image = readImage(job.spec.input);
    if (!image) return Error{image.error()};
    auto shape = bakeShape(job.bake, image->width, image->height);
    if (!shape) return Error{shape.error()};
    BakeRecord record;
    if (job.spec.detail) {
        const auto detailImage = readImage(*job.spec.detail);
        if (!detailImage) return Error{"--detail: " + detailImage.error()};
        auto detail = detailShape(detailImage->width, detailImage->height, job.detail);
        if (!detail) return Error{"--detail: " + detail.error()};
        shape.value().textures.push_back(std::move(detail.value()));
        record.detail = DetailRecord{*job.spec.detail, 0.0, job.detail.fadeStartMip, job.detail.fadeEndMip};
    }
    const auto plan = planExport(*shape, job.preset, job.exportOptions, record);
    if (!plan) return Error{plan.error()};

    NinjaJob nj;
    const fs::path out = absolutePath(job.spec.out);
    for (const auto& f : plan->files)
        for (const auto& p : f.paths)
            nj.outputs.push_back((out / p).string());
    nj.outputs.push_back((out / plan->manifestPath).string());
    if (report)
        for (const char* f :
             {"evaluate.md", "evaluate.json", "evaluate-error-per-mip.png", "evaluate-error-vs-cost.png"})
            nj.outputs.push_back((out / "report" / f).string());
    nj.inputs.push_back(absolutePath(job.spec.input));
    if (job.spec.gloss) nj.inputs.push_back(absolutePath(*job.spec.gloss));
    if (job.spec.detail) nj.inputs.push_back(absolutePath(*job.spec.detail));
    if (job.preset.origin != "built-in") nj.inputs.push_back(absolutePath(job.preset.origin));
    nj.inputs.push_back(absolutePath(manifest));
    for (const auto& a : jobCommand(exe, job, report))
        nj.command += (nj.command.empty() ? "" : " ") + shellQuote(a);
    nj.description = "burnish bake " + fs::path(job.spec.input).filename().string() + " -> " + out.string();
    return nj;
}

/// A Ninja build file with one build statement per job (written atomically).
Result<Json> writeNinja(const std::vector<Job>& jobs, const std::string& manifest, const std::string& path,
                        bool report) {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (ec) return Error{"--ninja: cannot find the running burnish binary (/proc/self/exe): " + ec.message()};

    // Only '$' needs escaping in a variable's value (ninja expands it); commands hold no newline.
    auto value = [](const std::string& v) {
        std::string out;
        for (char c : v)
            out += c == '$' ? std::string("$$") : std::string(1, c);
        return out;
    };
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
    std::map<std::string, size_t> owner; // output -> job number, to refuse two jobs writing one file
    Json outputs = Json::array();
    for (size_t i = 0; i < jobs.size(); ++i) {
        const std::string at = "manifest job " + std::to_string(i + 1) + " (" + jobs[i].spec.input + "): ";
        auto nj = planNinjaJob(exe.string(), jobs[i], manifest, report);
        if (!nj) return Error{at + nj.error()};
        std::string line = "\nbuild";
        for (const auto& o : nj->outputs) {
            const auto [it, fresh] = owner.emplace(o, i + 1);
            if (!fresh)
                return Error{at + "writes '" + o + "', which job " + std::to_string(it->second) +
                             " writes too"};
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
        text += line + "\n  cmd = " + value(nj->command) + "\n  desc = " + value(nj->description) + "\n";
    }
    if (const Status s = writeFileAtomic(path, text, Overwrite::Allow); !s)
        return Error{"--ninja: " + s.error()};
    return Json{{"ninja", path}, {"jobs", jobs.size()}, {"outputs", outputs}};
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
        "on the\n  command line are every job's defaults. All jobs are checked before the first runs.\n"
        "\nEach output folder gets bake.json: every file's channels and decode rule (value = stored*scale + "
        "bias).\n"
        "--detail FILE adds <stem>_detail.<ext> ([x, y, 0, variance], its own mip chain) to every preset, "
        "and\n"
        "  bake.json's \"detail\" entry gives the constant variance a shader adds beyond the fade.\n"
        "--ninja FILE (with --manifest) writes a Ninja build file instead of baking: `ninja -f FILE -j N`\n"
        "  bakes the jobs in parallel and reruns only those whose inputs changed.\n";
    return text;
}

} // namespace

static CommandRegistration registration(40, [](CLI::App& app) -> std::function<int()> {
    auto* cmd = app.add_subcommand(
        "bake", "Bake a normal map's prefiltered gloss/LEAN textures for an engine preset");
    auto spec = std::make_shared<JobSpec>();
    auto manifest = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    auto report = std::make_shared<bool>(false);
    auto ninja = std::make_shared<std::string>();

    cmd->add_option("input", spec->input, "Tangent-space normal map (PNG, TGA, EXR, TIFF, DDS, ...)");
    cmd->add_option("--preset", spec->preset, "Engine preset: a name listed below, or a preset FILE.json");
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
    cmd->add_option("--metallic", spec->metallic,
                    "Metalness in [0, 1] for presets with a metallic channel (gltf, unity)");
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
    cmd->add_option("--ninja", *ninja,
                    "With --manifest: write a Ninja build file (one `burnish bake` per job) instead of "
                    "baking");
    cmd->add_flag("--report", *report,
                  "Also measure every method against the ground truth for this map and power (as burnish "
                  "evaluate, mips 1-4) and write the report into <out>/report/");
    // Built lazily: listing the presets parses them, which other subcommands need not pay for.
    cmd->footer([] { return helpFooter(); });

    return [spec, manifest, json, report, ninja]() -> int {
        if (!builtinPresetErrors().empty()) return fail(builtinPresetErrors().front());
        std::vector<JobSpec> specs;
        if (!manifest->empty()) {
            if (!spec->input.empty()) return fail("give either an input map or --manifest, not both");
            auto read = readManifest(*manifest, *spec);
            if (!read) return fail(read.error());
            specs = std::move(read.value());
        } else {
            if (!ninja->empty())
                return fail("--ninja needs --manifest FILE (the jobs to write build statements for)");
            if (spec->input.empty()) return fail("no input normal map given (see 'burnish bake --help')");
            specs.push_back(*spec);
        }
        // Every job is checked before the first one writes anything.
        std::vector<Job> jobs;
        for (size_t i = 0; i < specs.size(); ++i) {
            auto job = resolve(specs[i]);
            if (!job)
                return fail(specs.size() > 1 || !manifest->empty()
                                ? "manifest job " + std::to_string(i + 1) + ": " + job.error()
                                : job.error());
            jobs.push_back(std::move(job.value()));
        }
        if (!ninja->empty()) {
            const auto written = writeNinja(jobs, *manifest, *ninja, *report);
            if (!written) return fail(written.error());
            if (*json)
                std::printf("%s\n", written->dump(2).c_str());
            else
                std::printf("%s: %zu build statements, %zu outputs; run ninja -f %s\n", ninja->c_str(),
                            jobs.size(), (*written)["outputs"].size(), ninja->c_str());
            return 0;
        }
        ProgressBar progress;
        Json summaries = Json::array();
        for (size_t i = 0; i < jobs.size(); ++i) {
            const std::string name = fs::path(jobs[i].spec.input).filename().string();
            const std::string label =
                jobs.size() > 1 ? fmt::format("[{}/{}] {}", i + 1, jobs.size(), name) : name;
            auto summary = runJob(jobs[i], progress, label, *report);
            progress.finish();
            if (!summary)
                return fail(jobs.size() > 1 || !manifest->empty()
                                ? "manifest job " + std::to_string(i + 1) + " (" + jobs[i].spec.input +
                                      "): " + summary.error()
                                : summary.error());
            for (const auto& w : (*summary)["warnings"])
                std::fprintf(stderr, "burnish: warning: %s\n", w.get<std::string>().c_str());
            if (!*json) {
                std::printf("%s -> %s: preset %s, method %s, %zu files + bake.json, %d mips, %.2f s\n",
                            jobs[i].spec.input.c_str(), jobs[i].spec.out.c_str(), jobs[i].preset.name.c_str(),
                            std::string(methodName(jobs[i].method)).c_str(), (*summary)["files"].size(),
                            (*summary)["mipCount"].get<int>(), (*summary)["seconds"].get<double>());
                for (const auto& n : (*summary)["notes"])
                    std::printf("  note: %s\n", n.get<std::string>().c_str());
            }
            summaries.push_back(std::move(summary.value()));
        }
        if (*json) std::printf("%s\n", Json{{"jobs", summaries}}.dump(2).c_str());
        return 0;
    };
});

} // namespace burnish::cli
