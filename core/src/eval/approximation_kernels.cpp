// The timed loops of the approximations report and of burnish_bench: each kernel evaluates one
// core function (float instantiation) over arrays prepared beforehand and writes an output array.
// Compiled with extra flags (see core/CMakeLists.txt); every kernel is [[gnu::flatten]] so the
// core templates are inlined into it and no copy compiled with those flags is shared with other
// translation units.
#include <burnish/core/eval/approximations.h>

#include <burnish/core/shading/color.h>
#include <burnish/core/shading/fresnel.h>
#include <burnish/core/shading/geometric_aa.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/spherical_gaussian.h>
#include <burnish/core/shading/visibility.h>

#include <fmt/format.h>

#include <cmath>
#include <random>

#ifndef BURNISH_KERNEL_FLAGS
#define BURNISH_KERNEL_FLAGS "(none beyond the build type's)"
#endif

namespace burnish {

namespace {

// Powers are drawn log-uniformly over the range the report measures errors on.
constexpr double kPowerMin = 1.0;
constexpr double kPowerMax = 1e4;
// Visibility directions stop 1° short of grazing, like the error grid (see approximations.cpp).
constexpr double kMaxThetaDeg = 89.0;

// The lights of the Phong pair: four fixed unit directions spread over the upper hemisphere.
constexpr int kPhongLights = 4;
constexpr float kLights[kPhongLights][3] = {
    {0.0f, 0.0f, 1.0f}, {0.6f, 0.0f, 0.8f}, {0.0f, -0.8f, 0.6f}, {-0.48f, 0.36f, 0.8f}};

using Rng = std::mt19937;

std::vector<float> uniform(Rng& rng, size_t count, double lo, double hi) {
    std::uniform_real_distribution<double> u(lo, hi);
    std::vector<float> v(count);
    for (auto& x : v)
        x = static_cast<float>(u(rng));
    return v;
}

std::vector<float> logUniform(Rng& rng, size_t count, double lo, double hi) {
    std::uniform_real_distribution<double> u(std::log(lo), std::log(hi));
    std::vector<float> v(count);
    for (auto& x : v)
        x = static_cast<float>(std::exp(u(rng)));
    return v;
}

/// NoL, NoV, NoH, VoH of random light and view directions with θ_l, θ_v in [0, 89°], φ in [0, π].
KernelInputs visibilityGeometry(size_t count, std::uint32_t seed) {
    Rng rng(seed);
    const double thetaMax = kMaxThetaDeg * kPi<double> / 180.0;
    std::uniform_real_distribution<double> theta(0.0, thetaMax), phi(0.0, kPi<double>);
    KernelInputs in;
    in.streams.assign(4, std::vector<float>(count));
    for (size_t i = 0; i < count; ++i) {
        const double tl = theta(rng), tv = theta(rng), p = phi(rng);
        const double l[3] = {std::sin(tl), 0.0, std::cos(tl)};
        const double v[3] = {std::sin(tv) * std::cos(p), std::sin(tv) * std::sin(p), std::cos(tv)};
        double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
        const double len = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]); // > 0: both within 89°
        for (double& c : h)
            c /= len;
        in.streams[0][i] = static_cast<float>(l[2]);
        in.streams[1][i] = static_cast<float>(v[2]);
        in.streams[2][i] = static_cast<float>(h[2]);
        in.streams[3][i] = static_cast<float>(v[0] * h[0] + v[1] * h[1] + v[2] * h[2]);
    }
    return in;
}

// ---- Kernels. Stream layout in the comment of each group. ----

// in0 = n
[[gnu::flatten]] void normApprox(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = blinnPhongBrdfNormApprox(a.in[0][i]);
}
[[gnu::flatten]] void normExact(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = blinnPhongBrdfNorm(a.in[0][i]);
}

// in0 = c (cosine), in1 = n, in2 = modified power A = n/ln 2
[[gnu::flatten]] void lobeExact(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = powCos(a.in[0][i], a.in[1][i]);
}
[[gnu::flatten]] void lobeSgPlain(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = sgLobe(a.in[0][i], a.in[1][i], float(kSgOffsetPlain));
}
[[gnu::flatten]] void lobeSgLagarde(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = sgLobe(a.in[0][i], a.in[1][i], float(kSgOffsetLagarde));
}
void lobeSgBestFit(const KernelArgs& a, const SgOffsetCurve& curve) {
    // The table lookup (binary search + log) per evaluation is this variant's real cost.
    for (size_t i = 0; i < a.count; ++i) {
        const float x = static_cast<float>(curve(double(a.in[1][i])));
        a.out[i] = sgLobe(a.in[0][i], a.in[1][i], x);
    }
}
[[gnu::flatten]] void lobeSgExp2(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = sgLobeExp2(a.in[0][i], a.in[2][i]);
}

