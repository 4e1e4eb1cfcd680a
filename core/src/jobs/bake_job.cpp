#include <burnish/core/jobs/bake_job.h>

#include <burnish/core/jobs/bake_farm.h>

#include <burnish/core/bake/detail.h>
#include <burnish/core/eval/evaluate_report.h>
#include <burnish/core/io/image.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/sample_maps.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/hash.h>
#include <burnish/core/util/numeric.h>

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <thread>
#include <utility>
#include <vector>

namespace burnish {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

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

/// An in-memory authored gloss checked and clamped as glossFromImage treats a gloss file's values,
/// so painted values and the same values read back from a float file bake the same bytes.
Result<std::vector<float>> checkedAuthoredGloss(const std::vector<float>& values, int width, int height) {
    const size_t texels = size_t(width) * size_t(height);
    if (values.size() != texels)
        return Error{fmt::format("authored gloss: {} values for a {}x{} normal map ({} texels)",
                                 values.size(), width, height, texels)};
    std::vector<float> gloss(texels);
    for (size_t i = 0; i < texels; ++i) {
        const float v = values[i];
        if (!std::isfinite(v))
            return Error{fmt::format("authored gloss: a NaN or infinite value at index {}", i)};
        // The gloss encodings are defined on [0, 1]; a file's values are clamped the same way.
        gloss[i] = std::clamp(v, 0.0f, 1.0f);
    }
    return gloss;
}

/// FNV-1a (64-bit) of the values' bytes, as 16 hex digits: names which painted gloss made a set.
std::string glossHash(const std::vector<float>& values) {
    return hashHex(fnv1a64(values.data(), values.size() * sizeof(float)));
}

/// The file stem of the outputs: the input's file stem, or the sample's name.
std::string inputStem(const std::string& input) {
    if (isSampleBakeInput(input)) return input.substr(kSampleInputPrefix.size());
    return fs::path(input).stem().string();
}

// The name of lobe i's role ("mixture-lobe<i>"), and of its file in the mixture presets' layout.
std::string mixtureLobeName(int i) {
    return std::string(roleName(TextureRole(int(TextureRole::MixtureLobe0) + i)));
}

// Rewrites a preset's mixture lobe files for `lobes` lobes when they are laid out as the built-in
// mixture preset's: file i named mixture-lobe<i>, holding lobe i's four values alone, for i = 0..n−1
// in a row of files. The files become mixture-lobe0..lobes−1, each as lobe 0's with its index, where
// the old ones stood. Returns false, changing nothing, for any other layout.
bool relayoutLobeFiles(Preset& preset, int lobes) {
    std::vector<size_t> at;
    for (size_t f = 0; f < preset.files.size(); ++f) {
        bool any = false, all = true;
        for (const PresetChannel& c : preset.files[f].channels) {
            const auto role = roleFromName(c.role);
            const bool lobe = c.kind == PresetChannel::Kind::Baked && role && isMixtureLobeRole(*role);
            any = any || lobe;
            all = all && lobe && c.role == mixtureLobeName(int(at.size()));
        }
        if (!any) continue;
        if (at.size() == size_t(kMaxMixtureLobes) || !all ||
            preset.files[f].name != mixtureLobeName(int(at.size())) || preset.files[f].channels.size() != 4 ||
            (!at.empty() && at.back() + 1 != f))
            return false;
        at.push_back(f);
    }
    if (at.empty()) return false;
    const PresetFile first = preset.files[at.front()];
    std::vector<PresetFile> files(preset.files.begin(), preset.files.begin() + std::ptrdiff_t(at.front()));
    for (int i = 0; i < lobes; ++i) {
        PresetFile f = first;
        f.name = mixtureLobeName(i);
        if (f.description.rfind("lobe 0", 0) == 0)
            f.description = "lobe " + std::to_string(i) + f.description.substr(6);
        for (PresetChannel& c : f.channels)
            c.role = mixtureLobeName(i);
        files.push_back(std::move(f));
    }
    files.insert(files.end(), preset.files.begin() + std::ptrdiff_t(at.back() + 1), preset.files.end());
    preset.files = std::move(files);
    return true;
}

// The mixture's lobe count: --lobes, or as many lobe textures as the preset's files store. Another
// count rewrites lobe files laid out as the mixture preset's (relayoutLobeFiles); a preset with any
// other layout that stores another count is refused (its files would drop or miss a lobe).
Status resolveLobes(const BakeJobSpec& spec, BakeJob& job) {
    int stored = 0;
    if (job.bake.roles)
        for (TextureRole r : *job.bake.roles)
            if (isMixtureLobeRole(r)) stored = std::max(stored, mixtureLobeIndex(r) + 1);
    if (spec.shadedFit && job.method != Method::Mixture)
        return Error{fmt::format("--shaded-fit applies to --method mixture only (the method is {})",
                                 methodName(job.method))};
    job.bake.params.mixtureShadedFit = spec.shadedFit;
    if (!spec.lobes) {
        if (job.method == Method::Mixture && stored > 0) job.bake.params.mixtureLobes = stored;
        return {};
    }
    if (job.method != Method::Mixture)
        return Error{fmt::format("--lobes applies to --method mixture only (the method is {})",
                                 methodName(job.method))};
    if (*spec.lobes < 1 || *spec.lobes > kMaxMixtureLobes)
        return Error{fmt::format("--lobes {} must lie in 1..{}", *spec.lobes, kMaxMixtureLobes)};
    if (stored > 0 && stored != *spec.lobes && relayoutLobeFiles(job.preset, *spec.lobes)) {
        job.bake.roles = presetRoles(job.preset);
        stored = *spec.lobes;
    }
    if (stored > 0 && stored != *spec.lobes)
        return Error{fmt::format(
            "--lobes {}: preset '{}' stores {} mixture lobe{} (files mixture-lobe0..{}); "
            "write a preset with {} lobe files for this count",
            *spec.lobes, job.preset.name, stored, stored == 1 ? "" : "s", stored - 1, *spec.lobes)};
    job.bake.params.mixtureLobes = *spec.lobes;
    return {};
}

} // namespace

