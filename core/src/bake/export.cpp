#include <burnish/core/bake/export.h>

#include "io/png_encode.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

namespace burnish {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

/// Where one channel of a file comes from: a baked texture's channel (flipped for the DirectX
/// convention), or a constant or parameter value.
struct Source {
    const BakedTexture* texture = nullptr;
    int index = 0;
    bool flip = false;
    float value = 0.0f;

    /// The stored value of texel t of level k, in [0, 1] (a texture kept as codes gives its
    /// code's value: compactStorage keeps codes only for files that store those codes).
    float at(size_t k, size_t t) const {
        if (!texture) return value;
        const size_t i = t * size_t(texture->channels) + size_t(index);
        const TextureMip& mip = texture->mips[k];
        float v = 0.0f;
        switch (texture->storage) {
        case TexelStorage::Unorm8:
            v = float(mip.unorm8[i]) / 255.0f;
            break;
        case TexelStorage::Unorm16:
            v = float(mip.unorm16[i]) / 65535.0f;
            break;
        case TexelStorage::Half: {
            Imath::half h;
            h.setBits(mip.halfBits[i]);
            v = float(h);
            break;
        }
        case TexelStorage::Float:
            v = std::clamp(mip.texels[i], 0.0f, 1.0f);
            break;
        }
        return flip ? 1.0f - v : v;
    }
};

/// How many values level k of a texture holds, in whichever array its storage uses.
size_t storedValueCount(const BakedTexture& texture, size_t k) {
    const TextureMip& mip = texture.mips[k];
    switch (texture.storage) {
    case TexelStorage::Unorm8:
        return mip.unorm8.size();
    case TexelStorage::Unorm16:
        return mip.unorm16.size();
    case TexelStorage::Half:
        return mip.halfBits.size();
    case TexelStorage::Float:
        break;
    }
    return mip.texels.size();
}

/// One file of the plan: its channels' sources (before any format padding), read straight from
/// the bake when each level is encoded, so no packed copy of the bake is ever held.
struct PlannedFile {
    ExportedFile info;
    std::vector<Source> sources;

