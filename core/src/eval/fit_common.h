// Helpers shared by the fit_*.cpp sources (private to core).
#pragma once

#include <burnish/core/eval/fit.h>
#include <burnish/core/util/error_accumulator.h>
#include <burnish/core/util/grid.h>
#include <burnish/core/util/report.h> // formatNumber(v, 6): the fits' numbers

#include <string>
#include <vector>

namespace burnish::fitdetail {

/// The fit's two figures of an accumulated error.
inline FitError fitError(const ErrorMetrics& m) {
    return {m.maxAbs, m.rms};
}

} // namespace burnish::fitdetail
