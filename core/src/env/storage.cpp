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
    for (int m = 0; m < cube.mipCount(); ++m)
        for (int f = 0; f < kCubeFaces; ++f) {
            const std::string name = cubeExrFaceName(cube, stem, m, f);
            const int size = cube.levels[size_t(m)].size;
            const Status s = set.add(name, [&](const fs::path& staged) {
                return writeImageFile(staged, size, size, 3, storedCubeFace(cube, m, f),
                                      {StoredType::Half, {}, {}}, set.folder() / name);
            });
            if (!s) return s;
        }
    return {};
}

void scaleCube(CubeMap& cube, const glm::dvec3& scale) {
    for (CubeLevel& level : cube.levels)
        for (auto& face : level.faces)
            for (size_t i = 0; i < face.size(); ++i)
                face[i] = float(face[i] * scale[int(i % 3)]);
}

} // namespace burnish
