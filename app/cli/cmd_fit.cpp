// `burnish fit`: derive the reference texts' constants by least squares and compare.
#include "command.h"

#include <burnish/core/eval/fit.h>
#include <burnish/core/util/files.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace burnish::cli {

namespace {

const std::vector<std::string> kFits{"sg-offset",         "fresnel-sg", "fresnel-sg-quadratic",
                                     "blinn-phong-ratio", "kv-cone",    "diffuse-aa"};

struct FitCliOptions {
    std::string what;
    std::optional<double> minPower;
    std::optional<double> maxPower;
    std::optional<double> exponent;
    std::optional<std::string> metric;
    std::optional<double> cut;
    std::optional<int> samples;
    std::optional<double> threshold;
    std::optional<std::string> kvAngle;
    std::optional<std::string> kvMeasure;
    std::optional<std::string> kvThreshold;
    std::optional<double> minLength;
    bool json = false;
    std::string out;
};

/// Which fits an option applies to; an option given for a fit it does not apply to is an error.
struct OptionUse {
    const char* name;
    bool given;
    std::vector<std::string> fits;
};

std::vector<OptionUse> optionUses(const FitCliOptions& o) {
    return {
        {"--min-power", o.minPower.has_value(), {"sg-offset", "blinn-phong-ratio", "kv-cone"}},
        {"--max-power", o.maxPower.has_value(), {"sg-offset", "blinn-phong-ratio", "kv-cone"}},
        {"--exponent", o.exponent.has_value(), {"fresnel-sg", "fresnel-sg-quadratic"}},
        {"--metric", o.metric.has_value(), {"sg-offset", "fresnel-sg-quadratic"}},
        {"--cut", o.cut.has_value(), {"fresnel-sg-quadratic"}},
        {"--samples", o.samples.has_value(), {"blinn-phong-ratio", "kv-cone"}},
        {"--threshold", o.threshold.has_value(), {"kv-cone"}},
        {"--kv-angle", o.kvAngle.has_value(), {"kv-cone"}},
        {"--kv-measure", o.kvMeasure.has_value(), {"kv-cone"}},
        {"--kv-threshold", o.kvThreshold.has_value(), {"kv-cone"}},
        {"--min-length", o.minLength.has_value(), {"diffuse-aa"}},
    };
}

bool appliesTo(const OptionUse& use, const std::string& fit) {
    for (const auto& f : use.fits)
        if (f == fit) return true;
    return false;
}

/// An integer power for sg-offset (the published mean is over integer powers).
Result<int> integerPower(const char* option, double v) {
    // 1e6 is fitSgOffsetReport's own bound; checking here keeps the int conversion defined.
    constexpr double kMaxIntegerPower = 1e6;
    if (!(v >= 1.0 && v <= kMaxIntegerPower) || v != std::floor(v))
        return Error{fmt::format("{} {:g}: sg-offset averages integer powers in [1, {:g}]", option, v,
                                 kMaxIntegerPower)};
    return static_cast<int>(v);
}

template <class Enum>
Result<Enum> parseChoice(const char* option, const std::string& value,
                         const std::map<std::string, Enum>& choices, const char* fit) {
    const auto it = choices.find(value);
    if (it != choices.end()) return it->second;
    std::string names;
    for (const auto& [name, e] : choices)
        names += (names.empty() ? "" : ", ") + name;
    return Error{fmt::format("{} '{}' is not a choice for {} ({})", option, value, fit, names)};
}

Result<FitReport> runOne(const std::string& fit, const FitCliOptions& o) {
    if (fit == "sg-offset") {
        SgOffsetFitOptions s;
        if (o.minPower) {
            const auto v = integerPower("--min-power", *o.minPower);
            if (!v) return Error{v.error()};
            s.minPower = *v;
        }
        if (o.maxPower) {
            const auto v = integerPower("--max-power", *o.maxPower);
            if (!v) return Error{v.error()};
            s.maxPower = *v;
        }
        if (o.metric) {
            const auto m = parseChoice<SgMetric>(
                "--metric", *o.metric, {{"cosine", SgMetric::L2Cosine}, {"angle", SgMetric::L2Angle}},
                "sg-offset");
            if (!m) return Error{m.error()};
            s.metric = *m;
        }
        return fitSgOffsetReport(s);
    }
    if (fit == "fresnel-sg") {
        FresnelSgFitOptions f;
        if (o.exponent) f.exponent = *o.exponent;
        return fitFresnelSgReport(f);
    }
    if (fit == "fresnel-sg-quadratic") {
        FresnelQuadFitOptions f;
        if (o.exponent) f.exponent = *o.exponent;
        if (o.cut) f.cut = *o.cut;
        if (o.metric) {
            const auto m = parseChoice<FresnelQuadMetric>("--metric", *o.metric,
                                                          {{"linear", FresnelQuadMetric::L2Linear},
                                                           {"relative", FresnelQuadMetric::L2Relative},
                                                           {"log2", FresnelQuadMetric::L2Log2},
                                                           {"angle", FresnelQuadMetric::L2Angle}},
                                                          "fresnel-sg-quadratic");
            if (!m) return Error{m.error()};
            f.metric = *m;
        }
        return fitFresnelSgQuadraticReport(f);
    }
    if (fit == "blinn-phong-ratio") {
        BlinnPhongRatioFitOptions b;
        if (o.minPower) b.minPower = *o.minPower;
        if (o.maxPower) b.maxPower = *o.maxPower;
        if (o.samples) b.samples = *o.samples;
        return fitBlinnPhongRatioReport(b);
    }
    if (fit == "kv-cone") {
        KvFitOptions k;
        if (o.minPower) k.minPower = *o.minPower;
        if (o.maxPower) k.maxPower = *o.maxPower;
        if (o.samples) k.samples = *o.samples;
        if (o.threshold) k.threshold = *o.threshold;
        if (o.kvAngle) {
            const auto v = parseChoice<KvLobeAngle>(
                "--kv-angle", *o.kvAngle,
                {{"half", KvLobeAngle::HalfAngle}, {"reflected", KvLobeAngle::Reflected}}, "kv-cone");
            if (!v) return Error{v.error()};
            k.definition.angle = *v;
        }
        if (o.kvMeasure) {
            const auto v = parseChoice<KvAngleMeasure>("--kv-measure", *o.kvMeasure,
                                                       {{"radians", KvAngleMeasure::Radians},
                                                        {"half-pi", KvAngleMeasure::RadiansOverHalfPi},
                                                        {"curvature", KvAngleMeasure::Curvature},
                                                        {"solid-angle", KvAngleMeasure::SqrtSolidAngle}},
                                                       "kv-cone");
            if (!v) return Error{v.error()};
            k.definition.measure = *v;
        }
        if (o.kvThreshold) {
            const auto v = parseChoice<KvThreshold>(
                "--kv-threshold", *o.kvThreshold,
                {{"relative", KvThreshold::RelativeToPeak}, {"absolute", KvThreshold::AbsoluteNormalized}},
                "kv-cone");
            if (!v) return Error{v.error()};
            k.definition.threshold = *v;
        }
        return fitKvConeReport(k);
    }
    DiffuseAaFitOptions d;
    if (o.minLength) d.minLength = *o.minLength;
    return fitDiffuseAaReport(d);
}

int runFit(const FitCliOptions& o) {
    const std::vector<std::string> fits = o.what == "all" ? kFits : std::vector<std::string>{o.what};
    for (const auto& use : optionUses(o)) {
        if (!use.given) continue;
        // --metric names differ between fits, so it needs one fit.
        if (o.what == "all" && std::string(use.name) == "--metric")
            return fail("--metric needs a single fit (sg-offset or fresnel-sg-quadratic), not 'all'");
        bool any = false;
        for (const auto& f : fits)
            any = any || appliesTo(use, f);
        if (!any) return fail(fmt::format("{} does not apply to {}", use.name, o.what));
    }

    std::vector<FitReport> reports;
    for (const auto& f : fits) {
        auto r = runOne(f, o);
        if (!r) return fail(r.error());
        reports.push_back(std::move(r).value());
    }

    std::string text;
    if (o.json) {
        text = fitReportsToJson(reports);
    } else {
        for (size_t i = 0; i < reports.size(); ++i)
            text += (i ? "\n" : "") + fitReportToText(reports[i]);
    }
    if (!o.out.empty()) {
        if (const Status s = writeFileAtomic(o.out, text); !s) return fail(s.error());
        return 0;
    }
    std::fwrite(text.data(), 1, text.size(), stdout);
    return 0;
}

const CommandRegistration registration{
    20, [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<FitCliOptions>();
        CLI::App* sub = app.add_subcommand(
            "fit", "Derive the reference texts' constants by least squares (SG offset, SG Fresnel, "
                   "Phong/Blinn ratio, "
                   "Kaplanyan–Valient cone, diffuse-AA curve) and compare with the published values.");
        std::vector<std::string> choices = kFits;
        choices.push_back("all");
        sub->add_option("what", o->what, "Which fit: " + fmt::format("{}", fmt::join(choices, ", ")))
            ->required()
            ->check(CLI::IsMember(choices));
        sub->add_option("--min-power", o->minPower,
                        "Lowest power (sg-offset: integer; blinn-phong-ratio; kv-cone)");
        sub->add_option("--max-power", o->maxPower,
                        "Highest power (sg-offset: integer; blinn-phong-ratio; kv-cone)");
        sub->add_option("--exponent", o->exponent, "Fresnel exponent p in (1 − x)^p (default 5)");
        sub->add_option("--metric", o->metric,
                        "sg-offset: cosine | angle; fresnel-sg-quadratic: linear | relative | log2 | angle");
        sub->add_option("--cut", o->cut,
                        "fresnel-sg-quadratic: upper x of the relative and log2 metrics (default 0.99)");
        sub->add_option("--samples", o->samples, "Powers sampled (blinn-phong-ratio, kv-cone)");
        sub->add_option("--threshold", o->threshold, "kv-cone: highlight threshold t (default 0.5)");
        sub->add_option("--kv-angle", o->kvAngle, "kv-cone: half | reflected (default reflected)");
        sub->add_option("--kv-measure", o->kvMeasure,
                        "kv-cone: radians | half-pi | curvature | solid-angle (default solid-angle)");
        sub->add_option("--kv-threshold", o->kvThreshold,
                        "kv-cone: relative (to the peak) | absolute (NDF value)");
        sub->add_option("--min-length", o->minLength,
                        "diffuse-aa: smallest |Na| of the domain (default 0.95)");
        sub->add_flag("--json", o->json, "Machine-readable output");
        sub->add_option("--out", o->out, "Write the output to FILE (atomically) instead of stdout");
        return [o] { return runFit(*o); };
    }};

} // namespace

} // namespace burnish::cli
