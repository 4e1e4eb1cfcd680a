// A normal map from a function of the texel, each normal normalized: the small synthetic maps of the
// core tests (checkers, grooves, tilts).
#pragma once

#include <burnish/core/prefilter/normal_map.h>

#include <glm/geometric.hpp>

#include <functional>
#include <vector>

namespace burnish::test {

inline NormalMap mapOf(int w, int h, const std::function<glm::vec3(int, int)>& normal) {
    std::vector<glm::vec3> n;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            n.push_back(glm::normalize(normal(x, y)));
    return makeNormalMap(w, h, std::move(n));
}

} // namespace burnish::test
