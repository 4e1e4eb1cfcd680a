// The evaluation report: each method's error against the ground truth per mip (evaluate.h) next
// to what it costs — bake time, measured shading time per lobe evaluation, texture fetches and
// bytes per texel stored — as Markdown, JSON, PNG plots and per-texel EXR error maps.
#pragma once

#include <burnish/core/eval/evaluate.h>
#include <burnish/core/io/plot.h>
#include <burnish/core/util/report.h>

#include <nlohmann/json.hpp>

#include <cstdint>

#include <filesystem>
#include <string>
#include <vector>

namespace burnish {

struct MethodCost {
    Method method;
    int lobes = 0;            // the mixture's K (0 for the other methods)
    double bakeSeconds = 0.0; // median over the runs of an in-memory bake (pyramid included)
    double nsPerLobe = 0.0;   // median ns per lobe evaluation (NDF × n·l, double, one core)
    MethodStorage storage;
};

struct EvaluationReport {
    std::string input;
    int width = 0;
    int height = 0;
    EvaluateOptions options;
    EvaluationResult result;
    std::vector<MethodCost> costs;
    int bakeRuns = 0;
    MachineInfo machine;
};

struct EvaluationReportOptions {
    EvaluateOptions evaluate;
    int bakeRuns = 3;
    std::string inputName;
};

/// Runs the evaluation and the cost measurements. `progress` (if set): the fraction done,
/// non-decreasing, ending at 1. `cancel` (if set, raised from any thread) is checked as in
/// evaluateMethods and between the methods' bake runs: a raised flag returns the Error
/// kCancelledMessage (evaluate.h) and no report.
Result<EvaluationReport> buildEvaluationReport(const NormalMap& map, const EvaluationReportOptions& options,
                                               const std::function<void(double)>& progress = {},
                                               const std::atomic<bool>* cancel = nullptr);

/// What an evaluation's peak memory is estimated from, known before the map is decoded.
struct EvaluationMemoryInput {
    std::uint64_t mapTexels = 0;
    size_t lobeCounts = 1; // the mixture's K values evaluated (--lobes 1,2,3,4: 4)
    bool betweenTexels = false;
    bool errorMaps = false;
    bool gloss = false;       // a gloss map: a power per texel
    bool openImageIo = false; // a map (or gloss map) core does not decode itself
};
/// The peak memory of `burnish evaluate` (all methods, the default mips and directions): 40 MB and per
/// map texel 330 bytes (the pyramid, each method's bake, the truth's bands), 90 more per extra K of the
/// mixture, 180 more between texels (and 60 more there per extra K), 100 with error maps, 20 with a
/// gloss map; 50 MB more when OpenImageIO reads the map (a 512² EXR: 149 MB, its PNG 98). Measured peaks
/// against this (core/bench/command_memory.sh, trak-rust1 resized): 512² 98 / 127 MB, 1024² 355 / 386 MB,
/// 2048² 1381 / 1424 MB; at 1024²: --between-texels 544 / 575, --lobes 1,2,3,4 629 / 669, both 975 / 1047,
/// --error-maps 456 / 491, --gloss 375 / 407 MB.
std::uint64_t estimatedEvaluationBytes(const EvaluationMemoryInput& input);

std::string evaluationMarkdown(const EvaluationReport& report);
nlohmann::json evaluationJson(const EvaluationReport& report);
/// Error per mip for each method (one series per method and base power).
PlotSpec evaluationErrorPerMipPlot(const EvaluationReport& report);
/// Error at the last evaluated mip against measured shading cost, Pareto front marked.
PlotSpec evaluationErrorVsCostPlot(const EvaluationReport& report);

/// Writes evaluate.md, evaluate.json, evaluate-error-per-mip.png, evaluate-error-vs-cost.png and,
/// when the result holds error maps, errors/<method>-s<power>-mip<k>.exr (one float channel),
/// as one set: everything staged first, then the old evaluate.json removed, the error maps switched
/// (those of an earlier report this one does not write removed), the other files renamed and
/// evaluate.json renamed last, so a folder holding evaluate.json holds the whole report; a killed
/// commit is finished by the next write into the folder. Creates `dir` and `dir/errors` when missing.
Status writeEvaluationReport(const EvaluationReport& report, const std::filesystem::path& dir);

} // namespace burnish
