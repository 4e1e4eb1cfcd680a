// A GoogleTest fixture for renderer tests: one headless OpenGL context and one Renderer per test
// suite (created in SetUpTestSuite, destroyed in TearDownTestSuite), made current before each test.
// A machine without any OpenGL context fails every test of the suite with the context's error.
#pragma once

#include <burnish/render/context.h>
#include <burnish/render/renderer.h>

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace burnish::test {

class RendererFixture : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        auto created = render::createHeadlessContext();
        if (!created) {
            s_error = created.error();
            return;
        }
        s_context = std::move(created).value();
        auto renderer = render::Renderer::create();
        if (!renderer)
            s_error = renderer.error();
        else
            s_renderer = std::move(renderer).value();
    }
    static void TearDownTestSuite() {
        s_renderer.reset();
        s_context.reset();
    }
    void SetUp() override {
        ASSERT_TRUE(s_context) << "no headless OpenGL context: " << s_error;
        ASSERT_TRUE(s_context->makeCurrent().ok());
        ASSERT_TRUE(s_renderer) << s_error;
    }

    static render::Renderer& renderer() { return *s_renderer; }
    static render::GlContext& context() { return *s_context; }

    static inline std::string s_error;
    static inline std::unique_ptr<render::GlContext> s_context;
    static inline std::unique_ptr<render::Renderer> s_renderer;
};

} // namespace burnish::test