Result<NormalMap> loadBakeInput(const std::string& input, const NormalMapOptions& options) {
    if (!isSampleBakeInput(input)) return loadNormalMap(input, options);
    const auto kind = sampleMapFromName(input.substr(kSampleInputPrefix.size()));
    if (!kind) return Error{"input '" + input + "': " + kind.error()};
    return makeSampleNormalMap(*kind, kSampleBakeSize);
}

Result<BakeJob> resolveBakeJob(const BakeJobSpec& spec) {
    BakeJob job;
    job.spec = spec;
    if (spec.input.empty()) return Error{"no input normal map given"};
    if (spec.out.empty()) return Error{"no output folder given (--out DIR)"};
    if (spec.authoredGloss && spec.authoredGloss->empty()) return Error{"authored gloss: no values given"};
    if (job.spec.preset.empty()) {
        // A method with a built-in preset of its own (named after it: toksvig-map, lean, clean, mixture)
        // bakes into that preset when none is named; bake.json records the preset so chosen.
        std::vector<std::string> own;
        for (const Preset& p : builtinPresets())
            if (p.name == methodName(p.method)) {
                own.push_back(p.name);
                if (spec.method && *spec.method == p.name) job.spec.preset = p.name;
            }
        if (job.spec.preset.empty())
            return Error{"no preset given (--preset P; known: " + joined(builtinPresetNames()) +
                         "; --method alone picks the method's own preset for: " + joined(own) + ")"};
    }
    if (isSampleBakeInput(spec.input)) {
        const auto kind = sampleMapFromName(spec.input.substr(kSampleInputPrefix.size()));
        if (!kind) return Error{"input '" + spec.input + "': " + kind.error()};
    }

    auto preset = findPreset(job.spec.preset);
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
    if (spec.materialClass && *spec.materialClass != "metal" && *spec.materialClass != "dielectric")
        return Error{"--material-class: '" + *spec.materialClass + "' is neither metal nor dielectric"};
    if (spec.materialClass && !spec.specular)
        return Error{"--material-class applies to a --specular colour given as numbers"};
    if (spec.specular) {
        BakeJob::Specular sp;
        if (const auto typed = parseLinearRgb(*spec.specular, "--specular")) {
            sp.f0 = *typed;
            sp.materialClass =
                spec.materialClass
                    ? (*spec.materialClass == "metal" ? MaterialClass::Metal : MaterialClass::Dielectric)
                : spec.metallic.value_or(0.0) >= 0.5 ? MaterialClass::Metal
                                                     : MaterialClass::Dielectric;
        } else {
            const Material* m = builtinMaterialTable().find(*spec.specular);
            if (!m)
                return Error{"--specular '" + *spec.specular +
                             "': neither a material of `burnish materials` nor linear F0 R,G,B (" +
                             typed.error() + ")"};
            if (spec.materialClass)
                return Error{"--material-class: '" + *spec.specular + "' is a " + toString(m->materialClass) +
                             " of its own"};
            sp.f0 = m->f0();
            sp.materialClass = m->materialClass;
            sp.name = m->name;
        }
        if (!spec.metallic && job.preset.findParameter("metallic"))
            job.exportOptions.parameters["metallic"] = sp.materialClass == MaterialClass::Metal ? 1.0 : 0.0;
        job.specular = sp;
    }
    // The power range every core formula accepts (numeric.h): above kMaxPower lobes are clamped.
    if (spec.power && !(*spec.power > 0.0 && *spec.power <= kMaxPower))
        return Error{fmt::format("--power {:g} must lie in (0, {:g}]", *spec.power, kMaxPower)};

    job.bake.method = job.method;
    job.bake.encoding = job.preset.encoding;
    // Only the textures the preset's files read are baked (LEAN's preset, for one, stores no
    // normal texture: it is rebuilt from B).
    job.bake.roles = presetRoles(job.preset);
    if (spec.power) job.bake.basePower = *spec.power;
    if (spec.kernel) {
        const auto k = choice<FilterKernel>(
            "--kernel", *spec.kernel,
            {{"box", FilterKernel::Box}, {"tent", FilterKernel::Tent}, {"gaussian", FilterKernel::Gaussian}});
        if (!k) return Error{k.error()};
        job.bake.pyramid.kernel = *k;
    } else {
        job.bake.pyramid.kernel = defaultKernel(job.method);
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
    if (spec.encoding) {
        const auto e = choice<NormalValueEncoding>("--encoding", *spec.encoding,
                                                   {{"auto", NormalValueEncoding::Auto},
                                                    {"unsigned", NormalValueEncoding::Unsigned},
                                                    {"signed", NormalValueEncoding::Signed}});
        if (!e) return Error{e.error()};
        job.normalMap.encoding = *e;
    }
    if (spec.mips) {
        if (*spec.mips < 1) return Error{fmt::format("--mips {} must be at least 1", *spec.mips)};
        job.bake.mipCount = *spec.mips;
    }
    if (const Status s = resolveLobes(spec, job); !s) return Error{s.error()};
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
    job.exportOptions.stem = inputStem(spec.input);
    if (job.exportOptions.stem.empty()) return Error{"input '" + spec.input + "' has no file name"};
    return job;
}

namespace {

/// The ground-truth report for the same map, power and border: how far each method is from the
/// truth per mip, next to its cost (as `burnish evaluate`), written into <out>/report. Returns the
/// path of its evaluate.md.
Result<std::string> writeBakeReport(const BakeJob& job, const NormalMap& map, const BakeOptions& options,
                                    const std::function<void(double)>& progress) {
    EvaluationReportOptions evaluation;
    evaluation.inputName = fs::path(job.spec.input).filename().string();
    evaluation.evaluate.basePowers = {options.basePower};
    evaluation.evaluate.border = options.pyramid.border;
    evaluation.evaluate.params = options.params;
    evaluation.evaluate.mixtureLobes = {options.params.mixtureLobes};
    // The truth of the engine the preset's encoding is for: GGX for the roughness presets.
    evaluation.evaluate.brdf = glossBrdf(options.encoding);
    evaluation.evaluate.methods = methodsUnder(evaluation.evaluate.brdf);
    if (options.authoredGloss) {
        // The ground truth with each texel's authored power, decoded as the bake decodes it.
        std::vector<double> powers(options.authoredGloss->size());
        for (size_t i = 0; i < powers.size(); ++i)
            powers[i] = options.encoding.power((*options.authoredGloss)[i]);
        evaluation.evaluate.texelPowers = std::move(powers);
    }
    auto built = buildEvaluationReport(map, evaluation, progress);
    if (!built) return Error{"--report: " + built.error()};
    const fs::path dir = fs::path(job.spec.out) / kBakeReportFolder;
    if (auto st = writeEvaluationReport(*built, dir); !st) return Error{"--report: " + st.error()};
    return (dir / kBakeReportFiles[0]).string();
}

} // namespace

Result<BakeOutput> bakeJobShape(const BakeJob& job, int width, int height, BakeRecord& record) {
    auto shape = bakeShape(job.bake, width, height);
    if (!shape) return Error{shape.error()};
    if (job.spec.detail) {
        const auto detailImage = readImageHeader(*job.spec.detail);
        if (!detailImage) return Error{"--detail: " + detailImage.error()};
        auto detail = detailShape(detailImage->width, detailImage->height, job.detail);
        if (!detail) return Error{"--detail: " + detail.error()};
        shape.value().textures.push_back(std::move(detail.value()));
        // The constant variance is not known before the bake; the plan names files only.
        record.detail = DetailRecord{*job.spec.detail, 0.0, job.detail.fadeStartMip, job.detail.fadeEndMip};
    }
    return shape;
}

double bakeBytesPerTexel(const BakeOutput& shape, const std::vector<ExportedFile>& files, bool glossMap,
                         bool decodedByCore) {
    constexpr double kMargin = 1.25;
    constexpr double kNormals = 12.0; // the decoded normals (three floats), held to the end
    // The file's decoded samples beside them: four floats at most through OpenImageIO, 8 bytes at most
    // of codes through core's PNG decoder.
    const double kRead = decodedByCore ? 8.0 : 16.0;
    constexpr double kGloss = 20.0; // a gloss map: its decoded samples, then a float and a variance per texel
    constexpr double kCoarser = 1.0 / 3.0; // levels 1, 2, … hold a third of level 0's texels
    constexpr double kChain = 1.0 + kCoarser;
    double textures = 0.0; // the finest level's bytes of every texture
    for (const BakedTexture& t : shape.textures) {
        const double bytes = t.storage == TexelStorage::Float    ? 4.0
                             : t.storage == TexelStorage::Unorm8 ? 1.0
                                                                 : 2.0;
        textures += bytes * t.channels;
    }
    // What the export holds beside the textures: the PNG, TGA, EXR or TIFF files being written at once
    // (in parallel, as many as the machine has cores), each the finest level converted to the file's
    // type; then each DDS file alone (nvtt runs one at a time), its 8-bit chain and the file's bytes.
    std::vector<double> parallel;
    double ddsCopies = 0.0;
    for (const ExportedFile& f : files) {
        switch (f.format) {
        case ExportFormat::Png8:
        case ExportFormat::Tga:
            parallel.push_back(1.0 * f.storedChannels);
            break;
        case ExportFormat::Png16:
        case ExportFormat::Tiff16:
        case ExportFormat::ExrHalf:
            parallel.push_back(2.0 * f.storedChannels);
            break;
        case ExportFormat::ExrFloat:
        case ExportFormat::TiffFloat:
            parallel.push_back(4.0 * f.storedChannels);
            break;
        case ExportFormat::Dds:
            ddsCopies =
                std::max(ddsCopies, (4.0 + (f.compression == DdsCompression::Rgba16f ? 8.0 : 4.0)) * kChain);
            break;
        }
    }
    std::sort(parallel.begin(), parallel.end(), std::greater<>());
    const size_t atOnce = std::max<size_t>(1, std::thread::hardware_concurrency());
    double parallelCopies = 0.0;
    for (size_t i = 0; i < std::min(atOnce, parallel.size()); ++i)
        parallelCopies += parallel[i];
    const double exportCopies = std::max(parallelCopies, ddsCopies);
    // A mixture of K >= 2 lobes keeps K lobes and a count per texel of the levels above the finest,
    // and a slot per finest texel; baking its own textures alone, it reads no moments.
    const auto lobes = std::count_if(shape.textures.begin(), shape.textures.end(),
                                     [](const BakedTexture& t) { return isMixtureLobeRole(t.role); });
    const bool mixtureOnly =
        lobes >= 2 && std::all_of(shape.textures.begin(), shape.textures.end(),
                                  [](const BakedTexture& t) { return isMixtureRole(t.role); });
    const double moments = mixtureOnly ? 0.0 : 4.0 * momentStride(momentsNeeded(shape.method)) * kCoarser;
    const double mixture =
        lobes >= 2 ? (double(sizeof(LobeMoments)) * double(lobes) + 1.0) * kCoarser + 1.0 : 0.0;
    // The coarser levels are baked first, beside the pyramid's moments (and the mixture's lobes);
    // then level 0, once those are freed; then the export.
    // The fitted lobe keeps a power per texel of the levels above the finest (and, with a gloss map, a
    // power per finest texel: its truth's).
    const double fitted = shape.method == Method::Fitted ? 4.0 * kCoarser + (glossMap ? 8.0 : 0.0) : 0.0;
    const double coarser = moments + mixture + fitted + textures * kCoarser;
    const double finest = textures * kChain + exportCopies;
    return kMargin * (kNormals + (glossMap ? kGloss : 0.0) + std::max({kRead, coarser, finest}));
}

Result<double> bakeJobBytesPerTexel(const BakeJob& job, int width, int height, bool decodedByCore) {
    BakeRecord planned;
    auto shape = bakeJobShape(job, width, height, planned);
    if (!shape) return Error{shape.error()};
    const auto storage = compactStorage(*shape, job.preset, job.exportOptions, planned);
    for (BakedTexture& t : shape.value().textures)
        if (const auto it = storage.find(t.role); it != storage.end()) t.storage = it->second;
    const auto plan = planExport(*shape, job.preset, job.exportOptions, planned);
    if (!plan) return Error{plan.error()};
    return bakeBytesPerTexel(*shape, plan->files, job.spec.gloss || job.spec.authoredGloss, decodedByCore);
}

std::uint64_t estimatedBakeBytes(double bytesPerTexel, int width, int height, bool openImageIo) {
    const double process = double(openImageIo ? kProcessBytes : kCoreProcessBytes);
    return std::uint64_t(process + bytesPerTexel * double(width) * double(height));
}

Status checkBakeMemory(std::uint64_t need, int width, int height) {
    auto usable = usableMemoryBytes();
    if (!usable) return Error{usable.error()};
    return checkBakeMemory(need, *usable, width, height);
}

Status checkBakeMemory(std::uint64_t need, std::optional<std::uint64_t> available, int width, int height) {
    return checkMemory(need, available, fmt::format("baking a {}x{} map", width, height),
                       "close other programs, or bake a smaller map");
}

Result<BakeJobResult> runBakeJob(const BakeJob& job, const BakeJobProgress& progress) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    // reading, baking, writing (and evaluating): each stage one equal share of the fraction done.
    const int steps = job.spec.report ? 4 : 3;
    auto step = [&](double done, std::string_view stage) {
        return !progress || progress(done / steps, stage);
    };
    const Error cancelled{"cancelled"};

    if (!step(0, "reading")) return cancelled;
    // The memory the bake will need, checked against what the system has before anything is
    // allocated: from the file's header (a small file can claim a huge image).
    {
        const auto need = estimatedJobBytes(job);
        if (!need) return Error{need.error()};
        if (!isSampleBakeInput(job.spec.input)) {
            const Status memory = checkBakeMemory(need->bytes, need->width, need->height);
            if (!memory) return Error{"'" + job.spec.input + "': " + memory.error()};
        }
        // A gloss map of another size is refused from its header, before either image is decoded.
        if (job.spec.gloss && !job.spec.authoredGloss) {
            const auto header = readImageHeader(*job.spec.gloss);
            if (!header) return Error{"--gloss: " + header.error()};
            if (header->width != need->width || header->height != need->height)
                return Error{fmt::format("--gloss '{}': gloss map is {}x{} but the normal map is {}x{}",
                                         *job.spec.gloss, header->width, header->height, need->width,
                                         need->height)};
        }
    }
    // The inputs' hashes before they are read: a file replaced meanwhile leaves a set that a later
    // check finds stale, never one that looks current.
    auto inputHashes = bakeInputHashes(job);
    if (!inputHashes) return Error{inputHashes.error()};
    auto map = loadBakeInput(job.spec.input, job.normalMap);
    if (!map) return Error{map.error()};
    const double readSeconds = std::chrono::duration<double>(Clock::now() - start).count();

    BakeOptions options = job.bake;
    // A bake made to be exported keeps the textures its files store as 8- or 16-bit codes as
    // those codes (a quarter or half of the floats' memory; the same bytes written).
    {
        BakeRecord planned;
        if (auto shape = bakeJobShape(job, map->width, map->height, planned))
            options.storage = compactStorage(*shape, job.preset, job.exportOptions, planned);
    }
    if (job.spec.authoredGloss) {
        // The in-memory gloss overrides the file: spec.gloss is only recorded, not read.
        auto gloss = checkedAuthoredGloss(*job.spec.authoredGloss, map->width, map->height);
        if (!gloss) return Error{gloss.error()};
        options.authoredGloss = std::move(gloss.value());
    } else if (job.spec.gloss) {
        const auto image = readImage(*job.spec.gloss);
        if (!image) return Error{"--gloss: " + image.error()};
        auto gloss = glossFromImage(*image, map->width, map->height);
        if (!gloss) return Error{"--gloss '" + *job.spec.gloss + "': " + gloss.error()};
        options.authoredGloss = std::move(gloss.value());
    }

    if (!step(1, "baking")) return cancelled;
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

    if (!step(2, "writing")) return cancelled;
    std::error_code ec;
    fs::create_directories(job.spec.out, ec);
    if (ec) return Error{"cannot create output folder '" + job.spec.out + "': " + ec.message()};

    BakeRecord record;
    record.inputs = {{"normalMap", job.spec.input},
                     {"glossMap", job.spec.gloss ? Json(*job.spec.gloss) : Json(nullptr)},
                     {"detailMap", job.spec.detail ? Json(*job.spec.detail) : Json(nullptr)},
                     {"width", map->width},
                     {"height", map->height},
                     {"fnv1a64", *inputHashes},
                     {"source",
                      {{"format", map->source.formatName},
                       {"channelType", map->source.channelType},
                       {"bitsPerChannel", map->source.bitsPerChannel}}}};
    if (job.spec.authoredGloss) {
        // Not a file: say where the gloss came from and which values it held, instead of a path.
        record.inputs.erase("glossMap");
        record.inputs["gloss"] = {{"source", std::string(kPaintedGlossSource)},
                                  {"paintedOver", job.spec.gloss ? Json(*job.spec.gloss) : Json(nullptr)},
                                  {"fnv1a64", glossHash(*options.authoredGloss)}};
    }
    const ExportFormat format = job.exportOptions.format.value_or(job.preset.format);
    record.options = {
        {"preset", job.spec.preset},
        {"method", std::string(methodName(job.method))},
        {"power", options.authoredGloss ? Json(nullptr) : Json(options.basePower)},
        {"format", std::string(exportFormatName(format))},
        {"compression", job.exportOptions.compression
                            ? Json(std::string(ddsCompressionName(*job.exportOptions.compression)))
                            : Json(nullptr)},
        {"kernel", std::string(kernelName(job.bake.pyramid.kernel))},
        {"border", job.spec.border.value_or("wrap")},
        {"green", job.spec.green.value_or("opengl")},
        {"layout", job.spec.layout.value_or("auto")},
        {"encoding", job.spec.encoding.value_or("auto")},
        {"mips", job.spec.mips ? Json(*job.spec.mips) : Json(nullptr)},
        {"allow8bit", job.spec.allowEightBit},
        {"allowImplausible", job.spec.allowImplausible},
        {"fnv1a64", bakeOptionsHash(job)}};
    if (detailRecord) record.options["detailFade"] = {detailRecord->fadeStartMip, detailRecord->fadeEndMip};
    if (job.specular) {
        const SpecularTerms terms =
            specularTerms(job.preset.specular, job.specular->materialClass, job.specular->f0);
        record.material = {{"class", toString(job.specular->materialClass)},
                           {"f0Linear", {job.specular->f0.r, job.specular->f0.g, job.specular->f0.b}},
                           {"name", job.specular->name.empty() ? Json(nullptr) : Json(job.specular->name)},
                           {"engine",
                            {{"convention", std::string(specularConventionName(job.preset.specular))},
                             {"values", terms.values},
                             {"warnings", terms.warnings}}}};
    }
    if (job.method == Method::Mixture) {
        record.options["lobes"] = job.bake.params.mixtureLobes;
        record.options["shadedFit"] = job.bake.params.mixtureShadedFit;
    }
    record.diagnostics = map->diagnostics;
    record.detail = detailRecord;

    const auto exportStart = Clock::now();
    auto exported = exportBake(*baked, job.preset, job.exportOptions, job.spec.out, record);
    const double exportSeconds = std::chrono::duration<double>(Clock::now() - exportStart).count();
    if (!exported) {
        std::string message = exported.error();
        if (message.rfind("refusing to overwrite", 0) == 0) message += " (use --force to replace the set)";
        return Error{message};
    }
    for (const auto& n : exported->notes)
        notes.push_back(n);
    // The time of the bake and its export; the report's evaluation (its own timed bakes) is not in it.
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();

    Json files = Json::array();
    for (const auto& f : exported->files)
        for (const auto& p : f.paths)
            files.push_back((fs::path(job.spec.out) / p).string());
    BakeJobResult result;
    result.summary = {{"input", job.spec.input},
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
                      {"readSeconds", readSeconds},
                      {"pyramidSeconds", baked->stats.pyramidSeconds},
                      {"methodSeconds", baked->stats.methodSeconds},
                      {"exportSeconds", exportSeconds},
                      {"seconds", seconds},
                      {"warnings", map->diagnostics.warnings}};
    if (!record.material.is_null()) {
        result.summary["material"] = record.material;
        for (const Json& w : record.material["engine"]["warnings"])
            result.summary["warnings"].push_back(w);
    }
    if (detailRecord)
        result.summary["detail"] = {{"file", exported->manifest["detail"]["file"]},
                                    {"constantVariance", detailRecord->constantVariance},
                                    {"fade", {detailRecord->fadeStartMip, detailRecord->fadeEndMip}}};

    if (job.spec.report) {
        if (!step(3, "evaluating")) return cancelled;
        // The evaluation cannot stop midway: its progress only moves the fraction within the step.
        auto report = writeBakeReport(job, *map, options, [&](double f) { step(3 + f, "evaluating"); });
        if (!report) return Error{report.error()};
        result.summary["report"] = *report;
    }
    step(steps, "done");

    result.map = std::move(map.value());
    result.baked = std::move(baked.value());
    result.exported = std::move(exported.value());
    return result;
}

