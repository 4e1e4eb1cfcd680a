// DDS output through NVIDIA Texture Tools 2.0: the bake's own mip chain, block-compressed or not,
// collected in memory (export.cpp stages and renames the bytes).
#include <burnish/core/bake/export.h>

#include "dds_dx10.h"

#include <nvtt/nvtt.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

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

// Round to nearest 8-bit code: the quantization every 8-bit format of the export shares.
std::uint8_t code8(float v) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
}

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

// RGBA16F with a DX10 header, every level in order: the stored values in [0, 1] as half floats
// (missing colour channels 0, missing alpha 1), for moments that 8 bits would ruin.
std::string encodeRgba16f(const std::vector<TextureMip>& mips, int channels) {
    std::string s = dds::rgba16fHeader(std::uint32_t(mips[0].width), std::uint32_t(mips[0].height),
                                       std::uint32_t(mips.size()), false);
    for (const auto& m : mips)
        for (size_t t = 0; t < size_t(m.width) * size_t(m.height); ++t)
            for (int c = 0; c < 4; ++c)
                dds::putHalf(s, c < channels ? std::clamp(float(m.texels[t * size_t(channels) + size_t(c)]),
                                                          0.0f, 1.0f)
                                             : (c == 3 ? 1.0f : 0.0f));
    return s;
}

} // namespace

Result<std::string> encodeDds(const std::vector<TextureMip>& mips, int channels, DdsCompression compression) {
    if (mips.empty()) return Error{"DDS: no mip levels to write"};
    if (channels < 1 || channels > 4) return Error{"DDS: a texture needs 1 to 4 channels"};
    if (compression == DdsCompression::Bc4 && channels != 1)
        return Error{"DDS: bc4 holds exactly one channel"};
    if (compression == DdsCompression::Bc5 && channels != 2)
        return Error{"DDS: bc5 holds exactly two channels"};
    // nvtt 2.0 takes int extents; DDS readers expect at most 16384 on a side (D3D11's limit).
    constexpr int kMaxDdsSide = 16384;
    if (mips[0].width < 1 || mips[0].height < 1 || mips[0].width > kMaxDdsSide ||
        mips[0].height > kMaxDdsSide)
        return Error{"DDS: " + std::to_string(mips[0].width) + "x" + std::to_string(mips[0].height) +
                     " is outside 1..16384 on a side"};
    for (size_t k = 0; k < mips.size(); ++k) {
        const auto& m = mips[k];
        if (k > 0 && (m.width != std::max(1, mips[k - 1].width / 2) ||
                      m.height != std::max(1, mips[k - 1].height / 2)))
            return Error{"DDS: mip " + std::to_string(k) + " is not half of mip " + std::to_string(k - 1)};
        if (m.texels.size() != size_t(m.width) * size_t(m.height) * size_t(channels))
            return Error{"DDS: mip " + std::to_string(k) + " has the wrong number of values"};
    }

    if (compression == DdsCompression::Rgba16f) return encodeRgba16f(mips, channels);
    nvtt::InputOptions input;
    input.setTextureLayout(nvtt::TextureType_2D, mips[0].width, mips[0].height);
    input.setFormat(nvtt::InputFormat_BGRA_8UB);
    // nvtt 2.0 writes only the top level when mipmap generation is off; with it on, a level given
    // through setMipmapData (matched by exact size) is used as is and nothing is generated.
    // maxLevel stops the chain where the bake's stops.
    input.setMipmapGeneration(true, int(mips.size()) - 1);
    input.setNormalMap(false);  // no renormalization: the bake's values are final
    input.setGamma(1.0f, 1.0f); // data, not colour: no gamma conversion
    input.setAlphaMode(nvtt::AlphaMode_None);

    std::vector<std::uint8_t> bgra;
    for (size_t k = 0; k < mips.size(); ++k) {
        const auto& m = mips[k];
        const size_t n = size_t(m.width) * size_t(m.height);
        bgra.assign(n * 4, 0);
        for (size_t t = 0; t < n; ++t) {
            const float* v = &m.texels[t * size_t(channels)];
            std::uint8_t r = 0, g = 0, b = 0, a = 255;
            if (channels == 1) {
                // Grey, and in alpha too: nvtt 2.0's BC4 compresses the alpha channel.
                r = g = b = a = code8(v[0]);
            } else {
                r = code8(v[0]);
                g = code8(v[1]);
                if (channels >= 3) b = code8(v[2]);
                if (channels == 4) a = code8(v[3]);
            }
            bgra[t * 4 + 0] = b;
            bgra[t * 4 + 1] = g;
            bgra[t * 4 + 2] = r;
            bgra[t * 4 + 3] = a;
        }
        if (!input.setMipmapData(bgra.data(), m.width, m.height, 1, 0, int(k)))
            return Error{"DDS: nvtt refused mip " + std::to_string(k)};
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
