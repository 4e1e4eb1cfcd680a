// The fitted one-lobe roughness: per texel and mip, the single isotropic lobe about the texel's mean
// normal (the normal an engine rebuilds from the normal texture's mips) that shades closest to the
// footprint's true shading, judged the way evaluate judges it: the relative L1 error over a set of
// light/view pairs, under the engine's BRDF (GGX for the roughness presets).
//
// Why: one lobe widened by the normals' variance (vMF, variance-to-gloss, Toksvig) flattens the bright
// core that most real footprints keep, because a few steep normals (grout, treads, bevels) carry most
// of the variance; in a real engine it is often worse than leaving the roughness alone. The fit chooses
// the lobe by how it shades instead, and its candidates always include the base power (the engine's
// default) and vMF's, so by its measure it is never worse than either.
//
// How (per texel of mips >= 1; mip 0's footprint is one normal, whose lobe is the base power's exactly):
//  1. the footprint's truth for every pair, mean_i f(n_i; s_i) with f the BRDF's lobe (lobe_shading.h)
//     over its finest normals as TruthNormals says (under GGX the bilinear interpolant an engine draws),
//     summed up the levels as evaluate's truth is;
//  2. the error E(α) = Σ_pairs |f(n̄; α) − truth| at α_base, α_vmf and kFitGrid + 2 roughnesses spaced
//     evenly in log α over [α_base, kFitReach·max(α_base, α_vmf)] (capped at 1): never sharper than the
//     base, since a lobe sharper than the footprint's own normals' lobes can hide its energy between the
//     sampled pairs (a sparkle no finite set of pairs sees) and so score well where it would shimmer;
//  3. a golden-section search of kFitSteps steps in the grid cell on each side of the best point; the
//     best α seen wins.
// The floor (FittedLobeOptions::floor) replaces 2–3 with a brute-force scan: kFloorGrid roughnesses
// evenly in log α from α_base to 1, α_base and α_vmf, and a 30-step golden refinement about the best:
// the best one isotropic lobe no sharper than the base can do, printed beside the fit by evaluate
// --floor.
#pragma once

#include <burnish/core/prefilter/normal_pyramid.h>
#include <burnish/core/shading/lobe_shading.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace burnish {

/// Roughnesses the fit's first scan tries inside its range (besides its ends and the two candidates).
inline constexpr int kFitGrid = 8;
/// The fit's range reaches this far above the rougher of the base and vMF's α (capped at 1).
inline constexpr double kFitReach = 4.0;
/// Golden-section steps the fit refines its best scan point with.
inline constexpr int kFitSteps = 8;
/// Roughnesses the floor's brute-force scan tries, evenly in log α from α_base to 1.
inline constexpr int kFloorGrid = 160;

/// How the truth sees the finest normals. Texels: each texel one flat facet (the source texts' truth).
/// Bilinear: the surface an engine draws when it magnifies the map, the bilinear interpolant of the
/// texels (renormalized; past the edges by the pyramid's border mode, wrap as a tiling sampler), each
/// texel the mean of kBilinearSamples² points of it. Texel-scale noise is about two thirds as wide there
/// (bilinear filtering averages neighbours: uncorrelated noise keeps 4/9 of its variance), so a lobe
/// fitted to facets comes out rougher than the surface the engine shows: on the tread plate at 32× in
/// three.js, fitted to facets 0.14× three.js alone's error, to the interpolant 0.07× (README, "One
/// roughness for engines").
enum class TruthNormals { Texels, Bilinear };
/// Points per texel side of TruthNormals::Bilinear, at ±1/4 texel (the 2×2 midpoint rule).
inline constexpr int kBilinearSamples = 2;
/// Bilinear for GGX (the engines' truth), Texels for Blinn-Phong (the source texts' and the mixture's).
TruthNormals defaultTruthNormals(Brdf brdf);
const char* truthNormalsName(TruthNormals t);
/// "texels" / "bilinear"; false for anything else.
bool truthNormalsFromName(const std::string& name, TruthNormals& out);

