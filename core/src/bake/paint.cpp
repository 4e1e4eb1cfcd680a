#include <burnish/core/bake/paint.h>

#include <burnish/core/io/image.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/util/files.h>

#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>

namespace burnish {

namespace {

namespace fs = std::filesystem;

float unit(double v) {
    return float(saturate(v));
}

bool finite2(const glm::dvec2& p) {
    return std::isfinite(p.x) && std::isfinite(p.y);
}

Status checkLayer(const PaintLayer& layer, const char* what) {
    const size_t n = size_t(std::max(layer.width, 0)) * size_t(std::max(layer.height, 0));
    // Both arrays allocated at the layer's size, or both not yet (an unpainted layer).
    const size_t held = layer.allocated() ? n : 0;
    if (layer.width <= 0 || layer.height <= 0 || layer.value.size() != held || layer.coverage.size() != held)
        return Error{std::string(what) + " layer's arrays do not match its size"};
    return {};
}

// Moments that make methodLobe read exactly the statistic cached per texel. The isotropic methods
// read only the mean and the covariance: with mean +z and cov = (v, 0, 0, 0, 0, 0),
// projectedVariance() = tr C − ẑᵀCẑ = (v + 0 + 0) − 0 = v exactly; with mean (0, 0, r),
// lengthNa() = √(r²) = r exactly in binary floating point (r² normal, i.e. r > 1.1e-19; below
// that the vMF power is far under every encoding's minimum power, so the stored value is the same).
NormalMoments momentsWithVariance(float v) {
    NormalMoments m;
    m.cov[0] = v;
    return m;
}

NormalMoments momentsWithLength(float r) {
    NormalMoments m;
    m.mean = glm::vec3(0.0f, 0.0f, r);
    return m;
}

} // namespace

std::string_view paintLayerName(PaintLayerKind kind) {
    return kind == PaintLayerKind::Gloss ? "gloss" : "variance-offset";
}

Result<PaintLayer> PaintLayer::create(PaintLayerKind kind, int width, int height) {
    if (width <= 0 || height <= 0 || width > kMaxImageSide || height > kMaxImageSide ||
        std::uint64_t(width) * std::uint64_t(height) > kMaxImageTexels)
        return Error{"a paint layer of " + std::to_string(width) + "x" + std::to_string(height) +
                     " texels is not possible (1 to " + std::to_string(kMaxImageSide) + " on a side)"};
    PaintLayer layer;
    layer.kind = kind;
    layer.width = width;
    layer.height = height;
    return layer;
}

void PaintLayer::allocate() {
    if (allocated()) return;
    value.assign(texelCount(), 0.0f);
    coverage.assign(texelCount(), 0.0f);
}

bool PaintLayer::painted() const {
    return std::any_of(coverage.begin(), coverage.end(), [](float c) { return c > 0.0f; });
}

void PaintLayer::clear() {
    value = {};
    coverage = {};
}

TexelRect paintedBounds(const PaintLayer& layer) {
    TexelRect bounds;
    if (!layer.allocated()) return bounds;
    for (int y = 0; y < layer.height; ++y)
        for (int x = 0; x < layer.width; ++x) {
            const size_t i = layer.index(x, y);
            // Bits, not values: a −0 is not what an unpainted texel holds either.
            if (std::bit_cast<std::uint32_t>(layer.value[i]) |
                std::bit_cast<std::uint32_t>(layer.coverage[i]))
                bounds.unite({x, y, x + 1, y + 1});
        }
    return bounds;
}

bool samePaint(const PaintLayer& a, const PaintLayer& b) {
    if (a.kind != b.kind || a.width != b.width || a.height != b.height) return false;
    for (size_t i = 0; i < a.texelCount(); ++i)
        if (std::bit_cast<std::uint32_t>(a.valueAt(i)) != std::bit_cast<std::uint32_t>(b.valueAt(i)) ||
            std::bit_cast<std::uint32_t>(a.coverageAt(i)) != std::bit_cast<std::uint32_t>(b.coverageAt(i)))
            return false;
    return true;
}

namespace {

// One axis of the area-weighted resampling: for each new texel, the old texels its interval
// [j·from/to, (j+1)·from/to) overlaps and by how much (the weights of one texel sum to 1).
struct AxisTaps {
    std::vector<int> first;     // per new texel, index into taps
    std::vector<int> index;     // old texel
    std::vector<double> weight; // overlap / interval length
};

AxisTaps axisTaps(int from, int to) {
    AxisTaps t;
    t.first.reserve(size_t(to) + 1);
    for (int j = 0; j < to; ++j) {
        t.first.push_back(int(t.index.size()));
        // In units of 1/to of an old texel, so the ends are exact integers.
        const std::int64_t a = std::int64_t(j) * from, b = std::int64_t(j + 1) * from;
        for (std::int64_t i = a / to; i * to < b; ++i) {
            const std::int64_t lo = std::max(a, i * to), hi = std::min(b, (i + 1) * to);
            if (hi > lo) {
                t.index.push_back(int(i));
                t.weight.push_back(double(hi - lo) / double(b - a));
            }
        }
    }
    t.first.push_back(int(t.index.size()));
    return t;
}

} // namespace

Result<PaintLayer> resamplePaintLayer(const PaintLayer& layer, int width, int height) {
    if (const Status st = checkLayer(layer, "the resampled"); !st) return Error{st.error()};
    auto out = PaintLayer::create(layer.kind, width, height);
    if (!out) return Error{out.error()};
    if (!layer.allocated()) return out; // nothing painted: nothing to carry
    const AxisTaps tx = axisTaps(layer.width, width), ty = axisTaps(layer.height, height);
    // Along x first (coverage and coverage·value in double), then along y.
    std::vector<double> rowsCover(size_t(width) * size_t(layer.height)), rowsPaint(rowsCover.size());
    tbb::parallel_for(0, layer.height, [&](int y) {
        for (int x = 0; x < width; ++x) {
            double cover = 0.0, paint = 0.0;
            for (int t = tx.first[size_t(x)]; t < tx.first[size_t(x) + 1]; ++t) {
                const size_t i = layer.index(tx.index[size_t(t)], y);
                cover += tx.weight[size_t(t)] * layer.coverage[i];
                paint += tx.weight[size_t(t)] * double(layer.coverage[i]) * double(layer.value[i]);
            }
            rowsCover[size_t(y) * size_t(width) + size_t(x)] = cover;
            rowsPaint[size_t(y) * size_t(width) + size_t(x)] = paint;
        }
    });
    PaintLayer& o = out.value();
    o.allocate();
    tbb::parallel_for(0, height, [&](int y) {
        for (int x = 0; x < width; ++x) {
            double cover = 0.0, paint = 0.0;
            for (int t = ty.first[size_t(y)]; t < ty.first[size_t(y) + 1]; ++t) {
                const size_t i = size_t(ty.index[size_t(t)]) * size_t(width) + size_t(x);
                cover += ty.weight[size_t(t)] * rowsCover[i];
                paint += ty.weight[size_t(t)] * rowsPaint[i];
            }
            const size_t i = o.index(x, y);
            o.coverage[i] = unit(cover);
            // Where nothing was painted the value stays 0; elsewhere the coverage-weighted mean.
            o.value[i] = cover > 0.0 ? unit(paint / cover) : 0.0f;
        }
    });
    return out;
}

PaintPatch copyPatch(const PaintLayer& layer, const TexelRect& rect) {
    PaintPatch patch;
    patch.rect = {std::max(rect.x0, 0), std::max(rect.y0, 0), std::min(rect.x1, layer.width),
                  std::min(rect.y1, layer.height)};
    if (patch.rect.empty()) {
        patch.rect = {};
        return patch;
    }
    patch.value.reserve(patch.rect.texelCount());
    patch.coverage.reserve(patch.rect.texelCount());
    for (int y = patch.rect.y0; y < patch.rect.y1; ++y)
        for (int x = patch.rect.x0; x < patch.rect.x1; ++x) {
            patch.value.push_back(layer.valueAt(layer.index(x, y)));
            patch.coverage.push_back(layer.coverageAt(layer.index(x, y)));
        }
    return patch;
}

Status applyPatch(PaintLayer& layer, const PaintPatch& patch) {
    const TexelRect& r = patch.rect;
    if (r.empty()) return {};
    if (r.x0 < 0 || r.y0 < 0 || r.x1 > layer.width || r.y1 > layer.height)
        return Error{"the paint patch lies outside the layer"};
    if (patch.value.size() != r.texelCount() || patch.coverage.size() != r.texelCount())
        return Error{"the paint patch's arrays do not match its rectangle"};
    // A patch of zeros onto an unpainted layer changes nothing: it stays unallocated.
    auto nonZero = [](float v) { return v != 0.0f || std::signbit(v); };
    if (!layer.allocated() && std::none_of(patch.value.begin(), patch.value.end(), nonZero) &&
        std::none_of(patch.coverage.begin(), patch.coverage.end(), nonZero))
        return {};
    layer.allocate();
    size_t i = 0;
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x, ++i) {
            layer.value[layer.index(x, y)] = patch.value[i];
            layer.coverage[layer.index(x, y)] = patch.coverage[i];
        }
    return {};
}

