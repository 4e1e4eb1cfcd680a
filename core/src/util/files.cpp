#include <burnish/core/util/files.h>

#include <burnish/core/util/hash.h>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <sys/file.h>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

namespace burnish {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

std::string describe(const fs::path& path, const char* what, int err) {
    return std::string(what) + " '" + path.string() + "': " + std::strerror(err);
}

std::function<void(int)>& commitStepHook() {
    static std::function<void(int)> hook;
    return hook;
}

// Steps are counted over the whole process (a report commits two sets), so a test can stop it
// after any step of any commit.
void stepDone(int& step) {
    static std::atomic<int> processSteps{0};
    ++step;
    const int done = ++processSteps;
    if (const auto& hook = commitStepHook()) hook(done);
}

/// A name that stays inside its folder: not empty, no '/', not "." or "..".
bool plainName(const std::string& name) {
    return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
           name.find('\0') == std::string::npos;
}

fs::path folderOf(const fs::path& path) {
    return path.has_parent_path() ? path.parent_path() : fs::path(".");
}

bool sameFolder(const fs::path& a, const fs::path& b) {
    std::error_code ec;
    return fs::equivalent(a, b, ec);
}

/// fsync of a folder, so the renames in it survive a crash. Best effort: some file systems refuse.
void syncFolder(const fs::path& folder) {
    const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;
    (void)::fsync(fd);
    ::close(fd);
}

constexpr const char* kJournal = "journal";
constexpr const char* kJournalPartial = "journal.partial";

/// A commit as its journal records it: file names only, staged ones inside the staging folder and
/// targets inside its parent.
struct Journal {
    std::vector<std::pair<std::string, std::string>> files; // staged name, target name
    std::string index;                                      // staged name of the index, "" none
    std::string indexTarget;
    std::vector<std::string> obsolete;
};

std::optional<Journal> parseJournal(const std::string& text) {
    const Json j = Json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object() || j.value("burnish-commit", 0) != 1) return std::nullopt;
    Journal journal;
    try {
        for (const auto& f : j.at("files")) {
            const auto staged = f.at(0).get<std::string>();
            const auto target = f.at(1).get<std::string>();
            if (!plainName(staged) || !plainName(target)) return std::nullopt;
            journal.files.emplace_back(staged, target);
        }
        journal.index = j.at("index").get<std::string>();
        journal.indexTarget = j.at("indexTarget").get<std::string>();
        if (!journal.index.empty() && (!plainName(journal.index) || !plainName(journal.indexTarget)))
            return std::nullopt;
        for (const auto& o : j.at("obsolete")) {
            const auto name = o.get<std::string>();
            if (plainName(name)) journal.obsolete.push_back(name);
        }
    } catch (const Json::exception&) {
        return std::nullopt;
    }
    return journal;
}

std::string journalText(const Journal& journal) {
    Json files = Json::array();
    for (const auto& [staged, target] : journal.files)
        files.push_back({staged, target});
    return Json{{"burnish-commit", 1},
                {"files", files},
                {"index", journal.index},
                {"indexTarget", journal.indexTarget},
                {"obsolete", journal.obsolete}}
        .dump();
}

/// Removes a file of the old set: a regular file or a link (never what a link points to), never a
/// folder; whether it removed one.
bool removeObsolete(const fs::path& path) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0 || !(S_ISREG(st.st_mode) || S_ISLNK(st.st_mode))) return false;
    return ::unlink(path.c_str()) == 0;
}

/// Carries a journal's commit to its end from wherever it stopped: every step is skipped when it
/// was done already (a staged file that is gone was renamed). Used by recoverStaging.
int finishJournal(const fs::path& staging, const fs::path& parent, const Journal& journal) {
    int renamed = 0;
    const bool indexPending =
        !journal.index.empty() && fs::exists(fs::symlink_status(staging / journal.index));
    if (indexPending) ::unlink((parent / journal.indexTarget).c_str());
    for (const auto& [staged, target] : journal.files)
        if (::rename((staging / staged).c_str(), (parent / target).c_str()) == 0) ++renamed;
    if (indexPending) {
        for (const auto& name : journal.obsolete)
            removeObsolete(parent / name);
        if (::rename((staging / journal.index).c_str(), (parent / journal.indexTarget).c_str()) == 0)
            ++renamed;
    }
    syncFolder(parent);
    return renamed;
}

