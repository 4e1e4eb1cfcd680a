#include <burnish/core/prefilter/normal_pyramid.h>

#include <burnish/core/util/simd.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace burnish {

namespace {

// Weighted raw sums in double: W, ΣwN (3), Σw NNᵀ (6: xx yy zz xy xz yz), Σw b (2), Σw bbᵀ (3).
// Central moments are recovered as Σw NNᵀ/W − μμᵀ in double, whose rounding (~1e-16 of |μ|² = 1)
// is far below any variance that matters (the smallest, 1/kMaxPower, is 1e-9), while the inputs
// are the float-stored central moments of the level below.
// Only the sums of the moments in the set S (MomentSet flags) are taken; the others stay 0 and
// toMoments leaves them at NormalMoments' defaults. Each sum's arithmetic is the same for every S.
template <unsigned S = kMomentsAll> struct RawMoments {
    static constexpr bool kCov = (S & kMomentsCov) != 0;
    static constexpr bool kSlope = (S & kMomentsSlope) != 0;
    double v[15] = {};

    void add(const NormalMoments& m, double w) {
        const double mx = m.mean.x, my = m.mean.y, mz = m.mean.z;
        v[0] += w;
        v[1] += w * mx;
        v[2] += w * my;
        v[3] += w * mz;
        if constexpr (kCov) {
            v[4] += w * (double(m.cov[0]) + mx * mx);
            v[5] += w * (double(m.cov[1]) + my * my);
            v[6] += w * (double(m.cov[2]) + mz * mz);
            v[7] += w * (double(m.cov[3]) + mx * my);
            v[8] += w * (double(m.cov[4]) + mx * mz);
            v[9] += w * (double(m.cov[5]) + my * mz);
        }
        if constexpr (kSlope) {
            const double bx = m.slope.x, by = m.slope.y;
            v[10] += w * bx;
            v[11] += w * by;
            v[12] += w * (double(m.slopeCov[0]) + bx * bx);
            v[13] += w * (double(m.slopeCov[1]) + by * by);
            v[14] += w * (double(m.slopeCov[2]) + bx * by);
        }
    }

    void addNormal(const glm::vec3& n, double w) {
        const double x = n.x, y = n.y, z = n.z;
        v[0] += w;
        v[1] += w * x;
        v[2] += w * y;
        v[3] += w * z;
        if constexpr (kCov) {
            v[4] += w * x * x;
            v[5] += w * y * y;
            v[6] += w * z * z;
            v[7] += w * x * y;
            v[8] += w * x * z;
            v[9] += w * y * z;
        }
        if constexpr (kSlope) {
            const double zs = std::max(z, double(kMinSlopeZ));
            const double bx = x / zs, by = y / zs;
            v[10] += w * bx;
            v[11] += w * by;
            v[12] += w * bx * bx;
            v[13] += w * by * by;
            v[14] += w * bx * by;
        }
    }

    NormalMoments toMoments() const {
        NormalMoments out;
        if (!(v[0] > 0.0)) return out;
        const double inv = 1.0 / v[0];
        const double mx = v[1] * inv, my = v[2] * inv, mz = v[3] * inv;
        out.mean = glm::vec3(float(mx), float(my), float(mz));
        // Variances are clamped at 0 against rounding; covariances are left signed.
        if constexpr (kCov)
            out.cov = {float(std::max(0.0, v[4] * inv - mx * mx)),
                       float(std::max(0.0, v[5] * inv - my * my)),
                       float(std::max(0.0, v[6] * inv - mz * mz)),
                       float(v[7] * inv - mx * my),
                       float(v[8] * inv - mx * mz),
                       float(v[9] * inv - my * mz)};
        if constexpr (kSlope) {
            const double bx = v[10] * inv, by = v[11] * inv;
            out.slope = glm::vec2(float(bx), float(by));
            out.slopeCov = {float(std::max(0.0, v[12] * inv - bx * bx)),
                            float(std::max(0.0, v[13] * inv - by * by)), float(v[14] * inv - bx * by)};
        }
        return out;
    }
};

// Calls fn with std::integral_constant<unsigned, S> for the run-time set: one instantiation each.
template <class Fn> decltype(auto) withMomentSet(unsigned set, Fn&& fn) {
    switch (set & kMomentsAll) {
    case kMomentsMean:
        return fn(std::integral_constant<unsigned, kMomentsMean>{});
    case kMomentsCov:
        return fn(std::integral_constant<unsigned, kMomentsCov>{});
    case kMomentsSlope:
        return fn(std::integral_constant<unsigned, kMomentsSlope>{});
    default:
        return fn(std::integral_constant<unsigned, kMomentsAll>{});
    }
}

// A texel's packed box moments (PyramidLevel::box): the mean, then the set's other moments.
template <unsigned S> void packMoments(const NormalMoments& m, float* out) {
    out[0] = m.mean.x;
    out[1] = m.mean.y;
    out[2] = m.mean.z;
    int o = 3;
    if constexpr ((S & kMomentsCov) != 0) {
        for (int j = 0; j < 6; ++j)
            out[o + j] = m.cov[size_t(j)];
        o += 6;
    }
    if constexpr ((S & kMomentsSlope) != 0) {
        out[o] = m.slope.x;
        out[o + 1] = m.slope.y;
        for (int j = 0; j < 3; ++j)
            out[o + 2 + j] = m.slopeCov[size_t(j)];
    }
}

NormalMoments unpackMoments(const float* in, unsigned set) {
    NormalMoments m;
    m.mean = glm::vec3(in[0], in[1], in[2]);
    int o = 3;
    if (set & kMomentsCov) {
        for (int j = 0; j < 6; ++j)
            m.cov[size_t(j)] = in[o + j];
        o += 6;
    }
    if (set & kMomentsSlope) {
        m.slope = glm::vec2(in[o], in[o + 1]);
        for (int j = 0; j < 3; ++j)
            m.slopeCov[size_t(j)] = in[o + 2 + j];
    }
    return m;
}

// Finest-level start of each child interval: parent x covers children
// [⌊x·wc/wp⌋, ⌊(x+1)·wc/wp⌋) of the level below.
std::vector<int> childStarts(int childSize, int parentSize) {
    std::vector<int> starts(static_cast<size_t>(parentSize) + 1);
    for (int x = 0; x <= parentSize; ++x)
        starts[size_t(x)] = static_cast<int>((static_cast<long long>(x) * childSize) / parentSize);
    return starts;
}

// The row filter: kernel-weighted moments of every texel of a row, from 2·radius + 1 rows of box
// moments. Sums are taken about the centre texel's own mean normal and slope (shifted, "central"
// sums: d = n_i − n_c), so the float sums hold the spread between neighbours, not 1 + spread:
// a variance of 1e-9 between normals of length 1 keeps float's relative precision instead of
// drowning in 1 − 1e-9. cov = Σw(C_i + d dᵀ)/W − d̄ d̄ᵀ then subtracts terms of the variance's
// own size. Every texel's arithmetic is the same whatever the blocking or thread count.
constexpr int kMaxTapRadius = 2; // the Gaussian's 5 taps

// One row of box moments as structure-of-arrays floats, padded by the tap radius on both sides
// (border-mapped) and by a SIMD width at the end, so the filter loads 4 texels at a time. Only
// the channels of the moment set are filled.
struct SoaRow {
    // 0–2 mean, 3–4 slope; levels above the finest also 5 weight (footprint count), 6–11 cov
    // (xx yy zz xy xz yz), 12–14 slope cov (xx yy xy).
    static constexpr int kChannels = 15;
    std::vector<float> c[kChannels];
    int width = 0;
    int radius = 0;
    unsigned set = kMomentsAll;
    bool aboveFinest = false;

