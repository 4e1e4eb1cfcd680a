// Framebuffers (exact 32F read-back, orientation, MSAA resolve), textures (round trip through a
// draw, mip levels, bad input), and tonemap.frag against its core twins (color.h, tonemap.h).
#include <burnish/core/shading/color.h>
#include <burnish/core/shading/tonemap.h>
#include <burnish/render/context.h>
#include <burnish/render/gpu_resources.h>
#include <burnish/render/program.h>
#include <burnish/render/shader_source.h>

#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

using namespace burnish;
using namespace burnish::render;

namespace {

// A float shader (llvmpipe's pow, exp2, log2 and a float division) against core's double
// formulas: a few float ulps near 1 (1.2e-7 each) plus pow's relative error. 2e-5 is 1/200 of an
// 8-bit display step, so a real mismatch (a wrong constant or branch) still fails.
constexpr double kShaderVsCoreTolerance = 2e-5;
// GL converts a float clear colour to 8 bits by rounding; 1 code allows either rounding rule.
constexpr int kUnormRoundingCodes = 1;

std::unique_ptr<GlContext>& resourcesContext() {
    static std::unique_ptr<GlContext> context;
    return context;
}

class GpuResources : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        auto created = createHeadlessContext();
        if (created) {
            resourcesContext() = std::move(created).value();
        } else {
            s_error = created.error();
        }
    }
    static void TearDownTestSuite() { resourcesContext().reset(); }
    void SetUp() override {
        ASSERT_TRUE(resourcesContext()) << "no headless OpenGL context: " << s_error;
        const Status status = resourcesContext()->makeCurrent();
        ASSERT_TRUE(status) << status.error();
    }
    static inline std::string s_error;
};

// fullscreen.vert with an inline fragment shader.
Result<Program> fullscreenProgram(const std::string& fragmentBody) {
    auto vertex = assembleShader("fullscreen.vert");
    if (!vertex) return Error{vertex.error()};
    return Program::fromSources(*vertex, "#version 330 core\n" + fragmentBody, "test fragment");
}

// Draws `texture` 1:1 into a 32F target of its size (nearest) and reads it back.
std::vector<float> drawTexture(const Texture2D& texture, const char* lookup = "texture(uTex, vUv)") {
    auto program =
        fullscreenProgram(std::string("uniform sampler2D uTex;\nin vec2 vUv;\nout vec4 fragColor;\n"
                                      "void main() { fragColor = ") +
                          lookup + "; }\n");
    EXPECT_TRUE(program) << program.error();
    auto fb = Framebuffer::create(texture.width(), texture.height(), ColorFormat::Rgba32f, false);
    EXPECT_TRUE(fb) << fb.error();
    if (!program || !fb) return {};
    fb->bind();
    texture.bind(0);
    program->set("uTex", 0);
    FullscreenTriangle triangle;
    triangle.draw();
    return fb->readRgbaFloat();
}

} // namespace

TEST_F(GpuResources, Clear32fReadsBackExactlyWithRowZeroAtTheTop) {
    constexpr int kWidth = 5;
    constexpr int kHeight = 4;
    auto fb = Framebuffer::create(kWidth, kHeight, ColorFormat::Rgba32f);
    ASSERT_TRUE(fb) << fb.error();
    fb->bind();
    // Values a narrower format would round: 32F must return them bit for bit.
    const float bottom[4] = {0.1234567f, -3.5f, 1.0e6f, 1.0f / 3.0f};
    const float top[4] = {7.0e-5f, 2.0f, -0.0625f, 0.999f};
    glClearColor(bottom[0], bottom[1], bottom[2], bottom[3]);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    // GL's y runs up: the scissor box with y = kHeight − 1 is the top row of the image.
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, kHeight - 1, kWidth, 1);
    glClearColor(top[0], top[1], top[2], top[3]);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_SCISSOR_TEST);

    const std::vector<float> pixels = fb->readRgbaFloat();
    ASSERT_EQ(pixels.size(), size_t(kWidth * kHeight * 4));
    for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) {
            const float* expected = y == 0 ? top : bottom;
            for (int c = 0; c < 4; ++c) {
                EXPECT_EQ(pixels[size_t((y * kWidth + x) * 4 + c)], expected[c]) << "x " << x << " y " << y;
            }
        }
    }
}

