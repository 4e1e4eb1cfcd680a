#include <burnish/core/util/error_accumulator.h>

#include <algorithm>
#include <cmath>

namespace burnish {

void ErrorAccumulator::add(double exact, double approx, double relFloor) {
    if (!std::isfinite(exact) || !std::isfinite(approx)) {
        ++m_nonFinite;
        return;
    }
    const double err = std::abs(approx - exact);
    m_maxAbs = std::max(m_maxAbs, err);
    m_sumSq += err * err;
    ++m_samples;
    const double mag = std::abs(exact);
    if (mag > 0.0 && mag >= relFloor) {
        m_maxRel = std::max(m_maxRel, err / mag);
        ++m_relSamples;
    }
}

ErrorAccumulator& ErrorAccumulator::addDomain(const std::vector<double>& weights,
                                              const std::vector<double>& errors, double measure) {
    double sum = 0.0;
    for (size_t i = 0; i < errors.size(); ++i) {
        if (!std::isfinite(errors[i])) {
            ++m_nonFinite;
            continue;
        }
        sum += weights[i] * errors[i] * errors[i];
        m_maxAbs = std::max(m_maxAbs, std::abs(errors[i]));
    }
    m_domainMeanSquares += sum / measure;
    ++m_domains;
    return *this;
}

ErrorMetrics ErrorAccumulator::metrics() const {
    ErrorMetrics m;
    m.samples = m_samples;
    m.relSamples = m_relSamples;
    m.maxAbs = m_maxAbs;
    const int domains = m_domains + (m_samples > 0 ? 1 : 0);
    const double meanSquares = m_domainMeanSquares + (m_samples > 0 ? m_sumSq / double(m_samples) : 0.0);
    m.rms = domains > 0 ? std::sqrt(meanSquares / domains) : 0.0;
    if (m_relSamples > 0) m.maxRel = m_maxRel;
    return m;
}

} // namespace burnish
