// Built-in procedural normal maps: the studio opens on one, and tests and benchmarks use them when
// no file is given. Deterministic (same kind and size → same normals on every machine), tileable
// (wrap borders are seamless), and rich in sub-pixel detail, so they alias when minified.
#pragma once

#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/util/result.h>

#include <string_view>
#include <vector>

namespace burnish {

enum class SampleMapKind {
    /// Overlapping round dents of several sizes: an isotropic, hammered-metal look.
    Hammered,
    /// Fine parallel grooves along x with a little noise: brushed metal, strongly anisotropic.
    Brushed,
    /// Noise bumps over four octaves: a rough stone or plaster look.
    Bumpy,
};

const std::vector<SampleMapKind>& allSampleMaps();
std::string_view sampleMapName(SampleMapKind kind);
Result<SampleMapKind> sampleMapFromName(std::string_view name);

/// The sample as unit tangent-space normals (OpenGL green), size × size texels (size ≥ 1).
NormalMap makeSampleNormalMap(SampleMapKind kind = SampleMapKind::Hammered, int size = 512);

} // namespace burnish
