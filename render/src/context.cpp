#include <burnish/render/context.h>

// epoxy first: it defines the GL and EGL prototypes, and its guards keep osmesa.h's <GL/gl.h> out.
#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <GL/osmesa.h>

#include <dlfcn.h>
#include <elf.h>
#include <link.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <type_traits>
#include <vector>

namespace burnish::render {

namespace {

// ---------------------------------------------------------------------------------------------
// libepoxy under OSMesa. epoxy resolves GL entry points through EGL or GLX only (its resolver
// asserts "Couldn't find current GLX or EGL context" otherwise), so with an OSMesa context current
// every epoxy dispatch pointer (the exported data symbols `epoxy_glFoo`) is pointed at OSMesa's own
// entry point, and put back when an EGL or host context is made current again. The names come from
// libepoxy's dynamic symbol table, so every function epoxy knows is covered.

// ---------------------------------------------------------------------------------------------
// libOSMesa is opened on first use instead of being linked: it pulls in LLVM (Mesa's llvmpipe),
// whose symbol lookups every start of `burnish` paid, even for commands that never render.

struct OsMesaApi {
    void* library = nullptr;
    decltype(&OSMesaCreateContextAttribs) createContextAttribs = nullptr;
    decltype(&OSMesaMakeCurrent) makeCurrent = nullptr;
    decltype(&OSMesaGetCurrentContext) getCurrentContext = nullptr;
    decltype(&OSMesaDestroyContext) destroyContext = nullptr;
    decltype(&OSMesaGetProcAddress) getProcAddress = nullptr;
};

// The library and its five entry points, opened once (never closed: contexts may outlive callers).
Result<const OsMesaApi*> osMesaApi() {
    static const Result<OsMesaApi> api = []() -> Result<OsMesaApi> {
        OsMesaApi a;
        std::string why;
        for (const char* name : {"libOSMesa.so.8", "libOSMesa.so.6"}) {
            a.library = dlopen(name, RTLD_NOW | RTLD_LOCAL);
            if (a.library) break;
            if (const char* error = dlerror()) why = error;
        }
        if (!a.library) return Error{"OSMesa: cannot load libOSMesa (" + why + ")"};
        auto bind = [&](auto& fn, const char* symbol) {
            fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(dlsym(a.library, symbol));
            return fn != nullptr;
        };
        if (!bind(a.createContextAttribs, "OSMesaCreateContextAttribs") ||
            !bind(a.makeCurrent, "OSMesaMakeCurrent") ||
            !bind(a.getCurrentContext, "OSMesaGetCurrentContext") ||
            !bind(a.destroyContext, "OSMesaDestroyContext") ||
            !bind(a.getProcAddress, "OSMesaGetProcAddress"))
            return Error{"OSMesa: libOSMesa lacks an entry point Burnish needs"};
        return a;
    }();
    if (!api) return Error{api.error()};
    return &*api;
}

struct EpoxyPointer {
    void** slot = nullptr; // &epoxy_glFoo: the pointer the `glFoo` macro calls through
    std::string glName;    // "glFoo"
    void* saved = nullptr; // epoxy's own value (resolver stub or resolved address)
};

enum class EpoxyBinding { Native, OsMesa };

std::mutex g_epoxyMutex;
EpoxyBinding g_epoxyBinding = EpoxyBinding::Native;
std::vector<EpoxyPointer> g_epoxyPointers;
bool g_epoxyPointersListed = false;

// The path of the loaded libepoxy, read from the dynamic linker's map (no guess at file names).
std::string loadedEpoxyPath() {
    void* handle = dlopen("libepoxy.so.0", RTLD_LAZY | RTLD_NOLOAD);
    if (!handle) return {};
    link_map* map = nullptr;
    std::string path;
    if (dlinfo(handle, RTLD_DI_LINKMAP, &map) == 0 && map && map->l_name) path = map->l_name;
    dlclose(handle);
    return path;
}

// Names of epoxy's GL dispatch pointers ("epoxy_glFoo", data objects), from the .dynsym section of
// the library file. GLX entry points (epoxy_glXFoo) and epoxy's internal `_unwrapped` pointers are
// left alone.
Status listEpoxyPointers(std::vector<EpoxyPointer>& out) {
    const std::string path = loadedEpoxyPath();
    if (path.empty()) return Error{"libepoxy.so.0 is not loaded as a shared library"};
    std::ifstream file(path, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    if (bytes.size() < sizeof(ElfW(Ehdr))) return Error{"cannot read " + path};
    ElfW(Ehdr) header;
    std::memcpy(&header, bytes.data(), sizeof(header));
    if (std::memcmp(header.e_ident, ELFMAG, SELFMAG) != 0 || header.e_shentsize != sizeof(ElfW(Shdr)) ||
        header.e_shoff + size_t(header.e_shnum) * sizeof(ElfW(Shdr)) > bytes.size()) {
        return Error{path + " is not an ELF library this build can read"};
    }
    std::vector<ElfW(Shdr)> sections(header.e_shnum);
    std::memcpy(sections.data(), bytes.data() + header.e_shoff, sections.size() * sizeof(ElfW(Shdr)));
    for (const auto& section : sections) {
        if (section.sh_type != SHT_DYNSYM || section.sh_link >= sections.size()) continue;
        const auto& strings = sections[section.sh_link];
        if (section.sh_offset + section.sh_size > bytes.size() ||
            strings.sh_offset + strings.sh_size > bytes.size()) {
            return Error{path + ": truncated symbol table"};
        }
        const size_t count = section.sh_size / sizeof(ElfW(Sym));
        for (size_t i = 0; i < count; ++i) {
            ElfW(Sym) symbol;
            std::memcpy(&symbol, bytes.data() + section.sh_offset + i * sizeof(ElfW(Sym)), sizeof(symbol));
            if (ELF64_ST_TYPE(symbol.st_info) != STT_OBJECT || symbol.st_shndx == SHN_UNDEF) continue;
            if (symbol.st_name >= strings.sh_size) continue;
            const char* name = bytes.data() + strings.sh_offset + symbol.st_name;
            const size_t length = strnlen(name, strings.sh_size - symbol.st_name);
            const std::string_view nameView(name, length);
            if (nameView.size() < 9 || nameView.substr(0, 8) != "epoxy_gl") continue;
            const char first = nameView[8];
            if (first < 'A' || first > 'Z' || first == 'X' ||
                nameView.find('_', 8) != std::string_view::npos) {
                continue;
            }
            // RTLD_DEFAULT finds the copy the program actually uses (a copy relocation may move it).
            void* slot = dlsym(RTLD_DEFAULT, std::string(nameView).c_str());
            if (!slot) continue;
            out.push_back({static_cast<void**>(slot), std::string(nameView.substr(6)), nullptr});
        }
    }
    if (out.empty()) return Error{path + " exports no epoxy_gl* dispatch pointers"};
    return {};
}

Status bindEpoxyToOsMesa() {
    std::lock_guard lock(g_epoxyMutex);
    if (g_epoxyBinding == EpoxyBinding::OsMesa) return {};
    if (!g_epoxyPointersListed) {
        if (auto status = listEpoxyPointers(g_epoxyPointers); !status) {
            return Error{"libepoxy cannot resolve GL under OSMesa (" + status.error() + ")"};
        }
        g_epoxyPointersListed = true;
    }
    const auto api = osMesaApi();
    if (!api) return Error{api.error()};
    for (auto& pointer : g_epoxyPointers) {
        pointer.saved = *pointer.slot;
        // The library's exported entry point first: OSMesaGetProcAddress would mint a dispatch
        // stub for every unknown name it is asked about.
        void* entry = dlsym((*api)->library, pointer.glName.c_str());
        if (!entry) entry = reinterpret_cast<void*>((*api)->getProcAddress(pointer.glName.c_str()));
        if (entry) *pointer.slot = entry;
    }
    g_epoxyBinding = EpoxyBinding::OsMesa;
    return {};
}

void bindEpoxyToNative() {
    std::lock_guard lock(g_epoxyMutex);
    if (g_epoxyBinding == EpoxyBinding::Native) return;
    for (const auto& pointer : g_epoxyPointers)
        *pointer.slot = pointer.saved;
    g_epoxyBinding = EpoxyBinding::Native;
}

// ---------------------------------------------------------------------------------------------
// Checks shared by every kind: the current context is OpenGL `minVersion` or later, core profile.

Status checkCurrentGl(int minVersion) {
    const int version = epoxy_gl_version();
    if (version == 0) return Error{"no current OpenGL context (glGetString(GL_VERSION) returned nothing)"};
    if (!epoxy_is_desktop_gl()) return Error{"the current context is OpenGL ES, not desktop OpenGL"};
    if (version < minVersion) {
        return Error{"OpenGL " + std::to_string(version / 10) + "." + std::to_string(version % 10) +
                     " is older than the required " + std::to_string(minVersion / 10) + "." +
                     std::to_string(minVersion % 10)};
    }
    GLint profile = 0;
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    if (!(profile & GL_CONTEXT_CORE_PROFILE_BIT)) return Error{"the current context is not a core profile"};
    return {};
}

// ---------------------------------------------------------------------------------------------
// EGL

std::string eglErrorName(EGLint error) {
    switch (error) {
    case EGL_SUCCESS:
        return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
        return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
        return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
        return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
        return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
        return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
        return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE:
        return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY:
        return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
        return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP:
        return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW:
        return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER:
        return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE:
        return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST:
        return "EGL_CONTEXT_LOST";
    default: {
        std::ostringstream out;
        out << "EGL error 0x" << std::hex << error;
        return out.str();
    }
    }
}

std::string eglFailure(const char* call) {
    return std::string(call) + " failed (" + eglErrorName(eglGetError()) + ")";
}

bool hasExtension(const char* list, std::string_view name) {
    if (!list) return false;
    std::string_view all(list);
    size_t pos = 0;
    while ((pos = all.find(name, pos)) != std::string_view::npos) {
        const size_t end = pos + name.size();
        const bool startOk = pos == 0 || all[pos - 1] == ' ';
        const bool endOk = end == all.size() || all[end] == ' ';
        if (startOk && endOk) return true;
        pos = end;
    }
    return false;
}

// EGLDisplays are process-wide singletons per platform/device: terminate one only when the last
// context made on it goes away, or a second context in the same process would lose its display.
std::mutex g_displayMutex;
std::map<EGLDisplay, int> g_displayUsers;

void retainDisplay(EGLDisplay display) {
    std::lock_guard lock(g_displayMutex);
    ++g_displayUsers[display];
}

void releaseDisplay(EGLDisplay display) {
    std::lock_guard lock(g_displayMutex);
    if (--g_displayUsers[display] == 0) {
        g_displayUsers.erase(display);
        eglTerminate(display);
    }
}

class EglContext final : public GlContext {
public:
    EglContext(EGLDisplay display, EGLContext context, std::string label)
        : m_display(display)
        , m_context(context)
        , m_label(std::move(label)) {}
    ~EglContext() override {
        if (eglGetCurrentContext() == m_context) {
            eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        }
        eglDestroyContext(m_display, m_context);
        releaseDisplay(m_display);
    }
    ContextKind kind() const override { return ContextKind::EglSurfaceless; }
    Status makeCurrent() override {
        bindEpoxyToNative();
        if (!eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, m_context)) {
            return Error{m_label + ": " + eglFailure("eglMakeCurrent")};
        }
        return {};
    }
    using GlContext::setDescription;

private:
    EGLDisplay m_display;
    EGLContext m_context;
    std::string m_label;
};

// A core-profile context on an initialized display, current with no surface: 4.5 first (the most
// any renderer code may use), then the required minimum.
Result<std::unique_ptr<EglContext>> createEglContextOn(EGLDisplay display, const std::string& label,
                                                       int minVersion) {
    EGLint major = 0;
    EGLint minor = 0;
    if (!eglInitialize(display, &major, &minor)) return Error{eglFailure("eglInitialize")};
    retainDisplay(display);
    auto fail = [&](std::string message) -> Result<std::unique_ptr<EglContext>> {
        releaseDisplay(display);
        return Error{std::move(message)};
    };
    const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
    if (!hasExtension(extensions, "EGL_KHR_surfaceless_context")) {
        return fail("EGL_KHR_surfaceless_context is not supported");
    }
    const bool createContext =
        (major > 1 || minor >= 5) || hasExtension(extensions, "EGL_KHR_create_context");
    if (!createContext) return fail("EGL 1.5 or EGL_KHR_create_context is needed for a core profile");
    if (!eglBindAPI(EGL_OPENGL_API)) return fail(eglFailure("eglBindAPI(EGL_OPENGL_API)"));

    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!hasExtension(extensions, "EGL_KHR_no_config_context")) {
        // Without no-config contexts any OpenGL-renderable config serves: nothing is drawn to a
        // surface, the renderer draws into its own framebuffer objects.
        const EGLint configAttribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLint count = 0;
        if (!eglChooseConfig(display, configAttribs, &config, 1, &count) || count < 1) {
            return fail("no EGL config renders OpenGL");
        }
    }
    std::string lastFailure;
    for (const int version : {45, minVersion}) {
        if (version < minVersion) continue;
        const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                  version / 10,
                                  EGL_CONTEXT_MINOR_VERSION,
                                  version % 10,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                  EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                  EGL_NONE};
        EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, attribs);
        if (context == EGL_NO_CONTEXT) {
            lastFailure = "OpenGL " + std::to_string(version / 10) + "." + std::to_string(version % 10) +
                          " core: " + eglFailure("eglCreateContext");
            continue;
        }
        auto result = std::make_unique<EglContext>(display, context, label);
        // The EglContext now owns one display reference (released by its destructor).
        if (auto status = result->makeCurrent(); !status) return Error{status.error()};
        if (auto status = checkCurrentGl(minVersion); !status) return Error{status.error()};
        result->setDescription(label + ", " + currentGlDescription());
        return result;
    }
    return fail(lastFailure);
}

