// Evaluate's inner loop: the value of many lobes, or of many finest normals' ground truth, for one
// direction pair, as structure-of-arrays with branch-free arithmetic that the compiler vectorises
// (exp by expNonPositive, log by log2Positive: no libm calls, no subnormal results). Each value is
// the scalar reference's (methodValue, mixtureValue, groundTruthTexel) within 1e-12 relative
// (test_evaluate.cpp), and values below e^-707 of the lobe's scale are 0.
#pragma once

#include <burnish/core/eval/evaluate.h>
#include <burnish/core/prefilter/fitted_lobe.h>
#include <burnish/core/prefilter/lobe_mixture.h>

#include <array>
#include <cstddef>
#include <vector>

namespace burnish {

/// The lobes of one variant at one level (or at its corner points), one entry per texel.
struct LobeTable {
    /// Blinn-Phong: D = (p+2)/(2π)·max(n·h, 0)^p (the isotropic methods). Gaussian: `slots` slope-space
    /// Gaussians per texel, each weighted by its share (LEAN and CLEAN: one slot of share 1; the
    /// mixture: K slots, empty ones of share 0).
    /// Ggx: ggxSpecularTerm with α = ggxAlphaFromPower(p) about n (the isotropic methods under --brdf ggx).
    /// GgxAnisotropic: ggxAnisotropicSpecularTerm about n with α_b in `power`, α_t in `alphaT` and
    /// t = (cosA, sinA, 0), b = (−sinA, cosA, 0) (the anisotropic fit, as engines shade it).
    /// GgxMixture: `slots` GGX lobes per texel, each its share (in `coef`) times ggxSpecularTerm about its
    /// normal with its α (in `power`): the mixture under --brdf ggx (mixtureGgxLobe).
    enum class Kind { BlinnPhong, Gaussian, Ggx, GgxAnisotropic, GgxMixture };
    Kind kind = Kind::BlinnPhong;
    int slots = 1;
    size_t count = 0;
    // Per texel (Blinn-Phong) or per slot and texel, slot-major: [slot·count + t].
    std::vector<double> nx, ny, nz;         // the normal of n·l (and of n·h for Blinn-Phong)
    std::vector<double> power, norm;        // Blinn-Phong: clampPower(p) and (p+2)/(2π); GGX: α in `power`
    std::vector<double> coef;               // Gaussian: share/(2π√det Σ), 0 for an empty slot or det <= 0
    std::vector<double> mx, my;             // Gaussian: mean slope
    std::vector<double> ixx, iyy, ixy;      // Gaussian: Σ⁻¹ (xx, yy, xy)
    std::vector<double> alphaT, cosA, sinA; // GgxAnisotropic

    /// The lobes under `brdf` (Ggx: isotropic lobes only; a slope-space lobe is a logic error).
    static LobeTable of(const std::vector<TexelLobe>& lobes, Brdf brdf = Brdf::BlinnPhong);
    static LobeTable of(const std::vector<DecodedMixture>& mixtures);
    /// Anisotropic GGX lobes, one per texel: its unit normal and lobe.
    static LobeTable ofAnisotropic(const std::vector<glm::dvec3>& normals,
                                   const std::vector<AnisotropicLobe>& lobes);
    /// Filtering after shading: point i is the blend of the mixtures texels[at[i][c]] with weights
    /// weights[c] (Σ weights[c]·mixture value), each of their lobes a slot of its own with its share
    /// times its texel's weight.
    static LobeTable ofBlends(const std::vector<DecodedMixture>& texels,
                              const std::vector<std::array<size_t, 4>>& at,
                              const std::array<double, 4>& weights);
    /// The mixture under GGX, `lobes` slots per texel (the rest of each array unread).
    using GgxMixtureTexel = std::array<MixtureGgxLobe, kMaxMixtureLobes>;
    static LobeTable ofGgxMixture(const std::vector<GgxMixtureTexel>& texels, int lobes);
    /// Filtering after shading under GGX: point i blends texels[at[i][c]] with weights[c], as ofBlends.
    static LobeTable ofGgxBlends(const std::vector<GgxMixtureTexel>& texels, int lobes,
                                 const std::vector<std::array<size_t, 4>>& at,
                                 const std::array<double, 4>& weights);
};

/// The stored lobes (mixtureGgxTexel per slot) of texel (x, y) of level k of a mixture fitted at base power
/// s, as burnish gltf writes them for an engine's GGX: storedTexel's slots with s's base variance.
using MixtureGgxStored = std::array<std::array<double, 4>, kMaxMixtureLobes>;
MixtureGgxStored mixtureGgxStored(const MixturePyramid& mix, const NormalMap& map, int k, int x, int y,
                                  double s);
/// Stored lobes (filtered or not) decoded as the engine does (mixtureGgxLobe, α0 of power s).
LobeTable::GgxMixtureTexel mixtureGgxDecoded(const MixtureGgxStored& stored, int lobes, double s);

/// out[i] = the value of lobe begin + i for direction pair d, i < end − begin.
void lobeValues(const LobeTable& table, size_t begin, size_t end, const DirectionPair& d, double* out);

} // namespace burnish
