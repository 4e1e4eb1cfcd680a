// libFuzzer target: an OBJ mesh as the renderer and the studio load it (tinyobjloader, then
// triangulation, normals and tangents): a loaded mesh has whole triangles indexing its vertices,
// and every vertex is finite.
#include <burnish/render/mesh.h>

#include "fuzz_support.h"

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace {

bool finite(float v) {
    return std::isfinite(v);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = burnish::fuzz::inputFile("obj", data, size);
    const auto mesh = burnish::render::loadObj(path);
    if (!mesh) return 0;
    if (mesh->indices.size() % 3 != 0) __builtin_trap();
    for (const auto i : mesh->indices)
        if (i >= mesh->vertices.size()) __builtin_trap();
    for (const auto& v : mesh->vertices)
        if (!finite(v.position.x) || !finite(v.position.y) || !finite(v.position.z) || !finite(v.normal.x) ||
            !finite(v.normal.y) || !finite(v.normal.z) || !finite(v.tangent.x) || !finite(v.uv.x) ||
            !finite(v.uv.y))
            __builtin_trap();
    return 0;
}
