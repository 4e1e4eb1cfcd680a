// The KTX2 writer and reader: byte layout against the KTX 2.0 specification's fixed fields, round trips
// of every format, and the reader's refusals of damaged files.
#include <burnish/core/io/ktx2.h>

#include <gtest/gtest.h>

#include <cstring>

using namespace burnish;

namespace {

std::uint32_t u32(const std::string& s, size_t at) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i)
        v = (v << 8) | static_cast<unsigned char>(s[at + size_t(i)]);
    return v;
}
std::uint64_t u64(const std::string& s, size_t at) {
    return std::uint64_t(u32(s, at)) | (std::uint64_t(u32(s, at + 4)) << 32);
}

Ktx2Texture chain(Ktx2Format format, int width, int height) {
    Ktx2Texture t;
    t.format = format;
    t.width = width;
    t.height = height;
    for (int k = 0;; ++k) {
        const int w = std::max(1, width >> k), h = std::max(1, height >> k);
        std::string level(ktx2LevelBytes(format, w, h), '\0');
        for (size_t i = 0; i < level.size(); ++i)
            level[i] = static_cast<char>((i * 7 + size_t(k) * 13) & 0xFF);
        t.levels.push_back(std::move(level));
        if (w == 1 && h == 1) break;
    }
    return t;
}

} // namespace

TEST(Ktx2, HeaderLevelIndexAndAlignmentFollowTheSpecification) {
    const Ktx2Texture t = chain(Ktx2Format::Rg8, 8, 4);
    auto bytes = encodeKtx2(t);
    ASSERT_TRUE(bytes) << bytes.error();
    const std::string& b = *bytes;
    const unsigned char id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    EXPECT_EQ(std::memcmp(b.data(), id, 12), 0);
    EXPECT_EQ(u32(b, 12), 16u); // VK_FORMAT_R8G8_UNORM
    EXPECT_EQ(u32(b, 16), 1u);  // typeSize
    EXPECT_EQ(u32(b, 20), 8u);
    EXPECT_EQ(u32(b, 24), 4u);
    EXPECT_EQ(u32(b, 28), 0u);
    EXPECT_EQ(u32(b, 32), 0u);
    EXPECT_EQ(u32(b, 36), 1u);
    EXPECT_EQ(u32(b, 40), 4u); // 8x4, 4x2, 2x1, 1x1
    EXPECT_EQ(u32(b, 44), 0u);
    const std::uint32_t dfdOffset = u32(b, 48), dfdLength = u32(b, 52);
    EXPECT_EQ(dfdOffset, 80u + 4 * 24);
    EXPECT_EQ(dfdLength, 4u + 24 + 2 * 16);
    EXPECT_EQ(u32(b, dfdOffset), dfdLength);
    EXPECT_EQ(static_cast<unsigned char>(b[dfdOffset + 12]), 1); // KHR_DF_MODEL_RGBSDA
    EXPECT_EQ(static_cast<unsigned char>(b[dfdOffset + 14]), 1); // linear transfer
    EXPECT_EQ(u32(b, 56), dfdOffset + dfdLength);
    // Levels stored smallest first, each offset a multiple of 4, the last one ending the file.
    std::uint64_t previous = 0;
    for (int k = 3; k >= 0; --k) {
        const std::uint64_t offset = u64(b, 80 + size_t(k) * 24), length = u64(b, 80 + size_t(k) * 24 + 8);
        EXPECT_EQ(offset % 4, 0u);
        EXPECT_GT(offset, previous);
        EXPECT_EQ(length, t.levels[size_t(k)].size());
        EXPECT_EQ(u64(b, 80 + size_t(k) * 24 + 16), length);
        EXPECT_EQ(b.substr(offset, length), t.levels[size_t(k)]);
        previous = offset;
    }
    EXPECT_EQ(u64(b, 80) + u64(b, 88), b.size());
    EXPECT_NE(b.find(std::string("KTXorientation\0rd\0", 18)), std::string::npos);
}

