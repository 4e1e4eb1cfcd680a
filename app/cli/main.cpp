// burnish: the command line over burnish_core.
#include "command.h"

#include <burnish/core/util/files.h>

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <set>
#include <string>

namespace burnish::cli {

std::vector<CommandEntry>& commandRegistry() {
    static std::vector<CommandEntry> registry;
    return registry;
}

std::string printable(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if (c == '\n')
            out += "\\n";
        else if (c == '\r')
            out += "\\r";
        else if (c == '\t')
            out += "\\t";
        else if (u < 0x20 || u == 0x7f) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(u));
            out += hex;
        } else
            out += c;
    }
    return out;
}

CLI::Validator rangeOrEmpty(double lo, double hi) {
    const CLI::Range range(lo, hi);
    return CLI::Validator(
        [range](std::string& value) { return value.empty() ? std::string() : range(value); },
        range.get_description());
}

int fail(const std::string& message) {
    std::fprintf(stderr, "burnish: error: %s\n", printable(message).c_str());
    return 1;
}

namespace {

/// A token that reads entirely as a number but is not a finite one ("nan", "inf", "-Infinity",
/// "1e999"): the reason, or "" for anything else (finite numbers and words alike).
std::string nonFiniteReason(const std::string& token) {
    if (token.empty()) return {};
    const char* begin = token.c_str();
    char* end = nullptr;
    const double value = std::strtod(begin, &end);
    if (end != begin + token.size() || std::isfinite(value)) return {};
    return "'" + token + "' is not a finite number";
}

/// Every option that takes numbers refuses NaN and infinities (and numbers too large for a double)
/// with one clear line, before the command runs: each comma- or colon-separated part of the
/// value is checked. Options that name files or folders are left alone, so a file called "inf"
/// can still be read.
void requireFiniteNumbers(CLI::App& app) {
    static const std::set<std::string> pathTypes{"TEXT", "FILE", "DIR", "PATH", "NORMAL_MAP", "IN", "MESH"};
    const CLI::Validator finite(
        [](std::string& value) -> std::string {
            std::string token;
            for (size_t i = 0; i <= value.size(); ++i) {
                const char c = i < value.size() ? value[i] : ',';
                if (c == ',' || c == ':') {
                    if (auto why = nonFiniteReason(token); !why.empty()) return why;
                    token.clear();
                } else {
                    token += c;
                }
            }
            return {};
        },
        "");
    // An empty value is an error, never the option's default (`--mips ""` baked every mip, `--yaw ""` drew
    // at 0): a script that lost a variable should hear of it.
    const CLI::Validator nonEmpty(
        [](std::string& value) -> std::string {
            return value.empty() ? "an empty value (give one, or leave the option out for its default)" : "";
        },
        "");
    for (CLI::Option* option : app.get_options()) {
        if (option->get_type_size() == 0) continue; // a flag takes no value
        option->check(nonEmpty);
        const std::string type = option->get_type_name();
        if (pathTypes.count(type.substr(0, type.find(':')))) continue;
        option->check(finite);
    }
    for (CLI::App* sub : app.get_subcommands({}))
        requireFiniteNumbers(*sub);
}

} // namespace

} // namespace burnish::cli

int main(int argc, char** argv) {
    using namespace burnish::cli;
    // A bake allocates and frees buffers of 100 MB and more in waves (decode, pyramid, one encode
    // buffer per file). glibc maps each with mmap and unmaps it on free, so the next buffer
    // page-faults fresh zeroed memory again. Heap allocation without trimming lets later buffers
    // reuse freed pages: measured 5-10% faster 4096² bakes for about 8% more peak memory.
    // A short-lived command-line process is where that trade belongs; the studio keeps glibc's
    // defaults.
    mallopt(M_MMAP_MAX, 0);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    CLI::App app{"Burnish: specular colour, gloss and normal-map prefiltering for real-time materials.\n"
                 "Every formula is measured against its exact form and its cost.",
                 "burnish"};
    app.set_version_flag("--version", "burnish 0.1.0");
    app.footer("Environment: BURNISH_MEMORY_LIMIT=SIZE (bytes, or K/M/G) caps the memory every command plans "
               "for: each estimates its peak from the inputs' headers and refuses, before reading, what "
               "needs more than that or than the system has available.\n");
    app.require_subcommand(1);

    auto& registry = commandRegistry();
    std::sort(registry.begin(), registry.end(),
              [](const auto& a, const auto& b) { return a.order < b.order; });
    std::vector<std::pair<CLI::App*, std::function<int()>>> runners;
    for (const auto& entry : registry) {
        const size_t before = app.get_subcommands({}).size();
        auto run = entry.setup(app);
        const auto subs = app.get_subcommands({});
        for (size_t i = before; i < subs.size(); ++i)
            runners.emplace_back(subs[i], run);
    }
    requireFiniteNumbers(app);
    // Fault injection for the tests of interrupted commits (test_cli_hostile.cpp): the process kills
    // itself after that many steps of a file set's commit, as a power cut or `kill -9` would.
    if (const char* step = std::getenv("BURNISH_FAULT_KILL_AT_COMMIT_STEP")) {
        const int at = std::atoi(step);
        burnish::setCommitStepHookForTesting([at](int done) {
            if (done == at) std::raise(SIGKILL);
        });
    }

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // One clear line; --help on the failing subcommand says more.
        std::string where = "burnish";
        for (const auto& [sub, run] : runners)
            if (sub->parsed()) where = "burnish " + sub->get_name();
        std::fprintf(stderr, "burnish: error: %s (see '%s --help')\n", printable(e.what()).c_str(),
                     where.c_str());
        return e.get_exit_code() == 0 ? 2 : e.get_exit_code();
    }

    for (const auto& [sub, run] : runners)
        if (sub->parsed()) {
            try {
                return run();
            } catch (const std::exception& e) {
                return fail(e.what());
            }
        }
    return fail("no subcommand given (see 'burnish --help')");
}
