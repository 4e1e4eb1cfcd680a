// `burnish materials`: the calibrated specular-colour table, and the check of one colour against it.
#include "command.h"

#include <burnish/core/shading/color.h>
#include <burnish/core/shading/materials.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace burnish::cli {

namespace {

struct MaterialsOptions {
    bool json = false;
    std::string file;
    std::string check;
    std::string checkSrgb;
    std::size_t nearest = 3;
};

// Splits "a,b,c" into fields; spaces around fields are allowed.
std::vector<std::string> splitComma(const std::string& text) {
    std::vector<std::string> out;
    std::string field;
    for (char c : text) {
        if (c == ',') {
            out.push_back(field);
            field.clear();
        } else if (c != ' ') {
            field.push_back(c);
        }
    }
    out.push_back(field);
    return out;
}

// "R,G,B" or one code for a grey, 8-bit sRGB codes 0..255.
Result<Srgb8> parseSrgb8Triple(const std::string& text) {
    const auto fields = splitComma(text);
    if (fields.size() != 1 && fields.size() != 3)
        return Error{fmt::format("--check-srgb '{}': give R,G,B or one code for a grey", text)};
    int v[3] = {0, 0, 0};
    for (std::size_t i = 0; i < fields.size(); ++i) {
        const std::string& f = fields[i];
        const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), v[i]);
        if (f.empty() || ec != std::errc() || end != f.data() + f.size())
            return Error{fmt::format("--check-srgb '{}': '{}' is not an integer", text, f)};
        if (v[i] < 0 || v[i] > 255)
            return Error{fmt::format("--check-srgb '{}': {} is outside the 8-bit range 0..255", text, f)};
    }
    if (fields.size() == 1) v[1] = v[2] = v[0];
    return Srgb8{std::uint8_t(v[0]), std::uint8_t(v[1]), std::uint8_t(v[2])};
}

bool isGrey(const LinearRgb& c) {
    return c.r == c.g && c.g == c.b;
}

std::string formatLinear(const LinearRgb& c) {
    if (isGrey(c)) return fmt::format("{:.3f}", c.r);
    return fmt::format("{:.3f} {:.3f} {:.3f}", c.r, c.g, c.b);
}

std::string formatSrgb(const Srgb8& c) {
    if (c.r == c.g && c.g == c.b) return fmt::format("{}", c.r);
    return fmt::format("{} {} {}", c.r, c.g, c.b);
}

std::string formatF0(const Material& m) {
    if (!m.isRange()) return formatLinear(m.f0Min);
    return formatLinear(m.f0Min) + " .. " + formatLinear(m.f0Max);
}

std::string formatF0Srgb(const Material& m) {
    if (!m.isRange()) return formatSrgb(toSrgb8(m.f0Min));
    return formatSrgb(toSrgb8(m.f0Min)) + " .. " + formatSrgb(toSrgb8(m.f0Max));
}

// One row of the ranges block: label, chart codes, linear interval, the source's printed numbers.
std::string formatRangeRow(const char* label, const std::string& codes, const std::string& linear,
                           const std::string& printed, const std::string& source) {
    return fmt::format("  {:<20}  {:<14}  {:<22}  {:<22}  [{}]\n", label, codes, linear, printed, source);
}

std::string formatRange(const char* label, const SpecularRange& r) {
    const std::string codes = r.srgb8 ? fmt::format("sRGB {}..{}", r.srgb8->first, r.srgb8->second) : "";
    const std::string linear = fmt::format("linear {:.4f}..{:.4f}", r.linear.min, r.linear.max);
    const std::string printed =
        r.publishedLinear
            ? fmt::format("printed {:.3f}..{:.3f}", r.publishedLinear->min, r.publishedLinear->max)
            : "";
    return formatRangeRow(label, codes, linear, printed, r.source);
}