    void resize(int w, int r, bool above, unsigned moments) {
        width = w;
        radius = r;
        set = moments;
        aboveFinest = above;
        // 4 lanes past the last texel: the last SIMD group reads up to 3 texels beyond it.
        const size_t padded = size_t(w) + 2 * size_t(r) + 4;
        for (int i = 0; i < kChannels; ++i)
            if (used(i)) c[i].assign(padded, 0.0f);
        // Lanes past the row see weight 1 and zero moments: finite, and discarded.
        if (above) std::fill(c[5].begin(), c[5].end(), 1.0f);
    }

    bool used(int channel) const {
        if (channel < 3) return true;
        if (channel < 5) return (set & kMomentsSlope) != 0;
        if (!aboveFinest) return false;
        if (channel == 5) return true;
        if (channel < 12) return (set & kMomentsCov) != 0;
        return (set & kMomentsSlope) != 0;
    }

    // Padded position p holds texel p − radius, border-mapped: the identity inside the row, so only
    // the 2·radius positions at the ends pay for borderIndex's division.
    int sourceIndex(int p, BorderMode border) const {
        const int x = p - radius;
        return x >= 0 && x < width ? x : borderIndex(x, width, border);
    }

    void fillFinest(const NormalMap& map, int y, BorderMode border) {
        const bool slopes = (set & kMomentsSlope) != 0;
        for (int p = 0; p < width + 2 * radius; ++p) {
            const glm::vec3& n = map.at(sourceIndex(p, border), y);
            c[0][size_t(p)] = n.x;
            c[1][size_t(p)] = n.y;
            c[2][size_t(p)] = n.z;
            if (slopes) {
                // The slope in double, rounded once: b = n.xy / max(n.z, kMinSlopeZ) as RawMoments has it.
                const double zs = std::max(double(n.z), double(kMinSlopeZ));
                c[3][size_t(p)] = float(double(n.x) / zs);
                c[4][size_t(p)] = float(double(n.y) / zs);
            }
        }
    }

