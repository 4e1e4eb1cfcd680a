#include <burnish/core/shading/materials.h>

#include <burnish/core/util/files.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <initializer_list>
#include <set>

namespace burnish::resources {
// resources/materials/materials.json, embedded by burnish_embed (core/CMakeLists.txt).
extern const std::string_view kMaterialsJson;
} // namespace burnish::resources

namespace burnish {

namespace {

using Json = nlohmann::json;

// Thrown inside this file only; parseMaterialTable turns it into an Error.
struct TableError {
    std::string message;
};

[[noreturn]] void failAt(const std::string& where, const std::string& what) {
    throw TableError{where.empty() ? what : where + ": " + what};
}

std::string lowerAscii(std::string_view s) {
    std::string out(s);
    for (char& c : out)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

// Messages are one line: nlohmann escapes control characters in what() already, this is a guard.
std::string oneLine(std::string s) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    std::replace(s.begin(), s.end(), '\r', ' ');
    return s;
}

const char* jsonTypeName(const Json& v) {
    if (v.is_boolean()) return "a boolean"; // before is_number: booleans are not numbers here
    if (v.is_number()) return "a number";
    if (v.is_string()) return "a string";
    if (v.is_array()) return "an array";
    if (v.is_object()) return "an object";
    return "null";
}

std::string join(const std::string& where, const std::string& key) {
    return where.empty() ? key : where + "." + key;
}

void checkObject(const Json& v, const std::string& where) {
    if (!v.is_object()) failAt(where, fmt::format("must be an object, got {}", jsonTypeName(v)));
}

// Unknown fields are errors: a misspelt "fo" must not silently drop a value.
void checkKeys(const Json& obj, std::initializer_list<const char*> allowed, const std::string& where) {
    for (const auto& item : obj.items()) {
        const std::string& key = item.key(); // a plain reference: clang 14 lambdas cannot capture bindings
        const bool known =
            std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; });
        if (!known) failAt(where, fmt::format("unknown field '{}'", key));
    }
}

const Json& field(const Json& obj, const char* key, const std::string& where) {
    const auto it = obj.find(key);
    if (it == obj.end()) failAt(where, fmt::format("missing field '{}'", key));
    return *it;
}

const Json* optionalField(const Json& obj, const char* key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
}

double readNumber(const Json& v, const std::string& where) {
    if (!v.is_number()) failAt(where, fmt::format("must be a number, got {}", jsonTypeName(v)));
    return v.get<double>();
}

int readSrgb8(const Json& v, const std::string& where) {
    if (!v.is_number_integer())
        failAt(where, fmt::format("must be an integer 8-bit sRGB code, got {}", jsonTypeName(v)));
    const auto code = v.get<long long>();
    if (code < 0 || code > 255) failAt(where, fmt::format("sRGB code {} is outside 0..255", code));
    return static_cast<int>(code);
}

std::string readString(const Json& v, const std::string& where) {
    if (!v.is_string()) failAt(where, fmt::format("must be a string, got {}", jsonTypeName(v)));
    auto s = v.get<std::string>();
    if (s.empty()) failAt(where, "must not be empty");
    return s;
}

std::pair<double, double> readNumberPair(const Json& v, const std::string& where) {
    if (!v.is_array() || v.size() != 2)
        failAt(where, fmt::format("must be an array [min, max], got {}", jsonTypeName(v)));
    return {readNumber(v[0], where + "[0]"), readNumber(v[1], where + "[1]")};
}

// A monochrome value (one number) or an [r, g, b] array.
LinearRgb readRgb(const Json& v, const std::string& where) {
    if (v.is_number()) return LinearRgb::grey(v.get<double>());
    if (!v.is_array() || v.size() != 3)
        failAt(where, fmt::format("must be a number or an array [r, g, b], got {}", jsonTypeName(v)));
    return {readNumber(v[0], where + "[0]"), readNumber(v[1], where + "[1]"),
            readNumber(v[2], where + "[2]")};
}