TEST(Ktx2, EveryFormatRoundTripsWithItsKeyValues) {
    for (Ktx2Format format : {Ktx2Format::R8, Ktx2Format::Rg8, Ktx2Format::Rgba8, Ktx2Format::Bc3,
                              Ktx2Format::Bc4, Ktx2Format::Bc5, Ktx2Format::Rgba16f}) {
        SCOPED_TRACE(std::string(ktx2FormatName(format)));
        Ktx2Texture t = chain(format, 13, 6); // not a power of two: 13x6, 6x3, 3x1, 1x1
        t.keyValues = {{"burnish:role", "roughness"}};
        auto bytes = encodeKtx2(t);
        ASSERT_TRUE(bytes) << bytes.error();
        const size_t blockBytes = ktx2IsBlockCompressed(format)   ? (format == Ktx2Format::Bc4 ? 8 : 16)
                                  : format == Ktx2Format::Rgba16f ? 8
                                                                  : 4;
        for (size_t k = 0; k < t.levels.size(); ++k)
            EXPECT_EQ(u64(*bytes, 80 + k * 24) % blockBytes, 0u);
        auto back = decodeKtx2(*bytes);
        ASSERT_TRUE(back) << back.error();
        EXPECT_EQ(back->format, format);
        EXPECT_EQ(back->width, 13);
        EXPECT_EQ(back->height, 6);
        EXPECT_EQ(back->levels, t.levels);
        EXPECT_EQ(back->keyValues, t.keyValues);
        auto again = encodeKtx2(*back);
        ASSERT_TRUE(again);
        EXPECT_EQ(*again, *bytes);
    }
}

TEST(Ktx2, HalfFloatsAreDescribedAsSignedFloatSamples) {
    // VK_FORMAT_R16G16B16A16_SFLOAT: typeSize 2, 8 bytes a texel, four 16-bit samples each flagged signed
    // and float (0xC0 beside the channel id) with the range -1.0f..1.0f, as toktx writes them.
    auto bytes = encodeKtx2(chain(Ktx2Format::Rgba16f, 4, 2));
    ASSERT_TRUE(bytes) << bytes.error();
    const std::string& b = *bytes;
    EXPECT_EQ(u32(b, 12), 97u);
    EXPECT_EQ(u32(b, 16), 2u);
    const std::uint32_t dfd = u32(b, 48);
    EXPECT_EQ(u32(b, 52), 4u + 24 + 4 * 16);
    EXPECT_EQ(static_cast<unsigned char>(b[dfd + 20]), 8); // bytesPlane0
    const unsigned char channels[4] = {0, 1, 2, 15};
    for (size_t i = 0; i < 4; ++i) {
        const size_t at = dfd + 28 + i * 16;
        EXPECT_EQ(u32(b, at), std::uint32_t(16 * i) | 15u << 16 | std::uint32_t(channels[i] | 0xC0) << 24);
        EXPECT_EQ(u32(b, at + 8), 0xBF800000u);
        EXPECT_EQ(u32(b, at + 12), 0x3F800000u);
    }
    // Every level at an offset that is a multiple of 8 (a texel), so a reader can view it as 16-bit words.
    for (size_t k = 0; k < 3; ++k)
        EXPECT_EQ(u64(b, 80 + k * 24) % 8, 0u);
    // A typeSize of 1 does not describe half floats.
    std::string wrong = b;
    wrong[16] = 1;
    auto r = decodeKtx2(wrong);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("typeSize"), std::string::npos) << r.error();
}

TEST(Ktx2, TheWriterRefusesAChainThatDoesNotFitItsExtent) {
    Ktx2Texture t = chain(Ktx2Format::Rgba8, 4, 4);
    t.levels[1].pop_back();
    auto bytes = encodeKtx2(t);
    ASSERT_FALSE(bytes);
    EXPECT_NE(bytes.error().find("level 1"), std::string::npos) << bytes.error();
    t = chain(Ktx2Format::Rgba8, 4, 4);
    t.levels.push_back(std::string(4, '\0'));
    EXPECT_FALSE(encodeKtx2(t));
    t = chain(Ktx2Format::Rgba8, 4, 4);
    t.width = 0;
    EXPECT_FALSE(encodeKtx2(t));
    t = chain(Ktx2Format::Rgba8, 4, 4);
    t.keyValues = {{std::string("a\0b", 3), "x"}};
    EXPECT_FALSE(encodeKtx2(t));
}

