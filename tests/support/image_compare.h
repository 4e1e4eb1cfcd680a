// Golden-image comparison with a threshold triple, the way OpenImageIO's testsuite (idiff's
// -fail/-failpercent/-hardfail) and Filament's renderdiff judge rendered images: a pixel fails when
// its largest channel difference exceeds `pixel`; the image fails when more than `allowedFraction`
// of its pixels fail, or when any pixel differs by more than `hardFail`. On failure the expected,
// actual and diff images are written as PNGs and the message names them.
#pragma once

#include <burnish/core/io/image.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/result.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace burnish::test {

/// An RGBA image of floats in [0, 1] (display values), row 0 at the top.
struct RgbaImage {
    int width = 0;
    int height = 0;
    std::vector<float> rgba;
};

struct ImageThresholds {
    float pixel = 0.0f;           // largest channel difference a pixel may have and still pass
    double allowedFraction = 0.0; // fraction of pixels allowed to exceed `pixel`
    float hardFail = 1.0f;        // any pixel over this fails the image outright
};

struct ImageComparison {
    bool passed = false;
    bool sizeMismatch = false;
    std::int64_t failingPixels = 0;
    double failingFraction = 0.0;
    float maxDifference = 0.0f;
    std::string message;
};

/// Compares two images (RGB channels; alpha ignored) under the thresholds.
inline ImageComparison compareImages(const RgbaImage& expected, const RgbaImage& actual,
                                     const ImageThresholds& thresholds) {
    ImageComparison c;
    if (expected.width != actual.width || expected.height != actual.height ||
        expected.rgba.size() != actual.rgba.size() ||
        expected.rgba.size() != size_t(expected.width) * size_t(expected.height) * 4) {
        c.sizeMismatch = true;
        c.message = "size " + std::to_string(actual.width) + "x" + std::to_string(actual.height) +
                    ", expected " + std::to_string(expected.width) + "x" + std::to_string(expected.height);
        return c;
    }
    const size_t pixels = expected.rgba.size() / 4;
    for (size_t p = 0; p < pixels; ++p) {
        float d = 0.0f;
        for (size_t k = 0; k < 3; ++k) {
            const float diff = std::abs(expected.rgba[4 * p + k] - actual.rgba[4 * p + k]);
            // A NaN in either image is the largest difference there is.
            d = std::max(d, std::isnan(diff) ? INFINITY : diff);
        }
        c.maxDifference = std::max(c.maxDifference, d);
        if (d > thresholds.pixel) ++c.failingPixels;
    }
    c.failingFraction = pixels ? double(c.failingPixels) / double(pixels) : 0.0;
    c.passed = c.failingFraction <= thresholds.allowedFraction && c.maxDifference <= thresholds.hardFail;
    std::ostringstream s;
    s << c.failingPixels << " of " << pixels << " pixels (" << 100.0 * c.failingFraction
      << "%) differ by more than " << thresholds.pixel << " (allowed " << 100.0 * thresholds.allowedFraction
      << "%); largest difference " << c.maxDifference << " (hard fail above " << thresholds.hardFail << ")";
    c.message = s.str();
    return c;
}

/// Encodes an RGBA image as an 8-bit RGBA PNG and writes it atomically.
inline Status writeRgbaPng(const std::filesystem::path& path, const RgbaImage& image) {
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput memory(bytes);
    auto out = OIIO::ImageOutput::create("png");
    if (!out) return Error{"no PNG writer: " + OIIO::geterror()};
    if (!out->set_ioproxy(&memory)) return Error{"the PNG writer cannot write to memory"};
    OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::UINT8);
    std::vector<float> clamped(image.rgba.size());
    for (size_t i = 0; i < clamped.size(); ++i)
        clamped[i] = std::isfinite(image.rgba[i]) ? std::clamp(image.rgba[i], 0.0f, 1.0f) : 1.0f;
    if (!out->open(path.filename().string(), spec) ||
        !out->write_image(OIIO::TypeDesc::FLOAT, clamped.data()) || !out->close())
        return Error{"cannot encode '" + path.string() + "': " + out->geterror()};
    return writeFileAtomic(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

/// Reads a PNG (or any image core reads) as RGBA in [0, 1]; 1-3 channel images get alpha 1.
inline Result<RgbaImage> readRgbaImage(const std::filesystem::path& path) {
    auto image = readImage(path);
    if (!image) return Error{image.error()};
    RgbaImage out{image->width, image->height, std::vector<float>(image->texelCount() * 4, 1.0f)};
    for (int y = 0; y < image->height; ++y)
        for (int x = 0; x < image->width; ++x)
            for (int c = 0; c < 4; ++c) {
                const size_t i = (size_t(y) * size_t(image->width) + size_t(x)) * 4 + size_t(c);
                if (c < image->channels)
                    out.rgba[i] = image->at(x, y, c);
                else if (c < 3)
                    out.rgba[i] = image->at(x, y, 0); // grey: replicate the one channel
            }
    return out;
}

/// |expected − actual| per pixel as grey, scaled so `hardFail` is white; pixels over the per-pixel
/// threshold are tinted red so the failing ones stand out.
inline RgbaImage diffImage(const RgbaImage& expected, const RgbaImage& actual,
                           const ImageThresholds& thresholds) {
    RgbaImage diff{expected.width, expected.height, std::vector<float>(expected.rgba.size(), 1.0f)};
    if (expected.rgba.size() != actual.rgba.size()) return diff;
    const float scale = 1.0f / std::max(thresholds.hardFail, 1e-6f); // a zero hard fail still scales finitely
    for (size_t p = 0; p < expected.rgba.size() / 4; ++p) {
        float d = 0.0f;
        for (size_t k = 0; k < 3; ++k)
            d = std::max(d, std::abs(expected.rgba[4 * p + k] - actual.rgba[4 * p + k]));
        const float grey = std::isfinite(d) ? std::min(d * scale, 1.0f) : 1.0f;
        const bool failing = !(d <= thresholds.pixel);
        diff.rgba[4 * p] = failing ? std::max(grey, 0.5f) : grey;
        diff.rgba[4 * p + 1] = failing ? grey * 0.25f : grey;
        diff.rgba[4 * p + 2] = failing ? grey * 0.25f : grey;
    }
    return diff;
}

/// Compares and, on failure, writes `<name>-expected.png`, `<name>-actual.png` and `<name>-diff.png`
/// into `diffDir` (created if missing); the message then names the three files.
inline ImageComparison compareAndReport(const std::string& name, const RgbaImage& expected,
                                        const RgbaImage& actual, const ImageThresholds& thresholds,
                                        const std::filesystem::path& diffDir) {
    ImageComparison c = compareImages(expected, actual, thresholds);
    if (c.passed) return c;
    std::error_code ec;
    std::filesystem::create_directories(diffDir, ec);
    const auto e = diffDir / (name + "-expected.png");
    const auto a = diffDir / (name + "-actual.png");
    const auto d = diffDir / (name + "-diff.png");
    std::string written;
    Status s = writeRgbaPng(e, expected);
    if (s) s = writeRgbaPng(a, actual);
    if (s && !c.sizeMismatch) s = writeRgbaPng(d, diffImage(expected, actual, thresholds));
    if (s)
        written = "; wrote " + e.string() + ", " + a.string() + (c.sizeMismatch ? "" : ", " + d.string());
    else
        written = "; could not write the images: " + s.error();
    c.message = name + ": " + c.message + written;
    return c;
}

} // namespace burnish::test