    int channels() const { return int(sources.size()); }
};

struct Plan {
    ExportResult result;
    std::vector<PlannedFile> files;
};

// Channels whose sign follows the green convention (flipsWithGreen in their method-table rows):
// flipping y negates them. Each decodes symmetrically (bias = −scale/2), so the negated value is
// stored as 1 − v.
bool flipsWithGreen(TextureRole role, const std::string& channel) {
    for (const ChannelSpec& c : textureSpec(role).channels)
        if (c.name == channel) return c.flipsWithGreen;
    return false;
}

std::string storageName(ExportFormat format, std::optional<DdsCompression> compression) {
    switch (format) {
    case ExportFormat::Png8:
    case ExportFormat::Tga:
        return "uint8";
    case ExportFormat::Png16:
    case ExportFormat::Tiff16:
        return "uint16";
    case ExportFormat::ExrHalf:
        return "half";
    case ExportFormat::ExrFloat:
    case ExportFormat::TiffFloat:
        return "float";
    case ExportFormat::Dds:
        if (compression == DdsCompression::Rgba16f) return "half";
        return compression && *compression != DdsCompression::Rgba8
                   ? std::string(ddsCompressionName(*compression))
                   : std::string("uint8");
    }
    return "uint8";
}

bool onePerMip(ExportFormat format) {
    return format == ExportFormat::Png8 || format == ExportFormat::Png16 || format == ExportFormat::Tga;
}

int storedChannelCount(ExportFormat format, std::optional<DdsCompression> compression, int channels) {
    if (format == ExportFormat::Dds) {
        switch (*compression) {
        case DdsCompression::Bc4:
            return 1;
        case DdsCompression::Bc5:
            return 2;
        case DdsCompression::Bc3:
        case DdsCompression::Rgba8:
        case DdsCompression::Rgba16f:
            return 4;
        }
    }
    // TGA holds grey, RGB or RGBA: a two-channel file gets B = 0.
    if (format == ExportFormat::Tga && channels == 2) return 3;
    return channels;
}

Json decodeJson(const ExportedChannel& c, int index) {
    static const char* kNames[] = {"R", "G", "B", "A"};
    Json j;
    j["channel"] = kNames[index];
    j["source"] = c.source;
    if (!c.role.empty()) j["role"] = c.role;
    if (c.value) j["value"] = *c.value;
    j["scale"] = c.decode.scale;
    j["bias"] = c.decode.bias;
    return j;
}

// The file a bake's detail texture goes to, beside the preset's own: every channel as baked.
constexpr const char* kDetailFileName = "detail";

/// `withValues`: also check that the bake holds every level's values (exportBake); planExport
/// needs only the names and sizes (bakeShape gives it textures without values).
// The preset's parameters: its defaults with the options' values, each checked against its range.
Result<std::map<std::string, double>> resolveParameters(const Preset& preset, const ExportOptions& options) {
    std::map<std::string, double> parameters;
    for (const auto& p : preset.parameters)
        parameters[p.name] = p.defaultValue;
    for (const auto& [name, value] : options.parameters) {
        const PresetParameter* p = preset.findParameter(name);
        if (!p) {
            std::string known;
            for (const auto& q : preset.parameters)
                known += (known.empty() ? "" : ", ") + q.name;
            return Error{"preset '" + preset.name + "' has no parameter '" + name + "' (" +
                         (known.empty() ? std::string("it has none") : "it has: " + known) + ")"};
        }
        if (!(value >= p->minValue && value <= p->maxValue))
            return Error{"parameter '" + name + "' must lie in [" + std::to_string(p->minValue) + ", " +
                         std::to_string(p->maxValue) + "]"};
        parameters[name] = value;
    }

    return parameters;
}

// The preset's files, plus the detail file when the bake holds a detail texture.
Result<std::vector<PresetFile>> filesToWrite(const BakeOutput& bake, const Preset& preset,
                                             const BakeRecord& record) {
    std::vector<PresetFile> fileList = preset.files;
    const BakedTexture* detail = bake.find(TextureRole::Detail);
    if (detail && !record.detail)
        return Error{"the bake holds a detail texture but the record has no detail entry"};
    if (!detail && record.detail)
        return Error{"the record names a detail map but the bake holds no detail texture"};
    if (detail) {
        for (const auto& f : preset.files)
            if (f.name == kDetailFileName)
                return Error{"preset '" + preset.name +
                             "' has a file named 'detail' of its own, which the detail map's file would "
                             "replace"};
        PresetFile f;
        f.name = kDetailFileName;
        f.description = detail->description;
        for (const auto& d : detail->decode) {
            PresetChannel ch;
            ch.kind = PresetChannel::Kind::Baked;
            ch.role = roleName(detail->role);
            ch.channel = d.name;
            f.channels.push_back(std::move(ch));
        }
        // Four channels: only bc3 and rgba8 hold them; rgba8 keeps the normal's x and y exact to
        // 8 bits where BC1's 5:6:5 endpoints would not.
        f.dds = DdsCompression::Rgba8;
        fileList.push_back(std::move(f));
    }

    return fileList;
}

// A file's channels resolved to baked texture channels, constants or parameter values, into the
// file's sources and exported channels; says whether any needs high precision or holds the normal.
struct ResolvedChannels {
    bool highPrecision = false;
    bool holdsNormal = false;
};
Result<ResolvedChannels> resolveChannels(const BakeOutput& bake, const PresetFile& file, bool flipGreen,
                                         const std::map<std::string, double>& parameters, PlannedFile& pf) {
    std::vector<Source>& sources = pf.sources;
    bool highPrecision = false;
    bool holdsNormal = false;
    for (const auto& ch : file.channels) {
        Source src;
        ExportedChannel out;
        if (ch.kind == PresetChannel::Kind::Baked) {
            const std::optional<TextureRole> role = roleFromName(ch.role);
            src.texture = role ? bake.find(*role) : nullptr;
            if (!src.texture)
                return Error{"the bake has no '" + ch.role + "' texture for file '" + file.name + "'"};
            const auto& decode = src.texture->decode;
            const auto it = std::find_if(decode.begin(), decode.end(),
                                         [&](const auto& d) { return d.name == ch.channel; });
            if (it == decode.end())
                return Error{"the bake's '" + ch.role + "' texture has no channel '" + ch.channel + "'"};
            src.index = int(it - decode.begin());
            src.flip = flipGreen && flipsWithGreen(*role, ch.channel);
            // A symmetric decode maps −value to 1 − stored; anything else cannot be flipped in place.
            constexpr double kSymmetryTolerance = 1e-12;
            if (src.flip && std::abs(it->bias + 0.5 * it->scale) > kSymmetryTolerance)
                return Error{"channel '" + ch.channel + "' cannot be flipped to the DirectX convention"};
            highPrecision = highPrecision || src.texture->needsHighPrecision;
            holdsNormal = holdsNormal || *role == TextureRole::Normal;
            out.source = ch.channel;
            out.role = ch.role;
            out.decode = *it;
        } else if (ch.kind == PresetChannel::Kind::Constant) {
            src.value = float(ch.constant);
            out.source = "constant";
            out.decode = {"constant", 1.0, 0.0};
            out.value = ch.constant;
        } else {
            src.value = float(parameters.at(ch.parameter));
            out.source = ch.parameter;
            out.decode = {ch.parameter, 1.0, 0.0};
            out.value = parameters.at(ch.parameter);
        }
        sources.push_back(src);
        pf.info.channels.push_back(std::move(out));
    }

    return ResolvedChannels{highPrecision, holdsNormal};
}

// One file of the plan: every channel resolved to a baked texture channel, a constant or a
// parameter value, checked against what the storage can hold, with its mip chain and paths.
Result<PlannedFile> planFile(const BakeOutput& bake, const Preset& preset, const ExportOptions& options,
                             const PresetFile& file, bool isDetailFile, ExportFormat format,
                             const std::map<std::string, double>& parameters, bool withValues) {
    const bool flipGreen = preset.green == GreenConvention::DirectX;
    const std::string ext(exportFormatExtension(format));
    PlannedFile pf;
    pf.info.name = file.name;
    pf.info.format = format;
    if (format == ExportFormat::Dds) pf.info.compression = options.compression.value_or(file.dds);
    if (isDetailFile && pf.info.compression && file.channels.size() > 2 &&
        (*pf.info.compression == DdsCompression::Bc4 || *pf.info.compression == DdsCompression::Bc5)) {
        pf.info.notes.push_back("the detail map's four channels do not fit " +
                                std::string(ddsCompressionName(*pf.info.compression)) + ": stored as rgba8");
        pf.info.compression = DdsCompression::Rgba8;
    }

    // Resolve every channel to a baked texture channel, a constant or a parameter value.
    const auto resolved = resolveChannels(bake, file, flipGreen, parameters, pf);
    if (!resolved) return Error{resolved.error()};
    const bool highPrecision = resolved->highPrecision, holdsNormal = resolved->holdsNormal;
    std::vector<Source>& sources = pf.sources;

    // What the storage can hold.
    const bool zLast = file.channels.size() == 3 && file.channels[2].kind == PresetChannel::Kind::Baked &&
                       file.channels[2].channel == "normal.z";
    if (pf.info.compression) {
        const auto c = *pf.info.compression;
        const std::string cname(ddsCompressionName(c));
        if (c == DdsCompression::Bc4 && file.channels.size() != 1)
            return Error{"file '" + file.name + "' has " + std::to_string(file.channels.size()) +
                         " channels; bc4 holds one (use bc3 or rgba8)"};
        if (c == DdsCompression::Bc5 && !(file.channels.size() == 2 || zLast))
            return Error{"file '" + file.name + "' has " + std::to_string(file.channels.size()) +
                         " channels; bc5 holds two (a normal's x and y)"};
        // Hill 2011: run-time Toksvig reads the variance from |Na|; a two-channel normal rebuilds
        // a unit z and block compression changes the length.
        if (methodSpec(bake.method).unnormalizedNormal && holdsNormal && c != DdsCompression::Rgba8 &&
            c != DdsCompression::Rgba16f)
            return Error{"method toksvig reads the variance from the stored normal's length, which " + cname +
                         " destroys (Hill 2011); store the normal uncompressed (rgba8 or a non-DDS format)"};
        if (c == DdsCompression::Bc5 && zLast) {
            sources.pop_back();
            pf.info.channels.pop_back();
            pf.info.notes.push_back("bc5 keeps x and y; rebuild z = sqrt(max(0, 1 - x^2 - y^2))");
        }
    }
    const bool eightBit = storesEightBits(format, pf.info.compression);
    if (highPrecision && eightBit && !options.allowEightBit)
        return Error{"file '" + file.name + "' holds " + std::string(methodName(bake.method)) +
                     " moments that need 16-bit or float storage, and " +
                     std::string(exportFormatName(format)) +
                     " stores 8 bits (choose png16, tiff16, exr-half, exr-float, tiff-float or dds with "
                     "--compression rgba16f, or allow 8-bit "
                     "storage with --allow-8bit)"};
    if (highPrecision && eightBit)
        pf.info.notes.push_back("8-bit storage of a high-precision texture was allowed explicitly");
    if (flipGreen && std::any_of(sources.begin(), sources.end(), [](const Source& s) { return s.flip; }))
        pf.info.notes.push_back(
            "DirectX convention (-Y): y-odd channels are stored flipped (1 - v) and decode "
            "to the DirectX value");

    pf.info.storedChannels = storedChannelCount(format, pf.info.compression, pf.channels());
    pf.info.storage = storageName(format, pf.info.compression);

    // The file's mip chain is its textures' own (the detail map tiles at its resolution); a
    // file of constants and parameters only takes the bake's main chain.
    const BakedTexture* chain = nullptr;
    for (const auto& s : sources)
        if (s.texture && !chain) chain = s.texture;
    for (const auto& t : bake.textures)
        if (!chain && t.role != TextureRole::Detail && !t.mips.empty()) chain = &t;
    if (!chain || chain->mips.empty()) return Error{"the bake holds no texture levels"};
    const size_t levels = chain->mips.size();
    for (const auto& s : sources) {
        if (!s.texture) continue;
        bool same = s.texture->mips.size() == levels;
        for (size_t k = 0; same && k < levels; ++k)
            same = s.texture->mips[k].width == chain->mips[k].width &&
                   s.texture->mips[k].height == chain->mips[k].height;
        if (!same)
            return Error{"file '" + file.name + "' packs textures with different mip chains ('" +
                         std::string(roleName(chain->role)) + "' and '" +
                         std::string(roleName(s.texture->role)) + "')"};
    }
    for (size_t k = 0; k < levels; ++k)
        pf.info.mipSizes.emplace_back(chain->mips[k].width, chain->mips[k].height);

    // Every level's values must be there to be encoded.
    if (withValues)
        for (size_t k = 0; k < levels; ++k) {
            const size_t n = size_t(pf.info.mipSizes[k].first) * size_t(pf.info.mipSizes[k].second);
            for (const Source& src : sources)
                if (src.texture && storedValueCount(*src.texture, k) != n * size_t(src.texture->channels))
                    return Error{"the bake's '" + std::string(roleName(src.texture->role)) +
                                 "' texture has no values at mip " + std::to_string(k)};
        }

    const std::string base = options.stem + "_" + file.name;
    if (onePerMip(format))
        for (size_t k = 0; k < levels; ++k)
            pf.info.paths.push_back(k == 0 ? base + "." + ext
                                           : base + "_mip" + std::to_string(k) + "." + ext);
    else
        pf.info.paths.push_back(base + "." + ext);
    return pf;
}

// bake.json: everything needed to decode the files, and nothing that varies between runs.
Json manifestJson(const Plan& plan, const BakeOutput& bake, const Preset& preset, ExportFormat format,
                  const BakeRecord& record, const std::map<std::string, double>& parameters) {
    Json m;
    m["schema"] = "burnish-bake";
    m["version"] = 1;
    m["preset"] = {{"name", preset.name},
                   {"title", preset.title},
                   {"origin", preset.origin},
                   {"conversion", preset.conversion}};
    m["method"] = std::string(methodName(bake.method));
    m["gloss"] = {{"encoding", preset.encoding.name()},
                  {"formula", preset.encoding.formula()},
                  {"minPower", preset.encoding.minPower()},
                  {"maxPower", preset.encoding.maxPower()}};
    m["green"] = preset.green == GreenConvention::DirectX ? "directx" : "opengl";
    m["format"] = std::string(exportFormatName(format));
    m["inputs"] = record.inputs;
    m["options"] = record.options;
    if (!record.material.is_null()) m["material"] = record.material;
    Json params = Json::object();
    for (const auto& [name, value] : parameters)
        params[name] = value;
    m["parameters"] = params;
    m["decodeRule"] = "value = stored * scale + bias, stored in [0, 1]";
    Json files = Json::array();
    for (const auto& pf : plan.files) {
        Json f;
        f["name"] = pf.info.name;
        f["paths"] = pf.info.paths;
        if (pf.info.compression) f["compression"] = std::string(ddsCompressionName(*pf.info.compression));
        f["storage"] = pf.info.storage;
        f["storedChannels"] = pf.info.storedChannels;
        Json channels = Json::array();
        for (size_t c = 0; c < pf.info.channels.size(); ++c)
            channels.push_back(decodeJson(pf.info.channels[c], int(c)));
        f["channels"] = channels;
        Json sizes = Json::array();
        for (const auto& [w, h] : pf.info.mipSizes)
            sizes.push_back({w, h});
        f["mips"] = sizes;
        if (!pf.info.notes.empty()) f["notes"] = pf.info.notes;
        files.push_back(f);
    }
    m["files"] = files;
    if (record.detail) {
        // The detail file is the last one planned.
        const ExportedFile& df = plan.files.back().info;
        m["detail"] = {{"file", df.paths.front()},
                       {"input", record.detail->input},
                       {"constantVariance", record.detail->constantVariance},
                       {"fade", {record.detail->fadeStartMip, record.detail->fadeEndMip}},
                       {"mipCount", df.mipSizes.size()},
                       {"rule",
                        "blend the detail normal with reoriented normal mapping; 1/s' = 1/s + variance, "
                        "with constantVariance where the detail map is no longer sampled"}};
    }
    m["stats"] = {{"mipCount", bake.stats.mipCount},
                  {"glossClampedLow", bake.stats.glossClampedLow},
                  {"glossClampedHigh", bake.stats.glossClampedHigh}};
    if (record.diagnostics) {
        m["diagnostics"] = diagnosticsJson(*record.diagnostics);
        m["warnings"] = record.diagnostics->warnings;
    } else {
        m["warnings"] = Json::array();
    }
    return m;
}

Result<Plan> makePlan(const BakeOutput& bake, const Preset& preset, const ExportOptions& options,
                      const BakeRecord& record, bool withValues) {
    const ExportFormat format = options.format.value_or(preset.format);
    if (options.compression && format != ExportFormat::Dds)
        return Error{"a DDS compression was given but the format is " +
                     std::string(exportFormatName(format))};
    if (const Status s = checkPresetMethod(preset, bake.method); !s) return Error{s.error()};
    if (options.stem.empty() || options.stem.find('/') != std::string::npos)
        return Error{"output file stem '" + options.stem + "' must be a non-empty name without '/'"};
    auto parameters = resolveParameters(preset, options);
    if (!parameters) return Error{parameters.error()};
    auto fileList = filesToWrite(bake, preset, record);
    if (!fileList) return Error{fileList.error()};

    Plan plan;
    const bool hasDetail = bake.find(TextureRole::Detail) != nullptr;
    for (const auto& file : *fileList) {
        const bool isDetailFile = hasDetail && &file == &fileList->back();
        auto pf = planFile(bake, preset, options, file, isDetailFile, format, *parameters, withValues);
        if (!pf) return Error{pf.error()};
        plan.files.push_back(std::move(pf).value());
    }
    ExportResult& result = plan.result;
    result.manifestPath = "bake.json";
    for (const auto& pf : plan.files)
        result.files.push_back(pf.info);
    result.manifest = manifestJson(plan, bake, preset, format, record, *parameters);
    return plan;
}

// Codes are bake.h's unormCode: x + 0.5 truncated is lround(x) for x >= 0 (x = v·maxCode is
// exact in double), and the clamp is written as selects (NaN gives 0), so conversion loops
// vectorise. A texture the bake kept as codes (compactStorage) was quantized by the same function.

// The level's values in the type the format stores.
// Uninitialised on resize: pixelsOf writes every value from parallel blocks.
struct PixelData {
    OIIO::TypeDesc type;
    std::vector<std::uint8_t, TexelAllocator<std::uint8_t>> u8;
    std::vector<std::uint16_t, TexelAllocator<std::uint16_t>> u16;
    std::vector<Imath::half, TexelAllocator<Imath::half>> f16;
    TexelVector f32;
    const void* borrowed = nullptr; // the bake's own codes, when they are the file's level as it is
    const void* data() const {
        if (borrowed) return borrowed;
        return type == OIIO::TypeDesc::UINT8    ? static_cast<const void*>(u8.data())
               : type == OIIO::TypeDesc::UINT16 ? static_cast<const void*>(u16.data())
               : type == OIIO::TypeDesc::HALF   ? static_cast<const void*>(f16.data())
                                                : static_cast<const void*>(f32.data());
    }
};

// The codes a file of this format stores for its texels (8- or 16-bit codes, or half floats; a DDS
// file 8-bit codes before nvtt's compression, half floats for rgba16f), or nullopt for floats.
std::optional<TexelStorage> fileCodes(ExportFormat format, std::optional<DdsCompression> compression) {
    switch (format) {
    case ExportFormat::Png8:
    case ExportFormat::Tga:
        return TexelStorage::Unorm8;
    case ExportFormat::Png16:
    case ExportFormat::Tiff16:
        return TexelStorage::Unorm16;
    case ExportFormat::ExrHalf:
        return TexelStorage::Half;
    case ExportFormat::Dds:
        if (!compression) return std::nullopt;
        return *compression == DdsCompression::Rgba16f ? TexelStorage::Half : TexelStorage::Unorm8;
    case ExportFormat::ExrFloat:
    case ExportFormat::TiffFloat:
        break;
    }
    return std::nullopt;
}

// Whether the file stores one baked texture's channels unchanged and in order, `stored` of them.
bool storesOneTextureInOrder(const PlannedFile& file, int stored) {
    const size_t channels = file.sources.size();
    bool inOrder = channels == size_t(stored) && channels > 0 && file.sources[0].texture &&
                   file.sources[0].texture->channels == stored;
    for (size_t c = 0; inOrder && c < channels; ++c)
        inOrder = file.sources[c].texture == file.sources[0].texture && file.sources[c].index == int(c) &&
                  !file.sources[c].flip;
    return inOrder;
}

// Texels [begin, end) of level k of the file, read from its sources and converted by `code` into
// out (texel `begin` first); `stored` channels per texel, those past the file's own zero (TGA's blue
// of a two-channel file).
template <class T, class Code>
void convertTexels(const PlannedFile& file, size_t k, int stored, size_t begin, size_t end, T* out,
                   const Code& code) {
    const size_t channels = file.sources.size();
    // The codes a compact texture holds, for this file's type: copied as they are.
    auto codesOf = [&](const BakedTexture& tex) -> const T* { // k is unused for float files
        if constexpr (std::is_same_v<T, std::uint8_t>) {
            if (tex.storage == TexelStorage::Unorm8) return tex.mips[k].unorm8.data();
        } else if constexpr (std::is_same_v<T, std::uint16_t>) {
            if (tex.storage == TexelStorage::Unorm16) return tex.mips[k].unorm16.data();
        } else if constexpr (std::is_same_v<T, Imath::half>) {
            static_assert(sizeof(Imath::half) == sizeof(std::uint16_t));
            if (tex.storage == TexelStorage::Half)
                return reinterpret_cast<const Imath::half*>(tex.mips[k].halfBits.data());
        }
        return nullptr;
    };
    bool contiguous = storesOneTextureInOrder(file, stored);
    // A compact texture in a file of another depth is read through Source::at (compactStorage
    // never plans one; this keeps a hand-made BakeOutput correct).
    contiguous = contiguous && (file.sources[0].texture->storage == TexelStorage::Float ||
                                codesOf(*file.sources[0].texture) != nullptr);
    if (contiguous) { // one texture's channels in order: a flat loop the compiler vectorises
        const size_t count = (end - begin) * size_t(stored);
        if (const T* codes = codesOf(*file.sources[0].texture)) {
            std::copy(codes + begin * size_t(stored), codes + begin * size_t(stored) + count, out);
            return;
        }
        const float* in = file.sources[0].texture->mips[k].texels.data() + begin * size_t(stored);
        for (size_t i = 0; i < count; ++i)
            out[i] = code(in[i]); // code clamps
        return;
    }
    for (size_t c = 0; c < size_t(stored); ++c) {
        T* o = out + c;
        const Source* source = c < channels ? &file.sources[c] : nullptr;
        if (!source || !source->texture) { // a constant channel, or the format's padding
            const auto constant = code(source ? source->at(k, 0) : 0.0f);
            for (size_t t = begin; t < end; ++t)
                o[(t - begin) * size_t(stored)] = constant;
            continue;
        }
        // Source::at with its texture and stride hoisted out of the loop (same values; code
        // clamps, and a flipped value is clamped before 1 − v as at() does).
        const size_t stride = size_t(source->texture->channels);
        if (const T* codes = codesOf(*source->texture); codes && !source->flip) {
            codes += size_t(source->index);
            for (size_t t = begin; t < end; ++t)
                o[(t - begin) * size_t(stored)] = codes[t * stride];
            continue;
        }
        if (source->texture->storage != TexelStorage::Float) {
            for (size_t t = begin; t < end; ++t)
                o[(t - begin) * size_t(stored)] = code(source->at(k, t));
            continue;
        }
        const float* in = source->texture->mips[k].texels.data() + size_t(source->index);
        if (source->flip)
            for (size_t t = begin; t < end; ++t)
                o[(t - begin) * size_t(stored)] = code(1.0f - std::clamp(in[t * stride], 0.0f, 1.0f));
        else
            for (size_t t = begin; t < end; ++t)
                o[(t - begin) * size_t(stored)] = code(in[t * stride]);
    }
}

// The codes as function objects, so the conversion loops inline (and vectorise) them.
constexpr auto code8 = [](float v) { return unorm8(v); };
constexpr auto code16 = [](float v) { return unorm16(v); };

// Level k of the file converted in parallel blocks of texels (convertTexels).
PixelData pixelsOf(const PlannedFile& file, size_t k, int stored, ExportFormat format) {
    PixelData p;
    // One texture's channels in order, kept as the codes this file stores: written from the bake's
    // own array, with no copy of the level.
    if (storesOneTextureInOrder(file, stored) &&
        fileCodes(format, file.info.compression) == file.sources[0].texture->storage) {
        const TextureMip& mip = file.sources[0].texture->mips[k];
        switch (file.sources[0].texture->storage) {
        case TexelStorage::Unorm8:
            p.type = OIIO::TypeDesc::UINT8, p.borrowed = mip.unorm8.data();
            return p;
        case TexelStorage::Unorm16:
            p.type = OIIO::TypeDesc::UINT16, p.borrowed = mip.unorm16.data();
            return p;
        case TexelStorage::Half:
            p.type = OIIO::TypeDesc::HALF, p.borrowed = mip.halfBits.data();
            return p;
        case TexelStorage::Float:
            break;
        }
    }
    const size_t n = size_t(file.info.mipSizes[k].first) * size_t(file.info.mipSizes[k].second);
    auto convert = [&](auto* out, auto&& code) {
        constexpr size_t kBlock = size_t(1) << 14; // texels per task: large enough to amortise
        tbb::parallel_for(size_t(0), (n + kBlock - 1) / kBlock, [&](size_t block) {
            const size_t begin = block * kBlock, end = std::min(n, (block + 1) * kBlock);
            convertTexels(file, k, stored, begin, end, out + begin * size_t(stored), code);
        });
    };
    if (format == ExportFormat::Png8 || format == ExportFormat::Tga) {
        p.type = OIIO::TypeDesc::UINT8;
        p.u8.resize(n * size_t(stored));
        convert(p.u8.data(), code8);
    } else if (format == ExportFormat::Png16 || format == ExportFormat::Tiff16) {
        p.type = OIIO::TypeDesc::UINT16;
        p.u16.resize(n * size_t(stored));
        convert(p.u16.data(), code16);
    } else if (format == ExportFormat::ExrHalf) {
        // Half as OpenImageIO would convert the floats (halfCode): the same bits, and a texture the
        // bake kept as half is copied as it is.
        p.type = OIIO::TypeDesc::HALF;
        p.f16.resize(n * size_t(stored));
        convert(p.f16.data(), [](float v) { return halfCode(v); });
    } else {
        p.type = OIIO::TypeDesc::FLOAT;
        p.f32.resize(n * size_t(stored));
        convert(p.f32.data(), [](float v) { return std::clamp(v, 0.0f, 1.0f); });
    }
    return p;
}

OIIO::TypeDesc fileType(ExportFormat format) {
    switch (format) {
    case ExportFormat::Png8:
    case ExportFormat::Tga:
    case ExportFormat::Dds:
        return OIIO::TypeDesc::UINT8;
    case ExportFormat::Png16:
    case ExportFormat::Tiff16:
        return OIIO::TypeDesc::UINT16;
    case ExportFormat::ExrHalf:
        return OIIO::TypeDesc::HALF;
    case ExportFormat::ExrFloat:
    case ExportFormat::TiffFloat:
        return OIIO::TypeDesc::FLOAT;
    }
    return OIIO::TypeDesc::UINT8;
}

/// The files a previous export's bake.json names (its files' paths), for removal of those the new
/// set does not write. Nothing when there is no bake.json or it cannot be read: then no file is
/// removed. commitSet removes only plain names inside the folder.
std::vector<fs::path> previousSetFiles(const fs::path& index) {
    std::vector<fs::path> files;
    auto text = readFile(index);
    if (!text) return files;
    const Json old = Json::parse(*text, nullptr, false);
    if (old.is_discarded() || !old.is_object() || !old.contains("files") || !old["files"].is_array())
        return files;
    for (const auto& f : old["files"]) {
        if (!f.is_object() || !f.contains("paths") || !f["paths"].is_array()) continue;
        for (const auto& p : f["paths"])
            if (p.is_string()) files.push_back(index.parent_path() / p.get<std::string>());
    }
    return files;
}

/// Writes level k of a PNG file to `staging` with core's parallel encoder: libpng compresses one
/// file on one core, and a 4096² level was the longest single step of a bake.
Status writePng(const PlannedFile& file, size_t k, const fs::path& target, const fs::path& staging) {
    const ExportFormat format = file.info.format;
    PngPixels png;
    png.width = file.info.mipSizes[k].first;
    png.height = file.info.mipSizes[k].second;
    png.channels = file.info.storedChannels;
    png.bitDepth = format == ExportFormat::Png16 ? 16 : 8;
    // Rows are converted by the encoder's own tasks, segment by segment, into a buffer each reuses:
    // no converted copy of the whole level is made (for a 4096² RGB16 level, 96 MiB less to
    // allocate, fault in and read back).
    const size_t width = size_t(png.width);
    const int stored = png.channels;
    png.rows = [&file, k, width, stored, eight = png.bitDepth == 8](size_t y0, size_t y1, void* out) {
        if (eight)
            convertTexels(file, k, stored, y0 * width, y1 * width, static_cast<std::uint8_t*>(out), code8);
        else
            convertTexels(file, k, stored, y0 * width, y1 * width, static_cast<std::uint16_t*>(out), code16);
    };
    const auto bytes = encodePng(png);
    if (!bytes) return Error{"cannot write '" + target.string() + "': " + bytes.error()};
    return writeNewFile(staging, *bytes, target);
}

/// Writes levels [first, last) of a file through OpenImageIO to `staging`; the plugin is chosen
/// from `target`'s extension.
Status writeOiio(const PlannedFile& file, size_t first, size_t last, const fs::path& target,
                 const fs::path& staging) {
    const ExportFormat format = file.info.format;
    auto out = OIIO::ImageOutput::create(target.string());
    if (!out) return Error{"cannot write '" + target.string() + "': " + OIIO::geterror()};
    const bool mipmapped = last - first > 1;
    const int stored = file.info.storedChannels;
    const auto [topWidth, topHeight] = file.info.mipSizes[first];
    OIIO::ImageSpec spec(topWidth, topHeight, stored, fileType(format));
    // No timestamp: OpenImageIO writes the current time into TIFF and EXR headers unless the
    // attribute is present; an empty one is left out, so output bytes depend on the data only.
    spec.attribute("DateTime", "");
    // The fourth channel is data (gloss, smoothness), not coverage: OpenImageIO must neither divide
    // the colour by it on write (PNG) nor mark it associated (TIFF ExtraSamples).
    spec.alpha_channel = -1;
    spec.attribute("oiio:UnassociatedAlpha", 1);
    const bool exr = format == ExportFormat::ExrHalf || format == ExportFormat::ExrFloat;
    if (mipmapped) {
        // Both plugins take MIP levels only for "Plain Texture" files (what maketx writes).
        spec.attribute("textureformat", "Plain Texture");
        if (exr) {
            // OpenEXR MIP maps are tiled; 64² tiles keep small levels small. Level sizes round down,
            // as the bake's do (levelmode 1 = MIPMAP_LEVELS, roundingmode 0 = ROUND_DOWN).
            spec.tile_width = 64;
            spec.tile_height = 64;
            spec.attribute("openexr:levelmode", 1);
            spec.attribute("openexr:roundingmode", 0);
        }
    }
    auto fail = [&](const std::string& what) -> Status {
        std::error_code ec;
        out.reset();
        fs::remove(staging, ec);
        return Error{"cannot write '" + target.string() + "': " + what};
    };
    if (!out->open(staging.string(), spec, OIIO::ImageOutput::Create)) return fail(out->geterror());
    for (size_t k = first; k < last; ++k) {
        if (k > first) {
            OIIO::ImageSpec level = spec;
            level.width = level.full_width = file.info.mipSizes[k].first;
            level.height = level.full_height = file.info.mipSizes[k].second;
            // TIFF has no MIP levels of its own: OpenImageIO stores them as reduced-image subimages.
            const auto mode = exr ? OIIO::ImageOutput::AppendMIPLevel : OIIO::ImageOutput::AppendSubimage;
            if (!out->open(staging.string(), level, mode)) return fail(out->geterror());
        }
        const PixelData pixels = pixelsOf(file, k, stored, format);
        if (!out->write_image(pixels.type, pixels.data())) return fail(out->geterror());
    }
    if (!out->close()) return fail(out->geterror());
    out.reset();
    return syncFile(staging, target);
}

} // namespace

