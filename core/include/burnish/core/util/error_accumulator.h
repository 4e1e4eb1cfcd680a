// The error of an approximation against its exact form, accumulated over samples or quadrature
// domains: what the approximations report and the fits print.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

namespace burnish {

/// Error of an approximation over a sample grid. maxRel is unset when no sample qualified for a
/// relative error (see ErrorAccumulator::add).
struct ErrorMetrics {
    double maxAbs = 0.0;
    std::optional<double> maxRel;
    double rms = 0.0;
    size_t samples = 0;
    size_t relSamples = 0; // samples that counted in maxRel
};

/// Accumulates |approx − exact| over samples and domains: max |error| over everything, and the RMS
/// as sqrt of the mean over domains of each domain's mean square. Samples given one at a time (add)
/// form one domain of equal weights, Σe²/n; a quadrature domain (addDomain) has (Σ w_i e_i²)/measure.
/// NaN/Inf samples are counted separately (nonFinite) rather than poisoning the metrics.
class ErrorAccumulator {
public:
    /// Adds one sample. The relative error |approx − exact|/|exact| counts only when
    /// |exact| >= relFloor and |exact| > 0 (relFloor = 0: wherever exact is non-zero).
    void add(double exact, double approx, double relFloor = 0.0);
    /// Adds one domain: errors e_i at nodes of quadrature weights w_i over a domain of `measure`.
    ErrorAccumulator& addDomain(const std::vector<double>& weights, const std::vector<double>& errors,
                                double measure);
    ErrorMetrics metrics() const;
    size_t nonFinite() const { return m_nonFinite; }

private:
    double m_maxAbs = 0.0;
    double m_maxRel = 0.0;
    double m_sumSq = 0.0; // the samples' domain
    size_t m_samples = 0;
    size_t m_relSamples = 0;
    size_t m_nonFinite = 0;
    double m_domainMeanSquares = 0.0; // Σ over quadrature domains of (Σ w e²)/measure
    int m_domains = 0;
};

} // namespace burnish
