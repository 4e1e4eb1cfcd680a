// Pieces several `burnish` subcommands share: normal-map import options and a terminal progress bar.
#pragma once

#include <burnish/core/normal_map.h>

#include <CLI/CLI.hpp>

#include <string>

namespace burnish::cli {

/// --green, --layout, --encoding and --allow-implausible, as parsed text.
struct NormalMapCliOptions {
    std::string green = "opengl";
    std::string layout = "auto";
    std::string encoding = "auto";
    bool allowImplausible = false;
};

void addNormalMapOptions(CLI::App* sub, NormalMapCliOptions& options);
/// The core options (the CLI11 checks have already restricted the names).
NormalMapOptions toNormalMapOptions(const NormalMapCliOptions& options);

/// A one-line progress bar on stderr, drawn only when stderr is a terminal.
class ProgressBar {
public:
    explicit ProgressBar(std::string label);
    ~ProgressBar();
    void update(double fraction);
    void finish();

private:
    std::string m_label;
    bool m_enabled = false;
    int m_lastPercent = -1;
};

} // namespace burnish::cli
