// A paint brush by its four settings, for the core and studio paint tests.
#pragma once

#include <burnish/core/bake/paint.h>

namespace burnish::test {

inline Brush brushOf(double radius, double hardness, double opacity, float value) {
    Brush b;
    b.radius = radius;
    b.hardness = hardness;
    b.opacity = opacity;
    b.value = value;
    return b;
}

} // namespace burnish::test