// in0..2 = reflected view vector R, in3 = n, in4 = A = n/ln 2; kPhongLights lights per element.
[[gnu::flatten]] void phongExact(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i) {
        const float R[3] = {a.in[0][i], a.in[1][i], a.in[2][i]};
        float sum = 0.0f;
        for (const auto& L : kLights)
            sum += powCos(R[0] * L[0] + R[1] * L[1] + R[2] * L[2], a.in[3][i]);
        a.out[i] = sum;
    }
}
[[gnu::flatten]] void phongSgDot4(const KernelArgs& a) {
    // Lagarde's dot4 form: A is folded into R once per pixel, each light costs a dot and an exp2.
    for (size_t i = 0; i < a.count; ++i) {
        const float R[3] = {a.in[0][i], a.in[1][i], a.in[2][i]};
        float sum = 0.0f;
        for (const auto& L : kLights)
            sum += sgLobeExp2(R[0] * L[0] + R[1] * L[1] + R[2] * L[2], a.in[4][i]);
        a.out[i] = sum;
    }
}

// in0 = c = cos θ (Phong angle), in1 = n
[[gnu::flatten]] void phongAsBlinnX4(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i) {
        // Half-angle identity: cos(θ/2) = sqrt((1 + cos θ)/2); θ in [0, π/2] keeps the root real.
        const float cHalf = std::sqrt(0.5f * (1.0f + a.in[0][i]));
        a.out[i] = powCos(cHalf, 4.0f * a.in[1][i]);
    }
}

// in0 = F0 (or c), in1 = x, in2 = g
[[gnu::flatten]] void fresnelExactKernel(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = fresnelDielectric(a.in[0][i], a.in[1][i]);
}
[[gnu::flatten]] void fresnelSchlickKernel(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = fresnelSchlick(a.in[0][i], a.in[1][i]);
}
[[gnu::flatten]] void fresnelSgKernel(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = fresnelSchlickSg(a.in[0][i], a.in[1][i]);
}
[[gnu::flatten]] void fresnelSgQuadKernel(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = fresnelSchlickSgQuadratic(a.in[0][i], a.in[1][i]);
}
[[gnu::flatten]] void fresnelGlossyKernel(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = fresnelGlossy(a.in[0][i], a.in[1][i], a.in[2][i]);
}
void fresnelGlossyExactKernel(const KernelArgs& a) {
    // The exact form is a double-precision hemispherical integral per evaluation.
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = static_cast<float>(glossyEnvironmentReference(a.in[1][i], a.in[2][i]).at(a.in[0][i]));
}

// in0 = NoL, in1 = NoV, in2 = NoH (or n for the Smith pair), in3 = VoH
[[gnu::flatten]] void visCookTorrance(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = visibilityCookTorrance(a.in[0][i], a.in[1][i], a.in[2][i], a.in[3][i]);
}
[[gnu::flatten]] void visKelemen(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = visibilityKelemen(a.in[3][i]);
}
[[gnu::flatten]] void visNone(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = visibilityNone<float>();
}
[[gnu::flatten]] void visSchlickSmith(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = visibilitySchlickSmith(a.in[0][i], a.in[1][i], a.in[2][i]);
}
[[gnu::flatten]] void visSmithBeckmann(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = visibilitySmithBeckmann(a.in[0][i], a.in[1][i], beckmannRoughnessFromPower(a.in[2][i]));
}

// in0 = NoH, in1 = n
[[gnu::flatten]] void ndfBlinnPhong(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = blinnPhongNdf(a.in[0][i], a.in[1][i]);
}
[[gnu::flatten]] void ndfBeckmann(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = beckmannNdf(a.in[0][i], beckmannRoughnessFromPower(a.in[1][i]));
}
[[gnu::flatten]] void ndfGgx(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = ggxNdf(a.in[0][i], ggxAlphaFromPower(a.in[1][i]));
}

