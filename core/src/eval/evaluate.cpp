#include <burnish/core/eval/evaluate.h>

#include "band_batches.h"
#include "lobe_values.h"

#include <burnish/core/prefilter/fitted_lobe.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/mixture_refine.h>
#include <burnish/core/shading/ggx_specular.h>
#include <burnish/core/shading/ndf.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

namespace burnish {

namespace {

struct Accumulator {
    double absError = 0.0;
    double method = 0.0;
    double truth = 0.0;
};

// The authored variance 1/s_i averaged over every footprint of every level (hierarchically: a
// level's sum is its children's), and the power each method gets from it — bake.cpp's
// BaseVariancePyramid, so the evaluation measures the textures the bake writes.
// Baker & Hill 2012, "Rock-Solid Shading": "storing power as 1/s will cause MIP filter to operate correctly"
class AuthoredPowers {
public:
    AuthoredPowers(const NormalPyramid& pyramid, const std::vector<double>& texelPowers, int lastMip)
        : m_pyramid(pyramid) {
        m_sums.resize(size_t(lastMip) + 1);
        m_sums[0].resize(texelPowers.size());
        for (size_t i = 0; i < texelPowers.size(); ++i)
            m_sums[0][i] = varianceFromPower(texelPowers[i], VarianceConvention::InversePower);
        for (int k = 1; k <= lastMip; ++k) {
            const PyramidLevel& level = pyramid.level(k);
            const PyramidLevel& child = pyramid.level(k - 1);
            auto& out = m_sums[size_t(k)];
            out.resize(size_t(level.width) * size_t(level.height));
            for (int y = 0; y < level.height; ++y)
                for (int x = 0; x < level.width; ++x) {
                    double sum = 0.0;
                    for (int j = level.yChild[size_t(y)]; j < level.yChild[size_t(y) + 1]; ++j)
                        for (int i = level.xChild[size_t(x)]; i < level.xChild[size_t(x) + 1]; ++i)
                            sum += m_sums[size_t(k - 1)][size_t(j) * size_t(child.width) + size_t(i)];
                    out[size_t(y) * size_t(level.width) + size_t(x)] = sum;
                }
        }
    }

