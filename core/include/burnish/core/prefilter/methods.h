// Prefiltering methods: how each turns the moments of a footprint's normals into the specular
// lobe a shader evaluates, what it stores, and its NDF. The bake, the ground-truth evaluator and
// (later) the renderer's GLSL twins all use these definitions.
#pragma once

#include <burnish/core/prefilter/normal_pyramid.h>
#include <burnish/core/util/numeric.h>
#include <burnish/core/util/result.h>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish {

enum class Method {
    /// Renormalized mean normal, base power s unchanged: the texts' too-shiny baseline.
    /// Stores: the normal map's mips. Shader: D_s about n̂a.
    Naive,
    /// Toksvig's power from |Na| at run time. Stores: unnormalized mean normals (3 channels, no
    /// compression that changes length). Shader: p = f_t·s with f_t = |Na|/(|Na| + s(1−|Na|)).
    // Toksvig 2004 via Hill 2011
    Toksvig,
    /// Baked Toksvig map: f_t for a fixed power (default 100) stored in 8 bits, converted to s at
    /// run time. Stores: normal + one 8-bit channel. Shader: ft /= lerp(s/fixed_s, 1, ft); p = ft·s.
    // Hill 2011, "Specular Showdown in the Wild West"
    ToksvigMap,
    /// Projected variance added to the authored gloss as 1/(n+1), clamped, back to gloss.
    /// Stores: the gloss map. Shader: plain Blinn-Phong with the stored gloss.
    // Lazarov 2011: p = 1/(v + 1/(s+1)) − 1
    VarianceToGloss,
    /// LEAN: a Gaussian in slope space with Σ = M − BBᵀ + I/s about the normal whose slope is B.
    /// Stores: B (2) and M (3), 16-bit or float. Shader: slope-space Gaussian with the 1/h_z⁴ Jacobian.
    // Olano & Baker 2010, "LEAN Mapping"; Baker & Hill 2012
    Lean,
    /// CLEAN: LEAN with the isotropic per-axis variance ((M_xx + M_yy) − |B|²)/2 + 1/s.
    /// Stores: B (2) and (M_xx + M_yy)/2 (1, 16-bit). Shader: isotropic slope-space Gaussian.
    // Baker 2011, "Spectacular Specular: LEAN and CLEAN Specular Highlights" via Baker & Hill 2012
    Clean,
    /// von Mises–Fisher fit of the mean-normal length: κ = (3r − r³)/(1 − r²), variance 1/κ added
    /// to the base lobe (1/p = 1/s + 1/κ): the form Filament, Godot and Unity use for GGX roughness.
    /// Stores: the gloss map. Shader: plain Blinn-Phong (or GGX with α² = 2/(p+2)).
    // Banerjee et al. 2005 (κ estimate); Han et al. 2007, "Frequency Domain Normal Map Filtering"
    Vmf,
    /// Lobe mixture: up to 4 slope-space Gaussians per texel (lobe_mixture.h), each stored as
    /// premultiplied raw moments (w, w·b, w·M) so hardware filtering merges same-index lobes with
    /// exact moments. K = 1 stores LEAN's B and M. Stores: K + 2 RGBA16 textures.
    /// Shader: Σ_i w_i D_i(h) max(0, n_i·l), each D_i LEAN's slope-space Gaussian.
    // Runnalls 2007 and Williams & Maybeck 2003 (merge costs) on Olano & Baker 2010's lobes
    Mixture,
    /// Fitted one lobe: per texel and mip, the isotropic lobe about the renormalized mean normal whose
    /// shading (GGX for the roughness presets, Blinn-Phong for the others) is closest to the footprint's
    /// true shading in relative L1 over evaluate's light/view pairs; the base power and vMF's are among
    /// its candidates, so by that measure it is never worse than either (prefilter/fitted_lobe.h).
    /// Stores: the gloss map. Shader: plain GGX (or Blinn-Phong) with the stored gloss.
    Fitted,
};

