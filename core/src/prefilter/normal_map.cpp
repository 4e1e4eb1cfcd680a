#include <burnish/core/prefilter/normal_map.h>

#include "io/image_read.h"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

namespace burnish {

namespace {

// Vectors shorter than this after decoding carry no direction (e.g. a mid-grey texel).
constexpr double kMinDecodedLength = 1e-4;
const glm::vec3 kFlat(0.0f, 0.0f, 1.0f);

std::string percent(size_t count, size_t total) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f%%", 100.0 * static_cast<double>(count) / static_cast<double>(total));
    return buf;
}

/// Whether any finite texel has a negative value in its first `channels` channels. Texels with a
/// NaN or infinite channel are left out: the decoder replaces them, and one -Inf must not turn a
/// whole unsigned map signed.
bool anyNegative(const Image& image, int channels) {
    for (size_t i = 0; i < image.texelCount(); ++i) {
        const float* texel = image.pixels.data() + i * static_cast<size_t>(image.channels);
        bool finite = true, negative = false;
        for (int c = 0; c < channels; ++c) {
            finite = finite && std::isfinite(texel[c]);
            negative = negative || texel[c] < -1e-6f;
        }
        if (finite && negative) return true;
    }
    return false;
}

// Sample `channel` of every texel equals the first texel's; `sample(i)` gives sample i.
template <class Sample> bool channelConstant(const Sample& sample, size_t texels, int channels, int channel) {
    const float first = sample(size_t(channel));
    for (size_t i = 0; i < texels; ++i)
        if (sample(i * size_t(channels) + size_t(channel)) != first) return false;
    return true;
}

// Texels are decoded in fixed blocks; each block's counts and length sum are added in block order,
// so the diagnostics depend neither on the thread count nor on how the rows arrived.
constexpr size_t kBlock = size_t(1) << 16;

struct BlockTally {
    double lengthSum = 0.0;
    size_t nonFinite = 0, offLength = 0, negativeZ = 0, zeroLength = 0, noData = 0;
};

// A texel without data holds this until fillNoData gives it its nearest texel's normal: no decoded
// normal is (0, 0, 0) (zero lengths become flat).
const glm::vec3 kNoData(0.0f);

/// How the stored values become normals, decided before any texel is decoded.
struct DecodeSettings {
    bool rg = false;
    bool isSigned = false;
    bool greenFlipped = false;
    bool renormalize = true;
    size_t stride = 0; // samples per texel
};

/// Decodes texels [begin, end): `sample(i)` gives sample i of the image as a float.
template <class Sample>
void decodeTexels(const Sample& sample, size_t begin, size_t end, const DecodeSettings& settings,
                  glm::vec3* normals, BlockTally& tally) {
    const bool rg = settings.rg;
    const int used = rg ? 2 : 3;
    for (size_t i = begin; i < end; ++i) {
        const size_t first = i * settings.stride;
        double v[3] = {sample(first), sample(first + 1), rg ? 0.0 : sample(first + 2)};
        bool finite = true;
        for (int c = 0; c < used; ++c) {
            if (!std::isfinite(v[c])) finite = false;
            if (!settings.isSigned) v[c] = 2.0 * v[c] - 1.0;
        }
        if (!finite) {
            ++tally.nonFinite;
            normals[i] = kFlat;
            continue;
        }
        // No data: every used channel stored as 0 in an unsigned map (an atlas's transparent
        // padding, RGBA 0, 0, 0, 0), which decodes to (-1, -1, -1), a vector no surface has. Left out
        // of the tallies (the plausibility test), filled afterwards (fillNoData).
        if (!settings.isSigned && v[0] == -1.0 && v[1] == -1.0 && (rg || v[2] == -1.0)) {
            ++tally.noData;
            normals[i] = kNoData;
            continue;
        }
        if (settings.greenFlipped) v[1] = -v[1];
        if (rg) {
            const double r2 = v[0] * v[0] + v[1] * v[1];
            // A stored (x, y) longer than 1 is no unit vector's projection: as bad as an RGB vector
            // of the wrong length.
            if (r2 > (1.0 + kOffLengthTolerance) * (1.0 + kOffLengthTolerance)) ++tally.offLength;
            if (r2 > 1.0) {
                const double s = 1.0 / std::sqrt(r2);
                v[0] *= s;
                v[1] *= s;
            }
            v[2] = std::sqrt(std::max(0.0, 1.0 - v[0] * v[0] - v[1] * v[1]));
        }
        const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!rg) {
            tally.lengthSum += len;
            if (std::abs(len - 1.0) > kOffLengthTolerance) ++tally.offLength;
        }
        if (v[2] < 0.0) ++tally.negativeZ;
        if (len < kMinDecodedLength) {
            ++tally.zeroLength;
            normals[i] = kFlat;
            continue;
        }
        const double s = settings.renormalize ? 1.0 / len : 1.0;
        normals[i] = glm::vec3(float(v[0] * s), float(v[1] * s), float(v[2] * s));
    }
}

