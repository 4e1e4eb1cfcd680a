#include "material_document.h"

#include <burnish/core/bake/bake.h>
#include <burnish/core/env/sampling.h>
#include <burnish/core/prefilter/sample_maps.h>

#include <QCoreApplication>
#include <QPointer>
#include <QThread>
#include <QUndoCommand>

#include <algorithm>
#include <cmath>

namespace burnish::studio {

namespace {

/// Merge ids of the edits a slider or colour drag repeats.
enum MergeField {
    kNoMerge = -1,
    kGlossField = 1,
    kAlbedoField = 2,
    kSpecularField = 3,
    kEnvironmentField = 4
};

class EditCommand : public QUndoCommand {
public:
    EditCommand(MaterialDocument* doc, MaterialSettings before, LoadedMaps beforeMaps, MaterialSettings after,
                LoadedMaps afterMaps, const QString& text, int mergeField, int epoch,
                std::shared_ptr<const PaintLayers> beforeLayers = nullptr,
                std::shared_ptr<const PaintLayers> afterLayers = nullptr)
        : QUndoCommand(text)
        , m_doc(doc)
        , m_before(std::move(before))
        , m_beforeMaps(std::move(beforeMaps))
        , m_after(std::move(after))
        , m_afterMaps(std::move(afterMaps))
        , m_beforeLayers(std::move(beforeLayers))
        , m_afterLayers(std::move(afterLayers))
        , m_mergeField(mergeField)
        , m_epoch(epoch) {}

    // An edit that carried the painted layers over (resampled, re-encoded) puts back exactly the
    // layers it replaced on undo, and the carried ones on redo.
    void redo() override { m_doc->apply(m_after, m_afterMaps, m_afterLayers.get()); }
    void undo() override { m_doc->apply(m_before, m_beforeMaps, m_beforeLayers.get()); }
    int id() const override { return m_mergeField; }
    bool mergeWith(const QUndoCommand* other) override {
        const auto* o = static_cast<const EditCommand*>(other);
        if (o->m_epoch != m_epoch || m_afterLayers || o->m_afterLayers) return false;
        m_after = o->m_after;
        m_afterMaps = o->m_afterMaps;
        setText(o->text()); // a drag is one step named by the value where it ended
        return true;
    }

private:
    MaterialDocument* m_doc;
    MaterialSettings m_before;
    LoadedMaps m_beforeMaps;
    MaterialSettings m_after;
    LoadedMaps m_afterMaps;
    std::shared_ptr<const PaintLayers> m_beforeLayers; // null: the edit leaves the layers alone
    std::shared_ptr<const PaintLayers> m_afterLayers;
    int m_mergeField;
    int m_epoch;
};

LinearRgb clamped(const LinearRgb& c) {
    return {saturate(c.r), saturate(c.g), saturate(c.b)};
}

bool finiteRgb(const LinearRgb& c) {
    return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b);
}

bool inUnitRange(const LinearRgb& c) {
    return finiteRgb(c) && c.r >= 0 && c.r <= 1 && c.g >= 0 && c.g <= 1 && c.b >= 0 && c.b <= 1;
}

Result<const Preset*> builtinPreset(const QString& name) {
    for (const auto& p : builtinPresets())
        if (QString::fromStdString(p.name) == name) return &p;
    return Error{"preset '" + name.toStdString() + "' is not known (known: " +
                 QStringList([] {
                     QStringList names;
                     for (const auto& n : builtinPresetNames())
                         names << QString::fromStdString(n);
                     return names;
                 }())
                     .join(", ")
                     .toStdString() +
                 ")"};
}

/// A gloss map is read per normal-map texel: checked as the bake will read it.
Status glossFits(const Image& gloss, const NormalMap& normal, const QString& path) {
    if (auto values = glossFromImage(gloss, normal.width, normal.height); !values)
        return Error{"gloss map '" + path.toStdString() + "': " + values.error()};
    return {};
}

} // namespace

const char* mapSlotName(MapSlot slot) {
    switch (slot) {
    case MapSlot::Normal:
        return "normal";
    case MapSlot::Gloss:
        return "gloss";
    case MapSlot::Detail:
        return "detail";
    }
    return "normal";
}

QString glossText(double gloss) {
    QString text = QString::number(gloss, 'f', kGlossDecimals);
    if (text.endsWith('0')) text.chop(1);
    return text;
}

QString glossQuantity(const GlossEncoding& encoding, bool capitalised) {
    QString name = QString::fromUtf8(encoding.quantity().data(), qsizetype(encoding.quantity().size()));
    if (capitalised && !name.isEmpty()) name[0] = name[0].toUpper();
    return name;
}

