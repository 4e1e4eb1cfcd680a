// One bake as a user describes it (names as text, as `burnish bake` and the studio's Bake & Export
// dialog take them): resolve the names → read the inputs → bake → export (→ the ground-truth
// report). Both front ends call these functions, so a bake started from a button and from the command
// line write identical bytes. Many jobs come from a manifest (readBakeManifest); bake_ninja.h turns
// resolved jobs into a Ninja build file.
#pragma once

#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/detail.h>
#include <burnish/core/bake/export.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/util/memory.h>
#include <burnish/core/util/result.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish {

/// Input name prefix of a built-in sample map instead of a file: "sample:hammered" bakes
/// makeSampleNormalMap(Hammered, kSampleBakeSize) with the file stem "hammered".
inline constexpr std::string_view kSampleInputPrefix = "sample:";
/// Size of a sample map baked through a job (the studio's default document size).
inline constexpr int kSampleBakeSize = 512;
/// Whether a job input names a built-in sample ("sample:<kind>") rather than a file.
inline bool isSampleBakeInput(std::string_view input) {
    return input.substr(0, kSampleInputPrefix.size()) == kSampleInputPrefix;
}

/// A bake as the user described it: every name still text, every option optional.
struct BakeJobSpec {
    std::string input; // a normal-map file, or "sample:<kind>"
    std::string out;   // output folder (created if missing)
    std::string preset;
    std::optional<std::string> method;
    std::optional<double> power;
    std::optional<std::string> gloss; // authored gloss map file
    /// An authored gloss held in memory instead of a file (the studio's painted layers composited
    /// over its gloss map or base gloss): one value per texel of the normal map, row-major, in the
    /// preset's gloss encoding; values are clamped to [0, 1] as a gloss file's are. It overrides
    /// `gloss` (that file is then not read, only named in bake.json as what was painted over), and
    /// bake.json records inputs.gloss = {"source": kPaintedGlossSource, "paintedOver", "fnv1a64"}
    /// in place of inputs.glossMap. Null: none. Not expressible in a manifest or a Ninja file.
    std::shared_ptr<const std::vector<float>> authoredGloss;
    std::optional<std::string> format;
    std::optional<std::string> compression;
    std::optional<std::string> kernel;
    std::optional<std::string> border;
    std::optional<std::string> green;
    std::optional<std::string> layout;
    /// How the input's stored values map to [-1, 1]: auto (detected), unsigned or signed.
    std::optional<std::string> encoding;
    std::optional<double> metallic;
    /// The specular colour: a material of `burnish materials` ("iron") or linear F0 "R,G,B"; bake.json
    /// records it with the preset's engine's values for it (shading/specular_terms.h) and the job's
    /// summary its warnings. Absent: no colour is recorded.
    std::optional<std::string> specular;
    /// "metal" or "dielectric": the class of a specular colour given as numbers (a named material has
    /// its own; saying another is an error). Absent with numbers: metal when --metallic >= 0.5, else
    /// dielectric. With a metallic channel and no --metallic, the class sets it (1 or 0).
    std::optional<std::string> materialClass;
    /// Mip levels to write (absent = the whole chain down to 1×1); must be >= 1.
    std::optional<int> mips;
    /// The mixture's lobes per texel (1..4; absent = as many as the preset's files store).
    std::optional<int> lobes;
    /// The mixture's lobes also fitted to the shaded ground truth (MethodParams::mixtureShadedFit).
    bool shadedFit = false;
    /// Detail normal map baked beside the method's textures (detail.h), and its fade "START:END".
    std::optional<std::string> detail;
    std::optional<std::string> detailFade;
    bool force = false;
    bool allowImplausible = false;
    bool allowEightBit = false;
    /// Also measure every method against the ground truth for this map, power (or the gloss map's
    /// per-texel powers) and border, and write the report into <out>/report/ (`--report`).
    bool report = false;
};

/// bake.json's inputs.gloss.source for a job with an in-memory authored gloss.
inline constexpr std::string_view kPaintedGlossSource = "painted layers";

/// Peak memory of a bake per texel of its input, from its textures (`shape` as bakeShape gives it,
/// each texture's storage set as the bake will keep it), the files its export writes and whether a
/// gloss map is read: the normals beside the largest of the read, the coarser levels (the pyramid's
/// moments, the mixture's lobes) and the finest level with the export's copies, with a quarter more
/// for margin. It covers the peaks core/bench/bake_memory.sh measures (tested against them).
double bakeBytesPerTexel(const BakeOutput& shape, const std::vector<ExportedFile>& files, bool glossMap,
                         bool decodedByCore = false);
