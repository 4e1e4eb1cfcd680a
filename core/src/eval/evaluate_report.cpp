#include <burnish/core/eval/evaluate_report.h>

#include "lobe_values.h"

#include <burnish/core/io/image.h>

#include <burnish/core/bake/bake.h>
#include <burnish/core/io/plot.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/util/files.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>

namespace burnish {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Shading cost: the value of the method's lobe (NDF × n̄·l) for the first kCostTexels texels of
// the first evaluated mip and every direction, computed by the evaluation's own vectorised loop on
// one core (lobe_values.h), kCostRepetitions times; the median time per value. The lobes fit in
// the core's cache, so this times the arithmetic, not memory.
constexpr size_t kCostTexels = 4096;
constexpr int kCostRepetitions = 9;

double medianNs(const LobeTable& table, const std::vector<DirectionPair>& directions) {
    std::vector<double> times, values(table.count);
    volatile double sink = 0.0;
    for (int r = 0; r < kCostRepetitions; ++r) {
        const auto start = Clock::now();
        double sum = 0.0;
        for (const auto& d : directions) {
            lobeValues(table, 0, table.count, d, values.data());
            sum += values[r % std::max<size_t>(table.count, 1)];
        }
        const double ns = std::chrono::duration<double, std::nano>(Clock::now() - start).count();
        sink = sink + sum;
        times.push_back(ns / double(std::max<size_t>(table.count, 1) * directions.size()));
    }
    return median(times);
}

double measureShadingNs(const NormalPyramid& pyramid, int mip, const EvaluatedVariant& v, double s,
                        const EvaluateOptions& options, const std::vector<DirectionPair>& directions) {
    const PyramidLevel& level = pyramid.level(mip);
    if (v.method == Method::Mixture && options.brdf == Brdf::Ggx) {
        // The mixture's GGX lobes at that mip, as evaluate and the engine draw them.
        const MixturePyramid mix = MixturePyramid::build(pyramid, s, v.lobes, mip);
        std::vector<LobeTable::GgxMixtureTexel> texels;
        for (int y = 0; y < level.height && texels.size() < kCostTexels; ++y)
            for (int x = 0; x < level.width && texels.size() < kCostTexels; ++x)
                texels.push_back(
                    mixtureGgxDecoded(mixtureGgxStored(mix, pyramid.finest(), mip, x, y, s), v.lobes, s));
        return medianNs(LobeTable::ofGgxMixture(texels, v.lobes), directions);
    }
    if (v.method == Method::Mixture && v.lobes > 1 && mip > 0) {
        // The mixture's own lobes at that mip, as evaluate draws them.
        const MixturePyramid mix = MixturePyramid::build(pyramid, s, v.lobes, mip);
        std::vector<DecodedMixture> texels;
        for (int y = 0; y < level.height && texels.size() < kCostTexels; ++y)
            for (int x = 0; x < level.width && texels.size() < kCostTexels; ++x)
                texels.push_back(decodeMixture(mix.at(mip, x, y), mix.minVariance()));
        return medianNs(LobeTable::of(texels), directions);
    }
    std::vector<TexelLobe> lobes;
    for (int y = 0; y < level.height && lobes.size() < kCostTexels; ++y)
        for (int x = 0; x < level.width && lobes.size() < kCostTexels; ++x)
            lobes.push_back(methodLobe(v.method, pyramid.boxMoments(mip, x, y), s, options.params));
    return medianNs(LobeTable::of(lobes, options.brdf), directions);
}

std::string powerLabel(double s) {
    std::ostringstream os;
    os << s;
    return os.str();
}

} // namespace