std::shared_ptr<const NormalMap> sampleNormalMap() {
    static const auto sample =
        std::make_shared<const NormalMap>(makeSampleNormalMap(SampleMapKind::Hammered, kSampleSize));
    return sample;
}

MaterialDocument::MaterialDocument(QObject* parent)
    : QObject(parent) {
    m_settings = defaultSettings();
    m_maps.normal = sampleNormalMap();
    m_glossLayer = PaintLayer::create(PaintLayerKind::Gloss, kSampleSize, kSampleSize).value();
    m_offsetLayer = PaintLayer::create(PaintLayerKind::VarianceOffset, kSampleSize, kSampleSize).value();
    m_undo.setClean();
}

MaterialSettings MaterialDocument::defaultSettings() {
    MaterialSettings s;
    const MaterialTable& table = builtinMaterialTable();
    if (const Material* m = table.find(kDefaultMaterial)) {
        s.materialClass = m->materialClass;
        s.specularName = QString::fromStdString(m->name);
        s.specular = m->f0();
    } else {
        // A broken build without the table: the table's default dielectric F0 is not there either,
        // so fall back to Lazarov 2011's hard-coded dielectric 0.03.
        s.materialClass = MaterialClass::Dielectric;
        s.specular = LinearRgb::grey(0.03);
    }
    // Metals have no diffuse term; a dark albedo keeps the default honest if switched to dielectric.
    s.albedo = LinearRgb::grey(0.0);
    if (auto p = builtinPreset(s.preset)) s.method = (*p)->method;
    return s;
}

const Preset& MaterialDocument::preset() const {
    if (auto p = builtinPreset(m_settings.preset)) return **p;
    // validate() refuses unknown presets, so this is reached only by a build without presets.
    static const Preset fallback;
    return fallback;
}

std::vector<Method> MaterialDocument::availableMethods() const {
    return compatibleMethods(preset());
}

double MaterialDocument::power() const {
    return preset().encoding.power(m_settings.gloss);
}

QStringList MaterialDocument::diagnostics(MapSlot slot) const {
    QStringList lines;
    const NormalMapDiagnostics* d = nullptr;
    const ImageSourceInfo* source = nullptr;
    if (slot == MapSlot::Normal && m_maps.normal && !m_settings.normalMapPath.isEmpty()) {
        d = &m_maps.normal->diagnostics;
        source = &m_maps.normal->source;
    } else if (slot == MapSlot::Detail && m_maps.detail) {
        d = &m_maps.detail->diagnostics;
        source = &m_maps.detail->source;
    } else if (slot == MapSlot::Gloss && m_maps.gloss) {
        source = &m_maps.gloss->source;
    }
    if (slot == MapSlot::Normal && m_settings.normalMapPath.isEmpty())
        return {QString("built-in sample '%1', %2×%2").arg(kSampleName).arg(kSampleSize)};
    if (source) {
        int w = 0, h = 0;
        if (slot == MapSlot::Gloss) {
            w = m_maps.gloss->width;
            h = m_maps.gloss->height;
        } else {
            const auto& map = slot == MapSlot::Normal ? *m_maps.normal : *m_maps.detail;
            w = map.width;
            h = map.height;
        }
        lines << QString("%1×%2, %3 %4")
                     .arg(w)
                     .arg(h)
                     .arg(QString::fromStdString(source->formatName),
                          QString::fromStdString(source->channelType));
    }
    if (d) {
        QStringList flags;
        if (!d->implausible.empty()) flags << "loaded anyway";
        if (d->zRebuilt) flags << "z rebuilt";
        if (d->greenFlipped) flags << "green flipped";
        if (d->alphaIgnored) flags << "alpha ignored";
        if (d->signedValues) flags << "signed values";
        if (!flags.isEmpty()) lines << flags.join(", ");
        // Padding (noDataTexels) is said once, by the decoder's warning below.
        if (d->nonFiniteTexels || d->zeroLengthTexels)
            lines << QString("%1 non-finite, %2 zero-length texels replaced by flat normals")
                         .arg(d->nonFiniteTexels)
                         .arg(d->zeroLengthTexels);
        for (const auto& w : d->warnings)
            lines << "warning: " + QString::fromStdString(w);
    }
    return lines;
}

void MaterialDocument::push(const MaterialSettings& after, const LoadedMaps& maps, const QString& text,
                            int mergeField, std::shared_ptr<const PaintLayers> layersAfter) {
    if (after == m_settings && maps.normal == m_maps.normal && maps.gloss == m_maps.gloss &&
        maps.detail == m_maps.detail)
        return;
    std::shared_ptr<const PaintLayers> layersBefore;
    if (layersAfter)
        layersBefore = std::make_shared<const PaintLayers>(PaintLayers{m_glossLayer, m_offsetLayer});
    m_undo.push(new EditCommand(this, m_settings, m_maps, after, maps, text, mergeField, m_mergeEpoch,
                                std::move(layersBefore), std::move(layersAfter)));
}

