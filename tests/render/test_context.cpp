// Headless OpenGL contexts: EGL surfaceless and OSMesa (both in one process, switching between
// them), BURNISH_GL narrowing the choice, and the host-context wrapper.
#include <burnish/render/context.h>
#include <burnish/render/gpu_resources.h>

#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

using namespace burnish;
using namespace burnish::render;

namespace {

// The renderer's floor: OpenGL 3.3 core (major*10 + minor, as epoxy_gl_version reports).
constexpr int kMinGlVersion = 33;

// Sets BURNISH_GL for one scope and restores the previous value (or its absence) afterwards.
class ScopedBurnishGl {
public:
    explicit ScopedBurnishGl(const char* value) {
        if (const char* old = std::getenv("BURNISH_GL")) m_old = old;
        if (value) {
            setenv("BURNISH_GL", value, 1);
        } else {
            unsetenv("BURNISH_GL");
        }
    }
    ~ScopedBurnishGl() {
        if (m_old) {
            setenv("BURNISH_GL", m_old->c_str(), 1);
        } else {
            unsetenv("BURNISH_GL");
        }
    }
    ScopedBurnishGl(const ScopedBurnishGl&) = delete;
    ScopedBurnishGl& operator=(const ScopedBurnishGl&) = delete;

private:
    std::optional<std::string> m_old;
};

bool isCoreProfile() {
    GLint profile = 0;
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    return (profile & GL_CONTEXT_CORE_PROFILE_BIT) != 0;
}

// Draws through the current context (clear of an FBO, read back): proves GL calls reach it, not
// only that glGetString answers.
::testing::AssertionResult clearAndReadBack(float value) {
    auto fb = Framebuffer::create(4, 4, ColorFormat::Rgba32f, false);
    if (!fb) return ::testing::AssertionFailure() << fb.error();
    fb->bind();
    glClearColor(value, value, value, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    const std::vector<float> pixels = fb->readRgbaFloat();
    for (size_t i = 0; i < pixels.size(); i += 4) {
        // A 32F target stores the clear colour exactly: no tolerance.
        if (pixels[i] != value)
            return ::testing::AssertionFailure() << "texel " << i / 4 << " = " << pixels[i];
    }
    return ::testing::AssertionSuccess();
}

void expectUsable(const GlContext& context, ContextKind kind) {
    EXPECT_EQ(context.kind(), kind);
    EXPECT_GE(epoxy_gl_version(), kMinGlVersion);
    EXPECT_TRUE(epoxy_is_desktop_gl());
    EXPECT_TRUE(isCoreProfile());
    const std::string description = context.description();
    EXPECT_EQ(description.rfind(std::string(contextKindName(kind)), 0), 0u) << description;
    EXPECT_NE(description.find("OpenGL "), std::string::npos) << description;
}

} // namespace

TEST(Context, DefaultHeadlessContextIsCore33OrLater) {
    auto context = createHeadlessContext();
    ASSERT_TRUE(context) << context.error();
    ASSERT_TRUE((*context)->makeCurrent()) << "makeCurrent failed";
    const ContextKind kind = (*context)->kind();
    EXPECT_TRUE(kind == ContextKind::EglSurfaceless || kind == ContextKind::OsMesa);
    expectUsable(**context, kind);
    EXPECT_TRUE(clearAndReadBack(0.25f));
}

TEST(Context, EglAndOsMesaInOneProcessAndSwitching) {
    std::unique_ptr<GlContext> egl;
    {
        ScopedBurnishGl only("egl");
        auto created = createHeadlessContext();
        if (!created) GTEST_SKIP() << "EGL surfaceless unavailable here: " << created.error();
        egl = std::move(created).value();
    }
    expectUsable(*egl, ContextKind::EglSurfaceless);
    EXPECT_TRUE(clearAndReadBack(0.5f));

    std::unique_ptr<GlContext> osmesa;
    {
        ScopedBurnishGl only("osmesa");
        auto created = createHeadlessContext();
        if (!created) GTEST_SKIP() << "OSMesa unavailable here: " << created.error();
        osmesa = std::move(created).value();
    }
    // OSMesa: epoxy cannot resolve GL by itself; makeCurrent() must have pointed it at OSMesa.
    expectUsable(*osmesa, ContextKind::OsMesa);
    EXPECT_TRUE(clearAndReadBack(0.75f));

    // Back and forth: each switch re-points epoxy, and each context still draws.
    ASSERT_TRUE(egl->makeCurrent());
    expectUsable(*egl, ContextKind::EglSurfaceless);
    EXPECT_TRUE(clearAndReadBack(0.125f));
    ASSERT_TRUE(osmesa->makeCurrent());
    expectUsable(*osmesa, ContextKind::OsMesa);
    EXPECT_TRUE(clearAndReadBack(0.625f));
}

TEST(Context, OsMesaAlone) {
    ScopedBurnishGl only("osmesa");
    auto context = createHeadlessContext();
    if (!context) GTEST_SKIP() << "OSMesa unavailable here: " << context.error();
    expectUsable(**context, ContextKind::OsMesa);
    EXPECT_TRUE(clearAndReadBack(1.0f));
}

TEST(Context, OptionsRestrictTheKind) {
    ScopedBurnishGl unset(nullptr);
    HeadlessContextOptions options;
    options.tryEgl = false;
    auto context = createHeadlessContext(options);
    if (!context) GTEST_SKIP() << "OSMesa unavailable here: " << context.error();
    EXPECT_EQ((*context)->kind(), ContextKind::OsMesa);
}

TEST(Context, BogusBurnishGlIsAClearError) {
    ScopedBurnishGl bogus("vulkan");
    auto context = createHeadlessContext();
    ASSERT_FALSE(context);
    EXPECT_NE(context.error().find("BURNISH_GL='vulkan'"), std::string::npos) << context.error();
    EXPECT_NE(context.error().find("egl, osmesa"), std::string::npos) << context.error();
    EXPECT_EQ(context.error().find('\n'), std::string::npos) << "errors are one line";
}

TEST(Context, NothingToTryIsAnError) {
    ScopedBurnishGl only("egl");
    HeadlessContextOptions options;
    options.tryEgl = false; // BURNISH_GL=egl removes OSMesa, the options remove EGL
    auto context = createHeadlessContext(options);
    ASSERT_FALSE(context);
    EXPECT_NE(context.error().find("no OpenGL context"), std::string::npos) << context.error();
}

TEST(Context, UnreachableVersionNamesEveryKindTried) {
    ScopedBurnishGl unset(nullptr);
    HeadlessContextOptions options;
    options.minVersion = 99; // OpenGL 9.9 exists nowhere: every kind must fail and say why
    auto context = createHeadlessContext(options);
    ASSERT_FALSE(context);
    const std::string& error = context.error();
    EXPECT_EQ(error.rfind("no OpenGL context: ", 0), 0u) << error;
    EXPECT_NE(error.find("EGL surfaceless: "), std::string::npos) << error;
    EXPECT_NE(error.find("OSMesa: "), std::string::npos) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << "errors are one line";
}

TEST(Context, HostContextChecksWhatIsCurrent) {
    ScopedBurnishGl unset(nullptr);
    auto host = wrapHostContext();
    EXPECT_EQ(host->kind(), ContextKind::Host);
    {
        auto headless = createHeadlessContext();
        ASSERT_TRUE(headless) << headless.error();
        ASSERT_TRUE((*headless)->makeCurrent());
        const Status status = host->makeCurrent();
        ASSERT_TRUE(status) << status.error();
        EXPECT_EQ(host->description().rfind("host, OpenGL ", 0), 0u) << host->description();
        EXPECT_TRUE(clearAndReadBack(0.375f));
    }
    // The headless context is gone: nothing is current, and the wrapper says so.
    const Status status = host->makeCurrent();
    ASSERT_FALSE(status);
    EXPECT_NE(status.error().find("no current OpenGL context"), std::string::npos) << status.error();
}