Result<EvaluationReport> buildEvaluationReport(const NormalMap& map, const EvaluationReportOptions& options,
                                               const std::function<void(double)>& progress,
                                               const std::atomic<bool>* cancel) {
    if (options.bakeRuns < 1) return Error{"bake runs must be at least 1"};
    auto cancelled = [cancel] { return cancel && cancel->load(std::memory_order_relaxed); };
    auto evaluated = evaluateMethods(
        map, options.evaluate,
        [&](double f) {
            if (progress) progress(0.8 * f);
        },
        cancel);
    if (!evaluated) return Error{evaluated.error()};

    EvaluationReport report;
    report.input = options.inputName;
    report.width = map.width;
    report.height = map.height;
    report.options = options.evaluate;
    report.result = std::move(*evaluated);
    // With an authored gloss map the results carry one label power (the map's mean).
    report.options.basePowers = report.result.basePowers;
    report.bakeRuns = options.bakeRuns;
    report.machine = machineInfo();

    const std::shared_ptr<const NormalMap> borrowed(&map, [](const NormalMap*) {});
    const NormalPyramid pyramid =
        NormalPyramid::build(borrowed, {options.evaluate.border, FilterKernel::Box});
    const double s = report.options.basePowers.front();
    // The bake timed in the encoding of the engine the truth is for (GGX roughness under GGX, where the
    // fitted lobe fits GGX; else the bake's default), with the authored gloss map too (its variance
    // pyramid costs time) stored in it.
    const GlossEncoding encoding =
        options.evaluate.brdf == Brdf::Ggx ? GlossEncoding::ggxRoughness() : BakeOptions{}.encoding;
    std::optional<std::vector<float>> authoredGloss;
    if (options.evaluate.texelPowers) {
        authoredGloss.emplace();
        for (double p : *options.evaluate.texelPowers)
            authoredGloss->push_back(float(encoding.value(p)));
    }
    std::vector<EvaluatedVariant> costed;
    for (const EvaluatedVariant& v : evaluatedVariants(options.evaluate))
        if (v.kernel == FilterKernel::Box && !v.floor && !v.anisotropic) costed.push_back(v);
    const size_t methodCount = costed.size();
    for (size_t i = 0; i < methodCount; ++i) {
        const EvaluatedVariant& v = costed[i];
        const Method method = v.method;
        MethodCost cost;
        cost.method = method;
        cost.lobes = v.lobes;
        MethodParams params = options.evaluate.params;
        if (v.lobes > 0) params.mixtureLobes = v.lobes;
        cost.storage = method == Method::Mixture && options.evaluate.brdf == Brdf::Ggx
                           ? mixtureGgxStorage(params.mixtureLobes)
                           : methodStorage(method, params);
        BakeOptions bakeOptions;
        bakeOptions.method = method;
        bakeOptions.basePower = s;
        bakeOptions.params = params;
        bakeOptions.pyramid = {options.evaluate.border, FilterKernel::Box};
        bakeOptions.mipCount = report.result.lastMip + 1;
        bakeOptions.encoding = encoding;
        bakeOptions.authoredGloss = authoredGloss;
        std::vector<double> runs;
        for (int r = 0; r < options.bakeRuns; ++r) {
            if (cancelled()) return Error{std::string(kCancelledMessage)};
            const auto start = Clock::now();
            auto baked = bake(map, bakeOptions);
            runs.push_back(std::chrono::duration<double>(Clock::now() - start).count());
            if (!baked) return Error{baked.error()};
        }
        cost.bakeSeconds = median(runs);
        if (cancelled()) return Error{std::string(kCancelledMessage)};
        cost.nsPerLobe = measureShadingNs(pyramid, report.result.firstMip, v, s, options.evaluate,
                                          report.result.directions);
        report.costs.push_back(cost);
        if (progress) progress(0.8 + 0.2 * double(i + 1) / double(methodCount));
    }
    if (cancelled()) return Error{std::string(kCancelledMessage)};
    return report;
}

