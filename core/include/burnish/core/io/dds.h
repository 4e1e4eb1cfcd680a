// DDS files of one texture's mip chain, collected in memory (the export stages and renames the
// bytes): block-compressed or 8-bit through NVIDIA Texture Tools 2.0 (src/io/dds_writer.cpp), half
// float by hand (src/io/dds_dx10.h: nvtt 2.0 has no half float nor DX10 header).
#pragma once

#include <burnish/core/util/result.h>

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace burnish {

/// DDS block compression (or none) of one file.
enum class DdsCompression {
    Bc4,     // one channel (ATI1)
    Bc5,     // two channels (ATI2): normal x, y; z is rebuilt by the shader
    Bc3,     // RGB + alpha (DXT5): normal + gloss in alpha
    Rgba8,   // uncompressed 8-bit A8R8G8B8
    Rgba16f, // uncompressed half float R16G16B16A16_FLOAT (DX10 header): moments that need 16 bits
};

/// The level sizes of a chain from width×height down: level k+1 is ⌊w/2⌋×⌊h/2⌋ (at least 1), down to
/// 1×1, at most `mipCount` levels (0 = all). Empty for an empty extent. The normal pyramid's rule, and
/// so every baked texture's.
std::vector<std::pair<int, int>> mipChainSizes(int width, int height, int mipCount = 0);

/// Texels [begin, end) of level k of a DDS file's texture, `channels` values per texel into `out`,
/// each in [0, 1]: what encodeDds reads instead of a whole chain of floats.
using DdsLevelReader = std::function<void(size_t k, size_t begin, size_t end, float* out)>;

/// One DDS file holding a chain of `levels` levels from width×height down (mipChainSizes), read
/// through `read` a block of texels at a time. BC4 holds exactly one channel, BC5 two, BC3 and RGBA8
/// up to four (missing colour channels 0, or channel 0 repeated for one-channel images; missing alpha
/// 1); RGBA16F up to four (missing colour channels 0, missing alpha 1). 1 to 16384 texels a side.
Result<std::string> encodeDds(int width, int height, int levels, int channels, DdsCompression compression,
                              const DdsLevelReader& read);

} // namespace burnish