// ---------------------------------------------------------------------------------------------
// The method table: for each method what it reads, what it stores and what its shader does. The
// bake, presets, export, evaluate's cost columns, the renderer and the studio's method list read
// it; role names ("normal", "lean-b", ...) exist only at the JSON and preset boundary.
//
// Adding a method: a Method value; its row in kMethodTable (methods.cpp) naming its textures (a new
// TextureRole with its row in kTextureTable if it stores something new); its lobe in methodLobe /
// methodPower; its texture rows in bake.cpp's row function for a new role; its GLSL twin in
// resources/shaders/methods.glsl (METHOD_<NAME>, with the sampler names of its textures' rows); and
// its tests (test_methods' table checks, a twin in test_twins, bake and evaluate cases).

/// A texture the bake produces. The order is the renderer's texture unit of each sampled role.
/// The mixture's roles: MixtureWeights holds w_0..w_3 (shares of the footprint, Σ = 1),
/// MixtureLobe0..3 lobe i's (w·b.x, w·b.y, w·M.xx, w·M.yy), MixtureCross w_i·M.xy of lobes 0..3.
enum class TextureRole {
    Normal,
    Gloss,
    Toksvig,
    LeanB,
    LeanM,
    Clean,
    LeanGloss,
    Detail,
    MixtureWeights,
    MixtureLobe0,
    MixtureLobe1,
    MixtureLobe2,
    MixtureLobe3,
    MixtureCross,
};
inline constexpr int kTextureRoleCount = 14;
/// The role's name in presets, bake.json and the studio ("normal", "gloss", "toksvig", "lean-b",
/// "lean-m", "clean", "lean-gloss", "detail", "mixture-weights", "mixture-lobe0".."mixture-lobe3",
/// "mixture-cross").
std::string_view roleName(TextureRole role);
std::optional<TextureRole> roleFromName(std::string_view name);

/// How a stored channel in [0, 1] decodes to its physical value (value = stored·scale + bias), with
/// the bake's binary slope scales sB (slopes) and sM (second moments).
enum class ChannelRange {
    Unit,         // scale 1, bias 0: gloss, the Toksvig factor, log variances, mixture weights
    Signed,       // scale 2, bias −1: normal components, the correlation ρ
    Slope,        // scale 2·sB, bias −sB: B.x, B.y, w·b
    Moment,       // scale sM, bias 0: M.xx, M.yy, M.avg, w·M.xx, w·M.yy
    SignedMoment, // scale 2·sM, bias −sM: M.xy, w·M.xy
    Variance,     // scale sV, bias 0: the detail map's variance
};
/// The binary scales a bake chose so every mip's values fit [0, 1] (powers of two).
struct ChannelScales {
    double slope = 1.0;    // sB
    double moment = 1.0;   // sM
    double variance = 1.0; // sV
};
/// The decode (value = stored·scale + bias) of a channel under the bake's scales.
struct ChannelDecodeRule {
    double scale = 1.0;
    double bias = 0.0;
};
ChannelDecodeRule channelDecode(ChannelRange range, const ChannelScales& scales);
struct ChannelSpec {
    std::string_view name; // "normal.x", "gloss", "B.x", "M.xx", ...
    ChannelRange range;
    /// Negated by the DirectX (−Y) green convention (symmetric decodes only).
    bool flipsWithGreen = false;
};

/// One texture's row: its channels, the precision it needs and how the shader reads it.
struct TextureSpec {
    TextureRole role;
    std::vector<ChannelSpec> channels;
    /// Needs 16-bit or float storage to keep the method's accuracy (LEAN's second moments).
    bool needsHighPrecision = false;
    /// The shader's sampler (empty: the texture is for export only, or bound by its own code, as the
    /// detail map is). The renderer uploads the decoded values (ChannelDecode): no decode uniforms.
    std::string_view sampler;
};
const TextureSpec& textureSpec(TextureRole role);

/// A texture of a method's row, with the description bake.json gives it. "{encoding}" stands for
/// the gloss encoding's formula, "{toksvig-power}" for the Toksvig map's fixed power.
struct MethodTexture {
    TextureRole role;
    std::string_view description;
};

/// What the method stores and fetches per shaded pixel, in the storage the texts recommend.
struct MethodStorage {
    int textureFetches = 0;
    double bytesPerTexel = 0.0; // at mip 0, block-compressed where the method allows it
    std::string_view layout;
};

