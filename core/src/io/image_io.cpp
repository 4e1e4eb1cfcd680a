#include <burnish/core/io/image.h>

#include <burnish/core/util/files.h>

#include "io/image_read.h"
#include "io/png_decode.h"

#include <OpenImageIO/imageio.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <numeric>
#include <optional>
#include <string_view>
#include <system_error>

namespace burnish {

namespace fs = std::filesystem;

namespace {

using FileBytes = std::vector<char, TexelAllocator<char>>;

/// The whole file, read with plain reads into a buffer that is not zero-filled first.
Result<FileBytes> readFileBytes(const fs::path& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return Error{std::strerror(errno)};
    struct stat st {};
    FileBytes bytes;
    std::string error;
    if (::fstat(fd, &st) != 0) {
        error = std::strerror(errno);
    } else {
        bytes.resize(size_t(st.st_size));
        size_t done = 0;
        while (done < bytes.size()) {
            const ssize_t got = ::read(fd, bytes.data() + done, bytes.size() - done);
            if (got < 0 && errno == EINTR) continue;
            if (got <= 0) {
                error = got < 0 ? std::strerror(errno) : "the file shrank while it was read";
                break;
            }
            done += size_t(got);
        }
    }
    ::close(fd);
    if (!error.empty()) return Error{error};
    return bytes;
}

/// A library's message as one line: its line breaks become "; ", trailing ones go.
std::string oneLine(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
        text.pop_back();
    for (size_t at = text.find('\n'); at != std::string::npos; at = text.find('\n', at))
        text.replace(at, 1, "; ");
    return text;
}

/// Whether the file starts with the 8-byte PNG signature.
bool fileHasPngSignature(const fs::path& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    char head[8] = {};
    const ssize_t got = ::read(fd, head, sizeof head);
    ::close(fd);
    return got > 0 && hasPngSignature(std::string_view(head, size_t(got)));
}

/// A DDS file checked against its header before OpenImageIO reads it: no more mip levels than the
/// image's chain has, texels OpenImageIO 2.4 decodes safely, and the file holds at least the first
/// level of its first surface. Header (Microsoft's
/// DDS_HEADER, little-endian, after the 4-byte magic "DDS "): height at 12, width at 16, the pixel
/// format's flags at 80, FourCC at 84 and bits per pixel at 88; a FourCC of "DX10" adds a 20-byte
/// header whose first field is the DXGI format.
Status checkDdsHeader(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::error_code ec;
    const std::uint64_t fileSize = fs::file_size(path, ec);
    if (!in || ec) return {}; // OpenImageIO says why it cannot read it
    unsigned char h[148] = {};
    in.read(reinterpret_cast<char*>(h), sizeof h);
    if (in.gcount() < 128 || std::memcmp(h, "DDS ", 4) != 0) return {};
    auto u32 = [&](int at) {
        return std::uint32_t(h[at]) | std::uint32_t(h[at + 1]) << 8 | std::uint32_t(h[at + 2]) << 16 |
               std::uint32_t(h[at + 3]) << 24;
    };
    const std::uint64_t height = std::max<std::uint32_t>(u32(12), 1),
                        width = std::max<std::uint32_t>(u32(16), 1);
    const std::uint32_t pfFlags = u32(80), bits = u32(88);
    // A mip count beyond the image's chain: OpenImageIO's reader seeks through every claimed level
    // (an 8×8 file claiming 905969666 levels took it 90 s; found by fuzzing).
    std::uint32_t levels = 1;
    while ((std::max(width, height) >> levels) > 0)
        ++levels;
    if (u32(28) > levels)
        return Error{"corrupt: its header claims " + std::to_string(u32(28)) + " mip levels, and a " +
                     std::to_string(width) + "x" + std::to_string(height) + " image has " +
                     std::to_string(levels)};
    const std::string fourCC(reinterpret_cast<const char*>(h + 84), 4);
    constexpr std::uint32_t kFourCC = 0x4;
    // Uncompressed texels other than 8, 16, 24 or 32 bits: OpenImageIO's reader steps through the
    // rows by the bytes per texel, so 0 bits per texel never ends (an 8×8 file ran for over 17
    // minutes; found by fuzzing), and it copies each texel into 32 bits, so a wider one overruns.
    if (!(pfFlags & kFourCC) && bits != 8 && bits != 16 && bits != 24 && bits != 32)
        return Error{"corrupt: its pixel format has no FourCC and " + std::to_string(bits) +
                     " bits per texel (uncompressed DDS texels take 8, 16, 24 or 32)"};
    // DXT2 and DXT4 (premultiplied alpha): OpenImageIO 2.4's reader divides by zero un-premultiplying
    // them, which kills the process (any such file; found by fuzzing). Refused with what to do.
    if ((pfFlags & kFourCC) && (fourCC == "DXT2" || fourCC == "DXT4"))
        return Error{"unsupported: it is " + fourCC +
                     " (BC2/BC3 with premultiplied alpha), which Burnish does not read; save it as "
                     "BC5 (ATI2), DXT5/BC3 or DXT1/BC1"};
    std::uint64_t header = 128, blockBytes = 0;
    if (pfFlags & kFourCC) {
        if (fourCC == "DX10") {
            header += 20;
            const std::uint32_t dxgi = u32(128);
            // BC1 and BC4 (DXGI 70-72, 79-81) take 8 bytes a 4×4 block; BC2, BC3, BC5, BC6H, BC7 16.
            if ((dxgi >= 70 && dxgi <= 72) || (dxgi >= 79 && dxgi <= 81))
                blockBytes = 8;
            else if (dxgi >= 73 && dxgi <= 99)
                blockBytes = 16;
        } else if (fourCC == "DXT1" || fourCC == "ATI1" || fourCC == "BC4U" || fourCC == "BC4S") {
            blockBytes = 8;
        } else if (fourCC == "DXT3" || fourCC == "DXT5" || fourCC == "ATI2" || fourCC == "BC5U" ||
                   fourCC == "BC5S") {
            blockBytes = 16;
        }
    }
    // Every level the header claims, of every surface: a file cut inside its mip tail was read with
    // level 0 whole and the rest from past the end. Surfaces: a cube's six faces (DDSCAPS2_CUBEMAP
    // with its face flags, or DX10's TEXTURECUBE), times DX10's array size.
    auto levelBytes = [&](std::uint64_t w, std::uint64_t hgt) -> std::uint64_t {
        if (blockBytes > 0) return ((w + 3) / 4) * ((hgt + 3) / 4) * blockBytes;
        if (!(pfFlags & kFourCC)) return w * hgt * (bits / 8);
        return 0; // a format not checked here: OpenImageIO's
    };
    const std::uint32_t claimedLevels = std::max<std::uint32_t>(u32(28), 1);
    std::uint64_t surfaces = 1;
    constexpr std::uint32_t kCubeMap = 0x200, kAllFaces = 0xfc00;
    if ((u32(112) & kCubeMap) != 0) surfaces = std::uint64_t(__builtin_popcount(u32(112) & kAllFaces));
    if (header == 148) {
        const std::uint32_t arraySize = std::max<std::uint32_t>(u32(140), 1);
        constexpr std::uint32_t kTextureCube = 0x4;
        surfaces = std::uint64_t(arraySize) * ((u32(136) & kTextureCube) ? 6 : 1);
    }
    std::uint64_t first = levelBytes(width, height), chain = 0;
    for (std::uint32_t k = 0; k < claimedLevels; ++k)
        chain += levelBytes(std::max<std::uint64_t>(width >> k, 1), std::max<std::uint64_t>(height >> k, 1));
    if (first == 0) return {};
    if (fileSize < header + first)
        return Error{"truncated: its header claims " + std::to_string(width) + "x" + std::to_string(height) +
                     " texels, whose first level needs " + std::to_string(header + first) +
                     " bytes, and the file has " + std::to_string(fileSize)};
    const std::uint64_t need = header + chain * std::max<std::uint64_t>(surfaces, 1);
    if (fileSize < need)
        return Error{"truncated: its header claims " + std::to_string(claimedLevels) + " mip levels of " +
                     std::to_string(width) + "x" + std::to_string(height) + " texels" +
                     (surfaces > 1 ? " on " + std::to_string(surfaces) + " surfaces" : std::string()) +
                     ", which need " + std::to_string(need) + " bytes, and the file has " +
                     std::to_string(fileSize)};
    return {};
}

/// An OpenEXR file's headers checked before OpenEXR reads them: every attribute's value must fit in
/// the file. OpenEXR allocates (and clears) whatever size an attribute claims, so a 300-byte file
/// claiming a 2 GB string took gigabytes and tens of seconds before failing (found by fuzzing).
/// Attributes: name NUL, type NUL, int32 size (little-endian), value; a header ends with an empty
/// name; a multi-part file (version flag 0x1000) ends its headers with an empty header.
Status checkExrHeaders(const fs::path& path) {
    constexpr std::uint32_t kMultiPart = 0x1000, kLongNames = 0x400;
    constexpr int kMaxAttributes = 1 << 16;
    std::ifstream in(path, std::ios::binary);
    std::error_code ec;
    const std::uint64_t fileSize = fs::file_size(path, ec);
    if (!in || ec) return {}; // OpenImageIO says why it cannot read it
    unsigned char head[8] = {};
    if (!in.read(reinterpret_cast<char*>(head), sizeof head)) return {};
    if (head[0] != 0x76 || head[1] != 0x2f || head[2] != 0x31 || head[3] != 0x01) return {};
    const std::uint32_t flags = std::uint32_t(head[5]) << 8 | std::uint32_t(head[6]) << 16;
    const size_t maxName = (flags & kLongNames) ? 256 : 32;
    auto readName = [&](std::string& out) {
        out.clear();
        for (char c; in.get(c);) {
            if (c == '\0') return true;
            if (out.size() >= maxName) return false;
            out += c;
        }
        return false;
    };
    const auto corrupt = [](const std::string& why) { return Error{"the file is corrupt (" + why + ")"}; };
    std::string name, type;
    int attributes = 0;
    for (bool firstHeader = true;; firstHeader = false) {
        // A multi-part file's list of headers ends with an empty one; a single part has one header.
        if (!firstHeader && !(flags & kMultiPart)) return {};
        bool emptyHeader = true;
        for (;;) {
            if (!readName(name)) return corrupt("an EXR header ends early or holds an over-long name");
            if (name.empty()) break;
            emptyHeader = false;
            if (!readName(type)) return corrupt("the EXR attribute '" + name + "' has no type");
            unsigned char sizeBytes[4];
            if (!in.read(reinterpret_cast<char*>(sizeBytes), 4))
                return Error{"the file is truncated (the EXR attribute '" + name + "' has no size)"};
            const std::int32_t size =
                std::int32_t(std::uint32_t(sizeBytes[0]) | std::uint32_t(sizeBytes[1]) << 8 |
                             std::uint32_t(sizeBytes[2]) << 16 | std::uint32_t(sizeBytes[3]) << 24);
            const std::uint64_t at = std::uint64_t(in.tellg());
            if (size < 0 || at + std::uint64_t(size) > fileSize)
                return corrupt("the EXR attribute '" + name + "' claims " + std::to_string(size) +
                               " bytes and " + std::to_string(fileSize - std::min(at, fileSize)) + " remain");
            // The data window sizes OpenEXR's tables (a line offset per chunk): one beyond what
            // Burnish accepts is refused here, before OpenEXR allocates for it (a 430-byte file
            // claiming 2^30 lines had it allocate and clear half a gigabyte; found by fuzzing).
            if ((name == "dataWindow" || name == "displayWindow") && type == "box2i" && size == 16) {
                unsigned char box[16];
                if (!in.read(reinterpret_cast<char*>(box), 16))
                    return Error{"the file is truncated (in the EXR attribute '" + name + "')"};
                auto at32 = [&](int i) {
                    return std::int64_t(std::int32_t(
                        std::uint32_t(box[4 * i]) | std::uint32_t(box[4 * i + 1]) << 8 |
                        std::uint32_t(box[4 * i + 2]) << 16 | std::uint32_t(box[4 * i + 3]) << 24));
                };
                const std::int64_t w = at32(2) - at32(0) + 1, h = at32(3) - at32(1) + 1;
                if (name == "dataWindow" && (w < 1 || h < 1))
                    return corrupt("the EXR data window is " + std::to_string(w) + "x" + std::to_string(h));
                if (w > kMaxImageSide || h > kMaxImageSide || w * h > std::int64_t(kMaxImageTexels))
                    return Error{"its EXR " + name + " is " + std::to_string(w) + "x" + std::to_string(h) +
                                 ", larger than Burnish accepts (65536 on a side, 2^30 texels)"};
            } else {
                in.seekg(std::streamoff(size), std::ios::cur);
            }
            if (++attributes > kMaxAttributes) return corrupt("more than 65536 EXR header attributes");
        }
        if (emptyHeader && !firstHeader) return {};
    }
}

/// A library's reason for a failed read, named as what it is: "the file is truncated (…)" when the
/// data ended early, "the file is corrupt (…)" otherwise.
std::string damaged(const std::string& why) {
    const bool truncated =
        why.find("end of file") != std::string::npos || why.find("EOF") != std::string::npos ||
        why.find("Premature end") != std::string::npos || why.find("truncat") != std::string::npos ||
        why.find("Failed to read") != std::string::npos || why.find("Read error") != std::string::npos;
    return std::string("the file is ") + (truncated ? "truncated" : "corrupt") + " (" + oneLine(why) + ")";
}

/// The error OpenImageIO recorded while reading pixels it nonetheless handed back (a DDS or JPEG
/// cut short is filled with zeros or grey and read_image succeeds): an error, never texels.
std::optional<Error> pendingReadError(OIIO::ImageInput& in, const fs::path& path) {
    const std::string why = in.geterror();
    if (why.empty()) return std::nullopt;
    return Error{"cannot read image '" + path.string() + "': " + damaged(why)};
}

} // namespace

namespace {

/// The size limits every reader shares.
Status checkImageSize(const fs::path& path, int width, int height, int channels) {
    if (width <= 0 || height <= 0 || channels <= 0)
        return Error{"image '" + path.string() + "' has no pixels"};
    if (width > kMaxImageSide || height > kMaxImageSide ||
        static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) > kMaxImageTexels)
        return Error{"image '" + path.string() + "' is " + std::to_string(width) + "x" +
                     std::to_string(height) + ", larger than Burnish accepts (65536 on a side, 2^30 texels)"};
    if (channels > 4)
        return Error{"image '" + path.string() + "' has " + std::to_string(channels) +
                     " channels; Burnish reads 1 to 4"};
    return Status::success();
}

/// Opens the file with OpenImageIO (the formats core does not decode itself) and checks what it sees.
Status openWithOiio(OpenedImage& opened) {
    const fs::path& path = opened.path;
    // Data maps are read as stored: OpenImageIO would otherwise premultiply the colour of PNG/TGA
    // files by their alpha ("associated alpha"), scaling an RGBA normal map's vectors by the
    // height map in its alpha.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    opened.input = OIIO::ImageInput::open(path.string(), &config);
    if (!opened.input) {
        const std::string why = OIIO::geterror();
        // A format OpenImageIO knows by the file's name that it could not open is damaged.
        const bool known = !why.empty() && OIIO::ImageInput::create(path.string(), false) != nullptr &&
                           why.find("Could not open file") != std::string::npos;
        return Error{"cannot read image '" + path.string() + "': " +
                     (why.empty() ? std::string("unknown or unsupported format")
                      : known     ? damaged(why)
                                  : oneLine(why))};
    }
    const OIIO::ImageSpec& spec = opened.input->spec();
    if (const Status size = checkImageSize(path, spec.width, spec.height, spec.nchannels); !size) return size;
    if (spec.depth > 1)
        return Error{"image '" + path.string() + "' is a volume texture; Burnish reads 2D images"};
    opened.width = spec.width;
    opened.height = spec.height;
    opened.channels = spec.nchannels;
    opened.source.path = path.string();
    opened.source.formatName = opened.input->format_name();
    opened.source.channelType = spec.format.c_str();
    opened.source.bitsPerChannel = static_cast<int>(spec.format.size() * 8);
    opened.source.isFloat = spec.format.is_floating_point();
    opened.source.colorSpace = spec.get_string_attribute("oiio:ColorSpace");

    if (spec.format == OIIO::TypeDesc::UINT8 || spec.format == OIIO::TypeDesc::UINT16) {
        // 8- and 16-bit images are read as stored and converted on every core through a table
        // that OpenImageIO fills with its own conversion, so each float is bit for bit what
        // read_image(FLOAT) gives, without its single-threaded conversion of every sample.
        const bool eightBit = spec.format == OIIO::TypeDesc::UINT8;
        const size_t codes = eightBit ? 256 : 65536;
        std::vector<std::uint8_t> codes8(eightBit ? codes : 0);
        std::vector<std::uint16_t> codes16(eightBit ? 0 : codes);
        std::iota(codes8.begin(), codes8.end(), std::uint8_t(0));
        std::iota(codes16.begin(), codes16.end(), std::uint16_t(0));
        opened.table.resize(codes);
        const void* codeData = eightBit ? static_cast<const void*>(codes8.data()) : codes16.data();
        if (!OIIO::convert_pixel_values(spec.format, codeData, OIIO::TypeDesc::FLOAT, opened.table.data(),
                                        int(codes)))
            return Error{"cannot read image '" + path.string() + "': no conversion from " +
                         std::string(spec.format.c_str())};
        opened.bitDepth = eightBit ? 8 : 16;
    }
    return Status::success();
}

} // namespace

