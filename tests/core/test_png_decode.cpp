// Core's PNG decoder (core/src/io/png_decode.h) and the imports built on it: PNGs built here byte by
// byte (every filter type, channel count and depth, IDAT split anywhere, several row batches) decode
// to exactly the samples they hold; readImage gives bit for bit OpenImageIO's own read_image(FLOAT)
// for them and for the files left to libpng (interlaced, palette, tRNS, 4-bit); loadNormalMap's
// direct PNG path gives bit for bit decodeNormalMap(readImage(...)); corrupt and truncated files
// are errors that say what is wrong, and data past the last row or a cut-off trailer lose nothing.
#include "../../core/src/io/image_read.h"
#include "../../core/src/io/png_decode.h"

#include <burnish/core/io/image.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/util/files.h>

#include "temp_dir.h"

#include <OpenImageIO/imageio.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace burnish {
namespace {

using burnish::test::TempDir;

void appendU32(std::string& out, uint32_t v) {
    const char bytes[4] = {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    out.append(bytes, 4);
}

// PNG 1.2 §5.3: length, type, data, CRC-32 of type and data.
std::string chunk(const std::string& type, const std::string& data) {
    std::string out;
    appendU32(out, uint32_t(data.size()));
    const std::string typeAndData = type + data;
    out += typeAndData;
    appendU32(out, uint32_t(crc32(0, reinterpret_cast<const Bytef*>(typeAndData.data()),
                                  uInt(typeAndData.size()))));
    return out;
}

std::string ihdr(int width, int height, int bitDepth, int colourType, int interlace = 0) {
    std::string data;
    appendU32(data, uint32_t(width));
    appendU32(data, uint32_t(height));
    data += char(bitDepth);
    data += char(colourType);
    data += std::string(2, '\0'); // compression 0, filter method 0
    data += char(interlace);
    return chunk("IHDR", data);
}

std::string zlibCompress(const std::string& data, int level = 6) {
    uLongf size = compressBound(uLong(data.size()));
    std::string out(size, '\0');
    EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(out.data()), &size,
                        reinterpret_cast<const Bytef*>(data.data()), uLong(data.size()), level),
              Z_OK);
    out.resize(size);
    return out;
}

// The zlib stream in IDAT chunks of `piece` bytes (the last shorter).
std::string idats(const std::string& stream, std::size_t piece) {
    std::string out;
    for (std::size_t at = 0; at < stream.size(); at += piece)
        out += chunk("IDAT", stream.substr(at, piece));
    return out;
}

const std::string kSignature("\x89PNG\r\n\x1a\n", 8);

int paeth(int a, int b, int c) {
    const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// PNG 1.2 §6.3, §9: filters row y of `raw` (rowBytes a row) with `type`, independently of the decoder.
std::string filterRow(const std::vector<uint8_t>& raw, std::size_t rowBytes, std::size_t bpp, int y,
                      int type) {
    std::string out(1, char(type));
    const uint8_t* row = raw.data() + std::size_t(y) * rowBytes;
    const uint8_t* up = y > 0 ? row - rowBytes : nullptr;
    for (std::size_t i = 0; i < rowBytes; ++i) {
        const int a = i >= bpp ? row[i - bpp] : 0, b = up ? up[i] : 0, c = up && i >= bpp ? up[i - bpp] : 0;
        const int predictor = type == 0   ? 0
                              : type == 1 ? a
                              : type == 2 ? b
                              : type == 3 ? (a + b) / 2
                                          : paeth(a, b, c);
        out += char(uint8_t(row[i] - predictor));
    }
    return out;
}

// A PNG's stored bytes: smooth gradients plus noise, so every Paeth branch and borrow occurs.
struct Sample {
    int width = 0, height = 0, channels = 0, bitDepth = 8;
    std::vector<uint8_t> raw; // rows as stored (16-bit big-endian)
    std::size_t bpp() const { return std::size_t(channels * bitDepth / 8); }
    void pushCode(int code) { // as stored: one byte, or two big-endian
        if (bitDepth == 16) raw.push_back(uint8_t(code >> 8));
        raw.push_back(uint8_t(code & 0xFF));
    }
    std::size_t rowBytes() const { return std::size_t(width) * bpp(); }
};

Sample makeSample(int width, int height, int channels, int bitDepth, unsigned seed) {
    Sample s{width, height, channels, bitDepth, {}};
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> noise(-6, 6);
    const int maxCode = bitDepth == 8 ? 255 : 65535;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < channels; ++c) {
                const int base = (x * 37 + y * 11 + c * 70) % (maxCode + 1);
                s.pushCode(std::clamp(base + noise(rng) * (bitDepth == 8 ? 1 : 257), 0, maxCode));
            }
    return s;
}

