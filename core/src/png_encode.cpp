#include "png_encode.h"

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
// deflateInit cost, small enough that 4096² RGB16 (96 MiB filtered) splits into ~100 tasks.
constexpr std::size_t kSegmentTargetBytes = std::size_t(1) << 20;
// IDAT chunks of at most 1 MiB: readers accept any split, and 1 MiB keeps the chunk count small.
constexpr std::size_t kMaxIdatBytes = std::size_t(1) << 20;
// zlib's avail_in/avail_out are 32-bit: inputs and outputs larger than this are fed in pieces.
constexpr std::size_t kMaxZlibPiece = std::size_t(1) << 30;
// Z_SYNC_FLUSH ends a segment with an empty stored block (up to 7 bits of padding and 4 bytes
// LEN/NLEN) that deflateBound, which assumes one Z_FINISH, does not count; the output still grows
// if ever this is too little.
constexpr std::size_t kSyncFlushSlack = 16;
// PNG 1.2 §11.2.2: width and height are at most 2^31 - 1.
constexpr int kMaxPngDimension = std::numeric_limits<int32_t>::max();
// raw deflate (no zlib wrapper) with the full 32 KiB window, zlib's default memory level 8.
constexpr int kRawDeflateWindowBits = -15;
constexpr int kDefaultMemLevel = 8;

static_assert(sizeof(uLong) >= sizeof(std::size_t), "deflateBound needs a 64-bit uLong");
static_assert(sizeof(z_off_t) >= sizeof(std::size_t), "adler32_combine needs a 64-bit z_off_t");

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
// Writes the filter-type byte and the filtered row of y to out.
void filterRowSub(const PngPixels& pixels, std::size_t y, unsigned char* out) {
    const std::size_t channels = std::size_t(pixels.channels);
    const std::size_t samplesPerRow = std::size_t(pixels.width) * channels;
    out[0] = 1;
    unsigned char* sub = out + 1;
    if (pixels.bitDepth == 8) {
        const auto* raw = static_cast<const uint8_t*>(pixels.data) + y * samplesPerRow;
        for (std::size_t k = 0; k < channels; ++k)
            sub[k] = raw[k];
        for (std::size_t k = channels; k < samplesPerRow; ++k)
            sub[k] = uint8_t(raw[k] - raw[k - channels]);
        return;
    }
    // 16-bit samples are stored big-endian (PNG 1.2 §2.1); the byte bpp to the left of each byte is
    // the same byte of the sample one pixel to the left, so the high and low bytes subtract apart.
    const auto* raw = static_cast<const uint16_t*>(pixels.data) + y * samplesPerRow;
    for (std::size_t k = 0; k < channels; ++k) {
        sub[2 * k] = uint8_t(raw[k] >> 8);
        sub[2 * k + 1] = uint8_t(raw[k]);
    }
    for (std::size_t k = channels; k < samplesPerRow; ++k) {
        const uint16_t v = raw[k], left = raw[k - channels];
        sub[2 * k] = uint8_t((v >> 8) - (left >> 8));
        sub[2 * k + 1] = uint8_t(v - left);
    }
}

// Frees a z_stream however the deflate ends.
struct DeflateStream {
    z_stream zs{};
    bool initialized = false;
    ~DeflateStream() {
        if (initialized) deflateEnd(&zs);
    }
};

// Per-thread buffers, reused from segment to segment.
struct Scratch {
    std::vector<unsigned char> filtered;
    std::vector<unsigned char> compressed;
};

/// One segment's compressed bytes (raw deflate) and the adler32 of its filtered bytes.
struct Segment {
    std::string deflated;
    uLong adler = 0;
    std::size_t filteredBytes = 0;
    int zlibStatus = Z_OK;
    std::string zlibMessage;
};

