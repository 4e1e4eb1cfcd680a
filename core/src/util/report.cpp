#include <burnish/core/util/report.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <thread>

namespace burnish {

std::string formatNumber(double v, int significant) {
    if (!std::isfinite(v)) return "n/a";
    if (v == 0.0) return "0";
    significant = std::clamp(significant, 1, 17);
    return fmt::format("{:.{}g}", v, significant);
}

nlohmann::json jsonNumber(double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

std::string markdownCell(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (const char ch : text) {
        if (ch == '|')
            out += "\\|";
        else if (ch == '\n' || ch == '\r')
            out += ' ';
        else
            out += ch;
    }
    return out;
}

MarkdownTable::MarkdownTable(std::vector<std::string> header, std::vector<Align> align)
    : m_header(std::move(header))
    , m_align(std::move(align)) {
    m_align.resize(m_header.size(), Align::Left);
}

void MarkdownTable::addRow(std::vector<std::string> cells) {
    cells.resize(m_header.size());
    m_rows.push_back(std::move(cells));
}

std::string MarkdownTable::render() const {
    auto line = [](const std::vector<std::string>& cells) {
        std::string s = "|";
        for (const auto& c : cells)
            s += " " + markdownCell(c) + " |";
        return s + "\n";
    };
    std::string out = line(m_header);
    out += "|";
    for (const Align a : m_align)
        out += a == Align::Right ? " ---: |" : " --- |";
    out += "\n";
    for (const auto& row : m_rows)
        out += line(row);
    return out;
}

std::vector<bool> paretoFront(const std::vector<ParetoPoint>& points) {
    std::vector<bool> front(points.size(), false);
    auto finite = [](const ParetoPoint& p) { return std::isfinite(p.cost) && std::isfinite(p.error); };
    for (size_t i = 0; i < points.size(); ++i) {
        const ParetoPoint& p = points[i];
        if (!finite(p)) continue;
        bool dominated = false;
        for (size_t j = 0; j < points.size() && !dominated; ++j) {
            const ParetoPoint& q = points[j];
            if (j == i || q.group != p.group || !finite(q)) continue;
            dominated = q.cost <= p.cost && q.error <= p.error && (q.cost < p.cost || q.error < p.error);
        }
        front[i] = !dominated;
    }
    return front;
}

MachineInfo machineInfo() {
    MachineInfo info;
    info.cpuModel = "unknown CPU";
    std::ifstream cpuinfo("/proc/cpuinfo");
    for (std::string line; std::getline(cpuinfo, line);) {
        if (line.rfind("model name", 0) != 0) continue;
        const size_t colon = line.find(':');
        if (colon == std::string::npos) continue;
        const size_t start = line.find_first_not_of(" \t", colon + 1);
        if (start != std::string::npos) info.cpuModel = line.substr(start);
        break;
    }
    info.logicalCpus = std::thread::hardware_concurrency();
#if defined(__clang__)
    info.compiler = fmt::format("Clang {}.{}.{}", __clang_major__, __clang_minor__, __clang_patchlevel__);
#elif defined(__GNUC__)
    info.compiler = fmt::format("GCC {}.{}.{}", __GNUC__, __GNUC_MINOR__, __GNUC_PATCHLEVEL__);
#else
    info.compiler = "unknown compiler";
#endif
    return info;
}

} // namespace burnish
