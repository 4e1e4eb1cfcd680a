// Least-squares fits that derive the published constants from first principles (Eigen's
// Levenberg–Marquardt over quadrature-evaluated residuals). Each fit states its domain and metric.
//
// Every fit minimizes Σ w_i r_i² with r_i the error of the approximation at Gauss–Legendre node i
// and w_i its weight, so the sum is the L2 integral of the error over the stated domain. The
// fitted functions are the ones the shading code uses (spherical_gaussian.h, fresnel.h,
// geometric_aa.h, ndf.h): the fit moves their parameters and never re-implements them.
#pragma once

#include <burnish/core/shading/spherical_gaussian.h>
#include <burnish/core/util/result.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace burnish {

// ---------------------------------------------------------------------------------------------
// Building blocks.

/// Nodes and weights of a quadrature rule: ∫ f ≈ Σ weights[i]·f(nodes[i]).
struct QuadratureRule {
    std::vector<double> nodes;
    std::vector<double> weights;
};

/// Composite 20-point Gauss–Legendre rule on [a, b] with `panels` equal panels (at least 1).
QuadratureRule gaussLegendreUniform(double a, double b, int panels);

/// Composite 20-point Gauss–Legendre rule on [a, b] whose panels start at width `width` next to a
/// and double away from it: resolves a feature of that width at a (a stiff lobe) and the smooth
/// rest with few nodes. width is clamped to [(b − a)·1e-12, b − a].
QuadratureRule gaussLegendreGeometric(double a, double b, double width);

/// Residuals r(p) of a least-squares problem with p.size() parameters; fills `residuals`
/// (already sized to the residual count).
using ResidualFunction = std::function<void(const std::vector<double>& p, std::vector<double>& residuals)>;

struct LeastSquaresResult {
    std::vector<double> parameters;
    double cost = 0.0;   // Σ r_i² at the solution
    int evaluations = 0; // residual evaluations, finite-difference Jacobians included
    bool converged = false;
};

/// Minimizes Σ r_i(p)² from `initial` with Eigen's Levenberg–Marquardt (MINPACK lmdif) and
/// central-difference Jacobians. Needs residualCount >= initial.size() >= 1; otherwise, or when
/// a residual is not finite at the start, returns an error.
Result<LeastSquaresResult> fitLeastSquares(const ResidualFunction& residuals, std::vector<double> initial,
                                           int residualCount);

// ---------------------------------------------------------------------------------------------
// Reports: what every fit hands back to the CLI and the studio.

struct FitParameter {
    std::string name;
    double fitted = 0.0;
    std::optional<double> published; // the reference text's value, where it gives one
};

/// Error of an approximation over the fit's domain: max |approx − exact| over the evaluation
/// points, and the RMS (sqrt of the L2 integral of the error divided by the domain's measure).
struct FitError {
    double maxAbs = 0.0;
    double rms = 0.0;
};

/// Supporting numbers (per-power fits, convergence, metric comparisons). Empty values are
/// quantities that do not exist for that row (e.g. no threshold reproduces a constant).
struct FitTable {
    struct Row {
        std::string label;
        std::vector<std::optional<double>> values;
    };
    std::string title;
    std::vector<std::string> columns; // names of the value columns (the label column is unnamed)
    std::vector<Row> rows;
};

struct FitReport {
    std::string name;         // CLI name, e.g. "sg-offset"
    std::string approximates; // the approximation, e.g. "c^n ≈ exp((n + x)(c − 1))"
    std::string source;       // the reference text the published values come from
    std::string domain;
    std::string metric;
    std::vector<FitParameter> parameters;
    FitError fittedError; // of the approximation with the fitted parameters
    /// Of the approximation with the published parameters; empty when the text publishes none for
    /// the chosen options (e.g. a Fresnel exponent other than 5).
    std::optional<FitError> publishedError;
    std::vector<FitTable> tables;
    std::string note; // how the fit compares with the published values, and why
};

/// The report as JSON (one object) and as human-readable text.
std::string fitReportsToJson(const std::vector<FitReport>& reports);
std::string fitReportToText(const FitReport& report);

// ---------------------------------------------------------------------------------------------
// 1. Spherical-Gaussian offset of cosine powers (Lagarde 2012).

enum class SgMetric {
    L2Cosine, // error integrated over c uniform in [0, 1] (the published fit)
    L2Angle,  // error integrated over θ = acos c uniform in [0, π/2]
};

/// Best-fit offset x for one power n in c^n ≈ exp((n + x)(c − 1)): minimizes the L2 error over
/// c uniform in [0, 1]. Tends to 0.75 as n grows. n is clamped to [1e-3, kMaxPower] (at n = 0
/// both sides are 1 and every x >= 0 fits).
double fitSgOffset(double n);
/// The same with a choice of metric; under L2Angle the limit is 5/8 instead of 3/4.
double fitSgOffset(double n, SgMetric metric);

/// x(n) tabulated at `nodes` powers log-spaced over [nMin, nMax] (see SgOffsetCurve). Invalid
/// ranges (nMin <= 0, nMax < nMin, non-finite, nodes < 1) give an empty curve, which evaluates to
/// kSgOffsetLimit; nodes == 1 or nMin == nMax give a one-node curve.
SgOffsetCurve fitSgOffsetCurve(double nMin = 1.0, double nMax = 1e4, int nodes = 33);

