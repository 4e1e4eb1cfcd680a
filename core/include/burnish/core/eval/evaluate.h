// Ground truth and the error of every prefiltering method against it, per mip.
//
// The ground truth is the texts' experiment (render big, downsample) done in texture space:
// for mip k, a texel's footprint is its block of finest texels (the aligned 2^k×2^k block for
// power-of-two maps; see normal_pyramid.h for other sizes), and
//   GT = mean over the footprint of D_s(n_i·h)·max(0, n_i·l)
// with D_s the normalized Blinn-Phong NDF of the base power s. A method's value is its own NDF
// (methods.h) times max(0, n̄·l) with the method's normal n̄, using box-footprint moments.
// Directions: the view at `viewAngle` from the macro normal (azimuth 0); half vectors at the
// polar angles `halfAngles` and `azimuths` evenly spaced azimuths (one at 0); pairs whose light
// is within `horizon` of the horizon are dropped.
//
// Authored gloss (texelPowers): each finest texel has its own power s_i, and
//   GT = mean over the footprint of D_{s_i}(n_i·h)·max(0, n_i·l).
// Every method gets the block's power the way the bake (bake.cpp) feeds it to every method:
// 1/s averaged over the footprint, s = 1/mean(1/s_i) (Baker & Hill 2012: "storing power as 1/s
// will cause MIP filter to operate correctly"), with the kernel applied for tent/Gaussian
// variants. The harmonic mean keeps the spread of a mixture of lobes, not its peak: on a flat map
// the peak D(1) ∝ s + 2 of a mixture is that of the arithmetic mean power, so no single lobe
// matches a mixture of very different powers (test_evaluate.cpp measures both).
#pragma once

#include <burnish/core/prefilter/fitted_lobe.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/prefilter/normal_pyramid.h>
#include <burnish/core/shading/lobe_shading.h>
#include <burnish/core/util/result.h>

#include <glm/vec3.hpp>

#include <array>
#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish {

/// The message of the Error a cancelled evaluation or measurement returns (and nothing else).
inline constexpr std::string_view kCancelledMessage = "cancelled";
/// Whether an error is the one a cancelled run returns.
inline bool isCancelled(const Error& error) {
    return error.message == kCancelledMessage;
}

/// The methods that have a form under `brdf`, in report order: every method under Blinn-Phong; under GGX
/// the isotropic ones an engine stores as one roughness and the mixture, whose lobes an engine shades as GGX
/// lobes (mixtureGgxLobe); not LEAN or CLEAN.
std::vector<Method> methodsUnder(Brdf brdf);

struct EvaluateOptions {
    std::vector<double> basePowers{512.0};
    int firstMip = 1;
    int lastMip = 4; // clamped to the map's last level
    // The light/view pairs (DirectionSet: its defaults are the fitted lobe's too).
    double viewAngleDeg = DirectionSet{}.viewAngleDeg;
    std::vector<double> halfAnglesDeg = DirectionSet{}.halfAnglesDeg;
    int azimuths = DirectionSet{}.azimuths;
    double horizonDeg = DirectionSet{}.horizonDeg;
    std::vector<Method> methods = allMethods();
    /// Footprint moments each method is evaluated with: Box is the definition above; Tent and
    /// Gaussian use the kernel-filtered moments a bake stores, and are reported beside it.
    std::vector<FilterKernel> kernels{FilterKernel::Box};
    /// The mixture's lobe counts, each evaluated as its own row ("mixture-k3"); K = 1 is LEAN's
    /// lobe exactly. The mixture fits box footprints, so it has no tent or Gaussian rows.
    std::vector<int> mixtureLobes{kDefaultMixtureLobes};
    MethodParams params;
    BorderMode border = BorderMode::Wrap;
    /// Keep per-texel error maps (relative L1 per texel: Σ_dir|M − GT| / Σ_dir GT).
    bool errorMaps = false;
    /// Also evaluate between texels, where real rendering samples: at the corner shared by texels
    /// (x, y)..(x+1, y+1) of each mip. There the ground truth is the bilinear-weighted union of the
    /// four footprints (¼ of each footprint's mean), and each method's value is what its shader
    /// computes from bilinearly filtered textures: the stored values averaged (moments for Toksvig,
    /// LEAN, CLEAN and the mixture's premultiplied lobes of the same index; normals renormalized and
    /// gloss averaged in the gloss encoding, blackops, for the others). Reported as extra rows with
    /// betweenTexels set.
    bool betweenTexels = false;
    /// How the mixture is filtered between texels (betweenTexels): its lobes merged slot by slot as
    /// bilinear filtering merges the stored moments, or filtered after shading (stochastic filtering's
    /// expected value: ¼ of each of the four texels' mixture values at a corner).
    MixtureFiltering mixtureFiltering = MixtureFiltering::Moments;
    /// Authored power per finest texel (row-major, the map's texel count, each in (0, 1e9]). When
    /// set, it replaces basePowers: the evaluation runs once, and results carry the arithmetic
    /// mean of the powers as their basePower label.
    std::optional<std::vector<double>> texelPowers;
    /// Also say where LEAN's energy goes (LeanEnergySplit), per base power and mip, with the finest
    /// normals tilted more than steepDeg (in (0, 90)) from the surface normal counted as steep. Not
    /// with texelPowers.
    bool energySplit = false;
    double steepDeg = 45.0;
    /// The BRDF of the truth and of every method's lobe. BlinnPhong: the definition above. Ggx: each
    /// finest normal shaded by ggxSpecularTerm (GGX D, height-correlated Smith visibility, n·l) with
    /// α² = 2/(s+2), against each method's one GGX lobe about its renormalized mean normal with the
    /// α of its power, as a roughness preset's engine shades them. Only the isotropic methods have a GGX
    /// form (not LEAN, CLEAN, the mixture or the energy split).
    Brdf brdf = Brdf::BlinnPhong;
    /// How the truth sees the finest normals (fitted_lobe.h): each texel a facet, or the bilinear
    /// interpolant an engine draws when it magnifies the map. Unset: defaultTruthNormals(brdf), the
    /// interpolant under GGX, facets under Blinn-Phong. The fitted lobe and the floor fit to this truth.
    std::optional<TruthNormals> truthNormals;
    TruthNormals resolvedTruthNormals() const { return truthNormals.value_or(defaultTruthNormals(brdf)); }
    /// Also evaluate the anisotropic fit (GGX only; fitted_lobe.h fitTexelAnisotropic): per texel the pair
    /// KHR_materials_anisotropy stores, shaded as the engines shade it (t and b in the geometric tangent
    /// plane), reported as a row labelled "fitted anisotropic"; between texels each of its three textures
    /// (roughness, direction·strength, normal) filtered as the engine filters them.
    bool anisotropic = false;
    /// Also evaluate the one-lobe floor: per texel the best isotropic lobe about the mean normal by a
    /// brute-force search (FittedLobeOptions::floor), reported as a row labelled "one-lobe floor".
    bool floor = false;
};

