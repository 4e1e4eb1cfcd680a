// DDS output through NVIDIA Texture Tools 2.0: a texture's mip chain, block-compressed or not, collected
// in memory (the export stages and renames the bytes).
#include <burnish/core/io/dds.h>
#include <burnish/core/io/texel_codes.h>

#include "dds_dx10.h"

#include <nvtt/nvtt.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

namespace burnish {

namespace {

struct MemoryOutput final : nvtt::OutputHandler {
    std::string bytes;
    void beginImage(int, int, int, int, int, int) override {}
    bool writeData(const void* data, int size) override {
        if (size > 0) bytes.append(static_cast<const char*>(data), static_cast<size_t>(size));
        return true;
    }
};

struct ErrorCollector final : nvtt::ErrorHandler {
    std::string message;
    void error(nvtt::Error e) override {
        if (message.empty()) message = nvtt::errorString(e);
    }
};

nvtt::Format nvttFormat(DdsCompression compression) {
    switch (compression) {
    case DdsCompression::Bc4:
        return nvtt::Format_BC4;
    case DdsCompression::Bc5:
        return nvtt::Format_BC5;
    case DdsCompression::Bc3:
        return nvtt::Format_BC3;
    case DdsCompression::Rgba8:
    case DdsCompression::Rgba16f: // written by hand (encodeRgba16f)
        return nvtt::Format_RGBA;
    }
    return nvtt::Format_RGBA;
}

// Texels a block the encoders read and convert at a time: one block of floats is all they hold
// beside their output.
constexpr size_t kReadBlock = size_t(1) << 12;

// Calls fn(begin, end, values) for every block of level k's n texels, values holding the block's
// `channels` floats per texel as `read` gives them.
template <class Fn> void forEachBlock(const DdsLevelReader& read, size_t k, size_t n, int channels, Fn&& fn) {
    std::vector<float> block(kReadBlock * size_t(channels));
    for (size_t begin = 0; begin < n; begin += kReadBlock) {
        const size_t end = std::min(n, begin + kReadBlock);
        read(k, begin, end, block.data());
        fn(begin, end, block.data());
    }
}

// RGBA16F with a DX10 header, every level in order: the stored values in [0, 1] as half floats
// (missing colour channels 0, missing alpha 1), for moments that 8 bits would ruin.
std::string encodeRgba16f(const std::vector<std::pair<int, int>>& sizes, int channels,
                          const DdsLevelReader& read) {
    std::string s = dds::rgba16fHeader(std::uint32_t(sizes[0].first), std::uint32_t(sizes[0].second),
                                       std::uint32_t(sizes.size()), false);
    for (size_t k = 0; k < sizes.size(); ++k)
        forEachBlock(read, k, size_t(sizes[k].first) * size_t(sizes[k].second), channels,
                     [&](size_t begin, size_t end, const float* v) {
                         for (size_t t = 0; t < end - begin; ++t)
                             for (int c = 0; c < 4; ++c)
                                 dds::putHalf(
                                     s, c < channels
                                            ? std::clamp(v[t * size_t(channels) + size_t(c)], 0.0f, 1.0f)
                                            : (c == 3 ? 1.0f : 0.0f));
                     });
    return s;
}

} // namespace

std::vector<std::pair<int, int>> mipChainSizes(int width, int height, int mipCount) {
    std::vector<std::pair<int, int>> sizes;
    if (width < 1 || height < 1) return sizes;
    sizes.emplace_back(width, height);
    // The pyramid's rule (normal_pyramid.h): halve rounding down, at least 1, down to 1×1.
    while ((sizes.back().first > 1 || sizes.back().second > 1) &&
           (mipCount <= 0 || int(sizes.size()) < mipCount))
        sizes.emplace_back(std::max(1, sizes.back().first / 2), std::max(1, sizes.back().second / 2));
    return sizes;
}

Result<std::string> encodeDds(int width, int height, int levels, int channels, DdsCompression compression,
                              const DdsLevelReader& read) {
    if (levels < 1) return Error{"DDS: no mip levels to write"};
    if (channels < 1 || channels > 4) return Error{"DDS: a texture needs 1 to 4 channels"};
    if (compression == DdsCompression::Bc4 && channels != 1)
        return Error{"DDS: bc4 holds exactly one channel"};
    if (compression == DdsCompression::Bc5 && channels != 2)
        return Error{"DDS: bc5 holds exactly two channels"};
    // nvtt 2.0 takes int extents; DDS readers expect at most 16384 on a side (D3D11's limit).
    constexpr int kMaxDdsSide = 16384;
    if (width < 1 || height < 1 || width > kMaxDdsSide || height > kMaxDdsSide)
        return Error{"DDS: " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1..16384 on a side"};
    const std::vector<std::pair<int, int>> sizes = mipChainSizes(width, height, levels);
    if (int(sizes.size()) != levels)
        return Error{"DDS: " + std::to_string(levels) + " levels asked of a " + std::to_string(width) + "x" +
                     std::to_string(height) + " chain of " + std::to_string(sizes.size())};

    if (compression == DdsCompression::Rgba16f) return encodeRgba16f(sizes, channels, read);
    nvtt::InputOptions input;
    input.setTextureLayout(nvtt::TextureType_2D, width, height);
    input.setFormat(nvtt::InputFormat_BGRA_8UB);
    // nvtt 2.0 writes only the top level when mipmap generation is off; with it on, a level given
    // through setMipmapData (matched by exact size) is used as is and nothing is generated.
    // maxLevel stops the chain where the bake's stops.
    input.setMipmapGeneration(true, levels - 1);
    input.setNormalMap(false);  // no renormalization: the bake's values are final
    input.setGamma(1.0f, 1.0f); // data, not colour: no gamma conversion
    input.setAlphaMode(nvtt::AlphaMode_None);

    {
        std::vector<std::uint8_t> bgra; // one level; nvtt keeps its own copy
        for (size_t k = 0; k < sizes.size(); ++k) {
            const auto [w, h] = sizes[k];
            const size_t n = size_t(w) * size_t(h);
            bgra.assign(n * 4, 0);
            forEachBlock(read, k, n, channels, [&](size_t begin, size_t end, const float* values) {
                for (size_t t = begin; t < end; ++t) {
                    const float* v = &values[(t - begin) * size_t(channels)];
                    // unorm8: the code every 8-bit format of the export stores, so a texture the
                    // bake kept as 8-bit codes is written as those codes.
                    std::uint8_t r = 0, g = 0, b = 0, a = 255;
                    if (channels == 1) {
                        // Grey, and in alpha too: nvtt 2.0's BC4 compresses the alpha channel.
                        r = g = b = a = unorm8(v[0]);
                    } else {
                        r = unorm8(v[0]);
                        g = unorm8(v[1]);
                        if (channels >= 3) b = unorm8(v[2]);
                        if (channels == 4) a = unorm8(v[3]);
                    }
                    bgra[t * 4 + 0] = b;
                    bgra[t * 4 + 1] = g;
                    bgra[t * 4 + 2] = r;
                    bgra[t * 4 + 3] = a;
                }
            });
            if (!input.setMipmapData(bgra.data(), w, h, 1, 0, int(k)))
                return Error{"DDS: nvtt refused mip " + std::to_string(k)};
        }
    }

    nvtt::CompressionOptions compressionOptions;
    compressionOptions.setFormat(nvttFormat(compression));
    // nvtt 2.0.8's BC3 colour compressor at Quality_Normal and above leaves bits of some index
    // bytes uninitialised (valgrind: "write(buf) points to uninitialised byte(s)"), so the same
    // input gave different bytes, and texels, from run to run; its Quality_Fastest path is fully
    // defined. BC4/BC5 are defined at every quality.
    compressionOptions.setQuality(compression == DdsCompression::Bc3 ? nvtt::Quality_Fastest
                                                                     : nvtt::Quality_Normal);

    MemoryOutput output;
    ErrorCollector errors;
    nvtt::OutputOptions outputOptions;
    outputOptions.setOutputHandler(&output);
    outputOptions.setErrorHandler(&errors);
    outputOptions.setOutputHeader(true);

    nvtt::Compressor compressor;
    // The CPU path only, so the bytes do not depend on the machine's GPU.
    compressor.enableCudaAcceleration(false);
    if (!compressor.process(input, compressionOptions, outputOptions))
        return Error{"DDS: compression failed: " +
                     (errors.message.empty() ? std::string("unknown error") : errors.message)};
    return std::move(output.bytes);
}

} // namespace burnish