std::string displayName(const ImageSourceInfo& source) {
    return source.path.empty() ? std::string("image") : "'" + source.path + "'";
}

/// The checks and settings that need no texel: channel counts, a forced layout, the green
/// convention. The auto layout's constant-blue test and the signed test are the caller's.
Result<NormalMap> startDecode(int width, int height, int channels, const ImageSourceInfo& source,
                              const NormalMapOptions& options) {
    const std::string name = displayName(source);
    if (width <= 0 || height <= 0) return Error{name + " has no pixels"};
    if (channels < 2)
        return Error{name + " has " + std::to_string(channels) +
                     " channel; a normal map needs 2 (RG) to 4 (RGBA) — is this a height or gloss map?"};
    if (options.layout == NormalLayout::Rgb && channels == 2)
        return Error{name + " has 2 channels; it cannot be read with the RGB layout (use RG)"};
    NormalMap map;
    map.width = width;
    map.height = height;
    map.source = source;
    map.diagnostics.texels = size_t(width) * size_t(height);
    map.diagnostics.alphaIgnored = channels == 4;
    map.diagnostics.greenFlipped = options.green == GreenConvention::DirectX;
    return map;
}

/// Whether an auto layout reads a 3/4-channel map as RG: a constant blue channel beside varying
/// red/green is a two-channel (BC5/3Dc-style) map saved as RGB.
bool autoCandidate(int channels, const NormalMapOptions& options) {
    return options.layout == NormalLayout::Auto && channels >= 3;
}

/// The settings both decoders start from: RG when forced or for 2 channels (the auto layout's
/// constant-blue test may still switch it), signed only when asked (decodeNormalMap also detects
/// signed float images).
DecodeSettings initialSettings(int channels, const NormalMapOptions& options,
                               const NormalMapDiagnostics& diag) {
    DecodeSettings settings;
    settings.rg = options.layout == NormalLayout::Rg || channels == 2;
    settings.isSigned = options.encoding == NormalValueEncoding::Signed;
    settings.greenFlipped = diag.greenFlipped;
    settings.renormalize = options.renormalize;
    settings.stride = size_t(channels);
    return settings;
}

void setLayout(NormalMap& map, bool rg, bool constantBlue) {
    if (constantBlue)
        map.diagnostics.warnings.push_back(
            "blue channel is constant: read as a two-channel map with z rebuilt");
    map.diagnostics.zRebuilt = rg;
}

/// Gives every texel without data (kNoData) the normal of its nearest texel with data, by a
/// breadth-first walk over the 4-neighbours from the texels with data (ties go to the texel met
/// first in row order): what texture tools' padding dilation does, so filtering across an atlas's
/// edge blends in the neighbouring surface, never a direction no surface has.
void fillNoData(NormalMap& map) {
    const size_t w = size_t(map.width), h = size_t(map.height);
    std::vector<std::uint32_t> queue;
    auto hole = [&](size_t i) { return map.normals[i] == kNoData; };
    auto neighbours = [&](size_t i, auto&& visit) {
        const size_t x = i % w, y = i / w;
        if (x > 0) visit(i - 1);
        if (x + 1 < w) visit(i + 1);
        if (y > 0) visit(i - w);
        if (y + 1 < h) visit(i + w);
    };
    for (size_t i = 0; i < w * h; ++i) {
        if (hole(i)) continue;
        bool edge = false;
        neighbours(i, [&](size_t j) { edge = edge || hole(j); });
        if (edge) queue.push_back(std::uint32_t(i));
    }
    for (size_t head = 0; head < queue.size(); ++head) {
        const size_t i = queue[head];
        neighbours(i, [&](size_t j) {
            if (!hole(j)) return;
            map.normals[j] = map.normals[i];
            queue.push_back(std::uint32_t(j));
        });
    }
}

