// A content hash for names that must change when the content does (painted layers' files, the
// painted gloss a bake records): FNV-1a, 64 bits.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace burnish {

// Fowler, Noll & Vo, "FNV-1a": offset basis 14695981039346656037, prime 1099511628211
inline constexpr std::uint64_t kFnv1a64Basis = 14695981039346656037ull;

/// FNV-1a of `size` bytes, continuing from `hash` (pass the previous result to hash several
/// buffers as one).
inline std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t hash = kFnv1a64Basis) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
        hash ^= bytes[i];
        hash *= 1099511628211ull;
    }
    return hash;
}

/// The hash as 16 lower-case hex digits.
inline std::string hashHex(std::uint64_t hash) {
    static constexpr char kDigits[] = "0123456789abcdef";
    std::string hex(16, '0');
    for (int i = 15; i >= 0; --i, hash >>= 4)
        hex[std::size_t(i)] = kDigits[hash & 0xf];
    return hex;
}

} // namespace burnish