/// One method's row.
struct MethodSpec {
    Method method;
    std::string_view name;
    /// One line: what the method stores and what its shader does (bake --help, reports).
    std::string_view description;
    /// The pyramid moments methodLobe and the stored textures read (MomentSet flags).
    unsigned moments;
    /// The textures it bakes, in bake order (the first is always the normal texture).
    std::vector<MethodTexture> textures;
    /// The normal texture holds the unnormalized mean normal Na (its length is the variance).
    bool unnormalizedNormal = false;
    /// The gloss texture holds the lobe's power (the method's adjustment), not the authored one.
    bool adjustsGloss = false;
    /// What its shader (methods.glsl) does with the fetched values.
    std::string_view shader;
    /// Its switch value in the shaders: methods.glsl #defines it as int(method).
    std::string_view glslMacro;
    MethodStorage storage;
};
const MethodSpec& methodSpec(Method method);
/// True when the method stores slope-space values (B, M): the bake then scans the slope scales.
bool storesSlopes(Method method);
/// True when the method's row names a texture of `role` (LEAN and CLEAN have no gloss texture).
bool hasTexture(Method method, TextureRole role);

/// All methods, in report order.
const std::vector<Method>& allMethods();
std::string_view methodName(Method method);

/// The per-mip filter a bake of `method` uses unless told otherwise: box for Fitted, tent for the rest.
/// The fitted lobe is fitted about the normal its chain stores, against the box footprint's truth, and
/// an engine rebuilds that normal by bilinear filtering of the chain: the box chain (three.js's own
/// generateMipmap) keeps the detail a pixel's footprint keeps, where the tent's smoother normals forced
/// wider lobes — in three.js on a sphere at 2× (six maps), the fitted lobe over the tent chain was 1.48×
/// three.js alone's error, over the box chain 1.08× (README, "One roughness for engines").
FilterKernel defaultKernel(Method method);
Result<Method> methodFromName(std::string_view name);
/// A one-line description of what the method stores and what its shader does.
std::string_view methodDescription(Method method);

/// The mixture's default lobe count: the knee of its error-against-cost curve on the real maps
/// (README, "Lobe mixtures").
inline constexpr int kDefaultMixtureLobes = 3;
/// The most lobes a mixture texel keeps (one RGBA texture each).
inline constexpr int kMaxMixtureLobes = 4;

struct MethodParams {
    /// Fixed power the Toksvig map is baked for (Hill 2011: "around 100 seems to work well").
    double toksvigMapPower = 100.0;
    /// Lobes per texel of the mixture (1..kMaxMixtureLobes of lobe_mixture.h; 1 is LEAN).
    int mixtureLobes = kDefaultMixtureLobes;
    /// The mixture's lobes also fitted to the shaded ground truth (eval/mixture_refine.h): a
    /// closer highlight, at many times the moment fit's bake time (for final exports).
    bool mixtureShadedFit = false;

    friend bool operator==(const MethodParams&, const MethodParams&) = default;
};

/// The mixture's lobe textures for K lobes: MixtureLobe0..MixtureLobe(K−1).
inline bool isMixtureLobeRole(TextureRole role) {
    return role >= TextureRole::MixtureLobe0 && role <= TextureRole::MixtureLobe3;
}
/// Any of the mixture's own textures: its weights, lobes and cross moments (contiguous roles).
inline bool isMixtureRole(TextureRole role) {
    return role >= TextureRole::MixtureWeights && role <= TextureRole::MixtureCross;
}
inline int mixtureLobeIndex(TextureRole role) {
    return int(role) - int(TextureRole::MixtureLobe0);
}
/// Whether the method's bake with these parameters writes `role` (its row names it and, for a
/// mixture lobe texture, the lobe index is below the lobe count).
bool bakesTexture(Method method, TextureRole role, const MethodParams& params);
/// The method's storage with these parameters (the mixture's depends on its lobe count).
MethodStorage methodStorage(Method method, const MethodParams& params);

/// A texel's lobe, as its shader would reconstruct it.
struct TexelLobe {
    /// The normal n̄ used for n̄·l (and the lobe axis of the isotropic methods).
    glm::vec3 normal{0.0f, 0.0f, 1.0f};
    /// Isotropic Blinn-Phong power (naive, Toksvig, Toksvig map, variance-to-gloss, vMF); for the
    /// Gaussian methods the power of the equal-variance isotropic lobe, 1/σ²_avg.
    double power = 1.0;
    /// Slope-space Gaussian (LEAN, CLEAN): mean B and covariance Σ (xx, yy, xy), 1/s included.
    bool slopeGaussian = false;
    glm::dvec2 slopeMean{0.0, 0.0};
    std::array<double, 3> slopeCov{0.0, 0.0, 0.0};
};

