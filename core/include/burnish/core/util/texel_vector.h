// Storage for large arrays of texel values that are written in parallel right after allocation.
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace burnish {

/// Allocator for large texel arrays: resize() leaves elements uninitialised (the bake writes every
/// texel from parallel rows, so pages are first touched, and zeroed by the kernel, by the threads
/// that fill them instead of by one serial memset first). Transparent huge pages were measured
/// and left out: clearing 2 MiB pages on first touch doubled the bake's system time.
template <class T> struct TexelAllocator {
    using value_type = T;
    TexelAllocator() = default;
    template <class U> TexelAllocator(const TexelAllocator<U>&) noexcept {}
    T* allocate(size_t n) { return std::allocator<T>{}.allocate(n); }
    void deallocate(T* p, size_t n) noexcept { std::allocator<T>{}.deallocate(p, n); }
    /// Value-initialisation (resize, the (n) constructor) is left out; copies construct normally.
    template <class U> void construct(U* p) noexcept { ::new (static_cast<void*>(p)) U; }
    template <class U, class... Args> void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
    template <class U> bool operator==(const TexelAllocator<U>&) const noexcept { return true; }
    template <class U> bool operator!=(const TexelAllocator<U>&) const noexcept { return false; }
};

/// Texel values whose new elements are uninitialised on resize(): write every one.
using TexelVector = std::vector<float, TexelAllocator<float>>;

} // namespace burnish
