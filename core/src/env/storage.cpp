#include <burnish/core/env/storage.h>

#include <burnish/core/io/image.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace burnish {

namespace fs = std::filesystem;

std::string cubeExrFaceName(const CubeMap& cube, const std::string& stem, int mip, int face) {
    return cube.mipCount() == 1 ? fmt::format("{}_{}.exr", stem, cubeFaceName(face))
                                : fmt::format("{}_m{}_{}.exr", stem, mip, cubeFaceName(face));
}

std::vector<float> storedCubeFace(const CubeMap& cube, int mip, int face) {
    std::vector<float> values = cube.levels[size_t(mip)].faces[size_t(face)];
    for (float& v : values)
        v = std::isfinite(v) ? std::clamp(v, 0.0f, kHalfMax) : 0.0f; // half storage: see toHalfBits
    return values;
}

Status stageCubeExrFaces(const CubeMap& cube, const std::string& stem, FileSet& set) {
    struct Face {
        int mip, face;
    };
    std::vector<Face> faces;
    std::vector<std::string> names;
    for (int m = 0; m < cube.mipCount(); ++m)
        for (int f = 0; f < kCubeFaces; ++f) {
            faces.push_back({m, f});
            names.push_back(cubeExrFaceName(cube, stem, m, f));
        }
    // Each file's encoding (OpenEXR's zip, and a few milliseconds of set-up per file) is independent.
    return set.addParallel(names, [&](size_t i, const fs::path& staged) {
        const Face& k = faces[i];
        const int size = cube.levels[size_t(k.mip)].size;
        return writeImageFile(staged, size, size, 3, storedCubeFace(cube, k.mip, k.face),
                              {StoredType::Half, {}, {}}, set.folder() / names[i]);
    });
}

void scaleCube(CubeMap& cube, const glm::dvec3& scale) {
    for (CubeLevel& level : cube.levels)
        for (auto& face : level.faces)
            for (size_t i = 0; i < face.size(); ++i)
                face[i] = float(face[i] * scale[int(i % 3)]);
}

} // namespace burnish
