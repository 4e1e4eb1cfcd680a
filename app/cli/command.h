// How `burnish` subcommands plug in: each cmd_*.cpp defines a static CommandRegistration that
// adds its subcommand to the CLI11 app. main.cpp knows none of them by name.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish::cli {

/// Adds a subcommand to the app; the returned callback runs it after parsing and returns the exit code.
using CommandSetup = std::function<std::function<int()>(CLI::App& app)>;

struct CommandEntry {
    int order; // position in --help
    CommandSetup setup;
};

std::vector<CommandEntry>& commandRegistry();

struct CommandRegistration {
    CommandRegistration(int order, CommandSetup setup) {
        commandRegistry().push_back({order, std::move(setup)});
    }
};

/// Prints "burnish: error: <message>" as one line on stderr and returns the exit code for it (1).
int fail(const std::string& message);
/// `text` with its control characters escaped (a newline as \n, others as \xNN): a message with a
/// path that holds a line break still prints as one line.
std::string printable(std::string_view text);
/// CLI::Range(lo, hi) that lets an empty value through to main's own check, which names it as empty
/// (checks run in the order added, and main adds its own after the command's).
CLI::Validator rangeOrEmpty(double lo, double hi);

} // namespace burnish::cli
