#include "project.h"

#include <burnish/core/env/sampling.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/hash.h>

#include <nlohmann/json.hpp>

#include <QCoreApplication>
#include <QCryptographicHash>
#include <QDir>
#include <QFileInfo>
#include <QRegularExpression>
#include <QStandardPaths>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

namespace burnish::studio {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

Json rgbJson(const LinearRgb& c) {
    return Json::array({c.r, c.g, c.b});
}

/// `path` relative to `folder` where one exists, else absolute.
Json relativePath(const QString& path, const QString& folder) {
    if (path.isEmpty()) return nullptr;
    const fs::path rel = fs::path(path.toStdString()).lexically_relative(folder.toStdString());
    return rel.empty() ? path.toStdString() : rel.generic_string();
}

QString qsv(std::string_view s) {
    return QString::fromUtf8(s.data(), int(s.size()));
}

QString folderOf(const QString& file) {
    return QFileInfo(file).absolutePath();
}

/// The environment source names of the project file (as `burnish render --env` spells them).
constexpr std::pair<EnvironmentChoice, const char*> kEnvironmentSources[] = {
    {EnvironmentChoice::Off, "off"},
    {EnvironmentChoice::ProceduralStudio, "studio"},
    {EnvironmentChoice::File, "file"}};

const char* environmentSourceName(EnvironmentChoice choice) {
    for (const auto& [c, name] : kEnvironmentSources)
        if (c == choice) return name;
    return "studio";
}

/// Reads fields of one JSON object, collecting the first error with its path.
class Reader {
public:
    Reader(const Json& object, std::string where)
        : m_object(object)
        , m_where(std::move(where)) {}

    Status known(std::initializer_list<const char*> names) const {
        const std::set<std::string> allowed(names.begin(), names.end());
        for (const auto& [key, value] : m_object.items())
            if (!allowed.count(key)) return Error{m_where + ": unknown field '" + key + "'"};
        return {};
    }
    const Json* get(const char* key, bool required) const {
        const auto it = m_object.find(key);
        if (it == m_object.end()) {
            if (required) m_error = Error{m_where + ": missing field '" + key + "'"};
            return nullptr;
        }
        return &*it;
    }
    std::optional<std::string> string(const char* key, bool required = true, bool nullable = false) const {
        const Json* v = get(key, required);
        if (!v || (nullable && v->is_null())) return std::nullopt;
        if (!v->is_string()) {
            fail(key, nullable ? "a string or null" : "a string");
            return std::nullopt;
        }
        return v->get<std::string>();
    }
    std::optional<double> number(const char* key, double min, double max) const {
        const Json* v = get(key, true);
        if (!v) return std::nullopt;
        if (!v->is_number() || !(v->get<double>() >= min && v->get<double>() <= max)) {
            char range[64];
            std::snprintf(range, sizeof range, "a number in [%g, %g]", min,
                          max); // [0, 64], not [0.000000, ...]
            fail(key, range);
            return std::nullopt;
        }
        return v->get<double>();
    }
    std::optional<LinearRgb> rgb(const char* key) const {
        const Json* v = get(key, true);
        if (!v) return std::nullopt;
        if (!v->is_array() || v->size() != 3 || !(*v)[0].is_number() || !(*v)[1].is_number() ||
            !(*v)[2].is_number()) {
            fail(key, "an array of 3 numbers");
            return std::nullopt;
        }
        const LinearRgb c{(*v)[0].get<double>(), (*v)[1].get<double>(), (*v)[2].get<double>()};
        for (double x : {c.r, c.g, c.b})
            if (!(x >= 0.0 && x <= 1.0)) {
                fail(key, "3 linear values in [0, 1]");
                return std::nullopt;
            }
        return c;
    }
    const Json* object(const char* key) const {
        const Json* v = get(key, true);
        if (v && !v->is_object()) {
            fail(key, "an object");
            return nullptr;
        }
        return v;
    }
    void fail(const char* key, const std::string& expected) const {
        if (!m_error) m_error = Error{m_where + ": '" + key + "' must be " + expected};
    }
    const std::optional<Error>& error() const { return m_error; }

private:
    const Json& m_object;
    std::string m_where;
    mutable std::optional<Error> m_error;
};

} // namespace

QString layerFolderFor(const QString& projectFile) {
    const QFileInfo info(projectFile);
    return info.absolutePath() + "/" + info.completeBaseName() + ".layers";
}