void printTable(const MaterialTable& table) {
    std::string out;
    out +=
        fmt::format("Calibrated specular colour (F0) and diffuse albedo, table version {}.\n", table.version);
    out += "8-bit sRGB codes are decoded with the exact IEC 61966-2-1 curve.\n\n";
    out += "Specular ranges:\n";
    out += formatRange("dielectric chart", table.dielectricChart);
    out += formatRange("metal chart", table.metalChart);
    out += formatRange("plausible dielectric", table.dielectricPlausible);
    out += formatRangeRow(
        "dielectric default", fmt::format("sRGB {}", linearToSrgb8(table.dielectricDefault.linear)),
        fmt::format("linear {:.4f}", table.dielectricDefault.linear), "", table.dielectricDefault.source);
    out += "  Between the dielectric bound and the metal chart lies no material.\n\n";
    out += fmt::format("Mid grey: sRGB {} = linear {:.4f}, not sRGB 128 = linear {:.4f} [{}]\n\n",
                       table.midGrey.srgb8.value_or(0), table.midGrey.linear, srgb8ToLinear(128),
                       table.midGrey.source);

    std::size_t nameWidth = 4;
    std::size_t f0Width = 17;
    std::size_t srgbWidth = 12;
    for (const Material& m : table.materials) {
        nameWidth = std::max(nameWidth, m.name.size());
        f0Width = std::max(f0Width, formatF0(m).size());
        srgbWidth = std::max(srgbWidth, formatF0Srgb(m).size());
    }
    out += "Specular F0 (linear RGB; a range is min .. max):\n";
    out += fmt::format("  {:<{}}  {:<10}  {:<{}}  {:<{}}  {}\n", "name", nameWidth, "class",
                       "linear F0 (R G B)", f0Width, "sRGB (R G B)", srgbWidth, "source");
    for (const Material& m : table.materials) {
        const std::string note = m.note.empty() ? "" : " (" + m.note + ")";
        out += fmt::format("  {:<{}}  {:<10}  {:<{}}  {:<{}}  {}{}\n", m.name, nameWidth,
                           toString(m.materialClass), formatF0(m), f0Width, formatF0Srgb(m), srgbWidth,
                           m.source, note);
    }

    if (!table.albedos.empty()) {
        std::size_t albedoNameWidth = 4;
        for (const DiffuseAlbedo& a : table.albedos)
            albedoNameWidth = std::max(albedoNameWidth, a.name.size());
        out += "\nDiffuse albedo (broadband, linear):\n";
        out += fmt::format("  {:<{}}  {:<12}  {:<10}  {}\n", "name", albedoNameWidth, "albedo", "sRGB",
                           "source");
        for (const DiffuseAlbedo& a : table.albedos) {
            const bool range = a.albedo.min != a.albedo.max;
            const std::string value = range ? fmt::format("{:.2f} .. {:.2f}", a.albedo.min, a.albedo.max)
                                            : fmt::format("{:.2f}", a.albedo.min);
            const std::string codes =
                range ? fmt::format("{} .. {}", linearToSrgb8(a.albedo.min), linearToSrgb8(a.albedo.max))
                      : fmt::format("{}", linearToSrgb8(a.albedo.min));
            const std::string note = a.note.empty() ? "" : " (" + a.note + ")";
            out += fmt::format("  {:<{}}  {:<12}  {:<10}  {}{}\n", a.name, albedoNameWidth, value, codes,
                               a.source, note);
        }
    }

    out += "\nSources:\n";
    for (const auto& [key, citation] : table.sources)
        out += fmt::format("  [{}] {}\n", key, citation);
    std::fputs(out.c_str(), stdout);
}

// Why a colour is implausible, in the chart's terms.
std::string implausibleReason(const MaterialTable& table, const LinearRgb& c) {
    const LinearInterval dielectric = table.dielectricPlausible.bounds();
    const double metalMin = table.metalChart.bounds().min;
    const auto inGap = [&](double v) { return v > dielectric.max && v < metalMin; };
    if (inGap(c.r) || inGap(c.g) || inGap(c.b))
        return fmt::format(
            "a channel lies between the dielectric bound (max {}) and the metal range (min {:.4f}): "
            "the chart's \"no material here\"",
            dielectric.max, metalMin);
    if (std::max({c.r, c.g, c.b}) <= dielectric.max)
        return fmt::format(
            "below the plausible dielectric bound (linear {}): no real surface reflects this little",
            dielectric.min);
    return "some channels are dielectric (or darker), others metal: no material mixes the two";
}

