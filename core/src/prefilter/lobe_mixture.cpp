// Double4 values pass only between inline functions and the target_clones copies of this file (see
// util/simd.h), never across a library's interface: GCC's note on their ABI does not apply.
#if defined(__GNUC__) // GCC, and Clang (which defines __GNUC__ and has the same warning)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

#include <burnish/core/prefilter/lobe_mixture.h>

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/shading/ggx_specular.h>
#include <burnish/core/util/numeric.h>
#include <burnish/core/util/simd.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>

namespace burnish {

namespace {

// Correlations are kept inside (−kMaxCorrelation, kMaxCorrelation): det Σ stays positive.
constexpr double kMaxCorrelation = 0.999; // as methods.glsl: det Σ stays positive in float too
// A merge costing less than this per unit of weight loses nothing a float texture could store.
constexpr double kNegligibleMergeCost = 1e-9;

// Canonical order: by mean slope x, then y, then weight (a total order on distinct lobes).
bool canonicalLess(const LobeMoments& a, const LobeMoments& b) {
    const glm::dvec2 ma = a.mean(), mb = b.mean();
    if (ma.x != mb.x) return ma.x < mb.x;
    if (ma.y != mb.y) return ma.y < mb.y;
    return a.w > b.w;
}

// The first n of `lobes` (n <= kMaxMixtureLobes) in canonical order, as a mixture: how every reduction
// hands back its lobes.
LobeMixture canonicalMixture(LobeMoments* lobes, size_t n) {
    std::sort(lobes, lobes + n, canonicalLess);
    LobeMixture out;
    out.count = int(n);
    std::copy_n(lobes, n, out.lobes.begin());
    return out;
}

using InjectiveMap = std::array<unsigned char, kMaxMixtureLobes>;

// The injective maps of n children into `slots` slots (1 <= n <= slots <= kMaxMixtureLobes), in
// lexicographic order of (slot of child 0, slot of child 1, ...): built once per (n, slots).
const std::vector<InjectiveMap>& injectiveMaps(int n, int slots) {
    static const auto tables = [] {
        std::array<std::array<std::vector<InjectiveMap>, kMaxMixtureLobes + 1>, kMaxMixtureLobes + 1> t;
        for (int count = 1; count <= kMaxMixtureLobes; ++count)
            for (int width = count; width <= kMaxMixtureLobes; ++width) {
                InjectiveMap current{};
                auto walk = [&](auto&& self, int c, unsigned used) -> void {
                    if (c == count) {
                        t[size_t(count)][size_t(width)].push_back(current);
                        return;
                    }
                    for (int slot = 0; slot < width; ++slot) {
                        if (used & (1u << slot)) continue;
                        current[size_t(c)] = (unsigned char)slot;
                        self(self, c + 1, used | (1u << slot));
                    }
                };
                walk(walk, 0, 0u);
            }
        return t;
    }();
    return tables[size_t(n)][size_t(slots)];
}

} // namespace

// A mixture's lobes decoded once for assigning many slopes to them: per lobe its mean, Σ's entries
// and det Σ, and log w − ½ log det Σ.
class LobeScorer {
public:
    /// The first `count` of `lobes` (a mixture's slots).
    LobeScorer(const LobeMoments* lobes, int count, double minVariance)
        : m_count(count)
        , m_minVariance(minVariance) {
        for (int i = 0; i < m_count; ++i) {
            const LobeMoments& l = lobes[size_t(i)];
            const auto c = l.covariance(minVariance);
            Lobe& d = m_lobes[size_t(i)];
            d.mean = l.mean();
            d.xx = c[0], d.yy = c[1], d.xy = c[2], d.det = c[0] * c[1] - c[2] * c[2];
            d.offset = 0.5 * std::log(l.w * l.w / d.det); // log w − ½ log det Σ in one logarithm
        }
    }
    /// Puts a child's lobes (the first `count` of its `slots` stored ones) into the slots of this
    /// mixture's lobes: the assignment of child lobes to distinct slots 0..slots−1 (the lobe count K, at
    /// least count) with the largest total score (an empty slot scores kEmptySlotScore, below any lobe's);
    /// ties to the first in lexicographic order. A child lobe's score for a slot is the expected
    /// log-likelihood of its normals under the slot's lobe: its weight times crossScoreOf, the whole
    /// lobe, its spread too, not only its mean, so a broad child lobe goes to a broad slot rather than
    /// to a narrow one that sits at its mean, where filtering would smear that narrow cluster. Weighted,
    /// a heavy lobe's slot counts for as many normals as it holds: a light broad lobe of scattered
    /// normals no longer moves a texel's main lobe to another slot than its neighbours' (bricks_n at
    /// s = 1024, mip 4, between texels, K = 4: 0.397 -> 0.086 unweighted -> weighted). Empty slots get
    /// empty lobes; count becomes the last used slot + 1.
    void reorder(LobeMoments* lobes, unsigned char& count, int slots) const {
        const int n = std::min(int(count), kMaxMixtureLobes);
        if (n == 0) return;
        std::array<std::array<double, kMaxMixtureLobes>, kMaxMixtureLobes> score{};
        for (int c = 0; c < n; ++c) {
            const glm::dvec2 mean = lobes[size_t(c)].mean();
            const auto cov = lobes[size_t(c)].covariance(m_minVariance);
            const double w = lobes[size_t(c)].w;
            for (int slot = 0; slot < slots; ++slot)
                score[size_t(c)][size_t(slot)] =
                    slot < m_count && m_lobes[size_t(slot)].offset > -std::numeric_limits<double>::infinity()
                        ? w * crossScoreOf(slot, mean, cov)
                        : kEmptySlotScore;
        }
        // Every injective map of the n child lobes into the slots (at most 4·3·2·1), in lexicographic
        // order, each total summed child by child: the first of the largest.
        InjectiveMap best{};
        double bestTotal = -std::numeric_limits<double>::infinity();
        for (const auto& map : injectiveMaps(n, slots)) {
            double total = 0.0;
            for (int c = 0; c < n; ++c)
                total += score[size_t(c)][map[size_t(c)]];
            if (total > bestTotal) bestTotal = total, best = map;
        }
        std::array<LobeMoments, kMaxMixtureLobes> out{};
        int outCount = 0;
        for (int c = 0; c < n; ++c) {
            out[size_t(best[size_t(c)])] = lobes[size_t(c)];
            outCount = std::max(outCount, best[size_t(c)] + 1);
        }
        std::copy_n(out.begin(), slots, lobes);
        count = (unsigned char)outCount;
    }

    /// The lobe with the largest log(w N(b; μ, Σ)) (up to a constant); ties to the lower index.
    int assign(const glm::dvec2& b) const {
        int best = 0;
        double bestScore = -std::numeric_limits<double>::infinity();
        for (int i = 0; i < m_count; ++i) {
            const double score = scoreOf(i, b);
            if (score > bestScore) bestScore = score, best = i;
        }
        return best;
    }

private:
    // Scores are log-likelihoods; an empty slot is worth less than any lobe a float can score.
    static constexpr double kEmptySlotScore = -1e300;

    double scoreOf(int slot, const glm::dvec2& b) const {
        const Lobe& l = m_lobes[size_t(slot)];
        const glm::dvec2 d = b - l.mean;
        const double e = (d.x * d.x * l.yy + d.y * d.y * l.xx - 2.0 * d.x * d.y * l.xy) / l.det;
        return l.offset - 0.5 * e;
    }