namespace {

// Whether KHR_materials_anisotropy pays on this map: the means of the isotropic fit's and the anisotropic
// fit's relative L1 over every (power, mip) both were evaluated at, texel centres, box kernel. A material
// turns the extension on for all its texels, so this is the choice an export makes.
struct AnisotropicVerdict {
    int cases = 0;
    double fittedMean = 0.0, anisotropicMean = 0.0;
};
std::optional<AnisotropicVerdict> anisotropicVerdict(const EvaluationReport& r) {
    if (!r.options.anisotropic) return std::nullopt;
    AnisotropicVerdict v;
    for (const MipError& a : r.result.errors) {
        if (!a.anisotropic || a.betweenTexels) continue;
        for (const MipError& f : r.result.errors)
            if (f.method == Method::Fitted && !f.anisotropic && !f.floor && !f.betweenTexels &&
                f.kernel == FilterKernel::Box && f.basePower == a.basePower && f.mip == a.mip) {
                v.fittedMean += f.relativeL1, v.anisotropicMean += a.relativeL1, ++v.cases;
                break;
            }
    }
    if (v.cases == 0) return std::nullopt;
    v.fittedMean /= v.cases, v.anisotropicMean /= v.cases;
    return v;
}

// Where LEAN's energy goes at base power s (EvaluateOptions::energySplit), beside each evaluated
// mixture's energy at the same mip; empty without a split.
std::string energySplitMarkdown(const EvaluationReport& r, double s) {
    std::vector<const LeanEnergySplit*> rows;
    for (const auto& e : r.result.energySplits)
        if (e.basePower == s) rows.push_back(&e);
    if (rows.empty()) return {};
    std::vector<EvaluatedVariant> mixtures;
    for (const EvaluatedVariant& v : evaluatedVariants(r.options))
        if (v.method == Method::Mixture) mixtures.push_back(v);
    std::vector<std::string> header{"mip",     "LEAN energy", "= cosine",
                                    "x shape", "x steep",     "steep normals' share of the truth"};
    for (const auto& v : mixtures)
        header.push_back(variantLabel(v) + " energy");
    std::vector<Align> align(header.size(), Align::Right);
    MarkdownTable table(header, align);
    for (const LeanEnergySplit* e : rows) {
        std::vector<std::string> row{std::to_string(e->mip),  formatNumber(e->energy),
                                     formatNumber(e->cosine), formatNumber(e->shape),
                                     formatNumber(e->steep),  formatNumber(e->steepTruth)};
        for (const auto& v : mixtures)
            for (const auto& x : r.result.errors)
                if (variantOf(x) == v && !x.betweenTexels && x.basePower == s && x.mip == e->mip)
                    row.push_back(formatNumber(x.energyRatio));
        table.addRow(row);
    }
    std::ostringstream md;
    md << "Where LEAN's energy goes (" << formatNumber(100.0 * rows.front()->steepNormals)
       << " % of the normals are steep, tilted more than " << formatNumber(r.options.steepDeg)
       << " deg): its energy ratio is the product of three steps from the truth. cosine: the truth with "
          "LEAN's one cosine max(0, n.l) for the footprint instead of each normal's own; shape: LEAN's "
          "slope-space Gaussian of the normals that are not steep, weighted by their share, against that "
          "truth (one Gaussian's tails and peak against the normals' own lobes); steep: LEAN against that "
          "Gaussian (the steep normals' pull on the slope moments). A factor of 1 loses nothing.\n\n"
       << table.render() << "\n";
    return md.str();
}

} // namespace

