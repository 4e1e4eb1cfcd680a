#include <burnish/core/eval/approximations.h>

#include <burnish/core/util/grid.h>

#include <burnish/core/eval/evaluate.h>
#include <burnish/core/eval/fit.h>
#include <burnish/core/shading/color.h>
#include <burnish/core/shading/fresnel.h>
#include <burnish/core/shading/geometric_aa.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/visibility.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/quadrature.h>
#include <burnish/core/util/report.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

namespace burnish {

// ---------------------------------------------------------------------------------------------
// Error metrics.

// ---------------------------------------------------------------------------------------------
// Glossy environment reference.

GlossyEnvironmentMoments glossyEnvironmentReference(double NoV, double g) {
    NoV = saturate(NoV);
    g = saturate(g);
    // Lazarov 2011: gloss encoding n = 8192^g
    const double n = std::pow(8192.0, g);
    const double sinV = std::sqrt(std::max(0.0, 1.0 - NoV * NoV));
    // Relative tolerance of each 1-D integral: far below the 1e-2..1e-1 errors being measured.
    constexpr double kTol = 1e-6;

    // Integrate over the half vector h = (sinθ cosφ, sinθ sinφ, cosθ) with v = (sinV, 0, NoV):
    // ∫ f (n·l) dω_l = ∫ D F V (n·l)(v·h) dω_h, since dω_l = 4 (v·h) dω_h and f = D·F·V/4.
    auto integral = [&](bool withFresnel) {
        auto overTheta = [&](double theta) {
            const double cosT = std::cos(theta), sinT = std::sin(theta);
            const double D = blinnPhongNdf(cosT, n);
            if (!(D > 0.0)) return 0.0;
            // n·l = 2(v·h)cosθ − n·v > 0 (which implies v·h > 0) holds for cos φ > kappa; integrating
            // over exactly that arc keeps the kink of the horizon out of the integrand.
            const double sinVsinT = sinV * sinT;
            const double rhs = NoV / (2.0 * cosT) - NoV * cosT; // needed: sinV·sinθ·cos φ > rhs
            double phiMax = kPi<double>;
            if (sinVsinT > 0.0) {
                const double kappa = rhs / sinVsinT;
                if (kappa >= 1.0) return 0.0;
                if (kappa > -1.0) phiMax = std::acos(kappa);
            } else if (!(rhs < 0.0)) {
                return 0.0;
            }
            auto overPhi = [&](double phi) {
                const double VoH = sinVsinT * std::cos(phi) + NoV * cosT;
                const double NoL = 2.0 * VoH * cosT - NoV; // l = 2(v·h)h − v
                if (!(NoL > 0.0) || !(VoH > 0.0)) return 0.0;
                const double F = withFresnel ? fresnelSchlick(0.0, VoH) : 1.0;
                return F * visibilitySchlickSmith(NoL, NoV, n) * NoL * VoH;
            };
            // The integrand is even in φ: twice the integral over [0, φmax].
            return 2.0 * integrate(overPhi, 0.0, phiMax, kTol) * D * sinT;
        };
        // Split θ geometrically from the lobe width 1/sqrt(n+1) so the sharp lobe is resolved.
        const double width = 1.0 / std::sqrt(n + 1.0);
        double sum = 0.0, a = 0.0;
        for (double b = width; a < kPi<double> / 2.0; b *= 2.0) {
            b = std::min(b, kPi<double> / 2.0);
            sum += integrate(overTheta, a, b, kTol);
            a = b;
        }
        return sum;
    };
    return {integral(false), integral(true)};
}

// ---------------------------------------------------------------------------------------------
// Timing.

const SgOffsetCurve& reportSgOffsetCurve() {
    // Powers 1..1e4: the range every lobe entry of the report covers.
    static const SgOffsetCurve curve = fitSgOffsetCurve(1.0, 1e4);
    return curve;
}

namespace {

volatile double g_checksumSink = 0.0; // consumes the checksums so no timed loop is dead code

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

} // namespace

KernelTiming timeKernelPair(const TimedKernelPair& pair, size_t inputs, int repetitions, std::uint32_t seed) {
    const KernelInputs in = pair.makeInputs(std::max<size_t>(inputs, 1), seed);
    const size_t n = in.size();
    const size_t nExact = pair.exactInputCap > 0 ? std::min(n, pair.exactInputCap) : n;
    std::vector<float> out(n);
    KernelArgs args;
    for (size_t k = 0; k < in.streams.size() && k < args.in.size(); ++k)
        args.in[k] = in.streams[k].data();
    args.out = out.data();

    KernelTiming t;
    t.approxInputs = n;
    t.exactInputs = nExact;
    t.repetitions = std::max(repetitions, 1);
    auto run = [&](const Kernel& kernel, size_t count) {
        args.count = count;
        const auto t0 = std::chrono::steady_clock::now();
        kernel(args);
        const auto t1 = std::chrono::steady_clock::now();
        double sum = 0.0;
        for (size_t i = 0; i < count; ++i)
            sum += double(out[i]);
        t.checksum += sum;
        return std::chrono::duration<double, std::nano>(t1 - t0).count();
    };
    run(pair.approx, n); // warm-up: page in the arrays, warm caches and branch predictors
    run(pair.exact, nExact);
    std::vector<double> approxNs, exactNs;
    for (int r = 0; r < t.repetitions; ++r) {
        approxNs.push_back(run(pair.approx, n) / (double(n) * pair.evalsPerElement));
        exactNs.push_back(run(pair.exact, nExact) / (double(nExact) * pair.evalsPerElement));
    }
    g_checksumSink = g_checksumSink + t.checksum;
    t.approxNs = median(approxNs);
    t.exactNs = median(exactNs);
    return t;
}

// ---------------------------------------------------------------------------------------------
// Entries.

double ApproximationEntry::ratio() const {
    return exactNs > 0.0 && std::isfinite(approxNs) ? approxNs / exactNs : std::nan("");
}

double ApproximationEntry::headlineError() const {
    if (metric == HeadlineMetric::MaxRel) return error.maxRel.value_or(std::nan(""));
    return error.maxAbs;
}

namespace {

/// Sizes of the error grids.
struct Density {
    int powers;      // powers per lobe entry (log-spaced 1..1e4)
    int lobeSamples; // cosines per power (twice: in lobe units and uniform)
    int unitSamples; // samples of a [0, 1] variable
    int f0s;         // F0 values in [0.02, 0.08]
    int angles;      // θ_l and θ_v values in [0°, 89°]
    int phis;        // φ values in [0°, 180°]
    int smithPowers; // powers of the Schlick–Smith grid
    int glossyX;     // n·v values of the glossy reference grid
    int glossyG;     // g values of the glossy reference grid
    int coneLengths; // |Na| values in [0.95, 1]
    int coneAlphas;  // cos α values in [−1, 1]
};
constexpr Density kDefaultDensity = {81, 256, 10001, 13, 46, 37, 41, 17, 9, 11, 201};
constexpr Density kQuickDensity = {9, 48, 501, 4, 10, 7, 7, 4, 3, 3, 41};

constexpr double kPowerMin = 1.0;
constexpr double kPowerMax = 1e4;
// Relative errors count only where the exact value is at least this fraction of its peak: below
// it a lobe, Fresnel factor or colour is invisible next to the peak and the ratio is noise.
constexpr double kRelFloor = 1e-3;
// Grazing directions stop 1° short of 90°: at 90° the visibility terms are clamped poles.
constexpr double kMaxThetaDeg = 89.0;
// Lobe samples in lobe units s = −n ln c cover the lobe down to e^−20 ≈ 2e-9 of its peak.
constexpr double kLobeUnits = 20.0;
// Specular colours of the glossy Fresnel grid: dielectrics (0.02..0.08), a bright dielectric /
// dark metal, and a white metal; the error is linear in c, so the ends bound it.
constexpr double kGlossyColors[] = {0.02, 0.04, 0.08, 0.5, 1.0};

/// Cosines that resolve the lobe c^n: half in lobe units (c = e^{−s/n}, s in [0, 20]), half uniform.
std::vector<double> lobeCosines(double n, int k) {
    std::vector<double> c;
    for (const double s : linSpaced(0.0, kLobeUnits, k))
        c.push_back(std::exp(-s / n));
    for (const double u : linSpaced(0.0, 1.0, k))
        c.push_back(u);
    return c;
}

struct Definition {
    std::string id, group, name, formula, exact, domain;
    HeadlineMetric metric;
    std::function<ErrorAccumulator(const Density&)> error;
    /// Whether the relative error is floored at kRelFloor of the peak (else pointwise everywhere).
    bool relFloored;
    std::vector<std::string> notes;
};

const char* kGroupNorm = "Normalization";
const char* kGroupBlinn = "Blinn-Phong lobe";
const char* kGroupPhong = "Phong lobe";
const char* kGroupFresnel = "Fresnel";
const char* kGroupVis = "Visibility";
const char* kGroupNdf = "NDF bridges";
const char* kGroupDiffuse = "Diffuse AA";
const char* kGroupDecode = "sRGB decode";
const char* kGroupEncode = "sRGB encode";

ErrorAccumulator sgLobeError(const Density& d, const std::function<double(double c, double n)>& approx) {
    ErrorAccumulator acc;
    for (const double n : logSpaced(kPowerMin, kPowerMax, d.powers))
        for (const double c : lobeCosines(n, d.lobeSamples))
            acc.add(powCos(c, n), approx(c, n), kRelFloor);
    return acc;
}

ErrorAccumulator unitError(const Density& d, const std::function<double(double)>& exact,
                           const std::function<double(double)>& approx, double relFloor) {
    ErrorAccumulator acc;
    for (const double x : linSpaced(0.0, 1.0, d.unitSamples))
        acc.add(exact(x), approx(x), relFloor);
    return acc;
}

ErrorAccumulator cookTorranceError(const Density& d, const std::function<double(double VoH)>& approx) {
    ErrorAccumulator acc;
    const double deg = kPi<double> / 180.0;
    for (const double tl : linSpaced(0.0, kMaxThetaDeg * deg, d.angles))
        for (const double tv : linSpaced(0.0, kMaxThetaDeg * deg, d.angles))
            for (const double p : linSpaced(0.0, kPi<double>, d.phis)) {
                const double l[3] = {std::sin(tl), 0.0, std::cos(tl)};
                const double v[3] = {std::sin(tv) * std::cos(p), std::sin(tv) * std::sin(p), std::cos(tv)};
                double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
                const double len = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]); // > 0 below 90°
                for (double& c : h)
                    c /= len;
                const double VoH = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
                acc.add(visibilityCookTorrance(l[2], v[2], h[2], VoH), approx(VoH));
            }
    return acc;
}