Result<std::shared_ptr<const PaintLayers>>
MaterialDocument::carriedLayers(int width, int height, const GlossEncoding& encoding, QString* what) const {
    const bool glossPainted = m_glossLayer.painted(), offsetPainted = m_offsetLayer.painted();
    if (!glossPainted && !offsetPainted) return std::shared_ptr<const PaintLayers>();
    const bool resize = width != m_glossLayer.width || height != m_glossLayer.height;
    const GlossEncoding& current = preset().encoding;
    const bool reencode = glossPainted && encoding.name() != current.name();
    if (!resize && !reencode) return std::shared_ptr<const PaintLayers>();
    auto layers = std::make_shared<PaintLayers>(PaintLayers{m_glossLayer, m_offsetLayer});
    QStringList done;
    if (resize) {
        // A loaded map's size is always a possible layer size; should resampling fail anyway, the
        // edit is refused (nothing changes) rather than done without the paint.
        auto gloss = resamplePaintLayer(m_glossLayer, width, height);
        if (!gloss) return Error{"the painted layers cannot follow the map: " + gloss.error()};
        auto offset = resamplePaintLayer(m_offsetLayer, width, height);
        if (!offset) return Error{"the painted layers cannot follow the map: " + offset.error()};
        layers->gloss = std::move(gloss).value();
        layers->offset = std::move(offset).value();
        done << QString("resampled from %1×%2 to %3×%4")
                    .arg(m_glossLayer.width)
                    .arg(m_glossLayer.height)
                    .arg(width)
                    .arg(height);
    }
    if (reencode) {
        // The painted gloss means a power under the preset's encoding: keep the power, as the base
        // gloss keeps it (setPreset).
        for (float& v : layers->gloss.value)
            v = float(saturate(encoding.value(current.power(v))));
        done << "re-encoded for the new gloss encoding";
    }
    if (what) *what = "Painted layers " + done.join(" and ") + " (undo restores them as they were)";
    return std::shared_ptr<const PaintLayers>(std::move(layers));
}

Status MaterialDocument::pushCarryingLayers(const MaterialSettings& after, const LoadedMaps& maps,
                                            const QString& text, const GlossEncoding& encoding) {
    QString what;
    auto layers = carriedLayers(maps.normal->width, maps.normal->height, encoding, &what);
    if (!layers) return Error{layers.error()};
    push(after, maps, text, kNoMerge, *layers);
    if (*layers) emit notice(what);
    return {};
}

void MaterialDocument::setMaterialClass(MaterialClass c) {
    MaterialSettings s = m_settings;
    s.materialClass = c;
    push(s, m_maps, c == MaterialClass::Metal ? "Set metal" : "Set dielectric", kNoMerge);
}

Status MaterialDocument::setSpecularMaterial(const QString& name) {
    const Material* m = builtinMaterialTable().find(name.toStdString());
    if (!m) return Error{"material '" + name.toStdString() + "' is not in the calibrated table"};
    MaterialSettings s = m_settings;
    s.specularName = QString::fromStdString(m->name);
    s.specular = m->f0();
    s.materialClass = m->materialClass;
    push(s, m_maps, "Specular: " + s.specularName, kNoMerge);
    return {};
}

void MaterialDocument::setCustomSpecular(const LinearRgb& f0) {
    MaterialSettings s = m_settings;
    s.specularName.clear();
    s.specular = clamped(f0);
    push(s, m_maps, "Custom specular colour", kSpecularField);
}

void MaterialDocument::setAlbedo(const LinearRgb& albedo) {
    MaterialSettings s = m_settings;
    s.albedo = clamped(albedo);
    push(s, m_maps, "Albedo", kAlbedoField);
}

void MaterialDocument::setGloss(double gloss, bool merge) {
    MaterialSettings s = m_settings;
    s.gloss = saturate(gloss);
    push(s, m_maps, QString("%1 %2").arg(glossQuantity(preset().encoding)).arg(glossText(s.gloss)),
         merge ? kGlossField : kNoMerge);
}

Status MaterialDocument::setMethod(Method method) {
    if (const Status st = checkPresetMethod(preset(), method); !st) return st;
    MaterialSettings s = m_settings;
    s.method = method;
    push(s, m_maps, "Method: " + QString::fromUtf8(methodName(method).data(), int(methodName(method).size())),
         kNoMerge);
    return {};
}

