#include <burnish/core/env/cube_dds.h>

#include <burnish/core/env/storage.h>

#include "io/dds_dx10.h"

#include <Imath/half.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace burnish {

namespace {

std::uint32_t get32(std::string_view s, size_t at) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i)
        v |= std::uint32_t(std::uint8_t(s[at + size_t(i)])) << (8 * i);
    return v;
}

using namespace dds;

std::uint16_t toHalfBits(float v) {
    // Finite and within half's range: above 65504 half would round to +Inf; a sun texel is stored at the
    // largest finite half instead (NaN and negatives cannot reach here, but become 0 if they did).
    const float clamped = std::isfinite(v) ? std::clamp(v, 0.0f, kHalfMax) : (v > 0.0f ? kHalfMax : 0.0f);
    return Imath::half(clamped).bits();
}

} // namespace

std::string encodeCubeDds(const CubeMap& cube) {
    const std::uint32_t size = std::uint32_t(cube.faceSize());
    std::string s = rgba16fHeader(size, size, std::uint32_t(cube.mipCount()), true);
    size_t bytes = s.size();
    for (const CubeLevel& level : cube.levels)
        for (const auto& face : level.faces)
            bytes += face.size() / 3 * 8;
    // Sized once, then filled in place: 8 bytes a texel (4 MB for a 256² chain).
    size_t at = s.size();
    s.resize(bytes);
    const std::uint16_t one = Imath::half(1.0f).bits();
    for (int f = 0; f < kCubeFaces; ++f)
        for (const CubeLevel& level : cube.levels) {
            const std::vector<float>& face = level.faces[size_t(f)];
            for (size_t i = 0; i < face.size() / 3; ++i) {
                for (int c = 0; c < 4; ++c) {
                    const std::uint16_t h = c < 3 ? toHalfBits(face[3 * i + size_t(c)]) : one;
                    s[at++] = char(h & 0xFF);
                    s[at++] = char(h >> 8);
                }
            }
        }
    return s;
}

Result<CubeMap> decodeCubeDds(std::string_view s) {
    if (s.size() < kDataOffset || get32(s, 0) != kMagic || get32(s, 4) != kHeaderSize)
        return Error{"not a DDS file (no 'DDS ' header)"};
    if (get32(s, 4 + 80) != kFourCCDx10 || get32(s, 4 + 124) != kDxgiR16G16B16A16Float)
        return Error{"DDS is not a DX10 RGBA16F texture"};
    if (!(get32(s, 4 + 108) & kCaps2Cubemap) || (get32(s, 4 + 108) & kCaps2AllFaces) != kCaps2AllFaces)
        return Error{"DDS is not a cube map with all six faces"};
    const std::uint32_t height = get32(s, 12), width = get32(s, 16);
    const std::uint32_t mips = std::max<std::uint32_t>(1, get32(s, 28));
    if (width != height || !isPowerOfTwo(int(std::min<std::uint32_t>(width, 1u << 30))) ||
        mips > std::uint32_t(fullMipCount(int(width))))
        return Error{fmt::format("DDS cube {}x{} with {} mips is not a square power-of-two chain", width,
                                 height, mips)};
    CubeMap cube = CubeMap::zeros(int(width), int(mips));
    size_t at = kDataOffset;
    size_t need = at;
    for (const CubeLevel& l : cube.levels)
        need += size_t(kCubeFaces) * size_t(l.size) * size_t(l.size) * 8;
    if (s.size() < need) return Error{fmt::format("DDS is truncated: {} bytes, {} needed", s.size(), need)};
    for (int f = 0; f < kCubeFaces; ++f)
        for (CubeLevel& level : cube.levels) {
            std::vector<float>& face = level.faces[size_t(f)];
            for (size_t i = 0; i < face.size() / 3; ++i) {
                for (int c = 0; c < 4; ++c) {
                    Imath::half h;
                    h.setBits(std::uint16_t(std::uint8_t(s[at]) | (std::uint8_t(s[at + 1]) << 8)));
                    at += 2;
                    if (c < 3) face[3 * i + size_t(c)] = float(h);
                }
            }
        }
    return cube;
}

} // namespace burnish