std::vector<float> unsignedCodeTable(int bitDepth) {
    // OpenImageIO's integer-to-float conversion: the code times the float reciprocal of the largest
    // code (a test checks every code against it), so core's decoder gives its floats bit for bit.
    const std::uint32_t codes = bitDepth == 8 ? 256u : 65536u;
    const float scale = 1.0f / float(codes - 1);
    std::vector<float> table(codes);
    for (std::uint32_t c = 0; c < codes; ++c)
        table[c] = float(c) * scale;
    return table;
}

Result<OpenedImage> openImage(const fs::path& path) {
    if (const Status st = requireRegularFile(path, "image"); !st) return Error{st.error()};

    // PNG files are read and their chunks checked first: libpng, which OpenImageIO reads them with,
    // prints its own multi-line messages for damaged headers before any error reaches us.
    OpenedImage opened;
    opened.path = path;
    if (fileHasPngSignature(path)) {
        auto file = readFileBytes(path);
        if (!file) return Error{"cannot read image '" + path.string() + "': " + file.error()};
        auto layout = parsePng(std::string_view(file->data(), file->size()));
        if (!layout) return Error{"cannot read image '" + path.string() + "': " + layout.error()};
        if (layout->decodable) {
            // Core decodes it (readPngCodes): OpenImageIO is not asked, nor loaded.
            if (const Status size = checkImageSize(path, layout->width, layout->height, layout->channels);
                !size)
                return Error{size.error()};
            opened.width = layout->width;
            opened.height = layout->height;
            opened.channels = layout->channels;
            opened.bitDepth = layout->bitDepth;
            opened.source.path = path.string();
            opened.source.formatName = "png";
            opened.source.channelType = layout->bitDepth == 8 ? "uint8" : "uint16";
            opened.source.bitsPerChannel = layout->bitDepth;
            opened.source.isFloat = false;
            opened.source.colorSpace = layout->colorSpace();
            opened.table = unsignedCodeTable(layout->bitDepth);
            opened.pngFile = std::move(file).value();
            return opened;
        }
        // Files core's decoder leaves to libpng: their data checked here, before libpng reads it.
        if (const Status data = checkPngData(*layout); !data)
            return Error{"cannot read image '" + path.string() + "': " + data.error()};
        opened.pngFile = std::move(file).value();
    }

    if (const Status exr = checkExrHeaders(path); !exr)
        return Error{"cannot read image '" + path.string() + "': " + exr.error()};
    if (const Status dds = checkDdsHeader(path); !dds)
        return Error{"cannot read image '" + path.string() + "': " + dds.error()};
    if (const Status oiio = openWithOiio(opened); !oiio) return Error{oiio.error()};
    return opened;
}