Status validateBrush(const Brush& b) {
    if (!(b.radius >= kMinBrushRadius && b.radius <= kMaxBrushRadius))
        return Error{"the brush radius must lie in [0.5, 65536] texels"};
    if (!(b.hardness >= 0.0 && b.hardness <= 1.0)) return Error{"the brush hardness must lie in [0, 1]"};
    if (!(b.opacity >= 0.0 && b.opacity <= 1.0)) return Error{"the brush opacity must lie in [0, 1]"};
    if (!(b.value >= 0.0f && b.value <= 1.0f)) return Error{"the brush value must lie in [0, 1]"};
    // 4 radii apart the dabs of a stroke no longer touch: more is a dotted line, not a stroke.
    if (!(b.spacing >= kMinBrushSpacing && b.spacing <= 4.0))
        return Error{"the brush spacing must lie in [0.01, 4] radii"};
    return {};
}

double brushFalloff(double distance, double radius, double hardness) {
    if (!(distance < radius)) return 0.0; // also NaN
    const double inner = saturate(hardness) * radius;
    if (distance <= inner) return 1.0;
    // Hermite smoothstep from the hard core to the rim: zero slope at both ends, so neither the
    // core's edge nor the rim shows as a ring. radius > distance > inner, so the division is safe.
    const double t = (distance - inner) / (radius - inner);
    return 1.0 - t * t * (3.0 - 2.0 * t);
}

