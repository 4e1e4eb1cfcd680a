#include <burnish/core/fresnel.h>
#include <burnish/core/geometric_aa.h>
#include <burnish/core/gloss.h>
#include <burnish/core/ndf.h>
#include <burnish/core/spherical_gaussian.h>
#include <burnish/core/visibility.h>
#include <burnish/core/quadrature.h>
#include <gtest/gtest.h>
TEST(Smoke, Furnace) {
    const double n = 10000;
    double I = burnish::integrateHemisphere([&](double c) { return burnish::blinnPhongNdf(c, n) * c; }, 1.0 / std::sqrt(n + 1));
    EXPECT_NEAR(I, 1.0, 1e-8);
}
