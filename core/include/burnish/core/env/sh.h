// Diffuse environment lighting: order-2 spherical harmonics (9 coefficients per channel) of a
// cube map's radiance, the irradiance they give (the clamped-cosine convolution), a brute-force
// irradiance integral to check them against, a small irradiance cube, and Lazarov's normalization
// of a probe by its average diffuse lighting.
//
// Units: radiance in, irradiance E(n) = ∫ L(l) max(n·l, 0) dω out. A white Lambert surface shows
// E/π; irradiance cubes store that (so a constant environment L gives an irradiance cube of L).
#pragma once

#include <burnish/core/env/cube.h>

#include <nlohmann/json.hpp>

#include <array>

namespace burnish {

/// Real SH coefficients of radiance, RGB, in the order (l, m) = (0,0), (1,−1), (1,0), (1,1), (2,−2),
/// (2,−1), (2,0), (2,1), (2,2).
struct Sh9 {
    std::array<glm::dvec3, 9> coefficients{};
};

/// The nine real SH basis functions at a unit direction, in Sh9's order.
// Ramamoorthi & Hanrahan 2001, "An Efficient Representation for Irradiance Environment Maps", eq. 3
std::array<double, 9> shBasis(const glm::dvec3& dir);

/// Projection of level 0: c_lm = Σ L(d) Y_lm(d) Ω(d) over every texel (exact texel solid angles).
Sh9 projectSh9(const CubeMap& cube);

/// Irradiance E(n) from the coefficients: Σ Â_l c_lm Y_lm(n), Â = (π, 2π/3, π/4); clamped at 0
/// (the truncated series can ring below 0 around very bright texels).
// Ramamoorthi & Hanrahan 2001, eq. 8: Â_0 = π, Â_1 = 2π/3, Â_2 = π/4
glm::dvec3 shIrradiance(const Sh9& sh, const glm::dvec3& normal);

/// Brute force: E(n) = Σ L(d) max(n·d, 0) Ω(d) over every level-0 texel.
glm::dvec3 bruteForceIrradiance(const CubeMap& cube, const glm::dvec3& normal);

/// A one-level cube of face size `faceSize` (a power of two) holding E(n)/π from the SH.
Result<CubeMap> irradianceCube(const Sh9& sh, int faceSize);

/// The average over all normals of E(n)/π, per channel; it equals the mean radiance (c_00·Y_00).
glm::dvec3 averageDiffuse(const Sh9& sh);

/// Divides the cube (every level) and the SH by the average diffuse lighting, per channel; a channel
/// whose average is not above `kMinAverageDiffuse` is left as it is (scale 1). Returns the divisor
/// used per channel (1 where left).
// Lazarov 2011: "Normalize – divide out environment map by average diffuse lighting at the capture point"
glm::dvec3 normalizeByAverageDiffuse(CubeMap& cube, Sh9& sh);
/// Below this mean radiance a channel is treated as black and not normalized: dividing by it would
/// turn float noise into a bright probe.
inline constexpr double kMinAverageDiffuse = 1e-8;

/// {"order": 2, "basis": ..., "coefficients": [[r, g, b] × 9], "irradianceScale": [π, 2π/3, π/4],
///  "averageDiffuse": [r, g, b]}
nlohmann::json sh9Json(const Sh9& sh);

} // namespace burnish
