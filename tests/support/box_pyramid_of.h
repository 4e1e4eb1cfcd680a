// A test map with its box-filtered, wrapping normal pyramid (the footprints the mixture fits and
// evaluate measures); the pyramid shares the map.
#pragma once

#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/prefilter/normal_pyramid.h>

#include <memory>
#include <utility>

namespace burnish::test {

struct Built {
    std::shared_ptr<NormalMap> map;
    NormalPyramid pyramid;
};

inline Built build(NormalMap map) {
    auto shared = std::make_shared<NormalMap>(std::move(map));
    NormalPyramid p = NormalPyramid::build(shared, {BorderMode::Wrap, FilterKernel::Box});
    return {shared, std::move(p)};
}

} // namespace burnish::test