TEST(Ktx2, TheReaderRefusesDamagedFilesInOneLine) {
    auto good = encodeKtx2(chain(Ktx2Format::Rgba8, 16, 16));
    ASSERT_TRUE(good);
    auto refused = [](const std::string& bytes, const std::string& what) {
        auto r = decodeKtx2(bytes);
        ASSERT_FALSE(r) << what;
        EXPECT_EQ(r.error().find('\n'), std::string::npos) << r.error();
        EXPECT_EQ(r.error().rfind("KTX2: ", 0), 0u) << r.error();
    };
    refused("", "empty");
    refused(std::string("\x89PNG\r\n\x1a\n", 8) + std::string(100, '\0'), "a PNG");
    for (size_t cut : {size_t(20), size_t(90), size_t(200), good->size() - 1})
        refused(good->substr(0, cut), "truncated at " + std::to_string(cut));
    auto patched = [&](size_t at, std::uint32_t value) {
        std::string b = *good;
        for (int i = 0; i < 4; ++i)
            b[at + size_t(i)] = static_cast<char>((value >> (8 * i)) & 0xFF);
        return b;
    };
    refused(patched(12, 23), "R8G8B8_UNORM");
    refused(patched(28, 2), "depth");
    refused(patched(36, 6), "a cube map");
    refused(patched(40, 6), "more levels than the chain");
    refused(patched(40, 0), "no levels");
    refused(patched(44, 2), "zstd supercompression");
    refused(patched(20, 0), "zero width");
    refused(patched(80, 0), "level 0 at offset 0");
    refused(patched(88, 3), "level 0's length");
    refused(patched(80 + 24, u32(*good, 80)), "levels 0 and 1 overlapping");
    const std::uint32_t dfd = u32(*good, 48);
    refused(patched(dfd + 12, 131u | (1u << 8) | (1u << 16)), "a BC4 descriptor on RGBA8");
    refused(patched(52, 0xFFFFFF00u), "a descriptor past the end");
    refused(patched(60, 0xFFFFFF00u), "key/value data past the end");
    refused(patched(u32(*good, 56), 0xFFFFu), "a key/value entry past its data");
    // Keys out of order: "KTXorientation" renamed "KTXz..." sorts after "KTXwriter".
    std::string unsorted = *good;
    const size_t key = unsorted.find("KTXorientation");
    ASSERT_NE(key, std::string::npos);
    unsorted[key + 3] = 'z';
    refused(unsorted, "keys out of order");

    // Every level's bytes must be there (issue 45): the file cut inside each level in turn — its first
    // byte, its middle, its last — is refused, for a compressed chain as for an 8-bit one.
    for (Ktx2Format format : {Ktx2Format::Rgba8, Ktx2Format::Bc5}) {
        auto file = encodeKtx2(chain(format, 16, 16));
        ASSERT_TRUE(file);
        const std::uint32_t levels = u32(*file, 40);
        ASSERT_GE(levels, 3u);
        for (std::uint32_t k = 0; k < levels; ++k) {
            const std::uint64_t offset = u64(*file, 80 + size_t(k) * 24),
                                length = u64(*file, 80 + size_t(k) * 24 + 8);
            for (std::uint64_t cut : {offset, offset + length / 2, offset + length - 1}) {
                const auto r = decodeKtx2(file->substr(0, size_t(cut)));
                ASSERT_FALSE(r) << "level " << k << " cut at " << cut;
                EXPECT_NE(r.error().find("outside"), std::string::npos) << r.error();
            }
        }
        EXPECT_TRUE(decodeKtx2(*file)) << "the whole file reads";
    }
}