int colourTypeOf(int channels) {
    return channels == 1 ? 0 : channels == 2 ? 4 : channels == 3 ? 2 : 6;
}

// The filtered rows; `filterOf(y)` picks each row's filter.
template <class FilterOf> std::string filtered(const Sample& s, FilterOf filterOf) {
    std::string rows;
    for (int y = 0; y < s.height; ++y)
        rows += filterRow(s.raw, s.rowBytes(), s.bpp(), y, filterOf(y));
    return rows;
}

std::string pngOf(const Sample& s, const std::string& rows, std::size_t idatPiece = 997,
                  const std::string& before = {}) {
    return kSignature + ihdr(s.width, s.height, s.bitDepth, colourTypeOf(s.channels)) + before +
           idats(zlibCompress(rows), idatPiece) + chunk("IEND", "");
}

struct Decoded {
    Status status;
    std::vector<uint8_t> raw;
    std::vector<std::pair<int, int>> batches;
};

Decoded decode(const std::string& png) {
    Decoded out;
    const auto layout = parsePng(png);
    if (!layout) {
        out.status = Error{layout.error()};
        return out;
    }
    EXPECT_TRUE(layout->decodable);
    out.raw.assign(layout->rowBytes() * std::size_t(layout->height) + kPngDecodePadding, 0);
    out.status =
        decodePngRows(*layout, out.raw.data(), [&](int y0, int y1) { out.batches.emplace_back(y0, y1); });
    out.raw.resize(layout->rowBytes() * std::size_t(layout->height));
    return out;
}

// OpenImageIO's own float read of the file: the reference readImage must match bit for bit.
std::vector<float> oiioFloats(const std::filesystem::path& path, int& channels) {
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path.string(), &config);
    EXPECT_TRUE(in) << OIIO::geterror();
    if (!in) return {};
    const OIIO::ImageSpec& spec = in->spec();
    channels = spec.nchannels;
    std::vector<float> pixels(std::size_t(spec.width) * std::size_t(spec.height) *
                              std::size_t(spec.nchannels));
    EXPECT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
        << in->geterror();
    return pixels;
}

void expectReadsLikeOiio(const std::filesystem::path& path, const std::string& what) {
    const auto image = readImage(path);
    ASSERT_TRUE(image.ok()) << what << ": " << image.error();
    int channels = 0;
    const std::vector<float> expected = oiioFloats(path, channels);
    ASSERT_EQ(image->channels, channels) << what;
    ASSERT_EQ(image->pixels.size(), expected.size()) << what;
    EXPECT_EQ(std::memcmp(image->pixels.data(), expected.data(), expected.size() * sizeof(float)), 0)
        << what << ": readImage differs from OpenImageIO's read_image(FLOAT)";
    // What the file is said to be, as OpenImageIO would say it (core's decoder never asks it).
    auto in = OIIO::ImageInput::open(path.string());
    ASSERT_TRUE(in) << what;
    EXPECT_EQ(image->source.formatName, in->format_name()) << what;
    EXPECT_EQ(image->source.channelType, in->spec().format.c_str()) << what;
    EXPECT_EQ(image->source.bitsPerChannel, int(in->spec().format.size() * 8)) << what;
    EXPECT_EQ(image->source.isFloat, in->spec().format.is_floating_point()) << what;
    EXPECT_EQ(image->source.colorSpace, in->spec().get_string_attribute("oiio:ColorSpace")) << what;
}

