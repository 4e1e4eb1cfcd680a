#include <burnish/core/methods.h>

#include <burnish/core/gloss.h>
#include <burnish/core/ndf.h>

#include <glm/geometric.hpp>

#include <cmath>

namespace burnish {

namespace {

struct MethodInfo {
    Method method;
    std::string_view name;
    std::string_view description;
};

const MethodInfo kMethods[] = {
    {Method::Naive, "naive", "renormalized mean normal, base power unchanged (the too-shiny baseline)"},
    {Method::Toksvig, "toksvig",
     "run-time Toksvig: p = s|Na|/(|Na| + s(1-|Na|)) from the unnormalized mean normal"},
    {Method::ToksvigMap, "toksvig-map",
     "baked 8-bit Toksvig factor for a fixed power, converted to s at run time"},
    {Method::VarianceToGloss, "variance-to-gloss",
     "projected variance added to gloss as 1/(n+1): p = 1/(v + 1/(s+1)) - 1"},
    {Method::Lean, "lean",
     "slope-space Gaussian, Sigma = M - BB^T + I/s about the normal of slope B (5 values)"},
    {Method::Clean, "clean",
     "isotropic slope-space Gaussian, variance ((Mxx+Myy) - |B|^2)/2 + 1/s (3 values)"},
    {Method::Vmf, "vmf",
     "von Mises-Fisher: kappa = (3r - r^3)/(1 - r^2), 1/p = 1/s + 1/kappa (Filament/Godot/Unity form)"},
};

const MethodInfo& info(Method method) {
    for (const auto& m : kMethods)
        if (m.method == method) return m;
    return kMethods[0];
}

glm::vec3 normalOfSlope(const glm::dvec2& b) {
    return glm::vec3(glm::normalize(glm::dvec3(b.x, b.y, 1.0)));
}

} // namespace

const std::vector<Method>& allMethods() {
    static const std::vector<Method> methods = [] {
        std::vector<Method> v;
        for (const auto& m : kMethods)
            v.push_back(m.method);
        return v;
    }();
    return methods;
}

std::string_view methodName(Method method) {
    return info(method).name;
}
std::string_view methodDescription(Method method) {
    return info(method).description;
}

Result<Method> methodFromName(std::string_view name) {
    for (const auto& m : kMethods)
        if (m.name == name) return m.method;
    std::string known;
    for (const auto& m : kMethods)
        known += (known.empty() ? "" : ", ") + std::string(m.name);
    return Error{"unknown method '" + std::string(name) + "' (known: " + known + ")"};
}

double vmfKappa(double r) {
    r = r > 0.0 ? std::min(r, 1.0) : 0.0;
    const double oneMinusR2 = (1.0 - r) * (1.0 + r);
    // r = 1 (all normals equal) is the limit κ → ∞: the lobe keeps the base power.
    if (!(oneMinusR2 > 0.0)) return kMaxPower;
    return std::clamp(r * (3.0 - r * r) / oneMinusR2, 0.0, kMaxPower);
}

double methodPower(Method method, const NormalMoments& moments, double s, const MethodParams& params) {
    if (method == Method::Lean || method == Method::Clean)
        return methodLobe(method, moments, s, params).power;
    s = std::max(clampPower(s), kMinBasePower);
    switch (method) {
    case Method::Naive:
        return s;
    case Method::Toksvig:
        return toksvigPower(double(moments.lengthNa()), s);
    case Method::ToksvigMap: {
        // The map stores f_t for the fixed power in 8 bits.
        const double ft =
            std::round(toksvigFactor(double(moments.lengthNa()), params.toksvigMapPower) * 255.0) / 255.0;
        return convertToksvigFactor(ft, params.toksvigMapPower, s) * s;
    }
    case Method::VarianceToGloss:
        return varianceToGlossPower(moments.projectedVariance(), s);
    case Method::Vmf: {
        const double kappa = vmfKappa(double(moments.lengthNa()));
        return kappa > 0.0 ? clampPower(1.0 / (1.0 / s + 1.0 / kappa)) : 0.0;
    }
    case Method::Lean:
    case Method::Clean:
        break;
    }
    return s;
}

TexelLobe methodLobe(Method method, const NormalMoments& moments, double s, const MethodParams& params) {
    TexelLobe lobe;
    if (method != Method::Lean && method != Method::Clean) {
        lobe.normal = moments.meanDirection();
        lobe.power = methodPower(method, moments, s, params);
        return lobe;
    }
    switch (method) {
    case Method::Lean:
    case Method::Clean: {
        lobe.slopeGaussian = true;
        lobe.slopeMean = glm::dvec2(moments.slope);
        lobe.normal = normalOfSlope(lobe.slopeMean);
        const double invS = slopeInverseBasePower(s);
        if (method == Method::Lean) {
            lobe.slopeCov = leanSlopeCovariance(moments, s);
        } else {
            const double sigma2 = 0.5 * (double(moments.slopeCov[0]) + double(moments.slopeCov[1])) + invS;
            lobe.slopeCov = {sigma2, sigma2, 0.0};
        }
        lobe.power =
            powerFromVariance(0.5 * (lobe.slopeCov[0] + lobe.slopeCov[1]), VarianceConvention::InversePower);
        break;
    }
    default: // the isotropic methods, above
        break;
    }
    return lobe;
}

unsigned momentsNeeded(Method method) {
    switch (method) {
    case Method::Naive:
    case Method::Toksvig:
    case Method::ToksvigMap:
    case Method::Vmf:
        return kMomentsMean;
    case Method::VarianceToGloss:
        return kMomentsCov;
    case Method::Lean:
    case Method::Clean:
        return kMomentsSlope;
    }
    return kMomentsAll;
}

double slopeGaussianNdf(const glm::dvec3& h, const glm::dvec2& mean, const std::array<double, 3>& cov) {
    if (!(h.z > 0.0)) return 0.0;
    const double det = cov[0] * cov[1] - cov[2] * cov[2];
    // Σ = C + I/s with C positive semi-definite, so det >= 1/s² > 0; guard rounding anyway.
    if (!(det > 0.0)) return 0.0;
    const double dx = h.x / h.z - mean.x;
    const double dy = h.y / h.z - mean.y;
    const double e = (dx * dx * cov[1] + dy * dy * cov[0] - 2.0 * dx * dy * cov[2]) / det;
    const double hz2 = h.z * h.z;
    // exp(−e/2) underflows to 0 long before 1/h_z⁴ overflows a double.
    return std::exp(-0.5 * e) / (2.0 * kPi<double> * std::sqrt(det) * hz2 * hz2);
}

double methodNdf(const TexelLobe& lobe, const glm::dvec3& h) {
    if (lobe.slopeGaussian) return slopeGaussianNdf(h, lobe.slopeMean, lobe.slopeCov);
    return blinnPhongNdf(glm::dot(glm::dvec3(lobe.normal), h), lobe.power);
}

} // namespace burnish
