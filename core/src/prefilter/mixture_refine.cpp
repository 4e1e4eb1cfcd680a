#include <burnish/core/prefilter/mixture_refine.h>

#include <burnish/core/util/numeric.h>

#include <Eigen/Core>
#include <tbb/parallel_for.h>
#include <unsupported/Eigen/NonLinearOptimization>

#include <algorithm>
#include <array>
#include <cmath>

namespace burnish {

namespace {

// Level 1 keeps its moment fit: K lobes for four normals are close to exact, and refined they
// erred more on evaluate's pairs than fitted (tread plate, s = 256: 0.0066 -> 0.0100).
constexpr int kFirstRefinedLevel = 2;

// Levenberg-Marquardt's budget of residual evaluations a texel. Tread plate, s = 1024, mip 4: the
// moment fit errs 0.081; 10 evaluations 0.024, 20 0.020; 800 (convergence) about 0.018 at 40
// times the cost.
constexpr int kMaxEvaluations = 16;

// The energy's residual: kShadedFitEnergyWeight/√n times the sum of the pairs' errors.
constexpr double kEnergyWeight = kShadedFitEnergyWeight;

// The light for view v mirrored about h (below the horizon where its z is negative).
glm::dvec3 mirrored(const glm::dvec3& v, const glm::dvec3& h) {
    return 2.0 * glm::dot(v, h) * h - v;
}

// What the residuals and their derivatives need of one lobe, decoded from its six parameters: log
// share (before normalising), mean slope, and the Cholesky factor L = [[a, 0], [b, c]] of its
// covariance above the base variance: Σ = v·I + LLᵀ.
struct LobeState {
    double share = 0.0;
    double mx = 0.0, my = 0.0;
    double a = 0.0, b = 0.0, c = 0.0;
    double ixx = 0.0, iyy = 0.0, ixy = 0.0; // Σ⁻¹
    double coef = 0.0;                      // 1/(2π√det Σ)
    glm::dvec3 n{0.0, 0.0, 1.0};            // the normal of the mean slope
    double invLen = 1.0;                    // 1/|(mx, my, 1)|
};

// The residuals share·D(h)·max(0, n·l) summed over the lobes minus the truth, over the mean truth,
// at each training pair; analytic Jacobian.
struct ShadedResiduals {
    using Scalar = double;
    enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
    using InputType = Eigen::VectorXd;
    using ValueType = Eigen::VectorXd;
    using JacobianType = Eigen::MatrixXd;

    const std::vector<DirectionPair>* directions = nullptr;
    const std::vector<double>* truth = nullptr;
    int lobes = 0;
    double v = 0.0;     // the base variance
    double scale = 1.0; // 1 / the mean truth
    double energyWeight = 0.0;

    int inputs() const { return 6 * lobes; }
    // One residual a pair, and the energy's: energyWeight/√n times their sum.
    int values() const { return int(directions->size()) + 1; }

    std::array<LobeState, kMaxMixtureLobes> decode(const Eigen::VectorXd& p) const {
        std::array<LobeState, kMaxMixtureLobes> out{};
        double top = -std::numeric_limits<double>::infinity();
        for (int i = 0; i < lobes; ++i)
            top = std::max(top, p[6 * i]);
        double total = 0.0;
        for (int i = 0; i < lobes; ++i)
            total += std::exp(p[6 * i] - top);
        for (int i = 0; i < lobes; ++i) {
            LobeState& s = out[size_t(i)];
            s.share = std::exp(p[6 * i] - top) / total;
            s.mx = p[6 * i + 1], s.my = p[6 * i + 2];
            s.a = p[6 * i + 3], s.b = p[6 * i + 4], s.c = p[6 * i + 5];
            const double sxx = v + s.a * s.a, syy = v + s.b * s.b + s.c * s.c, sxy = s.a * s.b;
            const double det = sxx * syy - sxy * sxy; // >= v² > 0
            s.ixx = syy / det, s.iyy = sxx / det, s.ixy = -sxy / det;
            s.coef = 1.0 / (2.0 * kPi<double> * std::sqrt(det));
            const glm::dvec3 u(s.mx, s.my, 1.0);
            s.invLen = 1.0 / glm::length(u);
            s.n = u * s.invLen;
        }
        return out;
    }

