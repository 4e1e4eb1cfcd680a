// The normal pyramid: per mip level and texel, the moments of the finest normals under the
// texel's footprint — mean normal Na, central second moments of n, and LEAN's slope mean B and
// slope covariance — from which every prefiltering method derives its lobe.
//
// Mip size rule: level k+1 is max(1, ⌊w_k/2⌋) × max(1, ⌊h_k/2⌋), down to 1×1. A parent texel x
// covers the children [⌊x·w_k/w_{k+1}⌋, ⌊(x+1)·w_k/w_{k+1}⌋) in each axis, so for power-of-two
// sizes a mip-k texel's footprint is the aligned 2^k×2^k block of finest texels, and for any
// size every finest texel belongs to exactly one texel of every level. Moments are exact
// averages over the footprint's finest texels (weighted by count where footprints differ).
//
// Accuracy: moments are combined with the pairwise (Chan et al.) update in double and stored as
// central moments in float, so a variance of 1e-9 survives next to a mean of 1, and the
// hierarchical sums keep 8k² and 16k² maps free of drift.
#pragma once

#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/util/texel_vector.h>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <string_view>
#include <vector>

namespace burnish {

/// Slopes b = n.xy/n.z use n.z clamped to at least this (normals within 0.6° of the horizon),
/// bounding |b| at 100 and LEAN's second moments at 1e4.
inline constexpr float kMinSlopeZ = 0.01f;

/// Moments of the finest normals n_i under one footprint.
struct NormalMoments {
    glm::vec3 mean{0.0f, 0.0f, 1.0f}; // Na = E[n]
    std::array<float, 6> cov{};       // E[(n−Na)(n−Na)ᵀ]: xx, yy, zz, xy, xz, yz
    glm::vec2 slope{0.0f, 0.0f};      // B = E[b], b = (n.x/n.z, n.y/n.z)
    std::array<float, 3> slopeCov{};  // E[(b−B)(b−B)ᵀ]: xx, yy, xy

    /// |Na|, in [0, 1].
    float lengthNa() const { return std::min(glm::length(mean), 1.0f); }
    /// Na/|Na|, or +z when |Na| is 0 (or not finite).
    glm::vec3 meanDirection() const {
        const float len = glm::length(mean);
        return len > 0.0f && std::isfinite(len) ? mean / len : glm::vec3(0.0f, 0.0f, 1.0f);
    }
    /// Projected variance about the mean direction, E[1 − (n_i·n̂a)²], computed from the central
    /// moments without cancellation (tr C − n̂ᵀCn̂), in [0, 1].
    // Lazarov 2011: v = (1/K) Σ (1 − (n_i·n̄)²)
    float projectedVariance() const { return projectedVarianceAbout(meanDirection()); }
    /// The same about a given unit direction n (projectedVariance with n = meanDirection()).
    float projectedVarianceAbout(const glm::vec3& n) const {
        const double trace = double(cov[0]) + double(cov[1]) + double(cov[2]);
        const double nCn =
            double(n.x) * n.x * cov[0] + double(n.y) * n.y * cov[1] + double(n.z) * n.z * cov[2] +
            2.0 * (double(n.x) * n.y * cov[3] + double(n.x) * n.z * cov[4] + double(n.y) * n.z * cov[5]);
        return float(std::clamp(trace - nCn, 0.0, 1.0));
    }
    /// LEAN's second slope moments M = E[bbᵀ] (xx, yy, xy).
    // Olano & Baker 2010, "LEAN Mapping": M = (B.x², B.y², B.x·B.y) filtered
    std::array<float, 3> slopeSecondMoments() const {
        return {slopeCov[0] + slope.x * slope.x, slopeCov[1] + slope.y * slope.y,
                slopeCov[2] + slope.x * slope.y};
    }

