// The parallel PNG encoder (core/src/io/png_encode.h): bit-exact round trips through OpenImageIO for
// every channel count and depth, the chunk layout, a zlib stream that really is made of independent
// segments and holds exactly the Sub-filtered rows, bytes independent of the thread count, and errors
// for bad input.
#include "../../core/src/io/png_encode.h"

#include <burnish/core/util/files.h>

#include "temp_dir.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace burnish {
namespace {

using burnish::test::TempDir;

// encodePng's IDAT limit (each chunk's data at most 1 MiB, as png_encode.h promises).
constexpr std::size_t kMaxIdatBytes = std::size_t(1) << 20;
// The four bytes a Z_SYNC_FLUSH ends on (an empty stored block's LEN = 0, NLEN = 0xFFFF): one between
// every two segments. Deflated data contains the pattern by chance with odds ~2^-32 per position.
constexpr unsigned char kSyncMarker[4] = {0x00, 0x00, 0xFF, 0xFF};

// An image as the test builds it: samples as uint16_t whatever the depth (8-bit ones are < 256).
struct TestImage {
    int width = 0, height = 0, channels = 0, bitDepth = 8;
    std::vector<uint8_t> bytes8;
    std::vector<uint16_t> bytes16;

    PngPixels pixels() const {
        return {width,
                height,
                channels,
                bitDepth,
                bitDepth == 8 ? static_cast<const void*>(bytes8.data()) : bytes16.data(),
                {}};
    }
    std::size_t samples() const { return std::size_t(width) * std::size_t(height) * std::size_t(channels); }
    uint16_t sample(std::size_t i) const { return bitDepth == 8 ? bytes8[i] : bytes16[i]; }
};

// Uniform noise over the whole range, so every byte value and every borrow of the filter occurs.
TestImage randomImage(int width, int height, int channels, int bitDepth, unsigned seed) {
    TestImage image{width, height, channels, bitDepth, {}, {}};
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> value(0, bitDepth == 8 ? 255 : 65535);
    if (bitDepth == 8)
        for (std::size_t i = 0; i < image.samples(); ++i)
            image.bytes8.push_back(uint8_t(value(rng)));
    else
        for (std::size_t i = 0; i < image.samples(); ++i)
            image.bytes16.push_back(uint16_t(value(rng)));
    return image;
}

// RGB16 gradients plus low-amplitude noise: compressible like a real map, but not trivially.
TestImage gradientNoiseImage(int width, int height, unsigned seed) {
    TestImage image{width, height, 3, 16, {}, {}};
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> noise(-300, 300);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const int base[3] = {x * 65535 / width, y * 65535 / height, (x + y) * 32767 / (width + height)};
            for (int c = 0; c < 3; ++c)
                image.bytes16.push_back(uint16_t(std::clamp(base[c] + noise(rng), 0, 65535)));
        }
    return image;
}

// The filtered scanlines as PNG 1.2 §6 defines them, built independently of the encoder: each row
// first as its file bytes (16-bit big-endian), then Sub: Raw(x) - Raw(x - bpp) mod 256.
std::string expectedFiltered(const TestImage& image) {
    const std::size_t bpp = std::size_t(image.channels * image.bitDepth / 8);
    const std::size_t rowBytes = std::size_t(image.width) * bpp;
    const std::size_t rowSamples = std::size_t(image.width) * std::size_t(image.channels);
    std::string out;
    std::vector<uint8_t> raw(rowBytes);
    for (int y = 0; y < image.height; ++y) {
        for (std::size_t k = 0; k < rowSamples; ++k) {
            const uint16_t v = image.sample(std::size_t(y) * rowSamples + k);
            if (image.bitDepth == 8) {
                raw[k] = uint8_t(v);
            } else {
                raw[2 * k] = uint8_t(v >> 8);
                raw[2 * k + 1] = uint8_t(v & 0xFF);
            }
        }
        out.push_back(char(1));
        for (std::size_t i = 0; i < rowBytes; ++i)
            out.push_back(char(uint8_t(raw[i] - (i >= bpp ? raw[i - bpp] : 0))));
    }
    return out;
}

struct Chunk {
    std::string type;
    std::string data;
};

uint32_t readU32(const std::string& bytes, std::size_t at) {
    return uint32_t(uint8_t(bytes[at])) << 24 | uint32_t(uint8_t(bytes[at + 1])) << 16 |
           uint32_t(uint8_t(bytes[at + 2])) << 8 | uint32_t(uint8_t(bytes[at + 3]));
}