QString layerPathFor(const QString& projectFile, const PaintLayer& layer) {
    // Named by content: a save never replaces a file the project on disk still names, so a save
    // killed half-way leaves the old project whole.
    std::uint64_t hash = fnv1a64(layer.value.data(), layer.value.size() * sizeof(float));
    hash = fnv1a64(layer.coverage.data(), layer.coverage.size() * sizeof(float), hash);
    hash = fnv1a64(&layer.width, sizeof layer.width, hash);
    hash = fnv1a64(&layer.height, sizeof layer.height, hash);
    return layerFolderFor(projectFile) + "/" + qsv(paintLayerName(layer.kind)) + "-" +
           QString::fromStdString(hashHex(hash)) + ".exr";
}

namespace {

// Layer files Burnish wrote into a project's layer folder: "<layer>.exr" (before content names)
// and "<layer>-<16 hex digits>.exr". Nothing else there is ever removed.
bool isLayerFileName(const QString& name) {
    static const QRegularExpression pattern("^(gloss|variance-offset)(-[0-9a-f]{16})?\\.exr$");
    return pattern.match(name).hasMatch();
}

} // namespace

void removeStaleLayerFiles(const QString& projectFile, const std::vector<LayerFile>& keep) {
    const QString folder = layerFolderFor(projectFile);
    QDir dir(folder);
    if (!dir.exists()) return;
    for (const QString& name : dir.entryList(QDir::Files | QDir::Hidden)) {
        if (!isLayerFileName(name)) continue;
        const QString path = dir.absoluteFilePath(name);
        const bool named = std::any_of(keep.begin(), keep.end(), [&](const LayerFile& l) {
            return QFileInfo(l.path).absoluteFilePath() == path;
        });
        if (!named) QFile::remove(path);
    }
    QDir().rmdir(folder); // only when empty: someone else's files keep it
}

Status removeProject(const QString& projectFile) {
    removeStaleLayerFiles(projectFile, {});
    if (QFileInfo::exists(projectFile) && !QFile::remove(projectFile))
        return Error{"cannot remove '" + projectFile.toStdString() + "'"};
    return {};
}

std::string projectToJson(const MaterialSettings& s, const QString& projectFile, const QString& autosaveOf,
                          const std::vector<LayerFile>& layers, const std::optional<ProjectView>& view) {
    const QString folder = folderOf(projectFile);
    const ExportSettings& e = s.exportSettings;
    Json root = {
        {"format", kProjectFormat},
        {"version", kProjectVersion},
        {"material",
         {{"class", toString(s.materialClass)},
          {"specular",
           {{"material", s.specularName.isEmpty() ? Json(nullptr) : Json(s.specularName.toStdString())},
            {"linear", rgbJson(s.specular)}}},
          {"albedo", rgbJson(s.albedo)},
          {"gloss", s.gloss}}},
        {"maps",
         {{"normal", relativePath(s.normalMapPath, folder)},
          {"gloss", relativePath(s.glossMapPath, folder)},
          {"detail", relativePath(s.detailMapPath, folder)}}},
        {"method", std::string(methodName(s.method))},
        {"lobes", s.mixtureLobes},
        {"preset", s.preset.toStdString()},
        {"export",
         {{"format", e.format.isEmpty() ? Json(nullptr) : Json(e.format.toStdString())},
          {"compression", e.compression.isEmpty() ? Json(nullptr) : Json(e.compression.toStdString())},
          {"mips", e.mips},
          {"outputFolder", relativePath(e.outputFolder, folder)},
          {"overwrite", e.overwrite},
          {"shadedFit", e.shadedFit}}},
        {"environment",
         {{"source", environmentSourceName(s.environment.choice)},
          // Kept when another source is chosen, as the settings keep it (the panel offers it again).
          {"file", relativePath(s.environment.path, folder)},
          {"rotation", s.environment.rotationDegrees},
          {"intensity", s.environment.intensity},
          {"lobe", lobeModelName(s.environment.lobe)},
          {"fis", s.environment.fis},
          {"fisSamples", s.environment.fisSamples},
          {"background", s.environment.background}}}};
    if (view)
        root["view"] = {{"mesh", std::string(render::meshKindName(view->mesh))},
                        {"obj", view->mesh == render::MeshKind::Obj ? relativePath(view->objPath, folder)
                                                                    : Json(nullptr)},
                        {"yaw", view->yawDegrees},
                        {"pitch", view->pitchDegrees},
                        {"distance", view->distance},
                        {"target", {view->target[0], view->target[1], view->target[2]}}};
    // Written only for a map loaded past the plausibility check ("Load Anyway").
    Json allowed = Json::array();
    if (s.allowImplausibleNormal && !s.normalMapPath.isEmpty()) allowed.push_back("normal");
    if (s.allowImplausibleDetail && !s.detailMapPath.isEmpty()) allowed.push_back("detail");
    if (!allowed.empty()) root["maps"]["allowImplausible"] = allowed;
    // "layers" is written only when something is painted.
    if (!layers.empty()) {
        Json list = Json::array();
        for (const LayerFile& l : layers)
            list.push_back(
                {{"name", std::string(paintLayerName(l.kind))}, {"file", relativePath(l.path, folder)}});
        root["layers"] = list;
    }
    if (!autosaveOf.isEmpty()) root["autosaveOf"] = autosaveOf.toStdString();
    return root.dump(2) + "\n";
}

