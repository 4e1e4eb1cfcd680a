// Cube maps (OpenGL face order and orientation): geometry, seamless lookups, the box chain, and the
// sources an environment comes from (equirectangular → cube, six faces, a procedural studio).
// The prefiltered radiance is env/prefilter.h; EXR faces env/storage.h; the DDS cube io/cube_dds.h.
//
// Layout, ready for glTexImage2D: level k of a cube with face size N is (N >> k)² texels per face,
// RGB float, row j holding t = (j + 0.5)/size and column i holding s = (i + 0.5)/size, faces in
// the order GL_TEXTURE_CUBE_MAP_POSITIVE_X + f: +X −X +Y −Y +Z −Z. Direction ↔ (face, s, t) is the
// OpenGL major-axis rule (OpenGL 4.6 spec, table 8.19). Face sizes are powers of two.
//
// Every value a function here returns is finite and non-negative: NaN, Inf and negative input
// texels are replaced by 0 on import (and counted).
#pragma once

#include <burnish/core/io/image.h>
#include <burnish/core/util/result.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace burnish {

enum class CubeFace : int { PosX = 0, NegX = 1, PosY = 2, NegY = 3, PosZ = 4, NegZ = 5 };
inline constexpr int kCubeFaces = 6;
/// Short face names for file names, in face order: px nx py ny pz nz.
const char* cubeFaceName(int face);

/// One mip level: `size`² RGB texels per face.
struct CubeLevel {
    int size = 0;
    std::array<std::vector<float>, kCubeFaces> faces;

    float* texel(int face, int x, int y) {
        return faces[size_t(face)].data() + (size_t(y) * size_t(size) + size_t(x)) * 3;
    }
    const float* texel(int face, int x, int y) const {
        return faces[size_t(face)].data() + (size_t(y) * size_t(size) + size_t(x)) * 3;
    }
};

/// A cube map with a mip chain (levels[0] is the finest).
struct CubeMap {
    std::vector<CubeLevel> levels;

    int faceSize() const { return levels.empty() ? 0 : levels[0].size; }
    int mipCount() const { return int(levels.size()); }
    /// An all-zero cube of face size `size` with `mips` levels (mips <= fullMipCount(size)).
    static CubeMap zeros(int size, int mips = 1);
};

/// log2(size) + 1: the levels down to 1×1.
int fullMipCount(int faceSize);
/// True for 1, 2, 4, ...
bool isPowerOfTwo(int n);

/// Unit direction through (s, t) ∈ [0, 1]² of a face (GL convention).
glm::dvec3 cubeDirection(int face, double s, double t);
/// Unit direction through the centre of texel (x, y) of a `size`² face.
glm::dvec3 texelDirection(int face, int size, int x, int y);

struct CubeCoord {
    int face = 0;
    double s = 0.5;
    double t = 0.5;
};
/// The face and (s, t) a direction hits (major axis; ties go to x, then y). The zero or a non-finite
/// vector gives the centre of +X.
CubeCoord cubeCoord(const glm::dvec3& dir);

/// Exact solid angle (sr) of texel (x, y) of a `size`² face; the 6·size² texels sum to 4π.
// Area element of the cube face z = 1: dω = dx dy / (1 + x² + y²)^(3/2), integral atan(xy/sqrt(x²+y²+1))
double texelSolidAngle(int size, int x, int y);
/// The solid angles of all texels of a `size`² face (every face has the same), row by row: equal to
/// texelSolidAngle bit for bit, from (size + 1)² area-element evaluations instead of 4·size².
std::vector<double> texelSolidAngles(int size);

/// Seamless bilinear lookup of one level: taps beyond a face edge are read from the neighbouring face
/// (the behaviour of GL_TEXTURE_CUBE_MAP_SEAMLESS). `level` is clamped to the chain.
glm::dvec3 sampleCube(const CubeMap& cube, const glm::dvec3& dir, int level);
/// Trilinear lookup: seamless bilinear in the two levels around `lod` (clamped to the chain).
glm::dvec3 sampleCubeLod(const CubeMap& cube, const glm::dvec3& dir, double lod);

/// Replaces the chain below level 0 with a solid-angle-weighted 2×2 box chain down to 1×1 (the
/// unfiltered source mips filtered importance sampling reads). Integrals over the sphere are kept.
void buildBoxMips(CubeMap& cube);

// ---------------------------------------------------------------------------------------------
// Sources.

/// What an import saw.
struct EnvironmentSource {
    CubeMap cube; // level 0 only
    std::string description;
    /// Texels that were NaN, infinite or negative and became 0.
    std::uint64_t replacedTexels = 0;
    /// Cube values above half float's largest (65504), which the half-float outputs clamp.
    std::uint64_t aboveHalfValues = 0;
    /// Whether an 8/16-bit source was decoded from sRGB to linear radiance.
    bool srgbDecoded = false;
    /// One line each for the user: replaced texels, clamped values, an sRGB source.
    std::vector<std::string> warnings;
    int sourceWidth = 0;
    int sourceHeight = 0;
};

/// Equirectangular (latitude–longitude) image to a cube of face size `faceSize` (a power of two).
/// Convention: +Y up, the top row is +Y, the image centre looks down −Z, u = 0.5 + atan2(x, −z)/2π,
/// v = acos(y)/π. Bilinear lookups (wrapping in u), supersampled k×k per texel where the cube is
/// coarser than the image (k = ceil(width / (4·faceSize))). Uses the first three channels (one
/// channel is grey). Errors: not a power-of-two size, empty image.
Result<EnvironmentSource> equirectToCube(const Image& image, int faceSize);

/// Six square face images of one power-of-two size, in face order, rows as in the layout above.
Result<EnvironmentSource> cubeFromFaces(const std::array<Image, kCubeFaces>& faces);

/// Reads an equirectangular HDR (EXR, HDR, float TIFF, ... through OpenImageIO; width = 2·height)
/// and converts it to a cube of face size `faceSize`.
Result<EnvironmentSource> loadEquirectEnvironment(const std::filesystem::path& path, int faceSize);
/// Reads six face files (order +X −X +Y −Y +Z −Z); they set the face size. Faces that are not square,
/// not a power of two or not all of one size are an error.
Result<EnvironmentSource> loadCubeFaceEnvironment(const std::array<std::filesystem::path, kCubeFaces>& paths);

/// The procedural studio: a vertical gradient (bright ceiling, dim floor) with three soft area lights
/// (a warm key, a cool fill, a white rim), radiance per channel in [0.02, 18]. Deterministic.
glm::dvec3 studioRadiance(const glm::dvec3& dir);
/// The studio on a cube, `supersample`² sub-samples per texel (4×4 for lighting, which resolves the
/// lights' rims at any size; a backdrop of fine texels needs fewer, at a 16th of the cost with 1);
/// `faceSize` a power of two, `supersample` in 1..8.
Result<CubeMap> proceduralStudioEnvironment(int faceSize, int supersample = 4);
/// The studio as an equirectangular image (3 channels), in equirectToCube's convention.
Image proceduralStudioEquirect(int width, int height);

} // namespace burnish