// The chunks of a PNG file; fails the test on a bad signature, a truncated chunk or a wrong CRC.
std::vector<Chunk> parseChunks(const std::string& png) {
    std::vector<Chunk> chunks;
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    std::size_t at = 8;
    while (at + 12 <= png.size()) {
        const uint32_t length = readU32(png, at);
        if (at + 12 + length > png.size()) break;
        Chunk chunk{png.substr(at + 4, 4), png.substr(at + 8, length)};
        const uLong crc = crc32(crc32(0, nullptr, 0), reinterpret_cast<const Bytef*>(png.data() + at + 4),
                                uInt(length + 4));
        EXPECT_EQ(readU32(png, at + 8 + length), uint32_t(crc)) << "CRC of " << chunk.type;
        chunks.push_back(std::move(chunk));
        at += 12 + length;
    }
    EXPECT_EQ(at, png.size()) << "trailing or truncated bytes";
    return chunks;
}

std::string idatStream(const std::vector<Chunk>& chunks) {
    std::string stream;
    for (const Chunk& chunk : chunks)
        if (chunk.type == "IDAT") stream += chunk.data;
    return stream;
}

// zlib's one-shot decoder: checks the header, the deflate data and the adler32 trailer.
std::string uncompressed(const std::string& stream, std::size_t expectedSize) {
    std::string out(expectedSize + 1, '\0'); // one spare byte: a longer output is an error, not a fit
    uLongf outSize = uLongf(out.size());
    const int rc = uncompress(reinterpret_cast<Bytef*>(out.data()), &outSize,
                              reinterpret_cast<const Bytef*>(stream.data()), uLong(stream.size()));
    EXPECT_EQ(rc, Z_OK) << "zlib uncompress";
    out.resize(rc == Z_OK ? outSize : 0);
    return out;
}

// Raw-inflates deflate data with a fresh decoder (no earlier window): succeeds only if nothing in
// it refers back before its start.
std::string rawInflate(const std::string& deflate, std::size_t expectedSize) {
    z_stream zs{};
    EXPECT_EQ(inflateInit2(&zs, -15), Z_OK);
    std::string out(expectedSize + 1, '\0');
    zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(deflate.data()));
    zs.avail_in = uInt(deflate.size());
    zs.next_out = reinterpret_cast<Bytef*>(out.data());
    zs.avail_out = uInt(out.size());
    const int rc = inflate(&zs, Z_FINISH);
    EXPECT_EQ(rc, Z_STREAM_END) << (zs.msg ? zs.msg : "");
    out.resize(zs.total_out);
    inflateEnd(&zs);
    return out;
}

// Writes the bytes to a file and decodes it with OpenImageIO (libpng), alpha kept unassociated.
void expectDecodesTo(const std::string& png, const TestImage& image, const std::string& what) {
    TempDir dir;
    const auto path = dir / "image.png";
    ASSERT_TRUE(writeFileAtomic(path, png).ok()) << what;
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path.string(), &config);
    ASSERT_TRUE(in) << what << ": " << OIIO::geterror();
    const OIIO::ImageSpec& spec = in->spec();
    ASSERT_EQ(spec.width, image.width) << what;
    ASSERT_EQ(spec.height, image.height) << what;
    ASSERT_EQ(spec.nchannels, image.channels) << what;
    ASSERT_EQ(spec.format, image.bitDepth == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16) << what;
    if (image.bitDepth == 8) {
        std::vector<uint8_t> read(image.samples());
        ASSERT_TRUE(in->read_image(0, 0, 0, image.channels, OIIO::TypeDesc::UINT8, read.data())) << what;
        EXPECT_TRUE(read == image.bytes8) << what << ": decoded samples differ";
    } else {
        std::vector<uint16_t> read(image.samples());
        ASSERT_TRUE(in->read_image(0, 0, 0, image.channels, OIIO::TypeDesc::UINT16, read.data())) << what;
        EXPECT_TRUE(read == image.bytes16) << what << ": decoded samples differ";
    }
}

std::string encodeOrFail(const TestImage& image) {
    auto png = encodePng(image.pixels());
    EXPECT_TRUE(png.ok()) << png.error();
    return png.ok() ? png.value() : std::string();
}

std::string describe(const TestImage& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height) + " " +
           std::to_string(image.channels) + "ch " + std::to_string(image.bitDepth) + "-bit";
}

TEST(PngEncode, RoundTripsEveryChannelCountAndDepth) {
    // 37×23: primes, so no row or image size is a multiple of anything the encoder might assume;
    // 1×1: the smallest image, one row of one texel.
    unsigned seed = 1;
    for (const auto& [width, height] : {std::pair{37, 23}, std::pair{1, 1}})
        for (int bitDepth : {8, 16})
            for (int channels = 1; channels <= 4; ++channels) {
                const TestImage image = randomImage(width, height, channels, bitDepth, seed++);
                expectDecodesTo(encodeOrFail(image), image, describe(image));
            }
}

