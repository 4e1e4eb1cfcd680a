// Float images in memory and their import through OpenImageIO (PNG, TGA, JPEG, EXR, TIFF, DDS,
// HDR; 8/16-bit, half, float; 1–4 channels). Pixel values are returned exactly as stored,
// scaled to [0, 1] for integer formats: no colour-space conversion is applied, so sRGB-tagged
// data maps (normal maps) are read as the linear data they are.
#pragma once

#include <burnish/core/util/result.h>
#include <burnish/core/util/texel_vector.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace burnish {

/// What a file stored, as reported by the importer.
struct ImageSourceInfo {
    std::string path;
    std::string formatName;  // "png", "openexr", ...
    std::string channelType; // "uint8", "uint16", "half", "float", ...
    int bitsPerChannel = 0;
    bool isFloat = false;
    std::string colorSpace; // the file's tag ("sRGB", "Linear", ...) — informative only
};

/// A tightly packed float image, row-major, top row first, `channels` floats per pixel. The pixels
/// are a TexelVector: resize() leaves them uninitialised, so write every one.
struct Image {
    int width = 0;
    int height = 0;
    int channels = 0;
    TexelVector pixels;
    ImageSourceInfo source;

    size_t texelCount() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
    float at(int x, int y, int c) const {
        return pixels[(static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) *
                          static_cast<size_t>(channels) +
                      static_cast<size_t>(c)];
    }
};

/// Largest accepted image: 65536 texels on a side and 2^30 texels in all (a 32k² map), so the
/// float copy of a 4-channel image stays below 16 GiB. Larger files are refused with a clear error.
inline constexpr int kMaxImageSide = 65536;
inline constexpr std::uint64_t kMaxImageTexels = std::uint64_t(1) << 30;

/// Reads the first subimage's top mip level. Errors name the file and say what is wrong
/// (missing, unreadable, corrupt or truncated, too large, no channels).
Result<Image> readImage(const std::filesystem::path& path);

/// What an image file's header says, read without its pixels.
struct ImageHeader {
    int width = 0;
    int height = 0;
    int channels = 0;
    ImageSourceInfo source;
};

/// Opens an image and checks its header as readImage does (size limits, 1 to 4 channels, not a
/// volume; for PNG files every chunk and, for files libpng decodes, the image data), reading no
/// pixels otherwise. For checking many inputs before any work starts.
Result<ImageHeader> readImageHeader(const std::filesystem::path& path);

/// How writeImageAtomic stores the channels.
enum class StoredType { UInt8, Half, Float };

struct ImageWriteOptions {
    StoredType type = StoredType::Float;
    std::vector<std::string> channelNames;                       // empty: the format's defaults
    std::vector<std::pair<std::string, std::string>> attributes; // extra string metadata
};

/// Writes an image to exactly `path`, which OpenImageIO opens as it is (for a file inside a
/// StagingFolder: see writeImageAtomic for everything else). The format comes from `target`'s
/// name, and errors name it.
Status writeImageFile(const std::filesystem::path& path, int width, int height, int channels,
                      const std::vector<float>& pixels, const ImageWriteOptions& options,
                      const std::filesystem::path& target);

/// Writes `pixels` (width·height·channels floats, row-major, top row first) in the format the
/// path's extension names, through a temporary file renamed over the target: readers never see a
/// partial file. UInt8 values are clamped to [0, 1] and rounded by OpenImageIO. EXR files are
/// zip-compressed; no file gets a timestamp, so its bytes depend on the data only. Errors: a
/// pixel count that does not match, an unknown extension, a failed write or rename.
Status writeImageAtomic(const std::filesystem::path& path, int width, int height, int channels,
                        const std::vector<float>& pixels, const ImageWriteOptions& options = {});

} // namespace burnish
