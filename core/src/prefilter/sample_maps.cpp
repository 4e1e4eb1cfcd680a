#include <burnish/core/prefilter/sample_maps.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace burnish {

namespace {

// A fixed integer hash (splitmix64's finalizer) instead of <random>'s distributions, whose
// output is implementation-defined: the samples must be the same on every machine.
std::uint64_t hash64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// Uniform in [0, 1) from a seed and an index.
double unitRandom(std::uint64_t seed, std::uint64_t index) {
    return static_cast<double>(hash64(seed * 0x100000001b3ull + index) >> 11) * 0x1.0p-53;
}

int wrapIndex(int i, int n) {
    const int r = i % n;
    return r < 0 ? r + n : r;
}

/// Tileable value noise with periodX × periodY lattice cells across the map, smoothstep-interpolated.
double valueNoise(double u, double v, int periodX, int periodY, std::uint64_t seed) {
    const double x = u * periodX;
    const double y = v * periodY;
    const int x0 = static_cast<int>(std::floor(x));
    const int y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0;
    const double fy = y - y0;
    const auto lattice = [&](int i, int j) {
        return unitRandom(seed, static_cast<std::uint64_t>(wrapIndex(j, periodY)) * 65536u +
                                    static_cast<std::uint64_t>(wrapIndex(i, periodX)));
    };
    const double sx = fx * fx * (3.0 - 2.0 * fx);
    const double sy = fy * fy * (3.0 - 2.0 * fy);
    const double top = lattice(x0, y0) + (lattice(x0 + 1, y0) - lattice(x0, y0)) * sx;
    const double bottom = lattice(x0, y0 + 1) + (lattice(x0 + 1, y0 + 1) - lattice(x0, y0 + 1)) * sx;
    return top + (bottom - top) * sy;
}

/// Height in texel units, row-major, top row first.
std::vector<double> hammeredHeight(int size) {
    std::vector<double> height(static_cast<size_t>(size) * static_cast<size_t>(size), 0.0);
    const double scale = size / 512.0;
    // About one dent per 180 texels² at 512²: dents overlap, so no flat metal is left between them.
    const int dents = std::max(1, static_cast<int>(size * size / 180));
    for (int d = 0; d < dents; ++d) {
        // Radii from 3 to 24 texels at 512², skewed small: a hammer's marks of several sizes.
        const double t = unitRandom(1, static_cast<std::uint64_t>(d) * 4);
        const double radius = std::max(0.75, (3.0 + 21.0 * t * t) * scale);
        const double cx = unitRandom(1, static_cast<std::uint64_t>(d) * 4 + 1) * size;
        const double cy = unitRandom(1, static_cast<std::uint64_t>(d) * 4 + 2) * size;
        // Depth proportional to the radius (similar dents at every size): slopes up to ~0.6.
        const double depth = radius * (0.15 + 0.15 * unitRandom(1, static_cast<std::uint64_t>(d) * 4 + 3));
        const int r = static_cast<int>(std::ceil(radius));
        for (int dy = -r; dy <= r; ++dy) {
            for (int dx = -r; dx <= r; ++dx) {
                const int x = static_cast<int>(std::floor(cx)) + dx;
                const int y = static_cast<int>(std::floor(cy)) + dy;
                const double ex = x + 0.5 - cx;
                const double ey = y + 0.5 - cy;
                const double q = (ex * ex + ey * ey) / (radius * radius);
                if (q >= 1.0) continue;
                // A smooth spherical-cap-like dent; overlapping dents keep the deepest.
                const double h = -depth * (1.0 - q) * (1.0 - q);
                double& cell = height[static_cast<size_t>(wrapIndex(y, size)) * static_cast<size_t>(size) +
                                      static_cast<size_t>(wrapIndex(x, size))];
                cell = std::min(cell, h);
            }
        }
    }
    return height;
}

std::vector<double> brushedHeight(int size) {
    std::vector<double> height(static_cast<size_t>(size) * static_cast<size_t>(size));
    // Grooves run along x: height varies quickly across rows, slowly along them.
    const int across = std::max(1, size / 2);
    const int along = std::max(1, size / 128);
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            const double u = (x + 0.5) / size;
            const double v = (y + 0.5) / size;
            // The slow wobble shifts grooves a little along their length so they are not ruled lines.
            const double wobble = 0.004 * valueNoise(u, v, along * 2, along * 2, 7);
            double h = 0.0;
            h += 1.0 * valueNoise(u, v + wobble, along, across, 11);
            h += 0.5 * valueNoise(u, v + wobble, along * 2, std::max(1, across / 2), 12);
            h += 0.1 * valueNoise(u, v, std::max(1, size / 16), std::max(1, size / 16), 13);
            height[static_cast<size_t>(y) * static_cast<size_t>(size) + static_cast<size_t>(x)] = h * 2.0;
        }
    }
    return height;
}

