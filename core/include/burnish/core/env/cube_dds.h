// The environment's DDS cube: half-float RGBA with a DX10 header, every face's mip chain (the
// baked textures' DDS files are dds_writer.cpp's, through NVIDIA Texture Tools). This one is written
// by hand because Debian's nvtt 2.0.8 takes only 8-bit BGRA input and writes only integer RGB(A)
// masks and BCn with the legacy header: no half float, no DX10 header, which HDR radiance needs.
#pragma once

#include <burnish/core/env/cube.h>
#include <burnish/core/util/result.h>

#include <string>
#include <string_view>

namespace burnish {

/// Half-float RGBA (DXGI_FORMAT_R16G16B16A16_FLOAT) DDS of a cube with all its mips, DX10 header,
/// faces in GL order, each face's chain in order (the DDS cube layout); alpha 1. Values above the
/// half range are stored as 65504.
std::string encodeCubeDds(const CubeMap& cube);
/// Reads what encodeCubeDds writes (RGBA16F DX10 cube maps); clear errors for anything else.
Result<CubeMap> decodeCubeDds(std::string_view bytes);

} // namespace burnish
