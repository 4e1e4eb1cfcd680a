#include <burnish/core/normal_pyramid.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace burnish {

namespace {

// Double-precision accumulator for the weighted pairwise combination of moments:
// mean = Σ w μ_j / W, C = Σ w (C_j + (μ_j − μ)(μ_j − μ)ᵀ) / W (Chan, Golub & LeVeque 1979).
struct MomentSum {
    double w = 0.0;
    double mean[3] = {0, 0, 0};
    double slope[2] = {0, 0};

    void addMeans(const NormalMoments& m, double weight) {
        w += weight;
        for (int i = 0; i < 3; ++i) mean[i] += weight * double(m.mean[i]);
        for (int i = 0; i < 2; ++i) slope[i] += weight * double(m.slope[i]);
    }
};

NormalMoments combine(const NormalMoments* const* items, const double* weights, size_t count) {
    MomentSum sum;
    for (size_t j = 0; j < count; ++j) sum.addMeans(*items[j], weights[j]);
    NormalMoments out;
    if (!(sum.w > 0.0)) return out;
    double mu[3], beta[2];
    for (int i = 0; i < 3; ++i) mu[i] = sum.mean[i] / sum.w;
    for (int i = 0; i < 2; ++i) beta[i] = sum.slope[i] / sum.w;
    double c[6] = {0, 0, 0, 0, 0, 0};
    double sc[3] = {0, 0, 0};
    for (size_t j = 0; j < count; ++j) {
        const NormalMoments& m = *items[j];
        const double w = weights[j];
        const double d[3] = {double(m.mean[0]) - mu[0], double(m.mean[1]) - mu[1], double(m.mean[2]) - mu[2]};
        c[0] += w * (double(m.cov[0]) + d[0] * d[0]);
        c[1] += w * (double(m.cov[1]) + d[1] * d[1]);
        c[2] += w * (double(m.cov[2]) + d[2] * d[2]);
        c[3] += w * (double(m.cov[3]) + d[0] * d[1]);
        c[4] += w * (double(m.cov[4]) + d[0] * d[2]);
        c[5] += w * (double(m.cov[5]) + d[1] * d[2]);
        const double e[2] = {double(m.slope[0]) - beta[0], double(m.slope[1]) - beta[1]};
        sc[0] += w * (double(m.slopeCov[0]) + e[0] * e[0]);
        sc[1] += w * (double(m.slopeCov[1]) + e[1] * e[1]);
        sc[2] += w * (double(m.slopeCov[2]) + e[0] * e[1]);
    }
    out.mean = glm::vec3(float(mu[0]), float(mu[1]), float(mu[2]));
    out.slope = glm::vec2(float(beta[0]), float(beta[1]));
    for (int i = 0; i < 6; ++i) out.cov[size_t(i)] = float(c[i] / sum.w);
    for (int i = 0; i < 3; ++i) out.slopeCov[size_t(i)] = float(sc[i] / sum.w);
    return out;
}

// Finest-level start of each child interval: parent x covers children
// [⌊x·wc/wp⌋, ⌊(x+1)·wc/wp⌋) of the level below.
std::vector<int> childStarts(int childSize, int parentSize) {
    std::vector<int> starts(static_cast<size_t>(parentSize) + 1);
    for (int x = 0; x <= parentSize; ++x)
        starts[size_t(x)] = static_cast<int>((static_cast<long long>(x) * childSize) / parentSize);
    return starts;
}

} // namespace

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

float NormalMoments::lengthNa() const { return std::min(glm::length(mean), 1.0f); }

glm::vec3 NormalMoments::meanDirection() const {
    const float len = glm::length(mean);
    return len > 0.0f && std::isfinite(len) ? mean / len : glm::vec3(0.0f, 0.0f, 1.0f);
}

float NormalMoments::projectedVariance() const {
    const glm::vec3 n = meanDirection();
    const double trace = double(cov[0]) + double(cov[1]) + double(cov[2]);
    const double nCn = double(n.x) * n.x * cov[0] + double(n.y) * n.y * cov[1] + double(n.z) * n.z * cov[2] +
                       2.0 * (double(n.x) * n.y * cov[3] + double(n.x) * n.z * cov[4] + double(n.y) * n.z * cov[5]);
    return float(std::clamp(trace - nCn, 0.0, 1.0));
}

std::array<float, 3> NormalMoments::slopeSecondMoments() const {
    return {slopeCov[0] + slope.x * slope.x, slopeCov[1] + slope.y * slope.y, slopeCov[2] + slope.x * slope.y};
}

NormalMoments NormalMoments::ofNormal(const glm::vec3& n) {
    NormalMoments m;
    m.mean = n;
    const float z = std::max(n.z, kMinSlopeZ);
    m.slope = glm::vec2(n.x / z, n.y / z);
    return m;
}

NormalMoments combineMoments(const NormalMoments* moments, const double* weights, size_t count) {
    std::vector<const NormalMoments*> items(count);
    for (size_t i = 0; i < count; ++i) items[i] = &moments[i];
    return combine(items.data(), weights, count);
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
        for (int x = 0; x <= parent.width; ++x) parent.xStart[size_t(x)] = child.xStart[size_t(cx[size_t(x)])];
        for (int y = 0; y <= parent.height; ++y) parent.yStart[size_t(y)] = child.yStart[size_t(cy[size_t(y)])];
        parent.xChild = cx;
        parent.yChild = cy;
        parent.box.resize(size_t(parent.width) * size_t(parent.height));

        tbb::parallel_for(0, parent.height, [&](int y) {
            std::vector<NormalMoments> leaf;
            std::vector<const NormalMoments*> items;
            std::vector<double> weights;
            for (int x = 0; x < parent.width; ++x) {
                items.clear();
                weights.clear();
                leaf.clear();
                for (int j = cy[size_t(y)]; j < cy[size_t(y) + 1]; ++j)
                    for (int i = cx[size_t(x)]; i < cx[size_t(x) + 1]; ++i) {
                        if (k == 0) leaf.push_back(NormalMoments::ofNormal(finest.at(i, j)));
                        weights.push_back(double(pyramid.footprintCount(k, i, j)));
                    }
                if (k == 0)
                    for (const auto& m : leaf) items.push_back(&m);
                else
                    for (int j = cy[size_t(y)]; j < cy[size_t(y) + 1]; ++j)
                        for (int i = cx[size_t(x)]; i < cx[size_t(x) + 1]; ++i)
                            items.push_back(&child.box[size_t(j) * size_t(child.width) + size_t(i)]);
                parent.box[size_t(y) * size_t(parent.width) + size_t(x)] =
                    combine(items.data(), weights.data(), items.size());
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
    NormalMoments local[25];
    const NormalMoments* items[25];
    double weights[25];
    size_t count = 0;
    for (int j = -taps.radius; j <= taps.radius; ++j)
        for (int i = -taps.radius; i <= taps.radius; ++i) {
            const int xi = borderIndex(x + i, l.width, m_options.border);
            const int yj = borderIndex(y + j, l.height, m_options.border);
            local[count] = boxMoments(k, xi, yj);
            items[count] = &local[count];
            weights[count] = taps.w[i + taps.radius] * taps.w[j + taps.radius] * footprintCount(k, xi, yj);
            ++count;
        }
    return combine(items, weights, count);
}

} // namespace burnish