std::vector<double> bumpyHeight(int size) {
    std::vector<double> height(static_cast<size_t>(size) * static_cast<size_t>(size));
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            const double u = (x + 0.5) / size;
            const double v = (y + 0.5) / size;
            double h = 0.0;
            double amplitude = 1.0;
            int period = std::max(1, size / 32); // 32-texel bumps, then finer octaves
            for (int octave = 0; octave < 4; ++octave) {
                h += amplitude * valueNoise(u, v, period, period, 20 + static_cast<std::uint64_t>(octave));
                amplitude *= 0.5;
                period = std::min(size, period * 2);
            }
            // 8 texels of relief over a 32-texel cell: slopes around 0.4, clearly rough when minified.
            height[static_cast<size_t>(y) * static_cast<size_t>(size) + static_cast<size_t>(x)] = h * 8.0;
        }
    }
    return height;
}

} // namespace

const std::vector<SampleMapKind>& allSampleMaps() {
    static const std::vector<SampleMapKind> kinds{SampleMapKind::Hammered, SampleMapKind::Brushed,
                                                  SampleMapKind::Bumpy};
    return kinds;
}

std::string_view sampleMapName(SampleMapKind kind) {
    switch (kind) {
    case SampleMapKind::Hammered:
        return "hammered";
    case SampleMapKind::Brushed:
        return "brushed";
    case SampleMapKind::Bumpy:
        return "bumpy";
    }
    return "hammered";
}

Result<SampleMapKind> sampleMapFromName(std::string_view name) {
    std::string names;
    for (SampleMapKind kind : allSampleMaps()) {
        if (sampleMapName(kind) == name) return kind;
        names += (names.empty() ? "" : ", ") + std::string(sampleMapName(kind));
    }
    return Error{"unknown sample map '" + std::string(name) + "' (known: " + names + ")"};
}

NormalMap makeSampleNormalMap(SampleMapKind kind, int size) {
    size = std::max(1, size);
    std::vector<double> height;
    switch (kind) {
    case SampleMapKind::Hammered:
        height = hammeredHeight(size);
        break;
    case SampleMapKind::Brushed:
        height = brushedHeight(size);
        break;
    case SampleMapKind::Bumpy:
        height = bumpyHeight(size);
        break;
    }
    const auto h = [&](int x, int y) {
        return height[static_cast<size_t>(wrapIndex(y, size)) * static_cast<size_t>(size) +
                      static_cast<size_t>(wrapIndex(x, size))];
    };
    std::vector<glm::vec3> normals(height.size());
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            // Central differences with wrap (the map tiles). Rows go down the image while tangent
            // space's +y goes up (OpenGL green), hence the sign of dhdy.
            const double dhdx = 0.5 * (h(x + 1, y) - h(x - 1, y));
            const double dhdy = -0.5 * (h(x, y + 1) - h(x, y - 1));
            const glm::dvec3 n = glm::normalize(glm::dvec3(-dhdx, -dhdy, 1.0));
            normals[static_cast<size_t>(y) * static_cast<size_t>(size) + static_cast<size_t>(x)] =
                glm::vec3(n);
        }
    }
    NormalMap map = makeNormalMap(size, size, std::move(normals));
    map.source.path = "builtin:" + std::string(sampleMapName(kind));
    return map;
}

} // namespace burnish
