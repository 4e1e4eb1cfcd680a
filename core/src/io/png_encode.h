// A parallel, deterministic PNG encoder (private to core): the filtered scanlines are cut into
// fixed segments of rows, each deflated on its own and joined into one zlib stream (the pigz
// technique), so a large PNG no longer compresses on a single core.
#pragma once

#include <burnish/core/util/result.h>

#include <cstddef>
#include <functional>
#include <string>

namespace burnish {

/// Pixels to encode, row-major and interleaved, top row first: in memory, or made row by row.
struct PngPixels {
    int width = 0, height = 0;
    int channels = 0;           // 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA
    int bitDepth = 8;           // 8 or 16
    const void* data = nullptr; // uint8_t, or uint16_t in host byte order
    /// Used when data is null: writes rows [y0, y1) into `out` as data would hold them. Called from
    /// several threads at once, for disjoint rows, so a caller can convert rows as they are encoded.
    std::function<void(std::size_t y0, std::size_t y1, void* out)> rows;
};

/// The PNG file's bytes: IHDR, the image data in IDAT chunks (each at most 1 MiB), IEND; no colour or
/// gamma chunks (the files hold data, not colour). Every row is filtered with Sub (filter type 1) and
/// deflated by ISA-L's igzip at its level 3. The bytes depend only on the pixels and on ISA-L (its
/// version, and the instruction set it picks at run time), never on the number of threads or their
/// scheduling. Errors (not exceptions): sizes of 0 or
/// over 2^31-1, channels outside 1-4, a depth other than 8 or 16, neither data nor rows, byte counts that
/// overflow, deflate or allocation failures.
Result<std::string> encodePng(const PngPixels& pixels);

/// Rows per independently deflated segment for rows of `filteredRowBytes` bytes (filter byte
/// included): about 1 MiB of filtered bytes, at least 1 row. Exposed so tests can check the layout.
std::size_t pngRowsPerSegment(std::size_t filteredRowBytes);

} // namespace burnish