    void fillLevel(const NormalPyramid& pyramid, int k, int y, BorderMode border) {
        const PyramidLevel& l = pyramid.level(k);
        const bool slopes = (set & kMomentsSlope) != 0, covs = (set & kMomentsCov) != 0;
        const int stride = momentStride(set);
        for (int p = 0; p < width + 2 * radius; ++p) {
            const int x = sourceIndex(p, border);
            const float* m = &l.box[(size_t(y) * size_t(width) + size_t(x)) * size_t(stride)];
            const size_t i = size_t(p);
            c[0][i] = m[0];
            c[1][i] = m[1];
            c[2][i] = m[2];
            c[5][i] = float(pyramid.footprintCount(k, x, y));
            int o = 3;
            if (covs) {
                for (int j = 0; j < 6; ++j)
                    c[6 + j][i] = m[o + j];
                o += 6;
            }
            if (slopes) {
                c[3][i] = m[o];
                c[4][i] = m[o + 1];
                for (int j = 0; j < 3; ++j)
                    c[12 + j][i] = m[o + 2 + j];
            }
        }
    }
};

using namespace simd;

// AboveFinest: the rows hold box moments with their own spread and footprint counts (levels
// k >= 1), not single normals. S: the moment set; the mean is always filtered.
template <bool AboveFinest, unsigned S>
void filterRow(const SoaRow* const* rows, const KernelTaps& taps, int width, NormalMoments* out) {
    constexpr bool kCov = (S & kMomentsCov) != 0;
    constexpr bool kSlope = (S & kMomentsSlope) != 0;
    const int r = taps.radius;
    const int n = 2 * r + 1;
    float w[2 * kMaxTapRadius + 1][2 * kMaxTapRadius + 1];
    float wSum = 0.0f;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            w[j][i] = float(taps.w[j] * taps.w[i]);
            wSum += w[j][i];
        }
    const SoaRow& centre = *rows[r];
    for (int x0 = 0; x0 < width; x0 += 4) {
        const size_t o = size_t(x0) + size_t(r); // padded index of texel x0
        const Float4 rx = load4(&centre.c[0][o]), ry = load4(&centre.c[1][o]), rz = load4(&centre.c[2][o]);
        // Normals: W, S1 = Σw d, S2 = Σw (C + d dᵀ) with d = mean − r.
        Float4 W = AboveFinest ? Float4{} : splat4(wSum);
        Float4 s1x{}, s1y{}, s1z{}, sxx{}, syy{}, szz{}, sxy{}, sxz{}, syz{};
        for (int j = 0; j < n; ++j) {
            const SoaRow& row = *rows[j];
            for (int i = 0; i < n; ++i) {
                const size_t p = size_t(x0) + size_t(i);
                Float4 wc = splat4(w[j][i]);
                if constexpr (AboveFinest) {
                    wc *= load4(&row.c[5][p]);
                    W += wc;
                    if constexpr (kCov) {
                        sxx += wc * load4(&row.c[6][p]);
                        syy += wc * load4(&row.c[7][p]);
                        szz += wc * load4(&row.c[8][p]);
                        sxy += wc * load4(&row.c[9][p]);
                        sxz += wc * load4(&row.c[10][p]);
                        syz += wc * load4(&row.c[11][p]);
                    }
                }
                const Float4 dx = load4(&row.c[0][p]) - rx, dy = load4(&row.c[1][p]) - ry,
                             dz = load4(&row.c[2][p]) - rz;
                const Float4 wdx = wc * dx, wdy = wc * dy, wdz = wc * dz;
                s1x += wdx;
                s1y += wdy;
                s1z += wdz;
                if constexpr (kCov) {
                    sxx += wdx * dx;
                    syy += wdy * dy;
                    szz += wdz * dz;
                    sxy += wdx * dy;
                    sxz += wdx * dz;
                    syz += wdy * dz;
                }
            }
        }
        // W > 0: every weight and footprint count is positive.
        const Float4 inv = 1.0f / W;
        const Float4 mx = s1x * inv, my = s1y * inv, mz = s1z * inv;
        const Float4 mean[3] = {rx + mx, ry + my, rz + mz};
        // Variances are clamped at 0 against rounding; covariances are left signed.
        Float4 cov[6] = {};
        if constexpr (kCov) {
            cov[0] = max04(sxx * inv - mx * mx);
            cov[1] = max04(syy * inv - my * my);
            cov[2] = max04(szz * inv - mz * mz);
            cov[3] = sxy * inv - mx * my;
            cov[4] = sxz * inv - mx * mz;
            cov[5] = syz * inv - my * mz;
        }
        Float4 slope[2] = {}, slopeCov[3] = {};
        if constexpr (kSlope) {
            // Slopes: T1 = Σw e, T2 = Σw (C_b + e eᵀ) with e = slope − q.
            const Float4 qx = load4(&centre.c[3][o]), qy = load4(&centre.c[4][o]);
            Float4 t1x{}, t1y{}, txx{}, tyy{}, txy{};
            for (int j = 0; j < n; ++j) {
                const SoaRow& row = *rows[j];
                for (int i = 0; i < n; ++i) {
                    const size_t p = size_t(x0) + size_t(i);
                    Float4 wc = splat4(w[j][i]);
                    if constexpr (AboveFinest) {
                        wc *= load4(&row.c[5][p]);
                        txx += wc * load4(&row.c[12][p]);
                        tyy += wc * load4(&row.c[13][p]);
                        txy += wc * load4(&row.c[14][p]);
                    }
                    const Float4 ex = load4(&row.c[3][p]) - qx, ey = load4(&row.c[4][p]) - qy;
                    const Float4 wex = wc * ex, wey = wc * ey;
                    t1x += wex;
                    t1y += wey;
                    txx += wex * ex;
                    tyy += wey * ey;
                    txy += wex * ey;
                }
            }
            const Float4 bx = t1x * inv, by = t1y * inv;
            slope[0] = qx + bx;
            slope[1] = qy + by;
            slopeCov[0] = max04(txx * inv - bx * bx);
            slopeCov[1] = max04(tyy * inv - by * by);
            slopeCov[2] = txy * inv - bx * by;
        }
        const int lanes = std::min(4, width - x0);
        for (int lane = 0; lane < lanes; ++lane) {
            NormalMoments& m = out[x0 + lane];
            m.mean = glm::vec3(mean[0][lane], mean[1][lane], mean[2][lane]);
            m.slope = glm::vec2(slope[0][lane], slope[1][lane]);
            for (int c = 0; c < 6; ++c)
                m.cov[size_t(c)] = cov[c][lane];
            for (int c = 0; c < 3; ++c)
                m.slopeCov[size_t(c)] = slopeCov[c][lane];
        }
    }
}

} // namespace