std::string describe(const Sample& s) {
    return std::to_string(s.width) + "x" + std::to_string(s.height) + " " + std::to_string(s.channels) +
           "ch " + std::to_string(s.bitDepth) + "-bit";
}

TEST(PngDecode, EveryFilterChannelCountAndDepthDecodesExactly) {
    // Each row's filter cycles through None, Sub, Up, Average, Paeth; then whole images of one
    // filter (Paeth rows after Paeth rows is the common case). 37×23: primes; 1×1 and 1×9: one texel a
    // row, where every predictor is at the edge.
    unsigned seed = 1;
    for (const auto& [width, height] : {std::pair{37, 23}, std::pair{1, 1}, std::pair{1, 9}, std::pair{2, 6}})
        for (int bitDepth : {8, 16})
            for (int channels = 1; channels <= 4; ++channels) {
                const Sample s = makeSample(width, height, channels, bitDepth, seed++);
                for (int only = -1; only <= 4; ++only) {
                    const std::string png =
                        pngOf(s, filtered(s, [&](int y) { return only < 0 ? y % 5 : only; }));
                    const Decoded d = decode(png);
                    const std::string what =
                        describe(s) + " filter " + (only < 0 ? "cycling" : std::to_string(only));
                    ASSERT_TRUE(d.status.ok()) << what << ": " << d.status.error();
                    EXPECT_TRUE(d.raw == s.raw) << what;
                }
            }
}

TEST(PngDecode, RowsArriveInOrderedBatchesCoveringTheImage) {
    // 600×200 RGBA16: 4801 filtered bytes a row, ~0.9 MiB, several batches; IDAT in 1000-byte pieces.
    const Sample s = makeSample(600, 200, 4, 16, 99);
    const Decoded d = decode(pngOf(s, filtered(s, [](int y) { return y % 5; }), 1000));
    ASSERT_TRUE(d.status.ok()) << d.status.error();
    EXPECT_TRUE(d.raw == s.raw);
    ASSERT_GT(d.batches.size(), 1u);
    int next = 0;
    for (const auto& [y0, y1] : d.batches) {
        EXPECT_EQ(y0, next);
        EXPECT_GT(y1, y0);
        next = y1;
    }
    EXPECT_EQ(next, s.height);
}

TEST(PngDecode, ReadImageMatchesOpenImageIO) {
    TempDir dir;
    unsigned seed = 50;
    for (int bitDepth : {8, 16})
        for (int channels = 1; channels <= 4; ++channels) {
            const Sample s = makeSample(53, 31, channels, bitDepth, seed++);
            const auto path = dir / ("s" + std::to_string(seed) + ".png");
            ASSERT_TRUE(writeFileAtomic(path, pngOf(s, filtered(s, [](int y) { return (y * 3) % 5; }))).ok());
            expectReadsLikeOiio(path, describe(s));
        }
}

TEST(PngDecode, ColourTagsAndCodeFloatsAreOpenImageIOs) {
    // sRGB, gAMA of display gamma 2.2 and 1.0, gAMA beside sRGB (sRGB wins), none.
    std::string gamma22, gamma1;
    appendU32(gamma22, 45455);
    appendU32(gamma1, 100000);
    const std::vector<std::pair<std::string, std::string>> tags = {
        {"sRGB", chunk("sRGB", std::string(1, '\0'))},
        {"gAMA 2.2", chunk("gAMA", gamma22)},
        {"gAMA 1", chunk("gAMA", gamma1)},
        {"gAMA and sRGB", chunk("gAMA", gamma22) + chunk("sRGB", std::string(1, '\0'))},
        {"no tag", ""}};
    TempDir dir;
    unsigned seed = 90;
    for (const auto& [name, before] : tags)
        for (int bitDepth : {8, 16}) {
            const Sample s = makeSample(9, 7, 3, bitDepth, seed++);
            const auto path = dir / ("tag" + std::to_string(seed) + ".png");
            ASSERT_TRUE(
                writeFileAtomic(path, pngOf(s, filtered(s, [](int) { return 4; }), 997, before)).ok());
            expectReadsLikeOiio(path, name + " " + describe(s));
        }
    // Every 8- and 16-bit code's float is OpenImageIO's conversion, bit for bit.
    for (int bitDepth : {8, 16}) {
        const std::vector<float> table = unsignedCodeTable(bitDepth);
        std::vector<float> oiio(table.size());
        std::vector<uint8_t> codes8(bitDepth == 8 ? 256 : 0);
        std::vector<uint16_t> codes16(bitDepth == 16 ? 65536 : 0);
        for (size_t c = 0; c < codes8.size(); ++c)
            codes8[c] = uint8_t(c);
        for (size_t c = 0; c < codes16.size(); ++c)
            codes16[c] = uint16_t(c);
        const void* data = bitDepth == 8 ? static_cast<const void*>(codes8.data()) : codes16.data();
        ASSERT_TRUE(OIIO::convert_pixel_values(bitDepth == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16,
                                               data, OIIO::TypeDesc::FLOAT, oiio.data(), int(oiio.size())));
        EXPECT_EQ(std::memcmp(table.data(), oiio.data(), table.size() * sizeof(float)), 0) << bitDepth;
    }
}

