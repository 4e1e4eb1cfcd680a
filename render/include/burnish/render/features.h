// The feature set of a scene: everything that decides which code the material program holds.
// One program is compiled per feature set, with numbered #defines injected after #version; a
// feature that is off emits no define, so its code (and its uniforms and samplers) is compiled out.
#pragma once

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/shading/fresnel.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/specular_aa.h>
#include <burnish/core/shading/visibility.h>
#include <burnish/render/shader_source.h>

#include <string>
#include <string_view>
#include <vector>

namespace burnish::render {

class Program;

enum class MeshKind { Sphere, Plane, Torus, Obj };
/// The environment's lighting: none, a constant radiance, the prefiltered radiance cube with SH9
/// irradiance (the mip read from the lobe's power), or filtered importance sampling of the
/// box-filtered source chain at shading time (Scene::environmentMap.fisSamples taps) with SH9 irradiance.
enum class EnvironmentKind { Off, ConstantAmbient, Prefiltered, FilteredImportanceSampling };
// The shading terms are core's (shading/ndf.h, fresnel.h, visibility.h, specular_aa.h), named here too.
using burnish::FresnelTerm;
using burnish::fresnelTermName;
using burnish::NdfTerm;
using burnish::ndfTermName;
using burnish::SpecularAa;
using burnish::specularAaName;
using burnish::VisibilityTerm;
using burnish::visibilityTermName;

enum class DebugView {
    None,
    LightingOnly, // white diffuse albedo: the lighting without the material's colour
    DiffuseOnly,
    SpecularOnly,
    Power,        // the lobe's Blinn-Phong power, log scale
    Normals,      // the shading normal in world space, n·0.5 + 0.5
    MipLevel,     // the level of detail the hardware picks for the normal map, colour ramp
    Variance,     // the lobe's variance 1/p, log scale
    ErrorHeatmap, // |this − supersampled reference| as a colour ramp (a second pass)
    Uv,           // the texture coordinate fract(uv) in rg and 1 in b (covered), unclamped: for picking
};

/// Largest number of point lights a program holds.
inline constexpr int kMaxPointLights = 4;

struct FeatureSet {
    MeshKind mesh = MeshKind::Sphere;
    int pointLights = 0; // 0..kMaxPointLights
    EnvironmentKind environment = EnvironmentKind::Off;
    bool normalMap = true;
    bool detailMap = false;
    bool glossMap = false;
    bool specularTexture = false; // specular colour from a texture instead of a constant
    bool metalOnly = false;       // no diffuse code at all (the texts' "pure metal" shader)
    Method method = Method::VarianceToGloss;
    NdfTerm ndf = NdfTerm::BlinnPhong;
    FresnelTerm fresnel = FresnelTerm::Schlick;
    VisibilityTerm visibility = VisibilityTerm::None;
    bool diffuseAa = false;
    SpecularAa specularAa = SpecularAa::None;
    DebugView debugView = DebugView::None;
    /// Ground truth: the finest normals (textureLod 0 everywhere) and the base power, no method.
    bool referenceMode = false;

    friend bool operator==(const FeatureSet&, const FeatureSet&) = default;
};

std::string_view meshKindName(MeshKind kind);
std::string_view environmentName(EnvironmentKind kind);
std::string_view debugViewName(DebugView view);

/// The #defines of a feature set: the numbered constants (METHOD_LEAN 4, ...), the switches
/// (METHOD METHOD_LEAN, NDF NDF_GGX, ...) and HAS_* = 1 for each feature that is on. A feature
/// that is off has no define. Deterministic: equal feature sets give equal define lists.
ShaderDefines defines(const FeatureSet& features);

/// The ubershader: every feature compiled in (UBERSHADER 1, all HAS_* on, kMaxPointLights lights),
/// the switches read from uniforms (uMethod, uNdf, ..., uHasDetailMap). Only to measure against.
ShaderDefines ubershaderDefines();

/// A human-readable account of a program: the features, the defines, and the active uniforms and
/// samplers queried from the linked program (glGetActiveUniform). Needs the program's context current.
std::string explain(const FeatureSet& features, const Program& program);

/// The active uniforms of a linked program as "type name" lines (sorted). Needs a current context.
std::vector<std::string> activeUniforms(const Program& program);

} // namespace burnish::render
