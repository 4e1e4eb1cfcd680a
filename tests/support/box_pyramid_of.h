// A test map with its box-filtered, wrapping normal pyramid (the footprints the mixture fits and
// evaluate measures); the pyramid shares the map.
#pragma once

#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/prefilter/normal_pyramid.h>

#include <cstring>
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

/// Whether two mixtures of `pyramid`'s map hold the same lobes, bit for bit, on levels 1..lastLevel.
inline bool sameLobesBitForBit(const MixturePyramid& a, const MixturePyramid& b, const NormalPyramid& pyramid,
                               int lastLevel) {
    for (int level = 1; level <= lastLevel; ++level) {
        const PyramidLevel& l = pyramid.level(level);
        for (int y = 0; y < l.height; ++y)
            for (int x = 0; x < l.width; ++x) {
                const LobeMixture ma = a.at(level, x, y), mb = b.at(level, x, y);
                if (ma.count != mb.count ||
                    std::memcmp(ma.lobes.data(), mb.lobes.data(), sizeof(ma.lobes)) != 0)
                    return false;
            }
    }
    return true;
}

} // namespace burnish::test
