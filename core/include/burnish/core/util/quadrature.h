// Numerical integration used by the reference integrals, white-furnace checks and fits.
// Adaptive Gauss–Kronrod (Boost.Math) with breakpoints placed at the lobe's width, so lobes as
// sharp as power 1e6 ("stiff" integrands, width ~1/sqrt(n)) integrate to full accuracy.
#pragma once

#include <functional>

namespace burnish {

/// ∫_a^b f(x) dx by adaptive 15-point Gauss–Kronrod to relative tolerance tol.
double integrate(const std::function<double(double)>& f, double a, double b, double tol = 1e-10);

/// ∫ f(cosθ) dω over the upper hemisphere for an azimuthally symmetric f:
/// 2π ∫_0^{π/2} f(cos θ) sin θ dθ. `width` is the angular scale (radians) where f changes,
/// e.g. 1/sqrt(n+1) for a cosine power n; the θ range is split geometrically from it so that
/// sharp lobes are resolved.
double integrateHemisphere(const std::function<double(double)>& f, double width = 1.0, double tol = 1e-10);

/// Same as integrateHemisphere over the whole sphere (θ in [0, π]).
double integrateSphere(const std::function<double(double)>& f, double width = 1.0, double tol = 1e-10);

} // namespace burnish
