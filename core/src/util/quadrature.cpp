#include <burnish/core/util/quadrature.h>

#include <burnish/core/util/numeric.h>

#include <boost/math/quadrature/gauss_kronrod.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace burnish {

namespace {

// Breakpoints 0, w/4, w/2, w, 2w, 4w, ... up to thetaMax: each panel holds a lobe feature of
// comparable scale, so the adaptive rule never has to find a narrow peak inside a wide panel.
std::vector<double> lobeBreakpoints(double width, double thetaMax) {
    std::vector<double> points{0.0};
    width = std::clamp(width, 1e-9, thetaMax);
    for (double t = width / 4.0; t < thetaMax; t *= 2.0)
        points.push_back(t);
    points.push_back(thetaMax);
    return points;
}

double integrateTheta(const std::function<double(double)>& f, double width, double thetaMax, double tol) {
    const auto points = lobeBreakpoints(width, thetaMax);
    double sum = 0.0;
    for (size_t i = 0; i + 1 < points.size(); ++i)
        sum +=
            integrate([&](double t) { return f(std::cos(t)) * std::sin(t); }, points[i], points[i + 1], tol);
    return 2.0 * kPi<double> * sum;
}

} // namespace

double integrate(const std::function<double(double)>& f, double a, double b, double tol) {
    if (!(b > a)) return 0.0;
    double error = 0.0;
    return boost::math::quadrature::gauss_kronrod<double, 15>::integrate(f, a, b, 15, tol, &error);
}

double integrateHemisphere(const std::function<double(double)>& f, double width, double tol) {
    return integrateTheta(f, width, kPi<double> / 2.0, tol);
}

double integrateSphere(const std::function<double(double)>& f, double width, double tol) {
    return integrateTheta(f, width, kPi<double>, tol);
}

} // namespace burnish
