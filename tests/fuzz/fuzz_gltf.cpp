// libFuzzer target: `burnish gltf`'s reader and writer (bake/gltf.h's processGltf) on an asset file,
// .gltf or .glb by its bytes, whose images come in data: URIs or a GLB's binary chunk; output goes to a
// private folder, replaced each run.
#include <burnish/core/bake/gltf.h>

#include "fuzz_support.h"

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto input = burnish::fuzz::inputFile("gltf", data, size);
    burnish::GltfOptions options;
    options.overwrite = burnish::Overwrite::Allow;
    (void)burnish::processGltf(input, input.parent_path() / "out", options);
    return 0;
}
