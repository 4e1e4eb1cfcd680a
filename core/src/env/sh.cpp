#include <burnish/core/env/sh.h>

#include <burnish/core/env/storage.h>
#include <burnish/core/util/numeric.h>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace burnish {

using glm::dvec3;

std::array<double, 9> shBasis(const glm::dvec3& dIn) {
    const double len = glm::length(dIn);
    const dvec3 d = len > 0.0 && std::isfinite(len) ? dIn / len : dvec3(0, 0, 1);
    const double x = d.x, y = d.y, z = d.z;
    // Ramamoorthi & Hanrahan 2001, eq. 3: Y00 = 0.282095; Y1m = 0.488603 (y, z, x);
    // Y2-2, Y2-1, Y21 = 1.092548 (xy, yz, xz); Y20 = 0.315392 (3z² − 1); Y22 = 0.546274 (x² − y²)
    return {0.282095,
            0.488603 * y,
            0.488603 * z,
            0.488603 * x,
            1.092548 * x * y,
            1.092548 * y * z,
            0.315392 * (3.0 * z * z - 1.0),
            1.092548 * x * z,
            0.546274 * (x * x - y * y)};
}

Sh9 projectSh9(const CubeMap& cube) {
    Sh9 sh;
    if (cube.levels.empty()) return sh;
    const CubeLevel& level = cube.levels[0];
    const std::vector<double> omegas = texelSolidAngles(level.size);
    for (int f = 0; f < kCubeFaces; ++f)
        for (int y = 0; y < level.size; ++y)
            for (int x = 0; x < level.size; ++x) {
                const double omega = omegas[size_t(y) * size_t(level.size) + size_t(x)];
                const auto Y = shBasis(texelDirection(f, level.size, x, y));
                const float* L = level.texel(f, x, y);
                for (size_t k = 0; k < 9; ++k)
                    sh.coefficients[k] += (Y[k] * omega) * dvec3(L[0], L[1], L[2]);
            }
    return sh;
}

glm::dvec3 shIrradiance(const Sh9& sh, const glm::dvec3& normal) {
    // Ramamoorthi & Hanrahan 2001, eq. 8: the clamped cosine's SH coefficients Â_l
    constexpr double kA0 = kPi<double>, kA1 = 2.0 * kPi<double> / 3.0, kA2 = kPi<double> / 4.0;
    constexpr std::array<double, 9> kA{kA0, kA1, kA1, kA1, kA2, kA2, kA2, kA2, kA2};
    const auto Y = shBasis(normal);
    dvec3 E(0.0);
    for (size_t k = 0; k < 9; ++k)
        E += kA[k] * Y[k] * sh.coefficients[k];
    // Order 2 rings below 0 opposite very bright texels (a sun); irradiance cannot be negative.
    return glm::max(E, dvec3(0.0));
}

glm::dvec3 bruteForceIrradiance(const CubeMap& cube, const glm::dvec3& nIn) {
    if (cube.levels.empty()) return {};
    const dvec3 n = glm::normalize(nIn);
    const CubeLevel& level = cube.levels[0];
    dvec3 E(0.0);
    for (int f = 0; f < kCubeFaces; ++f)
        for (int y = 0; y < level.size; ++y)
            for (int x = 0; x < level.size; ++x) {
                const double cosTheta = glm::dot(n, texelDirection(f, level.size, x, y));
                if (cosTheta <= 0.0) continue;
                const float* L = level.texel(f, x, y);
                E += (cosTheta * texelSolidAngle(level.size, x, y)) * dvec3(L[0], L[1], L[2]);
            }
    return E;
}

Result<CubeMap> irradianceCube(const Sh9& sh, int faceSize) {
    if (!isPowerOfTwo(faceSize) || faceSize > 4096)
        return Error{fmt::format("irradiance cube size {} must be a power of two in [1, 4096]", faceSize)};
    CubeMap cube = CubeMap::zeros(faceSize, 1);
    CubeLevel& level = cube.levels[0];
    tbb::parallel_for(0, kCubeFaces * faceSize, [&](int row) {
        const int f = row / faceSize, y = row % faceSize;
        for (int x = 0; x < faceSize; ++x) {
            // E/π: what a white Lambert surface facing this way shows.
            // Lagarde 2012, "PI or not to PI in game lighting equation": f = c_diff/π
            const dvec3 diffuse = shIrradiance(sh, texelDirection(f, faceSize, x, y)) / kPi<double>;
            float* out = level.texel(f, x, y);
            for (int c = 0; c < 3; ++c)
                out[c] = float(diffuse[c]);
        }
    });
    return cube;
}

glm::dvec3 averageDiffuse(const Sh9& sh) {
    // The mean of E(n)/π over all n is the mean radiance (∫ max(n·l, 0) dω_n = π), i.e. c_00·Y_00.
    return glm::max(sh.coefficients[0] * 0.282095, dvec3(0.0));
}

glm::dvec3 normalizeByAverageDiffuse(CubeMap& cube, Sh9& sh) {
    const dvec3 avg = averageDiffuse(sh);
    dvec3 divisor(1.0);
    for (int c = 0; c < 3; ++c)
        if (avg[c] > kMinAverageDiffuse) divisor[c] = avg[c];
    scaleCube(cube, 1.0 / divisor);
    for (auto& coefficient : sh.coefficients)
        coefficient /= divisor;
    return divisor;
}

nlohmann::json sh9Json(const Sh9& sh) {
    nlohmann::json coefficients = nlohmann::json::array();
    for (const auto& c : sh.coefficients)
        coefficients.push_back({c.r, c.g, c.b});
    const dvec3 avg = averageDiffuse(sh);
    return {
        {"order", 2},
        {"basis", "real SH (Ramamoorthi & Hanrahan 2001): Y00, Y1-1, Y10, Y11, Y2-2, Y2-1, Y20, Y21, Y22; "
                  "directions in the cube's GL frame"},
        {"quantity", "radiance coefficients c_lm = sum L Y_lm dw; irradiance E(n) = sum A_l c_lm Y_lm(n)"},
        {"coefficients", coefficients},
        {"irradianceScale", {kPi<double>, 2.0 * kPi<double> / 3.0, kPi<double> / 4.0}},
        {"averageDiffuse", {avg.r, avg.g, avg.b}},
    };
}

} // namespace burnish