Result<std::unique_ptr<EglContext>> createEglContext(int minVersion) {
    // epoxy exits the process when libEGL cannot be loaded: look for it first.
    void* libEgl = dlopen("libEGL.so.1", RTLD_LAZY | RTLD_LOCAL);
    if (!libEgl) return Error{"EGL: libEGL.so.1 cannot be loaded"};
    dlclose(libEgl);

    const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!hasExtension(clientExtensions, "EGL_EXT_platform_base")) {
        return Error{"EGL: EGL_EXT_platform_base is not supported"};
    }
    std::string surfacelessWhy;
    if (hasExtension(clientExtensions, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay display =
            eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (display == EGL_NO_DISPLAY) {
            surfacelessWhy = eglFailure("eglGetPlatformDisplayEXT");
        } else {
            auto context = createEglContextOn(display, "EGL surfaceless", minVersion);
            if (context) return context;
            surfacelessWhy = context.error();
        }
    } else {
        surfacelessWhy = "EGL_MESA_platform_surfaceless is not supported";
    }

    // NVIDIA's headless driver has no surfaceless platform: take the first device that works.
    std::string deviceWhy;
    if (hasExtension(clientExtensions, "EGL_EXT_platform_device") &&
        (hasExtension(clientExtensions, "EGL_EXT_device_enumeration") ||
         hasExtension(clientExtensions, "EGL_EXT_device_base"))) {
        // 16 devices: more than any one machine the renderer runs on carries.
        EGLDeviceEXT devices[16];
        EGLint count = 0;
        if (!eglQueryDevicesEXT(16, devices, &count) || count < 1) {
            deviceWhy = count < 1 ? "no EGL devices" : eglFailure("eglQueryDevicesEXT");
        }
        for (EGLint i = 0; i < count; ++i) {
            EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
            const std::string label = "EGL device " + std::to_string(i);
            if (display == EGL_NO_DISPLAY) {
                deviceWhy +=
                    (deviceWhy.empty() ? "" : "; ") + label + ": " + eglFailure("eglGetPlatformDisplayEXT");
                continue;
            }
            auto context = createEglContextOn(display, label, minVersion);
            if (context) return context;
            deviceWhy += (deviceWhy.empty() ? "" : "; ") + label + ": " + context.error();
        }
    } else {
        deviceWhy = "EGL_EXT_platform_device is not supported";
    }
    return Error{"EGL surfaceless: " + surfacelessWhy + "; EGL device: " + deviceWhy};
}

