// Environment lighting: cube maps (OpenGL face order and orientation), equirectangular → cube,
// a procedural studio, and the prefiltered mipmapped radiance environment map (PMREM): each mip
// filtered by a cosine-power lobe whose power drops per mip or follows a gloss encoding.
//
// Layout, ready for glTexImage2D: level k of a cube with face size N is (N >> k)² texels per face,
// RGB float, row j holding t = (j + 0.5)/size and column i holding s = (i + 0.5)/size, faces in
// the order GL_TEXTURE_CUBE_MAP_POSITIVE_X + f: +X −X +Y −Y +Z −Z. Direction ↔ (face, s, t) is the
// OpenGL major-axis rule (OpenGL 4.6 spec, table 8.19). Face sizes are powers of two.
//
// Every value a function here returns is finite and non-negative: NaN, Inf and negative input
// texels are replaced by 0 on import (and counted).
#pragma once

#include <burnish/core/gloss.h>
#include <burnish/core/image.h>
#include <burnish/core/result.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
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
/// The studio on a cube (4×4 supersampled per texel); `faceSize` a power of two.
Result<CubeMap> proceduralStudioEnvironment(int faceSize);
/// The studio as an equirectangular image (3 channels), in equirectToCube's convention.
Image proceduralStudioEquirect(int width, int height);

// ---------------------------------------------------------------------------------------------
// Prefiltered radiance (PMREM).

/// The lobe each mip is filtered with, about the reflection vector R (with N = V = R).
enum class LobeModel {
    /// (R·L)^n: what a single cube-map tap can show (AMD CubeMapGen's cosine power filter).
    Phong,
    /// (N·H)^n with N = V = R, i.e. cos^n(θ/2) = ((1 + R·L)/2)^(n/2): the Blinn-Phong highlight at
    /// normal incidence, close to Phong with n/4.
    // Lagarde 2012, "Relationship between Phong and Blinn lighting model": acos(R·E) = 2 acos(N·H)
    BlinnPhong,
};
const char* lobeModelName(LobeModel lobe);

struct PrefilterOptions {
    LobeModel lobe = LobeModel::Phong;
    /// Output mips; 0 is the full chain down to 1×1.
    int mips = 0;
    /// Power per mip from a drop factor: n_m = topPower · powerDrop^m.
    // Lagarde 2011, "AMD Cubemapgen for physically based rendering": 2048, 0.25 → 2048, 512, 128, ...
    double topPower = 2048.0;
    double powerDrop = 0.25;
    /// When set, the power per mip follows the encoding instead: mip m ↔ gloss g = 1 − m/(mips − 1)
    /// (the stored value is g for gloss-like encodings, 1 − g for roughness-like ones), n = power(v).
    // Lazarov 2011, "Physically Based Lighting in Call of Duty: Black Ops": the mip is selected from gloss
    std::optional<GlossEncoding> encoding;
    /// The lobe is cut where its weight falls below this fraction of its peak (the relative energy
    /// left out is about the same).
    double lobeCutoff = 1e-5;
    /// Source texels per lobe standard deviation: each mip reads the coarsest box-filtered source
    /// level that still has this many (more is slower and closer to the brute-force reference).
    double texelsPerSigma = 2.5;
    /// Called with the fraction done (0..1) from the calling thread, once per output mip.
    std::function<void(double)> progress;
};

/// The power of each of `mips` output levels under the options (clamped to [0, kMaxPower]).
std::vector<double> prefilterPowers(const PrefilterOptions& options, int mips);
/// The mip (fractional, in [0, mips − 1]) a gloss value g ∈ [0, 1] reads: (1 − g)·(mips − 1).
// Lazarov 2011: texCUBElod(uv, float4(R, nMips − gloss·nMips)), with the last mip at g = 0
double mipForGloss(double g, int mips);

struct PrefilteredEnvironment {
    CubeMap radiance;
    std::vector<double> powers;    // per mip
    std::vector<int> sourceLevels; // the box-filtered source level each mip read
    std::vector<double> seconds;   // wall time per mip
    LobeModel lobe = LobeModel::Phong;
};

/// Filters `source` (level 0 is used) into a radiance cube of the same face size: texel of mip m =
/// Σ L(d) w(R·d) Ω(d) / Σ w(R·d) Ω(d) over source texels d, with R the texel's direction and w the
/// lobe of power n_m. The integral runs over directions (not per face), so texels that touch across a
/// cube edge agree. Errors: empty or non-power-of-two source, mips out of range, bad options.
Result<PrefilteredEnvironment> prefilterRadiance(const CubeMap& source, const PrefilterOptions& options);

/// The lobe's weight for cosine c = R·L (0 outside its support), never NaN.
double lobeWeight(LobeModel lobe, double power, double c);

/// Brute force: the same normalized lobe integral at one direction over every level-0 texel of
/// `source`, with no cut and no coarser source level.
glm::dvec3 referencePrefilteredRadiance(const CubeMap& source, const glm::dvec3& R, LobeModel lobe,
                                        double power);

// ---------------------------------------------------------------------------------------------
// Storage.

/// Half-float RGBA (DXGI_FORMAT_R16G16B16A16_FLOAT) DDS of a cube with all its mips, DX10 header,
/// faces in GL order, each face's chain in order (the DDS cube layout); alpha 1. Values above the
/// half range are stored as 65504.
std::string encodeCubeDds(const CubeMap& cube);
/// Reads what encodeCubeDds writes (RGBA16F DX10 cube maps); clear errors for anything else.
Result<CubeMap> decodeCubeDds(std::string_view bytes);
/// Writes encodeCubeDds atomically.
Status writeCubeDds(const CubeMap& cube, const std::filesystem::path& path);
/// Writes one half-float RGB OpenEXR per face and mip, "<stem>_m<k>_<face>.exr" (or
/// "<stem>_<face>.exr" for a single-level cube), each atomically; returns the names written.
Result<std::vector<std::string>> writeCubeExrFaces(const CubeMap& cube, const std::filesystem::path& dir,
                                                   const std::string& stem);
/// The largest finite half float; larger values are stored as this.
inline constexpr float kHalfMax = 65504.0f;

/// Multiplies every texel of every level by `scale` per channel.
void scaleCube(CubeMap& cube, const glm::dvec3& scale);

} // namespace burnish
