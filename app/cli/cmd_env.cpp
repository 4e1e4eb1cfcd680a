// `burnish env`: an environment (equirectangular HDR, six cube faces, or the procedural studio)
// into a prefiltered radiance cube with mips, an SH9 irradiance and a small irradiance cube.
#include "command.h"
#include "common.h"

#include <burnish/core/env/cube.h>
#include <burnish/core/env/cube_dds.h>
#include <burnish/core/env/prefilter.h>
#include <burnish/core/env/sampling.h>
#include <burnish/core/env/sh.h>
#include <burnish/core/env/storage.h>
#include <burnish/core/io/image.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/memory.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace burnish::cli {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

struct EnvCliOptions {
    std::string input;
    std::vector<std::string> faces;
    std::string out;
    int faceSize = 256;
    int mips = 0;
    std::string lobe = "phong";
    double topPower = 2048.0;
    double powerDrop = 0.25;
    std::string glossEncoding;
    int irradianceSize = 32;
    unsigned samples = 64;
    unsigned directions = 64;
    std::string format = "both";
    bool normalizeDiffuse = false;
    bool json = false;
    bool report = false;
    bool force = false;
    bool faceSizeGiven = false;
};

Json vec3Json(const glm::dvec3& v) {
    return Json::array({v.x, v.y, v.z});
}

std::string reportMarkdown(const ReferenceComparison& c, LobeModel lobe, int faceSize) {
    std::string md =
        fmt::format("# Prefiltered environment against the brute-force reference\n\n"
                    "{} lobe, {}² faces, {} directions per mip. rel. RMS and max/mean: texel "
                    "values at their centres (the prefilter's own error); lookup: bilinear at the "
                    "directions (adds the mip's resolution). FIS: filtered importance sampling with "
                    "the lobe's own distribution against its brute-force integral.\n\n",
                    lobeModelName(lobe), faceSize, c.directions);
    md += fmt::format("| mip | size | power | source level | prefilter s | rel. RMS | max/mean | lookup rel. "
                      "RMS | reference s "
                      "| FIS taps | FIS rel. RMS | FIS s | taps to match map within {:g}% |\n",
                      100.0 * c.fisTolerance);
    md += "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
    for (const EnvironmentMipError& r : c.mips)
        md += fmt::format(
            "| {} | {} | {:.4g} | {} | {:.3f} | {:.3e} | {:.3e} | {:.3e} | {:.3f} | {} | {:.3e} "
            "| {:.4f} | {} |\n",
            r.mip, r.size, r.power, r.sourceLevel, r.prefilterSeconds, r.relativeRms, r.maxRelativeToMean,
            r.lookupRelativeRms, r.referenceSeconds, r.fisSamples, r.fisRelativeRms, r.fisSeconds,
            r.fisSamplesToMatch == 0 ? std::string("> ") + std::to_string(kMaxFisSamples)
                                     : std::to_string(r.fisSamplesToMatch));
    return md;
}

// The source cube: six face files (reduced to --face-size through the box chain), an
// equirectangular image, or the procedural studio.
Result<EnvironmentSource> readSource(const EnvCliOptions& o) {
    EnvironmentSource source;
    if (!o.faces.empty()) {
        std::array<fs::path, kCubeFaces> paths;
        for (int f = 0; f < kCubeFaces; ++f)
            paths[size_t(f)] = o.faces[size_t(f)];
        auto loaded = loadCubeFaceEnvironment(paths);
        if (!loaded) return Error{loaded.error()};
        source = std::move(loaded.value());
        // The faces set the size unless --face-size asks for a smaller one: then the box-filtered level.
        if (o.faceSizeGiven && o.faceSize != source.cube.faceSize()) {
            if (!isPowerOfTwo(o.faceSize) || o.faceSize > source.cube.faceSize())
                return Error{fmt::format("--face-size {} must be a power of two no larger than the faces' {}",
                                         o.faceSize, source.cube.faceSize())};
            buildBoxMips(source.cube);
            const int level = fullMipCount(source.cube.faceSize()) - fullMipCount(o.faceSize);
            CubeLevel kept = std::move(source.cube.levels[size_t(level)]);
            source.cube.levels.assign(1, std::move(kept));
        }
    } else if (!o.input.empty()) {
        auto loaded = loadEquirectEnvironment(o.input, o.faceSize);
        if (!loaded) return Error{loaded.error()};
        source = std::move(loaded.value());
    } else {
        auto studio = proceduralStudioEnvironment(o.faceSize);
        if (!studio) return Error{studio.error()};
        source.cube = std::move(studio.value());
        source.description = "procedural studio";
    }

    return source;
}

