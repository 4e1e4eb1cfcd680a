// Painting authored gloss and a variance offset: paint layers with coverage, brush dabs (size,
// hardness, opacity, smooth falloff, wrap-around for tiling maps), strokes interpolated between
// mouse events, the dirty rectangle, the painted layers composited into the authored gloss, the
// baked gloss chain recomputed only where a stroke changed it (rebakeRegion, bit-identical to a
// full bake), and the over-shine measure: where painted gloss asks for more shine than the normal
// variance at a mip permits, which brings the aliasing back.
//
// Coordinates: texel (x, y) covers [x, x+1) × [y, y+1), so its centre is (x + 0.5, y + 0.5); row 0
// is the top row, as in NormalMap and Image.
#pragma once

#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/base_variance.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/prefilter/normal_pyramid.h>
#include <burnish/core/util/result.h>

#include <glm/vec2.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace burnish {

/// What a layer's values mean.
enum class PaintLayerKind {
    /// Gloss in the preset's encoding, [0, 1]: replaces the authored gloss where painted.
    Gloss,
    /// A variance, [0, 1], added to the authored gloss as 1/(n+1) (Lazarov 2011's variance-to-gloss
    /// step): paints roughness on top of the gloss. Only adds: a negative variance has no meaning.
    VarianceOffset,
};

/// "gloss" or "variance-offset".
std::string_view paintLayerName(PaintLayerKind kind);

/// One painted layer: a value and a coverage per texel of the normal map, both in [0, 1]. Where
/// coverage is 0 nothing was painted; in between, the value is blended over what lies below.
/// The arrays are allocated when something is first painted or written (allocate()): until then
/// both are empty and every texel reads 0 (valueAt, coverageAt), so an unpainted layer of an 8192²
/// map costs nothing instead of 512 MB.
struct PaintLayer {
    PaintLayerKind kind = PaintLayerKind::Gloss;
    int width = 0;
    int height = 0;
    std::vector<float> value;    // texelCount() entries once allocated, else empty
    std::vector<float> coverage; // likewise

    /// An empty (unpainted, unallocated) layer. Errors: a non-positive or too large size (kMaxImageSide).
    static Result<PaintLayer> create(PaintLayerKind kind, int width, int height);
    size_t texelCount() const { return size_t(width) * size_t(height); }
    size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
    bool allocated() const { return !coverage.empty(); }
    /// The arrays, zero-filled, if they are not there yet (before writing texels directly).
    void allocate();
    float valueAt(size_t i) const { return value.empty() ? 0.0f : value[i]; }
    float coverageAt(size_t i) const { return coverage.empty() ? 0.0f : coverage[i]; }
    /// True when any texel has a coverage above 0.
    bool painted() const;
    /// Back to unpainted (value and coverage 0), the arrays freed.
    void clear();
};

/// Whether two layers hold the same kind, size and texels, bit for bit (an unallocated layer reads 0).
bool samePaint(const PaintLayer& a, const PaintLayer& b);

/// The bounding rectangle of the texels whose value or coverage is not +0 (empty for an unpainted
/// layer): what clearing the layer changes, so its undo step stores that rectangle, not the layer.
TexelRect paintedBounds(const PaintLayer& layer);

/// The layer at another size, over the same UV square (a normal map of another size was loaded):
/// each new texel is the area-weighted mean of the old texels its square covers, coverage and
/// coverage·value averaged separately (so unpainted texels do not darken the paint beside them).
/// Enlarging by a whole factor copies each texel into its block, and shrinking back gives the
/// layer again exactly. Errors: those of PaintLayer::create.
Result<PaintLayer> resamplePaintLayer(const PaintLayer& layer, int width, int height);

/// A rectangle of a layer's texels, before or after an edit (what an undo step stores).
struct PaintPatch {
    TexelRect rect;
    std::vector<float> value;    // rect's texels, row-major
    std::vector<float> coverage; // rect's texels, row-major
};

