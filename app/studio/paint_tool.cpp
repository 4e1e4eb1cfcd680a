#include "paint_tool.h"

#include "texture_view.h"
#include "viewport.h"

#include <QCheckBox>
#include <QComboBox>
#include <QCoreApplication>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QPointer>
#include <QPushButton>
#include <QSpinBox>
#include <QThread>
#include <QUndoCommand>

#include <algorithm>
#include <cmath>
#include <functional>

namespace burnish::studio {

namespace {

// A jump of more than a quarter of the map between two viewport events is a UV seam or another
// island, not a drag: the stroke restarts there instead of drawing a line across the map.
constexpr double kSeamJumpFraction = 0.25;
// Over-shining texels: the warning colour over the grey at this strength, so the gloss under it
// stays readable.
constexpr double kOverShineMix = 0.65;

/// An eyedropper pick: the brush's value before and after (`set` applies one to the tool).
class PickCommand : public QUndoCommand {
public:
    PickCommand(const QString& text, std::function<void(float)> set, float before, float after)
        : QUndoCommand(text)
        , m_set(std::move(set))
        , m_before(before)
        , m_after(after) {}
    void redo() override { m_set(m_after); }
    void undo() override { m_set(m_before); }

private:
    std::function<void(float)> m_set;
    float m_before;
    float m_after;
};

/// One stroke (or a clear) on a layer: the changed rectangle before and after.
class PaintCommand : public QUndoCommand {
public:
    /// `painted`: the layer already holds `after` (a stroke's dabs wrote it as they came).
    PaintCommand(MaterialDocument* doc, PaintLayerKind kind, PaintPatch before, PaintPatch after,
                 const QString& text, bool painted)
        : QUndoCommand(text)
        , m_doc(doc)
        , m_kind(kind)
        , m_before(std::move(before))
        , m_after(std::move(after))
        , m_first(painted) {}