// The memory the run will need (estimatedEnvironmentBytes) against what may be used, from the inputs'
// headers before any is read.
Status checkEnvironmentMemory(const EnvCliOptions& o) {
    int faceSize = o.faceSize;
    std::uint64_t inputTexels = 0;
    if (!o.faces.empty()) {
        // The faces set the cube (a smaller --face-size is their box-filtered level, made from them).
        const auto header = readImageHeader(o.faces[0]);
        if (!header) return Error{header.error()};
        faceSize = header->width;
        inputTexels = 6 * std::uint64_t(std::max(faceSize, 1)) * std::uint64_t(std::max(faceSize, 1));
    } else if (!o.input.empty()) {
        const auto header = readImageHeader(o.input);
        if (!header) return Error{header.error()};
        inputTexels = std::uint64_t(header->width) * std::uint64_t(header->height);
    }
    return checkMemory(estimatedEnvironmentBytes(faceSize, inputTexels),
                       fmt::format("an environment cube of face size {}", faceSize),
                       "close other programs, or ask for a smaller --face-size");
}

// The radiance and irradiance cubes in the asked formats and sh.json, staged into the set.
Status stageCubes(const EnvCliOptions& o, FileSet& set, const CubeMap& radiance, const CubeMap& irradiance,
                  const Sh9& sh, const std::optional<glm::dvec3>& divisor) {
    if (o.format == "dds" || o.format == "both") {
        if (const Status s = set.addBytes("radiance.dds", encodeCubeDds(radiance)); !s) return s;
        if (const Status s = set.addBytes("irradiance.dds", encodeCubeDds(irradiance)); !s) return s;
    }
    if (o.format == "exr" || o.format == "both") {
        if (const Status s = stageCubeExrFaces(radiance, "radiance", set); !s) return s;
        if (const Status s = stageCubeExrFaces(irradiance, "irradiance", set); !s) return s;
    }
    Json shJson = sh9Json(sh);
    if (divisor) shJson["normalizedBy"] = vec3Json(*divisor);
    return set.addBytes("sh.json", shJson.dump(2) + "\n");
}

// What the run made: the source, every mip's power and source level, the files (with timings).
Json envSummary(const EnvCliOptions& o, const EnvironmentSource& source,
                const PrefilteredEnvironment& filtered, const PrefilterOptions& prefilter, const Sh9& sh,
                const std::optional<glm::dvec3>& divisor, const std::vector<std::string>& files,
                double computeSeconds) {
    Json mips = Json::array();
    for (int m = 0; m < filtered.radiance.mipCount(); ++m)
        mips.push_back({{"mip", m},
                        {"size", filtered.radiance.levels[size_t(m)].size},
                        {"power", filtered.powers[size_t(m)]},
                        {"sourceLevel", filtered.sourceLevels[size_t(m)]},
                        {"seconds", filtered.seconds[size_t(m)]}});
    return Json{
        {"source", source.description},
        {"replacedTexels", source.replacedTexels},
        {"aboveHalfValues", source.aboveHalfValues},
        {"srgbDecoded", source.srgbDecoded},
        {"warnings", source.warnings},
        {"faceSize", filtered.radiance.faceSize()},
        {"lobe", lobeModelName(filtered.lobe)},
        {"powerRule", prefilter.encoding ? "gloss encoding " + prefilter.encoding->name() + " (" +
                                               prefilter.encoding->formula() + "), g = 1 - mip/(mips-1)"
                                         : fmt::format("drop: {:g} * {:g}^mip", o.topPower, o.powerDrop)},
        {"mips", mips},
        {"irradianceSize", o.irradianceSize},
        {"averageDiffuse", vec3Json(averageDiffuse(sh))},
        {"normalizedBy", divisor ? vec3Json(*divisor) : Json(nullptr)},
        {"layout", "GL cube faces +X -X +Y -Y +Z -Z; row j holds t = (j+0.5)/size; DDS RGBA16F (alpha 1), "
                   "EXR half RGB; values clamped to 65504"},
        {"seconds", computeSeconds},
        {"files", files},
    };
}