    int operator()(const Eigen::VectorXd& p, Eigen::VectorXd& r) const {
        const auto state = decode(p);
        for (size_t k = 0; k < directions->size(); ++k) {
            const DirectionPair& d = (*directions)[k];
            double m = 0.0;
            if (d.h.z > 0.0) {
                const double tx = d.h.x / d.h.z, ty = d.h.y / d.h.z, hz2 = d.h.z * d.h.z;
                for (int i = 0; i < lobes; ++i) {
                    const LobeState& s = state[size_t(i)];
                    const double dx = tx - s.mx, dy = ty - s.my;
                    const double q = dx * dx * s.ixx + dy * dy * s.iyy + 2.0 * dx * dy * s.ixy;
                    const double nl = std::max(0.0, glm::dot(s.n, d.l));
                    m += s.share * s.coef * std::exp(-0.5 * q) / (hz2 * hz2) * nl;
                }
            }
            const double e = (m - (*truth)[k]) * scale;
            r[Eigen::Index(k)] = std::isfinite(e) ? e : 1e150;
        }
        const Eigen::Index n = Eigen::Index(directions->size());
        r[n] = energyWeight / std::sqrt(double(n)) * r.head(n).sum();
        return 0;
    }

    int df(const Eigen::VectorXd& p, Eigen::MatrixXd& jac) const {
        const auto state = decode(p);
        jac.setZero();
        std::array<double, kMaxMixtureLobes> value{};
        for (size_t k = 0; k < directions->size(); ++k) {
            const DirectionPair& d = (*directions)[k];
            if (!(d.h.z > 0.0)) continue;
            const Eigen::Index row = Eigen::Index(k);
            const double tx = d.h.x / d.h.z, ty = d.h.y / d.h.z, hz2 = d.h.z * d.h.z;
            double m = 0.0;
            for (int i = 0; i < lobes; ++i) {
                const LobeState& s = state[size_t(i)];
                const double dx = tx - s.mx, dy = ty - s.my;
                const double q = dx * dx * s.ixx + dy * dy * s.iyy + 2.0 * dx * dy * s.ixy;
                const double g = s.coef * std::exp(-0.5 * q) / (hz2 * hz2);
                const double nlRaw = glm::dot(s.n, d.l);
                const double nl = std::max(0.0, nlRaw);
                const double val = g * nl;
                value[size_t(i)] = val;
                m += s.share * val;
                // e = Σ⁻¹d: ∂g/∂μ = g·e; ∂ log g/∂Σ = G = ½(eeᵀ − Σ⁻¹).
                const double ex = s.ixx * dx + s.ixy * dy, ey = s.ixy * dx + s.iyy * dy;
                const double gxx = 0.5 * (ex * ex - s.ixx), gyy = 0.5 * (ey * ey - s.iyy),
                             gxy = 0.5 * (ex * ey - s.ixy);
                // ∂(n·l)/∂μ = (l − (n·l)n)_{x,y}/|u| where n·l > 0.
                const double cx = nlRaw > 0.0 ? (d.l.x - nlRaw * s.n.x) * s.invLen : 0.0;
                const double cy = nlRaw > 0.0 ? (d.l.y - nlRaw * s.n.y) * s.invLen : 0.0;
                const double w = s.share * scale;
                const Eigen::Index c0 = 6 * i;
                jac(row, c0 + 1) = w * (val * ex + g * cx);
                jac(row, c0 + 2) = w * (val * ey + g * cy);
                jac(row, c0 + 3) = w * val * (2.0 * s.a * gxx + 2.0 * s.b * gxy);
                jac(row, c0 + 4) = w * val * (2.0 * s.b * gyy + 2.0 * s.a * gxy);
                jac(row, c0 + 5) = w * val * (2.0 * s.c * gyy);
            }
            // Softmax shares: ∂m/∂α_j = share_j (value_j − m).
            for (int i = 0; i < lobes; ++i)
                jac(row, 6 * i) = state[size_t(i)].share * (value[size_t(i)] - m) * scale;
        }
        const Eigen::Index n = Eigen::Index(directions->size());
        jac.row(n) = energyWeight / std::sqrt(double(n)) * jac.topRows(n).colwise().sum();
        return 0;
    }
};

// The half vector whose slope is t.
glm::dvec3 halfOfSlope(double tx, double ty) {
    return glm::normalize(glm::dvec3(tx, ty, 1.0));
}

// A light/view pair for half vector h: the view 30° from the normal across the lobe's azimuth
// mirrored about h, or the view along h itself where that light falls below 3° above the horizon.
DirectionPair pairForHalf(const glm::dvec3& h) {
    const double minLz = std::sin(radians(3.0));
    const double tv = radians(30.0);
    const glm::dvec3 v(0.0, std::sin(tv), std::cos(tv));
    glm::dvec3 l = mirrored(v, h);
    if (l.z >= minLz) return {glm::normalize(l), v, h};
    return {h, h, h};
}

// Per lobe of `fitted`, nine half vectors on its covariance's axes at 0, ±1 and ±2 standard
// deviations from its mean (those whose light stays above the horizon).
void lobeAxisPairs(const LobeMixture& fitted, double v, std::vector<DirectionPair>& out) {
    for (int i = 0; i < fitted.count; ++i) {
        const LobeMoments& l = fitted.lobes[size_t(i)];
        if (!(l.w > 0.0)) continue;
        const glm::dvec2 mean = l.mean();
        const std::array<double, 3> cov = l.covariance(v);
        // The eigen decomposition of the 2×2 covariance.
        const double tr = 0.5 * (cov[0] + cov[1]);
        const double dif = 0.5 * (cov[0] - cov[1]);
        const double root = std::sqrt(dif * dif + cov[2] * cov[2]);
        const double l1 = tr + root, l2 = std::max(tr - root, 0.0);
        const double angle = 0.5 * std::atan2(2.0 * cov[2], cov[0] - cov[1]);
        const glm::dvec2 e1(std::cos(angle), std::sin(angle)), e2(-e1.y, e1.x);
        const glm::dvec2 axes[2] = {e1 * std::sqrt(l1), e2 * std::sqrt(l2)};
        out.push_back(pairForHalf(halfOfSlope(mean.x, mean.y)));
        for (const glm::dvec2& axis : axes)
            for (double f : {-2.0, -1.0, 1.0, 2.0}) {
                const glm::dvec2 t = mean + f * axis;
                out.push_back(pairForHalf(halfOfSlope(t.x, t.y)));
            }
    }
}

// The finest normals of a footprint as three double arrays and their powers.
struct Footprint {
    std::vector<double> nx, ny, nz, power;

