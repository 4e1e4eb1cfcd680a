// What the renderer draws: a mesh seen by an orbit camera, lit by a directional light, point
// lights and an optional constant ambient, with one material (specular colour, gloss, normal maps,
// prefiltering method and BRDF terms). Plain data: the renderer derives its FeatureSet from it and
// bakes only what changed.
#pragma once

#include <burnish/core/env/cube.h>
#include <burnish/core/env/prefilter.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/prefilter/normal_pyramid.h>
#include <burnish/core/util/result.h>
#include <burnish/render/features.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace burnish::render {

/// An orbit camera around `target`: yaw about +y (0 looks along −z from +z), pitch above the
/// horizon, both in degrees; `distance` from the target pushes the object away to show
/// minification; vertical field of view in degrees.
struct OrbitCamera {
    float yawDegrees = 30.0f;
    float pitchDegrees = 20.0f;
    float distance = 3.0f;
    float fovDegrees = 40.0f;
    glm::vec3 target{0.0f};

    glm::vec3 position() const;
    glm::mat4 view() const;
    /// Perspective projection for the aspect ratio; near and far planes bracket a scene of radius
    /// `sceneRadius` around the target.
    glm::mat4 projection(float aspect, float sceneRadius) const;
    /// The vertical field of view the projection uses: fovDegrees within 1°..170°, in radians.
    float fovYRadians() const;

    friend bool operator==(const OrbitCamera&, const OrbitCamera&) = default;
};

struct DirectionalLight {
    glm::vec3 direction{0.4f, 0.7f, 0.6f}; // towards the light; normalized when used
    glm::vec3 color{1.0f};                 // linear
    float intensity = 1.0f; // in the π light units: a white Lambert facing it shows `intensity`

    friend bool operator==(const DirectionalLight&, const DirectionalLight&) = default;
};

struct PointLight {
    glm::vec3 position{0.0f, 2.0f, 2.0f};
    glm::vec3 color{1.0f};
    float intensity = 4.0f; // radiance scale at distance 1 (inverse-square falloff)

    friend bool operator==(const PointLight&, const PointLight&) = default;
};

/// A specular colour texture: linear F0, RGB floats, row-major, top row first.
struct SpecularColorMap {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;
};

struct MaterialSettings {
    glm::vec3 specularColor{0.04f}; // linear F0
    /// Metal: no diffuse (the "pure metal" shader); the specular colour carries the colour.
    bool metal = false;
    glm::vec3 albedo{0.5f}; // linear diffuse albedo (ignored for metals)
    /// Authored Blinn-Phong power where there is no gloss map (the base power s of the methods).
    double basePower = 1024.0;
    /// Encoding of the gloss map and of every baked gloss texture.
    GlossEncoding glossEncoding = GlossEncoding::blackOps();
    Method method = Method::VarianceToGloss;
    MethodParams methodParams;
    /// The per-mip filter the bake applies to the moments (BakeOptions::pyramid.kernel); none: the
    /// method's default (defaultKernel: box for the fitted lobe, tent for the rest), as a bake's.
    std::optional<FilterKernel> kernel;
    /// The tangent-space normal map, or none (a flat surface with the base power).
    std::shared_ptr<const NormalMap> normalMap;
    /// An optional detail normal map, tiled `detailUvScale` times over the base map.
    std::shared_ptr<const NormalMap> detailMap;
    float detailUvScale = 4.0f;
    /// An optional authored gloss map (in glossEncoding), one value per texel of the normal map.
    std::shared_ptr<const std::vector<float>> glossMap;
    /// An optional specular colour texture (replaces specularColor).
    std::shared_ptr<const SpecularColorMap> specularMap;
    /// Texture tiling on top of the mesh's UV repeat.
    float uvScale = 1.0f;
    NdfTerm ndf = NdfTerm::BlinnPhong;
    FresnelTerm fresnel = FresnelTerm::Schlick;
    VisibilityTerm visibility = VisibilityTerm::None;
    bool diffuseAa = false;
    SpecularAa specularAa = SpecularAa::None;
    /// How the mixture's textures are filtered: their moments by the hardware (lobes of one slot
    /// merge), or after shading (MixtureFiltering::Stochastic: each pass shades one texel of the
    /// trilinear footprint per pixel, and `mixtureSamples` passes are averaged, as temporal
    /// anti-aliasing would). The ubershader always filters the moments.
    MixtureFiltering mixtureFiltering = MixtureFiltering::Moments;
    int mixtureSamples = 16; // passes averaged under MixtureFiltering::Stochastic, 1..4096

    /// Sets the base power from a gloss value in glossEncoding (clamped to [0, 1]).
    void setGloss(double gloss) { basePower = glossEncoding.power(gloss); }

    friend bool operator==(const MaterialSettings&, const MaterialSettings&) = default;
};

/// Where an environment's radiance comes from.
enum class EnvironmentSourceKind {
    ProceduralStudio, // core's proceduralStudioEnvironment
    File,             // an equirectangular HDR (EXR, HDR, float TIFF) read by loadEquirectEnvironment
    Cube,             // a cube already in memory (level 0 is used)
};