std::string_view kernelName(FilterKernel kernel) {
    switch (kernel) {
    case FilterKernel::Box:
        return "box";
    case FilterKernel::Tent:
        return "tent";
    case FilterKernel::Gaussian:
        return "gaussian";
    }
    return "box";
}

int borderIndex(int i, int size, BorderMode border) {
    if (border == BorderMode::Clamp) return std::clamp(i, 0, size - 1);
    const int m = i % size;
    return m < 0 ? m + size : m;
}

KernelTaps kernelTaps(FilterKernel kernel) {
    switch (kernel) {
    case FilterKernel::Box:
        return {0, {1, 0, 0, 0, 0}};
    case FilterKernel::Tent:
        return {1, {0.25, 0.5, 0.25, 0, 0}};
    case FilterKernel::Gaussian: {
        // σ = 1 texel: exp(−i²/2) for i = −2..2, normalized.
        const double a = std::exp(-2.0), b = std::exp(-0.5);
        const double s = 1.0 + 2.0 * a + 2.0 * b;
        return {2, {a / s, b / s, 1.0 / s, b / s, a / s}};
    }
    }
    return {0, {1, 0, 0, 0, 0}};
}

NormalMoments combineMoments(const NormalMoments* moments, const double* weights, size_t count) {
    RawMoments<> raw;
    for (size_t i = 0; i < count; ++i)
        raw.add(moments[i], weights[i]);
    return raw.toMoments();
}