// ---------------------------------------------------------------------------------------------
// OSMesa

class OsMesaContext final : public GlContext {
public:
    OsMesaContext(const OsMesaApi& api, OSMesaContext context)
        : m_api(api)
        , m_context(context) {}
    ~OsMesaContext() override {
        if (m_api.getCurrentContext() == m_context) m_api.makeCurrent(nullptr, nullptr, 0, 0, 0);
        m_api.destroyContext(m_context);
    }
    ContextKind kind() const override { return ContextKind::OsMesa; }
    using GlContext::setDescription;
    Status makeCurrent() override {
        // A 1×1 default framebuffer: OSMesa needs one to make a context current, and the renderer
        // always draws into its own framebuffer objects.
        if (!m_api.makeCurrent(m_context, m_pixel, GL_UNSIGNED_BYTE, 1, 1)) {
            return Error{"OSMesa: OSMesaMakeCurrent failed"};
        }
        return bindEpoxyToOsMesa();
    }

private:
    const OsMesaApi& m_api;
    OSMesaContext m_context;
    unsigned char m_pixel[4] = {0, 0, 0, 0};
};

Result<std::unique_ptr<OsMesaContext>> createOsMesaContext(int minVersion) {
    const auto api = osMesaApi();
    if (!api) return Error{api.error()};
    std::string lastFailure;
    for (const int version : {45, minVersion}) {
        if (version < minVersion) continue;
        const int attribs[] = {OSMESA_FORMAT,
                               OSMESA_RGBA,
                               OSMESA_DEPTH_BITS,
                               0,
                               OSMESA_STENCIL_BITS,
                               0,
                               OSMESA_PROFILE,
                               OSMESA_CORE_PROFILE,
                               OSMESA_CONTEXT_MAJOR_VERSION,
                               version / 10,
                               OSMESA_CONTEXT_MINOR_VERSION,
                               version % 10,
                               0};
        OSMesaContext context = (*api)->createContextAttribs(attribs, nullptr);
        if (!context) {
            lastFailure = "OSMesaCreateContextAttribs(OpenGL " + std::to_string(version / 10) + "." +
                          std::to_string(version % 10) + " core) failed";
            continue;
        }
        auto result = std::make_unique<OsMesaContext>(**api, context);
        if (auto status = result->makeCurrent(); !status) return Error{status.error()};
        if (auto status = checkCurrentGl(minVersion); !status) return Error{status.error()};
        result->setDescription("OSMesa, " + currentGlDescription());
        return result;
    }
    return Error{lastFailure};
}

