#include <burnish/core/environment.h>

#include <burnish/core/image.h>

#include <burnish/core/atomic_file.h>
#include <burnish/core/numeric.h>

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

namespace burnish {

namespace fs = std::filesystem;
using glm::dvec3;

namespace {

/// The face's frame: direction = axis + sc·u + tc·v for sc, tc ∈ [−1, 1].
// OpenGL 4.6, table 8.19 (cube map face selection), inverted
struct FaceFrame {
    dvec3 axis, u, v;
};
constexpr std::array<FaceFrame, kCubeFaces> kFrames{{
    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},  // +X: sc = −z, tc = −y
    {{-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},  // −X: sc = +z, tc = −y
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},    // +Y: sc = +x, tc = +z
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},  // −Y: sc = +x, tc = −z
    {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}},   // +Z: sc = +x, tc = −y
    {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}}, // −Z: sc = −x, tc = −y
}};

dvec3 facePoint(int face, double sc, double tc) {
    const FaceFrame& f = kFrames[size_t(face)];
    return f.axis + sc * f.u + tc * f.v;
}

double clampUnit(double x) {
    return std::clamp(x, 0.0, 1.0);
}

/// Finite and non-negative, or 0.
float sanitize(float x, std::uint64_t& replaced) {
    if (std::isfinite(x) && x >= 0.0f) return x;
    ++replaced;
    return 0.0f;
}

// Integral of the face's area element from the face centre to (x, y).
// Driscoll 2012 / cmft: ∫∫ (1 + x² + y²)^(−3/2) dx dy = atan2(xy, sqrt(x² + y² + 1))
double areaElement(double x, double y) {
    return std::atan2(x * y, std::sqrt(x * x + y * y + 1.0));
}

glm::dvec3 fetch(const CubeLevel& level, int face, int x, int y) {
    const float* p = level.texel(face, x, y);
    return {p[0], p[1], p[2]};
}

/// Texel (x, y) of `face`, where x or y may lie one texel beyond the face: read from the face the
/// texel centre's direction falls on.
glm::dvec3 fetchSeamless(const CubeLevel& level, int face, int x, int y) {
    const int n = level.size;
    if (x >= 0 && y >= 0 && x < n && y < n) return fetch(level, face, x, y);
    const double sc = 2.0 * (x + 0.5) / n - 1.0;
    const double tc = 2.0 * (y + 0.5) / n - 1.0;
    const CubeCoord c = cubeCoord(facePoint(face, sc, tc));
    const int xi = std::clamp(int(c.s * n), 0, n - 1);
    const int yi = std::clamp(int(c.t * n), 0, n - 1);
    return fetch(level, c.face, xi, yi);
}

Status checkFaceSize(int faceSize) {
    // 65536 texels per side would already be 100 GiB of float faces; 16384 keeps a chain below 8 GiB.
    constexpr int kMaxFaceSize = 16384;
    if (!isPowerOfTwo(faceSize) || faceSize > kMaxFaceSize)
        return Error{
            fmt::format("cube face size {} must be a power of two in [1, {}]", faceSize, kMaxFaceSize)};
    return {};
}

} // namespace

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
    return {face, clampUnit(0.5 * (sc / ma + 1.0)), clampUnit(0.5 * (tc / ma + 1.0))};
}

