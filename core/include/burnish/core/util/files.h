// Atomic file output: bytes go to a temporary file beside the target, are flushed to disk, and
// the temporary is renamed over the target. A failed write (full disk, no permission, missing
// folder) leaves any existing file untouched and no temporary behind.
#pragma once

#include <burnish/core/util/result.h>

#include <filesystem>
#include <string_view>

namespace burnish {

enum class Overwrite { Allow, Refuse };

/// Writes `bytes` to `path` atomically. With Overwrite::Refuse an existing file is an error.
/// Creates no folders: a missing parent folder is an error naming it.
Status writeFileAtomic(const std::filesystem::path& path, std::string_view bytes,
                       Overwrite overwrite = Overwrite::Allow);

/// A temporary path in the same folder as `path` (so rename(2) is atomic), unique per process
/// and call: "<name>.tmp-<pid>-<counter>".
std::filesystem::path temporaryPathFor(const std::filesystem::path& path);

/// Makes a temporary path the file at `path` (rename), removing the temporary on failure.
Status commitTemporary(const std::filesystem::path& temporary, const std::filesystem::path& path,
                       Overwrite overwrite = Overwrite::Allow);

/// Reads a whole file; a clear error when it cannot.
Result<std::string> readFile(const std::filesystem::path& path);

} // namespace burnish
