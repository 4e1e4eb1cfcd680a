// Prefiltering methods: how each turns the moments of a footprint's normals into the specular
// lobe a shader evaluates, what it stores, and its NDF. The bake, the ground-truth evaluator and
// (later) the renderer's GLSL twins all use these definitions.
#pragma once

#include <burnish/core/normal_pyramid.h>
#include <burnish/core/numeric.h>
#include <burnish/core/result.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <array>
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
};

/// All methods, in report order.
const std::vector<Method>& allMethods();
std::string_view methodName(Method method);
Result<Method> methodFromName(std::string_view name);
/// A one-line description of what the method stores and what its shader does.
std::string_view methodDescription(Method method);

struct MethodParams {
    /// Fixed power the Toksvig map is baked for (Hill 2011: "around 100 seems to work well").
    double toksvigMapPower = 100.0;
};

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
/// zero variance and s up to kMaxPower.
TexelLobe methodLobe(Method method, const NormalMoments& moments, double s, const MethodParams& params = {});

/// methodLobe(...).power alone, without the lobe's normal (what a gloss texture stores).
double methodPower(Method method, const NormalMoments& moments, double s, const MethodParams& params = {});

/// Base powers below this are treated as this, so 1/s stays finite (s = 0 is a flat-white lobe).
inline constexpr double kMinBasePower = 1e-6;

/// Variance-to-gloss's power for projected variance v and base power s: 1/(v + 1/(s+1)) − 1, s
/// clamped to [kMinBasePower, kMaxPower], the result to [0, kMaxPower]. Branch-free (selects), so
/// the bake's rows of it vectorise; methodPower's VarianceToGloss case.
// Lazarov 2011, "Physically-based lighting in Call of Duty: Black Ops": v' = v + 1/(n+1)
inline double varianceToGlossPower(double v, double s) {
    s = clampPower(s);
    s = s > kMinBasePower ? s : kMinBasePower;
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

/// The moments methodLobe and the method's stored textures read (MomentSet flags): the mean
/// alone for naive, Toksvig, the Toksvig map and vMF; the covariance for variance-to-gloss; the
/// slopes for LEAN and CLEAN.
unsigned momentsNeeded(Method method);

/// The method's NDF at tangent-space half vector h (unit, z up), in projected-area normalization:
/// normalized Blinn-Phong (p+2)/(2π)(n̄·h)^p for the isotropic methods; for LEAN/CLEAN the
/// slope-space Gaussian exp(−½ dᵀΣ⁻¹d)/(2π√detΣ) / h_z⁴ with d = h.xy/h.z − B. 0 for h_z <= 0.
double methodNdf(const TexelLobe& lobe, const glm::dvec3& h);

/// The slope-space Gaussian NDF on its own (used by methodNdf and the GLSL twin's test).
// Olano & Baker 2010, "LEAN Mapping"
double slopeGaussianNdf(const glm::dvec3& h, const glm::dvec2& mean, const std::array<double, 3>& cov);

/// von Mises–Fisher concentration from the mean-normal length r, clamped to [0, kMaxPower].
// Banerjee et al. 2005, "Clustering on the Unit Hypersphere using von Mises-Fisher Distributions":
// κ ≈ (3r − r³)/(1 − r²)
double vmfKappa(double r);

} // namespace burnish