std::string evaluationMarkdown(const EvaluationReport& r) {
    std::ostringstream md;
    md << "# Burnish evaluation: " << (r.input.empty() ? std::string("normal map") : r.input) << "\n\n";
    md << r.width << "x" << r.height << " texels; mips " << r.result.firstMip << ".." << r.result.lastMip
       << "; view " << formatNumber(r.options.viewAngleDeg) << " deg from the macro normal; "
       << r.result.directions.size() << " light/view pairs (half vectors at";
    for (double a : r.options.halfAnglesDeg)
        md << " " << formatNumber(a);
    md << " deg x " << r.options.azimuths << " azimuths, lights within " << formatNumber(r.options.horizonDeg)
       << " deg of the horizon dropped).\n\n";
    if (r.options.texelPowers) {
        const auto& p = *r.options.texelPowers;
        const auto [lo, hi] = std::minmax_element(p.begin(), p.end());
        md << "Authored gloss map: every finest texel has its own power s_i (" << formatNumber(*lo) << " to "
           << formatNumber(*hi) << ", mean " << formatNumber(r.options.basePowers.front())
           << ", the label of the tables below). The ground truth uses D_{s_i} per texel; every method "
              "gets the block's power as the bake does, s = 1/mean(1/s_i) (variance averaged).\n\n";
    }
    if (r.options.brdf == Brdf::Ggx)
        md << "Ground truth (--brdf ggx): for mip k, the mean over the texel's footprint of finest texels of "
              "the GGX specular term an engine shades, D_GGX(n_i.h) V(n_i.l, n_i.v)/4 max(0, n_i.l) with "
              "the height-correlated Smith visibility of glTF's reference BRDF and alpha^2 = 2/(s+2) of the "
              "base power s (Fresnel 1). Each method: one GGX lobe about its renormalized mean normal with "
              "the alpha of its power, shaded the same way; the mixture: per lobe its share times a GGX lobe "
              "about the normal of its mean slope b with alpha^2 = alpha0^2 + "
           << kMixtureGgxSpreadScale
           << " (S - |b|^2), S - |b|^2 the "
              "spread of its normals' slopes, from the stored lobes (w, w.b, w.S) as burnish gltf --method "
              "mixture writes them and bilinear filtering merges them. ";
    else
        md << "Ground truth: for mip k, the mean over the texel's footprint of finest texels of "
              "D_s(n_i.h) max(0, n_i.l), D_s the normalized Blinn-Phong NDF of the base power s. "
              "Each method: its own NDF times max(0, n.l) with its normal, from box-footprint moments. ";
    if (r.options.resolvedTruthNormals() == TruthNormals::Bilinear)
        md << "The finest normals as an engine draws them when it magnifies the map (--truth-normals "
              "bilinear): each finest texel's truth is the mean over 2x2 sub-samples (at +-1/4 texel) of the "
              "bilinear interpolant of the texels, renormalized; bilinear filtering averages neighbours, so "
              "texel-scale noise is narrower there than the texels are. ";
    if (r.options.anisotropic)
        md << "Fitted anisotropic: per texel the pair KHR_materials_anisotropy stores (the roughness across, "
              "a strength that lengthens it along a direction), fitted by the same measure and shaded as "
              "three.js and the glTF sample viewer shade it, with the direction in the geometric tangent "
              "plane (so about a tilted mean normal even a round lobe differs from the isotropic term; "
              "with the extension on, every texel is shaded that way). ";
    if (r.options.floor)
        md << "The one-lobe floor: per texel the best one isotropic lobe about the mean normal no sharper "
              "than the base, by a brute-force search of its roughness (what no such roughness can beat). ";
    md << "Relative L1 = sum|M - GT| / sum GT; energy = sum M / sum GT (1 is exact). "
          "Rows marked (tent) or (gaussian) use the kernel-filtered moments a bake stores instead of the "
          "footprint's own, against the same ground truth.\n\n";

    for (double s : r.options.basePowers) {
        md << "## Base power " << powerLabel(s) << "\n\n";
        std::vector<std::string> header{"method"};
        for (int k = r.result.firstMip; k <= r.result.lastMip; ++k)
            header.push_back("mip " + std::to_string(k));
        std::vector<Align> align(header.size(), Align::Right);
        align[0] = Align::Left;
        for (const bool between : {false, true}) {
            if (between && !r.options.betweenTexels) continue;
            MarkdownTable errors(header, align);
            MarkdownTable energy(header, align);
            for (const EvaluatedVariant& v : evaluatedVariants(r.options)) {
                std::vector<std::string> e{variantLabel(v)}, en{variantLabel(v)};
                for (int k = r.result.firstMip; k <= r.result.lastMip; ++k)
                    for (const auto& x : r.result.errors)
                        if (variantOf(x) == v && x.betweenTexels == between && x.basePower == s &&
                            x.mip == k) {
                            e.push_back(formatNumber(x.relativeL1));
                            en.push_back(formatNumber(x.energyRatio));
                        }
                errors.addRow(e);
                energy.addRow(en);
            }
            if (between)
                md << "Between texels (at each texel's corner: the truth is the bilinear-weighted union of "
                      "the four "
                      "footprints, each method what its shader computes from bilinearly filtered "
                      "textures"
                   << (r.options.mixtureFiltering == MixtureFiltering::Stochastic
                           ? "; the mixture filtered after shading, stochastic filtering's expected value"
                           : "")
                   << "):\n\n";
            md << "Relative L1 error against the ground truth" << (between ? " between texels" : "")
               << ":\n\n"
               << errors.render() << "\nEnergy ratio" << (between ? " between texels" : "") << ":\n\n"
               << energy.render() << "\n";
        }
        md << energySplitMarkdown(r, s);
    }

    if (const auto v = anisotropicVerdict(r))
        md << "**KHR_materials_anisotropy on this map:** over the " << v->cases
           << " power and mip cases the anisotropic fit's mean relative L1 is "
           << formatNumber(v->anisotropicMean) << " against the isotropic fit's "
           << formatNumber(v->fittedMean) << ": "
           << (v->anisotropicMean < v->fittedMean
                   ? "by this measure turning the extension on pays here."
                   : "leave it off (with it on, every texel is shaded by the anisotropic form).")
           << "\n\n";
    md << "## Cost\n\n";
    MarkdownTable cost({"method", "bake (s, median of " + std::to_string(r.bakeRuns) + ")",
                        "shading (ns/lobe)", "fetches", "bytes/texel", "storage"},
                       {Align::Left, Align::Right, Align::Right, Align::Right, Align::Right, Align::Left});
    for (const auto& c : r.costs)
        cost.addRow({variantLabel({c.method, FilterKernel::Box, c.lobes}), formatNumber(c.bakeSeconds),
                     formatNumber(c.nsPerLobe), std::to_string(c.storage.textureFetches),
                     formatNumber(c.storage.bytesPerTexel), std::string(c.storage.layout)});
    md << cost.render() << "\n";
    md << "Bake: in-memory, pyramid included, to mip " << r.result.lastMip
       << ". Shading: the method's lobe (NDF times n.l) evaluated in double on one CPU core by the "
          "evaluation's own vectorised loop, "
       << kCostTexels
       << " lobes of the first mip in cache (a CPU proxy for its shader's arithmetic; the renderer measures "
          "GPU frame times). Measured on "
       << r.machine.cpuModel << " (" << r.machine.logicalCpus << " threads), " << r.machine.compiler
       << "; evaluation took " << formatNumber(r.result.seconds) << " s.\n\n";
    md << "Methods:\n\n";
    for (Method m : r.options.methods)
        md << "- `" << methodName(m) << "`: " << methodDescription(m) << "\n";
    return md.str();
}