TEST(PngEncode, HeaderAndChunkLayout) {
    // Colour type by channel count (PNG 1.2 §11.2.2): grey 0, grey+alpha 4, RGB 2, RGBA 6.
    const uint8_t colourTypes[5] = {0, 0, 4, 2, 6};
    for (int bitDepth : {8, 16})
        for (int channels = 1; channels <= 4; ++channels) {
            const TestImage image = randomImage(37, 23, channels, bitDepth, 7);
            const auto chunks = parseChunks(encodeOrFail(image));
            ASSERT_GE(chunks.size(), 3u) << describe(image);
            // Data, not colour: nothing but IHDR, IDAT and IEND.
            EXPECT_EQ(chunks.front().type, "IHDR");
            EXPECT_EQ(chunks.back().type, "IEND");
            EXPECT_TRUE(chunks.back().data.empty());
            for (std::size_t i = 1; i + 1 < chunks.size(); ++i)
                EXPECT_EQ(chunks[i].type, "IDAT") << describe(image);
            const std::string& ihdr = chunks.front().data;
            ASSERT_EQ(ihdr.size(), 13u);
            EXPECT_EQ(readU32(ihdr, 0), uint32_t(image.width));
            EXPECT_EQ(readU32(ihdr, 4), uint32_t(image.height));
            EXPECT_EQ(uint8_t(ihdr[8]), uint8_t(bitDepth)) << describe(image);
            EXPECT_EQ(uint8_t(ihdr[9]), colourTypes[channels]) << describe(image);
            // Compression 0, filter method 0, no interlace.
            EXPECT_EQ(ihdr.substr(10), std::string(3, '\0'));
        }
}

// 1500×900 RGB16: 9001 filtered bytes a row, ~8 MiB in all, so several segments and IDAT chunks.
class PngEncodeLarge : public ::testing::Test {
protected:
    static void SetUpTestSuite() { s_image = new TestImage(gradientNoiseImage(1500, 900, 42)); }
    static void TearDownTestSuite() {
        delete s_image;
        s_image = nullptr;
    }
    static const TestImage& image() { return *s_image; }
    static TestImage* s_image;
};
TestImage* PngEncodeLarge::s_image = nullptr;

TEST_F(PngEncodeLarge, RoundTrips) {
    expectDecodesTo(encodeOrFail(image()), image(), describe(image()));
}

TEST_F(PngEncodeLarge, StreamIsIndependentSegmentsOfTheSubFilteredRows) {
    const std::string expected = expectedFiltered(image());
    const std::size_t filteredRowBytes = expected.size() / std::size_t(image().height);
    const std::size_t rowsPerSegment = pngRowsPerSegment(filteredRowBytes);
    const std::size_t segments = (std::size_t(image().height) + rowsPerSegment - 1) / rowsPerSegment;
    ASSERT_GE(segments, 3u) << "the image must be large enough to need several segments";

    const auto chunks = parseChunks(encodeOrFail(image()));
    std::size_t idats = 0;
    for (const Chunk& chunk : chunks)
        if (chunk.type == "IDAT") {
            ++idats;
            EXPECT_LE(chunk.data.size(), kMaxIdatBytes);
        }
    EXPECT_GT(idats, 1u) << "the stream must span several IDAT chunks to test the split";

    // The whole stream: a valid zlib stream (header, deflate, adler32) holding exactly the rows.
    const std::string stream = idatStream(chunks);
    EXPECT_TRUE(uncompressed(stream, expected.size()) == expected)
        << "IDAT data is not the Sub-filtered rows";

    // One sync marker between every two segments, and each marks where an independent deflate
    // stream of the remaining rows starts (a fresh decoder would fail on a reference across it).
    constexpr std::size_t kZlibHeaderBytes = 2, kAdlerBytes = 4;
    const std::string deflate =
        stream.substr(kZlibHeaderBytes, stream.size() - kZlibHeaderBytes - kAdlerBytes);
    std::vector<std::size_t> markers;
    for (std::size_t at = deflate.find(reinterpret_cast<const char*>(kSyncMarker), 0, 4);
         at != std::string::npos; at = deflate.find(reinterpret_cast<const char*>(kSyncMarker), at + 1, 4))
        markers.push_back(at);
    ASSERT_EQ(markers.size(), segments - 1);
    for (std::size_t k = 0; k < markers.size(); ++k) {
        const std::size_t rowsBefore = (k + 1) * rowsPerSegment;
        const std::string tail = expected.substr(rowsBefore * filteredRowBytes);
        EXPECT_TRUE(rawInflate(deflate.substr(markers[k] + 4), tail.size()) == tail)
            << "segment " << k + 1 << " does not decode on its own to rows " << rowsBefore << "..";
    }
}

