#include <burnish/render/renderer.h>

#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/detail.h>
#include <burnish/core/bake/paint.h>
#include <burnish/core/env/sampling.h>
#include <burnish/core/env/sh.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/util/low_discrepancy.h>
#include <burnish/render/cubemap.h>
#include <burnish/render/gpu_resources.h>
#include <burnish/render/mesh.h>

#include <epoxy/gl.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

namespace burnish::render {

namespace {

using Clock = std::chrono::steady_clock;

// Texture units of material.frag's samplers: a baked texture's unit is its role's index in the method
// table (methods.h) up to the detail map's, then the detail map's and the others'; the mixture's
// roles (after Detail) follow the environment's unit (textureUnit).
enum TextureUnit : int {
    kUnitNormal = int(TextureRole::Normal),
    kUnitGloss = int(TextureRole::Gloss),
    kUnitDetail = 6,
    kUnitSpecular = 7,
    kUnitEnvironment = 8,
};

int textureUnit(TextureRole role) {
    return role < TextureRole::MixtureWeights
               ? int(role)
               : kUnitEnvironment + 1 + int(role) - int(TextureRole::MixtureWeights);
}

// Largest reference sample count: 4096 passes already take minutes on a software rasterizer.
constexpr int kMaxReferenceSamples = 4096;

// An RGBA32F off-screen target of the given size (with depth for the material pass), kept between
// frames and recreated only when the size changes; its colour texture feeds the next pass.
Status ensureTarget(std::optional<Framebuffer>& target, int width, int height, bool depth,
                    ColorFormat format = ColorFormat::Rgba32f) {
    if (target && target->width() == width && target->height() == height) return {};
    target.reset();
    auto created = Framebuffer::create(width, height, format, depth);
    if (!created) return Error{created.error()};
    target.emplace(std::move(created).value());
    return {};
}

// A baked texture on the GPU, holding decoded values (stored·scale + bias, its ChannelDecode), from
// the baked chain's level `firstLevel` on (setMaxTextureSize).
struct GpuBaked {
    Texture2D texture;
    int firstLevel = 0;
};

// Each channel's decode (stored·scale + bias), as uploadBaked applies it.
void channelDecode(const BakedTexture& baked, std::vector<float>& scale, std::vector<float>& bias) {
    const size_t channels = size_t(baked.channels);
    scale.assign(channels, 1.0f);
    bias.assign(channels, 0.0f);
    for (size_t c = 0; c < baked.decode.size() && c < channels; ++c) {
        scale[c] = float(baked.decode[c].scale);
        bias[c] = float(baked.decode[c].bias);
    }
}

// `maxSize` > 0: the chain from its first level no larger than that on a side (a display needs no
// more; an 8192² chain took most of 23 s to upload on llvmpipe), so the texture is that level's size
// and sampling picks its levels as for a smaller map.
Result<GpuBaked> uploadBaked(const BakedTexture& baked, int maxSize = 0) {
    std::vector<TextureLevel> levels;
    levels.reserve(baked.mips.size());
    size_t first = 0;
    while (maxSize > 0 && first + 1 < baked.mips.size() &&
           std::max(baked.mips[first].width, baked.mips[first].height) > maxSize)
        ++first;
    // Each channel's decode (stored·scale + bias) is applied here, in float as the shader did: it is
    // affine, so the hardware's filtering of decoded values is the decode of its filtering of the
    // stored ones, and the shader reads physical values without a uniform per channel (on llvmpipe
    // each uniform read is a gather: the decode of the mixture's five textures took 3 ms a frame).
    const size_t channels = size_t(baked.channels);
    std::vector<float> scale, bias;
    channelDecode(baked, scale, bias);
    for (size_t k = first; k < baked.mips.size(); ++k) {
        const auto& mip = baked.mips[k];
        // Decoded bottom row first, GL's order: the one copy the upload makes on this side (appended
        // row by row, so the vector is not zero-filled first).
        TextureLevel level{mip.width, mip.height, {}, true};
        level.texels.reserve(mip.texels.size());
        const size_t row = size_t(mip.width) * channels;
        for (int y = mip.height - 1; y >= 0; --y) {
            const float* in = mip.texels.data() + size_t(y) * row;
            for (size_t i = 0; i < row; i += channels)
                for (size_t c = 0; c < channels; ++c)
                    level.texels.push_back(in[i + c] * scale[c] + bias[c]);
        }
        levels.push_back(std::move(level));
    }
    // Hardware trilinear filtering over the baked chain is what the methods were baked for.
    auto texture = Texture2D::create(levels, baked.channels, TextureFilter::LinearMipLinear, true);
    if (!texture)
        return Error{"uploading the '" + std::string(roleName(baked.role)) + "' texture: " + texture.error()};
    return GpuBaked{std::move(texture).value(), int(first)};
}

// What a bake depends on; shared_ptrs keep the identities alive so an address is never reused.
struct BakeKey {
    std::shared_ptr<const NormalMap> normalMap;
    std::shared_ptr<const std::vector<float>> glossMap;
    Method method = Method::Naive;
    double toksvigMapPower = 0.0;
    double basePower = 0.0;
    std::string encoding;
    int mixtureLobes = 0;
    bool mixtureShadedFit = false;
    int largestLevel = 0; // the levels above it are not baked (BakeOptions::largestLevel)
    FilterKernel kernel = FilterKernel::Tent;

    bool operator==(const BakeKey& o) const {
        return normalMap == o.normalMap && glossMap == o.glossMap && method == o.method &&
               toksvigMapPower == o.toksvigMapPower && basePower == o.basePower && encoding == o.encoding &&
               mixtureLobes == o.mixtureLobes && mixtureShadedFit == o.mixtureShadedFit &&
               largestLevel == o.largestLevel && kernel == o.kernel;
    }
};

BakeKey bakeKeyOf(const MaterialSettings& m, int largestLevel) {
    return BakeKey{m.normalMap,
                   m.glossMap,
                   m.method,
                   m.methodParams.toksvigMapPower,
                   m.basePower,
                   m.glossEncoding.name(),
                   m.method == Method::Mixture ? m.methodParams.mixtureLobes : 0,
                   m.method == Method::Mixture && m.methodParams.mixtureShadedFit,
                   largestLevel,
                   m.kernel.value_or(defaultKernel(m.method))};
}

// The CPU half of a material's bake (any thread): core's bake, and the mixture's covariance floor.
struct CpuBake {
    Result<BakeOutput> out = Error{"not baked"};
    double mixtureMinVariance = 1.0 / 1024.0;
    std::shared_ptr<const NormalPyramid> pyramid; // the shared pyramid it read, kept by the renderer
};

// The pyramid a capped bake (largestLevel > 0: the studio's views) reads, one per map for every
// renderer of the process: built by the first bake of a map with the moments its method reads, read
// by every later one whose method reads no others (a gloss or method change then skips the pyramid,
// most of an 8192² bake), rebuilt with the union when one does, freed with the last renderer that
// holds it. Uncapped bakes (the command line) build their own and free it level by level.
std::shared_ptr<const NormalPyramid> sharedBakePyramid(const std::shared_ptr<const NormalMap>& map,
                                                       const BakeOptions& options) {
    static std::mutex mutex;
    static std::weak_ptr<const NormalPyramid> last;
    static int lastLargest = 0;
    const std::lock_guard<std::mutex> lock(mutex); // a second view's bake waits and shares it
    auto pyramid = last.lock();
    const unsigned needed = momentsNeeded(options.method);
    const bool sameMap = pyramid && &pyramid->finest() == map.get() && lastLargest == options.largestLevel &&
                         pyramid->options().border == options.pyramid.border &&
                         pyramid->options().kernel == options.pyramid.kernel;
    if (!sameMap || (pyramid->options().moments & needed) != needed) {
        pyramid = bakePyramid(map, options, needed | (sameMap ? pyramid->options().moments : 0u));
        last = pyramid;
        lastLargest = options.largestLevel;
    }
    return pyramid;
}

// Levels above largestLevel (the renderer's maximum texture size) are never uploaded, so not baked.
// `progress` is core's (BakeOptions::progress): the fraction done, false to stop.
CpuBake cpuBake(const MaterialSettings& m, int largestLevel, std::function<bool(double)> progress = {}) {
    BakeOptions options;
    options.largestLevel = largestLevel;
    options.progress = std::move(progress);
    options.method = m.method;
    options.encoding = m.glossEncoding;
    options.basePower = m.basePower;
    options.params = m.methodParams;
    options.pyramid.kernel = m.kernel.value_or(defaultKernel(m.method));
    if (m.glossMap) options.authoredGloss = *m.glossMap;
    CpuBake b;
    if (largestLevel > 0) options.cachedPyramid = sharedBakePyramid(m.normalMap, options);
    if (options.progress && !options.progress(0.0)) {
        b.out = Error{"cancelled"};
        return b;
    }
    b.out = bake(*m.normalMap, options);
    b.pyramid = options.cachedPyramid;
    double maxPower = m.basePower;
    if (m.glossMap) {
        maxPower = 0.0;
        for (float g : *m.glossMap)
            maxPower = std::max(maxPower, m.glossEncoding.power(g));
    }
    b.mixtureMinVariance = mixtureBaseVariance(maxPower, options.params.mixtureLobes);
    return b;
}

// A bake running on a worker thread for the studio (Renderer::setBackgroundBakes).
struct BackgroundBake {
    BakeKey key;
    MaterialSettings material;
    std::shared_ptr<CpuBake> result = std::make_shared<CpuBake>();
    std::shared_ptr<std::atomic<bool>> done = std::make_shared<std::atomic<bool>>(false);
    // Set when a newer request (or a return to the drawn material) withdraws this bake: core's bake
    // stops at its next level and the result is dropped.
    std::shared_ptr<std::atomic<bool>> cancel = std::make_shared<std::atomic<bool>>(false);
    std::shared_ptr<std::atomic<double>> progress = std::make_shared<std::atomic<double>>(0.0);
    std::thread worker;
};

int glossKindIndex(const GlossEncoding& encoding) {
    return int(encoding.kind());
}

// What an environment's source cube depends on; the shared_ptr keeps a Cube source's identity alive.
struct EnvironmentSourceKey {
    EnvironmentSourceKind kind = EnvironmentSourceKind::ProceduralStudio;
    std::filesystem::path path;
    std::shared_ptr<const CubeMap> cube;
    int faceSize = 0;

