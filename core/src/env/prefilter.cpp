#include <burnish/core/env/prefilter.h>

#include "env/cube_faces.h"

#include <burnish/core/util/numeric.h>
#include <burnish/core/util/simd.h>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

namespace burnish {

using glm::dvec3;
using namespace cubeface;

const char* lobeModelName(LobeModel lobe) {
    return lobe == LobeModel::Phong ? "phong" : "blinn-phong";
}

std::vector<double> prefilterPowers(const PrefilterOptions& o, int mips) {
    std::vector<double> powers;
    for (int m = 0; m < mips; ++m) {
        double n;
        if (o.encoding) {
            const double t = mips > 1 ? double(m) / double(mips - 1) : 0.0;
            const double g = 1.0 - t;
            n = o.encoding->power(o.encoding->increasesWithPower() ? g : 1.0 - g);
        } else {
            n = o.topPower * std::pow(o.powerDrop, double(m));
        }
        powers.push_back(clampPower(n));
    }
    return powers;
}

double mipForGloss(double g, int mips) {
    return (1.0 - saturate(g)) * double(std::max(mips, 1) - 1);
}

double lobeWeight(LobeModel lobe, double power, double c) {
    if (lobe == LobeModel::Phong) return powCos(c, power);
    // cos^n(θ/2) = ((1 + cosθ)/2)^(n/2); the half-angle cosine is 0 only at c = −1.
    return powCos(0.5 * (1.0 + std::clamp(c, -1.0, 1.0)), 0.5 * clampPower(power));
}

namespace {

/// 1 − cos of the angle beyond which the lobe's weight is below `cutoff` (2: the whole sphere). Computed
/// with expm1 so that it keeps its digits for the highest powers (1e9: 1.2e-8).
double lobeCutOneMinusCosine(LobeModel lobe, double power, double cutoff) {
    power = clampPower(power);
    if (power <= 0.0) return 2.0;
    // cos^n θ = cutoff
    if (lobe == LobeModel::Phong) return -std::expm1(std::log(cutoff) / power);
    // ((1 + c)/2)^(n/2) = cutoff: 1 − c = 2(1 − cutoff^(2/n))
    return std::min(2.0, -2.0 * std::expm1(2.0 * std::log(cutoff) / power));
}

/// The lobe's angular standard deviation (radians): cos^n θ ≈ exp(−nθ²/2) for Phong, and the Blinn
/// lobe cos^n(θ/2) ≈ exp(−nθ²/8) is twice as wide.
double lobeSigma(LobeModel lobe, double power) {
    const double sigma = 1.0 / std::sqrt(std::max(clampPower(power), 1e-6));
    return lobe == LobeModel::Phong ? sigma : 2.0 * sigma;
}

using namespace simd;

/// One face of a source level laid out for the inner loop, one plane per quantity (rows as in the cube
/// layout): unit direction of the texel centre, solid angle (sr), radiance.
struct SourceFace {
    std::vector<float> x, y, z, omega, r, g, b;
};

struct SourceLevel {
    int size = 0;
    std::array<SourceFace, kCubeFaces> faces;
};

SourceLevel flatten(const CubeLevel& level) {
    SourceLevel flat;
    const int n = level.size;
    flat.size = n;
    // A texel's solid angle depends on (x, y) only, not on the face: the area element at the (n + 1)²
    // corners once, then texelSolidAngle's four-corner difference (the same expression, the same bits).
    std::vector<double> corner(size_t(n + 1) * size_t(n + 1));
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            corner[size_t(j) * size_t(n + 1) + size_t(i)] = areaElement(2.0 * i / n - 1.0, 2.0 * j / n - 1.0);
    auto at = [&](int i, int j) { return corner[size_t(j) * size_t(n + 1) + size_t(i)]; };
    tbb::parallel_for(0, kCubeFaces, [&](int f) {
        SourceFace& out = flat.faces[size_t(f)];
        const size_t count = size_t(n) * size_t(n);
        for (auto* plane : {&out.x, &out.y, &out.z, &out.omega, &out.r, &out.g, &out.b})
            plane->resize(count);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const size_t i = size_t(y) * size_t(n) + size_t(x);
                const dvec3 d = texelDirection(f, n, x, y);
                const float* L = level.texel(f, x, y);
                out.x[i] = float(d.x);
                out.y[i] = float(d.y);
                out.z[i] = float(d.z);
                out.omega[i] = float(at(x, y) - at(x, y + 1) - at(x + 1, y) + at(x + 1, y + 1));
                out.r[i] = L[0];
                out.g[i] = L[1];
                out.b[i] = L[2];
            }
    });
    return flat;
}

/// The lobe as a function of u = 1 − R·L on [0, uCut], and 0 from uCut on. Sampled at kEntries + 1
/// points for linear interpolation: with the lobe cut at a fraction ε of its peak it falls by about
/// ln(1/ε) e-folds over the table (11.5 at ε = 1e-5), so interpolation errs by (ln(1/ε)/kEntries)²/8
/// ≈ 1e-6 of the weight, below the float rounding of the sums. Exponents below 2 (Phong n, Blinn n/2)
/// have an unbounded second derivative where the lobe reaches 0 (c = 0, or c = −1 for Blinn); those
/// wide lobes are evaluated exactly instead.
class LobeTable {
public:
    static constexpr int kEntries = 4096;