/// Adds the block tallies up in block order and applies the plausibility check.
Result<NormalMap> finishDecode(NormalMap map, const std::vector<BlockTally>& tallies,
                               const NormalMapOptions& options) {
    NormalMapDiagnostics& diag = map.diagnostics;
    const bool rg = diag.zRebuilt;
    const std::string name = displayName(map.source);
    double lengthSum = 0.0;
    for (const BlockTally& tally : tallies) {
        lengthSum += tally.lengthSum;
        diag.nonFiniteTexels += tally.nonFinite;
        diag.offLengthTexels += tally.offLength;
        diag.negativeZTexels += tally.negativeZ;
        diag.zeroLengthTexels += tally.zeroLength;
        diag.noDataTexels += tally.noData;
    }
    // Texels without data are not the map's: the plausibility test counts the others.
    const size_t valid = diag.texels - diag.nonFiniteTexels - diag.noDataTexels;
    if (!rg && valid > 0) diag.meanStoredLength = lengthSum / static_cast<double>(valid);

    if (diag.nonFiniteTexels > 0)
        diag.warnings.push_back(std::to_string(diag.nonFiniteTexels) +
                                " texels were NaN or infinite and were replaced by a flat normal");
    if (diag.zeroLengthTexels > 0)
        diag.warnings.push_back(std::to_string(diag.zeroLengthTexels) +
                                " texels decoded to a zero-length vector and were replaced by a flat normal");
    if (diag.noDataTexels > 0 && diag.noDataTexels < diag.texels) {
        diag.warnings.push_back(
            std::to_string(diag.noDataTexels) +
            " texels hold no data (stored 0, as an atlas's transparent padding): left out of "
            "the plausibility test and filled with the nearest texel's normal");
        fillNoData(map);
    }
    if (diag.noDataTexels == diag.texels)
        return Error{name + " holds no normals: every texel is stored as 0"};
    if (valid == 0) return Error{name + " has no finite texels"};

    // Plausibility: tangent-space normal maps store unit vectors that face +z.
    std::string implausible;
    if (static_cast<double>(diag.negativeZTexels) > kMaxNegativeZFraction * static_cast<double>(valid))
        implausible = percent(diag.negativeZTexels, valid) +
                      " of texels point below the surface (z < 0); tangent-space normal maps face +z";
    else if (rg &&
             static_cast<double>(diag.offLengthTexels) > kMaxOffLengthFraction * static_cast<double>(valid))
        implausible =
            percent(diag.offLengthTexels, valid) +
            " of texels store (x, y) longer than 1 by more than 25% (x^2 + y^2 > 1.56), which no unit "
            "normal has";
    else if (!rg &&
             static_cast<double>(diag.offLengthTexels) > kMaxOffLengthFraction * static_cast<double>(valid)) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.3f", diag.meanStoredLength);
        implausible = percent(diag.offLengthTexels, valid) +
                      " of texels store vectors whose length is off 1 by more than 25% (mean length " + buf +
                      ")";
    }
    if (!implausible.empty()) {
        const std::string what = name + " does not look like a tangent-space normal map: " + implausible;
        const std::string refusal = what + " (a photo, height map or object-space map?)";
        if (!options.allowImplausible) return Error{refusal};
        diag.implausible = refusal;
        diag.warnings.push_back(what);
    }
    return map;
}

