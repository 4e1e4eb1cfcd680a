// Atomic file output through one path that no planted link can redirect.
//
// Every file Burnish writes is first written into a private staging folder that mkdtemp(3) makes
// inside the target's folder (".burnish-staging-XXXXXX", mode 0700): no other user can create a
// name in it, so a symbolic link planted at a predictable temporary name cannot send a write
// elsewhere, and it lies on the target's file system, so rename(2) into place is atomic. Bytes are
// flushed to disk before the rename. A failed write (full disk, no permission, missing folder)
// leaves any existing file untouched and nothing behind.
//
// A set of files that belong together (a bake's textures and its bake.json) is committed as one
// unit: a journal naming every file is written into the staging folder first, the set's index file
// (bake.json) is removed, the files are renamed into place, files of the old set that the new one
// does not write are removed, and the new index is renamed last. A folder holding no index is
// therefore in the middle of a commit; a process killed there leaves its staging folder and
// journal, and the next recoverStaging() of that folder finishes the commit.
#pragma once

#include <burnish/core/util/result.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish {

enum class Overwrite { Allow, Refuse };

/// Name prefix of staging folders (followed by mkdtemp's six characters).
inline constexpr std::string_view kStagingPrefix = ".burnish-staging-";

/// The name of a folder's writer lock file (FolderLock), present only while a writer holds it (or after a
/// writer was killed, until recoverStaging or the next writer removes it).
inline constexpr std::string_view kWriterLockName = ".burnish-writer.lock";

/// How long a writer waits for another one to finish with a folder before it gives up (FolderLock).
inline constexpr int kWriterLockWaitSeconds = 300;

/// One writer at a time per output folder: an exclusive flock(2) on "<folder>/.burnish-writer.lock", held
/// from before a set is staged until after it is committed, so two processes writing sets into one folder
/// (a resubmitted farm task and its slow original, two studio exports) run one after the other and each set
/// lands whole. The file names the holder's pid; the holder removes it while still holding it, so a finished
/// folder has none, and a waiter that then locks the removed file tries again. A folder where the lock file
/// cannot be made (missing, not writable) is not locked: the writer's own checks report that.
class FolderLock {
public:
    /// Waits up to `waitSeconds` (polling) for the lock. Error, one line: another process holds it past the
    /// wait ("... is being written by another Burnish process (pid N) ...").
    static Result<FolderLock> acquire(const std::filesystem::path& folder,
                                      double waitSeconds = kWriterLockWaitSeconds);
    FolderLock(FolderLock&& other) noexcept;
    FolderLock& operator=(FolderLock&&) = delete;
    FolderLock(const FolderLock&) = delete;
    FolderLock& operator=(const FolderLock&) = delete;
    ~FolderLock();
    /// Whether a lock is held (false for a folder that could not be locked: see above).
    bool held() const { return m_fd >= 0; }

private:
    FolderLock() = default;
    int m_fd = -1;
    std::filesystem::path m_path;
};

/// A private, locked staging folder inside an existing folder. While the object lives it holds an
/// exclusive flock(2) on the folder, which tells recoverStaging() of another process that it is in
/// use; the destructor removes the folder and whatever is still in it.
class StagingFolder {
public:
    /// Makes one inside `folder`; an error names `folder` when it is missing or not writable.
    static Result<StagingFolder> create(const std::filesystem::path& folder);

    StagingFolder(StagingFolder&& other) noexcept;
    StagingFolder& operator=(StagingFolder&&) = delete;
    StagingFolder(const StagingFolder&) = delete;
    StagingFolder& operator=(const StagingFolder&) = delete;
    ~StagingFolder();

    /// The staging folder itself.
    const std::filesystem::path& path() const { return m_path; }
    /// The folder the staged files are committed into (where the staging folder lies).
    const std::filesystem::path& parent() const { return m_parent; }
    /// A new name inside the staging folder for the file that will become `target`. It ends in
    /// target's file name, so libraries that pick a format by extension see the right one.
    /// Not thread-safe: name every file before writing them in parallel.
    std::filesystem::path fileFor(const std::filesystem::path& target);

private:
    StagingFolder(std::filesystem::path path, std::filesystem::path parent, int lock);
    std::filesystem::path m_path;
    std::filesystem::path m_parent;
    int m_lock = -1;
    unsigned m_count = 0;
};

/// Writes `bytes` to a new file at `path` (created exclusively, never through a link) and flushes
/// it to disk. For files inside a StagingFolder; errors name `target` when given.
Status writeNewFile(const std::filesystem::path& path, std::string_view bytes,
                    const std::filesystem::path& target = {});

/// Flushes a file that a library wrote (OpenImageIO) to disk, so a crash after its rename cannot
/// leave an empty file in the target's place. `target` names the file in the error.
Status syncFile(const std::filesystem::path& path, const std::filesystem::path& target);

/// Renames a staged file to `target`. With Overwrite::Refuse an existing target is an error and
/// stays as it was (renameat2 with RENAME_NOREPLACE: no window between check and rename).
Status installFile(const std::filesystem::path& staged, const std::filesystem::path& target,
                   Overwrite overwrite = Overwrite::Allow);

/// Writes `bytes` to `path` atomically (a StagingFolder beside it, writeNewFile, installFile).
/// With Overwrite::Refuse an existing file is an error. Creates no folders: a missing parent
/// folder is an error naming it.
Status writeFileAtomic(const std::filesystem::path& path, std::string_view bytes,
                       Overwrite overwrite = Overwrite::Allow);