    // E[log(w N(x; μ, Σ))] over x ~ N(b, C), up to a constant: log w − ½ log det Σ
    // − ½[(b − μ)ᵀΣ⁻¹(b − μ) + tr(Σ⁻¹C)] (C: xx, yy, xy).
    double crossScoreOf(int slot, const glm::dvec2& b, const std::array<double, 3>& c) const {
        const Lobe& l = m_lobes[size_t(slot)];
        const glm::dvec2 d = b - l.mean;
        const double e = (d.x * d.x * l.yy + d.y * d.y * l.xx - 2.0 * d.x * d.y * l.xy + l.yy * c[0] +
                          l.xx * c[1] - 2.0 * l.xy * c[2]) /
                         l.det;
        return l.offset - 0.5 * e;
    }

    struct Lobe {
        glm::dvec2 mean{0.0};
        double xx = 1.0, yy = 1.0, xy = 0.0, det = 1.0, offset = 0.0;
    };
    std::array<Lobe, kMaxMixtureLobes> m_lobes{};
    int m_count = 0;
    double m_minVariance = 0.0;
};

const char* mixtureFilteringName(MixtureFiltering filtering) {
    return filtering == MixtureFiltering::Stochastic ? "stochastic" : "moments";
}

std::optional<MixtureFiltering> parseMixtureFiltering(std::string_view name) {
    if (name == "moments") return MixtureFiltering::Moments;
    if (name == "stochastic") return MixtureFiltering::Stochastic;
    return std::nullopt;
}

StochasticTexel stochasticTexel(glm::vec2 uv, float lod, glm::ivec2 size0, int levels, glm::vec3 xi) {
    levels = std::max(levels, 1);
    const float l = lod == lod ? std::clamp(lod, 0.0f, float(levels - 1)) : 0.0f; // NaN: level 0
    const float fl = std::floor(l);
    const int level = std::min(int(fl) + (xi.z < l - fl ? 1 : 0), levels - 1);
    const glm::ivec2 size = glm::max(glm::ivec2(size0.x >> level, size0.y >> level), glm::ivec2(1));
    // The repeat wrap first (GLSL's fract), so the texel index stays small; non-finite uv is 0.
    const float u = std::isfinite(uv.x) ? uv.x - std::floor(uv.x) : 0.0f;
    const float v = std::isfinite(uv.y) ? uv.y - std::floor(uv.y) : 0.0f;
    const float px = u * float(size.x) - 0.5f, py = v * float(size.y) - 0.5f;
    const float bx = std::floor(px), by = std::floor(py);
    const int x = int(bx) + (xi.x < px - bx ? 1 : 0), y = int(by) + (xi.y < py - by ? 1 : 0);
    return {(x + size.x) % size.x, (y + size.y) % size.y, level};
}

glm::vec3 stochasticNumbers(glm::uvec3 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> 16u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return glm::vec3(v >> 8u) * (1.0f / 16777216.0f);
}

namespace {

// LobeMoments::mean and covariance, always inlined: the squared-error reduction's AVX2 copy reads them
// for every merge, and a call from it into the default copy's code cost a fifth of its time.
[[gnu::always_inline]] inline glm::dvec2 meanOf(const LobeMoments& l) {
    return l.w > 0.0 ? glm::dvec2(l.bx / l.w, l.by / l.w) : glm::dvec2(0.0);
}

[[gnu::always_inline]] inline std::array<double, 3> covarianceOf(const LobeMoments& l, double minVariance) {
    if (!(l.w > 0.0)) return {minVariance, minVariance, 0.0};
    const glm::dvec2 b = meanOf(l);
    double xx = l.mxx / l.w - b.x * b.x, yy = l.myy / l.w - b.y * b.y, xy = l.mxy / l.w - b.x * b.y;
    xx = xx > minVariance ? xx : minVariance; // also NaN → minVariance
    yy = yy > minVariance ? yy : minVariance;
    const double limit = kMaxCorrelation * std::sqrt(xx * yy);
    xy = std::isfinite(xy) ? std::clamp(xy, -limit, limit) : 0.0;
    return {xx, yy, xy};
}

} // namespace

glm::dvec2 LobeMoments::mean() const {
    return meanOf(*this);
}

std::array<double, 3> LobeMoments::covariance(double minVariance) const {
    return covarianceOf(*this, minVariance);
}

namespace {

// A finest normal's slope: the pyramid's (NormalMoments), (0, 0) for a non-finite normal (decoders
// replace them; guarded anyway), which counts as the flat one. Its lobe's mean (w = 1).
glm::dvec2 finestSlope(const glm::vec3& n) {
    const NormalMoments m = NormalMoments::ofNormal(n);
    const bool finite = std::isfinite(m.slope.x) && std::isfinite(m.slope.y);
    return finite ? glm::dvec2(m.slope) : glm::dvec2(0.0);
}

// The two texels of a level of `parentSize` (and their weights) that bilinear filtering reads at the
// centre of texel i of a level of `size`, the border mode resolving those outside.
void bilinearTaps(int i, int size, int parentSize, BorderMode border, std::array<int, 2>& at,
                  std::array<double, 2>& weight) {
    const double u = (double(i) + 0.5) / double(size) * double(parentSize) - 0.5;
    const double f = std::floor(u);
    const int i0 = int(f);
    weight = {1.0 - (u - f), u - f};
    at = {borderIndex(i0, parentSize, border), borderIndex(i0 + 1, parentSize, border)};
}

} // namespace

LobeMoments LobeMoments::ofNormal(const glm::vec3& n, double v) {
    const glm::dvec2 b = finestSlope(n);
    const double bx = b.x, by = b.y;
    LobeMoments l;
    l.w = 1.0;
    l.bx = bx;
    l.by = by;
    l.mxx = bx * bx + v;
    l.myy = by * by + v;
    l.mxy = bx * by;
    return l;
}

double LobeMixture::totalWeight() const {
    double w = 0.0;
    for (int i = 0; i < count; ++i)
        w += lobes[size_t(i)].w;
    return w;
}

namespace {

// log det Σ of the lobe with raw moments (w, w·b, w·M), w > 0: LobeMoments::covariance's clamps
// (variances at least minVariance, |ρ| <= kMaxCorrelation) on det directly, without the square root,
// and the logarithm without a call (log2Positive: det is a positive normal double, at least
// minVariance²·(1 − kMaxCorrelation²)). The merge costs' inner loop: no branch, no call. D is double,
// or Double4 for four lobes at once (the same operations lane by lane: the same bits).
template <class D>
[[gnu::always_inline]] inline D logDetOfMoments(D w, D bx, D by, D mxx, D myy, D mxy, double minVariance) {
    const D floor = D{} + minVariance;
    const D inv = 1.0 / w;
    const D mx = bx * inv, my = by * inv;
    D xx = mxx * inv - mx * mx, yy = myy * inv - my * my;
    xx = xx > minVariance ? xx : floor; // also NaN → minVariance
    yy = yy > minVariance ? yy : floor;
    const D xy = mxy * inv - mx * my;
    const D limit = kMaxCorrelation * kMaxCorrelation * xx * yy;
    D xy2 = xy * xy;
    xy2 = xy2 < limit ? xy2 : limit; // also NaN → the limit
    if constexpr (std::is_same_v<D, double>)
        return kLn2<double> * log2Positive(xx * yy - xy2);
    else
        return kLn2<double> * log2Positive<D, simd::UInt64x4>(xx * yy - xy2);
}

// w · log det Σ of a lobe: the part of the merge cost each lobe brings, computed once per lobe.
[[gnu::always_inline]] inline double weightedLogDet(const LobeMoments& a, double minVariance) {
    return a.w * logDetOfMoments(a.w, a.bx, a.by, a.mxx, a.myy, a.mxy, minVariance);
}

// Runnalls' cost from the merged lobe's log det and the two lobes' w·log det, in this order.
template <class D> [[gnu::always_inline]] inline D costOfMerge(D w, D ld, D wlA, D wlB) {
    const D cost = 0.5 * (w * ld - wlA - wlB);
    return cost > 0.0 ? cost : D{}; // rounding below the bound's 0
}

double mergeCostOf(const LobeMoments& a, double wlA, const LobeMoments& b, double wlB, double minVariance) {
    const double w = a.w + b.w;
    const double ld = logDetOfMoments(w, a.bx + b.bx, a.by + b.by, a.mxx + b.mxx, a.myy + b.myy,
                                      a.mxy + b.mxy, minVariance);
    return costOfMerge(w, ld, wlA, wlB);
}

// The lobes of one reduction as columns with four to seven copies of lobe 0 after them (finite, w > 0:
// lanes past the last lobe compute a harmless cost nobody reads, and a run of four from any lobe
// stays inside), with each lobe's w·log det Σ.
struct LobeColumns {
    std::vector<double> w, bx, by, mxx, myy, mxy, wl;

