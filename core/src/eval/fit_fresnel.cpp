// Spherical-Gaussian Schlick Fresnel fits: the single-term exp2(−K·x) and the quadratic
// exponent exp2(a·x² + b·x), against (1 − x)^p.
#include <burnish/core/eval/fit.h>

#include "eval/fit_common.h"

#include <burnish/core/shading/fresnel.h>
#include <burnish/core/util/numeric.h>

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <limits>

namespace burnish {

namespace {

constexpr const char* kLagardeSg =
    "Lagarde 2012, \"Spherical Gaussian approximation for Blinn-Phong, Phong and "
    "Fresnel\"";
// Lagarde 2012: "the best fit solution for SpecularPower 5 which is x = 0.788"
constexpr double kFresnelSgOffsetPublished = 0.788;
// The published constants are for Schlick's exponent 5 only.
constexpr double kSchlickExponent = 5.0;
// Exponents beyond this make (1 − x)^p a spike narrower than any use of these fits.
constexpr double kMaxFresnelExponent = 1000.0;

bool isSchlick(double p) {
    return p == kSchlickExponent;
}

Status checkExponent(const char* fit, double p) {
    if (!(p > 0.0 && p <= kMaxFresnelExponent))
        return Error{
            fmt::format("{}: the exponent must be in (0, {:g}] (got {:g})", fit, kMaxFresnelExponent, p)};
    return {};
}

/// Nodes over x with the exact (1 − x)^p (fresnelSchlickPow with F0 = 0) at each.
struct FresnelProblem {
    QuadratureRule rule;
    std::vector<double> x; // the cosine fed to the Fresnel functions
    std::vector<double> exact;
    double measure = 1.0;
    double p = kSchlickExponent;
};

/// Over x in [0, hi]: (1 − x)^p falls off over a width 1/(p + 1) at x = 0.
FresnelProblem fresnelProblemInX(double p, double hi) {
    FresnelProblem f;
    f.p = p;
    f.rule = gaussLegendreGeometric(0.0, hi, 1.0 / (p + 1.0));
    f.x = f.rule.nodes;
    f.measure = hi;
    for (const double x : f.x)
        f.exact.push_back(fresnelSchlickPow(0.0, x, p));
    return f;
}

/// Over θ = acos x in [0, π/2] (uniform in angle, as the text's plots are drawn).
FresnelProblem fresnelProblemInAngle(double p) {
    FresnelProblem f;
    f.p = p;
    // The lobe sits at θ = π/2 with width ~1/sqrt(p): geometric panels from that end.
    const QuadratureRule fromEnd = gaussLegendreGeometric(0.0, 0.5 * kPi<double>, 1.0 / std::sqrt(p + 1.0));
    for (size_t i = 0; i < fromEnd.nodes.size(); ++i) {
        const double theta = 0.5 * kPi<double> - fromEnd.nodes[i];
        f.rule.nodes.push_back(theta);
        f.rule.weights.push_back(fromEnd.weights[i]);
        // sin(π/2 − θ) = cos θ, exact near the lobe where cos would lose digits.
        f.x.push_back(std::sin(fromEnd.nodes[i]));
    }
    f.measure = 0.5 * kPi<double>;
    for (const double x : f.x)
        f.exact.push_back(fresnelSchlickPow(0.0, x, p));
    return f;
}

std::vector<double> singleErrors(const FresnelProblem& f, double K) {
    std::vector<double> e(f.x.size());
    for (size_t i = 0; i < e.size(); ++i)
        e[i] = fresnelSchlickSg(0.0, f.x[i], K) - f.exact[i];
    return e;
}

std::vector<double> quadErrors(const FresnelProblem& f, double a, double b) {
    std::vector<double> e(f.x.size());
    for (size_t i = 0; i < e.size(); ++i)
        e[i] = fresnelSchlickSgQuadratic(0.0, f.x[i], a, b) - f.exact[i];
    return e;
}

FitError linearError(const FresnelProblem& f, const std::vector<double>& e) {
    return fitdetail::fitError(ErrorAccumulator{}.addDomain(f.rule.weights, e, f.measure).metrics());
}

const char* quadMetricName(FresnelQuadMetric m) {
    switch (m) {
    case FresnelQuadMetric::L2Linear:
        return "L2 of (approx − exact) over x uniform in [0, 1]";
    case FresnelQuadMetric::L2Relative:
        return "L2 of (approx − exact)/exact over x uniform in [0, cut]";
    case FresnelQuadMetric::L2Log2:
        return "L2 of log2(approx) − log2(exact) over x uniform in [0, cut]";
    case FresnelQuadMetric::L2Angle:
        return "L2 of (approx − exact) over θ = acos x uniform in [0, π/2]";
    }
    return "";
}

const char* quadMetricLabel(FresnelQuadMetric m) {
    switch (m) {
    case FresnelQuadMetric::L2Linear:
        return "L2 linear, x in [0,1]";
    case FresnelQuadMetric::L2Relative:
        return "L2 relative, x in [0,cut]";
    case FresnelQuadMetric::L2Log2:
        return "L2 log2, x in [0,cut]";
    case FresnelQuadMetric::L2Angle:
        return "L2 linear, θ in [0,π/2]";
    }
    return "";
}

struct QuadFit {
    double a = 0.0;
    double b = 0.0;
};

Result<QuadFit> fitQuadratic(double p, FresnelQuadMetric metric, double cut) {
    const bool fullRange = metric == FresnelQuadMetric::L2Linear || metric == FresnelQuadMetric::L2Angle;
    const FresnelProblem f = metric == FresnelQuadMetric::L2Angle
                                 ? fresnelProblemInAngle(p)
                                 : fresnelProblemInX(p, fullRange ? 1.0 : cut);
    const ResidualFunction residuals = [&](const std::vector<double>& q, std::vector<double>& r) {
        for (size_t i = 0; i < r.size(); ++i) {
            const double approx = fresnelSchlickSgQuadratic(0.0, f.x[i], q[0], q[1]);
            const double sw = std::sqrt(f.rule.weights[i]);
            switch (metric) {
            case FresnelQuadMetric::L2Linear:
            case FresnelQuadMetric::L2Angle:
                r[i] = sw * (approx - f.exact[i]);
                break;
            // exact = (1 − x)^p > 0 for x <= cut < 1, so both divisions and logs are finite
            // (a trial step that underflows approx to 0 gives −inf, which the fitter rejects).
            case FresnelQuadMetric::L2Relative:
                r[i] = sw * (approx - f.exact[i]) / f.exact[i];
                break;
            case FresnelQuadMetric::L2Log2:
                r[i] = sw * (std::log2(approx) - std::log2(f.exact[i]));
                break;
            }
        }
    };
    // Start from the single-term fit's slope: exp2(−(p + 0.75)/ln 2 · x).
    const double b0 = -(p + 0.75) / kLn2<double>;
    const auto fit = fitLeastSquares(residuals, {0.0, b0}, static_cast<int>(f.x.size()));
    if (!fit) return Error{fit.error()};
    return QuadFit{fit->parameters[0], fit->parameters[1]};
}

} // namespace

Result<FitReport> fitFresnelSgReport(const FresnelSgFitOptions& o) {
    if (const Status s = checkExponent("fresnel-sg", o.exponent); !s) return Error{s.error()};
    const double p = o.exponent;
    const FresnelProblem f = fresnelProblemInX(p, 1.0);
    const ResidualFunction residuals = [&](const std::vector<double>& q, std::vector<double>& r) {
        for (size_t i = 0; i < r.size(); ++i)
            r[i] = std::sqrt(f.rule.weights[i]) * (fresnelSchlickSg(0.0, f.x[i], q[0]) - f.exact[i]);
    };
    const auto fit =
        fitLeastSquares(residuals, {(p + kSgOffsetLimit) / kLn2<double>}, static_cast<int>(f.x.size()));
    if (!fit) return Error{"fresnel-sg: " + fit.error()};
    const double K = fit->parameters[0];
    // Lagarde 2012: exp2((p + k)/ln 2 · ((1 − x) − 1)) = exp2(−K x), so k = K ln 2 − p.
    const double k = K * kLn2<double> - p;
    // With c = 1 − x uniform in [0, 1], this is the sg-offset problem for power p.
    const double sgOffset = fitSgOffset(p);

    const bool schlick = isSchlick(p);
    FitReport r;
    r.name = "fresnel-sg";
    r.approximates =
        fmt::format("(1 − x)^{:g} ≈ exp2(−K·x) = exp(−({:g} + k)·x) (fresnelSchlickSg, F0 = 0)", p, p);
    r.source = kLagardeSg;
    r.domain = "x = h·v uniform in [0, 1]";
    r.metric = "L2 of (approx − exact) over x; max abs over the quadrature nodes";
    r.parameters.push_back(
        {"k (offset)", k, schlick ? std::optional(kFresnelSgOffsetPublished) : std::nullopt});
    r.parameters.push_back({"K = (p + k)/ln 2", K, schlick ? std::optional(kFresnelSgK) : std::nullopt});
    r.fittedError = linearError(f, singleErrors(f, K));
    if (schlick) r.publishedError = linearError(f, singleErrors(f, kFresnelSgK));
    const double publishedK = (kSchlickExponent + kFresnelSgOffsetPublished) / kLn2<double>;
    FitTable t{"cross-checks", {"value"}, {}};
    t.rows.push_back({"sg-offset x(p), same problem", {sgOffset}});
    t.rows.push_back({"exp2(−K) (error at x = 1)", {std::exp2(-K)}});
    if (schlick) t.rows.push_back({"(5 + 0.788)/ln 2", {publishedK}});
    r.tables = {t};

    if (schlick) {
        // Published to 3 digits (0.788) and 3 significant digits (8.35).
        constexpr double kOffsetDigits = 0.0005;
        constexpr double kKDigits = 0.005;
        const bool okOffset = std::abs(k - kFresnelSgOffsetPublished) <= kOffsetDigits;
        const bool okK = std::abs(K - kFresnelSgK) <= kKDigits;
        r.note = fmt::format(
            "The L2 fit gives k = {:.4f} and K = {:.4f}; the published k = 0.788 is {} and K = 8.35 is {} "
            "((5 + 0.788)/ln 2 = {:.4f}, rounded). With c = 1 − x this is exactly the sg-offset problem at n "
            "= 5, "
            "whose fit gives {:.4f}. The RMS error moves from {:.5g} to {:.5g} between the fitted and the "
            "published "
            "K. At x = 1 the approximation leaves exp2(−K) = {:.4f} where Schlick gives 0.",
            k, K,
            okOffset ? "reproduced to its 3 digits"
                     : fmt::format("off by {:+.4f}", kFresnelSgOffsetPublished - k),
            okK ? "reproduced to its 3 digits" : fmt::format("off by {:+.4f}", kFresnelSgK - K), publishedK,
            sgOffset, r.fittedError.rms, r.publishedError->rms, std::exp2(-K));
    } else {
        r.note = fmt::format(
            "The text publishes constants only for p = 5. For p = {:g} the L2 fit gives k = {:.4f}, "
            "K = {:.4f}; with c = 1 − x this is the sg-offset problem at n = p (x = {:.4f}).",
            p, k, K, sgOffset);
    }
    return r;
}

Result<FitReport> fitFresnelSgQuadraticReport(const FresnelQuadFitOptions& o) {
    if (const Status s = checkExponent("fresnel-sg-quadratic", o.exponent); !s) return Error{s.error()};
    // The relative and log metrics diverge at x = 1, where (1 − x)^p = 0: the cut keeps them finite.
    if (!(o.cut > 0.0 && o.cut < 1.0))
        return Error{fmt::format("fresnel-sg-quadratic: the cut must be in (0, 1) (got {:g})", o.cut)};
    const double p = o.exponent;
    const bool schlick = isSchlick(p);

    // Every metric is fitted so the report can say which one lands nearest the published pair; the
    // errors in the table are all measured the same way (linear, x in [0, 1]) to compare them.
    const FresnelProblem linear = fresnelProblemInX(p, 1.0);
    constexpr std::array kMetrics{FresnelQuadMetric::L2Linear, FresnelQuadMetric::L2Relative,
                                  FresnelQuadMetric::L2Log2, FresnelQuadMetric::L2Angle};
    FitTable t{"every metric (errors measured linearly over x in [0, 1])",
               schlick ? std::vector<std::string>{"a", "b", "max abs", "RMS", "|Δ published|"}
                       : std::vector<std::string>{"a", "b", "max abs", "RMS"},
               {}};
    QuadFit chosen;
    FresnelQuadMetric nearest = FresnelQuadMetric::L2Linear;
    double nearestDistance = std::numeric_limits<double>::infinity();
    for (const auto m : kMetrics) {
        const auto fit = fitQuadratic(p, m, o.cut);
        if (!fit) return Error{"fresnel-sg-quadratic: " + fit.error()};
        const FitError e = linearError(linear, quadErrors(linear, fit->a, fit->b));
        FitTable::Row row{quadMetricLabel(m), {fit->a, fit->b, e.maxAbs, e.rms}};
        if (schlick) {
            const double d = std::hypot(fit->a - kFresnelSgQuadA, fit->b - kFresnelSgQuadB);
            row.values.push_back(d);
            if (d < nearestDistance) {
                nearestDistance = d;
                nearest = m;
            }
        }
        t.rows.push_back(std::move(row));
        if (m == o.metric) chosen = *fit;
    }

    FitReport r;
    r.name = "fresnel-sg-quadratic";
    r.approximates = fmt::format("(1 − x)^{:g} ≈ exp2(a·x² + b·x) (fresnelSchlickSgQuadratic, F0 = 0)", p);
    r.source = kLagardeSg;
    const bool cutDomain = o.metric == FresnelQuadMetric::L2Relative || o.metric == FresnelQuadMetric::L2Log2;
    r.domain = cutDomain                                ? fmt::format("x = h·v in [0, {:g}]", o.cut)
               : o.metric == FresnelQuadMetric::L2Angle ? "θ = acos(h·v) in [0, π/2]"
                                                        : "x = h·v in [0, 1]";
    r.metric = fmt::format("{}; reported errors are linear over x in [0, 1] (max over the quadrature nodes)",
                           quadMetricName(o.metric));
    r.parameters.push_back({"a", chosen.a, schlick ? std::optional(kFresnelSgQuadA) : std::nullopt});
    r.parameters.push_back({"b", chosen.b, schlick ? std::optional(kFresnelSgQuadB) : std::nullopt});
    r.fittedError = linearError(linear, quadErrors(linear, chosen.a, chosen.b));
    if (schlick) r.publishedError = linearError(linear, quadErrors(linear, kFresnelSgQuadA, kFresnelSgQuadB));
    r.tables = {t};

    if (schlick) {
        // The published pair has 6 significant digits; agreement to 1e-3 would identify the metric.
        constexpr double kIdentifies = 1e-3;
        const FitError& pe = *r.publishedError;
        r.note = fmt::format(
            "Of the metrics tried, {} lands nearest the published (−5.55473, −6.98316), at a distance of "
            "{:.3g} in "
            "(a, b); {}. The published pair's linear RMS error is {:.4g} against {:.4g} for the linear L2 "
            "fit "
            "(max abs {:.4g} vs {:.4g}). The published exponent at x = 1, a + b = {:.5f}, gives exp2(a + b) "
            "= "
            "{:.3g}.",
            quadMetricLabel(nearest), nearestDistance,
            nearestDistance <= kIdentifies
                ? "that reproduces the published digits, so it is most likely the metric of the original fit"
                : "none reproduces the published digits, so the original metric or domain is not among these "
                  "(the text does not state it); the published pair is not bent toward here",
            pe.rms, t.rows[0].values[3].value_or(0.0), pe.maxAbs, t.rows[0].values[2].value_or(0.0),
            kFresnelSgQuadA + kFresnelSgQuadB, std::exp2(kFresnelSgQuadA + kFresnelSgQuadB));
    } else {
        r.note =
            fmt::format("The text publishes the pair only for p = 5; for p = {:g} the fit under {} gives a = "
                        "{:.5f}, b = {:.5f}.",
                        p, quadMetricName(o.metric), chosen.a, chosen.b);
    }
    return r;
}

} // namespace burnish