PaintStroke::PaintStroke(PaintLayer& layer, const Brush& brush, BorderMode border)
    : m_layer(&layer)
    , m_brush(brush)
    , m_border(border)
    , m_tilesX((layer.width + kStrokeTile - 1) / kStrokeTile)
    , m_tiles(size_t(m_tilesX) * size_t((layer.height + kStrokeTile - 1) / kStrokeTile)) {
    layer.allocate();
}

PaintStroke::Tile& PaintStroke::tileAt(int x, int y) {
    Tile& t = m_tiles[size_t(y / kStrokeTile) * size_t(m_tilesX) + size_t(x / kStrokeTile)];
    if (t.strength.empty()) {
        constexpr size_t n = size_t(kStrokeTile) * size_t(kStrokeTile);
        t.value.assign(n, 0.0f), t.coverage.assign(n, 0.0f), t.strength.assign(n, 0.0f);
        const int x0 = x / kStrokeTile * kStrokeTile, y0 = y / kStrokeTile * kStrokeTile;
        for (int j = y0; j < std::min(y0 + kStrokeTile, m_layer->height); ++j)
            for (int i = x0; i < std::min(x0 + kStrokeTile, m_layer->width); ++i) {
                const size_t at = size_t(j - y0) * size_t(kStrokeTile) + size_t(i - x0);
                t.value[at] = m_layer->value[m_layer->index(i, j)];
                t.coverage[at] = m_layer->coverage[m_layer->index(i, j)];
            }
    }
    return t;
}

const PaintStroke::Tile* PaintStroke::touchedTile(int x, int y) const {
    const Tile& t = m_tiles[size_t(y / kStrokeTile) * size_t(m_tilesX) + size_t(x / kStrokeTile)];
    return t.strength.empty() ? nullptr : &t;
}

