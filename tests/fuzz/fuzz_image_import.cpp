// libFuzzer target: image import as `burnish bake` does it, for every format Burnish documents
// (the first byte picks the extension the file gets): readImage through OpenImageIO (core's PNG
// decoder for PNGs), then the normal-map decoder and its plausibility check on what was read, and
// loadNormalMap's streaming path.
#include <burnish/core/io/image.h>
#include <burnish/core/prefilter/normal_map.h>

#include "fuzz_support.h"

#include <cmath>
#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    static const char* const kExtensions[] = {"png", "tga", "jpg", "exr", "tif", "dds", "hdr"};
    const auto path = burnish::fuzz::inputFile(kExtensions[data[0] % 7], data + 1, size - 1);
    // Headers that claim more than 4096² texels are refused early here (they are legal, but
    // allocating for them only slows the fuzzer down).
    const auto header = burnish::readImageHeader(path);
    if (!header || std::size_t(header->width) * std::size_t(header->height) > (std::size_t(1) << 24))
        return 0;
    const auto image = burnish::readImage(path);
    if (image) {
        if (image->pixels.size() != image->texelCount() * std::size_t(image->channels)) __builtin_trap();
        burnish::NormalMapOptions options;
        options.allowImplausible = true;
        if (const auto map = burnish::decodeNormalMap(*image, options))
            for (const auto& n : map->normals)
                if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z)) __builtin_trap();
    }
    (void)burnish::loadNormalMap(path);
    return 0;
}