/// The direction pairs the options define, in a fixed order.
std::vector<DirectionPair> evaluationDirections(const EvaluateOptions& options);

struct MipError {
    Method method;
    double basePower;
    int mip;
    double relativeL1;  // Σ|M − GT| / Σ GT over texels and directions
    double energyRatio; // Σ M / Σ GT
    FilterKernel kernel = FilterKernel::Box;
    int lobes = 0;              // the mixture's K (0 for the other methods)
    bool betweenTexels = false; // evaluated between texels (EvaluateOptions::betweenTexels)
    bool floor = false;         // the one-lobe floor (EvaluateOptions::floor), method Fitted
    bool anisotropic = false;   // the anisotropic fit (EvaluateOptions::anisotropic), method Fitted
};

/// Error maps divide a texel's absolute error by its truth, or by this fraction of the level's mean
/// truth per texel where the truth is smaller (footprints that face away from every light), so no
/// map holds an infinity or a division by almost zero.
inline constexpr double kErrorMapTruthFloor = 0.01;

struct ErrorMap {
    Method method;
    double basePower;
    int mip;
    int width;
    int height;
    std::vector<float> relativeError; // per texel, row-major: Σ|M − GT| / max(Σ GT, floor), finite
    FilterKernel kernel = FilterKernel::Box;
    int lobes = 0;
    bool floor = false; // the one-lobe floor's map
    bool anisotropic = false;
};

/// What one row of an evaluation is: a method, its footprint kernel and, for the mixture, its K.
struct EvaluatedVariant {
    Method method;
    FilterKernel kernel = FilterKernel::Box;
    int lobes = 0;
    bool floor = false;       // the one-lobe floor (method Fitted, box kernel)
    bool anisotropic = false; // the anisotropic fit (method Fitted, box kernel)
    bool operator==(const EvaluatedVariant&) const = default;
};
/// The rows the options ask for, kernel-major, methods in the options' order, the mixture once per
/// lobe count (box kernel only), then the one-lobe floor (box kernel) when asked for.
std::vector<EvaluatedVariant> evaluatedVariants(const EvaluateOptions& options);
/// "lean", "lean (tent)", "mixture-k3", "one-lobe floor".
std::string variantLabel(const EvaluatedVariant& variant);
inline constexpr std::string_view kFloorLabel = "one-lobe floor";
inline constexpr std::string_view kAnisotropicLabel = "fitted anisotropic";
inline EvaluatedVariant variantOf(const MipError& e) {
    return {e.method, e.kernel, e.lobes, e.floor, e.anisotropic};
}