    bool operator==(const EnvironmentSourceKey&) const = default;
};

EnvironmentSourceKey environmentSourceKey(const EnvironmentMap& e) {
    EnvironmentSourceKey key{e.source, {}, {}, e.faceSize};
    if (e.source == EnvironmentSourceKind::File) key.path = e.path;
    if (e.source == EnvironmentSourceKind::Cube) {
        key.cube = e.cube;
        key.faceSize = 0; // the cube sets its own size
    }
    return key;
}

// What the prefiltered cube depends on beyond its source: the lobe and the power per mip.
std::string prefilterKey(const EnvironmentMap& e, const GlossEncoding& encoding) {
    auto exact = [](double v) {
        char text[32];
        std::snprintf(text, sizeof(text), "%.17g", v); // round-trips a double: equal keys, equal values
        return std::string(text);
    };
    std::string key = std::string(lobeModelName(e.lobe)) + "/cut:" + exact(e.lobeCutoff) + "/";
    if (e.mipsFollowGloss) return key + "encoding:" + encoding.name();
    return key + "drop:" + exact(e.topPower) + ":" + exact(e.powerDrop);
}

// Radiance above this would let the SH sums and the shader's float arithmetic overflow; it is 10^4
// times a bright sun (1e5). NaN and negative texels carry no light.
constexpr float kMaxSourceRadiance = 1e9f;

void sanitizeRadiance(CubeMap& cube) {
    for (CubeLevel& level : cube.levels)
        for (auto& face : level.faces)
            for (float& v : face)
                v = v > 0.0f ? std::min(v, kMaxSourceRadiance) : 0.0f;
}

bool usesEnvironmentMap(EnvironmentKind kind) {
    return kind == EnvironmentKind::Prefiltered || kind == EnvironmentKind::FilteredImportanceSampling;
}

} // namespace

void haltonPoint(int index, float& x, float& y) {
    const auto i = std::uint32_t(std::max(index, 0));
    x = float(radicalInverse(i, 2));
    y = float(radicalInverse(i, 3));
}

struct Renderer::Impl {
    Scene scene;
    bool hasScene = false;
    bool useUbershader = false;
    FeatureSet features;
    const Program* program = nullptr;
    const Program* accumulate = nullptr;
    const Program* heatmap = nullptr;
    const Program* tonemap = nullptr;
    const Program* backgroundProgram = nullptr;        // background.frag, HDR
    const Program* backgroundDisplayProgram = nullptr; // background.frag with DISPLAY_OUTPUT
    ProgramCache programs;
    std::unique_ptr<FullscreenTriangle> fullscreen;

    // Mesh: an OBJ, the plane or the torus in `mesh`; the sphere in `spheres`, one per tessellation
    // drawn (sphereSegmentsForRadius of its size on screen), made when first needed.
    std::optional<GpuMesh> mesh;
    std::map<int, GpuMesh> spheres;
    int lastSphereSegments = 0;
    MeshKind meshKind = MeshKind::Sphere;
    std::filesystem::path meshPath;
    float meshRadius = 1.0f;

    // Method bake.
    std::shared_ptr<const NormalPyramid> keptPyramid; // sharedBakePyramid's, while this map is drawn
    std::optional<BakeKey> bakeKey;
    // Background bakes: the material last baked (drawn while a newer one bakes) and the bake in
    // flight (joined at destruction).
    bool backgroundBakes = false;
    int maxTextureSize = 0; // 0: every level uploaded
    std::function<void()> onBakeReady;
    std::optional<MaterialSettings> bakedMaterial;
    std::unique_ptr<BackgroundBake> pending;
    // The last setScene draws the last baked material while the requested one bakes (bakePending).
    bool drawingStale = false;
    ~Impl() {
        if (pending && pending->worker.joinable()) pending->worker.join();
    }
    std::map<TextureRole, GpuBaked> baked;
    int bakes = 0;
    // The mixture's covariance floor: the narrowest authored lobe's base variance (MixturePyramid's).
    double mixtureMinVariance = 1.0 / 1024.0;
    // The reference's finest normals and authored gloss, level 0 only.
    std::shared_ptr<const NormalMap> finestFor;
    std::shared_ptr<const std::vector<float>> finestGlossFor;
    std::optional<Texture2D> finestNormal;
    std::optional<Texture2D> finestGloss;
    // Detail and specular maps.
    std::shared_ptr<const NormalMap> detailFor;
    std::optional<GpuBaked> detail;
    std::shared_ptr<const SpecularColorMap> specularFor;
    std::optional<Texture2D> specular;

    // Environment: the source cube (level 0) and its SH9, the prefiltered cube (PMREM) and the
    // box-filtered chain FIS reads, each remade only when what it depends on changes.
    std::optional<EnvironmentSourceKey> envSourceKey;
    // The background's own cube (EnvironmentMap::backgroundFaceSize), keyed by its source and size.
    std::optional<CubeMapTexture> envBackground;
    std::optional<EnvironmentSourceKey> envBackgroundKey;
    CubeMap envSource;
    Sh9 envSh;
    std::string envPrefilterKey;
    std::optional<CubeMapTexture> envPrefiltered;
    std::optional<CubeMapTexture> envChain;
    int prefilters = 0;
    double lastEnvironmentMs = 0.0;