double texelSolidAngle(int size, int x, int y) {
    const double x0 = 2.0 * x / size - 1.0, x1 = 2.0 * (x + 1) / size - 1.0;
    const double y0 = 2.0 * y / size - 1.0, y1 = 2.0 * (y + 1) / size - 1.0;
    return areaElement(x0, y0) - areaElement(x0, y1) - areaElement(x1, y0) + areaElement(x1, y1);
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
        for (int face = 0; face < kCubeFaces; ++face) {
            coarse.faces[size_t(face)].assign(size_t(coarse.size) * size_t(coarse.size) * 3, 0.0f);
            for (int y = 0; y < coarse.size; ++y)
                for (int x = 0; x < coarse.size; ++x) {
                    // Weighted by the children's solid angles, so the coarse texel is their mean radiance.
                    dvec3 sum(0.0);
                    double omega = 0.0;
                    for (int j = 0; j < 2; ++j)
                        for (int i = 0; i < 2; ++i) {
                            const double w = texelSolidAngle(fine.size, 2 * x + i, 2 * y + j);
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
    return out;
}

Result<EnvironmentSource> loadEquirectEnvironment(const fs::path& path, int faceSize) {
    auto image = readImage(path);
    if (!image) return Error{image.error()};
    if (image->width != 2 * image->height)
        return Error{fmt::format("'{}' is {}x{}: an equirectangular environment is twice as wide as high",
                                 path.string(), image->width, image->height)};
    auto cube = equirectToCube(*image, faceSize);
    if (!cube) return Error{path.string() + ": " + cube.error()};
    cube.value().description = path.filename().string() + ", " + cube->description;
    return cube;
}

Result<EnvironmentSource> loadCubeFaceEnvironment(const std::array<fs::path, kCubeFaces>& paths) {
    std::array<Image, kCubeFaces> faces;
    for (int f = 0; f < kCubeFaces; ++f) {
        auto image = readImage(paths[size_t(f)]);
        if (!image) return Error{image.error()};
        faces[size_t(f)] = std::move(image.value());
    }
    return cubeFromFaces(faces);
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

Result<CubeMap> proceduralStudioEnvironment(int faceSize) {
    if (const Status s = checkFaceSize(faceSize); !s) return Error{s.error()};
    // 4×4 sub-samples per texel: the lights' rims are smooth, so this resolves them at any size.
    constexpr int kSupersample = 4;
    return rasterizeCube(faceSize, kSupersample, studioRadiance);
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

// ---------------------------------------------------------------------------------------------
// Prefiltered radiance.

const char* lobeModelName(LobeModel lobe) {
    return lobe == LobeModel::Phong ? "phong" : "blinn-phong";
}

std::vector<double> prefilterPowers(const PrefilterOptions& o, int mips) {
    std::vector<double> powers;
    for (int m = 0; m < mips; ++m) {
        double n;
        if (o.encoding) {
            const double t = mips > 1 ? double(m) / double(mips - 1) : 0.0;
            const double g = 1.0 - t;
            n = o.encoding->power(o.encoding->increasesWithPower() ? g : 1.0 - g);
        } else {
            n = o.topPower * std::pow(o.powerDrop, double(m));
        }
        powers.push_back(clampPower(n));
    }
    return powers;
}

double mipForGloss(double g, int mips) {
    return (1.0 - saturate(g)) * double(std::max(mips, 1) - 1);
}

double lobeWeight(LobeModel lobe, double power, double c) {
    if (lobe == LobeModel::Phong) return powCos(c, power);
    // cos^n(θ/2) = ((1 + cosθ)/2)^(n/2); the half-angle cosine is 0 only at c = −1.
    return powCos(0.5 * (1.0 + std::clamp(c, -1.0, 1.0)), 0.5 * clampPower(power));
}

namespace {

/// 1 − cos of the angle beyond which the lobe's weight is below `cutoff` (2: the whole sphere). Computed
/// with expm1 so that it keeps its digits for the highest powers (1e9: 1.2e-8).
double lobeCutOneMinusCosine(LobeModel lobe, double power, double cutoff) {
    power = clampPower(power);
    if (power <= 0.0) return 2.0;
    // cos^n θ = cutoff
    if (lobe == LobeModel::Phong) return -std::expm1(std::log(cutoff) / power);
    // ((1 + c)/2)^(n/2) = cutoff: 1 − c = 2(1 − cutoff^(2/n))
    return std::min(2.0, -2.0 * std::expm1(2.0 * std::log(cutoff) / power));
}

/// The lobe's angular standard deviation (radians): cos^n θ ≈ exp(−nθ²/2) for Phong, and the Blinn
/// lobe cos^n(θ/2) ≈ exp(−nθ²/8) is twice as wide.
double lobeSigma(LobeModel lobe, double power) {
    const double sigma = 1.0 / std::sqrt(std::max(clampPower(power), 1e-6));
    return lobe == LobeModel::Phong ? sigma : 2.0 * sigma;
}

/// Four floats in one SSE/NEON register (GCC and Clang vector extensions): the inner loop's lanes.
using Float4 = float __attribute__((vector_size(16)));
using Int4 = int __attribute__((vector_size(16)));

Float4 load4(const float* p) {
    Float4 v;
    std::memcpy(&v, p, sizeof v); // unaligned: runs start at any texel
    return v;
}

float horizontalSum(Float4 v) {
    return (v[0] + v[1]) + (v[2] + v[3]);
}

/// One face of a source level laid out for the inner loop, one plane per quantity (rows as in the cube
/// layout): unit direction of the texel centre, solid angle (sr), radiance.
struct SourceFace {
    std::vector<float> x, y, z, omega, r, g, b;
};

struct SourceLevel {
    int size = 0;
    std::array<SourceFace, kCubeFaces> faces;
};

SourceLevel flatten(const CubeLevel& level) {
    SourceLevel flat;
    const int n = level.size;
    flat.size = n;
    // A texel's solid angle depends on (x, y) only, not on the face: the area element at the (n + 1)²
    // corners once, then texelSolidAngle's four-corner difference (the same expression, the same bits).
    std::vector<double> corner(size_t(n + 1) * size_t(n + 1));
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            corner[size_t(j) * size_t(n + 1) + size_t(i)] = areaElement(2.0 * i / n - 1.0, 2.0 * j / n - 1.0);
    auto at = [&](int i, int j) { return corner[size_t(j) * size_t(n + 1) + size_t(i)]; };
    tbb::parallel_for(0, kCubeFaces, [&](int f) {
        SourceFace& out = flat.faces[size_t(f)];
        const size_t count = size_t(n) * size_t(n);
        for (auto* plane : {&out.x, &out.y, &out.z, &out.omega, &out.r, &out.g, &out.b})
            plane->resize(count);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const size_t i = size_t(y) * size_t(n) + size_t(x);
                const dvec3 d = texelDirection(f, n, x, y);
                const float* L = level.texel(f, x, y);
                out.x[i] = float(d.x);
                out.y[i] = float(d.y);
                out.z[i] = float(d.z);
                out.omega[i] = float(at(x, y) - at(x, y + 1) - at(x + 1, y) + at(x + 1, y + 1));
                out.r[i] = L[0];
                out.g[i] = L[1];
                out.b[i] = L[2];
            }
    });
    return flat;
}

/// The lobe as a function of u = 1 − R·L on [0, uCut], and 0 from uCut on. Sampled at kEntries + 1
/// points for linear interpolation: with the lobe cut at a fraction ε of its peak it falls by about
/// ln(1/ε) e-folds over the table (11.5 at ε = 1e-5), so interpolation errs by (ln(1/ε)/kEntries)²/8
/// ≈ 1e-6 of the weight, below the float rounding of the sums. Exponents below 2 (Phong n, Blinn n/2)
/// have an unbounded second derivative where the lobe reaches 0 (c = 0, or c = −1 for Blinn); those
/// wide lobes are evaluated exactly instead.
class LobeTable {
public:
    static constexpr int kEntries = 4096;

    LobeTable(LobeModel lobe, double power, double uCut)
        : m_lobe(lobe)
        , m_power(float(clampPower(power))) {
        // 2 is the whole sphere (u = 1 − cos); a zero-width cut would divide by 0 below.
        uCut = std::clamp(uCut, std::numeric_limits<double>::min(), 2.0);
        m_uCut = float(uCut);
        m_scale = float(kEntries / uCut);
        const double exponent = lobe == LobeModel::Phong ? clampPower(power) : 0.5 * clampPower(power);
        // Below 2 the lerp error near the lobe's zero grows without bound (x^p with p < 2 at x → 0).
        constexpr double kMinTableExponent = 2.0;
        m_exact = exponent > 0.0 && exponent < kMinTableExponent;
        std::array<double, kEntries + 1> w;
        for (int k = 0; k <= kEntries; ++k)
            w[size_t(k)] = weight(lobe, clampPower(power), uCut * k / kEntries);
        for (int k = 0; k < kEntries; ++k) {
            m_value[size_t(k)] = float(w[size_t(k)]);
            m_slope[size_t(k)] = float(w[size_t(k + 1)] - w[size_t(k)]);
        }
        // Past the cut: weight 0 (u·scale is clamped to kEntries before indexing).
        m_value[kEntries] = 0.0f;
        m_slope[kEntries] = 0.0f;
    }

    /// The weights at four u ≥ 0 (finite).
    Float4 operator()(Float4 u) const {
        if (m_exact) return Float4{(*this)(u[0]), (*this)(u[1]), (*this)(u[2]), (*this)(u[3])};
        Float4 x = u * m_scale;
        x = x < float(kEntries) ? x : float(kEntries);
        const Int4 i = __builtin_convertvector(x, Int4);
        const Float4 f = x - __builtin_convertvector(i, Float4);
        const Float4 value{m_value[size_t(i[0])], m_value[size_t(i[1])], m_value[size_t(i[2])],
                           m_value[size_t(i[3])]};
        const Float4 slope{m_slope[size_t(i[0])], m_slope[size_t(i[1])], m_slope[size_t(i[2])],
                           m_slope[size_t(i[3])]};
        return value + f * slope;
    }

    /// The weight at u ≥ 0 (finite).
    float operator()(float u) const {
        if (m_exact) {
            if (!(u < m_uCut)) return 0.0f;
            // n > 0 here: log1p(−1) = −inf gives exp(−inf) = 0 at the lobe's zero.
            return m_lobe == LobeModel::Phong ? std::exp(m_power * std::log1p(-u))
                                              : std::exp(0.5f * m_power * std::log1p(-0.5f * u));
        }
        const float x = std::min(u * m_scale, float(kEntries));
        const int i = int(x);
        return m_value[size_t(i)] + (x - float(i)) * m_slope[size_t(i)];
    }

private:
    /// lobeWeight in terms of u = 1 − c, with log1p so that u near 0 keeps its digits.
    static double weight(LobeModel lobe, double n, double u) {
        if (n == 0.0) return 1.0; // powCos(c, 0) = 1 everywhere, as lobeWeight
        if (lobe == LobeModel::Phong) return u < 1.0 ? std::exp(n * std::log1p(-u)) : 0.0;
        // ((1 + c)/2)^(n/2) = (1 − u/2)^(n/2)
        return u < 2.0 ? std::exp(0.5 * n * std::log1p(-0.5 * u)) : 0.0;
    }

    LobeModel m_lobe;
    float m_power = 0.0f;
    float m_uCut = 0.0f;
    bool m_exact = false;
    float m_scale = 0.0f;
    std::array<float, kEntries + 1> m_value{}, m_slope{};
};

/// The part [lo, hi] of [−1, 1] on the line base + t·along (base ⊥ along, |along| = 1) inside the cone
/// {d : R·d ≥ cosCut·|d|}, cosCut > 0. That cone is convex, so the part is one interval; its ends are
/// roots of a quadratic or ±1, and a midpoint test tells the cone from its mirror image.
bool lineInterval(const dvec3& R, double cosCut, const dvec3& base, const dvec3& along, double& lo,
                  double& hi) {
    // R·p = A + B t, |p|² = b2 + t²: (A + B t)² − c²(b2 + t²) = qa t² + 2 hb t + qc ≥ 0 with A + B t ≥ 0.
    const double A = glm::dot(R, base), B = glm::dot(R, along), b2 = glm::dot(base, base);
    const double c2 = cosCut * cosCut;
    const double qa = B * B - c2, hb = A * B, qc = A * A - c2 * b2;
    std::array<double, 4> breaks{-1.0, 1.0, 0.0, 0.0};
    int count = 2;
    const double disc = hb * hb - qa * qc;
    if (disc >= 0.0) {
        // Numerical Recipes' stable roots: q/qa and qc/q, no cancellation when qa or qc is tiny.
        const double q = -(hb + std::copysign(std::sqrt(disc), hb));
        for (const double r : {qa != 0.0 ? q / qa : 2.0, q != 0.0 ? qc / q : 2.0})
            if (r > -1.0 && r < 1.0) breaks[size_t(count++)] = r;
    }
    // At most four breaks: an insertion sort.
    for (int i = 1; i < count; ++i)
        for (int j = i; j > 0 && breaks[size_t(j)] < breaks[size_t(j - 1)]; --j)
            std::swap(breaks[size_t(j)], breaks[size_t(j - 1)]);
    bool any = false;
    for (int i = 0; i + 1 < count; ++i) {
        const double t = 0.5 * (breaks[size_t(i)] + breaks[size_t(i + 1)]);
        const double rp = A + B * t;
        if (rp >= 0.0 && rp * rp >= c2 * (b2 + t * t)) {
            if (!any) lo = breaks[size_t(i)];
            hi = breaks[size_t(i + 1)];
            any = true;
        }
    }
    return any;
}

/// The cone a mip's lobe is cut to, {d : R·d ≥ cosCut·|d|}, with what every texel's test shares.
struct CutCone {
    double cosCut = -1.0;
    double c2 = 1.0;
    /// The cone meets a face only if R·axis ≥ cosReach.
    double cosReach = -1.0;

    explicit CutCone(double cosCutIn)
        : cosCut(cosCutIn)
        , c2(cosCutIn * cosCutIn) {
        // Every direction of a face lies within acos(1/√3) (centre to corner) of its axis, so the cone
        // meets the face only if R lies within θc + acos(1/√3) of the axis (1e-9: rounding of the acos).
        const double faceRadius = std::acos(1.0 / std::sqrt(3.0));
        const double thetaCut = std::acos(std::clamp(cosCut, -1.0, 1.0));
        cosReach = std::cos(std::min(kPi<double>, thetaCut + faceRadius + 1e-9));
    }
};

/// Calls visit(face, y, x0, x1) for the runs of texels of a `size`² level whose centres lie within the
/// cone about R (to rounding: a centre on the cone's surface may fall either side). For cosCut ≤ 0
/// the cone is not convex and every row of every face is one run.
template <class Visit>
void forEachConeRun(const dvec3& R, const CutCone& cone, int size, const Visit& visit) {
    if (!(cone.cosCut > 0.0)) {
        for (int f = 0; f < kCubeFaces; ++f)
            for (int y = 0; y < size; ++y)
                visit(f, y, 0, size - 1);
        return;
    }
    const double c2 = cone.c2;
    // Texel index of a face coordinate: centres at (x + 0.5)/size·2 − 1.
    auto toTexel = [&](double c) { return 0.5 * (c + 1.0) * size - 0.5; };
    for (int f = 0; f < kCubeFaces; ++f) {
        const FaceFrame& fr = kFrames[size_t(f)];
        const double Ra = glm::dot(R, fr.axis), Ru = glm::dot(R, fr.u), Rv = glm::dot(R, fr.v);
        if (Ra < cone.cosReach) continue;
        // Rows tc whose line axis + tc·v + sc·u meets the double cone: the quadratic in sc below has real
        // roots when (Ra + tc·Rv)² ≥ (c² − Ru²)(1 + tc²); for c² ≤ Ru² every row's line does.
        double tLo = -1.0, tHi = 1.0;
        const double kk = c2 - Ru * Ru;
        if (kk > 0.0) {
            const double alpha = Rv * Rv - kk, beta = Ra * Rv, gamma = Ra * Ra - kk;
            const double disc = beta * beta - alpha * gamma;
            // Below 1e-12 the quadratic is linear to rounding: keep every row rather than divide.
            if (alpha < -1e-12) {
                if (disc < 0.0) continue; // no row meets the cone
                const double s = std::sqrt(disc);
                const double r0 = (-beta + s) / alpha, r1 = (-beta - s) / alpha;
                tLo = std::max(-1.0, std::min(r0, r1));
                tHi = std::min(1.0, std::max(r0, r1));
            } else if (alpha > 1e-12 && disc >= 0.0) {
                // Outside the roots: [−1, r0] ∪ [r1, 1], of which the hull.
                const double s = std::sqrt(disc);
                const double r0 = std::min((-beta + s) / alpha, (-beta - s) / alpha);
                const double r1 = std::max((-beta + s) / alpha, (-beta - s) / alpha);
                const bool low = r0 >= -1.0, high = r1 <= 1.0;
                if (!low && !high) continue;
                tLo = low ? -1.0 : r1;
                tHi = high ? 1.0 : r0;
            }
            if (tLo > tHi) continue;
        }
        const int y0 = std::max(0, int(std::ceil(toTexel(tLo))));
        const int y1 = std::min(size - 1, int(std::floor(toTexel(tHi))));
        // Along a row p(sc) = axis + tc·v + sc·u: R·p = A + Ru·sc, |p|² = 1 + tc² + sc², and the cone is
        // (A + Ru·sc)² − c²|p|² = qa·sc² + 2hb·sc + qc ≥ 0 on the side A + Ru·sc ≥ 0.
        const double qa = Ru * Ru - c2;
        for (int y = y0; y <= y1; ++y) {
            const double tc = 2.0 * (y + 0.5) / size - 1.0;
            const double A = Ra + tc * Rv;
            const double hb = A * Ru, qc = A * A - c2 * (1.0 + tc * tc);
            const double disc = hb * hb - qa * qc;
            double lo, hi;
            if (qa == 0.0 || disc < 0.0) {
                // A row along the cone's surface (a linear inequality) or grazing it: the general form.
                if (!lineInterval(R, cone.cosCut, fr.axis + tc * fr.v, fr.u, lo, hi)) continue;
            } else {
                // Numerical Recipes' stable roots q/qa and qc/q: no cancellation when qa or qc is small.
                const double q = -(hb + std::copysign(std::sqrt(disc), hb));
                const double rA = q / qa, rB = q != 0.0 ? qc / q : 0.0;
                const double r0 = std::min(rA, rB), r1 = std::max(rA, rB);
                if (qa < 0.0) {
                    // Inside between the roots: one segment, in R's nappe or in the mirror one.
                    if (A + Ru * 0.5 * (r0 + r1) < 0.0) continue;
                    lo = r0;
                    hi = r1;
                } else {
                    // u lies inside the double cone: the ray towards the sign of Ru is in R's nappe.
                    lo = Ru > 0.0 ? r1 : -2.0;
                    hi = Ru > 0.0 ? 2.0 : r0;
                }
            }
            const int x0 = std::max(0, int(std::ceil(toTexel(std::max(lo, -1.0)))));
            const int x1 = std::min(size - 1, int(std::floor(toTexel(std::min(hi, 1.0)))));
            if (x0 <= x1) visit(f, y, x0, x1);
        }
    }
}

} // namespace

Result<PrefilteredEnvironment> prefilterRadiance(const CubeMap& source, const PrefilterOptions& o) {
    if (source.levels.empty()) return Error{"the environment cube is empty"};
    const int size = source.faceSize();
    if (const Status s = checkFaceSize(size); !s) return Error{s.error()};
    const int full = fullMipCount(size);
    const int mips = o.mips == 0 ? full : o.mips;
    if (mips < 1 || mips > full)
        return Error{fmt::format("{} mips asked for a {}² cube, which has 1 to {}", o.mips, size, full)};
    if (!(o.topPower >= 0.0) || !(o.powerDrop > 0.0) || !std::isfinite(o.topPower) ||
        !std::isfinite(o.powerDrop))
        return Error{
            fmt::format("top power {:g} and power drop {:g} must be >= 0 and > 0", o.topPower, o.powerDrop)};
    if (!(o.lobeCutoff > 0.0 && o.lobeCutoff < 1.0))
        return Error{fmt::format("lobe cutoff {:g} must lie in (0, 1)", o.lobeCutoff)};
    if (!(o.texelsPerSigma > 0.0 && o.texelsPerSigma <= 64.0))
        return Error{fmt::format("texels per sigma {:g} must lie in (0, 64]", o.texelsPerSigma)};

    CubeMap chain;
    chain.levels.push_back(source.levels[0]);
    buildBoxMips(chain);
    std::vector<std::optional<SourceLevel>> flat(chain.levels.size());

    PrefilteredEnvironment out;
    out.lobe = o.lobe;
    out.powers = prefilterPowers(o, mips);
    out.radiance = CubeMap::zeros(size, mips);
    for (int m = 0; m < mips; ++m) {
        const auto start = std::chrono::steady_clock::now();
        const double n = out.powers[size_t(m)];
        // The coarsest source level whose texels (2/size radians across at a face centre) are still
        // texelsPerSigma to the lobe's standard deviation.
        const double sigma = lobeSigma(o.lobe, n);
        int sourceLevel = 0;
        // The Gaussian width estimate fails for powers near 0 (the lobe covers the sphere): never read
        // a level coarser than 64² faces. Measured on the courtyard probe at 256² against brute
        // force (`burnish env --report`): reading 16² faces left mips 3-8 0.14-0.5% off, 64² faces
        // 0.7e-4 to 5e-4, for about 70 ms more over the whole chain. (Mip 6, power 0.5, stays at
        // about 1.5% either way: a separate error of powers below 1, not of the source resolution.)
        constexpr int kMinSourceSize = 64;
        while (sourceLevel + 1 < chain.mipCount() &&
               chain.levels[size_t(sourceLevel + 1)].size >= kMinSourceSize &&
               2.0 / chain.levels[size_t(sourceLevel + 1)].size <= sigma / o.texelsPerSigma)
            ++sourceLevel;
        out.sourceLevels.push_back(sourceLevel);
        if (!flat[size_t(sourceLevel)])
            flat[size_t(sourceLevel)] = flatten(chain.levels[size_t(sourceLevel)]);
        const SourceLevel& src = *flat[size_t(sourceLevel)];
        // The cut leaves out the lobe's tail below lobeCutoff of its peak: for a near-Gaussian lobe that
        // is the same fraction of its energy (1e-5 by default), and the sums are renormalized by Σ w Ω.
        const double uCut = lobeCutOneMinusCosine(o.lobe, n, o.lobeCutoff);
        const CutCone cone(1.0 - uCut);
        const LobeTable lobe(o.lobe, n, uCut);
        CubeLevel& dst = out.radiance.levels[size_t(m)];

        tbb::parallel_for(0, kCubeFaces * dst.size, [&](int row) {
            const int face = row / dst.size, y = row % dst.size;
            for (int x = 0; x < dst.size; ++x) {
                const dvec3 R = texelDirection(face, dst.size, x, y);
                const float rx = float(R.x), ry = float(R.y), rz = float(R.z);
                double sum[3] = {0, 0, 0}, wsum = 0.0;
                forEachConeRun(R, cone, src.size, [&](int f, int ty, int x0, int x1) {
                    const SourceFace& sf = src.faces[size_t(f)];
                    const size_t rowStart = size_t(ty) * size_t(src.size);
                    const float *px = sf.x.data() + rowStart, *py = sf.y.data() + rowStart,
                                *pz = sf.z.data() + rowStart, *pw = sf.omega.data() + rowStart,
                                *pr = sf.r.data() + rowStart, *pg = sf.g.data() + rowStart,
                                *pb = sf.b.data() + rowStart;
                    // 1 − R·L = |R − L|²/2 for unit vectors: no cancellation near the peak, where 1 − c in
                    // float would keep only a few digits at high powers.
                    auto weight = [&](int tx) {
                        const float dx = px[tx] - rx, dy = py[tx] - ry, dz = pz[tx] - rz;
                        return lobe(0.5f * (dx * dx + dy * dy + dz * dz)) * pw[tx];
                    };
                    // Float partial sums over at most kBlock texels (relative rounding below 64·2^-24 =
                    // 4e-6), then double.
                    constexpr int kBlock = 64;
                    for (int xs = x0; xs <= x1; xs += kBlock) {
                        const int xe = std::min(x1, xs + kBlock - 1);
                        Float4 sw4{}, sr4{}, sg4{}, sb4{};
                        int tx = xs;
                        for (; tx + 3 <= xe; tx += 4) {
                            const Float4 dx = load4(px + tx) - rx, dy = load4(py + tx) - ry,
                                         dz = load4(pz + tx) - rz;
                            const Float4 wo = lobe(0.5f * (dx * dx + dy * dy + dz * dz)) * load4(pw + tx);
                            sw4 += wo;
                            sr4 += wo * load4(pr + tx);
                            sg4 += wo * load4(pg + tx);
                            sb4 += wo * load4(pb + tx);
                        }
                        float sw = horizontalSum(sw4), sr = horizontalSum(sr4), sg = horizontalSum(sg4),
                              sb = horizontalSum(sb4);
                        for (; tx <= xe; ++tx) {
                            const float wo = weight(tx);
                            sw += wo;
                            sr += wo * pr[tx];
                            sg += wo * pg[tx];
                            sb += wo * pb[tx];
                        }
                        wsum += sw;
                        sum[0] += sr;
                        sum[1] += sg;
                        sum[2] += sb;
                    }
                });
                float* out3 = dst.texel(face, x, y);
                if (wsum > 0.0) {
                    // A weighted mean of finite radiances, but float products of radiances near FLT_MAX
                    // can overflow: keep the stored value finite.
                    for (int k = 0; k < 3; ++k)
                        out3[k] = float(std::min(sum[k] / wsum, double(std::numeric_limits<float>::max())));
                } else {
                    // A lobe narrower than the source texels around R: no centre fell inside it, so
                    // the lobe sees the source's bilinear value at R.
                    const dvec3 L = sampleCube(chain, R, sourceLevel);
                    for (int k = 0; k < 3; ++k)
                        out3[k] = float(L[k]);
                }
            }
        });
        out.seconds.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        if (o.progress) o.progress(double(m + 1) / double(mips));
    }
    return out;
}

glm::dvec3 referencePrefilteredRadiance(const CubeMap& source, const glm::dvec3& Rin, LobeModel lobe,
                                        double power) {
    if (source.levels.empty()) return {};
    const dvec3 R = glm::normalize(Rin);
    const CubeLevel& level = source.levels[0];
    dvec3 sum(0.0);
    double wsum = 0.0;
    for (int f = 0; f < kCubeFaces; ++f)
        for (int y = 0; y < level.size; ++y)
            for (int x = 0; x < level.size; ++x) {
                const double w = lobeWeight(lobe, power, glm::dot(R, texelDirection(f, level.size, x, y))) *
                                 texelSolidAngle(level.size, x, y);
                if (w <= 0.0) continue;
                sum += w * fetch(level, f, x, y);
                wsum += w;
            }
    return wsum > 0.0 ? sum / wsum : sampleCube(source, R, 0);
}

// ---------------------------------------------------------------------------------------------
// Storage.

namespace {

void put32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        s.push_back(char((v >> (8 * i)) & 0xFF));
}

std::uint32_t get32(std::string_view s, size_t at) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i)
        v |= std::uint32_t(std::uint8_t(s[at + size_t(i)])) << (8 * i);
    return v;
}

// Microsoft, "DDS_HEADER structure" and "DDS_HEADER_DXT10 structure" (Direct3D 10+ DDS files)
constexpr std::uint32_t kDdsMagic = 0x20534444; // "DDS "
constexpr std::uint32_t kDdsHeaderSize = 124;
constexpr std::uint32_t kDdsCaps = 0x1, kDdsHeight = 0x2, kDdsWidth = 0x4, kDdsPitch = 0x8;
constexpr std::uint32_t kDdsPixelFormat = 0x1000, kDdsMipMapCount = 0x20000;
constexpr std::uint32_t kDdpfFourCC = 0x4;
constexpr std::uint32_t kFourCCDx10 = 0x30315844; // "DX10"
constexpr std::uint32_t kCapsComplex = 0x8, kCapsTexture = 0x1000, kCapsMipMap = 0x400000;
constexpr std::uint32_t kCaps2Cubemap = 0x200, kCaps2AllFaces = 0xFC00; // +X..−Z face bits
constexpr std::uint32_t kDxgiR16G16B16A16Float = 10;
constexpr std::uint32_t kD3d10ResourceTexture2D = 3;
constexpr std::uint32_t kResourceMiscTextureCube = 0x4;
constexpr size_t kDdsDataOffset = 4 + kDdsHeaderSize + 20;

std::uint16_t toHalfBits(float v) {
    // Finite and within half's range: above 65504 half would round to +Inf; a sun texel is stored at the
    // largest finite half instead (NaN and negatives cannot reach here, but become 0 if they did).
    const float clamped = std::isfinite(v) ? std::clamp(v, 0.0f, kHalfMax) : (v > 0.0f ? kHalfMax : 0.0f);
    return Imath::half(clamped).bits();
}

} // namespace

std::string encodeCubeDds(const CubeMap& cube) {
    std::string s;
    const std::uint32_t size = std::uint32_t(cube.faceSize());
    const std::uint32_t mips = std::uint32_t(cube.mipCount());
    put32(s, kDdsMagic);
    put32(s, kDdsHeaderSize);
    put32(s, kDdsCaps | kDdsHeight | kDdsWidth | kDdsPitch | kDdsPixelFormat | kDdsMipMapCount);
    put32(s, size);     // height
    put32(s, size);     // width
    put32(s, size * 8); // pitch: 4 half channels per texel
    put32(s, 0);        // depth
    put32(s, mips);
    for (int i = 0; i < 11; ++i)
        put32(s, 0); // reserved
    put32(s, 32);    // DDS_PIXELFORMAT size
    put32(s, kDdpfFourCC);
    put32(s, kFourCCDx10);
    for (int i = 0; i < 5; ++i)
        put32(s, 0); // RGB bit count and masks: unused with a FourCC
    put32(s, kCapsComplex | kCapsTexture | (mips > 1 ? kCapsMipMap : 0));
    put32(s, kCaps2Cubemap | kCaps2AllFaces);
    put32(s, 0); // caps3
    put32(s, 0); // caps4
    put32(s, 0); // reserved2
    put32(s, kDxgiR16G16B16A16Float);
    put32(s, kD3d10ResourceTexture2D);
    put32(s, kResourceMiscTextureCube);
    put32(s, 1); // array size: one cube
    put32(s, 0); // miscFlags2: alpha mode unknown
    const std::uint16_t one = Imath::half(1.0f).bits();
    for (int f = 0; f < kCubeFaces; ++f)
        for (const CubeLevel& level : cube.levels) {
            const std::vector<float>& face = level.faces[size_t(f)];
            for (size_t i = 0; i < face.size() / 3; ++i) {
                for (int c = 0; c < 4; ++c) {
                    const std::uint16_t h = c < 3 ? toHalfBits(face[3 * i + size_t(c)]) : one;
                    s.push_back(char(h & 0xFF));
                    s.push_back(char(h >> 8));
                }
            }
        }
    return s;
}

Result<CubeMap> decodeCubeDds(std::string_view s) {
    if (s.size() < kDdsDataOffset || get32(s, 0) != kDdsMagic || get32(s, 4) != kDdsHeaderSize)
        return Error{"not a DDS file (no 'DDS ' header)"};
    if (get32(s, 4 + 80) != kFourCCDx10 || get32(s, 4 + 124) != kDxgiR16G16B16A16Float)
        return Error{"DDS is not a DX10 RGBA16F texture"};
    if (!(get32(s, 4 + 108) & kCaps2Cubemap) || (get32(s, 4 + 108) & kCaps2AllFaces) != kCaps2AllFaces)
        return Error{"DDS is not a cube map with all six faces"};
    const std::uint32_t height = get32(s, 12), width = get32(s, 16);
    const std::uint32_t mips = std::max<std::uint32_t>(1, get32(s, 28));
    if (width != height || !isPowerOfTwo(int(std::min<std::uint32_t>(width, 1u << 30))) ||
        mips > std::uint32_t(fullMipCount(int(width))))
        return Error{fmt::format("DDS cube {}x{} with {} mips is not a square power-of-two chain", width,
                                 height, mips)};
    CubeMap cube = CubeMap::zeros(int(width), int(mips));
    size_t at = kDdsDataOffset;
    size_t need = at;
    for (const CubeLevel& l : cube.levels)
        need += size_t(kCubeFaces) * size_t(l.size) * size_t(l.size) * 8;
    if (s.size() < need) return Error{fmt::format("DDS is truncated: {} bytes, {} needed", s.size(), need)};
    for (int f = 0; f < kCubeFaces; ++f)
        for (CubeLevel& level : cube.levels) {
            std::vector<float>& face = level.faces[size_t(f)];
            for (size_t i = 0; i < face.size() / 3; ++i) {
                for (int c = 0; c < 4; ++c) {
                    Imath::half h;
                    h.setBits(std::uint16_t(std::uint8_t(s[at]) | (std::uint8_t(s[at + 1]) << 8)));
                    at += 2;
                    if (c < 3) face[3 * i + size_t(c)] = float(h);
                }
            }
        }
    return cube;
}

Status writeCubeDds(const CubeMap& cube, const fs::path& path) {
    if (cube.levels.empty()) return Error{"cannot write an empty cube to '" + path.string() + "'"};
    return writeFileAtomic(path, encodeCubeDds(cube));
}

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