    void gather(const NormalMap& finest, const std::vector<double>* texelPowers, int x0, int x1, int y0,
                int y1) {
        nx.clear(), ny.clear(), nz.clear(), power.clear();
        for (int j = y0; j < y1; ++j)
            for (int i = x0; i < x1; ++i) {
                const glm::vec3 n = finest.at(i, j);
                nx.push_back(n.x), ny.push_back(n.y), nz.push_back(n.z);
                if (texelPowers)
                    power.push_back((*texelPowers)[size_t(j) * size_t(finest.width) + size_t(i)]);
            }
    }
    // The mean truth over the footprint at d.
    double meanTruth(double s, const DirectionPair& d, std::vector<double>& scratch) const {
        scratch.resize(nx.size());
        truthValues(Brdf::BlinnPhong, nx.data(), ny.data(), nz.data(), power.empty() ? nullptr : power.data(),
                    s, nx.size(), d, scratch.data());
        double sum = 0.0;
        for (double t : scratch)
            sum += t;
        return sum / double(std::max<size_t>(1, nx.size()));
    }
};

// Refines texel (level, x, y) given the sum of its footprint's truth at the fixed pairs.
class TexelRefiner {
public:
    TexelRefiner(MixturePyramid& mixture, const NormalPyramid& pyramid, double s,
                 const std::vector<double>* texelPowers, const std::vector<DirectionPair>& fixed)
        : m_mixture(mixture)
        , m_pyramid(pyramid)
        , m_s(s)
        , m_powers(texelPowers)
        , m_fixed(fixed) {}

