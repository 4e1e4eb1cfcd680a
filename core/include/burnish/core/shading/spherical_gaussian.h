// Spherical-Gaussian approximations of cosine-power lobes (Blinn-Phong in n·h, Phong in r·l).
#pragma once

#include <burnish/core/util/numeric.h>

#include <vector>

namespace burnish {

/// Offsets x in c^n ≈ exp((n + x)(c − 1)).
// Lagarde 2012, "Spherical Gaussian approximation for Blinn-Phong, Phong and Fresnel":
// x = 0 is the plain SG of Wang et al. 2009; 0.775 is the mean best fit over powers 3..15;
// 0.75 is the limit of the best fit as n grows.
inline constexpr double kSgOffsetPlain = 0.0;
inline constexpr double kSgOffsetLagarde = 0.775;
inline constexpr double kSgOffsetLimit = 0.75;

/// Spherical-Gaussian approximation of the cosine-power lobe c^n (c = n·h for Blinn-Phong,
/// c = r·l for Phong): exp((n + x)(c − 1)), 0 for c <= 0 like the exact lobe (the exact lobe is
/// always multiplied by a clamped n·l, so the terminator stays at zero).
// Lagarde 2012 (after Wang et al. 2009, "All-Frequency Rendering with Dynamic, Spatially-Varying
// Reflectance")
template <class T> inline T sgLobe(T c, T n, T x) {
    if (!(c > T(0))) return T(0);
    const T k = clampPower(n) + x;
    return std::exp(std::max(k, T(0)) * (std::min(c, T(1)) - T(1)));
}

/// The same lobe in the GPU form of Lagarde 2012: exp2(A·c − A) with A = (n + x)/ln 2 folded
/// into the decoded power ("ModifiedSpecularPower"), one MAD and one EXP2.
template <class T> inline T sgLobeExp2(T c, T modifiedPower) {
    if (!(c > T(0))) return T(0);
    // A clamped like every power (NaN and negative → 0, at most kMaxPower/ln 2): +inf would give
    // inf − inf = NaN, and a negative A would raise the lobe above 1 (to overflow).
    const T A = modifiedPower > T(0) ? std::min(modifiedPower, T(kMaxPower / kLn2<double>)) : T(0);
    return std::exp2(A * std::min(c, T(1)) - A);
}

/// The per-power best-fit offset x(n) as a table in log n, made by fitting (see fit.h) and
/// interpolated linearly in log n between its nodes; outside the nodes it holds the end values.
class SgOffsetCurve {
public:
    SgOffsetCurve() = default;
    SgOffsetCurve(std::vector<double> powers, std::vector<double> offsets);

    /// x(n); for an empty curve, kSgOffsetLimit.
    double operator()(double n) const;
    const std::vector<double>& powers() const { return m_powers; }
    const std::vector<double>& offsets() const { return m_offsets; }

private:
    std::vector<double> m_powers; // ascending
    std::vector<double> m_offsets;
};

} // namespace burnish