SpecularRange readRange(const Json& obj, const char* key, const std::string& parent) {
    const std::string where = join(parent, key);
    const Json& v = field(obj, key, parent);
    checkObject(v, where);
    checkKeys(v, {"srgb8", "linear", "publishedLinear", "source", "note"}, where);
    SpecularRange range;
    const auto [lo, hi] = readNumberPair(field(v, "linear", where), where + ".linear");
    range.linear = {lo, hi};
    if (const Json* s = optionalField(v, "srgb8")) {
        if (!s->is_array() || s->size() != 2)
            failAt(where + ".srgb8", fmt::format("must be an array [min, max], got {}", jsonTypeName(*s)));
        range.srgb8 = {readSrgb8((*s)[0], where + ".srgb8[0]"), readSrgb8((*s)[1], where + ".srgb8[1]")};
    }
    if (const Json* p = optionalField(v, "publishedLinear")) {
        const auto [plo, phi] = readNumberPair(*p, where + ".publishedLinear");
        range.publishedLinear = LinearInterval{plo, phi};
    }
    range.source = readString(field(v, "source", where), where + ".source");
    if (const Json* n = optionalField(v, "note")) range.note = readString(*n, where + ".note");
    return range;
}

ReferenceValue readReference(const Json& obj, const char* key, bool needsSrgb8) {
    const std::string where = key;
    const Json& v = field(obj, key, "");
    checkObject(v, where);
    checkKeys(v, {"srgb8", "linear", "source", "note"}, where);
    ReferenceValue ref;
    if (const Json* s = optionalField(v, "srgb8"))
        ref.srgb8 = readSrgb8(*s, where + ".srgb8");
    else if (needsSrgb8)
        failAt(where, "missing field 'srgb8'");
    ref.linear = readNumber(field(v, "linear", where), where + ".linear");
    ref.source = readString(field(v, "source", where), where + ".source");
    if (const Json* n = optionalField(v, "note")) ref.note = readString(*n, where + ".note");
    return ref;
}

// "materials[3]" or "materials[3] ('gold')" once the name is known.
std::string entryWhere(const char* list, std::size_t i, const std::string& name) {
    return name.empty() ? fmt::format("{}[{}]", list, i) : fmt::format("{}[{}] ('{}')", list, i, name);
}

Material readMaterial(const Json& v, std::size_t i) {
    std::string where = entryWhere("materials", i, "");
    checkObject(v, where);
    Material m;
    m.name = readString(field(v, "name", where), where + ".name");
    where = entryWhere("materials", i, m.name);
    checkKeys(v, {"name", "class", "f0", "f0Min", "f0Max", "source", "note"}, where);
    const std::string cls = readString(field(v, "class", where), where + ".class");
    if (cls == "dielectric")
        m.materialClass = MaterialClass::Dielectric;
    else if (cls == "metal")
        m.materialClass = MaterialClass::Metal;
    else
        failAt(where, fmt::format("class must be 'dielectric' or 'metal', got '{}'", cls));

    const Json* f0 = optionalField(v, "f0");
    const Json* f0Min = optionalField(v, "f0Min");
    const Json* f0Max = optionalField(v, "f0Max");
    if (f0 && !f0Min && !f0Max) {
        m.f0Min = m.f0Max = readRgb(*f0, where + ".f0");
    } else if (!f0 && f0Min && f0Max) {
        m.f0Min = readRgb(*f0Min, where + ".f0Min");
        m.f0Max = readRgb(*f0Max, where + ".f0Max");
    } else {
        failAt(where, "needs either 'f0' or both 'f0Min' and 'f0Max'");
    }
    m.source = readString(field(v, "source", where), where + ".source");
    if (const Json* n = optionalField(v, "note")) m.note = readString(*n, where + ".note");
    return m;
}

DiffuseAlbedo readAlbedo(const Json& v, std::size_t i) {
    std::string where = entryWhere("albedos", i, "");
    checkObject(v, where);
    DiffuseAlbedo a;
    a.name = readString(field(v, "name", where), where + ".name");
    where = entryWhere("albedos", i, a.name);
    checkKeys(v, {"name", "albedo", "albedoMin", "albedoMax", "source", "note"}, where);
    const Json* one = optionalField(v, "albedo");
    const Json* lo = optionalField(v, "albedoMin");
    const Json* hi = optionalField(v, "albedoMax");
    if (one && !lo && !hi) {
        a.albedo.min = a.albedo.max = readNumber(*one, where + ".albedo");
    } else if (!one && lo && hi) {
        a.albedo = {readNumber(*lo, where + ".albedoMin"), readNumber(*hi, where + ".albedoMax")};
    } else {
        failAt(where, "needs either 'albedo' or both 'albedoMin' and 'albedoMax'");
    }
    a.source = readString(field(v, "source", where), where + ".source");
    if (const Json* n = optionalField(v, "note")) a.note = readString(*n, where + ".note");
    return a;
}

