// The bake: a normal map (plus an optional authored gloss map) through the normal pyramid and a
// prefiltering method into the textures, with full mip chains, that the method's shader reads.
// Values are returned as stored in an unsigned texture channel, in [0, 1], with the decode rule
// for each channel; writing them to files is export.h's job. Deterministic: the same inputs and
// options give the same values, bit for bit, on any thread count.
#pragma once

#include <burnish/core/io/texel_codes.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/prefilter/normal_pyramid.h>
#include <burnish/core/util/result.h>
#include <burnish/core/util/texel_vector.h>

#include <Imath/half.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace burnish {

/// How a baked texture holds its values. Float is what the renderer and the studio read; an export
/// whose files store a texture only as 8- or 16-bit codes or as half floats has the bake keep just
/// those (a quarter or half of the memory), converted as the export would (unormCode; Imath's
/// round-to-nearest-even half of the value clamped to [0, 1], what OpenImageIO writes).
enum class TexelStorage { Float, Unorm8, Unorm16, Half };

/// halfCode(v).bits() of each of `count` values, eight at a time: the same bits (tested over the
/// floats of [0, 1], -0, values outside and NaN). By the CPU's F16C conversion where it has one, else
/// by portableHalfCodes.
void halfCodes(const float* values, size_t count, std::uint16_t* bits);
/// halfCodes without F16C: integer lanes on the floats' bits (the same bits).
void portableHalfCodes(const float* values, size_t count, std::uint16_t* bits);

struct TextureMip {
    int width = 0;
    int height = 0;
    TexelVector texels; // row-major, `channels` per texel, each in [0, 1] (TexelStorage::Float)
    std::vector<std::uint8_t, TexelAllocator<std::uint8_t>> unorm8 = {};     // TexelStorage::Unorm8 codes
    std::vector<std::uint16_t, TexelAllocator<std::uint16_t>> unorm16 = {};  // TexelStorage::Unorm16's codes
    std::vector<std::uint16_t, TexelAllocator<std::uint16_t>> halfBits = {}; // TexelStorage::Half's bits
};

/// How a stored channel decodes to its physical value: value = stored·scale + bias.
struct ChannelDecode {
    std::string name; // "normal.x", "gloss", "B.x", "M.xx", ...
    double scale = 1.0;
    double bias = 0.0;
};

/// The decode of each channel of a texture row under the bake's scales (the table's channel names).
std::vector<ChannelDecode> textureDecode(TextureRole role, const ChannelScales& scales);

struct BakedTexture {
    TextureRole role = TextureRole::Normal; // its row in the method table (methods.h)
    std::string description;
    int channels = 0;
    std::vector<ChannelDecode> decode;
    /// Needs 16-bit or float storage to keep the method's accuracy (LEAN's second moments).
    bool needsHighPrecision = false;
    /// Which of the mips' arrays holds the values.
    TexelStorage storage = TexelStorage::Float;
    std::vector<TextureMip> mips;
};

struct BakeOptions {
    Method method = Method::VarianceToGloss;
    /// Encoding of the authored gloss input and of every gloss channel written.
    GlossEncoding encoding = GlossEncoding::blackOps();
    /// Authored power when there is no gloss map.
    double basePower = 1024.0;
    /// Authored gloss per finest texel, in `encoding` (size = the normal map's texel count).
    std::optional<std::vector<float>> authoredGloss;
    PyramidOptions pyramid{BorderMode::Wrap, FilterKernel::Tent};
    MethodParams params;
    /// Number of mip levels to produce (0 = all, down to 1×1).
    int mipCount = 0;
    /// Levels wider or taller than this (never the last one) are not computed: each keeps its size
    /// and no texels. For a viewer that draws from the first level no larger (the studio's viewport,
    /// render::Renderer::setMaxTextureSize): an 8192² map's method or gloss change then computes a
    /// sixteenth of the texels. Every level computed is the same as in a full bake. 0: every level.
    int largestLevel = 0;
    /// Only the textures of these roles are produced (the ones an export's files read); all of
    /// the method's when unset. Each texture produced is the same whatever the others are.
    std::optional<std::vector<TextureRole>> roles;
    /// Roles to keep as 8- or 16-bit codes or half floats instead of floats (compactStorage of
    /// export.h names the ones an export allows); every other role is float.
    std::map<TextureRole, TexelStorage> storage;
    /// Called on the bake's thread once the pyramids are built and after each level, with the
    /// fraction done (by texels: the pyramids count as the finest level's texels, a cachedPyramid as
    /// none); returning false stops the bake, which then fails with "cancelled". Empty: the bake runs
    /// to the end.
    std::function<bool(double fraction)> progress;
    /// A normal pyramid of this map (the same NormalMap object) with the options' border and kernel
    /// and at least the moments the method reads, to bake from instead of building one: what
    /// bakePyramid makes for a viewer that bakes one map again and again (a gloss or method change).
    /// Only its levels the bake computes are read; the output is the same as without it.
    std::shared_ptr<const NormalPyramid> cachedPyramid;
};

/// A pyramid for BakeOptions::cachedPyramid with the moments `moments` (MomentSet flags; all of them
/// serve every method), the levels larger than options.largestLevel released once built (a viewer's
/// bakes never read them: at 8192² with a 2048 cap it keeps 0.3 GB instead of 1.3 GB). It holds `map`.
std::shared_ptr<const NormalPyramid> bakePyramid(std::shared_ptr<const NormalMap> map,
                                                 const BakeOptions& options, unsigned moments = kMomentsAll);

struct BakeStats {
    int mipCount = 0;
    /// Texels whose lobe power fell outside the gloss encoding's range and were clamped to it.
    size_t glossClampedLow = 0;
    size_t glossClampedHigh = 0;
    double pyramidSeconds = 0.0;
    double methodSeconds = 0.0;
};

struct BakeOutput {
    Method method = Method::Naive;
    std::vector<BakedTexture> textures;
    BakeStats stats;
    const BakedTexture* find(TextureRole role) const;
};

/// Bakes the method's textures. Errors: an authored gloss map of the wrong size or with
/// non-finite values, a non-positive base power.
Result<BakeOutput> bake(const NormalMap& map, const BakeOptions& options);

/// The textures a bake with `options` of a width×height map holds — roles, channels, decode
/// rules and mip sizes — without their texels (and with decode scales of a flat map), from the
/// method table without baking anything: what planExport needs to name a job's files before anything
/// is baked. Errors as bake()'s options.
Result<BakeOutput> bakeShape(const BakeOptions& options, int width, int height);

/// The fraction of an image's texels whose first three channels, read as unsigned normals (2v − 1),
/// are unit vectors (within 0.1) facing up; 0 for fewer than 3 channels or a grey image (mean |R − B|
/// under 0.1).
double normalLikeFraction(const Image& image);
/// From this normalLikeFraction on an image is taken for a normal map: real ones score 0.97–1 (8-bit
/// rounding and steep texels aside), colour images and packed channel maps far less.
inline constexpr double kNormalLikeFraction = 0.9;

/// The authored gloss channel of an image (first channel, or the luminance-free first channel of
/// a grey image), checked against the normal map's size. Errors: another size, a NaN or infinite
/// texel, an image that looks like a tangent-space normal map (normalLikeFraction).
Result<std::vector<float>> glossFromImage(const Image& image, int width, int height);

} // namespace burnish
