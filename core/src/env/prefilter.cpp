#include <burnish/core/env/prefilter.h>

#include <burnish/core/util/memory.h>

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

/// The lobe as (1 − a·u)^k in u = 1 − R·L: Phong c^n is k = n, a = 1; Blinn ((1 + c)/2)^(n/2) is
/// k = n/2, a = 1/2. The cut, the table, the series and the exact evaluation below all start from it.
struct LobeForm {
    double k = 0.0;
    double a = 1.0;
};

LobeForm lobeForm(LobeModel lobe, double power) {
    const double n = clampPower(power);
    return lobe == LobeModel::Phong ? LobeForm{n, 1.0} : LobeForm{0.5 * n, 0.5};
}

/// 1 − cos of the angle beyond which the lobe's weight is below `cutoff` (2: the whole sphere). Computed
/// with expm1 so that it keeps its digits for the highest powers (1e9: 1.2e-8).
double lobeCutOneMinusCosine(LobeModel lobe, double power, double cutoff) {
    const LobeForm form = lobeForm(lobe, power);
    if (form.k <= 0.0) return 2.0;
    // (1 − a·u)^k = cutoff
    return std::min(2.0, -std::expm1(std::log(cutoff) / form.k) / form.a);
}

/// The lobe's angular standard deviation (radians): cos^n θ ≈ exp(−nθ²/2) for Phong, and the Blinn
/// lobe cos^n(θ/2) ≈ exp(−nθ²/8) is twice as wide.
double lobeSigma(LobeModel lobe, double power) {
    const double sigma = 1.0 / std::sqrt(std::max(clampPower(power), 1e-6));
    return lobe == LobeModel::Phong ? sigma : 2.0 * sigma;
}

/// The angle between two unit vectors a chord of length `chord` apart: 2 asin(chord/2), exact near 0.
double chordAngle(double chord) {
    return 2.0 * std::asin(std::min(1.0, 0.5 * chord));
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
    // A texel's solid angle depends on (x, y) only, not on the face.
    const std::vector<double> omega = texelSolidAngles(n);
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
                out.omega[i] = float(omega[i]);
                out.r[i] = L[0];
                out.g[i] = L[1];
                out.b[i] = L[2];
            }
    });
    return flat;
}

/// The lobe as a function of u = 1 − R·L on [0, uCut], and 0 from uCut on, evaluated one of three ways
/// chosen once per mip (see mode()):
/// - Series: narrow lobes, k·log2(1 − a·u) by the first 4 or 6 terms of its Taylor series in u (the
///   fewer that are within kSeriesTolerance of it on [0, uCut]), then 2^x by exp2NonPositive: no memory
///   reads, so it vectorises; the weight errs by about 2e-7 (relative).
/// - Table: sampled at kEntries + 1 points for linear interpolation: with the lobe cut at a fraction ε of
///   its peak it falls by about ln(1/ε) e-folds over the table (11.5 at ε = 1e-5), so interpolation errs
///   by (ln(1/ε)/kEntries)²/8 ≈ 1e-6 of the weight, below the float rounding of the sums.
/// - Exact: exponents k below 2 have an unbounded second derivative where the lobe reaches 0 (c = 0, or
///   c = −1 for Blinn), where the table's lerp error grows without bound; those wide lobes are evaluated
///   with log1p and exp.
class LobeWeights {
public:
    enum class Mode { Series4, Series6, Table, Exact };
    static constexpr int kEntries = 4096;
    static constexpr int kSeriesTerms = 6;
    /// Largest truncation error of the series in ℓ = log2(weight): 2^1e-7 − 1 = 7e-8 of the weight.
    static constexpr double kSeriesTolerance = 1e-7;
    /// The least ℓ at the cut for the series: exp2NonPositive's range ends at −125 (cutoffs below 1e-36).
    static constexpr double kMinSeriesLog2 = -120.0;

    LobeWeights(LobeModel lobe, double power, double uCut)
        : m_form(lobeForm(lobe, power)) {
        // 2 is the whole sphere (u = 1 − cos); a zero-width cut would divide by 0 below.
        uCut = std::clamp(uCut, std::numeric_limits<double>::min(), 2.0);
        m_uCut = float(uCut);
        m_qCut = 2.0f * m_uCut;
        m_k = float(m_form.k);
        m_a = float(m_form.a);
        // Below 2 the lerp error near the lobe's zero grows without bound (x^p with p < 2 at x → 0).
        constexpr double kMinTableExponent = 2.0;
        m_mode = m_form.k > 0.0 && m_form.k < kMinTableExponent ? Mode::Exact
                 : fitSeries(uCut, 4)                           ? Mode::Series4
                 : fitSeries(uCut, 6)                           ? Mode::Series6
                                                                : Mode::Table;
        if (m_mode == Mode::Table) fillTable(uCut);
    }