/// Where LEAN's energy goes at one base power and mip: its energy ratio Σ M / Σ GT over the texels
/// and direction pairs, split into three steps from the ground truth to LEAN, each a ratio of sums of
/// the same kind, whose product is the energy ratio:
///   GT   = mean_i D_s(n_i·h)·max(0, n_i·l), the truth;
///   GT_c = mean_i D_s(n_i·h)·max(0, n̄·l), the truth with LEAN's one cosine (n̄ its normal);
///   G    = LEAN's slope-space Gaussian of the footprint's normals that are not steep (their mean and
///          spread, with 1/s), weighted by their share of the footprint and shaded with n̄: LEAN as if
///          the steep normals neither reflected towards the sampled directions nor pulled on the
///          moments (0 where every normal is steep);
///   M    = LEAN.
/// cosine = Σ GT_c / Σ GT (one cosine for the footprint), shape = Σ G / Σ GT_c (one Gaussian for the
/// normals that are not steep: its tails and peak against their own lobes; the steep normals' own light,
/// steepTruth of the truth, counts here too), steep = Σ M / Σ G (the steep normals' pull on the slope
/// moments: steep slopes widen the Gaussian and move its mean). A step whose sum is 0 (GT_c: n̄ faces
/// away from every light; G: every normal steep) is skipped, its factor 1, so that the product is the
/// energy ratio in every case (every factor 1 where Σ GT = 0, as the energy).
/// steepNormals is the share of the map's finest normals that are steep; steepTruth their share of Σ GT.
struct LeanEnergySplit {
    double basePower = 0.0;
    int mip = 0;
    double energy = 1.0;
    double cosine = 1.0;
    double shape = 1.0;
    double steep = 1.0;
    double steepNormals = 0.0;
    double steepTruth = 0.0;
};

struct EvaluationResult {
    std::vector<MipError> errors;
    /// EvaluateOptions::energySplit: per base power and mip, in that order.
    std::vector<LeanEnergySplit> energySplits;
    std::vector<ErrorMap> maps;
    std::vector<DirectionPair> directions;
    int firstMip = 0;
    int lastMip = 0;
    double seconds = 0.0;
    /// The powers the results are labelled with: options.basePowers, or with texelPowers their mean.
    std::vector<double> basePowers;
};

/// Ground truth of one texel's footprint for one direction pair (the brute-force definition that
/// evaluateMethods' hierarchical sums are tested against); with TruthNormals::Bilinear each finest
/// texel is the mean over kBilinearSamples² points of the bilinear interpolant inside it.
double groundTruthTexel(const NormalPyramid& pyramid, int mip, int x, int y, double s, const DirectionPair& d,
                        Brdf brdf = Brdf::BlinnPhong, TruthNormals how = TruthNormals::Texels);

/// The same with each finest texel's own power (texelPowers, row-major over the finest level).
double groundTruthTexel(const NormalPyramid& pyramid, int mip, int x, int y,
                        const std::vector<double>& texelPowers, const DirectionPair& d);

/// A method's value for one texel and direction: the scalar reference that evaluateMethods'
/// vectorised loops (src/eval/lobe_values.h) are tested against, as groundTruthTexel is for the truth.
/// Under Brdf::Ggx an isotropic lobe is shaded by ggxSpecularTerm with the α of its power.
double methodValue(const TexelLobe& lobe, const DirectionPair& d, Brdf brdf = Brdf::BlinnPhong);

/// The lobe a method's shader reconstructs halfway between four texels from their bilinearly
/// filtered stored values (EvaluateOptions::betweenTexels): `moments` and `powers` of the four
/// texels, equal weights. Not for the mixture (its lobes are not NormalMoments).
/// `lobePowers` (if set) are the four texels' stored lobe powers, for a method whose lobe the moments
/// do not give (the fitted lobe); the gloss is averaged in the encoding of `brdf`'s engines (GGX
/// roughness for Ggx, Black Ops gloss for Blinn-Phong, the bake's default).
TexelLobe methodLobeBetween(Method method, const std::array<NormalMoments, 4>& moments,
                            const std::array<double, 4>& powers, const MethodParams& params,
                            const std::array<double, 4>* lobePowers = nullptr, Brdf brdf = Brdf::BlinnPhong);

/// LEAN's energy split (LeanEnergySplit) at base power s for mips firstMip..lastMip of a pyramid with
/// box slope moments, over `directions`; normals tilted more than steepDeg are steep. Deterministic on
/// any number of threads. `cancelled` (if set) is polled between batches of bands: true returns an empty
/// list.
std::vector<LeanEnergySplit> leanEnergySplit(const NormalPyramid& pyramid, double s, int firstMip,
                                             int lastMip, const std::vector<DirectionPair>& directions,
                                             double steepDeg, const MethodParams& params = {},
                                             const std::function<bool()>& cancelled = {});

/// Errors of every requested method, power and mip. Fails on bad options (no directions left,
/// empty power list, non-positive power, mip range outside the map, texelPowers of the wrong size
/// or with a power outside (0, 1e9]). `progress` (if set) is called with the fraction done,
/// non-decreasing, ending at exactly 1 on success. `cancel` (if set) may be raised from another
/// thread: it is read before the work starts, between the lobe tables and between batches of bands
/// (rows of the last evaluated mip, evaluated for every direction pair at once), and a raised flag
/// returns the Error kCancelledMessage and no partial result. Both are called on the calling thread.
Result<EvaluationResult> evaluateMethods(const NormalMap& map, const EvaluateOptions& options,
                                         const std::function<void(double)>& progress = {},
                                         const std::atomic<bool>* cancel = nullptr);

} // namespace burnish
