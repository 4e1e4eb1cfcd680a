#include <burnish/core/prefilter/gloss.h>

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/numeric.h>

#include <charconv>
#include <cmath>

namespace burnish {

namespace {

const double kMinAlpha = kMinRoughness;

double powerFromAlpha(double alpha) {
    return powerFromGgxAlpha(std::max(alpha, kMinAlpha));
}

bool parseDouble(std::string_view text, double& out) {
    const char* first = text.data();
    const char* last = text.data() + text.size();
    auto [ptr, ec] = std::from_chars(first, last, out);
    return ec == std::errc() && ptr == last && std::isfinite(out);
}

} // namespace

GlossEncoding::GlossEncoding(GlossKind kind, double nMin, double nMax, std::string name, std::string formula)
    : m_kind(kind)
    , m_nMin(nMin)
    , m_nMax(nMax)
    , m_log2Range(kind == GlossKind::LogPower ? log2Positive(nMax / nMin) : 0.0)
    , m_minPower(nMin)
    , m_maxPower(nMax)
    , m_name(std::move(name))
    , m_formula(std::move(formula)) {
    if (kind != GlossKind::LogPower) {
        m_minPower = power(increasesWithPower() ? 0.0 : 1.0);
        m_maxPower = power(increasesWithPower() ? 1.0 : 0.0);
    }
}

GlossEncoding GlossEncoding::blackOps() {
    return GlossEncoding(GlossKind::LogPower, 1.0, 8192.0, "blackops",
                         "n = 8192^g = 2^(13g), n in [1, 8192]");
}

GlossEncoding GlossEncoding::exp2Range() {
    return GlossEncoding(GlossKind::LogPower, 2.0, 2048.0, "exp2", "n = exp2(10g + 1), n in [2, 2048]");
}

Result<GlossEncoding> GlossEncoding::logRange(double nMin, double nMax) {
    if (!(nMin > 0.0) || !(nMax > nMin) || !(nMax <= kMaxPower))
        return Error{"gloss range must satisfy 0 < n_min < n_max <= 1e9 (got [" + std::to_string(nMin) +
                     ", " + std::to_string(nMax) + "])"};
    char buf[128];
    std::snprintf(buf, sizeof buf, "log:%g:%g", nMin, nMax);
    std::string name = buf;
    std::snprintf(buf, sizeof buf, "n = %g * (%g/%g)^g, n in [%g, %g]", nMin, nMax, nMin, nMin, nMax);
    return GlossEncoding(GlossKind::LogPower, nMin, nMax, name, buf);
}

GlossEncoding GlossEncoding::ggxRoughness() {
    return GlossEncoding(GlossKind::GgxRoughness, 0.0, kMaxPower, "ggx-roughness",
                         "r = perceptual roughness, alpha = r^2, n = 2/alpha^2 - 2");
}

GlossEncoding GlossEncoding::ggxAlpha() {
    return GlossEncoding(GlossKind::GgxAlpha, 0.0, kMaxPower, "ggx-alpha", "alpha stored, n = 2/alpha^2 - 2");
}

GlossEncoding GlossEncoding::beckmann() {
    return GlossEncoding(GlossKind::BeckmannM, 0.0, kMaxPower, "beckmann", "m stored, n = 2/m^2 - 2");
}

GlossEncoding GlossEncoding::smoothness() {
    return GlossEncoding(GlossKind::Smoothness, 0.0, kMaxPower, "smoothness",
                         "s = 1 - r, alpha = r^2, n = 2/alpha^2 - 2");
}

std::vector<std::string> GlossEncoding::presetNames() {
    return {"blackops", "exp2", "ggx-roughness", "ggx-alpha", "beckmann", "smoothness"};
}

Result<GlossEncoding> GlossEncoding::fromName(std::string_view name) {
    if (name == "blackops") return blackOps();
    if (name == "exp2") return exp2Range();
    if (name == "ggx-roughness") return ggxRoughness();
    if (name == "ggx-alpha") return ggxAlpha();
    if (name == "beckmann") return beckmann();
    if (name == "smoothness") return smoothness();
    if (name.substr(0, 4) == "log:") {
        const std::string_view rest = name.substr(4);
        const auto colon = rest.find(':');
        double nMin = 0.0;
        double nMax = 0.0;
        if (colon != std::string_view::npos && parseDouble(rest.substr(0, colon), nMin) &&
            parseDouble(rest.substr(colon + 1), nMax))
            return logRange(nMin, nMax);
        return Error{"gloss encoding '" + std::string(name) + "' is not of the form log:NMIN:NMAX"};
    }
    std::string known;
    for (const auto& n : presetNames())
        known += (known.empty() ? "" : ", ") + n;
    return Error{"unknown gloss encoding '" + std::string(name) + "' (known: " + known + ", log:NMIN:NMAX)"};
}

std::string_view GlossEncoding::quantity() const {
    switch (m_kind) {
    case GlossKind::LogPower:
        return "gloss";
    case GlossKind::GgxRoughness:
    case GlossKind::BeckmannM:
        return "roughness";
    case GlossKind::GgxAlpha:
        return "alpha";
    case GlossKind::Smoothness:
        return "smoothness";
    }
    return "gloss";
}

std::string_view GlossEncoding::symbol() const {
    switch (m_kind) {
    case GlossKind::LogPower:
        return "g";
    case GlossKind::GgxRoughness:
        return "r";
    case GlossKind::BeckmannM:
        return "m";
    case GlossKind::GgxAlpha:
        return "\u03b1";
    case GlossKind::Smoothness:
        return "s";
    }
    return "g";
}

double GlossEncoding::power(double v) const {
    v = saturate(v);
    switch (m_kind) {
    case GlossKind::LogPower:
        return clampPower(m_nMin * std::pow(m_nMax / m_nMin, v));
    case GlossKind::GgxRoughness:
        return powerFromAlpha(v * v);
    case GlossKind::GgxAlpha:
    case GlossKind::BeckmannM:
        return powerFromAlpha(v);
    case GlossKind::Smoothness:
        return powerFromAlpha((1.0 - v) * (1.0 - v));
    }
    return 0.0;
}

double GlossEncoding::value(double n) const {
    n = std::clamp(clampPower(n), minPower(), maxPower());
    switch (m_kind) {
    case GlossKind::LogPower:
        return logPowerValue(n);
    case GlossKind::GgxRoughness:
        return saturate(std::sqrt(ggxAlphaFromPower(n)));
    case GlossKind::GgxAlpha:
    case GlossKind::BeckmannM:
        return saturate(ggxAlphaFromPower(n));
    case GlossKind::Smoothness:
        return saturate(1.0 - std::sqrt(ggxAlphaFromPower(n)));
    }
    return 0.0;
}

void GlossEncoding::values(const double* powers, float* out, size_t count) const {
    if (m_kind != GlossKind::LogPower) {
        for (size_t i = 0; i < count; ++i)
            out[i] = float(value(powers[i]));
        return;
    }
    for (size_t i = 0; i < count; ++i)
        out[i] = float(logPowerValue(powers[i]));
}

double GlossEncoding::minPower() const {
    return m_minPower;
}
double GlossEncoding::maxPower() const {
    return m_maxPower;
}

bool GlossEncoding::increasesWithPower() const {
    return m_kind == GlossKind::LogPower || m_kind == GlossKind::Smoothness;
}

double varianceFromPower(double n, VarianceConvention convention) {
    n = clampPower(n);
    switch (convention) {
    case VarianceConvention::InversePower:
        return 1.0 / std::max(n, kMinVariance);
    case VarianceConvention::InversePowerPlusOne:
        return 1.0 / (n + 1.0);
    case VarianceConvention::InversePowerPlusTwo:
        return 1.0 / (n + 2.0);
    }
    return 0.0;
}

double powerFromVariance(double v, VarianceConvention convention) {
    // The smallest variance is that of kMaxPower under the same convention, so v = 0 maps to it.
    const double vMin = varianceFromPower(kMaxPower, convention);
    v = v > vMin ? v : vMin; // NaN -> vMin
    switch (convention) {
    case VarianceConvention::InversePower:
        return clampPower(1.0 / v);
    case VarianceConvention::InversePowerPlusOne:
        return clampPower(1.0 / v - 1.0);
    case VarianceConvention::InversePowerPlusTwo:
        return clampPower(1.0 / v - 2.0);
    }
    return 0.0;
}

double toksvigVariance(double lenNa) {
    lenNa = lenNa > 0.0 ? std::min(lenNa, 1.0) : 0.0;
    if (lenNa <= kMinVariance) return 1.0 / kMinVariance;
    return std::min((1.0 - lenNa) / lenNa, 1.0 / kMinVariance);
}

double toksvigFactor(double lenNa, double s) {
    lenNa = lenNa > 0.0 ? std::min(lenNa, 1.0) : 0.0;
    s = clampPower(s);
    const double denom = lenNa + s * (1.0 - lenNa);
    // denom is 0 only for |Na| = 0 and s = 0 (or |Na| = 1 and ... never): a power of 0 stays 0.
    return denom > 0.0 ? lenNa / denom : 1.0;
}

double toksvigPower(double lenNa, double s) {
    return std::clamp(toksvigFactor(lenNa, s) * clampPower(s), 0.0, clampPower(s));
}

double convertToksvigFactor(double ft, double fixedS, double s) {
    ft = ft > 0.0 ? std::min(ft, 1.0) : 0.0;
    fixedS = std::max(clampPower(fixedS), kMinVariance);
    const double ratio = clampPower(s) / fixedS;
    const double denom = ratio + (1.0 - ratio) * ft; // lerp(s/fixed_s, 1, ft)
    return denom > 0.0 ? std::min(ft / denom, 1.0) : 1.0;
}

double decodeLogVariance(double g) {
    return std::exp2(-13.0 * saturate(g));
}

double varianceToGloss(double g, double v, const GlossEncoding& encoding) {
    // Projected variance 1 − (n_i·n̄)² lies in [0, 1]; the power is the bake's varianceToGlossPower,
    // clamped to the encoding's range by value().
    return encoding.value(varianceToGlossPower(saturate(v), encoding.power(g)));
}

} // namespace burnish