TEST(PngDecode, FilesLeftToLibpngStillReadLikeOpenImageIO) {
    TempDir dir;
    // Interlaced (Adam7) 1×1 RGB: only pass 1 holds a texel.
    {
        const std::string rows = std::string(1, '\0') + "\x10\x80\xF0";
        const std::string png =
            kSignature + ihdr(1, 1, 8, 2, 1) + idats(zlibCompress(rows), 100) + chunk("IEND", "");
        const auto layout = parsePng(png);
        ASSERT_TRUE(layout.ok()) << layout.error();
        EXPECT_FALSE(layout->decodable);
        ASSERT_TRUE(writeFileAtomic(dir / "adam7.png", png).ok());
        expectReadsLikeOiio(dir / "adam7.png", "interlaced");
    }
    // Palette: 4×2, three colours.
    {
        const std::string plte("\x00\x00\xFF\x80\x80\x80\xFF\x10\x20", 9);
        const std::string rows = std::string("\0\0\1\2\1", 5) + std::string("\0\2\2\0\1", 5);
        const std::string png = kSignature + ihdr(4, 2, 8, 3) + chunk("PLTE", plte) +
                                idats(zlibCompress(rows), 100) + chunk("IEND", "");
        EXPECT_FALSE(parsePng(png)->decodable);
        ASSERT_TRUE(writeFileAtomic(dir / "palette.png", png).ok());
        expectReadsLikeOiio(dir / "palette.png", "palette");
    }
    // RGB with tRNS (libpng may add an alpha channel) and 4-bit grey.
    {
        const Sample s = makeSample(5, 3, 3, 8, 7);
        const std::string png =
            pngOf(s, filtered(s, [](int) { return 4; }), 997, chunk("tRNS", std::string(6, '\0')));
        EXPECT_FALSE(parsePng(png)->decodable);
        ASSERT_TRUE(writeFileAtomic(dir / "trns.png", png).ok());
        expectReadsLikeOiio(dir / "trns.png", "tRNS");
    }
    {
        const std::string rows = std::string("\0\x12\x34", 3) + std::string("\0\xAB\xCD", 3);
        const std::string png =
            kSignature + ihdr(4, 2, 4, 0) + idats(zlibCompress(rows), 100) + chunk("IEND", "");
        EXPECT_FALSE(parsePng(png)->decodable);
        ASSERT_TRUE(writeFileAtomic(dir / "grey4.png", png).ok());
        expectReadsLikeOiio(dir / "grey4.png", "4-bit grey");
    }
}

