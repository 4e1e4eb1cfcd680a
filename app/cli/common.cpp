#include "common.h"

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace burnish::cli {

void addNormalMapOptions(CLI::App* sub, NormalMapCliOptions& options) {
    sub->add_option("--green", options.green,
                    "Green-channel convention of the input normal map: opengl (+Y, default) or directx (-Y, "
                    "flipped on import).")
        ->check(CLI::IsMember({"opengl", "directx"}))
        ->type_name("CONV");
    sub->add_option("--layout", options.layout,
                    "Channels holding the normal: auto (2 channels: RG with z rebuilt; 3-4: RGB; alpha never "
                    "used), rgb, or rg (rebuild z from RG, e.g. BC5 maps saved as RGB).")
        ->check(CLI::IsMember({"auto", "rgb", "rg"}))
        ->type_name("LAYOUT");
    sub->add_option(
           "--encoding", options.encoding,
           "How stored values map to [-1,1]: auto (integer formats and non-negative float images: 2v-1; "
           "float images with negative values: as stored), unsigned, or signed.")
        ->check(CLI::IsMember({"auto", "unsigned", "signed"}))
        ->type_name("ENC");
    sub->add_flag(
        "--allow-implausible", options.allowImplausible,
        "Read an image that does not look like a tangent-space normal map (many texels facing down, "
        "vector lengths far from 1) with a warning instead of an error.");
}

NormalMapOptions toNormalMapOptions(const NormalMapCliOptions& options) {
    NormalMapOptions out;
    out.green = options.green == "directx" ? GreenConvention::DirectX : GreenConvention::OpenGL;
    out.layout = options.layout == "rgb"  ? NormalLayout::Rgb
                 : options.layout == "rg" ? NormalLayout::Rg
                                          : NormalLayout::Auto;
    out.encoding = options.encoding == "signed"     ? NormalValueEncoding::Signed
                   : options.encoding == "unsigned" ? NormalValueEncoding::Unsigned
                                                    : NormalValueEncoding::Auto;
    out.allowImplausible = options.allowImplausible;
    return out;
}

ProgressBar::ProgressBar(std::string label)
    : m_label(std::move(label))
    , m_enabled(::isatty(STDERR_FILENO) == 1) {}

ProgressBar::~ProgressBar() {
    finish();
}

void ProgressBar::setLabel(std::string label) {
    m_label = std::move(label);
}

void ProgressBar::update(double fraction, const std::string& stage) {
    if (!m_enabled) return;
    const int percent = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 100.0);
    if (percent == m_lastPercent && stage == m_stage) return;
    m_lastPercent = percent;
    m_stage = stage;
    constexpr int kWidth = 24;
    const int filled = percent * kWidth / 100;
    std::fprintf(stderr, "\r%-32.32s %-10s [%s%s] %3d%%", m_label.c_str(), m_stage.c_str(),
                 std::string(size_t(filled), '#').c_str(), std::string(size_t(kWidth - filled), '.').c_str(),
                 percent);
    std::fflush(stderr);
}

void ProgressBar::finish() {
    if (!m_enabled || m_lastPercent < 0) return;
    std::fprintf(stderr, "\r%80s\r", "");
    std::fflush(stderr);
    m_lastPercent = -1;
    m_stage.clear();
}

} // namespace burnish::cli
