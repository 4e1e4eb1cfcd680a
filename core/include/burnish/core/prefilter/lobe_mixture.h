// Mixtures of slope-space Gaussian lobes per footprint: the fit behind the multi-lobe prefiltering
// method. LEAN puts one Gaussian in slope space on a footprint; a mip texel over grooves, bevels or
// a pitted plate covers two or three clusters of normals, which one lobe blurs together. Here each
// footprint keeps up to kMaxMixtureLobes lobes, each a weight w, a slope mean b and a slope
// covariance Σ with the base lobe's variance on the diagonal: 1/s as LEAN for one lobe, and for two or
// more the 1/(s + 2) whose Gaussian peaks as high as the Blinn-Phong lobe (mixtureBaseVariance).
//
// Lobes are held as premultiplied raw moments (w, w·b, w·(Σ + bbᵀ)), so adding the lobes of the
// same index of several texels (a mip reduction, or hardware bilinear/trilinear filtering of the
// stored textures) merges them with exact moments and keeps their energy.
//
// The fit is hierarchical and deterministic: level 0 has one lobe per finest normal; each texel
// above reduces the lobes of its children (up to 4K of them) to K by merging (exact moments), again and
// again, the cheapest pair, and equal lobes always merge. Level 1 prices a merge by the information it
// loses (Runnalls' bound on the KL divergence); the levels above by the squared error it makes in the
// lobes' sum (mixtureCriterion), under which a few light lobes strewn over steep slopes gather in a
// wide lobe of their own instead of widening the main ones: steep outlier normals keep their energy,
// where they reflect, without dragging a lobe's moments as they drag LEAN's, and every lobe's mean is
// its normals' own. Lobes are then put in a canonical order (by mean slope, x then y). Last, top-down,
// each texel's lobes move to the slots of the parent lobes they belong to most (the assignment of largest
// expected log-likelihood of each whole lobe's normals, its spread too, so weighted by its weight, under
// the slot's lobe as filtered), so the texels under one parent and the levels between give one cluster
// one slot, and filtering between texels and mips merges like with like.
#pragma once

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/normal_pyramid.h>

#include <glm/ext/vector_int2.hpp>
#include <glm/ext/vector_uint3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <functional>
#include <memory>
#include <new>
#include <optional>
#include <string_view>
#include <vector>