void MaterialDocument::setMixtureLobes(int lobes) {
    MaterialSettings s = m_settings;
    s.mixtureLobes = std::clamp(lobes, 1, kMaxMixtureLobes);
    if (s.mixtureLobes == m_settings.mixtureLobes) return;
    push(s, m_maps, QString("Mixture lobes: %1").arg(s.mixtureLobes), kNoMerge);
}

Status MaterialDocument::setPreset(const QString& name) {
    const auto p = builtinPreset(name);
    if (!p) return Error{p.error()};
    MaterialSettings s = m_settings;
    // Keep what the artist sees: the same power, written in the new preset's encoding.
    s.gloss = (*p)->encoding.value(power());
    s.preset = name;
    if (!checkPresetMethod(**p, s.method)) s.method = (*p)->method;
    return pushCarryingLayers(s, m_maps, "Preset: " + name, (*p)->encoding);
}

Result<DecodedMap> MaterialDocument::decodeMap(MapSlot slot, const QString& path) {
    DecodedMap d;
    d.slot = slot;
    d.path = path;
    if (slot == MapSlot::Gloss) {
        auto image = readImage(path.toStdString());
        if (!image) return Error{"gloss map: " + image.error()};
        d.gloss = std::make_shared<const Image>(std::move(image.value()));
        return d;
    }
    const std::string what = slot == MapSlot::Normal ? "normal map: " : "detail map: ";
    // Decoded once, past the plausibility check: a map it refuses carries the refusal, and is held with
    // it for the artist to load anyway.
    NormalMapOptions options;
    options.allowImplausible = true;
    auto map = loadNormalMap(path.toStdString(), options);
    if (!map) return Error{what + map.error()};
    if (!map->diagnostics.implausible.empty())
        d.refusal = QString::fromStdString(what + map->diagnostics.implausible);
    (slot == MapSlot::Normal ? d.normal : d.detail) =
        std::make_shared<const NormalMap>(std::move(map.value()));
    return d;
}

Status MaterialDocument::applyDecodedMap(const DecodedMap& d) {
    if (!d.refusal.isEmpty() && !d.accepted) return Error{d.refusal.toStdString()};
    MaterialSettings s = m_settings;
    // Keep the maps of the other slots shared (no reload, same undo data).
    LoadedMaps next = m_maps;
    switch (d.slot) {
    case MapSlot::Normal:
        if (!d.normal) return Error{"normal map: nothing was decoded"};
        s.normalMapPath = d.path;
        s.allowImplausibleNormal = !d.normal->diagnostics.implausible.empty();
        next.normal = d.normal;
        break;
    case MapSlot::Gloss:
        if (!d.gloss) return Error{"gloss map: nothing was decoded"};
        s.glossMapPath = d.path;
        next.gloss = d.gloss;
        break;
    case MapSlot::Detail:
        if (!d.detail) return Error{"detail map: nothing was decoded"};
        s.detailMapPath = d.path;
        s.allowImplausibleDetail = !d.detail->diagnostics.implausible.empty();
        next.detail = d.detail;
        break;
    }
    if (next.gloss)
        if (const Status fits = glossFits(*next.gloss, *next.normal, s.glossMapPath); !fits) return fits;
    return pushCarryingLayers(s, next, QString("Load %1 map").arg(mapSlotName(d.slot)), preset().encoding);
}

Status MaterialDocument::loadMap(MapSlot slot, const QString& path) {
    auto decoded = decodeMap(slot, path);
    if (!decoded) return Error{decoded.error()};
    return applyDecodedMap(*decoded);
}

bool MaterialDocument::holdsRefusedMap(MapSlot slot) const {
    return m_refused[size_t(slot)].has_value();
}

Status MaterialDocument::acceptRefusedMap(MapSlot slot) {
    std::optional<DecodedMap> held = std::move(m_refused[size_t(slot)]);
    m_refused[size_t(slot)].reset();
    if (!held) return Error{QString("no refused %1 map is held").arg(mapSlotName(slot)).toStdString()};
    held->accepted = true;
    return applyDecodedMap(*held);
}

void MaterialDocument::dropRefusedMap(MapSlot slot) {
    m_refused[size_t(slot)].reset();
}

