// Small synthetic normal maps written as 8-bit unsigned RGB files (through OpenImageIO), for the
// command-line tests: a map of sines and a writer for any per-texel normal.
#pragma once

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <vector>

namespace burnish::test {

/// Writes normalAt(x, y) (normalized here) as 8-bit RGB, n·0.5 + 0.5 rounded to the nearest code.
inline void writeNormals8(const std::filesystem::path& path, int width, int height,
                          const std::function<void(int x, int y, float n[3])>& normalAt) {
    std::vector<unsigned char> pixels(size_t(width) * size_t(height) * 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float n[3] = {0.0f, 0.0f, 1.0f};
            normalAt(x, y, n);
            const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (int c = 0; c < 3; ++c)
                pixels[(size_t(y) * size_t(width) + size_t(x)) * 3 + size_t(c)] =
                    static_cast<unsigned char>(std::lround((0.5f * n[c] / len + 0.5f) * 255.0f));
        }
    auto out = OIIO::ImageOutput::create(path.string());
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path.string(), OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
    ASSERT_TRUE(out->close());
}

/// A size×size map of sines (slopes up to 0.4 in x, 0.3 in y, +Y green); `phase` shifts the x
/// sine, giving a different map of the same size.
inline void writeSineNormalMap(const std::filesystem::path& path, int size, float phase = 0.0f) {
    writeNormals8(path, size, size, [&](int x, int y, float n[3]) {
        n[0] = 0.4f * std::sin(6.2831853f * 3.0f * float(x) / float(size) + phase);
        n[1] = 0.3f * std::cos(6.2831853f * 2.0f * float(y) / float(size));
        n[2] = 1.0f;
    });
}

} // namespace burnish::test
