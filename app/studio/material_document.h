// The studio's one source of truth: the material being authored (class, specular colour, albedo,
// base gloss, maps, method, preset, export settings). Every edit is a QUndoCommand on the
// document's stack; views listen to changed() and never keep their own copy.
#pragma once

#include <burnish/core/bake/paint.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/env/cube.h>
#include <burnish/core/env/prefilter.h>
#include <burnish/core/io/image.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/shading/color.h>
#include <burnish/core/shading/materials.h>
#include <burnish/core/util/result.h>

#include <QObject>
#include <QString>
#include <QUndoStack>

#include <array>
#include <memory>
#include <optional>
#include <vector>

class QThread;

namespace burnish::studio {

/// The material slots that take an image file.
enum class MapSlot { Normal, Gloss, Detail };
const char* mapSlotName(MapSlot slot); // "normal", "gloss", "detail"

/// What the Bake & Export dialog writes (saved with the project).
struct ExportSettings {
    QString format;      // an export format name; empty = the preset's default
    QString compression; // a DDS compression name; empty = each file's preset choice
    int mips = 0;        // mip levels written; 0 = the whole chain
    QString outputFolder;
    bool overwrite = false;
    bool shadedFit = false; // the mixture's lobes also fitted to the shaded truth (bake --shaded-fit)
    friend bool operator==(const ExportSettings&, const ExportSettings&) = default;
};

/// Where the viewport's environment lighting comes from.
enum class EnvironmentChoice { Off, ProceduralStudio, File };

/// The viewport's environment (saved with the settings, undoable like every edit): the source, its
/// rotation and intensity, the prefilter lobe, filtered importance sampling instead of the
/// prefiltered map, and whether it is drawn as the viewport's background.
struct EnvironmentSettings {
    EnvironmentChoice choice = EnvironmentChoice::ProceduralStudio;
    QString path;                 // for File: an equirectangular .exr/.hdr/.tif, absolute
    double rotationDegrees = 0.0; // about +y, [-180, 180]
    double intensity = 1.0;       // linear radiance scale, [0, kMaxEnvironmentIntensity]
    LobeModel lobe = LobeModel::BlinnPhong;
    bool fis = false;       // filtered importance sampling at shading time
    int fisSamples = 64;    // taps per pixel, [1, kMaxFisSamples of env_sampling.h]
    bool background = true; // drawn behind the mesh
    friend bool operator==(const EnvironmentSettings&, const EnvironmentSettings&) = default;
};
/// The highest environment intensity the studio accepts (a 2^10 exposure range above 1).
inline constexpr double kMaxEnvironmentIntensity = 1024.0;

/// Every user-visible setting of a material. Paths are absolute; an empty normal-map path means
/// the built-in sample.
struct MaterialSettings {
    MaterialClass materialClass = MaterialClass::Metal;
    QString specularName; // a calibrated material of core's table; empty = custom colour
    LinearRgb specular;   // linear F0
    LinearRgb albedo;     // linear diffuse albedo (0 for metals by convention, kept as set)
    double gloss = 0.7;   // base gloss in the preset's gloss encoding, [0, 1]
    QString normalMapPath;
    QString glossMapPath;
    QString detailMapPath;
    /// The normal (detail) map was loaded past the normal-map plausibility check, which refused it: the
    /// artist chose "Load Anyway" (`burnish bake --allow-implausible`). Reset by loading another map.
    bool allowImplausibleNormal = false;
    bool allowImplausibleDetail = false;
    Method method = Method::VarianceToGloss;
    /// The lobe mixture's lobes per texel, K in 1..kMaxMixtureLobes (with method mixture: the viewport's,
    /// and the export's lobe files mixture-lobe0..K−1).
    int mixtureLobes = kDefaultMixtureLobes;
    QString preset = "blackops";
    ExportSettings exportSettings;
    EnvironmentSettings environment;
    friend bool operator==(const MaterialSettings&, const MaterialSettings&) = default;
};

/// The decoded maps that go with a MaterialSettings (shared, immutable: undo steps share them).
struct LoadedMaps {
    std::shared_ptr<const NormalMap> normal; // never null: the sample when no path is set
    std::shared_ptr<const Image> gloss;      // null when no gloss map
    std::shared_ptr<const NormalMap> detail; // null when no detail map
};

/// Both painted layers as one value: what an edit that changes them wholesale (a normal map of
/// another size, a preset of another gloss encoding) keeps for its undo.
struct PaintLayers {
    PaintLayer gloss;
    PaintLayer offset;
};

/// One map decoded from its file, not yet in a document (MaterialDocument::decodeMap).
struct DecodedMap {
    MapSlot slot = MapSlot::Normal;
    QString path;
    std::shared_ptr<const NormalMap> normal; // MapSlot::Normal
    std::shared_ptr<const Image> gloss;      // MapSlot::Gloss
    std::shared_ptr<const NormalMap> detail; // MapSlot::Detail
    /// Not empty: the normal-map plausibility check refused the map, for this reason; the map above was
    /// decoded past the check, and a document takes it only when `accepted` (the artist's "Load Anyway").
    QString refusal;
    bool accepted = false;
};

/// A painted layer saved as a file (a project's "layers" entry; path absolute).
struct LayerFile {
    PaintLayerKind kind = PaintLayerKind::Gloss;
    QString path;
};

/// Name of the built-in sample a new document starts with.
inline constexpr const char* kSampleName = "hammered";
/// Side of the built-in sample map in texels.
inline constexpr int kSampleSize = 512;
/// The calibrated material a new document starts with.
inline constexpr const char* kDefaultMaterial = "iron";

class MaterialDocument : public QObject {
    Q_OBJECT
public:
    explicit MaterialDocument(QObject* parent = nullptr);
    ~MaterialDocument() override;