TEST_F(GpuResources, Rgba8ReadBack) {
    auto fb = Framebuffer::create(3, 2, ColorFormat::Rgba8, false);
    ASSERT_TRUE(fb) << fb.error();
    fb->bind();
    glClearColor(0.5f, 1.0f, 0.0f, 0.2f);
    glClear(GL_COLOR_BUFFER_BIT);
    const auto pixels = fb->readRgba8();
    ASSERT_EQ(pixels.size(), 3u * 2u * 4u);
    const int expected[4] = {128, 255, 0, 51}; // round(255·c)
    for (size_t i = 0; i < pixels.size(); ++i)
        EXPECT_NEAR(int(pixels[i]), expected[i % 4], kUnormRoundingCodes);
}

TEST_F(GpuResources, MsaaResolveAveragesCoverage) {
    constexpr int kSize = 16;
    // A triangle over the lower-left half of the viewport: its hypotenuse crosses pixels.
    const std::string vertex =
        "#version 330 core\nvoid main() {\n"
        "  vec2 p = vec2(gl_VertexID == 1 ? 1.0 : -1.0, gl_VertexID == 2 ? 1.0 : -1.0);\n"
        "  gl_Position = vec4(p, 0.0, 1.0);\n}\n";
    const std::string fragment = "#version 330 core\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n";
    auto program = Program::fromSources(vertex, fragment, "half triangle");
    ASSERT_TRUE(program) << program.error();
    FullscreenTriangle vao; // an empty VAO: the positions come from gl_VertexID

    auto render = [&](int samples) {
        auto fb = Framebuffer::create(kSize, kSize, ColorFormat::Rgba32f, true, samples);
        EXPECT_TRUE(fb) << fb.error();
        if (!fb) return std::vector<float>{};
        fb->bind();
        glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        program->use();
        vao.draw();
        return fb->readRgbaFloat();
    };
    const auto single = render(1);
    const auto msaa = render(4);
    ASSERT_EQ(single.size(), msaa.size());
    int partial = 0;
    double sum = 0.0;
    for (size_t i = 0; i < msaa.size(); i += 4) {
        EXPECT_TRUE(single[i] == 0.0f || single[i] == 1.0f) << "one sample per pixel: no partial coverage";
        if (msaa[i] > 0.0f && msaa[i] < 1.0f) ++partial;
        sum += msaa[i];
    }
    // Every pixel on the diagonal is partly covered: at least one per row.
    EXPECT_GE(partial, kSize);
    // The resolved image integrates the triangle's area (half the target) up to the sample
    // quantization along the diagonal: at most half a pixel's worth per diagonal pixel.
    const double coverage = sum / double(kSize * kSize);
    const double kDiagonalQuantization = 0.5 * double(kSize) / double(kSize * kSize);
    EXPECT_NEAR(coverage, 0.5, kDiagonalQuantization);
    // The resolved texture is what colorTexture() names for a later pass.
    auto fb = Framebuffer::create(kSize, kSize, ColorFormat::Rgba16f, false, 4);
    ASSERT_TRUE(fb) << fb.error();
    EXPECT_NE(fb->colorTexture(), 0u);
    EXPECT_EQ(fb->samples(), 4);
}

TEST_F(GpuResources, BadFramebufferSizesAreRejected) {
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &maxSize);
    EXPECT_FALSE(Framebuffer::create(0, 4, ColorFormat::Rgba8));
    EXPECT_FALSE(Framebuffer::create(4, -1, ColorFormat::Rgba8));
    EXPECT_FALSE(Framebuffer::create(maxSize + 1, 4, ColorFormat::Rgba32f));
    EXPECT_FALSE(Framebuffer::create(4, 4, ColorFormat::Rgba8, true, 0));
    auto tooManySamples = Framebuffer::create(4, 4, ColorFormat::Rgba8, true, 1 << 20);
    ASSERT_FALSE(tooManySamples);
    EXPECT_NE(tooManySamples.error().find("samples"), std::string::npos) << tooManySamples.error();
}