// in0 = cos α, in1 = |Na|
[[gnu::flatten]] void diffuseAaKernel(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = diffuseAaCurve(a.in[0][i], a.in[1][i]);
}
void diffuseConeExactKernel(const KernelArgs& a) {
    // The exact form is an adaptive quadrature in double per evaluation.
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] =
            static_cast<float>(diffuseConeIntegral(a.in[0][i], coneCosFromNormalLength(double(a.in[1][i]))));
}

// in0 = v (encoded) or L (linear)
[[gnu::flatten]] void srgbDecodeExact(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = srgbToLinear(a.in[0][i]);
}
[[gnu::flatten]] void srgbDecodeGamma22(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = gamma22ToLinear(a.in[0][i]);
}
[[gnu::flatten]] void srgbDecodeGamma20(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = gamma20ToLinear(a.in[0][i]);
}
[[gnu::flatten]] void srgbEncodeExact(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = linearToSrgb(a.in[0][i]);
}
[[gnu::flatten]] void srgbEncodeGamma22(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = linearToGamma22(a.in[0][i]);
}
[[gnu::flatten]] void srgbEncodeGamma20(const KernelArgs& a) {
    for (size_t i = 0; i < a.count; ++i)
        a.out[i] = linearToGamma20(a.in[0][i]);
}

// ---- Input makers ----

KernelInputs powerInputs(size_t count, std::uint32_t seed) {
    Rng rng(seed);
    return {{logUniform(rng, count, kPowerMin, kPowerMax)}};
}

/// c uniform in [0, 1], n log-uniform, A = n/ln 2 (the "modified power" a gloss decode produces).
KernelInputs lobeInputs(size_t count, std::uint32_t seed) {
    Rng rng(seed);
    KernelInputs in{{uniform(rng, count, 0.0, 1.0), logUniform(rng, count, kPowerMin, kPowerMax)}};
    std::vector<float> A(count);
    for (size_t i = 0; i < count; ++i)
        A[i] = static_cast<float>(double(in.streams[1][i]) / kLn2<double>);
    in.streams.push_back(std::move(A));
    return in;
}

/// R uniform on the unit sphere, n log-uniform, A = n/ln 2.
KernelInputs phongInputs(size_t count, std::uint32_t seed) {
    Rng rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0), phi(0.0, 2.0 * kPi<double>);
    KernelInputs in;
    in.streams.assign(3, std::vector<float>(count));
    for (size_t i = 0; i < count; ++i) {
        const double z = u(rng), p = phi(rng), r = std::sqrt(std::max(0.0, 1.0 - z * z));
        in.streams[0][i] = static_cast<float>(r * std::cos(p));
        in.streams[1][i] = static_cast<float>(r * std::sin(p));
        in.streams[2][i] = static_cast<float>(z);
    }
    in.streams.push_back(logUniform(rng, count, kPowerMin, kPowerMax));
    std::vector<float> A(count);
    for (size_t i = 0; i < count; ++i)
        A[i] = static_cast<float>(double(in.streams[3][i]) / kLn2<double>);
    in.streams.push_back(std::move(A));
    return in;
}

KernelInputs fresnelInputs(size_t count, std::uint32_t seed, double cMin, double cMax) {
    Rng rng(seed);
    return {{uniform(rng, count, cMin, cMax), uniform(rng, count, 0.0, 1.0), uniform(rng, count, 0.0, 1.0)}};
}

KernelInputs smithInputs(size_t count, std::uint32_t seed) {
    KernelInputs in = visibilityGeometry(count, seed);
    Rng rng(seed + 1);
    return {{in.streams[0], in.streams[1], logUniform(rng, count, kPowerMin, kPowerMax)}};
}

KernelInputs ndfInputs(size_t count, std::uint32_t seed) {
    Rng rng(seed);
    return {{uniform(rng, count, 0.0, 1.0), logUniform(rng, count, kPowerMin, kPowerMax)}};
}

KernelInputs diffuseAaInputs(size_t count, std::uint32_t seed) {
    Rng rng(seed);
    return {{uniform(rng, count, -1.0, 1.0), uniform(rng, count, kDiffuseAaMinLength, 1.0)}};
}

KernelInputs unitInputs(size_t count, std::uint32_t seed) {
    Rng rng(seed);
    return {{uniform(rng, count, 0.0, 1.0)}};
}