    const MaterialSettings& settings() const { return m_settings; }
    const LoadedMaps& maps() const { return m_maps; }
    QUndoStack* undoStack() { return &m_undo; }

    /// The preset named by settings().preset (a built-in; never fails on a valid document).
    const Preset& preset() const;
    /// Methods the current preset can store, in report order.
    std::vector<Method> availableMethods() const;
    /// Blinn-Phong power of the base gloss under the preset's encoding.
    double power() const;
    /// The diagnostics the decoder reported for a slot's map, as short lines (empty when none).
    QStringList diagnostics(MapSlot slot) const;

    // Edits: each pushes one undo step (nothing when the value does not change).
    void setMaterialClass(MaterialClass c);
    /// Specular colour from core's calibrated table; fails on an unknown name.
    Status setSpecularMaterial(const QString& name);
    /// A custom linear specular colour (channels clamped to [0, 1]).
    void setCustomSpecular(const LinearRgb& f0);
    void setAlbedo(const LinearRgb& albedo);
    /// Base gloss in [0, 1]. With merge, consecutive calls inside one drag become one undo step.
    void setGloss(double gloss, bool merge = false);
    /// Ends a slider drag: the next merging edit starts a new undo step.
    void endMerge() { ++m_mergeEpoch; }
    /// Fails when the preset cannot store the method.
    Status setMethod(Method method);
    /// The mixture's lobe count K (clamped to 1..kMaxMixtureLobes); kept with other methods.
    void setMixtureLobes(int lobes);
    /// Switches preset keeping the base power (gloss re-encoded); the method is kept when the
    /// preset stores it, else the preset's default. Fails on an unknown preset.
    Status setPreset(const QString& name);
    /// Loads a map through core (loadNormalMap / readImage); on error nothing changes.
    Status loadMap(MapSlot slot, const QString& path);
    /// loadMap with the decoding on a worker thread, so the window never waits on a big file:
    /// mapLoadStarted now, mapLoadFinished when the map is in (one undo step) or refused. A newer
    /// request for the slot supersedes an older one, whose result is dropped.
    void loadMapInBackground(MapSlot slot, const QString& path);
    /// Whether a background load of the slot is in flight.
    bool loading(MapSlot slot) const;
    /// The expensive half of loadMap: reads and decodes the file (any thread; no document state). A
    /// normal or detail map the plausibility check refuses is decoded past it, once, and returned with
    /// its `refusal`.
    static Result<DecodedMap> decodeMap(MapSlot slot, const QString& path);
    /// The other half, on the document's thread: checks the map against the document (a gloss map
    /// has the normal map's size), carries the painted layers over, pushes one undo step. A map with a
    /// refusal is refused unless accepted.
    Status applyDecodedMap(const DecodedMap& decoded);
    /// A background load the plausibility check refused is held, decoded, until the artist decides:
    /// whether the slot holds one (mapLoadFinished said why it was not loaded), and taking it in as
    /// loaded anyway (one undo step, allowImplausible* set) or dropping it. A newer load of the slot, a
    /// reset or a cleared map drops it.
    bool holdsRefusedMap(MapSlot slot) const;
    Status acceptRefusedMap(MapSlot slot);
    void dropRefusedMap(MapSlot slot);
    /// Removes a map (the normal slot returns to the built-in sample).
    void clearMap(MapSlot slot);
    void setExportSettings(const ExportSettings& exportSettings);
    /// The viewport's environment; out-of-range values are clamped. With merge, consecutive calls
    /// inside one slider drag become one undo step (ended by endMerge()).
    void setEnvironment(const EnvironmentSettings& environment, bool merge = false);

