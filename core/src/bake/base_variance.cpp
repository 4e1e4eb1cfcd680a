#include <burnish/core/bake/base_variance.h>

#include <algorithm>

namespace burnish {

void copyTexelRect(const std::vector<float>& from, std::vector<float>& to, int width, const TexelRect& rect) {
    for (int y = rect.y0; y < rect.y1; ++y) {
        const size_t row = size_t(y) * size_t(width);
        std::copy(from.begin() + ptrdiff_t(row + size_t(rect.x0)),
                  from.begin() + ptrdiff_t(row + size_t(rect.x1)),
                  to.begin() + ptrdiff_t(row + size_t(rect.x0)));
    }
}

void TexelRect::unite(const TexelRect& other) {
    if (other.empty()) return;
    if (empty()) {
        *this = other;
        return;
    }
    x0 = std::min(x0, other.x0);
    y0 = std::min(y0, other.y0);
    x1 = std::max(x1, other.x1);
    y1 = std::max(y1, other.y1);
}

BaseVariancePyramid::BaseVariancePyramid(const NormalPyramid& pyramid, int levels)
    : m_options(pyramid.options())
    , m_taps(kernelTaps(pyramid.options().kernel)) {
    const int count = levels > 0 ? std::min(levels, pyramid.levelCount()) : pyramid.levelCount();
    const int finestWidth = pyramid.level(0).width, finestHeight = pyramid.level(0).height;
    m_levels.resize(size_t(count));
    for (int k = 0; k < count; ++k) {
        const PyramidLevel& p = pyramid.level(k);
        Level& l = m_levels[size_t(k)];
        l.width = p.width;
        l.height = p.height;
        l.xStart = p.xStart;
        l.yStart = p.yStart;
        l.xChild = p.xChild;
        l.yChild = p.yChild;
        l.xOfFinest.resize(size_t(finestWidth));
        l.yOfFinest.resize(size_t(finestHeight));
        for (int x = 0; x < l.width; ++x)
            for (int i = l.xStart[size_t(x)]; i < l.xStart[size_t(x) + 1]; ++i)
                l.xOfFinest[size_t(i)] = x;
        for (int y = 0; y < l.height; ++y)
            for (int j = l.yStart[size_t(y)]; j < l.yStart[size_t(y) + 1]; ++j)
                l.yOfFinest[size_t(j)] = y;
        l.variance.resize(size_t(l.width) * size_t(l.height));
    }
}

int BaseVariancePyramid::footprintCount(int k, int x, int y) const {
    const Level& l = m_levels[size_t(k)];
    return (l.xStart[size_t(x) + 1] - l.xStart[size_t(x)]) * (l.yStart[size_t(y) + 1] - l.yStart[size_t(y)]);
}

void BaseVariancePyramid::build(const std::vector<float>& gloss, const GlossEncoding& encoding) {
    if (m_levels.empty()) return;
    update(gloss, encoding, TexelRect::full(m_levels[0].width, m_levels[0].height));
}

std::vector<TexelRect> BaseVariancePyramid::update(const std::vector<float>& gloss,
                                                   const GlossEncoding& encoding, const TexelRect& dirty) {
    std::vector<TexelRect> box(m_levels.size());
    if (m_levels.empty()) return box;
    const int w0 = m_levels[0].width, h0 = m_levels[0].height;
    const TexelRect d{std::max(dirty.x0, 0), std::max(dirty.y0, 0), std::min(dirty.x1, w0),
                      std::min(dirty.y1, h0)};
    if (d.empty()) return box;
    // Level 0's 1/s, then the box averages of every level above, inside the dirty footprint: a
    // level-k texel changes exactly when its footprint holds a dirty finest texel.
    for (size_t k = 0; k < m_levels.size(); ++k) {
        Level& l = m_levels[k];
        box[k] = {l.xOfFinest[size_t(d.x0)], l.yOfFinest[size_t(d.y0)], l.xOfFinest[size_t(d.x1 - 1)] + 1,
                  l.yOfFinest[size_t(d.y1 - 1)] + 1};
        for (int y = box[k].y0; y < box[k].y1; ++y)
            for (int x = box[k].x0; x < box[k].x1; ++x) {
                const size_t t = size_t(y) * size_t(l.width) + size_t(x);
                if (k == 0) {
                    l.variance[t] =
                        varianceFromPower(encoding.power(gloss[t]), VarianceConvention::InversePower);
                    continue;
                }
                const Level& child = m_levels[k - 1];
                double sum = 0.0, weight = 0.0;
                for (int j = l.yChild[size_t(y)]; j < l.yChild[size_t(y) + 1]; ++j)
                    for (int i = l.xChild[size_t(x)]; i < l.xChild[size_t(x) + 1]; ++i) {
                        const double w = footprintCount(int(k) - 1, i, j);
                        sum += w * child.variance[size_t(j) * size_t(child.width) + size_t(i)];
                        weight += w;
                    }
                l.variance[t] = sum / weight;
            }
    }
    return box;
}

double BaseVariancePyramid::power(int k, int x, int y) const {
    const KernelTaps& taps = m_taps;
    const Level& level = m_levels[size_t(k)];
    double sum = 0.0, weight = 0.0;
    for (int j = -taps.radius; j <= taps.radius; ++j)
        for (int i = -taps.radius; i <= taps.radius; ++i) {
            const int xi = borderIndex(x + i, level.width, m_options.border);
            const int yj = borderIndex(y + j, level.height, m_options.border);
            const double w = taps.w[i + taps.radius] * taps.w[j + taps.radius] * footprintCount(k, xi, yj);
            sum += w * level.variance[size_t(yj) * size_t(level.width) + size_t(xi)];
            weight += w;
        }
    return powerFromVariance(sum / weight, VarianceConvention::InversePower);
}

} // namespace burnish
