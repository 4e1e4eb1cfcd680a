// KTX 2.0 writer and reader (Khronos KTX File Format Specification 2.0, sections 3–4; the Data Format
// Descriptor from the Khronos Data Format Specification 1.3, section 5, "basic descriptor block").
#include <burnish/core/io/image.h>
#include <burnish/core/io/ktx2.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <map>
#include <numeric>

namespace burnish {

namespace {

constexpr std::array<unsigned char, 12> kIdentifier = {0xAB, 'K',  'T',  'X',  ' ',  '2',
                                                       '0',  0xBB, '\r', '\n', 0x1A, '\n'};
constexpr std::uint32_t kHeaderBytes = 12 + 9 * 4 + 4 * 4 + 2 * 8; // identifier, header, index: 80
constexpr std::uint32_t kLevelIndexEntryBytes = 3 * 8;
constexpr std::string_view kWriter = "Burnish";

// Khronos Data Format: colour models, channels and the linear transfer function.
constexpr std::uint8_t kModelRgbsda = 1, kModelBc3 = 130, kModelBc4 = 131, kModelBc5 = 132;
constexpr std::uint8_t kPrimariesBt709 = 1, kTransferLinear = 1;
constexpr std::uint8_t kChannelAlpha = 15;
// A sample's qualifiers beside its channel: a signed IEEE float (KHR_DF_SAMPLE_DATATYPE_SIGNED | _FLOAT).
constexpr std::uint8_t kSignedFloat = 0x40 | 0x80;
constexpr std::uint32_t kFloatMinusOne = 0xBF800000u, kFloatOne = 0x3F800000u;

struct FormatInfo {
    Ktx2Format format;
    std::uint32_t vkFormat;
    std::string_view name;
    int channels;
    int blockBytes; // bytes per texel (uncompressed) or per 4×4 block
    bool blocks;
    std::uint8_t model;
    std::uint32_t typeSize; // the header's: bytes of the format's data type (1 for blocks)
};

// VK_FORMAT_R8_UNORM 9, R8G8_UNORM 16, R8G8B8A8_UNORM 37, BC3_UNORM_BLOCK 137, BC4_UNORM_BLOCK 139,
// BC5_UNORM_BLOCK 141, R16G16B16A16_SFLOAT 97 (the Vulkan specification's VkFormat).
constexpr std::array<FormatInfo, 7> kFormats = {{
    {Ktx2Format::R8, 9, "r8", 1, 1, false, kModelRgbsda, 1},
    {Ktx2Format::Rg8, 16, "rg8", 2, 2, false, kModelRgbsda, 1},
    {Ktx2Format::Rgba8, 37, "rgba8", 4, 4, false, kModelRgbsda, 1},
    {Ktx2Format::Bc3, 137, "bc3", 4, 16, true, kModelBc3, 1},
    {Ktx2Format::Bc4, 139, "bc4", 1, 8, true, kModelBc4, 1},
    {Ktx2Format::Bc5, 141, "bc5", 2, 16, true, kModelBc5, 1},
    {Ktx2Format::Rgba16f, 97, "rgba16f", 4, 8, false, kModelRgbsda, 2},
}};

const FormatInfo& info(Ktx2Format format) {
    return kFormats[static_cast<size_t>(format)];
}

// One sample of the basic descriptor block: bit range, channel, and the range of its values.
struct Sample {
    std::uint16_t bitOffset;
    std::uint8_t bitLengthMinusOne;
    std::uint8_t channel; // channel id and qualifiers
    std::uint32_t upper;
    std::uint32_t lower = 0;
};

std::vector<Sample> samples(Ktx2Format format) {
    switch (format) {
    case Ktx2Format::R8:
        return {{0, 7, 0, 255}};
    case Ktx2Format::Rg8:
        return {{0, 7, 0, 255}, {8, 7, 1, 255}};
    case Ktx2Format::Rgba8:
        return {{0, 7, 0, 255}, {8, 7, 1, 255}, {16, 7, 2, 255}, {24, 7, kChannelAlpha, 255}};
    case Ktx2Format::Bc3:
        return {{0, 63, kChannelAlpha, 0xFFFFFFFFu}, {64, 63, 0, 0xFFFFFFFFu}};
    case Ktx2Format::Bc4:
        return {{0, 63, 0, 0xFFFFFFFFu}};
    case Ktx2Format::Bc5:
        return {{0, 63, 0, 0xFFFFFFFFu}, {64, 63, 1, 0xFFFFFFFFu}};
    case Ktx2Format::Rgba16f: // floats: the range the values are normalised to, −1..1 as the format's own
        return {{0, 15, kSignedFloat, kFloatOne, kFloatMinusOne},
                {16, 15, 1 | kSignedFloat, kFloatOne, kFloatMinusOne},
                {32, 15, 2 | kSignedFloat, kFloatOne, kFloatMinusOne},
                {48, 15, kChannelAlpha | kSignedFloat, kFloatOne, kFloatMinusOne}};
    }
    return {};
}

void put32(std::string& out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put64(std::string& out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i)
        out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void set64(std::string& out, size_t at, std::uint64_t v) {
    for (int i = 0; i < 8; ++i)
        out[at + size_t(i)] = static_cast<char>((v >> (8 * i)) & 0xFF);
}
std::uint32_t get32(std::string_view in, size_t at) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i)
        v = (v << 8) | static_cast<unsigned char>(in[at + size_t(i)]);
    return v;
}
std::uint64_t get64(std::string_view in, size_t at) {
    return std::uint64_t(get32(in, at)) | (std::uint64_t(get32(in, at + 4)) << 32);
}
void padTo(std::string& out, size_t alignment) {
    while (out.size() % alignment != 0)
        out.push_back('\0');
}

std::string dataFormatDescriptor(Ktx2Format format) {
    const FormatInfo& f = info(format);
    const std::vector<Sample> s = samples(format);
    const std::uint32_t blockSize = 24 + 16 * std::uint32_t(s.size());
    std::string out;
    put32(out, 4 + blockSize);        // dfdTotalSize
    put32(out, 0);                    // vendorId KHRONOS (17 bits), descriptorType BASICFORMAT (15 bits)
    put32(out, 2u | blockSize << 16); // versionNumber 1.3 (2), descriptorBlockSize
    out.push_back(static_cast<char>(f.model));
    out.push_back(static_cast<char>(kPrimariesBt709));
    out.push_back(static_cast<char>(kTransferLinear));
    out.push_back(0); // flags: straight alpha
    const char dim = f.blocks ? 3 : 0;
    out.append({dim, dim, 0, 0});                   // texelBlockDimension0..3 (size − 1)
    out.push_back(static_cast<char>(f.blockBytes)); // bytesPlane0
    out.append(7, '\0');                            // bytesPlane1..7
    for (const Sample& sample : s) {
        put32(out, std::uint32_t(sample.bitOffset) | std::uint32_t(sample.bitLengthMinusOne) << 16 |
                       std::uint32_t(sample.channel) << 24);
        put32(out, 0); // samplePosition0..3
        put32(out, sample.lower);
        put32(out, sample.upper);
    }
    return out;
}

int fullChainLevels(int width, int height) {
    int levels = 1;
    while (width > 1 || height > 1) {
        width = std::max(1, width / 2);
        height = std::max(1, height / 2);
        ++levels;
    }
    return levels;
}

std::pair<int, int> levelExtent(int width, int height, int k) {
    return {std::max(1, width >> k), std::max(1, height >> k)};
}

} // namespace