MaterialTable readTable(const Json& root) {
    if (!root.is_object())
        failAt("materials table", fmt::format("the top level must be an object, got {}", jsonTypeName(root)));
    // The version first, so that a newer file is reported as newer, not as a list of unknown fields.
    const auto versionIt = root.find("version");
    if (versionIt == root.end()) failAt("materials table", "missing field 'version'");
    if (!versionIt->is_number_integer())
        failAt("materials table",
               fmt::format("'version' must be an integer, got {}", jsonTypeName(*versionIt)));
    const auto version = versionIt->get<long long>();
    if (version > kMaterialTableVersion)
        failAt("", fmt::format("materials table version {} is newer than this burnish reads (up to {})",
                               version, kMaterialTableVersion));
    if (version < 1)
        failAt("", fmt::format("materials table version {} is unknown (this burnish reads version {})",
                               version, kMaterialTableVersion));
    checkKeys(root, {"version", "sources", "ranges", "dielectricDefault", "midGrey", "materials", "albedos"},
              "materials table");

    MaterialTable table;
    table.version = static_cast<int>(version);

    const Json& sources = field(root, "sources", "materials table");
    checkObject(sources, "sources");
    for (const auto& [key, value] : sources.items())
        table.sources[key] = readString(value, "sources." + key);

    const Json& ranges = field(root, "ranges", "materials table");
    checkObject(ranges, "ranges");
    checkKeys(ranges, {"dielectricChart", "metalChart", "dielectricPlausible"}, "ranges");
    table.dielectricChart = readRange(ranges, "dielectricChart", "ranges");
    table.metalChart = readRange(ranges, "metalChart", "ranges");
    table.dielectricPlausible = readRange(ranges, "dielectricPlausible", "ranges");
    table.dielectricDefault = readReference(root, "dielectricDefault", false);
    table.midGrey = readReference(root, "midGrey", true);

    const Json& materials = field(root, "materials", "materials table");
    if (!materials.is_array())
        failAt("materials", fmt::format("must be an array, got {}", jsonTypeName(materials)));
    for (std::size_t i = 0; i < materials.size(); ++i)
        table.materials.push_back(readMaterial(materials[i], i));

    const Json& albedos = field(root, "albedos", "materials table");
    if (!albedos.is_array())
        failAt("albedos", fmt::format("must be an array, got {}", jsonTypeName(albedos)));
    for (std::size_t i = 0; i < albedos.size(); ++i)
        table.albedos.push_back(readAlbedo(albedos[i], i));
    return table;
}

// ---- validation of values (also for tables built in code) ----

void checkUnit(double v, const std::string& where, const std::string& what) {
    if (!std::isfinite(v)) failAt(where, fmt::format("{} is not finite", what));
    if (v < 0.0 || v > 1.0) failAt(where, fmt::format("{} = {} is outside [0, 1]", what, v));
}

void checkInterval(const LinearInterval& iv, const std::string& where, const std::string& what) {
    checkUnit(iv.min, where, what + " min");
    checkUnit(iv.max, where, what + " max");
    if (iv.min > iv.max) failAt(where, fmt::format("{} min {} > max {}", what, iv.min, iv.max));
}

void checkSource(const MaterialTable& table, const std::string& key, const std::string& where) {
    if (key.empty()) failAt(where, "missing source");
    if (!table.sources.count(key)) failAt(where, fmt::format("unknown source '{}' (not in 'sources')", key));
}

// A linear value written beside an 8-bit code must be that code's exact sRGB decode.
void checkDecode(double linear, int code, const std::string& where, const std::string& what) {
    const double exact = srgb8ToLinear(static_cast<std::uint8_t>(code));
    if (std::abs(linear - exact) > kStoredLinearTolerance)
        failAt(where, fmt::format("{} = {} does not match sRGB {} (exact decode {:.4f})", what, linear, code,
                                  exact));
}

