#include <burnish/core/shading/geometric_aa.h>

#include <burnish/core/util/quadrature.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace burnish {

namespace {

// NaN-safe clamp to [lo, hi]: NaN becomes `nanValue`.
double clampOr(double x, double lo, double hi, double nanValue) {
    if (std::isnan(x)) return nanValue;
    return std::clamp(x, lo, hi);
}

// ∫_0^{2π} max(0, A + B cos φ) dφ for B >= 0: the azimuthal integral of n_i·l over the ring of
// normals at polar angle θ about the cone axis, with A = cosθ cosα and B = sinθ sinα.
double azimuthIntegral(double A, double B) {
    if (A >= B) return 2.0 * kPi<double> * A; // the whole ring faces the light
    if (A <= -B) return 0.0;                  // the whole ring faces away
    // Lit arc |φ| < φ0 with A + B cos φ0 = 0; B > |A| >= 0 here, so the ratio is in (−1, 1).
    const double phi0 = std::acos(std::clamp(-A / B, -1.0, 1.0));
    return 2.0 * (A * phi0 + B * std::sin(phi0));
}

} // namespace

// Baker & Hill 2012, "Rock-Solid Shading": mean of max(0, n_i·l) over a uniform cone of normals
double diffuseConeIntegral(double cosAlpha, double cosCone) {
    // NaN light cosine: treated as the domain's lower end (light behind, result 0 at cone 0).
    cosAlpha = clampOr(cosAlpha, -1.0, 1.0, -1.0);
    // NaN cone: treated as no spread (|Na| = 1), the identity of the prefilter.
    cosCone = clampOr(cosCone, -1.0, 1.0, 1.0);
    const double thetaC = std::acos(cosCone);
    // A cone of zero solid angle (also the cones below double resolution): the limit is the
    // clamped cosine of the axis itself.
    if (!(thetaC > 0.0)) return saturate(cosAlpha);
    const double alpha = std::acos(cosAlpha);
    const double sinAlpha = std::sin(alpha);

    // The azimuthal integral switches regime (a kink) where A = ±|B|, i.e. where the ring touches
    // the terminator: θ = |π/2 − α|, θ = α + π/2 and θ = 3π/2 − α. Breakpoints there keep the
    // Gauss–Kronrod panels smooth.
    std::vector<double> points{0.0, thetaC};
    for (const double kink :
         {std::abs(kPi<double> / 2.0 - alpha), alpha + kPi<double> / 2.0, 1.5 * kPi<double> - alpha})
        if (kink > 0.0 && kink < thetaC) points.push_back(kink);
    std::sort(points.begin(), points.end());

    const auto integrand = [&](double theta) {
        const double A = std::cos(theta) * cosAlpha;
        const double B = std::sin(theta) * sinAlpha;
        return azimuthIntegral(A, B) * std::sin(theta);
    };
    // Relative tolerance of each panel; the header promises ~1e-9 overall.
    constexpr double kPanelTolerance = 1e-11;
    double sum = 0.0;
    for (size_t i = 0; i + 1 < points.size(); ++i)
        sum += integrate(integrand, points[i], points[i + 1], kPanelTolerance);

    // Cone solid angle 2π(1 − cos θc); 1 − cos θc written as 2 sin²(θc/2), exact for tiny cones.
    const double halfSin = std::sin(thetaC / 2.0);
    const double solidAngle = 2.0 * kPi<double> * (2.0 * halfSin * halfSin);
    const double mean = sum / solidAngle;
    // The mean of a quantity in [0, 1] lies in [0, 1]; clamp away quadrature round-off.
    return saturate(mean);
}

} // namespace burnish
