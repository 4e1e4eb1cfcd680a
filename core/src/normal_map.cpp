#include <burnish/core/normal_map.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
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

bool anyNegative(const Image& image, int channels) {
    for (size_t i = 0; i < image.texelCount(); ++i)
        for (int c = 0; c < channels; ++c)
            if (image.pixels[i * static_cast<size_t>(image.channels) + static_cast<size_t>(c)] < -1e-6f)
                return true;
    return false;
}

bool channelConstant(const Image& image, int channel) {
    const float first = image.pixels[static_cast<size_t>(channel)];
    for (size_t i = 0; i < image.texelCount(); ++i)
        if (image.pixels[i * static_cast<size_t>(image.channels) + static_cast<size_t>(channel)] != first)
            return false;
    return true;
}

} // namespace

Result<NormalMap> decodeNormalMap(const Image& image, const NormalMapOptions& options) {
    const std::string name = image.source.path.empty() ? std::string("image") : "'" + image.source.path + "'";
    if (image.width <= 0 || image.height <= 0 || image.texelCount() == 0)
        return Error{name + " has no pixels"};
    if (image.channels < 2)
        return Error{name + " has " + std::to_string(image.channels) +
                     " channel; a normal map needs 2 (RG) to 4 (RGBA) — is this a height or gloss map?"};

    NormalMap map;
    map.width = image.width;
    map.height = image.height;
    map.source = image.source;
    NormalMapDiagnostics& diag = map.diagnostics;
    diag.texels = image.texelCount();

    bool rg = options.layout == NormalLayout::Rg || image.channels == 2;
    if (options.layout == NormalLayout::Rgb && image.channels == 2)
        return Error{name + " has 2 channels; it cannot be read with the RGB layout (use RG)"};
    if (options.layout == NormalLayout::Auto && image.channels >= 3 && channelConstant(image, 2) &&
        !(channelConstant(image, 0) && channelConstant(image, 1))) {
        // A constant blue channel beside varying red/green is a two-channel (BC5/3Dc-style) map
        // saved as RGB: rebuild z instead of reading the constant.
        rg = true;
        diag.warnings.push_back("blue channel is constant: read as a two-channel map with z rebuilt");
    }
    diag.zRebuilt = rg;
    diag.alphaIgnored = image.channels == 4;
    diag.greenFlipped = options.green == GreenConvention::DirectX;

    const int used = rg ? 2 : 3;
    bool isSigned = options.encoding == NormalValueEncoding::Signed;
    if (options.encoding == NormalValueEncoding::Auto)
        isSigned = image.source.isFloat && anyNegative(image, used);
    diag.signedValues = isSigned;

    map.normals.resize(image.texelCount());
    // Decoded in parallel over fixed blocks of texels; each block's counts and length sum are
    // added in block order, so the diagnostics do not depend on the thread count.
    struct BlockTally {
        double lengthSum = 0.0;
        size_t nonFinite = 0, offLength = 0, negativeZ = 0, zeroLength = 0;
    };
    constexpr size_t kBlock = size_t(1) << 16;
    const size_t texels = image.texelCount();
    std::vector<BlockTally> tallies((texels + kBlock - 1) / kBlock);
    const size_t stride = static_cast<size_t>(image.channels);
    const bool greenFlipped = diag.greenFlipped;
    tbb::parallel_for(size_t(0), tallies.size(), [&](size_t block) {
        BlockTally& tally = tallies[block];
        const size_t end = std::min(texels, (block + 1) * kBlock);
        for (size_t i = block * kBlock; i < end; ++i) {
            const float* p = &image.pixels[i * stride];
            double v[3] = {p[0], p[1], rg ? 0.0 : p[2]};
            bool finite = true;
            for (int c = 0; c < used; ++c) {
                if (!std::isfinite(v[c])) finite = false;
                if (!isSigned) v[c] = 2.0 * v[c] - 1.0;
            }
            if (!finite) {
                ++tally.nonFinite;
                map.normals[i] = kFlat;
                continue;
            }
            if (greenFlipped) v[1] = -v[1];
            if (rg) {
                const double r2 = v[0] * v[0] + v[1] * v[1];
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
                map.normals[i] = kFlat;
                continue;
            }
            const double s = options.renormalize ? 1.0 / len : 1.0;
            map.normals[i] = glm::vec3(float(v[0] * s), float(v[1] * s), float(v[2] * s));
        }
    });
    double lengthSum = 0.0;
    for (const BlockTally& tally : tallies) {
        lengthSum += tally.lengthSum;
        diag.nonFiniteTexels += tally.nonFinite;
        diag.offLengthTexels += tally.offLength;
        diag.negativeZTexels += tally.negativeZ;
        diag.zeroLengthTexels += tally.zeroLength;
    }
    const size_t valid = diag.texels - diag.nonFiniteTexels;
    if (!rg && valid > 0) diag.meanStoredLength = lengthSum / static_cast<double>(valid);

    if (diag.nonFiniteTexels > 0)
        diag.warnings.push_back(std::to_string(diag.nonFiniteTexels) +
                                " texels were NaN or infinite and were replaced by a flat normal");
    if (diag.zeroLengthTexels > 0)
        diag.warnings.push_back(std::to_string(diag.zeroLengthTexels) +
                                " texels decoded to a zero-length vector and were replaced by a flat normal");
    if (valid == 0) return Error{name + " has no finite texels"};

    // Plausibility: tangent-space normal maps store unit vectors that face +z.
    std::string implausible;
    if (static_cast<double>(diag.negativeZTexels) > kMaxNegativeZFraction * static_cast<double>(valid))
        implausible = percent(diag.negativeZTexels, valid) +
                      " of texels point below the surface (z < 0); tangent-space normal maps face +z";
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
        if (!options.allowImplausible) return Error{what + " (a photo, height map or object-space map?)"};
        diag.warnings.push_back(what);
    }
    return map;
}

Result<NormalMap> loadNormalMap(const std::filesystem::path& path, const NormalMapOptions& options) {
    auto image = readImage(path);
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
