#include <burnish/core/prefilter/normal_map.h>

#include "temp_dir.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>

using namespace burnish;

namespace {

// Unit length after renormalization, to float precision.
constexpr float kUnitTolerance = 1e-6f;
// One 8-bit step in [-1, 1]: 2/255.
constexpr float kByteStep = 2.0f / 255.0f;

Image makeImage(int w, int h, int c, const std::vector<float>& pixels, bool isFloat = false) {
    Image image;
    image.width = w;
    image.height = h;
    image.channels = c;
    image.pixels.assign(pixels.begin(), pixels.end());
    image.source.isFloat = isFloat;
    return image;
}

// Encodes unit normals as unsigned [0,1] RGB.
Image encodeRgb(int w, int h, const std::vector<glm::vec3>& normals) {
    std::vector<float> px;
    for (const auto& n : normals) {
        px.push_back(n.x * 0.5f + 0.5f);
        px.push_back(n.y * 0.5f + 0.5f);
        px.push_back(n.z * 0.5f + 0.5f);
    }
    return makeImage(w, h, 3, px);
}

bool writeImage(const std::filesystem::path& path, int w, int h, int c, OIIO::TypeDesc type,
                const std::vector<float>& pixels) {
    OIIO::ImageSpec spec(w, h, c, type);
    auto out = OIIO::ImageOutput::create(path.string());
    if (!out || !out->open(path.string(), spec)) return false;
    const bool ok = out->write_image(OIIO::TypeDesc::FLOAT, pixels.data());
    return out->close() && ok;
}

} // namespace

TEST(NormalMap, DecodesUnsignedRgbAndRenormalizes) {
    const glm::vec3 tilted = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    auto map = decodeNormalMap(encodeRgb(2, 1, {tilted, glm::vec3(0, 0, 1)}));
    ASSERT_TRUE(map.ok()) << map.error();
    EXPECT_NEAR(glm::length(map->at(0, 0)), 1.0f, kUnitTolerance);
    EXPECT_NEAR(map->at(0, 0).x, tilted.x, 1e-6f);
    EXPECT_NEAR(map->at(0, 0).y, tilted.y, 1e-6f);
    EXPECT_FALSE(map->diagnostics.zRebuilt);
}

TEST(NormalMap, DirectXGreenIsFlipped) {
    const glm::vec3 n = glm::normalize(glm::vec3(0.1f, 0.4f, 0.9f));
    NormalMapOptions options;
    options.green = GreenConvention::DirectX;
    auto map = decodeNormalMap(encodeRgb(1, 1, {n}), options);
    ASSERT_TRUE(map.ok());
    EXPECT_NEAR(map->at(0, 0).y, -n.y, 1e-6f);
    EXPECT_NEAR(map->at(0, 0).x, n.x, 1e-6f);
}

TEST(NormalMap, TwoChannelMapRebuildsZ) {
    const float x = 0.3f, y = -0.4f;
    auto map = decodeNormalMap(makeImage(1, 1, 2, {x * 0.5f + 0.5f, y * 0.5f + 0.5f}));
    ASSERT_TRUE(map.ok()) << map.error();
    EXPECT_TRUE(map->diagnostics.zRebuilt);
    EXPECT_NEAR(map->at(0, 0).z, std::sqrt(1.0f - x * x - y * y), 1e-6f);
}

TEST(NormalMap, ConstantBlueIsReadAsTwoChannel) {
    // A BC5-style export: RG vary, blue is 0 everywhere.
    auto map = decodeNormalMap(makeImage(2, 1, 3, {0.6f, 0.5f, 0.0f, 0.4f, 0.55f, 0.0f}));
    ASSERT_TRUE(map.ok()) << map.error();
    EXPECT_TRUE(map->diagnostics.zRebuilt);
    EXPECT_GT(map->at(0, 0).z, 0.9f);
}

