#include <burnish/core/normal_pyramid.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace burnish {

namespace {

// Weighted raw sums in double: W, ΣwN (3), Σw NNᵀ (6: xx yy zz xy xz yz), Σw b (2), Σw bbᵀ (3).
// Central moments are recovered as Σw NNᵀ/W − μμᵀ in double, whose rounding (~1e-16 of |μ|² = 1)
// is far below any variance that matters (the smallest, 1/kMaxPower, is 1e-9), while the inputs
// are the float-stored central moments of the level below.
struct RawMoments {
    double v[15] = {};

    void add(const NormalMoments& m, double w) {
        const double mx = m.mean.x, my = m.mean.y, mz = m.mean.z, bx = m.slope.x, by = m.slope.y;
        v[0] += w;
        v[1] += w * mx;
        v[2] += w * my;
        v[3] += w * mz;
        v[4] += w * (double(m.cov[0]) + mx * mx);
        v[5] += w * (double(m.cov[1]) + my * my);
        v[6] += w * (double(m.cov[2]) + mz * mz);
        v[7] += w * (double(m.cov[3]) + mx * my);
        v[8] += w * (double(m.cov[4]) + mx * mz);
        v[9] += w * (double(m.cov[5]) + my * mz);
        v[10] += w * bx;
        v[11] += w * by;
        v[12] += w * (double(m.slopeCov[0]) + bx * bx);
        v[13] += w * (double(m.slopeCov[1]) + by * by);
        v[14] += w * (double(m.slopeCov[2]) + bx * by);
    }

    void addNormal(const glm::vec3& n, double w) {
        const double x = n.x, y = n.y, z = n.z;
        const double zs = std::max(z, double(kMinSlopeZ));
        const double bx = x / zs, by = y / zs;
        v[0] += w;
        v[1] += w * x;
        v[2] += w * y;
        v[3] += w * z;
        v[4] += w * x * x;
        v[5] += w * y * y;
        v[6] += w * z * z;
        v[7] += w * x * y;
        v[8] += w * x * z;
        v[9] += w * y * z;
        v[10] += w * bx;
        v[11] += w * by;
        v[12] += w * bx * bx;
        v[13] += w * by * by;
        v[14] += w * bx * by;
    }

