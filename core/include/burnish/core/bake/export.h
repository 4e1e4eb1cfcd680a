// Writing a bake to files: a preset's packing applied to the baked textures, each file with its
// full mip chain, in one of the export formats, plus `bake.json` describing every file's
// channels and decode rules. Writes are all-or-nothing: every file is staged under a temporary
// name first and renamed only when all of them were written; existing files are never
// overwritten unless asked. Output bytes depend only on the inputs (no timestamps).
//
// Mip storage per format:
//   exr-half, exr-float   one tiled MIP-mapped OpenEXR file (ROUND_DOWN level sizes)
//   tiff16, tiff-float    one TIFF, level k as subimage k ("Plain Texture" reduced images: OpenImageIO
//                         and maketx read them as MIP levels)
//   dds                   one file with the whole chain (NVIDIA Texture Tools 2.0)
//   png8, png16, tga      one file per level: <stem>_<name>.<ext> for level 0 and
//                         <stem>_<name>_mip<k>.<ext> for level k >= 1 (these formats hold no mips)
// Each file has the mip chain of the textures it packs: a bake's "detail" texture (detail.h) tiles
// at its own resolution and is written, with every preset, as the extra file <stem>_detail.<ext>
// with its own chain (DDS: rgba8 unless the compression asked for holds four channels: bc3).
#pragma once

#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/io/dds.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/result.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace burnish {

struct ExportOptions {
    /// The output format (the preset's default when not set).
    std::optional<ExportFormat> format;
    /// DDS only: one compression for every file instead of each file's preset default.
    std::optional<DdsCompression> compression;
    /// File names are <stem>_<file name>[_mip<k>].<ext>.
    std::string stem = "texture";
    /// Values of the preset's parameters; missing ones take the preset's defaults.
    std::map<std::string, double> parameters;
    /// Store high-precision textures (LEAN, CLEAN) in 8-bit formats anyway.
    bool allowEightBit = false;
    Overwrite overwrite = Overwrite::Refuse;
};

/// bake.json's "detail" entry: what a shader needs beside the detail file.
struct DetailRecord {
    std::string input; // the detail normal map the texture was baked from
    /// The detail map's whole variance, added (1/s' = 1/s + σ²) where the map is no longer sampled.
    double constantVariance = 0.0;
    int fadeStartMip = 3;
    int fadeEndMip = 6;
};

/// What bake.json records besides the files: the caller's description of the inputs and
/// settings (free-form JSON objects) and what the normal-map decoder saw.
struct BakeRecord {
    nlohmann::json inputs = nlohmann::json::object();
    nlohmann::json options = nlohmann::json::object();
    std::optional<NormalMapDiagnostics> diagnostics;
    /// Required when the bake holds a "detail" texture, and only then.
    std::optional<DetailRecord> detail;
    /// bake.json's "material": the specular colour and the engine's values for it (null: none given).
    nlohmann::json material;
};

/// One stored channel of an exported file.
struct ExportedChannel {
    std::string source; // "normal.y", "gloss", "constant", or a parameter's name
    std::string role;   // baked role, empty for constants and parameters
    ChannelDecode decode;
    std::optional<double> value; // the stored value of a constant or parameter
};

struct ExportedFile {
    std::string name; // the preset file's name
    /// Written files, relative to the output folder: one, or one per mip level for PNG/TGA.
    std::vector<std::string> paths;
    ExportFormat format = ExportFormat::Png8;
    std::optional<DdsCompression> compression;
    std::string storage;    // "uint8", "uint16", "half", "float", "bc4", ...
    int storedChannels = 0; // channels in the file (>= channels.size() where a format pads)
    std::vector<ExportedChannel> channels;
    std::vector<std::pair<int, int>> mipSizes;
    std::vector<std::string> notes;
};

/// What one export produced (and what bake.json says).
struct ExportResult {
    std::vector<ExportedFile> files;
    std::string manifestPath; // "bake.json", relative to the output folder
    nlohmann::json manifest;  // bake.json's content
    /// Every path written, absolute or as given under outDir.
    std::vector<std::filesystem::path> written;
    /// What exportBake cleaned up after killed runs in outDir first (recoverStaging's notes).
    std::vector<std::string> notes;
};

/// The file set of an export without writing anything: names, format and precision checks (no
/// texel is read, so a bakeShape() is enough). Errors: a method whose roles the preset does not
/// store, an unknown or out-of-range parameter, a compression that cannot hold a file's channels,
/// a Toksvig normal (its length is the variance) in a block-compressed or two-channel file, a
/// high-precision texture in an 8-bit format without allowEightBit, textures of one file with
/// different mip chains, a detail texture without its DetailRecord (or a record without the
/// texture), a preset that has a file named "detail" of its own.
Result<ExportResult> planExport(const BakeOutput& bake, const Preset& preset, const ExportOptions& options,
                                const BakeRecord& record = {});

/// The roles an export stores only as 8- or 16-bit codes or half floats (every file that reads the
/// role is a PNG, TGA, 16-bit TIFF, half EXR or DDS of one kind, and none flips it; a DDS file
/// takes 8-bit codes, or half floats for rgba16f):
/// BakeOptions::storage for a bake made only to be exported, which then holds a quarter (8-bit) or
/// half (16-bit, half) of the float textures' memory and exports the same bytes. `shape` is bakeShape's.
/// Empty when the plan fails.
std::map<TextureRole, TexelStorage> compactStorage(const BakeOutput& shape, const Preset& preset,
                                                   const ExportOptions& options,
                                                   const BakeRecord& record = {});

/// Writes the files of planExport and `bake.json` into `outDir` (which must exist) as one set
/// (files.h's commitSet): staged in a private folder, bake.json removed first and written last, so a
/// folder with a bake.json holds a complete set; with Overwrite::Allow the files the previous
/// bake.json names that this set does not write are removed. Interrupted commits of killed runs
/// in outDir are finished first (recoverStaging). If any target exists and overwrite is Refuse,
/// nothing is written. A failure leaves no temporary file: staged files are removed, and files
/// renamed before a later rename failed are removed again unless they replaced an existing file.
Result<ExportResult> exportBake(const BakeOutput& bake, const Preset& preset, const ExportOptions& options,
                                const std::filesystem::path& outDir, const BakeRecord& record = {});

/// The decoder's diagnostics as JSON (as bake.json records them).
nlohmann::json diagnosticsJson(const NormalMapDiagnostics& diagnostics);

/// A baked mip chain (each level `channels` wide, values in [0, 1]) as DDS bytes: io/dds.h's
/// encodeDds over its levels, which must each be half their parent (rounded down, at least 1).
Result<std::string> encodeDds(const std::vector<TextureMip>& mips, int channels, DdsCompression compression);

} // namespace burnish