namespace burnish {

/// The slope variance of a finest normal's lobe of Blinn-Phong power s (clamped as slopeInverseBasePower
/// clamps it) in a mixture of k lobes: LEAN's 1/s for k = 1, so that one lobe is LEAN's exactly; for
/// k >= 2, 1/(s + 2), the Beckmann lobe's slope variance m²/2 for the Blinn-Phong one. Its Gaussian
/// peaks at (s + 2)/2π, the Blinn-Phong lobe's own peak, where 1/s gives s/2π: 3 % low at s = 64,
/// which is all the error left on smooth maps. Measured on 27 real maps (core/bench/mixture_study.py,
/// 324 cases per K, K = 3): the mean ratio to LEAN's error 0.447 -> 0.384, cases worse than LEAN
/// 6 -> 4 (dense directions 0.465 -> 0.424, between texels 0.724 -> 0.672); s + 1 gave 0.398, s + 3
/// 0.438, s + 4 0.502.
// Lazarov 2011, "Physically Based Lighting in Call of Duty: Black Ops": Beckmann m = sqrt(2/(n+2))
inline double mixtureBaseVariance(double s, int k) {
    return k <= 1 ? slopeInverseBasePower(s) : 1.0 / (std::max(clampPower(s), kMinBasePower) + 2.0);
}

/// How a renderer filters the mixture's textures between texels and mips.
enum class MixtureFiltering {
    /// Hardware bilinear and trilinear filtering of the stored moments: the lobes of one slot of the
    /// texels (and mips) around the sample merge into one lobe before shading.
    Moments,
    /// Filtering after shading: each sample shades the lobes of one texel of the bilinear (and
    /// trilinear) footprint, picked with the probability of its filter weight, so the expected value is
    /// the filter applied to the shaded values (mixtureValue of each texel), where no lobes merge. A
    /// frame is noisy; averaged over samples or frames (temporal anti-aliasing) it converges.
    // Pharr et al. 2024, "Filtering After Shading With Stochastic Texture Filtering": filter importance
    // sampling
    Stochastic,
};
/// "moments" or "stochastic".
const char* mixtureFilteringName(MixtureFiltering filtering);
/// The filtering named "moments" or "stochastic"; nothing for another name.
std::optional<MixtureFiltering> parseMixtureFiltering(std::string_view name);

/// The texel a sample shades under MixtureFiltering::Stochastic: its column, row and mip level.
struct StochasticTexel {
    int x = 0, y = 0, level = 0;
};
/// Filtering after shading's pick (the GLSL twin in methods.glsl, in float as the shader computes
/// it): of the texels that trilinear filtering of a texture of `levels` levels, level 0 `size0`
/// texels (each level half the last, at least 1), blends at uv with level of detail lod, the one of
/// three uniform numbers xi in [0, 1): the upper of the two levels around lod when xi.z < its fraction,
/// then the right texel of the bilinear pair when xi.x < the horizontal fraction, the lower one when
/// xi.y < the vertical one: each texel with the probability of its filter weight. The textures repeat.
// Pharr et al. 2024, "Filtering After Shading With Stochastic Texture Filtering": filter importance sampling
StochasticTexel stochasticTexel(glm::vec2 uv, float lod, glm::ivec2 size0, int levels, glm::vec3 xi);
/// Three uniform numbers in [0, 1) (multiples of 2^-24) from a pixel and a sample index: the pcg3d hash
/// of (x, y, sample), each word's top 24 bits (the GLSL twin stochasticNumbers in methods.glsl).
// Jarzynski & Olano 2020, "Hash Functions for GPU Rendering": pcg3d
glm::vec3 stochasticNumbers(glm::uvec3 v);

/// One lobe as premultiplied raw moments: w (a weight, here finest texels), w·b and w·M with
/// M = Σ + bbᵀ (xx, yy, xy). Adding two is merging them with exact moments.
struct LobeMoments {
    double w = 0.0;
    double bx = 0.0, by = 0.0;
    double mxx = 0.0, myy = 0.0, mxy = 0.0;

    LobeMoments& operator+=(const LobeMoments& o) {
        w += o.w;
        bx += o.bx;
        by += o.by;
        mxx += o.mxx;
        myy += o.myy;
        mxy += o.mxy;
        return *this;
    }
    /// The lobe with its weight times f (its mean and covariance unchanged): f·(w, w·b, w·M).
    LobeMoments scaled(double f) const { return {w * f, bx * f, by * f, mxx * f, myy * f, mxy * f}; }
    /// The slope mean b = (w·b)/w ((0, 0) for an empty lobe).
    glm::dvec2 mean() const;
    /// The slope covariance Σ = (w·M)/w − bbᵀ (xx, yy, xy), its variances at least `minVariance`
    /// and its correlation inside (−1, 1), so it stays positive definite against rounding.
    std::array<double, 3> covariance(double minVariance) const;

    /// One finest normal n with base variance v (mixtureBaseVariance): b = n.xy / max(n.z, kMinSlopeZ)
    /// (NormalMoments' slope), Σ = v·I, weight 1 (one finest texel).
    static LobeMoments ofNormal(const glm::vec3& n, double v);
};

/// Up to kMaxMixtureLobes lobes of one footprint in slots 0..count−1, an empty slot a lobe of weight
/// 0. reduceLobes packs them in canonical order; MixturePyramid then moves every level's lobes below
/// the top into the slots of the level above's lobes, bilinearly filtered at the texel's centre.
struct LobeMixture {
    std::array<LobeMoments, kMaxMixtureLobes> lobes{};
    int count = 0;