TEST(NormalMap, AlphaIsNeverMixedIntoTheNormal) {
    std::vector<float> px = {0.5f, 0.5f, 1.0f, 0.0f, 0.5f, 0.5f, 1.0f, 1.0f};
    auto map = decodeNormalMap(makeImage(2, 1, 4, px));
    ASSERT_TRUE(map.ok());
    EXPECT_TRUE(map->diagnostics.alphaIgnored);
    EXPECT_EQ(map->at(0, 0), map->at(1, 0));
}

TEST(NormalMap, SignedFloatMapsAreDetected) {
    const glm::vec3 n = glm::normalize(glm::vec3(-0.3f, 0.2f, 0.9f));
    auto map = decodeNormalMap(makeImage(1, 1, 3, {n.x, n.y, n.z}, /*isFloat=*/true));
    ASSERT_TRUE(map.ok()) << map.error();
    EXPECT_TRUE(map->diagnostics.signedValues);
    EXPECT_NEAR(map->at(0, 0).x, n.x, 1e-6f);
}

TEST(NormalMap, NanTexelsAreReportedAndReplaced) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    auto image =
        encodeRgb(2, 2, {glm::vec3(0, 0, 1), glm::vec3(0, 0, 1), glm::vec3(0, 0, 1), glm::vec3(0, 0, 1)});
    image.pixels[3] = nan;
    image.pixels[7] = std::numeric_limits<float>::infinity();
    auto map = decodeNormalMap(image);
    ASSERT_TRUE(map.ok()) << map.error();
    EXPECT_EQ(map->diagnostics.nonFiniteTexels, 2u);
    ASSERT_FALSE(map->diagnostics.warnings.empty());
    for (const auto& n : map->normals)
        EXPECT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z));
}

// One -Inf (or +Inf, NaN) texel in an unsigned float map (an EXR of 2v-1 codes) does not switch
// the automatic encoding to signed: non-finite texels are left out of the detection and replaced.
TEST(NormalMap, NonFiniteTexelsDoNotChangeTheEncoding) {
    const glm::vec3 n = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    for (float bad : {-std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                      std::numeric_limits<float>::quiet_NaN()}) {
        auto image = encodeRgb(3, 1, {n, n, glm::vec3(0, 0, 1)});
        image.source.isFloat = true;
        image.pixels[6] = bad;
        auto map = decodeNormalMap(image);
        ASSERT_TRUE(map.ok()) << map.error();
        EXPECT_FALSE(map->diagnostics.signedValues) << bad;
        EXPECT_EQ(map->diagnostics.nonFiniteTexels, 1u);
        EXPECT_NEAR(map->at(0, 0).x, n.x, 1e-6f);
        EXPECT_EQ(map->at(2, 0), glm::vec3(0, 0, 1));
    }
    // The explicit encoding still overrides the detection.
    auto image = makeImage(1, 1, 3, {0.5f, 0.5f, 1.0f}, true);
    NormalMapOptions options;
    options.encoding = NormalValueEncoding::Signed;
    auto map = decodeNormalMap(image, options);
    ASSERT_TRUE(map.ok()) << map.error();
    EXPECT_TRUE(map->diagnostics.signedValues);
    EXPECT_NEAR(map->at(0, 0).x, 0.5f / std::sqrt(1.5f), 1e-6f);
}