    std::optional<Framebuffer> hdr;
    // The frame's display values with their depth (drawFused), copied into the caller's target; at
    // half size for an interactive frame.
    std::optional<Framebuffer> display;
    std::optional<Framebuffer> displayInteractive;
    std::optional<Framebuffer> accumulation;
    std::optional<Framebuffer> heatmapReference;
    std::optional<Framebuffer> stochasticSum; // the passes of a stochastically filtered mixture, summed
    int stochasticSample = 0;                 // the pass being drawn (uStochasticSample)
    // Progressive frames (RenderTarget::progressive): the passes so far, summed, of the scene and
    // size they were drawn for; whether the last render() was such a frame.
    std::optional<Framebuffer> progressiveSum;
    std::optional<Scene> progressiveScene;
    int progressiveCount = 0;
    bool progressiveLast = false;
    bool heatmapReferenceValid = false;
    double lastMs = 0.0;

    Status prepareMesh();
    Result<const GpuMesh*> drawnMesh(int height);
    Status prepareBake();
    Status prepareFinest();
    Status uploadBake(const BakeKey& key, const CpuBake& cpu);
    Result<bool> replaceGloss(const MaterialSettings& m, const LiveGlossBake& live,
                              const std::vector<TexelRect>* dirty);
    /// Background bakes: whether the bake of `m` is in (a finished worker's bake is taken in now),
    /// else starts it unless another runs, and returns false.
    Result<bool> backgroundBake(const MaterialSettings& m);
    Status prepareMaps();
    Status prepareEnvironment(EnvironmentKind kind);
    void setEnvironmentUniforms(const Program& p, const FeatureSet& f);
    /// The material program of f; with `display` its DISPLAY_OUTPUT variant (tonemap fused).
    Result<const Program*> materialProgram(const FeatureSet& f, bool displayOutput = false);
    void setMaterialUniforms(const Program& p, const FeatureSet& f, int width, int height,
                             glm::vec2 jitterNdc, bool reference);
    Status drawMaterial(const FeatureSet& f, const Program& p, int width, int height, glm::vec2 jitterNdc,
                        bool reference, bool withBackground);
    /// Draws `source`'s colour times `weight` into `target` (left bound): added to what it holds
    /// (`add`, for the averages of several passes) or replacing it (a copy).
    void drawWeighted(Framebuffer& target, const Framebuffer& source, float weight, bool add);
    Status accumulateReference(int width, int height, int samples, bool withBackground);
    void drawBackground(int width, int height, bool displayOutput);
    /// The cube the lighting reads for `kind` (the prefiltered one, or FIS's chain), when made.
    const CubeMapTexture* lightingCube(EnvironmentKind kind) const;
    /// uEnvironmentRotation and uEnvironmentIntensity of the scene's environment map.
    void setEnvironmentTurnAndScale(const Program& p) const;
    /// The camera's projection × view for a width×height target.
    glm::mat4 cameraViewProjection(int width, int height) const;
    Status displayPass(const RenderTarget& target, const Framebuffer& source, bool dataView);
    Status drawHdr(int width, int height, bool withBackground);
    /// The next pass of a progressive frame added to the average of the passes before (from the
    /// first when the scene or the size changed), that average in the HDR target.
    Status drawProgressive(int width, int height);
    /// Whether the material is a mixture filtered after shading by a specialized program
    /// (MaterialSettings::mixtureFiltering; the ubershader and the reference filter the moments).
    bool stochasticMixture() const {
        return !useUbershader && hasScene && scene.material.method == Method::Mixture &&
               scene.material.mixtureFiltering == MixtureFiltering::Stochastic;
    }
    /// The passes a stochastically filtered frame averages (MaterialSettings::mixtureSamples). One
    /// pass is drawn as any frame is (the fused display pass, the interactive half size).
    int stochasticPasses() const {
        return std::clamp(scene.material.mixtureSamples, 1, kMaxReferenceSamples);
    }
    Status drawFused(const RenderTarget& target);
    void setFaceCulling() const;
    void beginMaterialPass(const Framebuffer& target) const;
};

// The material pass's state: the target bound and cleared to black with its depth, depth-tested, no
// blending, the closed meshes' back faces culled.
void Renderer::Impl::beginMaterialPass(const Framebuffer& target) const {
    target.bind();
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    setFaceCulling();
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

// The built-in sphere and torus are closed, wound counter-clockwise seen from outside, and the camera
// never enters them: their back faces are always hidden, so they are culled rather than shaded and then
// covered. Both faces of the plane are seen, and an OBJ's winding is not trusted.
void Renderer::Impl::setFaceCulling() const {
    if (meshKind == MeshKind::Sphere || meshKind == MeshKind::Torus) {
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
        glFrontFace(GL_CCW);
    } else {
        glDisable(GL_CULL_FACE);
    }
}

Status Renderer::Impl::prepareMesh() {
    if (scene.mesh == MeshKind::Sphere) {
        // Drawn from `spheres` (drawnMesh); the unit sphere's bounds.
        mesh.reset();
        meshKind = MeshKind::Sphere;
        meshPath.clear();
        meshRadius = 1.0f;
        return {};
    }
    if (mesh && meshKind == scene.mesh && (scene.mesh != MeshKind::Obj || meshPath == scene.objPath))
        return {};
    // An OBJ shared with whoever read it before (loadObjShared: parsed once), the others made here.
    std::shared_ptr<const MeshData> shared;
    switch (scene.mesh) {
    case MeshKind::Sphere: // returned above: drawnMesh makes it for each frame's size
        break;
    case MeshKind::Plane:
        shared = std::make_shared<const MeshData>(makePlane());
        break;
    case MeshKind::Torus:
        shared = std::make_shared<const MeshData>(makeTorus());
        break;
    case MeshKind::Obj: {
        auto loaded = loadObjShared(scene.objPath);
        if (!loaded) return Error{loaded.error()};
        shared = std::move(loaded).value();
        break;
    }
    }
    const MeshData& data = *shared;
    auto uploaded = GpuMesh::upload(data);
    if (!uploaded) return Error{"uploading the mesh: " + uploaded.error()};
    mesh.emplace(std::move(uploaded).value());
    meshKind = scene.mesh;
    meshPath = scene.objPath;
    meshRadius = std::max(glm::length(data.boundsMin), glm::length(data.boundsMax));
    return {};
}

// The mesh a frame `height` pixels tall draws: the sphere tessellated for its size on screen, or
// the scene's other mesh.
Result<const GpuMesh*> Renderer::Impl::drawnMesh(int height) {
    if (meshKind != MeshKind::Sphere) {
        if (!mesh) return Error{"no mesh to draw"};
        lastSphereSegments = 0;
        return &*mesh;
    }
    const OrbitCamera& camera = scene.camera;
    const int segments = sphereSegmentsForRadius(
        sphereScreenRadius(double(glm::length(camera.position())), double(camera.fovYRadians()), height));
    auto found = spheres.find(segments);
    if (found == spheres.end()) {
        auto uploaded = GpuMesh::upload(makeSphere(segments, segments / 2));
        if (!uploaded) return Error{"uploading the mesh: " + uploaded.error()};
        found = spheres.emplace(segments, std::move(uploaded).value()).first;
    }
    lastSphereSegments = segments;
    return &found->second;
}

Status Renderer::Impl::uploadBake(const BakeKey& key, const CpuBake& cpu) {
    if (!cpu.out) return Error{"bake: " + cpu.out.error()};
    keptPyramid = cpu.pyramid; // kept for the next bake of this map
    mixtureMinVariance = cpu.mixtureMinVariance;
    ++bakes;
    baked.clear();
    bakeKey.reset();
    for (const BakedTexture& t : cpu.out->textures) {
        // Textures the shader does not sample (the compact LEAN gloss is for export) stay on the CPU.
        if (textureSpec(t.role).sampler.empty()) continue;
        auto gpu = uploadBaked(t, maxTextureSize);
        if (!gpu) return Error{gpu.error()};
        baked.emplace(t.role, std::move(gpu).value());
    }
    bakeKey = key;
    return {};
}

Result<bool> Renderer::Impl::replaceGloss(const MaterialSettings& m, const LiveGlossBake& live,
                                          const std::vector<TexelRect>* dirty) {
    // Only where the live chain is exactly what a bake of `m` would upload: the drawn bake is of
    // `m` but for its gloss values, and the live bake was made with the options this bake uses.
    if (!bakeKey || !bakedMaterial || !m.glossMap || !m.normalMap) return false;
    BakeKey key = bakeKeyOf(m, maxTextureSize);
    key.glossMap = bakeKey->glossMap;
    if (!(key == *bakeKey)) return false;
    const BakeOptions& o = live.options();
    const BakeOptions defaults;
    if (o.method != m.method || o.encoding.name() != m.glossEncoding.name() || o.basePower != m.basePower ||
        o.pyramid.kernel != key.kernel || o.pyramid.border != defaults.pyramid.border || o.mipCount != 0 ||
        o.params.toksvigMapPower != m.methodParams.toksvigMapPower || live.width() != m.normalMap->width ||
        live.height() != m.normalMap->height)
        return false;
    const auto found = baked.find(TextureRole::Gloss);
    if (found == baked.end()) return false;
    GpuBaked& gpu = found->second;
    const BakedTexture& gloss = live.gloss();
    if (gloss.channels != gpu.texture.channels()) return false;
    for (int level = 0; level < gpu.texture.levels(); ++level) {
        const size_t k = size_t(gpu.firstLevel + level);
        if (k >= gloss.mips.size() || gloss.mips[k].width != std::max(1, gpu.texture.width() >> level) ||
            gloss.mips[k].height != std::max(1, gpu.texture.height() >> level))
            return false;
    }
    // A bake still running is older than the live chain: it is stopped and dropped (taking it in
    // would draw the values before the last strokes).
    if (pending) pending->cancel->store(true);
    std::vector<float> scale, bias, texels;
    channelDecode(gloss, scale, bias);
    const size_t channels = size_t(gloss.channels);
    for (int level = 0; level < gpu.texture.levels(); ++level) {
        const size_t k = size_t(gpu.firstLevel + level);
        const TextureMip& mip = gloss.mips[k];
        TexelRect r = TexelRect::full(mip.width, mip.height);
        if (dirty) {
            r = k < dirty->size() ? (*dirty)[k] : TexelRect{};
            r = {std::max(r.x0, 0), std::max(r.y0, 0), std::min(r.x1, mip.width), std::min(r.y1, mip.height)};
        }
        if (r.empty()) continue;
        texels.clear();
        texels.reserve(r.texelCount() * channels);
        for (int y = r.y0; y < r.y1; ++y) {
            const float* in = mip.texels.data() + (size_t(y) * size_t(mip.width) + size_t(r.x0)) * channels;
            for (size_t i = 0; i < size_t(r.width()) * channels; i += channels)
                for (size_t c = 0; c < channels; ++c)
                    texels.push_back(in[i + c] * scale[c] + bias[c]);
        }
        if (const Status st = gpu.texture.updateRegion(level, r.x0, r.y0, r.width(), r.height(), texels); !st)
            return Error{"updating the gloss texture: " + st.error()};
    }
    bakeKey->glossMap = m.glossMap;
    bakedMaterial->glossMap = m.glossMap;
    return true;
}

Result<bool> Renderer::Impl::backgroundBake(const MaterialSettings& m) {
    const BakeKey key = bakeKeyOf(m, maxTextureSize);
    if (bakeKey && *bakeKey == key) {
        // The request came back to what is drawn: a bake started for a request since withdrawn is
        // stopped, and dropped once it finishes (taking it in would draw the withdrawn material).
        if (pending) pending->cancel->store(true);
        if (pending && pending->done->load()) {
            pending->worker.join();
            pending.reset();
        }
        return true;
    }
    if (pending && pending->done->load() && pending->cancel->load()) {
        // Stopped for a newer request: nothing to take in.
        pending->worker.join();
        pending.reset();
    }
    if (pending && pending->done->load()) {
        // A finished bake is newer than what is drawn: taken in, even if the request moved on.
        pending->worker.join();
        const std::unique_ptr<BackgroundBake> finished = std::move(pending);
        if (const Status s = uploadBake(finished->key, *finished->result); !s) return Error{s.error()};
        bakedMaterial = finished->material;
        if (*bakeKey == key) return true;
    }
    // One bake at a time (core's bake uses every core): a request made while one runs stops it at
    // its next level, and is started by the first setScene after it finishes (its callback asks for
    // one), so a stroke of changes never piles bakes up, and the newest request is always baked last.
    if (pending) {
        if (!(pending->key == key)) pending->cancel->store(true);
        return false;
    }
    pending = std::make_unique<BackgroundBake>();
    pending->key = key;
    pending->material = m;
    pending->worker =
        std::thread([material = m, largest = maxTextureSize, result = pending->result, done = pending->done,
                     cancel = pending->cancel, progress = pending->progress, ready = onBakeReady] {
            *result = cpuBake(material, largest, [&cancel, &progress](double fraction) {
                progress->store(fraction);
                return !cancel->load();
            });
            done->store(true);
            if (ready) ready();
        });
    return false;
}

Status Renderer::Impl::prepareBake() {
    const MaterialSettings& m = scene.material;
    if (!m.normalMap || m.normalMap->texelCount() == 0) {
        baked.clear();
        bakeKey.reset();
        return {};
    }
    const BakeKey key = bakeKeyOf(m, maxTextureSize);
    if (!(bakeKey && *bakeKey == key)) {
        if (const Status s = uploadBake(key, cpuBake(m, maxTextureSize)); !s) return s;
        bakedMaterial = m;
    }
    return {};
}

Status Renderer::Impl::prepareFinest() {
    // The reference's finest level: the normals and authored gloss as given, unfiltered. Uploaded
    // when a reference is first drawn (a big map's finest level is most of a frame's upload).
    const MaterialSettings& m = scene.material;
    if (!m.normalMap || m.normalMap->texelCount() == 0) return {};
    if (finestFor != m.normalMap) {
        TextureLevel level{m.normalMap->width, m.normalMap->height, {}};
        level.texels.reserve(m.normalMap->texelCount() * 3);
        for (const glm::vec3& n : m.normalMap->normals)
            level.texels.insert(level.texels.end(), {n.x, n.y, n.z});
        auto tex = Texture2D::create({level}, 3, TextureFilter::Linear, true);
        if (!tex) return Error{"uploading the finest normals: " + tex.error()};
        finestNormal.emplace(std::move(tex).value());
        finestFor = m.normalMap;
    }
    if (finestGlossFor != m.glossMap) {
        finestGloss.reset();
        if (m.glossMap) {
            // Its size is the normal map's: core's bake refuses any other, and this material is baked.
            auto tex = Texture2D::create({TextureLevel{m.normalMap->width, m.normalMap->height, *m.glossMap}},
                                         1, TextureFilter::Linear, true);
            if (!tex) return Error{"uploading the gloss map: " + tex.error()};
            finestGloss.emplace(std::move(tex).value());
        }
        finestGlossFor = m.glossMap;
    }
    return {};
}

Status Renderer::Impl::prepareMaps() {
    const MaterialSettings& m = scene.material;
    if (m.detailMap && m.detailMap->texelCount() > 0 && detailFor != m.detailMap) {
        auto out = bakeDetail(*m.detailMap);
        if (!out) return Error{"detail bake: " + out.error()};
        auto gpu = uploadBaked(out->texture);
        if (!gpu) return Error{gpu.error()};
        detail.emplace(std::move(gpu).value());
        detailFor = m.detailMap;
    }
    if (m.specularMap && m.specularMap->width > 0 && specularFor != m.specularMap) {
        const SpecularColorMap& s = *m.specularMap;
        if (s.rgb.size() != size_t(s.width) * size_t(s.height) * 3)
            return Error{"the specular colour map has " + std::to_string(s.rgb.size()) + " values for " +
                         std::to_string(s.width) + "x" + std::to_string(s.height) + " RGB texels"};
        auto tex = Texture2D::create({TextureLevel{s.width, s.height, s.rgb}}, 3,
                                     TextureFilter::LinearMipLinear, true);
        if (!tex) return Error{"uploading the specular colour map: " + tex.error()};
        specular.emplace(std::move(tex).value());
        specularFor = m.specularMap;
    }
    return {};
}

namespace {

// Level 0 of an environment's source as a cube of `faceSize` faces (a Cube source: its own level 0),
// with non-finite and negative radiance removed. A backdrop (the background's own cube) samples the
// procedural studio once per texel: its texels are as small as pixels, and 4×4 sub-samples made
// the studio's 512² backdrop cost 0.7 s.
Result<CubeMap> environmentSource(const EnvironmentMap& e, int faceSize, bool backdrop = false) {
    CubeMap source;
    switch (e.source) {
    case EnvironmentSourceKind::ProceduralStudio: {
        auto studio = proceduralStudioEnvironment(faceSize, backdrop ? 1 : 4);
        if (!studio) return Error{"environment: " + studio.error()};
        source = std::move(studio).value();
        break;
    }
    case EnvironmentSourceKind::File: {
        auto loaded = loadEquirectEnvironment(e.path, faceSize);
        if (!loaded) return Error{"environment '" + e.path.string() + "': " + loaded.error()};
        source = std::move(loaded->cube);
        break;
    }
    case EnvironmentSourceKind::Cube:
        if (!e.cube || e.cube->levels.empty() || !isPowerOfTwo(e.cube->faceSize()))
            return Error{"environment: the cube is empty or its face size is not a power of two"};
        source.levels.push_back(e.cube->levels[0]);
        break;
    }
    sanitizeRadiance(source);
    return source;
}

} // namespace

Status Renderer::Impl::prepareEnvironment(EnvironmentKind kind) {
    if (!usesEnvironmentMap(kind)) return {};
    const EnvironmentMap& e = scene.environmentMap;
    const auto start = Clock::now();
    const EnvironmentSourceKey key = environmentSourceKey(e);
    if (!(envSourceKey && *envSourceKey == key)) {
        auto source = environmentSource(e, e.faceSize);
        if (!source) return Error{source.error()};
        envSource = std::move(source).value();
        envSh = projectSh9(envSource);
        envSourceKey = key;
        envPrefilterKey.clear();
        envPrefiltered.reset();
        envChain.reset();
    }
    if (kind == EnvironmentKind::Prefiltered) {
        const std::string pkey = prefilterKey(e, scene.material.glossEncoding);
        if (!envPrefiltered || envPrefilterKey != pkey) {
            PrefilterOptions options;
            options.lobe = e.lobe;
            options.topPower = e.topPower;
            options.powerDrop = e.powerDrop;
            options.lobeCutoff = e.lobeCutoff;
            if (e.mipsFollowGloss) options.encoding = scene.material.glossEncoding;
            auto filtered = prefilterRadiance(envSource, options);
            if (!filtered) return Error{"environment prefilter: " + filtered.error()};
            auto texture = CubeMapTexture::create(filtered->radiance);
            if (!texture) return Error{"environment: " + texture.error()};
            envPrefiltered.emplace(std::move(texture).value());
            envPrefilterKey = pkey;
            ++prefilters;
        }
    } else if (!envChain) {
        CubeMap chain = envSource;
        buildBoxMips(chain);
        auto texture = CubeMapTexture::create(chain);
        if (!texture) return Error{"environment: " + texture.error()};
        envChain.emplace(std::move(texture).value());
    }
    // The background's sharper cube, made only while it is shown and kept while its source stays.
    if (scene.environmentBackground && e.backgroundFaceSize > e.faceSize &&
        e.source != EnvironmentSourceKind::Cube) {
        EnvironmentMap backdrop = e;
        backdrop.faceSize = e.backgroundFaceSize;
        const EnvironmentSourceKey bkey = environmentSourceKey(backdrop);
        if (!(envBackgroundKey && *envBackgroundKey == bkey)) {
            auto source = environmentSource(backdrop, backdrop.faceSize, true);
            if (!source) return Error{source.error()};
            auto texture = CubeMapTexture::create(*source);
            if (!texture) return Error{"environment background: " + texture.error()};
            envBackground.emplace(std::move(texture).value());
            envBackgroundKey = bkey;
        }
    } else {
        envBackground.reset();
        envBackgroundKey.reset();
    }
    lastEnvironmentMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return {};
}

const CubeMapTexture* Renderer::Impl::lightingCube(EnvironmentKind kind) const {
    if (kind == EnvironmentKind::Prefiltered) return envPrefiltered ? &*envPrefiltered : nullptr;
    if (kind == EnvironmentKind::FilteredImportanceSampling) return envChain ? &*envChain : nullptr;
    return nullptr;
}

void Renderer::Impl::setEnvironmentTurnAndScale(const Program& p) const {
    const EnvironmentMap& e = scene.environmentMap;
    // World → environment: the inverse of turning the environment by +rotation about +y.
    p.set("uEnvironmentRotation", glm::mat3(glm::rotate(glm::mat4(1.0f), glm::radians(-e.rotationDegrees),
                                                        glm::vec3(0.0f, 1.0f, 0.0f))));
    // Negative or non-finite intensities would put negative or NaN radiance into the image.
    p.set("uEnvironmentIntensity", std::isfinite(e.intensity) ? std::max(e.intensity, 0.0f) : 0.0f);
}

glm::mat4 Renderer::Impl::cameraViewProjection(int width, int height) const {
    return scene.camera.projection(float(width) / float(height), meshRadius) * scene.camera.view();
}

void Renderer::Impl::setEnvironmentUniforms(const Program& p, const FeatureSet& f) {
    // Always: an unset samplerCube stays on unit 0 beside the normal map's sampler2D, and two sampler
    // types on one unit fail the draw (the ubershader declares it even without an environment).
    p.set("uEnvironment", int(kUnitEnvironment));
    p.set("uEnvironmentKind", int(f.environment));
    if (!usesEnvironmentMap(f.environment)) return;
    const CubeMapTexture* cube = lightingCube(f.environment);
    if (!cube) return;
    const EnvironmentMap& e = scene.environmentMap;
    const MaterialSettings& m = scene.material;
    cube->bind(kUnitEnvironment);
    p.set("uEnvironmentMips", float(cube->mipCount()));
    p.set("uEnvironmentFaceSize", float(cube->faceSize()));
    setEnvironmentTurnAndScale(p);
    for (size_t k = 0; k < envSh.coefficients.size(); ++k)
        p.set(("uEnvironmentSh[" + std::to_string(k) + "]").c_str(), glm::vec3(envSh.coefficients[k]));
    p.set("uEnvironmentLobe", int(e.lobe));
    p.set("uEnvironmentMipRule", e.mipsFollowGloss ? 1 : 0);
    p.set("uEnvironmentTopPower", float(e.topPower));
    p.set("uEnvironmentPowerDrop", float(e.powerDrop));
    p.set("uEnvironmentGlossKind", glossKindIndex(m.glossEncoding));
    p.set("uEnvironmentGlossMinPower", float(m.glossEncoding.minPower()));
    p.set("uEnvironmentGlossMaxPower", float(m.glossEncoding.maxPower()));
    p.set("uEnvironmentSamples", std::clamp(e.fisSamples, 1, int(kMaxFisSamples)));
}

Result<const Program*> Renderer::Impl::materialProgram(const FeatureSet& f, bool displayOutput) {
    // The reference is always specialized: the ubershader has no reference mode.
    const bool uber = useUbershader && !f.referenceMode;
    ShaderDefines d = uber ? ubershaderDefines() : defines(f);
    if (!uber && f.method == Method::Mixture && !f.referenceMode)
        d.push_back({"MIXTURE_LOBES", std::to_string(std::clamp(scene.material.methodParams.mixtureLobes, 1,
                                                                kMaxMixtureLobes))});
    if (!uber && f.method == Method::Mixture && !f.referenceMode &&
        scene.material.mixtureFiltering == MixtureFiltering::Stochastic)
        d.push_back({"MIXTURE_STOCHASTIC", "1"});
    if (displayOutput) d.push_back({"DISPLAY_OUTPUT", "1"});
    return programs.get("material.vert", "material.frag", d);
}

void Renderer::Impl::setMaterialUniforms(const Program& p, const FeatureSet& f, int width, int height,
                                         glm::vec2 jitterNdc, bool reference) {
    const MaterialSettings& m = scene.material;
    const glm::mat4 viewProjection = cameraViewProjection(width, height);
    p.set("uModel", glm::mat4(1.0f));
    p.set("uNormalMatrix", glm::mat3(1.0f));
    p.set("uViewProjection", viewProjection);
    p.set("uJitterNdc", jitterNdc);
    p.set("uUvScale", m.uvScale);
    p.set("uCameraPosition", scene.camera.position());
    const glm::vec3 toLight = glm::length(scene.light.direction) > 0.0f
                                  ? glm::normalize(scene.light.direction)
                                  : glm::vec3(0.0f, 1.0f, 0.0f);
    p.set("uLightDirection", toLight);
    p.set("uLightColor", scene.light.color * scene.light.intensity);
    const int lights = std::min(int(scene.pointLights.size()), kMaxPointLights);
    for (int i = 0; i < lights; ++i) {
        const std::string index = "[" + std::to_string(i) + "]";
        p.set(("uPointLightPosition" + index).c_str(), scene.pointLights[size_t(i)].position);
        p.set(("uPointLightColor" + index).c_str(),
              scene.pointLights[size_t(i)].color * scene.pointLights[size_t(i)].intensity);
    }
    p.set("uAmbient", scene.ambient);
    p.set("uSpecularColor", m.specularColor);
    p.set("uAlbedo", m.albedo);
    p.set("uBasePower", float(clampPower(m.basePower)));
    p.set("uGlossKind", glossKindIndex(m.glossEncoding));
    p.set("uGlossMinPower", float(m.glossEncoding.minPower()));
    p.set("uGlossMaxPower", float(m.glossEncoding.maxPower()));
    p.set("uToksvigFixedPower", float(m.methodParams.toksvigMapPower));
    p.set("uMixtureLobes", std::clamp(m.methodParams.mixtureLobes, 1, kMaxMixtureLobes));
    p.set("uMixtureMinVariance", float(mixtureMinVariance));
    p.set("uStochasticSample", stochasticSample);
    p.set("uDetailUvScale", m.detailUvScale);
    if (m.normalMap)
        p.set("uNormalMapSize", glm::vec2(float(m.normalMap->width), float(m.normalMap->height)));

    // A baked texture at its role's unit, under the sampler its table row names.
    auto bindBaked = [&](TextureRole role, const GpuBaked& gpu) {
        const int unit = textureUnit(role);
        gpu.texture.bind(unit);
        p.set(std::string(textureSpec(role).sampler).c_str(), unit);
        if (role == TextureRole::MixtureWeights) p.set("uMixtureLevels", gpu.texture.levels());
    };
    if (reference) {
        // The finest normals are stored signed: no decode.
        if (finestNormal) {
            finestNormal->bind(kUnitNormal);
            p.set("uNormalMap", int(kUnitNormal));
        }
        if (finestGloss) {
            finestGloss->bind(kUnitGloss);
            p.set("uGlossMap", int(kUnitGloss));
        }
    } else {
        // In role order, as the named calls did before (normal, gloss, toksvig, B, M, CLEAN).
        for (const auto& [role, gpu] : baked)
            bindBaked(role, gpu);
    }
    if (detail && f.detailMap) {
        detail->texture.bind(kUnitDetail);
        p.set("uDetailMap", int(kUnitDetail));
    }
    if (specular && f.specularTexture) {
        specular->bind(kUnitSpecular);
        p.set("uSpecularMap", int(kUnitSpecular));
    }
    // The ubershader's switches (ignored by specialized programs, which have no such uniforms).
    p.set("uMethod", int(f.method));
    p.set("uNdf", int(f.ndf));
    p.set("uFresnel", int(f.fresnel));
    p.set("uVisibility", int(f.visibility));
    p.set("uSpecularAa", int(f.specularAa));
    p.set("uDebugView", int(f.debugView));
    p.set("uPointLightCount", f.pointLights);
    p.set("uHasAmbient", int(f.environment == EnvironmentKind::ConstantAmbient));
    p.set("uHasNormalMap", int(f.normalMap));
    p.set("uHasDetailMap", int(f.detailMap));
    p.set("uHasGlossMap", int(f.glossMap));
    p.set("uHasSpecularMap", int(f.specularTexture));
    p.set("uHasDiffuse", int(!f.metalOnly));
    p.set("uHasDiffuseAa", int(f.diffuseAa));
    setEnvironmentUniforms(p, f);
}

Status Renderer::Impl::drawMaterial(const FeatureSet& f, const Program& p, int width, int height,
                                    glm::vec2 jitterNdc, bool reference, bool withBackground) {
    if (auto s = ensureTarget(hdr, width, height, true); !s) return s;
    beginMaterialPass(*hdr);
    if (withBackground) drawBackground(width, height, false);
    auto drawn = drawnMesh(height);
    if (!drawn) return Error{drawn.error()};
    p.use();
    setMaterialUniforms(p, f, width, height, jitterNdc, reference);
    (*drawn)->draw();
    glDisable(GL_DEPTH_TEST);
    return {};
}

void Renderer::Impl::drawWeighted(Framebuffer& target, const Framebuffer& source, float weight, bool add) {
    target.bind();
    if (add) {
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE);
        glBlendEquation(GL_FUNC_ADD);
    } else {
        glDisable(GL_BLEND);
    }
    accumulate->use();
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, source.colorTexture());
    accumulate->set("uSource", 0);
    accumulate->set("uWeight", weight);
    fullscreen->draw();
    glDisable(GL_BLEND);
}