ErrorAccumulator ndfError(const Density& d, const std::function<double(double c, double n)>& exact,
                          const std::function<double(double c, double n)>& approx) {
    ErrorAccumulator acc;
    for (const double n : logSpaced(kPowerMin, kPowerMax, d.powers)) {
        // Both NDFs of each bridge peak at (n+2)/(2π); errors are in units of that peak.
        const double peak = blinnPhongNdfNorm(n);
        for (const double c : lobeCosines(n, d.lobeSamples))
            acc.add(exact(c, n) / peak, approx(c, n) / peak, kRelFloor);
    }
    return acc;
}

std::vector<Definition> definitions() {
    std::vector<Definition> defs;
    const std::string lobeDomain = "n in [1, 1e4] log-spaced; c in [0, 1] (uniform and in lobe units)";

    defs.push_back({"norm-blinn-phong-brdf",
                    kGroupNorm,
                    "Blinn-Phong BRDF normalization (n+8)/8π",
                    "(n+8)/(8π)",
                    "(n+2)(n+4)/(8π(2^(−n/2)+n))",
                    "n in [1, 1e4] log-spaced",
                    HeadlineMetric::MaxRel,
                    [](const Density& d) {
                        ErrorAccumulator acc;
                        for (const double n : logSpaced(kPowerMin, kPowerMax, d.unitSamples))
                            acc.add(blinnPhongBrdfNorm(n), blinnPhongBrdfNormApprox(n));
                        return acc;
                    },
                    false,
                    {"max abs is in units of the factor itself (which grows like n/8π); the relative error "
                     "is the meaningful one."}});

    defs.push_back({"sg-blinn-x0",
                    kGroupBlinn,
                    "SG, x = 0",
                    "exp(n(c−1))",
                    "c^n (c = n·h)",
                    lobeDomain,
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return sgLobeError(d,
                                           [](double c, double n) { return sgLobe(c, n, kSgOffsetPlain); });
                    },
                    true,
                    {}});
    defs.push_back({"sg-blinn-x0775",
                    kGroupBlinn,
                    "SG, x = 0.775 (Lagarde)",
                    "exp((n+0.775)(c−1))",
                    "c^n (c = n·h)",
                    lobeDomain,
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return sgLobeError(d,
                                           [](double c, double n) { return sgLobe(c, n, kSgOffsetLagarde); });
                    },
                    true,
                    {}});
    defs.push_back({"sg-blinn-bestfit",
                    kGroupBlinn,
                    "SG, best-fit x(n) table",
                    "exp((n+x(n))(c−1))",
                    "c^n (c = n·h)",
                    lobeDomain,
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        const SgOffsetCurve& curve = reportSgOffsetCurve();
                        return sgLobeError(d, [&](double c, double n) { return sgLobe(c, n, curve(n)); });
                    },
                    true,
                    {"x(n): fitSgOffsetCurve, L2 fit per power over c in [0, 1], 33 nodes log-spaced over "
                     "[1, 1e4], linear in log n; the timed loop includes the table lookup per evaluation."}});
    defs.push_back({"sg-blinn-exp2",
                    kGroupBlinn,
                    "SG exp2 'modified power' (x = 0)",
                    "exp2(A·c − A), A = n/ln 2",
                    "c^n (c = n·h)",
                    lobeDomain,
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return sgLobeError(
                            d, [](double c, double n) { return sgLobeExp2(c, n / kLn2<double>); });
                    },
                    true,
                    {"A is computed beforehand (folded into the gloss decode, as Lagarde 2012 does), so the "
                     "timed loop is one multiply-add and one exp2."}});

    defs.push_back({"sg-phong-dot4",
                    kGroupPhong,
                    "SG dot4 per light (x = 0)",
                    "exp2(dot(R2, (L,1))), R2 = (A·R, −A), A = n/ln 2",
                    "cos^n θ = (r·l)^n",
                    lobeDomain,
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return sgLobeError(
                            d, [](double c, double n) { return sgLobeExp2(c, n / kLn2<double>); });
                    },
                    true,
                    {"timed with 4 lights per pixel and reported per light; A·R is formed once per pixel. "
                     "The error is that of the x = 0 SG (the same function of r·l)."}});
    defs.push_back({"phong-as-blinn-x4",
                    kGroupPhong,
                    "Blinn lobe with power 4n (x = 4)",
                    "cos^(4n)(θ/2)",
                    "cos^n θ = (r·l)^n",
                    "n in [1, 1e4] log-spaced; θ in [0°, 90°]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return sgLobeError(d, [](double c, double n) {
                            // Half-angle identity: cos(θ/2) = sqrt((1 + cos θ)/2).
                            return powCos(std::sqrt(0.5 * (1.0 + c)), 4.0 * n);
                        });
                    },
                    true,
                    {"the timed loop forms cos(θ/2) from cos θ with the half-angle identity (a shader would "
                     "compute n·h instead)."}});

    defs.push_back({"fresnel-schlick",
                    kGroupFresnel,
                    "Schlick",
                    "c + (1−c)(1−x)^5",
                    "exact dielectric Fresnel (unpolarized, η from F0)",
                    "F0 in [0.02, 0.08]; x = h·l in [0, 1]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        ErrorAccumulator acc;
                        for (const double F0 : linSpaced(0.02, 0.08, d.f0s))
                            for (const double x : linSpaced(0.0, 1.0, d.unitSamples / 10 + 1))
                                acc.add(fresnelDielectric(F0, x), fresnelSchlick(F0, x));
                        return acc;
                    },
                    false,
                    {}});
    defs.push_back({"fresnel-sg",
                    kGroupFresnel,
                    "SG single term",
                    "exp2(−8.35·x)",
                    "(1−x)^5 (Schlick's factor)",
                    "x in [0, 1]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return unitError(
                            d, [](double x) { return fresnelSchlick(0.0, x); },
                            [](double x) { return fresnelSchlickSg(0.0, x); }, kRelFloor);
                    },
                    true,
                    {"errors of the factor alone (c = 0); timed as the full c + (1−c)·factor."}});
    defs.push_back({"fresnel-sg-quadratic",
                    kGroupFresnel,
                    "SG quadratic exponent",
                    "exp2((−5.55473·x − 6.98316)·x)",
                    "(1−x)^5 (Schlick's factor)",
                    "x in [0, 1]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return unitError(
                            d, [](double x) { return fresnelSchlick(0.0, x); },
                            [](double x) { return fresnelSchlickSgQuadratic(0.0, x); }, kRelFloor);
                    },
                    true,
                    {"errors of the factor alone (c = 0); timed as the full c + (1−c)·factor."}});
    defs.push_back(
        {"fresnel-glossy",
         kGroupFresnel,
         "Glossy environment (4−3g)",
         "c + (1−c)(1−x)^5/(4−3g)",
         "∫ D·F·V/4·(n·l) dω under a white environment (Blinn-Phong D, n = 8192^g, Schlick F, Schlick–Smith "
         "V)",
         "c in {0.02, 0.04, 0.08, 0.5, 1}; x = n·v in [0, 1]; g in [0, 1]",
         HeadlineMetric::MaxAbs,
         [](const Density& d) {
             ErrorAccumulator acc;
             // The reference is computed once per (x, g) node and reused for every c (it is linear in c).
             for (const double x : linSpaced(0.0, 1.0, d.glossyX))
                 for (const double g : linSpaced(0.0, 1.0, d.glossyG)) {
                     const GlossyEnvironmentMoments m = glossyEnvironmentReference(x, g);
                     for (const double c : kGlossyColors)
                         acc.add(m.at(c), fresnelGlossy(c, x, g));
                 }
             return acc;
         },
         false,
         {"a coarse fit (Lazarov 2011: a cheap curve fitted to the integral of the BRDF). Its error is "
          "largest for metals: at c = 1 the fit returns 1 whatever the gloss and angle, while the integral "
          "loses energy (about 0.34-0.39 at g = 0, 0.23 at g = 1 and n·v = 0). The exact form is a "
          "double-precision quadrature timed on a few inputs; a 2-D lookup table is the practical "
          "alternative."}});

    defs.push_back({"vis-kelemen",
                    kGroupVis,
                    "Kelemen",
                    "1/(v·h)²",
                    "Cook–Torrance G/((n·l)(n·v))",
                    "θ_l, θ_v in [0°, 89°]; φ in [0°, 180°]",
                    HeadlineMetric::MaxRel,
                    [](const Density& d) {
                        return cookTorranceError(d, [](double VoH) { return visibilityKelemen(VoH); });
                    },
                    false,
                    {}});
    defs.push_back({"vis-none",
                    kGroupVis,
                    "None",
                    "1",
                    "Cook–Torrance G/((n·l)(n·v))",
                    "θ_l, θ_v in [0°, 89°]; φ in [0°, 180°]",
                    HeadlineMetric::MaxRel,
                    [](const Density& d) {
                        return cookTorranceError(d, [](double) { return visibilityNone<double>(); });
                    },
                    false,
                    {"the loop only stores a constant: its cost is the memory traffic."}});
    defs.push_back({"vis-schlick-smith",
                    kGroupVis,
                    "Schlick–Smith",
                    "1/((n·l(1−a)+a)(n·v(1−a)+a)), a = 1/sqrt(πn/4+π/2)",
                    "Smith–Beckmann G1(l)G1(v)/((n·l)(n·v)), m = sqrt(2/(n+2))",
                    "θ_l, θ_v in [0°, 89°]; n in [1, 1e4] log-spaced",
                    HeadlineMetric::MaxRel,
                    [](const Density& d) {
                        ErrorAccumulator acc;
                        const double deg = kPi<double> / 180.0;
                        for (const double n : logSpaced(kPowerMin, kPowerMax, d.smithPowers)) {
                            const double m = beckmannRoughnessFromPower(n);
                            for (const double tl : linSpaced(0.0, kMaxThetaDeg * deg, d.angles))
                                for (const double tv : linSpaced(0.0, kMaxThetaDeg * deg, d.angles)) {
                                    const double NoL = std::cos(tl), NoV = std::cos(tv);
                                    acc.add(visibilitySmithBeckmann(NoL, NoV, m),
                                            visibilitySchlickSmith(NoL, NoV, n));
                                }
                        }
                        return acc;
                    },
                    false,
                    {}});

    defs.push_back({"ndf-blinn-for-beckmann",
                    kGroupNdf,
                    "Blinn-Phong for Beckmann",
                    "(n+2)/(2π)·c^n",
                    "Beckmann with m = sqrt(2/(n+2)) (reference)",
                    lobeDomain + "; values ÷ peak (n+2)/(2π)",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return ndfError(
                            d,
                            [](double c, double n) { return beckmannNdf(c, beckmannRoughnessFromPower(n)); },
                            [](double c, double n) { return blinnPhongNdf(c, n); });
                    },
                    true,
                    {"errors in units of the common peak (n+2)/(2π) of both NDFs."}});
    defs.push_back({"ndf-ggx-for-blinn",
                    kGroupNdf,
                    "GGX for Blinn-Phong",
                    "GGX with α² = 2/(n+2)",
                    "Blinn-Phong (n+2)/(2π)·c^n (reference: the authored lobe)",
                    lobeDomain + "; values ÷ peak (n+2)/(2π)",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return ndfError(
                            d, [](double c, double n) { return blinnPhongNdf(c, n); },
                            [](double c, double n) { return ggxNdf(c, ggxAlphaFromPower(n)); });
                    },
                    true,
                    {"GGX's long tail is a different shape, not a fitting error: the bridge matches the peak "
                     "and the width, not the tail."}});

    defs.push_back({"diffuse-aa-curve",
                    kGroupDiffuse,
                    "Baker–Hill curve",
                    "w·(|c0·a| <= c1·x ? (c0·a+c1·x)²/x : saturate(a)), x = sqrt(1−w)",
                    "mean of max(0, n_i·l) over the cone of normals (diffuseConeIntegral)",
                    "|Na| in [0.95, 1]; cos α in [−1, 1]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        ErrorAccumulator acc;
                        for (const double lenNa : linSpaced(kDiffuseAaMinLength, 1.0, d.coneLengths))
                            for (const double a : linSpaced(-1.0, 1.0, d.coneAlphas))
                                acc.add(diffuseConeIntegral(a, coneCosFromNormalLength(lenNa)),
                                        diffuseAaCurve(a, lenNa), kRelFloor);
                        return acc;
                    },
                    true,
                    {"the exact form is an adaptive quadrature in double, timed on fewer inputs."}});

    defs.push_back({"srgb-decode-gamma22",
                    kGroupDecode,
                    "gamma 2.2",
                    "v^2.2",
                    "sRGB piecewise decode (IEC 61966-2-1)",
                    "v in [0, 1]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return unitError(
                            d, [](double v) { return srgbToLinear(v); },
                            [](double v) { return gamma22ToLinear(v); }, kRelFloor);
                    },
                    true,
                    {}});
    defs.push_back({"srgb-decode-gamma20",
                    kGroupDecode,
                    "gamma 2.0",
                    "v²",
                    "sRGB piecewise decode (IEC 61966-2-1)",
                    "v in [0, 1]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return unitError(
                            d, [](double v) { return srgbToLinear(v); },
                            [](double v) { return gamma20ToLinear(v); }, kRelFloor);
                    },
                    true,
                    {}});
    defs.push_back({"srgb-encode-gamma22",
                    kGroupEncode,
                    "gamma 1/2.2",
                    "L^(1/2.2)",
                    "sRGB piecewise encode (IEC 61966-2-1)",
                    "L in [0, 1]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return unitError(
                            d, [](double L) { return linearToSrgb(L); },
                            [](double L) { return linearToGamma22(L); }, kRelFloor);
                    },
                    true,
                    {}});
    defs.push_back({"srgb-encode-gamma20",
                    kGroupEncode,
                    "gamma 1/2.0",
                    "sqrt(L)",
                    "sRGB piecewise encode (IEC 61966-2-1)",
                    "L in [0, 1]",
                    HeadlineMetric::MaxAbs,
                    [](const Density& d) {
                        return unitError(
                            d, [](double L) { return linearToSrgb(L); },
                            [](double L) { return linearToGamma20(L); }, kRelFloor);
                    },
                    true,
                    {}});
    return defs;
}