void MaterialDocument::loadMapInBackground(MapSlot slot, const QString& path) {
    // A newer request for the slot supersedes an older one: its result is dropped on arrival.
    const quint64 generation = ++m_loadGeneration[int(slot)];
    m_refused[size_t(slot)].reset();
    emit mapLoadStarted(slot, path);
    QPointer<MaterialDocument> self(this);
    QThread* worker = QThread::create([self, slot, path, generation] {
        auto decoded = std::make_shared<Result<DecodedMap>>(decodeMap(slot, path));
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, slot, path, generation, decoded] {
                if (!self || self->m_loadGeneration[int(slot)] != generation) return; // superseded
                self->m_loadDone[int(slot)] = generation;
                const Status st =
                    *decoded ? self->applyDecodedMap(**decoded) : Status(Error{decoded->error()});
                if (*decoded && !(*decoded)->refusal.isEmpty()) self->m_refused[size_t(slot)] = **decoded;
                emit self->mapLoadFinished(slot, path, st.ok(),
                                           st.ok() ? QString() : QString::fromStdString(st.error()));
            },
            Qt::QueuedConnection);
    });
    startWorker(worker);
}

void MaterialDocument::startWorker(QThread* worker) {
    worker->setParent(this); // deleted with the document if it goes before the thread's finished()
    m_loaders.push_back(worker);
    connect(worker, &QThread::finished, this, [this, worker] {
        m_loaders.erase(std::remove(m_loaders.begin(), m_loaders.end(), worker), m_loaders.end());
        worker->deleteLater();
    });
    worker->start();
}

bool MaterialDocument::loading(MapSlot slot) const {
    return m_loadGeneration[int(slot)] != m_loadDone[int(slot)];
}

MaterialDocument::~MaterialDocument() {
    // A decode in flight finishes (it touches nothing of the document) before the document goes.
    for (QThread* worker : m_loaders)
        worker->wait();
}

void MaterialDocument::clearMap(MapSlot slot) {
    MaterialSettings s = m_settings;
    LoadedMaps next = m_maps;
    m_refused[size_t(slot)].reset();
    switch (slot) {
    case MapSlot::Normal:
        s.normalMapPath.clear();
        s.allowImplausibleNormal = false;
        next.normal = sampleNormalMap();
        break;
    case MapSlot::Gloss:
        s.glossMapPath.clear();
        next.gloss.reset();
        break;
    case MapSlot::Detail:
        s.detailMapPath.clear();
        s.allowImplausibleDetail = false;
        next.detail.reset();
        break;
    }
    if (slot == MapSlot::Normal && m_maps.gloss &&
        (m_maps.gloss->width != next.normal->width || m_maps.gloss->height != next.normal->height)) {
        // The gloss map is per normal-map texel: it cannot outlive a change of size.
        s.glossMapPath.clear();
        next.gloss.reset();
    }
    // Clearing to the sample cannot fail to carry the layers (its size is a possible one).
    (void)pushCarryingLayers(s, next, QString("Clear %1 map").arg(mapSlotName(slot)), preset().encoding);
}

void MaterialDocument::setExportSettings(const ExportSettings& exportSettings) {
    MaterialSettings s = m_settings;
    s.exportSettings = exportSettings;
    push(s, m_maps, "Export settings", kNoMerge);
}

void MaterialDocument::setEnvironment(const EnvironmentSettings& environment, bool merge) {
    MaterialSettings s = m_settings;
    EnvironmentSettings e = environment;
    // Non-finite values become the defaults; the rest is clamped to the ranges the settings promise.
    e.rotationDegrees = std::isfinite(e.rotationDegrees) ? std::clamp(e.rotationDegrees, -180.0, 180.0) : 0.0;
    e.intensity = std::isfinite(e.intensity) ? std::clamp(e.intensity, 0.0, kMaxEnvironmentIntensity) : 1.0;
    e.fisSamples = std::clamp(e.fisSamples, 1, int(kMaxFisSamples));
    s.environment = e;
    push(s, m_maps, "Environment", merge ? kEnvironmentField : kNoMerge);
}

Status MaterialDocument::validate(const MaterialSettings& s) {
    const auto p = builtinPreset(s.preset);
    if (!p) return Error{p.error()};
    if (const Status st = checkPresetMethod(**p, s.method); !st) return st;
    if (!s.specularName.isEmpty()) {
        const Material* m = builtinMaterialTable().find(s.specularName.toStdString());
        if (!m)
            return Error{"material '" + s.specularName.toStdString() + "' is not in the calibrated table"};
    }
    if (!inUnitRange(s.specular)) return Error{"the specular colour must have channels in [0, 1]"};
    if (!inUnitRange(s.albedo)) return Error{"the albedo must have channels in [0, 1]"};
    if (!(s.gloss >= 0.0 && s.gloss <= 1.0)) return Error{"the gloss must lie in [0, 1]"};
    if (s.mixtureLobes < 1 || s.mixtureLobes > kMaxMixtureLobes)
        return Error{"the mixture's lobe count must lie in 1.." + std::to_string(kMaxMixtureLobes)};
    const ExportSettings& e = s.exportSettings;
    if (!e.format.isEmpty() && !exportFormatFromName(e.format.toStdString()))
        return Error{"export format '" + e.format.toStdString() + "' is not known"};
    if (!e.compression.isEmpty() && !ddsCompressionFromName(e.compression.toStdString()))
        return Error{"compression '" + e.compression.toStdString() + "' is not known"};
    if (e.mips < 0) return Error{"the mip count must not be negative"};
    const EnvironmentSettings& env = s.environment;
    if (env.choice == EnvironmentChoice::File && env.path.isEmpty())
        return Error{"the environment file is not set"};
    if (!(env.intensity >= 0.0 && env.intensity <= kMaxEnvironmentIntensity))
        return Error{"the environment intensity must lie in [0, 1024]"};
    if (!(std::abs(env.rotationDegrees) <= 180.0))
        return Error{"the environment rotation must lie in [-180, 180]"};
    if (env.fisSamples < 1 || env.fisSamples > int(kMaxFisSamples))
        return Error{"the environment sample count must lie in [1, 4096]"};
    return {};
}