    LobeTable(LobeModel lobe, double power, double uCut)
        : m_lobe(lobe)
        , m_power(float(clampPower(power))) {
        // 2 is the whole sphere (u = 1 − cos); a zero-width cut would divide by 0 below.
        uCut = std::clamp(uCut, std::numeric_limits<double>::min(), 2.0);
        m_uCut = float(uCut);
        m_scale = float(kEntries / uCut);
        const double exponent = lobe == LobeModel::Phong ? clampPower(power) : 0.5 * clampPower(power);
        // Below 2 the lerp error near the lobe's zero grows without bound (x^p with p < 2 at x → 0).
        constexpr double kMinTableExponent = 2.0;
        m_exact = exponent > 0.0 && exponent < kMinTableExponent;
        std::array<double, kEntries + 1> w;
        for (int k = 0; k <= kEntries; ++k)
            w[size_t(k)] = weight(lobe, clampPower(power), uCut * k / kEntries);
        for (int k = 0; k < kEntries; ++k) {
            m_value[size_t(k)] = float(w[size_t(k)]);
            m_slope[size_t(k)] = float(w[size_t(k + 1)] - w[size_t(k)]);
        }
        // Past the cut: weight 0 (u·scale is clamped to kEntries before indexing).
        m_value[kEntries] = 0.0f;
        m_slope[kEntries] = 0.0f;
    }

    /// The weights at four u ≥ 0 (finite).
    Float4 operator()(Float4 u) const {
        if (m_exact) return Float4{(*this)(u[0]), (*this)(u[1]), (*this)(u[2]), (*this)(u[3])};
        Float4 x = u * m_scale;
        x = x < float(kEntries) ? x : float(kEntries);
        const Int4 i = __builtin_convertvector(x, Int4);
        const Float4 f = x - __builtin_convertvector(i, Float4);
        const Float4 value{m_value[size_t(i[0])], m_value[size_t(i[1])], m_value[size_t(i[2])],
                           m_value[size_t(i[3])]};
        const Float4 slope{m_slope[size_t(i[0])], m_slope[size_t(i[1])], m_slope[size_t(i[2])],
                           m_slope[size_t(i[3])]};
        return value + f * slope;
    }

    /// The weight at u ≥ 0 (finite).
    float operator()(float u) const {
        if (m_exact) {
            if (!(u < m_uCut)) return 0.0f;
            // n > 0 here: log1p(−1) = −inf gives exp(−inf) = 0 at the lobe's zero.
            return m_lobe == LobeModel::Phong ? std::exp(m_power * std::log1p(-u))
                                              : std::exp(0.5f * m_power * std::log1p(-0.5f * u));
        }
        const float x = std::min(u * m_scale, float(kEntries));
        const int i = int(x);
        return m_value[size_t(i)] + (x - float(i)) * m_slope[size_t(i)];
    }

private:
    /// lobeWeight in terms of u = 1 − c, with log1p so that u near 0 keeps its digits.
    static double weight(LobeModel lobe, double n, double u) {
        if (n == 0.0) return 1.0; // powCos(c, 0) = 1 everywhere, as lobeWeight
        if (lobe == LobeModel::Phong) return u < 1.0 ? std::exp(n * std::log1p(-u)) : 0.0;
        // ((1 + c)/2)^(n/2) = (1 − u/2)^(n/2)
        return u < 2.0 ? std::exp(0.5 * n * std::log1p(-0.5 * u)) : 0.0;
    }