Json diagnosticsJson(const NormalMapDiagnostics& d) {
    return Json{{"texels", d.texels},
                {"nonFiniteTexels", d.nonFiniteTexels},
                {"zeroLengthTexels", d.zeroLengthTexels},
                {"noDataTexels", d.noDataTexels},
                {"negativeZTexels", d.negativeZTexels},
                {"offLengthTexels", d.offLengthTexels},
                {"meanStoredLength", d.meanStoredLength},
                {"zRebuilt", d.zRebuilt},
                {"alphaIgnored", d.alphaIgnored},
                {"greenFlipped", d.greenFlipped},
                {"signedValues", d.signedValues}};
}

Result<std::string> encodeDds(const std::vector<TextureMip>& mips, int channels, DdsCompression compression) {
    if (mips.empty()) return Error{"DDS: no mip levels to write"};
    if (channels < 1 || channels > 4) return Error{"DDS: a texture needs 1 to 4 channels"};
    for (size_t k = 0; k < mips.size(); ++k) {
        const auto& m = mips[k];
        if (k > 0 && (m.width != std::max(1, mips[k - 1].width / 2) ||
                      m.height != std::max(1, mips[k - 1].height / 2)))
            return Error{"DDS: mip " + std::to_string(k) + " is not half of mip " + std::to_string(k - 1)};
        if (m.texels.size() != size_t(m.width) * size_t(m.height) * size_t(channels))
            return Error{"DDS: mip " + std::to_string(k) + " has the wrong number of values"};
    }
    return encodeDds(mips[0].width, mips[0].height, int(mips.size()), channels, compression,
                     [&](size_t k, size_t begin, size_t end, float* out) {
                         std::copy(mips[k].texels.begin() + std::ptrdiff_t(begin * size_t(channels)),
                                   mips[k].texels.begin() + std::ptrdiff_t(end * size_t(channels)), out);
                     });
}