/// "<name>.tmp-<pid>-<n>": the pid of a temporary of the previous naming scheme, or 0.
pid_t oldTemporaryPid(const std::string& name) {
    const size_t dash = name.rfind('-');
    const size_t tmp = name.rfind(".tmp-");
    if (tmp == std::string::npos || tmp == 0 || dash == std::string::npos || dash <= tmp + 5 ||
        dash + 1 == name.size())
        return 0;
    const std::string pid = name.substr(tmp + 5, dash - tmp - 5);
    const std::string counter = name.substr(dash + 1);
    auto digits = [](const std::string& s) { return s.find_first_not_of("0123456789") == std::string::npos; };
    if (pid.empty() || pid.size() > 9 || !digits(pid) || !digits(counter)) return 0;
    return pid_t(std::stol(pid));
}

} // namespace

StagingFolder::StagingFolder(fs::path path, fs::path parent, int lock)
    : m_path(std::move(path))
    , m_parent(std::move(parent))
    , m_lock(lock) {}

StagingFolder::StagingFolder(StagingFolder&& other) noexcept
    : m_path(std::move(other.m_path))
    , m_parent(std::move(other.m_parent))
    , m_lock(other.m_lock)
    , m_count(other.m_count) {
    other.m_lock = -1;
    other.m_path.clear();
}

StagingFolder::~StagingFolder() {
    if (m_path.empty()) return;
    std::error_code ec;
    fs::remove_all(m_path, ec); // the lock is held until the folder is gone
    if (m_lock >= 0) ::close(m_lock);
}

Result<StagingFolder> StagingFolder::create(const fs::path& folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return Error{"folder '" + folder.string() + "' does not exist"};
    std::string name = (folder / (std::string(kStagingPrefix) + "XXXXXX")).string();
    if (::mkdtemp(name.data()) == nullptr) return Error{describe(folder, "cannot write into folder", errno)};
    const int lock = ::open(name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (lock < 0 || ::flock(lock, LOCK_EX) != 0) {
        const int err = errno;
        if (lock >= 0) ::close(lock);
        fs::remove_all(name, ec);
        return Error{describe(folder, "cannot write into folder", err)};
    }
    return StagingFolder(fs::path(name), folder, lock);
}

fs::path StagingFolder::fileFor(const fs::path& target) {
    return m_path / (std::to_string(m_count++) + "-" + target.filename().string());
}

Status writeNewFile(const fs::path& path, std::string_view bytes, const fs::path& target) {
    const fs::path& named = target.empty() ? path : target;
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) return Error{describe(named, "cannot write", errno)};
    const char* data = bytes.data();
    size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, data, left);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            ::close(fd);
            ::unlink(path.c_str());
            return Error{describe(named, "cannot write", err)};
        }
        data += n;
        left -= static_cast<size_t>(n);
    }
    // fsync before the rename: a crash after it must not leave an empty file in the target's place.
    if (::fsync(fd) != 0 || ::close(fd) != 0) {
        const int err = errno;
        ::unlink(path.c_str());
        return Error{describe(named, "cannot write", err)};
    }
    return {};
}

Status syncFile(const fs::path& path, const fs::path& target) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) return Error{describe(target, "cannot write", errno)};
    const bool ok = ::fsync(fd) == 0;
    const int err = errno;
    ::close(fd);
    if (!ok) return Error{describe(target, "cannot write", err)};
    return {};
}