    Mode mode() const { return m_mode; }

    /// The weights at eight q = |R − L|² = 2u ≥ 0 (finite) in mode M (mode(), or Exact or Table); the
    /// exact mode leaves the lanes from `lanes` on at 0 (they repeat others).
    template <Mode M> [[gnu::always_inline]] Float8 at(Float8 q, int lanes) const {
        if constexpr (M == Mode::Series4 || M == Mode::Series6) {
            // ℓ = q·(c1 + c2·q + ... + c6·q⁵) by Estrin's scheme (see exp2NonPositive)
            const Float8 q2 = q * q;
            Float8 l = (m_series[0] + m_series[1] * q) + q2 * (m_series[2] + m_series[3] * q);
            if constexpr (M == Mode::Series6) l += (q2 * q2) * (m_series[4] + m_series[5] * q);
            // Past the cut ℓ may leave exp2NonPositive's range: those lanes are dropped.
            return q < m_qCut ? exp2NonPositive(l * q) : Float8{};
        } else if constexpr (M == Mode::Table) {
            Float8 x = q * m_scale;
            x = x < float(kEntries) ? x : float(kEntries);
            const Int8 i = __builtin_convertvector(x, Int8);
            const Float8 f = x - __builtin_convertvector(i, Float8);
            Float8 value, slope;
            for (int lane = 0; lane < 8; ++lane) {
                value[lane] = m_value[size_t(i[lane])];
                slope[lane] = m_slope[size_t(i[lane])];
            }
            return value + f * slope;
        } else {
            Float8 w{};
            for (int lane = 0; lane < lanes; ++lane)
                w[lane] = exact(0.5f * q[lane]);
            return w;
        }
    }

private:
    /// lobeForm's (1 − a·u)^k with log1p so that u near 0 keeps its digits; 0 from a·u = 1 on.
    static double weight(const LobeForm& form, double u) {
        if (form.k == 0.0) return 1.0; // powCos(c, 0) = 1 everywhere, as lobeWeight
        return form.a * u < 1.0 ? std::exp(form.k * std::log1p(-form.a * u)) : 0.0;
    }

    /// The same in float for the exact mode (k > 0 there: log1p(−1) = −inf gives exp(−inf) = 0 at the
    /// lobe's zero).
    float exact(float u) const {
        if (!(u < m_uCut)) return 0.0f;
        return std::exp(m_k * std::log1p(-m_a * u));
    }

    /// The series coefficients of ℓ(u)/u when `terms` terms are within kSeriesTolerance on [0, uCut] and
    /// ℓ stays within exp2NonPositive's range there; false when they are not (wide lobes).
    // k·log2(1 − a·u) = −(k/ln 2) Σ_{j≥1} (a·u)^j / j; the tail after J terms is at most
    // (k/ln 2)(a·u)^(J+1)/((J + 1)(1 − a·u))
    bool fitSeries(double uCut, int terms) {
        const double au = m_form.a * uCut, scale = m_form.k / std::log(2.0);
        if (!(au < 1.0) || !(m_form.k * std::log2(1.0 - au) > kMinSeriesLog2)) return false;
        const double tail = scale * std::pow(au, terms + 1) / ((terms + 1) * (1.0 - au));
        if (!(tail <= kSeriesTolerance)) return false;
        m_series.fill(0.0f);
        // In q = 2u: the j-th coefficient over 2^j.
        for (int j = 1; j <= terms; ++j)
            m_series[size_t(j - 1)] = float(-scale * std::pow(0.5 * m_form.a, j) / j);
        return true;
    }

    void fillTable(double uCut) {
        // u·(kEntries/uCut) as q·(kEntries/(2 uCut)): the halving is exact, so the same bits.
        m_scale = 0.5f * float(kEntries / uCut);
        std::vector<double> w(kEntries + 1);
        for (int k = 0; k <= kEntries; ++k)
            w[size_t(k)] = weight(m_form, uCut * k / kEntries);
        m_value.resize(kEntries + 1);
        m_slope.resize(kEntries + 1);
        for (int k = 0; k < kEntries; ++k) {
            m_value[size_t(k)] = float(w[size_t(k)]);
            m_slope[size_t(k)] = float(w[size_t(k + 1)] - w[size_t(k)]);
        }
        // Past the cut: weight 0 (u·scale is clamped to kEntries before indexing).
        m_value[kEntries] = 0.0f;
        m_slope[kEntries] = 0.0f;
    }