void validateRange(const MaterialTable& table, const SpecularRange& r, const std::string& where) {
    checkInterval(r.linear, where, "linear");
    if (r.srgb8) {
        const auto [lo, hi] = *r.srgb8;
        if (lo < 0 || lo > 255 || hi < 0 || hi > 255)
            failAt(where, fmt::format("sRGB codes {}..{} are outside 0..255", lo, hi));
        if (lo > hi) failAt(where, fmt::format("srgb8 min {} > max {}", lo, hi));
        checkDecode(r.linear.min, lo, where, "linear min");
        checkDecode(r.linear.max, hi, where, "linear max");
    }
    if (r.publishedLinear) checkInterval(*r.publishedLinear, where, "publishedLinear");
    checkSource(table, r.source, where);
}

const char* channelName(int c) {
    return c == 0 ? "r" : c == 1 ? "g" : "b";
}
double channel(const LinearRgb& v, int c) {
    return c == 0 ? v.r : c == 1 ? v.g : v.b;
}

std::string formatInterval(const LinearInterval& iv) {
    return fmt::format("[{}, {}]", iv.min, iv.max);
}

void validateMaterial(const MaterialTable& table, const Material& m, std::size_t i) {
    const std::string where = entryWhere("materials", i, m.name);
    if (m.name.empty()) failAt(where, "missing name");
    for (int c = 0; c < 3; ++c) {
        const std::string ch = channelName(c);
        checkUnit(channel(m.f0Min, c), where, m.isRange() ? "f0Min." + ch : "f0." + ch);
        checkUnit(channel(m.f0Max, c), where, m.isRange() ? "f0Max." + ch : "f0." + ch);
        if (channel(m.f0Min, c) > channel(m.f0Max, c))
            failAt(where, fmt::format("f0Min.{} {} > f0Max.{} {}", ch, channel(m.f0Min, c), ch,
                                      channel(m.f0Max, c)));
    }
    for (int c = 0; c < 3; ++c) {
        const double lo = channel(m.f0Min, c);
        const double hi = channel(m.f0Max, c);
        if (m.materialClass == MaterialClass::Metal) {
            const LinearInterval metal = table.metalChart.bounds();
            if (lo < metal.min)
                failAt(where,
                       fmt::format(
                           "metal F0.{} = {} lies below the metal range (linear {:.4f}, ranges.metalChart)",
                           channelName(c), lo, metal.min));
        } else {
            const LinearInterval bound = table.dielectricPlausible.bounds();
            if (!bound.contains(lo) || !bound.contains(hi))
                failAt(where,
                       fmt::format("dielectric F0.{} = {} lies outside the plausible dielectric bound {} "
                                   "(ranges.dielectricPlausible)",
                                   channelName(c), bound.contains(lo) ? hi : lo, formatInterval(bound)));
        }
    }
    checkSource(table, m.source, where);
}