// Two-channel maps: (x, y) longer than 1 counts against plausibility like a bad RGB vector, so a
// map of zeros (decoded to (-1, -1)) is refused as its RGB twin is; the rim of a real map passes.
TEST(NormalMap, TwoChannelVectorsLongerThanOneAreImplausible) {
    // Stored (0.02, 0.02): (-0.96, -0.96), 1.36 long.
    auto longer = decodeNormalMap(makeImage(4, 4, 2, std::vector<float>(32, 0.02f)));
    ASSERT_FALSE(longer.ok());
    EXPECT_NE(longer.error().find("longer than 1"), std::string::npos) << longer.error();
    NormalMapOptions allow;
    allow.allowImplausible = true;
    auto allowed = decodeNormalMap(makeImage(4, 4, 2, std::vector<float>(32, 0.02f)), allow);
    ASSERT_TRUE(allowed.ok()) << allowed.error();
    EXPECT_EQ(allowed->diagnostics.offLengthTexels, 16u);
    EXPECT_EQ(allowed->diagnostics.implausible, longer.error()); // let through, with the refusal it passed
    // A map of zeros holds no data at all (stored 0 is padding, NormalMap.PaddingStoredAsZero...),
    // RG and RGB alike, and nothing can be read from it even when implausible maps are allowed.
    for (int channels : {2, 3}) {
        auto zeros = decodeNormalMap(
            makeImage(4, 4, channels, std::vector<float>(size_t(16 * channels), 0.0f)), allow);
        ASSERT_FALSE(zeros.ok());
        EXPECT_NE(zeros.error().find("every texel is stored as 0"), std::string::npos) << zeros.error();
    }
    // A steep but valid map with a corner texel at (1, 1) (8-bit rounding of a grazing normal).
    std::vector<float> px;
    for (int i = 0; i < 16; ++i) {
        const float x = i == 0 ? 1.0f : 0.5f + 0.4f * std::cos(float(i));
        const float y = i == 0 ? 1.0f : 0.5f + 0.4f * std::sin(float(i));
        px.push_back(x);
        px.push_back(y);
    }
    auto real = decodeNormalMap(makeImage(4, 4, 2, px));
    ASSERT_TRUE(real.ok()) << real.error();
    EXPECT_EQ(real->diagnostics.offLengthTexels, 1u);
}

TEST(NormalMap, RejectsOneChannelImages) {
    auto map = decodeNormalMap(makeImage(1, 1, 1, {0.5f}));
    ASSERT_FALSE(map.ok());
    EXPECT_NE(map.error().find("height or gloss"), std::string::npos) << map.error();
}

TEST(NormalMap, RejectsPhotosAndAcceptsThemOnRequest) {
    // A "photo": random colours, most stored vectors far from unit length, many pointing down.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> px(64 * 64 * 3);
    for (auto& v : px)
        v = u(rng);
    auto map = decodeNormalMap(makeImage(64, 64, 3, px));
    ASSERT_FALSE(map.ok());
    EXPECT_NE(map.error().find("does not look like a tangent-space normal map"), std::string::npos)
        << map.error();

    NormalMapOptions options;
    options.allowImplausible = true;
    auto forced = decodeNormalMap(makeImage(64, 64, 3, px), options);
    ASSERT_TRUE(forced.ok());
    EXPECT_FALSE(forced->diagnostics.warnings.empty());
    EXPECT_EQ(forced->diagnostics.implausible, map.error());
    // A plausible map allowed through is not marked.
    std::vector<float> flat(48, 0.5f);
    for (size_t i = 2; i < flat.size(); i += 3)
        flat[i] = 1.0f;
    auto plain = decodeNormalMap(makeImage(4, 4, 3, flat), options);
    ASSERT_TRUE(plain.ok()) << plain.error();
    EXPECT_TRUE(plain->diagnostics.implausible.empty());
}

TEST(NormalMap, RejectsMidGreyHeightMapsStoredAsRgb) {
    std::vector<float> px(16 * 16 * 3, 0.5f);
    for (size_t i = 0; i < px.size(); i += 3)
        px[i] = px[i + 1] = px[i + 2] = 0.3f + 0.001f * float(i % 50);
    EXPECT_FALSE(decodeNormalMap(makeImage(16, 16, 3, px)).ok());
}

TEST(NormalMap, EightBitFlatMapDecodesToOneDirection) {
    // (128, 128, 255) is the flat normal of 8-bit maps: it is not exactly +z, but every texel
    // must decode to the same unit vector (no spread, hence no false roughness).
    std::vector<float> px;
    for (int i = 0; i < 16; ++i)
        px.insert(px.end(), {128.0f / 255.0f, 128.0f / 255.0f, 1.0f});
    auto map = decodeNormalMap(makeImage(4, 4, 3, px));
    ASSERT_TRUE(map.ok());
    for (const auto& n : map->normals) {
        EXPECT_EQ(n, map->normals[0]);
        EXPECT_NEAR(glm::length(n), 1.0f, kUnitTolerance);
        EXPECT_NEAR(n.z, 1.0f, kByteStep * kByteStep);
    }
}