/// The finest normals of rows [rowBegin, rowEnd) of a map as the truth samples them: one set of
/// (x, y, z) arrays per sub-sample (1 for Texels, kBilinearSamples² for Bilinear), each one value per
/// texel of the rows, and the truth of each texel as the mean over its sub-samples.
class TruthBand {
public:
    TruthBand(const NormalMap& map, int rowBegin, int rowEnd, TruthNormals how, BorderMode border);
    size_t size() const { return m_count; }
    /// Per texel of the rows, the mean of truthValues over its sub-samples (powers: per texel, or null).
    void values(Brdf brdf, const double* powers, double s, const DirectionPair& d, double* out);

private:
    size_t m_count = 0;
    int m_samples = 1;
    std::vector<double> m_x, m_y, m_z; // sample-major: [sample·count + texel]
    std::vector<double> m_scratch;
};

/// One texel's anisotropic lobe as KHR_materials_anisotropy stores it: the roughness texture's α (α_b,
/// across), a strength k with α_t = mix(α_b, 1, k²) (along), and the direction of t in the tangent plane,
/// t = (cos θ, sin θ, 0), b = (−sin θ, cos θ, 0) (the normal map's x and y: glTF's tangent and bitangent).
struct AnisotropicLobe {
    double alphaT = 1.0;
    double alphaB = 1.0;
    double angle = 0.0; // θ, radians in [0, π)
    /// KHR_materials_anisotropy's strength: α_t = α_b + (1 − α_b)·k², so k = √((α_t − α_b)/(1 − α_b)).
    double strength() const;
};

/// E of one texel for an anisotropic lobe about the unit normal n: Σ_pairs |ggxAnisotropicSpecularTerm −
/// truth| (the isotropic fit's objective, fitTexelError, with the anisotropic term).
double anisotropicFitError(const double* truth, const std::vector<DirectionPair>& dirs, const glm::dvec3& n,
                           const AnisotropicLobe& lobe);

/// The anisotropic fit of one texel: the lobe about n, no sharper than alphaBase across and along, that
/// minimizes anisotropicFitError. The engines form t and b in the geometric tangent plane (three.js, the
/// glTF sample viewer, Filament), not about the shading normal, so about a tilted mean normal even a
/// round lobe of this family is not ggxSpecularTerm's: with KHR_materials_anisotropy on, every texel is
/// shaded this way, and the family can be better or worse than the isotropic fit (evaluate's "fitted
/// anisotropic" row measures which, per map). Its first candidates are the round lobes of alphaIso (the
/// isotropic fit's α) and alphaBase, so it is never worse than those in its own family. Search:
/// directions principalAngle (the footprint's widest spread of normals) and kAnisotropicAngles evenly over
/// [0, π), at each kFitGrid α_t from α_b to 1 for three α_b up to alphaIso; then kFitSteps golden-section
/// steps on θ (±π/(2·kAnisotropicAngles)), log α_t and log α_b, twice.
AnisotropicLobe fitTexelAnisotropic(const double* truth, const std::vector<DirectionPair>& dirs,
                                    const glm::dvec3& n, double alphaBase, double alphaIso,
                                    double principalAngle);
/// Directions the anisotropic fit tries besides the footprint's principal one.
inline constexpr int kAnisotropicAngles = 4;
/// The direction of the widest spread of a footprint's normals in the tangent plane (the principal axis
/// of their x, y covariance), in [0, π); 0 where the spread is round.
double principalAngle(const NormalMoments& m);

struct FittedLobeOptions {
    Brdf brdf = Brdf::Ggx;
    /// Also fit the anisotropic lobe (GGX only): FittedPyramid::anisotropic.
    bool anisotropic = false;
    /// How the truth sees the finest normals (defaultTruthNormals(brdf) unless set).
    std::optional<TruthNormals> truthNormals;
    /// The pairs the error is summed over (evaluate's defaults).
    std::vector<DirectionPair> directions = directionPairs({});
    /// The brute-force floor instead of the fit.
    bool floor = false;
    /// Levels below this (and 0) are not fitted and their moments not read: a bake that skips its largest
    /// levels (BakeOptions::largestLevel) from a pyramid that released them. Their powers stay 0.
    int firstLevel = 1;
};

/// Per level and texel, the fitted lobe's power (the isotropic Blinn-Phong power; GGX α² = 2/(p+2)).
class FittedPyramid {
public:
    /// The base power of texel (x, y) of level k: the engine's default roughness there (the authored
    /// power as the bake filters it, or the one base power).
    using BasePower = std::function<double(int k, int x, int y)>;