Status Renderer::Impl::accumulateReference(int width, int height, int samples, bool withBackground) {
    if (auto s = prepareFinest(); !s) return s;
    FeatureSet f = features;
    f.referenceMode = true;
    f.debugView = DebugView::None;
    auto reference = materialProgram(f);
    if (!reference) return Error{reference.error()};
    if (auto s = ensureTarget(accumulation, width, height, false); !s) return s;
    accumulation->bind();
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    for (int i = 0; i < samples; ++i) {
        float jx = 0.0f, jy = 0.0f;
        // Halton from index 1 (index 0 is the corner (0, 0)); centred on the pixel centre.
        haltonPoint(i + 1, jx, jy);
        // A pixel is 2/size wide in normalized device coordinates.
        const glm::vec2 jitterNdc((jx - 0.5f) * 2.0f / float(width), (jy - 0.5f) * 2.0f / float(height));
        if (auto s = drawMaterial(f, **reference, width, height, jitterNdc, true, withBackground); !s)
            return s;
        drawWeighted(*accumulation, *hdr, 1.0f / float(samples), true);
    }
    return {};
}

namespace {

// Binds the target for its final pass, with its scissor rectangle when it has one.
void bindTarget(const RenderTarget& target) {
    glBindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
    glViewport(0, 0, target.width, target.height);
    if (target.hasScissor()) {
        glEnable(GL_SCISSOR_TEST);
        glScissor(target.scissorX, target.scissorY, target.scissorWidth, target.scissorHeight);
    } else {
        glDisable(GL_SCISSOR_TEST);
    }
}

} // namespace

