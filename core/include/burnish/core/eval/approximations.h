// The approximations report: every approximation in core measured against its exact form, with
// its error over a stated domain and its cost per evaluation timed against the exact form's in
// the same run. Also exposes the timed float kernels, so Google Benchmark times the same loops.
#pragma once

#include <burnish/core/io/plot.h>
#include <burnish/core/shading/spherical_gaussian.h>
#include <burnish/core/util/error_accumulator.h>
#include <burnish/core/util/result.h>

#include <nlohmann/json.hpp>

#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace burnish {

// ---------------------------------------------------------------------------------------------
// Error metrics.

/// Which error a group is ranked by (Pareto flag, plot).
enum class HeadlineMetric { MaxAbs, MaxRel };

// ---------------------------------------------------------------------------------------------
// Timed kernels: plain loops over float arrays prepared beforehand, written for the vectorizer.

/// Up to six input streams (which stream holds what is the kernel's documentation) and an output.
struct KernelArgs {
    std::array<const float*, 6> in{};
    float* out = nullptr;
    size_t count = 0;
};
using Kernel = std::function<void(const KernelArgs&)>;

/// Input streams of one kernel pair, all of the same length.
struct KernelInputs {
    std::vector<std::vector<float>> streams;
    size_t size() const { return streams.empty() ? 0 : streams.front().size(); }
};

/// An approximation's kernel and its exact form's kernel over the same inputs.
struct TimedKernelPair {
    std::string id; // stable key, e.g. "fresnel-schlick"; the report's entries use the same ids
    Kernel approx;
    Kernel exact;
    /// Deterministic inputs covering the entry's domain.
    std::function<KernelInputs(size_t count, std::uint32_t seed)> makeInputs;
    /// Evaluations per input element (the Phong pair shades several lights per element).
    double evalsPerElement = 1.0;
    /// When > 0, the exact form is timed on at most this many inputs: it is a numerical integral
    /// (milliseconds per evaluation), so a million evaluations would take hours.
    size_t exactInputCap = 0;
};

/// The best-fit SG offset table x(n) the report measures and times: fitSgOffsetCurve over powers
/// 1..1e4 (33 nodes), fitted once per process.
const SgOffsetCurve& reportSgOffsetCurve();

/// Every pair the report times, in report order (built once per process).
const std::vector<TimedKernelPair>& timedKernelPairs();

/// Median time per evaluation of approx and exact, measured interleaved (approx, exact, approx, …)
/// after one untimed warm-up run each, so machine noise falls on both alike.
struct KernelTiming {
    double approxNs = 0.0;
    double exactNs = 0.0;
    size_t approxInputs = 0;
    size_t exactInputs = 0;
    int repetitions = 0;
    double checksum = 0.0; // sum of all outputs, consumed so the loops cannot be optimized away
};
KernelTiming timeKernelPair(const TimedKernelPair& pair, size_t inputs, int repetitions,
                            std::uint32_t seed = 1);

/// How the kernel translation unit was compiled (flags and the instruction-set macros it saw).
std::string kernelBuildDescription();

// ---------------------------------------------------------------------------------------------
// The report.

struct ApproximationOptions {
    bool quick = false;  // fewer inputs and repetitions, coarser error grids (for tests)
    size_t inputs = 0;   // 0: 2^20 (quick: 2^16)
    int repetitions = 0; // 0: 7 (quick: 3)
};

struct ApproximationEntry {
    std::string id;
    std::string group;
    std::string name;
    std::string formula;
    std::string exact;  // the reference form
    std::string domain; // where the error was measured
    HeadlineMetric metric = HeadlineMetric::MaxAbs;
    ErrorMetrics error;
    /// What maxRel is relative to, or why it is n/a.
    std::string relBasis;
    double approxNs = 0.0;
    double exactNs = 0.0;
    size_t approxInputs = 0;
    size_t exactInputs = 0;
    bool pareto = false;
    std::vector<std::string> notes;

    double ratio() const; // approxNs / exactNs; NaN when not measurable
    double headlineError() const;
};

struct ApproximationReport {
    bool quick = false;
    size_t inputs = 0;
    int repetitions = 0;
    std::string cpuModel;
    unsigned logicalCpus = 0;
    std::string compiler;
    std::string kernelBuild;
    double seconds = 0.0;            // wall time of the measurement
    std::vector<std::string> groups; // in report order
    std::vector<ApproximationEntry> entries;
};

/// Measures every entry. Fails if a measurement produced a non-finite number (a bug), or when
/// `cancel` (if set, raised from any thread; read before each entry's error grid and timing) is
/// raised: then the Error's message is "cancelled" (kCancelledMessage of evaluate.h) and no report.
Result<ApproximationReport> measureApproximations(const ApproximationOptions& options,
                                                  const std::atomic<bool>* cancel = nullptr);

/// Marks each entry's Pareto flag among the entries of its group with the same exact form (cost:
/// approx ns/eval; error: headline metric). Alternatives to different references never compete.
void markParetoFront(std::vector<ApproximationEntry>& entries);

std::string approximationsMarkdown(const ApproximationReport& report);
nlohmann::json approximationsJson(const ApproximationReport& report);
PlotSpec approximationsPlot(const ApproximationReport& report);

/// Writes approximations.md, approximations.json and approximations.png into `dir` (which must
/// exist), each atomically.
Status writeApproximationReport(const ApproximationReport& report, const std::filesystem::path& dir);

// ---------------------------------------------------------------------------------------------
// The reference of the glossy environment Fresnel, exposed for tests.

/// Hemispherical integral of the Blinn-Phong specular BRDF D·F·V/4·(n·l) under a white
/// environment, split by linearity in the specular colour c: result(c) = c·full + (1−c)·fresnel,
/// with full the integral for F = 1 and fresnel the one for F = (1 − h·l)^5. D: normalized
/// Blinn-Phong, n = 8192^g; V: Schlick–Smith. NoV and g are clamped to [0, 1].
struct GlossyEnvironmentMoments {
    double full = 0.0;
    double fresnel = 0.0;
    double at(double c) const { return c * full + (1.0 - c) * fresnel; }
};
GlossyEnvironmentMoments glossyEnvironmentReference(double NoV, double g);

} // namespace burnish