    static size_t padded(size_t n) { return (n + 7) / 4 * 4; }
    [[gnu::always_inline]] void set(size_t i, const LobeMoments& l) {
        w[i] = l.w, bx[i] = l.bx, by[i] = l.by, mxx[i] = l.mxx, myy[i] = l.myy, mxy[i] = l.mxy;
    }
    /// Columns of `lobes` (at least one) and their w·log det Σ, four at a time.
    [[gnu::always_inline]] void assign(const std::vector<LobeMoments>& lobes, double minVariance) {
        const size_t n = padded(lobes.size());
        for (auto* c : {&w, &bx, &by, &mxx, &myy, &mxy, &wl})
            c->resize(n);
        for (size_t i = 0; i < n; ++i)
            set(i, lobes[i < lobes.size() ? i : 0]);
        // The lobes' own w·log det Σ; lanes past them hold any finite value (zeros or an earlier
        // reduction's), read only by costs nobody reads.
        for (size_t i = 0; i < lobes.size(); i += 4) {
            const simd::Double4 wi = load(w, i);
            store(wl, i,
                  wi * logDetOfMoments(wi, load(bx, i), load(by, i), load(mxx, i), load(myy, i), load(mxy, i),
                                       minVariance));
        }
    }
    /// Lobe i changed (a merge): its columns and w·log det Σ.
    [[gnu::always_inline]] void update(size_t i, const LobeMoments& l, double minVariance) {
        set(i, l);
        wl[i] = weightedLogDet(l, minVariance);
    }
    /// Lobe i is a merge whose log det Σ its pair's cost computed (the same sums of moments and the
    /// same operations as weightedLogDet's, lane for scalar: the same bits).
    [[gnu::always_inline]] void updateMerged(size_t i, const LobeMoments& l, double logDet) {
        set(i, l);
        wl[i] = l.w * logDet;
    }
    /// The merge costs of lobe i with lobes j (j0 <= j < j0 + 4·⌈count/4⌉) into out[j]: as
    /// mergeCostOf(lobe lo, wl[lo], lobe hi, wl[hi]) with (lo, hi) = (i, j), or with `byIndex` the
    /// pair in index order (min(i, j), max(i, j)), the order of the cost matrix. j = i gives garbage.
    /// Each merged lobe's log det Σ into logDets[j] as well.
    [[gnu::always_inline]] void costsWith(size_t i, size_t j0, size_t count, bool byIndex, double minVariance,
                                          std::vector<double>& out, std::vector<double>& logDets) const {
        const simd::Double4 wi = D4(w[i]), bxi = D4(bx[i]), byi = D4(by[i]), mxxi = D4(mxx[i]),
                            myyi = D4(myy[i]), mxyi = D4(mxy[i]), wli = D4(wl[i]);
        for (size_t j = j0; j < j0 + count; j += 4) {
            const simd::Double4 ww = wi + load(w, j);
            const simd::Double4 ld =
                logDetOfMoments(ww, bxi + load(bx, j), byi + load(by, j), mxxi + load(mxx, j),
                                myyi + load(myy, j), mxyi + load(mxy, j), minVariance);
            const simd::Double4 wlj = load(wl, j);
            const simd::Int64x4 index{std::int64_t(j), std::int64_t(j + 1), std::int64_t(j + 2),
                                      std::int64_t(j + 3)};
            const simd::Int64x4 swap = byIndex ? index < std::int64_t(i) : simd::Int64x4{};
            store(out, j, costOfMerge(ww, ld, swap ? wlj : wli, swap ? wli : wlj));
            store(logDets, j, ld);
        }
    }

private:
    [[gnu::always_inline]] static simd::Double4 D4(double v) { return simd::Double4{v, v, v, v}; }
    [[gnu::always_inline]] static simd::Double4 load(const std::vector<double>& c, size_t i) {
        simd::Double4 v;
        std::memcpy(&v, c.data() + i, sizeof v);
        return v;
    }
    [[gnu::always_inline]] static void store(std::vector<double>& c, size_t i, simd::Double4 v) {
        std::memcpy(c.data() + i, &v, sizeof v);
    }
};

} // namespace

double mergeCost(const LobeMoments& a, const LobeMoments& b, double minVariance) {
    return mergeCostOf(a, weightedLogDet(a, minVariance), b, weightedLogDet(b, minVariance), minVariance);
}

namespace {

// The lobes of one squared-error reduction as columns: each lobe's weight, mean, covariance
// (LobeMoments::covariance: positive definite) and overlap with itself, w²/(4π√det Σ). With weights
// of 1 to 2^24 finest texels and det Σ at least minVariance²·(1 − 0.999²), every cost stays far
// inside a double's range.
struct IseColumns {
    std::vector<double> w, mx, my, xx, yy, xy, self;

