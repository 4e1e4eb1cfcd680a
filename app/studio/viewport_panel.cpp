#include "viewport_panel.h"

#include "viewport.h"

#include "flow_layout.h"

#include <burnish/render/mesh.h>

#include <QCheckBox>
#include <QComboBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QLabel>
#include <QPointer>
#include <QProgressDialog>
#include <QResizeEvent>
#include <QSettings>
#include <QSlider>
#include <QThread>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>
#include <initializer_list>

namespace burnish::studio {

namespace {

QString qs(std::string_view s) {
    return QString::fromUtf8(s.data(), int(s.size()));
}

// The debug views the combo offers, in enum order; DebugView::Uv is picking's, not a view.
constexpr render::DebugView kDebugViews[] = {
    render::DebugView::None,         render::DebugView::LightingOnly, render::DebugView::DiffuseOnly,
    render::DebugView::SpecularOnly, render::DebugView::Power,        render::DebugView::Normals,
    render::DebugView::MipLevel,     render::DebugView::Variance,     render::DebugView::ErrorHeatmap,
};

constexpr render::MeshKind kMeshes[] = {render::MeshKind::Sphere, render::MeshKind::Plane,
                                        render::MeshKind::Torus, render::MeshKind::Obj};

QSlider* slider(int min, int max, int value, const QString& tip, QWidget* parent) {
    auto* s = new QSlider(Qt::Horizontal, parent);
    s->setRange(min, max);
    s->setValue(value);
    s->setToolTip(tip);
    s->setMinimumWidth(80);
    return s;
}

QLabel* caption(const QString& text, QWidget* parent) {
    auto* l = new QLabel(text, parent);
    l->setContentsMargins(6, 0, 2, 0);
    return l;
}

// A slider's value beside it, wide enough for its longest text so the row does not jump.
QLabel* readout(QWidget* parent) {
    auto* l = new QLabel(parent);
    l->setMinimumWidth(l->fontMetrics().horizontalAdvance("+0.0 EV "));
    return l;
}

// Widgets that wrap as one: a caption with its control and readout.
QWidget* group(std::initializer_list<QWidget*> widgets, QWidget* parent) {
    auto* box = new QWidget(parent);
    auto* row = new QHBoxLayout(box);
    row->setContentsMargins(0, 0, 0, 0);
    row->setSpacing(2);
    for (QWidget* w : widgets) {
        w->setParent(box);
        row->addWidget(w);
    }
    return box;
}

} // namespace

ViewportPanel::ViewportPanel(MaterialDocument* doc, QWidget* parent)
    : QWidget(parent)
    , m_doc(doc)
    , m_viewport(new Viewport(doc, this)) {
    setObjectName("viewportPanel");
    const ViewSettings& v = m_viewport->viewSettings();

    m_mesh = new QComboBox(this);
    for (render::MeshKind k : kMeshes)
        m_mesh->addItem(k == render::MeshKind::Obj ? QString("OBJ…") : qs(render::meshKindName(k)));
    m_debug = new QComboBox(this);
    m_debug->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_debug->setMinimumContentsLength(8);
    for (render::DebugView d : kDebugViews)
        m_debug->addItem(qs(render::debugViewName(d)));
    m_debug->setToolTip("Debug view");

    const double octaves = std::log2(Viewport::kMaxDistance / Viewport::kMinDistance);
    m_distance = slider(0, int(std::lround(octaves * kDistanceStepsPerOctave)), 0,
                        "Camera distance: push the object away to see the material shrink", this);
    // ±6 stops: from a dim highlight to a blown-out one of the 1024 base power.
    m_exposure = slider(-6 * kExposureStepsPerStop, 6 * kExposureStepsPerStop, 0, "Exposure (stops)", this);
    m_azimuth = slider(-180, 180, int(v.lightAzimuthDegrees), "Light azimuth (degrees)", this);
    m_elevation = slider(-89, 89, int(v.lightElevationDegrees), "Light elevation (degrees)", this);

    m_split = new QCheckBox("A/B", this);
    m_split->setToolTip("Split the view: the document's method (A) left, B right");
    m_methodA = new QComboBox(this);
    m_methodA->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_methodA->setMinimumContentsLength(10);
    m_methodA->setToolTip("A: the document's method");
    m_methodB = new QComboBox(this);
    m_methodB->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_methodB->setMinimumContentsLength(10);
    m_methodB->setToolTip("B: another method, or the supersampled reference");
    for (Method m : allMethods())
        m_methodB->addItem(qs(methodName(m)), int(m));
    m_methodB->addItem(QString("reference (%1 spp)").arg(v.referenceSamples), -1);
    m_afterShading = new QCheckBox("filter after shading", this);
    m_afterShading->setToolTip(
        "The mixture filtered after shading (stochastic texture filtering): each pass shades one texel "
        "of every pixel's footprint, and the passes are averaged (the reference's count at rest, one "
        "while the camera moves), so neighbouring texels' lobes are never merged. Closer to the truth "
        "between texels and mips; grainy while the camera moves. What an engine with temporal "
        "anti-aliasing draws; the exported textures are the same.");
    m_orbit = new QCheckBox("auto-orbit", this);
    m_orbit->setToolTip("Turn the camera slowly and measure the shimmer of A and B");
    m_shimmer = new QLabel("shimmer: —", this);
    m_shimmer->setToolTip(
        "Shimmer: the mean change of linear luminance per object pixel between consecutive "
        "auto-orbit frames (0.5° apart, 128² frames), for A and B, and A/B: the measurement "
        "`burnish render --sequence` prints. Without the split B is the reference; beside it "
        "its own sampling noise, the shimmer its finite samples alone would show (a "
        "reference shimmer near its noise is noise; more reference samples lower it).");
    m_frame = new QLabel(this);
    m_frame->setContentsMargins(8, 0, 0, 0);

    // The controls flow onto as many rows as the width needs: at 1280 px the viewport is a few
    // hundred pixels wide, on a 4K screen one row holds everything. Each caption travels with its
    // control, and a slider shows its value beside it.
    m_distanceValue = readout(this);
    m_exposureValue = readout(this);
    m_lightValue = readout(this);
    auto* controls = m_controls = new FlowLayout(nullptr, 6, 2);
    controls->setContentsMargins(4, 2, 4, 2);
    controls->addWidget(m_mesh);
    controls->addWidget(group({caption("distance", this), m_distance, m_distanceValue}, this));
    controls->addWidget(group({caption("exposure", this), m_exposure, m_exposureValue}, this));
    controls->addWidget(group({caption("light", this), m_azimuth, m_elevation, m_lightValue}, this));
    controls->addWidget(m_debug);
    controls->addWidget(group({m_split, caption("A", this), m_methodA}, this));
    controls->addWidget(group({caption("B", this), m_methodB}, this));
    controls->addWidget(m_afterShading);
    controls->addWidget(m_orbit);
    controls->addWidget(group({m_shimmer, m_frame}, this));
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->setSpacing(2);
    layout->addLayout(controls);
    layout->addWidget(m_viewport, 1);

    connect(m_mesh, &QComboBox::activated, this, &ViewportPanel::chooseMesh);
    connect(m_debug, &QComboBox::currentIndexChanged, this, [this](int i) {
        if (!m_syncing && i >= 0) m_viewport->setDebugView(kDebugViews[i]);
    });
    connect(m_distance, &QSlider::valueChanged, this, [this](int value) {
        if (m_syncing) return;
        m_viewport->setDistance(Viewport::kMinDistance *
                                float(std::exp2(double(value) / kDistanceStepsPerOctave)));
    });
    connect(m_exposure, &QSlider::valueChanged, this, [this](int value) {
        if (!m_syncing) m_viewport->setExposure(float(value) / kExposureStepsPerStop);
    });
    auto light = [this] {
        if (!m_syncing) m_viewport->setLight(float(m_azimuth->value()), float(m_elevation->value()));
    };
    connect(m_azimuth, &QSlider::valueChanged, this, light);
    connect(m_elevation, &QSlider::valueChanged, this, light);
    connect(m_split, &QCheckBox::toggled, this, [this](bool on) {
        if (!m_syncing) m_viewport->setSplit(on);
    });
    connect(m_methodA, &QComboBox::activated, this, [this](int i) {
        const Status st = m_doc->setMethod(Method(m_methodA->itemData(i).toInt()));
        if (!st) syncFromDocument();
    });
    connect(m_methodB, &QComboBox::activated, this, &ViewportPanel::chooseMethodB);
    connect(m_orbit, &QCheckBox::toggled, this, [this](bool on) { m_viewport->setAutoOrbit(on); });
    connect(m_afterShading, &QCheckBox::toggled, this, [this](bool on) {
        if (!m_syncing) m_viewport->setFilterAfterShading(on);
    });
    connect(m_viewport, &Viewport::viewChanged, this, &ViewportPanel::syncFromView);
    connect(m_viewport, &Viewport::shimmerChanged, this, &ViewportPanel::updateShimmer);
    connect(m_viewport, &Viewport::frameRendered, this, [this](double ms) {
        QString text = QString("%1 ms").arg(ms, 0, 'f', 1);
        // A frame of the mixture filtered after shading at rest: how far its average has come.
        if (m_viewport->addingPasses())
            text += QString(" · pass %1/%2")
                        .arg(m_viewport->progressivePasses())
                        .arg(m_viewport->viewSettings().referenceSamples);
        m_frame->setText(text);
    });
    connect(m_doc, &MaterialDocument::changed, this, &ViewportPanel::syncFromDocument);
    syncFromDocument();
    syncFromView();
}

void ViewportPanel::syncFromView() {
    const ViewSettings& v = m_viewport->viewSettings();
    m_syncing = true;
    for (int i = 0; i < int(std::size(kMeshes)); ++i)
        if (kMeshes[i] == v.mesh) m_mesh->setCurrentIndex(i);
    for (int i = 0; i < int(std::size(kDebugViews)); ++i)
        if (kDebugViews[i] == v.debugView) m_debug->setCurrentIndex(i);
    m_distance->setValue(
        int(std::lround(std::log2(v.distance / Viewport::kMinDistance) * kDistanceStepsPerOctave)));
    m_exposure->setValue(int(std::lround(v.exposure * kExposureStepsPerStop)));
    m_azimuth->setValue(int(std::lround(v.lightAzimuthDegrees)));
    m_elevation->setValue(int(std::lround(v.lightElevationDegrees)));
    m_distanceValue->setText(QString("%1 r").arg(double(v.distance), 0, 'f', v.distance < 10.0f ? 1 : 0));
    m_distanceValue->setToolTip(
        "Camera distance in radii of the mesh (an OBJ's: its farthest vertex from the "
        "centre), never closer than 1.5");
    m_exposureValue->setText(
        QString("%1%2 EV").arg(v.exposure >= 0.0f ? "+" : "").arg(double(v.exposure), 0, 'f', 1));
    m_lightValue->setText(QString("%1° %2°")
                              .arg(int(std::lround(v.lightAzimuthDegrees)))
                              .arg(int(std::lround(v.lightElevationDegrees))));
    m_lightValue->setToolTip("Light azimuth and elevation");
    m_split->setChecked(v.split);
    m_methodB->setCurrentIndex(m_methodB->findData(v.right.reference ? -1 : int(v.right.method)));
    m_orbit->setChecked(m_viewport->autoOrbit());
    m_afterShading->setChecked(v.filterAfterShading);
    syncAfterShading();
    m_syncing = false;
}

void ViewportPanel::syncAfterShading() {
    // Only the mixture has lobes to filter after shading: A's method, or B's when the split shows it.
    const ViewSettings& v = m_viewport->viewSettings();
    const bool mixture = m_doc->settings().method == Method::Mixture ||
                         (v.split && !v.right.reference && v.right.method == Method::Mixture);
    m_afterShading->setEnabled(mixture);
}

void ViewportPanel::syncFromDocument() {
    m_methodA->clear();
    for (Method m : m_doc->availableMethods())
        m_methodA->addItem(qs(methodName(m)), int(m));
    m_methodA->setCurrentIndex(m_methodA->findData(int(m_doc->settings().method)));
    syncAfterShading();
}

void ViewportPanel::chooseMesh(int index) {
    const render::MeshKind kind = kMeshes[index];
    QString path;
    if (kind == render::MeshKind::Obj) {
        QSettings settings;
        path =
            QFileDialog::getOpenFileName(this, "Open OBJ mesh", settings.value("folders/meshes").toString(),
                                         "Wavefront OBJ (*.obj);;All files (*)");
        if (path.isEmpty()) {
            syncFromView();
            return;
        }
        settings.setValue("folders/meshes", QFileInfo(path).absolutePath());
    }
    if (kind == render::MeshKind::Obj && m_backgroundMeshLoads)
        loadMeshInBackground(path);
    else
        loadMesh(kind, path);
}

ViewportPanel::~ViewportPanel() {
    // A read still running finishes (it touches nothing of the panel) before the panel goes.
    for (QThread* worker : m_meshWorkers)
        worker->wait();
}

void ViewportPanel::loadMeshInBackground(const QString& path) {
    const quint64 generation = ++m_meshGeneration;
    m_meshLoading = true;
    const std::string file = path.toStdString();
    QPointer<ViewportPanel> self(this);
    QThread* worker = QThread::create([self, generation, path, file] {
        // Reads the file into render::loadObjShared's cache; the GUI thread then draws it from there.
        const auto read = render::loadObjShared(file);
        const QString error = read ? QString() : QString::fromStdString(read.error());
        if (!self) return;
        QMetaObject::invokeMethod(
            self,
            [self, generation, path, error] {
                if (!self || generation != self->m_meshGeneration) return; // cancelled or superseded
                self->finishMeshLoad(path, error);
            },
            Qt::QueuedConnection);
    });
    m_meshWorkers.push_back(worker);
    connect(worker, &QThread::finished, this, [this, worker] {
        m_meshWorkers.erase(std::remove(m_meshWorkers.begin(), m_meshWorkers.end(), worker),
                            m_meshWorkers.end());
        worker->deleteLater();
    });
    if (!m_meshProgress) {
        m_meshProgress = new QProgressDialog(this);
        m_meshProgress->setWindowTitle("Reading mesh");
        m_meshProgress->setRange(0, 0); // a file is read in one piece: busy, not a percentage
        m_meshProgress->setMinimumDuration(400);
        m_meshProgress->setAutoReset(false);
        connect(m_meshProgress, &QProgressDialog::canceled, this, [this] {
            ++m_meshGeneration; // the read finishes on its own; its result is dropped
            m_meshLoading = false;
            m_meshProgress->reset();
            syncFromView();
            emit meshLoaded(false);
        });
    }
    m_meshProgress->setLabelText("Reading " + QFileInfo(path).fileName() + "…");
    m_meshProgress->reset();
    m_meshProgress->setValue(0); // starts the minimum-duration timer
    worker->start();
}

void ViewportPanel::finishMeshLoad(const QString& path, const QString& error) {
    m_meshLoading = false;
    if (m_meshProgress) m_meshProgress->reset();
    if (!error.isEmpty()) {
        syncFromView();
        emit errorOccurred("Cannot use this mesh", error);
        emit meshLoaded(false);
        return;
    }
    emit meshLoaded(loadMesh(render::MeshKind::Obj, path)); // read already: the cache answers
}

bool ViewportPanel::loadMesh(render::MeshKind kind, const QString& path) {
    // A refused OBJ leaves the mesh as it was and says why where the user looks (it hid in a tooltip).
    const Status st = m_viewport->setMesh(kind, path);
    syncFromView();
    if (!st) {
        emit errorOccurred("Cannot use this mesh", QString::fromStdString(st.error()));
        return false;
    }
    return true;
}

void ViewportPanel::chooseMethodB(int index) {
    const int choice = m_methodB->itemData(index).toInt();
    SplitSide side;
    side.reference = choice < 0;
    if (!side.reference) side.method = Method(choice);
    m_viewport->setRightSide(side);
    // Choosing what B shows means the user wants to see it.
    if (!m_viewport->viewSettings().split) m_viewport->setSplit(true);
}

void ViewportPanel::updateShimmer() {
    const auto r = m_viewport->shimmer();
    if (!r) {
        m_shimmer->setText("shimmer: —");
        return;
    }
    const QString b = r->reference
                          ? QString("truth %1 (noise %2)").arg(r->b, 0, 'f', 4).arg(r->noise, 0, 'f', 4)
                          : QString("B %1").arg(r->b, 0, 'f', 4);
    m_shimmer->setText(
        QString("shimmer A %1  %2  A/B %3").arg(r->a, 0, 'f', 4).arg(b).arg(r->ratio, 0, 'f', 2));
}

int ViewportPanel::controlsHeightForWidth(int width) const {
    return m_controls->heightForWidth(width);
}

void ViewportPanel::resizeEvent(QResizeEvent* event) {
    QWidget::resizeEvent(event);
    const int spacing = layout() ? layout()->spacing() : 0;
    const int need = controlsHeightForWidth(event->size().width()) + spacing + m_viewport->minimumHeight();
    if (minimumHeight() != need) setMinimumHeight(need);
}

} // namespace burnish::studio