Result<ExportResult> planExport(const BakeOutput& bake, const Preset& preset, const ExportOptions& options,
                                const BakeRecord& record) {
    auto plan = makePlan(bake, preset, options, record, false);
    if (!plan) return Error{plan.error()};
    return std::move(plan.value().result);
}

Result<ExportResult> exportBake(const BakeOutput& bake, const Preset& preset, const ExportOptions& options,
                                const fs::path& outDir, const BakeRecord& record) {
    auto planned = makePlan(bake, preset, options, record, true);
    if (!planned) return Error{planned.error()};
    Plan& plan = planned.value();

    std::error_code ec;
    if (!fs::is_directory(outDir, ec)) return Error{"output folder '" + outDir.string() + "' does not exist"};

    // One writer at a time in this folder (FolderLock), from the checks below until the commit: a second
    // bake into it waits, so neither leaves a mixed set nor removes the other's bake.json.
    auto lock = FolderLock::acquire(outDir);
    if (!lock) return Error{lock.error()};

    // Staging folders and temporaries that killed runs left here: an interrupted commit is finished
    // first, so the old set this one replaces is whole.
    const StagingRecovery recovered = recoverStaging(outDir);
    plan.result.notes = recovered.notes;

    // Every target first: if one exists and may not be replaced, nothing is written.
    struct Target {
        fs::path path;
        fs::path staging;
        const PlannedFile* file = nullptr; // nullptr: bake.json
        size_t mip = 0;                    // first level written (one-file-per-level formats)
    };
    std::vector<Target> targets;
    for (const auto& pf : plan.files)
        for (size_t i = 0; i < pf.info.paths.size(); ++i)
            targets.push_back({outDir / pf.info.paths[i], {}, &pf, i});
    const fs::path index = outDir / plan.result.manifestPath;
    targets.push_back({index, {}, nullptr, 0});
    for (auto& t : targets)
        if (options.overwrite == Overwrite::Refuse && fs::exists(fs::symlink_status(t.path, ec)))
            return Error{"refusing to overwrite existing file '" + t.path.string() + "'"};

    // Stage: every file in one private folder. Files and PNG/TGA levels are independent, so they
    // are written in parallel (the zlib/EXR encoding dominates large bakes); DDS files go through
    // nvtt one at a time.
    auto staging = StagingFolder::create(outDir);
    if (!staging) return Error{staging.error()};
    for (auto& t : targets)
        t.staging = staging.value().fileFor(t.path);
    std::vector<Status> staged(targets.size());
    auto stage = [&](size_t i) {
        const Target& t = targets[i];
        if (!t.file) {
            staged[i] = writeNewFile(t.staging, plan.result.manifest.dump(2) + "\n", t.path);
        } else if (t.file->info.format == ExportFormat::Dds) {
            // Read from the bake a block at a time: no float copy of the file's chain.
            const PlannedFile& file = *t.file;
            const auto bytes =
                encodeDds(file.info.mipSizes[0].first, file.info.mipSizes[0].second,
                          int(file.info.mipSizes.size()), file.channels(), *file.info.compression,
                          [&file](size_t k, size_t begin, size_t end, float* out) {
                              const size_t channels = file.sources.size();
                              for (size_t texel = begin; texel < end; ++texel)
                                  for (size_t c = 0; c < channels; ++c)
                                      out[(texel - begin) * channels + c] = file.sources[c].at(k, texel);
                          });
            staged[i] = bytes ? writeNewFile(t.staging, *bytes, t.path)
                              : Status(Error{"cannot write '" + t.path.string() + "': " + bytes.error()});
        } else if (t.file->info.format == ExportFormat::Png8 || t.file->info.format == ExportFormat::Png16) {
            staged[i] = writePng(*t.file, t.mip, t.path, t.staging);
        } else if (onePerMip(t.file->info.format)) {
            staged[i] = writeOiio(*t.file, t.mip, t.mip + 1, t.path, t.staging);
        } else {
            staged[i] = writeOiio(*t.file, 0, t.file->info.mipSizes.size(), t.path, t.staging);
        }
    };
    auto isDds = [&](const Target& t) { return t.file && t.file->info.format == ExportFormat::Dds; };
    tbb::parallel_for(size_t(0), targets.size(), [&](size_t i) {
        if (!isDds(targets[i])) stage(i);
    });
    for (size_t i = 0; i < targets.size(); ++i)
        if (isDds(targets[i])) stage(i);
    for (const Status& s : staged)
        if (!s) return Error{s.error()};

    // Commit as one set: the old bake.json goes first, the new one last; files the previous set
    // wrote (its bake.json names them) that this one does not are removed, so exactly the new set
    // is left.
    SetCommit commit;
    commit.index = index;
    commit.overwrite = options.overwrite;
    if (options.overwrite == Overwrite::Allow) commit.obsolete = previousSetFiles(index);
    std::vector<StagedFile> files;
    for (const auto& t : targets)
        files.push_back({t.staging, t.path});
    if (const Status s = commitSet(staging.value(), files, commit); !s) return Error{s.error()};
    for (const auto& t : targets)
        plan.result.written.push_back(t.path);
    return std::move(plan.result);
}

std::map<TextureRole, TexelStorage> compactStorage(const BakeOutput& shape, const Preset& preset,
                                                   const ExportOptions& options, const BakeRecord& record) {
    std::map<TextureRole, TexelStorage> storage;
    const auto plan = makePlan(shape, preset, options, record, false);
    if (!plan) return storage;                               // the export will say why; the bake stays float
    std::map<TextureRole, std::optional<TexelStorage>> uses; // nullopt: some use needs floats
    for (const PlannedFile& f : plan->files)
        for (const Source& s : f.sources) {
            if (!s.texture) continue;
            // Codes only where this file would store exactly those codes: an unflipped channel.
            const std::optional<TexelStorage> want =
                s.flip ? std::nullopt : fileCodes(f.info.format, f.info.compression);
            const auto [it, first] = uses.emplace(s.texture->role, want);
            if (!first && it->second != want) it->second.reset();
        }
    for (const auto& [role, use] : uses)
        if (use && role != TextureRole::Detail) storage[role] = *use;
    return storage;
}

} // namespace burnish
