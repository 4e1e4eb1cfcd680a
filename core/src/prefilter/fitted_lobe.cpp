#include <burnish/core/prefilter/fitted_lobe.h>

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/shading/ggx_specular.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/simd.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace burnish {

namespace {

// The most pairs the GGX fit's padded objective takes (more: fitTexelError's plain loop).
constexpr size_t kMaxPaddedPairs = 512;

// The truth sums a band keeps per level are this many bytes at most for the level whose rows are the
// bands (larger maps band at a coarser level).
constexpr double kBandLevelBytes = 64.0 * 1024.0 * 1024.0;

// The ground truth of finest normals under one BRDF, with one power s (kOwnPowers false) or each its own.
template <Brdf kBrdf, bool kOwnPowers>
[[gnu::always_inline]] inline void truthLoop(const double* nx, const double* ny, const double* nz,
                                             const double* powers, double s, size_t count,
                                             const DirectionPair& d, double* out) {
    const double hx = d.h.x, hy = d.h.y, hz = d.h.z, lx = d.l.x, ly = d.l.y, lz = d.l.z;
    const double vx = d.v.x, vy = d.v.y, vz = d.v.z;
    const double sc = clampPower(s), normS = blinnPhongNdfNorm(s),
                 alphaS = ggxSpecularAlpha(ggxAlphaFromPower(s));
    for (size_t i = 0; i < count; ++i) {
        const double c = nx[i] * hx + ny[i] * hy + nz[i] * hz;
        const double nl = nx[i] * lx + ny[i] * ly + nz[i] * lz;
        if constexpr (kBrdf == Brdf::Ggx) {
            const double a = kOwnPowers ? ggxSpecularAlpha(ggxAlphaFromPower(powers[i])) : alphaS;
            out[i] = ggxSpecularTermClamped(c, nl, nx[i] * vx + ny[i] * vy + nz[i] * vz, a);
        } else {
            const double p = kOwnPowers ? clampPower(powers[i]) : sc;
            const double norm = kOwnPowers ? (p + 2.0) / (2.0 * kPi<double>) : normS;
            out[i] = norm * powCosFast(c, p) * std::max(0.0, nl);
        }
    }
}

// One copy per BRDF; the power source is chosen outside the loop, so each loop stays branch-free.
BURNISH_AVX512_CLONES void truthBlinnPhong(const double* nx, const double* ny, const double* nz,
                                           const double* powers, double s, size_t count,
                                           const DirectionPair& d, double* out) {
    if (powers)
        truthLoop<Brdf::BlinnPhong, true>(nx, ny, nz, powers, s, count, d, out);
    else
        truthLoop<Brdf::BlinnPhong, false>(nx, ny, nz, nullptr, s, count, d, out);
}

BURNISH_AVX512_CLONES void truthGgx(const double* nx, const double* ny, const double* nz,
                                    const double* powers, double s, size_t count, const DirectionPair& d,
                                    double* out) {
    if (powers)
        truthLoop<Brdf::Ggx, true>(nx, ny, nz, powers, s, count, d, out);
    else
        truthLoop<Brdf::Ggx, false>(nx, ny, nz, nullptr, s, count, d, out);
}

// The GGX fit's objective, eight pairs at a time (n a multiple of 8; padding pairs with n·l = 0 and truth 0
// add nothing): the values in a plain loop (vectorised), then their sum in eight lanes. Lane by lane IEEE
// operations in a fixed order, so every copy of the clone gives the same bits.
BURNISH_AVX512_CLONES double ggxFitErrorPadded(const double* truth, const double* noh, const double* nol,
                                               const double* nov, size_t n, double alpha) {
    alignas(64) double err[kMaxPaddedPairs];
    const double a = ggxSpecularAlpha(alpha);
    for (size_t i = 0; i < n; ++i)
        err[i] = std::abs(ggxSpecularTermClamped(noh[i], nol[i], nov[i], a) - truth[i]);
    double acc[8] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    for (size_t i = 0; i < n; i += 8)
        for (size_t j = 0; j < 8; ++j)
            acc[j] += err[i + j];
    return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

// Golden-section search for the least E on [a, b] (in log α), `steps` steps; best/eBest keep the best
// point seen (including those the caller tried before).
template <class E>
void goldenSection(const E& error, double a, double b, int steps, double& best, double& eBest) {
    const double r = 0.5 * (std::sqrt(5.0) - 1.0);
    double c = b - r * (b - a), dd = a + r * (b - a);
    double ec = error(c), ed = error(dd);
    auto keep = [&](double u, double e) {
        if (e < eBest) eBest = e, best = u;
    };
    keep(c, ec), keep(dd, ed);
    for (int i = 0; i < steps; ++i) {
        if (ec <= ed) {
            b = dd, dd = c, ed = ec;
            c = b - r * (b - a);
            ec = error(c);
            keep(c, ec);
        } else {
            a = c, c = dd, ec = ed;
            dd = a + r * (b - a);
            ed = error(dd);
            keep(dd, ed);
        }
    }
}

} // namespace

void truthValues(Brdf brdf, const double* nx, const double* ny, const double* nz, const double* powers,
                 double s, size_t count, const DirectionPair& d, double* out) {
    if (brdf == Brdf::Ggx)
        truthGgx(nx, ny, nz, powers, s, count, d, out);
    else
        truthBlinnPhong(nx, ny, nz, powers, s, count, d, out);
}

TruthNormals defaultTruthNormals(Brdf brdf) {
    return brdf == Brdf::Ggx ? TruthNormals::Bilinear : TruthNormals::Texels;
}

const char* truthNormalsName(TruthNormals t) {
    return t == TruthNormals::Bilinear ? "bilinear" : "texels";
}

bool truthNormalsFromName(const std::string& name, TruthNormals& out) {
    if (name == "texels") return out = TruthNormals::Texels, true;
    if (name == "bilinear") return out = TruthNormals::Bilinear, true;
    return false;
}

TruthBand::TruthBand(const NormalMap& map, int rowBegin, int rowEnd, TruthNormals how, BorderMode border)
    : m_count(size_t(std::max(rowEnd - rowBegin, 0)) * size_t(map.width))
    , m_samples(how == TruthNormals::Bilinear ? kBilinearSamples * kBilinearSamples : 1) {
    m_x.resize(m_count * size_t(m_samples)), m_y.resize(m_x.size()), m_z.resize(m_x.size());
    const size_t begin = size_t(rowBegin) * size_t(map.width);
    if (m_samples == 1) {
        for (size_t i = 0; i < m_count; ++i) {
            const glm::vec3& n = map.normals[begin + i];
            m_x[i] = n.x, m_y[i] = n.y, m_z[i] = n.z;
        }
        return;
    }
    // Sub-sample (a, b) of texel (x, y) lies at (x + 0.5 + oa, y + 0.5 + ob), o = (a + 0.5)/K − 0.5: the
    // bilinear interpolant there weighs the texel and its neighbour towards the sample by 1 − |o| and |o|
    // per axis (past the edges by `border`); renormalized as the engine's shader does, or the texel's own
    // normal where the blend cancels out.
    const int K = kBilinearSamples, W = map.width, H = map.height;
    for (int y = rowBegin; y < rowEnd; ++y)
        for (int b = 0; b < K; ++b) {
            const double oy = (b + 0.5) / K - 0.5;
            const int y2 = borderIndex(y + (oy < 0 ? -1 : 1), H, border);
            const double wy = std::abs(oy);
            for (int a = 0; a < K; ++a) {
                const double ox = (a + 0.5) / K - 0.5;
                const double wx = std::abs(ox);
                const size_t out = size_t(b * K + a) * m_count + size_t(y - rowBegin) * size_t(W);
                for (int x = 0; x < W; ++x) {
                    const int x2 = borderIndex(x + (ox < 0 ? -1 : 1), W, border);
                    const glm::dvec3 n =
                        (1 - wy) * ((1 - wx) * glm::dvec3(map.at(x, y)) + wx * glm::dvec3(map.at(x2, y))) +
                        wy * ((1 - wx) * glm::dvec3(map.at(x, y2)) + wx * glm::dvec3(map.at(x2, y2)));
                    const double len = glm::length(n);
                    const glm::dvec3 u = len > 1e-6 ? n / len : glm::dvec3(map.at(x, y));
                    m_x[out + size_t(x)] = u.x, m_y[out + size_t(x)] = u.y, m_z[out + size_t(x)] = u.z;
                }
            }
        }
    m_scratch.resize(m_count);
}

void TruthBand::values(Brdf brdf, const double* powers, double s, const DirectionPair& d, double* out) {
    if (m_samples == 1) {
        truthValues(brdf, m_x.data(), m_y.data(), m_z.data(), powers, s, m_count, d, out);
        return;
    }
    std::fill(out, out + m_count, 0.0);
    for (int k = 0; k < m_samples; ++k) {
        const size_t o = size_t(k) * m_count;
        truthValues(brdf, m_x.data() + o, m_y.data() + o, m_z.data() + o, powers, s, m_count, d,
                    m_scratch.data());
        for (size_t i = 0; i < m_count; ++i)
            out[i] += m_scratch[i];
    }
    const double inv = 1.0 / m_samples;
    for (size_t i = 0; i < m_count; ++i)
        out[i] *= inv;
}

double fitTexelError(Brdf brdf, const double* truth, const double* NoH, const double* NoL, const double* NoV,
                     size_t pairs, double alpha) {
    double sum = 0.0;
    if (brdf == Brdf::Ggx) {
        for (size_t d = 0; d < pairs; ++d)
            sum += std::abs(ggxSpecularTerm(NoH[d], NoL[d], NoV[d], alpha) - truth[d]);
        return sum;
    }
    const double p = powerFromGgxAlpha(alpha);
    for (size_t d = 0; d < pairs; ++d)
        sum += std::abs(isotropicLobeShading(Brdf::BlinnPhong, NoH[d], NoL[d], NoV[d], p) - truth[d]);
    return sum;
}

double fitTexelAlpha(Brdf brdf, const double* truth, const double* NoH, const double* NoL, const double* NoV,
                     size_t pairs, double alphaBase, double alphaVmf, bool floor) {
    const double aBase = ggxSpecularAlpha(alphaBase), aVmf = ggxSpecularAlpha(alphaVmf);
    // The search's objective: for GGX, the pairs padded to a multiple of 8 (ggxFitErrorPadded).
    const size_t padded = (pairs + 7) / 8 * 8;
    const bool usePadded = brdf == Brdf::Ggx && padded <= kMaxPaddedPairs;
    alignas(64) double pt[kMaxPaddedPairs], ph[kMaxPaddedPairs], pl[kMaxPaddedPairs], pv[kMaxPaddedPairs];
    if (usePadded)
        for (size_t d = 0; d < padded; ++d) {
            const bool real = d < pairs;
            pt[d] = real ? truth[d] : 0.0;
            ph[d] = real ? NoH[d] : 0.0;
            pl[d] = real ? NoL[d] : 0.0;
            pv[d] = real ? NoV[d] : 0.0;
        }
    // The candidates every fit tries, by their own α (not through log/exp): the base and vMF's.
    auto errorAt = [&](double alpha) {
        return usePadded ? ggxFitErrorPadded(pt, ph, pl, pv, padded, alpha)
                         : fitTexelError(brdf, truth, NoH, NoL, NoV, pairs, alpha);
    };
    double eCandidates = errorAt(aBase);
    double bestAlpha = aBase;
    if (const double e = errorAt(aVmf); e < eCandidates) eCandidates = e, bestAlpha = aVmf;
    auto error = [&](double u) { return errorAt(std::exp(u)); };
    // Never sharper than the base: a lobe sharper than the footprint's own normals' lobes can hide its
    // energy between the sampled pairs (a sparkle the measure cannot see) and score well on noisy
    // footprints; the floor obeys the same bound.
    const double lo = std::log(aBase);
    const double hi = floor ? 0.0 : std::log(std::min(1.0, kFitReach * std::max(aBase, aVmf)));
    const int grid = floor ? kFloorGrid : kFitGrid;
    if (!(hi - lo > 1e-9)) return bestAlpha; // a flat footprint, or a base of α = 1: the base is the lobe
    // The scan: grid + 2 points from lo to hi, ends included.
    const int points = grid + 2;
    int bestIndex = 0;
    double eScan = std::numeric_limits<double>::infinity();
    for (int i = 0; i < points; ++i) {
        const double u = lo + (hi - lo) * double(i) / double(points - 1);
        const double e = error(u);
        if (e < eScan) eScan = e, bestIndex = i;
    }
    double refined = lo + (hi - lo) * double(bestIndex) / double(points - 1), eRefined = eScan;
    {
        const double a = lo + (hi - lo) * double(std::max(bestIndex - 1, 0)) / double(points - 1);
        const double b = lo + (hi - lo) * double(std::min(bestIndex + 1, points - 1)) / double(points - 1);
        goldenSection(error, a, b, floor ? 30 : kFitSteps, refined, eRefined);
    }
    // Strictly better than the candidates by the same sum (eRefined is errorAt(exp(refined))), or the
    // better candidate itself: never worse than either.
    // (α is clamped to 1 as ggxSpecularAlpha clamps it: the scan's top end may round a hair above.)
    return eRefined < eCandidates ? std::min(std::exp(refined), 1.0) : bestAlpha;
}

double AnisotropicLobe::strength() const {
    if (!(alphaB < 1.0)) return 0.0;
    return std::sqrt(std::clamp((alphaT - alphaB) / (1.0 - alphaB), 0.0, 1.0));
}

namespace {

// One texel's anisotropic objective: per pair the lobe normal's cosines and the pair's tangent-plane
// components, so a trial lobe costs one pass over the pairs.
struct AnisotropicObjective {
    const double* truth;
    size_t D;
    std::vector<double> noh, nol, nov, hx, hy, lx, ly, vx, vy;

    AnisotropicObjective(const double* t, const std::vector<DirectionPair>& dirs, const glm::dvec3& n)
        : truth(t)
        , D(dirs.size()) {
        for (auto* a : {&noh, &nol, &nov, &hx, &hy, &lx, &ly, &vx, &vy})
            a->resize(D);
        for (size_t d = 0; d < D; ++d) {
            const DirectionPair& p = dirs[d];
            noh[d] = glm::dot(n, p.h), nol[d] = glm::dot(n, p.l), nov[d] = glm::dot(n, p.v);
            hx[d] = p.h.x, hy[d] = p.h.y, lx[d] = p.l.x, ly[d] = p.l.y, vx[d] = p.v.x, vy[d] = p.v.y;
        }
    }
    double operator()(double angle, double at, double ab) const {
        const double c = std::cos(angle), s = std::sin(angle);
        double sum = 0.0;
        for (size_t d = 0; d < D; ++d) {
            const double toh = c * hx[d] + s * hy[d], boh = c * hy[d] - s * hx[d];
            const double tol = c * lx[d] + s * ly[d], bol = c * ly[d] - s * lx[d];
            const double tov = c * vx[d] + s * vy[d], bov = c * vy[d] - s * vx[d];
            sum += std::abs(
                ggxAnisotropicSpecularTerm(noh[d], toh, boh, nol[d], tol, bol, nov[d], tov, bov, at, ab) -
                truth[d]);
        }
        return sum;
    }
};

// θ folded into [0, π).
double foldAngle(double a) {
    a = std::fmod(a, kPi<double>);
    return a < 0.0 ? a + kPi<double> : a;
}

} // namespace

double anisotropicFitError(const double* truth, const std::vector<DirectionPair>& dirs, const glm::dvec3& n,
                           const AnisotropicLobe& lobe) {
    return AnisotropicObjective(truth, dirs, n)(lobe.angle, lobe.alphaT, lobe.alphaB);
}

double principalAngle(const NormalMoments& m) {
    const double xx = m.cov[0], yy = m.cov[1], xy = m.cov[3];
    if (!(std::abs(xx - yy) + std::abs(xy) > 1e-12)) return 0.0;
    return foldAngle(0.5 * std::atan2(2.0 * xy, xx - yy));
}

AnisotropicLobe fitTexelAnisotropic(const double* truth, const std::vector<DirectionPair>& dirs,
                                    const glm::dvec3& n, double alphaBase, double alphaIso,
                                    double principal) {
    const AnisotropicObjective E(truth, dirs, n);
    const double aBase = ggxSpecularAlpha(alphaBase);
    const double aIso = std::max(ggxSpecularAlpha(alphaIso), aBase);
    AnisotropicLobe best{aIso, aIso, 0.0};
    double eBest = E(0.0, aIso, aIso);
    if (const double e = E(0.0, aBase, aBase); e < eBest) eBest = e, best = {aBase, aBase, 0.0};
    auto tryLobe = [&](double angle, double at, double ab) {
        at = std::clamp(at, ab, 1.0);
        const double e = E(angle, at, ab);
        if (e < eBest) eBest = e, best = {at, ab, foldAngle(angle)};
    };
    // The grid: per direction, three α_b up to α_iso and α_t from α_b to 1 evenly in log α.
    std::array<double, kAnisotropicAngles + 1> angles{};
    angles[0] = foldAngle(principal);
    for (int i = 0; i < kAnisotropicAngles; ++i)
        angles[size_t(i) + 1] = kPi<double> * i / kAnisotropicAngles;
    for (double angle : angles)
        for (double f : {0.5, 0.75, 1.0}) {
            const double ab = std::max(aBase, f * aIso);
            for (int j = 1; j <= kFitGrid; ++j)
                tryLobe(angle, std::exp(std::log(ab) * (1.0 - double(j) / kFitGrid)), ab);
        }
    if (!(best.alphaT > best.alphaB)) return best; // still round
    // Refinement, one coordinate at a time (θ; log α_t over [α_b, 1]; log α_b over [α_base, α_t]).
    const double step = kPi<double> / (2.0 * kAnisotropicAngles);
    for (int round = 0; round < 2; ++round) {
        double u = best.angle, eu = eBest;
        goldenSection([&](double a) { return E(a, best.alphaT, best.alphaB); }, best.angle - step,
                      best.angle + step, kFitSteps, u, eu);
        if (eu < eBest) eBest = eu, best.angle = foldAngle(u);
        u = std::log(best.alphaT), eu = eBest;
        goldenSection([&](double la) { return E(best.angle, std::exp(la), best.alphaB); },
                      std::log(best.alphaB), 0.0, kFitSteps, u, eu);
        if (eu < eBest) eBest = eu, best.alphaT = std::min(std::exp(u), 1.0);
        u = std::log(best.alphaB), eu = eBest;
        goldenSection([&](double la) { return E(best.angle, best.alphaT, std::exp(la)); }, std::log(aBase),
                      std::log(best.alphaT), kFitSteps, u, eu);
        if (eu < eBest) eBest = eu, best.alphaB = std::min(std::exp(u), best.alphaT);
    }
    return best;
}

FittedPyramid::FitErrors FittedPyramid::fitErrors(int k) const {
    FitErrors sum;
    const std::vector<float>& e = m_levels[size_t(k)].errors;
    for (size_t i = 0; i + 2 < e.size(); i += 3) // texel order: the same sums on any thread count
        sum.isotropic += e[i], sum.anisotropic += e[i + 1], sum.truth += e[i + 2];
    return sum;
}

FittedPyramid FittedPyramid::build(const NormalPyramid& pyramid, const BasePower& basePower,
                                   const std::vector<double>* texelPowers, double s, int lastLevel,
                                   const FittedLobeOptions& options, const std::function<bool()>& cancelled) {
    FittedPyramid out;
    const int last = lastLevel < 0 ? pyramid.levelCount() - 1 : std::min(lastLevel, pyramid.levelCount() - 1);
    out.m_levels.resize(size_t(std::max(last, 0)) + 1);
    for (int k = 0; k <= last; ++k) {
        out.m_levels[size_t(k)].width = pyramid.level(k).width;
        out.m_levels[size_t(k)].height = pyramid.level(k).height;
        if (k > 0)
            out.m_levels[size_t(k)].power.assign(
                size_t(pyramid.level(k).width) * size_t(pyramid.level(k).height), 0.0f);
    }
    if (last < 1) return out;
    const std::vector<DirectionPair>& dirs = options.directions;
    const size_t D = dirs.size();
    if (D == 0) {
        // No pair to judge by: every texel keeps the base power.
        for (int k = 1; k <= last; ++k)
            for (int y = 0; y < pyramid.level(k).height; ++y)
                for (int x = 0; x < pyramid.level(k).width; ++x)
                    out.m_levels[size_t(k)].power[size_t(y) * size_t(pyramid.level(k).width) + size_t(x)] =
                        float(basePower(k, x, y));
        return out;
    }
    // The level whose rows are the bands: the finest of 4 and the first whose truth sums fit kBandLevelBytes.
    int bandLevel = std::min(last, 4);
    auto levelBytes = [&](int k) {
        return double(pyramid.level(k).width) * double(pyramid.level(k).height) * double(D) * 8.0;
    };
    while (bandLevel < last && levelBytes(bandLevel) > kBandLevelBytes)
        ++bandLevel;
    const NormalMap& map = pyramid.finest();
    const TruthNormals truthNormals = options.truthNormals.value_or(defaultTruthNormals(options.brdf));
    const bool anisotropic = options.anisotropic && options.brdf == Brdf::Ggx && !options.floor;
    out.m_anisotropic = anisotropic;
    if (anisotropic)
        for (int k = std::max(1, options.firstLevel); k <= last; ++k) {
            out.m_levels[size_t(k)].aniso.assign(3 * out.m_levels[size_t(k)].power.size(), 0.0f);
            out.m_levels[size_t(k)].errors.assign(3 * out.m_levels[size_t(k)].power.size(), 0.0f);
        }

    // One texel's fit from its truth sums (D values, Σ over the footprint).
    auto fitTexel = [&](int k, int x, int y, const double* sums, double* scratch) {
        double* truth = scratch;
        double* noh = scratch + D;
        double* nol = scratch + 2 * D;
        double* nov = scratch + 3 * D;
        const double count = double(pyramid.footprintCount(k, x, y));
        const NormalMoments m = pyramid.moments(k, x, y);
        const glm::dvec3 n(m.meanDirection());
        for (size_t d = 0; d < D; ++d) {
            truth[d] = sums[d] / count;
            noh[d] = glm::dot(n, dirs[d].h);
            nol[d] = glm::dot(n, dirs[d].l);
            nov[d] = glm::dot(n, dirs[d].v);
        }
        const double base = basePower(k, x, y);
        const double vmf = methodPower(Method::Vmf, m, base);
        const double alpha = fitTexelAlpha(options.brdf, truth, noh, nol, nov, D, ggxAlphaFromPower(base),
                                           ggxAlphaFromPower(vmf), options.floor);
        const size_t t = size_t(y) * size_t(pyramid.level(k).width) + size_t(x);
        out.m_levels[size_t(k)].power[t] = float(powerFromGgxAlpha(alpha));
        if (anisotropic) {
            const AnisotropicLobe a =
                fitTexelAnisotropic(truth, dirs, n, ggxAlphaFromPower(base), alpha, principalAngle(m));
            float* o = &out.m_levels[size_t(k)].aniso[3 * t];
            o[0] = float(a.alphaT), o[1] = float(a.alphaB), o[2] = float(a.angle);
            double truthSum = 0.0;
            for (size_t d = 0; d < D; ++d)
                truthSum += truth[d];
            float* e = &out.m_levels[size_t(k)].errors[3 * t];
            e[0] = float(fitTexelError(options.brdf, truth, noh, nol, nov, D, alpha));
            e[1] = float(anisotropicFitError(truth, dirs, n, a));
            e[2] = float(truthSum);
        }
    };

    // Level bandLevel's truth sums, every texel, pair-minor: [t·D + d].
    std::vector<double> bandLevelSums(size_t(pyramid.level(bandLevel).width) *
                                      size_t(pyramid.level(bandLevel).height) * D);
    const int bands = pyramid.level(bandLevel).height;
    auto doBand = [&](int y) {
        // The band's rows at each level down to the finest.
        std::vector<int> rowBegin(size_t(bandLevel) + 1), rowEnd(size_t(bandLevel) + 1);
        rowBegin[size_t(bandLevel)] = y, rowEnd[size_t(bandLevel)] = y + 1;
        for (int k = bandLevel; k > 0; --k) {
            rowBegin[size_t(k - 1)] = pyramid.level(k).yChild[size_t(rowBegin[size_t(k)])];
            rowEnd[size_t(k - 1)] = pyramid.level(k).yChild[size_t(rowEnd[size_t(k)])];
        }
        const size_t begin = size_t(rowBegin[0]) * size_t(map.width);
        TruthBand finest(map, rowBegin[0], rowEnd[0], truthNormals, pyramid.options().border);
        std::vector<double> values(finest.size());
        // Per level 1..bandLevel the band's sums, pair-minor; level 0 is `values` for one pair at a time.
        std::vector<std::vector<double>> sums(size_t(bandLevel) + 1);
        for (int k = 1; k <= bandLevel; ++k)
            sums[size_t(k)].assign(
                size_t(rowEnd[size_t(k)] - rowBegin[size_t(k)]) * size_t(pyramid.level(k).width) * D, 0.0);
        for (size_t d = 0; d < D; ++d) {
            finest.values(options.brdf, texelPowers ? texelPowers->data() + begin : nullptr, s, dirs[d],
                          values.data());
            for (int k = 1; k <= bandLevel; ++k) {
                const PyramidLevel& level = pyramid.level(k);
                const PyramidLevel& child = pyramid.level(k - 1);
                const int childRow0 = rowBegin[size_t(k - 1)];
                // The child level's value for this pair: the finest values, or the sums just made.
                auto childValue = [&](int j, int i) {
                    const size_t t = size_t(j - childRow0) * size_t(child.width) + size_t(i);
                    return k == 1 ? values[t] : sums[size_t(k - 1)][t * D + d];
                };
                for (int yy = rowBegin[size_t(k)]; yy < rowEnd[size_t(k)]; ++yy)
                    for (int x = 0; x < level.width; ++x) {
                        double sum = 0.0;
                        for (int j = level.yChild[size_t(yy)]; j < level.yChild[size_t(yy) + 1]; ++j)
                            for (int i = level.xChild[size_t(x)]; i < level.xChild[size_t(x) + 1]; ++i)
                                sum += childValue(j, i);
                        sums[size_t(k)]
                            [(size_t(yy - rowBegin[size_t(k)]) * size_t(level.width) + size_t(x)) * D + d] =
                                sum;
                    }
            }
        }
        std::vector<double> scratch(4 * D);
        for (int k = std::max(1, options.firstLevel); k <= bandLevel; ++k) {
            const PyramidLevel& level = pyramid.level(k);
            for (int yy = rowBegin[size_t(k)]; yy < rowEnd[size_t(k)]; ++yy)
                for (int x = 0; x < level.width; ++x)
                    fitTexel(k, x, yy,
                             &sums[size_t(k)]
                                  [(size_t(yy - rowBegin[size_t(k)]) * size_t(level.width) + size_t(x)) * D],
                             scratch.data());
        }
        const size_t w = size_t(pyramid.level(bandLevel).width);
        std::copy(sums[size_t(bandLevel)].begin(), sums[size_t(bandLevel)].end(),
                  bandLevelSums.begin() + std::ptrdiff_t(size_t(y) * w * D));
    };
    // Batches of bands, so a cancel is seen between them.
    const int batches = std::clamp(bands / 4, 1, 32);
    for (int b = 0; b < batches; ++b) {
        if (cancelled && cancelled()) return FittedPyramid{};
        const int from = int(int64_t(bands) * b / batches), to = int(int64_t(bands) * (b + 1) / batches);
        tbb::parallel_for(from, to, doBand);
    }
    // The coarser levels from bandLevel's sums.
    std::vector<double> childSums = std::move(bandLevelSums);
    for (int k = bandLevel + 1; k <= last; ++k) {
        if (cancelled && cancelled()) return FittedPyramid{};
        const PyramidLevel& level = pyramid.level(k);
        const PyramidLevel& child = pyramid.level(k - 1);
        std::vector<double> levelSums(size_t(level.width) * size_t(level.height) * D, 0.0);
        tbb::parallel_for(0, level.height, [&](int y) {
            std::vector<double> scratch(4 * D);
            for (int x = 0; x < level.width; ++x) {
                double* sum = &levelSums[(size_t(y) * size_t(level.width) + size_t(x)) * D];
                for (int j = level.yChild[size_t(y)]; j < level.yChild[size_t(y) + 1]; ++j)
                    for (int i = level.xChild[size_t(x)]; i < level.xChild[size_t(x) + 1]; ++i) {
                        const double* c = &childSums[(size_t(j) * size_t(child.width) + size_t(i)) * D];
                        for (size_t d = 0; d < D; ++d)
                            sum[d] += c[d];
                    }
                if (k >= options.firstLevel) fitTexel(k, x, y, sum, scratch.data());
            }
        });
        childSums = std::move(levelSums);
    }
    return out;
}

} // namespace burnish
