#include <burnish/core/eval/evaluate.h>

#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/shading/ndf.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace burnish {

namespace {

double radians(double deg) {
    return deg * kPi<double> / 180.0;
}

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
    return out;
}

std::string variantLabel(const EvaluatedVariant& v) {
    std::string label(methodName(v.method));
    if (v.method == Method::Mixture) label += "-k" + std::to_string(v.lobes);
    if (v.kernel != FilterKernel::Box) label += " (" + std::string(kernelName(v.kernel)) + ")";
    return label;
}

std::vector<DirectionPair> evaluationDirections(const EvaluateOptions& options) {
    std::vector<DirectionPair> pairs;
    const double thetaV = radians(options.viewAngleDeg);
    const glm::dvec3 v(std::sin(thetaV), 0.0, std::cos(thetaV));
    const double minLz = std::sin(radians(options.horizonDeg));
    for (double thetaDeg : options.halfAnglesDeg) {
        const double thetaH = radians(thetaDeg);
        // At θh = 0 every azimuth gives the same half vector: count it once.
        const int count = thetaDeg == 0.0 ? 1 : std::max(options.azimuths, 1);
        for (int j = 0; j < count; ++j) {
            const double phi = 2.0 * kPi<double> * j / count;
            const glm::dvec3 h(std::sin(thetaH) * std::cos(phi), std::sin(thetaH) * std::sin(phi),
                               std::cos(thetaH));
            const glm::dvec3 l = 2.0 * glm::dot(v, h) * h - v;
            if (l.z < minLz) continue;
            pairs.push_back({glm::normalize(l), v, h});
        }
    }
    return pairs;
}

TexelLobe methodLobeBetween(Method method, const std::array<NormalMoments, 4>& moments,
                            const std::array<double, 4>& powers, const MethodParams& params) {
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
        // Variance-to-gloss and vMF store the adjusted gloss: averaged in the encoding (the bake's
        // default, blackops), decoded by the shader.
        const GlossEncoding encoding = GlossEncoding::blackOps();
        double g = 0.0;
        for (size_t i = 0; i < 4; ++i)
            g += 0.25 * encoding.value(methodPower(method, moments[i], powers[i], params));
        lobe.power = encoding.power(float(g));
    }
    return lobe;
}

double methodValue(const TexelLobe& lobe, const DirectionPair& d) {
    return methodNdf(lobe, d.h) * std::max(0.0, glm::dot(glm::dvec3(lobe.normal), d.l));
}

static double truthOfNormal(const glm::dvec3& n, double s, const DirectionPair& d) {
    return blinnPhongNdf(glm::dot(n, d.h), s) * std::max(0.0, glm::dot(n, d.l));
}

double groundTruthTexel(const NormalPyramid& pyramid, int mip, int x, int y,
                        const std::vector<double>& texelPowers, const DirectionPair& d) {
    const PyramidLevel& l = pyramid.level(mip);
    const int width = pyramid.finest().width;
    double sum = 0.0;
    for (int j = l.yStart[size_t(y)]; j < l.yStart[size_t(y) + 1]; ++j)
        for (int i = l.xStart[size_t(x)]; i < l.xStart[size_t(x) + 1]; ++i)
            sum += truthOfNormal(glm::dvec3(pyramid.finest().at(i, j)),
                                 texelPowers[size_t(j) * size_t(width) + size_t(i)], d);
    return sum / pyramid.footprintCount(mip, x, y);
}