Result<PaintStroke> PaintStroke::begin(PaintLayer& layer, const Brush& brush, BorderMode border) {
    if (const Status st = validateBrush(brush); !st) return Error{st.error()};
    if (const Status st = checkLayer(layer, "the painted"); !st) return Error{st.error()};
    return PaintStroke(layer, brush, border);
}

Status PaintStroke::addPoint(const glm::dvec2& point) {
    if (!finite2(point)) return Error{"a stroke point is not finite"};
    if (!m_lastDab) {
        dab(point);
        m_lastDab = point;
        return {};
    }
    const glm::dvec2 from = *m_lastDab;
    const glm::dvec2 d = point - from;
    const double dist = std::sqrt(d.x * d.x + d.y * d.y);
    const double step = m_brush.spacing * m_brush.radius;
    if (!(dist >= step)) return {}; // the next dab is further along: the distance accumulates
    const double n = std::floor(dist / step);
    // Each dab from the segment's start, not from the previous dab, so no error accumulates.
    for (double i = 1.0; i <= n; i += 1.0)
        dab(from + d * (step * i / dist));
    m_lastDab = from + d * (step * n / dist);
    return {};
}

Status PaintStroke::jumpTo(const glm::dvec2& point) {
    if (!finite2(point)) return Error{"a stroke point is not finite"};
    dab(point);
    m_lastDab = point;
    return {};
}

void PaintStroke::dab(const glm::dvec2& centre) {
    m_dabs.push_back(centre);
    PaintLayer& layer = *m_layer;
    const double r = m_brush.radius;
    const bool wrap = m_border == BorderMode::Wrap;
    // Texel columns [lo, hi] (unwrapped) whose centres may lie within the radius; with Wrap the
    // centre is first brought into the map and a dab wider than the map covers one period around
    // it, so each texel is reached once, at its nearest image.
    struct Span {
        double c;
        int lo, hi;
    };
    auto span = [&](double c, int size) -> std::optional<Span> {
        if (wrap)
            c -= size * std::floor(c / size);
        else if (c < -r - 1.0 || c > size + r + 1.0)
            return std::nullopt; // entirely outside
        int lo = int(std::floor(c - r - 0.5));
        int hi = int(std::ceil(c + r - 0.5));
        if (wrap && hi - lo + 1 >= size) {
            lo = int(std::floor(c - 0.5 * size));
            hi = lo + size - 1;
        } else if (!wrap) {
            lo = std::max(lo, 0);
            hi = std::min(hi, size - 1);
            if (lo > hi) return std::nullopt;
        }
        return Span{c, lo, hi};
    };
    const auto sx = span(centre.x, layer.width);
    const auto sy = span(centre.y, layer.height);
    if (!sx || !sy) return;

    const double b = m_brush.value;
    TexelRect touched;
    for (int py = sy->lo; py <= sy->hi; ++py) {
        const int y = borderIndex(py, layer.height, m_border);
        const double dy = py + 0.5 - sy->c;
        for (int px = sx->lo; px <= sx->hi; ++px) {
            const double dx = px + 0.5 - sx->c;
            const double w =
                m_brush.opacity * brushFalloff(std::sqrt(dx * dx + dy * dy), r, m_brush.hardness);
            if (!(w > 0.0)) continue;
            const int x = borderIndex(px, layer.width, m_border);
            const size_t i = layer.index(x, y);
            // A stroke keeps the strongest dab per texel and composites it once over the layer as
            // it was before the stroke: overlapping dabs do not pile up beyond the opacity.
            Tile& tile = tileAt(x, y);
            const size_t t = size_t(y % kStrokeTile) * size_t(kStrokeTile) + size_t(x % kStrokeTile);
            if (!(w > double(tile.strength[t]))) continue;
            tile.strength[t] = float(w);
            const double a = tile.coverage[t], v = tile.value[t];
            if (m_brush.erase) {
                layer.coverage[i] = unit(a * (1.0 - w));
                layer.value[i] = float(v);
            } else {
                // Porter & Duff 1984, "Compositing Digital Images": b over (v, a) with alpha w.
                const double aOut = w + a * (1.0 - w);
                layer.coverage[i] = unit(aOut);
                layer.value[i] = aOut > 0.0 ? unit((w * b + a * (1.0 - w) * v) / aOut) : float(v);
            }
            touched.unite({x, y, x + 1, y + 1});
        }
    }
    m_dirty.unite(touched);
    m_recent.unite(touched);
}

