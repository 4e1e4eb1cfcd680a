// A fast PNG decoder (private to core) for the images normal maps and gloss maps come in: the
// zlib stream is inflated by ISA-L and the rows are unfiltered with SSE2 (Paeth, the filter most
// encoders pick, is the serial part), in batches handed to the caller as soon as they are final so
// their conversion runs on the other cores while later rows decode. Files it does not decode
// (interlaced, palette, tRNS, fewer than 8 bits) are left to libpng through OpenImageIO.
#pragma once

#include <burnish/core/util/result.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

namespace burnish {

/// A PNG file's layout: its header and where its image data lies in the file's bytes.
struct PngLayout {
    int width = 0, height = 0;
    int channels = 0;                   // 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA (colour types 0, 4, 2, 6)
    int bitDepth = 0;                   // 8 or 16 when decodable
    bool decodable = false;             // false: interlaced, palette, tRNS or < 8 bits (left to libpng)
    bool interlaced = false;            // Adam7
    std::vector<std::string_view> idat; // the IDAT chunks' data, in order (views into the file)
    bool srgb = false;                  // an sRGB chunk
    double fileGamma = 0.0;             // a gAMA chunk's value (0.45455 for display gamma 2.2), 0 without

    /// The colour space tag OpenImageIO gives the file ("oiio:ColorSpace"): sRGB with an sRGB chunk
    /// or none, else from gAMA ("linear", "Gamma2.2"). Informative only: the values are read as stored.
    std::string colorSpace() const;

    std::size_t rowBytes() const {
        return std::size_t(width) * std::size_t(channels) * std::size_t(bitDepth / 8);
    }
};

/// Whether `head` (a file's first bytes) starts with the 8-byte PNG signature.
bool hasPngSignature(std::string_view head);

/// Bytes decodePngRows may write past the last row (whole-pixel stores); `out` must have them.
inline constexpr std::size_t kPngDecodePadding = 16;

/// Parses the chunks of a PNG file held in `file` (which must outlive the layout). Errors: not a
/// PNG (signature), a truncated or malformed chunk before any image data, a CRC mismatch in a
/// critical chunk with data (IHDR, PLTE, IDAT), a bad IHDR (sizes of 0 or over 2^31 - 1, an invalid colour
/// type, depth, compression, filter or interlace method), no IDAT, IDAT chunks that are not
/// consecutive. Ancillary chunks are skipped unchecked, as libpng does.
Result<PngLayout> parsePng(std::string_view file);

/// Inflates and unfilters a decodable layout's rows into `out`: row y at y·rowBytes(), samples as
/// stored (16-bit ones big-endian), then kPngDecodePadding spare bytes. `rowsDone(y0, y1)` is called
/// on this thread, in order, for consecutive batches covering every row, once rows [y0, y1) are
/// final; nothing at or after row y1 is final yet. Errors: a corrupt zlib stream or adler32, too
/// little image data, an unknown filter type.
Status decodePngRows(const PngLayout& layout, std::uint8_t* out,
                     const std::function<void(int, int)>& rowsDone);

/// Checks the image data of any layout, decodable or not (interlaced, palette, low depths): the
/// zlib stream inflates without error to at least every row of every pass, each row's filter type
/// is known, the adler32 matches. What libpng would stop on with messages of its own, found first.
Status checkPngData(const PngLayout& layout);

} // namespace burnish