Result<ParsedProject> parseProject(std::string_view text, const QString& projectFile) {
    const std::string where = "project '" + projectFile.toStdString() + "'";
    Json root;
    try {
        root = Json::parse(text);
    } catch (const Json::parse_error& e) { // said in the artist's words, not the parser's
        return Error{where + ": not a Burnish project: not valid JSON (at byte " + std::to_string(e.byte) +
                     ")"};
    } catch (const Json::exception&) { // numbers out of range (out_of_range.406)
        return Error{where + ": not a Burnish project: a number out of range"};
    }
    if (!root.is_object()) return Error{where + ": not a Burnish project (expected a JSON object)"};
    if (!root.contains("format") || root["format"] != kProjectFormat)
        return Error{where + ": not a Burnish project (\"format\" must be \"" + kProjectFormat + "\")"};
    if (!root.contains("version") || !root["version"].is_number_integer() || root["version"].get<int>() < 1)
        return Error{where + ": \"version\" must be a positive integer"};
    if (const int version = root["version"].get<int>(); version > kProjectVersion)
        return Error{where + ": written by a newer Burnish (project version " + std::to_string(version) +
                     "; this studio reads up to version " + std::to_string(kProjectVersion) + ")"};

    const Reader top(root, where);
    if (Status st = top.known({"format", "version", "material", "maps", "method", "lobes", "preset", "export",
                               "environment", "layers", "autosaveOf", "view"});
        !st)
        return Error{st.error()};

    const QDir folder(folderOf(projectFile));
    auto absolute = [&](const std::optional<std::string>& p) {
        return p ? QDir::cleanPath(folder.absoluteFilePath(QString::fromStdString(*p))) : QString();
    };

    ParsedProject out;
    MaterialSettings& s = out.settings;
    const Json* material = top.object("material");
    const Json* maps = top.object("maps");
    const Json* exportJson = top.object("export");
    if (top.error()) return *top.error();

    const Reader m(*material, where + " material");
    if (Status st = m.known({"class", "specular", "albedo", "gloss"}); !st) return Error{st.error()};
    const auto cls = m.string("class");
    if (cls && *cls != "metal" && *cls != "dielectric") m.fail("class", "\"metal\" or \"dielectric\"");
    const Json* specular = m.object("specular");
    const auto albedo = m.rgb("albedo");
    const auto gloss = m.number("gloss", 0.0, 1.0);
    if (m.error()) return *m.error();
    s.materialClass = *cls == "metal" ? MaterialClass::Metal : MaterialClass::Dielectric;
    s.albedo = *albedo;
    s.gloss = *gloss;

    const Reader sp(*specular, where + " material.specular");
    if (Status st = sp.known({"material", "linear"}); !st) return Error{st.error()};
    const auto specularName = sp.string("material", true, true);
    const auto linear = sp.rgb("linear");
    if (sp.error()) return *sp.error();
    s.specularName = specularName ? QString::fromStdString(*specularName) : QString();
    s.specular = *linear;

    const Reader mp(*maps, where + " maps");
    if (Status st = mp.known({"normal", "gloss", "detail", "allowImplausible"}); !st)
        return Error{st.error()};
    const auto normalPath = mp.string("normal", true, true);
    const auto glossPath = mp.string("gloss", true, true);
    const auto detailPath = mp.string("detail", true, true);
    if (mp.error()) return *mp.error();
    s.normalMapPath = absolute(normalPath);
    s.glossMapPath = absolute(glossPath);
    s.detailMapPath = absolute(detailPath);
    // The maps loaded past the plausibility check ("Load Anyway"); optional.
    if (const Json* allowed = mp.get("allowImplausible", false)) {
        if (!allowed->is_array()) return Error{where + " maps: 'allowImplausible' must be an array"};
        for (const Json& slot : *allowed) {
            const std::string name = slot.is_string() ? slot.get<std::string>() : std::string();
            if (name == "normal" && !s.normalMapPath.isEmpty())
                s.allowImplausibleNormal = true;
            else if (name == "detail" && !s.detailMapPath.isEmpty())
                s.allowImplausibleDetail = true;
            else
                return Error{
                    where +
                    " maps: 'allowImplausible' holds \"normal\" or \"detail\" for a map that is set, not " +
                    slot.dump()};
        }
    }

    const auto method = top.string("method");
    const auto preset = top.string("preset");
    const auto autosaveOf = top.string("autosaveOf", false);
    // Projects written before the lobe count was saved draw and export the default mixture.
    std::optional<double> lobes;
    if (top.get("lobes", false)) lobes = top.number("lobes", 1.0, double(kMaxMixtureLobes));
    if (lobes && *lobes != std::floor(*lobes)) top.fail("lobes", "a whole number");
    if (top.error()) return *top.error();
    s.mixtureLobes = lobes ? int(*lobes) : kDefaultMixtureLobes;
    const auto methodValue = methodFromName(*method);
    if (!methodValue) return Error{where + ": method: " + methodValue.error()};
    s.method = *methodValue;
    s.preset = QString::fromStdString(*preset);
    out.autosaveOf = autosaveOf ? QString::fromStdString(*autosaveOf) : QString();

    if (const Json* layers = top.get("layers", false)) {
        if (!layers->is_array()) return Error{where + ": 'layers' must be an array"};
        for (const Json& entry : *layers) {
            if (!entry.is_object()) return Error{where + ": each of 'layers' must be an object"};
            const Reader l(entry, where + " layers");
            if (Status st = l.known({"name", "file"}); !st) return Error{st.error()};
            const auto name = l.string("name");
            const auto file = l.string("file");
            if (l.error()) return *l.error();
            LayerFile layer;
            if (*name == paintLayerName(PaintLayerKind::Gloss))
                layer.kind = PaintLayerKind::Gloss;
            else if (*name == paintLayerName(PaintLayerKind::VarianceOffset))
                layer.kind = PaintLayerKind::VarianceOffset;
            else
                return Error{where + ": unknown layer '" + *name + "' (known: gloss, variance-offset)"};
            layer.path = absolute(file);
            out.layers.push_back(layer);
        }
    }

    const Reader ex(*exportJson, where + " export");
    if (Status st = ex.known({"format", "compression", "mips", "outputFolder", "overwrite", "shadedFit"});
        !st)
        return Error{st.error()};
    const auto format = ex.string("format", true, true);
    const auto compression = ex.string("compression", true, true);
    const auto mips = ex.number("mips", 0.0, 64.0); // 64 levels: a 2^63-texel side, beyond any image
    const auto outputFolder = ex.string("outputFolder", true, true);
    const Json* overwrite = ex.get("overwrite", true);
    if (overwrite && !overwrite->is_boolean()) ex.fail("overwrite", "true or false");
    // Projects written before the shaded fit existed bake the moment fit.
    const Json* shadedFit = ex.get("shadedFit", false);
    if (shadedFit && !shadedFit->is_boolean()) ex.fail("shadedFit", "true or false");
    if (mips && *mips != std::floor(*mips)) ex.fail("mips", "a whole number");
    if (ex.error()) return *ex.error();
    s.exportSettings.format = format ? QString::fromStdString(*format) : QString();
    s.exportSettings.compression = compression ? QString::fromStdString(*compression) : QString();
    s.exportSettings.mips = int(*mips);
    s.exportSettings.outputFolder = absolute(outputFolder);
    s.exportSettings.overwrite = overwrite->get<bool>();
    s.exportSettings.shadedFit = shadedFit && shadedFit->get<bool>();

    // Projects written before the environment was saved light the viewport with the defaults.
    if (const Json* environment = top.get("environment", false)) {
        if (!environment->is_object()) return Error{where + ": 'environment' must be an object"};
        const Reader en(*environment, where + " environment");
        if (Status st = en.known(
                {"source", "file", "rotation", "intensity", "lobe", "fis", "fisSamples", "background"});
            !st)
            return Error{st.error()};
        const auto source = en.string("source");
        std::optional<EnvironmentChoice> choice;
        for (const auto& [c, name] : kEnvironmentSources)
            if (source && *source == name) choice = c;
        if (source && !choice) en.fail("source", "\"off\", \"studio\" or \"file\"");
        const auto file = en.string("file", true, true);
        if (choice == EnvironmentChoice::File && !file && !en.error())
            en.fail("file", "a path when the source is \"file\"");
        const auto rotation = en.number("rotation", -180.0, 180.0);
        const auto intensity = en.number("intensity", 0.0, kMaxEnvironmentIntensity);
        const auto lobe = en.string("lobe");
        std::optional<LobeModel> lobeValue;
        for (LobeModel l : {LobeModel::BlinnPhong, LobeModel::Phong})
            if (lobe && *lobe == lobeModelName(l)) lobeValue = l;
        if (lobe && !lobeValue)
            en.fail("lobe", std::string("\"") + lobeModelName(LobeModel::BlinnPhong) + "\" or \"" +
                                lobeModelName(LobeModel::Phong) + "\"");
        const Json* fis = en.get("fis", true);
        if (fis && !fis->is_boolean()) en.fail("fis", "true or false");
        const auto samples = en.number("fisSamples", 1.0, double(kMaxFisSamples));
        if (samples && *samples != std::floor(*samples)) en.fail("fisSamples", "a whole number");
        // Projects written before the background was saved show it, as a new document does.
        const Json* background = en.get("background", false);
        if (background && !background->is_boolean()) en.fail("background", "true or false");
        if (en.error()) return *en.error();
        EnvironmentSettings& e = s.environment;
        e.choice = *choice;
        e.path = absolute(file);
        e.rotationDegrees = *rotation;
        e.intensity = *intensity;
        e.lobe = *lobeValue;
        e.fis = fis->get<bool>();
        e.fisSamples = int(*samples);
        e.background = !background || background->get<bool>();
        // The viewport would fail on every frame: refuse it here with the file's name instead.
        if (e.choice == EnvironmentChoice::File && !QFileInfo(e.path).isFile())
            return Error{where + ": environment file '" + e.path.toStdString() + "' does not exist"};
    }

    // Projects written before the view was saved open on the default sphere and camera.
    if (const Json* view = top.get("view", false)) {
        if (!view->is_object()) return Error{where + ": 'view' must be an object"};
        const Reader v(*view, where + " view");
        if (Status st = v.known({"mesh", "obj", "yaw", "pitch", "distance", "target"}); !st)
            return Error{st.error()};
        const auto mesh = v.string("mesh");
        std::optional<render::MeshKind> kind;
        for (render::MeshKind k : {render::MeshKind::Sphere, render::MeshKind::Plane, render::MeshKind::Torus,
                                   render::MeshKind::Obj})
            if (mesh && *mesh == render::meshKindName(k)) kind = k;
        if (mesh && !kind) v.fail("mesh", "\"sphere\", \"plane\", \"torus\" or \"obj\"");
        const auto obj = v.string("obj", false, true);
        if (kind == render::MeshKind::Obj && !obj && !v.error())
            v.fail("obj", "a path when the mesh is \"obj\"");
        // The ranges the viewport keeps (its orbit wraps the yaw, stops the pitch short of the poles).
        const auto yaw = v.number("yaw", -360.0, 360.0);
        const auto pitch = v.number("pitch", -90.0, 90.0);
        const auto distance = v.number("distance", 1e-3, 1e4);
        const Json* target = v.get("target", true);
        constexpr double kMaxTarget = 1e6;
        std::array<double, 3> t{};
        if (target) {
            bool ok = target->is_array() && target->size() == 3;
            for (size_t i = 0; ok && i < 3; ++i) {
                ok = (*target)[i].is_number() && std::abs((*target)[i].get<double>()) <= kMaxTarget;
                if (ok) t[i] = (*target)[i].get<double>();
            }
            if (!ok) v.fail("target", "an array of 3 numbers within ±1e6");
        }
        if (v.error()) return *v.error();
        ProjectView pv;
        pv.mesh = *kind;
        pv.objPath = kind == render::MeshKind::Obj ? absolute(obj) : QString();
        pv.yawDegrees = *yaw;
        pv.pitchDegrees = *pitch;
        pv.distance = *distance;
        pv.target = t;
        out.view = pv;
    }

    if (Status st = MaterialDocument::validate(s); !st) return Error{where + ": " + st.error()};
    return out;
}