void validateTable(const MaterialTable& table) {
    if (table.version < 1 || table.version > kMaterialTableVersion)
        failAt("", fmt::format("materials table version {} is not supported (this burnish reads version {})",
                               table.version, kMaterialTableVersion));
    for (const auto& [key, text] : table.sources)
        if (key.empty() || text.empty()) failAt("sources", "keys and citations must not be empty");

    validateRange(table, table.dielectricChart, "ranges.dielectricChart");
    validateRange(table, table.metalChart, "ranges.metalChart");
    validateRange(table, table.dielectricPlausible, "ranges.dielectricPlausible");
    if (!table.dielectricChart.srgb8 || !table.metalChart.srgb8)
        failAt("ranges", "dielectricChart and metalChart need their 'srgb8' chart end points");
    // The chart's point: between the two gradients lies no material, so they must not touch.
    if (table.dielectricChart.bounds().max >= table.metalChart.bounds().min)
        failAt("ranges", fmt::format("dielectricChart (max {:.4f}) overlaps metalChart (min {:.4f})",
                                     table.dielectricChart.bounds().max, table.metalChart.bounds().min));
    if (table.dielectricPlausible.bounds().max >= table.metalChart.bounds().min)
        failAt("ranges", fmt::format("dielectricPlausible (max {}) overlaps metalChart (min {:.4f})",
                                     table.dielectricPlausible.bounds().max, table.metalChart.bounds().min));

    checkUnit(table.dielectricDefault.linear, "dielectricDefault", "linear");
    if (!table.dielectricPlausible.bounds().contains(table.dielectricDefault.linear))
        failAt("dielectricDefault", fmt::format("linear = {} lies outside the plausible dielectric bound {}",
                                                table.dielectricDefault.linear,
                                                formatInterval(table.dielectricPlausible.bounds())));
    checkSource(table, table.dielectricDefault.source, "dielectricDefault");
    if (table.dielectricDefault.srgb8)
        checkDecode(table.dielectricDefault.linear, *table.dielectricDefault.srgb8, "dielectricDefault",
                    "linear");

    checkUnit(table.midGrey.linear, "midGrey", "linear");
    if (!table.midGrey.srgb8) failAt("midGrey", "missing field 'srgb8'");
    checkDecode(table.midGrey.linear, *table.midGrey.srgb8, "midGrey", "linear");
    checkSource(table, table.midGrey.source, "midGrey");

    if (table.materials.empty()) failAt("materials", "the list is empty");
    std::map<std::string, std::size_t> seen;
    for (std::size_t i = 0; i < table.materials.size(); ++i) {
        const Material& m = table.materials[i];
        validateMaterial(table, m, i);
        const auto [it, inserted] = seen.emplace(lowerAscii(m.name), i);
        if (!inserted)
            failAt(entryWhere("materials", i, m.name),
                   fmt::format("duplicate name (also materials[{}]; names compare case-insensitively)",
                               it->second));
    }

    seen.clear();
    for (std::size_t i = 0; i < table.albedos.size(); ++i) {
        const DiffuseAlbedo& a = table.albedos[i];
        const std::string where = entryWhere("albedos", i, a.name);
        if (a.name.empty()) failAt(where, "missing name");
        checkInterval(a.albedo, where, "albedo");
        checkSource(table, a.source, where);
        const auto [it, inserted] = seen.emplace(lowerAscii(a.name), i);
        if (!inserted)
            failAt(where, fmt::format("duplicate name (also albedos[{}]; names compare case-insensitively)",
                                      it->second));
    }
}

// nlohmann keeps the last of two equal keys silently; a table with "f0" twice is corrupt, so the
// parse callback refuses it.
Json parseStrict(std::string_view text) {
    std::vector<std::set<std::string>> keysPerObject;
    const auto callback = [&](int /*depth*/, Json::parse_event_t event, Json& parsed) {
        switch (event) {
        case Json::parse_event_t::object_start:
            keysPerObject.emplace_back();
            break;
        case Json::parse_event_t::object_end:
            if (!keysPerObject.empty()) keysPerObject.pop_back();
            break;
        case Json::parse_event_t::key:
            if (!keysPerObject.empty() && !keysPerObject.back().insert(parsed.get<std::string>()).second)
                failAt("materials table",
                       fmt::format("duplicate key '{}' in one object", parsed.get<std::string>()));
            break;
        default:
            break;
        }
        return true;
    };
    return Json::parse(text.begin(), text.end(), callback);
}

// Strips nlohmann's "[json.exception.parse_error.101] " prefix: the rest is the useful part.
std::string jsonMessage(const nlohmann::json::exception& e) {
    std::string what = e.what();
    if (!what.empty() && what.front() == '[') {
        const auto close = what.find("] ");
        if (close != std::string::npos) what.erase(0, close + 2);
    }
    return what;
}

LinearRgb midpoint(const LinearRgb& a, const LinearRgb& b) {
    return {0.5 * (a.r + b.r), 0.5 * (a.g + b.g), 0.5 * (a.b + b.b)};
}

// Euclidean distance in sRGB-encoded units from `v` to the box [lo, hi] (lo, hi, v linear).
double encodedBoxDistance(const LinearRgb& v, const LinearRgb& lo, const LinearRgb& hi) {
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) {
        const double e = linearToSrgb(channel(v, c));
        const double eLo = linearToSrgb(channel(lo, c));
        const double eHi = linearToSrgb(channel(hi, c));
        const double d = e < eLo ? eLo - e : e > eHi ? e - eHi : 0.0;
        sum += d * d;
    }
    return std::sqrt(sum);
}

} // namespace