// --report: the prefilter against brute force per mip, written as report.json and report.md.
Result<std::pair<Json, std::string>> stageReport(const EnvCliOptions& o, FileSet& set,
                                                 const PrefilteredEnvironment& filtered,
                                                 const CubeMap& source) {
    // Compare against the source as filtered (normalized when asked), so only the prefilter's error
    // shows.
    auto comparison = compareWithReference(filtered, source, o.directions, o.samples);
    if (!comparison) return Error{comparison.error()};
    Json rows = Json::array();
    for (const EnvironmentMipError& r : comparison->mips)
        rows.push_back({{"mip", r.mip},
                        {"size", r.size},
                        {"power", r.power},
                        {"sourceLevel", r.sourceLevel},
                        {"prefilterSeconds", r.prefilterSeconds},
                        {"relativeRms", r.relativeRms},
                        {"maxRelativeToMean", r.maxRelativeToMean},
                        {"lookupRelativeRms", r.lookupRelativeRms},
                        {"referenceSeconds", r.referenceSeconds},
                        {"fisSamples", r.fisSamples},
                        {"fisRelativeRms", r.fisRelativeRms},
                        {"fisSeconds", r.fisSeconds},
                        {"fisSamplesToMatch", r.fisSamplesToMatch}});
    Json report{{"directions", comparison->directions},
                {"fisTolerance", comparison->fisTolerance},
                {"lobe", lobeModelName(filtered.lobe)},
                {"faceSize", filtered.radiance.faceSize()},
                {"mips", rows}};
    if (const Status s = set.addBytes("report.json", report.dump(2) + "\n"); !s) return Error{s.error()};
    const std::string md = reportMarkdown(*comparison, filtered.lobe, filtered.radiance.faceSize());
    if (const Status s = set.addBytes("report.md", md); !s) return Error{s.error()};
    return std::pair{std::move(report), md};
}

