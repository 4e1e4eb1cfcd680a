// Gloss encodings (what a texture channel stores) and conversions between specular power,
// normal variance and the Toksvig factor. Every conversion is monotonic, clamps its input to the
// encoding's domain, and returns finite values for all inputs including NaN (treated as the
// domain's lower end).
#pragma once

#include <burnish/core/shading/lobe_shading.h>
#include <burnish/core/util/numeric.h>
#include <burnish/core/util/result.h>

#include <string>
#include <string_view>
#include <vector>

namespace burnish {

/// How a stored channel value v in [0, 1] maps to a Blinn-Phong power n.
enum class GlossKind {
    /// n = nMin·(nMax/nMin)^v: log-space gloss. nMin = 1, nMax = 8192 is Black Ops' 8192^g = 2^(13g)
    /// (Lazarov 2011); nMin = 2, nMax = 2048 is exp2(10g+1) (Lagarde 2011).
    LogPower,
    /// v = GGX perceptual roughness r, α = r², n = 2/α² − 2 (glTF, Unreal, Filament, Godot).
    GgxRoughness,
    /// v = GGX α directly, n = 2/α² − 2.
    GgxAlpha,
    /// v = Beckmann RMS slope m, n = 2/m² − 2 (Lazarov 2011).
    BeckmannM,
    /// v = smoothness = 1 − r, with r the GGX perceptual roughness (Unity).
    Smoothness,
};

/// One gloss encoding with its parameters. Roughness-like kinds decrease in power as v grows;
/// increasesWithPower() tells the direction.
class GlossEncoding {
public:
    /// Black Ops: n = 8192^g = 2^(13g), n in [1, 8192].
    static GlossEncoding blackOps();
    /// n = exp2(10g + 1), n in [2, 2048].
    static GlossEncoding exp2Range();
    /// n = nMin·(nMax/nMin)^g for a configurable range; fails unless 0 < nMin < nMax <= kMaxPower.
    static Result<GlossEncoding> logRange(double nMin, double nMax);
    static GlossEncoding ggxRoughness();
    static GlossEncoding ggxAlpha();
    static GlossEncoding beckmann();
    static GlossEncoding smoothness();

    /// Looks an encoding up by name: "blackops", "exp2", "ggx-roughness", "ggx-alpha", "beckmann",
    /// "smoothness", or "log:NMIN:NMAX".
    static Result<GlossEncoding> fromName(std::string_view name);
    /// The names fromName accepts (without the log:NMIN:NMAX form).
    static std::vector<std::string> presetNames();

    GlossKind kind() const { return m_kind; }
    /// What the stored value is called where an artist reads it: "gloss" (log-power encodings),
    /// "roughness" (GGX perceptual roughness, Beckmann's m), "alpha", "smoothness".
    std::string_view quantity() const;
    /// Its one-letter symbol for tight labels: "g", "r", "α" (UTF-8), "m", "s".
    std::string_view symbol() const;
    const std::string& name() const { return m_name; }
    /// A one-line formula for reports and --help, e.g. "n = 8192^g".
    const std::string& formula() const { return m_formula; }

    /// Power for a stored value; v is clamped to [0, 1].
    double power(double v) const;
    /// Stored value for a power; n is clamped to [powerAtMin(), powerAtMax()] in power order.
    double value(double n) const;
    /// value() of `count` powers as floats (a bake's row); for the log-power encodings a loop
    /// without calls that the compiler vectorises.
    void values(const double* powers, float* out, size_t count) const;
    /// The powers the encoding can represent (lowest and highest).
    double minPower() const;
    double maxPower() const;
    bool increasesWithPower() const;

    friend bool operator==(const GlossEncoding&, const GlossEncoding&) = default;

private:
    GlossEncoding(GlossKind kind, double nMin, double nMax, std::string name, std::string formula);
    /// value() of the log-power kind: g = log2(n/nMin)/log2(nMax/nMin), n clamped to the range with
    /// selects and the logarithms log2Positive's (within 2e-14 of std::log2), so g is exactly 0
    /// and 1 at the range's ends and a row of it vectorises.
    double logPowerValue(double n) const {
        n = clampPower(n);
        n = n > m_minPower ? n : m_minPower;
        n = n < m_maxPower ? n : m_maxPower;
        const double g = log2Positive(n / m_nMin) / m_log2Range; // n/nMin >= 1: a normal double
        return g < 1.0 ? g : 1.0;
    }