TexelRect PaintStroke::takeRecentDirty() {
    const TexelRect out = m_recent;
    m_recent = {};
    return out;
}

PaintPatch PaintStroke::before() const {
    PaintPatch patch;
    patch.rect = m_dirty;
    for (int y = m_dirty.y0; y < m_dirty.y1; ++y)
        for (int x = m_dirty.x0; x < m_dirty.x1; ++x) {
            // Texels of tiles no dab reached are as they were.
            const Tile* tile = touchedTile(x, y);
            const size_t t = size_t(y % kStrokeTile) * size_t(kStrokeTile) + size_t(x % kStrokeTile);
            const size_t i = m_layer->index(x, y);
            patch.value.push_back(tile ? tile->value[t] : m_layer->value[i]);
            patch.coverage.push_back(tile ? tile->coverage[t] : m_layer->coverage[i]);
        }
    return patch;
}

PaintPatch PaintStroke::after() const {
    return copyPatch(*m_layer, m_dirty);
}

Status compositeAuthoredGloss(const std::vector<float>* glossMap, double baseGloss, const PaintLayer* gloss,
                              const PaintLayer* varianceOffset, const GlossEncoding& encoding, int width,
                              int height, const TexelRect& region, std::vector<float>& out) {
    const size_t n = size_t(std::max(width, 0)) * size_t(std::max(height, 0));
    if (n == 0 || out.size() != n) return Error{"the authored gloss does not match the map's size"};
    if (glossMap && glossMap->size() != n) return Error{"the gloss map does not match the normal map's size"};
    for (const PaintLayer* l : {gloss, varianceOffset})
        if (l && (l->width != width || l->height != height || !checkLayer(*l, "a")))
            return Error{"a paint layer does not match the normal map's size"};
    const float base = unit(std::isfinite(baseGloss) ? baseGloss : 0.0);
    const TexelRect r{std::max(region.x0, 0), std::max(region.y0, 0), std::min(region.x1, width),
                      std::min(region.y1, height)};
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            // A NaN in a loaded map is refused by glossFromImage; here it would become 0 anyway.
            double g = glossMap ? double(unit(std::isfinite((*glossMap)[i]) ? (*glossMap)[i] : 0.0f)) : base;
            if (gloss && gloss->coverageAt(i) > 0.0f) {
                const double a = gloss->coverageAt(i);
                g = g + a * (double(gloss->valueAt(i)) - g);
            }
            if (varianceOffset && varianceOffset->coverageAt(i) > 0.0f) {
                const double v = double(varianceOffset->coverageAt(i)) * double(varianceOffset->valueAt(i));
                // Lazarov 2011: v' = v + 1/(n+1), clamped, back to gloss. Applied only where painted,
                // so an unpainted texel keeps its gloss bit for bit (no round trip through power).
                if (v > 0.0) g = varianceToGloss(g, v, encoding);
            }
            out[i] = unit(g);
        }
    return {};
}

// ---------------------------------------------------------------------------------------------
// LiveGlossBake. The base power is bake()'s own BaseVariancePyramid (updated by rectangle), and the
// gloss texel repeats bake()'s Gloss role operation for operation, so the results are the same
// doubles; the bit-identity tests hold the two together.

float LiveGlossBake::glossTexel(int k, int x, int y) const {
    const Level& level = m_levels[size_t(k)];
    const size_t t = size_t(y) * size_t(level.width) + size_t(x);
    const double s = m_base.power(k, x, y);
    double p = s;
    if (m_options.method == Method::VarianceToGloss)
        p = methodLobe(m_options.method, momentsWithVariance(level.variance[t]), s, m_options.params).power;
    else if (m_options.method == Method::Vmf)
        p = methodLobe(m_options.method, momentsWithLength(level.lengthNa[t]), s, m_options.params).power;
    return unit(m_options.encoding.value(p));
}