// The frame's view in one pass: the material program's DISPLAY_OUTPUT variant writes display values
// (tonemap.frag's transform) into an 8-bit target with its own depth, copied into the caller's target
// (its scissor kept). What the HDR target and the display pass gave, without writing and reading a
// float target: the background stays black (the transform of 0).
Status Renderer::Impl::drawFused(const RenderTarget& target) {
    auto fused = materialProgram(features, true);
    if (!fused) return Error{fused.error()};
    const int width = target.interactive ? std::max(1, (target.width + 1) / 2) : target.width;
    const int height = target.interactive ? std::max(1, (target.height + 1) / 2) : target.height;
    std::optional<Framebuffer>& out = target.interactive ? displayInteractive : display;
    if (auto s = ensureTarget(out, width, height, true, ColorFormat::Rgba8); !s) return s;
    auto drawn = drawnMesh(height);
    if (!drawn) return Error{drawn.error()};
    beginMaterialPass(*out);
    drawBackground(width, height, true);
    (*fused)->use();
    setMaterialUniforms(**fused, features, width, height, glm::vec2(0.0f), false);
    // tonemap.frag takes the linear scale 2^EV.
    (*fused)->set("uExposure", std::exp2(scene.exposure));
    (*drawn)->draw();
    glDisable(GL_DEPTH_TEST);
    bindTarget(target); // binds it for reading too: read from the display target
    glBindFramebuffer(GL_READ_FRAMEBUFFER, out->id());
    glBlitFramebuffer(0, 0, width, height, 0, 0, target.width, target.height, GL_COLOR_BUFFER_BIT,
                      target.interactive ? GL_LINEAR : GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, target.framebuffer);
    glDisable(GL_SCISSOR_TEST);
    return {};
}

