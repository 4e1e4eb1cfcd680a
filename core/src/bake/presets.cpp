#include <burnish/core/bake/presets.h>

#include <burnish/core/bake/bake.h>
#include <burnish/core/util/files.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>

namespace burnish {

namespace resources {
// Embedded by core/CMakeLists.txt from resources/presets/<name>.json.
extern const std::string_view kPreset_blackops;
extern const std::string_view kPreset_exp2;
extern const std::string_view kPreset_gltf;
extern const std::string_view kPreset_unreal;
extern const std::string_view kPreset_unity;
extern const std::string_view kPreset_godot;
extern const std::string_view kPreset_filament;
extern const std::string_view kPreset_toksvig_map;
extern const std::string_view kPreset_lean;
extern const std::string_view kPreset_clean;
extern const std::string_view kPreset_mixture;
} // namespace resources

namespace {

using Json = nlohmann::json;

struct FormatInfo {
    ExportFormat format;
    const char* name;
    const char* extension;
    bool eightBit;
};

constexpr std::array<FormatInfo, 8> kFormats{{
    {ExportFormat::Png8, "png8", "png", true},
    {ExportFormat::Png16, "png16", "png", false},
    {ExportFormat::Tga, "tga", "tga", true},
    {ExportFormat::ExrHalf, "exr-half", "exr", false},
    {ExportFormat::ExrFloat, "exr-float", "exr", false},
    {ExportFormat::Tiff16, "tiff16", "tif", false},
    {ExportFormat::TiffFloat, "tiff-float", "tif", false},
    {ExportFormat::Dds, "dds", "dds", true},
}};

struct CompressionInfo {
    DdsCompression compression;
    const char* name;
};

constexpr std::array<CompressionInfo, 5> kCompressions{{
    {DdsCompression::Bc4, "bc4"},
    {DdsCompression::Bc5, "bc5"},
    {DdsCompression::Bc3, "bc3"},
    {DdsCompression::Rgba8, "rgba8"},
    {DdsCompression::Rgba16f, "rgba16f"},
}};

template <class Names> std::string joinNames(const Names& names) {
    std::string out;
    for (const auto& n : names)
        out += (out.empty() ? "" : ", ") + std::string(n);
    return out;
}

std::string typeName(const Json& j) {
    return j.type_name();
}

// Strict field access: every error names the preset's origin and the field's path.
class Fields {
public:
    Fields(const Json& object, std::string where, const std::string& origin)
        : m_object(object)
        , m_where(std::move(where))
        , m_origin(origin) {}

    Error error(const std::string& what) const {
        return Error{"preset " + m_origin + ": " + (m_where.empty() ? "" : m_where + ": ") + what};
    }

    /// Fails on a field not in `known`.
    Status onlyKnown(std::initializer_list<const char*> known) const {
        for (const auto& [key, value] : m_object.items()) {
            bool found = false;
            for (const char* k : known)
                found = found || key == k;
            if (!found) return error("unknown field '" + key + "' (known: " + joinNames(known) + ")");
        }
        return {};
    }

    const Json* find(const char* key) const {
        const auto it = m_object.find(key);
        return it == m_object.end() ? nullptr : &*it;
    }

    Result<std::string> string(const char* key, bool required = true, std::string fallback = {}) const {
        const Json* j = find(key);
        if (!j) {
            if (required) return error("missing field '" + std::string(key) + "'");
            return fallback;
        }
        if (!j->is_string()) return error("'" + std::string(key) + "' must be a string, not " + typeName(*j));
        return j->get<std::string>();
    }

    Result<double> number(const char* key, bool required, double fallback = 0.0) const {
        const Json* j = find(key);
        if (!j) {
            if (required) return error("missing field '" + std::string(key) + "'");
            return fallback;
        }
        if (!j->is_number()) return error("'" + std::string(key) + "' must be a number, not " + typeName(*j));
        const double v = j->get<double>();
        if (!std::isfinite(v)) return error("'" + std::string(key) + "' must be finite");
        return v;
    }

