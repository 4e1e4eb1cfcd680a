// Random normal maps for the core tests.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <random>
#include <vector>

namespace burnish::test {

/// `count` unit normals whose slopes are independent N(0, sigma) in x and y (seeded: the same on every
/// run), normalized in double.
inline std::vector<glm::vec3> gaussianSlopes(int count, double sigma, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, sigma);
    std::vector<glm::vec3> n(static_cast<size_t>(count));
    for (auto& v : n)
        v = glm::vec3(glm::normalize(glm::dvec3(g(rng), g(rng), 1.0)));
    return n;
}

} // namespace burnish::test
