// `burnish bake`: a normal map (and an optional authored gloss map and detail normal map) through
// a prefiltering method into an engine preset's textures with their mip chains, plus bake.json.
// One job from the options, or many from a manifest; or, with --ninja, a Ninja build file that
// runs the manifest's jobs one `burnish bake` each. The job itself is core's (bake_job.h, the same
// as the studio's Bake & Export dialog; bake_ninja.h): this file holds the options and the output.
#include "command.h"
#include "common.h"

#include <burnish/core/bake/bake_job.h>
#include <burnish/core/bake/bake_ninja.h>
#include <burnish/core/bake/export.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/prefilter/methods.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>
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
        "  bakes the jobs in parallel and reruns only those whose inputs changed.\n";
    return text;
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

    return [spec, manifest, json, ninja, outRoot]() -> int {
        if (!builtinPresetErrors().empty()) return fail(builtinPresetErrors().front());
        std::vector<BakeJobSpec> specs;
        if (!manifest->empty()) {
            if (!spec->input.empty()) return fail("give either an input map or --manifest, not both");
            auto read = readBakeManifest(*manifest, *spec);
            if (!read) return fail(read.error());
            specs = std::move(read.value());
        } else {
            if (!ninja->empty())
                return fail("--ninja needs --manifest FILE (the jobs to write build statements for)");
            if (spec->input.empty()) return fail("no input normal map given (see 'burnish bake --help')");
            specs.push_back(*spec);
        }
        // Every job is checked before the first one writes anything.
        std::vector<BakeJob> jobs;
        for (size_t i = 0; i < specs.size(); ++i) {
            auto job = resolveBakeJob(specs[i]);
            if (!job)
                return fail(specs.size() > 1 || !manifest->empty()
                                ? "manifest job " + std::to_string(i + 1) + ": " + job.error()
                                : job.error());
            jobs.push_back(std::move(job.value()));
        }
        std::optional<fs::path> root;
        if (!outRoot->empty()) root = fs::path(*outRoot);
        if (!manifest->empty() || root)
            if (const Status s = checkBakeJobs(jobs, root, !manifest->empty()); !s) return fail(s.error());
        if (!ninja->empty()) {
            // The build statements run this very binary.
            std::error_code ec;
            const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
            if (ec)
                return fail("--ninja: cannot find the running burnish binary (/proc/self/exe): " +
                            ec.message());
            const auto written = writeBakeNinja(jobs, *manifest, *ninja, exe.string());
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
            progress.setLabel(label);
            auto run = runBakeJob(jobs[i], [&](double fraction, std::string_view stage) {
                progress.update(fraction, std::string(stage));
                return true;
            });
            progress.finish();
            if (!run)
                return fail(jobs.size() > 1 || !manifest->empty()
                                ? "manifest job " + std::to_string(i + 1) + " (" + jobs[i].spec.input +
                                      "): " + run.error()
                                : run.error());
            Json& summary = run.value().summary;
            for (const auto& w : summary["warnings"])
                std::fprintf(stderr, "burnish: warning: %s\n", printable(w.get<std::string>()).c_str());
            if (!*json) {
                std::printf("%s -> %s: preset %s, method %s, %zu files + bake.json, %d mips, %.2f s\n",
                            jobs[i].spec.input.c_str(), jobs[i].spec.out.c_str(), jobs[i].preset.name.c_str(),
                            std::string(methodName(jobs[i].method)).c_str(), summary["files"].size(),
                            summary["mipCount"].get<int>(), summary["seconds"].get<double>());
                for (const auto& n : summary["notes"])
                    std::printf("  note: %s\n", n.get<std::string>().c_str());
            }
            summaries.push_back(std::move(summary));
        }
        if (*json) std::printf("%s\n", Json{{"jobs", summaries}}.dump(2).c_str());
        return 0;
    };
});

} // namespace burnish::cli