/// An 8/16-bit PNG decoded straight into normals: each block of texels is decoded on the other
/// cores as soon as the rows under it are final, from the stored codes through OpenImageIO's
/// table, so the normals are bit for bit decodeNormalMap(readImage(...))'s without a float copy of
/// the image. nullopt: not a PNG core's decoder reads (the caller falls back).
std::optional<Result<NormalMap>> loadPngNormalMap(const OpenedImage& opened,
                                                  const NormalMapOptions& options) {
    if (opened.source.formatName != "png" || opened.bitDepth == 0) return std::nullopt;
    auto started = startDecode(opened.width, opened.height, opened.channels, opened.source, options);
    if (!started) return Result<NormalMap>(Error{started.error()});
    NormalMap map = std::move(started).value();
    const size_t texels = map.diagnostics.texels;
    const int channels = opened.channels;
    try {
        map.normals.resize(texels);
    } catch (const std::bad_alloc&) {
        return Result<NormalMap>(Error{"not enough memory to read image '" + opened.path.string() + "'"});
    }

    // Integer files are unsigned unless the caller says otherwise (decodeNormalMap's rule).
    DecodeSettings settings = initialSettings(channels, options, map.diagnostics);

    PngCodes codes;
    const std::vector<float>& table = opened.table;
    auto sample = [&](size_t i) { return table[codes.code(i)]; };
    std::vector<BlockTally> tallies((texels + kBlock - 1) / kBlock);
    tbb::task_group decoding;
    size_t launched = 0;
    auto launchBlocks = [&](size_t finalTexels) {
        for (; launched < tallies.size() && std::min(texels, (launched + 1) * kBlock) <= finalTexels;
             ++launched)
            decoding.run([&, block = launched] {
                decodeTexels(sample, block * kBlock, std::min(texels, (block + 1) * kBlock), settings,
                             map.normals.data(), tallies[block]);
            });
    };
    // The auto layout waits for a blue sample that differs from the first (usually in the first
    // row); until then nothing is decoded, and if none does, the decision is made at the end.
    bool decided = !autoCandidate(channels, options);
    size_t blueChecked = 0; // texels whose blue sample was compared
    auto rowsDone = [&](int, int y1) {
        const size_t finalTexels = size_t(y1) * size_t(opened.width);
        if (!decided) {
            const float firstBlue = sample(2);
            for (; blueChecked < finalTexels && !decided; ++blueChecked)
                decided = sample(blueChecked * size_t(channels) + 2) != firstBlue;
            if (!decided) return;
        }
        launchBlocks(finalTexels);
    };
    auto status = readPngCodes(opened, codes, rowsDone);
    if (!status || !*status) {
        decoding.wait();
        if (!status) return std::nullopt;
        return Result<NormalMap>(Error{status->error()});
    }
    // Every blue sample equal: RG when red or green varies.
    const bool constantBlue = !decided && !(channelConstant(sample, texels, channels, 0) &&
                                            channelConstant(sample, texels, channels, 1));
    if (constantBlue) settings.rg = true;
    setLayout(map, settings.rg, constantBlue);
    launchBlocks(texels);
    decoding.wait();
    map.diagnostics.signedValues = settings.isSigned;
    return finishDecode(std::move(map), tallies, options);
}

} // namespace

Result<NormalMap> decodeNormalMap(const Image& image, const NormalMapOptions& options) {
    if (image.texelCount() == 0) return Error{displayName(image.source) + " has no pixels"};
    auto started = startDecode(image.width, image.height, image.channels, image.source, options);
    if (!started) return Error{started.error()};
    NormalMap map = std::move(started).value();
    auto sample = [&image](size_t i) { return image.pixels[i]; };
    const size_t texels = image.texelCount();

    DecodeSettings settings = initialSettings(image.channels, options, map.diagnostics);
    const bool constantBlue = autoCandidate(image.channels, options) &&
                              channelConstant(sample, texels, image.channels, 2) &&
                              !(channelConstant(sample, texels, image.channels, 0) &&
                                channelConstant(sample, texels, image.channels, 1));
    if (constantBlue) settings.rg = true;
    setLayout(map, settings.rg, constantBlue);
    if (options.encoding == NormalValueEncoding::Auto)
        settings.isSigned = image.source.isFloat && anyNegative(image, settings.rg ? 2 : 3);
    map.diagnostics.signedValues = settings.isSigned;

    map.normals.resize(texels);
    std::vector<BlockTally> tallies((texels + kBlock - 1) / kBlock);
    tbb::parallel_for(size_t(0), tallies.size(), [&](size_t block) {
        decodeTexels(sample, block * kBlock, std::min(texels, (block + 1) * kBlock), settings,
                     map.normals.data(), tallies[block]);
    });
    return finishDecode(std::move(map), tallies, options);
}

Result<NormalMap> loadNormalMap(const std::filesystem::path& path, const NormalMapOptions& options) {
    auto opened = openImage(path);
    if (!opened) return Error{opened.error()};
    if (auto fast = loadPngNormalMap(*opened, options)) return std::move(*fast);
    auto image = readOpenedImage(std::move(opened).value());
    if (!image) return Error{image.error()};
    return decodeNormalMap(*image, options);
}

NormalMap makeNormalMap(int width, int height, std::vector<glm::vec3> normals) {
    NormalMap map;
    map.width = width;
    map.height = height;
    map.normals.assign(normals.begin(), normals.end());
    map.diagnostics.texels = map.normals.size();
    for (auto& n : map.normals) {
        const float len = glm::length(n);
        n = (std::isfinite(len) && len > float(kMinDecodedLength)) ? n / len : kFlat;
    }
    return map;
}

} // namespace burnish
