// What an isotropic lobe looks like under the BRDF an engine shades with, and the light/view pairs it
// is measured over: the common ground of evaluate's ground truth and of the fitted one-lobe roughness
// (prefilter/fitted_lobe.h), which must judge a lobe the same way.
#pragma once

#include <burnish/core/shading/ggx_specular.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/numeric.h>
#include <burnish/core/util/result.h>

#include <glm/vec3.hpp>

#include <algorithm>
#include <string_view>
#include <vector>

namespace burnish {

/// The specular BRDF a lobe is shaded with. BlinnPhong: D_s(n·h)·max(0, n·l), the reference texts'
/// normalized Blinn-Phong NDF and no visibility term. Ggx: ggxSpecularTerm with α² = 2/(s+2), what
/// every roughness preset's engine (glTF clients, Unreal, Unity, Godot, Filament) shades.
enum class Brdf { BlinnPhong, Ggx };
/// "blinn-phong" or "ggx".
std::string_view brdfName(Brdf brdf);
Result<Brdf> brdfFromName(std::string_view name);

/// The value of an isotropic lobe of power p about normal n for one light/view pair, from the
/// cosines n·h, n·l and n·v, under `brdf`. Finite and >= 0 for every input.
template <class T> inline T isotropicLobeShading(Brdf brdf, T NoH, T NoL, T NoV, T p) {
    if (brdf == Brdf::Ggx) return ggxSpecularTerm(NoH, NoL, NoV, ggxAlphaFromPower(p));
    return blinnPhongNdf(NoH, p) * std::max(NoL, T(0));
}

/// One light/view pair in tangent space (z the macro normal) and its half vector.
struct DirectionPair {
    glm::dvec3 l;
    glm::dvec3 v;
    glm::dvec3 h;
};

/// A set of light/view pairs: the view at viewAngleDeg from the macro normal (azimuth 0); half
/// vectors at the polar angles halfAnglesDeg with `azimuths` evenly spaced azimuths (one at 0, one
/// only at θh = 0); pairs whose light is within horizonDeg of the horizon dropped. The defaults are
/// evaluate's, and the fitted lobe's.
struct DirectionSet {
    double viewAngleDeg = 30.0;
    std::vector<double> halfAnglesDeg{0.0, 2.5, 5.0, 10.0, 15.0, 20.0, 30.0};
    int azimuths = 8;
    double horizonDeg = 3.0;
};
/// The pairs of a set, in a fixed order.
std::vector<DirectionPair> directionPairs(const DirectionSet& set);

} // namespace burnish
