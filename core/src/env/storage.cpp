#include <burnish/core/env/storage.h>

#include <burnish/core/io/image.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace burnish {

namespace fs = std::filesystem;

Result<std::vector<std::string>> writeCubeExrFaces(const CubeMap& cube, const fs::path& dir,
                                                   const std::string& stem) {
    std::vector<std::string> names;
    for (int m = 0; m < cube.mipCount(); ++m) {
        const CubeLevel& level = cube.levels[size_t(m)];
        for (int f = 0; f < kCubeFaces; ++f) {
            const std::string name = cube.mipCount() == 1
                                         ? fmt::format("{}_{}.exr", stem, cubeFaceName(f))
                                         : fmt::format("{}_m{}_{}.exr", stem, m, cubeFaceName(f));
            const fs::path path = dir / name;
            std::vector<float> values = level.faces[size_t(f)];
            for (float& v : values)
                v = std::isfinite(v) ? std::clamp(v, 0.0f, kHalfMax) : 0.0f; // half storage: see toHalfBits
            if (const Status s =
                    writeImageAtomic(path, level.size, level.size, 3, values, {StoredType::Half, {}, {}});
                !s)
                return Error{s.error()};
            names.push_back(name);
        }
    }
    return names;
}

void scaleCube(CubeMap& cube, const glm::dvec3& scale) {
    for (CubeLevel& level : cube.levels)
        for (auto& face : level.faces)
            for (size_t i = 0; i < face.size(); ++i)
                face[i] = float(face[i] * scale[int(i % 3)]);
}

} // namespace burnish