    /// Fits levels 1..lastLevel (lastLevel < 0: every level) of `pyramid`. The lobe's normal is the
    /// renormalized mean of pyramid.moments (its own kernel: the normal the bake stores); the truth
    /// is the box footprint's, each finest normal with texelPowers[i] (row-major over the finest
    /// level) or s. vMF's candidate is methodPower(Vmf) of the same moments and base power.
    /// Deterministic on any number of threads. `cancelled` (if set) is polled between batches; a
    /// raised flag returns an empty pyramid (levelCount() 0).
    static FittedPyramid build(const NormalPyramid& pyramid, const BasePower& basePower,
                               const std::vector<double>* texelPowers, double s, int lastLevel,
                               const FittedLobeOptions& options, const std::function<bool()>& cancelled = {});

    int levelCount() const { return int(m_levels.size()); }
    /// The fitted power of texel (x, y) of level k (k >= 1: level 0 is not fitted, its lobe is the
    /// base power's).
    double power(int k, int x, int y) const {
        const Level& l = m_levels[size_t(k)];
        return double(l.power[size_t(y) * size_t(l.width) + size_t(x)]);
    }
    /// Frees level k's powers once nothing reads them again.
    void releaseLevel(int k) {
        m_levels[size_t(k)].power = {}, m_levels[size_t(k)].aniso = {}, m_levels[size_t(k)].errors = {};
    }
    /// Whether the anisotropic lobes were fitted (FittedLobeOptions::anisotropic).
    bool hasAnisotropic() const { return m_anisotropic; }
    /// The anisotropic lobe of texel (x, y) of level k >= 1 (with hasAnisotropic()).
    AnisotropicLobe anisotropic(int k, int x, int y) const {
        const Level& l = m_levels[size_t(k)];
        const size_t i = 3 * (size_t(y) * size_t(l.width) + size_t(x));
        return {double(l.aniso[i]), double(l.aniso[i + 1]), double(l.aniso[i + 2])};
    }

    /// Level k's fit errors summed over its texels (with hasAnisotropic()): the isotropic fit's E (its lobe
    /// as ggxSpecularTerm shades it), the anisotropic fit's (as the engines shade every texel with
    /// KHR_materials_anisotropy on), and the truth's Σ over the pairs — each error / truth is the level's
    /// relative L1 of that fit: whether turning the extension on pays for a map (burnish gltf).
    struct FitErrors {
        double isotropic = 0.0, anisotropic = 0.0, truth = 0.0;
    };
    FitErrors fitErrors(int k) const;

private:
    struct Level {
        int width = 0, height = 0;
        std::vector<float> power;
        std::vector<float> aniso;  // per texel α_t, α_b, θ
        std::vector<float> errors; // per texel E_iso, E_aniso, Σ truth (anisotropic fits only)
    };
    bool m_anisotropic = false;
    std::vector<Level> m_levels;
};

/// The best α for one texel (the fit's search, or the floor's with floor = true): `truth` the footprint's
/// value per pair, (NoH, NoL, NoV) of the lobe's normal per pair, the base and vMF's α. Exposed for the
/// tests: E(result) <= min(E(alphaBase), E(alphaVmf)) always.
double fitTexelAlpha(Brdf brdf, const double* truth, const double* NoH, const double* NoL, const double* NoV,
                     size_t pairs, double alphaBase, double alphaVmf, bool floor);

/// The ground truth of `count` finest normals (x, y, z in three arrays) for pair d under `brdf`:
/// isotropicLobeShading about each normal, with its own power powers[i], or s for all when powers is
/// null. Branch-free loops (vectorised): the truth of evaluate and of the fit.
void truthValues(Brdf brdf, const double* nx, const double* ny, const double* nz, const double* powers,
                 double s, size_t count, const DirectionPair& d, double* out);

/// E(α) of one texel: Σ_pairs |lobe(α) − truth| (the fit's objective).
double fitTexelError(Brdf brdf, const double* truth, const double* NoH, const double* NoL, const double* NoV,
                     size_t pairs, double alpha);

} // namespace burnish
