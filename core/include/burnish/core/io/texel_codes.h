// The codes a file stores a value in [0, 1] as: unsigned normalized 8/16-bit integers and half floats,
// converted as the export writes them (and as OpenImageIO does).
#pragma once

#include <Imath/half.h>

#include <algorithm>
#include <cstdint>

namespace burnish {

/// The stored code of a value v in [0, 1] (clamped; NaN gives 0) in an unsigned normalized format
/// of `maxCode` (255, 65535): round to nearest, v·maxCode + 0.5 truncated.
template <class T> inline T unormCode(float v, double maxCode) {
    v = v > 0.0f ? v : 0.0f;
    v = v < 1.0f ? v : 1.0f;
    return static_cast<T>(static_cast<std::int32_t>(double(v) * maxCode + 0.5));
}
inline std::uint8_t unorm8(float v) {
    return unormCode<std::uint8_t>(v, 255.0);
}
inline std::uint16_t unorm16(float v) {
    return unormCode<std::uint16_t>(v, 65535.0);
}
/// The half-float a value in [0, 1] is stored as (clamped; Imath rounds to nearest even, as
/// OpenImageIO does when it writes floats as half).
inline Imath::half halfCode(float v) {
    return Imath::half(std::clamp(v, 0.0f, 1.0f));
}

} // namespace burnish