double groundTruthTexel(const NormalPyramid& pyramid, int mip, int x, int y, double s,
                        const DirectionPair& d) {
    const PyramidLevel& l = pyramid.level(mip);
    double sum = 0.0;
    for (int j = l.yStart[size_t(y)]; j < l.yStart[size_t(y) + 1]; ++j)
        for (int i = l.xStart[size_t(x)]; i < l.xStart[size_t(x) + 1]; ++i)
            sum += truthOfNormal(glm::dvec3(pyramid.finest().at(i, j)), s, d);
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
std::vector<TexelLobe> levelLobes(const NormalPyramid& pyramid, const NormalPyramid* filtered, int k,
                                  Method method, FilterKernel kernel, const AuthoredPowers* authored,
                                  double s, const MethodParams& params) {
    const PyramidLevel& level = pyramid.level(k);
    std::vector<TexelLobe> out(size_t(level.width) * size_t(level.height));
    tbb::parallel_for(0, level.height, [&](int y) {
        for (int x = 0; x < level.width; ++x)
            out[size_t(y) * size_t(level.width) + size_t(x)] =
                methodLobe(method, filtered ? filtered->moments(k, x, y) : pyramid.boxMoments(k, x, y),
                           authored ? authored->power(k, x, y, kernel) : s, params);
    });
    return out;
}

// The ground truth for one direction pair, summed hierarchically: level 0 holds each finest
// normal's D_s(n·h)·max(0, n·l), level k the sum of its children at level k−1 (sums has one vector
// per level up to the last evaluated one).
void truthSums(const NormalMap& map, const NormalPyramid& pyramid, const std::vector<double>* texelPowers,
               double s, const DirectionPair& d, std::vector<std::vector<double>>& sums) {
    const PyramidLevel& l0 = pyramid.level(0);
    tbb::parallel_for(0, l0.height, [&](int y) {
        for (int x = 0; x < l0.width; ++x)
            sums[0][size_t(y) * size_t(l0.width) + size_t(x)] =
                truthOfNormal(glm::dvec3(map.at(x, y)),
                              texelPowers ? (*texelPowers)[size_t(y) * size_t(l0.width) + size_t(x)] : s, d);
    });
    for (int k = 1; k < int(sums.size()); ++k) {
        const PyramidLevel& level = pyramid.level(k);
        const PyramidLevel& child = pyramid.level(k - 1);
        tbb::parallel_for(0, level.height, [&](int y) {
            for (int x = 0; x < level.width; ++x) {
                double sum = 0.0;
                for (int j = level.yChild[size_t(y)]; j < level.yChild[size_t(y) + 1]; ++j)
                    for (int i = level.xChild[size_t(x)]; i < level.xChild[size_t(x) + 1]; ++i)
                        sum += sums[size_t(k - 1)][size_t(j) * size_t(child.width) + size_t(i)];
                sums[size_t(k)][size_t(y) * size_t(level.width) + size_t(x)] = sum;
            }
        });
    }
}

// One method's figures at one mip from its accumulated sums. Σ GT > 0 whenever a direction has its
// light above the horizon and a normal faces it; a truth of exactly 0 (all normals facing away)
// reports zero error and energy 1.
MipError errorOf(const Accumulator& a, const EvaluatedVariant& v, double s, int k) {
    const bool lit = a.truth > 0.0;
    return {v.method, s,      k, lit ? a.absError / a.truth : 0.0, lit ? a.method / a.truth : 1.0,
            v.kernel, v.lobes};
}

// The per-texel relative error map of one method at one mip: Σ|M − GT| / max(Σ GT, floor), the
// floor kErrorMapTruthFloor of the level's mean truth per texel (a texel whose footprint faces
// away from every light gets its absolute error in units of that floor, not a division by almost
// zero), clamped to the largest float.
ErrorMap errorMapOf(const std::vector<double>& absSum, const std::vector<double>& truthSum,
                    const EvaluatedVariant& v, double s, int k, const PyramidLevel& level) {
    ErrorMap em{v.method, s, k, level.width, level.height, {}, v.kernel, v.lobes};
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

// One base power's pass: every variant's lobes per evaluated mip, their accumulated sums, and the
// per-texel sums of the error maps ([method][mip] |M − GT|, [mip] GT) when they are asked for.
struct Pass {
    std::vector<std::vector<std::vector<TexelLobe>>> lobes;
    // Between texels (options.betweenTexels): per variant and mip the lobe at each texel's corner
    // point, a decoded mixture for the mixture's variants (K >= 2), and the sums.
    std::vector<std::vector<std::vector<TexelLobe>>> betweenLobes;
    std::vector<std::vector<std::vector<DecodedMixture>>> betweenMixtures;
    std::vector<std::vector<Accumulator>> betweenAcc;
    // Per variant: the mixture's lobes (K >= 2), or none (its TexelLobes above).
    std::vector<const MixturePyramid*> mixtures;
    std::vector<std::vector<Accumulator>> acc;
    std::vector<std::vector<std::vector<double>>> texelAbs;
    std::vector<std::vector<double>> texelTruth;
    bool errorMaps = false;
};

// Adds per-row partial sums (rows[y·M + m], M variants) to acc[m][mi] in row order: deterministic.
void addRows(const std::vector<Accumulator>& rows, int height, size_t mi,
             std::vector<std::vector<Accumulator>>& acc) {
    const size_t methodCount = acc.size();
    for (int y = 0; y < height; ++y)
        for (size_t m = 0; m < methodCount; ++m) {
            const Accumulator& r = rows[size_t(y) * methodCount + m];
            acc[m][mi].absError += r.absError;
            acc[m][mi].method += r.method;
            acc[m][mi].truth += r.truth;
        }
}

// Adds one direction pair's error at level k (evaluated mip mi) to the pass: per texel the truth
// (the mean of its footprint's sum) against every variant's value. Per-row partial sums, added in
// row order afterwards: deterministic results.
void accumulateLevel(const NormalPyramid& pyramid, int k, size_t mi, const std::vector<double>& levelSums,
                     const DirectionPair& d, Pass& pass) {
    const PyramidLevel& level = pyramid.level(k);
    const size_t methodCount = pass.lobes.size();
    std::vector<Accumulator> rows(size_t(level.height) * methodCount);
    tbb::parallel_for(0, level.height, [&](int y) {
        for (int x = 0; x < level.width; ++x) {
            const size_t t = size_t(y) * size_t(level.width) + size_t(x);
            const double truth = levelSums[t] / pyramid.footprintCount(k, x, y);
            if (pass.errorMaps) pass.texelTruth[mi][t] += truth;
            for (size_t m = 0; m < methodCount; ++m) {
                const MixturePyramid* mix = pass.mixtures[m];
                const double value = mix && k > 0
                                         ? mixtureValue(mix->at(k, x, y), d.l, d.h, mix->minVariance())
                                         : methodValue(pass.lobes[m][mi][t], d);
                Accumulator& a = rows[size_t(y) * methodCount + m];
                a.absError += std::abs(value - truth);
                a.method += value;
                a.truth += truth;
                if (pass.errorMaps) pass.texelAbs[m][mi][t] += std::abs(value - truth);
            }
        }
    });
    addRows(rows, level.height, mi, pass.acc);
}

// The four texels whose shared corner is the point of texel (x, y): (x, y), (x+1, y), (x, y+1),
// (x+1, y+1) through the border mode.
std::array<size_t, 4> cornerTexels(const PyramidLevel& level, int x, int y, BorderMode border) {
    const int x1 = borderIndex(x + 1, level.width, border), y1 = borderIndex(y + 1, level.height, border);
    const size_t w = size_t(level.width);
    return {size_t(y) * w + size_t(x), size_t(y) * w + size_t(x1), size_t(y1) * w + size_t(x),
            size_t(y1) * w + size_t(x1)};
}

// Every variant's lobe at every corner point of level k (mip index mi) into the pass.
void betweenLevel(const NormalMap& map, const NormalPyramid& pyramid, int k, size_t mi,
                  const std::vector<EvaluatedVariant>& variants, const AuthoredPowers* authored,
                  const std::vector<double>* texelPowers, double s, const MethodParams& params, Pass& pass) {
    const PyramidLevel& level = pyramid.level(k);
    const BorderMode border = pyramid.options().border;
    const size_t n = size_t(level.width) * size_t(level.height);
    for (size_t m = 0; m < variants.size(); ++m) {
        const MixturePyramid* mix = pass.mixtures[m];
        if (mix) {
            auto& out = pass.betweenMixtures[m][mi];
            out.assign(n, {});
            tbb::parallel_for(0, level.height, [&](int y) {
                for (int x = 0; x < level.width; ++x) {
                    // Bilinear filtering at the corner: ¼ of each texel's stored lobes, by slot.
                    const auto t = cornerTexels(level, x, y, border);
                    std::array<LobeMoments, kMaxMixtureLobes> sum{};
                    for (size_t c = 0; c < 4; ++c) {
                        const int xi = int(t[c] % size_t(level.width)), yi = int(t[c] / size_t(level.width));
                        const double p = k == 0 && texelPowers
                                             ? (*texelPowers)[size_t(yi) * size_t(map.width) + size_t(xi)]
                                             : s;
                        const auto stored = mix->storedTexel(map, k, xi, yi, p);
                        for (size_t i = 0; i < stored.size(); ++i) {
                            LobeMoments l = stored[i];
                            l.w *= 0.25, l.bx *= 0.25, l.by *= 0.25, l.mxx *= 0.25, l.myy *= 0.25,
                                l.mxy *= 0.25;
                            sum[i] += l;
                        }
                    }
                    LobeMixture filtered;
                    for (const LobeMoments& l : sum)
                        if (l.w > 0.0) filtered.lobes[size_t(filtered.count++)] = l;
                    out[size_t(y) * size_t(level.width) + size_t(x)] =
                        decodeMixture(filtered, mix->minVariance());
                }
            });
            continue;
        }
        auto& out = pass.betweenLobes[m][mi];
        out.assign(n, {});
        tbb::parallel_for(0, level.height, [&](int y) {
            for (int x = 0; x < level.width; ++x) {
                const auto t = cornerTexels(level, x, y, border);
                std::array<NormalMoments, 4> moments;
                std::array<double, 4> powers;
                for (size_t c = 0; c < 4; ++c) {
                    const int xi = int(t[c] % size_t(level.width)), yi = int(t[c] / size_t(level.width));
                    moments[c] = pyramid.boxMoments(k, xi, yi);
                    powers[c] = authored ? authored->power(k, xi, yi, FilterKernel::Box) : s;
                }
                out[size_t(y) * size_t(level.width) + size_t(x)] =
                    methodLobeBetween(variants[m].method, moments, powers, params);
            }
        });
    }
}

// One direction pair's error at the corner points of level k: the truth is ¼ of each of the four
// footprints' means (the bilinear-weighted union), against every variant's filtered lobe.
void accumulateBetween(const NormalPyramid& pyramid, int k, size_t mi, const std::vector<double>& levelSums,
                       const DirectionPair& d, Pass& pass) {
    const PyramidLevel& level = pyramid.level(k);
    const BorderMode border = pyramid.options().border;
    const size_t methodCount = pass.lobes.size();
    std::vector<Accumulator> rows(size_t(level.height) * methodCount);
    tbb::parallel_for(0, level.height, [&](int y) {
        for (int x = 0; x < level.width; ++x) {
            const auto t = cornerTexels(level, x, y, border);
            double truth = 0.0;
            for (size_t c = 0; c < 4; ++c) {
                const int xi = int(t[c] % size_t(level.width)), yi = int(t[c] / size_t(level.width));
                truth += 0.25 * levelSums[t[c]] / pyramid.footprintCount(k, xi, yi);
            }
            const size_t p = size_t(y) * size_t(level.width) + size_t(x);
            for (size_t m = 0; m < methodCount; ++m) {
                const double value = pass.mixtures[m] ? mixtureValue(pass.betweenMixtures[m][mi][p], d.l, d.h)
                                                      : methodValue(pass.betweenLobes[m][mi][p], d);
                Accumulator& a = rows[size_t(y) * methodCount + m];
                a.absError += std::abs(value - truth);
                a.method += value;
                a.truth += truth;
            }
        }
    });
    addRows(rows, level.height, mi, pass.betweenAcc);
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

    // Hierarchical sums of the per-texel truth: level k = Σ of its children at level k−1.
    std::vector<std::vector<double>> sums(size_t(lastMip) + 1);
    for (int k = 0; k <= lastMip; ++k)
        sums[size_t(k)].resize(size_t(pyramid.level(k).width) * size_t(pyramid.level(k).height));

    const double totalSteps = double(basePowers.size() * directions.size());
    double stepsDone = 0.0;
    for (double s : basePowers) {
        Pass pass;
        pass.errorMaps = options.errorMaps;
        // Lobes of every method at every evaluated mip.
        auto& lobes = pass.lobes;
        lobes.assign(methodCount, std::vector<std::vector<TexelLobe>>(size_t(mipCount)));
        // The mixtures, one per K >= 2 (K = 1 is LEAN's lobe, from the moments).
        std::vector<std::optional<MixturePyramid>> mixtures(kMaxMixtureLobes + 1);
        pass.mixtures.assign(methodCount, nullptr);
        for (size_t m = 0; m < methodCount; ++m) {
            const EvaluatedVariant& v = variants[m];
            if (v.method != Method::Mixture || v.lobes < 2) continue;
            if (cancelled()) return Error{std::string(kCancelledMessage)};
            auto& mix = mixtures[size_t(v.lobes)];
            if (!mix) mix.emplace(MixturePyramid::build(pyramid, s, v.lobes, lastMip, texelPowers));
            pass.mixtures[m] = &*mix;
        }
        for (size_t m = 0; m < methodCount; ++m)
            for (int k = firstMip; k <= lastMip; ++k) {
                if (cancelled()) return Error{std::string(kCancelledMessage)};
                const EvaluatedVariant& v = variants[m];
                // A mixture's level 0 is each normal's own lobe: LEAN's of the one-texel footprint.
                if (pass.mixtures[m] && k > 0) continue;
                const auto& kernelPyramid = filtered[kernelIndex(v.kernel)];
                lobes[m][size_t(k - firstMip)] =
                    levelLobes(pyramid, kernelPyramid ? &*kernelPyramid : nullptr, k, v.method, v.kernel,
                               authored ? &*authored : nullptr, s, options.params);
            }

        pass.acc.assign(methodCount, std::vector<Accumulator>(size_t(mipCount)));
        if (options.betweenTexels) {
            pass.betweenLobes.assign(methodCount, std::vector<std::vector<TexelLobe>>(size_t(mipCount)));
            pass.betweenMixtures.assign(methodCount,
                                        std::vector<std::vector<DecodedMixture>>(size_t(mipCount)));
            pass.betweenAcc.assign(methodCount, std::vector<Accumulator>(size_t(mipCount)));
            for (int k = firstMip; k <= lastMip; ++k) {
                if (cancelled()) return Error{std::string(kCancelledMessage)};
                betweenLevel(map, pyramid, k, size_t(k - firstMip), variants, authored ? &*authored : nullptr,
                             texelPowers, s, options.params, pass);
            }
        }
        auto& texelAbs = pass.texelAbs;
        auto& texelTruth = pass.texelTruth;
        if (options.errorMaps) {
            texelAbs.assign(methodCount, std::vector<std::vector<double>>(size_t(mipCount)));
            texelTruth.resize(size_t(mipCount));
            for (int k = firstMip; k <= lastMip; ++k) {
                const size_t n = sums[size_t(k)].size();
                texelTruth[size_t(k - firstMip)].assign(n, 0.0);
                for (size_t m = 0; m < methodCount; ++m)
                    texelAbs[m][size_t(k - firstMip)].assign(n, 0.0);
            }
        }

        for (const DirectionPair& d : directions) {
            if (cancelled()) return Error{std::string(kCancelledMessage)};
            truthSums(map, pyramid, texelPowers, s, d, sums);
            for (int k = firstMip; k <= lastMip; ++k) {
                if (cancelled()) return Error{std::string(kCancelledMessage)};
                accumulateLevel(pyramid, k, size_t(k - firstMip), sums[size_t(k)], d, pass);
                if (options.betweenTexels)
                    accumulateBetween(pyramid, k, size_t(k - firstMip), sums[size_t(k)], d, pass);
            }
            stepsDone += 1.0;
            if (progress) progress(stepsDone / totalSteps);
        }

        for (size_t m = 0; m < methodCount; ++m)
            for (int k = firstMip; k <= lastMip; ++k) {
                const size_t mi = size_t(k - firstMip);
                result.errors.push_back(errorOf(pass.acc[m][mi], variants[m], s, k));
                if (options.betweenTexels) {
                    result.errors.push_back(errorOf(pass.betweenAcc[m][mi], variants[m], s, k));
                    result.errors.back().betweenTexels = true;
                }
                if (options.errorMaps)
                    result.maps.push_back(
                        errorMapOf(texelAbs[m][mi], texelTruth[mi], variants[m], s, k, pyramid.level(k)));
            }
    }
    // A flag raised during the last pass still wins: the caller asked for no result.
    if (cancelled()) return Error{std::string(kCancelledMessage)};
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

} // namespace burnish