TEST_F(GpuResources, TextureRoundTripKeepsValuesAndOrientation) {
    // Non-square and odd so a transposed or flipped upload cannot pass.
    constexpr int kWidth = 5;
    constexpr int kHeight = 3;
    for (const int channels : {1, 2, 3, 4}) {
        TextureLevel level{kWidth, kHeight, {}};
        for (int i = 0; i < kWidth * kHeight * channels; ++i)
            level.texels.push_back(float(i) * 0.37f - 2.0f);
        auto texture = Texture2D::create({level}, channels, TextureFilter::Nearest, false);
        ASSERT_TRUE(texture) << texture.error();
        EXPECT_EQ(texture->levels(), 1);
        const auto pixels = drawTexture(*texture);
        ASSERT_EQ(pixels.size(), size_t(kWidth * kHeight * 4));
        for (int p = 0; p < kWidth * kHeight; ++p) {
            for (int c = 0; c < 4; ++c) {
                // Missing channels read as GL's (0, 0, 0, 1).
                const float expected =
                    c < channels ? level.texels[size_t(p * channels + c)] : (c == 3 ? 1.0f : 0.0f);
                EXPECT_EQ(pixels[size_t(p * 4 + c)], expected)
                    << channels << " channels, texel " << p << " c " << c;
            }
        }
    }
}

// A region update writes exactly its rectangle of its level, upright (image rows top first, as the
// upload): the rest of the texture and the other levels keep their texels; bad requests change
// nothing.
TEST_F(GpuResources, UpdateRegionWritesItsRectangleOfItsLevelOnly) {
    constexpr int kWidth = 6, kHeight = 4, kChannels = 2;
    std::vector<TextureLevel> levels;
    for (int k = 0, w = kWidth, h = kHeight; k < 2; ++k, w /= 2, h /= 2) {
        TextureLevel level{w, h, {}};
        for (int i = 0; i < w * h * kChannels; ++i)
            level.texels.push_back(float(k * 100 + i));
        levels.push_back(level);
    }
    auto created = Texture2D::create(levels, kChannels, TextureFilter::Nearest, false);
    ASSERT_TRUE(created) << created.error();
    Texture2D texture = std::move(created).value();
    // A 3×2 rectangle at (2, 1) of level 0: rows top first.
    std::vector<float> patch;
    for (int i = 0; i < 3 * 2 * kChannels; ++i)
        patch.push_back(-1.0f - float(i));
    ASSERT_TRUE(texture.updateRegion(0, 2, 1, 3, 2, patch));
    std::vector<float> expected = levels[0].texels;
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 3; ++x)
            for (int c = 0; c < kChannels; ++c)
                expected[size_t(((1 + y) * kWidth + 2 + x) * kChannels + c)] =
                    patch[size_t((y * 3 + x) * kChannels + c)];
    const auto pixels = drawTexture(texture);
    ASSERT_EQ(pixels.size(), size_t(kWidth * kHeight * 4));
    for (int p = 0; p < kWidth * kHeight; ++p)
        for (int c = 0; c < kChannels; ++c)
            EXPECT_EQ(pixels[size_t(p * 4 + c)], expected[size_t(p * kChannels + c)])
                << "texel " << p << " c " << c;
    const auto level1 = drawTexture(texture, "texelFetch(uTex, ivec2(vUv * vec2(3.0, 2.0)), 1)");
    ASSERT_FALSE(level1.empty());
    // Level 1 (3×2) untouched: its texels all lie at 100 and above.
    for (size_t i = 0; i < level1.size(); i += 4)
        EXPECT_GE(level1[i], 100.0f);

    EXPECT_FALSE(texture.updateRegion(2, 0, 0, 1, 1, {0.0f, 0.0f})) << "no level 2";
    EXPECT_FALSE(texture.updateRegion(0, 4, 0, 3, 1, std::vector<float>(6, 0.0f))) << "past the right edge";
    EXPECT_FALSE(texture.updateRegion(1, 0, 1, 2, 2, std::vector<float>(8, 0.0f))) << "past level 1's bottom";
    EXPECT_FALSE(texture.updateRegion(0, 0, 0, 2, 1, std::vector<float>(3, 0.0f))) << "a wrong count";
    EXPECT_FALSE(texture.updateRegion(0, 0, 0, 1, 1, {0.0f, std::nanf("")})) << "a NaN";
    EXPECT_EQ(drawTexture(texture), pixels) << "refused updates change nothing";
}

TEST_F(GpuResources, HalfTextureRoundTrip) {
    // Multiples of 1/8 below 2048 are exact in half precision: the round trip is exact.
    TextureLevel level{4, 2, {}};
    for (int i = 0; i < 4 * 2 * 4; ++i)
        level.texels.push_back(float(i) * 0.125f - 1.0f);
    auto texture = Texture2D::create({level}, 4, TextureFilter::Nearest, true, true);
    ASSERT_TRUE(texture) << texture.error();
    const auto pixels = drawTexture(*texture);
    ASSERT_EQ(pixels.size(), level.texels.size());
    for (size_t i = 0; i < pixels.size(); ++i)
        EXPECT_EQ(pixels[i], level.texels[i]) << "index " << i;
}