Status installFile(const fs::path& staged, const fs::path& target, Overwrite overwrite) {
    if (overwrite == Overwrite::Refuse) {
        if (::renameat2(AT_FDCWD, staged.c_str(), AT_FDCWD, target.c_str(), RENAME_NOREPLACE) == 0) return {};
        const int err = errno;
        if (err == EEXIST) return Error{"refusing to overwrite existing file '" + target.string() + "'"};
        if (err != EINVAL && err != ENOSYS) return Error{describe(target, "cannot write", err)};
        // A file system without RENAME_NOREPLACE: check, then rename.
        std::error_code ec;
        if (fs::exists(fs::symlink_status(target, ec)))
            return Error{"refusing to overwrite existing file '" + target.string() + "'"};
    }
    if (::rename(staged.c_str(), target.c_str()) != 0) return Error{describe(target, "cannot write", errno)};
    return {};
}

Status writeAtomicWith(const fs::path& path, const std::function<Status(const fs::path&)>& write,
                       Overwrite overwrite) {
    std::error_code ec;
    if (overwrite == Overwrite::Refuse && fs::exists(fs::symlink_status(path, ec)))
        return Error{"refusing to overwrite existing file '" + path.string() + "'"};
    auto staging = StagingFolder::create(folderOf(path));
    if (!staging) return Error{"cannot write '" + path.string() + "': " + staging.error()};
    const fs::path staged = staging.value().fileFor(path);
    if (const Status s = write(staged); !s) return s;
    if (const Status s = syncFile(staged, path); !s) return s;
    return installFile(staged, path, overwrite);
}

Status writeFileAtomic(const fs::path& path, std::string_view bytes, Overwrite overwrite) {
    return writeAtomicWith(
        path, [&](const fs::path& staged) { return writeNewFile(staged, bytes, path); }, overwrite);
}

Status commitSet(StagingFolder& staging, const std::vector<StagedFile>& files, const SetCommit& commit) {
    const fs::path& parent = staging.parent();
    Journal journal;
    std::vector<fs::path> order; // staged files in rename order, the index last
    std::vector<fs::path> targets;
    for (const auto& f : files) {
        if (!sameFolder(folderOf(f.target), parent) || !sameFolder(folderOf(f.staged), staging.path()))
            return Error{"cannot write '" + f.target.string() + "': not in the set's folder '" +
                         parent.string() + "'"};
        if (!commit.index.empty() && f.target == commit.index) {
            journal.index = f.staged.filename().string();
            journal.indexTarget = f.target.filename().string();
            continue;
        }
        journal.files.emplace_back(f.staged.filename().string(), f.target.filename().string());
        order.push_back(f.staged);
        targets.push_back(f.target);
    }
    if (!commit.index.empty() && journal.index.empty())
        return Error{"cannot write '" + commit.index.string() + "': the set's index is not among its files"};
    for (const auto& o : commit.obsolete) {
        const std::string name = o.filename().string();
        if (!sameFolder(folderOf(o), parent) || !plainName(name) || name == journal.indexTarget) continue;
        bool written = false;
        for (const auto& [staged, target] : journal.files)
            written = written || target == name;
        if (!written) journal.obsolete.push_back(name);
    }

    std::error_code ec;
    std::vector<bool> existed;
    for (const auto& t : targets)
        existed.push_back(fs::exists(fs::symlink_status(t, ec)));
    const fs::path indexTarget = journal.index.empty() ? fs::path() : parent / journal.indexTarget;
    if (commit.overwrite == Overwrite::Refuse) {
        for (size_t i = 0; i < targets.size(); ++i)
            if (existed[i]) return Error{"refusing to overwrite existing file '" + targets[i].string() + "'"};
        if (!indexTarget.empty() && fs::exists(fs::symlink_status(indexTarget, ec)))
            return Error{"refusing to overwrite existing file '" + indexTarget.string() + "'"};
    }

    // The journal, complete or absent: written beside, then renamed inside the private folder.
    int step = 0;
    if (const Status s = writeNewFile(staging.path() / kJournalPartial, journalText(journal)); !s) return s;
    if (::rename((staging.path() / kJournalPartial).c_str(), (staging.path() / kJournal).c_str()) != 0)
        return Error{describe(parent, "cannot write into folder", errno)};
    stepDone(step);

    bool indexRemoved = false;
    if (!indexTarget.empty() && fs::exists(fs::symlink_status(indexTarget, ec))) {
        if (::unlink(indexTarget.c_str()) != 0) return Error{describe(indexTarget, "cannot replace", errno)};
        indexRemoved = true;
        stepDone(step);
    }
    for (size_t i = 0; i < order.size(); ++i) {
        if (const Status s = installFile(order[i], targets[i], commit.overwrite); !s) {
            for (size_t j = 0; j < i; ++j)
                if (!existed[j]) fs::remove(targets[j], ec);
            std::remove((staging.path() / kJournal).c_str()); // nothing to finish: this commit failed
            if (indexRemoved)
                return Error{s.error() + "; the set in '" + parent.string() + "' is incomplete (its " +
                             indexTarget.filename().string() + " was removed): write it again"};
            return s;
        }
        stepDone(step);
    }
    for (const auto& name : journal.obsolete) {
        removeObsolete(parent / name);
        stepDone(step);
    }
    if (!indexTarget.empty()) {
        if (const Status s = installFile(staging.path() / journal.index, indexTarget, commit.overwrite); !s) {
            std::remove((staging.path() / kJournal).c_str());
            return s;
        }
        stepDone(step);
    }
    syncFolder(parent);
    return {};
}