const char* toString(MaterialClass c) {
    return c == MaterialClass::Metal ? "metal" : "dielectric";
}

const char* toString(F0Class c) {
    switch (c) {
    case F0Class::Dielectric:
        return "dielectric";
    case F0Class::Metal:
        return "metal";
    case F0Class::Implausible:
        return "implausible";
    }
    return "implausible";
}

LinearRgb Material::f0() const {
    return midpoint(f0Min, f0Max);
}

LinearInterval SpecularRange::bounds() const {
    if (!srgb8) return linear;
    const auto code = [](int c) { return srgb8ToLinear(static_cast<std::uint8_t>(std::clamp(c, 0, 255))); };
    return {code(srgb8->first), code(srgb8->second)};
}

const Material* MaterialTable::find(std::string_view name) const {
    const std::string wanted = lowerAscii(name);
    for (const Material& m : materials)
        if (lowerAscii(m.name) == wanted) return &m;
    return nullptr;
}

const std::string& MaterialTable::citation(const std::string& key) const {
    const auto it = sources.find(key);
    return it == sources.end() ? key : it->second;
}

Result<MaterialTable> parseMaterialTable(std::string_view json) {
    try {
        Json root;
        try {
            root = parseStrict(json);
        } catch (const nlohmann::json::exception& e) {
            return Error{oneLine("materials table is not valid JSON: " + jsonMessage(e))};
        }
        MaterialTable table = readTable(root);
        validateTable(table);
        return table;
    } catch (const TableError& e) {
        return Error{oneLine(e.message)};
    } catch (const nlohmann::json::exception& e) {
        return Error{oneLine("materials table: " + jsonMessage(e))};
    } catch (const std::exception& e) {
        return Error{oneLine(std::string("materials table: ") + e.what())};
    }
}

Result<MaterialTable> loadMaterialTable(const std::filesystem::path& path) {
    auto bytes = readFile(path);
    if (!bytes) return Error{bytes.error()};
    auto table = parseMaterialTable(bytes.value());
    if (!table) return Error{path.string() + ": " + table.error()};
    return table;
}

namespace {
struct Builtin {
    MaterialTable table;
    Status status;
};
const Builtin& builtin() {
    static const Builtin instance = [] {
        auto parsed = parseMaterialTable(resources::kMaterialsJson);
        if (parsed) return Builtin{std::move(parsed).value(), Status::success()};
        return Builtin{MaterialTable{}, Status{Error{"built-in materials table: " + parsed.error()}}};
    }();
    return instance;
}
} // namespace

const MaterialTable& builtinMaterialTable() {
    return builtin().table;
}
Status builtinMaterialTableStatus() {
    return builtin().status;
}

