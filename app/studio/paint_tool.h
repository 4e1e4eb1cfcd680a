// The brush: paints the document's gloss or variance-offset layer on the 2D texture view and on
// the 3D viewport (through its UV picking), with size, hardness, opacity, an eyedropper and
// "clear layer"; each stroke is one undo step storing the changed rectangle before and after.
// While painting, the variance-to-gloss bake of the painted gloss is kept live (core's
// LiveGlossBake: only the dirty region's mips are recomputed) and the view shows where the painted
// gloss over-shines: asks for more shine than the normal variance at the chosen mip permits.
#pragma once

#include "material_document.h"

#include <burnish/core/bake/paint.h>

#include <QImage>
#include <QPointF>
#include <QWidget>

#include <optional>

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QPushButton;
class QSpinBox;
class QThread;

namespace burnish::studio {

class TextureView;
class Viewport;

/// Warning colour of over-shining texels in the overlay (an orange no gloss grey can be).
inline constexpr unsigned kOverShineColor = 0xffff6a00u;

class PaintTool : public QWidget {
    Q_OBJECT
public:
    PaintTool(MaterialDocument* doc, TextureView* view, QWidget* parent = nullptr);
    ~PaintTool() override;

    /// Connects strokes on the 3D viewport (its paintAt/strokeFinished signals).
    void attachViewport(Viewport* viewport);

    void setPaintMode(bool on);
    bool paintMode() const { return m_paintMode; }
    /// Whether the Paint panel is in view (its dock's visibility; true until told otherwise). The
    /// views paint only while paint mode is on and the panel shows it: with the panel hidden behind a
    /// tab or closed, a drag on the 3D view orbits (painting by accident otherwise).
    void setPanelVisible(bool visible);
    /// Paint mode on and its panel in view: what the views' left button does.
    bool armed() const { return m_paintMode && m_panelVisible; }
    /// The live bake is built on a worker thread (the studio; an 8192² map's took half a minute on the
    /// GUI thread); strokes paint meanwhile and it catches up with them when it lands. Off (tests that
    /// read it right after a change): built at once.
    void setBackgroundBakes(bool on) { m_background = on; }
    /// A background live bake is being built.
    bool liveBuilding() const { return m_liveBuilding; }
    /// The live bake when it holds every stroke so far (paint mode on, built, nothing missed), else
    /// null: what the 3D view draws a stroke from.
    const LiveGlossBake* currentLive() const;
    void setLayer(PaintLayerKind kind);
    PaintLayerKind layer() const { return m_layer; }
    void setBrush(const Brush& brush);
    const Brush& brush() const { return m_brush; }
    /// Arms the eyedropper for the next click: only in paint mode (turning paint mode off disarms
    /// it). A pick sets the brush's value as one undo step ("Pick gloss 0.45").
    void setEyedropper(bool on);
    bool eyedropper() const { return m_eyedropper; }
    /// The value under a texel: the authored gloss (gloss layer) or the painted variance.
    float pickAt(QPointF texel) const;
    /// Clears the current layer (one undo step).
    void clearLayer();
    /// The mip whose normal variance the over-shine warning compares with.
    void setOverShineMip(int mip);

    // A stroke, in texel coordinates (the view's and viewport's handlers call these).
    void pressAt(QPointF texel);
    void moveTo(QPointF texel);
    void release();

    /// The live bake of the painted gloss (null before paint mode or when it cannot be made).
    const LiveGlossBake* liveBake() const { return m_live ? &*m_live : nullptr; }
    const OverShineMap& overShineMap() const { return m_overShine; }
    /// Texels recomputed by the last live update (all mips).
    size_t lastRecomputedTexels() const { return m_live ? m_live->lastRecomputedTexels() : 0; }

signals:
    /// The live bake or the over-shine map changed.
    void liveUpdated();
    /// Paint mode was switched on or off.
    void paintModeChanged(bool on);

private:
    void syncWidgets();
    /// The views' paint mode: armed().
    void applyViewModes();
    /// Hands the last rebakeRegion's rectangles to the attached viewport.
    void liveRebaked();
    /// The document's gloss without paint, for the over-shine warning (only paint that raised the
    /// shine is flagged).
    UnpaintedGloss unpainted() const;
    /// The gloss layer and its tooltips in the preset's own word (gloss or roughness).
    void retitle();
    QString term(bool capitalised = true) const;
    QString layerTitle(PaintLayerKind kind) const;
    void readWidgets();
    void onDocumentChanged();
    void onLayersChanged(const TexelRect& rect);
    void rebuildLive();
    /// A live bake built for generation `generation` arrived (at once, or from a background build):
    /// catches up with strokes painted meanwhile, then over-shine, the overlay and liveUpdated.
    void liveBuilt(quint64 generation, Result<LiveGlossBake> live);
    /// Starts a worker the destructor waits for (m_liveWorkers), deleted once finished.
    void startWorker(QThread* worker);
    /// The first overlay of a background build arrived.
    void overlayBuilt(const QImage& image);
    void updateOverlay(const std::optional<TexelRect>& rect);
    std::vector<float> currentAuthored() const;

    MaterialDocument* m_doc;
    TextureView* m_view;
    Viewport* m_viewport = nullptr;
    bool m_paintMode = false;
    bool m_panelVisible = true;
    bool m_eyedropper = false;
    PaintLayerKind m_layer = PaintLayerKind::Gloss;
    Brush m_brush;
    int m_overShineMip = 3;
    std::optional<PaintStroke> m_stroke;
    std::optional<glm::dvec2> m_lastPoint;
    std::optional<LiveGlossBake> m_live;
    bool m_background = false;
    bool m_liveBuilding = false;
    quint64 m_liveGeneration = 0;
    TexelRect m_liveMissed;              // painted while a background build ran: rebaked when it lands
    std::vector<QThread*> m_liveWorkers; // in flight, waited for by the destructor
    bool m_overlayPending = false;       // the first overlay of a background build is being made
    TexelRect m_overlayMissed;           // dabs before it landed
    QString m_liveKey;                   // what the live bake was made from (rebuilt when it changes)
    OverShineMap m_overShine;

    QPushButton* m_paintButton;
    QComboBox* m_layerCombo;
    QDoubleSpinBox* m_radiusSpin;
    QDoubleSpinBox* m_hardnessSpin;
    QDoubleSpinBox* m_opacitySpin;
    QDoubleSpinBox* m_valueSpin;
    QPushButton* m_eyedropperButton;
    QPushButton* m_clearButton;
    QCheckBox* m_overShineCheck;
    QCheckBox* m_showBakedCheck;
    QSpinBox* m_mipSpin;
    QLabel* m_status;
};

} // namespace burnish::studio