Result<LoadedMaps> MaterialDocument::loadMaps(const MaterialSettings& s) {
    LoadedMaps maps;
    if (s.normalMapPath.isEmpty()) {
        maps.normal = sampleNormalMap();
    } else {
        NormalMapOptions options;
        options.allowImplausible = s.allowImplausibleNormal;
        auto normal = loadNormalMap(s.normalMapPath.toStdString(), options);
        if (!normal) return Error{"normal map: " + normal.error()};
        maps.normal = std::make_shared<const NormalMap>(std::move(normal.value()));
    }
    if (!s.glossMapPath.isEmpty()) {
        auto image = readImage(s.glossMapPath.toStdString());
        if (!image) return Error{"gloss map: " + image.error()};
        if (const Status fits = glossFits(*image, *maps.normal, s.glossMapPath); !fits)
            return Error{fits.error()};
        maps.gloss = std::make_shared<const Image>(std::move(image.value()));
    }
    if (!s.detailMapPath.isEmpty()) {
        NormalMapOptions options;
        options.allowImplausible = s.allowImplausibleDetail;
        auto detail = loadNormalMap(s.detailMapPath.toStdString(), options);
        if (!detail) return Error{"detail map: " + detail.error()};
        maps.detail = std::make_shared<const NormalMap>(std::move(detail.value()));
    }
    return maps;
}

Status MaterialDocument::reset(const MaterialSettings& settings, const std::vector<LayerFile>& layers) {
    if (const Status st = validate(settings); !st) return st;
    auto maps = loadMaps(settings);
    if (!maps) return Error{maps.error()};
    const int w = maps->normal->width, h = maps->normal->height;
    auto gloss = PaintLayer::create(PaintLayerKind::Gloss, w, h);
    auto offset = PaintLayer::create(PaintLayerKind::VarianceOffset, w, h);
    if (!gloss || !offset) return Error{gloss ? offset.error() : gloss.error()};
    for (const LayerFile& file : layers) {
        auto layer = readPaintLayerExr(file.path.toStdString(), file.kind, w, h);
        if (!layer) return Error{layer.error()};
        (file.kind == PaintLayerKind::Gloss ? gloss : offset) = std::move(layer);
    }
    // A map still decoding for the old document must not land in the new one.
    for (size_t i = 0; i < std::size(m_loadGeneration); ++i) {
        m_loadDone[i] = ++m_loadGeneration[i];
        m_refused[i].reset();
    }
    m_undo.clear();
    m_glossLayer = std::move(gloss).value();
    m_offsetLayer = std::move(offset).value();
    m_authored.reset(); // recomposited by apply()
    m_published.reset();
    m_snapshots.clear();
    m_preparedAuthored = {};
    apply(settings, *maps);
    m_undo.setClean();
    return {};
}

void MaterialDocument::apply(const MaterialSettings& settings, const LoadedMaps& maps,
                             const PaintLayers* layers) {
    const LoadedMaps old = m_maps;
    const bool glossInputs = old.normal != maps.normal || old.gloss != maps.gloss ||
                             m_settings.gloss != settings.gloss || m_settings.preset != settings.preset ||
                             layers != nullptr;
    m_settings = settings;
    m_maps = maps;
    const int w = maps.normal->width, h = maps.normal->height;
    if (layers && layers->gloss.width == w && layers->gloss.height == h) {
        m_glossLayer = layers->gloss;
        m_offsetLayer = layers->offset;
    } else if (m_glossLayer.width != w || m_glossLayer.height != h) {
        // Unpainted layers of another size (painted ones come with the edit, carriedLayers).
        m_glossLayer = PaintLayer::create(PaintLayerKind::Gloss, w, h).value();
        m_offsetLayer = PaintLayer::create(PaintLayerKind::VarianceOffset, w, h).value();
    }
    if (glossInputs || !m_authored) recomposite(TexelRect::full(w, h), true);
    if (old.normal != maps.normal) emit mapChanged(MapSlot::Normal);
    if (old.gloss != maps.gloss) emit mapChanged(MapSlot::Gloss);
    if (old.detail != maps.detail) emit mapChanged(MapSlot::Detail);
    if (layers) emit layersChanged(TexelRect::full(w, h));
    emit changed();
}

