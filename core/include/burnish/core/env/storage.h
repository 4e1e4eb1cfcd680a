// Storing environment cubes as files: one half-float OpenEXR per face and mip (the DDS cube is
// io/cube_dds.h), and the scale an intensity applies before storage.
#pragma once

#include <burnish/core/env/cube.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/result.h>

#include <glm/vec3.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace burnish {

/// The file of face `face` at mip `mip` in the EXR scheme: "<stem>_m<k>_<face>.exr", or
/// "<stem>_<face>.exr" for a single-level cube.
std::string cubeExrFaceName(const CubeMap& cube, const std::string& stem, int mip, int face);
/// A face's RGB values as half-float storage holds them: non-finite values 0, the rest clamped to
/// [0, kHalfMax].
std::vector<float> storedCubeFace(const CubeMap& cube, int mip, int face);
/// Stages one half-float RGB OpenEXR per face and mip (cubeExrFaceName, storedCubeFace) into a
/// file set, which commits them with the rest of the set (files.h).
Status stageCubeExrFaces(const CubeMap& cube, const std::string& stem, FileSet& set);
/// The largest finite half float; larger values are stored as this.
inline constexpr float kHalfMax = 65504.0f;

/// Multiplies every texel of every level by `scale` per channel.
void scaleCube(CubeMap& cube, const glm::dvec3& scale);

} // namespace burnish