/// Copies a rectangle (clipped to the layer) out of a layer.
PaintPatch copyPatch(const PaintLayer& layer, const TexelRect& rect);
/// Writes a patch back. Errors: the patch does not fit the layer or its arrays the rectangle.
Status applyPatch(PaintLayer& layer, const PaintPatch& patch);

struct Brush {
    /// Radius in texels of the finest level, [kMinBrushRadius, kMaxBrushRadius].
    double radius = 16.0;
    /// Fraction of the radius painted at full strength, [0, 1]; the rest falls off smoothly
    /// (1 gives a hard edge).
    double hardness = 0.5;
    /// The most one stroke moves a texel towards the brush value, [0, 1]: overlapping dabs of a
    /// stroke take the strongest dab, not the sum, so a stroke never exceeds its opacity.
    double opacity = 1.0;
    /// The value painted, [0, 1] (gloss in the preset's encoding, or a variance).
    float value = 1.0f;
    /// Distance between dabs along a stroke, as a fraction of the radius, [kMinBrushSpacing, 4].
    double spacing = 0.25;
    /// Removes paint (lowers coverage) instead of adding it.
    bool erase = false;
};

/// Smallest brush radius: half a texel, so a dab always reaches the texel it is centred on.
inline constexpr double kMinBrushRadius = 0.5;
/// Largest brush radius: the largest map side, so a dab's texel span stays far inside int.
inline constexpr double kMaxBrushRadius = 65536.0;
/// Smallest dab spacing (fraction of the radius): bounds the dabs per stroke segment.
inline constexpr double kMinBrushSpacing = 0.01;

/// Checks a brush (finite values in their documented ranges).
Status validateBrush(const Brush& brush);

/// The brush's strength at `distance` texels from a dab's centre, before opacity: 1 inside
/// hardness·radius, a smoothstep down to 0 at the radius, 0 beyond. In [0, 1], non-increasing.
double brushFalloff(double distance, double radius, double hardness);

/// One stroke of a brush on a layer, from mouse-down to mouse-up. The layer is edited in place as
/// points arrive; the stroke remembers the layer as it was, so its undo patch is exact.
class PaintStroke {
public:
    /// Starts a stroke (nothing painted until the first point). Errors: an invalid brush.
    static Result<PaintStroke> begin(PaintLayer& layer, const Brush& brush, BorderMode border);

    /// The next point of the stroke, in texel coordinates (may lie outside the map: with Wrap it
    /// wraps around, with Clamp the part outside is dropped). The first point places a dab; later
    /// points place dabs every spacing·radius along the straight segment from the last dab, so the
    /// dab spacing does not depend on how fast the mouse moved. Errors: a non-finite point.
    Status addPoint(const glm::dvec2& point);

    /// Places a dab at `point` without joining it to the last one: a jump across a UV seam of a
    /// 3D model. The stroke goes on from there. Errors: a non-finite point.
    Status jumpTo(const glm::dvec2& point);

    /// The centres of the dabs placed so far, in the order placed.
    const std::vector<glm::dvec2>& dabs() const { return m_dabs; }
    /// Bounding rectangle of every texel the stroke changed (empty before the first dab).
    const TexelRect& dirty() const { return m_dirty; }
    /// The texels changed since the last call (for live updates while the stroke goes on).
    TexelRect takeRecentDirty();
    /// The layer inside dirty() as it was before the stroke, and as it is now.
    PaintPatch before() const;
    PaintPatch after() const;

private:
    PaintStroke(PaintLayer& layer, const Brush& brush, BorderMode border);
    void dab(const glm::dvec2& centre);

    // Per tile of kStrokeTile² texels, filled when a dab first reaches it: the tile's values and
    // coverage before the stroke, and the strongest dab weight per texel so far. A stroke's memory
    // follows what it touches, not the layer's size.
    static constexpr int kStrokeTile = 64;
    struct Tile {
        std::vector<float> value, coverage, strength; // empty until reached
    };
    Tile& tileAt(int x, int y);
    const Tile* touchedTile(int x, int y) const;