nlohmann::json evaluationJson(const EvaluationReport& r) {
    nlohmann::json j;
    j["input"] = r.input;
    j["width"] = r.width;
    j["height"] = r.height;
    j["mips"] = {r.result.firstMip, r.result.lastMip};
    j["view_angle_deg"] = r.options.viewAngleDeg;
    j["half_angles_deg"] = r.options.halfAnglesDeg;
    j["azimuths"] = r.options.azimuths;
    j["horizon_deg"] = r.options.horizonDeg;
    j["directions"] = r.result.directions.size();
    j["mixture_filtering"] = mixtureFilteringName(r.options.mixtureFiltering);
    j["brdf"] = brdfName(r.options.brdf);
    j["truth_normals"] = truthNormalsName(r.options.resolvedTruthNormals());
    if (const auto v = anisotropicVerdict(r))
        j["anisotropic_verdict"] = {{"cases", v->cases},
                                    {"fitted_mean", jsonNumber(v->fittedMean)},
                                    {"anisotropic_mean", jsonNumber(v->anisotropicMean)},
                                    {"anisotropic_better", v->anisotropicMean < v->fittedMean}};
    j["base_powers"] = r.options.basePowers;
    if (r.options.texelPowers) {
        const auto& p = *r.options.texelPowers;
        const auto [lo, hi] = std::minmax_element(p.begin(), p.end());
        j["authored_gloss"] = {{"min_power", *lo},
                               {"max_power", *hi},
                               {"mean_power", r.options.basePowers.front()},
                               {"method_power", "1/mean(1/s_i) over the footprint, as the bake"}};
    }
    j["evaluation_seconds"] = jsonNumber(r.result.seconds);
    j["errors"] = nlohmann::json::array();
    for (const auto& e : r.result.errors)
        j["errors"].push_back({{"method", e.floor         ? std::string(kFloorLabel)
                                          : e.anisotropic ? std::string(kAnisotropicLabel)
                                                          : std::string(methodName(e.method))},
                               {"variant", variantLabel(variantOf(e))},
                               {"lobes", e.lobes},
                               {"between_texels", e.betweenTexels},
                               {"kernel", kernelName(e.kernel)},
                               {"base_power", e.basePower},
                               {"mip", e.mip},
                               {"relative_l1", jsonNumber(e.relativeL1)},
                               {"energy_ratio", jsonNumber(e.energyRatio)}});
    if (r.options.energySplit) {
        j["steep_deg"] = r.options.steepDeg;
        j["lean_energy_split"] = nlohmann::json::array();
        for (const auto& e : r.result.energySplits)
            j["lean_energy_split"].push_back({{"base_power", e.basePower},
                                              {"mip", e.mip},
                                              {"energy", jsonNumber(e.energy)},
                                              {"cosine", jsonNumber(e.cosine)},
                                              {"shape", jsonNumber(e.shape)},
                                              {"steep", jsonNumber(e.steep)},
                                              {"steep_normals", jsonNumber(e.steepNormals)},
                                              {"steep_truth", jsonNumber(e.steepTruth)}});
    }
    j["costs"] = nlohmann::json::array();
    for (const auto& c : r.costs)
        j["costs"].push_back({{"method", methodName(c.method)},
                              {"variant", variantLabel({c.method, FilterKernel::Box, c.lobes})},
                              {"lobes", c.lobes},
                              {"bake_seconds_median", jsonNumber(c.bakeSeconds)},
                              {"bake_runs", r.bakeRuns},
                              {"shading_ns_per_lobe", jsonNumber(c.nsPerLobe)},
                              {"texture_fetches", c.storage.textureFetches},
                              {"bytes_per_texel", c.storage.bytesPerTexel},
                              {"storage", std::string(c.storage.layout)}});
    j["machine"] = {
        {"cpu", r.machine.cpuModel}, {"threads", r.machine.logicalCpus}, {"compiler", r.machine.compiler}};
    return j;
}