    double totalWeight() const;
};

/// Runnalls' cost of merging a and b: an upper bound on the KL divergence the merge adds,
/// ½[(wa + wb) log det Σab − wa log det Σa − wb log det Σb] (≥ 0; 0 for equal lobes).
// Runnalls 2007, "Kullback-Leibler Approach to Gaussian Mixture Reduction", eq. 21
double mergeCost(const LobeMoments& a, const LobeMoments& b, double minVariance);

/// The integral squared error (in slope space) between lobes a and b and their merge m (exact moments):
/// ∫ (a + b − m)² = ⟨a,a⟩ + ⟨b,b⟩ + 2⟨a,b⟩ − 2⟨a,m⟩ − 2⟨b,m⟩ + ⟨m,m⟩, each lobe its weight times its
/// Gaussian, ⟨x,y⟩ = wx·wy·N(bx − by; 0, Σx + Σy). At least 0; 0 for equal lobes.
// Williams & Maybeck 2003, "Cost-Function-Based Gaussian Mixture Reduction for Target Tracking": integral
// squared error
double iseMergeCost(const LobeMoments& a, const LobeMoments& b, double minVariance);

/// How a reduction picks the pair it merges next.
enum class MergeCriterion {
    /// The smallest mergeCost (Runnalls' bound on the KL divergence).
    KullbackLeibler,
    /// The smallest iseMergeCost (the integral squared error).
    SquaredError,
};

/// The criterion MixturePyramid reduces level `level` (>= 1) by: Runnalls' at level 1, where every lobe is a
/// finest normal's own, all as wide as the base lobe (there the two criteria pick alike: the same figures
/// on 27 real maps, and Runnalls' has closed forms that make level 1 fast); the squared error above, where
/// the lobes are fitted clusters of all widths. On noisy maps Runnalls' merges widen the main lobes and
/// dim the highlight (asphalt_01 at s = 1024, mip 4: 50 % of the energy kept); the squared error counts
/// a merge by how much it changes the lobes' heights, which for light lobes far apart is little, so the
/// scattered normals gather in a wide lobe of their own and the main lobes keep their shape (79 %, and
/// the error 0.59 -> 0.26). Measured on 27 real maps, K = 3 (core/bench/mixture_study.py, 324 cases): the
/// mean ratio to LEAN's error 0.384 -> 0.336, cases worse than LEAN 4 -> 1, cases outside the energy band
/// [0.97, 1.03] 45 -> 34; the squared error from level 3 only gave 0.351, 4 and 41.
inline MergeCriterion mixtureCriterion(int level) {
    return level <= 1 ? MergeCriterion::KullbackLeibler : MergeCriterion::SquaredError;
}

/// Reduces `lobes` (any number) to at most k (1..kMaxMixtureLobes): the cheapest pair under `criterion`
/// is merged (exact moments) until k remain, and then while a pair costs a negligible amount (equal
/// lobes: 1e-9 of the total weight for Runnalls' cost, of the pair's overlaps with themselves for the
/// squared error); ties go to the lower indices. The total weight is kept; k = 1 is the exact sum,
/// LEAN's moments. Canonical order. A k outside 1..kMaxMixtureLobes is taken as the nearest of them.
LobeMixture reduceLobes(std::vector<LobeMoments> lobes, int k, double minVariance,
                        MergeCriterion criterion = MergeCriterion::KullbackLeibler);

/// The lobes of the levels above the finest of a normal map's box pyramid (the footprints of
/// NormalPyramid). Level 0 is one lobe per finest normal and is not stored.
class MixturePyramid {
public:
    /// Level 1 from the finest normals with base power s (or each finest texel's own power,
    /// texelPowers, row-major), each level above from its children's lobes, up to level `lastLevel`
    /// (the pyramid's last when < 0; 0 builds no level); in parallel over rows, the same result on any thread
    /// count. k is clamped to [1, kMaxMixtureLobes].
    ///
    /// `refine`, when given, runs once every level's lobes are fitted and before they take their slots:
    /// it may replace any texel's lobes (replace), as the shaded fit does (eval/mixture_refine.h).
    static MixturePyramid build(const NormalPyramid& pyramid, double s, int k, int lastLevel = -1,
                                const std::vector<double>* texelPowers = nullptr,
                                const std::function<void(MixturePyramid&)>& refine = {});