std::vector<int> LiveGlossBake::borderRange(int lo, int hi, int size) const {
    std::vector<int> out;
    if (hi - lo >= size) {
        out.resize(size_t(size));
        for (int i = 0; i < size; ++i)
            out[size_t(i)] = i;
        return out;
    }
    for (int i = lo; i < hi; ++i)
        out.push_back(borderIndex(i, size, m_options.pyramid.border));
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

Result<LiveGlossBake> LiveGlossBake::create(std::shared_ptr<const NormalMap> map,
                                            const BakeOptions& options) {
    if (!map || map->texelCount() == 0) return Error{"the normal map is empty"};
    if (!(options.basePower > 0.0) || !(options.basePower <= kMaxPower))
        return Error{"base power must lie in (0, 1e9]"};
    if (!options.authoredGloss) return Error{"the live gloss bake needs an authored gloss"};
    if (!hasTexture(options.method, TextureRole::Gloss))
        return Error{"method '" + std::string(methodName(options.method)) +
                     "' stores no gloss texture (its authored power lives in the moment textures)"};
    if (options.method == Method::Fitted)
        return Error{
            "the fitted lobe's gloss comes from the footprint's shading, not the moments the live bake "
            "keeps: bake it in full"};
    if (options.authoredGloss->size() != map->texelCount())
        return Error{"authored gloss has " + std::to_string(options.authoredGloss->size()) +
                     " texels, the normal map " + std::to_string(map->texelCount())};
    for (float g : *options.authoredGloss)
        if (!std::isfinite(g)) return Error{"authored gloss has a NaN or infinite texel"};

    LiveGlossBake out;
    out.m_authored = *options.authoredGloss;
    out.m_options = options;
    out.m_options.authoredGloss.reset(); // kept once, in m_authored
    // Only the moments read below (the mean and the covariance: 36 bytes a texel, not all 68; the
    // pyramid of an 8192² map is most of the live bake's peak).
    PyramidOptions pyramidOptions = options.pyramid;
    pyramidOptions.moments = kMomentsCov;
    const NormalPyramid pyramid = NormalPyramid::build(map, pyramidOptions);
    const int levels =
        options.mipCount > 0 ? std::min(options.mipCount, pyramid.levelCount()) : pyramid.levelCount();
    out.m_base = BaseVariancePyramid(pyramid, levels);
    out.m_levels.resize(size_t(levels));
    const bool vmf = options.method == Method::Vmf;
    for (int k = 0; k < levels; ++k) {
        const PyramidLevel& p = pyramid.level(k);
        Level& l = out.m_levels[size_t(k)];
        l.width = p.width;
        l.height = p.height;
        const size_t texels = size_t(l.width) * size_t(l.height);
        l.variance.resize(texels);
        if (vmf) l.lengthNa.resize(texels);
        // The same filtered moments the bake streams (deterministic whatever the blocking).
        pyramid.forEachMomentRow(k, [&](int y, const NormalMoments* row) {
            for (int x = 0; x < l.width; ++x) {
                const size_t t = size_t(y) * size_t(l.width) + size_t(x);
                l.variance[t] = row[x].projectedVariance();
                if (vmf) l.lengthNa[t] = row[x].lengthNa();
            }
        });
    }

    out.m_gloss.role = TextureRole::Gloss;
    out.m_gloss.description = "adjusted gloss (live), " + options.encoding.formula();
    out.m_gloss.decode = textureDecode(TextureRole::Gloss, {});
    out.m_gloss.channels = int(out.m_gloss.decode.size());
    out.m_gloss.mips.resize(size_t(levels));
    for (int k = 0; k < levels; ++k) {
        TextureMip& mip = out.m_gloss.mips[size_t(k)];
        mip.width = out.m_levels[size_t(k)].width;
        mip.height = out.m_levels[size_t(k)].height;
        mip.texels.resize(size_t(mip.width) * size_t(mip.height));
    }
    // The whole map is the first dirty region.
    const std::vector<float> authored = out.m_authored;
    if (const Status st = out.rebakeRegion(authored, TexelRect::full(map->width, map->height)); !st)
        return Error{st.error()};
    return out;
}

Status LiveGlossBake::rebakeRegion(const std::vector<float>& authoredGloss, const TexelRect& dirty) {
    m_lastRecomputed = 0;
    m_lastRects.assign(m_levels.size(), TexelRect{});
    if (authoredGloss.size() != m_authored.size())
        return Error{"authored gloss has " + std::to_string(authoredGloss.size()) + " texels, the map " +
                     std::to_string(m_authored.size())};
    const int w0 = width(), h0 = height();
    const TexelRect d{std::max(dirty.x0, 0), std::max(dirty.y0, 0), std::min(dirty.x1, w0),
                      std::min(dirty.y1, h0)};
    if (d.empty()) return {};
    for (int y = d.y0; y < d.y1; ++y)
        for (int x = d.x0; x < d.x1; ++x)
            if (!std::isfinite(authoredGloss[size_t(y) * size_t(w0) + size_t(x)]))
                return Error{"authored gloss has a NaN or infinite texel"};

    // The authored values inside the dirty rectangle, then the base variances there and above.
    for (int y = d.y0; y < d.y1; ++y)
        for (int x = d.x0; x < d.x1; ++x) {
            const size_t t = size_t(y) * size_t(w0) + size_t(x);
            m_authored[t] = authoredGloss[t];
        }
    const std::vector<TexelRect> box = m_base.update(m_authored, m_options.encoding, d);

    // The gloss texels whose kernel reads a changed box texel: the box rectangle grown by the
    // kernel radius, mapped through the border mode (exact for both: see borderIndex).
    const int r = m_base.kernelRadius();
    for (size_t k = 0; k < m_levels.size(); ++k) {
        const Level& l = m_levels[k];
        const std::vector<int> xs = borderRange(box[k].x0 - r, box[k].x1 + r, l.width);
        const std::vector<int> ys = borderRange(box[k].y0 - r, box[k].y1 + r, l.height);
        TextureMip& mip = m_gloss.mips[k];
        tbb::parallel_for(size_t(0), ys.size(), [&](size_t yi) {
            const int y = ys[yi];
            for (int x : xs)
                mip.texels[size_t(y) * size_t(l.width) + size_t(x)] = glossTexel(int(k), x, y);
        });
        m_lastRecomputed += xs.size() * ys.size();
        m_lastRects[k] = {xs.front(), ys.front(), xs.back() + 1, ys.back() + 1};
    }
    return {};
}

float LiveGlossBake::projectedVariance(int k, int x, int y) const {
    const Level& l = m_levels[size_t(k)];
    return l.variance[size_t(y) * size_t(l.width) + size_t(x)];
}

glm::ivec2 LiveGlossBake::texelAtLevel(int k, int x, int y) const {
    return {m_base.columnAt(k, x), m_base.rowAt(k, y)};
}

Status overShine(const LiveGlossBake& bake, const std::vector<float>& authoredGloss, int mip,
                 double thresholdStops, const PaintLayer* paintedMask, OverShineMap& inOut,
                 const std::optional<TexelRect>& region, const std::optional<UnpaintedGloss>& unpainted) {
    const int w = bake.width(), h = bake.height();
    const size_t n = size_t(w) * size_t(h);
    if (authoredGloss.size() != n) return Error{"the authored gloss does not match the baked map's size"};
    if (paintedMask &&
        (paintedMask->width != w || paintedMask->height != h || !checkLayer(*paintedMask, "the")))
        return Error{"the paint layer does not match the baked map's size"};
    if (!std::isfinite(thresholdStops)) return Error{"the over-shine threshold must be finite"};
    if (unpainted && unpainted->values && unpainted->values->size() != n)
        return Error{"the unpainted gloss does not match the baked map's size"};
    const int k = std::clamp(mip, 0, bake.levelCount() - 1);
    TexelRect r = TexelRect::full(w, h);
    if (region && inOut.width == w && inOut.height == h && inOut.mip == k && inOut.stops.size() == n) {
        r = {std::max(region->x0, 0), std::max(region->y0, 0), std::min(region->x1, w),
             std::min(region->y1, h)};
    } else {
        inOut.width = w;
        inOut.height = h;
        inOut.mip = k;
        inOut.stops.assign(n, 0.0f);
        inOut.flagged.assign(n, 0);
        inOut.flaggedCount = 0;
        inOut.mipWidth = bake.levelWidth(k);
        inOut.mipHeight = bake.levelHeight(k);
        inOut.flaggedUnder.assign(size_t(inOut.mipWidth) * size_t(inOut.mipHeight), 0);
        inOut.flaggedMipTexels = 0;
    }
    const GlossEncoding& encoding = bake.options().encoding;
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            const glm::ivec2 p = bake.texelAtLevel(k, x, y);
            const float v = bake.projectedVariance(k, p.x, p.y);
            const double np = encoding.power(authoredGloss[i]);
            // The variance-to-gloss result for this texel's painted power at mip k.
            const double pv = methodLobe(Method::VarianceToGloss, momentsWithVariance(v), np).power;
            // (n+1)/(p+1) >= 1 as p <= n; both terms are >= 1, so the log is finite.
            const double stops = std::max(0.0, std::log2((np + 1.0) / (pv + 1.0)));
            // Painted, and (when the unpainted gloss is known) made shinier by the paint.
            const bool painted = (!paintedMask || paintedMask->coverageAt(i) > 0.0f) &&
                                 (!unpainted || np > encoding.power(unpainted->at(i)));
            const uint8_t flag = stops > thresholdStops && painted ? 1 : 0;
            uint32_t& under = inOut.flaggedUnder[size_t(p.y) * size_t(inOut.mipWidth) + size_t(p.x)];
            if (flag && !inOut.flagged[i]) {
                ++inOut.flaggedCount;
                if (under++ == 0) ++inOut.flaggedMipTexels;
            }
            if (!flag && inOut.flagged[i]) {
                --inOut.flaggedCount;
                if (--under == 0) --inOut.flaggedMipTexels;
            }
            inOut.stops[i] = float(stops);
            inOut.flagged[i] = flag;
        }
    return {};
}