    // A stroke's first redo (from push) finds it already painted: it only tells the document's
    // listeners that the stroke is done. Later ones (redo after undo) write it again.
    void redo() override {
        if (m_first) {
            m_first = false;
            m_doc->strokeCommitted();
            return;
        }
        m_doc->applyPaintPatch(m_kind, m_after);
    }
    void undo() override { m_doc->applyPaintPatch(m_kind, m_before); }

private:
    MaterialDocument* m_doc;
    PaintLayerKind m_kind;
    PaintPatch m_before;
    PaintPatch m_after;
    bool m_first;
};

// An authored value as the overlay draws it where nothing warns.
QRgb authoredGrey(float g) {
    const int v = toByte(std::clamp(double(g), 0.0, 1.0));
    return qRgb(v, v, v);
}

QString qs(std::string_view s) {
    return QString::fromUtf8(s.data(), int(s.size()));
}

} // namespace

PaintTool::PaintTool(MaterialDocument* doc, TextureView* view, QWidget* parent)
    : QWidget(parent)
    , m_doc(doc)
    , m_view(view) {
    m_paintButton = new QPushButton("Paint", this);
    m_paintButton->setCheckable(true);
    m_paintButton->setObjectName("paintButton");
    // On and off must look different: a checked button in the studio's dark style barely does.
    m_paintButton->setStyleSheet("QPushButton:checked { background: palette(highlight); "
                                 "color: palette(highlighted-text); font-weight: bold; }");
    m_paintButton->setToolTip("Paint mode: the left button paints on the texture view and the 3D view");
    m_layerCombo = new QComboBox(this);
    m_layerCombo->addItem("Gloss", int(PaintLayerKind::Gloss));
    m_layerCombo->addItem("Variance offset", int(PaintLayerKind::VarianceOffset));
    auto spin = [this](double lo, double hi, double step, int decimals, const QString& tip) {
        auto* s = new QDoubleSpinBox(this);
        s->setRange(lo, hi);
        s->setSingleStep(step);
        s->setDecimals(decimals);
        s->setToolTip(tip);
        s->setKeyboardTracking(false); // commit on Enter or focus-out, not per keystroke
        return s;
    };
    m_radiusSpin = spin(kMinBrushRadius, 1024.0, 1.0, 1, "Brush radius in texels of the finest level");
    m_hardnessSpin = spin(0.0, 1.0, 0.05, 2, "Fraction of the radius painted at full strength");
    m_opacitySpin = spin(0.0, 1.0, 0.05, 2, "The most one stroke changes a texel");
    m_valueSpin = spin(0.0, 1.0, 0.01, kGlossDecimals, {}); // its tooltip names the preset's term: retitle
    m_radiusSpin->setObjectName("paintRadius");
    m_hardnessSpin->setObjectName("paintHardness");
    m_opacitySpin->setObjectName("paintOpacity");
    m_valueSpin->setObjectName("paintValue");
    m_eyedropperButton = new QPushButton("Eyedropper", this);
    m_eyedropperButton->setCheckable(true);
    m_eyedropperButton->setObjectName("paintEyedropper");
    m_eyedropperButton->setToolTip("Pick the value under the cursor on the next click (in paint mode; "
                                   "Ctrl+Z undoes the pick)");
    m_eyedropperButton->setStyleSheet(m_paintButton->styleSheet());
    m_clearButton = new QPushButton("Clear layer", this);
    m_overShineCheck = new QCheckBox("Show over-shine", this);
    m_overShineCheck->setChecked(true);
    m_showBakedCheck = new QCheckBox("Show the live bake at the mip", this);
    m_mipSpin = new QSpinBox(this);
    m_mipSpin->setPrefix("mip ");
    m_mipSpin->setRange(0, 16);
    m_mipSpin->setKeyboardTracking(false);
    m_status = new QLabel(this);
    m_status->setObjectName("paintStatus");
    m_status->setWordWrap(true);

    auto* buttons = new QHBoxLayout;
    buttons->addWidget(m_paintButton);
    buttons->addWidget(m_eyedropperButton);
    buttons->addWidget(m_clearButton);
    auto* form = new QFormLayout(this);
    form->addRow(buttons);
    form->addRow("Layer", m_layerCombo);
    form->addRow("Radius", m_radiusSpin);
    form->addRow("Hardness", m_hardnessSpin);
    form->addRow("Opacity", m_opacitySpin);
    form->addRow("Value", m_valueSpin);
    form->addRow(m_overShineCheck, m_mipSpin);
    form->addRow(m_showBakedCheck);
    form->addRow(m_status);

    syncWidgets();
    retitle();
    m_mipSpin->setValue(m_overShineMip);
    connect(m_paintButton, &QPushButton::toggled, this, &PaintTool::setPaintMode);
    connect(m_eyedropperButton, &QPushButton::toggled, this, &PaintTool::setEyedropper);
    connect(m_clearButton, &QPushButton::clicked, this, &PaintTool::clearLayer);
    connect(m_layerCombo, &QComboBox::currentIndexChanged, this,
            [this](int i) { setLayer(PaintLayerKind(m_layerCombo->itemData(i).toInt())); });
    for (QDoubleSpinBox* s : {m_radiusSpin, m_hardnessSpin, m_opacitySpin, m_valueSpin})
        connect(s, &QDoubleSpinBox::valueChanged, this, &PaintTool::readWidgets);
    connect(m_mipSpin, &QSpinBox::valueChanged, this, &PaintTool::setOverShineMip);
    connect(m_overShineCheck, &QCheckBox::toggled, this, [this] { updateOverlay(std::nullopt); });
    connect(m_showBakedCheck, &QCheckBox::toggled, this, [this] { updateOverlay(std::nullopt); });

    connect(m_view, &TextureView::paintPressed, this, &PaintTool::pressAt);
    connect(m_view, &TextureView::paintMoved, this, &PaintTool::moveTo);
    connect(m_view, &TextureView::paintReleased, this, &PaintTool::release);
    connect(m_doc, &MaterialDocument::changed, this, &PaintTool::retitle);
    connect(m_doc, &MaterialDocument::changed, this, &PaintTool::onDocumentChanged);
    connect(m_doc, &MaterialDocument::layersChanged, this, &PaintTool::onLayersChanged);
}

PaintTool::~PaintTool() {
    // A live bake still building finishes (it touches nothing of the tool) before the tool goes.
    for (QThread* worker : m_liveWorkers)
        worker->wait();
}

void PaintTool::attachViewport(Viewport* viewport) {
    m_viewport = viewport;
    viewport->setPaintMode(armed());
    connect(viewport, &Viewport::paintAt, this, [this](QPointF uv, bool strokeStart) {
        const NormalMap& map = *m_doc->maps().normal;
        // uvAt's v grows upwards; texel rows grow downwards (image pixel (u·w, (1 − v)·h)).
        QPointF texel(uv.x() * map.width, (1.0 - uv.y()) * map.height);
        if (strokeStart || !m_stroke || !m_lastPoint) {
            pressAt(texel);
            return;
        }
        // The nearest image of the point to the last one, so a stroke crosses the wrap seam.
        const double dx = texel.x() - m_lastPoint->x, dy = texel.y() - m_lastPoint->y;
        texel -= QPointF(map.width * std::round(dx / map.width), map.height * std::round(dy / map.height));
        const double jump = std::hypot(texel.x() - m_lastPoint->x, texel.y() - m_lastPoint->y);
        if (jump > kSeamJumpFraction * std::min(map.width, map.height)) {
            m_lastPoint = glm::dvec2(texel.x(), texel.y());
            if (m_stroke->jumpTo(*m_lastPoint)) m_doc->layerEdited(m_layer, m_stroke->takeRecentDirty());
            return;
        }
        moveTo(texel);
    });
    connect(viewport, &Viewport::strokeFinished, this, &PaintTool::release);
    // The view draws a stroke from the live bake's rebaked texels instead of baking the map again.
    viewport->setLiveGloss([this]() -> const LiveGlossBake* { return currentLive(); });
}

UnpaintedGloss PaintTool::unpainted() const {
    return {m_doc->unpaintedGloss(), m_doc->settings().gloss};
}

const LiveGlossBake* PaintTool::currentLive() const {
    // Every stroke so far is in it: it exists, is not being built, and missed nothing.
    return m_paintMode && m_live && !m_liveBuilding && m_liveMissed.empty() ? &*m_live : nullptr;
}

void PaintTool::liveRebaked() {
    if (m_viewport && m_live) m_viewport->liveGlossRebaked(m_live->lastRecomputedRects());
}

void PaintTool::syncWidgets() {
    const QSignalBlocker b1(m_radiusSpin), b2(m_hardnessSpin), b3(m_opacitySpin), b4(m_valueSpin),
        b5(m_layerCombo), b6(m_eyedropperButton), b7(m_paintButton);
    m_radiusSpin->setValue(m_brush.radius);
    m_hardnessSpin->setValue(m_brush.hardness);
    m_opacitySpin->setValue(m_brush.opacity);
    m_valueSpin->setValue(m_brush.value);
    m_layerCombo->setCurrentIndex(m_layerCombo->findData(int(m_layer)));
    m_eyedropperButton->setChecked(m_eyedropper);
    m_eyedropperButton->setEnabled(m_paintMode);
    m_paintButton->setChecked(m_paintMode);
    m_paintButton->setText(m_paintMode ? "Painting" : "Paint");
    m_view->setBrushRadius(m_brush.radius);
}

void PaintTool::readWidgets() {
    Brush b = m_brush;
    b.radius = m_radiusSpin->value();
    b.hardness = m_hardnessSpin->value();
    b.opacity = m_opacitySpin->value();
    b.value = float(m_valueSpin->value());
    setBrush(b);
}

void PaintTool::setBrush(const Brush& brush) {
    // The spin boxes keep every value in range; a programmatic brush is checked the same way.
    if (!validateBrush(brush)) return;
    m_brush = brush;
    syncWidgets();
}

void PaintTool::setLayer(PaintLayerKind kind) {
    m_layer = kind;
    if (m_paintMode) m_doc->prepareForPainting(kind);
    syncWidgets();
}

void PaintTool::setEyedropper(bool on) {
    // Armed only where a click can pick: in paint mode (else it fired on the first click after
    // paint mode came on, long after it was armed).
    m_eyedropper = on && m_paintMode;
    syncWidgets();
}

void PaintTool::applyViewModes() {
    if (!armed() && m_stroke) release(); // a stroke in progress ends where the panel went
    m_view->setPaintMode(armed());
    if (m_viewport) m_viewport->setPaintMode(armed());
}

void PaintTool::setPanelVisible(bool visible) {
    if (visible == m_panelVisible) return;
    m_panelVisible = visible;
    applyViewModes();
}

void PaintTool::setPaintMode(bool on) {
    const bool changed = on != m_paintMode;
    m_paintMode = on;
    if (!on) m_eyedropper = false;
    applyViewModes();
    syncWidgets();
    if (on) {
        // The arrays a first stroke needs, made off the GUI thread while the artist aims.
        m_doc->prepareForPainting(m_layer);
        rebuildLive();
    } else {
        m_view->setOverlay({});
        m_status->clear();
    }
    if (changed) emit paintModeChanged(on);
}

void PaintTool::setOverShineMip(int mip) {
    m_overShineMip = std::max(0, mip);
    if (m_mipSpin->value() != m_overShineMip) m_mipSpin->setValue(m_overShineMip);
    if (m_live) {
        (void)overShine(*m_live, m_live->authoredGloss(), m_overShineMip, kOverShineStops,
                        &m_doc->paintLayer(PaintLayerKind::Gloss), m_overShine, std::nullopt, unpainted());
        updateOverlay(std::nullopt);
    }
}

std::vector<float> PaintTool::currentAuthored() const {
    if (const std::vector<float>* gloss = m_doc->authoredValues()) return *gloss;
    return std::vector<float>(m_doc->maps().normal->texelCount(), float(m_doc->settings().gloss));
}

float PaintTool::pickAt(QPointF texel) const {
    const NormalMap& map = *m_doc->maps().normal;
    // The texel under the point, wrapped like the brush.
    const int x = borderIndex(int(std::floor(texel.x())), map.width, BorderMode::Wrap);
    const int y = borderIndex(int(std::floor(texel.y())), map.height, BorderMode::Wrap);
    const size_t i = size_t(y) * size_t(map.width) + size_t(x);
    if (m_layer == PaintLayerKind::VarianceOffset) {
        const PaintLayer& l = m_doc->paintLayer(PaintLayerKind::VarianceOffset);
        return l.coverageAt(i) > 0.0f ? l.valueAt(i) : 0.0f;
    }
    if (const std::vector<float>* gloss = m_doc->authoredValues()) return (*gloss)[i];
    return float(m_doc->settings().gloss);
}

void PaintTool::pressAt(QPointF texel) {
    if (m_eyedropper) {
        setEyedropper(false);
        const float before = m_brush.value;
        const float picked = pickAt(texel);
        if (picked == before) return;
        // One undo step: Ctrl+Z right after a pick gives the value back (it undid the stroke before).
        QPointer<PaintTool> tool(this);
        auto set = [tool](float value) {
            if (!tool) return;
            Brush b = tool->m_brush;
            b.value = value;
            tool->setBrush(b);
        };
        const QString what = m_layer == PaintLayerKind::Gloss ? term(false) : QString("variance offset");
        m_doc->undoStack()->push(new PickCommand(
            QString("Pick %1 %2").arg(what).arg(double(picked), 0, 'f', 4), set, before, picked));
        return;
    }
    m_stroke.reset();
    auto stroke = PaintStroke::begin(m_doc->editablePaintLayer(m_layer), m_brush, BorderMode::Wrap);
    if (!stroke) {
        m_status->setText("cannot paint: " + QString::fromStdString(stroke.error()));
        return;
    }
    m_stroke.emplace(std::move(stroke).value());
    moveTo(texel);
}

void PaintTool::moveTo(QPointF texel) {
    if (!m_stroke) return;
    m_lastPoint = glm::dvec2(texel.x(), texel.y());
    if (!m_stroke->addPoint(*m_lastPoint)) return; // a non-finite position: nothing to paint
    m_doc->layerEdited(m_layer, m_stroke->takeRecentDirty());
}

void PaintTool::release() {
    if (!m_stroke) return;
    PaintStroke stroke = std::move(*m_stroke);
    m_stroke.reset();
    m_lastPoint.reset();
    if (stroke.dirty().empty()) return;
    const QString text = "Paint " + layerTitle(m_layer);
    m_doc->undoStack()->push(new PaintCommand(m_doc, m_layer, stroke.before(), stroke.after(), text, true));
}

void PaintTool::clearLayer() {
    const PaintLayer& l = m_doc->paintLayer(m_layer);
    // Only the painted rectangle goes into the undo step (a whole 8192² layer would be 512 MB twice).
    const TexelRect painted = paintedBounds(l);
    if (painted.empty()) return; // nothing to clear, no undo step
    PaintPatch before = copyPatch(l, painted);
    PaintPatch after = before;
    std::fill(after.value.begin(), after.value.end(), 0.0f);
    std::fill(after.coverage.begin(), after.coverage.end(), 0.0f);
    m_doc->undoStack()->push(new PaintCommand(m_doc, m_layer, std::move(before), std::move(after),
                                              "Clear " + layerTitle(m_layer) + " layer", false));
}

QString PaintTool::term(bool capitalised) const {
    return glossQuantity(m_doc->preset().encoding, capitalised);
}

QString PaintTool::layerTitle(PaintLayerKind kind) const {
    return kind == PaintLayerKind::Gloss ? term(false) : QString("variance offset");
}

void PaintTool::retitle() {
    // The preset's own word (roughness for gltf, unreal, …) wherever the gloss layer is named.
    m_layerCombo->setItemText(m_layerCombo->findData(int(PaintLayerKind::Gloss)), term());
    m_layerCombo->setToolTip(QString("%1 replaces the authored %2 (in the preset's encoding); a variance "
                                     "offset adds roughness as 1/(n+1)")
                                 .arg(term(), term(false)));
    m_valueSpin->setToolTip(
        QString("The value painted: %1 in the preset's encoding (0 to 1), or the variance offset")
            .arg(term(false)));
    m_overShineCheck->setToolTip(QString("Mark texels whose painted %1 asks for more shine than the normal "
                                         "variance at the chosen mip permits: there the highlight aliases")
                                     .arg(term(false)));
}

void PaintTool::onDocumentChanged() {
    if (!m_paintMode) return;
    const MaterialSettings& s = m_doc->settings();
    const QString key = QString("%1/%2/%3/%4/%5")
                            .arg(quintptr(m_doc->maps().normal.get()))
                            .arg(quintptr(m_doc->maps().gloss.get()))
                            .arg(s.gloss, 0, 'g', 17)
                            .arg(s.preset, qs(methodName(s.method)));
    // Paint undo/redo arrive through layersChanged; anything else that feeds the bake rebuilds it.
    if (key != m_liveKey) rebuildLive();
}

void PaintTool::rebuildLive() {
    m_live.reset();
    const quint64 generation = ++m_liveGeneration;
    m_liveBuilding = false;
    m_liveMissed = {};
    m_overlayPending = false;
    const MaterialSettings& s = m_doc->settings();
    m_liveKey = QString("%1/%2/%3/%4/%5")
                    .arg(quintptr(m_doc->maps().normal.get()))
                    .arg(quintptr(m_doc->maps().gloss.get()))
                    .arg(s.gloss, 0, 'g', 17)
                    .arg(s.preset, qs(methodName(s.method)));
    BakeOptions options;
    // LEAN and CLEAN store no gloss texture, and the fitted lobe's gloss needs the footprint's shading
    // (not the moments the live bake keeps per texel): the live view shows variance-to-gloss for them,
    // which is also what the over-shine measure compares with. The 3D view draws the method itself.
    options.method = hasTexture(s.method, TextureRole::Gloss) && s.method != Method::Fitted
                         ? s.method
                         : Method::VarianceToGloss;
    options.encoding = m_doc->preset().encoding;
    options.basePower = m_doc->power();
    if (!m_background) {
        options.authoredGloss = currentAuthored();
        liveBuilt(generation, LiveGlossBake::create(m_doc->maps().normal, options));
        return;
    }
    // On a worker: the map, a snapshot of the authored gloss (never changed under it) or the base
    // gloss, and the options. Strokes meanwhile are remembered and rebaked when it lands.
    m_liveBuilding = true;
    m_status->setText(
        QString("Preparing the live bake of the painted %1… (paint away: it catches up)").arg(term(false)));
    const std::shared_ptr<const NormalMap> normal = m_doc->maps().normal;
    const std::shared_ptr<const std::vector<float>> authored = m_doc->authoredGloss();
    const float base = float(s.gloss);
    QPointer<PaintTool> self(this);
    QThread* worker = QThread::create([self, generation, normal, authored, base, options]() mutable {
        options.authoredGloss = authored ? *authored : std::vector<float>(normal->texelCount(), base);
        auto live = std::make_shared<Result<LiveGlossBake>>(LiveGlossBake::create(normal, options));
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, generation, live] {
                if (self) self->liveBuilt(generation, std::move(*live));
            },
            Qt::QueuedConnection);
    });
    startWorker(worker);
    // The overlay (the authored gloss in grey: an 8192² image is 256 MB to fill) on a worker as well;
    // dabs before it lands are drawn into it when it does.
    m_overlayPending = true;
    m_overlayMissed = {};
    QThread* painter = QThread::create([self, generation, normal, authored, base] {
        QImage image(normal->width, normal->height, QImage::Format_RGB32);
        for (int y = 0; y < normal->height; ++y) {
            auto* row = reinterpret_cast<QRgb*>(image.scanLine(y));
            for (int x = 0; x < normal->width; ++x) {
                const float g = authored ? (*authored)[size_t(y) * size_t(normal->width) + size_t(x)] : base;
                row[x] = authoredGrey(g);
            }
        }
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, generation, image = std::move(image)] {
                if (self && self->m_liveGeneration == generation) self->overlayBuilt(image);
            },
            Qt::QueuedConnection);
    });
    startWorker(painter);
}