    NormalMoments toMoments() const {
        NormalMoments out;
        if (!(v[0] > 0.0)) return out;
        const double inv = 1.0 / v[0];
        const double mx = v[1] * inv, my = v[2] * inv, mz = v[3] * inv, bx = v[10] * inv, by = v[11] * inv;
        out.mean = glm::vec3(float(mx), float(my), float(mz));
        out.slope = glm::vec2(float(bx), float(by));
        // Variances are clamped at 0 against rounding; covariances are left signed.
        out.cov = {float(std::max(0.0, v[4] * inv - mx * mx)),
                   float(std::max(0.0, v[5] * inv - my * my)),
                   float(std::max(0.0, v[6] * inv - mz * mz)),
                   float(v[7] * inv - mx * my),
                   float(v[8] * inv - mx * mz),
                   float(v[9] * inv - my * mz)};
        out.slopeCov = {float(std::max(0.0, v[12] * inv - bx * bx)),
                        float(std::max(0.0, v[13] * inv - by * by)), float(v[14] * inv - bx * by)};
        return out;
    }
};

// Finest-level start of each child interval: parent x covers children
// [⌊x·wc/wp⌋, ⌊(x+1)·wc/wp⌋) of the level below.
std::vector<int> childStarts(int childSize, int parentSize) {
    std::vector<int> starts(static_cast<size_t>(parentSize) + 1);
    for (int x = 0; x <= parentSize; ++x)
        starts[size_t(x)] = static_cast<int>((static_cast<long long>(x) * childSize) / parentSize);
    return starts;
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

float NormalMoments::lengthNa() const {
    return std::min(glm::length(mean), 1.0f);
}

glm::vec3 NormalMoments::meanDirection() const {
    const float len = glm::length(mean);
    return len > 0.0f && std::isfinite(len) ? mean / len : glm::vec3(0.0f, 0.0f, 1.0f);
}

float NormalMoments::projectedVariance() const {
    const glm::vec3 n = meanDirection();
    const double trace = double(cov[0]) + double(cov[1]) + double(cov[2]);
    const double nCn =
        double(n.x) * n.x * cov[0] + double(n.y) * n.y * cov[1] + double(n.z) * n.z * cov[2] +
        2.0 * (double(n.x) * n.y * cov[3] + double(n.x) * n.z * cov[4] + double(n.y) * n.z * cov[5]);
    return float(std::clamp(trace - nCn, 0.0, 1.0));
}

std::array<float, 3> NormalMoments::slopeSecondMoments() const {
    return {slopeCov[0] + slope.x * slope.x, slopeCov[1] + slope.y * slope.y,
            slopeCov[2] + slope.x * slope.y};
}

NormalMoments NormalMoments::ofNormal(const glm::vec3& n) {
    NormalMoments m;
    m.mean = n;
    const float z = std::max(n.z, kMinSlopeZ);
    m.slope = glm::vec2(n.x / z, n.y / z);
    return m;
}

NormalMoments combineMoments(const NormalMoments* moments, const double* weights, size_t count) {
    RawMoments raw;
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
        parent.box.resize(size_t(parent.width) * size_t(parent.height));

        tbb::parallel_for(0, parent.height, [&](int y) {
            for (int x = 0; x < parent.width; ++x) {
                RawMoments raw;
                for (int j = cy[size_t(y)]; j < cy[size_t(y) + 1]; ++j)
                    for (int i = cx[size_t(x)]; i < cx[size_t(x) + 1]; ++i) {
                        if (k == 0)
                            raw.addNormal(finest.at(i, j), 1.0);
                        else
                            raw.add(child.box[size_t(j) * size_t(child.width) + size_t(i)],
                                    double(pyramid.footprintCount(k, i, j)));
                    }
                parent.box[size_t(y) * size_t(parent.width) + size_t(x)] = raw.toMoments();
            }
        });
        pyramid.m_levels.push_back(std::move(parent));
    }
    return pyramid;
}

int NormalPyramid::footprintCount(int k, int x, int y) const {
    const PyramidLevel& l = level(k);
    return (l.xStart[size_t(x) + 1] - l.xStart[size_t(x)]) * (l.yStart[size_t(y) + 1] - l.yStart[size_t(y)]);
}

NormalMoments NormalPyramid::boxMoments(int k, int x, int y) const {
    if (k == 0) return NormalMoments::ofNormal(m_map->at(x, y));
    const PyramidLevel& l = level(k);
    return l.box[size_t(y) * size_t(l.width) + size_t(x)];
}

NormalMoments NormalPyramid::moments(int k, int x, int y) const {
    const KernelTaps taps = kernelTaps(m_options.kernel);
    if (taps.radius == 0) return boxMoments(k, x, y);
    const PyramidLevel& l = level(k);
    RawMoments raw;
    for (int j = -taps.radius; j <= taps.radius; ++j)
        for (int i = -taps.radius; i <= taps.radius; ++i) {
            const int xi = borderIndex(x + i, l.width, m_options.border);
            const int yj = borderIndex(y + j, l.height, m_options.border);
            raw.add(boxMoments(k, xi, yj),
                    taps.w[i + taps.radius] * taps.w[j + taps.radius] * footprintCount(k, xi, yj));
        }
    return raw.toMoments();
}

void NormalPyramid::forEachMomentRow(int k,
                                     const std::function<void(int y, const NormalMoments* row)>& fn) const {
    const PyramidLevel& l = level(k);
    const int width = l.width;
    const KernelTaps taps = kernelTaps(m_options.kernel);
    // Blocks of rows: each block filters its rows plus a halo of `radius` rows horizontally once.
    constexpr int kBlockRows = 16;
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
        const int rows = (y1 - y0) + 2 * r;
        // Horizontally filtered raw sums of rows y0−r .. y1+r−1 (border-mapped).
        std::vector<RawMoments> horizontal(size_t(rows) * size_t(width));
        std::vector<RawMoments> single(static_cast<size_t>(width));
        for (int j = 0; j < rows; ++j) {
            const int yy = borderIndex(y0 - r + j, l.height, m_options.border);
            for (int x = 0; x < width; ++x) {
                RawMoments m;
                if (k == 0)
                    m.addNormal(m_map->at(x, yy), 1.0);
                else
                    m.add(l.box[size_t(yy) * size_t(width) + size_t(x)], double(footprintCount(k, x, yy)));
                single[size_t(x)] = m;
            }
            RawMoments* h = &horizontal[size_t(j) * size_t(width)];
            for (int x = 0; x < width; ++x) {
                RawMoments sum;
                for (int i = -r; i <= r; ++i) {
                    const RawMoments& s = single[size_t(borderIndex(x + i, width, m_options.border))];
                    const double w = taps.w[i + r];
                    for (int c = 0; c < 15; ++c)
                        sum.v[c] += w * s.v[c];
                }
                h[x] = sum;
            }
        }
        for (int y = y0; y < y1; ++y) {
            for (int x = 0; x < width; ++x) {
                RawMoments sum;
                for (int j = -r; j <= r; ++j) {
                    const RawMoments& h = horizontal[size_t(y - y0 + r + j) * size_t(width) + size_t(x)];
                    const double w = taps.w[j + r];
                    for (int c = 0; c < 15; ++c)
                        sum.v[c] += w * h.v[c];
                }
                out[size_t(x)] = sum.toMoments();
            }
            fn(y, out.data());
        }
    });
}

} // namespace burnish