    /// Levels 0..lastLevel (level 0 included in the count).
    int levelCount() const { return int(m_levels.size()) + 1; }
    int lobeCount() const { return m_k; }
    double minVariance() const { return m_minVariance; }
    /// Texel (x, y) of level `level` (1 <= level < levelCount()).
    LobeMixture at(int level, int x, int y) const;
    /// Replaces texel (x, y) of level `level`'s lobes (at most lobeCount() of them). Safe from
    /// parallel threads on distinct texels.
    void replace(int level, int x, int y, const LobeMixture& mixture);
    /// The lobe index a finest texel's own lobe takes at level 0: that of the lobe of its level-1
    /// parent it belongs to most (the largest w_i N(b; b_i, Σ_i)), so trilinear filtering between levels 0
    /// and 1 merges a normal into its own cluster. 0 without a level 1.
    int finestLobe(int x, int y) const;
    /// Texel (x, y) of level k as the mixture's textures store it: each lobe in its slot, its moments
    /// over the texel's total weight (the weights sum to 1). Level 0 is the finest normal of `finest`
    /// with base power `finestPower`, in slot finestLobe(x, y). What the bake writes and what
    /// evaluate filters between texels.
    std::array<LobeMoments, kMaxMixtureLobes> storedTexel(const NormalMap& finest, int k, int x, int y,
                                                          double finestPower) const;
    /// Frees level k's lobes (1 <= k < levelCount()) once nothing reads them again: every level was
    /// built with the pyramid, and level 0's slots (finestLobe) are kept apart. Reading level k
    /// afterwards is an error the caller must not make.
    void releaseLevel(int k);

private:
    /// Frees storage from ::operator new.
    struct FreeStorage {
        void operator()(void* p) const noexcept { ::operator delete(p); }
    };
    /// A level's texels, each its lobe count and m_k lobes (the slots from the count up empty): 200
    /// bytes of LobeMixture a texel would be 145 at K = 3. Not value-initialised: the build writes
    /// every texel from parallel rows, so the kernel clears the pages in the threads that fill them,
    /// with no serial memset first.
    struct Level {
        int width = 0;
        int height = 0;
        std::unique_ptr<LobeMoments[], FreeStorage> lobes;
        std::unique_ptr<unsigned char[], FreeStorage> counts;