std::optional<Status> readPngCodes(const OpenedImage& opened, PngCodes& codes,
                                   const std::function<void(int, int)>& rowsDone) {
    if (opened.source.formatName != "png" || opened.bitDepth == 0) return std::nullopt;
    const std::string name = opened.path.string();
    const auto& file = opened.pngFile;
    if (file.empty()) return std::nullopt;
    auto layout = parsePng(std::string_view(file.data(), file.size()));
    if (!layout) return Status(Error{"cannot read image '" + name + "': " + layout.error()});
    if (!layout->decodable || layout->width != opened.width || layout->height != opened.height ||
        layout->channels != opened.channels || layout->bitDepth != opened.bitDepth)
        return std::nullopt;
    codes.bitDepth = opened.bitDepth;
    codes.rowSamples = size_t(opened.width) * size_t(opened.channels);
    try {
        codes.raw.resize(layout->rowBytes() * size_t(opened.height) + kPngDecodePadding);
    } catch (const std::bad_alloc&) {
        return Status(Error{"not enough memory to read image '" + name + "'"});
    }
    const Status decoded = decodePngRows(*layout, codes.raw.data(), rowsDone);
    if (!decoded) return Status(Error{"cannot read image '" + name + "': " + decoded.error()});
    return Status{};
}

Result<Image> readOpenedImage(OpenedImage&& opened) {
    const fs::path& path = opened.path;
    Image image;
    image.width = opened.width;
    image.height = opened.height;
    image.channels = opened.channels;
    image.source = opened.source;
    try {
        image.pixels.resize(image.texelCount() * static_cast<size_t>(image.channels));
    } catch (const std::bad_alloc&) {
        return Error{"not enough memory to read image '" + path.string() + "'"};
    }
    const std::vector<float>& table = opened.table;
    if (opened.bitDepth != 0) {
        // PNGs core decodes itself: each batch of rows is converted on the other cores while later
        // rows decode (batches split further so both cores share the last ones).
        PngCodes codes;
        tbb::task_group converting;
        auto convert = [&](int y0, int y1) {
            tbb::parallel_for(y0, y1, [&](int y) {
                const size_t first = size_t(y) * codes.rowSamples;
                float* to = image.pixels.data() + first;
                for (size_t i = 0; i < codes.rowSamples; ++i)
                    to[i] = table[codes.code(first + i)];
            });
        };
        auto fast = readPngCodes(
            opened, codes, [&](int y0, int y1) { converting.run([&convert, y0, y1] { convert(y0, y1); }); });
        converting.wait();
        if (fast) {
            if (!*fast) return Error{fast->error()};
            if (opened.input) opened.input->close();
            return image;
        }
    }
    // The rest is OpenImageIO's to read.
    if (!opened.input)
        if (const Status oiio = openWithOiio(opened); !oiio) return Error{oiio.error()};
    OIIO::ImageInput& in = *opened.input;
    const OIIO::ImageSpec& spec = in.spec();
    auto readFailed = [&]() -> Error {
        const std::string why = in.geterror();
        return Error{"cannot read image '" + path.string() +
                     "': " + (why.empty() ? std::string("the file is truncated or corrupt") : damaged(why))};
    };
    if (opened.bitDepth != 0) {

        const size_t samples = image.pixels.size();
        const bool eightBit = opened.bitDepth == 8;
        std::vector<std::uint8_t, TexelAllocator<std::uint8_t>> raw8; // filled by OpenImageIO
        std::vector<std::uint16_t, TexelAllocator<std::uint16_t>> raw16;
        try {
            if (eightBit)
                raw8.resize(samples);
            else
                raw16.resize(samples);
        } catch (const std::bad_alloc&) {
            return Error{"not enough memory to read image '" + path.string() + "'"};
        }
        void* raw = eightBit ? static_cast<void*>(raw8.data()) : static_cast<void*>(raw16.data());
        if (!in.read_image(0, 0, 0, spec.nchannels, spec.format, raw)) return readFailed();
        if (auto pending = pendingReadError(in, path)) return *pending;
        constexpr size_t kBlock = size_t(1) << 16;
        tbb::parallel_for(size_t(0), (samples + kBlock - 1) / kBlock, [&](size_t block) {
            const size_t end = std::min(samples, (block + 1) * kBlock);
            for (size_t i = block * kBlock; i < end; ++i)
                image.pixels[i] = table[eightBit ? raw8[i] : raw16[i]];
        });
    } else if (!in.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
        return readFailed();
    } else if (auto pending = pendingReadError(in, path)) {
        return *pending;
    }
    in.close();
    return image;
}

