#include <burnish/core/image.h>

#include <burnish/core/atomic_file.h>

#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <numeric>

#include <system_error>

namespace burnish {

namespace fs = std::filesystem;

Result<Image> readImage(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) return Error{"image '" + path.string() + "' does not exist"};
    if (fs::is_directory(path, ec)) return Error{"'" + path.string() + "' is a folder, not an image"};

    // Data maps are read as stored: OpenImageIO would otherwise premultiply the colour of PNG/TGA
    // files by their alpha ("associated alpha"), scaling an RGBA normal map's vectors by the
    // height map in its alpha.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path.string(), &config);
    if (!in) {
        std::string why = OIIO::geterror();
        if (why.empty()) why = "unknown or unsupported format";
        return Error{"cannot read image '" + path.string() + "': " + why};
    }
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        return Error{"image '" + path.string() + "' has no pixels"};
    if (spec.width > kMaxImageSide || spec.height > kMaxImageSide ||
        static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height) > kMaxImageTexels)
        return Error{"image '" + path.string() + "' is " + std::to_string(spec.width) + "x" +
                     std::to_string(spec.height) +
                     ", larger than Burnish accepts (65536 on a side, 2^30 texels)"};
    if (spec.nchannels > 4)
        return Error{"image '" + path.string() + "' has " + std::to_string(spec.nchannels) +
                     " channels; Burnish reads 1 to 4"};
    if (spec.depth > 1)
        return Error{"image '" + path.string() + "' is a volume texture; Burnish reads 2D images"};

    Image image;
    image.width = spec.width;
    image.height = spec.height;
    image.channels = spec.nchannels;
    image.source.path = path.string();
    image.source.formatName = in->format_name();
    image.source.channelType = spec.format.c_str();
    image.source.bitsPerChannel = static_cast<int>(spec.format.size() * 8);
    image.source.isFloat = spec.format.is_floating_point();
    image.source.colorSpace = spec.get_string_attribute("oiio:ColorSpace");
    try {
        image.pixels.resize(image.texelCount() * static_cast<size_t>(image.channels));
    } catch (const std::bad_alloc&) {
        return Error{"not enough memory to read image '" + path.string() + "'"};
    }
    auto readFailed = [&]() -> Error {
        std::string why = in->geterror();
        if (why.empty()) why = "corrupt or truncated data";
        return Error{"cannot read image '" + path.string() + "': " + why};
    };
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
        std::vector<float> table(codes);
        const void* codeData = eightBit ? static_cast<const void*>(codes8.data()) : codes16.data();
        if (!OIIO::convert_pixel_values(spec.format, codeData, OIIO::TypeDesc::FLOAT, table.data(),
                                        int(codes)))
            return Error{"cannot read image '" + path.string() + "': no conversion from " +
                         std::string(spec.format.c_str())};
        const size_t samples = image.pixels.size();
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
        if (!in->read_image(0, 0, 0, spec.nchannels, spec.format, raw)) return readFailed();
        constexpr size_t kBlock = size_t(1) << 16;
        tbb::parallel_for(size_t(0), (samples + kBlock - 1) / kBlock, [&](size_t block) {
            const size_t end = std::min(samples, (block + 1) * kBlock);
            for (size_t i = block * kBlock; i < end; ++i)
                image.pixels[i] = table[eightBit ? raw8[i] : raw16[i]];
        });
    } else if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
        return readFailed();
    }
    in->close();
    return image;
}

Status writeImageAtomic(const fs::path& path, int width, int height, int channels,
                        const std::vector<float>& pixels, const ImageWriteOptions& options) {
    if (width < 1 || height < 1 || channels < 1 ||
        pixels.size() != size_t(width) * size_t(height) * size_t(channels))
        return Error{"cannot write '" + path.string() + "': the pixels do not match a " +
                     std::to_string(width) + "x" + std::to_string(height) + "x" + std::to_string(channels) +
                     " image"};
    auto out = OIIO::ImageOutput::create(path.string()); // the plugin chosen by the real name
    if (!out) return Error{"cannot write '" + path.string() + "': " + OIIO::geterror()};
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
    const fs::path tmp = temporaryPathFor(path);
    if (!out->open(tmp.string(), spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) ||
        !out->close()) {
        const std::string why = out->geterror();
        out.reset();
        std::error_code ec;
        fs::remove(tmp, ec);
        return Error{"cannot write '" + path.string() + "': " + why};
    }
    out.reset();
    return commitTemporary(tmp, path);
}

} // namespace burnish