    void refine(int level, int x, int y, const double* fixedSums) {
        const LobeMixture fitted = m_mixture.at(level, x, y);
        const PyramidLevel& l = m_pyramid.level(level);
        const double count = double(m_pyramid.footprintCount(level, x, y));
        m_directions = m_fixed;
        m_truth.resize(m_fixed.size());
        for (size_t d = 0; d < m_fixed.size(); ++d)
            m_truth[d] = fixedSums[d] / count;
        const size_t first = m_directions.size();
        lobeAxisPairs(fitted, m_mixture.minVariance(), m_directions);
        if (m_directions.size() > first) {
            m_footprint.gather(m_pyramid.finest(), m_powers, l.xStart[size_t(x)], l.xStart[size_t(x) + 1],
                               l.yStart[size_t(y)], l.yStart[size_t(y) + 1]);
            for (size_t d = first; d < m_directions.size(); ++d)
                m_truth.push_back(m_footprint.meanTruth(m_s, m_directions[d], m_scratch));
        }
        m_mixture.replace(level, x, y,
                          refineMixtureToTruth(fitted, m_directions, m_truth, m_mixture.minVariance()));
    }

private:
    MixturePyramid& m_mixture;
    const NormalPyramid& m_pyramid;
    double m_s;
    const std::vector<double>* m_powers;
    const std::vector<DirectionPair>& m_fixed;
    std::vector<DirectionPair> m_directions;
    std::vector<double> m_truth, m_scratch;
    Footprint m_footprint;
};

} // namespace

std::vector<DirectionPair> shadedFitDirections() {
    static const double kRings[] = {0.75, 2.25, 4.0,  6.0,  8.5,  11.5, 15.0,
                                    19.0, 24.0, 30.0, 37.0, 45.0, 55.0};
    static const double kViews[] = {10.0, 35.0, 60.0};
    constexpr int kAzimuths = 12;
    const double minLz = std::sin(radians(3.0));
    std::vector<DirectionPair> out;
    int ring = 0;
    for (double thetaDeg : kRings) {
        const double th = radians(thetaDeg);
        for (int j = 0; j < kAzimuths; ++j) {
            // Azimuths offset by 7° a ring, never on evaluate's multiples of 45°.
            const double phi = radians(15.0 + 30.0 * j + 7.0 * ring);
            const glm::dvec3 h(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th));
            // The view by turns; where the light would fall below the horizon limit, the next lower.
            for (int view = (ring + j) % 3; view >= 0; --view) {
                const double tv = radians(kViews[view]);
                const glm::dvec3 v(std::sin(tv), 0.0, std::cos(tv));
                const glm::dvec3 l = mirrored(v, h);
                if (l.z >= minLz) {
                    out.push_back({glm::normalize(l), v, h});
                    break;
                }
            }
        }
        ++ring;
    }
    return out;
}