// Raw-deflates `in` into `scratch` and copies the result to `segment.deflated`. The segment ends with
// Z_SYNC_FLUSH (byte-aligned, not final: the next segment's blocks follow) or, for the last one,
// Z_FINISH (the final block).
void deflateSegment(const unsigned char* in, std::size_t inSize, int level, bool last,
                    std::vector<unsigned char>& scratch, Segment& segment) {
    DeflateStream stream;
    z_stream& zs = stream.zs;
    int rc =
        deflateInit2(&zs, level, Z_DEFLATED, kRawDeflateWindowBits, kDefaultMemLevel, Z_DEFAULT_STRATEGY);
    if (rc != Z_OK) {
        segment.zlibStatus = rc;
        return;
    }
    stream.initialized = true;
    const std::size_t bound = std::size_t(deflateBound(&zs, uLong(inSize))) + kSyncFlushSlack;
    if (scratch.size() < bound) scratch.resize(bound);

    const int finalFlush = last ? Z_FINISH : Z_SYNC_FLUSH;
    std::size_t inPos = 0, outPos = 0;
    for (;;) {
        if (outPos == scratch.size()) scratch.resize(scratch.size() * 2);
        const std::size_t inPiece = std::min(inSize - inPos, kMaxZlibPiece);
        const std::size_t outPiece = std::min(scratch.size() - outPos, kMaxZlibPiece);
        const bool lastInput = inPos + inPiece == inSize;
        zs.next_in = const_cast<Bytef*>(in + inPos); // zlib's API predates const; it never writes here
        zs.avail_in = uInt(inPiece);
        zs.next_out = scratch.data() + outPos;
        zs.avail_out = uInt(outPiece);
        rc = deflate(&zs, lastInput ? finalFlush : Z_NO_FLUSH);
        const std::size_t consumed = inPiece - zs.avail_in, produced = outPiece - zs.avail_out;
        inPos += consumed;
        outPos += produced;
        if (rc == Z_STREAM_END) break;
        // Z_BUF_ERROR only means "no progress": an error only if output space was there to use.
        if (rc != Z_OK && !(rc == Z_BUF_ERROR && zs.avail_out == 0)) {
            segment.zlibStatus = rc;
            if (zs.msg) segment.zlibMessage = zs.msg;
            return;
        }
        // A flush is complete when deflate leaves output space unused (zlib manual, deflate()).
        if (!last && lastInput && inPos == inSize && zs.avail_out != 0) break;
    }
    segment.deflated.assign(reinterpret_cast<const char*>(scratch.data()), outPos);
}

std::string zlibError(const Segment& segment) {
    const char* name = segment.zlibStatus == Z_MEM_ERROR      ? "out of memory"
                       : segment.zlibStatus == Z_STREAM_ERROR ? "invalid parameter"
                                                              : "error";
    std::string message =
        "PNG encoding failed: zlib " + std::string(name) + " (" + std::to_string(segment.zlibStatus) + ")";
    if (!segment.zlibMessage.empty()) message += ": " + segment.zlibMessage;
    return message;
}

Result<std::string> encodeChecked(const PngPixels& pixels, int level) {
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
        for (std::size_t y = y0; y < y1; ++y)
            filterRowSub(pixels, y, scratch.filtered.data() + (y - y0) * filteredRowBytes);
        Segment& segment = segments[s];
        segment.filteredBytes = bytes;
        segment.adler = adler32_z(adler32_z(0, nullptr, 0), scratch.filtered.data(), bytes);
        deflateSegment(scratch.filtered.data(), bytes, level, s + 1 == segmentCount, scratch.compressed,
                       segment);
    });
    scratches.clear(); // the per-thread buffers are not needed for the assembly

    // The first failure in segment order, so the message too is independent of scheduling.
    for (const Segment& segment : segments)
        if (segment.zlibStatus != Z_OK) return Error{zlibError(segment)};

    // RFC 1950 §2.2: CMF = deflate with a 32 KiB window (0x78); FLEVEL as zlib's deflate.c sets it
    // (0 fastest, 1 fast, 2 default, 3 best); FCHECK makes CMF·256 + FLG a multiple of 31.
    const unsigned levelFlags = level < 2 ? 0 : level < 6 ? 1 : level == 6 ? 2 : 3;
    unsigned header = (0x78u << 8) | (levelFlags << 6);
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

Result<std::string> encodePng(const PngPixels& pixels, int level) {
    if (pixels.width < 1 || pixels.height < 1 || pixels.width > kMaxPngDimension ||
        pixels.height > kMaxPngDimension)
        return Error{"PNG width and height must be 1 to 2147483647, got " + std::to_string(pixels.width) +
                     "×" + std::to_string(pixels.height)};
    if (pixels.channels < 1 || pixels.channels > 4)
        return Error{"PNG holds 1 to 4 channels (grey, grey+alpha, RGB, RGBA), got " +
                     std::to_string(pixels.channels)};
    if (pixels.bitDepth != 8 && pixels.bitDepth != 16)
        return Error{"PNG encoding supports 8 or 16 bits per sample, got " + std::to_string(pixels.bitDepth)};
    if (!pixels.data) return Error{"PNG encoding failed: no pixel data"};
    if (level < 0 || level > 9)
        return Error{"PNG compression level must be 0 to 9, got " + std::to_string(level)};
    // Only allocation can throw below (a huge image or output); it becomes an error value.
    try {
        return encodeChecked(pixels, level);
    } catch (const std::bad_alloc&) {
        return Error{"PNG encoding failed: out of memory for a " + std::to_string(pixels.width) + "×" +
                     std::to_string(pixels.height) + " image"};
    } catch (const std::length_error&) {
        return Error{"PNG encoding failed: the image is too large to hold in memory"};
    }
}

} // namespace burnish