TEST(PngDecode, CorruptFilesAreErrorsThatSayWhy) {
    const Sample s = makeSample(40, 30, 3, 8, 3);
    const std::string rows = filtered(s, [](int y) { return y % 5; });
    const std::string good = pngOf(s, rows, 500);
    ASSERT_TRUE(decode(good).status.ok());
    auto expectError = [](const std::string& png, const std::string& needle, const std::string& what) {
        const Decoded d = decode(png);
        ASSERT_FALSE(d.status.ok()) << what;
        EXPECT_NE(d.status.error().find(needle), std::string::npos) << what << ": " << d.status.error();
    };
    const std::size_t firstIdatData = 8 + 25 + 8; // signature, IHDR chunk, IDAT length and type

    std::string bad = good;
    bad[firstIdatData + 10] = char(bad[firstIdatData + 10] ^ 0x40);
    expectError(bad, "CRC mismatch in chunk IDAT", "flipped IDAT byte");
    expectError(good.substr(0, good.size() / 2), "truncated PNG image data", "cut inside the image data");
    expectError(good.substr(0, 8 + 20), "truncated PNG file", "cut inside IHDR");
    expectError(std::string("\x89PNG\r\n\x1a\x0a", 7), "not a PNG", "short signature");
    expectError("GIF89a" + good.substr(6), "not a PNG", "wrong signature");

    // Unknown filter type 5 in row 3.
    std::string badRows = rows;
    badRows[3 * (s.rowBytes() + 1)] = 5;
    expectError(pngOf(s, badRows), "unknown filter type 5 in row 3", "filter type 5");
    // Valid zlib framing around garbage deflate data.
    expectError(pngOf(s, rows).substr(0, 8 + 25) +
                    chunk("IDAT", std::string("\x78\x9c\xff\xff\xff\xff\xff", 7)) + chunk("IEND", ""),
                "corrupt PNG image data", "garbage deflate");
    // A stream of fewer rows than the header says.
    expectError(pngOf(s, rows.substr(0, 10 * (s.rowBytes() + 1))), "truncated PNG image data",
                "10 of 30 rows");
    // Wrong adler32 (the chunk CRCs recomputed, so only the zlib check can tell).
    std::string stream = zlibCompress(rows);
    stream.back() = char(stream.back() ^ 1);
    expectError(kSignature + ihdr(40, 30, 8, 2) + idats(stream, 500) + chunk("IEND", ""), "adler32",
                "adler32");
    // Bad header fields and chunk order.
    expectError(kSignature + ihdr(0, 30, 8, 2) + idats(zlibCompress(rows), 500), "corrupt PNG header",
                "width 0");
    expectError(kSignature + ihdr(40, 30, 12, 2) + idats(zlibCompress(rows), 500), "corrupt PNG header",
                "12-bit");
    expectError(kSignature + chunk("IDAT", "x") + ihdr(40, 30, 8, 2), "IHDR is not the first chunk",
                "IDAT first");
    expectError(kSignature + ihdr(40, 30, 8, 2) + chunk("IEND", ""), "no image data", "no IDAT");
    const std::string stream2 = zlibCompress(rows);
    expectError(kSignature + ihdr(40, 30, 8, 2) + chunk("IDAT", stream2.substr(0, 100)) +
                    chunk("tEXt", "a\0b") + chunk("IDAT", stream2.substr(100)) + chunk("IEND", ""),
                "not consecutive", "split IDAT");
}

TEST(PngDecode, DataPastTheRowsAndACutTrailerLoseNothing) {
    const Sample s = makeSample(40, 30, 4, 8, 4);
    const std::string rows = filtered(s, [](int y) { return y % 5; });
    // Extra bytes in the stream after the last row (libpng warns and reads the image).
    const Decoded extra = decode(pngOf(s, rows + std::string(300, '\x07')));
    ASSERT_TRUE(extra.status.ok()) << extra.status.error();
    EXPECT_TRUE(extra.raw == s.raw);
    // No IEND, and an ancillary chunk cut off after the image data.
    const std::string noTrailer = kSignature + ihdr(40, 30, 8, 6) + idats(zlibCompress(rows), 700);
    const Decoded cut = decode(noTrailer + chunk("tEXt", "comment").substr(0, 9));
    ASSERT_TRUE(cut.status.ok()) << cut.status.error();
    EXPECT_TRUE(cut.raw == s.raw);
    // An ancillary chunk with a wrong CRC is skipped, as libpng skips it.
    std::string text = chunk("tEXt", "key\0value");
    text.back() = char(text.back() ^ 1);
    const Decoded skipped = decode(pngOf(s, rows, 997, text));
    ASSERT_TRUE(skipped.status.ok()) << skipped.status.error();
    EXPECT_TRUE(skipped.raw == s.raw);
    // A wrong CRC in IEND, which holds no data (seen in real files that libpng reads).
    std::string badEnd = pngOf(s, rows);
    badEnd.back() = char(badEnd.back() ^ 1);
    const Decoded end = decode(badEnd);
    ASSERT_TRUE(end.status.ok()) << end.status.error();
    EXPECT_TRUE(end.raw == s.raw);
}