    LobeForm m_form;
    Mode m_mode = Mode::Table;
    float m_k = 0.0f, m_a = 1.0f, m_uCut = 0.0f, m_qCut = 0.0f, m_scale = 0.0f;
    std::array<float, kSeriesTerms> m_series{};
    std::vector<float> m_value, m_slope;
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

/// Source texels (face, row y, columns x0..x1) an output tile's sums read.
struct Run {
    int face, y, x0, x1;
};

/// Output texels are filtered eight at a time, one per lane: a kTileWidth × kTileHeight tile of a face,
/// which shares one list of runs (the source texels within the cut of any of them). Per texel, the
/// tile's runs hold about a quarter more texels than its own cone at the top mip (a cone of about 14
/// texels' radius widened by the tile's half-diagonal, 1.6), against a row search per texel and a
/// partly used last vector per run (a third more, measured) when the lanes hold source texels instead.
constexpr int kTileWidth = 4, kTileHeight = 2;

/// The texels of a tile: those of (x0.., y0..) inside the `size`² face.
struct Tile {
    int face = 0, x0 = 0, y0 = 0, width = 0, height = 0;

    Tile(int faceIn, int size, int x0In, int y0In)
        : face(faceIn)
        , x0(x0In)
        , y0(y0In)
        , width(std::min(kTileWidth, size - x0In))
        , height(std::min(kTileHeight, size - y0In)) {}

