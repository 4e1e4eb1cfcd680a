// KTX 2.0 files (Khronos Texture 2.0: identifier, header, level index, Data Format Descriptor,
// key/value data, levels), written and read by Burnish itself: one 2D texture (no layers, faces or
// depth), no supercompression, every mip level given. Formats: uncompressed 8-bit unsigned normalized
// R8/RG8/RGBA8, the BC4/BC5/BC3 blocks NVIDIA Texture Tools makes, and RGBA16F (half floats, for
// values outside [0, 1] that filtering must keep linear: the lobe mixture's moments). Levels are stored
// smallest first, each at an offset aligned to lcm(texel block size, 4), rows top first (KTXorientation "rd",
// as glTF's UV origin expects). Output bytes depend only on the inputs.
#pragma once

#include <burnish/core/util/result.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace burnish {

enum class Ktx2Format { R8, Rg8, Rgba8, Bc3, Bc4, Bc5, Rgba16f };

/// The Vulkan format code the file's header stores (VK_FORMAT_R8_UNORM = 9, ...).
std::uint32_t ktx2VkFormat(Ktx2Format format);
std::string_view ktx2FormatName(Ktx2Format format); // "r8", "rg8", "rgba8", "bc3", "bc4", "bc5", "rgba16f"
/// Channels the format stores (BC3: 4, BC4: 1, BC5: 2).
int ktx2Channels(Ktx2Format format);
bool ktx2IsBlockCompressed(Ktx2Format format);
/// Bytes of one level of width×height texels (4×4 blocks for BC formats, at least one block).
std::uint64_t ktx2LevelBytes(Ktx2Format format, int width, int height);

struct Ktx2Texture {
    Ktx2Format format = Ktx2Format::Rgba8;
    int width = 0;
    int height = 0;
    /// Level k is max(1, ⌊width/2^k⌋) × max(1, ⌊height/2^k⌋), its bytes row-major, top row first.
    std::vector<std::string> levels;
    /// Key/value data besides KTXorientation and KTXwriter, which the writer adds (sorted by key).
    std::vector<std::pair<std::string, std::string>> keyValues;
};

/// The bytes of a .ktx2 file. Errors: an empty or oversized extent, a level count that is not the full
/// chain's prefix, a level whose size does not match its extent, a key that is empty or holds a NUL.
Result<std::string> encodeKtx2(const Ktx2Texture& texture);

/// Reads a .ktx2 file of the subset encodeKtx2 writes (any level count, any key/value data). Errors, in
/// one line each: a wrong identifier, a truncated file, a format outside Ktx2Format, layers, faces or
/// depth, supercompression, key/value keys out of order or repeated, level or data ranges outside the file or
/// overlapping the header, a level whose byte count does not match its extent, a DFD that does not describe
/// the format.
Result<Ktx2Texture> decodeKtx2(std::string_view bytes);

} // namespace burnish
