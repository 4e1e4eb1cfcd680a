// Calibrated materials: the specular-colour ranges artists must stay in (Lagarde's chart), the
// linear F0 of common dielectrics and metals (Hoffman 2015), and broadband diffuse albedos, each
// value with its public source. The table is versioned JSON (resources/materials/materials.json,
// embedded in the build); parsing validates every value and never throws.
#pragma once

#include <burnish/core/shading/color.h>
#include <burnish/core/util/result.h>

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish {

/// The newest table version this code reads.
inline constexpr int kMaterialTableVersion = 1;

/// Linear values written in the table beside an 8-bit sRGB code must equal the code's exact decode
/// within this: the table writes them to 4 decimals, so half a unit of the 4th decimal plus slack
/// for the binary representation.
inline constexpr double kStoredLinearTolerance = 5e-5 + 1e-12;

enum class MaterialClass { Dielectric, Metal };

/// "dielectric" / "metal".
const char* toString(MaterialClass c);

/// A closed interval of linear values, min <= max, both in [0, 1].
struct LinearInterval {
    double min = 0.0;
    double max = 0.0;
    bool contains(double v) const { return v >= min && v <= max; }
    friend bool operator==(const LinearInterval&, const LinearInterval&) = default;
};

/// A specular range: the linear interval, and where it comes from a chart, the chart's 8-bit sRGB
/// end points and the linear numbers the source printed (which may use a gamma approximation).
struct SpecularRange {
    LinearInterval linear;
    std::optional<std::pair<int, int>> srgb8;      // chart end points, 0..255
    std::optional<LinearInterval> publishedLinear; // as printed in the source
    std::string source;                            // key into MaterialTable::sources
    std::string note;

    /// The interval used for classification: the exact sRGB decode of the chart end points where
    /// there are any (the stored linear numbers are those rounded to 4 decimals), else `linear`.
    LinearInterval bounds() const;
    friend bool operator==(const SpecularRange&, const SpecularRange&) = default;
};

/// One calibrated material. A single published value has f0Min == f0Max; a published range
/// ("0.04-0.056") keeps both ends. Values are linear RGB.
struct Material {
    std::string name;
    MaterialClass materialClass = MaterialClass::Dielectric;
    LinearRgb f0Min;
    LinearRgb f0Max;
    std::string source; // key into MaterialTable::sources
    std::string note;

    bool isRange() const { return !(f0Min == f0Max); }
    /// The single value, or the middle of the range.
    LinearRgb f0() const;
    friend bool operator==(const Material&, const Material&) = default;
};

/// A broadband diffuse albedo (fraction of light diffusely reflected), as a value or a range.
struct DiffuseAlbedo {
    std::string name;
    LinearInterval albedo;
    std::string source;
    std::string note;
    friend bool operator==(const DiffuseAlbedo&, const DiffuseAlbedo&) = default;
};

/// A single reference value with its source (the middle grey, the default dielectric F0).
struct ReferenceValue {
    std::optional<int> srgb8; // 8-bit code, where the source gives one
    double linear = 0.0;
    std::string source;
    std::string note;
    friend bool operator==(const ReferenceValue&, const ReferenceValue&) = default;
};

struct MaterialTable {
    int version = kMaterialTableVersion;
    std::map<std::string, std::string> sources; // key → citation
    SpecularRange dielectricChart;              // Lagarde's non-metal gradient, sRGB 40-75
    SpecularRange metalChart;                   // Lagarde's metal gradient, sRGB 155-255
    SpecularRange dielectricPlausible;          // lowest to highest dielectric F0 of the source
    ReferenceValue dielectricDefault;           // Lazarov's hard-coded 0.03
    ReferenceValue midGrey;                     // sRGB 187
    std::vector<Material> materials;
    std::vector<DiffuseAlbedo> albedos;

    /// The material named `name`, compared case-insensitively (ASCII); nullptr when none.
    const Material* find(std::string_view name) const;
    /// The citation for a source key; the key itself when unknown (a validated table has none).
    const std::string& citation(const std::string& key) const;
    friend bool operator==(const MaterialTable&, const MaterialTable&) = default;
};

/// Parses and validates a table. Every failure is one line saying what and where, e.g.
/// "materials[3] ('gold'): f0[2] = 1.2 is outside [0, 1]". Never throws.
Result<MaterialTable> parseMaterialTable(std::string_view json);

/// The value checks parseMaterialTable makes, for tables built or edited in code: values finite
/// and in [0, 1], min <= max, linear values matching their 8-bit codes, ranges that do not
/// overlap, every metal channel at or above the metal range, every dielectric channel inside the
/// plausible dielectric bound, known sources, no duplicate names.
Status validateMaterialTable(const MaterialTable& table);

/// Reads and parses a table file; errors name the file.
Result<MaterialTable> loadMaterialTable(const std::filesystem::path& path);

/// The table embedded at build time (resources/materials/materials.json), parsed once.
/// The test suite guarantees the embedded copy is valid; should a broken build embed an invalid
/// one, this returns an empty table and builtinMaterialTableStatus() says why.
const MaterialTable& builtinMaterialTable();
Status builtinMaterialTableStatus();

/// The table as JSON in the file's schema; parseMaterialTable of it gives the table back.
std::string materialTableToJson(const MaterialTable& table, int indent = 2);

/// Where a linear specular colour falls.
enum class F0Class {
    Dielectric,  // every channel inside the plausible dielectric bound (dielectricPlausible.bounds())
    Metal,       // every channel inside the metal range (metalChart.bounds())
    Implausible, // anywhere else: between the ranges (the chart's "no material here"), below the
                 // dielectric bound, channels in both ranges, or a channel that is not finite
};

/// "dielectric" / "metal" / "implausible".
const char* toString(F0Class c);

struct F0Classification {
    F0Class f0Class = F0Class::Implausible;
    /// Every channel inside the chart gradient of its class (dielectricChart or metalChart).
    bool insideChart = false;
    /// A dielectric whose channels encode to different 8-bit sRGB codes: non-metal specular is
    /// monochrome (Lazarov 2011), so a tint is worth a warning.
    bool tinted = false;
};

/// Classifies a linear F0 against the table's ranges.
F0Classification classifyF0(const MaterialTable& table, const LinearRgb& f0);

/// Where a colour sits on the artist chart: its 8-bit sRGB code per channel, and the position of
/// its luminance along its class's gradient (0 at the gradient's first code, 1 at its last,
/// clamped), absent for implausible colours.
struct ChartPosition {
    Srgb8 srgb8;
    F0Class f0Class = F0Class::Implausible;
    std::optional<double> gradient;
};
ChartPosition chartPosition(const MaterialTable& table, const LinearRgb& f0);

struct MaterialMatch {
    const Material* material = nullptr;
    /// Euclidean distance in sRGB-encoded [0, 1] units from the colour to the material's F0 (to the
    /// nearest point of its range; 0 inside it). sRGB encoding spaces the distance closer to
    /// perceived difference than linear values do.
    double distance = 0.0;
};

/// The `count` materials nearest to `f0`, nearest first; among equal distances (several ranges
/// containing the colour) the one whose middle is nearest comes first, then table order. Non-finite
/// channels are clamped to [0, 1] (NaN to 0) by the sRGB encode.
std::vector<MaterialMatch> nearestMaterials(const MaterialTable& table, const LinearRgb& f0,
                                            std::size_t count);

} // namespace burnish