    /// The tile's texel count: lanes 0..texels() − 1 hold them row by row, the rest repeat them (a face
    /// smaller than the tile).
    int texels() const { return width * height; }
    int x(int k) const { return x0 + k % texels() % width; }
    int y(int k) const { return y0 + k % texels() / width; }
    bool holds(int k) const { return k < texels(); }
};

/// The runs of a `srcSize`² level within the lobe's cut cone (1 − cos = uCut) of any texel of the tile
/// (of a `size`² face): the cone about the tile's middle direction, widened by the largest angle from it
/// to a texel.
void tileRuns(const Tile& tile, int size, double uCut, int srcSize, std::vector<Run>& runs) {
    const dvec3 middle =
        cubeDirection(tile.face, (tile.x0 + 0.5 * tile.width) / size, (tile.y0 + 0.5 * tile.height) / size);
    double spread = 0.0;
    for (int k = 0; k < 8; ++k)
        spread = std::max(
            spread, chordAngle(glm::length(texelDirection(tile.face, size, tile.x(k), tile.y(k)) - middle)));
    // The angle of 1 − cos = uCut without cancellation: θ = 2 asin(sqrt(uCut/2)); 1e-9 for rounding.
    const double theta = std::min(kPi<double>, chordAngle(std::sqrt(2.0 * uCut)) + spread + 1e-9);
    runs.clear();
    forEachConeRun(middle, CutCone(std::cos(theta)), srcSize, [&](int f, int ty, int x0, int x1) {
        runs.push_back({f, ty, x0, x1});
    });
}

/// Per lane: Σ w Ω L (r, g, b) and Σ w Ω.
struct TileSums {
    std::array<std::array<double, 4>, 8> lane{};
};

/// Σ w(1 − R·d) Ω(d) L(d) and Σ w Ω over the runs for the eight directions R in the lanes, of which the
/// first `lanes` are distinct (Tile). The lobe's mode is a template argument: a branch (and calls) in
/// the inner loop would keep its sums out of registers.
template <LobeWeights::Mode M>
[[gnu::always_inline]] inline TileSums sumTile(const SourceLevel& src, const std::vector<Run>& runs,
                                               const LobeWeights& lobe, const Float8& rx, const Float8& ry,
                                               const Float8& rz, int lanes) {
    // Float partial sums over at most kBlock texels (relative rounding below 64·2^-24 = 4e-6), then
    // double.
    constexpr int kBlock = 64;
    TileSums sums;
    Float8 sw{}, sr{}, sg{}, sb{};
    int count = 0;
    auto flush = [&] {
        for (int k = 0; k < 8; ++k) {
            sums.lane[size_t(k)][0] += sr[k];
            sums.lane[size_t(k)][1] += sg[k];
            sums.lane[size_t(k)][2] += sb[k];
            sums.lane[size_t(k)][3] += sw[k];
        }
        sw = sr = sg = sb = Float8{};
        count = 0;
    };
    for (const Run& run : runs) {
        const SourceFace& sf = src.faces[size_t(run.face)];
        const size_t start = size_t(run.y) * size_t(src.size);
        for (size_t i = start + size_t(run.x0); i <= start + size_t(run.x1); ++i) {
            // 1 − R·L = |R − L|²/2 for unit vectors: no cancellation near the peak, where 1 − c in float
            // would keep only a few digits at high powers.
            const Float8 dx = sf.x[i] - rx, dy = sf.y[i] - ry, dz = sf.z[i] - rz;
            const Float8 wo = lobe.at<M>(dx * dx + dy * dy + dz * dz, lanes) * sf.omega[i];
            sw += wo;
            sr += wo * sf.r[i];
            sg += wo * sf.g[i];
            sb += wo * sf.b[i];
            if (++count == kBlock) flush();
        }
    }
    flush();
    return sums;
}

/// sumTile in the lobe's mode, with an AVX2 copy.
BURNISH_AVX2_CLONES TileSums sumTileClones(const SourceLevel& src, const std::vector<Run>& runs,
                                           const LobeWeights& lobe, const Float8& rx, const Float8& ry,
                                           const Float8& rz, int lanes) {
    switch (lobe.mode()) {
    case LobeWeights::Mode::Series4:
        return sumTile<LobeWeights::Mode::Series4>(src, runs, lobe, rx, ry, rz, lanes);
    case LobeWeights::Mode::Series6:
        return sumTile<LobeWeights::Mode::Series6>(src, runs, lobe, rx, ry, rz, lanes);
    case LobeWeights::Mode::Table:
        return sumTile<LobeWeights::Mode::Table>(src, runs, lobe, rx, ry, rz, lanes);
    case LobeWeights::Mode::Exact:
        break;
    }
    return sumTile<LobeWeights::Mode::Exact>(src, runs, lobe, rx, ry, rz, lanes);
}

/// Filters one tile of `dst` from `src`: the lobe-weighted mean per texel, or where no source texel
/// centre fell inside a texel's lobe (one narrower than the source texels around R), the source's
/// bilinear value at R from level `sourceLevel` of `chain`.
void filterTile(const Tile& tile, CubeLevel& dst, const SourceLevel& src, const LobeWeights& lobe,
                double uCut, const CubeMap& chain, int sourceLevel, std::vector<Run>& runs) {
    tileRuns(tile, dst.size, uCut, src.size, runs);
    std::array<dvec3, 8> R;
    Float8 rx, ry, rz;
    for (int k = 0; k < 8; ++k) {
        R[size_t(k)] = texelDirection(tile.face, dst.size, tile.x(k), tile.y(k));
        rx[k] = float(R[size_t(k)].x);
        ry[k] = float(R[size_t(k)].y);
        rz[k] = float(R[size_t(k)].z);
    }
    const TileSums sums = sumTileClones(src, runs, lobe, rx, ry, rz, tile.texels());
    for (int k = 0; k < 8; ++k) {
        if (!tile.holds(k)) continue;
        const auto& s = sums.lane[size_t(k)];
        float* out = dst.texel(tile.face, tile.x(k), tile.y(k));
        if (s[3] > 0.0) {
            // A weighted mean of finite radiances, but float products of radiances near FLT_MAX can
            // overflow: keep the stored value finite.
            for (int c = 0; c < 3; ++c)
                out[c] = float(std::min(s[size_t(c)] / s[3], double(std::numeric_limits<float>::max())));
        } else {
            const dvec3 L = sampleCube(chain, R[size_t(k)], sourceLevel);
            for (int c = 0; c < 3; ++c)
                out[c] = float(L[c]);
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
        const LobeWeights lobe(o.lobe, n, uCut);
        CubeLevel& dst = out.radiance.levels[size_t(m)];

        // Tasks of one row of tiles each.
        const int tilesAcross = (dst.size + kTileWidth - 1) / kTileWidth;
        const int tilesDown = (dst.size + kTileHeight - 1) / kTileHeight;
        tbb::parallel_for(0, kCubeFaces * tilesDown, [&](int task) {
            const int face = task / tilesDown, y0 = task % tilesDown * kTileHeight;
            std::vector<Run> runs;
            for (int t = 0; t < tilesAcross; ++t)
                filterTile(Tile(face, dst.size, t * kTileWidth, y0), dst, src, lobe, uCut, chain, sourceLevel,
                           runs);
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

std::uint64_t estimatedEnvironmentBytes(int faceSize, std::uint64_t inputTexels) {
    constexpr double kPerCubeTexel = 48.0, kPerInputTexel = 32.0;
    const double cubeTexels = 6.0 * double(std::max(faceSize, 1)) * double(std::max(faceSize, 1));
    return std::uint64_t(double(kProcessBytes) + kPerCubeTexel * cubeTexels +
                         kPerInputTexel * double(inputTexels));
}

} // namespace burnish
