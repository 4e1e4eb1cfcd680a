// The GLSL twins of core's shading math (resources/shaders/*.glsl) against core: twins.frag evaluates
// one group of functions per pixel of a small RGBA32F target, on arguments read from RGBA32F
// textures; the test evaluates core (in double) on the same float arguments and compares.
//
// Tolerances. The shaders compute in float32, core in double, on identical inputs, so the difference
// is the shader's own rounding. Rational formulas of a few operations stay within a few float ULPs
// (ε = 2^-24 ≈ 6e-8 per operation). Lobes evaluated as exp(E) carry the exponent's relative error
// into an absolute one: E up to ~88 in magnitude with a relative error of a few ε gives ~1e-5, and
// llvmpipe's exp/log polynomials add a few ULPs. Values spanning decades are compared relative to
// |core| above a named floor and absolutely below it.
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/shading/fresnel.h>
#include <burnish/core/shading/geometric_aa.h>
#include <burnish/core/shading/ggx_specular.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/specular_aa.h>
#include <burnish/core/shading/spherical_gaussian.h>
#include <burnish/core/shading/visibility.h>
#include <burnish/core/util/numeric.h>
#include <burnish/render/context.h>
#include <burnish/render/gpu_resources.h>
#include <burnish/render/program.h>
#include <burnish/render/shader_source.h>

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace burnish::render {
namespace {

// The TWIN numbers of twins.frag.
enum Twin {
    kTwinIdentity = 0,
    kTwinNumeric = 1,
    kTwinNdfNormA = 2,
    kTwinNdfNormB = 3,
    kTwinNdf = 4,
    kTwinNdfBridge = 5,
    kTwinFresnelA = 6,
    kTwinFresnelB = 7,
    kTwinFresnelIor = 8,
    kTwinVisibilityA = 9,
    kTwinVisibilityB = 10,
    kTwinSg = 11,
    kTwinGeometricAaA = 12,
    kTwinGeometricAaB = 13,
    kTwinSpecularAa = 14,
    kTwinSpecularAaDerivatives = 15,
    kTwinGloss = 16,
    kTwinToksvig = 17,
    kTwinMethodPowers = 18,
    kTwinLeanClean = 19,
    kTwinSlopeNdf = 20,
    kTwinIsotropicNdf = 21,
    kTwinMixtureLobe = 22,
    kTwinMixtureValue = 23,
    kTwinStochasticTexel = 24,
    kTwinStochasticNumbers = 25,
    kTwinGgxSpecular = 26,
    kTwinGgxAnisotropic = 27,
    kTwinFresnelRgbFirst = 30,
};

// 64×64 pixels: room for every argument slice below, small enough for llvmpipe to draw instantly.
constexpr int kSize = 64;
constexpr size_t kCapacity = size_t(kSize) * kSize;

constexpr double kEps = 5.96e-8; // float32 unit round-off, 2^-24

// Few-operation rational formulas (sums, products, one division or sqrt): 20 ULPs of margin.
constexpr double kRationalRel = 20.0 * kEps;
// Formulas through exp/exp2/log with arguments up to ~88 in magnitude: 88·(a few ε) plus the
// polynomial error of llvmpipe's exp/log.
constexpr double kExpRel = 5e-5;
// Values below this are compared absolutely (times the relative tolerance): the smallest normal
// float is 1.2e-38, and a lobe value below 1e-30 of its peak is invisible.
constexpr double kTinyFloor = 1e-30;
// Unit-range results (cosines, Fresnel, gloss values in [0, 1]): absolute comparison at the scale 1.
constexpr double kUnitFloor = 1.0;

using Args = std::array<float, 8>; // a.xyzw, b.xyzw of twins.frag
using Ref = std::function<std::array<double, 4>(const Args&)>;

struct Tolerance {
    double rel = kRationalRel;
    double floor = kTinyFloor;
};

// Every combination of the given values (axis 0 varies fastest); missing axes are 0.
std::vector<Args> product(const std::vector<std::vector<float>>& axes) {
    std::vector<Args> out(1, Args{});
    for (size_t axis = 0; axis < axes.size(); ++axis) {
        std::vector<Args> next;
        for (const Args& base : out)
            for (const float v : axes[axis]) {
                Args args = base;
                args[axis] = v;
                next.push_back(args);
            }
        out = std::move(next);
    }
    return out;
}

// Slices over each argument's range, the extremes included.
const std::vector<float> kPowers{0.0f,   1e-3f,   0.5f,    1.0f, 2.0f, 8.0f, 32.0f, 100.0f,
                                 512.0f, 2048.0f, 8192.0f, 1e5f, 1e6f, 1e9f, 4e9f};
const std::vector<float> kCosines{0.0f,      1e-7f, 1e-6f, 1e-3f,  0.01f,  0.1f,    0.3f,
                                  0.5f,      0.7f,  0.9f,  0.99f,  0.999f, 0.9999f, 0.99999f,
                                  0.999999f, 1.0f,  -0.5f, -1e-3f, 1.5f};
const std::vector<float> kUnit{0.0f, 1e-6f, 0.01f, 0.04f, 0.1f,      0.25f,
                               0.5f, 0.75f, 0.9f,  0.99f, 0.999999f, 1.0f};
const std::vector<float> kRoughness{0.0f, 1e-5f, 4.47e-5f, 1e-3f, 0.01f, 0.1f,
                                    0.3f, 0.5f,  0.8f,     0.99f, 1.0f,  2.0f};

// The full-screen triangle, from gl_VertexID (no attributes).
constexpr const char* kVertexSource = R"(#version 330 core
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

class Twins : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        auto context = createHeadlessContext();
        if (context) {
            s_context = std::move(context).value();
        } else {
            s_contextError = context.error();
        }
    }
    static void TearDownTestSuite() { s_context.reset(); }

    void SetUp() override {
        ASSERT_TRUE(s_context) << "no headless OpenGL context: " << s_contextError;
        ASSERT_TRUE(s_context->makeCurrent());
    }

    // Evaluates twin `twin` of twins.frag on each argument set; one RGBA result per set.
    static std::vector<std::array<float, 4>> evaluate(int twin, const std::vector<Args>& args) {
        auto fragment = assembleShader("twins.frag", {{"TWIN", std::to_string(twin)}});
        EXPECT_TRUE(fragment) << fragment.error();
        if (!fragment) return {};
        return evaluateSource(*fragment, "twins.frag TWIN=" + std::to_string(twin), args);
    }

    // Evaluates a fragment shader that reads uInputs and uInputs2 at its pixel and writes fragColor.
    static std::vector<std::array<float, 4>>
    evaluateSource(const std::string& fragment, const std::string& label, const std::vector<Args>& args) {
        EXPECT_LE(args.size(), kCapacity);
        std::vector<float> a(kCapacity * 4, 0.0f);
        std::vector<float> b(kCapacity * 4, 0.0f);
        for (size_t i = 0; i < kCapacity; ++i) {
            // Pixels past the slice repeat its last argument set (never compared).
            const Args& arg = args[std::min(i, args.size() - 1)];
            std::copy(arg.begin(), arg.begin() + 4, a.begin() + ptrdiff_t(i * 4));
            std::copy(arg.begin() + 4, arg.end(), b.begin() + ptrdiff_t(i * 4));
        }
        auto texA = Texture2D::create({TextureLevel{kSize, kSize, a}}, 4, TextureFilter::Nearest, false);
        auto texB = Texture2D::create({TextureLevel{kSize, kSize, b}}, 4, TextureFilter::Nearest, false);
        EXPECT_TRUE(texA && texB) << (texA ? texB.error() : texA.error());
        if (!texA || !texB) return {};
        auto program = Program::fromSources(kVertexSource, fragment, label);
        EXPECT_TRUE(program) << program.error();
        if (!program) return {};
        auto target = Framebuffer::create(kSize, kSize, ColorFormat::Rgba32f, false);
        EXPECT_TRUE(target) << target.error();
        if (!target) return {};

        target->bind();
        program->use();
        texA->bind(0);
        texB->bind(1);
        program->set("uInputs", 0);
        program->set("uInputs2", 1);
        glDisable(GL_BLEND);
        glDisable(GL_DEPTH_TEST);
        FullscreenTriangle triangle;
        triangle.draw();
        const std::vector<float> pixels = target->readRgbaFloat();
        EXPECT_EQ(pixels.size(), kCapacity * 4);
        std::vector<std::array<float, 4>> out(args.size());
        for (size_t i = 0; i < args.size() && i * 4 + 3 < pixels.size(); ++i)
            out[i] = {pixels[i * 4], pixels[i * 4 + 1], pixels[i * 4 + 2], pixels[i * 4 + 3]};
        return out;
    }

    // Runs the twin, asserts every output channel finite and the first `channels` within tolerance
    // of core. Prints the largest error relative to the tolerance per channel (the measured margin).
    static void expectTwin(const char* label, int twin, const std::vector<Args>& args, const Ref& reference,
                           const std::array<Tolerance, 4>& tolerance, int channels) {
        expectResults(label, evaluate(twin, args), args, reference, tolerance, channels);
    }

    // expectTwin's comparison of results `gpu` (one per argument set) with core.
    static void expectResults(const char* label, const std::vector<std::array<float, 4>>& gpu,
                              const std::vector<Args>& args, const Ref& reference,
                              const std::array<Tolerance, 4>& tolerance, int channels) {
        ASSERT_LE(args.size(), kCapacity) << label;
        ASSERT_EQ(gpu.size(), args.size()) << label;
        std::array<double, 4> worst{};
        int failures = 0;
        for (size_t i = 0; i < args.size(); ++i) {
            const auto cpu = reference(args[i]);
            for (int c = 0; c < 4; ++c) {
                ASSERT_TRUE(std::isfinite(gpu[i][size_t(c)])) << label << " channel " << c << " sample " << i;
                if (c >= channels) continue;
                const double expected = cpu[size_t(c)];
                ASSERT_TRUE(std::isfinite(expected)) << label;
                const double scale = std::max(std::abs(expected), tolerance[size_t(c)].floor);
                const double error = std::abs(double(gpu[i][size_t(c)]) - expected) / scale;
                worst[size_t(c)] = std::max(worst[size_t(c)], error / tolerance[size_t(c)].rel);
                if (error > tolerance[size_t(c)].rel && ++failures <= 8) {
                    ADD_FAILURE() << label << " channel " << c << ": GLSL " << gpu[i][size_t(c)]
                                  << " vs core " << expected << " (relative error " << error << " > "
                                  << tolerance[size_t(c)].rel << ") at a = (" << args[i][0] << ", "
                                  << args[i][1] << ", " << args[i][2] << ", " << args[i][3] << "), b = ("
                                  << args[i][4] << ", " << args[i][5] << ", " << args[i][6] << ", "
                                  << args[i][7] << ")";
                }
            }
        }
        EXPECT_EQ(failures, 0) << label;
        std::printf("[ twin     ] %-28s %4zu samples, worst error / tolerance:", label, args.size());
        for (int c = 0; c < channels; ++c)
            std::printf(" %.3f", worst[size_t(c)]);
        std::printf("\n");
    }

    static std::unique_ptr<GlContext> s_context;
    static std::string s_contextError;
};

