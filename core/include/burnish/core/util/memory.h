// The one memory ceiling every command checks before it allocates: what the system can still hand
// out (or less, BURNISH_MEMORY_LIMIT), against an estimate made from the inputs' headers and the
// options, refused in one line that gives both.
#pragma once

#include <burnish/core/util/result.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace burnish {

/// What the system can still hand out now: MemAvailable plus SwapFree of /proc/meminfo; nullopt
/// where that cannot be read.
std::optional<std::uint64_t> availableMemoryBytes();

/// BURNISH_MEMORY_LIMIT: the most memory a command may plan to use, in bytes with an optional K, M or
/// G suffix (powers of 1024), e.g. "6G" on a farm node shared by several tasks. nullopt when unset;
/// an error for any other value.
Result<std::optional<std::uint64_t>> memoryLimitFromEnvironment();

/// The memory a command may use: availableMemoryBytes, capped by BURNISH_MEMORY_LIMIT.
Result<std::optional<std::uint64_t>> usableMemoryBytes();

/// "850 MB" below 1 GB, "12.3 GB" from there (decimal units).
std::string formatBytes(std::uint64_t bytes);

/// An error "<what> needs about <need> of memory, and <available> are available (<advice>)" when
/// `need` exceeds `available`; ok when it fits or `available` is unknown.
Status checkMemory(std::uint64_t need, std::optional<std::uint64_t> available, std::string_view what,
                   std::string_view advice);
/// checkMemory against usableMemoryBytes() (an invalid BURNISH_MEMORY_LIMIT is the error).
Status checkMemory(std::uint64_t need, std::string_view what, std::string_view advice);

/// What a command's process holds before any image when it reads and writes through core's own PNG
/// codecs (a 1×1 PNG bake peaks at 12.5 MB).
inline constexpr std::uint64_t kCoreProcessBytes = 16'000'000;
/// What OpenImageIO, loaded on its first call with the ~240 libraries Debian's build pulls in, adds to
/// a bake (a 512² bake peaks at 21 MB from a PNG, at 152 MB from an EXR).
inline constexpr std::uint64_t kOpenImageIoBytes = 135'000'000;
/// A process that has loaded OpenImageIO.
inline constexpr std::uint64_t kProcessBytes = kCoreProcessBytes + kOpenImageIoBytes;

/// Whether an image of this header is decoded by core itself (8/16-bit PNG), without OpenImageIO.
bool decodedByCore(std::string_view formatName, std::string_view channelType);

} // namespace burnish
