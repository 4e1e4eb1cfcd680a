// `burnish render`: the scene renderer headless — an image (PNG or EXR), the supersampled ground
// truth, a debug view, the program's features (--explain), the shimmer of a slow orbit
// (--sequence), a frame's error against the ground truth (--compare) and frame-time figures (--bench).
#include "command.h"
#include "common.h"

#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/env/sampling.h>
#include <burnish/core/io/image.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/sample_maps.h>
#include <burnish/core/shading/materials.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/memory.h>
#include <burnish/render/context.h>
#include <burnish/render/gpu_resources.h>
#include <burnish/render/renderer.h>
#include <burnish/render/shimmer.h>

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace burnish::cli {

namespace {

namespace fs = std::filesystem;
using namespace burnish::render;

// Default frame sizes: a still image, a shimmer sequence (small: every frame is rendered once
// with the method and referenceSamples times for the ground truth), and the benchmark (720p).
constexpr int kImageSize = 512;
constexpr int kSequenceSize = 128;
constexpr int kBenchWidth = 1280;
constexpr int kBenchHeight = 720;
// Largest side accepted on the command line; the renderer also checks GL_MAX_RENDERBUFFER_SIZE.
constexpr int kMaxSide = 16384;
// Reference samples of a --sequence when --reference is not given (the shimmer test's count).
constexpr int kSequenceReferenceSamples = 16;
// Frames drawn and thrown away before timing: the first draws compile and upload lazily.
constexpr int kBenchWarmupFrames = 2;

struct RenderCliOptions {
    std::string input;
    int lobes = kDefaultMixtureLobes;
    bool shadedFit = false;
    std::string mixtureFiltering = "moments";
    int mixtureSamples = 16;
    std::string out;
    std::string sample = "hammered";
    int sampleSize = 256;
    std::string mesh = "sphere";
    std::string method;
    std::optional<double> power;
    std::string gloss;
    std::string preset;
    std::string glossEncoding;
    std::string material;
    std::vector<double> specular;
    bool metal = false;
    std::vector<double> albedo;
    float uvScale = 1.0f;
    std::optional<float> distance;
    std::optional<float> yaw;
    std::optional<float> pitch;
    std::vector<float> lightDir;
    float exposure = 0.0f;
    std::string size;
    int reference = 0;
    std::string debug = "none";
    std::string ndf = "blinn-phong";
    std::string fresnel = "schlick";
    std::string visibility = "none";
    std::string specularAa = "none";
    bool diffuseAa = false;
    bool explain = false;
    bool force = false;
    bool ubershader = false;
    int sequence = 0;
    int compare = 0;
    std::string kernel; // empty: the method's default
    float orbitDegrees = 0.5f;
    std::string framesDir;
    std::string shimmerSpace = "hdr";
    bool json = false;
    bool bench = false;
    int benchFrames = 9;
    std::string gl = "auto";
    NormalMapCliOptions normalMap;
    // Environment lighting: off, the procedural studio, or an equirectangular HDR file.
    std::string env = "off";
    float envRotation = 0.0f;
    float envIntensity = 1.0f;
    bool envBackground = false;
    int envFis = 0; // 0: the prefiltered map; N: filtered importance sampling with N taps
};

std::string lower(std::string text) {
    for (char& c : text)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    return text;
}

// An enum value by the name its *Name() function gives; the error lists the names.
template <class E, class NameFn>
Result<E> enumFromName(const std::string& what, const std::string& name, std::initializer_list<E> values,
                       NameFn nameOf) {
    std::string known;
    for (E v : values) {
        if (lower(name) == nameOf(v)) return v;
        known += (known.empty() ? "" : ", ") + std::string(nameOf(v));
    }
    return Error{what + ": unknown name '" + name + "' (known: " + known + ")"};
}

Result<std::pair<int, int>> parseSize(const std::string& text) {
    const auto x = text.find_first_of("xX");
    int w = 0, h = 0;
    const char* begin = text.data();
    const char* end = text.data() + text.size();
    if (x == std::string::npos || std::from_chars(begin, begin + x, w).ptr != begin + x ||
        std::from_chars(begin + x + 1, end, h).ptr != end)
        return Error{"--size: '" + text + "' is not WIDTHxHEIGHT (e.g. 512x512)"};
    if (w < 1 || h < 1 || w > kMaxSide || h > kMaxSide)
        return Error{"--size: " + text + " is outside 1x1.." + std::to_string(kMaxSide) + "x" +
                     std::to_string(kMaxSide)};
    return std::make_pair(w, h);
}

glm::vec3 toVec3(const std::vector<double>& v) {
    return v.size() == 1 ? glm::vec3(float(v[0])) : glm::vec3(float(v[0]), float(v[1]), float(v[2]));
}

// The scene the options describe (everything but the frame size).
// The memory the render will need (render::estimatedRenderBytes) against what may be used, from the
// map's header and the resolved method before anything is decoded.
Status checkRenderMemory(const RenderCliOptions& o, Method method, int width, int height) {
    RenderMemoryInput need;
    need.frameWidth = width;
    need.frameHeight = height;
    need.method = method;
    need.everyMethod = o.bench;
    need.reference = o.reference > 0 || o.sequence > 0 || o.compare > 0;
    need.mapTexels = std::uint64_t(o.sampleSize) * std::uint64_t(o.sampleSize);
    std::string what =
        fmt::format("rendering the {}x{} sample at {}x{}", o.sampleSize, o.sampleSize, width, height);
    if (!o.input.empty()) {
        const auto header = readImageHeader(o.input);
        if (!header) return Error{header.error()};
        need.mapTexels = std::uint64_t(header->width) * std::uint64_t(header->height);
        what = fmt::format("rendering a {}x{} map at {}x{}", header->width, header->height, width, height);
    }
    return checkMemory(estimatedRenderBytes(need), what,
                       "close other programs, or render a smaller map or frame");
}

Result<Scene> buildScene(const RenderCliOptions& o, int width, int height) {
    Scene scene;
    MaterialSettings& m = scene.material;

    // Mesh: a primitive by name or an OBJ file.
    if (o.mesh.size() > 4 && lower(o.mesh.substr(o.mesh.size() - 4)) == ".obj") {
        scene.mesh = MeshKind::Obj;
        scene.objPath = o.mesh;
    } else {
        auto mesh = enumFromName("--mesh", o.mesh, {MeshKind::Sphere, MeshKind::Plane, MeshKind::Torus},
                                 meshKindName);
        if (!mesh) return Error{mesh.error() + " or a .obj file"};
        scene.mesh = *mesh;
    }

    // Method and gloss encoding: the preset's, unless given.
    if (!o.preset.empty()) {
        auto preset = findPreset(o.preset);
        if (!preset) return Error{"--preset: " + preset.error()};
        m.method = preset->method;
        m.glossEncoding = preset->encoding;
    }
    if (!o.glossEncoding.empty()) {
        auto encoding = GlossEncoding::fromName(o.glossEncoding);
        if (!encoding) return Error{"--gloss-encoding: " + encoding.error()};
        m.glossEncoding = *encoding;
    }
    if (!o.method.empty()) {
        auto method = methodFromName(o.method);
        if (!method) return Error{"--method: " + method.error()};
        m.method = *method;
    }
    m.methodParams.mixtureLobes = o.lobes;
    m.methodParams.mixtureShadedFit = o.shadedFit;
    m.mixtureFiltering = *parseMixtureFiltering(o.mixtureFiltering); // checked by CLI11
    m.mixtureSamples = o.mixtureSamples;
    if (!o.kernel.empty())
        m.kernel = o.kernel == "box"        ? FilterKernel::Box
                   : o.kernel == "gaussian" ? FilterKernel::Gaussian
                                            : FilterKernel::Tent;

    // Base power: --power, or --gloss as a value in the encoding or as an authored gloss map (read
    // after the normal map, whose size it must have).
    std::string glossMapPath;
    if (o.power && !o.gloss.empty()) return Error{"give --power or --gloss, not both"};
    if (o.power) m.basePower = *o.power;
    if (!o.gloss.empty()) {
        double value = 0.0;
        const char* end = o.gloss.data() + o.gloss.size();
        if (std::from_chars(o.gloss.data(), end, value).ptr == end) {
            if (!(value >= 0.0 && value <= 1.0)) return Error{"--gloss: " + o.gloss + " is outside [0, 1]"};
            m.setGloss(value);
        } else {
            glossMapPath = o.gloss;
        }
    }

    // Specular colour: a calibrated material or an explicit linear F0.
    if (!o.material.empty() && !o.specular.empty()) return Error{"give --material or --specular, not both"};
    if (!o.material.empty()) {
        auto f0 = calibratedSpecularColor(o.material);
        if (!f0) return Error{"--material: " + f0.error() + " (see 'burnish materials')"};
        m.specularColor = *f0;
        const Material* entry = builtinMaterialTable().find(o.material);
        m.metal = entry && entry->materialClass == MaterialClass::Metal;
    }
    if (!o.specular.empty()) m.specularColor = toVec3(o.specular);
    if (o.metal) m.metal = true;
    if (!o.albedo.empty()) m.albedo = toVec3(o.albedo);
    m.uvScale = o.uvScale;

    auto ndf =
        enumFromName("--ndf", o.ndf, {NdfTerm::BlinnPhong, NdfTerm::Beckmann, NdfTerm::Ggx}, ndfTermName);
    if (!ndf) return Error{ndf.error()};
    m.ndf = *ndf;
    auto fresnel = enumFromName(
        "--fresnel", o.fresnel,
        {FresnelTerm::None, FresnelTerm::Schlick, FresnelTerm::SchlickSg, FresnelTerm::SchlickSgQuadratic},
        fresnelTermName);
    if (!fresnel) return Error{fresnel.error()};
    m.fresnel = *fresnel;
    auto visibility = enumFromName("--visibility", o.visibility,
                                   {VisibilityTerm::None, VisibilityTerm::Kelemen,
                                    VisibilityTerm::SchlickSmith, VisibilityTerm::CookTorrance,
                                    VisibilityTerm::SmithBeckmann, VisibilityTerm::SmithGgxCorrelated},
                                   visibilityTermName);
    if (!visibility) return Error{visibility.error()};
    m.visibility = *visibility;
    auto specularAa = enumFromName(
        "--specular-aa", o.specularAa,
        {SpecularAa::None, SpecularAa::KaplanyanValient, SpecularAa::TokuyoshiKaplanyan}, specularAaName);
    if (!specularAa) return Error{specularAa.error()};
    m.specularAa = *specularAa;
    m.diffuseAa = o.diffuseAa;

    auto debug = enumFromName("--debug", o.debug,
                              {DebugView::None, DebugView::LightingOnly, DebugView::DiffuseOnly,
                               DebugView::SpecularOnly, DebugView::Power, DebugView::Normals,
                               DebugView::MipLevel, DebugView::Variance, DebugView::ErrorHeatmap},
                              debugViewName);
    if (!debug) return Error{debug.error()};
    scene.debugView = *debug;

    if (o.distance) scene.camera.distance = *o.distance;
    if (o.yaw) scene.camera.yawDegrees = *o.yaw;
    if (o.pitch) scene.camera.pitchDegrees = *o.pitch;
    if (!o.lightDir.empty()) {
        const glm::vec3 d(o.lightDir[0], o.lightDir[1], o.lightDir[2]);
        if (!(glm::length(d) > 0.0f)) return Error{"--light-dir: the direction has no length"};
        scene.light.direction = d;
    }
    scene.exposure = o.exposure;

    // One memory ceiling for every command: checked before the map is decoded.
    if (const Status memory = checkRenderMemory(o, m.method, width, height); !memory)
        return Error{memory.error()};
    // Normal map: a file, or the built-in sample (last, after the cheap checks above).
    if (!o.input.empty()) {
        auto map = loadNormalMap(o.input, toNormalMapOptions(o.normalMap));
        if (!map) return Error{map.error()};
        for (const auto& w : map->diagnostics.warnings)
            std::fprintf(stderr, "burnish: warning: %s\n", printable(w).c_str());
        m.normalMap = std::make_shared<const NormalMap>(std::move(map).value());
    } else {
        auto kind = sampleMapFromName(o.sample);
        if (!kind) return Error{"--sample: " + kind.error()};
        m.normalMap = std::make_shared<const NormalMap>(makeSampleNormalMap(*kind, o.sampleSize));
    }

    if (!glossMapPath.empty()) {
        auto image = readImage(glossMapPath);
        if (!image) return Error{"--gloss: " + image.error()};
        auto gloss = glossFromImage(*image, m.normalMap->width, m.normalMap->height);
        if (!gloss) return Error{"--gloss '" + glossMapPath + "': " + gloss.error()};
        m.glossMap = std::make_shared<const std::vector<float>>(std::move(gloss).value());
    }

    // Environment: --env off|studio|FILE, prefiltered unless --env-fis N asks for N-tap FIS.
    if (lower(o.env) != "off") {
        scene.environment =
            o.envFis > 0 ? EnvironmentKind::FilteredImportanceSampling : EnvironmentKind::Prefiltered;
        EnvironmentMap& env = scene.environmentMap;
        if (lower(o.env) == "studio") {
            env.source = EnvironmentSourceKind::ProceduralStudio;
        } else {
            if (!fs::is_regular_file(o.env))
                return Error{"--env: '" + o.env + "' is not 'off', 'studio' or a readable HDR file"};
            env.source = EnvironmentSourceKind::File;
            env.path = o.env;
        }
        env.rotationDegrees = o.envRotation;
        env.intensity = o.envIntensity;
        if (o.envFis > 0) env.fisSamples = o.envFis;
        scene.environmentBackground = o.envBackground;
        // The background from its own faces: sharp where the lighting's cube is small.
        env.backgroundFaceSize = kBackdropFaceSize;
    } else if (o.envFis > 0) {
        return Error{"--env-fis needs an environment (--env studio or --env FILE)"};
    } else if (o.envBackground) {
        return Error{"--env-background needs an environment (--env studio or --env FILE)"};
    }
    return scene;
}

// Writes RGBA floats as a PNG (8-bit RGB, values clamped to [0, 1]) or an EXR (float RGB),
// through a temporary file renamed over the target.
Status writeImage(const fs::path& path, int width, int height, const std::vector<float>& rgba, float scale) {
    const std::string ext = lower(path.extension().string());
    const bool exr = ext == ".exr";
    if (!exr && ext != ".png") return Error{"--out: '" + path.string() + "' must end in .png or .exr"};
    std::vector<float> rgb(size_t(width) * size_t(height) * 3);
    for (size_t p = 0; p < rgb.size() / 3; ++p)
        for (size_t c = 0; c < 3; ++c)
            rgb[3 * p + c] = exr ? rgba[4 * p + c] * scale : std::clamp(rgba[4 * p + c], 0.0f, 1.0f);
    return writeImageAtomic(path, width, height, 3, rgb,
                            {exr ? StoredType::Float : StoredType::UInt8, {}, {}});
}

Result<std::unique_ptr<GlContext>> makeContext(const std::string& gl) {
    HeadlessContextOptions options;
    options.tryEgl = gl != "osmesa";
    options.tryOsMesa = gl != "egl";
    return createHeadlessContext(options);
}

double median(std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double peakRssMiB() {
    rusage usage{};
    ::getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0; // ru_maxrss is in KiB on Linux
}

// Median frame time of `frames` draws of the renderer's scene into `target` (interactive: the frame
// drawn while the camera moves, RenderTarget::interactive).
Result<double> medianFrameMs(Renderer& renderer, const Framebuffer& target, int frames,
                             bool interactive = false) {
    std::vector<double> ms;
    for (int i = 0; i < kBenchWarmupFrames + frames; ++i) {
        RenderTarget t{target.id(), target.width(), target.height()};
        t.interactive = interactive;
        if (auto s = renderer.render(t); !s) return Error{s.error()};
        if (i >= kBenchWarmupFrames) ms.push_back(renderer.lastFrameMs());
    }
    return median(ms);
}

int runBench(Renderer& renderer, const GlContext& context, Scene scene, int width, int height,
             const RenderCliOptions& o) {
    auto target = Framebuffer::create(width, height, ColorFormat::Rgba8, false);
    if (!target) return fail(target.error());
    ProgressBar bar("benchmark");
    const auto& methods = allMethods();
    const double steps = double(methods.size() + 2);
    nlohmann::json perMethod = nlohmann::json::array();
    std::string table;
    // The sphere's tessellation at full size and at the interactive frame's half size (0: not a sphere).
    int sphereSegments = 0, interactiveSphereSegments = 0;
    scene.debugView = DebugView::None;
    for (size_t i = 0; i < methods.size(); ++i) {
        bar.update(double(i) / steps, std::string(methodName(methods[i])));
        scene.material.method = methods[i];
        if (auto s = renderer.setScene(scene); !s) return fail(s.error());
        auto ms = medianFrameMs(renderer, *target, o.benchFrames);
        if (!ms) return fail(ms.error());
        sphereSegments = renderer.lastSphereSegments();
        auto moving = medianFrameMs(renderer, *target, o.benchFrames, true);
        if (!moving) return fail(moving.error());
        interactiveSphereSegments = renderer.lastSphereSegments();
        perMethod.push_back(
            {{"method", methodName(methods[i])}, {"median_ms", *ms}, {"interactive_median_ms", *moving}});
        char row[128];
        std::snprintf(row, sizeof row, "| %s | %.2f | %.2f |\n", std::string(methodName(methods[i])).c_str(),
                      *ms, *moving);
        table += row;
    }
    // The simple scene: no normal map, a constant dielectric, no point lights, no environment.
    Scene simple = scene;
    simple.material.normalMap.reset();
    simple.material.glossMap.reset();
    simple.material.detailMap.reset();
    simple.material.specularMap.reset();
    simple.pointLights.clear();
    simple.environment = EnvironmentKind::Off;
    bar.update(double(methods.size()) / steps, "specialised");
    renderer.setUseUbershader(false);
    if (auto s = renderer.setScene(simple); !s) return fail(s.error());
    auto specialised = medianFrameMs(renderer, *target, o.benchFrames);
    if (!specialised) return fail(specialised.error());
    bar.update(double(methods.size() + 1) / steps, "ubershader");
    renderer.setUseUbershader(true);
    if (auto s = renderer.setScene(simple); !s) return fail(s.error());
    auto uber = medianFrameMs(renderer, *target, o.benchFrames);
    renderer.setUseUbershader(false);
    if (!uber) return fail(uber.error());
    bar.finish();
    // A frame below the clock's resolution still gives a finite ratio.
    const double ratio = *uber / std::max(*specialised, 1e-6);
    const double rss = peakRssMiB();

    if (o.json) {
        nlohmann::json j{{"context", context.description()},
                         {"width", width},
                         {"height", height},
                         {"frames", o.benchFrames},
                         {"mesh", meshKindName(scene.mesh)},
                         {"sphere_segments", sphereSegments},
                         {"interactive_sphere_segments", interactiveSphereSegments},
                         {"methods", perMethod},
                         {"simple_scene",
                          {{"specialised_ms", *specialised},
                           {"ubershader_ms", *uber},
                           {"ubershader_over_specialised", ratio}}},
                         {"peak_rss_mib", rss}};
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("Frame times on %s\n%dx%d, %s mesh, median of %d frames (after %d warm-up), GPU work "
                "included (glFinish). Figures, not a pass/fail test.\n\n",
                context.description().c_str(), width, height, std::string(meshKindName(scene.mesh)).c_str(),
                o.benchFrames, kBenchWarmupFrames);
    if (sphereSegments > 0)
        std::printf(
            "Sphere tessellated for its size on screen: %d x %d segments (interactive frame: %d x %d).\n\n",
            sphereSegments, sphereSegments / 2, interactiveSphereSegments, interactiveSphereSegments / 2);
    std::printf(
        "| method | median ms | interactive (half size, while the camera moves) |\n| --- | --- | --- |\n%s\n",
        table.c_str());
    std::printf("Simple scene (no normal map, constant dielectric): specialised program %.3f ms, ubershader "
                "%.3f ms, ubershader / specialised = %.2f\n",
                *specialised, *uber, ratio);
    std::printf("Peak resident memory (getrusage): %.1f MiB\n", rss);
    return 0;
}

int runSequence(Renderer& renderer, const Scene& scene, int width, int height, const RenderCliOptions& o) {
    ShimmerOptions options;
    options.frames = o.sequence;
    options.degreesPerFrame = o.orbitDegrees;
    options.width = width;
    options.height = height;
    options.referenceSamples = o.reference > 0 ? o.reference : kSequenceReferenceSamples;
    options.space = o.shimmerSpace == "display" ? ImageKind::Display : ImageKind::Hdr;
    // The reference's own sampling noise beside its shimmer, as the studio's meter shows it (its
    // halves need linear frames and 2 samples).
    options.estimateReferenceNoise = options.space == ImageKind::Hdr && options.referenceSamples >= 2;
    if (!o.framesDir.empty()) {
        std::error_code ec;
        fs::create_directories(o.framesDir, ec);
        if (ec) return fail("--frames-dir: cannot create '" + o.framesDir + "': " + ec.message());
    }
    ProgressBar bar("shimmer");
    Status frameError;
    options.onFrame = [&](const ShimmerFrame& frame) {
        bar.update(double(frame.index + 1) / double(options.frames), "frame " + std::to_string(frame.index));
        if (o.framesDir.empty() || !frameError.ok()) return;
        char name[64];
        const char* ext = options.space == ImageKind::Hdr ? "exr" : "png";
        std::snprintf(name, sizeof name, "frame-%03d-method.%s", frame.index, ext);
        frameError = writeImage(fs::path(o.framesDir) / name, width, height, *frame.method, 1.0f);
        if (!frameError.ok()) return;
        std::snprintf(name, sizeof name, "frame-%03d-reference.%s", frame.index, ext);
        frameError = writeImage(fs::path(o.framesDir) / name, width, height, *frame.reference, 1.0f);
    };
    auto report = measureShimmer(renderer, scene, options);
    bar.finish();
    if (!report) return fail(report.error());
    if (!frameError.ok()) return fail(frameError.error());

    const std::string method(methodName(scene.material.method));
    const char* space = report->space == ImageKind::Hdr ? "hdr" : "display";
    if (o.json) {
        nlohmann::json j{{"method", method},
                         {"mesh", meshKindName(scene.mesh)},
                         {"frames", report->frames},
                         {"degrees_per_frame", report->degreesPerFrame},
                         {"width", report->width},
                         {"height", report->height},
                         {"reference_samples", report->referenceSamples},
                         {"space", space},
                         {"measured_pixels", report->measuredPixels},
                         {"method_deltas", report->methodDeltas},
                         {"reference_deltas", report->referenceDeltas},
                         {"method_mean", report->methodMean},
                         {"reference_mean", report->referenceMean},
                         {"reference_noise_deltas", report->referenceNoiseDeltas},
                         {"reference_noise", options.estimateReferenceNoise
                                                 ? nlohmann::json(report->referenceNoise)
                                                 : nlohmann::json(nullptr)},
                         {"ratio", report->ratio}};
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("Shimmer of a %d-frame orbit (%g degrees per frame), %dx%d, %s mesh, method %s against the "
                "%d-sample reference.\nMean |dY| per pixel between consecutive frames, Rec. 709 %s, over the "
                "pixels the object covers in both frames (silhouette dropped; at least %lld). The studio's "
                "meter takes the same measurement.\n\n",
                report->frames, double(report->degreesPerFrame), report->width, report->height,
                std::string(meshKindName(scene.mesh)).c_str(), method.c_str(), report->referenceSamples,
                report->space == ImageKind::Hdr ? "luminance of linear HDR" : "luma of the display frames",
                static_cast<long long>(report->measuredPixels));
    const bool noise = options.estimateReferenceNoise;
    std::printf("| frames | %s | reference |%s\n| --- | --- | --- |%s\n", method.c_str(),
                noise ? " reference's own noise |" : "", noise ? " --- |" : "");
    for (size_t i = 0; i < report->methodDeltas.size(); ++i) {
        std::printf("| %zu-%zu | %.6f | %.6f |", i, i + 1, report->methodDeltas[i],
                    report->referenceDeltas[i]);
        if (noise) std::printf(" %.6f |", report->referenceNoiseDeltas[i]);
        std::printf("\n");
    }
    std::printf("| mean | %.6f | %.6f |", report->methodMean, report->referenceMean);
    if (noise) std::printf(" %.6f |", report->referenceNoise);
    std::printf("\n\nratio (method / reference): %.3f\n", report->ratio);
    // Noise between frames adds to the truth's own change about in quadrature: a reference within
    // twice its noise is mostly noise.
    if (noise && report->referenceMean < 2.0 * report->referenceNoise)
        std::printf("The reference's shimmer is within twice its own sampling noise: mostly noise, not the "
                    "truth's shimmer (raise --reference).\n");
    return 0;
}

int runCompare(Renderer& renderer, const Scene& scene, int width, int height, const RenderCliOptions& o) {
    ImageErrorOptions options;
    options.width = width;
    options.height = height;
    options.referenceSamples = o.compare;
    ProgressBar bar("compare");
    bar.update(0.0, "method and reference");
    auto report = measureImageError(renderer, scene, options);
    bar.finish();
    if (!report) return fail(report.error());
    std::string method(methodName(scene.material.method));
    const bool mixture = scene.material.method == Method::Mixture;
    const bool stochastic = mixture && scene.material.mixtureFiltering == MixtureFiltering::Stochastic;
    if (mixture) method += "-k" + std::to_string(scene.material.methodParams.mixtureLobes);
    if (o.json) {
        nlohmann::json j{{"method", method},
                         {"mixture_filtering",
                          mixture ? nlohmann::json(mixtureFilteringName(scene.material.mixtureFiltering))
                                  : nlohmann::json(nullptr)},
                         {"mixture_samples", stochastic ? nlohmann::json(scene.material.mixtureSamples)
                                                        : nlohmann::json(nullptr)},
                         {"mesh", meshKindName(scene.mesh)},
                         {"distance", scene.camera.distance},
                         {"width", report->width},
                         {"height", report->height},
                         {"reference_samples", report->referenceSamples},
                         {"measured_pixels", report->measuredPixels},
                         {"relative_l1", report->relativeL1},
                         {"energy_ratio", report->energyRatio},
                         {"reference_noise_l1", report->referenceNoiseL1}};
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    if (stochastic)
        method += " (filtered after shading, " + std::to_string(scene.material.mixtureSamples) + " passes)";
    std::printf(
        "%s on the %s at distance %g, %dx%d, against the %d-sample reference (linear HDR luminance over "
        "the %lld pixels the object covers, silhouette dropped):\n"
        "relative L1 %.4f, energy ratio %.4f; the reference's own noise %.4f%s\n",
        method.c_str(), std::string(meshKindName(scene.mesh)).c_str(), double(scene.camera.distance),
        report->width, report->height, report->referenceSamples,
        static_cast<long long>(report->measuredPixels), report->relativeL1, report->energyRatio,
        report->referenceNoiseL1,
        report->relativeL1 < 3.0 * report->referenceNoiseL1
            ? " (the error is within 3x the reference's noise: raise --compare)"
            : "");
    return 0;
}

int runRender(const RenderCliOptions& o, bool sizeGiven) {
    if (o.reference > 0 && o.debug != "none")
        return fail("--reference draws the ground truth, which has no debug view; drop --debug");
    const int modes = (o.sequence > 0 ? 1 : 0) + (o.bench ? 1 : 0) + (o.compare > 0 ? 1 : 0);
    if (modes > 1) return fail("give one of --sequence, --bench and --compare");
    if (o.compare > 0 && (o.reference > 0 || !o.out.empty()))
        return fail("--compare renders the method and its reference itself: drop --reference and --out");
    if (modes == 0 && o.out.empty() && !o.explain) return fail("no --out FILE.png|FILE.exr given");
    if (!o.out.empty()) {
        const std::string ext = lower(fs::path(o.out).extension().string());
        if (ext != ".png" && ext != ".exr") return fail("--out: '" + o.out + "' must end in .png or .exr");
        // One rule for every command: an existing file is replaced only with --force.
        std::error_code ec;
        if (!o.force && fs::exists(fs::symlink_status(o.out, ec)))
            return fail("refusing to overwrite existing file '" + o.out + "' (use --force)");
    }

    int width = o.bench ? kBenchWidth : o.sequence > 0 ? kSequenceSize : kImageSize;
    int height = o.bench ? kBenchHeight : o.sequence > 0 ? kSequenceSize : kImageSize;
    if (sizeGiven) {
        auto size = parseSize(o.size);
        if (!size) return fail(size.error());
        width = size->first;
        height = size->second;
    }

    auto scene = buildScene(o, width, height);
    if (!scene) return fail(scene.error());

    auto context = makeContext(o.gl);
    if (!context) return fail(context.error());
    auto renderer = Renderer::create();
    if (!renderer) return fail(renderer.error());
    (*renderer)->setUseUbershader(o.ubershader);
    if (auto s = (*renderer)->setScene(*scene); !s) return fail(s.error());

    if (o.explain) std::printf("%s\n", (*renderer)->explainProgram().c_str());
    if (o.bench) return runBench(**renderer, **context, *scene, width, height, o);
    if (o.sequence > 0) return runSequence(**renderer, *scene, width, height, o);
    if (o.compare > 0) return runCompare(**renderer, *scene, width, height, o);
    if (o.out.empty()) return 0; // --explain alone

    const bool exr = lower(fs::path(o.out).extension().string()) == ".exr";
    const ImageKind kind = exr ? ImageKind::Hdr : ImageKind::Display;
    ProgressBar bar(o.reference > 0 ? "reference" : "render");
    bar.update(0.0);
    auto image = o.reference > 0 ? (*renderer)->renderReference(width, height, o.reference, kind)
                                 : (*renderer)->renderToImage(width, height, kind);
    bar.finish();
    if (!image) return fail(image.error());
    // The EXR holds linear radiance with the exposure applied (no tonemapping); data debug views
    // (normals, power, ...) are written as they are.
    const bool dataView = scene->debugView == DebugView::Power || scene->debugView == DebugView::Normals ||
                          scene->debugView == DebugView::MipLevel ||
                          scene->debugView == DebugView::Variance ||
                          scene->debugView == DebugView::ErrorHeatmap;
    const float scale = dataView ? 1.0f : std::exp2(o.exposure);
    if (auto s = writeImage(o.out, width, height, *image, scale); !s) return fail(s.error());
    if (o.json) {
        nlohmann::json j{{"out", o.out},
                         {"width", width},
                         {"height", height},
                         {"method", methodName(scene->material.method)},
                         {"reference_samples", o.reference},
                         {"frame_ms", (*renderer)->lastFrameMs()},
                         {"context", (*context)->description()}};
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        std::printf("Wrote %s (%dx%d, %s%s).\n", o.out.c_str(), width, height,
                    o.reference > 0
                        ? ("reference, " + std::to_string(o.reference) + " samples per pixel").c_str()
                        : std::string(methodName(scene->material.method)).c_str(),
                    exr ? ", linear HDR" : "");
    }
    return 0;
}

const CommandRegistration registration{
    45, [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<RenderCliOptions>();
        CLI::App* sub = app.add_subcommand(
            "render", "Render the material headless (OpenGL on EGL or OSMesa): an image, the supersampled "
                      "ground truth, a debug view, the shimmer of a slow orbit, a frame's error against "
                      "the ground truth, or frame-time figures.");
        sub->add_option(
               "normal_map", o->input,
               "Tangent-space normal map (PNG, TGA, JPEG, EXR, TIFF, DDS); none: the built-in --sample.")
            ->type_name("NORMAL_MAP");
        sub->add_option(
               "--out", o->out,
               "Image to write: .png (display: exposure, filmic tonemap, sRGB, 8-bit) or .exr (linear "
               "HDR radiance times 2^exposure, float).")
            ->type_name("FILE");
        sub->add_option("--sample", o->sample,
                        "Built-in normal map when none is given: hammered (default), "
                        "brushed or bumpy.")
            ->check(CLI::IsMember({"hammered", "brushed", "bumpy"}))
            ->type_name("NAME");
        sub->add_option("--sample-size", o->sampleSize,
                        "Side of the built-in normal map in texels (default 256).")
            ->check(CLI::Range(1, 4096));
        sub->add_option("--mesh", o->mesh, "sphere (default), plane, torus, or an OBJ file (with UVs).")
            ->type_name("MESH");
        sub->add_option(
               "--method", o->method,
               "Prefiltering method: naive, toksvig, toksvig-map, variance-to-gloss (default), lean, "
               "clean, vmf, mixture, fitted.")
            ->type_name("NAME");
        sub->add_option("--lobes", o->lobes,
                        "Lobes per texel of --method mixture, 1..4 (default 3; 1 is LEAN).")
            ->check(CLI::Range(1, 4))
            ->type_name("K");
        sub->add_flag("--shaded-fit", o->shadedFit,
                      "--method mixture: its lobes also fitted to the shaded ground truth, as burnish bake "
                      "--shaded-fit (a slower bake).");
        sub->add_option(
               "--mixture-filtering", o->mixtureFiltering,
               "--method mixture: moments (hardware trilinear filtering of its stored lobes, which "
               "merges each slot's lobes; default) or stochastic (filtering after shading: each pass "
               "shades one texel of every pixel's trilinear footprint, and --mixture-samples passes "
               "are averaged, as temporal anti-aliasing would).")
            ->check(CLI::IsMember({"moments", "stochastic"}));
        sub->add_option("--mixture-samples", o->mixtureSamples,
                        "Passes averaged with --mixture-filtering stochastic (default 16).")
            ->check(CLI::Range(1, 4096));
        sub->add_option(
               "--kernel", o->kernel,
               "Per-mip filter of the moments the bake stores, as burnish bake --kernel: box, "
               "tent or gaussian (default: as the bake's, box for --method fitted, tent for the rest).")
            ->check(CLI::IsMember({"box", "tent", "gaussian"}));
        sub->add_option("--power", o->power, "Base Blinn-Phong power (default 1024).")
            ->check(CLI::Range(1.0, 1e9))
            ->type_name("S");
        sub->add_option(
               "--gloss", o->gloss,
               "Base gloss as a value in [0, 1] in the gloss encoding, or an authored gloss map image "
               "(first channel, the normal map's size). Replaces --power.")
            ->type_name("G|FILE");
        sub->add_option("--preset", o->preset,
                        "Engine preset (name or .json) whose method and gloss encoding are the defaults.")
            ->type_name("PRESET");
        sub->add_option("--gloss-encoding", o->glossEncoding,
                        "Gloss encoding: blackops (default), exp2, ggx-roughness, ggx-alpha, beckmann, "
                        "smoothness or log:NMIN:NMAX.")
            ->type_name("NAME");
        sub->add_option("--material", o->material,
                        "A calibrated material of 'burnish materials' (its F0; metals get no diffuse).")
            ->type_name("NAME");
        sub->add_option("--specular", o->specular, "Linear specular colour F0 r,g,b (or one grey value).")
            ->delimiter(',')
            ->expected(1, 3)
            ->check(CLI::Range(0.0, 1.0))
            ->type_name("R,G,B");
        sub->add_flag("--metal", o->metal, "A metal: no diffuse (the 'pure metal' program).");
        sub->add_option("--albedo", o->albedo,
                        "Linear diffuse albedo r,g,b (or one grey value; default 0.5).")
            ->delimiter(',')
            ->expected(1, 3)
            ->check(CLI::Range(0.0, 1.0))
            ->type_name("R,G,B");
        sub->add_option("--uv-scale", o->uvScale, "Texture tiling on top of the mesh's (default 1).")
            ->check(CLI::Range(1e-3, 1e4));
        sub->add_option("--distance", o->distance, "Camera distance from the target (default 3).")
            ->check(CLI::Range(0.01, 1e5));
        sub->add_option("--yaw", o->yaw,
                        "Camera yaw about +y in degrees (default 30; 100 turns either way at most).")
            ->check(rangeOrEmpty(-36000.0, 36000.0));
        sub->add_option("--pitch", o->pitch, "Camera pitch above the horizon in degrees (default 20).")
            ->check(CLI::Range(-89.9, 89.9));
        sub->add_option("--light-dir", o->lightDir,
                        "Direction towards the key light x,y,z, each in [-1e6, 1e6], not all 0 (default "
                        "0.4,0.7,0.6).")
            ->check(rangeOrEmpty(-1e6, 1e6))
            ->delimiter(',')
            ->expected(3)
            ->type_name("X,Y,Z");
        sub->add_option("--exposure", o->exposure, "Exposure in stops (default 0).")
            ->check(CLI::Range(-30.0, 30.0));
        sub->add_option("--size", o->size,
                        "Frame size WxH (default 512x512; 128x128 for --sequence; 1280x720 for --bench).")
            ->type_name("WxH");
        sub->add_option(
               "--reference", o->reference,
               "Render the supersampled ground truth with N jittered samples per pixel instead; with "
               "--sequence, the reference's samples (default 16).")
            ->check(CLI::Range(1, 4096))
            ->type_name("N");
        sub->add_option(
               "--debug", o->debug,
               "Debug view: none, lighting-only, diffuse-only, specular-only, power, normals, mip-level, "
               "variance, error-heatmap.")
            ->type_name("VIEW");
        sub->add_option("--ndf", o->ndf, "NDF: blinn-phong (default), beckmann, ggx.")->type_name("NAME");
        sub->add_option("--fresnel", o->fresnel,
                        "Fresnel: none, schlick (default), schlick-sg, schlick-sg-quadratic.")
            ->type_name("NAME");
        sub->add_option("--visibility", o->visibility,
                        "Visibility: none (default), kelemen, schlick-smith, cook-torrance, smith-beckmann, "
                        "smith-ggx-correlated.")
            ->type_name("NAME");
        sub->add_option("--specular-aa", o->specularAa,
                        "Geometric specular AA: none (default), kaplanyan-valient, tokuyoshi-kaplanyan.")
            ->type_name("NAME");
        sub->add_flag("--diffuse-aa", o->diffuseAa, "Diffuse AA (cone of normals).");
        sub->add_flag("--force", o->force, "Replace an existing --out file.");
        sub->add_flag("--explain", o->explain,
                      "Print the program's features, defines, uniforms and samplers (alone: then exit).");
        sub->add_flag("--ubershader", o->ubershader,
                      "Draw with the ubershader (every feature, switched by uniforms) instead of the "
                      "specialised program.");
        sub->add_option(
               "--sequence", o->sequence,
               "Render an N-frame slow orbit with the method and the reference and print the shimmer "
               "(mean |dY| per pixel between frames) of both and their ratio.")
            ->check(CLI::Range(2, 10000))
            ->type_name("N");
        sub->add_option("--compare", o->compare,
                        "Render the method and its N-sample supersampled ground truth and print the method's "
                        "error on the screen: relative L1 of linear HDR luminance over the pixels the object "
                        "covers (silhouette dropped), the energy ratio, and the reference's own noise.")
            ->check(CLI::Range(2, 4096))
            ->type_name("N");
        sub->add_option("--orbit-degrees", o->orbitDegrees, "Yaw step per frame of --sequence (default 0.5).")
            ->check(CLI::Range(-360.0, 360.0));
        sub->add_option("--frames-dir", o->framesDir,
                        "Also write each --sequence frame (method and reference).")
            ->type_name("DIR");
        sub->add_option("--shimmer-space", o->shimmerSpace,
                        "Frames the shimmer is measured on: hdr (default; linear radiance, where popping "
                        "highlights keep their energy) or display (tonemapped sRGB, what a screen shows).")
            ->check(CLI::IsMember({"display", "hdr"}));
        sub->add_flag("--json", o->json, "Print the result as JSON.");
        sub->add_flag(
            "--bench", o->bench,
            "Frame-time figures: the median per method on the scene, full size and the interactive "
            "frame (half size, scaled up: the studio's while the camera moves), and the specialised "
            "program against the ubershader on a simple scene; peak memory. Never pass/fail.");
        sub->add_option("--bench-frames", o->benchFrames, "Timed frames per figure of --bench (default 9).")
            ->check(CLI::Range(1, 1000));
        sub->add_option("--gl", o->gl, "OpenGL context: auto (EGL, then OSMesa; default), egl or osmesa.")
            ->check(CLI::IsMember({"auto", "egl", "osmesa"}));
        sub->add_option(
               "--env", o->env,
               "Environment lighting: off (default), studio (the procedural studio) or an "
               "equirectangular HDR file (.exr/.hdr/.tif), prefiltered per gloss with SH9 irradiance.")
            ->type_name("FILE|studio|off");
        sub->add_option("--env-rotation", o->envRotation,
                        "Environment rotation about +y in degrees (default 0).")
            ->check(CLI::Range(-360.0f, 360.0f));
        sub->add_option("--env-intensity", o->envIntensity, "Environment radiance scale (default 1).")
            ->check(CLI::Range(0.0f, 1e6f));
        sub->add_flag("--env-background", o->envBackground,
                      "Draw the environment behind the mesh (from its own 512² cube faces, turned and "
                      "scaled as the lighting); the reference (--reference) shows it too.");
        sub->add_option(
               "--env-fis", o->envFis,
               "Filtered importance sampling of the environment with N taps per pixel instead of the "
               "prefiltered map (default 0: prefiltered).")
            ->check(CLI::Range(0, int(kMaxFisSamples)))
            ->type_name("N");
        addNormalMapOptions(sub, o->normalMap);
        CLI::Option* size = sub->get_option("--size");
        return [o, size] { return runRender(*o, size->count() > 0); };
    }};

} // namespace

} // namespace burnish::cli
