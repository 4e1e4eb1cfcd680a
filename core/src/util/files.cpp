#include <burnish/core/util/files.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace burnish {

namespace fs = std::filesystem;

namespace {

std::string describe(const fs::path& path, const char* what, int err) {
    return std::string(what) + " '" + path.string() + "': " + std::strerror(err);
}

} // namespace

fs::path temporaryPathFor(const fs::path& path) {
    static std::atomic<unsigned> counter{0};
    fs::path tmp = path;
    tmp += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    return tmp;
}

Status commitTemporary(const fs::path& temporary, const fs::path& path, Overwrite overwrite) {
    std::error_code ec;
    if (overwrite == Overwrite::Refuse && fs::exists(path, ec)) {
        fs::remove(temporary, ec);
        return Error{"refusing to overwrite existing file '" + path.string() + "'"};
    }
    if (::rename(temporary.c_str(), path.c_str()) != 0) {
        const int err = errno;
        fs::remove(temporary, ec);
        return Error{describe(path, "cannot write", err)};
    }
    return {};
}

Status writeFileAtomic(const fs::path& path, std::string_view bytes, Overwrite overwrite) {
    const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(parent, ec)) return Error{"folder '" + parent.string() + "' does not exist"};
    if (overwrite == Overwrite::Refuse && fs::exists(path, ec))
        return Error{"refusing to overwrite existing file '" + path.string() + "'"};

    const fs::path tmp = temporaryPathFor(path);
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) return Error{describe(path, "cannot write", errno)};
    const char* data = bytes.data();
    size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, data, left);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            ::close(fd);
            fs::remove(tmp, ec);
            return Error{describe(path, "cannot write", err)};
        }
        data += n;
        left -= static_cast<size_t>(n);
    }
    // fsync before rename: a crash after the rename must not leave an empty file in its place.
    if (::fsync(fd) != 0 || ::close(fd) != 0) {
        const int err = errno;
        fs::remove(tmp, ec);
        return Error{describe(path, "cannot write", err)};
    }
    return commitTemporary(tmp, path, overwrite);
}

Result<std::string> readFile(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) return Error{"file '" + path.string() + "' does not exist"};
    if (fs::is_directory(path, ec)) return Error{"'" + path.string() + "' is a folder, not a file"};
    std::ifstream in(path, std::ios::binary);
    if (!in) return Error{describe(path, "cannot read", errno)};
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) return Error{describe(path, "cannot read", errno)};
    return ss.str();
}

} // namespace burnish