Status Renderer::Impl::drawHdr(int width, int height, bool withBackground) {
    if (!hasScene || !program) return Error{"no scene to render"};
    stochasticSample = 0;
    if (!stochasticMixture() || stochasticPasses() == 1)
        return drawMaterial(features, *program, width, height, glm::vec2(0.0f), false, withBackground);
    // Filtering after shading: each pass shades one texel of each pixel's trilinear footprint (its
    // own random numbers), and the passes' average converges to the filter applied to the shading,
    // as temporal anti-aliasing accumulates it over frames. The average ends in the HDR target.
    const int samples = stochasticPasses();
    if (auto s = ensureTarget(stochasticSum, width, height, false); !s) return s;
    stochasticSum->bind();
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    for (int i = 0; i < samples; ++i) {
        stochasticSample = i;
        if (auto s = drawMaterial(features, *program, width, height, glm::vec2(0.0f), false, withBackground);
            !s)
            return s;
        drawWeighted(*stochasticSum, *hdr, 1.0f / float(samples), true);
    }
    stochasticSample = 0;
    drawWeighted(*hdr, *stochasticSum, 1.0f, false);
    return {};
}

Status Renderer::Impl::drawProgressive(int width, int height) {
    if (!hasScene || !program) return Error{"no scene to render"};
    const bool carryOn = progressiveCount > 0 && progressiveScene && *progressiveScene == scene &&
                         progressiveSum && progressiveSum->width() == width &&
                         progressiveSum->height() == height;
    if (!carryOn) {
        progressiveScene = scene;
        progressiveCount = 0;
    }
    if (progressiveCount < stochasticPasses()) {
        // Pass i is drawHdr's pass i: the same random numbers, so the average converges to its image.
        stochasticSample = progressiveCount;
        const Status drawn = drawMaterial(features, *program, width, height, glm::vec2(0.0f), false, true);
        stochasticSample = 0;
        if (!drawn) return drawn;
        if (auto s = ensureTarget(progressiveSum, width, height, false); !s) return s;
        drawWeighted(*progressiveSum, *hdr, 1.0f, progressiveCount > 0);
        ++progressiveCount;
    }
    // Another call (a meter's image, a grab) may have left the HDR target another size since.
    if (auto s = ensureTarget(hdr, width, height, true); !s) return s;
    drawWeighted(*hdr, *progressiveSum, 1.0f / float(progressiveCount), false);
    return {};
}