// Quadrature-based exact forms: a handful of evaluations already takes milliseconds.
constexpr size_t kGlossyExactCap = 8;
constexpr size_t kConeExactCap = 2048;

} // namespace

const std::vector<TimedKernelPair>& timedKernelPairs() {
    static const std::vector<TimedKernelPair> pairs = [] {
        const SgOffsetCurve* curve = &reportSgOffsetCurve();
        auto fresnelF0 = [](size_t n, std::uint32_t s) { return fresnelInputs(n, s, 0.02, 0.08); };
        auto glossyIn = [](size_t n, std::uint32_t s) { return fresnelInputs(n, s, 0.02, 1.0); };
        std::vector<TimedKernelPair> v;
        v.push_back({"norm-blinn-phong-brdf", normApprox, normExact, powerInputs});
        v.push_back({"sg-blinn-x0", lobeSgPlain, lobeExact, lobeInputs});
        v.push_back({"sg-blinn-x0775", lobeSgLagarde, lobeExact, lobeInputs});
        v.push_back({"sg-blinn-bestfit", [curve](const KernelArgs& a) { lobeSgBestFit(a, *curve); },
                     lobeExact, lobeInputs});
        v.push_back({"sg-blinn-exp2", lobeSgExp2, lobeExact, lobeInputs});
        v.push_back({"sg-phong-dot4", phongSgDot4, phongExact, phongInputs, double(kPhongLights)});
        v.push_back({"phong-as-blinn-x4", phongAsBlinnX4, lobeExact, ndfInputs});
        v.push_back({"fresnel-schlick", fresnelSchlickKernel, fresnelExactKernel, fresnelF0});
        v.push_back({"fresnel-sg", fresnelSgKernel, fresnelSchlickKernel, fresnelF0});
        v.push_back({"fresnel-sg-quadratic", fresnelSgQuadKernel, fresnelSchlickKernel, fresnelF0});
        v.push_back({"fresnel-glossy", fresnelGlossyKernel, fresnelGlossyExactKernel, glossyIn, 1.0,
                     kGlossyExactCap});
        v.push_back({"vis-kelemen", visKelemen, visCookTorrance, visibilityGeometry});
        v.push_back({"vis-none", visNone, visCookTorrance, visibilityGeometry});
        v.push_back({"vis-schlick-smith", visSchlickSmith, visSmithBeckmann, smithInputs});
        v.push_back({"ndf-blinn-for-beckmann", ndfBlinnPhong, ndfBeckmann, ndfInputs});
        v.push_back({"ndf-ggx-for-blinn", ndfGgx, ndfBlinnPhong, ndfInputs});
        v.push_back({"diffuse-aa-curve", diffuseAaKernel, diffuseConeExactKernel, diffuseAaInputs, 1.0,
                     kConeExactCap});
        v.push_back({"srgb-decode-gamma22", srgbDecodeGamma22, srgbDecodeExact, unitInputs});
        v.push_back({"srgb-decode-gamma20", srgbDecodeGamma20, srgbDecodeExact, unitInputs});
        v.push_back({"srgb-encode-gamma22", srgbEncodeGamma22, srgbEncodeExact, unitInputs});
        v.push_back({"srgb-encode-gamma20", srgbEncodeGamma20, srgbEncodeExact, unitInputs});
        return v;
    }();
    return pairs;
}

std::string kernelBuildDescription() {
    std::string isa = "x86-64 baseline";
#if defined(__AVX512F__)
    isa = "AVX-512";
#elif defined(__AVX2__)
    isa = "AVX2";
#elif defined(__AVX__)
    isa = "AVX";
#elif defined(__SSE4_2__)
    isa = "SSE4.2";
#elif defined(__SSE2__)
    isa = "SSE2";
#endif
#if defined(__FAST_MATH__)
    const char* math = "fast-math";
#else
    const char* math = "IEEE semantics kept (no fast-math): exp/log/pow/erf are scalar libm calls";
#endif
#if defined(__OPTIMIZE__)
    const char* opt = "optimized";
#else
    const char* opt = "NOT optimized (debug build: costs are not representative)";
#endif
    return fmt::format("kernel flags {}; {}; {}; {}", BURNISH_KERNEL_FLAGS, opt, isa, math);
}

} // namespace burnish
