#include <burnish/core/env/cube.h>

#include <burnish/core/env/storage.h>
#include <burnish/core/shading/color.h>
#include <burnish/core/util/numeric.h>

#include "env/cube_faces.h"

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace burnish {

namespace fs = std::filesystem;
using glm::dvec3;
using namespace cubeface;

const char* cubeFaceName(int face) {
    static const char* const kNames[kCubeFaces] = {"px", "nx", "py", "ny", "pz", "nz"};
    return face >= 0 && face < kCubeFaces ? kNames[face] : "?";
}

CubeMap CubeMap::zeros(int size, int mips) {
    CubeMap cube;
    mips = std::clamp(mips, 1, fullMipCount(std::max(size, 1)));
    for (int k = 0; k < mips; ++k) {
        CubeLevel level;
        level.size = std::max(1, size >> k);
        for (auto& f : level.faces)
            f.assign(size_t(level.size) * size_t(level.size) * 3, 0.0f);
        cube.levels.push_back(std::move(level));
    }
    return cube;
}

int fullMipCount(int faceSize) {
    int mips = 1;
    while (faceSize > 1) {
        faceSize >>= 1;
        ++mips;
    }
    return mips;
}

bool isPowerOfTwo(int n) {
    return n > 0 && (n & (n - 1)) == 0;
}

glm::dvec3 cubeDirection(int face, double s, double t) {
    return glm::normalize(facePoint(std::clamp(face, 0, kCubeFaces - 1), 2.0 * s - 1.0, 2.0 * t - 1.0));
}

glm::dvec3 texelDirection(int face, int size, int x, int y) {
    return cubeDirection(face, (x + 0.5) / size, (y + 0.5) / size);
}

CubeCoord cubeCoord(const glm::dvec3& d) {
    const double ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
    if (!(ax + ay + az > 0.0) || !std::isfinite(ax + ay + az)) return {};
    int face;
    double ma, sc, tc;
    // OpenGL 4.6, table 8.19: the major axis picks the face; ties go to x, then y.
    if (ax >= ay && ax >= az) {
        face = d.x >= 0 ? 0 : 1;
        ma = ax;
        sc = d.x >= 0 ? -d.z : d.z;
        tc = -d.y;
    } else if (ay >= az) {
        face = d.y >= 0 ? 2 : 3;
        ma = ay;
        sc = d.x;
        tc = d.y >= 0 ? d.z : -d.z;
    } else {
        face = d.z >= 0 ? 4 : 5;
        ma = az;
        sc = d.z >= 0 ? d.x : -d.x;
        tc = -d.y;
    }
    return {face, saturate(0.5 * (sc / ma + 1.0)), saturate(0.5 * (tc / ma + 1.0))};
}

double texelSolidAngle(int size, int x, int y) {
    const double x0 = 2.0 * x / size - 1.0, x1 = 2.0 * (x + 1) / size - 1.0;
    const double y0 = 2.0 * y / size - 1.0, y1 = 2.0 * (y + 1) / size - 1.0;
    return solidAngleFromCorners(areaElement(x0, y0), areaElement(x0, y1), areaElement(x1, y0),
                                 areaElement(x1, y1));
}

std::vector<double> texelSolidAngles(int size) {
    const size_t n = size_t(std::max(size, 0));
    // The area element at the corners, with texelSolidAngle's coordinates 2i/size − 1.
    std::vector<double> corner((n + 1) * (n + 1));
    for (size_t j = 0; j <= n; ++j)
        for (size_t i = 0; i <= n; ++i)
            corner[j * (n + 1) + i] = areaElement(2.0 * int(i) / size - 1.0, 2.0 * int(j) / size - 1.0);
    auto at = [&](size_t i, size_t j) { return corner[j * (n + 1) + i]; };
    std::vector<double> omega(n * n);
    for (size_t y = 0; y < n; ++y)
        for (size_t x = 0; x < n; ++x)
            omega[y * n + x] = solidAngleFromCorners(at(x, y), at(x, y + 1), at(x + 1, y), at(x + 1, y + 1));
    return omega;
}

glm::dvec3 sampleCube(const CubeMap& cube, const glm::dvec3& dir, int levelIndex) {
    if (cube.levels.empty()) return {};
    const CubeLevel& level = cube.levels[size_t(std::clamp(levelIndex, 0, cube.mipCount() - 1))];
    const CubeCoord c = cubeCoord(dir);
    const double x = c.s * level.size - 0.5, y = c.t * level.size - 0.5;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    const dvec3 a = fetchSeamless(level, c.face, x0, y0), b = fetchSeamless(level, c.face, x0 + 1, y0);
    const dvec3 e = fetchSeamless(level, c.face, x0, y0 + 1),
                f = fetchSeamless(level, c.face, x0 + 1, y0 + 1);
    return (a * (1 - fx) + b * fx) * (1 - fy) + (e * (1 - fx) + f * fx) * fy;
}

glm::dvec3 sampleCubeLod(const CubeMap& cube, const glm::dvec3& dir, double lod) {
    if (cube.levels.empty()) return {};
    lod = std::isfinite(lod) ? std::clamp(lod, 0.0, double(cube.mipCount() - 1)) : 0.0;
    const int l0 = int(std::floor(lod));
    const double f = lod - l0;
    const dvec3 a = sampleCube(cube, dir, l0);
    return f > 0.0 ? a * (1 - f) + sampleCube(cube, dir, l0 + 1) * f : a;
}

void buildBoxMips(CubeMap& cube) {
    if (cube.levels.empty()) return;
    cube.levels.resize(1);
    const int mips = fullMipCount(cube.faceSize());
    for (int k = 1; k < mips; ++k) {
        const CubeLevel& fine = cube.levels[size_t(k - 1)];
        CubeLevel coarse;
        coarse.size = fine.size / 2;
        const std::vector<double> fineOmega = texelSolidAngles(fine.size);
        for (int face = 0; face < kCubeFaces; ++face) {
            coarse.faces[size_t(face)].assign(size_t(coarse.size) * size_t(coarse.size) * 3, 0.0f);
            for (int y = 0; y < coarse.size; ++y)
                for (int x = 0; x < coarse.size; ++x) {
                    // Weighted by the children's solid angles, so the coarse texel is their mean radiance.
                    dvec3 sum(0.0);
                    double omega = 0.0;
                    for (int j = 0; j < 2; ++j)
                        for (int i = 0; i < 2; ++i) {
                            const double w =
                                fineOmega[size_t(2 * y + j) * size_t(fine.size) + size_t(2 * x + i)];
                            sum += w * fetch(fine, face, 2 * x + i, 2 * y + j);
                            omega += w;
                        }
                    float* out = coarse.texel(face, x, y);
                    for (int c = 0; c < 3; ++c)
                        out[c] = float(sum[c] / omega);
                }
        }
        cube.levels.push_back(std::move(coarse));
    }
}

// ---------------------------------------------------------------------------------------------
// Sources.

namespace {

/// Bilinear lookup of an equirectangular image, wrapping in u and clamping in v.
dvec3 sampleEquirect(const Image& image, const dvec3& d) {
    // u = 0.5 + atan2(x, −z)/2π puts −Z at the image centre; v = acos(y)/π puts +Y at the top row.
    const double u = 0.5 + std::atan2(d.x, -d.z) / (2.0 * kPi<double>);
    const double v = std::acos(std::clamp(d.y, -1.0, 1.0)) / kPi<double>;
    const double x = u * image.width - 0.5, y = v * image.height - 0.5;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    auto texel = [&](int xi, int yi) {
        xi = ((xi % image.width) + image.width) % image.width;
        yi = std::clamp(yi, 0, image.height - 1);
        dvec3 c;
        for (int k = 0; k < 3; ++k)
            c[k] = image.at(xi, yi, image.channels >= 3 ? k : 0);
        return c;
    };
    return (texel(x0, y0) * (1 - fx) + texel(x0 + 1, y0) * fx) * (1 - fy) +
           (texel(x0, y0 + 1) * (1 - fx) + texel(x0 + 1, y0 + 1) * fx) * fy;
}

/// A copy whose texels are all finite and non-negative (the rest become 0 and are counted).
Image sanitizedImage(const Image& image, std::uint64_t& replaced) {
    Image clean = image;
    for (float& p : clean.pixels)
        p = sanitize(p, replaced);
    return clean;
}

/// Fills level 0 of a cube by averaging `radiance` over k×k sub-texel directions per texel.
template <class F> CubeMap rasterizeCube(int faceSize, int k, const F& radiance) {
    CubeMap cube = CubeMap::zeros(faceSize, 1);
    CubeLevel& level = cube.levels[0];
    tbb::parallel_for(0, kCubeFaces * faceSize, [&](int row) {
        const int face = row / faceSize, y = row % faceSize;
        for (int x = 0; x < faceSize; ++x) {
            // Sub-samples weighted by their own solid angle share (area element at the point).
            dvec3 sum(0.0);
            double wsum = 0.0;
            for (int j = 0; j < k; ++j)
                for (int i = 0; i < k; ++i) {
                    const double sc = 2.0 * (x + (i + 0.5) / k) / faceSize - 1.0;
                    const double tc = 2.0 * (y + (j + 0.5) / k) / faceSize - 1.0;
                    const double w = std::pow(1.0 + sc * sc + tc * tc, -1.5);
                    sum += w * radiance(glm::normalize(facePoint(face, sc, tc)));
                    wsum += w;
                }
            float* out = level.texel(face, x, y);
            for (int c = 0; c < 3; ++c)
                out[c] = float(sum[c] / wsum);
        }
    });
    return cube;
}

/// A soft disc light: 1 at its centre, a smooth fall-off to 0 at angular radius `radius` (radians).
double softDisc(const dvec3& d, const dvec3& centre, double radius) {
    const double c = glm::dot(d, glm::normalize(centre));
    const double edge = std::cos(radius);
    if (c <= edge) return 0.0;
    const double x = (c - edge) / (1.0 - edge);
    return x * x * (3.0 - 2.0 * x); // smoothstep: continuous value and slope at the rim
}

} // namespace

/// The warnings a source's counts call for; values above half float's largest are counted here.
void finishSource(EnvironmentSource& out, const std::string& name) {
    for (const auto& face : out.cube.levels[0].faces)
        for (const float v : face)
            out.aboveHalfValues += v > kHalfMax ? 1 : 0;
    if (out.replacedTexels > 0)
        out.warnings.push_back(fmt::format("{}: {} NaN, infinite or negative values were replaced by 0", name,
                                           out.replacedTexels));
    if (out.aboveHalfValues > 0)
        out.warnings.push_back(
            fmt::format("{}: {} cube values exceed 65504, half float's largest; the half-float "
                        "outputs (DDS RGBA16F, EXR half) clamp them to 65504",
                        name, out.aboveHalfValues));
}

/// An 8- or 16-bit image holds display-encoded colours, not radiance: decoded from sRGB to linear
/// (every colour channel; alpha is not read), with a warning that it cannot hold a light's range.
bool decodeDisplayImage(Image& image) {
    if (image.source.isFloat) return false;
    const int colour = std::min(image.channels, 3);
    for (size_t t = 0; t < image.texelCount(); ++t)
        for (int c = 0; c < colour; ++c) {
            float& v = image.pixels[t * size_t(image.channels) + size_t(c)];
            v = float(srgbToLinear(double(std::clamp(v, 0.0f, 1.0f))));
        }
    return true;
}

std::string displayWarning(const std::string& name, const ImageSourceInfo& source) {
    return fmt::format("{}: a {}-bit image holds display colours, not radiance: read as sRGB and converted "
                       "to linear, it tops out at 1 (use EXR or HDR for lights brighter than white)",
                       name, source.bitsPerChannel);
}

Result<EnvironmentSource> equirectToCube(const Image& image, int faceSize) {
    if (const Status s = checkFaceSize(faceSize); !s) return Error{s.error()};
    if (image.width <= 0 || image.height <= 0 || image.channels <= 0 || image.pixels.empty())
        return Error{"equirectangular image is empty"};
    EnvironmentSource out;
    const Image clean = sanitizedImage(image, out.replacedTexels);
    // A face spans a quarter of the image's width; below one image texel per cube texel, supersample.
    const int k = std::max(1, int(std::ceil(double(image.width) / (4.0 * faceSize))));
    out.cube = rasterizeCube(faceSize, k, [&](const dvec3& d) { return sampleEquirect(clean, d); });
    out.sourceWidth = image.width;
    out.sourceHeight = image.height;
    out.description =
        fmt::format("equirectangular {}x{} ({}x{} samples per texel)", image.width, image.height, k, k);
    finishSource(out, image.source.path.empty() ? std::string("environment") : image.source.path);
    return out;
}

Result<EnvironmentSource> cubeFromFaces(const std::array<Image, kCubeFaces>& faces) {
    const int size = faces[0].width;
    if (const Status s = checkFaceSize(size); !s) return Error{s.error()};
    EnvironmentSource out;
    out.cube = CubeMap::zeros(size, 1);
    for (int f = 0; f < kCubeFaces; ++f) {
        const Image& img = faces[size_t(f)];
        if (img.width != size || img.height != size || img.channels <= 0 ||
            img.pixels.size() != img.texelCount() * size_t(img.channels))
            return Error{fmt::format("cube face {} is {}x{}, expected {}x{} like face px", cubeFaceName(f),
                                     img.width, img.height, size, size)};
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                float* o = out.cube.levels[0].texel(f, x, y);
                for (int c = 0; c < 3; ++c)
                    o[c] = sanitize(img.at(x, y, img.channels >= 3 ? c : 0), out.replacedTexels);
            }
    }
    out.sourceWidth = size;
    out.sourceHeight = size;
    out.description = fmt::format("six {}x{} cube faces", size, size);
    finishSource(out, "cube faces");
    return out;
}