struct SgOffsetFitOptions {
    int minPower = 3; // integer powers minPower..maxPower are averaged, as in the published fit
    int maxPower = 15;
    SgMetric metric = SgMetric::L2Cosine;
    std::vector<double> limitPowers{1e4, 1e5, 1e6}; // where the large-power limit is shown
};
Result<FitReport> fitSgOffsetReport(const SgOffsetFitOptions& options = {});

// ---------------------------------------------------------------------------------------------
// 2–3. Spherical-Gaussian Schlick Fresnel (Lagarde 2012).

/// (1 − x)^p ≈ exp2(−K·x) = exp(−(p + k)x): fits K (fresnelSchlickSg's constant) by L2 over x
/// uniform in [0, 1]; reports k = K·ln 2 − p next to the published 0.788 and 8.35.
struct FresnelSgFitOptions {
    double exponent = 5.0; // p, in (0, 1000]
};
Result<FitReport> fitFresnelSgReport(const FresnelSgFitOptions& options = {});

enum class FresnelQuadMetric {
    L2Linear,   // ∫_0^1 (approx − exact)² dx
    L2Relative, // ∫_0^cut ((approx − exact)/exact)² dx
    L2Log2,     // ∫_0^cut (log2 approx − log2 exact)² dx (a linear least-squares problem)
    L2Angle,    // ∫_0^{π/2} (approx − exact)² dθ with x = cos θ
};

/// (1 − x)^p ≈ exp2(a·x² + b·x): fits (a, b) of fresnelSchlickSgQuadratic under `metric` and
/// reports every metric's pair in a table, with which one lands nearest the published pair.
struct FresnelQuadFitOptions {
    double exponent = 5.0;
    FresnelQuadMetric metric = FresnelQuadMetric::L2Linear;
    double cut = 0.99; // upper end of x for the relative and log2 metrics, in (0, 1)
};
Result<FitReport> fitFresnelSgQuadraticReport(const FresnelQuadFitOptions& options = {});

// ---------------------------------------------------------------------------------------------
// 4. Phong ↔ Blinn power ratio (Lagarde 2012, after Fisher & Woo 1994 and Gotanda 2010).

/// Best-fit x for one power ρ in cos^ρ(θ) ≈ cos^{xρ}(θ/2) (Phong lobe of reflected angle θ by a
/// Blinn lobe of half angle θ/2), L2 in value over θ uniform in [0, π/2]. Tends to 4.
double fitBlinnPhongRatio(double rho);

struct BlinnPhongRatioFitOptions {
    double minPower = 1.0; // powers log-spaced over [minPower, maxPower] are averaged
    double maxPower = 100.0;
    int samples = 16;
    std::vector<double> limitPowers{1e4, 1e5, 1e6};
};
Result<FitReport> fitBlinnPhongRatioReport(const BlinnPhongRatioFitOptions& options = {});

// ---------------------------------------------------------------------------------------------
// 5. Kaplanyan–Valient cone-angle constant (Baker & Hill 2012): angle = k/sqrt(n).

/// Which angle of the Blinn-Phong lobe cos^n(θ_h) defines the highlight's extent.
enum class KvLobeAngle {
    HalfAngle, // θ_h, between n and h
    Reflected, // 2θ_h, between l and the mirror direction (exact at normal incidence)
};
/// How the angle is measured.
enum class KvAngleMeasure {
    Radians,           // the angle φ itself
    RadiansOverHalfPi, // φ/(π/2), the unit of the first published listing's acos(…)/(π/2)
    Curvature,         // sqrt(1 − cos φ), the unit of the optimised listing's curvature term
    SqrtSolidAngle,    // sqrt(2π(1 − cos φ)), sqrt of the solid angle of the cone above threshold
};
/// What the threshold t is relative to.
enum class KvThreshold {
    RelativeToPeak,     // the lobe cos^n falls to t·peak (normalization cancels)
    AbsoluteNormalized, // the normalized NDF (n+2)/(2π)·cos^n falls to t (sr⁻¹)
};

struct KvDefinition {
    KvLobeAngle angle = KvLobeAngle::Reflected;
    KvAngleMeasure measure = KvAngleMeasure::SqrtSolidAngle;
    KvThreshold threshold = KvThreshold::RelativeToPeak;
};

/// Highlight extent of power n under a definition and threshold t; empty when the lobe never
/// reaches t (absolute thresholds above the peak).
std::optional<double> kvHighlightAngle(double n, double t, const KvDefinition& definition);

struct KvFitOptions {
    double minPower = 16.0; // powers log-spaced over [minPower, maxPower]
    double maxPower = 8192.0;
    int samples = 64;
    double threshold = 0.5; // t for the headline fit of k
    KvDefinition definition{};
};
Result<FitReport> fitKvConeReport(const KvFitOptions& options = {});

// ---------------------------------------------------------------------------------------------
// 6. Diffuse anti-aliasing curve (Baker & Hill 2012).

/// Fits (c0, c1) of diffuseAaCurve to diffuseConeIntegral over |Na| in [minLength, 1] and
/// cosAlpha in [−1, 1] (L2), and the one-parameter fit with c0 = 1/(4·c1).
struct DiffuseAaFitOptions {
    double minLength = 0.95; // kDiffuseAaMinLength: the curve clamps |Na| below it
};
Result<FitReport> fitDiffuseAaReport(const DiffuseAaFitOptions& options = {});

} // namespace burnish