TEST_F(PngEncodeLarge, BytesDoNotDependOnThreads) {
    const std::string first = encodeOrFail(image());
    EXPECT_TRUE(encodeOrFail(image()) == first) << "two encodings differ";
    std::string single;
    tbb::task_arena arena(1);
    arena.execute([&] { single = encodeOrFail(image()); });
    EXPECT_TRUE(single == first) << "one thread and the default arena give different bytes";
}

TEST(PngEncode, CompressesGradientsAndStoresNoise) {
    // 600×300 RGB16 gradients with ±300 noise: 3601 filtered bytes a row, ~1.03 MiB in all, so two
    // segments. The gradients compress; the noise bits do not (zlib's level 9 reaches 77 % of the rows).
    const TestImage gradients = gradientNoiseImage(600, 300, 9);
    const std::string gradientRows = expectedFiltered(gradients);
    const std::string gradientPng = encodeOrFail(gradients);
    const std::string gradientStream = idatStream(parseChunks(gradientPng));
    EXPECT_TRUE(uncompressed(gradientStream, gradientRows.size()) == gradientRows);
    expectDecodesTo(gradientPng, gradients, "gradients");
    EXPECT_LT(double(gradientStream.size()), 0.85 * double(gradientRows.size())) << "gradients must compress";

    // 1100×300 RGBA8 uniform noise: 4401 filtered bytes a row, ~1.26 MiB, two segments that do not
    // compress. Deflate must fall back to stored blocks, adding only their headers (5 bytes per
    // 65535), a Huffman header and a flush per segment, the zlib header and the adler32.
    const TestImage noise = randomImage(1100, 300, 4, 8, 11);
    const std::string noiseRows = expectedFiltered(noise);
    const std::string noisePng = encodeOrFail(noise);
    const std::string noiseStream = idatStream(parseChunks(noisePng));
    EXPECT_TRUE(uncompressed(noiseStream, noiseRows.size()) == noiseRows);
    expectDecodesTo(noisePng, noise, "noise");
    const std::size_t storedLimit =
        noiseRows.size() + (noiseRows.size() / 65535 + 2) * 5 + 2 * (328 + 16) + 6;
    EXPECT_LE(noiseStream.size(), storedLimit) << "incompressible rows must be stored, not expanded";
}

TEST_F(PngEncodeLarge, RowsMadeOnRequestGiveTheSameBytes) {
    // The same image handed over as a row callback: every row asked for exactly once, in disjoint
    // ranges (from several threads), and the file byte for byte the one encoded from memory.
    const TestImage& im = image();
    const std::size_t rowSamples = std::size_t(im.width) * std::size_t(im.channels);
    std::vector<std::atomic<int>> asked(std::size_t(im.height));
    PngPixels pixels{im.width, im.height, im.channels, im.bitDepth, nullptr, {}};
    pixels.rows = [&](std::size_t y0, std::size_t y1, void* out) {
        for (std::size_t y = y0; y < y1; ++y) {
            asked[y].fetch_add(1);
            std::memcpy(static_cast<uint16_t*>(out) + (y - y0) * rowSamples,
                        im.bytes16.data() + y * rowSamples, rowSamples * sizeof(uint16_t));
        }
    };
    const auto fromRows = encodePng(pixels);
    ASSERT_TRUE(fromRows.ok()) << fromRows.error();
    EXPECT_TRUE(*fromRows == encodeOrFail(im)) << "rows made on request encode differently";
    for (std::size_t y = 0; y < asked.size(); ++y)
        EXPECT_EQ(asked[y].load(), 1) << "row " << y;
}

TEST(PngEncode, RefusesBadInput) {
    const std::vector<uint16_t> data(64, 0);
    const PngPixels good{4, 4, 4, 16, data.data(), {}};
    ASSERT_TRUE(encodePng(good).ok());

    auto expectError = [](PngPixels pixels, const std::string& what) {
        const auto result = encodePng(pixels);
        EXPECT_FALSE(result.ok()) << what;
        EXPECT_FALSE(result.error().empty()) << what;
    };
    PngPixels p = good;
    p.width = 0;
    expectError(p, "zero width");
    p = good;
    p.height = 0;
    expectError(p, "zero height");
    p = good;
    p.width = -5;
    expectError(p, "negative width");
    p = good;
    p.channels = 5;
    expectError(p, "5 channels");
    p = good;
    p.channels = 0;
    expectError(p, "0 channels");
    p = good;
    p.bitDepth = 12;
    expectError(p, "12-bit");
    p = good;
    p.data = nullptr;
    expectError(p, "null data");
    // (2^31 - 1)² RGBA16 needs ~3.7e19 filtered bytes, beyond size_t: refused before any pixel is read
    // (the 64 samples here would be far too few).
    p = good;
    p.width = 2147483647;
    p.height = 2147483647;
    expectError(p, "byte count overflow");
}

} // namespace
} // namespace burnish