// ---------------------------------------------------------------------------------------------
// Host

class HostContext final : public GlContext {
public:
    ContextKind kind() const override { return ContextKind::Host; }
    Status makeCurrent() override {
        bindEpoxyToNative();
        if (auto status = checkCurrentGl(33); !status) return Error{"host OpenGL context: " + status.error()};
        setDescription(std::string(contextKindName(ContextKind::Host)) + ", " + currentGlDescription());
        return {};
    }
};

} // namespace

std::string_view contextKindName(ContextKind kind) {
    switch (kind) {
    case ContextKind::EglSurfaceless:
        return "EGL surfaceless";
    case ContextKind::OsMesa:
        return "OSMesa";
    case ContextKind::Host:
        return "host";
    }
    return "unknown";
}

std::string GlContext::description() const {
    return m_description;
}

std::string currentGlDescription() {
    const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    if (!version) return "no current OpenGL context";
    return std::string("OpenGL ") + version + ", " + (renderer ? renderer : "unknown renderer");
}

Result<std::unique_ptr<GlContext>> createHeadlessContext(const HeadlessContextOptions& options) {
    bool tryEgl = options.tryEgl;
    bool tryOsMesa = options.tryOsMesa;
    if (const char* env = std::getenv("BURNISH_GL"); env && *env) {
        const std::string_view choice(env);
        if (choice == "egl") {
            tryOsMesa = false;
        } else if (choice == "osmesa") {
            tryEgl = false;
        } else {
            return Error{"no OpenGL context: BURNISH_GL='" + std::string(choice) +
                         "' is not one of egl, osmesa"};
        }
    }
    if (!tryEgl && !tryOsMesa) {
        return Error{
            "no OpenGL context: no kind left to try (options and BURNISH_GL exclude both EGL and OSMesa)"};
    }
    std::string why;
    if (tryEgl) {
        auto context = createEglContext(options.minVersion);
        if (context) return std::unique_ptr<GlContext>(std::move(context).value());
        why += context.error();
    }
    if (tryOsMesa) {
        auto context = createOsMesaContext(options.minVersion);
        if (context) return std::unique_ptr<GlContext>(std::move(context).value());
        why += (why.empty() ? "" : "; ") + std::string("OSMesa: ") + context.error();
    }
    return Error{"no OpenGL context: " + why};
}

std::unique_ptr<GlContext> wrapHostContext() {
    return std::make_unique<HostContext>();
}

} // namespace burnish::render
