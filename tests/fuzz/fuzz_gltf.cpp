// libFuzzer target: `burnish gltf`'s reader and writer (jobs/gltf.h's processGltf) on an asset file,
// .gltf or .glb by its bytes, whose images come in data: URIs or a GLB's binary chunk; output goes to a
// private folder, replaced each run. Inputs of odd size also write the lobe mixture (--method mixture,
// two lobes), so its pyramid, its RGBA16F chains and its textureInfos meet the same assets.
#include <burnish/core/jobs/gltf.h>

#include "fuzz_support.h"

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto input = burnish::fuzz::inputFile("gltf", data, size);
    burnish::GltfOptions options;
    options.overwrite = burnish::Overwrite::Allow;
    if (size % 2 == 1) {
        options.method = "mixture";
        options.mixtureLobes = 2;
    }
    (void)burnish::processGltf(input, input.parent_path() / "out", options);
    return 0;
}