        LobeMixture get(size_t texel, int k) const;
        void set(size_t texel, int k, const LobeMixture& m);
    };
    int m_k = 1;
    double m_minVariance = 1.0;
    std::vector<Level> m_levels; // levels 1, 2, ...
    int m_finestWidth = 0;
    std::vector<unsigned char> m_finestLobe; // per finest texel, row-major (empty: all 0)
};

/// The mixture's NDF at tangent-space half vector h: Σ_i (w_i/Σw) D_i(h), each D_i the
/// slope-space Gaussian of lobe i (slopeGaussianNdf, methods.h). 0 for h_z <= 0 or no weight.
double mixtureNdf(const LobeMixture& mixture, const glm::dvec3& h, double minVariance);

/// A mixture decoded as its shader decodes it once per pixel: per lobe its share w_i/Σw, mean slope,
/// covariance (LobeMoments::covariance) and the normal of its mean slope.
struct DecodedMixture {
    struct Lobe {
        double share = 0.0;
        glm::dvec2 mean{0.0};
        std::array<double, 3> cov{0.0, 0.0, 0.0};
        glm::dvec3 normal{0.0, 0.0, 1.0};
    };
    std::array<Lobe, kMaxMixtureLobes> lobes{};
    int count = 0; // 0 for a mixture without weight
};
DecodedMixture decodeMixture(const LobeMixture& mixture, double minVariance);

/// The mixture's reflected value for light l and half vector h, as evaluate measures every method:
/// Σ_i (w_i/Σw) D_i(h) max(0, n_i·l) with n_i the normal of lobe i's mean slope.
double mixtureValue(const DecodedMixture& mixture, const glm::dvec3& l, const glm::dvec3& h);
double mixtureValue(const LobeMixture& mixture, const glm::dvec3& l, const glm::dvec3& h, double minVariance);

// ---------------------------------------------------------------------------------------------
// The mixture under an engine's GGX (evaluate --brdf ggx, burnish gltf --method mixture and its three.js
// module resources/three/burnish-mixture.js): each lobe a GGX lobe about the normal of its mean slope, as
// wide as the base roughness and its normals' spread together.

/// The four numbers one lobe stores for GGX shading: (w, w·b.x, w·b.y, w·(tr M − 2v)), v the base variance
/// the mixture was fitted with (mixtureBaseVariance), so the last is w·(tr C + |b|²) with C the covariance of
/// the lobe's normals' slopes alone. Linear in the moments, so filtering merges lobes of a slot exactly, and
/// free of the base roughness, which the engine supplies.
std::array<double, 4> mixtureGgxTexel(const LobeMoments& lobe, double baseVariance);

/// One lobe decoded for GGX shading.
struct MixtureGgxLobe {
    double share = 0.0;         // w / total, 0 for an empty lobe
    glm::dvec3 normal{0, 0, 1}; // the normal of the mean slope b = (w·b)/w, tangent space
    double alpha = 0.0;         // GGX α, in [α0, 1]
};

/// The spread scale c of mixtureGgxLobe: the GGX α² a lobe's slope spread tr C adds. Beckmann's α² = 2σ² per
/// axis gives c = 1; GGX's tails are longer than a Gaussian's, so the widened GGX lobe already spreads more
/// light than the convolution, and less widening fits better. Measured against the GGX truth (evaluate
/// --brdf ggx, power 256, K = 3, mips 1-6, bilinear truth normals) on six real maps (README, "The mixture
/// in three.js"), mean relative L1 over maps and mips: c = 0.5 0.1035, 0.625 0.0984, 0.75 0.0985,
/// 0.875 0.1026, 1 0.1086; the lowest energy ratio 0.908, 0.875, 0.815, 0.764, 0.722. 0.625 is the least
/// error with the energy kept best of the two lowest.
inline constexpr double kMixtureGgxSpreadScale = 0.625;

/// A stored lobe t (mixtureGgxTexel, filtered or not) of a texel whose lobes' weights sum to `total`, as the
/// engine shades it: share w/total, the normal of b = (w·b)/w, and α = min(1, √(α0² + c·max(0, (w·S)/w −
/// |b|²))) with α0 the base GGX α and c the spread scale. An empty lobe (w <= 0 or NaN) has share 0 and α0.
// Olano & Baker 2010, "LEAN Mapping": slope Gaussians convolve by adding covariances; Walter et al. 2007:
// α² = 2σ²
MixtureGgxLobe mixtureGgxLobe(const std::array<double, 4>& t, double total, double alpha0,
                              double spreadScale = kMixtureGgxSpreadScale);

/// What the mixture's GGX form stores and an engine fetches (burnish gltf --method mixture): the normal
/// texture (BC5) and K RGBA16F lobe textures of mixtureGgxTexel's.
MethodStorage mixtureGgxStorage(int k);

/// The mixture's value under GGX for light l, view v and half vector h (tangent space): Σ share ·
/// ggxSpecularTerm(n_i·h, n_i·l, n_i·v, α_i) over the first `count` lobes, each about its own normal with its
/// own cosine, as burnish-gltf.js shades it through three.js's BRDF_GGX (Fresnel 1). The scalar reference of
/// evaluate's loop.
double mixtureGgxValue(const std::array<MixtureGgxLobe, kMaxMixtureLobes>& lobes, int count,
                       const glm::dvec3& l, const glm::dvec3& v, const glm::dvec3& h);

} // namespace burnish
