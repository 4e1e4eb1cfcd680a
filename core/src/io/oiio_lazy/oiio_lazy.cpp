// The run-time half of the lazily loaded OpenImageIO (see oiio_lazy.cmake): the first call of any
// OpenImageIO function a program links through the generated trampolines lands here, with the
// address of that function's slot; OpenImageIO is opened once and the slot pointed at the function.
//
// Debian's OpenImageIO pulls in about 240 shared libraries (FFmpeg, GDAL, GStreamer, DICOM...)
// whose relocation took 0.25-0.3 s of every `burnish` start, PNG in and PNG out included, which
// never call it (core has its own PNG codec and plot renderer).
#include <dlfcn.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <mutex>

namespace {

void* openLibrary() {
    static void* handle = nullptr;
    static std::once_flag once;
    std::call_once(once, [] {
        handle = ::dlopen(BURNISH_OIIO_LIBRARY, RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* why = ::dlerror();
            std::fprintf(stderr, "burnish: error: cannot load OpenImageIO (%s): %s\n", BURNISH_OIIO_LIBRARY,
                         why ? why : "unknown error");
            std::fflush(stderr);
            std::_Exit(70); // EX_SOFTWARE: the program was installed without its library
        }
    });
    return handle;
}

} // namespace

// slot[0]: the address the trampoline jumps through; slot[1]: the function's mangled name.
extern "C" __attribute__((visibility("hidden"))) void* burnish_oiio_lazy_resolve(void** slot) {
    void* handle = openLibrary();
    const char* name = static_cast<const char*>(slot[1]);
    void* function = ::dlsym(handle, name);
    if (!function) {
        const char* why = ::dlerror();
        std::fprintf(stderr, "burnish: error: OpenImageIO (%s) has no %s: %s\n", BURNISH_OIIO_LIBRARY, name,
                     why ? why : "not found");
        std::fflush(stderr);
        std::_Exit(70);
    }
    // Another thread may resolve the same slot at the same time: both store the same address.
    __atomic_store_n(slot, function, __ATOMIC_RELEASE);
    return function;
}