Status saveProject(const MaterialSettings& settings, const QString& projectFile, const QString& autosaveOf,
                   const std::vector<const PaintLayer*>& layers, const std::optional<ProjectView>& view) {
    std::vector<LayerFile> files;
    for (const PaintLayer* layer : layers) {
        if (!layer || !layer->painted()) continue;
        const QString path = layerPathFor(projectFile, *layer);
        if (!QDir().mkpath(QFileInfo(path).absolutePath()))
            return Error{"cannot create folder '" + QFileInfo(path).absolutePath().toStdString() + "'"};
        // The layers first: the project never names a file that is not there. A file of the same
        // content name was written whole (atomically) by an earlier save: it is kept as it is.
        if (!QFileInfo::exists(path))
            if (Status st = writePaintLayerExr(*layer, path.toStdString()); !st) return st;
        files.push_back({layer->kind, path});
    }
    if (Status st = writeFileAtomic(projectFile.toStdString(),
                                    projectToJson(settings, projectFile, autosaveOf, files, view));
        !st)
        return st;
    // Only now that the new project names its layers: the files no save names any more go.
    removeStaleLayerFiles(projectFile, files);
    return {};
}

Result<ParsedProject> loadProject(const QString& projectFile) {
    const auto text = readFile(projectFile.toStdString());
    if (!text) return Error{text.error()};
    return parseProject(*text, projectFile);
}