/// Writes a file atomically with a writer that fills a staged path (a library that opens files by
/// name, such as OpenImageIO): `write(staged)` writes the whole file there; it is then flushed to
/// disk and renamed to `path`. The writer's error is returned as it is.
Status writeAtomicWith(const std::filesystem::path& path,
                       const std::function<Status(const std::filesystem::path& staged)>& write,
                       Overwrite overwrite = Overwrite::Allow);

/// One file of a set: the staged file and the target it becomes (in the staging folder's parent).
struct StagedFile {
    std::filesystem::path staged;
    std::filesystem::path target;
};

/// What commitSet does besides renaming the files.
struct SetCommit {
    /// The set's index (bake.json), one of the files: an existing index is removed before the first
    /// rename and the new one is renamed last. Empty: no index.
    std::filesystem::path index;
    /// Files of the previous set the new one does not write, removed after the renames. Only plain
    /// file names inside the parent folder are removed; anything else is ignored.
    std::vector<std::filesystem::path> obsolete;
    Overwrite overwrite = Overwrite::Allow;
};

/// Commits staged files as one set through the staging folder's journal (see the top of this
/// file). Every target must lie directly in staging.parent(). On a failed rename the files that
/// were new are removed again and the error says the folder's set is incomplete.
Status commitSet(StagingFolder& staging, const std::vector<StagedFile>& files, const SetCommit& commit);

struct StagingRecovery;

/// A set of files written into one folder as one unit: each file is staged in a private folder as
/// it is produced, and commit() puts them all in place through commitSet, the set's index renamed
/// last. Interrupted commits of killed runs in the folder are finished first (begin()).
class FileSet {
public:
    /// The folder's writer lock (FolderLock: waits for another writer), recoverStaging(folder), then a
    /// StagingFolder inside it (which must exist).
    static Result<FileSet> begin(const std::filesystem::path& folder);
    /// Stages the file `name` (a plain name in the folder) that `write(staged)` writes in full.
    Status add(const std::string& name,
               const std::function<Status(const std::filesystem::path& staged)>& write);
    /// Stages the file `name` with these bytes.
    Status addBytes(const std::string& name, std::string_view bytes);
    /// Stages the files `names`, listed in this order, that `write(i, staged)` writes in full, several
    /// at a time (the writers must be safe to run together). Returns the first error in order; then
    /// none of them is listed.
    Status addParallel(const std::vector<std::string>& names,
                       const std::function<Status(size_t i, const std::filesystem::path& staged)>& write);
    /// The names staged so far, in order.
    const std::vector<std::string>& names() const { return m_names; }
    /// The folder the set is committed into.
    const std::filesystem::path& folder() const { return m_staging.parent(); }
    /// Commits every staged file; `index` (one of the names, or empty for a set without one) is
    /// renamed last and a previous one removed first; `obsolete` names of the previous set that this one does
    /// not hold are removed.
    Status commit(const std::string& index, const std::vector<std::string>& obsolete, Overwrite overwrite);
    /// recoverStaging's notes from begin().
    const std::vector<std::string>& recoveryNotes() const { return m_notes; }

private:
    FileSet(FolderLock lock, StagingFolder staging)
        : m_lock(std::move(lock))
        , m_staging(std::move(staging)) {}
    FolderLock m_lock; // held until the set is committed or dropped
    StagingFolder m_staging;
    std::vector<std::string> m_names;
    std::vector<StagedFile> m_files;
    std::vector<std::string> m_notes;
};

/// What recoverStaging found and did.
struct StagingRecovery {
    int commitsFinished = 0;    // interrupted commits carried to their end (files renamed)
    int foldersRemoved = 0;     // abandoned staging folders (no journal) removed with their files
    int temporariesRemoved = 0; // "<name>.tmp-<pid>-<n>" files of dead processes (the old scheme)
    /// One line per action, for the user ("finished an interrupted commit of 14 files in ...").
    std::vector<std::string> notes;
};

/// Cleans up after killed processes in `folder`: staging folders that no live process holds are
/// finished (a complete journal: the commit is carried to its end) or removed (no journal: nothing
/// had been renamed), and temporaries of the previous naming scheme whose process is gone are
/// removed. Only entries of the current user that match Burnish's own names are touched; a missing
/// folder is not an error.
StagingRecovery recoverStaging(const std::filesystem::path& folder);

/// Removes from `folder` the files of a previous run that this run did not write: every name of
/// `previous` not in `written`, when it is a plain name (no '/', not "." or "..") of a regular
/// file or link there; nothing else is touched. Returns how many were removed.
int removeStaleFiles(const std::filesystem::path& folder, const std::vector<std::string>& previous,
                     const std::vector<std::string>& written);

/// The names under "files" of a previous run's JSON index (env.json), or none when it is missing
/// or unreadable (then nothing is removed).
std::vector<std::string> indexedFiles(const std::filesystem::path& index);

/// For tests: called after every step of a commit with the number of commit steps the process has
/// done so far, over every commit (each commit: its journal written, then one per removal or
/// rename), so a test can kill the process at any point.
/// Null (the default) does nothing.
void setCommitStepHookForTesting(std::function<void(int step)> hook);

/// Inputs are regular files (after following links): a FIFO, a device such as /dev/zero or a socket
/// would block or never end, so it is refused in one line naming what it is. `what` names the input
/// ("image", "manifest", ...). Errors: it does not exist, is a folder, or is not a regular file.
Status requireRegularFile(const std::filesystem::path& path, std::string_view what);

/// Reads a whole file; a clear error when it cannot (requireRegularFile's refusals included).
Result<std::string> readFile(const std::filesystem::path& path);

/// FNV-1a 64 (util/hash.h) of a file's bytes, read in blocks (a file of any size costs a block of
/// memory); the same errors as readFile.
Result<std::uint64_t> fileFnv1a64(const std::filesystem::path& path);

} // namespace burnish
