// The authored base power as a pyramid of variances 1/s, box-averaged over each texel's footprint
// and filtered with the pyramid's kernel when read: variances (not powers or gloss values) are what
// average correctly under minification (Baker & Hill 2012: "storing power as 1/s will cause MIP
// filter to operate correctly"). One type for the bake (a full build) and the live paint rebake
// (a rectangle update), so both give the same doubles.
#pragma once

#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/normal_pyramid.h>

#include <cstddef>
#include <vector>

namespace burnish {

/// A half-open rectangle of texels [x0, x1) × [y0, y1) inside a map.
struct TexelRect {
    int x0 = 0;
    int y0 = 0;
    int x1 = 0;
    int y1 = 0;

    bool empty() const { return x1 <= x0 || y1 <= y0; }
    int width() const { return empty() ? 0 : x1 - x0; }
    int height() const { return empty() ? 0 : y1 - y0; }
    size_t texelCount() const { return size_t(width()) * size_t(height()); }
    bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
    /// The bounding rectangle of both (an empty one leaves the other unchanged).
    void unite(const TexelRect& other);
    static TexelRect full(int width, int height) { return {0, 0, width, height}; }
    friend bool operator==(const TexelRect&, const TexelRect&) = default;
};

/// Copies the texels inside `rect` (which lies inside both) between two row-major arrays of the same
/// `width`: what keeps a copy of a big array up to date where it was edited.
void copyTexelRect(const std::vector<float>& from, std::vector<float>& to, int width, const TexelRect& rect);

class BaseVariancePyramid {
public:
    BaseVariancePyramid() = default;
    /// The footprint geometry of the pyramid's first `levels` levels (all when 0), no values yet.
    explicit BaseVariancePyramid(const NormalPyramid& pyramid, int levels = 0);

    /// Every level from `gloss` (one value per finest texel, decoded with `encoding`).
    void build(const std::vector<float>& gloss, const GlossEncoding& encoding);
    /// Level 0 inside `dirty` (clipped to the map) from `gloss`, then every level's texels whose
    /// footprint holds a dirty finest texel; returns those rectangles per level (empty when `dirty`
    /// is). Texels outside are not read from `gloss`. The values equal a full build's.
    std::vector<TexelRect> update(const std::vector<float>& gloss, const GlossEncoding& encoding,
                                  const TexelRect& dirty);

    /// Base power at a texel of level k: the kernel-filtered 1/s, inverted.
    double power(int k, int x, int y) const;

    int levelCount() const { return int(m_levels.size()); }
    /// The radius of the kernel power() filters with: a changed texel reaches this far.
    int kernelRadius() const { return m_taps.radius; }
    /// Finest texels under texel (x, y) of level k.
    int footprintCount(int k, int x, int y) const;
    /// The level-k column / row whose footprint holds finest column x / row y.
    int columnAt(int k, int x) const { return m_levels[size_t(k)].xOfFinest[size_t(x)]; }
    int rowAt(int k, int y) const { return m_levels[size_t(k)].yOfFinest[size_t(y)]; }

private:
    struct Level {
        int width = 0;
        int height = 0;
        std::vector<int> xStart, yStart;       // finest footprint starts, size width+1 / height+1
        std::vector<int> xChild, yChild;       // first child in level k−1, size width+1 / height+1
        std::vector<int> xOfFinest, yOfFinest; // level texel of each finest column / row
        std::vector<double> variance;          // box-averaged 1/s over the footprint
    };

    PyramidOptions m_options;
    KernelTaps m_taps; // looked up once: the Gaussian's weights cost two exp() each
    std::vector<Level> m_levels;
};

} // namespace burnish