int runEnv(const EnvCliOptions& o) {
    if (o.out.empty()) return fail("--out DIR is required");
    if (!o.input.empty() && !o.faces.empty()) return fail("give either an input file or --faces, not both");
    // Checked before any work: each is otherwise found only after the whole prefilter ran, or (a
    // top power below 1 spreads every mip's lobe over the whole sphere) makes it run for minutes.
    if (!isPowerOfTwo(o.irradianceSize) || o.irradianceSize > 4096)
        return fail(
            fmt::format("--irradiance-size {} must be a power of two in [1, 4096]", o.irradianceSize));
    if (o.glossEncoding.empty() && !(o.topPower >= 1.0 && o.topPower <= 1e9))
        return fail(fmt::format("--top-power {:g} must lie in [1, 1e9]: it is mip 0's power, the sharpest "
                                "(below 1 the lobe covers the whole sphere)",
                                o.topPower));
    if (!(o.powerDrop > 0.0 && o.powerDrop <= 1.0))
        return fail(
            fmt::format("--power-drop {:g} must lie in (0, 1]: each mip is at most as sharp as the one "
                        "above",
                        o.powerDrop));
    PrefilterOptions prefilter;
    prefilter.lobe = o.lobe == "phong" ? LobeModel::Phong : LobeModel::BlinnPhong;
    prefilter.mips = o.mips;
    prefilter.topPower = o.topPower;
    prefilter.powerDrop = o.powerDrop;
    if (!o.glossEncoding.empty()) {
        auto encoding = GlossEncoding::fromName(o.glossEncoding);
        if (!encoding) return fail("--gloss-encoding: " + encoding.error());
        prefilter.encoding = encoding.value();
    }

    // One rule for every command: a previous set (its env.json) is replaced only with --force.
    const fs::path index = fs::path(o.out) / "env.json";
    if (!o.force && fs::exists(index))
        return fail("refusing to replace the environment in '" + o.out + "' (use --force)");
    const std::vector<std::string> previous = indexedFiles(index);
    // One memory ceiling for every command: refused before anything is allocated.
    if (const Status memory = checkEnvironmentMemory(o); !memory) return fail(memory.error());
    ProgressBar progress("env");
    progress.update(0.0, "reading");
    auto read = readSource(o);
    if (!read) return fail(read.error());
    EnvironmentSource source = std::move(read).value();
    progress.finish();
    for (const auto& w : source.warnings)
        std::fprintf(stderr, "burnish: warning: %s\n", printable(w).c_str());
    const auto start = std::chrono::steady_clock::now();
    Sh9 sh = projectSh9(source.cube);
    std::optional<glm::dvec3> divisor;
    if (o.normalizeDiffuse) divisor = normalizeByAverageDiffuse(source.cube, sh);

    prefilter.progress = [&](double f) { progress.update(0.05 + 0.8 * f, "prefiltering"); };
    auto filtered = prefilterRadiance(source.cube, prefilter);
    if (!filtered) return fail(filtered.error());
    auto irradiance = irradianceCube(sh, o.irradianceSize);
    if (!irradiance) return fail("--irradiance-size: " + irradiance.error());
    const double computeSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (ec) return fail("cannot create '" + o.out + "': " + ec.message());
    // The whole set is staged, then committed as one unit (files.h): env.json is removed first and
    // written last, and a run killed in between is finished by the next one into this folder.
    auto set = FileSet::begin(o.out);
    if (!set) return fail(set.error());
    for (const auto& note : set->recoveryNotes())
        std::fprintf(stderr, "burnish: note: %s\n", printable(note).c_str());
    progress.update(0.87, "writing");
    if (const Status s = stageCubes(o, set.value(), filtered->radiance, *irradiance, sh, divisor); !s)
        return fail(s.error());
    const std::vector<std::string> files = set->names();

    Json summary = envSummary(o, source, *filtered, prefilter, sh, divisor, files, computeSeconds);
    // Timings vary run to run; env.json keeps only what the inputs determine, so reruns write the same bytes.
    Json manifest = summary;
    manifest.erase("seconds");
    for (auto& m : manifest["mips"])
        m.erase("seconds");
    if (o.report) {
        progress.update(0.9, "comparing with brute force");
        auto report = stageReport(o, set.value(), *filtered, source.cube);
        if (!report) return fail(report.error());
        const std::string& md = report->second;
        summary["report"] = report->first;
        for (const char* name : {"report.json", "report.md"}) {
            summary["files"].push_back(name);
            manifest["files"].push_back(name);
        }
        if (!o.json) std::fputs(md.c_str(), stdout);
    }
    if (const Status s = set.value().addBytes("env.json", manifest.dump(2) + "\n"); !s)
        return fail(s.error());
    // With --force, what the previous set held beyond this one goes (its env.json names it).
    if (const Status s = set.value().commit("env.json", previous, Overwrite::Allow); !s)
        return fail(s.error());
    progress.finish();

    if (o.json) {
        std::puts(summary.dump(2).c_str());
        return 0;
    }
    std::printf("%s -> %s: %d² faces, %d mips (%s lobe), SH9 and %d² irradiance, %zu files in %.2f s\n",
                source.description.c_str(), o.out.c_str(), filtered->radiance.faceSize(),
                filtered->radiance.mipCount(), lobeModelName(filtered->lobe), o.irradianceSize, files.size(),
                computeSeconds);
    for (int m = 0; m < filtered->radiance.mipCount(); ++m)
        std::printf("  mip %d: %4d², power %-10.4g (source level %d, %.3f s)\n", m,
                    filtered->radiance.levels[size_t(m)].size, filtered->powers[size_t(m)],
                    filtered->sourceLevels[size_t(m)], filtered->seconds[size_t(m)]);
    return 0;
}

