// libFuzzer target: an engine preset file (presets.h's parsePreset), and a method-table check of
// what it describes.
#include <burnish/core/bake/presets.h>

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view json(reinterpret_cast<const char*>(data), size);
    const auto preset = burnish::parsePreset(json, "fuzz.json");
    if (preset) (void)burnish::checkPresetMethod(*preset, preset->method);
    return 0;
}
