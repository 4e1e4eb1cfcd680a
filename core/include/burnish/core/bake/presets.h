// Engine presets: which baked roles go to which file and channel, with constants for unused
// channels, plus the gloss encoding, default method, default storage format and the green
// convention an engine expects. A preset is data (resources/presets/*.json, embedded into the
// library), never a code path per engine; export.h applies it.
#pragma once

#include <burnish/core/io/dds.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/shading/specular_terms.h>
#include <burnish/core/util/result.h>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish {

/// The newest preset schema version this code reads.
inline constexpr int kPresetVersion = 1;

/// File formats a bake can be written to.
enum class ExportFormat {
    Png8,      // 8-bit PNG, one file per mip level
    Png16,     // 16-bit PNG, one file per mip level
    Tga,       // 8-bit TGA, one file per mip level
    ExrHalf,   // half-float OpenEXR, one tiled MIP-mapped file
    ExrFloat,  // float OpenEXR, one tiled MIP-mapped file
    Tiff16,    // 16-bit TIFF, one file, MIP levels as reduced-image subimages
    TiffFloat, // float TIFF, one file, MIP levels as reduced-image subimages
    Dds,       // DDS (BC4/BC5/BC3 or uncompressed RGBA8), the whole chain in one file
};

const std::vector<ExportFormat>& allExportFormats();
std::string_view exportFormatName(ExportFormat format);
Result<ExportFormat> exportFormatFromName(std::string_view name);
/// File extension without the dot: "png", "tga", "exr", "tif", "dds".
std::string_view exportFormatExtension(ExportFormat format);
/// 8 bits or fewer per stored channel (PNG8, TGA, every DDS variant).
bool exportFormatIsEightBit(ExportFormat format);
/// Whether the export writes this format through OpenImageIO (loaded on its first call): TGA, EXR and
/// TIFF; PNG has core's own encoder and DDS goes through nvtt.
bool exportFormatUsesOpenImageIo(ExportFormat format);
/// The same for a file with its DDS compression: DDS stores 8 bits except as rgba16f.
bool storesEightBits(ExportFormat format, std::optional<DdsCompression> compression);

const std::vector<DdsCompression>& allDdsCompressions();
std::string_view ddsCompressionName(DdsCompression compression);
Result<DdsCompression> ddsCompressionFromName(std::string_view name);

/// Where one stored channel's value comes from.
struct PresetChannel {
    enum class Kind { Baked, Constant, Parameter };
    Kind kind = Kind::Constant;
    std::string role;      // Baked: the baked texture's role ("normal", "gloss", "lean-b", ...)
    std::string channel;   // Baked: the baked channel's decode name ("normal.x", "gloss", "B.y", ...)
    double constant = 0.0; // Constant: the stored value, in [0, 1]
    std::string parameter; // Parameter: the name of one of the preset's parameters
};

/// One output file of a preset: `<stem>_<name>.<ext>`.
struct PresetFile {
    std::string name;
    std::string description;
    std::vector<PresetChannel> channels; // 1 to 4, in file channel order (R, G, B, A)
    DdsCompression dds = DdsCompression::Rgba8;
};

/// A user-settable value stored in a channel (glTF's and Unity's metallic).
struct PresetParameter {
    std::string name;
    std::string description;
    double defaultValue = 0.0;
    double minValue = 0.0;
    double maxValue = 1.0;
};

struct Preset {
    int version = kPresetVersion;
    std::string name;
    std::string title;
    std::string description;
    /// How a Blinn-Phong power p becomes the stored value (documentation, for reports and --help).
    std::string conversion;
    Method method = Method::VarianceToGloss;
    /// Encoding of the authored gloss input and of the stored gloss channel.
    GlossEncoding encoding = GlossEncoding::blackOps();
    /// The green convention written (the normal map's y, LEAN's B.y and M.xy flip with it).
    GreenConvention green = GreenConvention::OpenGL;
    /// How the engine takes the specular colour ("specular" in the file; f0 when absent).
    SpecularConvention specular = SpecularConvention::F0;
    ExportFormat format = ExportFormat::Png8;
    std::vector<PresetParameter> parameters;
    std::vector<PresetFile> files;
    std::vector<std::string> notes;
    /// "built-in" or the file it was read from.
    std::string origin;

    const PresetParameter* findParameter(std::string_view name) const;
};

/// Parses and validates a preset. `origin` names the source in error messages. Errors (one line,
/// naming the origin and the field): invalid JSON, a newer version, unknown or missing fields,
/// unknown method/gloss/format/compression/role/channel/parameter names, constants outside
/// [0, 1], 0 or more than 4 channels, a DDS compression that cannot hold the file's channels,
/// duplicate or unsafe file names, and a default method whose baked roles the files do not
/// store (or that does not produce a packed role).
Result<Preset> parsePreset(std::string_view json, const std::string& origin);

/// Reads and parses a preset file.
Result<Preset> loadPresetFile(const std::filesystem::path& path);

/// The built-in presets (embedded resources/presets/*.json), in --help order. Parsed once; a
/// built-in that fails validation is a build defect reported by builtinPresetErrors().
const std::vector<Preset>& builtinPresets();
/// Validation errors of the embedded presets (empty when all are valid).
const std::vector<std::string>& builtinPresetErrors();
std::vector<std::string> builtinPresetNames();

/// A built-in preset by name, or a preset file when `nameOrPath` ends in ".json". Unknown names
/// list the known ones.
Result<Preset> findPreset(std::string_view nameOrPath);

/// The baked roles the preset's files read, in first-use order: what a bake for it must produce
/// (names that are no texture role are left out; checkPresetMethod refuses them).
std::vector<TextureRole> presetRoles(const Preset& preset);

/// Checks, against the method's row in the method table (methods.h), that `method` produces every
/// role and channel the preset stores, and that every role the method produces (except "normal",
/// which slope methods carry in B) is stored. The error lists the methods that fit the preset.
Status checkPresetMethod(const Preset& preset, Method method);
/// The methods checkPresetMethod accepts for the preset, in report order.
std::vector<Method> compatibleMethods(const Preset& preset);

} // namespace burnish
