// Detail normal maps: the reoriented blend that lays a detail normal over a base normal, the
// variance rule that folds the detail's roughness into the base power, and the bake of a detail
// texture [x, y, 0, variance] whose normal fades out, and whose variance fades to the map's
// constant total, over the detail map's mips.
#pragma once

#include <burnish/core/bake/bake.h>
#include <burnish/core/prefilter/normal_pyramid.h>
#include <burnish/core/util/result.h>

#include <glm/vec3.hpp>

namespace burnish {

/// Reoriented normal mapping: rotates the detail normal from +z onto the base normal. Both are
/// unit tangent-space normals (z up); the result is unit. A flat detail returns the base, a flat
/// base returns the detail.
// Barré-Brisebois & Hill 2012, "Blending in Detail": t = b + (0,0,1), u = d·(−1,−1,1), r = t·(t·u)/t.z − u
glm::vec3 reorientedBlend(const glm::vec3& base, const glm::vec3& detail);

/// The base power with the detail map's variance added: 1/s' = 1/s + σ² (σ² ≥ 0), finite for all inputs.
// Baker & Hill 2012, "Rock-Solid Shading", detail normal maps
double addVarianceToPower(double s, double sigma2);

struct DetailOptions {
    PyramidOptions pyramid{BorderMode::Wrap, FilterKernel::Tent};
    /// Between these mips of the detail map the stored normal fades to flat and the stored
    /// variance to the map's constant total variance; from fadeEndMip on both are constant.
    int fadeStartMip = 3;
    int fadeEndMip = 6;
    /// Levels stored (0 = all, down to 1×1; more than the chain holds stores the whole chain).
    /// A short chain is the first levels of the full one, value for value.
    int mipCount = 0;
};

struct DetailBake {
    /// Role "detail": [x, y, 0, variance], variance by Toksvig's estimate (1 − |Na|)/|Na| of the
    /// filtered footprint (the 1/n convention, as the rule 1/s' = 1/s + σ² needs), stored linearly
    /// so hardware filtering averages it correctly.
    BakedTexture texture;
    /// The whole map's variance: what the shader adds where the detail map is no longer sampled.
    double constantVariance = 0.0;
};

/// Bakes the detail texture; fails on bad fade mips (start > end or negative) or a negative mip count.
Result<DetailBake> bakeDetail(const NormalMap& detail, const DetailOptions& options = {});

/// The detail texture of a width×height detail map without its texels (role, channels, decode
/// names and mip sizes; the variance scale is a flat map's): what export's planExport needs to
/// name the detail file before anything is baked.
Result<BakedTexture> detailShape(int width, int height, const DetailOptions& options = {});

} // namespace burnish