std::string materialTableToJson(const MaterialTable& table, int indent) {
    const auto rgbJson = [](const LinearRgb& c) -> Json {
        if (c.r == c.g && c.g == c.b) return c.r;
        return Json::array({c.r, c.g, c.b});
    };
    const auto rangeJson = [](const SpecularRange& r) {
        Json j = Json::object();
        if (r.srgb8) j["srgb8"] = Json::array({r.srgb8->first, r.srgb8->second});
        j["linear"] = Json::array({r.linear.min, r.linear.max});
        if (r.publishedLinear)
            j["publishedLinear"] = Json::array({r.publishedLinear->min, r.publishedLinear->max});
        j["source"] = r.source;
        if (!r.note.empty()) j["note"] = r.note;
        return j;
    };
    const auto referenceJson = [](const ReferenceValue& v) {
        Json j = Json::object();
        if (v.srgb8) j["srgb8"] = *v.srgb8;
        j["linear"] = v.linear;
        j["source"] = v.source;
        if (!v.note.empty()) j["note"] = v.note;
        return j;
    };

    Json root = Json::object();
    root["version"] = table.version;
    root["sources"] = Json(table.sources);
    root["ranges"] = {{"dielectricChart", rangeJson(table.dielectricChart)},
                      {"metalChart", rangeJson(table.metalChart)},
                      {"dielectricPlausible", rangeJson(table.dielectricPlausible)}};
    root["dielectricDefault"] = referenceJson(table.dielectricDefault);
    root["midGrey"] = referenceJson(table.midGrey);
    Json materials = Json::array();
    for (const Material& m : table.materials) {
        Json j = {{"name", m.name}, {"class", toString(m.materialClass)}};
        if (m.isRange()) {
            j["f0Min"] = rgbJson(m.f0Min);
            j["f0Max"] = rgbJson(m.f0Max);
        } else {
            j["f0"] = rgbJson(m.f0Min);
        }
        j["source"] = m.source;
        if (!m.note.empty()) j["note"] = m.note;
        materials.push_back(std::move(j));
    }
    root["materials"] = std::move(materials);
    Json albedos = Json::array();
    for (const DiffuseAlbedo& a : table.albedos) {
        Json j = {{"name", a.name}};
        if (a.albedo.min == a.albedo.max) {
            j["albedo"] = a.albedo.min;
        } else {
            j["albedoMin"] = a.albedo.min;
            j["albedoMax"] = a.albedo.max;
        }
        j["source"] = a.source;
        if (!a.note.empty()) j["note"] = a.note;
        albedos.push_back(std::move(j));
    }
    root["albedos"] = std::move(albedos);
    // Non-finite numbers cannot reach here from a validated table; dump() would write them as null.
    return root.dump(indent) + "\n";
}

F0Classification classifyF0(const MaterialTable& table, const LinearRgb& f0) {
    F0Classification out;
    const auto all = [&](const LinearInterval& iv) {
        return iv.contains(f0.r) && iv.contains(f0.g) && iv.contains(f0.b); // false for NaN
    };
    if (all(table.dielectricPlausible.bounds())) {
        out.f0Class = F0Class::Dielectric;
        out.insideChart = all(table.dielectricChart.bounds());
        const Srgb8 code = toSrgb8(f0);
        out.tinted = !(code.r == code.g && code.g == code.b);
    } else if (all(table.metalChart.bounds())) {
        out.f0Class = F0Class::Metal;
        out.insideChart = true; // the metal bound is the chart's gradient itself
    }
    return out;
}

ChartPosition chartPosition(const MaterialTable& table, const LinearRgb& f0) {
    ChartPosition out;
    out.srgb8 = toSrgb8(f0);
    out.f0Class = classifyF0(table, f0).f0Class;
    const SpecularRange* range = out.f0Class == F0Class::Dielectric ? &table.dielectricChart
                                 : out.f0Class == F0Class::Metal    ? &table.metalChart
                                                                    : nullptr;
    if (range && range->srgb8) {
        const auto [lo, hi] = *range->srgb8;
        const double code = linearToSrgb(luminance(f0)) * 255.0;
        // A one-code gradient has no length: everything on it sits at its start.
        out.gradient = hi > lo ? saturate((code - lo) / double(hi - lo)) : 0.0;
    }
    return out;
}

std::vector<MaterialMatch> nearestMaterials(const MaterialTable& table, const LinearRgb& f0,
                                            std::size_t count) {
    struct Ranked {
        MaterialMatch match;
        double toMiddle; // breaks ties between ranges that all contain the colour
    };
    std::vector<Ranked> ranked;
    ranked.reserve(table.materials.size());
    for (const Material& m : table.materials)
        ranked.push_back(
            {{&m, encodedBoxDistance(f0, m.f0Min, m.f0Max)}, encodedBoxDistance(f0, m.f0(), m.f0())});
    std::stable_sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) {
        if (a.match.distance != b.match.distance) return a.match.distance < b.match.distance;
        return a.toMiddle < b.toMiddle;
    });
    std::vector<MaterialMatch> matches;
    for (std::size_t i = 0; i < ranked.size() && i < count; ++i)
        matches.push_back(ranked[i].match);
    return matches;
}

Status validateMaterialTable(const MaterialTable& table) {
    try {
        validateTable(table);
        return Status::success();
    } catch (const TableError& e) {
        return Status{Error{oneLine(e.message)}};
    } catch (const std::exception& e) {
        return Status{Error{oneLine(std::string("materials table: ") + e.what())}};
    }
}

} // namespace burnish
