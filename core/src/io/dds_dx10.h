// The DDS header with a DX10 extension for half-float RGBA (DXGI_FORMAT_R16G16B16A16_FLOAT), shared by
// the environment's cube (cube_dds.cpp) and the baked textures' rgba16f files (dds_writer.cpp):
// Debian's nvtt 2.0.8 writes neither half float nor the DX10 header.
#pragma once

#include <Imath/half.h>

#include <cstdint>
#include <string>

namespace burnish::dds {

inline void put32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        s.push_back(char((v >> (8 * i)) & 0xFF));
}

inline void putHalf(std::string& s, float v) {
    const std::uint16_t h = Imath::half(v).bits();
    s.push_back(char(h & 0xFF));
    s.push_back(char(h >> 8));
}

// Microsoft, "DDS_HEADER structure" and "DDS_HEADER_DXT10 structure" (Direct3D 10+ DDS files)
inline constexpr std::uint32_t kMagic = 0x20534444; // "DDS "
inline constexpr std::uint32_t kHeaderSize = 124;
inline constexpr std::uint32_t kCaps = 0x1, kHeight = 0x2, kWidth = 0x4, kPitch = 0x8;
inline constexpr std::uint32_t kPixelFormat = 0x1000, kMipMapCount = 0x20000;
inline constexpr std::uint32_t kDdpfFourCC = 0x4;
inline constexpr std::uint32_t kFourCCDx10 = 0x30315844; // "DX10"
inline constexpr std::uint32_t kCapsComplex = 0x8, kCapsTexture = 0x1000, kCapsMipMap = 0x400000;
inline constexpr std::uint32_t kCaps2Cubemap = 0x200, kCaps2AllFaces = 0xFC00; // +X..−Z face bits
inline constexpr std::uint32_t kDxgiR16G16B16A16Float = 10;
inline constexpr std::uint32_t kD3d10ResourceTexture2D = 3;
inline constexpr std::uint32_t kResourceMiscTextureCube = 0x4;
inline constexpr size_t kDataOffset = 4 + kHeaderSize + 20;

/// The magic, header and DX10 header of an RGBA16F 2D texture or cube with `mips` levels.
inline std::string rgba16fHeader(std::uint32_t width, std::uint32_t height, std::uint32_t mips, bool cube) {
    std::string s;
    put32(s, kMagic);
    put32(s, kHeaderSize);
    put32(s, kCaps | kHeight | kWidth | kPitch | kPixelFormat | kMipMapCount);
    put32(s, height);
    put32(s, width);
    put32(s, width * 8); // pitch: 4 half channels per texel
    put32(s, 0);         // depth
    put32(s, mips);
    for (int i = 0; i < 11; ++i)
        put32(s, 0); // reserved
    put32(s, 32);    // DDS_PIXELFORMAT size
    put32(s, kDdpfFourCC);
    put32(s, kFourCCDx10);
    for (int i = 0; i < 5; ++i)
        put32(s, 0); // RGB bit count and masks: unused with a FourCC
    put32(s, kCapsComplex | kCapsTexture | (mips > 1 ? kCapsMipMap : 0));
    put32(s, cube ? kCaps2Cubemap | kCaps2AllFaces : 0);
    put32(s, 0); // caps3
    put32(s, 0); // caps4
    put32(s, 0); // reserved2
    put32(s, kDxgiR16G16B16A16Float);
    put32(s, kD3d10ResourceTexture2D);
    put32(s, cube ? kResourceMiscTextureCube : 0);
    put32(s, 1); // array size
    put32(s, 0); // miscFlags2: alpha mode unknown
    return s;
}

} // namespace burnish::dds