QString autosaveFolder() {
    return QStandardPaths::writableLocation(QStandardPaths::AppDataLocation) + "/autosave";
}

QString autosavePathFor(const QString& projectFile) {
    // An empty path: the one untitled copy studios before per-window copies wrote (still recovered).
    if (projectFile.isEmpty()) return autosaveFolder() + "/untitled." + kProjectSuffix;
    const QString absolute = QFileInfo(projectFile).absoluteFilePath();
    // The name keeps copies recognisable; the hash of the whole path keeps two "material.burnish"
    // files in different folders apart. 16 hex digits make a collision practically impossible.
    const QString hash =
        QCryptographicHash::hash(absolute.toUtf8(), QCryptographicHash::Sha1).toHex().left(16);
    return autosaveFolder() + "/" + QFileInfo(projectFile).completeBaseName() + "-" + hash + "." +
           kProjectSuffix;
}

QString newUntitledAutosavePath() {
    static std::atomic<int> serial{0};
    return autosaveFolder() + QString("/untitled-%1-%2-%3.%4")
                                  .arg(QDateTime::currentDateTime().toString("yyyyMMdd-HHmmss"))
                                  .arg(QCoreApplication::applicationPid())
                                  .arg(++serial)
                                  .arg(kProjectSuffix);
}

