// `burnish evaluate`: every prefiltering method against the texture-space ground truth, per mip,
// next to its cost.
#include "command.h"
#include "common.h"

#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/eval/evaluate_report.h>
#include <burnish/core/io/image.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/util/memory.h>

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>

namespace burnish::cli {

namespace {

struct EvaluateCliOptions {
    std::string input;
    std::vector<double> powers{512.0};
    bool powerGiven = false;
    std::string gloss;
    std::string glossEncoding = "blackops";
    int firstMip = 1;
    int lastMip = 4;
    double viewAngle = 30.0;
    std::vector<double> halfAngles;
    int azimuths = 8;
    std::vector<std::string> methods;
    std::vector<std::string> kernels{"box"};
    std::string out = "burnish-evaluate";
    bool outGiven = false; // --out on the command line
    bool errorMaps = false;
    bool betweenTexels = false;
    int bakeRuns = 3;
    std::string border = "wrap";
    double toksvigMapPower = 100.0;
    std::vector<int> lobes{kDefaultMixtureLobes};
    bool shadedFit = false;
    bool energySplit = false;
    std::string truthNormals;
    bool anisotropic = false;
    double steepDeg = 45.0;
    std::string mixtureFiltering = "moments";
    std::string brdf;
    std::string preset;
    bool floor = false;
    bool json = false;
    bool force = false;
    NormalMapCliOptions normalMap;
};

int runEvaluate(const EvaluateCliOptions& o) {
    // One memory ceiling for every command: estimated from the map's header, refused before it is decoded.
    {
        const auto header = readImageHeader(o.input);
        if (!header) return fail(header.error());
        EvaluationMemoryInput need;
        need.mapTexels = std::uint64_t(header->width) * std::uint64_t(header->height);
        need.lobeCounts = o.lobes.size();
        need.betweenTexels = o.betweenTexels;
        need.errorMaps = o.errorMaps;
        need.gloss = !o.gloss.empty();
        need.openImageIo = !decodedByCore(header->source.formatName, header->source.channelType);
        if (need.gloss)
            if (const auto gloss = readImageHeader(o.gloss))
                need.openImageIo =
                    need.openImageIo || !decodedByCore(gloss->source.formatName, gloss->source.channelType);
        if (const Status memory =
                checkMemory(estimatedEvaluationBytes(need),
                            fmt::format("evaluating a {}x{} map", header->width, header->height),
                            "close other programs, or evaluate a smaller map");
            !memory)
            return fail(memory.error());
    }
    auto map = loadNormalMap(o.input, toNormalMapOptions(o.normalMap));
    if (!map) return fail(map.error());
    for (const auto& w : map->diagnostics.warnings)
        std::fprintf(stderr, "burnish: warning: %s\n", printable(w).c_str());

    EvaluationReportOptions options;
    if (!o.gloss.empty()) {
        if (o.powerGiven)
            return fail("give --power or --gloss, not both (the gloss map sets every texel's power)");
        const auto encoding = GlossEncoding::fromName(o.glossEncoding);
        if (!encoding) return fail("--gloss-encoding: " + encoding.error());
        const auto image = readImage(o.gloss);
        if (!image) return fail("--gloss: " + image.error());
        const auto gloss = glossFromImage(*image, map->width, map->height);
        if (!gloss) return fail("--gloss '" + o.gloss + "': " + gloss.error());
        std::vector<double> powers(gloss->size());
        for (size_t i = 0; i < powers.size(); ++i)
            powers[i] = encoding->power((*gloss)[i]);
        options.evaluate.texelPowers = std::move(powers);
    }
    options.inputName = std::filesystem::path(o.input).filename().string();
    options.bakeRuns = o.bakeRuns;
    options.evaluate.basePowers = o.powers;
    options.evaluate.firstMip = o.firstMip;
    options.evaluate.lastMip = o.lastMip;
    options.evaluate.viewAngleDeg = o.viewAngle;
    if (!o.halfAngles.empty()) options.evaluate.halfAnglesDeg = o.halfAngles;
    options.evaluate.azimuths = o.azimuths;
    options.evaluate.border = o.border == "clamp" ? BorderMode::Clamp : BorderMode::Wrap;
    options.evaluate.errorMaps = o.errorMaps;
    options.evaluate.betweenTexels = o.betweenTexels;
    options.evaluate.params.toksvigMapPower = o.toksvigMapPower;
    options.evaluate.mixtureLobes = o.lobes;
    options.evaluate.params.mixtureShadedFit = o.shadedFit;
    options.evaluate.energySplit = o.energySplit;
    options.evaluate.steepDeg = o.steepDeg;
    options.evaluate.mixtureFiltering = *parseMixtureFiltering(o.mixtureFiltering); // checked by CLI11
    // The BRDF: --brdf, else the --preset's engine's (GGX for the roughness presets), else Blinn-Phong.
    if (!o.preset.empty()) {
        const auto preset = findPreset(o.preset);
        if (!preset) return fail("--preset: " + preset.error());
        options.evaluate.brdf = glossBrdf(preset->encoding);
    }
    if (!o.brdf.empty()) options.evaluate.brdf = *brdfFromName(o.brdf); // checked by CLI11
    if (!o.truthNormals.empty()) {
        TruthNormals t{};
        truthNormalsFromName(o.truthNormals, t); // checked by CLI11
        options.evaluate.truthNormals = t;
    }
    options.evaluate.floor = o.floor;
    options.evaluate.anisotropic = o.anisotropic;
    options.evaluate.methods = methodsUnder(options.evaluate.brdf);
    if (!o.methods.empty()) {
        options.evaluate.methods.clear();
        for (const auto& name : o.methods) {
            auto m = methodFromName(name);
            if (!m) return fail(m.error());
            options.evaluate.methods.push_back(*m);
        }
    }

    options.evaluate.kernels.clear();
    for (const auto& k : o.kernels)
        options.evaluate.kernels.push_back(k == "tent"       ? FilterKernel::Tent
                                           : k == "gaussian" ? FilterKernel::Gaussian
                                                             : FilterKernel::Box);

    // --json without --out (or --error-maps, which are files) prints the report and writes nothing: a script
    // piping it runs again without tripping over its own last report.
    const bool writeFiles = !o.json || o.outGiven || o.errorMaps;
    // One rule for every command: a previous report is replaced only with --force (checked before
    // the evaluation runs).
    if (writeFiles && !o.force && std::filesystem::exists(std::filesystem::path(o.out) / "evaluate.json"))
        return fail("refusing to replace the report in '" + o.out + "' (use --force)");
    ProgressBar bar("evaluating");
    auto report = buildEvaluationReport(*map, options, [&](double f) { bar.update(f); });
    bar.finish();
    if (!report) return fail(report.error());
    if (writeFiles)
        if (auto st = writeEvaluationReport(*report, o.out); !st) return fail(st.error());
    if (o.json)
        std::printf("%s\n", evaluationJson(*report).dump(2).c_str());
    else
        std::printf("%s\nWritten to %s/ (evaluate.md, evaluate.json, two PNG plots%s).\n",
                    evaluationMarkdown(*report).c_str(), o.out.c_str(), o.errorMaps ? ", errors/*.exr" : "");
    return 0;
}

const CommandRegistration registration{
    50, [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<EvaluateCliOptions>();
        CLI::App* sub = app.add_subcommand(
            "evaluate",
            "Measure every prefiltering method against the ground truth (render big, downsample, done in "
            "texture space) per mip, next to its bake time, shading cost and storage.");
        sub->add_option("input", o->input, "Tangent-space normal map (PNG, TGA, JPEG, EXR, TIFF, DDS).")
            ->required()
            ->type_name("IN");
        sub->add_option("--power", o->powers,
                        "Base Blinn-Phong power(s) s of the ground truth (default 512).")
            ->check(CLI::Range(1e-3, 1e9))
            ->type_name("S")
            ->each([o](const std::string&) { o->powerGiven = true; });
        sub->add_option("--gloss", o->gloss,
                        "Authored gloss map (first channel, the normal map's size): the ground truth uses "
                        "each texel's own power, the methods the block's power as the bake does "
                        "(1/s averaged). Replaces --power.")
            ->type_name("FILE");
        sub->add_option("--gloss-encoding", o->glossEncoding,
                        "Encoding of the --gloss map: blackops (default, 8192^g), exp2, ggx-roughness, "
                        "ggx-alpha, beckmann, smoothness or log:NMIN:NMAX.")
            ->type_name("NAME");
        sub->add_option("--first-mip", o->firstMip, "First mip level evaluated (default 1).")
            ->check(CLI::Range(0, 30));
        sub->add_option("--last-mip", o->lastMip,
                        "Last mip level evaluated (default 4; limited to the map's last level).")
            ->check(CLI::Range(0, 30));
        sub->add_option("--view-angle", o->viewAngle,
                        "View angle from the macro normal in degrees (default 30).")
            ->check(CLI::Range(0.0, 89.0));
        sub->add_option("--half-angles", o->halfAngles,
                        "Polar angles of the half vectors in degrees, comma separated (default "
                        "0,2.5,5,10,15,20,30; e.g. every degree to 40 for a dense set).")
            ->delimiter(',')
            ->check(CLI::Range(0.0, 89.0))
            ->type_name("LIST");
        sub->add_option("--azimuths", o->azimuths,
                        "Half-vector azimuths per polar angle, evenly spaced (default 8).")
            ->check(CLI::Range(1, 360));
        sub->add_option("--methods", o->methods,
                        "Methods to evaluate, comma separated (default all: naive, toksvig, toksvig-map, "
                        "variance-to-gloss, lean, clean, vmf, mixture, fitted; under --brdf ggx all but "
                        "the slope-space lean and clean, the mixture as an engine shades it: each lobe a GGX "
                        "lobe about its mean slope's normal, widened by its slopes' spread, as burnish gltf "
                        "--method mixture writes it for three.js).")
            ->delimiter(',')
            ->type_name("LIST");
        sub->add_option("--kernels", o->kernels,
                        "Footprint moments the methods read, comma separated: box (the definition, default), "
                        "tent, gaussian (the filtered moments a bake stores, reported beside box).")
            ->delimiter(',')
            ->check(CLI::IsMember({"box", "tent", "gaussian"}))
            ->type_name("LIST");
        auto* out =
            sub->add_option("--out", o->out,
                            "Folder for the report files (default burnish-evaluate; with --json and "
                            "without --out or --error-maps nothing is written, the report is on stdout).")
                ->type_name("DIR");
        sub->add_flag(
            "--error-maps", o->errorMaps,
            "Also write per-texel relative error maps as EXR (errors/<method>-s<power>-mip<k>.exr).");
        sub->add_flag(
            "--between-texels", o->betweenTexels,
            "Also evaluate at texel corners, where rendering samples: the truth is the bilinear-weighted "
            "union of four footprints, each method its shader's value from bilinearly filtered textures "
            "(extra tables and JSON rows with between_texels).");
        sub->add_option(
               "--mixture-filtering", o->mixtureFiltering,
               "How --between-texels filters the mixture: moments (hardware bilinear filtering of "
               "its stored lobes, which merges each slot's lobes; default) or stochastic (filtering "
               "after shading, as render --mixture-filtering stochastic draws it: the expected value "
               "over its samples, each texel's own mixture shaded and weighted).")
            ->check(CLI::IsMember({"moments", "stochastic"}));
        sub->add_option("--bake-runs", o->bakeRuns,
                        "Bake timings are the median of this many runs (default 3).")
            ->check(CLI::Range(1, 100));
        sub->add_option("--border", o->border, "Texture borders: wrap (tiling, default) or clamp.")
            ->check(CLI::IsMember({"wrap", "clamp"}));
        sub->add_option("--toksvig-map-power", o->toksvigMapPower,
                        "Fixed power the Toksvig map is baked for (default 100).")
            ->check(CLI::Range(1.0, 1e6));
        sub->add_option(
               "--lobes", o->lobes,
               "Lobe counts K of the mixture, comma separated, each its own row mixture-kK (default 3; "
               "1,2,3,4 draws the error-against-cost curve; K = 1 is LEAN; under --brdf ggx one GGX lobe "
               "widened by the whole footprint's spread).")
            ->delimiter(',')
            ->check(CLI::Range(1, 4))
            ->type_name("LIST");
        sub->add_flag("--shaded-fit", o->shadedFit,
                      "Fit the mixture's lobes to the shaded ground truth as well as to the moments (the "
                      "bake's --shaded-fit): its rows, and its bake time, are the refined fit's.");
        sub->add_flag(
            "--energy-split", o->energySplit,
            "Say where LEAN's energy goes, per power and mip: its energy ratio as the product of "
            "three steps from the truth (one cosine for the footprint, one Gaussian's shape, the "
            "steep normals' pull on the slope moments), beside the mixture's energy. Not with --gloss.");
        sub->add_option("--steep-deg", o->steepDeg,
                        "Tilt from the surface normal beyond which --energy-split counts a normal as steep "
                        "(default 45).")
            ->check(CLI::Range(0.001, 89.999));
        sub->add_option("--brdf", o->brdf,
                        "BRDF of the ground truth and of every lobe: blinn-phong (the reference texts' "
                        "normalized Blinn-Phong NDF times n.l) or ggx (GGX D, height-correlated Smith "
                        "visibility and n.l, as glTF engines shade; alpha^2 = 2/(s+2)). Default: the "
                        "--preset's engine's (ggx for gltf, unreal, unity, godot, filament), else "
                        "blinn-phong.")
            ->check(CLI::IsMember({"blinn-phong", "ggx"}))
            ->type_name("NAME");
        sub->add_flag(
            "--anisotropic", o->anisotropic,
            "Also evaluate the anisotropic fit (GGX only): per texel the pair KHR_materials_anisotropy "
            "stores (roughness across, strength and direction along), shaded as three.js and the glTF "
            "sample viewer shade it, as the row 'fitted anisotropic'.");
        sub->add_option("--truth-normals", o->truthNormals,
                        "How the ground truth sees the finest normals: texels (each texel a flat facet, the "
                        "reference texts' truth) or bilinear (the surface an engine draws when it magnifies "
                        "the map: each texel the mean of 2x2 sub-samples of the bilinear interpolant, "
                        "renormalized). Default: bilinear under ggx, texels under blinn-phong. The fitted "
                        "lobe and the floor fit to this truth.")
            ->check(CLI::IsMember({"texels", "bilinear"}))
            ->type_name("NAME");
        sub->add_option("--preset", o->preset,
                        "Engine preset (name or JSON file) whose BRDF the evaluation uses when --brdf is not "
                        "given.")
            ->type_name("NAME");
        sub->add_flag(
            "--floor", o->floor,
            "Also evaluate the one-lobe floor: per texel the best single isotropic roughness, no sharper "
            "than the base, by a brute-force search (slow), as a row 'one-lobe floor' beside the "
            "fitted lobe.");
        sub->add_flag("--json", o->json, "Print the report as JSON on stdout instead of Markdown.");
        sub->add_flag(
            "--force", o->force,
            "Replace the report already in --out (its error maps included: exactly the new report is "
            "left)");
        addNormalMapOptions(sub, o->normalMap);
        return [o, out] {
            o->outGiven = out->count() > 0;
            return runEvaluate(*o);
        };
    }};

} // namespace

} // namespace burnish::cli