TEST(ImageIo, ReadsFormatsAndSizes) {
    test::TempDir dir;
    struct Case {
        const char* name;
        OIIO::TypeDesc type;
        int w, h;
    };
    // Odd sizes and 1×1 included; each format round-trips the flat normal.
    const Case cases[] = {{"a.png", OIIO::TypeDesc::UINT8, 3, 5}, {"b.png", OIIO::TypeDesc::UINT16, 1, 1},
                          {"c.tga", OIIO::TypeDesc::UINT8, 7, 2}, {"d.exr", OIIO::TypeDesc::HALF, 4, 4},
                          {"e.tif", OIIO::TypeDesc::FLOAT, 5, 3}, {"f.jpg", OIIO::TypeDesc::UINT8, 8, 8}};
    for (const auto& c : cases) {
        std::vector<float> px;
        for (int i = 0; i < c.w * c.h; ++i)
            px.insert(px.end(), {0.5f, 0.5f, 1.0f});
        ASSERT_TRUE(writeImage(dir / c.name, c.w, c.h, 3, c.type, px)) << c.name;
        auto map = loadNormalMap(dir / c.name);
        ASSERT_TRUE(map.ok()) << c.name << ": " << map.error();
        EXPECT_EQ(map->width, c.w);
        EXPECT_EQ(map->height, c.h);
        // JPEG is lossy: allow a few 8-bit steps.
        EXPECT_NEAR(map->at(0, 0).z, 1.0f, 4 * kByteStep) << c.name;
    }
}

TEST(ImageIo, ClearErrorsForMissingAndCorruptFiles) {
    test::TempDir dir;
    auto missing = readImage(dir / "nope.png");
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().find("does not exist"), std::string::npos);

    std::ofstream(dir / "corrupt.png") << "\x89PNG\r\n\x1a\n this is not a png";
    auto corrupt = readImage(dir / "corrupt.png");
    ASSERT_FALSE(corrupt.ok());
    EXPECT_NE(corrupt.error().find("corrupt.png"), std::string::npos) << corrupt.error();

    auto folder = readImage(dir.path());
    ASSERT_FALSE(folder.ok());
    EXPECT_NE(folder.error().find("folder"), std::string::npos);
}

TEST(ImageIo, TruncatedFileIsAnError) {
    test::TempDir dir;
    std::vector<float> px(64 * 64 * 3, 0.5f);
    ASSERT_TRUE(writeImage(dir / "full.png", 64, 64, 3, OIIO::TypeDesc::UINT8, px));
    const auto size = std::filesystem::file_size(dir / "full.png");
    std::filesystem::copy_file(dir / "full.png", dir / "cut.png");
    std::filesystem::resize_file(dir / "cut.png", size / 2);
    EXPECT_FALSE(readImage(dir / "cut.png").ok());
}

