#include <burnish/core/shading/color.h>

#include <fmt/format.h>

#include <charconv>
#include <string>
#include <vector>

namespace burnish {

Result<LinearRgb> parseLinearRgb(std::string_view text, std::string_view option) {
    std::vector<std::string_view> fields;
    for (size_t start = 0;;) {
        const size_t comma = text.find(',', start);
        fields.push_back(
            text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
        if (comma == std::string_view::npos) break;
        start = comma + 1;
    }
    if (fields.size() != 1 && fields.size() != 3)
        return Error{fmt::format("{} '{}': give R,G,B or one value for a grey", option, text)};
    double v[3] = {0, 0, 0};
    for (std::size_t i = 0; i < fields.size(); ++i) {
        const std::string_view f = fields[i];
        const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), v[i]);
        if (f.empty() || ec != std::errc() || end != f.data() + f.size())
            return Error{fmt::format("{} '{}': '{}' is not a number", option, text, f)};
        if (!std::isfinite(v[i]) || v[i] < 0.0 || v[i] > 1.0)
            return Error{fmt::format("{} '{}': {} is outside the linear range [0, 1]", option, text, f)};
    }
    if (fields.size() == 1) return LinearRgb::grey(v[0]);
    return LinearRgb{v[0], v[1], v[2]};
}

} // namespace burnish