StagingRecovery recoverStaging(const fs::path& folder) {
    StagingRecovery recovery;
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return recovery;
    std::vector<fs::path> entries;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
        entries.push_back(it->path());
    const uid_t me = ::geteuid();
    for (const auto& entry : entries) {
        const std::string name = entry.filename().string();
        struct stat st {};
        if (::lstat(entry.c_str(), &st) != 0 || st.st_uid != me) continue;
        if (name.rfind(kStagingPrefix, 0) == 0 && S_ISDIR(st.st_mode)) {
            const int fd = ::open(entry.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
            if (fd < 0) continue;
            if (::flock(fd, LOCK_EX | LOCK_NB) != 0) { // a live process is using it
                ::close(fd);
                continue;
            }
            std::optional<Journal> journal;
            if (auto text = readFile(entry / kJournal)) journal = parseJournal(*text);
            if (journal) {
                const int renamed = finishJournal(entry, folder, *journal);
                ++recovery.commitsFinished;
                recovery.notes.push_back("finished an interrupted commit in '" + folder.string() + "' (" +
                                         std::to_string(renamed) + " files put in place)");
            } else {
                ++recovery.foldersRemoved;
                recovery.notes.push_back("removed the staging folder of an interrupted write: '" +
                                         entry.string() + "'");
            }
            fs::remove_all(entry, ec);
            ::close(fd);
        } else if (name == kWriterLockName && S_ISREG(st.st_mode)) {
            // A writer lock no live process holds (its writer was killed): removed under the lock, as its
            // writer would have (FolderLock). One held here — by this process's own writer too — stays.
            const int fd = ::open(entry.c_str(), O_RDWR | O_NOFOLLOW | O_CLOEXEC);
            if (fd < 0) continue;
            struct stat held {
            }, current{};
            if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::fstat(fd, &held) == 0 &&
                ::stat(entry.c_str(), &current) == 0 && held.st_ino == current.st_ino &&
                held.st_dev == current.st_dev)
                ::unlink(entry.c_str());
            ::close(fd);
        } else if (S_ISREG(st.st_mode)) {
            const pid_t pid = oldTemporaryPid(name);
            if (pid <= 0 || ::kill(pid, 0) == 0 || errno != ESRCH) continue; // not ours, or still running
            if (::unlink(entry.c_str()) == 0) {
                ++recovery.temporariesRemoved;
                recovery.notes.push_back("removed a temporary file of an interrupted write: '" +
                                         entry.string() + "'");
            }
        }
    }
    return recovery;
}