    Result<const Json*> array(const char* key, bool required = true) const {
        const Json* j = find(key);
        if (!j) {
            if (required) return error("missing field '" + std::string(key) + "'");
            static const Json empty = Json::array();
            return &empty;
        }
        if (!j->is_array()) return error("'" + std::string(key) + "' must be an array, not " + typeName(*j));
        return j;
    }

    const std::string& where() const { return m_where; }

private:
    const Json& m_object;
    std::string m_where;
    const std::string& m_origin;
};

// A file name part that is safe on every file system and in a shell: letters, digits, '-', '_'.
bool safeFileName(const std::string& name) {
    if (name.empty() || name.size() > 64) return false;
    return std::all_of(name.begin(), name.end(), [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
               c == '_';
    });
}

// parameters[i]: a name, a description, a default and a range inside [0, 1], not declared before.
Result<PresetParameter> parseParameter(const Json& pj, size_t i, const std::string& origin, const Fields& top,
                                       const Preset& preset) {
    const std::string where = "parameters[" + std::to_string(i) + "]";
    if (!pj.is_object()) return top.error(where + " must be an object");
    const Fields pf(pj, where, origin);
    if (const Status s = pf.onlyKnown({"name", "description", "default", "min", "max"}); !s)
        return Error{s.error()};
    PresetParameter p;
    auto name = pf.string("name");
    auto description = pf.string("description");
    auto def = pf.number("default", true);
    auto lo = pf.number("min", false, 0.0);
    auto hi = pf.number("max", false, 1.0);
    for (const std::string* e : {&name.error(), &description.error(), &def.error(), &lo.error(), &hi.error()})
        if (!e->empty()) return Error{*e};
    p.name = *name;
    p.description = *description;
    p.defaultValue = *def;
    p.minValue = *lo;
    p.maxValue = *hi;
    if (!safeFileName(p.name)) return pf.error("'name' must be letters, digits, '-' or '_'");
    // Parameters are stored in unsigned normalized channels: their range must lie in [0, 1].
    if (!(p.minValue >= 0.0 && p.minValue <= p.maxValue && p.maxValue <= 1.0))
        return pf.error("'min' and 'max' must satisfy 0 <= min <= max <= 1");
    if (!(p.defaultValue >= p.minValue && p.defaultValue <= p.maxValue))
        return pf.error("'default' must lie in [min, max]");
    if (preset.findParameter(p.name)) return pf.error("duplicate parameter '" + p.name + "'");
    return p;
}

// One channel of a file: a baked role and channel, a constant, or a declared parameter.
Result<PresetChannel> parseChannel(const Json& cj, const std::string& cwhere, const std::string& origin,
                                   const Fields& top, const Preset& preset) {
    if (!cj.is_object()) return top.error(cwhere + " must be an object");
    const Fields cf(cj, cwhere, origin);
    if (const Status s = cf.onlyKnown({"role", "channel", "constant", "parameter"}); !s)
        return Error{s.error()};
    PresetChannel ch;
    const bool baked = cf.find("role") || cf.find("channel");
    const int kinds = int(baked) + int(cf.find("constant") != nullptr) + int(cf.find("parameter") != nullptr);
    if (kinds != 1) return cf.error("give exactly one of 'role' + 'channel', 'constant' or 'parameter'");
    if (baked) {
        auto role = cf.string("role");
        auto channel = cf.string("channel");
        if (!role) return Error{role.error()};
        if (!channel) return Error{channel.error()};
        ch.kind = PresetChannel::Kind::Baked;
        ch.role = *role;
        ch.channel = *channel;
    } else if (cf.find("constant")) {
        auto value = cf.number("constant", true);
        if (!value) return Error{value.error()};
        // Constants are stored values of an unsigned normalized channel.
        if (!(*value >= 0.0 && *value <= 1.0)) return cf.error("'constant' must lie in [0, 1]");
        ch.kind = PresetChannel::Kind::Constant;
        ch.constant = *value;
    } else {
        auto parameter = cf.string("parameter");
        if (!parameter) return Error{parameter.error()};
        if (!preset.findParameter(*parameter))
            return cf.error("unknown parameter '" + *parameter + "' (declared: " +
                            (preset.parameters.empty() ? std::string("none") : [&] {
                                std::vector<std::string> names;
                                for (const auto& p : preset.parameters) names.push_back(p.name);
                                return joinNames(names);
                            }()) +
                            ")");
        ch.kind = PresetChannel::Kind::Parameter;
        ch.parameter = *parameter;
    }
    return ch;
}

// files[i]: a unique safe name, a DDS compression and 1 to 4 channels it can hold.
Result<PresetFile> parseFile(const Json& fj, size_t i, const std::string& origin, const Fields& top,
                             const Preset& preset, std::set<std::string>& fileNames) {
    const std::string where = "files[" + std::to_string(i) + "]";
    if (!fj.is_object()) return top.error(where + " must be an object");
    const Fields ff(fj, where, origin);
    if (const Status s = ff.onlyKnown({"name", "description", "dds", "channels"}); !s)
        return Error{s.error()};
    PresetFile file;
    auto name = ff.string("name");
    if (!name) return Error{name.error()};
    file.name = *name;
    if (!safeFileName(file.name))
        return ff.error("'name' \"" + file.name + "\" must be 1-64 letters, digits, '-' or '_'");
    if (!fileNames.insert(file.name).second) return ff.error("duplicate file name '" + file.name + "'");
    auto description = ff.string("description", false);
    if (!description) return Error{description.error()};
    file.description = *description;
    auto dds = ff.string("dds");
    if (!dds) return Error{dds.error()};
    const auto c = ddsCompressionFromName(*dds);
    if (!c) return ff.error("'dds': " + c.error());
    file.dds = *c;

    const auto channels = ff.array("channels");
    if (!channels) return Error{channels.error()};
    // Texture files hold one to four channels (R, G, B, A).
    if ((*channels)->empty() || (*channels)->size() > 4)
        return ff.error("'channels' must list 1 to 4 channels");
    for (size_t k = 0; k < (*channels)->size(); ++k) {
        const Json& cj = (**channels)[k];
        const std::string cwhere = where + ".channels[" + std::to_string(k) + "]";
        auto ch = parseChannel(cj, cwhere, origin, top, preset);
        if (!ch) return Error{ch.error()};
        file.channels.push_back(std::move(ch).value());
    }

    // The DDS compression must be able to hold the file's channels.
    const size_t n = file.channels.size();
    const bool zLast = n == 3 && file.channels[2].kind == PresetChannel::Kind::Baked &&
                       file.channels[2].channel == "normal.z";
    if (file.dds == DdsCompression::Bc4 && n != 1) return ff.error("'dds': bc4 holds exactly one channel");
    if (file.dds == DdsCompression::Bc5 && !(n == 2 || zLast))
        return ff.error("'dds': bc5 holds two channels (or a normal whose z it drops)");
    return file;
}

// Parses the preset without the method-dependent checks.
Result<Preset> parseFields(const Json& root, const std::string& origin) {
    if (!root.is_object()) return Error{"preset " + origin + ": the top level must be a JSON object"};
    const Fields top(root, "", origin);

    // The version is checked first, so a newer file says so rather than naming a field it added.
    const Json* version = top.find("version");
    if (!version) return top.error("missing field 'version'");
    if (!version->is_number_integer()) return top.error("'version' must be an integer");
    const int v = version->get<int>();
    if (v > kPresetVersion)
        return top.error("version " + std::to_string(v) + " is newer than this burnish reads (" +
                         std::to_string(kPresetVersion) + ")");
    if (v < 1) return top.error("version must be >= 1");

    if (const Status s =
            top.onlyKnown({"schema", "version", "name", "title", "description", "conversion", "gloss",
                           "method", "green", "specular", "format", "parameters", "files", "notes"});
        !s)
        return Error{s.error()};
    const auto schema = top.string("schema");
    if (!schema) return Error{schema.error()};
    if (*schema != "burnish-preset")
        return top.error("'schema' must be \"burnish-preset\", not \"" + *schema + "\"");

    Preset preset;
    preset.version = v;
    preset.origin = origin;
    for (auto [key, dest] :
         {std::pair{"name", &preset.name}, std::pair{"title", &preset.title},
          std::pair{"description", &preset.description}, std::pair{"conversion", &preset.conversion}}) {
        auto s = top.string(key);
        if (!s) return Error{s.error()};
        *dest = std::move(s.value());
    }
    if (!safeFileName(preset.name))
        return top.error("'name' \"" + preset.name + "\" must be 1-64 letters, digits, '-' or '_'");

    const auto gloss = top.string("gloss");
    if (!gloss) return Error{gloss.error()};
    auto encoding = GlossEncoding::fromName(*gloss);
    if (!encoding) return top.error("'gloss': " + encoding.error());
    preset.encoding = std::move(encoding.value());

    const auto method = top.string("method");
    if (!method) return Error{method.error()};
    const auto m = methodFromName(*method);
    if (!m) return top.error("'method': " + m.error());
    preset.method = *m;

    const auto green = top.string("green");
    if (!green) return Error{green.error()};
    if (*green == "opengl")
        preset.green = GreenConvention::OpenGL;
    else if (*green == "directx")
        preset.green = GreenConvention::DirectX;
    else
        return top.error("'green' must be \"opengl\" or \"directx\", not \"" + *green + "\"");

    if (const Json* specular = top.find("specular")) {
        if (!specular->is_string()) return top.error("'specular' must be a string");
        const auto convention = specularConventionFromName(specular->get<std::string>());
        if (!convention) return top.error("'specular': " + convention.error());
        preset.specular = *convention;
    }

    const auto format = top.string("format");
    if (!format) return Error{format.error()};
    const auto f = exportFormatFromName(*format);
    if (!f) return top.error("'format': " + f.error());
    preset.format = *f;

    const auto parameters = top.array("parameters", false);
    if (!parameters) return Error{parameters.error()};
    for (size_t i = 0; i < (*parameters)->size(); ++i) {
        const Json& pj = (**parameters)[i];
        auto p = parseParameter(pj, i, origin, top, preset);
        if (!p) return Error{p.error()};
        preset.parameters.push_back(std::move(p).value());
    }

    const auto files = top.array("files");
    if (!files) return Error{files.error()};
    if ((*files)->empty()) return top.error("'files' must list at least one file");
    std::set<std::string> fileNames;
    for (size_t i = 0; i < (*files)->size(); ++i) {
        auto file = parseFile((**files)[i], i, origin, top, preset, fileNames);
        if (!file) return Error{file.error()};
        preset.files.push_back(std::move(file).value());
    }

    const auto notes = top.array("notes", false);
    if (!notes) return Error{notes.error()};
    for (const auto& nj : **notes) {
        if (!nj.is_string()) return top.error("'notes' must be an array of strings");
        preset.notes.push_back(nj.get<std::string>());
    }
    return preset;
}

struct BuiltinSet {
    std::vector<Preset> presets;
    std::vector<std::string> errors;
};

const BuiltinSet& builtins() {
    static const BuiltinSet set = [] {
        BuiltinSet s;
        const std::array<std::pair<const char*, std::string_view>, 11> sources{{
            {"blackops", resources::kPreset_blackops},
            {"exp2", resources::kPreset_exp2},
            {"gltf", resources::kPreset_gltf},
            {"unreal", resources::kPreset_unreal},
            {"unity", resources::kPreset_unity},
            {"godot", resources::kPreset_godot},
            {"filament", resources::kPreset_filament},
            {"toksvig-map", resources::kPreset_toksvig_map},
            {"lean", resources::kPreset_lean},
            {"clean", resources::kPreset_clean},
            {"mixture", resources::kPreset_mixture},
        }};
        for (const auto& [file, text] : sources) {
            auto p = parsePreset(text, "built-in '" + std::string(file) + ".json'");
            if (!p) {
                s.errors.push_back(p.error());
                continue;
            }
            if (p->name != file) {
                s.errors.push_back("preset built-in '" + std::string(file) + ".json': 'name' is \"" +
                                   p->name + "\"; it must match the file name");
                continue;
            }
            p.value().origin = "built-in";
            s.presets.push_back(std::move(p.value()));
        }
        return s;
    }();
    return set;
}

} // namespace

const std::vector<ExportFormat>& allExportFormats() {
    static const std::vector<ExportFormat> formats = [] {
        std::vector<ExportFormat> v;
        for (const auto& f : kFormats)
            v.push_back(f.format);
        return v;
    }();
    return formats;
}

std::string_view exportFormatName(ExportFormat format) {
    for (const auto& f : kFormats)
        if (f.format == format) return f.name;
    return "unknown";
}

Result<ExportFormat> exportFormatFromName(std::string_view name) {
    for (const auto& f : kFormats)
        if (f.name == name) return f.format;
    std::vector<std::string> names;
    for (const auto& f : kFormats)
        names.emplace_back(f.name);
    return Error{"unknown format '" + std::string(name) + "' (known: " + joinNames(names) + ")"};
}

std::string_view exportFormatExtension(ExportFormat format) {
    for (const auto& f : kFormats)
        if (f.format == format) return f.extension;
    return "bin";
}

bool exportFormatIsEightBit(ExportFormat format) {
    for (const auto& f : kFormats)
        if (f.format == format) return f.eightBit;
    return true;
}

bool exportFormatUsesOpenImageIo(ExportFormat format) {
    return format != ExportFormat::Png8 && format != ExportFormat::Png16 && format != ExportFormat::Dds;
}

bool storesEightBits(ExportFormat format, std::optional<DdsCompression> compression) {
    if (format == ExportFormat::Dds && compression == DdsCompression::Rgba16f) return false;
    return exportFormatIsEightBit(format);
}

const std::vector<DdsCompression>& allDdsCompressions() {
    static const std::vector<DdsCompression> all = [] {
        std::vector<DdsCompression> v;
        for (const auto& c : kCompressions)
            v.push_back(c.compression);
        return v;
    }();
    return all;
}

std::string_view ddsCompressionName(DdsCompression compression) {
    for (const auto& c : kCompressions)
        if (c.compression == compression) return c.name;
    return "unknown";
}

Result<DdsCompression> ddsCompressionFromName(std::string_view name) {
    for (const auto& c : kCompressions)
        if (c.name == name) return c.compression;
    std::vector<std::string> names;
    for (const auto& c : kCompressions)
        names.emplace_back(c.name);
    return Error{"unknown DDS compression '" + std::string(name) + "' (known: " + joinNames(names) + ")"};
}

const PresetParameter* Preset::findParameter(std::string_view parameterName) const {
    for (const auto& p : parameters)
        if (p.name == parameterName) return &p;
    return nullptr;
}

namespace {

// Why the method's textures (its method-table row) do not fit the preset's files, or empty when they
// do: every baked channel the preset stores must be one the method bakes, and every texture the
// method bakes (except the normal, which slope methods carry in B) must be stored.
std::string presetMismatch(const Preset& preset, Method method) {
    std::set<std::string> stored;
    for (const auto& file : preset.files)
        for (const auto& ch : file.channels) {
            if (ch.kind != PresetChannel::Kind::Baked) continue;
            const std::optional<TextureRole> role = roleFromName(ch.role);
            if (!role || !hasTexture(method, *role)) return "it bakes no '" + ch.role + "' texture";
            std::vector<std::string> channels;
            for (const ChannelSpec& c : textureSpec(*role).channels)
                channels.emplace_back(c.name);
            if (std::find(channels.begin(), channels.end(), ch.channel) == channels.end())
                return "its '" + ch.role + "' texture has no channel '" + ch.channel + "' (it has " +
                       joinNames(channels) + ")";
            stored.insert(ch.role);
        }
    // A mixture preset stores lobes 0..K−1 for its K (1..4): the lobes above K are not baked.
    int lobes = 0;
    while (lobes < kMaxMixtureLobes &&
           stored.count(std::string(roleName(TextureRole(int(TextureRole::MixtureLobe0) + lobes)))))
        ++lobes;
    for (const MethodTexture& t : methodSpec(method).textures) {
        if (t.role == TextureRole::Normal || stored.count(std::string(roleName(t.role)))) continue;
        if (isMixtureLobeRole(t.role) && lobes > 0 && mixtureLobeIndex(t.role) >= lobes) continue;
        return "the preset stores none of its '" + std::string(roleName(t.role)) + "' texture";
    }
    for (int i = lobes; i < kMaxMixtureLobes; ++i)
        if (stored.count(std::string(roleName(TextureRole(int(TextureRole::MixtureLobe0) + i)))))
            return "it stores mixture lobe " + std::to_string(i) + " without lobe " + std::to_string(lobes);
    return {};
}

} // namespace

Status checkPresetMethod(const Preset& preset, Method method) {
    const std::string why = presetMismatch(preset, method);
    if (why.empty()) return {};
    std::vector<std::string> fits;
    for (Method m : compatibleMethods(preset))
        fits.emplace_back(methodName(m));
    return Error{"preset '" + preset.name + "' cannot store method " + std::string(methodName(method)) +
                 ": " + why +
                 " (methods that fit: " + (fits.empty() ? std::string("none") : joinNames(fits)) + ")"};
}

std::vector<Method> compatibleMethods(const Preset& preset) {
    std::vector<Method> out;
    for (Method m : allMethods())
        if (presetMismatch(preset, m).empty()) out.push_back(m);
    return out;
}

Result<Preset> parsePreset(std::string_view json, const std::string& origin) {
    Json root;
    try {
        root = Json::parse(json.begin(), json.end());
    } catch (const Json::exception& e) { // parse errors, and numbers out of range (out_of_range.406)
        // nlohmann's message carries the byte offset; keep only what follows its "parse error" tag.
        std::string what = e.what();
        const auto colon = what.find(": ");
        if (colon != std::string::npos) what = what.substr(colon + 2);
        return Error{"preset " + origin + ": invalid JSON: " + what};
    }
    auto preset = parseFields(root, origin);
    if (!preset) return preset;
    if (const Status s = checkPresetMethod(*preset, preset->method); !s)
        return Error{"preset " + origin + ": default method: " + s.error()};
    return preset;
}

Result<Preset> loadPresetFile(const std::filesystem::path& path) {
    const auto text = readFile(path);
    if (!text) return Error{text.error()};
    return parsePreset(*text, "'" + path.string() + "'");
}

std::vector<TextureRole> presetRoles(const Preset& preset) {
    std::vector<TextureRole> roles;
    for (const auto& file : preset.files)
        for (const auto& ch : file.channels) {
            if (ch.kind != PresetChannel::Kind::Baked) continue;
            const auto role = roleFromName(ch.role); // unknown names: checkPresetMethod refuses them
            if (role && std::find(roles.begin(), roles.end(), *role) == roles.end()) roles.push_back(*role);
        }
    return roles;
}

const std::vector<Preset>& builtinPresets() {
    return builtins().presets;
}

const std::vector<std::string>& builtinPresetErrors() {
    return builtins().errors;
}

std::vector<std::string> builtinPresetNames() {
    std::vector<std::string> names;
    for (const auto& p : builtinPresets())
        names.push_back(p.name);
    return names;
}

Result<Preset> findPreset(std::string_view nameOrPath) {
    const std::string text(nameOrPath);
    if (text.size() > 5 && text.substr(text.size() - 5) == ".json") return loadPresetFile(text);
    for (const auto& p : builtinPresets())
        if (p.name == text) return p;
    return Error{"unknown preset '" + text + "' (known: " + joinNames(builtinPresetNames()) +
                 ", or a FILE.json)"};
}

} // namespace burnish