/// The memory a bake of a width×height map needs at its peak: the process's own (16 MB, and 135 MB more
/// when OpenImageIO reads the map or writes a file: util/memory.h) plus bytesPerTexel
/// (bakeBytesPerTexel) per texel.
std::uint64_t estimatedBakeBytes(double bytesPerTexel, int width, int height, bool openImageIo = true);
struct BakeJob;
/// bakeBytesPerTexel of a job for a width×height input: its textures as the bake keeps them
/// (compactStorage) and its export's files. Errors: the job's shape or export plan fails.
/// `decodedByCore`: the map is an 8/16-bit PNG core decodes itself (its codes, not four floats a texel,
/// beside the normals while it is read).
Result<double> bakeJobBytesPerTexel(const BakeJob& job, int width, int height, bool decodedByCore = false);
/// An error naming the map's size, the need and what is available when `need` exceeds `available`
/// (util/memory.h's checkMemory; the bake checks against usableMemoryBytes()).
Status checkBakeMemory(std::uint64_t need, std::optional<std::uint64_t> available, int width, int height);
/// checkBakeMemory against usableMemoryBytes() now (an invalid BURNISH_MEMORY_LIMIT is the error).
Status checkBakeMemory(std::uint64_t need, int width, int height);

/// A job with every name resolved and checked: nothing of it is read or written yet.
struct BakeJob {
    BakeJobSpec spec;
    Preset preset;
    Method method = Method::VarianceToGloss;
    BakeOptions bake;
    NormalMapOptions normalMap;
    ExportOptions exportOptions;
    DetailOptions detail; // used when spec.detail is set
    /// The resolved specular colour (spec.specular), its class and name ("" for numbers).
    struct Specular {
        LinearRgb f0;
        MaterialClass materialClass = MaterialClass::Metal;
        std::string name;
    };
    std::optional<Specular> specular;
};

/// Resolves and checks every name and value of a spec. Errors name the option as the command line
/// spells it ("--method: ...", "--compression bc4 applies to --format dds only ...").
Result<BakeJob> resolveBakeJob(const BakeJobSpec& spec);

/// The shape of a job's bake for a `width` × `height` input (bakeShape, plus the detail texture's
/// when the job has one, its record put in `record`): what export's planning reads.
Result<BakeOutput> bakeJobShape(const BakeJob& job, int width, int height, BakeRecord& record);

/// Reads a manifest, {"version": 1, "jobs": [{"input": ..., "out": ..., <any option by its long
/// command-line name>}]}, into one spec per job: each starts from `defaults` (the options given on the
/// command line) and takes the job's fields; relative paths (input, out, gloss, detail, a preset
/// *.json) are taken from the manifest's folder. Nothing is resolved yet. Errors name the manifest,
/// the job (1-based) and the field: unreadable file, invalid JSON, unknown or mistyped fields, no jobs.
Result<std::vector<BakeJobSpec>> readBakeManifest(const std::string& path, const BakeJobSpec& defaults);

/// Called between the stages with the fraction done (0..1) and the stage ("reading", "baking",
/// "writing", with spec.report "evaluating", then "done"); returning false cancels the job before its
/// next stage (nothing is written when writing has not started; the export itself is all-or-nothing;
/// a job cancelled at "evaluating" keeps its exported set but writes no report). While evaluating it
/// is also called with the evaluation's own progress, its answer then ignored.
using BakeJobProgress = std::function<bool(double fraction, std::string_view stage)>;

/// The files of the ground-truth report (spec.report) in <out>/report/.
inline constexpr std::string_view kBakeReportFolder = "report";
inline constexpr std::string_view kBakeReportFiles[] = {
    "evaluate.md", "evaluate.json", "evaluate-error-per-mip.png", "evaluate-error-vs-cost.png"};

/// What a finished job produced: the bake and export results and a JSON summary (input, out,
/// preset, method, format, files, bakeJson, width, height, mipCount, mipsRequested, notes — a --mips
/// beyond a chain, a fade beyond the detail map's levels —, glossClampedLow/High, the stage times
/// readSeconds, pyramidSeconds, methodSeconds and exportSeconds, seconds (the whole job before any
/// report), warnings, detail when baked, report (the evaluate.md path) with spec.report).
struct BakeJobResult {
    NormalMap map;    // the decoded input
    BakeOutput baked; // the textures the preset's files read
    ExportResult exported;
    nlohmann::json summary;
};

/// Reads the input (and authored gloss map and detail map), bakes and exports into spec.out, then
/// with spec.report writes the ground-truth report. Errors: unreadable or implausible inputs, a gloss
/// map of the wrong size ("--gloss ..."), an in-memory authored gloss of the wrong size or with a
/// non-finite value ("authored gloss: ..."), a bad detail map ("--detail ..."), an existing output set
/// without force ("refusing to overwrite ... (use --force to replace the set)"), a failed report
/// ("--report: ..."), "cancelled" when progress returned false.
Result<BakeJobResult> runBakeJob(const BakeJob& job, const BakeJobProgress& progress = {});

/// The normal map a job reads: a file through loadNormalMap, or the built-in sample it names.
Result<NormalMap> loadBakeInput(const std::string& input, const NormalMapOptions& options);

} // namespace burnish