TEST(PngDecode, DamagedFilesNeverCrashOrHang) {
    // Random byte damage, with the chunk CRCs recomputed so the damage reaches the inflater and the
    // unfilter too, and truncation at every length in steps: each decode either succeeds with the
    // full image or fails with a message (the sanitizer builds check the memory accesses).
    const Sample s = makeSample(33, 21, 4, 8, 12);
    const std::string rows = filtered(s, [](int y) { return 4 - y % 5; });
    const std::string stream = zlibCompress(rows);
    std::mt19937 rng(2024);
    for (int trial = 0; trial < 400; ++trial) {
        std::string damaged = stream;
        const int flips = 1 + trial % 4;
        for (int f = 0; f < flips; ++f)
            damaged[rng() % damaged.size()] = char(rng());
        const std::string png =
            kSignature + ihdr(33, 21, 8, 6) + idats(damaged, 50 + trial % 300) + chunk("IEND", "");
        const Decoded d = decode(png);
        if (d.status.ok())
            EXPECT_EQ(d.raw.size(), s.raw.size()) << "trial " << trial;
        else
            EXPECT_FALSE(d.status.error().empty()) << "trial " << trial;
    }
    // A cut inside the image data is an error; one that loses only IEND (12 bytes) loses no pixel.
    const std::string good = pngOf(s, rows, 200);
    constexpr std::size_t kIendBytes = 12;
    for (std::size_t length = 0; length < good.size(); length += 7) {
        const Decoded d = decode(good.substr(0, length));
        if (length < good.size() - kIendBytes)
            EXPECT_FALSE(d.status.ok()) << "cut at " << length << " of " << good.size();
        else
            EXPECT_TRUE(d.status.ok() && d.raw == s.raw) << "cut at " << length << " of " << good.size();
    }
}