int runCheck(const MaterialTable& table, const LinearRgb& c, const MaterialsOptions& options) {
    const F0Classification cls = classifyF0(table, c);
    const ChartPosition chart = chartPosition(table, c);
    const auto nearest = nearestMaterials(table, c, options.nearest);

    if (options.json) {
        nlohmann::json j = {{"linear", {c.r, c.g, c.b}},
                            {"srgb8", {chart.srgb8.r, chart.srgb8.g, chart.srgb8.b}},
                            {"class", toString(cls.f0Class)},
                            {"insideChart", cls.insideChart},
                            {"tinted", cls.tinted}};
        j["gradient"] = chart.gradient ? nlohmann::json(*chart.gradient) : nlohmann::json(nullptr);
        nlohmann::json list = nlohmann::json::array();
        for (const MaterialMatch& m : nearest)
            list.push_back({{"name", m.material->name},
                            {"class", toString(m.material->materialClass)},
                            {"distance", m.distance}});
        j["nearest"] = std::move(list);
        std::fputs((j.dump(2) + "\n").c_str(), stdout);
        return 0;
    }

    std::string out;
    out += fmt::format("colour    linear {:.4f} {:.4f} {:.4f}   sRGB {} {} {}\n", c.r, c.g, c.b,
                       chart.srgb8.r, chart.srgb8.g, chart.srgb8.b);
    switch (cls.f0Class) {
    case F0Class::Dielectric:
        out += fmt::format("class     dielectric ({} the chart's dielectric gradient, sRGB {}..{})\n",
                           cls.insideChart ? "inside" : "outside", table.dielectricChart.srgb8->first,
                           table.dielectricChart.srgb8->second);
        if (cls.tinted)
            out += "warning   tinted: non-metal specular is monochrome (Lazarov 2011); use one value\n";
        break;
    case F0Class::Metal:
        out += fmt::format("class     metal (inside the chart's metal gradient, sRGB {}..{})\n",
                           table.metalChart.srgb8->first, table.metalChart.srgb8->second);
        break;
    case F0Class::Implausible:
        out += "class     implausible: " + implausibleReason(table, c) + "\n";
        break;
    }
    if (chart.gradient) out += fmt::format("chart     position {:.2f} along the gradient\n", *chart.gradient);
    out += "nearest   (distance in 8-bit sRGB steps)\n";
    for (const MaterialMatch& m : nearest)
        out += fmt::format("          {:<16} {:<10} {:>6.1f}   {}\n", m.material->name,
                           toString(m.material->materialClass), m.distance * 255.0, formatF0(*m.material));
    std::fputs(out.c_str(), stdout);
    return 0;
}

int runMaterials(const MaterialsOptions& options) {
    MaterialTable loaded;
    const MaterialTable* table = &builtinMaterialTable();
    if (!options.file.empty()) {
        auto result = loadMaterialTable(options.file);
        if (!result) return fail(result.error());
        loaded = std::move(result).value();
        table = &loaded;
    } else if (const Status status = builtinMaterialTableStatus(); !status) {
        return fail(status.error());
    }

    if (!options.check.empty() && !options.checkSrgb.empty())
        return fail("give --check or --check-srgb, not both");
    if (!options.check.empty()) {
        const auto colour = parseLinearRgb(options.check, "--check");
        if (!colour) return fail(colour.error());
        return runCheck(*table, colour.value(), options);
    }
    if (!options.checkSrgb.empty()) {
        const auto code = parseSrgb8Triple(options.checkSrgb);
        if (!code) return fail(code.error());
        return runCheck(*table, toLinear(code.value()), options);
    }

    if (options.json) {
        std::fputs(materialTableToJson(*table).c_str(), stdout);
        return 0;
    }
    printTable(*table);
    return 0;
}

const CommandRegistration registration{
    30, [](CLI::App& app) -> std::function<int()> {
        auto options = std::make_shared<MaterialsOptions>();
        CLI::App* sub = app.add_subcommand(
            "materials",
            "Calibrated specular colours: the dielectric and metal ranges, F0 of common materials, "
            "diffuse albedos; check a colour against them.");
        sub->add_flag("--json", options->json,
                      "Print JSON instead of text: the validated table (same schema as the file), or with "
                      "--check/--check-srgb the classification and nearest materials.");
        sub->add_option(
               "--file", options->file,
               "Load and validate this materials table (JSON) instead of the built-in one; an invalid "
               "file is a one-line error and exit code 1.")
            ->type_name("PATH");
        sub->add_option(
               "--check", options->check,
               "Classify a LINEAR specular colour (F0) as dielectric, metal or implausible and name the "
               "nearest calibrated materials. R,G,B in [0,1], or one value for a grey, e.g. 0.04 or "
               "1,0.782,0.344.")
            ->type_name("R,G,B");
        sub->add_option("--check-srgb", options->checkSrgb,
                        "As --check, with 8-bit sRGB codes 0..255 (as picked from a texture), e.g. 187 or "
                        "255,229,158.")
            ->type_name("R,G,B");
        sub->add_option("--nearest", options->nearest,
                        "How many nearest materials --check names (default 3).")
            ->check(CLI::Range(1, 1000))
            ->type_name("N");
        return [options] { return runMaterials(*options); };
    }};

} // namespace

} // namespace burnish::cli