NormalPyramid NormalPyramid::build(std::shared_ptr<const NormalMap> map, const PyramidOptions& options) {
    NormalPyramid pyramid;
    pyramid.m_map = std::move(map);
    pyramid.m_options = options;
    const NormalMap& finest = *pyramid.m_map;

    PyramidLevel level0;
    level0.width = finest.width;
    level0.height = finest.height;
    level0.xStart = childStarts(finest.width, finest.width);
    level0.yStart = childStarts(finest.height, finest.height);
    level0.xChild = level0.xStart;
    level0.yChild = level0.yStart;
    pyramid.m_levels.push_back(std::move(level0));

    while (pyramid.m_levels.back().width > 1 || pyramid.m_levels.back().height > 1) {
        const int k = pyramid.levelCount() - 1;
        const PyramidLevel& child = pyramid.m_levels.back();
        PyramidLevel parent;
        parent.width = std::max(1, child.width / 2);
        parent.height = std::max(1, child.height / 2);
        const auto cx = childStarts(child.width, parent.width);
        const auto cy = childStarts(child.height, parent.height);
        parent.xStart.resize(size_t(parent.width) + 1);
        parent.yStart.resize(size_t(parent.height) + 1);
        for (int x = 0; x <= parent.width; ++x)
            parent.xStart[size_t(x)] = child.xStart[size_t(cx[size_t(x)])];
        for (int y = 0; y <= parent.height; ++y)
            parent.yStart[size_t(y)] = child.yStart[size_t(cy[size_t(y)])];
        parent.xChild = cx;
        parent.yChild = cy;
        if (!options.boxMoments) {
            pyramid.m_levels.push_back(std::move(parent));
            continue;
        }
        const unsigned set = options.moments & kMomentsAll;
        const size_t stride = size_t(momentStride(set));
        parent.box.resize(size_t(parent.width) * size_t(parent.height) * stride);

        withMomentSet(set, [&](auto setConstant) {
            constexpr unsigned S = decltype(setConstant)::value;
            tbb::parallel_for(0, parent.height, [&](int y) {
                float* out = &parent.box[size_t(y) * size_t(parent.width) * stride];
                for (int x = 0; x < parent.width; ++x, out += stride) {
                    RawMoments<S> raw;
                    if (k == 0) {
                        for (int j = cy[size_t(y)]; j < cy[size_t(y) + 1]; ++j)
                            for (int i = cx[size_t(x)]; i < cx[size_t(x) + 1]; ++i)
                                raw.addNormal(finest.at(i, j), 1.0);
                    } else {
                        for (int j = cy[size_t(y)]; j < cy[size_t(y) + 1]; ++j)
                            for (int i = cx[size_t(x)]; i < cx[size_t(x) + 1]; ++i)
                                raw.add(
                                    unpackMoments(
                                        &child.box[(size_t(j) * size_t(child.width) + size_t(i)) * stride],
                                        S),
                                    double(pyramid.footprintCount(k, i, j)));
                    }
                    packMoments<S>(raw.toMoments(), out);
                }
            });
        });
        pyramid.m_levels.push_back(std::move(parent));
    }
    return pyramid;
}