// What core leaves to libpng (interlaced, palette, low depths) is checked before libpng reads it:
// a damaged file is one error from core, and libpng prints nothing of its own on stderr.
TEST(PngDecode, FilesLeftToLibpngAreCheckedFirst) {
    TempDir dir;
    // A 9×9 Adam7 RGB image: the rows of all seven passes, filter type 0, grey ramps.
    const int passes[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                              {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};
    std::string rows;
    std::vector<std::size_t> rowStarts;
    for (const auto& p : passes) {
        const int w = (9 - p[0] + p[2] - 1) / p[2], h = (9 - p[1] + p[3] - 1) / p[3];
        for (int y = 0; y < h; ++y) {
            rowStarts.push_back(rows.size());
            rows += '\0';
            for (int x = 0; x < 3 * w; ++x)
                rows += char(17 * x + y);
        }
    }
    auto pngWith = [&](const std::string& stream) {
        return kSignature + ihdr(9, 9, 8, 2, 1) + idats(stream, 40) + chunk("IEND", "");
    };
    const std::string good = pngWith(zlibCompress(rows));
    const auto layout = parsePng(good);
    ASSERT_TRUE(layout.ok()) << layout.error();
    EXPECT_FALSE(layout->decodable);
    EXPECT_TRUE(layout->interlaced);
    EXPECT_TRUE(checkPngData(*layout).ok()) << checkPngData(*layout).error();
    ASSERT_TRUE(writeFileAtomic(dir / "good.png", good).ok());
    expectReadsLikeOiio(dir / "good.png", "9x9 interlaced");

    std::string badFilter = rows;
    badFilter[rowStarts[9]] = 7; // a row of pass 4
    std::string adler = zlibCompress(rows);
    adler.back() = char(adler.back() ^ 1);
    const std::vector<std::tuple<std::string, std::string, std::string>> damaged{
        {"filter.png", pngWith(zlibCompress(badFilter)), "unknown filter type 7"},
        {"short.png", pngWith(zlibCompress(rows.substr(0, rows.size() / 2))), "truncated PNG image data"},
        {"adler.png", pngWith(adler), "adler32"},
        {"garbage.png", pngWith(std::string("\x78\x9c\xff\xff\xff\xff\xff", 7)), "corrupt PNG image data"}};
    for (const auto& [name, png, needle] : damaged) {
        SCOPED_TRACE(name);
        const auto parsed = parsePng(png);
        ASSERT_TRUE(parsed.ok()) << parsed.error();
        const Status checked = checkPngData(*parsed);
        ASSERT_FALSE(checked.ok());
        EXPECT_NE(checked.error().find(needle), std::string::npos) << checked.error();
        ASSERT_TRUE(writeFileAtomic(dir / name, png).ok());
        // stderr into a file while the image is read: nothing may arrive there.
        const auto errPath = dir / (name + ".stderr");
        std::fflush(stderr);
        const int saved = ::dup(2);
        const int to = ::open(errPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ::dup2(to, 2);
        const auto image = readImage(dir / name);
        std::fflush(stderr);
        ::dup2(saved, 2);
        ::close(to);
        ::close(saved);
        ASSERT_FALSE(image.ok());
        EXPECT_NE(image.error().find(name), std::string::npos) << image.error();
        EXPECT_NE(image.error().find(needle), std::string::npos) << image.error();
        EXPECT_EQ(std::filesystem::file_size(errPath), 0u) << readFile(errPath).value();
    }
}

TEST(PngDecode, ReadImageNamesTheFileOfACorruptPng) {
    TempDir dir;
    const Sample s = makeSample(40, 30, 3, 8, 5);
    std::string png = pngOf(s, filtered(s, [](int y) { return y % 5; }), 500);
    png[8 + 25 + 8 + 20] = char(png[8 + 25 + 8 + 20] ^ 0x10);
    const auto path = dir / "broken.png";
    ASSERT_TRUE(writeFileAtomic(path, png).ok());
    const auto image = readImage(path);
    ASSERT_FALSE(image.ok());
    EXPECT_NE(image.error().find("broken.png"), std::string::npos) << image.error();
    EXPECT_NE(image.error().find("CRC"), std::string::npos) << image.error();
    const auto map = loadNormalMap(path);
    ASSERT_FALSE(map.ok());
    EXPECT_NE(map.error().find("broken.png"), std::string::npos) << map.error();
}

void expectSameNormalMap(const std::filesystem::path& path, const NormalMapOptions& options,
                         const std::string& what) {
    const auto direct = loadNormalMap(path, options);
    const auto image = readImage(path);
    ASSERT_TRUE(image.ok()) << what << ": " << image.error();
    const auto reference = decodeNormalMap(*image, options);
    ASSERT_EQ(direct.ok(), reference.ok()) << what;
    if (!reference.ok()) {
        EXPECT_EQ(direct.error(), reference.error()) << what;
        return;
    }
    ASSERT_EQ(direct->normals.size(), reference->normals.size()) << what;
    EXPECT_EQ(std::memcmp(direct->normals.data(), reference->normals.data(),
                          reference->normals.size() * sizeof(glm::vec3)),
              0)
        << what << ": normals differ";
    const NormalMapDiagnostics &a = direct->diagnostics, &b = reference->diagnostics;
    EXPECT_EQ(a.texels, b.texels) << what;
    EXPECT_EQ(a.nonFiniteTexels, b.nonFiniteTexels) << what;
    EXPECT_EQ(a.zeroLengthTexels, b.zeroLengthTexels) << what;
    EXPECT_EQ(a.negativeZTexels, b.negativeZTexels) << what;
    EXPECT_EQ(a.offLengthTexels, b.offLengthTexels) << what;
    EXPECT_EQ(a.meanStoredLength, b.meanStoredLength) << what; // same blocks, same order: exact
    EXPECT_EQ(a.zRebuilt, b.zRebuilt) << what;
    EXPECT_EQ(a.alphaIgnored, b.alphaIgnored) << what;
    EXPECT_EQ(a.greenFlipped, b.greenFlipped) << what;
    EXPECT_EQ(a.signedValues, b.signedValues) << what;
    EXPECT_EQ(a.warnings, b.warnings) << what;
    EXPECT_EQ(direct->source.formatName, reference->source.formatName) << what;
    EXPECT_EQ(direct->source.channelType, reference->source.channelType) << what;
}

// A normal map's codes: tilted normals around +z, blue from z unless `blue` is given.
Sample normalSample(int width, int height, int channels, int bitDepth, int blue = -1) {
    Sample s{width, height, channels, bitDepth, {}};
    const double maxCode = bitDepth == 8 ? 255.0 : 65535.0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const double nx = 0.4 * std::sin(0.3 * x + 0.1 * y), ny = 0.4 * std::cos(0.2 * y - 0.05 * x);
            const double nz = std::sqrt(std::max(0.0, 1.0 - nx * nx - ny * ny));
            const double v[4] = {nx, ny, nz, 0.5};
            for (int c = 0; c < channels; ++c) {
                const int code = int(std::lround((0.5 * v[c] + 0.5) * maxCode));
                s.pushCode(c == 2 && blue >= 0 ? blue : code);
            }
        }
    return s;
}

TEST(PngDecode, LoadNormalMapMatchesDecodingTheReadImage) {
    TempDir dir;
    auto write = [&](const Sample& s, const std::string& name) {
        const auto path = dir / name;
        EXPECT_TRUE(writeFileAtomic(path, pngOf(s, filtered(s, [](int y) { return (y + 4) % 5; }))).ok());
        return path;
    };
    const NormalMapOptions defaults;
    NormalMapOptions directX;
    directX.green = GreenConvention::DirectX;
    NormalMapOptions keepLength;
    keepLength.renormalize = false;
    // 300×200: 60000 texels, one block of 65536; 700×400: five blocks, decoded as their rows arrive.
    expectSameNormalMap(write(normalSample(300, 200, 3, 8), "rgb8.png"), defaults, "RGB8");
    expectSameNormalMap(write(normalSample(700, 400, 3, 8), "rgb8-big.png"), defaults, "RGB8 several blocks");
    expectSameNormalMap(write(normalSample(700, 400, 3, 8), "rgb8-dx.png"), directX, "RGB8 DirectX");
    expectSameNormalMap(write(normalSample(300, 200, 4, 16), "rgba16.png"), keepLength, "RGBA16 kept length");
    expectSameNormalMap(write(normalSample(300, 200, 2, 8), "ga8.png"), defaults, "grey+alpha as RG");
    expectSameNormalMap(write(normalSample(1, 1, 3, 8), "one.png"), defaults, "1x1");
    // Constant blue (a BC5-style map saved as RGB): read as RG with z rebuilt, as decodeNormalMap does.
    const auto constantBlue = write(normalSample(700, 400, 3, 8, 0), "blue0.png");
    expectSameNormalMap(constantBlue, defaults, "constant blue");
    const auto loaded = loadNormalMap(constantBlue);
    ASSERT_TRUE(loaded.ok()) << loaded.error();
    EXPECT_TRUE(loaded->diagnostics.zRebuilt);
    // Blue that first varies only in the last row: decided at the end, as RGB.
    Sample late = normalSample(700, 400, 3, 8, 128);
    late.raw[late.raw.size() - 1] = 129;
    expectSameNormalMap(write(late, "late-blue.png"), defaults, "blue varying in the last texel");
    // Not a normal map (uniform noise): the same refusal.
    expectSameNormalMap(write(makeSample(200, 100, 3, 8, 77), "noise.png"), defaults, "noise");
    // A real map from the test data.
    expectSameNormalMap(std::filesystem::path(BURNISH_TEST_DATA_DIR) / "trak-rust1_nm.png", defaults,
                        "trak-rust1");
}

} // namespace
} // namespace burnish