    /// Replaces the whole document (a loaded project): every map is loaded and every name checked
    /// first; on error nothing changes. Clears the undo history and marks the document clean.
    /// `layers` are painted layers to load (EXR files of the normal map's size).
    Status reset(const MaterialSettings& settings, const std::vector<LayerFile>& layers = {});
    /// The settings of a new document: the calibrated default material on the built-in sample.
    static MaterialSettings defaultSettings();

    /// Loads the maps of `settings` without touching the document.
    static Result<LoadedMaps> loadMaps(const MaterialSettings& settings);
    /// Checks the names of `settings` (preset, method for the preset, material, values in range).
    static Status validate(const MaterialSettings& settings);

    /// Applies a state without an undo step (used by the undo commands); `layers`, when given,
    /// replace both painted layers (they match the normal map's size).
    void apply(const MaterialSettings& settings, const LoadedMaps& maps, const PaintLayers* layers = nullptr);

    // Painting (paint_tool.h): two layers of the normal map's size, composited into the authored
    // gloss the bake and the renderer read. Strokes are undo steps of the paint tool.
    const PaintLayer& paintLayer(PaintLayerKind kind) const;
    /// The authored gloss with the layers applied, one value per normal-map texel in the preset's
    /// encoding; null when there is no gloss map and nothing is painted (the base power applies).
    /// A snapshot: later edits never change what a caller holds, and the first call after a change
    /// returns a new pointer, so the renderer's bake cache (keyed on it) sees it. Taking one after a
    /// stroke's dab copies the texels changed since that buffer was last handed out, not the map
    /// (buffers nobody else holds any more are reused).
    std::shared_ptr<const std::vector<float>> authoredGloss() const;
    /// Makes, on a worker thread, the big arrays a first stroke on `kind` needs (the layer's value and
    /// coverage, the authored gloss before any paint, the snapshot buffers), and hands them to the
    /// document when ready if nothing they depend on changed meanwhile: on an 8192² map allocating them
    /// at the first dab stalled it for seconds. The values are exactly those the stroke would make.
    void prepareForPainting(PaintLayerKind kind);
    /// The current authored values (null where authoredGloss() is), read in place: for readers on the
    /// GUI thread that use them at once (the paint tool's live bake on each dab), never to keep.
    const std::vector<float>* authoredValues() const { return m_authored.get(); }
    /// The layer a stroke in progress paints into; report each change with layerEdited().
    PaintLayer& editablePaintLayer(PaintLayerKind kind);
    /// Recomposites the authored gloss inside `rect` and emits layersChanged(rect).
    void layerEdited(PaintLayerKind kind, const TexelRect& rect);
    /// Writes a patch into a layer (the paint undo commands), then as layerEdited and changed().
    void applyPaintPatch(PaintLayerKind kind, const PaintPatch& patch);
    /// A stroke whose dabs were reported through layerEdited() became an undo step: emits changed()
    /// (the layers and the authored gloss already hold it; writing the stroke's rectangle again would
    /// rebake it for nothing).
    void strokeCommitted() { emit changed(); }