void PaintTool::overlayBuilt(const QImage& image) {
    m_overlayPending = false;
    if (!m_paintMode || m_live) return; // the live bake landed first and drew the overlay itself
    m_view->setOverlay(image);
    if (const TexelRect missed = std::exchange(m_overlayMissed, {}); !missed.empty()) updateOverlay(missed);
}

void PaintTool::startWorker(QThread* worker) {
    m_liveWorkers.push_back(worker);
    connect(worker, &QThread::finished, this, [this, worker] {
        std::erase(m_liveWorkers, worker);
        worker->deleteLater();
    });
    worker->start();
}

void PaintTool::liveBuilt(quint64 generation, Result<LiveGlossBake> live) {
    if (generation != m_liveGeneration) return; // superseded by a newer build
    m_liveBuilding = false;
    if (!live) {
        m_status->setText("live bake failed: " + QString::fromStdString(live.error()));
        m_view->setOverlay({});
        return;
    }
    m_live.emplace(std::move(live).value());
    // A new live chain: the view takes it whole once before it takes regions of it again.
    if (m_viewport) m_viewport->liveGlossRebuilt();
    // Strokes painted while it was built: their rectangle, from the document's values now.
    const TexelRect missed = std::exchange(m_liveMissed, {});
    if (!missed.empty()) {
        // (No authored values left after those strokes: the paint was all erased. Built again.)
        const std::vector<float>* authored = m_doc->authoredValues();
        if (!authored || !m_live->rebakeRegion(*authored, missed)) {
            rebuildLive();
            return;
        }
    }
    m_mipSpin->setRange(0, m_live->levelCount() - 1);
    (void)overShine(*m_live, m_live->authoredGloss(), m_overShineMip, kOverShineStops,
                    &m_doc->paintLayer(PaintLayerKind::Gloss), m_overShine, std::nullopt, unpainted());
    updateOverlay(std::nullopt);
    emit liveUpdated();
}