    LobeModel m_lobe;
    float m_power = 0.0f;
    float m_uCut = 0.0f;
    bool m_exact = false;
    float m_scale = 0.0f;
    std::array<float, kEntries + 1> m_value{}, m_slope{};
};

/// The part [lo, hi] of [−1, 1] on the line base + t·along (base ⊥ along, |along| = 1) inside the cone
/// {d : R·d ≥ cosCut·|d|}, cosCut > 0. That cone is convex, so the part is one interval; its ends are
/// roots of a quadratic or ±1, and a midpoint test tells the cone from its mirror image.
bool lineInterval(const dvec3& R, double cosCut, const dvec3& base, const dvec3& along, double& lo,
                  double& hi) {
    // R·p = A + B t, |p|² = b2 + t²: (A + B t)² − c²(b2 + t²) = qa t² + 2 hb t + qc ≥ 0 with A + B t ≥ 0.
    const double A = glm::dot(R, base), B = glm::dot(R, along), b2 = glm::dot(base, base);
    const double c2 = cosCut * cosCut;
    const double qa = B * B - c2, hb = A * B, qc = A * A - c2 * b2;
    std::array<double, 4> breaks{-1.0, 1.0, 0.0, 0.0};
    int count = 2;
    const double disc = hb * hb - qa * qc;
    if (disc >= 0.0) {
        // Numerical Recipes' stable roots: q/qa and qc/q, no cancellation when qa or qc is tiny.
        const double q = -(hb + std::copysign(std::sqrt(disc), hb));
        for (const double r : {qa != 0.0 ? q / qa : 2.0, q != 0.0 ? qc / q : 2.0})
            if (r > -1.0 && r < 1.0) breaks[size_t(count++)] = r;
    }
    // At most four breaks: an insertion sort.
    for (int i = 1; i < count; ++i)
        for (int j = i; j > 0 && breaks[size_t(j)] < breaks[size_t(j - 1)]; --j)
            std::swap(breaks[size_t(j)], breaks[size_t(j - 1)]);
    bool any = false;
    for (int i = 0; i + 1 < count; ++i) {
        const double t = 0.5 * (breaks[size_t(i)] + breaks[size_t(i + 1)]);
        const double rp = A + B * t;
        if (rp >= 0.0 && rp * rp >= c2 * (b2 + t * t)) {
            if (!any) lo = breaks[size_t(i)];
            hi = breaks[size_t(i + 1)];
            any = true;
        }
    }
    return any;
}

/// The cone a mip's lobe is cut to, {d : R·d ≥ cosCut·|d|}, with what every texel's test shares.
struct CutCone {
    double cosCut = -1.0;
    double c2 = 1.0;
    /// The cone meets a face only if R·axis ≥ cosReach.
    double cosReach = -1.0;