/// The environment of EnvironmentKind::Prefiltered and ::FilteredImportanceSampling.
struct EnvironmentMap {
    EnvironmentSourceKind source = EnvironmentSourceKind::ProceduralStudio;
    std::filesystem::path path;          // for File
    std::shared_ptr<const CubeMap> cube; // for Cube (its identity is the cache key)
    /// Face size of the cube made from the procedural studio or a file (a power of two).
    int faceSize = 64;
    /// Rotation of the environment about +y, in degrees (a feature at azimuth φ moves to φ + rotation).
    float rotationDegrees = 0.0f;
    /// Radiance scale (linear).
    float intensity = 1.0f;
    /// The lobe each prefiltered mip is filtered with (core's LobeModel); Blinn-Phong matches the
    /// material's Blinn-Phong power at normal incidence, Phong is read with a quarter of the power.
    LobeModel lobe = LobeModel::BlinnPhong;
    /// The power per mip: the material's gloss encoding (Lazarov: the mip is chosen from gloss), or
    /// topPower·powerDrop^m (Lagarde's Cubemapgen setting).
    bool mipsFollowGloss = true;
    double topPower = 2048.0;
    double powerDrop = 0.25;
    /// PrefilterOptions::lobeCutoff: the lobe is cut where it falls below this fraction of its peak.
    /// 1e-3 leaves about 0.1% of the lobe's energy out (invisible) and prefilters a third faster than
    /// core's default of 1e-5.
    double lobeCutoff = 1e-3;
    /// Taps per pixel of EnvironmentKind::FilteredImportanceSampling (1..kMaxFisSamples).
    int fisSamples = 64;
    /// Face size of the cube drawn as the background (Scene::environmentBackground), made from the
    /// same source when larger than faceSize (kBackdropFaceSize for a display); otherwise (and for
    /// a Cube source) the background is level 0 of the cube the lighting reads.
    int backgroundFaceSize = 0;

    friend bool operator==(const EnvironmentMap&, const EnvironmentMap&) = default;
};

/// The background's face size for a display (the studio, `burnish render --env-background`): sharp
/// at a 1920-pixel view's usual field of view (a 90° face over 512 texels).
inline constexpr int kBackdropFaceSize = 512;

/// The linear F0 of a calibrated material of core's table (materials.h), by name (case-insensitive);
/// a range gives its middle. Errors: an unknown name.
Result<glm::vec3> calibratedSpecularColor(std::string_view name);

/// What a render's peak memory is estimated from, known before any image is decoded.
struct RenderMemoryInput {
    std::uint64_t mapTexels = 0; // the normal map's (and a gloss map's, the same size)
    int frameWidth = 0, frameHeight = 0;
    Method method = Method::VarianceToGloss;
    bool everyMethod = false; // --bench: each method baked and drawn in turn
    bool reference = false;   // the supersampled ground truth drawn too (--reference, --sequence, --compare)
};
/// The peak memory of one `burnish render`: the process with its OpenGL driver (220 MB), 80 bytes per map
/// texel (the decoded map, its pyramid, the baked chain and its textures), 340 more for the mixture (its
/// lobes) or 90 for LEAN and CLEAN (their slope moments), 40 for the reference's finest normals, and 45
/// per frame pixel. Measured peaks against this (core/bench/command_memory.sh, trak-rust1 resized, llvmpipe):
/// 512² map at 512×512 239 / 253 MB, 1024² 268 / 316, 2048² 524 / 567, 2048² with a 16-sample reference
/// 725 / 735, 1024² mixture 605 / 672, LEAN 356 / 410, at 2048×2048 436 / 493, --bench at 1280×720 602
/// / 701 MB (tests/render/test_renderer.cpp's RenderMemory holds them).
std::uint64_t estimatedRenderBytes(const RenderMemoryInput& input);

struct Scene {
    MeshKind mesh = MeshKind::Sphere;
    std::filesystem::path objPath; // for MeshKind::Obj
    OrbitCamera camera;
    DirectionalLight light;
    std::vector<PointLight> pointLights; // at most kMaxPointLights are drawn
    EnvironmentKind environment = EnvironmentKind::Off;
    glm::vec3 ambient{0.03f};      // constant radiance for EnvironmentKind::ConstantAmbient
    EnvironmentMap environmentMap; // for EnvironmentKind::Prefiltered and ::FilteredImportanceSampling
    /// Draw the environment behind the mesh (Prefiltered and FilteredImportanceSampling only): level 0
    /// of the cube the lighting reads, or of its own sharper cube (EnvironmentMap::backgroundFaceSize),
    /// turned and scaled as the lighting. Not in debug views or the error heatmap, whose comparisons
    /// are of the mesh alone.
    bool environmentBackground = false;
    /// Exposure in stops, applied in the tonemap pass.
    float exposure = 0.0f;
    MaterialSettings material;
    DebugView debugView = DebugView::None;
    /// Samples per pixel of the reference the error heatmap compares with.
    int heatmapReferenceSamples = 16;
    /// Absolute difference of linear luminance (HDR, before exposure) at the top of the heatmap's ramp.
    float heatmapFullScale = 0.5f;

    /// The studio's opening scene: the hammered sample normal map (core's makeSampleNormalMap) of
    /// `mapSize`² on the sphere, a dielectric of F0 0.04, variance-to-gloss at power 1024.
    static Scene sample(int mapSize = 256);

    /// The feature set the renderer compiles for this scene.
    FeatureSet features() const;

    friend bool operator==(const Scene&, const Scene&) = default;
};

} // namespace burnish::render
