// Sample grids of the reports and fits: evenly spaced and log-spaced values.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace burnish {

/// `count` values evenly spaced over [lo, hi], both ends included; {lo} when count <= 1.
inline std::vector<double> linSpaced(double lo, double hi, int count) {
    std::vector<double> v(size_t(std::max(count, 1)));
    for (int i = 0; i < count; ++i)
        v[size_t(i)] = count > 1 ? lo + (hi - lo) * double(i) / double(count - 1) : lo;
    return v;
}

/// `count` values log-spaced over [lo, hi] (lo > 0), both ends exact; {lo} when count <= 1.
inline std::vector<double> logSpaced(double lo, double hi, int count) {
    if (count <= 1 || hi == lo) return {lo};
    std::vector<double> values;
    for (int i = 0; i < count; ++i)
        values.push_back(lo * std::pow(hi / lo, double(i) / (count - 1)));
    values.back() = hi; // exact end despite rounding in pow
    return values;
}

} // namespace burnish
