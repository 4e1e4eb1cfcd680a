#include <burnish/core/shading/spherical_gaussian.h>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace burnish {

SgOffsetCurve::SgOffsetCurve(std::vector<double> powers, std::vector<double> offsets)
    : m_powers(std::move(powers))
    , m_offsets(std::move(offsets)) {
    assert(m_powers.size() == m_offsets.size());
    assert(std::is_sorted(m_powers.begin(), m_powers.end()));
}

double SgOffsetCurve::operator()(double n) const {
    if (m_powers.empty()) return kSgOffsetLimit;
    if (!(n > m_powers.front())) return m_offsets.front();
    if (n >= m_powers.back()) return m_offsets.back();
    const auto it = std::upper_bound(m_powers.begin(), m_powers.end(), n);
    const size_t i = static_cast<size_t>(it - m_powers.begin());
    const double t = std::log(n / m_powers[i - 1]) / std::log(m_powers[i] / m_powers[i - 1]);
    return m_offsets[i - 1] + t * (m_offsets[i] - m_offsets[i - 1]);
}

} // namespace burnish