    explicit CutCone(double cosCutIn)
        : cosCut(cosCutIn)
        , c2(cosCutIn * cosCutIn) {
        // Every direction of a face lies within acos(1/√3) (centre to corner) of its axis, so the cone
        // meets the face only if R lies within θc + acos(1/√3) of the axis (1e-9: rounding of the acos).
        const double faceRadius = std::acos(1.0 / std::sqrt(3.0));
        const double thetaCut = std::acos(std::clamp(cosCut, -1.0, 1.0));
        cosReach = std::cos(std::min(kPi<double>, thetaCut + faceRadius + 1e-9));
    }
};

/// Calls visit(face, y, x0, x1) for the runs of texels of a `size`² level whose centres lie within the
/// cone about R (to rounding: a centre on the cone's surface may fall either side), and maybe more.
/// For cosCut ≤ kMinConeCosine every row of every face is one run: at or below 0 the cone is not
/// convex, and just above 0 (half-angles within 0.006° of 90°) the row quadratics below are too
/// close to (A + Ru·sc)² to tell their two roots apart in double: the disc c²(...) is far below the
/// rounding of its terms, and a row came out whole or empty (the Phong lobe of power 0.5 cut at 1e-5,
/// cosCut = 1e-10, missed up to 7% of its hemisphere).
template <class Visit>
void forEachConeRun(const dvec3& R, const CutCone& cone, int size, const Visit& visit) {
    // c² = 1e-8 keeps the disc eight digits above the rounding of its O(1) terms.
    constexpr double kMinConeCosine = 1e-4;
    if (!(cone.cosCut > kMinConeCosine)) {
        for (int f = 0; f < kCubeFaces; ++f)
            for (int y = 0; y < size; ++y)
                visit(f, y, 0, size - 1);
        return;
    }
    const double c2 = cone.c2;
    // Texel index of a face coordinate: centres at (x + 0.5)/size·2 − 1.
    auto toTexel = [&](double c) { return 0.5 * (c + 1.0) * size - 0.5; };
    for (int f = 0; f < kCubeFaces; ++f) {
        const FaceFrame& fr = kFrames[size_t(f)];
        const double Ra = glm::dot(R, fr.axis), Ru = glm::dot(R, fr.u), Rv = glm::dot(R, fr.v);
        if (Ra < cone.cosReach) continue;
        // Rows tc whose line axis + tc·v + sc·u meets the double cone: the quadratic in sc below has real
        // roots when (Ra + tc·Rv)² ≥ (c² − Ru²)(1 + tc²); for c² ≤ Ru² every row's line does.
        double tLo = -1.0, tHi = 1.0;
        const double kk = c2 - Ru * Ru;
        if (kk > 0.0) {
            const double alpha = Rv * Rv - kk, beta = Ra * Rv, gamma = Ra * Ra - kk;
            const double disc = beta * beta - alpha * gamma;
            // Below 1e-12 the quadratic is linear to rounding: keep every row rather than divide.
            if (alpha < -1e-12) {
                if (disc < 0.0) continue; // no row meets the cone
                const double s = std::sqrt(disc);
                const double r0 = (-beta + s) / alpha, r1 = (-beta - s) / alpha;
                tLo = std::max(-1.0, std::min(r0, r1));
                tHi = std::min(1.0, std::max(r0, r1));
            } else if (alpha > 1e-12 && disc >= 0.0) {
                // Outside the roots: [−1, r0] ∪ [r1, 1], of which the hull.
                const double s = std::sqrt(disc);
                const double r0 = std::min((-beta + s) / alpha, (-beta - s) / alpha);
                const double r1 = std::max((-beta + s) / alpha, (-beta - s) / alpha);
                const bool low = r0 >= -1.0, high = r1 <= 1.0;
                if (!low && !high) continue;
                tLo = low ? -1.0 : r1;
                tHi = high ? 1.0 : r0;
            }
            if (tLo > tHi) continue;
        }
        const int y0 = std::max(0, int(std::ceil(toTexel(tLo))));
        const int y1 = std::min(size - 1, int(std::floor(toTexel(tHi))));
        // Along a row p(sc) = axis + tc·v + sc·u: R·p = A + Ru·sc, |p|² = 1 + tc² + sc², and the cone is
        // (A + Ru·sc)² − c²|p|² = qa·sc² + 2hb·sc + qc ≥ 0 on the side A + Ru·sc ≥ 0.
        const double qa = Ru * Ru - c2;
        for (int y = y0; y <= y1; ++y) {
            const double tc = 2.0 * (y + 0.5) / size - 1.0;
            const double A = Ra + tc * Rv;
            const double hb = A * Ru, qc = A * A - c2 * (1.0 + tc * tc);
            const double disc = hb * hb - qa * qc;
            double lo, hi;
            if (qa == 0.0 || disc < 0.0) {
                // A row along the cone's surface (a linear inequality) or grazing it: the general form.
                if (!lineInterval(R, cone.cosCut, fr.axis + tc * fr.v, fr.u, lo, hi)) continue;
            } else {
                // Numerical Recipes' stable roots q/qa and qc/q: no cancellation when qa or qc is small.
                const double q = -(hb + std::copysign(std::sqrt(disc), hb));
                const double rA = q / qa, rB = q != 0.0 ? qc / q : 0.0;
                const double r0 = std::min(rA, rB), r1 = std::max(rA, rB);
                if (qa < 0.0) {
                    // Inside between the roots: one segment, in R's nappe or in the mirror one.
                    if (A + Ru * 0.5 * (r0 + r1) < 0.0) continue;
                    lo = r0;
                    hi = r1;
                } else {
                    // u lies inside the double cone: the ray towards the sign of Ru is in R's nappe.
                    lo = Ru > 0.0 ? r1 : -2.0;
                    hi = Ru > 0.0 ? 2.0 : r0;
                }
            }
            const int x0 = std::max(0, int(std::ceil(toTexel(std::max(lo, -1.0)))));
            const int x1 = std::min(size - 1, int(std::floor(toTexel(std::min(hi, 1.0)))));
            if (x0 <= x1) visit(f, y, x0, x1);
        }
    }
}

} // namespace

