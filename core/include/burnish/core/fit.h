// Least-squares fits that derive the published constants from first principles (Eigen's
// Levenberg–Marquardt over quadrature-evaluated residuals). Each fit states its domain and metric.
#pragma once

#include <burnish/core/spherical_gaussian.h>

namespace burnish {

/// Best-fit offset x for one power n in c^n ≈ exp((n + x)(c − 1)): minimizes the L2 error over
/// c uniform in [0, 1]. Tends to 0.75 as n grows.
double fitSgOffset(double n);

/// x(n) tabulated at `nodes` powers log-spaced over [nMin, nMax] (see SgOffsetCurve).
SgOffsetCurve fitSgOffsetCurve(double nMin = 1.0, double nMax = 1e4, int nodes = 33);

} // namespace burnish