Result<EnvironmentSource> loadEquirectEnvironment(const fs::path& path, int faceSize) {
    auto image = readImage(path);
    if (!image) return Error{image.error()};
    const bool display = decodeDisplayImage(image.value());
    if (image->width != 2 * image->height)
        return Error{fmt::format("'{}' is {}x{}: an equirectangular environment is twice as wide as high",
                                 path.string(), image->width, image->height)};
    auto cube = equirectToCube(*image, faceSize);
    if (!cube) return Error{path.string() + ": " + cube.error()};
    cube.value().description = path.filename().string() + ", " + cube->description;
    if (display) {
        cube.value().srgbDecoded = true;
        cube.value().warnings.insert(cube.value().warnings.begin(),
                                     displayWarning(path.string(), image->source));
    }
    return cube;
}

Result<EnvironmentSource> loadCubeFaceEnvironment(const std::array<fs::path, kCubeFaces>& paths) {
    std::array<Image, kCubeFaces> faces;
    std::vector<std::string> display;
    for (int f = 0; f < kCubeFaces; ++f) {
        auto image = readImage(paths[size_t(f)]);
        if (!image) return Error{image.error()};
        if (decodeDisplayImage(image.value()))
            display.push_back(displayWarning(paths[size_t(f)].string(), image->source));
        faces[size_t(f)] = std::move(image.value());
    }
    auto cube = cubeFromFaces(faces);
    if (cube && !display.empty()) {
        cube.value().srgbDecoded = true;
        cube.value().warnings.insert(cube.value().warnings.begin(), display.begin(), display.end());
    }
    return cube;
}

