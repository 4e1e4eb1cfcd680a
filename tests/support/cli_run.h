// Runs the built `burnish` binary (BURNISH_EXE) in end-to-end tests, capturing its exit code,
// stdout and stderr.
#pragma once

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace burnish::test {

struct CliResult {
    int exitCode = -1;
    std::string out;
    std::string err;
};

/// `text` quoted for /bin/sh.
inline std::string shellQuote(const std::string& text) {
    std::string q = "'";
    for (char c : text)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// Runs `burnish <args>` (args already shell-quoted where needed), with `environment` (NAME=value
/// words, quoted as needed) set for it; stdout through a pipe, stderr through a temporary file that
/// is removed afterwards. With `timeoutSeconds` > 0 the run is stopped after that long (exit code
/// 124, timeout(1)'s): for a test of something that must not hang.
inline CliResult runBurnish(const std::string& args, const std::string& environment = "",
                            int timeoutSeconds = 0) {
    static std::atomic<int> counter{0};
    const auto errPath =
        std::filesystem::temp_directory_path() /
        ("burnish-cli-err-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".txt");
    const std::string command =
        (environment.empty() ? std::string() : "env " + environment + " ") +
        (timeoutSeconds > 0 ? "timeout -k 5 " + std::to_string(timeoutSeconds) + " " : "") +
        shellQuote(BURNISH_EXE) + " " + args + " 2>" + shellQuote(errPath.string());
    CliResult result;
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) return result;
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0)
        result.out.append(buffer, n);
    const int status = ::pclose(pipe);
    result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream err(errPath);
    std::stringstream ss;
    ss << err.rdbuf();
    result.err = ss.str();
    std::error_code ec;
    std::filesystem::remove(errPath, ec);
    return result;
}

/// Number of '\n'-terminated lines.
inline int lineCount(const std::string& text) {
    int lines = 0;
    for (char c : text)
        lines += c == '\n';
    return lines;
}

} // namespace burnish::test