std::string metricName(HeadlineMetric m) {
    return m == HeadlineMetric::MaxRel ? "max_rel" : "max_abs";
}

std::string relBasisText(bool floored) {
    return floored ? fmt::format("pointwise where the exact value is at least {} of its peak", kRelFloor)
                   : "pointwise over the whole domain";
}

} // namespace

namespace {
std::string paretoKey(const ApproximationEntry& e) {
    return e.group + '\n' + e.exact;
}
} // namespace

void markParetoFront(std::vector<ApproximationEntry>& entries) {
    std::vector<ParetoPoint> points;
    // Only alternatives to the same exact form compete: within "Visibility", Kelemen (against
    // Cook–Torrance) must not push Schlick–Smith (against Smith–Beckmann) off the front.
    for (const auto& e : entries)
        points.push_back({paretoKey(e), e.approxNs, e.headlineError()});
    const std::vector<bool> front = paretoFront(points);
    for (size_t i = 0; i < entries.size(); ++i)
        entries[i].pareto = front[i];
}

Result<ApproximationReport> measureApproximations(const ApproximationOptions& options,
                                                  const std::atomic<bool>* cancel) {
    // Relaxed: the flag carries no data, only "stop"; the worker sees it at its next check.
    auto cancelled = [cancel] { return cancel && cancel->load(std::memory_order_relaxed); };
    const auto start = std::chrono::steady_clock::now();
    ApproximationReport report;
    report.quick = options.quick;
    report.inputs = options.inputs > 0 ? options.inputs : (options.quick ? size_t(1) << 16 : size_t(1) << 20);
    report.repetitions = options.repetitions > 0 ? options.repetitions : (options.quick ? 3 : 7);
    const MachineInfo machine = machineInfo();
    report.cpuModel = machine.cpuModel;
    report.logicalCpus = machine.logicalCpus;
    report.compiler = machine.compiler;
    report.kernelBuild = kernelBuildDescription();
    const Density& density = options.quick ? kQuickDensity : kDefaultDensity;

    const auto& pairs = timedKernelPairs();
    for (const Definition& def : definitions()) {
        const auto pair =
            std::find_if(pairs.begin(), pairs.end(), [&](const auto& p) { return p.id == def.id; });
        if (pair == pairs.end()) return Error{"approximations: no timed kernel for entry " + def.id};
        if (cancelled()) return Error{std::string(kCancelledMessage)};
        const ErrorAccumulator acc = def.error(density);
        if (acc.nonFinite() > 0)
            return Error{
                fmt::format("approximations: {} produced {} NaN/Inf samples", def.id, acc.nonFinite())};
        if (cancelled()) return Error{std::string(kCancelledMessage)};
        const KernelTiming timing = timeKernelPair(*pair, report.inputs, report.repetitions);

        ApproximationEntry e;
        e.id = def.id;
        e.group = def.group;
        e.name = def.name;
        e.formula = def.formula;
        e.exact = def.exact;
        e.domain = def.domain;
        e.metric = def.metric;
        e.error = acc.metrics();
        e.relBasis = e.error.maxRel ? relBasisText(def.relFloored)
                                    : "n/a: no sample has an exact value large enough for a relative error";
        e.approxNs = timing.approxNs;
        e.exactNs = timing.exactNs;
        e.approxInputs = timing.approxInputs;
        e.exactInputs = timing.exactInputs;
        e.notes = def.notes;
        if (!std::isfinite(e.error.maxAbs) || !std::isfinite(e.error.rms) || !std::isfinite(e.approxNs) ||
            !std::isfinite(e.exactNs))
            return Error{"approximations: " + def.id + " produced a non-finite metric"};
        if (std::find(report.groups.begin(), report.groups.end(), e.group) == report.groups.end())
            report.groups.push_back(e.group);
        report.entries.push_back(std::move(e));
    }
    if (cancelled()) return Error{std::string(kCancelledMessage)};
    markParetoFront(report.entries);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

// ---------------------------------------------------------------------------------------------
// Output.

namespace {

std::string headlineCell(const ApproximationEntry& e, HeadlineMetric which, const std::string& text) {
    return e.metric == which ? "**" + text + "**" : text;
}

std::string relCell(const ApproximationEntry& e) {
    if (!e.error.maxRel) return "n/a (no exact value above the floor)";
    const std::string v = formatNumber(*e.error.maxRel);
    return e.relBasis.rfind("pointwise where", 0) == 0 ? v + " (≥1e-3 peak)" : v;
}

} // namespace

std::string approximationsMarkdown(const ApproximationReport& r) {
    std::string md = "# Burnish: approximations against their exact forms\n\n";
    if (r.quick)
        md += fmt::format("**Quick run** ({} inputs, {} repetitions, coarse error grids): for tests, not for "
                          "reading the numbers.\n\n",
                          r.inputs, r.repetitions);
    md += fmt::format("- **Machine**: {} ({} logical CPUs), {}; {}.\n", r.cpuModel, r.logicalCpus, r.compiler,
                      r.kernelBuild);
    md += fmt::format(
        "- **Cost**: median of {} repetitions of a loop over {} float inputs per entry (inputs prepared "
        "beforehand, results written to an array, a checksum consumed); the exact form is timed in the same "
        "run, interleaved with the approximation. On a shared machine absolute ns are noisy: read the ratio "
        "(approximation / exact, same run). Loops of arithmetic vectorize; loops that call exp, log, pow or "
        "erf "
        "run scalar libm code, so on this CPU an exp2 costs more than a few multiplies, unlike on a GPU "
        "where it is one instruction: the ratios are this CPU's.\n",
        r.repetitions, r.inputs);
    md += "- **Error**: both forms in double precision over the grid in *domain*. max rel marked (≥1e-3 "
          "peak) counts only samples whose exact value is at least 1e-3 of its peak (1 for lobes, Fresnel "
          "factors and colours, (n+2)/2π for NDFs, 1 for the cone integral); otherwise it is pointwise over "
          "the whole domain. RMS is over the grid's samples.\n";
    md += "- **Pareto**: among the entries of a group that approximate the same exact form, no other is both "
          "cheaper and more accurate, by the group's headline metric (in **bold**).\n";
    md += fmt::format("- Measured in {:.1f} s.\n\n", r.seconds);

    MarkdownTable table({"#", "group", "approximation", "formula", "exact (reference)", "domain", "max abs",
                         "max rel", "RMS", "ns/eval", "exact ns/eval", "ratio", "Pareto"},
                        {Align::Right, Align::Left, Align::Left, Align::Left, Align::Left, Align::Left,
                         Align::Right, Align::Right, Align::Right, Align::Right, Align::Right, Align::Right,
                         Align::Left});
    for (size_t i = 0; i < r.entries.size(); ++i) {
        const auto& e = r.entries[i];
        table.addRow({std::to_string(i + 1), e.group, e.name, e.formula, e.exact, e.domain,
                      headlineCell(e, HeadlineMetric::MaxAbs, formatNumber(e.error.maxAbs)),
                      headlineCell(e, HeadlineMetric::MaxRel, relCell(e)), formatNumber(e.error.rms),
                      formatNumber(e.approxNs), formatNumber(e.exactNs), formatNumber(e.ratio()),
                      e.pareto ? "yes" : ""});
    }
    md += table.render();
    md += "\n## Notes\n\n";
    for (size_t i = 0; i < r.entries.size(); ++i) {
        const auto& e = r.entries[i];
        std::string note;
        for (const auto& n : e.notes)
            note += (note.empty() ? "" : " ") + n;
        if (e.exactInputs < e.approxInputs)
            note += fmt::format("{}Exact form timed on {} inputs.", note.empty() ? "" : " ", e.exactInputs);
        if (!note.empty()) md += fmt::format("{}. {}: {}\n", i + 1, e.name, note);
    }
    return md;
}

nlohmann::json approximationsJson(const ApproximationReport& r) {
    nlohmann::json j;
    j["report"] = "approximations";
    j["version"] = 1;
    j["quick"] = r.quick;
    j["measurement"] = {
        {"cpu", r.cpuModel},
        {"logical_cpus", r.logicalCpus},
        {"compiler", r.compiler},
        {"kernel_build", r.kernelBuild},
        {"inputs", r.inputs},
        {"repetitions", r.repetitions},
        {"seconds", jsonNumber(r.seconds)},
        {"cost", "median ns per evaluation, float kernels; exact timed interleaved in the same run"},
        {"error", "double precision over the stated domain grid"}};
    j["groups"] = r.groups;
    nlohmann::json list = nlohmann::json::array();
    for (const auto& e : r.entries) {
        list.push_back({{"id", e.id},
                        {"group", e.group},
                        {"name", e.name},
                        {"formula", e.formula},
                        {"exact", e.exact},
                        {"domain", e.domain},
                        {"headline_metric", metricName(e.metric)},
                        {"error",
                         {{"max_abs", jsonNumber(e.error.maxAbs)},
                          {"max_rel", e.error.maxRel ? jsonNumber(*e.error.maxRel) : nlohmann::json(nullptr)},
                          {"max_rel_basis", e.relBasis},
                          {"rms", jsonNumber(e.error.rms)},
                          {"samples", e.error.samples},
                          {"rel_samples", e.error.relSamples}}},
                        {"cost",
                         {{"ns_per_eval", jsonNumber(e.approxNs)},
                          {"exact_ns_per_eval", jsonNumber(e.exactNs)},
                          {"ratio", jsonNumber(e.ratio())},
                          {"inputs", e.approxInputs},
                          {"exact_inputs", e.exactInputs}}},
                        {"pareto", e.pareto},
                        {"notes", e.notes}});
    }
    j["approximations"] = std::move(list);
    return j;
}

PlotSpec approximationsPlot(const ApproximationReport& r) {
    PlotSpec spec;
    spec.title =
        "Approximation error against cost (filled, joined: Pareto front per exact form; labels: table #)";
    spec.x = {"cost of the approximation (ns per evaluation, float, this CPU)", AxisScale::Log, {}, {}};
    spec.y = {"error: group's headline metric (max abs or max rel, see table)", AxisScale::Log, {}, {}};
    for (size_t g = 0; g < r.groups.size(); ++g) {
        // One joined front per exact form within the group; the group's colour and legend entry once.
        std::vector<std::string> keys;
        for (const auto& e : r.entries)
            if (e.group == r.groups[g] && std::find(keys.begin(), keys.end(), paretoKey(e)) == keys.end())
                keys.push_back(paretoKey(e));
        PlotSeries others;
        others.color = plotPalette(g);
        others.marker = MarkerShape::HollowSquare;
        others.markerSize = 9; // hollow squares read as small as filled ones: one size up
        for (size_t k = 0; k < keys.size(); ++k) {
            PlotSeries front;
            front.name = k == 0 ? r.groups[g] : "";
            front.color = plotPalette(g);
            front.line = true;
            front.marker = MarkerShape::OutlinedSquare;
            std::vector<std::pair<double, size_t>> frontOrder;
            for (size_t i = 0; i < r.entries.size(); ++i) {
                const auto& e = r.entries[i];
                if (paretoKey(e) != keys[k]) continue;
                if (e.pareto) {
                    frontOrder.push_back({e.approxNs, i});
                } else {
                    others.x.push_back(e.approxNs);
                    others.y.push_back(e.headlineError());
                    others.pointLabels.push_back(std::to_string(i + 1));
                }
            }
            std::sort(frontOrder.begin(), frontOrder.end());
            for (const auto& [cost, i] : frontOrder) {
                front.x.push_back(cost);
                front.y.push_back(r.entries[i].headlineError());
                front.pointLabels.push_back(std::to_string(i + 1));
            }
            spec.series.push_back(std::move(front));
        }
        if (!others.x.empty()) spec.series.push_back(std::move(others));
    }
    return spec;
}

Status writeApproximationReport(const ApproximationReport& report, const std::filesystem::path& dir) {
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
        return Error{fmt::format("report: output folder {} does not exist", dir.string())};
    if (auto st = writeFileAtomic(dir / "approximations.md", approximationsMarkdown(report)); !st) return st;
    if (auto st = writeFileAtomic(dir / "approximations.json", approximationsJson(report).dump(2) + "\n");
        !st)
        return st;
    return savePlotPng(approximationsPlot(report), dir / "approximations.png");
}

} // namespace burnish
