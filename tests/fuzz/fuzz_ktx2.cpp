// libFuzzer target: the KTX2 reader (io/ktx2.h's decodeKtx2); whatever it accepts must encode back to a
// file it reads as the same texture.
#include <burnish/core/io/ktx2.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto texture = burnish::decodeKtx2(std::string_view(reinterpret_cast<const char*>(data), size));
    if (!texture) return 0;
    const auto bytes = burnish::encodeKtx2(*texture);
    if (!bytes) std::abort();
    const auto again = burnish::decodeKtx2(*bytes);
    if (!again || again->levels != texture->levels || again->keyValues != texture->keyValues ||
        again->format != texture->format || again->width != texture->width ||
        again->height != texture->height)
        std::abort();
    return 0;
}