    PaintLayer* m_layer;
    Brush m_brush;
    BorderMode m_border;
    int m_tilesX = 0;
    std::vector<Tile> m_tiles;
    std::vector<glm::dvec2> m_dabs;
    std::optional<glm::dvec2> m_lastDab;
    TexelRect m_dirty;
    TexelRect m_recent;
};

/// The authored gloss after painting, for the texels of `region`: the base (the gloss map's
/// texel, or `baseGloss` where there is no map), the gloss layer blended over it by coverage (in
/// the encoding's gloss space), then the variance layer's coverage·value added as 1/(n+1)
/// (varianceToGloss: clamped to the encoding's power range). Texels outside `region` are left as
/// they are in `out`, which must hold width·height values. Either layer may be null. Errors:
/// sizes that do not match.
Status compositeAuthoredGloss(const std::vector<float>* glossMap, double baseGloss, const PaintLayer* gloss,
                              const PaintLayer* varianceOffset, const GlossEncoding& encoding, int width,
                              int height, const TexelRect& region, std::vector<float>& out);

/// The baked gloss chain of a bake, kept current while the authored gloss is painted: after
/// create(), gloss() equals bake(map, options).find("gloss") bit for bit, and after each
/// rebakeRegion() it equals the full bake of the new authored gloss, bit for bit, while only the
/// texels whose value can change are recomputed: at each level, the dirty rectangle's footprint
/// expanded by the pyramid kernel's radius (wrapping or clamped like the kernel).
///
/// The normal map does not change while painting, so the moments of its pyramid are read once,
/// at create(): per level and texel, the kernel-filtered projected variance (and |Na| for vMF),
/// 4–8 bytes a texel. The authored base variance 1/s is kept per level in double, as the bake
/// averages it.
class LiveGlossBake {
public:
    /// Bakes the full chain. `options.authoredGloss` must be set (the painted gloss, one value
    /// per texel of the map). Errors: those of bake(), and a method that stores no gloss texture
    /// (LEAN, CLEAN: their authored power lives in the moment textures).
    static Result<LiveGlossBake> create(std::shared_ptr<const NormalMap> map, const BakeOptions& options);

    /// The "gloss" texture, every mip.
    const BakedTexture& gloss() const { return m_gloss; }
    const std::vector<float>& authoredGloss() const { return m_authored; }
    int levelCount() const { return int(m_levels.size()); }
    int levelWidth(int k) const { return m_levels[size_t(k)].width; }
    int levelHeight(int k) const { return m_levels[size_t(k)].height; }
    int width() const { return m_levels.empty() ? 0 : m_levels[0].width; }
    int height() const { return m_levels.empty() ? 0 : m_levels[0].height; }
    const BakeOptions& options() const { return m_options; }

    /// Takes the authored gloss inside `dirty` (clipped to the map) from `authoredGloss` (the whole
    /// map's values; texels outside `dirty` are taken to be unchanged and are not read) and
    /// recomputes the chain there. Errors: a wrong size or a non-finite value inside `dirty`
    /// (nothing changes then).
    Status rebakeRegion(const std::vector<float>& authoredGloss, const TexelRect& dirty);
    /// Gloss texels recomputed by the last rebakeRegion, all levels together.
    size_t lastRecomputedTexels() const { return m_lastRecomputed; }
    /// Per level, the bounding rectangle of the texels the last rebakeRegion recomputed.
    const std::vector<TexelRect>& lastRecomputedRects() const { return m_lastRects; }