// Scene::environmentBackground: the environment in each pixel's view direction, from the background's
// own cube or level 0 of the lighting's, drawn into the bound material target after its clear and
// before the mesh (no depth written, so the mesh covers it). Nothing without an environment map.
void Renderer::Impl::drawBackground(int width, int height, bool displayOutput) {
    if (!scene.environmentBackground || !usesEnvironmentMap(features.environment)) return;
    const CubeMapTexture* cube = envBackground ? &*envBackground : lightingCube(features.environment);
    const Program* p = displayOutput ? backgroundDisplayProgram : backgroundProgram;
    if (!cube || !p) return;
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    p->use();
    cube->bind(kUnitEnvironment);
    p->set("uEnvironment", int(kUnitEnvironment));
    setEnvironmentTurnAndScale(*p);
    p->set("uInverseViewProjection", glm::inverse(cameraViewProjection(width, height)));
    p->set("uExposure", std::exp2(scene.exposure));
    fullscreen->draw();
    glDepthMask(GL_TRUE);
    glEnable(GL_DEPTH_TEST);
    setFaceCulling();
}

Status Renderer::Impl::displayPass(const RenderTarget& target, const Framebuffer& source, bool dataView) {
    bindTarget(target);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, source.colorTexture());
    if (dataView) {
        accumulate->use();
        accumulate->set("uSource", 0);
        accumulate->set("uWeight", 1.0f);
    } else {
        tonemap->use();
        tonemap->set("uHdr", 0);
        // tonemap.frag takes the linear scale 2^EV.
        tonemap->set("uExposure", std::exp2(scene.exposure));
    }
    fullscreen->draw();
    glDisable(GL_SCISSOR_TEST);
    return {};
}

Renderer::Renderer()
    : m_impl(std::make_unique<Impl>()) {}

Renderer::~Renderer() = default;

Result<std::unique_ptr<Renderer>> Renderer::create() {
    std::unique_ptr<Renderer> r(new Renderer());
    Impl& impl = *r->m_impl;
    auto accumulate = impl.programs.get("fullscreen.vert", "accumulate.frag", {});
    if (!accumulate) return Error{accumulate.error()};
    auto heatmap = impl.programs.get("fullscreen.vert", "heatmap.frag", {});
    if (!heatmap) return Error{heatmap.error()};
    auto tonemap = impl.programs.get("fullscreen.vert", "tonemap.frag", {});
    if (!tonemap) return Error{tonemap.error()};
    auto background = impl.programs.get("fullscreen.vert", "background.frag", {});
    if (!background) return Error{background.error()};
    auto backgroundDisplay =
        impl.programs.get("fullscreen.vert", "background.frag", {{"DISPLAY_OUTPUT", "1"}});
    if (!backgroundDisplay) return Error{backgroundDisplay.error()};
    impl.accumulate = *accumulate;
    impl.heatmap = *heatmap;
    impl.tonemap = *tonemap;
    impl.backgroundProgram = *background;
    impl.backgroundDisplayProgram = *backgroundDisplay;
    impl.fullscreen = std::make_unique<FullscreenTriangle>();
    return r;
}

Status Renderer::setScene(const Scene& requested) {
    Impl& impl = *m_impl;
    Scene scene = requested;
    const MaterialSettings& want = requested.material;
    impl.drawingStale = false;
    if (impl.backgroundBakes && impl.bakedMaterial && want.normalMap && want.normalMap->texelCount() > 0) {
        // Never bake on the caller's thread once something is baked: until the new bake is in,
        // the material's baked inputs (maps, method, power, encoding) stay the last baked ones,
        // the rest (colours, view, light) follow the request.
        auto ready = impl.backgroundBake(want);
        if (!ready) return Error{ready.error()};
        impl.drawingStale = !*ready;
        if (!*ready) {
            const MaterialSettings& b = *impl.bakedMaterial;
            scene.material.normalMap = b.normalMap;
            scene.material.glossMap = b.glossMap;
            scene.material.method = b.method;
            scene.material.methodParams = b.methodParams;
            scene.material.basePower = b.basePower;
            scene.material.glossEncoding = b.glossEncoding;
        }
    }
    // On failure the previous scene stays the one drawn.
    Scene previous = std::move(impl.scene);
    impl.scene = scene;
    impl.heatmapReferenceValid = false;
    auto fail = [&](Status status) {
        impl.scene = std::move(previous);
        return status;
    };
    if (auto s = impl.prepareMesh(); !s) return fail(s);
    if (auto s = impl.prepareBake(); !s) return fail(s);
    if (auto s = impl.prepareMaps(); !s) return fail(s);
    const FeatureSet f = scene.features();
    if (auto s = impl.prepareEnvironment(f.environment); !s) return fail(s);
    auto program = impl.materialProgram(f);
    if (!program) return fail(Error{program.error()});
    impl.features = f;
    impl.program = *program;
    impl.hasScene = true;
    return {};
}