    void resize(size_t n) {
        for (auto* c : {&w, &mx, &my, &xx, &yy, &xy, &self})
            c->resize(n);
    }
    /// Lobe i of `count` removed: the lobes after it move down one place.
    void erase(size_t i, size_t count) {
        for (auto* c : {&w, &mx, &my, &xx, &yy, &xy, &self})
            std::copy(c->begin() + std::ptrdiff_t(i) + 1, c->begin() + std::ptrdiff_t(count),
                      c->begin() + std::ptrdiff_t(i));
    }
    [[gnu::always_inline]] void set(size_t i, const LobeMoments& l, double minVariance) {
        const glm::dvec2 m = meanOf(l);
        const auto c = covarianceOf(l, minVariance);
        w[i] = l.w;
        mx[i] = m.x, my[i] = m.y;
        xx[i] = c[0], yy[i] = c[1], xy[i] = c[2];
        self[i] = w[i] * w[i] / (4.0 * kPi<double> * std::sqrt(c[0] * c[1] - c[2] * c[2]));
    }
};

// ∫ wx·N(x; bx, Σx) · wy·N(x; by, Σy) dx = wx·wy·N(d; 0, S), d = bx − by, S = Σx + Σy (xx, yy, xy).
// No branch and no call (expNonPositive), so that the loops over it vectorise.
[[gnu::always_inline]] inline double overlapOf(double wxy, double dx, double dy, double sxx, double syy,
                                               double sxy) {
    const double inv = 1.0 / (sxx * syy - sxy * sxy);
    const double e = (dx * dx * syy + dy * dy * sxx - 2.0 * dx * dy * sxy) * inv;
    return wxy * (1.0 / (2.0 * kPi<double>)) * std::sqrt(inv) * expNonPositive(-0.5 * e);
}

// The columns' arrays, read through pointers that alias nothing written (loads the loops can hoist).
struct IseView {
    const double* __restrict w;
    const double* __restrict mx;
    const double* __restrict my;
    const double* __restrict xx;
    const double* __restrict yy;
    const double* __restrict xy;
    const double* __restrict self;
    explicit IseView(const IseColumns& c)
        : w(c.w.data())
        , mx(c.mx.data())
        , my(c.my.data())
        , xx(c.xx.data())
        , yy(c.yy.data())
        , xy(c.xy.data())
        , self(c.self.data()) {}
};

// iseMergeCost of lobes a and b of the columns: the merge m's weight w, and Σm = fa·Σa + fb·Σb +
// fa·fb·ddᵀ (fa = wa/w, fb = wb/w, d = ba − bb: the exact moments), then ⟨a,a⟩ + ⟨b,b⟩ + 2⟨a,b⟩ −
// 2(⟨a,m⟩ + ⟨b,m⟩) + ⟨m,m⟩ with ba − bm = fb·d and bb − bm = −fa·d. The same bits for (b, a) as for
// (a, b): every sum is of two terms that swap, the negations are exact. Rounding below 0 gives 0 (and
// NaN, which finite lobes do not make, too: the scan for the cheapest pair reads no NaN).
[[gnu::always_inline]] inline double iseCostOf(const IseView& c, size_t a, size_t b) {
    const double w = c.w[a] + c.w[b], invW = 1.0 / w, fa = c.w[a] * invW, fb = c.w[b] * invW;
    const double dx = c.mx[a] - c.mx[b], dy = c.my[a] - c.my[b];
    const double mxx = fa * c.xx[a] + fb * c.xx[b] + fa * fb * dx * dx;
    const double myy = fa * c.yy[a] + fb * c.yy[b] + fa * fb * dy * dy;
    const double mxy = fa * c.xy[a] + fb * c.xy[b] + fa * fb * dx * dy;
    const double self = w * w * (1.0 / (4.0 * kPi<double>)) * std::sqrt(1.0 / (mxx * myy - mxy * mxy));
    const double ab =
        overlapOf(c.w[a] * c.w[b], dx, dy, c.xx[a] + c.xx[b], c.yy[a] + c.yy[b], c.xy[a] + c.xy[b]);
    const double am = overlapOf(c.w[a] * w, fb * dx, fb * dy, c.xx[a] + mxx, c.yy[a] + myy, c.xy[a] + mxy);
    const double bm =
        overlapOf(c.w[b] * w, -(fa * dx), -(fa * dy), c.xx[b] + mxx, c.yy[b] + myy, c.xy[b] + mxy);
    const double cost = (c.self[a] + c.self[b]) + 2.0 * ab - 2.0 * (am + bm) + self;
    return cost > 0.0 ? cost : 0.0;
}

// The costs of lobe i with lobes begin..end−1 into out[begin..end), and with the lobes after them up to
// a multiple of four (the columns' padding: finite lobes, costs nobody reads), so that the vectorised
// loop leaves no scalar remainder: out and the columns hold end + 3 entries at least.
BURNISH_AVX2_CLONES void iseCostRow(const IseColumns& columns, size_t i, size_t begin, size_t end,
                                    double* __restrict out) {
    const IseView c(columns);
    const size_t count = (end - begin + 3) / 4 * 4;
    for (size_t j = begin; j < begin + count; ++j)
        out[j] = iseCostOf(c, i, j);
}

} // namespace

double iseMergeCost(const LobeMoments& a, const LobeMoments& b, double minVariance) {
    IseColumns c;
    c.resize(2);
    c.set(0, a, minVariance);
    c.set(1, b, minVariance);
    return iseCostOf(IseView(c), 0, 1);
}

namespace {

// The pairs (i, j), i < j, of n lobes packed row by row: (i, j) at rowStart[i] + j − i − 1, so a
// scan meets them in the order of the full matrix's rows; index[i·n + j] is the position of
// (min(i, j), max(i, j)) (i ≠ j) and pair[p] the pair at position p. Built once per n and thread: a
// merge's bookkeeping reads positions instead of computing them.
struct PairLayout {
    std::vector<size_t> rowStart;
    std::vector<std::uint32_t> index;
    std::vector<std::array<std::uint32_t, 2>> pair;
};

const PairLayout& pairLayout(size_t n) {
    thread_local std::vector<std::unique_ptr<PairLayout>> layouts;
    if (layouts.size() <= n) layouts.resize(n + 1);
    std::unique_ptr<PairLayout>& layout = layouts[n];
    if (!layout) {
        layout = std::make_unique<PairLayout>();
        layout->rowStart.resize(n + 1);
        for (size_t i = 0; i <= n; ++i)
            layout->rowStart[i] = i * n - i * (i + 1) / 2;
        // The diagonal (i, i) points just past the pairs, at a slot that holds +∞ between merges.
        layout->index.assign(n * n, std::uint32_t(layout->rowStart[n]));
        layout->pair.resize(layout->rowStart[n]);
        for (size_t i = 0; i < n; ++i)
            for (size_t j = i + 1; j < n; ++j) {
                const size_t p = layout->rowStart[i] + j - i - 1;
                layout->index[i * n + j] = layout->index[j * n + i] = std::uint32_t(p);
                layout->pair[p] = {std::uint32_t(i), std::uint32_t(j)};
            }
    }
    return *layout;
}

// The index of the first of the smallest of c[0..count) (count a multiple of 4; finite or +∞
// values, no NaN, no −0), with that value in `best`: what a scan that keeps a value only when it is
// strictly below the best so far picks. Two passes without a chain of selects through the whole array
// (a reduction of 12 lobes scans 66 pairs nine times): the smallest value, by lane-wise minima in two
// independent chains (min is exact and order-free), then the first position holding it, four
// compared at a time.
[[gnu::always_inline]] inline size_t firstCheapest(const double* c, size_t count, double& best) {
    simd::Double4 m0, m1;
    std::memcpy(&m0, c, sizeof m0);
    m1 = m0;
    size_t i = 4;
    for (; i + 8 <= count; i += 8) {
        simd::Double4 v0, v1;
        std::memcpy(&v0, c + i, sizeof v0);
        std::memcpy(&v1, c + i + 4, sizeof v1);
        m0 = v0 < m0 ? v0 : m0;
        m1 = v1 < m1 ? v1 : m1;
    }
    if (i < count) {
        simd::Double4 v;
        std::memcpy(&v, c + i, sizeof v);
        m0 = v < m0 ? v : m0;
    }
    m0 = m1 < m0 ? m1 : m0;
    best = std::min(std::min(m0[0], m0[1]), std::min(m0[2], m0[3]));
    const simd::Double4 target = simd::Double4{} + best;
    for (size_t at = 0;; at += 4) {
        simd::Double4 v;
        std::memcpy(&v, c + at, sizeof v);
        const simd::Int64x4 hit = v == target;
        for (int lane = 0; lane < 4; ++lane)
            if (hit[lane]) return at + size_t(lane);
    }
}

// Whether l is LobeMoments::ofNormal's lobe of a finest normal of base variance v: weight 1 and raw
// moments bbᵀ + vI, computed as ofNormal computes them (so the test is exact).
[[gnu::always_inline]] inline bool isFinestLobe(const LobeMoments& l, double v) {
    return l.w == 1.0 && l.mxx == l.bx * l.bx + v && l.myy == l.by * l.by + v && l.mxy == l.bx * l.by;
}

// reduceLobesInPlace's result for four bit-identical finest lobes a (a flat footprint, or the inside of
// an upsampled map; no lobe is light, and the total weight is 4), for any k: the general path's merges
// replayed with its own costs. Equal lobes merge at a cost of exactly 0 (2a has a's mean and covariance
// to the bit), so (0, 1) merges first. Of the pairs left, (0, 2) and (0, 3) cost c = mergeCost(2a, a),
// whose rounding may leave it 0 or not, and (2, 3) costs 0:
//  - c = 0: (0, 2) comes first and lobe 0 becomes 2a + a; then (0, 3), costing c' = mergeCost(2a + a, a),
//    merges if k = 1 or c' is negligible (it can be a rounding's worth above kNegligibleMergeCost with steep
//    normals at a high power), leaving one lobe or two;
//  - c > 0: (2, 3) comes first, giving 2a, and then 2a with 2a costs exactly 0: one lobe, 2a + 2a.
void reduceFourEqual(const LobeMoments& a, int k, double minVariance, LobeMixture& out) {
    std::array<LobeMoments, 4> lobes{a, a, a, a};
    size_t n = 2;
    lobes[0] += a;
    if (mergeCost(lobes[0], a, minVariance) > 0.0) {
        lobes[1] = a;
        lobes[1] += a;
        lobes[0] += lobes[1];
        n = 1;
    } else {
        lobes[0] += a;
        if (k == 1 || mergeCost(lobes[0], a, minVariance) <= kNegligibleMergeCost * 4.0) {
            lobes[0] += a;
            n = 1;
        }
    }
    out = canonicalMixture(lobes.data(), n);
}

// reduceLobesInPlace's result for four finest lobes of one power (isFinestLobe with v the floor
// minVariance, their base variance) and k >= 3, or four bit-identical ones for any k (reduceFourEqual),
// found without a logarithm; false (out untouched) where this cannot promise the general path's choice
// bit for bit. Level 1 of a power-of-two map is millions of these.
// Two finest lobes differ only in their means, so merging lobes i and j costs exactly log(1 + u_ij),
// u_ij = |b_i − b_j|²/(4v) (det(Σ + ddᵀ/4) = det Σ·(1 + dᵀΣ⁻¹d/4) for Σ = vI): the cheapest pair is the
// closest. It declines when
//  - the closest pair's computed cost could round above the next pair's: the gap between them is
//    within 4δ, δ bounding a computed cost's error (log2Positive's 2e-14, and the raw moments'
//    cancellation, |b|²/v ulps of a variance);
//  - the closest pair's merged correlation reaches covariance's clamp, which raises its cost;
//  - a pair is close enough (u < 1e-3) that a merge after the first could cost nothing
//    (kNegligibleMergeCost), or δ is not small. Otherwise none can: a pair of the other two costs at
//    least log(1 + u1), and the merged lobe with another at least f(u1) = ½[3 log(1 + 2u1/3) −
//    2 log(1 + u1)] (the cost of its covariance alone; means apart cost more), f increasing from
//    f(1e-3) = 1.67e-7: both above kNegligibleMergeCost·4 (the total weight) + 2δ for δ < 5e-8.
// Then the closest pair merges into the lower index, as the general path merges it, and the lobes take
// the canonical order.
bool reduceFourFinest(std::array<LobeMoments, 4> lobes, int k, double v, LobeMixture& out) {
    if (std::memcmp(&lobes[0], &lobes[1], sizeof(LobeMoments)) == 0 &&
        std::memcmp(&lobes[0], &lobes[2], sizeof(LobeMoments)) == 0 &&
        std::memcmp(&lobes[0], &lobes[3], sizeof(LobeMoments)) == 0 && isFinestLobe(lobes[0], v)) {
        reduceFourEqual(lobes[0], k, v, out);
        return true;
    }
    if (k < 3) return false;
    double bmax2 = 0.0;
    for (const LobeMoments& l : lobes) {
        if (!isFinestLobe(l, v)) return false;
        bmax2 = std::max(bmax2, l.bx * l.bx + l.by * l.by);
    }
    // Bit-identical lobes (an 8-bit map's equal neighbours, an upsampled map's flat runs: a third of
    // level 1 of a resized map): group[i] is the first lobe lobe i equals.
    std::array<size_t, 4> group{0, 1, 2, 3};
    bool identical = false;
    for (size_t i = 1; i < 4; ++i)
        for (size_t j = 0; j < i; ++j)
            if (std::memcmp(&lobes[j], &lobes[i], sizeof(LobeMoments)) == 0) {
                group[i] = group[j];
                identical = true;
                break;
            }
    constexpr std::array<std::array<unsigned char, 2>, 6> kPairs{
        {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
    const double toU = 0.25 / v;
    double u1 = std::numeric_limits<double>::infinity(), u2 = u1;
    size_t closest = 0;
    for (size_t p = 0; p < kPairs.size(); ++p) {
        if (group[kPairs[p][0]] == group[kPairs[p][1]]) continue; // the same lobe twice
        const LobeMoments &a = lobes[kPairs[p][0]], &b = lobes[kPairs[p][1]];
        const double dx = a.bx - b.bx, dy = a.by - b.by, u = (dx * dx + dy * dy) * toU;
        if (u < u1)
            u2 = u1, u1 = u, closest = p;
        else if (u < u2)
            u2 = u;
    }
    const double delta = 1e-13 * (1.0 + bmax2 / v);
    size_t n = 4;
    if (identical) {
        // Two equal lobes merge at a cost of exactly 0 (2a has a's mean and covariance to the bit, as
        // in reduceFourEqual), every other pair (u >= 1e-3, δ small) well above kNegligibleMergeCost·4:
        // the general path merges equal pairs first, in the pairs' order, each into its lower index,
        // and then, k >= 3 lobes being left, only what costs nothing. A pair of equal lobes is one
        // merge; of three (i1 < i2 < i3) (i1, i2) merges first, and then 2a with a costs
        // c = mergeCost(2a, a), which rounding leaves 0 or not: it merges if negligible.
        if (!(u1 >= 1e-3) || !(delta < 5e-8)) return false;
        std::array<bool, 4> alive{true, true, true, true};
        std::array<int, 4> merged{};
        for (size_t i = 1; i < 4; ++i) {
            const size_t g = group[i];
            if (g == i) continue;
            if (merged[g]++ == 0 || mergeCost(lobes[g], lobes[i], v) <= kNegligibleMergeCost * 4.0) {
                lobes[g] += lobes[i];
                alive[i] = false;
            }
        }
        n = 0;
        for (size_t i = 0; i < 4; ++i)
            if (alive[i]) lobes[n++] = lobes[i];
    } else if (!(u1 >= 1e-3) || !(delta < 5e-8) || !std::isfinite(u2)) {
        return false;
    } else if (k == 3) {
        // The gap log(1 + u2) − log(1 + u1) >= (u2 − u1)/(1 + u2).
        if (!((u2 - u1) / (1.0 + u2) > 4.0 * delta)) return false;
        const size_t i = kPairs[closest][0], j = kPairs[closest][1];
        const double dx = lobes[i].bx - lobes[j].bx, dy = lobes[i].by - lobes[j].by;
        const double xx = v + 0.25 * dx * dx, yy = v + 0.25 * dy * dy, xy = 0.25 * dx * dy;
        if (!(xy * xy < 0.998 * xx * yy)) return false; // the clamp is at 0.999² = 0.998001
        lobes[i] += lobes[j];
        std::copy(lobes.begin() + std::ptrdiff_t(j) + 1, lobes.end(), lobes.begin() + std::ptrdiff_t(j));
        n = 3;
    }
    // Canonical order by a stable insertion sort on each lobe's mean computed once: canonicalLess is a
    // strict weak order, so this is the order std::sort gives these few lobes (its insertion sort, also
    // stable), with 2n divisions instead of 4 per comparison.
    std::array<glm::dvec2, 4> mean;
    for (size_t i = 0; i < n; ++i)
        mean[i] = lobes[i].mean();
    const auto less = [&](size_t a, size_t b) {
        if (mean[a].x != mean[b].x) return mean[a].x < mean[b].x;
        if (mean[a].y != mean[b].y) return mean[a].y < mean[b].y;
        return lobes[a].w > lobes[b].w;
    };
    std::array<size_t, 4> order{0, 1, 2, 3};
    for (size_t i = 1; i < n; ++i)
        for (size_t j = i; j > 0 && less(order[j], order[j - 1]); --j)
            std::swap(order[j], order[j - 1]);
    out = LobeMixture{};
    out.count = int(n);
    for (size_t i = 0; i < n; ++i)
        out.lobes[i] = lobes[order[i]];
    return true;
}

// reduceLobes on the caller's vector (changed), with the pair costs in per-thread buffers: no
// allocation per texel once the buffers have grown. The costs are computed four pairs at a time
// (LobeColumns), each bit for bit the scalar mergeCost. k in 1..kMaxMixtureLobes (reduceLobesWith).
BURNISH_AVX2_CLONES LobeMixture reduceLobesInPlace(std::vector<LobeMoments>& lobes, int k,
                                                   double minVariance) {
    if (LobeMixture fast;
        lobes.size() == 4 && reduceFourFinest({lobes[0], lobes[1], lobes[2], lobes[3]}, k, minVariance, fast))
        return fast;
    std::erase_if(lobes, [](const LobeMoments& l) { return !(l.w > 0.0); });
    double total = 0.0;
    for (const auto& l : lobes)
        total += l.w;
    thread_local LobeColumns columns;
    thread_local std::vector<double> row;
    // The cheapest pair until k remain, and then while a pair costs nothing (equal lobes: a flat
    // footprint keeps one lobe, not k copies), with the pair costs kept in a matrix: a merge
    // recomputes only the merged lobe's row.
    const size_t n = lobes.size();
    if (n > 1) {
        // A merged-away lobe's pairs cost +∞ (a cost is finite or +∞, never NaN): the scan for the
        // first cheapest pair needs no test of which lobes remain.
        constexpr double kGone = std::numeric_limits<double>::infinity();
        thread_local std::vector<double> cost;
        thread_local std::vector<char> alive;
        columns.assign(lobes, minVariance);
        row.resize(columns.w.size());
        const PairLayout& layout = pairLayout(n);
        cost.assign((layout.rowStart[n] + 4) / 4 * 4, kGone); // the pairs and the diagonal's slot
        alive.assign(n, 1);
        // Beside each pair's cost, its merged lobe's log det Σ: the merge that picks the pair takes its
        // w·log det Σ from there instead of computing it again.
        thread_local std::vector<double> rowLogDet, logDet;
        rowLogDet.resize(row.size());
        logDet.resize(cost.size());
        for (size_t i = 0; i + 1 < n; ++i) {
            columns.costsWith(i, i + 1, n - i - 1, false, minVariance, row, rowLogDet);
            std::copy(row.begin() + std::ptrdiff_t(i + 1), row.begin() + std::ptrdiff_t(n),
                      cost.begin() + std::ptrdiff_t(layout.rowStart[i]));
            std::copy(rowLogDet.begin() + std::ptrdiff_t(i + 1), rowLogDet.begin() + std::ptrdiff_t(n),
                      logDet.begin() + std::ptrdiff_t(layout.rowStart[i]));
        }
        for (size_t remaining = n; remaining > 1; --remaining) {
            double best = kGone;
            const size_t first = firstCheapest(cost.data(), cost.size(), best);
            size_t bi = 0, bj = 0;
            if (best < kGone) bi = layout.pair[first][0], bj = layout.pair[first][1];
            if (remaining <= size_t(k) && !(best <= kNegligibleMergeCost * total)) break;
            lobes[bi] += lobes[bj];
            if (best < kGone)
                columns.updateMerged(bi, lobes[bi], logDet[first]);
            else
                columns.update(bi, lobes[bi], minVariance);
            alive[bj] = 0;
            // Without a branch per lobe (whether it is alive was a coin toss the predictor lost).
            const std::uint32_t* gone = &layout.index[bj * n];
            for (size_t o = 0; o < n; ++o)
                cost[gone[o]] = kGone;
            columns.costsWith(bi, 0, n, true, minVariance, row, rowLogDet);
            const std::uint32_t* merged = &layout.index[bi * n];
            for (size_t o = 0; o < n; ++o) {
                cost[merged[o]] = alive[o] ? row[o] : kGone;
                logDet[merged[o]] = rowLogDet[o];
            }
            cost[merged[bi]] = kGone; // the diagonal's slot took row[bi], which is garbage
        }
        size_t out = 0;
        for (size_t i = 0; i < n; ++i)
            if (alive[i]) lobes[out++] = lobes[i];
        lobes.resize(out);
    }
    return canonicalMixture(lobes.data(), lobes.size());
}

// reduceLobes by MergeCriterion::SquaredError: the cheapest pair (iseCostOf, iseMergeCost's bits)
// merges until k remain and then while a pair costs a negligible part of its own lobes'
// overlaps (equal lobes), with the costs kept in a matrix of which a merge recomputes the merged lobe's row.
// k in 2..kMaxMixtureLobes (reduceLobesWith).
BURNISH_AVX2_CLONES LobeMixture reduceLobesBySquaredError(std::vector<LobeMoments>& lobes, int k,
                                                          double minVariance) {
    std::erase_if(lobes, [](const LobeMoments& l) { return !(l.w > 0.0); });
    size_t m = lobes.size(); // the lobes left, in order: a merged-away lobe leaves its place
    if (m > 1) {
        constexpr double kGone = std::numeric_limits<double>::infinity();
        // The packed pair costs of m lobes (pairLayout(m)), and +∞ up to a multiple of four.
        const auto packedSize = [](size_t count) { return (pairLayout(count).rowStart[count] + 4) / 4 * 4; };
        thread_local IseColumns columns;
        thread_local std::vector<double> cost, next, row;
        // Three columns of padding after the lobes (iseCostRow), copies of lobe 0; after a merge they
        // and the column the erase leaves behind keep finite lobes.
        columns.resize(m + 3);
        for (size_t i = 0; i < m + 3; ++i)
            columns.set(i, lobes[i < m ? i : 0], minVariance);
        cost.assign(packedSize(m), kGone);
        row.resize(m + 3);
        const PairLayout* layout = &pairLayout(m);
        for (size_t i = 0; i + 1 < m; ++i) {
            iseCostRow(columns, i, i + 1, m, row.data());
            std::copy(row.begin() + std::ptrdiff_t(i + 1), row.begin() + std::ptrdiff_t(m),
                      cost.begin() + std::ptrdiff_t(layout->rowStart[i]));
        }
        while (m > 1) {
            double best = kGone;
            const size_t first = firstCheapest(cost.data(), cost.size(), best);
            // Every cost +∞ (overflow) cannot happen with a pyramid's finite lobes: then the first two
            // merge, so that at most k remain all the same.
            const size_t bi = best < kGone ? layout->pair[first][0] : 0;
            const size_t bj = best < kGone ? layout->pair[first][1] : 1;
            if (m <= size_t(k) && !(best <= kNegligibleMergeCost * (columns.self[bi] + columns.self[bj])))
                break;
            lobes[bi] += lobes[bj];
            lobes.erase(lobes.begin() + std::ptrdiff_t(bj));
            columns.erase(bj, m);
            // The costs of the m − 1 lobes left: the old ones of every pair without bi or bj (bi < bj
            // keeps its place, the lobes after bj move down one), then the merged lobe's row afresh.
            const PairLayout* smaller = &pairLayout(m - 1);
            next.assign(packedSize(m - 1), kGone);
            for (size_t i = 0; i + 1 < m - 1; ++i) {
                const size_t oi = i + (i >= bj);
                for (size_t j = i + 1; j < m - 1; ++j)
                    next[smaller->rowStart[i] + j - i - 1] = cost[layout->index[oi * m + j + (j >= bj)]];
            }
            --m;
            layout = smaller;
            columns.set(bi, lobes[bi], minVariance);
            iseCostRow(columns, bi, 0, m, row.data());
            const std::uint32_t* merged = &layout->index[bi * m];
            for (size_t o = 0; o < m; ++o)
                if (o != bi) next[merged[o]] = row[o];
            std::swap(cost, next);
        }
    }
    return canonicalMixture(lobes.data(), lobes.size());
}

// reduceLobes on the caller's vector, k clamped to 1..kMaxMixtureLobes. k = 1 is the exact sum under
// either criterion.
LobeMixture reduceLobesWith(std::vector<LobeMoments>& lobes, int k, double minVariance,
                            MergeCriterion criterion) {
    k = std::clamp(k, 1, kMaxMixtureLobes);
    if (criterion == MergeCriterion::SquaredError && k > 1)
        return reduceLobesBySquaredError(lobes, k, minVariance);
    return reduceLobesInPlace(lobes, k, minVariance);
}

} // namespace

LobeMixture reduceLobes(std::vector<LobeMoments> lobes, int k, double minVariance, MergeCriterion criterion) {
    return reduceLobesWith(lobes, k, minVariance, criterion);
}

MixturePyramid MixturePyramid::build(const NormalPyramid& pyramid, double s, int k, int lastLevel,
                                     const std::vector<double>* texelPowers,
                                     const std::function<void(MixturePyramid&)>& refine) {
    MixturePyramid out;
    out.m_k = std::clamp(k, 1, kMaxMixtureLobes);
    // The narrowest lobe any finest texel brings: its covariance floor.
    double maxPower = s;
    if (texelPowers) {
        maxPower = 0.0;
        for (double p : *texelPowers)
            maxPower = std::max(maxPower, p);
    }
    out.m_minVariance = mixtureBaseVariance(maxPower, out.m_k);
    const int last =
        lastLevel >= 0 ? std::min(lastLevel, pyramid.levelCount() - 1) : pyramid.levelCount() - 1;
    const NormalMap& finest = pyramid.finest();
    const size_t K = size_t(out.m_k);
    const double baseVariance = mixtureBaseVariance(s, out.m_k); // every finest lobe's, without texelPowers
    for (int level = 1; level <= last; ++level) {
        const PyramidLevel& l = pyramid.level(level);
        Level built;
        built.width = l.width;
        built.height = l.height;
        const size_t texels = size_t(l.width) * size_t(l.height);
        built.lobes.reset(static_cast<LobeMoments*>(::operator new(sizeof(LobeMoments) * texels * K)));
        built.counts.reset(static_cast<unsigned char*>(::operator new(texels)));
        const Level* child = level > 1 ? &out.m_levels.back() : nullptr;
        const MergeCriterion criterion = mixtureCriterion(level);
        tbb::parallel_for(0, l.height, [&](int y) {
            std::vector<LobeMoments> lobes;
            for (int x = 0; x < l.width; ++x) {
                lobes.clear();
                for (int j = l.yChild[size_t(y)]; j < l.yChild[size_t(y) + 1]; ++j)
                    for (int i = l.xChild[size_t(x)]; i < l.xChild[size_t(x) + 1]; ++i) {
                        if (!child) {
                            const double v =
                                texelPowers
                                    ? mixtureBaseVariance(
                                          (*texelPowers)[size_t(j) * size_t(finest.width) + size_t(i)],
                                          out.m_k)
                                    : baseVariance;
                            lobes.push_back(LobeMoments::ofNormal(finest.at(i, j), v));
                            continue;
                        }
                        const size_t t = size_t(j) * size_t(child->width) + size_t(i);
                        lobes.insert(lobes.end(), &child->lobes[t * K],
                                     &child->lobes[t * K] + child->counts[t]);
                    }
                built.set(size_t(y) * size_t(l.width) + size_t(x), out.m_k,
                          reduceLobesWith(lobes, out.m_k, out.m_minVariance, criterion));
            }
        });
        out.m_levels.push_back(std::move(built));
    }
    if (refine) refine(out);
    // Top-down, each texel's lobes take the slots of the lobes they belong to most in the level above
    // as a GPU samples it at the texel's centre: its parents' lobes bilinearly filtered, slot by slot.
    // That reference varies smoothly across texels, whichever parent they fall under, so
    // neighbouring texels, and the levels between, give one cluster one slot: bilinear and trilinear
    // filtering then merge like with like. The top level keeps the canonical order.
    const BorderMode border = pyramid.options().border;
    for (int level = last - 1; level >= 1; --level) {
        const Level& parents = out.m_levels[size_t(level)];
        Level& children = out.m_levels[size_t(level - 1)];
        tbb::parallel_for(0, children.height, [&](int y) {
            std::array<int, 2> py{};
            std::array<double, 2> wy{};
            bilinearTaps(y, children.height, parents.height, border, py, wy);
            for (int x = 0; x < children.width; ++x) {
                std::array<int, 2> px{};
                std::array<double, 2> wx{};
                bilinearTaps(x, children.width, parents.width, border, px, wx);
                std::array<LobeMoments, kMaxMixtureLobes> reference{};
                for (size_t j = 0; j < 2; ++j)
                    for (size_t i = 0; i < 2; ++i) {
                        const double weight = wy[j] * wx[i];
                        if (weight == 0.0) continue;
                        const size_t p = size_t(py[j]) * size_t(parents.width) + size_t(px[i]);
                        for (size_t slot = 0; slot < parents.counts[p]; ++slot)
                            reference[slot] += parents.lobes[p * K + slot].scaled(weight);
                    }
                const LobeScorer scorer(reference.data(), out.m_k, out.m_minVariance);
                const size_t t = size_t(y) * size_t(children.width) + size_t(x);
                scorer.reorder(&children.lobes[t * K], children.counts[t], out.m_k);
            }
        });
    }
    // Level 0's lobe indices, from the level-1 parents: a finest texel has one lobe, and the
    // filtered reference for each of them would cost more than the rest of the build.
    out.m_finestWidth = finest.width;
    if (last >= 1 && out.m_k > 1) {
        const PyramidLevel& l1 = pyramid.level(1);
        const Level& level1 = out.m_levels.front();
        out.m_finestLobe.assign(finest.texelCount(), 0);
        tbb::parallel_for(0, l1.height, [&](int y) {
            for (int x = 0; x < l1.width; ++x) {
                const size_t t = size_t(y) * size_t(l1.width) + size_t(x);
                const LobeScorer parent(&level1.lobes[t * K], level1.counts[t], out.m_minVariance);
                for (int j = l1.yChild[size_t(y)]; j < l1.yChild[size_t(y) + 1]; ++j)
                    for (int i = l1.xChild[size_t(x)]; i < l1.xChild[size_t(x) + 1]; ++i)
                        // The mean of LobeMoments::ofNormal's lobe (w = 1) is its slope.
                        out.m_finestLobe[size_t(j) * size_t(finest.width) + size_t(i)] =
                            (unsigned char)parent.assign(finestSlope(finest.at(i, j)));
            }
        });
    }
    return out;
}

int MixturePyramid::finestLobe(int x, int y) const {
    if (m_finestLobe.empty()) return 0;
    return m_finestLobe[size_t(y) * size_t(m_finestWidth) + size_t(x)];
}

std::array<LobeMoments, kMaxMixtureLobes> MixturePyramid::storedTexel(const NormalMap& finest, int k, int x,
                                                                      int y, double finestPower) const {
    std::array<LobeMoments, kMaxMixtureLobes> out{}; // empty slots store zero moments
    if (k == 0) {
        out[size_t(finestLobe(x, y))] = // weight 1
            LobeMoments::ofNormal(finest.at(x, y), mixtureBaseVariance(finestPower, m_k));
        return out;
    }
    // From the level's own storage (LobeMixture::totalWeight's sum).
    const Level& level = m_levels[size_t(k - 1)];
    const size_t t = size_t(y) * size_t(level.width) + size_t(x);
    const int count = level.counts[t];
    const LobeMoments* lobes = &level.lobes[t * size_t(m_k)];
    double total = 0.0;
    for (int i = 0; i < count; ++i)
        total += lobes[i].w;
    const double inv = total > 0.0 ? 1.0 / total : 0.0;
    for (int i = 0; i < count; ++i)
        out[size_t(i)] = lobes[i].scaled(inv);
    return out;
}

void MixturePyramid::releaseLevel(int k) {
    if (k < 1 || k >= levelCount()) return;
    m_levels[size_t(k - 1)].lobes.reset();
    m_levels[size_t(k - 1)].counts.reset();
}

LobeMixture MixturePyramid::at(int level, int x, int y) const {
    const Level& l = m_levels[size_t(level - 1)];
    return l.get(size_t(y) * size_t(l.width) + size_t(x), m_k);
}

void MixturePyramid::replace(int level, int x, int y, const LobeMixture& mixture) {
    Level& l = m_levels[size_t(level - 1)];
    l.set(size_t(y) * size_t(l.width) + size_t(x), m_k, mixture);
}

LobeMixture MixturePyramid::Level::get(size_t texel, int k) const {
    LobeMixture m;
    m.count = counts[texel];
    std::copy_n(&lobes[texel * size_t(k)], k, m.lobes.begin());
    return m;
}

void MixturePyramid::Level::set(size_t texel, int k, const LobeMixture& m) {
    counts[texel] = (unsigned char)m.count; // at most k
    std::copy_n(m.lobes.begin(), k, &lobes[texel * size_t(k)]);
}

double mixtureNdf(const LobeMixture& mixture, const glm::dvec3& h, double minVariance) {
    const double total = mixture.totalWeight();
    if (!(total > 0.0)) return 0.0;
    double sum = 0.0;
    for (int i = 0; i < mixture.count; ++i) {
        const LobeMoments& l = mixture.lobes[size_t(i)];
        sum += l.w / total * slopeGaussianNdf(h, l.mean(), l.covariance(minVariance));
    }
    return sum;
}

DecodedMixture decodeMixture(const LobeMixture& mixture, double minVariance) {
    DecodedMixture out;
    const double total = mixture.totalWeight();
    if (!(total > 0.0)) return out;
    for (int i = 0; i < mixture.count; ++i) {
        const LobeMoments& l = mixture.lobes[size_t(i)];
        if (!(l.w > 0.0)) continue; // an empty slot
        DecodedMixture::Lobe& d = out.lobes[size_t(out.count++)];
        d.share = l.w / total;
        d.mean = l.mean();
        d.cov = l.covariance(minVariance);
        d.normal = normalOfSlope(d.mean);
    }
    return out;
}

double mixtureValue(const DecodedMixture& mixture, const glm::dvec3& lightDir, const glm::dvec3& h) {
    double sum = 0.0;
    for (int i = 0; i < mixture.count; ++i) {
        const DecodedMixture::Lobe& l = mixture.lobes[size_t(i)];
        sum += l.share * slopeGaussianNdf(h, l.mean, l.cov) * std::max(0.0, glm::dot(l.normal, lightDir));
    }
    return sum;
}

double mixtureValue(const LobeMixture& mixture, const glm::dvec3& lightDir, const glm::dvec3& h,
                    double minVariance) {
    return mixtureValue(decodeMixture(mixture, minVariance), lightDir, h);
}

std::array<double, 4> mixtureGgxTexel(const LobeMoments& lobe, double baseVariance) {
    return {lobe.w, lobe.bx, lobe.by, lobe.mxx + lobe.myy - 2.0 * baseVariance * lobe.w};
}

MixtureGgxLobe mixtureGgxLobe(const std::array<double, 4>& t, double total, double alpha0,
                              double spreadScale) {
    MixtureGgxLobe out;
    const double a0 = std::isfinite(alpha0) ? std::clamp(alpha0, 0.0, 1.0) : 0.0;
    out.alpha = a0;
    const double w = t[0];
    if (!(w > 0.0) || !(total > 0.0) || !std::isfinite(total)) return out;
    const double r = 1.0 / w;
    const glm::dvec2 b(t[1] * r, t[2] * r);
    const double spread = t[3] * r - glm::dot(b, b);
    const double c = std::isfinite(spreadScale) ? std::max(spreadScale, 0.0) : 0.0;
    const double a2 = a0 * a0 + c * (spread > 0.0 && std::isfinite(spread) ? spread : 0.0);
    out.alpha = std::min(std::sqrt(a2), 1.0);
    out.share = std::min(w / total, 1.0);
    const glm::dvec3 n(b, 1.0);
    const double len = glm::length(n);
    out.normal = std::isfinite(len) ? n / len : glm::dvec3(0, 0, 1);
    return out;
}

MethodStorage mixtureGgxStorage(int k) {
    static const std::string_view layouts[kMaxMixtureLobes] = {
        "normal BC5 + 1 lobe (w, w.b, w.S) RGBA16F", "normal BC5 + 2 lobes (w, w.b, w.S) RGBA16F",
        "normal BC5 + 3 lobes (w, w.b, w.S) RGBA16F", "normal BC5 + 4 lobes (w, w.b, w.S) RGBA16F"};
    k = std::clamp(k, 1, kMaxMixtureLobes);
    return {k + 1, 8.0 * k + 1.0, layouts[k - 1]};
}

double mixtureGgxValue(const std::array<MixtureGgxLobe, kMaxMixtureLobes>& lobes, int count,
                       const glm::dvec3& l, const glm::dvec3& v, const glm::dvec3& h) {
    double sum = 0.0;
    for (int i = 0; i < std::clamp(count, 0, kMaxMixtureLobes); ++i) {
        const MixtureGgxLobe& lobe = lobes[size_t(i)];
        sum += lobe.share * ggxSpecularTerm(glm::dot(lobe.normal, h), glm::dot(lobe.normal, l),
                                            glm::dot(lobe.normal, v), lobe.alpha);
    }
    return sum;
}

} // namespace burnish
