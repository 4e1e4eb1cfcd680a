// Decoding tangent-space normal maps: channel layout, value encoding, green convention, z
// reconstruction, renormalization, and a plausibility check that refuses photos, height maps
// and object-space maps with a clear reason.
#pragma once

#include <burnish/core/io/image.h>
#include <burnish/core/util/result.h>
#include <burnish/core/util/texel_vector.h>

#include <glm/vec3.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace burnish {

/// Which way the green channel points. OpenGL (+Y, "Y up") is Burnish's internal convention;
/// DirectX maps (−Y) are flipped on import.
enum class GreenConvention { OpenGL, DirectX };

/// Which channels hold the normal. Auto: 2 channels → RG (z rebuilt), 3 or 4 → RGB; the alpha
/// of an RGBA map is never mixed into the normal (it often holds a height or gloss map).
enum class NormalLayout { Auto, Rgb, Rg };

/// How stored values map to [-1, 1]. Auto: integer formats and float images without negative
/// values are unsigned (2v − 1); float images with any negative value are already signed.
enum class NormalValueEncoding { Auto, Unsigned, Signed };

struct NormalMapOptions {
    GreenConvention green = GreenConvention::OpenGL;
    NormalLayout layout = NormalLayout::Auto;
    NormalValueEncoding encoding = NormalValueEncoding::Auto;
    /// Renormalize every texel at mip 0, so 8-bit quantization of the vector length does not
    /// show up as roughness downstream.
    bool renormalize = true;
    /// Turn the plausibility check's refusal into a warning.
    bool allowImplausible = false;
};

/// What the decoder saw and did.
struct NormalMapDiagnostics {
    size_t texels = 0;
    size_t nonFiniteTexels = 0;  // NaN/Inf in any used channel: replaced by a flat normal
    size_t zeroLengthTexels = 0; // decoded to (near) zero length: replaced by a flat normal
    /// No data: every used channel stored as 0 in an unsigned map (an atlas's transparent padding);
    /// left out of the plausibility test, filled with the nearest texel's normal (4-neighbour steps).
    size_t noDataTexels = 0;
    size_t negativeZTexels = 0;    // z < 0 before renormalization (impossible in tangent space)
    size_t offLengthTexels = 0;    // stored length off 1 by more than 25% (RG maps: only longer)
    double meanStoredLength = 1.0; // RGB maps: mean length of the stored vectors
    bool zRebuilt = false;
    /// Where the plausibility check refused the map and allowImplausible let it through: the refusal it
    /// would have given (the error decodeNormalMap returns without allowImplausible); empty where it passed.
    std::string implausible;
    bool alphaIgnored = false;
    bool greenFlipped = false;
    bool signedValues = false;
    std::vector<std::string> warnings;
};

/// Normals whose new elements are uninitialised on resize (texel_vector.h): decoding writes every
/// one from parallel blocks instead of after a serial zero-fill of the whole array.
using NormalVector = std::vector<glm::vec3, TexelAllocator<glm::vec3>>;

/// Unit tangent-space normals (OpenGL convention), row-major, top row first.
struct NormalMap {
    int width = 0;
    int height = 0;
    NormalVector normals;
    NormalMapDiagnostics diagnostics;
    ImageSourceInfo source;

    size_t texelCount() const { return normals.size(); }
    const glm::vec3& at(int x, int y) const {
        return normals[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
    }
};

/// Thresholds of the plausibility check (tangent-space maps store unit vectors facing +z).
inline constexpr double kMaxNegativeZFraction = 0.02;
inline constexpr double kMaxOffLengthFraction = 0.10;
inline constexpr double kOffLengthTolerance = 0.25;

/// Decodes an image into unit normals. Errors: fewer than 2 channels, an RG layout forced on
/// a 1-channel image, or (unless allowImplausible) an image that is not a plausible
/// tangent-space normal map, with the measured reason.
Result<NormalMap> decodeNormalMap(const Image& image, const NormalMapOptions& options = {});

/// readImage + decodeNormalMap.
Result<NormalMap> loadNormalMap(const std::filesystem::path& path, const NormalMapOptions& options = {});

/// A normal map from unit (or not: they are normalized, zero becomes +z) vectors, for synthetic inputs.
NormalMap makeNormalMap(int width, int height, std::vector<glm::vec3> normals);

} // namespace burnish