    /// The kernel-filtered projected variance at a texel of level k, as the bake reads it.
    float projectedVariance(int k, int x, int y) const;
    /// The level-k texel whose footprint holds finest texel (x, y).
    glm::ivec2 texelAtLevel(int k, int x, int y) const;

private:
    struct Level {
        int width = 0;
        int height = 0;
        std::vector<float> variance; // filtered projected variance
        std::vector<float> lengthNa; // filtered |Na| (vMF only)
    };

    float glossTexel(int k, int x, int y) const;
    /// Sorted distinct in-range indices of [lo, hi) after the border mapping.
    std::vector<int> borderRange(int lo, int hi, int size) const;

    BakeOptions m_options; // authoredGloss moved out into m_authored
    std::vector<float> m_authored;
    std::vector<Level> m_levels;
    BaseVariancePyramid m_base; // the authored 1/s, as bake() builds it
    BakedTexture m_gloss;
    size_t m_lastRecomputed = 0;
    std::vector<TexelRect> m_lastRects;
};

/// The over-shine measure at one mip: per finest texel, how far the painted power n exceeds the
/// power p the variance-to-gloss bake can deliver there, given the filtered normal variance v of
/// the mip-`mip` texel above it: stops = log2((n+1)/(p+1)) with p = 1/(v + 1/(n+1)) − 1, which is
/// log2(1 + v(n+1)). 1 stop is where the lobe's own variance 1/(n+1) equals the normal variance:
/// above it the painted gloss asks for more shine than the surface's normals permit at that
/// distance, and drawing it unadjusted aliases.
struct OverShineMap {
    int width = 0;
    int height = 0;
    int mip = 0;
    std::vector<float> stops;     // per finest texel, >= 0
    std::vector<uint8_t> flagged; // 1 where stops > threshold (and painted, when a mask is given)
    size_t flaggedCount = 0;      // finest texels flagged
    /// Per texel of level `mip` (mipWidth × mipHeight), how many finest texels under it are flagged, and
    /// how many of those texels have any: the count at the mip the measure names.
    int mipWidth = 0;
    int mipHeight = 0;
    std::vector<uint32_t> flaggedUnder;
    size_t flaggedMipTexels = 0;
};

/// Default over-shine threshold: 1 stop, where the painted lobe is narrower than the normal spread.
inline constexpr double kOverShineStops = 1.0;

/// What the authored gloss is without paint (the gloss map's values, or one base value): with it,
/// overShine flags only texels the paint made shinier — a stroke rougher than what it covers never
/// asks for shine the normals cannot give, however much the surface under it over-shines already.
struct UnpaintedGloss {
    const std::vector<float>* values = nullptr; // per texel, in the bake's encoding; null: `value`
    double value = 0.0;
    float at(size_t i) const { return values ? (*values)[i] : float(value); }
};

/// Computes (or, with `region`, updates inside it) the over-shine measure of `authoredGloss` (the
/// whole map, in the bake's encoding) at `mip` (clamped to the chain). With `paintedMask`, only
/// texels the mask's layer covers are flagged; with `unpainted`, only those whose painted power is
/// above the unpainted one. `inOut` is resized on a full computation. Errors: sizes that do not match.
Status overShine(const LiveGlossBake& bake, const std::vector<float>& authoredGloss, int mip,
                 double thresholdStops, const PaintLayer* paintedMask, OverShineMap& inOut,
                 const std::optional<TexelRect>& region = std::nullopt,
                 const std::optional<UnpaintedGloss>& unpainted = std::nullopt);

/// Writes a layer as a float EXR with channels "value" and "coverage", atomically (temporary
/// file and rename). Errors name the file.
Status writePaintLayerExr(const PaintLayer& layer, const std::filesystem::path& path);
/// Reads a layer written by writePaintLayerExr. Errors: unreadable file, missing channels, a
/// size other than width × height, values outside [0, 1] or not finite.
Result<PaintLayer> readPaintLayerExr(const std::filesystem::path& path, PaintLayerKind kind, int width,
                                     int height);

} // namespace burnish