    /// The power of texel (x, y) of level k: the footprint's mean variance, with the kernel's taps
    /// over the neighbours weighted by their footprint counts (Box: the footprint alone).
    double power(int k, int x, int y, FilterKernel kernel) const {
        const KernelTaps taps = kernelTaps(kernel);
        const PyramidLevel& level = m_pyramid.level(k);
        const BorderMode border = m_pyramid.options().border;
        double sum = 0.0, weight = 0.0;
        for (int j = -taps.radius; j <= taps.radius; ++j)
            for (int i = -taps.radius; i <= taps.radius; ++i) {
                const int xi = borderIndex(x + i, level.width, border);
                const int yj = borderIndex(y + j, level.height, border);
                const double count = m_pyramid.footprintCount(k, xi, yj);
                const double w = taps.w[i + taps.radius] * taps.w[j + taps.radius];
                // Σ over the footprint = count × its mean: weight w·count on the mean, as bake.cpp.
                sum += w * m_sums[size_t(k)][size_t(yj) * size_t(level.width) + size_t(xi)];
                weight += w * count;
            }
        return powerFromVariance(sum / weight, VarianceConvention::InversePower);
    }

private:
    const NormalPyramid& m_pyramid;
    std::vector<std::vector<double>> m_sums; // per level, Σ 1/s_i over each footprint
};

} // namespace

std::vector<Method> methodsUnder(Brdf brdf) {
    std::vector<Method> out;
    for (Method m : allMethods())
        if (brdf == Brdf::BlinnPhong || (m != Method::Lean && m != Method::Clean)) out.push_back(m);
    return out;
}

std::vector<EvaluatedVariant> evaluatedVariants(const EvaluateOptions& options) {
    std::vector<EvaluatedVariant> out;
    for (FilterKernel kernel : options.kernels)
        for (Method m : options.methods) {
            if (m != Method::Mixture) {
                out.push_back({m, kernel, 0});
                continue;
            }
            if (kernel != FilterKernel::Box) continue;
            for (int k : options.mixtureLobes)
                out.push_back({m, kernel, std::clamp(k, 1, kMaxMixtureLobes)});
        }
    if (options.floor) out.push_back({Method::Fitted, FilterKernel::Box, 0, true});
    if (options.anisotropic) out.push_back({Method::Fitted, FilterKernel::Box, 0, false, true});
    return out;
}

std::string variantLabel(const EvaluatedVariant& v) {
    std::string label(v.floor ? kFloorLabel : v.anisotropic ? kAnisotropicLabel : methodName(v.method));
    if (v.method == Method::Mixture) label += "-k" + std::to_string(v.lobes);
    if (v.kernel != FilterKernel::Box) label += " (" + std::string(kernelName(v.kernel)) + ")";
    return label;
}

std::vector<DirectionPair> evaluationDirections(const EvaluateOptions& options) {
    return directionPairs(
        {options.viewAngleDeg, options.halfAnglesDeg, options.azimuths, options.horizonDeg});
}

TexelLobe methodLobeBetween(Method method, const std::array<NormalMoments, 4>& moments,
                            const std::array<double, 4>& powers, const MethodParams& params,
                            const std::array<double, 4>* lobePowers, Brdf brdf) {
    // The authored power the filtered moments carry: 1/s averaged, as the bake's 1/s on M's diagonal.
    double invS = 0.0;
    for (double p : powers)
        invS += 0.25 / std::max(clampPower(p), kMinBasePower);
    const double s = 1.0 / invS;
    if (method == Method::Mixture) method = Method::Lean;
    if (method == Method::Toksvig || method == Method::Lean || method == Method::Clean) {
        // Stored values linear in the moments (Na; B and M): filtering averages the moments.
        const double w[4] = {0.25, 0.25, 0.25, 0.25};
        return methodLobe(method, combineMoments(moments.data(), w, 4), s, params);
    }
    // The stored normal is each texel's renormalized mean: averaged, renormalized by the shader.
    glm::dvec3 n(0.0);
    for (const NormalMoments& m : moments)
        n += 0.25 * glm::dvec3(m.meanDirection());
    TexelLobe lobe;
    lobe.normal = glm::length(n) > 0.0 ? glm::vec3(glm::normalize(n)) : glm::vec3(0.0f, 0.0f, 1.0f);
    if (method == Method::Naive) {
        lobe.power = std::max(clampPower(s), kMinBasePower);
    } else if (method == Method::ToksvigMap) {
        // The 8-bit Toksvig factors filtered, converted at run time.
        double ft = 0.0;
        for (const NormalMoments& m : moments)
            ft += 0.25 * std::round(toksvigFactor(double(m.lengthNa()), params.toksvigMapPower) * 255.0) /
                  255.0;
        lobe.power = convertToksvigFactor(ft, params.toksvigMapPower, s) * s;
    } else {
        // Variance-to-gloss, vMF and the fitted lobe store the adjusted gloss: averaged in the encoding
        // (GGX roughness for GGX engines, else the bake's default, blackops), decoded by the shader.
        const GlossEncoding encoding =
            brdf == Brdf::Ggx ? GlossEncoding::ggxRoughness() : GlossEncoding::blackOps();
        double g = 0.0;
        for (size_t i = 0; i < 4; ++i)
            g += 0.25 * encoding.value(lobePowers ? (*lobePowers)[i]
                                                  : methodPower(method, moments[i], powers[i], params));
        lobe.power = encoding.power(float(g));
    }
    return lobe;
}

double methodValue(const TexelLobe& lobe, const DirectionPair& d, Brdf brdf) {
    if (brdf == Brdf::Ggx && !lobe.slopeGaussian) {
        const glm::dvec3 n(lobe.normal);
        return isotropicLobeShading(Brdf::Ggx, glm::dot(n, d.h), glm::dot(n, d.l), glm::dot(n, d.v),
                                    lobe.power);
    }
    return methodNdf(lobe, d.h) * std::max(0.0, glm::dot(glm::dvec3(lobe.normal), d.l));
}

static double truthOfNormal(const glm::dvec3& n, double s, const DirectionPair& d, Brdf brdf) {
    return isotropicLobeShading(brdf, glm::dot(n, d.h), glm::dot(n, d.l), glm::dot(n, d.v), s);
}

double groundTruthTexel(const NormalPyramid& pyramid, int mip, int x, int y,
                        const std::vector<double>& texelPowers, const DirectionPair& d) {
    const PyramidLevel& l = pyramid.level(mip);
    const int width = pyramid.finest().width;
    double sum = 0.0;
    for (int j = l.yStart[size_t(y)]; j < l.yStart[size_t(y) + 1]; ++j)
        for (int i = l.xStart[size_t(x)]; i < l.xStart[size_t(x) + 1]; ++i)
            sum += truthOfNormal(glm::dvec3(pyramid.finest().at(i, j)),
                                 texelPowers[size_t(j) * size_t(width) + size_t(i)], d, Brdf::BlinnPhong);
    return sum / pyramid.footprintCount(mip, x, y);
}

// The bilinear interpolant of the finest normals at point p (texel units, texel (i, j)'s centre at
// (i + 0.5, j + 0.5)), past the edges by the pyramid's border mode, renormalized (the texel under p's
// own normal where the blend cancels).
static glm::dvec3 bilinearNormal(const NormalPyramid& pyramid, glm::dvec2 p) {
    const NormalMap& map = pyramid.finest();
    const BorderMode border = pyramid.options().border;
    const glm::dvec2 u = p - 0.5;
    const int i0 = int(std::floor(u.x)), j0 = int(std::floor(u.y));
    const double tx = u.x - i0, ty = u.y - j0;
    auto at = [&](int i, int j) {
        return glm::dvec3(map.at(borderIndex(i, map.width, border), borderIndex(j, map.height, border)));
    };
    const glm::dvec3 n = (1 - ty) * ((1 - tx) * at(i0, j0) + tx * at(i0 + 1, j0)) +
                         ty * ((1 - tx) * at(i0, j0 + 1) + tx * at(i0 + 1, j0 + 1));
    const double len = glm::length(n);
    return len > 1e-6 ? n / len : at(int(std::floor(p.x)), int(std::floor(p.y)));
}

double groundTruthTexel(const NormalPyramid& pyramid, int mip, int x, int y, double s, const DirectionPair& d,
                        Brdf brdf, TruthNormals how) {
    const PyramidLevel& l = pyramid.level(mip);
    double sum = 0.0;
    const int K = how == TruthNormals::Bilinear ? kBilinearSamples : 1;
    for (int j = l.yStart[size_t(y)]; j < l.yStart[size_t(y) + 1]; ++j)
        for (int i = l.xStart[size_t(x)]; i < l.xStart[size_t(x) + 1]; ++i) {
            if (K == 1) {
                sum += truthOfNormal(glm::dvec3(pyramid.finest().at(i, j)), s, d, brdf);
                continue;
            }
            double texel = 0.0;
            for (int b = 0; b < K; ++b)
                for (int a = 0; a < K; ++a)
                    texel += truthOfNormal(bilinearNormal(pyramid, {i + (a + 0.5) / K, j + (b + 0.5) / K}), s,
                                           d, brdf);
            sum += texel / (K * K);
        }
    return sum / pyramid.footprintCount(mip, x, y);
}

namespace {

// The base powers of the passes, checked: the options' list, or with authored powers one pass
// labelled with their mean.
Result<std::vector<double>> evaluationPowers(const NormalMap& map, const EvaluateOptions& options) {
    std::vector<double> basePowers = options.basePowers;
    if (options.texelPowers) {
        const std::vector<double>& texelPowers = *options.texelPowers;
        if (texelPowers.size() != map.texelCount())
            return Error{"authored powers hold " + std::to_string(texelPowers.size()) + " texels, the map " +
                         std::to_string(map.texelCount())};
        double sum = 0.0;
        for (double s : texelPowers) {
            if (!(s > 0.0) || !(s <= kMaxPower))
                return Error{"an authored power " + std::to_string(s) + " is outside (0, 1e9]"};
            sum += s;
        }
        basePowers = {sum / double(texelPowers.size())};
    }
    if (basePowers.empty()) return Error{"no base power given"};
    for (double s : basePowers)
        if (!(s > 0.0) || !(s <= kMaxPower))
            return Error{"base power " + std::to_string(s) + " is outside (0, 1e9]"};
    return basePowers;
}

// Every lobe of one method at level k: from the kernel-filtered moments when a filtered pyramid is
// given, else the footprint's own box moments; the authored power per texel or the base power s.
// The fitted lobe (fitted set) takes its power from the fit at levels >= 1.
std::vector<TexelLobe> levelLobes(const NormalPyramid& pyramid, const NormalPyramid* filtered, int k,
                                  Method method, FilterKernel kernel, const AuthoredPowers* authored,
                                  double s, const MethodParams& params, const FittedPyramid* fitted) {
    const PyramidLevel& level = pyramid.level(k);
    std::vector<TexelLobe> out(size_t(level.width) * size_t(level.height));
    tbb::parallel_for(0, level.height, [&](int y) {
        for (int x = 0; x < level.width; ++x) {
            TexelLobe& lobe = out[size_t(y) * size_t(level.width) + size_t(x)];
            lobe = methodLobe(method, filtered ? filtered->moments(k, x, y) : pyramid.boxMoments(k, x, y),
                              authored ? authored->power(k, x, y, kernel) : s, params);
            if (fitted && k > 0) lobe.power = fitted->power(k, x, y);
        }
    });
    return out;
}

// The four texels whose shared corner is the point of texel (x, y): (x, y), (x+1, y), (x, y+1),
// (x+1, y+1) through the border mode.
std::array<size_t, 4> cornerTexels(const PyramidLevel& level, int x, int y, BorderMode border) {
    const int x1 = borderIndex(x + 1, level.width, border), y1 = borderIndex(y + 1, level.height, border);
    const size_t w = size_t(level.width);
    return {size_t(y) * w + size_t(x), size_t(y) * w + size_t(x1), size_t(y1) * w + size_t(x),
            size_t(y1) * w + size_t(x1)};
}

// The anisotropic fit's lobe of texel (x, y) of level k; at level 0 (not fitted) the round lobe of the
// texel's base power, which an engine with KHR_materials_anisotropy on still shades in the geometric frame.
AnisotropicLobe anisotropicLobeAt(const NormalPyramid& pyramid, int k, int x, int y,
                                  const FittedPyramid* fitted, double s,
                                  const std::vector<double>* texelPowers) {
    if (k > 0 && fitted) return fitted->anisotropic(k, x, y);
    const double p = texelPowers ? (*texelPowers)[size_t(y) * size_t(pyramid.finest().width) + size_t(x)] : s;
    const double a = ggxSpecularAlpha(ggxAlphaFromPower(p));
    return {a, a, 0.0};
}

// The anisotropic fit's lobes at level k about each texel's renormalized mean normal (the normal texture
// the bake stores).
LobeTable anisotropicTable(const NormalPyramid& pyramid, int k, const FittedPyramid* fitted, double s,
                           const std::vector<double>* texelPowers) {
    const PyramidLevel& level = pyramid.level(k);
    const size_t n = size_t(level.width) * size_t(level.height);
    std::vector<glm::dvec3> normals(n);
    std::vector<AnisotropicLobe> lobes(n);
    tbb::parallel_for(0, level.height, [&](int y) {
        for (int x = 0; x < level.width; ++x) {
            const size_t t = size_t(y) * size_t(level.width) + size_t(x);
            normals[t] = glm::dvec3(pyramid.boxMoments(k, x, y).meanDirection());
            lobes[t] = anisotropicLobeAt(pyramid, k, x, y, fitted, s, texelPowers);
        }
    });
    return LobeTable::ofAnisotropic(normals, lobes);
}

// The anisotropic fit at the corner points of level k as an engine filters its three textures bilinearly
// there: the normal texture's unit normals averaged and renormalized; the roughness texture's r = √α_b
// averaged (α_b = r̄²); the anisotropy texture's direction (cos θ, sin θ) averaged and normalized (three.js,
// the glTF sample viewer) and its strength averaged, α_t = mix(α_b, 1, k̄²).
LobeTable anisotropicCornerTable(const NormalPyramid& pyramid, int k, const FittedPyramid* fitted, double s,
                                 const std::vector<double>* texelPowers) {
    const PyramidLevel& level = pyramid.level(k);
    const BorderMode border = pyramid.options().border;
    const size_t n = size_t(level.width) * size_t(level.height);
    std::vector<glm::dvec3> normals(n);
    std::vector<AnisotropicLobe> lobes(n);
    tbb::parallel_for(0, level.height, [&](int y) {
        for (int x = 0; x < level.width; ++x) {
            const auto t = cornerTexels(level, x, y, border);
            glm::dvec3 normal(0.0);
            glm::dvec2 dir(0.0);
            double r = 0.0, strength = 0.0;
            for (size_t c = 0; c < 4; ++c) {
                const int xi = int(t[c] % size_t(level.width)), yi = int(t[c] / size_t(level.width));
                normal += 0.25 * glm::dvec3(pyramid.boxMoments(k, xi, yi).meanDirection());
                const AnisotropicLobe a = anisotropicLobeAt(pyramid, k, xi, yi, fitted, s, texelPowers);
                r += 0.25 * std::sqrt(a.alphaB);
                dir += 0.25 * glm::dvec2(std::cos(a.angle), std::sin(a.angle));
                strength += 0.25 * a.strength();
            }
            const double len = glm::length(normal), dirLen = glm::length(dir);
            const size_t i = size_t(y) * size_t(level.width) + size_t(x);
            normals[i] = len > 0.0 ? normal / len : glm::dvec3(0.0, 0.0, 1.0);
            const double alphaB = r * r;
            // Directions that cancel leave none: a round lobe.
            const double k2 = dirLen > 1e-9 ? strength * strength : 0.0;
            lobes[i] = {alphaB + (1.0 - alphaB) * k2, alphaB, dirLen > 1e-9 ? std::atan2(dir.y, dir.x) : 0.0};
        }
    });
    return LobeTable::ofAnisotropic(normals, lobes);
}

// One method's figures at one mip from its accumulated sums. Σ GT > 0 whenever a direction has its
// light above the horizon and a normal faces it; a truth of exactly 0 (all normals facing away)
// reports zero error and energy 1.
MipError errorOf(const Accumulator& a, const EvaluatedVariant& v, double s, int k) {
    const bool lit = a.truth > 0.0;
    return {v.method,
            s,
            k,
            lit ? a.absError / a.truth : 0.0,
            lit ? a.method / a.truth : 1.0,
            v.kernel,
            v.lobes,
            false,
            v.floor,
            v.anisotropic};
}

// The per-texel relative error map of one method at one mip: Σ|M − GT| / max(Σ GT, floor), the
// floor kErrorMapTruthFloor of the level's mean truth per texel (a texel whose footprint faces
// away from every light gets its absolute error in units of that floor, not a division by almost
// zero), clamped to the largest float.
ErrorMap errorMapOf(const std::vector<double>& absSum, const std::vector<double>& truthSum,
                    const EvaluatedVariant& v, double s, int k, const PyramidLevel& level) {
    ErrorMap em{v.method, s, k, level.width, level.height, {}, v.kernel, v.lobes, v.floor, v.anisotropic};
    em.relativeError.resize(absSum.size());
    double meanTruth = 0.0;
    for (double t : truthSum)
        meanTruth += t;
    meanTruth /= double(std::max<size_t>(1, truthSum.size()));
    const double floor = kErrorMapTruthFloor * meanTruth;
    for (size_t t = 0; t < absSum.size(); ++t) {
        const double denominator = std::max(truthSum[t], floor);
        const double e = denominator > 0.0 ? absSum[t] / denominator : 0.0;
        em.relativeError[t] = std::isfinite(e) ? float(std::min(e, double(std::numeric_limits<float>::max())))
                                               : std::numeric_limits<float>::max();
    }
    return em;
}

// One base power's pass: every variant's lobe tables per evaluated mip (at texels and, with
// betweenTexels, at corner points), and the per-texel sums of the error maps ([method][mip]
// |M − GT|, [mip] GT) when they are asked for.
struct Pass {
    std::vector<std::vector<LobeTable>> tables;
    std::vector<std::vector<LobeTable>> betweenTables;
    std::vector<std::vector<std::vector<double>>> texelAbs;
    std::vector<std::vector<double>> texelTruth;
    bool errorMaps = false;
    bool betweenTexels = false;
};

// Every variant's lobe at every corner point of level k (mip index mi) into the pass's tables.
void betweenLevel(const NormalMap& map, const NormalPyramid& pyramid, int k, size_t mi,
                  const std::vector<EvaluatedVariant>& variants,
                  const std::vector<const MixturePyramid*>& mixtures,
                  const std::vector<const FittedPyramid*>& fitted, const AuthoredPowers* authored,
                  const std::vector<double>* texelPowers, double s, const MethodParams& params,
                  MixtureFiltering filtering, Brdf brdf, Pass& pass) {
    const PyramidLevel& level = pyramid.level(k);
    const BorderMode border = pyramid.options().border;
    const size_t n = size_t(level.width) * size_t(level.height);
    for (size_t m = 0; m < variants.size(); ++m) {
        const MixturePyramid* mix = mixtures[m];
        // A stored texel of the mixture (its lobes over its total weight, in their slots).
        auto stored = [&](const MixturePyramid& mixture, size_t t) {
            const int xi = int(t % size_t(level.width)), yi = int(t / size_t(level.width));
            const double p =
                k == 0 && texelPowers ? (*texelPowers)[size_t(yi) * size_t(map.width) + size_t(xi)] : s;
            return mixture.storedTexel(map, k, xi, yi, p);
        };
        if (mix && brdf == Brdf::Ggx) {
            // The GGX form (mixtureGgxLobe): the stored lobes bilinearly filtered at the corner, by slot, or
            // after shading each texel's own.
            const int lobes = mix->lobeCount();
            std::vector<MixtureGgxStored> texels(n);
            tbb::parallel_for(0, level.height, [&](int y) {
                for (int x = 0; x < level.width; ++x)
                    texels[size_t(y) * size_t(level.width) + size_t(x)] =
                        mixtureGgxStored(*mix, map, k, x, y, s);
            });
            std::vector<std::array<size_t, 4>> corners(n);
            std::vector<LobeTable::GgxMixtureTexel> decoded(n);
            tbb::parallel_for(0, level.height, [&](int y) {
                for (int x = 0; x < level.width; ++x) {
                    const size_t i = size_t(y) * size_t(level.width) + size_t(x);
                    corners[i] = cornerTexels(level, x, y, border);
                    if (filtering == MixtureFiltering::Stochastic) {
                        decoded[i] = mixtureGgxDecoded(texels[i], lobes, s);
                        continue;
                    }
                    MixtureGgxStored sum{};
                    for (size_t c = 0; c < 4; ++c)
                        for (size_t l = 0; l < sum.size(); ++l)
                            for (size_t j = 0; j < 4; ++j)
                                sum[l][j] += 0.25 * texels[corners[i][c]][l][j];
                    decoded[i] = mixtureGgxDecoded(sum, lobes, s);
                }
            });
            pass.betweenTables[m][mi] =
                filtering == MixtureFiltering::Stochastic
                    ? LobeTable::ofGgxBlends(decoded, lobes, corners, {0.25, 0.25, 0.25, 0.25})
                    : LobeTable::ofGgxMixture(decoded, lobes);
            continue;
        }
        if (mix && filtering == MixtureFiltering::Stochastic) {
            // Filtering after shading: the corner's value is ¼ of each of its four texels' mixture values.
            std::vector<DecodedMixture> texels(n);
            std::vector<std::array<size_t, 4>> corners(n);
            tbb::parallel_for(0, level.height, [&](int y) {
                for (int x = 0; x < level.width; ++x) {
                    const size_t t = size_t(y) * size_t(level.width) + size_t(x);
                    LobeMixture own;
                    for (const LobeMoments& l : stored(*mix, t))
                        if (l.w > 0.0) own.lobes[size_t(own.count++)] = l;
                    texels[t] = decodeMixture(own, mix->minVariance());
                    corners[t] = cornerTexels(level, x, y, border);
                }
            });
            pass.betweenTables[m][mi] = LobeTable::ofBlends(texels, corners, {0.25, 0.25, 0.25, 0.25});
            continue;
        }
        if (mix) {
            std::vector<DecodedMixture> out(n);
            tbb::parallel_for(0, level.height, [&](int y) {
                for (int x = 0; x < level.width; ++x) {
                    // Bilinear filtering at the corner: ¼ of each texel's stored lobes, by slot.
                    const auto t = cornerTexels(level, x, y, border);
                    std::array<LobeMoments, kMaxMixtureLobes> sum{};
                    for (size_t c = 0; c < 4; ++c) {
                        const auto lobes = stored(*mix, t[c]);
                        for (size_t i = 0; i < lobes.size(); ++i)
                            sum[i] += lobes[i].scaled(0.25);
                    }
                    LobeMixture filtered;
                    for (const LobeMoments& l : sum)
                        if (l.w > 0.0) filtered.lobes[size_t(filtered.count++)] = l;
                    out[size_t(y) * size_t(level.width) + size_t(x)] =
                        decodeMixture(filtered, mix->minVariance());
                }
            });
            pass.betweenTables[m][mi] = LobeTable::of(out);
            continue;
        }
        if (variants[m].anisotropic) {
            pass.betweenTables[m][mi] = anisotropicCornerTable(pyramid, k, fitted[m], s, texelPowers);
            continue;
        }
        std::vector<TexelLobe> out(n);
        tbb::parallel_for(0, level.height, [&](int y) {
            for (int x = 0; x < level.width; ++x) {
                const auto t = cornerTexels(level, x, y, border);
                std::array<NormalMoments, 4> moments;
                std::array<double, 4> powers, lobePowers;
                for (size_t c = 0; c < 4; ++c) {
                    const int xi = int(t[c] % size_t(level.width)), yi = int(t[c] / size_t(level.width));
                    moments[c] = pyramid.boxMoments(k, xi, yi);
                    powers[c] = authored ? authored->power(k, xi, yi, FilterKernel::Box) : s;
                    lobePowers[c] = fitted[m] && k > 0 ? fitted[m]->power(k, xi, yi) : powers[c];
                }
                out[size_t(y) * size_t(level.width) + size_t(x)] =
                    methodLobeBetween(variants[m].method, moments, powers, params,
                                      variants[m].method == Method::Fitted ? &lobePowers : nullptr, brdf);
            }
        });
        pass.betweenTables[m][mi] = LobeTable::of(out, brdf);
    }
}

// The mixture's lobes at every texel of level k (0 included) as an engine's GGX shades them.
LobeTable ggxMixtureLevel(const MixturePyramid& mix, const NormalMap& map, const PyramidLevel& level, int k,
                          double s) {
    std::vector<LobeTable::GgxMixtureTexel> out(size_t(level.width) * size_t(level.height));
    tbb::parallel_for(0, level.height, [&](int y) {
        for (int x = 0; x < level.width; ++x)
            out[size_t(y) * size_t(level.width) + size_t(x)] =
                mixtureGgxDecoded(mixtureGgxStored(mix, map, k, x, y, s), mix.lobeCount(), s);
    });
    return LobeTable::ofGgxMixture(out, mix.lobeCount());
}

// The decoded mixture of every texel of level k (k >= 1).
std::vector<DecodedMixture> decodedLevel(const MixturePyramid& mix, const PyramidLevel& level, int k) {
    std::vector<DecodedMixture> out(size_t(level.width) * size_t(level.height));
    tbb::parallel_for(0, level.height, [&](int y) {
        for (int x = 0; x < level.width; ++x)
            out[size_t(y) * size_t(level.width) + size_t(x)] =
                decodeMixture(mix.at(k, x, y), mix.minVariance());
    });
    return out;
}

// A band: the texels under one row of the coarsest evaluated level, at every level down to the
// finest. The pyramid nests (each row's children are rows of the level below), so a band's truth
// sums need nothing outside it, and its rows are contiguous at every level.
struct Band {
    std::vector<int> rowBegin, rowEnd; // per level 0..last: the band's rows there
};

Band bandOf(const NormalPyramid& pyramid, int last, int y) {
    Band b;
    b.rowBegin.resize(size_t(last) + 1);
    b.rowEnd.resize(size_t(last) + 1);
    b.rowBegin[size_t(last)] = y, b.rowEnd[size_t(last)] = y + 1;
    for (int k = last; k > 0; --k) {
        const PyramidLevel& level = pyramid.level(k);
        b.rowBegin[size_t(k - 1)] = level.yChild[size_t(b.rowBegin[size_t(k)])];
        b.rowEnd[size_t(k - 1)] = level.yChild[size_t(b.rowEnd[size_t(k)])];
    }
    return b;
}

// A band's finest normals as three float arrays (what the truth loop reads for every direction),
// and per level the truth of each of its texels for the current direction pair.
struct BandTruth {
    Band band;
    TruthBand finest;
    std::vector<std::vector<double>> sums;  // per level: Σ over each texel's footprint
    std::vector<std::vector<double>> truth; // per evaluated level: the footprint's mean