    GlossKind m_kind;
    double m_nMin;
    double m_nMax;
    double m_log2Range; // log2(nMax/nMin), computed once: value() runs per texel in the bake
    double m_minPower;  // minPower() and maxPower(), computed once for the same reason
    double m_maxPower;
    std::string m_name;
    std::string m_formula;
};

/// The BRDF the engine that reads this encoding shades with: GGX for the roughness kinds (glTF,
/// Unreal, Unity, Godot, Filament), Blinn-Phong for log-power gloss and Beckmann m.
inline Brdf glossBrdf(const GlossEncoding& encoding) {
    const GlossKind k = encoding.kind();
    return k == GlossKind::GgxRoughness || k == GlossKind::GgxAlpha || k == GlossKind::Smoothness
               ? Brdf::Ggx
               : Brdf::BlinnPhong;
}

/// How normal variance relates to a specular power; each text makes its own choice.
enum class VarianceConvention {
    /// σ² = 1/n: Toksvig 2004 (p = s/(1+σ²s), i.e. 1/p = 1/s + σ²), LEAN's 1/s on M's diagonal
    /// (Olano & Baker 2010) and the detail-map rule 1/s' = 1/s + σ² (Baker & Hill 2012).
    InversePower,
    /// σ² = 1/(n+1): Lazarov 2011's variance-to-gloss (v' = v + 1/(n+1), g = log(1/v'' − 1)/log(nMax)).
    InversePowerPlusOne,
    /// σ² = 1/(n+2): the per-axis slope variance m²/2 of the Beckmann lobe with m² = 2/(n+2).
    InversePowerPlusTwo,
};

/// Variance of power n under a convention; n clamped to [0, kMaxPower].
double varianceFromPower(double n, VarianceConvention convention);
/// Power of variance v under a convention; v is clamped to at least the variance of kMaxPower,
/// so v = 0 gives kMaxPower, and the result is never negative.
double powerFromVariance(double v, VarianceConvention convention);

/// Toksvig's variance estimate from the length of the mean normal, clamped to [0, 1/kMinVariance].
// Toksvig 2004 via Baker & Hill 2012: σ² = (1 − |Na|)/|Na|
double toksvigVariance(double lenNa);
/// The Toksvig factor f_t for base power s: the adjusted power is f_t·s; |Na| -> 0 gives 0.
// Toksvig 2004 via Hill 2011: f_t = |Na| / (|Na| + s(1 − |Na|))
double toksvigFactor(double lenNa, double s);
/// f_t·s, never below 0 nor above s.
double toksvigPower(double lenNa, double s);
/// Converts a Toksvig factor baked for power fixedS to the factor for power s.
// Hill 2011, "Specular Showdown in the Wild West": ft /= lerp(s/fixed_s, 1, ft)
double convertToksvigFactor(double ft, double fixedS, double s);

/// The two-value log-space encoding of a per-axis slope variance: g = log2(1/Σ)/13 in [0, 1]. Σ is
/// clamped to [2^-13, 1] first (NaN and Σ <= 0 give g = 1), which is the clamp of g, so the
/// logarithm is log2Positive's and a row of them vectorises.
// Baker & Hill 2012, "Rock-Solid Shading": store log2(1/Σ_{x,y})/13
inline double encodeLogVariance(double sigma2) {
    sigma2 = sigma2 > 0x1p-13 ? sigma2 : 0x1p-13; // NaN fails the test
    sigma2 = sigma2 < 1.0 ? sigma2 : 1.0;
    return (0.0 - log2Positive(sigma2)) / 13.0; // 0 − x: +0, not −0, at Σ = 1
}
/// Inverse of encodeLogVariance: Σ = 2^(−13g).
double decodeLogVariance(double g);

/// Lazarov's variance-to-gloss step for one texel: the authored gloss g's power n with the projected
/// normal variance v (clamped to [0, 1]) added as 1/(n+1) — varianceToGlossPower (methods.h), the
/// bake's formula — then the power clamped to the encoding's range and encoded as the new gloss.
// Lazarov 2011: v' = v + 1/(n+1); n' = 1/v' − 1 in [nMin, nMax]; back to gloss
double varianceToGloss(double g, double v, const GlossEncoding& encoding);

} // namespace burnish