std::unique_ptr<QLockFile> claimAutosave(const QString& copy) {
    QDir().mkpath(QFileInfo(copy).absolutePath());
    auto lock = std::make_unique<QLockFile>(copy + ".lock");
    // Held as long as its process lives, however long that is; a dead process's lock is stale.
    lock->setStaleLockTime(0);
    if (!lock->tryLock(0)) return nullptr;
    return lock;
}

std::vector<AutosaveCopy> recoverableAutosaves() {
    std::vector<AutosaveCopy> out;
    const QFileInfoList files =
        QDir(autosaveFolder()).entryInfoList({QString("*.") + kProjectSuffix}, QDir::Files, QDir::Time);
    for (const QFileInfo& info : files) {
        const QString path = info.absoluteFilePath();
        if (!claimAutosave(path)) continue; // a live window's work in progress (the claim ends at once)
        AutosaveCopy copy{path, {}, info.lastModified()};
        // Only the owner is read here; a copy that does not parse is still offered (its error shows
        // when it is chosen, and Discard removes it).
        if (const auto text = readFile(path.toStdString())) {
            const Json root = Json::parse(*text, nullptr, false);
            if (root.is_object() && root.contains("autosaveOf") && root["autosaveOf"].is_string())
                copy.autosaveOf = QString::fromStdString(root["autosaveOf"].get<std::string>());
        }
        if (!copy.autosaveOf.isEmpty()) {
            const QFileInfo project(copy.autosaveOf);
            if (project.exists() && project.lastModified() >= copy.modified) continue; // saved since
        }
        out.push_back(std::move(copy));
    }
    return out; // QDir::Time: newest first
}

std::optional<QString> recoverableAutosave(const QString& projectFile) {
    const QString path = autosavePathFor(projectFile);
    const QFileInfo copy(path);
    if (!copy.exists()) return std::nullopt;
    if (projectFile.isEmpty()) return path;
    const QFileInfo project(projectFile);
    if (!project.exists() || copy.lastModified() > project.lastModified()) return path;
    return std::nullopt;
}

} // namespace burnish::studio