// OpenImageIO hands back zeros (DDS) or grey (JPEG) for the missing part of a file cut short and
// reports success: that is an error naming the file as truncated, never texels.
// An OpenEXR header whose attribute claims more bytes than the file holds is refused before
// OpenEXR reads it: OpenEXR allocates and clears whatever an attribute claims, and fuzzing found a
// 300-byte file that took 2 GB and 20 s that way. Valid EXRs (tiled, mip-mapped) still read.
TEST(ImageIo, ExrHeadersThatClaimMoreThanTheFileAreCorrupt) {
    test::TempDir dir;
    std::string exr("\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
    exr += std::string("comments\0string\0", 16);
    exr += std::string("\xff\xff\xff\x7f", 4); // 2^31 - 1 bytes of comment
    exr += "short";
    std::ofstream(dir / "huge.exr", std::ios::binary) << exr;
    const auto huge = readImage(dir / "huge.exr");
    ASSERT_FALSE(huge.ok());
    EXPECT_NE(
        huge.error().find("corrupt (the EXR attribute 'comments' claims 2147483647 bytes and 5 remain)"),
        std::string::npos)
        << huge.error();
    EXPECT_FALSE(readImageHeader(dir / "huge.exr").ok());

    // A data window beyond what Burnish accepts is refused before OpenEXR sizes its tables by it.
    std::string wide("\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
    wide += std::string("dataWindow\0box2i\0\x10\0\0\0", 21);
    wide += std::string("\0\0\0\0\0\0\0\0\xff\xff\x01\0\x09\0\0\0", 16); // 0..131071 × 0..9
    wide += std::string(64, '\0');
    std::ofstream(dir / "wide.exr", std::ios::binary) << wide;
    const auto wideRead = readImageHeader(dir / "wide.exr");
    ASSERT_FALSE(wideRead.ok());
    EXPECT_NE(wideRead.error().find("EXR dataWindow is 131072x10, larger than Burnish accepts"),
              std::string::npos)
        << wideRead.error();

    std::vector<float> px(16 * 8 * 3, 0.5f);
    for (const char* name : {"scan.exr", "tiled.exr"}) {
        const auto path = dir / name;
        auto out = OIIO::ImageOutput::create(path.string());
        OIIO::ImageSpec spec(16, 8, 3, OIIO::TypeDesc::HALF);
        spec.attribute("Software", "a comment long enough to matter");
        if (std::string(name) == "tiled.exr") spec.tile_width = spec.tile_height = 16;
        ASSERT_TRUE(out && out->open(path.string(), spec) &&
                    out->write_image(OIIO::TypeDesc::FLOAT, px.data()) && out->close());
        const auto read = readImage(path);
        ASSERT_TRUE(read.ok()) << read.error();
        EXPECT_EQ(read->width, 16);
    }
}

TEST(ImageIo, FilesCutShortAreTruncatedNotTexels) {
    test::TempDir dir;
    std::vector<float> px(64 * 64 * 3);
    for (size_t i = 0; i < px.size(); ++i)
        px[i] = float(i % 97) / 96.0f;
    ASSERT_TRUE(writeImage(dir / "full.jpg", 64, 64, 3, OIIO::TypeDesc::UINT8, px));
    ASSERT_TRUE(writeImage(dir / "full.tif", 64, 64, 3, OIIO::TypeDesc::UINT8, px));
    ASSERT_TRUE(readImage(dir / "full.jpg").ok());
    for (const char* name : {"full.jpg", "full.tif"}) {
        const auto cut = dir / (std::string("cut-") + name);
        std::filesystem::copy_file(dir / name, cut);
        std::filesystem::resize_file(cut, std::filesystem::file_size(cut) / 2);
        const auto r = readImage(cut);
        ASSERT_FALSE(r.ok()) << name;
        EXPECT_NE(r.error().find(cut.filename().string()), std::string::npos) << r.error();
        EXPECT_NE(r.error().find("truncated"), std::string::npos) << r.error();
        EXPECT_EQ(r.error().find('\n'), std::string::npos) << r.error();
    }
    // A DDS header (128 bytes: 64x64 uncompressed RGBA8) and no data at all.
    std::string header(128, '\0');
    auto put32 = [&](size_t at, uint32_t v) { std::memcpy(header.data() + at, &v, 4); };
    std::memcpy(header.data(), "DDS ", 4);
    put32(4, 124);                      // header size
    put32(8, 0x1 | 0x2 | 0x4 | 0x1000); // caps, height, width, pixel format
    put32(12, 64);
    put32(16, 64);
    put32(76, 32);         // pixel format size
    put32(80, 0x40 | 0x1); // RGB | alpha pixels
    put32(88, 32);         // bits per pixel
    put32(92, 0x00ff0000);
    put32(96, 0x0000ff00);
    put32(100, 0x000000ff);
    put32(104, 0xff000000);
    put32(108, 0x1000); // texture
    std::ofstream(dir / "header-only.dds", std::ios::binary) << header;
    const auto dds = readImage(dir / "header-only.dds");
    ASSERT_FALSE(dds.ok());
    EXPECT_NE(dds.error().find("truncated"), std::string::npos) << dds.error();
    EXPECT_FALSE(loadNormalMap(dir / "header-only.dds").ok());

    // A DDS claiming 2048² BC5 (FourCC ATI2) with 132 bytes of data: refused from its size before
    // OpenImageIO reads it (its DDS reader seeked for over a minute on such a file; found by fuzzing).
    // The same header with the whole first level is read.
    put32(80, 0x4); // FourCC
    std::memcpy(header.data() + 84, "ATI2", 4);
    put32(88, 0);
    put32(12, 2048);
    put32(16, 2048);
    std::ofstream(dir / "claims-2048.dds", std::ios::binary) << header << std::string(132, '\xdf');
    const auto start = std::chrono::steady_clock::now();
    const auto claims = readImage(dir / "claims-2048.dds");
    ASSERT_FALSE(claims.ok());
    EXPECT_NE(claims.error().find("truncated"), std::string::npos) << claims.error();
    EXPECT_NE(claims.error().find("4194432 bytes"), std::string::npos) << claims.error();
    EXPECT_FALSE(loadNormalMap(dir / "claims-2048.dds").ok());
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 30.0);
    put32(12, 8);
    put32(16, 8);
    std::ofstream(dir / "whole.dds", std::ios::binary) << header << std::string(4 * 16, '\x80');
    const auto whole = readImage(dir / "whole.dds");
    ASSERT_TRUE(whole.ok()) << whole.error();
    EXPECT_EQ(whole->width, 8);
    // The same 8×8 file claiming 905969666 mip levels (an 8×8 chain has 4): refused as corrupt
    // before OpenImageIO seeks through them (it took 90 s; found by fuzzing).
    put32(28, 905969666);
    std::ofstream(dir / "levels.dds", std::ios::binary) << header << std::string(4 * 16, '\x80');
    const auto levels = readImage(dir / "levels.dds");
    ASSERT_FALSE(levels.ok());
    EXPECT_NE(levels.error().find("corrupt"), std::string::npos) << levels.error();
    EXPECT_NE(levels.error().find("905969666 mip levels"), std::string::npos) << levels.error();
    // The same 8×8 BC5 claiming its 4 levels (4 + 1 + 1 + 1 blocks of 16 bytes): cut inside its mip
    // tail (level 0 whole, 90 % of the file) it is refused as truncated (issue 45, point 9: it was
    // read); whole, it is read.
    put32(28, 4);
    std::ofstream(dir / "tail-cut.dds", std::ios::binary) << header << std::string(4 * 16 + 2 * 16, '\x80');
    const auto tailCut = readImage(dir / "tail-cut.dds");
    ASSERT_FALSE(tailCut.ok());
    EXPECT_NE(tailCut.error().find("truncated"), std::string::npos) << tailCut.error();
    EXPECT_NE(tailCut.error().find("4 mip levels"), std::string::npos) << tailCut.error();
    EXPECT_NE(tailCut.error().find("240 bytes"), std::string::npos) << tailCut.error();
    std::ofstream(dir / "tail-whole.dds", std::ios::binary) << header << std::string(7 * 16, '\x80');
    const auto tailWhole = readImage(dir / "tail-whole.dds");
    EXPECT_TRUE(tailWhole.ok()) << tailWhole.error();
    // The same 8×8 blocks as DXT2 or DXT4 (premultiplied alpha): refused as unsupported before
    // OpenImageIO's reader, which divides by zero on any such file (found by fuzzing); the same
    // blocks as DXT3 and DXT5 are read.
    put32(28, 0);
    for (const char* fourCC : {"DXT2", "DXT4", "DXT3", "DXT5"}) {
        std::memcpy(header.data() + 84, fourCC, 4);
        std::ofstream(dir / "premultiplied.dds", std::ios::binary) << header << std::string(4 * 16, '\x80');
        const auto read = readImage(dir / "premultiplied.dds");
        const bool premultiplied = fourCC[3] == '2' || fourCC[3] == '4';
        ASSERT_EQ(read.ok(), !premultiplied) << fourCC;
        if (premultiplied) {
            EXPECT_NE(read.error().find(std::string("unsupported: it is ") + fourCC), std::string::npos)
                << read.error();
            EXPECT_NE(read.error().find("save it as BC5"), std::string::npos) << read.error();
            EXPECT_FALSE(loadNormalMap(dir / "premultiplied.dds").ok());
        }
    }
    // An uncompressed 8×8 file (no FourCC flag) of 0 bits per texel: refused as corrupt before
    // OpenImageIO's reader, which never returned on it (found by fuzzing); 4 bits too, and 64 (its
    // reader copies a texel into 32 bits).
    put32(80, 0x41); // RGB | alpha, no FourCC
    for (std::uint32_t bits : {0u, 4u, 64u}) {
        put32(88, bits);
        std::ofstream(dir / "no-bits.dds", std::ios::binary) << header << std::string(256, '\x80');
        const auto noBits = readImage(dir / "no-bits.dds");
        ASSERT_FALSE(noBits.ok());
        EXPECT_NE(noBits.error().find("corrupt"), std::string::npos) << noBits.error();
        EXPECT_NE(noBits.error().find(std::to_string(bits) + " bits per texel"), std::string::npos)
            << noBits.error();
        EXPECT_FALSE(loadNormalMap(dir / "no-bits.dds").ok());
    }
    // 32 bits per texel with its masks is still read.
    put32(88, 32);
    std::ofstream(dir / "rgba32.dds", std::ios::binary) << header << std::string(256, '\x80');
    const auto rgba32 = readImage(dir / "rgba32.dds");
    ASSERT_TRUE(rgba32.ok()) << rgba32.error();
    EXPECT_EQ(rgba32->width, 8);
}

TEST(ImageIo, AlphaIsNotPremultipliedIntoTheColour) {
    // RGBA normal maps often carry a height map in alpha; reading must not scale RGB by it.
    test::TempDir dir;
    std::vector<float> px = {0.5f, 0.5f, 1.0f, 0.25f};
    ASSERT_TRUE(writeImage(dir / "rgba.png", 1, 1, 4, OIIO::TypeDesc::UINT8, px));
    auto image = readImage(dir / "rgba.png");
    ASSERT_TRUE(image.ok()) << image.error();
    EXPECT_NEAR(image->at(0, 0, 2), 1.0f, 1e-6f);
    EXPECT_NEAR(image->at(0, 0, 3), 64.0f / 255.0f, 1e-6f);
}

// readImage converts 8- and 16-bit files itself, in parallel through a table: every code of both
// depths (as PNG and TIFF, 1 to 4 channels) must read bit for bit as OpenImageIO's own float read.
TEST(ReadImage, IntegerFilesReadBitForBitAsOpenImageIOsFloatRead) {
    test::TempDir dir;
    for (const OIIO::TypeDesc type : {OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT16})
        for (const char* ext : {"png", "tif"})
            for (int channels = 1; channels <= 4; ++channels) {
                const bool eight = type == OIIO::TypeDesc::UINT8;
                const int codes = eight ? 256 : 65536;
                const int width = 256, height = codes * 1 / 256; // every code once per channel
                std::vector<std::uint16_t> values(size_t(width) * size_t(height) * size_t(channels));
                for (size_t i = 0; i < values.size(); ++i)
                    values[i] =
                        std::uint16_t((i / size_t(channels) + 97 * (i % size_t(channels))) % size_t(codes));
                std::vector<std::uint8_t> bytes(values.begin(), values.end());
                const std::string path = (dir.path() / ("codes." + std::string(ext))).string();
                OIIO::ImageSpec spec(width, height, channels, type);
                spec.attribute("oiio:UnassociatedAlpha", 1);
                auto out = OIIO::ImageOutput::create(path);
                ASSERT_TRUE(
                    out && out->open(path, spec) &&
                    out->write_image(type, eight ? static_cast<const void*>(bytes.data()) : values.data()) &&
                    out->close());
                const auto image = readImage(path);
                ASSERT_TRUE(image) << image.error();
                OIIO::ImageSpec config;
                config.attribute("oiio:UnassociatedAlpha", 1);
                auto in = OIIO::ImageInput::open(path, &config);
                ASSERT_TRUE(in);
                std::vector<float> expected(values.size());
                ASSERT_TRUE(in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, expected.data()));
                ASSERT_EQ(image->pixels.size(), expected.size());
                EXPECT_EQ(std::memcmp(image->pixels.data(), expected.data(), expected.size() * sizeof(float)),
                          0)
                    << ext << " " << channels << " channels, " << (eight ? 8 : 16) << "-bit";
            }
}