    BandTruth(const NormalMap& map, const NormalPyramid& pyramid, int last, int y, TruthNormals how)
        : band(bandOf(pyramid, last, y))
        , finest(map, band.rowBegin[0], band.rowEnd[0], how, pyramid.options().border) {
        sums.resize(size_t(last) + 1);
        truth.resize(size_t(last) + 1);
        for (int k = 0; k <= last; ++k) {
            const size_t n = size_t(rows(k)) * size_t(pyramid.level(k).width);
            sums[size_t(k)].resize(n);
            truth[size_t(k)].resize(n);
        }
    }
    int rows(int k) const { return band.rowEnd[size_t(k)] - band.rowBegin[size_t(k)]; }

    // The truth for pair d: the finest normals' values, summed up the levels (each a sum of its
    // children), and divided by the footprint's texel count from level `first` on.
    void compute(const NormalMap& map, const NormalPyramid& pyramid, const std::vector<double>* texelPowers,
                 double s, int first, const DirectionPair& d, Brdf brdf) {
        const size_t begin = size_t(band.rowBegin[0]) * size_t(map.width);
        finest.values(brdf, texelPowers ? texelPowers->data() + begin : nullptr, s, d, sums[0].data());
        for (int k = 1; k < int(sums.size()); ++k) {
            const PyramidLevel& level = pyramid.level(k);
            const PyramidLevel& child = pyramid.level(k - 1);
            const int childRow0 = band.rowBegin[size_t(k - 1)];
            for (int y = band.rowBegin[size_t(k)]; y < band.rowEnd[size_t(k)]; ++y)
                for (int x = 0; x < level.width; ++x) {
                    double sum = 0.0;
                    for (int j = level.yChild[size_t(y)]; j < level.yChild[size_t(y) + 1]; ++j)
                        for (int i = level.xChild[size_t(x)]; i < level.xChild[size_t(x) + 1]; ++i)
                            sum +=
                                sums[size_t(k - 1)][size_t(j - childRow0) * size_t(child.width) + size_t(i)];
                    sums[size_t(k)][size_t(y - band.rowBegin[size_t(k)]) * size_t(level.width) + size_t(x)] =
                        sum;
                }
        }
        for (int k = first; k < int(sums.size()); ++k) {
            const PyramidLevel& level = pyramid.level(k);
            for (int y = band.rowBegin[size_t(k)]; y < band.rowEnd[size_t(k)]; ++y) {
                const size_t row = size_t(y - band.rowBegin[size_t(k)]) * size_t(level.width);
                for (int x = 0; x < level.width; ++x)
                    truth[size_t(k)][row + size_t(x)] =
                        sums[size_t(k)][row + size_t(x)] / pyramid.footprintCount(k, x, y);
            }
        }
    }
    // The truth of texel (x, y) of level k, which lies in this band.
    double at(const NormalPyramid& pyramid, int k, int x, int y) const {
        return truth[size_t(k)]
                    [size_t(y - band.rowBegin[size_t(k)]) * size_t(pyramid.level(k).width) + size_t(x)];
    }
};

// What evaluating one band adds up: per variant and evaluated mip [m·mips + mi].
struct BandSums {
    std::vector<Accumulator> acc, between;
};

// Adds |v − truth|, v and truth of n texels to a, and |v − truth| to the error map row when given.
void accumulate(const double* v, const double* truth, size_t n, Accumulator& a, double* absMap) {
    double absError = 0.0, method = 0.0, sumTruth = 0.0;
    for (size_t i = 0; i < n; ++i) {
        absError += std::abs(v[i] - truth[i]);
        method += v[i];
        sumTruth += truth[i];
    }
    a.absError += absError, a.method += method, a.truth += sumTruth;
    if (absMap)
        for (size_t i = 0; i < n; ++i)
            absMap[i] += std::abs(v[i] - truth[i]);
}

// Every direction pair's error over one band (row y of the last evaluated level), for every variant
// and evaluated mip. The corner points of the band's last row at each level need the truth of the
// next band's first row, so with betweenTexels the next band's truth is computed too.
BandSums evaluateBand(const NormalMap& map, const NormalPyramid& pyramid,
                      const std::vector<double>* texelPowers, double s, int first, int last, int y,
                      const std::vector<DirectionPair>& directions, Brdf brdf, TruthNormals how, Pass& pass) {
    const size_t variants = pass.tables.size();
    const size_t mips = size_t(last - first + 1);
    const BorderMode border = pyramid.options().border;
    BandSums out;
    out.acc.assign(variants * mips, {});
    if (pass.betweenTexels) out.between.assign(variants * mips, {});
    BandTruth band(map, pyramid, last, y, how);
    std::optional<BandTruth> next;
    const int nextY = borderIndex(y + 1, pyramid.level(last).height, border);
    if (pass.betweenTexels && nextY != y) next.emplace(map, pyramid, last, nextY, how);
    std::vector<double> values(band.truth[size_t(first)].size()), corner(values.size());
    for (const DirectionPair& d : directions) {
        band.compute(map, pyramid, texelPowers, s, first, d, brdf);
        if (next) next->compute(map, pyramid, texelPowers, s, first, d, brdf);
        for (int k = first; k <= last; ++k) {
            const size_t mi = size_t(k - first);
            const PyramidLevel& level = pyramid.level(k);
            const size_t begin = size_t(band.band.rowBegin[size_t(k)]) * size_t(level.width);
            const size_t n = size_t(band.rows(k)) * size_t(level.width);
            const double* truth = band.truth[size_t(k)].data();
            if (pass.errorMaps)
                for (size_t i = 0; i < n; ++i)
                    pass.texelTruth[mi][begin + i] += truth[i];
            for (size_t m = 0; m < variants; ++m) {
                lobeValues(pass.tables[m][mi], begin, begin + n, d, values.data());
                accumulate(values.data(), truth, n, out.acc[m * mips + mi],
                           pass.errorMaps ? pass.texelAbs[m][mi].data() + begin : nullptr);
            }
            if (!pass.betweenTexels) continue;
            // The truth at each corner point: ¼ of each of the four footprints' means.
            for (int yy = band.band.rowBegin[size_t(k)]; yy < band.band.rowEnd[size_t(k)]; ++yy) {
                const int y1 = borderIndex(yy + 1, level.height, border);
                const BandTruth& below =
                    y1 < band.band.rowEnd[size_t(k)] && y1 >= band.band.rowBegin[size_t(k)] ? band : *next;
                for (int x = 0; x < level.width; ++x) {
                    const int x1 = borderIndex(x + 1, level.width, border);
                    corner[size_t(yy - band.band.rowBegin[size_t(k)]) * size_t(level.width) + size_t(x)] =
                        0.25 * band.at(pyramid, k, x, yy) + 0.25 * band.at(pyramid, k, x1, yy) +
                        0.25 * below.at(pyramid, k, x, y1) + 0.25 * below.at(pyramid, k, x1, y1);
                }
            }
            for (size_t m = 0; m < variants; ++m) {
                lobeValues(pass.betweenTables[m][mi], begin, begin + n, d, values.data());
                accumulate(values.data(), corner.data(), n, out.between[m * mips + mi], nullptr);
            }
        }
    }
    return out;
}

} // namespace

Result<EvaluationResult> evaluateMethods(const NormalMap& map, const EvaluateOptions& options,
                                         const std::function<void(double)>& progress,
                                         const std::atomic<bool>* cancel) {
    const auto start = std::chrono::steady_clock::now();
    // Relaxed: the flag carries no data, only "stop"; the worker sees it at its next check.
    auto cancelled = [cancel] { return cancel && cancel->load(std::memory_order_relaxed); };
    if (cancelled()) return Error{std::string(kCancelledMessage)};
    if (map.texelCount() == 0) return Error{"the normal map is empty"};
    const std::vector<double>* texelPowers = options.texelPowers ? &*options.texelPowers : nullptr;
    auto checkedPowers = evaluationPowers(map, options);
    if (!checkedPowers) return Error{checkedPowers.error()};
    const std::vector<double> basePowers = std::move(checkedPowers).value();
    if (options.methods.empty()) return Error{"no method given"};
    if (!(options.viewAngleDeg >= 0.0 && options.viewAngleDeg < 90.0))
        return Error{"view angle must lie in [0, 90) degrees"};
    const auto directions = evaluationDirections(options);
    if (directions.empty()) return Error{"no light direction lies above the horizon limit for these angles"};
    if (options.energySplit && texelPowers)
        return Error{"the energy split takes base powers, not authored gloss (each texel's own power)"};
    if (options.energySplit && !(options.steepDeg > 0.0 && options.steepDeg < 90.0))
        return Error{"the steep angle must lie in (0, 90) degrees"};
    if (options.energySplit && options.resolvedTruthNormals() != TruthNormals::Texels)
        return Error{"the energy split is measured on the finest texels (--truth-normals texels)"};
    if (options.anisotropic && options.brdf != Brdf::Ggx)
        return Error{
            "the anisotropic fit is KHR_materials_anisotropy's, under the GGX truth only (--brdf ggx)"};
    if (options.brdf == Brdf::Ggx) {
        if (options.energySplit) return Error{"the energy split is LEAN's, under the Blinn-Phong truth only"};
        const bool mixture = std::find(options.methods.begin(), options.methods.end(), Method::Mixture) !=
                             options.methods.end();
        if (mixture && texelPowers)
            return Error{
                "the mixture under --brdf ggx is fitted for one base roughness, not authored gloss (each "
                "texel's own), as burnish gltf writes it"};
        if (mixture && options.params.mixtureShadedFit)
            return Error{
                "the mixture's shaded fit is the Blinn-Phong truth's; under --brdf ggx the lobes are the "
                "moments' own"};
        const std::vector<Method> ggx = methodsUnder(Brdf::Ggx);
        for (Method m : options.methods)
            if (std::find(ggx.begin(), ggx.end(), m) == ggx.end()) {
                std::string names;
                for (Method g : ggx)
                    names += (names.empty() ? "" : ", ") + std::string(methodName(g));
                return Error{"method '" + std::string(methodName(m)) +
                             "' is a slope-space Gaussian with no GGX form; --brdf ggx evaluates the methods "
                             "an engine shades as GGX lobes (" +
                             names + ")"};
            }
    }

    // The pyramid only borrows the map for the duration of this call.
    const std::shared_ptr<const NormalMap> borrowed(&map, [](const NormalMap*) {});
    const NormalPyramid pyramid = NormalPyramid::build(borrowed, {options.border, FilterKernel::Box});
    const int lastLevel = pyramid.levelCount() - 1;
    if (options.firstMip < 0 || options.firstMip > lastLevel || options.lastMip < options.firstMip)
        return Error{"mip range " + std::to_string(options.firstMip) + ".." +
                     std::to_string(options.lastMip) + " does not fit a " + std::to_string(map.width) + "x" +
                     std::to_string(map.height) + " map (levels 0.." + std::to_string(lastLevel) + ")"};
    const int firstMip = options.firstMip;
    const int lastMip = std::min(options.lastMip, lastLevel);
    const int mipCount = lastMip - firstMip + 1;
    if (options.kernels.empty()) return Error{"no footprint kernel given"};
    // Variants: every method with every kernel, kernel-major, the mixture once per K (box only).
    // Box variants read the footprint's own moments (the definition); others read the
    // kernel-filtered moments a bake would store, reported beside them.
    const std::vector<EvaluatedVariant> variants = evaluatedVariants(options);
    if (variants.empty()) return Error{"no method to evaluate (the mixture has box footprints only)"};
    const size_t methodCount = variants.size();
    auto kernelIndex = [&](FilterKernel kernel) {
        return size_t(std::find(options.kernels.begin(), options.kernels.end(), kernel) -
                      options.kernels.begin());
    };
    std::vector<std::optional<NormalPyramid>> filtered(options.kernels.size());
    for (size_t i = 0; i < options.kernels.size(); ++i)
        if (options.kernels[i] != FilterKernel::Box)
            filtered[i].emplace(NormalPyramid::build(borrowed, {options.border, options.kernels[i]}));

    EvaluationResult result;
    result.directions = directions;
    result.firstMip = firstMip;
    result.lastMip = lastMip;
    result.basePowers = basePowers;
    std::optional<AuthoredPowers> authored;
    if (texelPowers) authored.emplace(pyramid, *texelPowers, lastMip);

    // Work is done a band at a time (evaluateBand), in batches so that progress and the cancel flag
    // are seen on this thread between them.
    const int bands = pyramid.level(lastMip).height;
    const int batches = bandBatches(bands);
    const double totalSteps = double(basePowers.size()) * double(bands);
    double stepsDone = 0.0;
    for (double s : basePowers) {
        Pass pass;
        pass.errorMaps = options.errorMaps;
        pass.betweenTexels = options.betweenTexels;
        // The mixtures, one per K >= 2 (K = 1 is LEAN's lobe, from the moments), every level up to
        // 1×1 as the bake builds them: a level's lobe slots follow the level above (the top level's
        // are canonical), so the last evaluated mip holds the slots the bake stores.
        std::vector<std::optional<MixturePyramid>> mixturePyramids(kMaxMixtureLobes + 1);
        std::vector<const MixturePyramid*> mixtures(methodCount, nullptr);
        for (size_t m = 0; m < methodCount; ++m) {
            const EvaluatedVariant& v = variants[m];
            // Under GGX every K, 1 included, is the mixture's own GGX form (no LEAN lobe there).
            if (v.method != Method::Mixture || (v.lobes < 2 && options.brdf != Brdf::Ggx)) continue;
            if (cancelled()) return Error{std::string(kCancelledMessage)};
            auto& mix = mixturePyramids[size_t(v.lobes)];
            if (!mix)
                mix.emplace(options.params.mixtureShadedFit
                                ? buildShadedMixture(pyramid, s, v.lobes, -1, texelPowers)
                                : MixturePyramid::build(pyramid, s, v.lobes, -1, texelPowers));
            mixtures[m] = &*mix;
        }
        // The fitted lobes (and the floor), one per kernel: each fitted to the normal its kernel's
        // moments give, against the box footprint's truth.
        std::vector<std::optional<FittedPyramid>> fittedPyramids(methodCount);
        std::vector<const FittedPyramid*> fitted(methodCount, nullptr);
        for (size_t m = 0; m < methodCount; ++m) {
            const EvaluatedVariant& v = variants[m];
            if (v.method != Method::Fitted || lastMip < 1) continue;
            if (cancelled()) return Error{std::string(kCancelledMessage)};
            const auto& kernelPyramid = filtered[kernelIndex(v.kernel)];
            FittedLobeOptions fit;
            fit.brdf = options.brdf;
            fit.truthNormals = options.resolvedTruthNormals();
            fit.directions = directions;
            fit.floor = v.floor;
            fit.anisotropic = v.anisotropic;
            const AuthoredPowers* a = authored ? &*authored : nullptr;
            fittedPyramids[m].emplace(FittedPyramid::build(
                kernelPyramid ? *kernelPyramid : pyramid,
                [&](int k, int x, int y) { return a ? a->power(k, x, y, v.kernel) : s; }, texelPowers, s,
                lastMip, fit, cancelled));
            if (cancelled()) return Error{std::string(kCancelledMessage)};
            fitted[m] = &*fittedPyramids[m];
        }
        // Lobes of every variant at every evaluated mip.
        pass.tables.assign(methodCount, std::vector<LobeTable>(size_t(mipCount)));
        for (size_t m = 0; m < methodCount; ++m)
            for (int k = firstMip; k <= lastMip; ++k) {
                if (cancelled()) return Error{std::string(kCancelledMessage)};
                const EvaluatedVariant& v = variants[m];
                auto& table = pass.tables[m][size_t(k - firstMip)];
                if (mixtures[m] && options.brdf == Brdf::Ggx) {
                    table = ggxMixtureLevel(*mixtures[m], map, pyramid.level(k), k, s);
                    continue;
                }
                // A mixture's level 0 is each normal's own lobe: LEAN's of the one-texel footprint.
                if (mixtures[m] && k > 0) {
                    table = LobeTable::of(decodedLevel(*mixtures[m], pyramid.level(k), k));
                    continue;
                }
                const auto& kernelPyramid = filtered[kernelIndex(v.kernel)];
                if (v.anisotropic) {
                    table = anisotropicTable(pyramid, k, fitted[m], s, texelPowers);
                    continue;
                }
                table = LobeTable::of(levelLobes(pyramid, kernelPyramid ? &*kernelPyramid : nullptr, k,
                                                 v.method, v.kernel, authored ? &*authored : nullptr, s,
                                                 options.params, fitted[m]),
                                      options.brdf);
            }
        if (options.betweenTexels) {
            pass.betweenTables.assign(methodCount, std::vector<LobeTable>(size_t(mipCount)));
            for (int k = firstMip; k <= lastMip; ++k) {
                if (cancelled()) return Error{std::string(kCancelledMessage)};
                betweenLevel(map, pyramid, k, size_t(k - firstMip), variants, mixtures, fitted,
                             authored ? &*authored : nullptr, texelPowers, s, options.params,
                             options.mixtureFiltering, options.brdf, pass);
            }
        }
        if (options.errorMaps) {
            pass.texelAbs.assign(methodCount, std::vector<std::vector<double>>(size_t(mipCount)));
            pass.texelTruth.resize(size_t(mipCount));
            for (int k = firstMip; k <= lastMip; ++k) {
                const size_t n = size_t(pyramid.level(k).width) * size_t(pyramid.level(k).height);
                pass.texelTruth[size_t(k - firstMip)].assign(n, 0.0);
                for (size_t m = 0; m < methodCount; ++m)
                    pass.texelAbs[m][size_t(k - firstMip)].assign(n, 0.0);
            }
        }

        std::vector<BandSums> sums(static_cast<size_t>(bands));
        for (int b = 0; b < batches; ++b) {
            if (cancelled()) return Error{std::string(kCancelledMessage)};
            const int from = int(int64_t(bands) * b / batches), to = int(int64_t(bands) * (b + 1) / batches);
            tbb::parallel_for(from, to, [&](int y) {
                sums[size_t(y)] = evaluateBand(map, pyramid, texelPowers, s, firstMip, lastMip, y, directions,
                                               options.brdf, options.resolvedTruthNormals(), pass);
            });
            stepsDone += double(to - from);
            if (progress) progress(stepsDone / totalSteps);
        }

        // Added in band order: the same figures on any number of threads.
        std::vector<Accumulator> acc(methodCount * size_t(mipCount)), between(acc.size());
        for (const BandSums& band : sums)
            for (size_t i = 0; i < acc.size(); ++i) {
                acc[i].absError += band.acc[i].absError, acc[i].method += band.acc[i].method,
                    acc[i].truth += band.acc[i].truth;
                if (!options.betweenTexels) continue;
                between[i].absError += band.between[i].absError, between[i].method += band.between[i].method,
                    between[i].truth += band.between[i].truth;
            }
        for (size_t m = 0; m < methodCount; ++m)
            for (int k = firstMip; k <= lastMip; ++k) {
                const size_t mi = size_t(k - firstMip);
                result.errors.push_back(errorOf(acc[m * size_t(mipCount) + mi], variants[m], s, k));
                if (options.betweenTexels) {
                    result.errors.push_back(errorOf(between[m * size_t(mipCount) + mi], variants[m], s, k));
                    result.errors.back().betweenTexels = true;
                }
                if (options.errorMaps)
                    result.maps.push_back(errorMapOf(pass.texelAbs[m][mi], pass.texelTruth[mi], variants[m],
                                                     s, k, pyramid.level(k)));
            }
        if (options.energySplit) {
            auto split = leanEnergySplit(pyramid, s, firstMip, lastMip, directions, options.steepDeg,
                                         options.params, cancelled);
            if (cancelled()) return Error{std::string(kCancelledMessage)};
            result.energySplits.insert(result.energySplits.end(), split.begin(), split.end());
        }
    }
    // A flag raised during the last pass still wins: the caller asked for no result.
    if (cancelled()) return Error{std::string(kCancelledMessage)};
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

} // namespace burnish