TEST_F(GpuResources, UploadedMipLevelsAreSampledAndMaxLevelIsSet) {
    std::vector<TextureLevel> levels;
    const float values[3] = {0.25f, 0.5f, 0.75f};
    int size = 4;
    for (const float value : values) {
        levels.push_back({size, size, std::vector<float>(size_t(size * size), value)});
        size /= 2;
    }
    auto texture = Texture2D::create(levels, 1, TextureFilter::LinearMipLinear);
    ASSERT_TRUE(texture) << texture.error();
    EXPECT_EQ(texture->levels(), 3);
    texture->bind(0);
    GLint maxLevel = -1;
    glGetTexParameteriv(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, &maxLevel);
    EXPECT_EQ(maxLevel, 2);
    for (int lod = 0; lod < 3; ++lod) {
        const std::string lookup = "textureLod(uTex, vUv, " + std::to_string(lod) + ".0)";
        const auto pixels = drawTexture(*texture, lookup.c_str());
        ASSERT_FALSE(pixels.empty());
        for (size_t i = 0; i < pixels.size(); i += 4)
            EXPECT_EQ(pixels[i], values[lod]) << "lod " << lod;
    }

    // One level with LinearMipLinear: GL generates the full chain (8 → 4 → 2 → 1).
    auto generated =
        Texture2D::create({{8, 8, std::vector<float>(64, 1.0f)}}, 1, TextureFilter::LinearMipLinear);
    ASSERT_TRUE(generated) << generated.error();
    EXPECT_EQ(generated->levels(), 4);
}

TEST_F(GpuResources, BadTextureInputIsRejected) {
    const TextureLevel good{2, 2, std::vector<float>(4, 0.5f)};
    EXPECT_FALSE(Texture2D::create({}, 1, TextureFilter::Linear));
    EXPECT_FALSE(Texture2D::create({good}, 0, TextureFilter::Linear));
    EXPECT_FALSE(Texture2D::create({good}, 5, TextureFilter::Linear));
    EXPECT_FALSE(Texture2D::create({{0, 2, {}}}, 1, TextureFilter::Linear));
    EXPECT_FALSE(Texture2D::create({{2, 2, std::vector<float>(3, 0.5f)}}, 1, TextureFilter::Linear));
    // Level 1 of a 2×2 is 1×1, not 2×2.
    EXPECT_FALSE(Texture2D::create({good, good}, 1, TextureFilter::LinearMipLinear));
    // A 2×2 chain has 2 levels, not 3.
    const TextureLevel one{1, 1, {0.5f}};
    EXPECT_FALSE(Texture2D::create({good, one, one}, 1, TextureFilter::LinearMipLinear));
    TextureLevel nan = good;
    nan.texels[1] = std::numeric_limits<float>::quiet_NaN();
    auto nanResult = Texture2D::create({nan}, 1, TextureFilter::Linear);
    ASSERT_FALSE(nanResult);
    EXPECT_NE(nanResult.error().find("non-finite"), std::string::npos) << nanResult.error();
    TextureLevel huge = good;
    huge.texels[0] = 1.0e5f; // beyond half's 65504: fine in 32F, Inf in 16F
    EXPECT_TRUE(Texture2D::create({huge}, 1, TextureFilter::Linear, true, false));
    EXPECT_FALSE(Texture2D::create({huge}, 1, TextureFilter::Linear, true, true));
}

