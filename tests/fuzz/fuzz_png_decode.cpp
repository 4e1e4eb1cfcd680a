// libFuzzer target: core's own PNG decoder (png_decode.h) on any bytes: the chunk parser, the
// inflate and unfilter of decodable files, and the data check of files left to libpng.
#include "../../core/src/io/png_decode.h"

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view file(reinterpret_cast<const char*>(data), size);
    const auto layout = burnish::parsePng(file);
    if (!layout) return 0;
    (void)burnish::checkPngData(*layout);
    // Images up to 16 MiB of samples are decoded (larger headers are legal but only slow the fuzzer).
    if (!layout->decodable || layout->rowBytes() * std::size_t(layout->height) > (std::size_t(16) << 20))
        return 0;
    std::vector<std::uint8_t> out(layout->rowBytes() * std::size_t(layout->height) +
                                  burnish::kPngDecodePadding);
    int next = 0;
    (void)burnish::decodePngRows(*layout, out.data(), [&](int y0, int y1) {
        if (y0 != next || y1 <= y0 || y1 > layout->height) __builtin_trap(); // batches in order, in range
        next = y1;
    });
    return 0;
}
