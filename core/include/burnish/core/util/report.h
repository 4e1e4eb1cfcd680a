// Helpers shared by Burnish's reports (approximations, bake): number formatting that never prints
// NaN/Inf, Markdown tables, JSON numbers, Pareto fronts, and a description of the machine that
// measured the numbers.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace burnish {

/// `v` with `significant` significant digits ("0.0123", "1.23e-05", "412"); "n/a" when v is NaN or
/// infinite, so no report ever prints "nan" or "inf".
std::string formatNumber(double v, int significant = 3);

/// `v` as a JSON number, or null when it is NaN or infinite (JSON has no such numbers).
nlohmann::json jsonNumber(double v);

/// `text` made safe for one Markdown table cell: '|' escaped, newlines turned into spaces.
std::string markdownCell(std::string_view text);

enum class Align { Left, Right };

/// A GitHub-flavoured Markdown table. Cells are escaped with markdownCell when rendered.
class MarkdownTable {
public:
    /// `align` may be shorter than `header`; missing columns are left-aligned.
    explicit MarkdownTable(std::vector<std::string> header, std::vector<Align> align = {});

    /// Adds a row; a row shorter than the header is padded with empty cells, a longer one truncated.
    void addRow(std::vector<std::string> cells);
    size_t rowCount() const { return m_rows.size(); }
    size_t columnCount() const { return m_header.size(); }

    /// The table, one line per row, ending with a newline.
    std::string render() const;

private:
    std::vector<std::string> m_header;
    std::vector<Align> m_align;
    std::vector<std::vector<std::string>> m_rows;
};

/// One candidate of a cost/error trade-off. Points are compared only within their group.
struct ParetoPoint {
    std::string group;
    double cost = 0.0;
    double error = 0.0;
};

/// For each point, whether it is on the Pareto front of its group: no other point of the group is
/// at least as cheap and at least as accurate while strictly better in one of the two. Points
/// with a NaN or infinite cost or error are never on the front and never dominate.
std::vector<bool> paretoFront(const std::vector<ParetoPoint>& points);

/// What the numbers were measured on.
struct MachineInfo {
    std::string cpuModel;     // "model name" of /proc/cpuinfo, or "unknown CPU"
    unsigned logicalCpus = 0; // std::thread::hardware_concurrency(), 0 when unknown
    std::string compiler;     // e.g. "GCC 12.2.0"
};
MachineInfo machineInfo();

} // namespace burnish