// Manifest: {"version": 1, "jobs": [{"input": ..., "out": ..., <any option by its long name>}]}.
// Relative paths are relative to the manifest's folder; options on the command line are defaults.
Result<std::vector<BakeJobSpec>> readBakeManifest(const std::string& path, const BakeJobSpec& defaults) {
    const auto text = readFile(path);
    if (!text) return Error{"--manifest: " + text.error()};
    // JSON text holds no raw NUL: one means a file that is not a manifest (the parser stopped at it
    // and ignored what followed).
    if (const size_t nul = text->find('\0'); nul != std::string::npos)
        return Error{"manifest '" + path + "': a NUL byte at byte " + std::to_string(nul) +
                     " (not a JSON text)"};
    Json root;
    try {
        root = Json::parse(*text);
    } catch (const Json::exception& e) { // parse errors, and numbers out of range (out_of_range.406)
        return Error{"manifest '" + path + "': invalid JSON: " + e.what()};
    }
    const std::string where = "manifest '" + path + "'";
    if (!root.is_object() || !root.contains("jobs") || !root["jobs"].is_array())
        return Error{where + ": expected an object with a \"jobs\" array"};
    for (const auto& [key, value] : root.items())
        if (key != "jobs" && key != "version")
            return Error{where + ": unknown field '" + key + "' (known: version, jobs)"};
    if (!root.contains("version"))
        return Error{where + ": no \"version\" (write \"version\": 1, the manifest format it follows)"};
    if (!(root["version"].is_number_integer() && root["version"].get<int>() == 1))
        return Error{where + ": version must be 1"};
    const fs::path base = fs::path(path).parent_path();
    auto rebase = [&](const std::string& p) {
        return fs::path(p).is_absolute() ? p : (base / p).lexically_normal().string();
    };

    std::vector<BakeJobSpec> jobs;
    const auto& list = root["jobs"];
    if (list.empty()) return Error{where + ": \"jobs\" is empty"};
    for (size_t i = 0; i < list.size(); ++i) {
        const Json& j = list[i];
        const std::string at = where + " job " + std::to_string(i + 1);
        if (!j.is_object()) return Error{at + ": must be an object"};
        BakeJobSpec spec = defaults;
        for (const auto& item : j.items()) {
            // Plain references: clang 14's lambdas cannot capture structured bindings.
            const std::string& key = item.key();
            const Json& value = item.value();
            // JSON strings may hold "\u0000", which no path or name can: refused, not cut short.
            auto stringValue = [&]() -> Result<std::string> {
                if (!value.is_string()) return Error{at + ": '" + key + "' must be a string"};
                std::string v = value.get<std::string>();
                if (v.find('\0') != std::string::npos)
                    return Error{at + ": '" + key + "' holds a NUL character"};
                return v;
            };
            auto str = [&](std::string& dest) -> Status {
                auto v = stringValue();
                if (!v) return Error{v.error()};
                dest = std::move(v).value();
                return {};
            };
            auto optStr = [&](std::optional<std::string>& dest) -> Status {
                auto v = stringValue();
                if (!v) return Error{v.error()};
                dest = std::move(v).value();
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
            else if (key == "encoding")
                s = optStr(spec.encoding);
            else if (key == "metallic")
                s = num(spec.metallic);
            else if (key == "specular")
                s = optStr(spec.specular);
            else if (key == "material-class")
                s = optStr(spec.materialClass);
            else if (key == "mips") {
                if (!value.is_number_integer())
                    s = Error{at + ": 'mips' must be an integer"};
                else
                    spec.mips = value.get<int>();
            } else if (key == "lobes") {
                if (!value.is_number_integer())
                    s = Error{at + ": 'lobes' must be an integer"};
                else
                    spec.lobes = value.get<int>();
            } else if (key == "shaded-fit")
                s = flag(spec.shadedFit);
            else if (key == "detail")
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
                          "green, layout, encoding, metallic, specular, material-class, mips, lobes, "
                          "shaded-fit, detail, "
                          "detail-fade, force, "
                          "allow-implausible, "
                          "allow-8bit)"};
            if (!s) return Error{s.error()};
        }
        if (j.contains("input") && !isSampleBakeInput(spec.input)) spec.input = rebase(spec.input);
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

} // namespace burnish
