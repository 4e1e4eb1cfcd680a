#include "io/png_decode.h"

#include <isa-l/crc.h>
#include <isa-l/igzip_lib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <span>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace burnish {

namespace {

// PNG 1.2 §12.12: the signature.
constexpr std::string_view kSignature{"\x89PNG\r\n\x1a\n", 8};
// PNG 1.2 §5.3: a chunk is length (4), type (4), data, CRC (4); the length is at most 2^31 - 1.
constexpr std::size_t kChunkOverhead = 12;
constexpr uint32_t kMaxChunkLength = uint32_t(std::numeric_limits<int32_t>::max());
constexpr std::size_t kIhdrBytes = 13;
// Rows are inflated in batches of about this many filtered bytes: small enough to stay in cache
// between inflating and unfiltering, large enough that handing a batch over costs nothing.
constexpr std::size_t kBatchBytes = std::size_t(256) << 10;

uint32_t readU32(const char* p) {
    const auto* b = reinterpret_cast<const unsigned char*>(p);
    return uint32_t(b[0]) << 24 | uint32_t(b[1]) << 16 | uint32_t(b[2]) << 8 | uint32_t(b[3]);
}

// PNG 1.2 §3.4: CRC-32 (ISO 3309, the one zlib and gzip use) of the chunk's type and data.
uint32_t chunkCrc(const char* typeAndData, std::size_t bytes) {
    return crc32_gzip_refl(0, reinterpret_cast<const unsigned char*>(typeAndData), bytes);
}

// PNG 1.2 §4.1.1: the IHDR fields; a layout with decodable set only for what core decodes.
Result<PngLayout> parseHeader(std::string_view ihdr) {
    PngLayout layout;
    const uint32_t width = readU32(ihdr.data()), height = readU32(ihdr.data() + 4);
    const int depth = uint8_t(ihdr[8]), colourType = uint8_t(ihdr[9]);
    const int compression = uint8_t(ihdr[10]), filter = uint8_t(ihdr[11]), interlace = uint8_t(ihdr[12]);
    if (width == 0 || height == 0 || width > kMaxChunkLength || height > kMaxChunkLength)
        return Error{"corrupt PNG header: size " + std::to_string(width) + "x" + std::to_string(height)};
    // Colour type → allowed depths (PNG 1.2 Table 11.1).
    const bool depthOk =
        colourType == 0   ? (depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16)
        : colourType == 3 ? (depth == 1 || depth == 2 || depth == 4 || depth == 8)
        : (colourType == 2 || colourType == 4 || colourType == 6) ? (depth == 8 || depth == 16)
                                                                  : false;
    if (!depthOk)
        return Error{"corrupt PNG header: colour type " + std::to_string(colourType) + " with " +
                     std::to_string(depth) + " bits"};
    if (compression != 0 || filter != 0 || interlace > 1)
        return Error{"corrupt PNG header: compression " + std::to_string(compression) + ", filter method " +
                     std::to_string(filter) + ", interlace " + std::to_string(interlace)};
    layout.width = int(width);
    layout.height = int(height);
    layout.bitDepth = depth;
    layout.channels = colourType == 0   ? 1
                      : colourType == 4 ? 2
                      : colourType == 2 ? 3
                      : colourType == 6 ? 4
                                        : 1;
    layout.decodable = colourType != 3 && depth >= 8 && interlace == 0;
    layout.interlaced = interlace == 1;
    return layout;
}

// ---- Unfiltering (PNG 1.2 §6.3, §9.2) ----------------------------------------------------------
// Each function writes the unfiltered row to `out` from the filtered bytes `filt` (filter byte
// excluded) and the previous unfiltered row `prev` (zeros for the first row).

void unfilterSub(const uint8_t* filt, uint8_t* out, std::size_t rowBytes, std::size_t bpp) {
    const std::size_t head = std::min(bpp, rowBytes);
    std::memcpy(out, filt, head);
    for (std::size_t i = head; i < rowBytes; ++i)
        out[i] = uint8_t(filt[i] + out[i - bpp]);
}

void unfilterUp(const uint8_t* filt, const uint8_t* prev, uint8_t* out, std::size_t rowBytes) {
    for (std::size_t i = 0; i < rowBytes; ++i)
        out[i] = uint8_t(filt[i] + prev[i]);
}

void unfilterAverage(const uint8_t* filt, const uint8_t* prev, uint8_t* out, std::size_t rowBytes,
                     std::size_t bpp) {
    const std::size_t head = std::min(bpp, rowBytes);
    for (std::size_t i = 0; i < head; ++i)
        out[i] = uint8_t(filt[i] + (prev[i] >> 1));
    for (std::size_t i = head; i < rowBytes; ++i)
        out[i] = uint8_t(filt[i] + ((unsigned(out[i - bpp]) + unsigned(prev[i])) >> 1));
}

// PNG 1.2 §9.4: the Paeth predictor of left a, above b, upper-left c.
inline int paethPredictor(int a, int b, int c) {
    const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

void unfilterPaethScalar(const uint8_t* filt, const uint8_t* prev, uint8_t* out, std::size_t rowBytes,
                         std::size_t bpp) {
    const std::size_t head = std::min(bpp, rowBytes);
    for (std::size_t i = 0; i < head; ++i)
        out[i] = uint8_t(filt[i] + prev[i]); // a = c = 0: the predictor is b
    for (std::size_t i = head; i < rowBytes; ++i)
        out[i] = uint8_t(filt[i] + paethPredictor(out[i - bpp], prev[i], prev[i - bpp]));
}

#if defined(__SSE2__)
// One Paeth step on bytes held in 16-bit lanes: a (left), b (above), c (upper left), x (filtered)
// give the unfiltered bytes, lane by lane. Ties go to a, then b, then c (PNG 1.2 §9.4).
inline __m128i paethStep(__m128i a, __m128i b, __m128i c, __m128i x) {
    const __m128i zero = _mm_setzero_si128();
    auto abs16 = [&](__m128i v) { return _mm_max_epi16(v, _mm_sub_epi16(zero, v)); };
    auto select = [](__m128i mask, __m128i ifSet, __m128i otherwise) {
        return _mm_or_si128(_mm_and_si128(mask, ifSet), _mm_andnot_si128(mask, otherwise));
    };
    const __m128i bc = _mm_sub_epi16(b, c), ac = _mm_sub_epi16(a, c);
    const __m128i pa = abs16(bc), pb = abs16(ac), pc = abs16(_mm_add_epi16(bc, ac));
    const __m128i smallest = _mm_min_epi16(pc, _mm_min_epi16(pa, pb));
    const __m128i nearest =
        select(_mm_cmpeq_epi16(smallest, pa), a, select(_mm_cmpeq_epi16(smallest, pb), b, c));
    return _mm_and_si128(_mm_add_epi16(x, nearest), _mm_set1_epi16(0xFF));
}

// 4 or 8 bytes at p, widened to 16-bit lanes.
template <std::size_t Bytes> inline __m128i loadWide(const uint8_t* p) {
    if constexpr (Bytes == 4) {
        int32_t v;
        std::memcpy(&v, p, 4);
        return _mm_unpacklo_epi8(_mm_cvtsi32_si128(v), _mm_setzero_si128());
    } else {
        long long v;
        std::memcpy(&v, p, 8);
        return _mm_unpacklo_epi8(_mm_cvtsi64_si128(v), _mm_setzero_si128());
    }
}

// The low 4 or 8 lanes of v, narrowed to bytes, stored at p.
template <std::size_t Bytes> inline void storeNarrow(uint8_t* p, __m128i v) {
    const __m128i packed = _mm_packus_epi16(v, v);
    if constexpr (Bytes == 4) {
        const int32_t bytes = _mm_cvtsi128_si32(packed);
        std::memcpy(p, &bytes, 4);
    } else {
        const long long bytes = _mm_cvtsi128_si64(packed);
        std::memcpy(p, &bytes, 8);
    }
}

// Paeth one pixel at a time, its bytes in 16-bit lanes (the approach of libpng's SSE2 code): each
// pixel depends on the one to its left, so the latency of this chain is the cost. Loads and stores
// are 4 bytes (BPP 3, 4) or 8 bytes (BPP 6, 8): the spare lanes read or write up to 2 bytes beyond the
// pixel, which the next pixel (or the next row, or the padding after the rows) rewrites, and never
// feed a used lane.
template <int BPP>
void unfilterPaethSse2(const uint8_t* filt, const uint8_t* prev, uint8_t* out, std::size_t rowBytes) {
    static_assert(BPP == 3 || BPP == 4 || BPP == 6 || BPP == 8);
    constexpr std::size_t kBytes = BPP <= 4 ? 4 : 8;
    __m128i a = _mm_setzero_si128(), c = a;
    for (std::size_t i = 0; i < rowBytes; i += BPP) {
        const __m128i b = loadWide<kBytes>(prev + i);
        a = paethStep(a, b, c, loadWide<kBytes>(filt + i));
        storeNarrow<kBytes>(out + i, a);
        c = b;
    }
}

// Two Paeth rows at once, for 3- and 4-byte pixels: row y in lanes 0-3 and row y + 1, one pixel
// behind, in lanes 4-7, so one chain of steps decodes two pixels. The lower row's pixel j - 1 reads
// above it pixels j - 1 and j - 2 of the upper row, both decoded by the previous steps: its b is
// the upper half's last result and its c the b before. This halves the latency per pixel.
template <int BPP>
void unfilterPaethPairSse2(const uint8_t* filtUpper, const uint8_t* filtLower, const uint8_t* prev,
                           uint8_t* outUpper, uint8_t* outLower, std::size_t rowBytes) {
    static_assert(BPP == 3 || BPP == 4);
    const std::size_t width = rowBytes / BPP;
    const __m128i lowHalf = _mm_set_epi32(0, 0, -1, -1);
    // result = [upper pixel j - 1 | lower pixel j - 2], b = [above upper j - 1 | upper j - 2]
    __m128i result = _mm_setzero_si128(), b = result;
    // j = 0: the upper row's first pixel alone (a = c = 0); the lower half must stay 0 (its left
    // and upper-left are 0 at pixel 0).
    {
        const __m128i bNew = _mm_unpacklo_epi64(loadWide<4>(prev), result);
        result = _mm_and_si128(paethStep(result, bNew, b, loadWide<4>(filtUpper)), lowHalf);
        b = bNew;
        // Its spare byte lands on the lower row's first pixel, which is stored later.
        storeNarrow<4>(outUpper, result);
    }
    for (std::size_t j = 1; j < width; ++j) {
        const __m128i bNew = _mm_unpacklo_epi64(loadWide<4>(prev + j * BPP), result);
        const __m128i x =
            _mm_unpacklo_epi64(loadWide<4>(filtUpper + j * BPP), loadWide<4>(filtLower + (j - 1) * BPP));
        result = paethStep(result, bNew, b, x);
        b = bNew;
        if (j + 1 < width) {
            storeNarrow<4>(outUpper + j * BPP, result);
        } else {
            // The upper row's last pixel: exactly BPP bytes, the lower row's first pixel follows it.
            const int32_t bytes = _mm_cvtsi128_si32(_mm_packus_epi16(result, result));
            std::memcpy(outUpper + j * BPP, &bytes, BPP);
        }
        storeNarrow<4>(outLower + (j - 1) * BPP, _mm_unpackhi_epi64(result, result));
    }
    // j = width: the lower row's last pixel.
    const __m128i bNew = _mm_unpacklo_epi64(_mm_setzero_si128(), result);
    const __m128i x = _mm_unpacklo_epi64(_mm_setzero_si128(), loadWide<4>(filtLower + (width - 1) * BPP));
    result = paethStep(result, bNew, b, x);
    storeNarrow<4>(outLower + (width - 1) * BPP, _mm_unpackhi_epi64(result, result));
}
#endif

void unfilterPaeth(const uint8_t* filt, const uint8_t* prev, uint8_t* out, std::size_t rowBytes,
                   std::size_t bpp) {
#if defined(__SSE2__)
    switch (bpp) {
    case 3:
        return unfilterPaethSse2<3>(filt, prev, out, rowBytes);
    case 4:
        return unfilterPaethSse2<4>(filt, prev, out, rowBytes);
    case 6:
        return unfilterPaethSse2<6>(filt, prev, out, rowBytes);
    case 8:
        return unfilterPaethSse2<8>(filt, prev, out, rowBytes);
    default:
        break;
    }
#endif
    unfilterPaethScalar(filt, prev, out, rowBytes, bpp);
}

std::string inflateError(int rc) {
    const char* what = rc == ISAL_INVALID_BLOCK        ? "invalid deflate block"
                       : rc == ISAL_INVALID_SYMBOL     ? "invalid deflate symbol"
                       : rc == ISAL_INVALID_LOOKBACK   ? "invalid back-reference distance"
                       : rc == ISAL_INVALID_WRAPPER    ? "invalid zlib header"
                       : rc == ISAL_UNSUPPORTED_METHOD ? "unsupported zlib compression method"
                       : rc == ISAL_INCORRECT_CHECKSUM ? "adler32 checksum mismatch"
                       : rc == ISAL_NEED_DICT          ? "zlib preset dictionary (not allowed in PNG)"
                                                       : "inflate error";
    return "corrupt PNG image data: " + std::string(what);
}

/// The zlib stream of a layout's IDAT chunks, inflated by ISA-L piece by piece.
class IdatInflater {
public:
    explicit IdatInflater(const PngLayout& layout)
        : m_layout(layout)
        , m_state(std::make_unique<inflate_state>()) { // ~50 KiB of history and tables: on the heap
        isal_inflate_init(m_state.get());
        m_state->crc_flag = ISAL_ZLIB; // parse the zlib header, check the adler32 trailer
    }

    /// Inflates until `bytes` bytes are out at `to`; false: the data ended first.
    Result<bool> into(uint8_t* to, std::size_t bytes) {
        inflate_state& state = *m_state;
        state.next_out = to;
        state.avail_out = uint32_t(bytes);
        while (state.avail_out > 0) {
            if (state.block_state == ISAL_BLOCK_FINISH) return false;
            if (state.avail_in == 0 && m_nextIdat < m_layout.idat.size()) {
                const std::string_view chunk = m_layout.idat[m_nextIdat++];
                state.next_in = reinterpret_cast<uint8_t*>(const_cast<char*>(chunk.data())); // only read
                state.avail_in = uint32_t(chunk.size());
            }
            // Called even with no input left: ISA-L reads ahead into its bit buffer, and the bits
            // there may still hold output.
            const uint32_t inBefore = state.avail_in, outBefore = state.avail_out;
            const isal_block_state blockBefore = state.block_state;
            const int rc = isal_inflate(&state);
            if (rc < 0 || rc == ISAL_NEED_DICT) return Error{inflateError(rc)};
            if (state.avail_in == inBefore && state.avail_out == outBefore &&
                state.block_state == blockBefore && m_nextIdat == m_layout.idat.size())
                return false; // no progress and no more data
        }
        return true;
    }

    /// Drains the stream to its end so the adler32 is checked. Bytes beyond the rows (libpng warns
    /// "extra compressed data") and a stream cut off after the last row lose no pixel: accepted.
    Status drain() {
        uint8_t spare[4096];
        while (m_state->block_state != ISAL_BLOCK_FINISH) {
            auto more = into(spare, sizeof spare);
            if (!more) return Error{more.error()};
            if (!*more && m_state->block_state != ISAL_BLOCK_FINISH) break;
        }
        return {};
    }

private:
    const PngLayout& m_layout;
    std::unique_ptr<inflate_state> m_state;
    std::size_t m_nextIdat = 0;
};

} // namespace

bool hasPngSignature(std::string_view head) {
    return head.substr(0, kSignature.size()) == kSignature;
}

Result<PngLayout> parsePng(std::string_view file) {
    if (!hasPngSignature(file)) return Error{"not a PNG file (bad signature)"};
    PngLayout layout;
    bool haveHeader = false, idatEnded = false;
    std::size_t at = kSignature.size();
    for (;;) {
        // A file cut off after some image data ends the chunks there: if the rows are all in the
        // IDAT chunks read so far (a lost trailer, ancillary chunks or IEND), no pixel is lost;
        // otherwise decodePngRows says which row the data ends before.
        if (file.size() - at < kChunkOverhead) {
            if (!layout.idat.empty()) break;
            return Error{"truncated PNG file (ends inside a chunk header before the image data ends)"};
        }
        const uint32_t length = readU32(file.data() + at);
        const std::string_view type = file.substr(at + 4, 4);
        if (length > kMaxChunkLength) return Error{"corrupt PNG chunk length " + std::to_string(length)};
        if (file.size() - at - kChunkOverhead < length) {
            if (!layout.idat.empty()) break;
            return Error{"truncated PNG file (chunk " + std::string(type) + " runs past the end)"};
        }
        const std::string_view data = file.substr(at + 8, length);
        // PNG 1.2 §5.4: bit 5 of the first type byte set = ancillary.
        const bool critical = (uint8_t(type[0]) & 0x20) == 0;
        // IEND carries no data: a wrong CRC there loses nothing (libpng reads such files too).
        if (critical && type != "IEND" &&
            chunkCrc(file.data() + at + 4, length + 4) != readU32(file.data() + at + 8 + length))
            return Error{"corrupt PNG file (CRC mismatch in chunk " + std::string(type) + ")"};
        at += kChunkOverhead + length;

        if (!haveHeader) {
            if (type != "IHDR" || length != kIhdrBytes)
                return Error{"corrupt PNG file (IHDR is not the first chunk)"};
            auto header = parseHeader(data);
            if (!header) return Error{header.error()};
            layout = std::move(*header);
            haveHeader = true;
        } else if (type == "IDAT") {
            if (idatEnded) return Error{"corrupt PNG file (IDAT chunks are not consecutive)"};
            layout.idat.push_back(data);
        } else {
            if (!layout.idat.empty()) idatEnded = true;
            if (type == "IEND") break;
            if (type == "tRNS") layout.decodable = false; // libpng turns it into an alpha channel
            if (type == "sRGB") layout.srgb = true;
            if (type == "gAMA" && length == 4) layout.fileGamma = double(readU32(data.data())) / 100000.0;
            if (critical && type != "PLTE")
                return Error{"PNG file has an unknown critical chunk " + std::string(type)};
        }
    }
    if (layout.idat.empty()) return Error{"corrupt PNG file (no image data)"};
    return layout;
}

std::string PngLayout::colorSpace() const {
    if (srgb || !(fileGamma > 0.0)) return "sRGB";
    // Display gamma rounded to hundredths, 2.2 rather than 2.19998.
    const float g = std::round(100.0f * float(1.0 / fileGamma)) / 100.0f;
    if (g == 1.0f) return "linear";
    char name[32];
    std::snprintf(name, sizeof name, "Gamma%.2g", double(g));
    return name;
}

Status decodePngRows(const PngLayout& layout, uint8_t* out, const std::function<void(int, int)>& rowsDone) {
    if (!layout.decodable) return Error{"PNG layout is not one core decodes"};
    const std::size_t rowBytes = layout.rowBytes(), filteredRowBytes = rowBytes + 1;
    const std::size_t bpp = std::size_t(layout.channels) * std::size_t(layout.bitDepth / 8);
    const std::size_t batchRows = std::max<std::size_t>(1, kBatchBytes / filteredRowBytes);
    std::vector<uint8_t> filtered(batchRows * filteredRowBytes + kPngDecodePadding);
    const std::vector<uint8_t> zeroRow(rowBytes + kPngDecodePadding, 0);

    IdatInflater inflater(layout);
    auto inflateInto = [&](uint8_t* to, std::size_t bytes) { return inflater.into(to, bytes); };

    const int height = layout.height;
    for (int y0 = 0; y0 < height;) {
        const int rows = int(std::min<std::size_t>(batchRows, std::size_t(height - y0)));
        auto full = inflateInto(filtered.data(), std::size_t(rows) * filteredRowBytes);
        if (!full) return Error{full.error()};
        if (!*full)
            return Error{"truncated PNG image data (the rows end before row " + std::to_string(y0 + rows) +
                         " of " + std::to_string(height) + ")"};
        for (int r = 0; r < rows; ++r) {
            const int y = y0 + r;
            const uint8_t* row = filtered.data() + std::size_t(r) * filteredRowBytes;
            const uint8_t* filt = row + 1;
            uint8_t* dst = out + std::size_t(y) * rowBytes;
            const uint8_t* prev = y > 0 ? dst - rowBytes : zeroRow.data();
#if defined(__SSE2__)
            // Two Paeth rows in a row (the common case): decoded together.
            if (row[0] == 4 && r + 1 < rows && row[filteredRowBytes] == 4 && (bpp == 3 || bpp == 4)) {
                const uint8_t* lower = row + filteredRowBytes + 1;
                if (bpp == 3)
                    unfilterPaethPairSse2<3>(filt, lower, prev, dst, dst + rowBytes, rowBytes);
                else
                    unfilterPaethPairSse2<4>(filt, lower, prev, dst, dst + rowBytes, rowBytes);
                ++r;
                continue;
            }
#endif
            switch (row[0]) {
            case 0:
                std::memcpy(dst, filt, rowBytes);
                break;
            case 1:
                unfilterSub(filt, dst, rowBytes, bpp);
                break;
            case 2:
                unfilterUp(filt, prev, dst, rowBytes);
                break;
            case 3:
                unfilterAverage(filt, prev, dst, rowBytes, bpp);
                break;
            case 4:
                unfilterPaeth(filt, prev, dst, rowBytes, bpp);
                break;
            default:
                return Error{"corrupt PNG image data: unknown filter type " + std::to_string(row[0]) +
                             " in row " + std::to_string(y)};
            }
        }
        rowsDone(y0, y0 + rows);
        y0 += rows;
    }
    return inflater.drain();
}

Status checkPngData(const PngLayout& layout) {
    // PNG 1.2 §8.2: Adam7's passes (first column and row, steps); a plain image is one pass.
    struct Pass {
        int x0, y0, dx, dy;
    };
    static const Pass kAdam7[7] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                                   {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};
    static const Pass kPlain[1] = {{0, 0, 1, 1}};
    const std::size_t bitsPerPixel = std::size_t(layout.channels) * std::size_t(layout.bitDepth);
    IdatInflater inflater(layout);
    std::vector<uint8_t> row;
    for (const Pass& pass :
         layout.interlaced ? std::span<const Pass>(kAdam7) : std::span<const Pass>(kPlain)) {
        const std::size_t w = layout.width > pass.x0
                                  ? std::size_t(layout.width - pass.x0 + pass.dx - 1) / std::size_t(pass.dx)
                                  : 0;
        const std::size_t h = layout.height > pass.y0
                                  ? std::size_t(layout.height - pass.y0 + pass.dy - 1) / std::size_t(pass.dy)
                                  : 0;
        if (w == 0 || h == 0) continue; // an empty pass has no rows, not even filter bytes
        row.resize(1 + (w * bitsPerPixel + 7) / 8);
        for (std::size_t y = 0; y < h; ++y) {
            auto full = inflater.into(row.data(), row.size());
            if (!full) return Error{full.error()};
            if (!*full) return Error{"truncated PNG image data (the rows end early)"};
            if (row[0] > 4)
                return Error{"corrupt PNG image data: unknown filter type " + std::to_string(row[0])};
        }
    }
    return inflater.drain();
}

} // namespace burnish
