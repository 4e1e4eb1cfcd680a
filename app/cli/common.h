// Pieces several `burnish` subcommands share: normal-map import options and a terminal progress bar.
#pragma once

#include <burnish/core/prefilter/normal_map.h>

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

/// A one-line progress bar on stderr, drawn only when stderr is a terminal:
/// "<label> <stage> [#####.....]  50%".
class ProgressBar {
public:
    explicit ProgressBar(std::string label = {});
    ~ProgressBar();
    void setLabel(std::string label);
    /// Redraws when the percentage or the stage changed.
    void update(double fraction, const std::string& stage = {});
    /// Clears the line.
    void finish();

private:
    std::string m_label;
    std::string m_stage;
    bool m_enabled = false;
    int m_lastPercent = -1;
};

} // namespace burnish::cli