LobeMixture refineMixtureToTruth(const LobeMixture& fitted, const std::vector<DirectionPair>& directions,
                                 const std::vector<double>& truth, double v) {
    std::array<int, kMaxMixtureLobes> slot{};
    int n = 0;
    double total = 0.0;
    for (int i = 0; i < fitted.count; ++i)
        if (fitted.lobes[size_t(i)].w > 0.0) slot[size_t(n++)] = i, total += fitted.lobes[size_t(i)].w;
    if (n == 0 || directions.size() < size_t(6 * n) || truth.size() != directions.size()) return fitted;
    double meanTruth = 0.0;
    for (double t : truth)
        meanTruth += t;
    meanTruth /= double(truth.size());
    if (!(meanTruth > 0.0) || !std::isfinite(meanTruth)) return fitted;

    Eigen::VectorXd p(6 * n);
    for (int i = 0; i < n; ++i) {
        const LobeMoments& l = fitted.lobes[size_t(slot[size_t(i)])];
        const glm::dvec2 mean = l.mean();
        const std::array<double, 3> cov = l.covariance(v);
        // Σ − v·I by Cholesky; a factor at 0 has no gradient, so each starts at least at 1e-3·√v.
        const double floor = 1e-3 * std::sqrt(v);
        const double a = std::max(std::sqrt(std::max(cov[0] - v, 0.0)), floor);
        const double b = cov[2] / a;
        const double c = std::max(std::sqrt(std::max(cov[1] - v - b * b, 0.0)), floor);
        p.segment(6 * i, 6) << std::log(l.w / total), mean.x, mean.y, a, b, c;
    }
    ShadedResiduals residuals;
    residuals.directions = &directions;
    residuals.truth = &truth;
    residuals.lobes = n;
    residuals.v = v;
    residuals.scale = 1.0 / meanTruth;
    residuals.energyWeight = kEnergyWeight;
    Eigen::VectorXd r(residuals.values());
    residuals(p, r);
    const double before = r.squaredNorm();
    if (!std::isfinite(before)) return fitted;

    Eigen::LevenbergMarquardt<ShadedResiduals> lm(residuals);
    lm.parameters.maxfev = kMaxEvaluations;
    lm.parameters.ftol = 1e-8;
    lm.parameters.xtol = 1e-8;
    Eigen::VectorXd refined = p;
    lm.minimize(refined);
    if (!refined.allFinite()) return fitted;
    residuals(refined, r);
    const double after = r.squaredNorm();
    if (!(after < before)) return fitted;

    const auto state = residuals.decode(refined);
    double kept = 0.0;
    for (int i = 0; i < n; ++i)
        if (state[size_t(i)].share >= 1e-4 && std::abs(state[size_t(i)].mx) < 1e3 &&
            std::abs(state[size_t(i)].my) < 1e3)
            kept += state[size_t(i)].share;
    if (!(kept > 0.0)) return fitted;
    LobeMixture out;
    out.count = fitted.count;
    for (int i = 0; i < n; ++i) {
        const LobeState& s = state[size_t(i)];
        LobeMoments& m = out.lobes[size_t(slot[size_t(i)])];
        if (!(s.share >= 1e-4) || !(std::abs(s.mx) < 1e3) || !(std::abs(s.my) < 1e3)) continue;
        const double w = total * s.share / kept;
        const double sxx = v + s.a * s.a, syy = v + s.b * s.b + s.c * s.c, sxy = s.a * s.b;
        m.w = w;
        m.bx = w * s.mx, m.by = w * s.my;
        m.mxx = w * (sxx + s.mx * s.mx), m.myy = w * (syy + s.my * s.my), m.mxy = w * (sxy + s.mx * s.my);
    }
    return out;
}