// A game asset's atlas with fully transparent padding (RGBA 0, 0, 0, 0) read as "35.5 % of texels
// point below the surface" and was refused (issue 48, point 4). Texels stored as 0 are no data:
// left out of the plausibility test and filled with their nearest texel's normal, the same through
// the PNG decoder and the float path.
TEST(NormalMap, PaddingStoredAsZeroIsNoDataFilledWithTheNearestNormal) {
    constexpr int kW = 16, kH = 8, kFilled = 6; // columns 0..5 hold normals, 6..15 padding
    std::vector<float> px;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            if (x >= kFilled) {
                px.insert(px.end(), {0.0f, 0.0f, 0.0f, 0.0f});
                continue;
            }
            const glm::vec3 n = glm::normalize(glm::vec3(0.1f * float(x), -0.05f * float(y), 1.0f));
            px.insert(px.end(), {n.x * 0.5f + 0.5f, n.y * 0.5f + 0.5f, n.z * 0.5f + 0.5f, 1.0f});
        }
    const auto map = decodeNormalMap(makeImage(kW, kH, 4, px));
    ASSERT_TRUE(map) << map.error();
    EXPECT_EQ(map->diagnostics.noDataTexels, size_t((kW - kFilled) * kH));
    EXPECT_EQ(map->diagnostics.negativeZTexels, 0u) << "the padding is not counted as the map's";
    ASSERT_FALSE(map->diagnostics.warnings.empty());
    EXPECT_NE(map->diagnostics.warnings.back().find("hold no data"), std::string::npos);
    for (int y = 0; y < kH; ++y)
        for (int x = kFilled; x < kW; ++x)
            EXPECT_EQ(map->at(x, y), map->at(kFilled - 1, y)) << "padding texel " << x << ", " << y;

    // The same from an 8-bit PNG (core's own decoder): bit for bit.
    test::TempDir dir;
    const auto path = dir / "atlas.png";
    ASSERT_TRUE(writeImage(path, kW, kH, 4, OIIO::TypeDesc::UINT8, px));
    const auto png = loadNormalMap(path);
    ASSERT_TRUE(png) << png.error();
    EXPECT_EQ(png->diagnostics.noDataTexels, map->diagnostics.noDataTexels);
    for (int y = 0; y < kH; ++y)
        EXPECT_EQ(png->at(kW - 1, y), png->at(kFilled - 1, y));

    // All padding: nothing to read.
    const auto empty = decodeNormalMap(makeImage(2, 2, 4, std::vector<float>(16, 0.0f)));
    ASSERT_FALSE(empty);
    EXPECT_NE(empty.error().find("every texel is stored as 0"), std::string::npos) << empty.error();
    // A signed map's zero vector is no padding: it stays a zero-length texel, made flat.
    NormalMapOptions signedValues;
    signedValues.encoding = NormalValueEncoding::Signed;
    std::vector<float> mostlyFlat;
    for (int i = 0; i < 16; ++i)
        mostlyFlat.insert(mostlyFlat.end(), {0.0f, 0.0f, i == 0 ? 0.0f : 1.0f});
    const auto zero = decodeNormalMap(makeImage(4, 4, 3, mostlyFlat, true), signedValues);
    ASSERT_TRUE(zero) << zero.error();
    EXPECT_EQ(zero->diagnostics.noDataTexels, 0u);
    EXPECT_EQ(zero->diagnostics.zeroLengthTexels, 1u);
}
