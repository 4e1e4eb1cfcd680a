// Image import in steps (private to core), so the normal-map loader can decode an 8- or 16-bit
// PNG's rows straight into normals while later rows are still being read, without a float copy
// of the whole image (normal_map.cpp); readImage is openImage + readOpenedImage.
#pragma once

#include <burnish/core/io/image.h>
#include <burnish/core/util/result.h>
#include <burnish/core/util/texel_vector.h>

#include <OpenImageIO/imageio.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace burnish {

/// A file opened through OpenImageIO with its header checked (size, channels, not a volume).
struct OpenedImage {
    std::filesystem::path path;
    std::unique_ptr<OIIO::ImageInput> input; // null for the PNG files core decodes (openImage)
    int width = 0, height = 0, channels = 0;
    ImageSourceInfo source;
    /// 8 or 16 for unsigned integer files, 0 otherwise.
    int bitDepth = 0;
    /// For 8/16-bit files: each stored code's float, OpenImageIO's own conversion (bit for bit what
    /// read_image(FLOAT) gives).
    std::vector<float> table;
    /// A PNG file's bytes, read and parsed (parsePng) before OpenImageIO saw the file, so a damaged
    /// header or chunk is refused with core's own one-line reason and libpng never prints its own;
    /// core's decoder reads them again from here. Empty for other formats.
    std::vector<char, TexelAllocator<char>> pngFile;
};

/// Opens an image and makes the checks readImage documents: PNG files core decodes itself (8 or 16
/// bits, not interlaced, no palette or tRNS) from their header alone, without OpenImageIO (input stays
/// null); every other file through OpenImageIO.
Result<OpenedImage> openImage(const std::filesystem::path& path);

/// Each unsigned 8- or 16-bit code's float, as OpenImageIO converts them (code / (2^bits − 1)).
std::vector<float> unsignedCodeTable(int bitDepth);

/// Reads the pixels of an opened image as floats (readImage's second half).
Result<Image> readOpenedImage(OpenedImage&& opened);

/// An 8- or 16-bit PNG's samples as stored: row-major, `rowSamples` a row, 16-bit ones big-endian.
struct PngCodes {
    std::vector<std::uint8_t, TexelAllocator<std::uint8_t>> raw;
    int bitDepth = 8;
    std::size_t rowSamples = 0;
    /// The code of sample i (an index into OpenedImage::table).
    std::size_t code(std::size_t i) const {
        return bitDepth == 8 ? raw[i] : std::size_t(raw[2 * i]) << 8 | raw[2 * i + 1];
    }
};

/// Decodes an opened 8/16-bit PNG with core's decoder (png_decode.h) into `codes`, calling
/// `rowsDone(y0, y1)` on this thread as consecutive batches of rows become final. nullopt: not a
/// PNG the decoder handles (interlaced, palette, tRNS, low depths, or a header that disagrees with
/// OpenImageIO's), nothing decoded: read it with readOpenedImage. Otherwise the decode's status,
/// with errors naming the file.
std::optional<Status> readPngCodes(const OpenedImage& opened, PngCodes& codes,
                                   const std::function<void(int, int)>& rowsDone);

} // namespace burnish
