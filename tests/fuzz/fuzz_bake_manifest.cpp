// libFuzzer target: `burnish bake --manifest` reading a manifest and resolving its jobs (names,
// options, presets), without baking.
#include <burnish/core/jobs/bake_job.h>

#include "fuzz_support.h"

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = burnish::fuzz::inputFile("json", data, size);
    const auto specs = burnish::readBakeManifest(path.string(), burnish::BakeJobSpec{});
    if (!specs) return 0;
    for (const auto& spec : *specs)
        (void)burnish::resolveBakeJob(spec);
    return 0;
}