const CommandRegistration kRegistration{
    60, [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<EnvCliOptions>();
        CLI::App* cmd = app.add_subcommand(
            "env",
            "Environment lighting: a prefiltered radiance cube with mips (a cosine-power lobe per mip), SH9 "
            "irradiance and an irradiance cube, from an equirectangular HDR, six faces, or the procedural "
            "studio");
        cmd->add_option("input", o->input,
                        "Equirectangular environment (EXR, HDR, float TIFF; width = 2 x height); "
                        "the procedural studio when omitted");
        cmd->add_option("--faces", o->faces, "Six cube-face images instead, in the order +X -X +Y -Y +Z -Z")
            ->expected(kCubeFaces);
        cmd->add_option("--out", o->out, "Output folder (created if missing)")->required();
        cmd->add_option("--face-size", o->faceSize, "Cube face size of the output (a power of two)")
            ->capture_default_str();
        cmd->add_option("--mips", o->mips, "Output mips (0: the full chain down to 1x1)")
            ->capture_default_str();
        cmd->add_option("--lobe", o->lobe,
                        "Lobe per mip: phong, (R.L)^n, or blinn-phong, (N.H)^n with N = V = R")
            ->check(CLI::IsMember({"phong", "blinn-phong"}))
            ->capture_default_str();
        cmd->add_option("--top-power", o->topPower, "Power of mip 0 (Lagarde's drop rule)")
            ->capture_default_str();
        cmd->add_option("--power-drop", o->powerDrop, "Factor from one mip's power to the next")
            ->capture_default_str();
        cmd->add_option(
            "--gloss-encoding", o->glossEncoding,
            "Power per mip from this gloss encoding (mip m <-> g = 1 - m/(mips-1)) instead of the drop: "
            "blackops, exp2, ggx-roughness, ggx-alpha, beckmann, smoothness, log:NMIN:NMAX");
        cmd->add_option("--irradiance-size", o->irradianceSize, "Face size of the irradiance cube")
            ->capture_default_str();
        cmd->add_option("--samples", o->samples, "Filtered-importance-sampling taps in --report")
            ->check(CLI::Range(1u, kMaxFisSamples))
            ->capture_default_str();
        cmd->add_option("--directions", o->directions, "Directions per mip in --report")
            ->check(CLI::Range(1u, 65536u))
            ->capture_default_str();
        cmd->add_option("--format", o->format,
                        "Output files: dds (RGBA16F cube with mips), exr (half faces), both")
            ->check(CLI::IsMember({"dds", "exr", "both"}))
            ->capture_default_str();
        cmd->add_flag("--normalize-diffuse", o->normalizeDiffuse,
                      "Divide the probe by its average diffuse lighting, per channel (Lazarov 2011)");
        cmd->add_flag("--json", o->json, "Print the summary as JSON");
        cmd->add_flag("--force", o->force,
                      "Replace the environment already in --out: exactly the new set is left (files the old "
                      "env.json names that this run does not write are removed)");
        cmd->add_flag(
            "--report", o->report,
            "Error per mip against the brute-force integral, with times, and FIS (report.json, report.md)");
        CLI::Option* faceSize = cmd->get_option("--face-size");
        return [o, faceSize] {
            o->faceSizeGiven = faceSize->count() > 0;
            return runEnv(*o);
        };
    }};

} // namespace

} // namespace burnish::cli