Result<bool> Renderer::replaceGloss(const MaterialSettings& material, const LiveGlossBake& live,
                                    const std::vector<TexelRect>* dirty) {
    return m_impl->replaceGloss(material, live, dirty);
}

std::shared_ptr<const std::vector<float>> Renderer::drawnGlossMap() const {
    return m_impl->bakeKey ? m_impl->bakeKey->glossMap : nullptr;
}

void Renderer::setBackgroundBakes(bool on, std::function<void()> onReady) {
    m_impl->backgroundBakes = on;
    m_impl->onBakeReady = std::move(onReady);
}

void Renderer::setMaxTextureSize(int size) {
    m_impl->maxTextureSize = std::max(size, 0);
}

bool Renderer::progressiveDone() const {
    return !m_impl->progressiveLast || m_impl->progressiveCount >= m_impl->stochasticPasses();
}

int Renderer::progressivePasses() const {
    return m_impl->progressiveCount;
}

bool Renderer::bakePending() const {
    return m_impl->drawingStale;
}

double Renderer::bakeProgress() const {
    const auto& pending = m_impl->pending;
    return pending && !pending->cancel->load() ? pending->progress->load() : 0.0;
}

void Renderer::setUseUbershader(bool on) {
    m_impl->useUbershader = on;
}

const Scene& Renderer::scene() const {
    return m_impl->scene;
}

Status Renderer::render(const RenderTarget& target) {
    Impl& impl = *m_impl;
    if (!impl.hasScene) return Error{"no scene to render"};
    const auto start = Clock::now();
    // A host context (the studio's) may leave a scissor on: the off-screen passes draw everything.
    glDisable(GL_SCISSOR_TEST);
    const DebugView view = impl.features.debugView;
    impl.progressiveLast = false;
    if (view == DebugView::None && impl.stochasticMixture() && impl.stochasticPasses() > 1) {
        // The passes are averaged in HDR, then shown (the fused pass would average display values):
        // all of them now, or the next one added to those of the calls before (progressive).
        if (target.progressive && !target.interactive) {
            if (auto s = impl.drawProgressive(target.width, target.height); !s) return s;
            impl.progressiveLast = true;
        } else if (auto s = impl.drawHdr(target.width, target.height, true); !s) {
            return s;
        }
        if (auto s = impl.displayPass(target, *impl.hdr, false); !s) return s;
        glFinish();
        impl.lastMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        return {};
    }
    if (view == DebugView::None) {
        if (auto s = impl.drawFused(target); !s) return s;
        glFinish();
        impl.lastMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        return {};
    }
    if (auto s = impl.drawHdr(target.width, target.height, false); !s) return s;
    if (view == DebugView::ErrorHeatmap) {
        // The reference reuses the HDR target, so it is accumulated first (and cached until the
        // scene or the size changes), copied aside, and the method's image drawn again after it.
        const int samples = std::clamp(impl.scene.heatmapReferenceSamples, 1, kMaxReferenceSamples);
        if (!impl.heatmapReferenceValid || impl.heatmapReference->width() != target.width ||
            impl.heatmapReference->height() != target.height) {
            if (auto s = impl.accumulateReference(target.width, target.height, samples, false); !s) return s;
            if (auto s = ensureTarget(impl.heatmapReference, target.width, target.height, false); !s)
                return s;
            impl.drawWeighted(*impl.heatmapReference, *impl.accumulation, 1.0f, false);
            impl.heatmapReferenceValid = true;
            if (auto s = impl.drawHdr(target.width, target.height, false); !s) return s;
        }
        bindTarget(target);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_BLEND);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, impl.hdr->colorTexture());
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, impl.heatmapReference->colorTexture());
        impl.heatmap->use();
        impl.heatmap->set("uCurrent", 0);
        impl.heatmap->set("uReference", 1);
        impl.heatmap->set("uFullScale", impl.scene.heatmapFullScale);
        impl.fullscreen->draw();
        glDisable(GL_SCISSOR_TEST);
        glActiveTexture(GL_TEXTURE0);
    } else {
        const bool dataView = view == DebugView::Power || view == DebugView::Normals ||
                              view == DebugView::MipLevel || view == DebugView::Variance ||
                              view == DebugView::Uv;
        if (auto s = impl.displayPass(target, *impl.hdr, dataView); !s) return s;
    }
    glFinish();
    impl.lastMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return {};
}

Result<std::vector<float>> Renderer::renderToImage(int width, int height, ImageKind kind) {
    Impl& impl = *m_impl;
    if (!impl.hasScene) return Error{"no scene to render"};
    if (kind == ImageKind::Display || impl.features.debugView == DebugView::ErrorHeatmap) {
        auto fb = Framebuffer::create(width, height, ColorFormat::Rgba8, false);
        if (!fb) return Error{fb.error()};
        if (auto s = render(RenderTarget{fb->id(), width, height}); !s) return Error{s.error()};
        return fb->readRgbaFloat();
    }
    const auto start = Clock::now();
    if (auto s = impl.drawHdr(width, height, impl.features.debugView == DebugView::None); !s)
        return Error{s.error()};
    glFinish();
    impl.lastMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return impl.hdr->readRgbaFloat();
}

Result<std::vector<float>> Renderer::renderReference(int width, int height, int samplesPerPixel,
                                                     ImageKind kind) {
    Impl& impl = *m_impl;
    if (!impl.hasScene) return Error{"no scene to render"};
    if (samplesPerPixel < 1 || samplesPerPixel > kMaxReferenceSamples)
        return Error{"reference samples per pixel must lie in 1.." + std::to_string(kMaxReferenceSamples)};
    if (auto s = impl.accumulateReference(width, height, samplesPerPixel, true); !s) return Error{s.error()};
    if (kind == ImageKind::Hdr) return impl.accumulation->readRgbaFloat();
    auto fb = Framebuffer::create(width, height, ColorFormat::Rgba8, false);
    if (!fb) return Error{fb.error()};
    if (auto s = impl.displayPass(RenderTarget{fb->id(), width, height}, *impl.accumulation, false); !s)
        return Error{s.error()};
    return fb->readRgbaFloat();
}

Status Renderer::renderReference(const RenderTarget& target, int samplesPerPixel) {
    Impl& impl = *m_impl;
    if (!impl.hasScene) return Error{"no scene to render"};
    if (samplesPerPixel < 1 || samplesPerPixel > kMaxReferenceSamples)
        return Error{"reference samples per pixel must lie in 1.." + std::to_string(kMaxReferenceSamples)};
    const auto start = Clock::now();
    glDisable(GL_SCISSOR_TEST);
    if (auto s = impl.accumulateReference(target.width, target.height, samplesPerPixel, true); !s) return s;
    if (auto s = impl.displayPass(target, *impl.accumulation, false); !s) return s;
    glFinish();
    impl.lastMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return {};
}

double Renderer::lastFrameMs() const {
    return m_impl->lastMs;
}

int Renderer::lastSphereSegments() const {
    return m_impl->lastSphereSegments;
}

const FeatureSet& Renderer::features() const {
    return m_impl->features;
}

std::string Renderer::explainProgram() {
    if (!m_impl->program) return "no program (no scene set)\n";
    return explain(m_impl->features, *m_impl->program);
}

const Program* Renderer::program() const {
    return m_impl->program;
}

int Renderer::bakeCount() const {
    return m_impl->bakes;
}

int Renderer::prefilterCount() const {
    return m_impl->prefilters;
}

double Renderer::lastEnvironmentMs() const {
    return m_impl->lastEnvironmentMs;
}

ProgramCache& Renderer::programCache() {
    return m_impl->programs;
}

} // namespace burnish::render