/// The lobe of `method` for a footprint with base power s. Finite for every input: |Na| → 0,
/// zero variance and s up to kMaxPower. The mixture and the fitted lobe need the footprint's normals
/// (lobe_mixture.h, fitted_lobe.h): from moments alone the mixture's lobe is LEAN's, and the fitted
/// lobe is the base power's (its first candidate, and its lobe at mip 0).
TexelLobe methodLobe(Method method, const NormalMoments& moments, double s, const MethodParams& params = {});

/// methodLobe(...).power alone, without the lobe's normal (what a gloss texture stores).
double methodPower(Method method, const NormalMoments& moments, double s, const MethodParams& params = {});

/// Base powers below this are treated as this, so 1/s stays finite (s = 0 is a flat-white lobe).
inline constexpr double kMinBasePower = 1e-6;

/// Variance-to-gloss's power for projected variance v and base power s: 1/(v + 1/(s+1)) − 1, with s
/// and the result clamped to [0, kMaxPower] (NaN → 0; s = 0, the flat-white lobe, needs no floor:
/// 1/(s+1) stays finite). The one home of the formula: the bake's rows, methodPower's
/// VarianceToGloss case and the painted variance offset (gloss.h varianceToGloss) all call it.
/// Branch-free (selects), so the bake's rows of it vectorise.
// Lazarov 2011, "Physically-based lighting in Call of Duty: Black Ops": v' = v + 1/(n+1)
inline double varianceToGlossPower(double v, double s) {
    s = clampPower(s);
    return clampPower(1.0 / (v + 1.0 / (s + 1.0)) - 1.0);
}

/// 1/s for the slope-space lobes (LEAN, CLEAN), s clamped as methodLobe clamps it (to
/// [kMinBasePower, kMaxPower]): the I/s their covariance adds.
inline double slopeInverseBasePower(double s) {
    return 1.0 / std::max(clampPower(s), kMinBasePower);
}

/// LEAN's slope covariance Σ = M − BBᵀ + I/s (xx, yy, xy) for base power s (clamped as
/// methodLobe clamps it): what methodLobe gives a LEAN lobe, without the rest of the lobe.
// Olano & Baker 2010, "LEAN Mapping": Σ = M − BBᵀ + I/s
inline std::array<double, 3> leanSlopeCovariance(const NormalMoments& moments, double s) {
    const double invS = slopeInverseBasePower(s);
    return {double(moments.slopeCov[0]) + invS, double(moments.slopeCov[1]) + invS,
            double(moments.slopeCov[2])};
}

/// The moments methodLobe and the method's stored textures read (MomentSet flags): its table
/// row's `moments`.
unsigned momentsNeeded(Method method);

/// The method's NDF at tangent-space half vector h (unit, z up), in projected-area normalization:
/// normalized Blinn-Phong (p+2)/(2π)(n̄·h)^p for the isotropic methods; for LEAN/CLEAN the
/// slope-space Gaussian exp(−½ dᵀΣ⁻¹d)/(2π√detΣ) / h_z⁴ with d = h.xy/h.z − B. 0 for h_z <= 0.
double methodNdf(const TexelLobe& lobe, const glm::dvec3& h);

/// The unit normal whose slope (n.x/n.z, n.y/n.z) is b: the axis of a slope-space lobe.
inline glm::dvec3 normalOfSlope(const glm::dvec2& b) {
    return glm::normalize(glm::dvec3(b.x, b.y, 1.0));
}

/// The slope-space Gaussian NDF on its own (used by methodNdf and the GLSL twin's test).
// Olano & Baker 2010, "LEAN Mapping"
double slopeGaussianNdf(const glm::dvec3& h, const glm::dvec2& mean, const std::array<double, 3>& cov);

/// von Mises–Fisher concentration from the mean-normal length r, clamped to [0, kMaxPower].
// Banerjee et al. 2005, "Clustering on the Unit Hypersphere using von Mises-Fisher Distributions":
// κ ≈ (3r − r³)/(1 − r²)
double vmfKappa(double r);

} // namespace burnish