PlotSpec evaluationErrorPerMipPlot(const EvaluationReport& r) {
    PlotSpec spec;
    spec.title =
        "Error against the ground truth per mip" + (r.input.empty() ? std::string() : " - " + r.input);
    spec.x = {"mip level", AxisScale::Linear, double(r.result.firstMip) - 0.25,
              double(r.result.lastMip) + 0.25};
    spec.y = {"relative L1 error", AxisScale::Log, std::nullopt, std::nullopt};
    size_t colour = 0;
    for (double s : r.options.basePowers)
        for (const EvaluatedVariant& v : evaluatedVariants(r.options)) {
            PlotSeries series;
            series.name = variantLabel(v) + (r.options.basePowers.size() > 1 ? " s=" + powerLabel(s) : "");
            series.color = plotPalette(colour++);
            series.line = true;
            for (const auto& e : r.result.errors)
                if (variantOf(e) == v && !e.betweenTexels && e.basePower == s) {
                    series.x.push_back(e.mip);
                    series.y.push_back(e.relativeL1);
                }
            spec.series.push_back(std::move(series));
        }
    return spec;
}

PlotSpec evaluationErrorVsCostPlot(const EvaluationReport& r) {
    PlotSpec spec;
    const double s = r.options.basePowers.front();
    spec.title = "Error at mip " + std::to_string(r.result.lastMip) +
                 " against shading cost (s=" + powerLabel(s) + ")";
    spec.x = {"shading cost (ns per lobe evaluation, CPU)", AxisScale::Log, std::nullopt, std::nullopt};
    spec.y = {"relative L1 error", AxisScale::Log, std::nullopt, std::nullopt};
    std::vector<ParetoPoint> points;
    std::vector<std::string> names;
    for (const auto& c : r.costs)
        for (const auto& e : r.result.errors)
            if (e.method == c.method && e.lobes == c.lobes && !e.betweenTexels &&
                e.kernel == FilterKernel::Box && e.basePower == s && e.mip == r.result.lastMip) {
                points.push_back({"methods", c.nsPerLobe, e.relativeL1});
                names.emplace_back(variantLabel({c.method, FilterKernel::Box, c.lobes}));
            }
    const auto front = paretoFront(points);
    PlotSeries all{"methods", {}, {}, {0.2f, 0.3f, 0.7f}, false, 2, MarkerShape::Square, 9, {}};
    PlotSeries pareto{
        "Pareto front", {}, {}, {0.85f, 0.2f, 0.15f}, true, 2, MarkerShape::HollowSquare, 15, {}};
    std::vector<std::pair<double, double>> frontPoints;
    for (size_t i = 0; i < points.size(); ++i) {
        all.x.push_back(points[i].cost);
        all.y.push_back(points[i].error);
        all.pointLabels.push_back(names[i]);
        if (front[i]) frontPoints.emplace_back(points[i].cost, points[i].error);
    }
    std::sort(frontPoints.begin(), frontPoints.end());
    for (const auto& [x, y] : frontPoints) {
        pareto.x.push_back(x);
        pareto.y.push_back(y);
    }
    spec.series = {all, pareto};
    return spec;
}