const PaintLayer& MaterialDocument::paintLayer(PaintLayerKind kind) const {
    return kind == PaintLayerKind::Gloss ? m_glossLayer : m_offsetLayer;
}

PaintLayer& MaterialDocument::editablePaintLayer(PaintLayerKind kind) {
    return kind == PaintLayerKind::Gloss ? m_glossLayer : m_offsetLayer;
}

void MaterialDocument::layerEdited(PaintLayerKind, const TexelRect& rect) {
    if (rect.empty()) return;
    recomposite(rect, false);
    emit layersChanged(rect);
}

void MaterialDocument::applyPaintPatch(PaintLayerKind kind, const PaintPatch& patch) {
    // Patches come from strokes on a layer of this size; one that does not fit changes nothing.
    if (!applyPatch(editablePaintLayer(kind), patch)) return;
    layerEdited(kind, patch.rect);
    emit changed();
}

namespace {

// Snapshot buffers kept for reuse: the newest handed out, the one the renderer may still hold, a spare.
constexpr size_t kMaxAuthoredSnapshots = 3;

bool anyCoverage(const PaintLayer& layer, const TexelRect& r) {
    if (!layer.allocated()) return false;
    for (int y = std::max(r.y0, 0); y < std::min(r.y1, layer.height); ++y)
        for (int x = std::max(r.x0, 0); x < std::min(r.x1, layer.width); ++x)
            if (layer.coverage[layer.index(x, y)] > 0.0f) return true;
    return false;
}

} // namespace

std::shared_ptr<const std::vector<float>> MaterialDocument::authoredGloss() const {
    if (!m_authored) return nullptr;
    if (m_published) return m_published;
    const int w = m_maps.normal->width;
    for (AuthoredSnapshot& snapshot : m_snapshots) {
        if (snapshot.values.use_count() != 1 || snapshot.values->size() != m_authored->size()) continue;
        // Nobody else holds it: bring the rectangle edited since its last use up to date, in place.
        copyTexelRect(*m_authored, *snapshot.values, w, snapshot.stale);
        snapshot.stale = {};
        m_published = snapshot.values;
        return m_published;
    }
    // Every buffer is held (the renderer's cache, a bake): a new one, the oldest let go to its holders.
    auto values = std::make_shared<std::vector<float>>(*m_authored);
    if (m_snapshots.size() >= kMaxAuthoredSnapshots) m_snapshots.erase(m_snapshots.begin());
    m_snapshots.push_back({values, {}});
    m_published = values;
    return m_published;
}

void MaterialDocument::prepareForPainting(PaintLayerKind kind) {
    const std::shared_ptr<const NormalMap> normal = m_maps.normal;
    if (!normal) return;
    const size_t n = normal->texelCount();
    const bool layer = !paintLayer(kind).allocated();
    const bool authored = !m_authored && !m_maps.gloss;
    size_t spare = 0;
    for (const AuthoredSnapshot& snapshot : m_snapshots)
        spare += snapshot.values->size() == n ? 1 : 0;
    const size_t snapshots = kMaxAuthoredSnapshots - std::min(spare, kMaxAuthoredSnapshots);
    if (!layer && !authored && snapshots == 0) return;
    const quint64 generation = ++m_prepareGeneration;
    const double gloss = m_settings.gloss;
    const QString preset = m_settings.preset;
    const GlossEncoding encoding = this->preset().encoding;
    QPointer<MaterialDocument> self(this);
    QThread* worker = QThread::create([=] {
        struct Made {
            std::vector<float> value, coverage;
            std::shared_ptr<std::vector<float>> authored;
            std::vector<std::shared_ptr<std::vector<float>>> snapshots;
        };
        auto made = std::make_shared<Made>();
        if (layer) made->value.assign(n, 0.0f), made->coverage.assign(n, 0.0f);
        if (authored) {
            // What recomposite() would write before any paint: the same function over unpainted layers.
            const auto none = PaintLayer::create(PaintLayerKind::Gloss, normal->width, normal->height);
            const auto noOffset =
                PaintLayer::create(PaintLayerKind::VarianceOffset, normal->width, normal->height);
            made->authored = std::make_shared<std::vector<float>>(n);
            if (!none || !noOffset ||
                !compositeAuthoredGloss(nullptr, gloss, &*none, &*noOffset, encoding, normal->width,
                                        normal->height, TexelRect::full(normal->width, normal->height),
                                        *made->authored))
                made->authored.reset();
        }
        for (size_t i = 0; i < snapshots; ++i)
            // Holding the prepared values when there are some: the first snapshots of the stroke then
            // copy its dabs, not the map.
            made->snapshots.push_back(made->authored ? std::make_shared<std::vector<float>>(*made->authored)
                                                     : std::make_shared<std::vector<float>>(n));
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, made, generation, normal, gloss, preset, kind] {
                if (!self || self->m_prepareGeneration != generation || self->m_maps.normal != normal) return;
                PaintLayer& l = self->editablePaintLayer(kind);
                if (!l.allocated() && made->value.size() == l.texelCount()) {
                    l.value.swap(made->value);
                    l.coverage.swap(made->coverage);
                }
                if (made->authored) {
                    self->m_preparedAuthored = {made->authored, normal, gloss, preset,
                                                std::move(made->snapshots)};
                    return;
                }
                for (auto& values : made->snapshots)
                    if (self->m_snapshots.size() < kMaxAuthoredSnapshots)
                        self->m_snapshots.push_back({values, TexelRect::full(normal->width, normal->height)});
            },
            Qt::QueuedConnection);
    });
    startWorker(worker);
}