std::uint32_t ktx2VkFormat(Ktx2Format format) {
    return info(format).vkFormat;
}
std::string_view ktx2FormatName(Ktx2Format format) {
    return info(format).name;
}
int ktx2Channels(Ktx2Format format) {
    return info(format).channels;
}
bool ktx2IsBlockCompressed(Ktx2Format format) {
    return info(format).blocks;
}
std::uint64_t ktx2LevelBytes(Ktx2Format format, int width, int height) {
    const FormatInfo& f = info(format);
    if (!f.blocks) return std::uint64_t(width) * std::uint64_t(height) * std::uint64_t(f.blockBytes);
    return std::uint64_t((width + 3) / 4) * std::uint64_t((height + 3) / 4) * std::uint64_t(f.blockBytes);
}

Result<std::string> encodeKtx2(const Ktx2Texture& texture) {
    const FormatInfo& f = info(texture.format);
    if (texture.width < 1 || texture.height < 1 || texture.width > kMaxImageSide ||
        texture.height > kMaxImageSide)
        return Error{fmt::format("KTX2: a {}x{} texture is outside 1..{} on a side", texture.width,
                                 texture.height, kMaxImageSide)};
    const int full = fullChainLevels(texture.width, texture.height);
    if (texture.levels.empty() || int(texture.levels.size()) > full)
        return Error{fmt::format("KTX2: {} levels for a {}x{} texture (1 to {})", texture.levels.size(),
                                 texture.width, texture.height, full)};
    for (size_t k = 0; k < texture.levels.size(); ++k) {
        const auto [w, h] = levelExtent(texture.width, texture.height, int(k));
        const std::uint64_t want = ktx2LevelBytes(texture.format, w, h);
        if (texture.levels[k].size() != want)
            return Error{fmt::format("KTX2: level {} ({}x{} {}) holds {} bytes, not {}", k, w, h, f.name,
                                     texture.levels[k].size(), want)};
    }
    std::map<std::string, std::string> keyValues;
    keyValues["KTXorientation"] = std::string("rd") + '\0';
    keyValues["KTXwriter"] = std::string(kWriter) + '\0';
    for (const auto& [key, value] : texture.keyValues) {
        if (key.empty() || key.find('\0') != std::string::npos)
            return Error{"KTX2: a key/value key is empty or holds a NUL"};
        keyValues[key] = value;
    }

    const std::string dfd = dataFormatDescriptor(texture.format);
    std::string kvd;
    for (const auto& [key, value] : keyValues) { // std::map: sorted by key bytes, as the format asks
        put32(kvd, std::uint32_t(key.size() + 1 + value.size()));
        kvd += key;
        kvd.push_back('\0');
        kvd += value;
        padTo(kvd, 4);
    }

    const size_t levels = texture.levels.size();
    const std::uint32_t dfdOffset = kHeaderBytes + kLevelIndexEntryBytes * std::uint32_t(levels);
    const std::uint32_t kvdOffset = dfdOffset + std::uint32_t(dfd.size());
    std::string out(reinterpret_cast<const char*>(kIdentifier.data()), kIdentifier.size());
    put32(out, f.vkFormat);
    put32(out, f.typeSize);
    put32(out, std::uint32_t(texture.width));
    put32(out, std::uint32_t(texture.height));
    put32(out, 0); // pixelDepth
    put32(out, 0); // layerCount
    put32(out, 1); // faceCount
    put32(out, std::uint32_t(levels));
    put32(out, 0); // supercompressionScheme: none
    put32(out, dfdOffset);
    put32(out, std::uint32_t(dfd.size()));
    put32(out, kvdOffset);
    put32(out, std::uint32_t(kvd.size()));
    put64(out, 0); // sgdByteOffset
    put64(out, 0); // sgdByteLength
    const size_t levelIndex = out.size();
    out.append(kLevelIndexEntryBytes * levels, '\0');
    out += dfd;
    out += kvd;
    const size_t alignment = std::lcm(size_t(f.blockBytes), size_t(4));
    for (size_t k = levels; k-- > 0;) { // smallest level first
        padTo(out, alignment);
        const std::uint64_t offset = out.size(), bytes = texture.levels[k].size();
        set64(out, levelIndex + k * kLevelIndexEntryBytes, offset);
        set64(out, levelIndex + k * kLevelIndexEntryBytes + 8, bytes);
        set64(out, levelIndex + k * kLevelIndexEntryBytes + 16, bytes);
        out += texture.levels[k];
    }
    return out;
}