Result<PrefilteredEnvironment> prefilterRadiance(const CubeMap& source, const PrefilterOptions& o) {
    if (source.levels.empty()) return Error{"the environment cube is empty"};
    const int size = source.faceSize();
    if (const Status s = checkFaceSize(size); !s) return Error{s.error()};
    const int full = fullMipCount(size);
    const int mips = o.mips == 0 ? full : o.mips;
    if (mips < 1 || mips > full)
        return Error{fmt::format("{} mips asked for a {}² cube, which has 1 to {}", o.mips, size, full)};
    if (!(o.topPower >= 0.0) || !(o.powerDrop > 0.0) || !std::isfinite(o.topPower) ||
        !std::isfinite(o.powerDrop))
        return Error{
            fmt::format("top power {:g} and power drop {:g} must be >= 0 and > 0", o.topPower, o.powerDrop)};
    if (!(o.lobeCutoff > 0.0 && o.lobeCutoff < 1.0))
        return Error{fmt::format("lobe cutoff {:g} must lie in (0, 1)", o.lobeCutoff)};
    if (!(o.texelsPerSigma > 0.0 && o.texelsPerSigma <= 64.0))
        return Error{fmt::format("texels per sigma {:g} must lie in (0, 64]", o.texelsPerSigma)};

    CubeMap chain;
    chain.levels.push_back(source.levels[0]);
    buildBoxMips(chain);
    std::vector<std::optional<SourceLevel>> flat(chain.levels.size());

    PrefilteredEnvironment out;
    out.lobe = o.lobe;
    out.powers = prefilterPowers(o, mips);
    out.radiance = CubeMap::zeros(size, mips);
    for (int m = 0; m < mips; ++m) {
        const auto start = std::chrono::steady_clock::now();
        const double n = out.powers[size_t(m)];
        // The coarsest source level whose texels (2/size radians across at a face centre) are still
        // texelsPerSigma to the lobe's standard deviation.
        const double sigma = lobeSigma(o.lobe, n);
        int sourceLevel = 0;
        // The Gaussian width estimate fails for powers near 0 (the lobe covers the sphere): never read
        // a level coarser than 64² faces. Measured on the courtyard probe at 256² against brute
        // force (`burnish env --report`): reading 16² faces left mips 3-8 0.14-0.5% off, 64² faces
        // 0.7e-4 to 5e-4, for about 70 ms more over the whole chain.
        constexpr int kMinSourceSize = 64;
        while (sourceLevel + 1 < chain.mipCount() &&
               chain.levels[size_t(sourceLevel + 1)].size >= kMinSourceSize &&
               2.0 / chain.levels[size_t(sourceLevel + 1)].size <= sigma / o.texelsPerSigma)
            ++sourceLevel;
        out.sourceLevels.push_back(sourceLevel);
        if (!flat[size_t(sourceLevel)])
            flat[size_t(sourceLevel)] = flatten(chain.levels[size_t(sourceLevel)]);
        const SourceLevel& src = *flat[size_t(sourceLevel)];
        // The cut leaves out the lobe's tail below lobeCutoff of its peak: for a near-Gaussian lobe that
        // is the same fraction of its energy (1e-5 by default), and the sums are renormalized by Σ w Ω.
        const double uCut = lobeCutOneMinusCosine(o.lobe, n, o.lobeCutoff);
        const CutCone cone(1.0 - uCut);
        const LobeTable lobe(o.lobe, n, uCut);
        CubeLevel& dst = out.radiance.levels[size_t(m)];

        tbb::parallel_for(0, kCubeFaces * dst.size, [&](int row) {
            const int face = row / dst.size, y = row % dst.size;
            for (int x = 0; x < dst.size; ++x) {
                const dvec3 R = texelDirection(face, dst.size, x, y);
                const float rx = float(R.x), ry = float(R.y), rz = float(R.z);
                double sum[3] = {0, 0, 0}, wsum = 0.0;
                forEachConeRun(R, cone, src.size, [&](int f, int ty, int x0, int x1) {
                    const SourceFace& sf = src.faces[size_t(f)];
                    const size_t rowStart = size_t(ty) * size_t(src.size);
                    const float *px = sf.x.data() + rowStart, *py = sf.y.data() + rowStart,
                                *pz = sf.z.data() + rowStart, *pw = sf.omega.data() + rowStart,
                                *pr = sf.r.data() + rowStart, *pg = sf.g.data() + rowStart,
                                *pb = sf.b.data() + rowStart;
                    // 1 − R·L = |R − L|²/2 for unit vectors: no cancellation near the peak, where 1 − c in
                    // float would keep only a few digits at high powers.
                    auto weight = [&](int tx) {
                        const float dx = px[tx] - rx, dy = py[tx] - ry, dz = pz[tx] - rz;
                        return lobe(0.5f * (dx * dx + dy * dy + dz * dz)) * pw[tx];
                    };
                    // Float partial sums over at most kBlock texels (relative rounding below 64·2^-24 =
                    // 4e-6), then double.
                    constexpr int kBlock = 64;
                    for (int xs = x0; xs <= x1; xs += kBlock) {
                        const int xe = std::min(x1, xs + kBlock - 1);
                        Float4 sw4{}, sr4{}, sg4{}, sb4{};
                        int tx = xs;
                        for (; tx + 3 <= xe; tx += 4) {
                            const Float4 dx = load4(px + tx) - rx, dy = load4(py + tx) - ry,
                                         dz = load4(pz + tx) - rz;
                            const Float4 wo = lobe(0.5f * (dx * dx + dy * dy + dz * dz)) * load4(pw + tx);
                            sw4 += wo;
                            sr4 += wo * load4(pr + tx);
                            sg4 += wo * load4(pg + tx);
                            sb4 += wo * load4(pb + tx);
                        }
                        float sw = horizontalSum(sw4), sr = horizontalSum(sr4), sg = horizontalSum(sg4),
                              sb = horizontalSum(sb4);
                        for (; tx <= xe; ++tx) {
                            const float wo = weight(tx);
                            sw += wo;
                            sr += wo * pr[tx];
                            sg += wo * pg[tx];
                            sb += wo * pb[tx];
                        }
                        wsum += sw;
                        sum[0] += sr;
                        sum[1] += sg;
                        sum[2] += sb;
                    }
                });
                float* out3 = dst.texel(face, x, y);
                if (wsum > 0.0) {
                    // A weighted mean of finite radiances, but float products of radiances near FLT_MAX
                    // can overflow: keep the stored value finite.
                    for (int k = 0; k < 3; ++k)
                        out3[k] = float(std::min(sum[k] / wsum, double(std::numeric_limits<float>::max())));
                } else {
                    // A lobe narrower than the source texels around R: no centre fell inside it, so
                    // the lobe sees the source's bilinear value at R.
                    const dvec3 L = sampleCube(chain, R, sourceLevel);
                    for (int k = 0; k < 3; ++k)
                        out3[k] = float(L[k]);
                }
            }
        });
        out.seconds.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        if (o.progress) o.progress(double(m + 1) / double(mips));
    }
    return out;
}

glm::dvec3 referencePrefilteredRadiance(const CubeMap& source, const glm::dvec3& Rin, LobeModel lobe,
                                        double power) {
    if (source.levels.empty()) return {};
    const dvec3 R = glm::normalize(Rin);
    const CubeLevel& level = source.levels[0];
    dvec3 sum(0.0);
    double wsum = 0.0;
    for (int f = 0; f < kCubeFaces; ++f)
        for (int y = 0; y < level.size; ++y)
            for (int x = 0; x < level.size; ++x) {
                const double w = lobeWeight(lobe, power, glm::dot(R, texelDirection(f, level.size, x, y))) *
                                 texelSolidAngle(level.size, x, y);
                if (w <= 0.0) continue;
                sum += w * fetch(level, f, x, y);
                wsum += w;
            }
    return wsum > 0.0 ? sum / wsum : sampleCube(source, R, 0);
}

} // namespace burnish