namespace {

// HDR test values: black, the sRGB linear segment, mid grey, white, over-range, and where the
// filmic curve saturates (~7.24) and beyond.
const float kHdrValues[] = {0.0f, 0.001f, 0.0031308f, 0.02f, 0.18f, 0.5f,
                            1.0f, 1.5f,   3.0f,       7.0f,  8.0f,  100.0f};
constexpr int kHdrCount = int(sizeof(kHdrValues) / sizeof(kHdrValues[0]));

// tonemap.frag over a kHdrCount×1 RGB texture (the value in r, half of it in g, a tenth in b).
std::vector<float> runTonemap(const ShaderDefines& defines, float exposure) {
    TextureLevel level{kHdrCount, 1, {}};
    for (const float x : kHdrValues)
        level.texels.insert(level.texels.end(), {x, 0.5f * x, 0.1f * x});
    auto texture = Texture2D::create({level}, 3, TextureFilter::Nearest, false);
    EXPECT_TRUE(texture) << texture.error();
    auto program = Program::fromFiles("fullscreen.vert", "tonemap.frag", defines);
    EXPECT_TRUE(program) << program.error();
    auto fb = Framebuffer::create(kHdrCount, 1, ColorFormat::Rgba32f, false);
    EXPECT_TRUE(fb) << fb.error();
    if (!texture || !program || !fb) return {};
    fb->bind();
    texture->bind(0);
    program->set("uHdr", 0);
    program->set("uExposure", exposure);
    FullscreenTriangle triangle;
    triangle.draw();
    return fb->readRgbaFloat();
}

} // namespace

TEST_F(GpuResources, TonemapNoneIsTheSrgbEncodingOfCore) {
    for (const float exposure : {1.0f, 0.25f}) {
        const auto pixels = runTonemap({{"TONEMAP_NONE", "1"}}, exposure);
        ASSERT_EQ(pixels.size(), size_t(kHdrCount * 4));
        for (int i = 0; i < kHdrCount; ++i) {
            const double scales[3] = {1.0, 0.5, 0.1};
            for (int c = 0; c < 3; ++c) {
                const double x = double(kHdrValues[i]) * scales[c] * exposure;
                EXPECT_NEAR(pixels[size_t(i * 4 + c)], linearToSrgb(x), kShaderVsCoreTolerance)
                    << "x " << x << " exposure " << exposure;
            }
            EXPECT_EQ(pixels[size_t(i * 4 + 3)], 1.0f);
        }
    }
}

TEST_F(GpuResources, TonemapFilmicMatchesCoreTwin) {
    for (const float exposure : {1.0f, 2.0f}) {
        const auto pixels = runTonemap({}, exposure);
        ASSERT_EQ(pixels.size(), size_t(kHdrCount * 4));
        for (int i = 0; i < kHdrCount; ++i) {
            const double scales[3] = {1.0, 0.5, 0.1};
            for (int c = 0; c < 3; ++c) {
                const double x = double(kHdrValues[i]) * scales[c] * exposure;
                EXPECT_NEAR(pixels[size_t(i * 4 + c)], linearToSrgb(tonemapFilmic(x)), kShaderVsCoreTolerance)
                    << "x " << x << " exposure " << exposure;
            }
        }
    }
}

TEST(TonemapFilmic, ZeroMonotoneBoundedAndFiniteAtExtremes) {
    EXPECT_EQ(tonemapFilmic(0.0), 0.0);
    EXPECT_EQ(tonemapFilmic(-5.0), 0.0);
    EXPECT_EQ(tonemapFilmic(std::numeric_limits<double>::quiet_NaN()), 0.0);
    EXPECT_EQ(tonemapFilmic(std::numeric_limits<double>::infinity()), 1.0);
    EXPECT_EQ(tonemapFilmic(std::numeric_limits<float>::max()), 1.0f);
    EXPECT_EQ(tonemapFilmic(1.0e30), 1.0);
    // Hand-evaluated from Narkowicz's constants (catches a mistyped one): mid grey 0.18 →
    // 0.086724/0.324932 = 0.2669, 1 → 2.54/3.16 = 0.8038.
    constexpr double kFourDigits = 5e-5; // the reference values are rounded to 4 digits
    EXPECT_NEAR(tonemapFilmic(0.18), 0.2669, kFourDigits);
    EXPECT_NEAR(tonemapFilmic(1.0), 0.8038, kFourDigits);
    double previous = 0.0;
    for (int i = 1; i <= 20000; ++i) {
        const double x = double(i) * 1e-3; // 0.001 .. 20, past saturation
        const double y = tonemapFilmic(x);
        EXPECT_GE(y, previous) << "x " << x;
        EXPECT_LE(y, 1.0);
        previous = y;
        if (::testing::Test::HasFailure()) break;
    }
    // float and double agree (the GLSL twin computes in float).
    constexpr double kFloatTolerance = 1e-6; // a few float ulps of values in [0, 1]
    for (const double x : {0.01, 0.18, 1.0, 4.0})
        EXPECT_NEAR(tonemapFilmic(float(x)), tonemapFilmic(x), kFloatTolerance);
}