Result<Ktx2Texture> decodeKtx2(std::string_view bytes) {
    if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kIdentifier.data(), kIdentifier.size()) != 0)
        return Error{bytes.size() >= kIdentifier.size() &&
                             std::memcmp(bytes.data(), kIdentifier.data(), kIdentifier.size()) == 0
                         ? "KTX2: truncated header"
                         : "KTX2: not a KTX 2.0 file (wrong identifier)"};
    const std::uint32_t vkFormat = get32(bytes, 12), typeSize = get32(bytes, 16);
    const std::uint32_t width = get32(bytes, 20), height = get32(bytes, 24), depth = get32(bytes, 28);
    const std::uint32_t layers = get32(bytes, 32), faces = get32(bytes, 36), levels = get32(bytes, 40);
    const std::uint32_t scheme = get32(bytes, 44);
    const std::uint32_t dfdOffset = get32(bytes, 48), dfdLength = get32(bytes, 52);
    const std::uint32_t kvdOffset = get32(bytes, 56), kvdLength = get32(bytes, 60);
    const std::uint64_t sgdOffset = get64(bytes, 64), sgdLength = get64(bytes, 72);
    const auto found = std::find_if(kFormats.begin(), kFormats.end(),
                                    [&](const FormatInfo& f) { return f.vkFormat == vkFormat; });
    if (found == kFormats.end())
        return Error{fmt::format(
            "KTX2: vkFormat {} is not one Burnish reads (r8, rg8, rgba8, bc3, bc4, bc5, rgba16f)", vkFormat)};
    if (typeSize != found->typeSize)
        return Error{fmt::format("KTX2: typeSize {} for {} ({})", typeSize, found->name, found->typeSize)};
    if (width < 1 || height < 1 || width > std::uint32_t(kMaxImageSide) ||
        height > std::uint32_t(kMaxImageSide))
        return Error{
            fmt::format("KTX2: a {}x{} texture is outside 1..{} on a side", width, height, kMaxImageSide)};
    if (depth != 0 || layers != 0 || faces != 1)
        return Error{"KTX2: a volume, array or cube map (Burnish reads one 2D texture)"};
    if (scheme != 0)
        return Error{fmt::format("KTX2: supercompression scheme {} (Burnish reads none)", scheme)};
    const int full = fullChainLevels(int(width), int(height));
    if (levels < 1 || levels > std::uint32_t(full))
        return Error{
            fmt::format("KTX2: {} levels for a {}x{} texture (1 to {})", levels, width, height, full)};
    if (sgdOffset != 0 || sgdLength != 0) return Error{"KTX2: supercompression global data without a scheme"};
    const std::uint64_t indexEnd = kHeaderBytes + std::uint64_t(kLevelIndexEntryBytes) * levels;
    auto inside = [&](std::uint64_t offset, std::uint64_t length) {
        return offset >= indexEnd && offset <= bytes.size() && length <= bytes.size() - offset;
    };
    if (indexEnd > bytes.size()) return Error{"KTX2: truncated level index"};
    if (!inside(dfdOffset, dfdLength) || dfdLength < 4)
        return Error{"KTX2: the data format descriptor lies outside the file"};
    if (kvdLength != 0 && !inside(kvdOffset, kvdLength))
        return Error{"KTX2: the key/value data lies outside the file"};

    Ktx2Texture texture;
    texture.format = found->format;
    texture.width = int(width);
    texture.height = int(height);
    const std::string expectedDfd = dataFormatDescriptor(texture.format);
    const std::string_view dfd = bytes.substr(dfdOffset, dfdLength);
    // The descriptor must name the format's colour model, block size, bytes and samples (primaries,
    // transfer function and flags are free).
    auto sameExceptColour = [&](std::string_view a, std::string_view b) {
        if (a.size() != b.size()) return false;
        for (size_t i = 0; i < a.size(); ++i)
            if ((i < 13 || i > 15) && a[i] != b[i]) return false;
        return true;
    };
    if (!sameExceptColour(dfd, expectedDfd))
        return Error{fmt::format("KTX2: the data format descriptor does not describe {}", found->name)};

    std::string previousKey;
    for (size_t at = 0; at < kvdLength;) {
        if (kvdLength - at < 4) return Error{"KTX2: truncated key/value data"};
        const std::uint32_t length = get32(bytes, kvdOffset + at);
        if (length > kvdLength - at - 4) return Error{"KTX2: a key/value entry runs past its data"};
        const std::string_view entry = bytes.substr(kvdOffset + at + 4, length);
        const size_t nul = entry.find('\0');
        if (nul == std::string_view::npos || nul == 0) return Error{"KTX2: a key/value entry without a key"};
        std::string key(entry.substr(0, nul));
        // The format sorts the keys by their bytes, each once (what the writer's map gives back).
        if (!previousKey.empty() && !(previousKey < key))
            return Error{"KTX2: the key/value keys are not sorted and unique"};
        previousKey = key;
        if (key != "KTXorientation" && key != "KTXwriter")
            texture.keyValues.emplace_back(std::move(key), std::string(entry.substr(nul + 1)));
        at += 4 + length;
        at += (4 - at % 4) % 4;
    }

    std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;
    const std::uint64_t dataStart =
        std::uint64_t(kvdLength != 0 ? kvdOffset + kvdLength : dfdOffset + dfdLength);
    for (std::uint32_t k = 0; k < levels; ++k) {
        const size_t at = kHeaderBytes + size_t(k) * kLevelIndexEntryBytes;
        const std::uint64_t offset = get64(bytes, at), length = get64(bytes, at + 8),
                            raw = get64(bytes, at + 16);
        const auto [w, h] = levelExtent(texture.width, texture.height, int(k));
        const std::uint64_t want = ktx2LevelBytes(texture.format, w, h);
        if (length != want || raw != want)
            return Error{fmt::format("KTX2: level {} ({}x{} {}) holds {} bytes, not {}", k, w, h, found->name,
                                     length, want)};
        if (offset < dataStart || !inside(offset, length))
            return Error{fmt::format("KTX2: level {} lies outside the file's level data", k)};
        ranges.emplace_back(offset, length);
        texture.levels.emplace_back(bytes.substr(offset, length));
    }
    std::sort(ranges.begin(), ranges.end());
    for (size_t i = 1; i < ranges.size(); ++i)
        if (ranges[i - 1].first + ranges[i - 1].second > ranges[i].first)
            return Error{"KTX2: two levels overlap"};
    return texture;
}

} // namespace burnish
