#include <burnish/core/shading/lobe_shading.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <string>

namespace burnish {

std::string_view brdfName(Brdf brdf) {
    return brdf == Brdf::Ggx ? "ggx" : "blinn-phong";
}

Result<Brdf> brdfFromName(std::string_view name) {
    if (name == "ggx") return Brdf::Ggx;
    if (name == "blinn-phong") return Brdf::BlinnPhong;
    return Error{"unknown BRDF '" + std::string(name) + "' (known: blinn-phong, ggx)"};
}

std::vector<DirectionPair> directionPairs(const DirectionSet& set) {
    std::vector<DirectionPair> pairs;
    const double thetaV = radians(set.viewAngleDeg);
    const glm::dvec3 v(std::sin(thetaV), 0.0, std::cos(thetaV));
    const double minLz = std::sin(radians(set.horizonDeg));
    for (double thetaDeg : set.halfAnglesDeg) {
        const double thetaH = radians(thetaDeg);
        // At θh = 0 every azimuth gives the same half vector: count it once.
        const int count = thetaDeg == 0.0 ? 1 : std::max(set.azimuths, 1);
        for (int j = 0; j < count; ++j) {
            const double phi = 2.0 * kPi<double> * j / count;
            const glm::dvec3 h(std::sin(thetaH) * std::cos(phi), std::sin(thetaH) * std::sin(phi),
                               std::cos(thetaH));
            const glm::dvec3 l = 2.0 * glm::dot(v, h) * h - v;
            if (l.z < minLz) continue;
            pairs.push_back({glm::normalize(l), v, h});
        }
    }
    return pairs;
}

} // namespace burnish