Result<ImageHeader> readImageHeader(const fs::path& path) {
    auto opened = openImage(path);
    if (!opened) return Error{opened.error()};
    return ImageHeader{opened->width, opened->height, opened->channels, opened->source};
}

Result<Image> readImage(const fs::path& path) {
    auto opened = openImage(path);
    if (!opened) return Error{opened.error()};
    return readOpenedImage(std::move(opened).value());
}

Status writeImageFile(const fs::path& path, int width, int height, int channels,
                      const std::vector<float>& pixels, const ImageWriteOptions& options,
                      const fs::path& target) {
    if (width < 1 || height < 1 || channels < 1 ||
        pixels.size() != size_t(width) * size_t(height) * size_t(channels))
        return Error{"cannot write '" + target.string() + "': the pixels do not match a " +
                     std::to_string(width) + "x" + std::to_string(height) + "x" + std::to_string(channels) +
                     " image"};
    auto out = OIIO::ImageOutput::create(target.string()); // the plugin chosen by the real name
    if (!out) return Error{"cannot write '" + target.string() + "': " + OIIO::geterror()};
    const OIIO::TypeDesc type = options.type == StoredType::UInt8  ? OIIO::TypeDesc::UINT8
                                : options.type == StoredType::Half ? OIIO::TypeDesc::HALF
                                                                   : OIIO::TypeDesc::FLOAT;
    OIIO::ImageSpec spec(width, height, channels, type);
    if (!options.channelNames.empty()) spec.channelnames = options.channelNames;
    if (std::string(out->format_name()) == "openexr") spec.attribute("compression", "zip");
    // No timestamp: OpenImageIO stamps the current time unless the attribute is present and empty.
    spec.attribute("DateTime", "");
    for (const auto& [name, value] : options.attributes)
        spec.attribute(name, value);
    if (!out->open(path.string(), spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) ||
        !out->close())
        return Error{"cannot write '" + target.string() + "': " + oneLine(out->geterror())};
    return {};
}

Status writeImageAtomic(const fs::path& path, int width, int height, int channels,
                        const std::vector<float>& pixels, const ImageWriteOptions& options) {
    return writeAtomicWith(path, [&](const fs::path& staged) {
        return writeImageFile(staged, width, height, channels, pixels, options, path);
    });
}

} // namespace burnish