const std::vector<float>* MaterialDocument::unpaintedGloss() {
    if (!m_maps.normal) return nullptr;
    const int w = m_maps.normal->width, h = m_maps.normal->height;
    if (!m_maps.gloss) {
        m_baseGloss.reset();
        m_baseGlossOf.reset();
    } else if (m_baseGlossOf != m_maps.gloss || !m_baseGloss ||
               m_baseGloss->size() != size_t(w) * size_t(h)) {
        auto gloss = glossFromImage(*m_maps.gloss, w, h);
        m_baseGloss = gloss ? std::make_shared<const std::vector<float>>(std::move(gloss).value()) : nullptr;
        m_baseGlossOf = m_maps.gloss;
    }
    return m_baseGloss.get();
}

void MaterialDocument::recomposite(const TexelRect& rect, bool full) {
    const int w = m_maps.normal->width, h = m_maps.normal->height;
    (void)unpaintedGloss(); // m_baseGloss, current
    // The edited rectangle first: a dab's own texels answer at once; only an erase looks further.
    const bool painted = (!full && (anyCoverage(m_glossLayer, rect) || anyCoverage(m_offsetLayer, rect))) ||
                         m_glossLayer.painted() || m_offsetLayer.painted();
    m_published.reset();
    if (!m_baseGloss && !painted) {
        m_authored.reset(); // nothing authored per texel: the bake uses the base power
        return;
    }
    TexelRect region = rect;
    const PreparedAuthored prepared = std::exchange(m_preparedAuthored, {});
    if (!full && !m_authored && !m_baseGloss && prepared.values && prepared.normal == m_maps.normal &&
        prepared.gloss == m_settings.gloss && prepared.preset == m_settings.preset) {
        // Nothing was painted before this edit (there was no authored gloss) and the prepared values
        // are this document's unpainted ones: only the edited rectangle changes them.
        m_authored = prepared.values;
        for (AuthoredSnapshot& snapshot : m_snapshots)
            snapshot.stale = TexelRect::full(w, h); // spare buffers: nothing of these values yet
        for (const auto& values : prepared.snapshots)
            if (m_snapshots.size() < kMaxAuthoredSnapshots)
                m_snapshots.push_back({values, {}}); // equal so far
    } else if (full || !m_authored) {
        m_authored = std::make_shared<std::vector<float>>(size_t(w) * size_t(h));
        region = TexelRect::full(w, h);
    }
    // Buffers of another map size are no use any more (their holders keep theirs).
    std::erase_if(m_snapshots, [&](const AuthoredSnapshot& snapshot) {
        return snapshot.values->size() != m_authored->size();
    });
    region = {std::max(region.x0, 0), std::max(region.y0, 0), std::min(region.x1, w), std::min(region.y1, h)};
    for (AuthoredSnapshot& snapshot : m_snapshots)
        snapshot.stale.unite(region);
    // Sizes match by construction (layers follow the normal map, loadMaps checks the gloss map).
    (void)compositeAuthoredGloss(m_baseGloss.get(), m_settings.gloss, &m_glossLayer, &m_offsetLayer,
                                 preset().encoding, w, h, region, *m_authored);
}

} // namespace burnish::studio