Result<FolderLock> FolderLock::acquire(const fs::path& folder, double waitSeconds) {
    FolderLock lock;
    lock.m_path = folder / std::string(kWriterLockName);
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(std::max(waitSeconds, 0.0));
    for (;;) {
        const int fd = ::open(lock.m_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
        if (fd < 0) {
            // A missing or read-only folder: the writer's own checks say so in their words.
            if (errno == ENOENT || errno == EACCES || errno == EROFS || errno == ENOTDIR || errno == EPERM)
                return lock;
            return Error{"cannot lock '" + folder.string() + "' for writing: " + std::strerror(errno)};
        }
        if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {
            struct stat held {
            }, current{};
            if (::fstat(fd, &held) == 0 && ::stat(lock.m_path.c_str(), &current) == 0 &&
                held.st_ino == current.st_ino && held.st_dev == current.st_dev) {
                const std::string pid = std::to_string(::getpid()) + "\n";
                // The pid is only for a waiter's message: a failed write costs that line its pid, nothing
                // else.
                const bool named = ::ftruncate(fd, 0) == 0 && ::pwrite(fd, pid.data(), pid.size(), 0) > 0;
                static_cast<void>(named);
                lock.m_fd = fd;
                return lock;
            }
            ::close(fd); // its holder removed it before letting go: lock the file that is there now
            continue;
        }
        const int error = errno;
        char text[32] = {};
        const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
        ::close(fd);
        if (error != EWOULDBLOCK)
            return Error{"cannot lock '" + folder.string() + "' for writing: " + std::strerror(error)};
        if (std::chrono::steady_clock::now() >= deadline) {
            std::string holder(text, n > 0 ? size_t(n) : 0);
            holder.erase(
                std::remove_if(holder.begin(), holder.end(), [](char c) { return c < '0' || c > '9'; }),
                holder.end());
            return Error{"'" + folder.string() + "' is being written by another Burnish process" +
                         (holder.empty() ? std::string() : " (pid " + holder + ")") + "; gave up after " +
                         std::to_string(int(waitSeconds)) + " s, nothing written"};
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
}

FolderLock::FolderLock(FolderLock&& other) noexcept
    : m_fd(other.m_fd)
    , m_path(std::move(other.m_path)) {
    other.m_fd = -1;
}

FolderLock::~FolderLock() {
    if (m_fd < 0) return;
    ::unlink(m_path.c_str()); // while still held: a waiter that then gets this file sees it gone and retries
    ::close(m_fd);
}

Result<FileSet> FileSet::begin(const fs::path& folder) {
    auto lock = FolderLock::acquire(folder);
    if (!lock) return Error{lock.error()};
    const StagingRecovery recovered = recoverStaging(folder);
    auto staging = StagingFolder::create(folder);
    if (!staging) return Error{staging.error()};
    FileSet set(std::move(lock).value(), std::move(staging).value());
    set.m_notes = recovered.notes;
    return set;
}

Status FileSet::add(const std::string& name, const std::function<Status(const fs::path&)>& write) {
    if (!plainName(name)) return Error{"'" + name + "' is not a file name inside the folder"};
    const fs::path target = m_staging.parent() / name;
    const fs::path staged = m_staging.fileFor(target);
    if (const Status s = write(staged); !s) return s;
    if (const Status s = syncFile(staged, target); !s) return s;
    m_names.push_back(name);
    m_files.push_back({staged, target});
    return {};
}

Status FileSet::addParallel(const std::vector<std::string>& names,
                            const std::function<Status(size_t, const fs::path&)>& write) {
    std::vector<StagedFile> files;
    for (const auto& name : names) {
        if (!plainName(name)) return Error{"'" + name + "' is not a file name inside the folder"};
        const fs::path target = m_staging.parent() / name;
        files.push_back({m_staging.fileFor(target), target}); // named in order, before any is written
    }
    std::vector<Status> written(files.size());
    tbb::parallel_for(size_t(0), files.size(), [&](size_t i) {
        written[i] = write(i, files[i].staged);
        if (written[i]) written[i] = syncFile(files[i].staged, files[i].target);
    });
    for (const Status& s : written)
        if (!s) return s;
    m_names.insert(m_names.end(), names.begin(), names.end());
    m_files.insert(m_files.end(), files.begin(), files.end());
    return {};
}

Status FileSet::addBytes(const std::string& name, std::string_view bytes) {
    const fs::path target = m_staging.parent() / name;
    return add(name, [&](const fs::path& staged) { return writeNewFile(staged, bytes, target); });
}

Status FileSet::commit(const std::string& index, const std::vector<std::string>& obsolete,
                       Overwrite overwrite) {
    SetCommit commit;
    if (!index.empty()) commit.index = m_staging.parent() / index;
    commit.overwrite = overwrite;
    for (const auto& name : obsolete)
        if (plainName(name)) commit.obsolete.push_back(m_staging.parent() / name);
    return commitSet(m_staging, m_files, commit);
}

int removeStaleFiles(const fs::path& folder, const std::vector<std::string>& previous,
                     const std::vector<std::string>& written) {
    int removed = 0;
    for (const auto& name : previous) {
        if (!plainName(name) || std::find(written.begin(), written.end(), name) != written.end()) continue;
        removed += removeObsolete(folder / name) ? 1 : 0;
    }
    return removed;
}

std::vector<std::string> indexedFiles(const fs::path& index) {
    std::vector<std::string> names;
    auto text = readFile(index);
    if (!text) return names;
    const Json j = Json::parse(*text, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("files") || !j["files"].is_array()) return names;
    for (const auto& f : j["files"])
        if (f.is_string()) names.push_back(f.get<std::string>());
    return names;
}

void setCommitStepHookForTesting(std::function<void(int)> hook) {
    commitStepHook() = std::move(hook);
}

Status requireRegularFile(const fs::path& path, std::string_view what) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) return Error{std::string(what) + " '" + path.string() + "' does not exist"};
    if (fs::is_directory(st)) {
        const bool vowel =
            !what.empty() && std::string_view("aeiou").find(what.front()) != std::string_view::npos;
        return Error{"'" + path.string() + "' is a folder, not " + (vowel ? "an " : "a ") +
                     std::string(what)};
    }
    if (fs::is_regular_file(st)) return Status::success();
    const char* kind = fs::is_fifo(st)             ? "a FIFO"
                       : fs::is_character_file(st) ? "a character device"
                       : fs::is_block_file(st)     ? "a block device"
                       : fs::is_socket(st)         ? "a socket"
                                                   : "a special file";
    return Error{std::string(what) + " '" + path.string() + "' is " + kind +
                 ", not a regular file (Burnish reads its inputs from files, which end)"};
}

Result<std::string> readFile(const fs::path& path) {
    if (const Status st = requireRegularFile(path, "file"); !st) return Error{st.error()};
    std::ifstream in(path, std::ios::binary);
    if (!in) return Error{describe(path, "cannot read", errno)};
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) return Error{describe(path, "cannot read", errno)};
    return ss.str();
}

Result<std::uint64_t> fileFnv1a64(const fs::path& path) {
    if (const Status st = requireRegularFile(path, "file"); !st) return Error{st.error()};
    std::ifstream in(path, std::ios::binary);
    if (!in) return Error{describe(path, "cannot read", errno)};
    std::vector<char> block(std::size_t(1) << 20);
    std::uint64_t hash = kFnv1a64Basis;
    while (in) {
        in.read(block.data(), std::streamsize(block.size()));
        hash = fnv1a64(block.data(), std::size_t(in.gcount()), hash);
    }
    if (in.bad()) return Error{describe(path, "cannot read", errno)};
    return hash;
}

} // namespace burnish