std::unique_ptr<GlContext> Twins::s_context;
std::string Twins::s_contextError;

constexpr Tolerance kRational{kRationalRel, kTinyFloor};
constexpr Tolerance kExp{kExpRel, kTinyFloor};
constexpr Tolerance kUnitRational{kRationalRel, kUnitFloor};
constexpr Tolerance kUnitExp{kExpRel, kUnitFloor};

double d(float x) {
    return double(x);
}

TEST_F(Twins, InputsRoundTripExactly) {
    // The plumbing every other twin relies on: argument i comes back as result i, bit for bit.
    const auto args = product({kCosines, kPowers});
    const auto gpu = evaluate(kTwinIdentity, args);
    ASSERT_EQ(gpu.size(), args.size());
    for (size_t i = 0; i < args.size(); ++i)
        for (size_t c = 0; c < 4; ++c)
            ASSERT_EQ(gpu[i][c], args[i][c]) << "sample " << i << " channel " << c;
}

TEST_F(Twins, Numeric) {
    expectTwin(
        "powCos/powUnit/saturate", kTwinNumeric,
        product({kCosines, kPowers, {-1.0f, 0.5f, 2.0f}, {3e9f, 7.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{powCos(d(a[0]), d(a[1])), powUnit(d(a[0]), d(a[1])),
                                         saturate(d(a[2])), clampPower(d(a[3]))};
        },
        {kExp, kExp, kRational, kRational}, 4);
}

TEST_F(Twins, NdfNormalizations) {
    const auto args = product({kPowers});
    expectTwin(
        "ndf norms A", kTwinNdfNormA, args,
        [](const Args& a) {
            return std::array<double, 4>{blinnPhongNdfNorm(d(a[0])), phongLobeNorm(d(a[0])),
                                         phongBrdfNorm(d(a[0])), blinnPhongLobeNorm(d(a[0]))};
        },
        {kRational, kRational, kRational, kExp}, 4);
    expectTwin(
        "ndf norms B", kTwinNdfNormB, args,
        [](const Args& a) {
            return std::array<double, 4>{blinnPhongBrdfNorm(d(a[0])), blinnPhongBrdfNormApprox(d(a[0])),
                                         beckmannRoughnessFromPower(d(a[0])), ggxAlphaFromPower(d(a[0]))};
        },
        {kExp, kRational, kRational, kRational}, 4);
}

TEST_F(Twins, Ndfs) {
    // a = (NoH, power, Beckmann m, GGX α); α and m pair with each power through m = sqrt(2/(n+2)).
    std::vector<Args> args;
    for (const float NoH : kCosines)
        for (const float n : kPowers) {
            const float m = float(beckmannRoughnessFromPower(double(n)));
            args.push_back(Args{NoH, n, m, m, 0, 0, 0, 0});
        }
    for (const float NoH : kCosines)
        for (const float r : kRoughness)
            args.push_back(Args{NoH, 1.0f, r, r, 0, 0, 0, 0});
    expectTwin(
        "blinnPhong/beckmann/ggx Ndf", kTwinNdf, args,
        [](const Args& a) {
            return std::array<double, 4>{blinnPhongNdf(d(a[0]), d(a[1])), beckmannNdf(d(a[0]), d(a[2])),
                                         ggxNdf(d(a[0]), d(a[3])), lambertBrdf<double>()};
        },
        {kExp, kExp, kRational, kRational}, 4);
    expectTwin(
        "roughness->power, radiance", kTwinNdfBridge,
        product({kRoughness, {0.0f, 0.3f, 5.0f}, {0.0f, 1.0f, 3.0f}, {-0.5f, 0.0f, 0.5f, 1.0f, 2.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{powerFromBeckmannRoughness(d(a[0])), powerFromGgxAlpha(d(a[0])),
                                         punctualRadiance(d(a[1]), d(a[2]), d(a[3])), 0.0};
        },
        // Powers near 0 (α near 1) compared absolutely at the scale of a power of 1.
        {Tolerance{kRationalRel, 1.0}, Tolerance{kRationalRel, 1.0}, kRational, kRational}, 4);
}

TEST_F(Twins, FresnelScalar) {
    const std::vector<float> exponents{0.0f, 1.0f, 5.0f, 30.0f};
    const std::vector<float> glosses{-0.5f, 0.5f, 1.0f};
    expectTwin(
        "fresnel A", kTwinFresnelA, product({kUnit, kCosines, exponents, glosses}),
        [](const Args& a) {
            return std::array<double, 4>{
                fresnelSchlick(d(a[0]), d(a[1])), fresnelSchlickPow(d(a[0]), d(a[1]), d(a[2])),
                fresnelGlossy(d(a[0]), d(a[1]), d(a[3])), fresnelSchlickSg(d(a[0]), d(a[1]))};
        },
        {kUnitRational, kUnitExp, kUnitRational, kUnitExp}, 4);
    expectTwin(
        "fresnel B", kTwinFresnelB,
        product({kUnit, kCosines, {0.0f, 8.35f, 12.0f}, {-5.55473f, -3.0f}, {-6.98316f, -9.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{fresnelSchlickSg(d(a[0]), d(a[1]), d(a[2])),
                                         fresnelSchlickSgQuadratic(d(a[0]), d(a[1])),
                                         fresnelSchlickSgQuadratic(d(a[0]), d(a[1]), d(a[3]), d(a[4])),
                                         fresnelDielectric(d(a[0]), d(a[1]))};
        },
        // fresnelDielectric near F0 = 1 goes through η up to 4e6 and η²: a few hundred ULPs of 1.
        {kUnitExp, kUnitExp, kUnitExp, Tolerance{1e-5, kUnitFloor}}, 4);
    expectTwin(
        "iorFromF0", kTwinFresnelIor, product({kUnit}),
        [](const Args& a) {
            return std::array<double, 4>{iorFromF0(d(a[0])), 0.0, 0.0, 0.0};
        },
        {kRational}, 1);
}

TEST_F(Twins, FresnelRgb) {
    // a = (F0.rgb, x), b = (p, g, k, _) or (qa, qb, _, _); channel i is the scalar core function on F0[i].
    const std::vector<float> f0s{0.02f, 0.04f, 0.5f, 0.95f, 1.0f};
    using Scalar = std::function<double(double c, const Args& a)>;
    const std::vector<std::pair<const char*, Scalar>> functions{
        {"fresnelSchlick rgb", [](double c, const Args& a) { return fresnelSchlick(c, d(a[3])); }},
        {"fresnelSchlickPow rgb",
         [](double c, const Args& a) { return fresnelSchlickPow(c, d(a[3]), d(a[4])); }},
        {"fresnelGlossy rgb", [](double c, const Args& a) { return fresnelGlossy(c, d(a[3]), d(a[5])); }},
        {"fresnelSchlickSg rgb", [](double c, const Args& a) { return fresnelSchlickSg(c, d(a[3])); }},
        {"fresnelSchlickSg(k) rgb",
         [](double c, const Args& a) { return fresnelSchlickSg(c, d(a[3]), d(a[6])); }},
        {"fresnelSchlickSgQuad rgb",
         [](double c, const Args& a) { return fresnelSchlickSgQuadratic(c, d(a[3])); }},
        {"fresnelSchlickSgQuad(ab) rgb",
         [](double c, const Args& a) { return fresnelSchlickSgQuadratic(c, d(a[3]), d(a[4]), d(a[5])); }},
        {"iorFromF0 rgb", [](double c, const Args&) { return iorFromF0(c); }},
        {"fresnelDielectric rgb", [](double c, const Args& a) { return fresnelDielectric(c, d(a[3])); }},
    };
    for (size_t f = 0; f < functions.size(); ++f) {
        // The explicit quadratic reads (qa, qb) from b.xy; the others (p, g, k).
        const bool quadratic = f == 6;
        const auto args =
            quadratic ? product({f0s, {0.04f}, {0.9f}, kCosines, {-5.55473f, -2.0f}, {-6.98316f, -8.0f}})
                      : product({f0s, {0.04f}, {0.9f}, kCosines, {1.0f, 5.0f}, {0.0f, 1.0f}, {8.35f}});
        const Scalar& scalar = functions[f].second;
        const bool ior = f == 7;
        const Tolerance tol = ior ? kRational : (f == 8 ? Tolerance{1e-5, kUnitFloor} : kUnitExp);
        expectTwin(
            functions[f].first, kTwinFresnelRgbFirst + int(f), args,
            [&](const Args& a) {
                return std::array<double, 4>{scalar(d(a[0]), a), scalar(d(a[1]), a), scalar(d(a[2]), a), 0.0};
            },
            {tol, tol, tol, tol}, 3);
    }
}

TEST_F(Twins, Visibility) {
    expectTwin(
        "visibility A", kTwinVisibilityA,
        product({kCosines, {0.0f, 1e-6f, 0.5f, 1.0f}, kPowers, {0.0f, 0.3f, 1.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{visibilityNone<double>(), visibilityKelemen(d(a[3])),
                                         schlickSmithA(d(a[2])),
                                         visibilitySchlickSmith(d(a[0]), d(a[1]), d(a[2]))};
        },
        {kRational, kRational, kRational, kRational}, 4);
    const std::vector<float> cos4{0.0f, 1e-6f, 0.05f, 0.3f, 0.7f, 0.999f, 1.0f};
    expectTwin(
        "visibility B", kTwinVisibilityB,
        product({cos4,
                 {0.0f, 0.2f, 1.0f},
                 {0.0f, 0.5f, 1.0f},
                 {0.0f, 0.6f, 1.0f},
                 {0.0f, 1e-3f, 0.1f, 0.5f, 1.5f},
                 {0.0f, 0.02f, 0.3f, 1.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{visibilityCookTorrance(d(a[0]), d(a[1]), d(a[2]), d(a[3])),
                                         smithBeckmannG1(d(a[0]), d(a[4])),
                                         visibilitySmithBeckmann(d(a[0]), d(a[1]), d(a[4])),
                                         visibilitySmithGgxCorrelated(d(a[0]), d(a[1]), d(a[5]))};
        },
        // Smith–Beckmann goes through an erf approximation with absolute error 1.5e-7
        // (Abramowitz & Stegun 7.1.26) on a denominator >= 1, and exp(−a²).
        {kRational, Tolerance{1e-5, kTinyFloor}, Tolerance{1e-5, kTinyFloor}, kRational}, 4);
}

TEST_F(Twins, GgxSpecularTerm) {
    // Cosines from behind the surface to past 1, NaN-free grazing values, and α from below the clamp
    // (0, the NaN-free sharpest) to past 1.
    const std::vector<float> cosines{-0.5f, 0.0f, 1e-7f, 1e-3f, 0.05f, 0.3f, 0.7f, 0.95f, 0.999f, 1.0f, 1.2f};
    expectTwin(
        "ggxSpecularTerm/ggxSpecularAlpha", kTwinGgxSpecular,
        product({cosines,
                 {-1.0f, 0.0f, 0.2f, 0.9f, 1.0f},
                 {0.0f, 1e-3f, 0.5f, 1.0f},
                 {0.0f, 1e-5f, 0.01f, 0.088f, 0.3f, 1.0f, 3.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{ggxSpecularTerm(d(a[0]), d(a[1]), d(a[2]), d(a[3])),
                                         ggxSpecularAlpha(d(a[3])), 0, 0};
        },
        // A rational formula, but D = α²/(πd²) with d = sin² + c²α² at c → 1 and α = kMinRoughness has
        // d ≈ 2e-9: the float argument's rounding (c = 0.999 stored in float) moves sin² by a few ulps.
        {Tolerance{1e-4, kTinyFloor}, kRational}, 2);
}

TEST_F(Twins, GgxAnisotropicSpecularTerm) {
    // Views and lights from overhead to grazing (and one below the horizon), a tilted shading normal in
    // the geometric frame, α_t and α_b from below the clamp to 1 and past it, equal and far apart.
    const std::vector<float> xy{-0.999f, 0.0f, 0.6f};
    const std::vector<float> alphas{0.0f, 0.088f, 0.5f, 1.0f, 2.0f};
    auto reference = [](const Args& a) {
        const glm::dvec3 v(d(a[0]), d(a[1]),
                           std::sqrt(std::max(1.0 - d(a[0]) * d(a[0]) - d(a[1]) * d(a[1]), 0.0)));
        const glm::dvec3 l(d(a[2]), d(a[3]),
                           std::sqrt(std::max(1.0 - d(a[2]) * d(a[2]) - d(a[3]) * d(a[3]), 0.0)));
        const glm::dvec3 n = glm::normalize(glm::dvec3(d(a[4]), d(a[5]), 1.0));
        const glm::dvec3 h = glm::normalize(l + v);
        return std::array<double, 4>{ggxAnisotropicSpecularTerm(glm::dot(n, h), h.x, h.y, glm::dot(n, l), l.x,
                                                                l.y, glm::dot(n, v), v.x, v.y, d(a[6]),
                                                                d(a[7])),
                                     0, 0, 0};
    };
    std::vector<Args> args;
    for (const Args& a :
         product({xy, {0.0f, 0.5f}, xy, {-0.3f, 0.0f}, {0.0f, 0.4f}, {0.0f, -0.2f}, alphas, alphas}))
        if (a[0] * a[0] + a[1] * a[1] <= 1.0f && a[2] * a[2] + a[3] * a[3] <= 1.0f &&
            !(a[0] == -a[2] && a[1] == -a[3])) // l = -v has no half vector
            args.push_back(a);
    // The same rational formula as the isotropic term, in float: a few ulps of its many products, more
    // near the clamp's sharpest lobes.
    expectTwin("ggxAnisotropicSpecularTerm", kTwinGgxAnisotropic, args, reference,
               {Tolerance{1e-4, kTinyFloor}, kRational}, 1);
}

TEST_F(Twins, SphericalGaussian) {
    const std::vector<float> modified{0.0f, 1.0f, 12.0f, 1e3f, 1e6f, 1.4e9f, 3e9f, -5.0f};
    expectTwin(
        "sgLobe/sgLobeExp2", kTwinSg, product({kCosines, kPowers, {0.0f, 0.75f, 0.775f, -2.0f}, {1.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{sgLobe(d(a[0]), d(a[1]), d(a[2])), sgLobeExp2(d(a[0]), d(a[3])), 0,
                                         0};
        },
        {kExp, kExp}, 2);
    expectTwin(
        "sgLobeExp2 powers", kTwinSg, product({kCosines, {1.0f}, {0.0f}, modified}),
        [](const Args& a) {
            return std::array<double, 4>{sgLobe(d(a[0]), d(a[1]), d(a[2])), sgLobeExp2(d(a[0]), d(a[3])), 0,
                                         0};
        },
        {kExp, kExp}, 2);
}

TEST_F(Twins, GeometricAa) {
    const std::vector<float> lengths{0.0f, 1e-6f, 0.5f, 0.9f, 0.95f, 0.97f, 0.99f, 0.9999f, 1.0f, 1.2f};
    const std::vector<float> cosAlphas{-1.0f, -0.3f, -0.05f, -0.01f, 0.0f, 0.01f, 0.05f, 0.2f, 0.7f, 1.0f};
    expectTwin(
        "cone/diffuseAa/kv", kTwinGeometricAaA,
        product({lengths, cosAlphas, {0.0f, 1.0f, 64.0f, 1e6f, 1e9f}, {-1.0f, 0.0f, 0.05f, 1.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{coneCosFromNormalLength(d(a[0])), diffuseAaCurve(d(a[1]), d(a[0])),
                                         kvConeAngleFromPower(d(a[2])),
                                         kvCurvatureAdjustedPower(d(a[2]), d(a[3]))};
        },
        {kUnitRational, kUnitRational, kRational, kRational}, 4);
    expectTwin(
        "kv explicit constants", kTwinGeometricAaB,
        product({{0.0f, 1e-6f, 0.01f, 0.5f, 4.0f},
                 {0.0f, 10.0f, 1e6f},
                 {0.373837f, 0.5f},
                 {0.66874f, 0.5f},
                 {-0.2f, 0.0f, 0.1f, 0.8f},
                 {0.9f, 0.96f, 1.0f},
                 {4.11893f, 3.0f},
                 {16.9656f, 9.0f}}),
        [](const Args& a) {
            return std::array<double, 4>{
                kvPowerFromConeAngle(d(a[0])), diffuseAaCurve(d(a[4]), d(a[5]), d(a[2]), d(a[3])),
                kvConeAngleFromPower(d(a[1]), d(a[6])), kvPowerFromConeAngle(d(a[0]), d(a[7]))};
        },
        {kRational, kUnitRational, kRational, kRational}, 4);
}

TEST_F(Twins, SpecularAa) {
    // a = (dndx, α), b = (dndy, n).
    std::vector<Args> args;
    for (const float dx : {0.0f, 1e-4f, 0.05f, 0.3f, 2.0f})
        for (const float dy : {0.0f, 0.02f, 0.5f})
            for (const float alpha : {0.0f, 1e-4f, 0.1f, 0.5f, 1.0f})
                for (const float n : {0.0f, 10.0f, 1e4f, 1e9f})
                    args.push_back(Args{dx, 0.5f * dx, -dx, alpha, 0.0f, dy, 0.3f * dy, n});
    const auto reference = [](const Args& a) {
        const glm::dvec3 dndx(a[0], a[1], a[2]);
        const glm::dvec3 dndy(a[4], a[5], a[6]);
        return std::array<double, 4>{
            specularAaGgxAlpha(d(a[3]), dndx, dndy), specularAaBeckmannM(d(a[3]), dndx, dndy),
            specularAaPower(d(a[7]), dndx, dndy), specularAaKernelRoughness2(normalDerivative2(dndx, dndy))};
    };
    // Filtered powers near 0 are compared absolutely at the scale of a power of 1.
    expectTwin("specularAa", kTwinSpecularAa, args, reference,
               {kRational, kRational, Tolerance{kRationalRel, 1.0}, kRational}, 4);

    // The dFdx/dFdy wrappers: inputs constant over each 2×2 quad, normal field (gx·x, gy·y, gz).
    std::vector<Args> quads;
    std::vector<Args> expected;
    for (const float g : {0.0f, 0.01f, 0.2f, 1.0f})
        for (const float alpha : {0.0f, 0.05f, 0.5f})
            for (const float n : {1.0f, 100.0f, 1e6f})
                expected.push_back(Args{g, 0.5f * g, 1.0f, alpha, n, 0, 0, 0});
    // Pixel (x, y) belongs to the quad (x/2, y/2); give every pixel its quad's arguments.
    std::vector<Args> pixels(kCapacity);
    std::vector<size_t> caseOfPixel(kCapacity);
    for (size_t i = 0; i < kCapacity; ++i) {
        const size_t x = i % kSize;
        const size_t y = i / kSize;
        const size_t quad = (y / 2) * (kSize / 2) + x / 2;
        caseOfPixel[i] = quad % expected.size();
        pixels[i] = expected[caseOfPixel[i]];
    }
    expectTwin(
        "specularAa from dFdx/dFdy", kTwinSpecularAaDerivatives, pixels,
        [](const Args& a) {
            const glm::dvec3 dndx(a[0], 0.0, 0.0);
            const glm::dvec3 dndy(0.0, a[1], 0.0);
            return std::array<double, 4>{specularAaGgxAlpha(d(a[3]), dndx, dndy),
                                         specularAaBeckmannM(d(a[3]), dndx, dndy),
                                         specularAaPower(d(a[4]), dndx, dndy), 0.0};
        },
        // The derivative is a difference of gx·x at x and x+1 (x < 64): ~64 ULPs of gx.
        {Tolerance{1e-5, kTinyFloor}, Tolerance{1e-5, kTinyFloor}, Tolerance{1e-5, 1.0}}, 3);
}

TEST_F(Twins, Gloss) {
    struct Encoding {
        GlossEncoding encoding;
        float nMin;
        float nMax;
    };
    const std::vector<Encoding> encodings{
        {GlossEncoding::blackOps(), 1.0f, 8192.0f},       {GlossEncoding::exp2Range(), 2.0f, 2048.0f},
        {*GlossEncoding::logRange(0.5, 1e6), 0.5f, 1e6f}, {GlossEncoding::ggxRoughness(), 0.0f, 0.0f},
        {GlossEncoding::ggxAlpha(), 0.0f, 0.0f},          {GlossEncoding::beckmann(), 0.0f, 0.0f},
        {GlossEncoding::smoothness(), 0.0f, 0.0f},
    };
    for (const auto& e : encodings) {
        const auto args = product({{-0.5f, 0.0f, 1e-4f, 0.1f, 0.5f, 0.9f, 0.999f, 1.0f, 1.5f},
                                   {0.0f, 0.5f, 1.0f, 2.0f, 100.0f, 8192.0f, 1e6f, 1e9f},
                                   {0.0f, 0.3f, 0.7f, 1.0f},
                                   {0.0f, 1e-6f, 1e-3f, 0.1f, 1.0f, 2.0f},
                                   {float(int(e.encoding.kind()))},
                                   {e.nMin},
                                   {e.nMax}});
        const std::string label = "gloss " + e.encoding.name();
        expectTwin(
            label.c_str(), kTwinGloss, args,
            [&](const Args& a) {
                return std::array<double, 4>{e.encoding.power(d(a[0])), e.encoding.value(d(a[1])),
                                             varianceToGloss(d(a[2]), d(a[3]), e.encoding), 0.0};
            },
            // Powers through exp2/log2 of up to log2(2e6) ≈ 21 bits of range; powers below 1
            // compared absolutely; gloss values in [0, 1] absolutely.
            {Tolerance{kExpRel, 1.0}, kUnitExp, kUnitExp}, 3);
    }
}

// Moments of a footprint with mean normal (0, 0, |Na|) and projected variance v.
NormalMoments footprint(float lenNa, float v) {
    NormalMoments m;
    m.mean = glm::vec3(0.0f, 0.0f, lenNa);
    m.cov = {v, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    return m;
}

TEST_F(Twins, ToksvigAndMethodPowers) {
    const std::vector<float> lengths{0.0f, 1e-9f, 1e-4f, 0.1f, 0.5f, 0.9f, 0.99f, 0.9999f, 1.0f};
    const std::vector<float> factors{0.0f, 0.01f, 0.5f, 0.9f, 1.0f};
    expectTwin(
        "toksvig", kTwinToksvig, product({lengths, kPowers, factors, {0.0f, 1.0f, 100.0f, 1e4f}}),
        [](const Args& a) {
            return std::array<double, 4>{toksvigVariance(d(a[0])), toksvigFactor(d(a[0]), d(a[1])),
                                         toksvigPower(d(a[0]), d(a[1])),
                                         convertToksvigFactor(d(a[2]), d(a[3]), d(a[1]))};
        },
        // Factors in [0, 1] absolutely; powers below 1 absolutely.
        {kRational, kUnitRational, Tolerance{kRationalRel, 1.0}, kUnitRational}, 4);

    // The method-level powers against core's methodLobe on the same footprint. The Toksvig map's
    // stored factor is the 8-bit one methodLobe quantizes; |Na| as core measures it (float length).
    std::vector<Args> args;
    for (const float lenNa : lengths)
        for (const float s : kPowers)
            for (const float fixedS : {1.0f, 100.0f})
                for (const float v : {0.0f, 1e-7f, 1e-3f, 0.2f, 1.0f}) {
                    const float measured = footprint(lenNa, v).lengthNa();
                    const float ft = float(std::round(toksvigFactor(measured, fixedS) * 255.0) / 255.0);
                    args.push_back(Args{measured, s, ft, fixedS, v, 0, 0, 0});
                }
    expectTwin(
        "toksvig map/v2g/vmf powers", kTwinMethodPowers, args,
        [](const Args& a) {
            const NormalMoments m = footprint(a[0], a[4]);
            MethodParams params;
            params.toksvigMapPower = a[3];
            return std::array<double, 4>{methodLobe(Method::ToksvigMap, m, a[1], params).power,
                                         methodLobe(Method::VarianceToGloss, m, a[1]).power,
                                         vmfKappa(d(a[0])), methodLobe(Method::Vmf, m, a[1]).power};
        },
        // The Toksvig map's conversion divides by s/fixedS − (s/fixedS − 1)·ft, which cancels for
        // s ≫ fixedS and ft near 1: the float argument ft (core keeps the 8-bit value in double)
        // differs by ε, amplified up to ~100× on these slices. Powers below 1 compared absolutely.
        {Tolerance{1e-4, 1.0}, Tolerance{kRationalRel, 1.0}, Tolerance{kRationalRel, 1.0},
         Tolerance{kRationalRel, 1.0}},
        4);
}

TEST_F(Twins, LeanAndClean) {
    // a = (B, s, mIso), b = M. Footprints with slope mean B and slope covariance C; the shader gets
    // what a bake stores, M = C + BBᵀ, and subtracts BBᵀ in float again.
    std::vector<Args> args;
    std::vector<NormalMoments> moments;
    for (const glm::vec2 B : {glm::vec2(0.0f), glm::vec2(0.3f, -0.1f), glm::vec2(-2.0f, 1.5f)})
        for (const std::array<float, 3> C : {std::array<float, 3>{0.0f, 0.0f, 0.0f},
                                             {1e-4f, 2e-4f, -5e-5f},
                                             {0.05f, 0.02f, 0.01f},
                                             {1.0f, 0.5f, 0.7f}})
            for (const float s : kPowers) {
                const glm::vec3 M(C[0] + B.x * B.x, C[1] + B.y * B.y, C[2] + B.x * B.y);
                args.push_back(Args{B.x, B.y, s, 0.5f * (M.x + M.y), M.x, M.y, M.z, 0.0f});
            }
    const auto reference = [](const Args& a) {
        NormalMoments m;
        m.slope = glm::vec2(a[0], a[1]);
        // The covariance a bake derives from the stored M, in double: M − BBᵀ.
        m.slopeCov = {float(d(a[4]) - d(a[0]) * d(a[0])), float(d(a[5]) - d(a[1]) * d(a[1])),
                      float(d(a[6]) - d(a[0]) * d(a[1]))};
        const TexelLobe lean = methodLobe(Method::Lean, m, a[2]);
        const TexelLobe clean = methodLobe(Method::Clean, m, a[2]);
        return std::array<double, 4>{lean.slopeCov[0], lean.slopeCov[1], lean.slopeCov[2], clean.slopeCov[0]};
    };
    // M − BBᵀ cancels in float: an absolute error of a few ULPs of |M| + |B|² <= 8, i.e. ~1e-6;
    // relative to a covariance scale of 0.1 that is 1e-5.
    constexpr Tolerance kCancel{1e-5, 0.1};
    expectTwin("lean covariance, clean variance", kTwinLeanClean, args, reference,
               {kCancel, kCancel, kCancel, kCancel}, 4);
}

TEST_F(Twins, SlopeGaussianAndIsotropicNdf) {
    // a = (h, B.x), b = (B.y, Σxx, Σyy, Σxy); h spans normal incidence to grazing and below.
    std::vector<Args> args;
    const std::vector<glm::vec3> halfVectors{{0.0f, 0.0f, 1.0f},  {0.1f, 0.0f, 0.995f},  {0.3f, -0.2f, 0.93f},
                                             {0.7f, 0.7f, 0.14f}, {0.999f, 0.0f, 0.04f}, {1.0f, 0.0f, 1e-4f},
                                             {1.0f, 0.0f, 1e-7f}, {1.0f, 0.0f, 0.0f},    {0.0f, 0.0f, -1.0f}};
    const std::vector<std::array<float, 3>> covariances{{1e-9f, 1e-9f, 0.0f},  {1e-6f, 1e-6f, 0.0f},
                                                        {1e-3f, 2e-3f, 5e-4f}, {0.1f, 0.1f, 0.0f},
                                                        {1.0f, 1.0f, 1.0f}, // singular: det = 0
                                                        {1.0f, 0.5f, 0.7f}, // not positive definite: det < 0
                                                        {1e4f, 1e4f, 0.0f}};
    for (const glm::vec3& h : halfVectors)
        for (const glm::vec2 B : {glm::vec2(0.0f), glm::vec2(0.1f, -0.05f), glm::vec2(3.0f, 1.0f)})
            for (const auto& cov : covariances) {
                const glm::vec3 hn = glm::length(h) > 0.0f ? glm::normalize(h) : h;
                args.push_back(Args{hn.x, hn.y, hn.z, B.x, B.y, cov[0], cov[1], cov[2]});
            }
    expectTwin(
        "slopeGaussianNdf", kTwinSlopeNdf, args,
        [](const Args& a) {
            return std::array<double, 4>{slopeGaussianNdf(glm::dvec3(a[0], a[1], a[2]),
                                                          glm::dvec2(a[3], a[4]),
                                                          {d(a[5]), d(a[6]), d(a[7])}),
                                         0.0, 0.0, 0.0};
        },
        {kExp}, 1);

    // a = (normal, power), b = (h, _): methodNdf of an isotropic lobe; the last three channels are
    // normalOfSlope(a.xy), the LEAN lobe normal (methodLobe's), compared for slopes a.xy.
    std::vector<Args> iso;
    for (const glm::vec3 n : {glm::vec3(0.0f, 0.0f, 1.0f), glm::normalize(glm::vec3(0.2f, 0.1f, 1.0f))})
        for (const glm::vec3& h : halfVectors)
            for (const float p : kPowers) {
                const glm::vec3 hn = glm::length(h) > 0.0f ? glm::normalize(h) : h;
                iso.push_back(Args{n.x, n.y, n.z, p, hn.x, hn.y, hn.z, 0.0f});
            }
    expectTwin(
        "isotropic lobe NDF, lobe normal", kTwinIsotropicNdf, iso,
        [](const Args& a) {
            TexelLobe lobe;
            lobe.normal = glm::vec3(a[0], a[1], a[2]);
            lobe.power = a[3];
            NormalMoments m;
            m.slope = glm::vec2(a[0], a[1]);
            const glm::vec3 leanNormal = methodLobe(Method::Lean, m, 1.0).normal;
            return std::array<double, 4>{methodNdf(lobe, glm::dvec3(a[4], a[5], a[6])), leanNormal.x,
                                         leanNormal.y, leanNormal.z};
        },
        // n·h is a float dot product in the shader (3 roundings) against core's double one:
        // at power 1e6 near the peak that is 1e6·(3ε) relative in the lobe.
        {Tolerance{1e-3, kTinyFloor}, kUnitRational, kUnitRational, kUnitRational}, 4);
}

} // namespace
} // namespace burnish::render

namespace burnish::render {
namespace {

TEST_F(Twins, MixtureLobeDecodeAndValue) {
    // a = (w, wb.x, wb.y, wM.xx), b = (wM.yy, wM.xy, minVariance, _): LobeMoments::covariance and
    // mean; weights from empty to whole, means to slope 3, moments below the floor (clamped), a
    // correlation beyond ±1 (clamped) and a covariance that cancels to 0.
    std::vector<Args> args;
    for (const float w : {0.0f, 1e-3f, 0.25f, 1.0f})
        for (const glm::vec2 b : {glm::vec2(0.0f), glm::vec2(0.3f, -0.1f), glm::vec2(3.0f, 1.0f)})
            for (const std::array<float, 3> sigma :
                 {std::array<float, 3>{1e-3f, 2e-3f, 5e-4f}, std::array<float, 3>{0.1f, 0.05f, 0.2f},
                  std::array<float, 3>{0.0f, 0.0f, 0.0f}})
                for (const float minVariance : {1e-6f, 1e-3f}) {
                    const float mxx = w * (sigma[0] + b.x * b.x), myy = w * (sigma[1] + b.y * b.y),
                                mxy = w * (sigma[2] + b.x * b.y);
                    args.push_back(Args{w, w * b.x, w * b.y, mxx, myy, mxy, minVariance, 0.0f});
                    // The swapped case: channel 3 then gives mean.y.
                    args.push_back(Args{w, w * b.y, w * b.x, myy, mxx, mxy, minVariance, 0.0f});
                }
    auto lobeOf = [](const Args& a) {
        LobeMoments l;
        l.w = a[0], l.bx = a[1], l.by = a[2], l.mxx = a[3], l.myy = a[4], l.mxy = a[5];
        return l;
    };
    // (w·M)/w − b² cancels in float as LEAN's M − BBᵀ does (kCancel there): ~1e-6 of |M|/w + b².
    constexpr Tolerance kCancel{1e-5, 0.1};
    expectTwin(
        "mixtureLobeCovariance, mixtureLobeMean", kTwinMixtureLobe, args,
        [&](const Args& a) {
            const LobeMoments l = lobeOf(a);
            const auto c = l.covariance(d(a[6]));
            return std::array<double, 4>{c[0], c[1], c[2], l.mean().x};
        },
        {kCancel, kCancel, kCancel, kRational}, 4);

    // a = (l, t), b = (h, minVariance): mixtureValue of the four-lobe mixture twins.frag builds.
    std::vector<Args> values;
    const std::vector<glm::vec3> dirs{{0.0f, 0.0f, 1.0f},
                                      {0.3f, -0.2f, 0.93f},
                                      {-0.6f, 0.5f, 0.62f},
                                      {0.99f, 0.0f, 0.1f},
                                      {0.0f, 0.0f, -1.0f}};
    for (const glm::vec3& l : dirs)
        for (const glm::vec3& h : dirs)
            for (const float t : {0.0f, 0.05f, 0.3f})
                for (const float minVariance : {1e-4f, 1e-2f}) {
                    const glm::vec3 ln = glm::normalize(l), hn = glm::normalize(h);
                    values.push_back(Args{ln.x, ln.y, ln.z, t, hn.x, hn.y, hn.z, minVariance});
                }
    expectTwin(
        "mixtureValue", kTwinMixtureValue, values,
        [](const Args& a) {
            LobeMixture all;
            const float weights[4] = {0.1f, 0.2f, 0.3f, 0.4f};
            for (int i = 0; i < 4; ++i) {
                // The shader's float arithmetic, then core in double on those values.
                const float w = weights[i];
                const glm::vec2 m = a[3] * glm::vec2(float(i) - 1.5f, 0.5f * float(i) - 0.7f);
                const float v = 0.01f * float(i + 1);
                LobeMoments l;
                l.w = w, l.bx = w * m.x, l.by = w * m.y;
                l.mxx = w * (v + m.x * m.x), l.myy = w * (2.0f * v + m.y * m.y),
                l.mxy = w * (0.3f * v + m.x * m.y);
                all.lobes[size_t(i)] = l;
            }
            all.count = 4;
            LobeMixture two = all;
            two.count = 2;
            const glm::dvec3 l(a[0], a[1], a[2]), h(a[4], a[5], a[6]);
            return std::array<double, 4>{mixtureValue(all, l, h, d(a[7])), mixtureValue(two, l, h, d(a[7])),
                                         0.0, 0.0};
        },
        {kExp, kExp, kExp, kExp}, 2);
}

// The GLSL of three.js's BURNISH_lobe_mixture module (resources/three/burnish-gltf.js, the text between its
// markers, as the module injects it into three.js's shader) against core's mixtureGgxLobe. The module
// computes in GLSL ES 3.0 float as this GLSL 3.30 core shader does.
std::string threeJsMixtureFragment() {
    std::ifstream in(std::string(BURNISH_SOURCE_DIR) + "/resources/three/burnish-gltf.js");
    std::stringstream text;
    text << in.rdbuf();
    const std::string js = text.str(), begin = "/* BEGIN mixtureGgxLobe */", end = "/* END mixtureGgxLobe */";
    const size_t from = js.find(begin), to = js.find(end);
    if (from == std::string::npos || to == std::string::npos || to < from) return {};
    return "#version 330 core\n" + js.substr(from, to + end.size() - from) + R"(
uniform sampler2D uInputs;
uniform sampler2D uInputs2;
out vec4 fragColor;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 a = texelFetch(uInputs, p, 0);
    vec4 b = texelFetch(uInputs2, p, 0); // (total, alpha0, spreadScale, output: 0 share/alpha/n.xy, 1 n.z)
    vec3 n;
    float alpha;
    float share = mixtureGgxLobe(a, b.x, b.y, b.z, n, alpha);
    fragColor = b.w < 0.5 ? vec4(share, alpha * alpha, n.x, n.y) : vec4(n.z, alpha, 0.0, 0.0);
}
)";
}

TEST_F(Twins, ThreeJsMixtureGgxLobe) {
    const std::string fragment = threeJsMixtureFragment();
    ASSERT_FALSE(fragment.empty()) << "resources/three/burnish-gltf.js lacks the mixtureGgxLobe markers";
    // a = a stored lobe (w, w·b.x, w·b.y, w·S), b = (total, α0, c, output): empty, tiny and whole weights,
    // means to slope 3, spreads from negative (rounding: clamped) to wide, α0 from 0 to past 1, c 0 to 2.
    std::vector<Args> args;
    for (const float w : {0.0f, 1e-4f, 0.3f, 1.0f})
        for (const glm::vec2 b : {glm::vec2(0.0f), glm::vec2(0.3f, -0.1f), glm::vec2(-3.0f, 1.0f)})
            for (const float spread : {-1e-3f, 0.0f, 0.02f, 0.5f})
                for (const float alpha0 : {0.0f, 0.088f, 0.5f, 1.5f})
                    for (const float c : {0.0f, 1.0f, 2.0f})
                        for (const float total : {0.0f, 1.0f}) {
                            const float ws = w * (spread + glm::dot(b, b));
                            const Args base{w, w * b.x, w * b.y, ws, std::max(total, w), alpha0, c, 0.0f};
                            args.push_back(base);
                        }
    ASSERT_LE(args.size() * 2, kCapacity);
    std::vector<Args> withZ = args;
    for (Args& a : withZ)
        a[7] = 1.0f;
    auto lobe = [](const Args& a) {
        return mixtureGgxLobe({d(a[0]), d(a[1]), d(a[2]), d(a[3])}, d(a[4]), d(a[5]), d(a[6]));
    };
    // S − |b|² cancels in float as LEAN's M − BBᵀ does: an absolute error of a few ε of c·(S/w + |b|²) on α²
    // (|b|² up to 10, c up to 2: ~5e-6), which α's square root magnifies where α is near 0; so α² is compared
    // at the unit scale, and α itself where no spread cancels (c = 0: α = α0 clamped).
    constexpr Tolerance kCancelUnit{1e-5, 1.0};
    expectResults(
        "mixtureGgxLobe (three.js)", evaluateSource(fragment, "burnish-gltf.js mixtureGgxLobe", args), args,
        [&](const Args& a) {
            const MixtureGgxLobe l = lobe(a);
            return std::array<double, 4>{l.share, l.alpha * l.alpha, l.normal.x, l.normal.y};
        },
        {kUnitRational, kCancelUnit, kUnitRational, kUnitRational}, 4);
    std::vector<Args> noSpread;
    for (const Args& a : withZ)
        if (a[6] == 0.0f) noSpread.push_back(a);
    expectResults(
        "mixtureGgxLobe normal.z (three.js)",
        evaluateSource(fragment, "burnish-gltf.js mixtureGgxLobe", withZ), withZ,
        [&](const Args& a) {
            return std::array<double, 4>{lobe(a).normal.z, 0.0, 0.0, 0.0};
        },
        {kUnitRational, kUnitRational, kUnitRational, kUnitRational}, 1);
    expectResults(
        "mixtureGgxLobe alpha, c = 0 (three.js)",
        evaluateSource(fragment, "burnish-gltf.js mixtureGgxLobe", noSpread), noSpread,
        [&](const Args& a) {
            return std::array<double, 4>{lobe(a).normal.z, lobe(a).alpha, 0.0, 0.0};
        },
        {kUnitRational, kUnitRational, kUnitRational, kUnitRational}, 2);
}

TEST_F(Twins, StochasticTexelAndNumbers) {
    // Filtering after shading's pick: the same texel and level in core and GLSL, bit for bit (the
    // arguments keep clear of the decision boundaries, where an FMA could tip a comparison), and the
    // same pcg3d numbers (integer arithmetic: exact).
    constexpr Tolerance kExact{0.0, 1.0};
    std::vector<Args> args;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const std::array<glm::ivec2, 4> sizes{glm::ivec2(1, 1), glm::ivec2(16, 8), glm::ivec2(5, 3),
                                          glm::ivec2(512, 512)};
    for (const glm::ivec2 size : sizes) {
        const int levels = 1 + int(std::floor(std::log2(float(std::max(size.x, size.y)))));
        for (int i = 0; i < 200; ++i) {
            const glm::vec2 uv(3.0f * unit(rng) - 1.0f, 3.0f * unit(rng) - 1.0f);
            const float lod = 12.0f * unit(rng) - 2.0f;
            args.push_back(Args{uv.x, uv.y, lod, float(levels), unit(rng), unit(rng), unit(rng),
                                float(size.x + 4096 * size.y)});
        }
    }
    // Keep the comparisons (xi against a fraction) clear of ties: drop arguments within 1e-4 of one.
    std::erase_if(args, [](const Args& a) {
        const int levels = int(a[3]);
        const float l = std::clamp(a[2], 0.0f, float(levels - 1));
        if (std::abs(a[6] - (l - std::floor(l))) < 1e-4f) return true;
        const glm::ivec2 size0(int(a[7]) % 4096, int(a[7]) / 4096);
        for (int level = 0; level < levels; ++level) {
            const glm::ivec2 size = glm::max(glm::ivec2(size0.x >> level, size0.y >> level), glm::ivec2(1));
            const float px = (a[0] - std::floor(a[0])) * float(size.x) - 0.5f;
            const float py = (a[1] - std::floor(a[1])) * float(size.y) - 0.5f;
            if (std::abs(a[4] - (px - std::floor(px))) < 1e-4f ||
                std::abs(a[5] - (py - std::floor(py))) < 1e-4f)
                return true;
        }
        return false;
    });
    ASSERT_GT(args.size(), 500u);
    expectTwin(
        "stochasticTexel", kTwinStochasticTexel, args,
        [](const Args& a) {
            const StochasticTexel t = stochasticTexel(
                {a[0], a[1]}, a[2], {int(a[7]) % 4096, int(a[7]) / 4096}, int(a[3]), {a[4], a[5], a[6]});
            return std::array<double, 4>{double(t.x), double(t.y), double(t.level), 0.0};
        },
        {kExact, kExact, kExact, kExact}, 3);
    std::vector<Args> pixels;
    for (const unsigned x : {0u, 1u, 7u, 640u, 1919u})
        for (const unsigned y : {0u, 3u, 719u, 1079u})
            for (const unsigned sample : {0u, 1u, 15u, 4095u})
                pixels.push_back(Args{float(x), float(y), float(sample), 0.0f, 0.0f, 0.0f, 0.0f, 0.0f});
    expectTwin(
        "stochasticNumbers", kTwinStochasticNumbers, pixels,
        [](const Args& a) {
            const glm::vec3 xi = stochasticNumbers({unsigned(a[0]), unsigned(a[1]), unsigned(a[2])});
            return std::array<double, 4>{xi.x, xi.y, xi.z, 0.0};
        },
        {kExact, kExact, kExact, kExact}, 3);
}

} // namespace
} // namespace burnish::render
