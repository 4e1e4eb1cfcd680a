// Helpers shared by the fit_*.cpp sources (private to core).
#pragma once

#include <burnish/core/fit.h>

#include <string>
#include <vector>

namespace burnish::fitdetail {

/// Accumulates the error of an approximation over one or more domains (e.g. one per power):
/// max |error| over all nodes, and the RMS as sqrt of the mean over domains of
/// (Σ w_i e_i²)/measure.
struct ErrorAccumulator {
    double maxAbs = 0.0;
    double meanSquareSum = 0.0;
    int domains = 0;

    ErrorAccumulator& add(const QuadratureRule& rule, const std::vector<double>& error, double measure);
    FitError result() const;
};

/// count values log-spaced over [lo, hi] (lo > 0), both ends included; {lo} when count <= 1.
std::vector<double> logSpaced(double lo, double hi, int count);

/// A number with 6 significant digits, as printed in reports.
std::string fmtNumber(double v);

} // namespace burnish::fitdetail