void refineMixturePyramid(MixturePyramid& mixture, const NormalPyramid& pyramid, double s,
                          const std::vector<double>* texelPowers) {
    const int last = mixture.levelCount() - 1;
    if (last < 1) return;
    const std::vector<DirectionPair> fixed = shadedFitDirections();
    const size_t T = fixed.size();
    const NormalMap& finest = pyramid.finest();
    // Levels 1..tile depth first under each texel of level `tile` (its footprint's truth at the
    // fixed pairs computed once, from its finest normals, and summed up the levels); the levels
    // above from the sums of the level below.
    const int tile = std::min(last, 4);
    const PyramidLevel& tl = pyramid.level(tile);
    std::vector<double> below(size_t(tl.width) * size_t(tl.height) * T);
    tbb::parallel_for(0, tl.height, [&](int ty) {
        TexelRefiner refiner(mixture, pyramid, s, texelPowers, fixed);
        Footprint tileNormals;
        std::vector<double> values; // [d][finest texel of the tile]
        // Per level 1..tile, the sums at the fixed pairs of one texel under construction.
        std::vector<std::vector<double>> sums(size_t(tile) + 1, std::vector<double>(T));
        for (int tx = 0; tx < tl.width; ++tx) {
            const int x0 = tl.xStart[size_t(tx)], x1 = tl.xStart[size_t(tx) + 1];
            const int y0 = tl.yStart[size_t(ty)], y1 = tl.yStart[size_t(ty) + 1];
            const int tw = x1 - x0;
            tileNormals.gather(finest, texelPowers, x0, x1, y0, y1);
            const size_t count = tileNormals.nx.size();
            values.resize(T * count);
            for (size_t d = 0; d < T; ++d)
                truthValues(Brdf::BlinnPhong, tileNormals.nx.data(), tileNormals.ny.data(),
                            tileNormals.nz.data(),
                            tileNormals.power.empty() ? nullptr : tileNormals.power.data(), s, count,
                            fixed[d], values.data() + d * count);
            // The sums of texel (k, x, y), refined on the way up.
            auto visit = [&](auto&& self, int k, int x, int y) -> void {
                std::vector<double>& out = sums[size_t(k)];
                std::fill(out.begin(), out.end(), 0.0);
                const PyramidLevel& l = pyramid.level(k);
                for (int j = l.yChild[size_t(y)]; j < l.yChild[size_t(y) + 1]; ++j)
                    for (int i = l.xChild[size_t(x)]; i < l.xChild[size_t(x) + 1]; ++i) {
                        if (k == 1) {
                            const size_t at = size_t(j - y0) * size_t(tw) + size_t(i - x0);
                            for (size_t d = 0; d < T; ++d)
                                out[d] += values[d * count + at];
                            continue;
                        }
                        self(self, k - 1, i, j);
                        const std::vector<double>& child = sums[size_t(k - 1)];
                        for (size_t d = 0; d < T; ++d)
                            out[d] += child[d];
                    }
                if (k >= kFirstRefinedLevel) refiner.refine(k, x, y, sums[size_t(k)].data());
            };
            // sums[k] is reused by every child at level k, so a parent adds each child's as it ends.
            visit(visit, tile, tx, ty);
            std::copy(sums[size_t(tile)].begin(), sums[size_t(tile)].end(),
                      below.begin() + std::ptrdiff_t((size_t(ty) * size_t(tl.width) + size_t(tx)) * T));
        }
    });
    for (int k = tile + 1; k <= last; ++k) {
        const PyramidLevel& l = pyramid.level(k);
        const PyramidLevel& child = pyramid.level(k - 1);
        std::vector<double> here(size_t(l.width) * size_t(l.height) * T, 0.0);
        tbb::parallel_for(0, l.height, [&](int y) {
            TexelRefiner refiner(mixture, pyramid, s, texelPowers, fixed);
            for (int x = 0; x < l.width; ++x) {
                double* out = here.data() + (size_t(y) * size_t(l.width) + size_t(x)) * T;
                for (int j = l.yChild[size_t(y)]; j < l.yChild[size_t(y) + 1]; ++j)
                    for (int i = l.xChild[size_t(x)]; i < l.xChild[size_t(x) + 1]; ++i) {
                        const double* in = below.data() + (size_t(j) * size_t(child.width) + size_t(i)) * T;
                        for (size_t d = 0; d < T; ++d)
                            out[d] += in[d];
                    }
                refiner.refine(k, x, y, out);
            }
        });
        below = std::move(here);
    }
}

MixturePyramid buildShadedMixture(const NormalPyramid& pyramid, double s, int k, int lastLevel,
                                  const std::vector<double>* texelPowers) {
    return MixturePyramid::build(pyramid, s, k, lastLevel, texelPowers, [&](MixturePyramid& m) {
        refineMixturePyramid(m, pyramid, s, texelPowers);
    });
}

} // namespace burnish