    /// The authored gloss without paint: the gloss map's values at the normal map's size, or null
    /// where there is no gloss map (settings().gloss on every texel then).
    const std::vector<float>* unpaintedGloss();

signals:
    /// Any setting changed (by an edit, undo/redo or reset).
    void changed();
    /// A slot's map changed (loaded, cleared, undone or reset).
    void mapChanged(MapSlot slot);
    /// A background load began / ended (ok, or the error message), loadMapInBackground.
    void mapLoadStarted(MapSlot slot, const QString& path);
    void mapLoadFinished(MapSlot slot, const QString& path, bool ok, const QString& error);
    /// Something the artist should know happened to their work (painted layers resampled to a new
    /// map's size, re-encoded for a new preset): one line for the status bar.
    void notice(const QString& text);
    /// Painted texels changed inside `rect` (finest texels of the normal map).
    void layersChanged(burnish::TexelRect rect);

private:
    void push(const MaterialSettings& after, const LoadedMaps& maps, const QString& text, int mergeField,
              std::shared_ptr<const PaintLayers> layersAfter = nullptr);
    /// The painted layers carried over to a normal map of `width` × `height` (resampled) and to
    /// `encoding` (painted gloss re-encoded to keep its power); null when nothing is painted or
    /// nothing changes for them. `what` says what happened, for notice().
    Result<std::shared_ptr<const PaintLayers>>
    carriedLayers(int width, int height, const GlossEncoding& encoding, QString* what) const;
    /// push() of an edit to `maps` under `encoding` with the painted layers carried over (one undo
    /// step that restores them exactly) and a notice when they were; refused, with nothing changed,
    /// if they cannot be carried.
    Status pushCarryingLayers(const MaterialSettings& after, const LoadedMaps& maps, const QString& text,
                              const GlossEncoding& encoding);
    /// Recomputes the authored gloss inside `rect` (all of it when the inputs changed).
    void recomposite(const TexelRect& rect, bool full);
    /// Starts a worker thread the destructor waits for (m_loaders), deleted once finished.
    void startWorker(QThread* worker);

    MaterialSettings m_settings;
    LoadedMaps m_maps;
    std::array<std::optional<DecodedMap>, 3> m_refused; // per MapSlot: a refused map held for "Load Anyway"
    QUndoStack m_undo;
    int m_mergeEpoch = 0;
    PaintLayer m_glossLayer;
    PaintLayer m_offsetLayer;
    std::shared_ptr<std::vector<float>> m_authored; // the working values, edited in place
    // Snapshots authoredGloss() handed out, each with the rectangle edited since it was last brought up
    // to date; one nobody else holds is brought up to date and handed out again.
    struct AuthoredSnapshot {
        std::shared_ptr<std::vector<float>> values;
        TexelRect stale;
    };
    mutable std::vector<AuthoredSnapshot> m_snapshots;
    mutable std::shared_ptr<const std::vector<float>> m_published; // null: an edit since the last one
    // The authored gloss before any paint (the base gloss everywhere), made by prepareForPainting() for
    // what it was made from; the first dab takes it instead of compositing the whole map.
    struct PreparedAuthored {
        std::shared_ptr<std::vector<float>> values;
        std::shared_ptr<const NormalMap> normal;
        double gloss = 0.0;
        QString preset;
        std::vector<std::shared_ptr<std::vector<float>>> snapshots; // spare buffers holding the same values
    };
    PreparedAuthored m_preparedAuthored;
    quint64 m_prepareGeneration = 0;
    // The gloss map as values of the normal map's size (what recomposite() blends over), made once per map.
    std::shared_ptr<const std::vector<float>> m_baseGloss;
    std::shared_ptr<const Image> m_baseGlossOf;
    // Background loads per slot: the newest request's number and the last one that arrived.
    std::array<quint64, 3> m_loadGeneration{};
    std::array<quint64, 3> m_loadDone{};
    std::vector<QThread*> m_loaders; // in flight, waited for by the destructor
};

/// What the preset stores, in the studio's words: "Gloss", "Roughness", "Smoothness", "Alpha"
/// (lower case with capitalised = false), so a roughness preset never says gloss.
QString glossQuantity(const GlossEncoding& encoding, bool capitalised = true);

/// Decimals a gloss field keeps: what is typed to four places (0.4567), finer than an 8-bit channel's
/// step (1/255) and as fine as a person types.
inline constexpr int kGlossDecimals = 4;
/// A gloss value as the studio writes it (history, status bar): four places, a trailing zero of the
/// fourth dropped ("0.450", "0.4567").
QString glossText(double gloss);

/// The built-in sample normal map (shared; made once).
std::shared_ptr<const NormalMap> sampleNormalMap();

} // namespace burnish::studio