void NormalPyramid::releaseBox(int k) {
    if (k >= 0 && k < levelCount()) TexelVector().swap(m_levels[size_t(k)].box);
}

int NormalPyramid::footprintCount(int k, int x, int y) const {
    const PyramidLevel& l = level(k);
    return (l.xStart[size_t(x) + 1] - l.xStart[size_t(x)]) * (l.yStart[size_t(y) + 1] - l.yStart[size_t(y)]);
}

NormalMoments NormalPyramid::boxMoments(int k, int x, int y) const {
    if (k == 0) return NormalMoments::ofNormal(m_map->at(x, y));
    const PyramidLevel& l = level(k);
    const unsigned set = m_options.moments & kMomentsAll;
    return unpackMoments(&l.box[(size_t(y) * size_t(l.width) + size_t(x)) * size_t(momentStride(set))], set);
}

NormalMoments NormalPyramid::moments(int k, int x, int y) const {
    const KernelTaps taps = kernelTaps(m_options.kernel);
    if (taps.radius == 0) return boxMoments(k, x, y);
    const PyramidLevel& l = level(k);
    return withMomentSet(m_options.moments, [&](auto set) {
        RawMoments<decltype(set)::value> raw;
        for (int j = -taps.radius; j <= taps.radius; ++j)
            for (int i = -taps.radius; i <= taps.radius; ++i) {
                const int xi = borderIndex(x + i, l.width, m_options.border);
                const int yj = borderIndex(y + j, l.height, m_options.border);
                raw.add(boxMoments(k, xi, yj),
                        taps.w[i + taps.radius] * taps.w[j + taps.radius] * footprintCount(k, xi, yj));
            }
        return raw.toMoments();
    });
}

void NormalPyramid::forEachMomentRow(int k,
                                     const std::function<void(int y, const NormalMoments* row)>& fn) const {
    const PyramidLevel& l = level(k);
    const int width = l.width;
    const KernelTaps taps = kernelTaps(m_options.kernel);
    const BorderMode border = m_options.border;
    // Blocks of rows: each block converts its rows plus a halo of `radius` rows once, into a
    // rolling window of 2·radius + 1 rows, so the halo costs 2·radius/kBlockRows of the work.
    constexpr int kBlockRows = 32;
    const int blocks = (l.height + kBlockRows - 1) / kBlockRows;
    tbb::parallel_for(0, blocks, [&](int block) {
        const int y0 = block * kBlockRows;
        const int y1 = std::min(l.height, y0 + kBlockRows);
        std::vector<NormalMoments> out(static_cast<size_t>(width));
        if (taps.radius == 0) {
            for (int y = y0; y < y1; ++y) {
                for (int x = 0; x < width; ++x)
                    out[size_t(x)] = boxMoments(k, x, y);
                fn(y, out.data());
            }
            return;
        }
        const int r = taps.radius;
        const int window = 2 * r + 1;
        const bool finest = k == 0;
        std::vector<SoaRow> rows(static_cast<size_t>(window));
        for (auto& row : rows)
            row.resize(width, r, !finest, m_options.moments);
        auto fill = [&](int yy) {
            // Row yy (border-mapped) of the level goes to slot (yy + window) mod window; yy >= −r.
            SoaRow& row = rows[size_t((yy + window) % window)];
            const int ym = borderIndex(yy, l.height, border);
            if (finest)
                row.fillFinest(*m_map, ym, border);
            else
                row.fillLevel(*this, k, ym, border);
        };
        for (int yy = y0 - r; yy < y0 + r; ++yy)
            fill(yy);
        for (int y = y0; y < y1; ++y) {
            fill(y + r);
            const SoaRow* inputs[2 * kMaxTapRadius + 1] = {};
            for (int j = 0; j < window; ++j)
                inputs[j] = &rows[size_t((y - r + j + window) % window)];
            withMomentSet(m_options.moments, [&](auto set) {
                if (finest)
                    filterRow<false, decltype(set)::value>(inputs, taps, width, out.data());
                else
                    filterRow<true, decltype(set)::value>(inputs, taps, width, out.data());
            });
            fn(y, out.data());
        }
    });
}

} // namespace burnish
