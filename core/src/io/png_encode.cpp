#include "io/png_encode.h"

#include <isa-l/igzip_lib.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <limits>
#include <new>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace burnish {

namespace {

// Segments of about 1 MiB of filtered bytes: enough work per task to hide the scheduling and the
// deflate set-up cost, small enough that 4096² RGB16 (96 MiB filtered) splits into ~100 tasks.
constexpr std::size_t kSegmentTargetBytes = std::size_t(1) << 20;
// IDAT chunks of at most 1 MiB: readers accept any split, and 1 MiB keeps the chunk count small.
constexpr std::size_t kMaxIdatBytes = std::size_t(1) << 20;
// ISA-L's avail_in/avail_out are 32-bit: inputs and outputs larger than this are fed in pieces.
constexpr std::size_t kMaxIsalPiece = std::size_t(1) << 30;
// ISA-L's level 3, its best: on baked 4096² maps (8-bit normal and gloss, 16-bit LEAN moments) it
// deflates 2.5-10x faster than zlib's level 1 and its files are 0-7% smaller. Its levels 1 and 2 are
// as fast but left tiled 16-bit maps nearly uncompressed (84 of 100 MB).
constexpr uint32_t kIsalLevel = 3;
constexpr std::size_t kIsalLevelBufferBytes = ISAL_DEF_LVL3_DEFAULT;
// Not an ISA-L status (those are 0 or negative): deflate took no input and wrote no output.
constexpr int kIsalNoProgress = 1;
// PNG 1.2 §11.2.2: width and height are at most 2^31 - 1.
constexpr int kMaxPngDimension = std::numeric_limits<int32_t>::max();

static_assert(sizeof(uLong) >= sizeof(std::size_t), "adler32_combine needs a 64-bit uLong");
static_assert(sizeof(z_off_t) >= sizeof(std::size_t), "adler32_combine needs a 64-bit z_off_t");

// Room for `inSize` bytes however they deflate: ISA-L falls back to stored blocks (at most 65535
// bytes, 5 header bytes each) when coding does not pay, after at most one Huffman header, and a sync
// flush adds an empty stored block (up to 7 bits of padding and 4 bytes LEN/NLEN). The output still
// grows if ever this is too little.
std::size_t storedBound(std::size_t inSize) {
    constexpr std::size_t kStoredBlockBytes = 65535, kStoredHeaderBytes = 5, kSyncFlushBytes = 16;
    return inSize + (inSize / kStoredBlockBytes + 1) * kStoredHeaderBytes + ISAL_DEF_MAX_HDR_SIZE +
           kSyncFlushBytes;
}

// PNG 1.2 §11.2.2, colour type by channel count: grey 0, RGB 2, grey+alpha 4, RGBA 6.
uint8_t colourType(int channels) {
    switch (channels) {
    case 1:
        return 0;
    case 2:
        return 4;
    case 3:
        return 2;
    default:
        return 6;
    }
}

void appendU32(std::string& out, uint32_t v) {
    // PNG 1.2 §2.1: all integers are big-endian.
    const char bytes[4] = {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    out.append(bytes, 4);
}

// PNG 1.2 §6.3, filter type 1 (Sub): Sub(x) = Raw(x) - Raw(x - bpp) mod 256, Raw(x < 0) = 0.
// Writes the filter-type byte and the filtered row `raw` (samplesPerRow samples) to out.
void filterRowSub(const void* raw, std::size_t samplesPerRow, std::size_t channels, int bitDepth,
                  unsigned char* out) {
    out[0] = 1;
    unsigned char* sub = out + 1;
    if (bitDepth == 8) {
        const auto* row = static_cast<const uint8_t*>(raw);
        for (std::size_t k = 0; k < channels; ++k)
            sub[k] = row[k];
        for (std::size_t k = channels; k < samplesPerRow; ++k)
            sub[k] = uint8_t(row[k] - row[k - channels]);
        return;
    }
    // 16-bit samples are stored big-endian (PNG 1.2 §2.1); the byte bpp to the left of each byte is
    // the same byte of the sample one pixel to the left, so the high and low bytes subtract apart.
    const auto* row = static_cast<const uint16_t*>(raw);
    for (std::size_t k = 0; k < channels; ++k) {
        sub[2 * k] = uint8_t(row[k] >> 8);
        sub[2 * k + 1] = uint8_t(row[k]);
    }
    for (std::size_t k = channels; k < samplesPerRow; ++k) {
        const uint16_t v = row[k], left = row[k - channels];
        sub[2 * k] = uint8_t((v >> 8) - (left >> 8));
        sub[2 * k + 1] = uint8_t(v - left);
    }
}

// Per-thread buffers, reused from segment to segment.
struct Scratch {
    std::vector<unsigned char> raw; // the segment's rows, when PngPixels::rows makes them
    std::vector<unsigned char> filtered;
    std::vector<unsigned char> compressed;
    std::vector<uint8_t> levelBuffer; // ISA-L's hash tables and tokens for kIsalLevel
};

/// One segment's compressed bytes (raw deflate) and the adler32 of its filtered bytes.
struct Segment {
    std::string deflated;
    uint32_t adler = 1; // RFC 1950 §8.2: the adler32 of no bytes
    std::size_t filteredBytes = 0;
    int isalStatus = COMP_OK;
};

// Raw-deflates `in` with ISA-L into `scratch.compressed` and copies the result to
// `segment.deflated`. The segment ends with a sync flush (byte-aligned, not final: the next segment's
// blocks follow) or, for the last one, the final block.
void deflateSegment(const unsigned char* in, std::size_t inSize, bool last, Scratch& scratch,
                    Segment& segment) {
    isal_zstream zs;
    isal_deflate_init(&zs);
    zs.level = kIsalLevel;
    scratch.levelBuffer.resize(kIsalLevelBufferBytes);
    zs.level_buf = scratch.levelBuffer.data();
    zs.level_buf_size = uint32_t(scratch.levelBuffer.size());
    zs.gzip_flag = IGZIP_DEFLATE; // raw deflate: the zlib header and trailer are written around it
    std::vector<unsigned char>& out = scratch.compressed;
    const std::size_t bound = storedBound(inSize);
    if (out.size() < bound) out.resize(bound);

    std::size_t inPos = 0, outPos = 0;
    for (;;) {
        if (outPos == out.size()) out.resize(out.size() * 2);
        const std::size_t inPiece = std::min(inSize - inPos, kMaxIsalPiece);
        const std::size_t outPiece = std::min(out.size() - outPos, kMaxIsalPiece);
        const bool lastInput = inPos + inPiece == inSize;
        zs.next_in = const_cast<uint8_t*>(in + inPos); // ISA-L only reads the input
        zs.avail_in = uint32_t(inPiece);
        zs.next_out = out.data() + outPos;
        zs.avail_out = uint32_t(outPiece);
        zs.flush = lastInput && !last ? SYNC_FLUSH : NO_FLUSH;
        zs.end_of_stream = lastInput && last ? 1 : 0;
        const int rc = isal_deflate(&zs);
        const std::size_t consumed = inPiece - zs.avail_in, produced = outPiece - zs.avail_out;
        inPos += consumed;
        outPos += produced;
        if (rc != COMP_OK) {
            segment.isalStatus = rc;
            return;
        }
        // igzip_lib.h: a flush is complete once output space is left unused; the stream is complete
        // in the end state.
        if (lastInput && inPos == inSize &&
            (last ? zs.internal_state.state == ZSTATE_END : zs.avail_out != 0))
            break;
        // Neither input taken nor output written although both had room: ISA-L is stuck.
        if (consumed == 0 && produced == 0 && zs.avail_out != 0) {
            segment.isalStatus = kIsalNoProgress;
            return;
        }
    }
    segment.deflated.assign(reinterpret_cast<const char*>(out.data()), outPos);
}

std::string isalError(int status) {
    const char* what = status == ISAL_INVALID_LEVEL       ? "invalid compression level"
                       : status == ISAL_INVALID_LEVEL_BUF ? "level buffer too small"
                       : status == INVALID_FLUSH          ? "invalid flush"
                       : status == kIsalNoProgress        ? "no progress"
                                                          : "error";
    return "PNG encoding failed: ISA-L deflate " + std::string(what) + " (" + std::to_string(status) + ")";
}

Result<std::string> encodeChecked(const PngPixels& pixels) {
    const std::size_t height = std::size_t(pixels.height);
    const std::size_t bytesPerSample = std::size_t(pixels.bitDepth / 8);
    // Cannot overflow: width < 2^31, channels <= 4, 2 bytes per sample, size_t is 64-bit.
    const std::size_t rowBytes = std::size_t(pixels.width) * std::size_t(pixels.channels) * bytesPerSample;
    const std::size_t filteredRowBytes = rowBytes + 1; // PNG 1.2 §6.1: one filter-type byte per row
    if (filteredRowBytes > std::numeric_limits<std::size_t>::max() / height)
        return Error{"PNG encoding failed: the image's byte count overflows (" +
                     std::to_string(pixels.width) + "×" + std::to_string(pixels.height) + ")"};

    const std::size_t rowsPerSegment = pngRowsPerSegment(filteredRowBytes);
    const std::size_t segmentCount = (height + rowsPerSegment - 1) / rowsPerSegment;
    std::vector<Segment> segments(segmentCount);

    tbb::enumerable_thread_specific<Scratch> scratches;
    // One task per segment; each depends only on its rows, so the bytes do not depend on scheduling.
    tbb::parallel_for(std::size_t(0), segmentCount, [&](std::size_t s) {
        Scratch& scratch = scratches.local();
        const std::size_t y0 = s * rowsPerSegment, y1 = std::min(height, y0 + rowsPerSegment);
        const std::size_t bytes = (y1 - y0) * filteredRowBytes;
        if (scratch.filtered.size() < bytes) scratch.filtered.resize(bytes);
        const unsigned char* raw = nullptr;
        if (pixels.data) {
            raw = static_cast<const unsigned char*>(pixels.data) + y0 * rowBytes;
        } else {
            if (scratch.raw.size() < (y1 - y0) * rowBytes) scratch.raw.resize((y1 - y0) * rowBytes);
            pixels.rows(y0, y1, scratch.raw.data());
            raw = scratch.raw.data();
        }
        const std::size_t samplesPerRow = std::size_t(pixels.width) * std::size_t(pixels.channels);
        for (std::size_t y = y0; y < y1; ++y)
            filterRowSub(raw + (y - y0) * rowBytes, samplesPerRow, std::size_t(pixels.channels),
                         pixels.bitDepth, scratch.filtered.data() + (y - y0) * filteredRowBytes);
        Segment& segment = segments[s];
        segment.filteredBytes = bytes;
        segment.adler = isal_adler32(segment.adler, scratch.filtered.data(), bytes);
        deflateSegment(scratch.filtered.data(), bytes, s + 1 == segmentCount, scratch, segment);
    });
    scratches.clear(); // the per-thread buffers are not needed for the assembly

    // The first failure in segment order, so the message too is independent of scheduling.
    for (const Segment& segment : segments)
        if (segment.isalStatus != COMP_OK) return Error{isalError(segment.isalStatus)};

    // RFC 1950 §2.2: CMF = deflate with a 32 KiB window (0x78); FLEVEL as zlib's deflate.c sets it
    // (0 fastest, 1 fast, 2 default, 3 best): 1, ISA-L being a fast compressor; FCHECK makes
    // CMF·256 + FLG a multiple of 31.
    constexpr unsigned kFastLevelFlags = 1;
    unsigned header = (0x78u << 8) | (kFastLevelFlags << 6);
    header += 31 - header % 31;
    const char zlibHeader[2] = {char(header >> 8), char(header)};

    // RFC 1950 §2.2: ADLER32 of all the uncompressed (filtered) bytes, big-endian, after the data.
    uLong adler = adler32_z(0, nullptr, 0);
    for (const Segment& segment : segments)
        adler = adler32_combine(adler, segment.adler, z_off_t(segment.filteredBytes));
    const uint32_t adler32 = uint32_t(adler);
    const char zlibTrailer[4] = {char(adler32 >> 24), char(adler32 >> 16), char(adler32 >> 8), char(adler32)};

    std::vector<std::string_view> pieces;
    pieces.reserve(segmentCount + 2);
    pieces.emplace_back(zlibHeader, 2);
    for (const Segment& segment : segments)
        pieces.emplace_back(segment.deflated);
    pieces.emplace_back(zlibTrailer, 4);
    std::size_t streamBytes = 0;
    for (std::string_view piece : pieces)
        streamBytes += piece.size();
    const std::size_t idatCount = (streamBytes + kMaxIdatBytes - 1) / kMaxIdatBytes;

    // PNG 1.2 §5.3: a chunk is length, type, data, CRC-32 of type and data.
    constexpr std::size_t kChunkOverhead = 12;
    constexpr std::size_t kIhdrDataBytes = 13;
    std::string out;
    out.reserve(8 + (kChunkOverhead + kIhdrDataBytes) + idatCount * kChunkOverhead + streamBytes +
                kChunkOverhead);
    auto beginChunk = [&out](const char* type, std::size_t length) {
        appendU32(out, uint32_t(length));
        const std::size_t start = out.size();
        out.append(type, 4);
        return start;
    };
    auto endChunk = [&out](std::size_t start) {
        const auto* typeAndData = reinterpret_cast<const Bytef*>(out.data() + start);
        appendU32(out, uint32_t(crc32_z(crc32_z(0, nullptr, 0), typeAndData, out.size() - start)));
    };

    // PNG 1.2 §12.12: the signature.
    out.append("\x89PNG\r\n\x1a\n", 8);

    // PNG 1.2 §11.2.2: IHDR; compression 0 (deflate), filter method 0, no interlace.
    std::size_t chunk = beginChunk("IHDR", kIhdrDataBytes);
    appendU32(out, uint32_t(pixels.width));
    appendU32(out, uint32_t(pixels.height));
    out.push_back(char(pixels.bitDepth));
    out.push_back(char(colourType(pixels.channels)));
    out.append(3, '\0');
    endChunk(chunk);

    // PNG 1.2 §11.2.4: the zlib stream split over consecutive IDAT chunks at arbitrary boundaries.
    std::size_t piece = 0, pieceOffset = 0;
    for (std::size_t remaining = streamBytes; remaining > 0;) {
        const std::size_t length = std::min(remaining, kMaxIdatBytes);
        chunk = beginChunk("IDAT", length);
        for (std::size_t left = length; left > 0;) {
            const std::string_view from = pieces[piece];
            const std::size_t take = std::min(left, from.size() - pieceOffset);
            out.append(from.data() + pieceOffset, take);
            left -= take;
            pieceOffset += take;
            if (pieceOffset == from.size()) {
                ++piece;
                pieceOffset = 0;
            }
        }
        endChunk(chunk);
        remaining -= length;
    }

    // PNG 1.2 §11.2.5: IEND, empty.
    endChunk(beginChunk("IEND", 0));
    return out;
}

} // namespace

std::size_t pngRowsPerSegment(std::size_t filteredRowBytes) {
    return std::max<std::size_t>(1, kSegmentTargetBytes / std::max<std::size_t>(1, filteredRowBytes));
}

Result<std::string> encodePng(const PngPixels& pixels) {
    if (pixels.width < 1 || pixels.height < 1 || pixels.width > kMaxPngDimension ||
        pixels.height > kMaxPngDimension)
        return Error{"PNG width and height must be 1 to 2147483647, got " + std::to_string(pixels.width) +
                     "×" + std::to_string(pixels.height)};
    if (pixels.channels < 1 || pixels.channels > 4)
        return Error{"PNG holds 1 to 4 channels (grey, grey+alpha, RGB, RGBA), got " +
                     std::to_string(pixels.channels)};
    if (pixels.bitDepth != 8 && pixels.bitDepth != 16)
        return Error{"PNG encoding supports 8 or 16 bits per sample, got " + std::to_string(pixels.bitDepth)};
    if (!pixels.data && !pixels.rows) return Error{"PNG encoding failed: no pixel data"};
    // Only allocation can throw below (a huge image or output); it becomes an error value.
    try {
        return encodeChecked(pixels);
    } catch (const std::bad_alloc&) {
        return Error{"PNG encoding failed: out of memory for a " + std::to_string(pixels.width) + "×" +
                     std::to_string(pixels.height) + " image"};
    } catch (const std::length_error&) {
        return Error{"PNG encoding failed: the image is too large to hold in memory"};
    }
}

} // namespace burnish