Status writePaintLayerExr(const PaintLayer& layer, const fs::path& path) {
    if (const Status st = checkLayer(layer, "the saved"); !st) return st;
    std::vector<float> interleaved(layer.texelCount() * 2);
    for (size_t i = 0; i < layer.texelCount(); ++i) {
        interleaved[2 * i] = layer.valueAt(i);
        interleaved[2 * i + 1] = layer.coverageAt(i);
    }
    return writeImageAtomic(path, layer.width, layer.height, 2, interleaved,
                            {StoredType::Float,
                             {"value", "coverage"},
                             {{"burnish:layer", std::string(paintLayerName(layer.kind))}}});
}

Result<PaintLayer> readPaintLayerExr(const fs::path& path, PaintLayerKind kind, int width, int height) {
    const std::string where = "paint layer '" + path.string() + "'";
    if (const Status st = requireRegularFile(path, "paint layer"); !st) return Error{st.error()};
    auto in = OIIO::ImageInput::open(path.string());
    if (!in) return Error{where + ": " + OIIO::geterror()};
    const OIIO::ImageSpec spec = in->spec();
    if (spec.width != width || spec.height != height)
        return Error{where + " is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                     " but the normal map is " + std::to_string(width) + "x" + std::to_string(height)};
    const int cv = spec.channelindex("value"), cc = spec.channelindex("coverage");
    if (cv < 0 || cc < 0) return Error{where + ": no 'value' and 'coverage' channels"};
    const int nch = spec.nchannels;
    std::vector<float> pixels(size_t(width) * size_t(height) * size_t(nch));
    if (!in->read_image(0, 0, 0, nch, OIIO::TypeDesc::FLOAT, pixels.data()))
        return Error{where + ": " + in->geterror()};
    auto layer = PaintLayer::create(kind, width, height);
    if (!layer) return Error{where + ": " + layer.error()};
    layer.value().allocate();
    for (size_t i = 0; i < layer->texelCount(); ++i) {
        const float v = pixels[i * size_t(nch) + size_t(cv)], c = pixels[i * size_t(nch) + size_t(cc)];
        if (!(v >= 0.0f && v <= 1.0f) || !(c >= 0.0f && c <= 1.0f))
            return Error{where + ": texel " + std::to_string(i) + " holds a value outside [0, 1]"};
        layer.value().value[i] = v;
        layer.value().coverage[i] = c;
    }
    return layer;
}

} // namespace burnish
