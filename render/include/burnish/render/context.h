// OpenGL contexts the renderer draws in: a headless one it creates itself (EGL surfaceless, the
// default, then OSMesa as the fallback) or the host's (the studio's QOpenGLWidget), which the
// renderer only uses while the host keeps it current. OpenGL 3.3 core or later, through libepoxy.
#pragma once

#include <burnish/core/util/result.h>

#include <memory>
#include <string>
#include <string_view>
#include <utility>

namespace burnish::render {

enum class ContextKind {
    EglSurfaceless, // EGL_MESA_platform_surfaceless / EGL_EXT_platform_device: no display needed
    OsMesa,         // Mesa's off-screen software context
    Host,           // created and made current by the application (e.g. Qt)
};

std::string_view contextKindName(ContextKind kind);

struct HeadlessContextOptions {
    /// Kinds to try, in order. The default tries EGL surfaceless, then OSMesa.
    /// The environment variable BURNISH_GL=egl|osmesa, when set, narrows the default to one kind.
    bool tryEgl = true;
    bool tryOsMesa = true;
    /// Lowest OpenGL core version accepted (major*10 + minor).
    int minVersion = 33;
};

/// An OpenGL context the renderer owns. Destroying it releases the context and everything made
/// in it; GL objects must not outlive it.
class GlContext {
public:
    virtual ~GlContext() = default;
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    virtual ContextKind kind() const = 0;
    /// Makes the context current on the calling thread. Fails with a message when it cannot.
    /// Contexts of different kinds may live in one process; call makeCurrent() when switching, as
    /// it also points libepoxy's dispatch at the right library (epoxy alone cannot resolve GL under
    /// OSMesa). One thread at a time.
    virtual Status makeCurrent() = 0;
    /// "EGL surfaceless, OpenGL 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)"
    /// ("EGL device 0, ..." on NVIDIA's headless EGL). Taken when the context was created (for the
    /// host's, at the last successful makeCurrent()), so it needs no current context.
    std::string description() const;

protected:
    GlContext() = default;
    void setDescription(std::string description) { m_description = std::move(description); }

private:
    std::string m_description;
};

/// Creates a headless context, current on the calling thread. When none can be made the error
/// names each kind tried and why it failed, in one line.
Result<std::unique_ptr<GlContext>> createHeadlessContext(const HeadlessContextOptions& options = {});

/// Wraps a context the host has made current (the studio's). makeCurrent() checks that a context
/// is current and that it is OpenGL 3.3 core or later; the host owns its lifetime.
std::unique_ptr<GlContext> wrapHostContext();

/// "OpenGL 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)" of the current context.
std::string currentGlDescription();

} // namespace burnish::render