Status writeEvaluationReport(const EvaluationReport& r, const fs::path& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return Error{"cannot create folder '" + dir.string() + "': " + ec.message()};
    // The report is one set with evaluate.json as its index, the error maps a set of their own in
    // errors/: both staged in full first; then the old index goes, the maps are switched, and the
    // new index comes last. A folder holding evaluate.json holds the whole report it describes; a
    // killed commit is finished by the next run (FileSet::begin).
    auto begun = FileSet::begin(dir);
    if (!begun) return Error{begun.error()};
    FileSet& report = begun.value();
    if (auto st = report.addBytes("evaluate.md", evaluationMarkdown(r)); !st) return st;
    if (auto st = report.addBytes("evaluate.json", evaluationJson(r).dump(2) + "\n"); !st) return st;
    for (const auto& [name, plot] : {std::pair{"evaluate-error-per-mip.png", evaluationErrorPerMipPlot(r)},
                                     std::pair{"evaluate-error-vs-cost.png", evaluationErrorVsCostPlot(r)}}) {
        const auto png = encodePlotPng(plot);
        if (!png) return Error{png.error()};
        if (auto st = report.addBytes(name, *png); !st) return st;
    }
    const fs::path errorsDir = dir / "errors";
    std::optional<FileSet> errors;
    std::vector<std::string> written;
    if (!r.result.maps.empty() || fs::is_directory(errorsDir, ec)) {
        fs::create_directories(errorsDir, ec);
        if (ec) return Error{"cannot create folder '" + errorsDir.string() + "': " + ec.message()};
        auto set = FileSet::begin(errorsDir);
        if (!set) return Error{set.error()};
        errors.emplace(std::move(set).value());
        for (const auto& m : r.result.maps) {
            const std::string kernel =
                m.kernel == FilterKernel::Box ? "" : "-" + std::string(kernelName(m.kernel));
            // The floor's label has spaces: its file is "floor-…".
            const std::string name =
                (m.floor         ? std::string("floor")
                 : m.anisotropic ? std::string("fitted-anisotropic")
                                 : variantLabel({m.method, FilterKernel::Box, m.lobes})) +
                kernel + "-s" + powerLabel(m.basePower) + "-mip" + std::to_string(m.mip) + ".exr";
            const Status st = errors->add(name, [&](const fs::path& staged) {
                return writeImageFile(staged, m.width, m.height, 1, m.relativeError,
                                      {StoredType::Float, {"Y"}, {}}, errorsDir / name);
            });
            if (!st) return st;
            written.push_back(name);
        }
    }
    // The error maps of an earlier report that this one does not write (other powers, methods or
    // mips) go: the folder holds exactly this report.
    std::vector<std::string> obsolete;
    for (fs::directory_iterator it(errorsDir, ec), end; !ec && it != end; it.increment(ec))
        if (it->path().extension() == ".exr" &&
            std::find(written.begin(), written.end(), it->path().filename().string()) == written.end())
            obsolete.push_back(it->path().filename().string());
    if (errors) {
        // Without the old index first, a kill while the maps are switched cannot leave an old
        // evaluate.json beside new maps.
        if (fs::exists(fs::symlink_status(dir / "evaluate.json", ec)) &&
            !fs::remove(dir / "evaluate.json", ec))
            return Error{"cannot remove '" + (dir / "evaluate.json").string() + "': " + ec.message()};
        if (auto st = errors->commit({}, obsolete, Overwrite::Allow); !st) return st;
    }
    return report.commit("evaluate.json", {}, Overwrite::Allow);
}

std::uint64_t estimatedEvaluationBytes(const EvaluationMemoryInput& in) {
    constexpr double kBase = 40e6, kPerTexel = 330.0, kPerExtraLobeCount = 90.0, kBetween = 180.0,
                     kBetweenPerExtraLobeCount = 60.0, kErrorMaps = 100.0, kGloss = 20.0;
    const double extra = double(std::max<size_t>(in.lobeCounts, 1) - 1);
    double perTexel = kPerTexel + kPerExtraLobeCount * extra;
    if (in.betweenTexels) perTexel += kBetween + kBetweenPerExtraLobeCount * extra;
    if (in.errorMaps) perTexel += kErrorMaps;
    if (in.gloss) perTexel += kGloss;
    constexpr double kOpenImageIo = 50e6;
    return std::uint64_t(kBase + (in.openImageIo ? kOpenImageIo : 0.0) + perTexel * double(in.mapTexels));
}

} // namespace burnish