glm::dvec3 studioRadiance(const glm::dvec3& dirIn) {
    const dvec3 d = glm::length(dirIn) > 0.0 ? glm::normalize(dirIn) : dvec3(0, 1, 0);
    // Gradient: a dim floor (0.02) rising to a soft grey ceiling (0.6), smooth through the horizon.
    const double up = 0.5 * (d.y + 1.0);
    const dvec3 floorColor(0.02, 0.02, 0.025), ceilingColor(0.55, 0.58, 0.6);
    dvec3 L = floorColor + (ceilingColor - floorColor) * (up * up);
    // Three soft area lights: warm key (front-left, high), cool fill (right), white rim (behind, small).
    L += dvec3(18.0, 15.0, 11.0) * softDisc(d, {-0.6, 0.6, -0.5}, 0.25);
    L += dvec3(2.0, 2.6, 3.2) * softDisc(d, {0.9, 0.15, -0.2}, 0.45);
    L += dvec3(9.0, 9.0, 9.0) * softDisc(d, {0.1, 0.3, 1.0}, 0.12);
    return L;
}

Result<CubeMap> proceduralStudioEnvironment(int faceSize, int supersample) {
    if (const Status s = checkFaceSize(faceSize); !s) return Error{s.error()};
    if (supersample < 1 || supersample > 8) return Error{"the studio's supersampling must lie in 1..8"};
    return rasterizeCube(faceSize, supersample, studioRadiance);
}

Image proceduralStudioEquirect(int width, int height) {
    Image image;
    image.width = std::max(width, 1);
    image.height = std::max(height, 1);
    image.channels = 3;
    image.pixels.resize(image.texelCount() * 3);
    image.source.formatName = "procedural";
    image.source.channelType = "float";
    image.source.isFloat = true;
    tbb::parallel_for(0, image.height, [&](int y) {
        const double theta = kPi<double> * (y + 0.5) / image.height;
        for (int x = 0; x < image.width; ++x) {
            // Inverse of sampleEquirect's mapping: u = 0.5 + atan2(x, −z)/2π, v = θ/π.
            const double phi = 2.0 * kPi<double> * ((x + 0.5) / image.width - 0.5);
            const dvec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
            const dvec3 L = studioRadiance(d);
            for (int c = 0; c < 3; ++c)
                image.pixels[(size_t(y) * size_t(image.width) + size_t(x)) * 3 + size_t(c)] = float(L[c]);
        }
    });
    return image;
}

} // namespace burnish