    /// Moments of a single unit normal. Inline: the mixture's bake reads each finest normal's slope
    /// three times (its fit, its lobe's slot, its texels), 48 million calls for a 4096² map.
    static NormalMoments ofNormal(const glm::vec3& n) {
        NormalMoments m;
        m.mean = n;
        const float z = std::max(n.z, kMinSlopeZ);
        m.slope = glm::vec2(n.x / z, n.y / z);
        return m;
    }
};

/// Weighted combination of footprints (weights >= 0, not all 0).
NormalMoments combineMoments(const NormalMoments* moments, const double* weights, size_t count);

enum class BorderMode { Wrap, Clamp };

/// The filter applied to each level's box moments before a method reads them.
/// Box: the footprint alone. Tent: 3×3 [1 2 1]² over the level's neighbours, standing in for the
/// hardware bilinear filter the shader will apply (Hill 2011; Baker & Hill 2012, "Baking
/// Variance": tent [Lazarov 2011] or Gaussian). Gaussian: 5×5, σ = 1 texel of the level.
enum class FilterKernel { Box, Tent, Gaussian };

/// "box", "tent" or "gaussian".
std::string_view kernelName(FilterKernel kernel);

/// The separable weights of a kernel: taps −radius..radius, summing to 1.
struct KernelTaps {
    int radius = 0;
    double w[5] = {1, 0, 0, 0, 0};
};
KernelTaps kernelTaps(FilterKernel kernel);

/// Index i mapped into [0, size) by the border mode.
int borderIndex(int i, int size, BorderMode border);

/// Which moments a pyramid computes, as bit flags; the mean normal Na always. A method reads only
/// some (momentsNeeded in methods.h), and the rest cost most of the work: the naive and Toksvig
/// methods need 3 of the 17 values. Moments not computed keep NormalMoments' defaults (zero
/// spread, zero slope); those computed are bit for bit what a full pyramid holds.
enum MomentSet : unsigned {
    kMomentsMean = 0,
    kMomentsCov = 1u,   // central second moments of n (projected variance)
    kMomentsSlope = 2u, // slope mean B and slope covariance (LEAN, CLEAN)
    kMomentsAll = 3u,
};

/// Floats per texel of a level's packed box moments for a moment set.
constexpr int momentStride(unsigned set) {
    return 3 + ((set & kMomentsCov) ? 6 : 0) + ((set & kMomentsSlope) ? 5 : 0);
}

struct PyramidOptions {
    BorderMode border = BorderMode::Wrap;
    FilterKernel kernel = FilterKernel::Tent;
    unsigned moments = kMomentsAll; // MomentSet flags
    /// false: the levels' extents and footprints alone, no box moments (every level's box empty),
    /// for a reader of footprints only (the mixture's own textures). Nothing may read moments then.
    bool boxMoments = true;
};

/// One level's extent and where its footprints lie in the finest level.
struct PyramidLevel {
    int width = 0;
    int height = 0;
    std::vector<int> xStart; // finest column where column x's footprint starts; size width+1
    std::vector<int> yStart; // finest row where row y's footprint starts; size height+1
    std::vector<int> xChild; // first column of level k−1 under column x; size width+1 (level 0: identity)
    std::vector<int> yChild; // first row of level k−1 under row y; size height+1
    /// Box moments, row-major, packed as momentStride(set) floats per texel: Na, then the
    /// covariance and then B and the slope covariance when the set holds them (a mean-only
    /// level takes 12 bytes a texel instead of a NormalMoments' 68). Empty for level 0: see
    /// NormalPyramid::boxMoments.
    TexelVector box;
};

class NormalPyramid {
public:
    /// Builds every level from the finest normals down to 1×1 (in parallel over rows).
    static NormalPyramid build(std::shared_ptr<const NormalMap> map, const PyramidOptions& options = {});

    int levelCount() const { return static_cast<int>(m_levels.size()); }
    const PyramidLevel& level(int k) const { return m_levels[static_cast<size_t>(k)]; }
    const PyramidOptions& options() const { return m_options; }
    const NormalMap& finest() const { return *m_map; }

    /// Box moments of texel (x, y) of level k (level 0 is derived from the normals).
    NormalMoments boxMoments(int k, int x, int y) const;
    /// Moments with the pyramid's kernel applied (equal to boxMoments for FilterKernel::Box).
    NormalMoments moments(int k, int x, int y) const;
    /// Calls fn(y, row) for every row of level k, row holding the kernel-filtered moments of its
    /// `width` texels (equal to moments(k, x, y) to float precision). Rows are computed in
    /// parallel blocks, four texels at a time in float, with sums taken about each texel's own
    /// mean normal and slope, so the relative precision of a variance does not depend on the
    /// mean's length (a 1e-9 variance beside |Na| = 1 keeps ~1e-6 relative accuracy); each
    /// texel's value is independent of the blocking and thread count. fn is called concurrently
    /// for distinct rows.
    void forEachMomentRow(int k, const std::function<void(int y, const NormalMoments* row)>& fn) const;
    /// Number of finest texels in the footprint of texel (x, y) of level k.
    int footprintCount(int k, int x, int y) const;
    /// Frees level k's box moments once nothing reads them again (a bake that has written level k:
    /// every coarser level was built when the pyramid was). Its geometry stays; reading its
    /// moments afterwards is an error the caller must not make.
    void releaseBox(int k);

private:
    std::shared_ptr<const NormalMap> m_map;
    PyramidOptions m_options;
    std::vector<PyramidLevel> m_levels;
};

} // namespace burnish