void PaintTool::onLayersChanged(const TexelRect& rect) {
    if (!m_paintMode) return;
    if (m_liveBuilding) {
        m_liveMissed.unite(rect);
        updateOverlay(rect);
        return;
    }
    if (!m_live) {
        rebuildLive();
        return;
    }
    // The document's values in place: a dab changes a few texels, and copying an 8192² map's 256 MB on
    // each would freeze the stroke.
    const std::vector<float>* authored = m_doc->authoredValues();
    if (!authored || !m_live->rebakeRegion(*authored, rect)) {
        rebuildLive();
        return;
    }
    liveRebaked();
    (void)overShine(*m_live, *authored, m_overShineMip, kOverShineStops,
                    &m_doc->paintLayer(PaintLayerKind::Gloss), m_overShine, rect, unpainted());
    updateOverlay(rect);
    emit liveUpdated();
}

void PaintTool::updateOverlay(const std::optional<TexelRect>& rect) {
    if (!m_paintMode || (!m_live && !m_liveBuilding)) return;
    if (!m_live && m_overlayPending) {
        // The overlay is still being made: the dab is drawn into it when it lands.
        m_overlayMissed.unite(
            rect.value_or(TexelRect::full(m_doc->maps().normal->width, m_doc->maps().normal->height)));
        return;
    }
    if (m_showBakedCheck->isChecked()) {
        if (!m_live) return; // the live bake is still being built: nothing baked to show yet
        const int k = std::clamp(m_overShineMip, 0, m_live->levelCount() - 1);
        const TextureMip& mip = m_live->gloss().mips[size_t(k)];
        QImage image(mip.width, mip.height, QImage::Format_ARGB32);
        for (int y = 0; y < mip.height; ++y)
            for (int x = 0; x < mip.width; ++x) {
                const int g = toByte(mip.texels[size_t(y) * size_t(mip.width) + size_t(x)]);
                image.setPixel(x, y, qRgb(g, g, g));
            }
        m_view->setOverlay(image);
    } else {
        const NormalMap& map = *m_doc->maps().normal;
        const int w = map.width, h = map.height;
        TexelRect r = rect.value_or(TexelRect::full(w, h));
        // Written in place into the view's overlay (an opaque RGB32 image): a dab rewrites its own
        // rectangle, never the whole image.
        if (m_view->overlay().width() != w || m_view->overlay().height() != h ||
            m_view->overlay().format() != QImage::Format_RGB32) {
            m_view->setOverlay(QImage(w, h, QImage::Format_RGB32));
            r = TexelRect::full(w, h);
        }
        QImage& overlay = m_view->overlayForEdit();
        // While a background build runs, the document's values (the over-shine warning comes with it).
        const std::vector<float>* values = m_live ? &m_live->authoredGloss() : m_doc->authoredValues();
        const float base = float(m_doc->settings().gloss);
        auto authoredAt = [&](size_t i) { return values ? (*values)[i] : base; };
        const bool warn =
            m_live && m_overShineCheck->isChecked() && m_overShine.flagged.size() == map.texelCount();
        const QColor warning = QColor::fromRgba(kOverShineColor);
        for (int y = r.y0; y < r.y1; ++y) {
            auto* row = reinterpret_cast<QRgb*>(overlay.scanLine(y));
            for (int x = r.x0; x < r.x1; ++x) {
                const size_t i = size_t(y) * size_t(w) + size_t(x);
                const double g = std::clamp(double(authoredAt(i)), 0.0, 1.0);
                if (warn && m_overShine.flagged[i]) {
                    auto mix = [&](int c) {
                        return toByte((kOverShineMix * c / 255.0) + (1 - kOverShineMix) * g);
                    };
                    row[x] = qRgb(mix(warning.red()), mix(warning.green()), mix(warning.blue()));
                } else {
                    row[x] = authoredGrey(float(g));
                }
            }
        }
        m_view->overlayChanged(QRect(r.x0, r.y0, r.width(), r.height()));
    }
    if (!m_live) return; // the status says the live bake is being prepared
    m_status->setText(QString("%1 of %2 texels over-shine at mip %3 (painted %5 shinier than the normal "
                              "variance permits); last update recomputed %4 baked texels")
                          .arg(m_overShine.flaggedMipTexels)
                          .arg(qulonglong(m_overShine.mipWidth) * qulonglong(m_overShine.mipHeight))
                          .arg(m_overShine.mip)
                          .arg(m_live->lastRecomputedTexels())
                          .arg(term(false)));
}

} // namespace burnish::studio
