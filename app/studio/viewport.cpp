#include "viewport.h"

#include "scene_from_document.h"

#include <burnish/core/bake/paint.h>
#include <burnish/core/eval/evaluate.h>
#include <burnish/render/context.h>
#include <burnish/render/gpu_resources.h>
#include <burnish/render/mesh.h>
#include <burnish/render/renderer.h>
#include <burnish/render/shimmer.h>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <QCoreApplication>
#include <QLabel>
#include <QMouseEvent>
#include <QOpenGLContext>
#include <QOpenGLWidget>
#include <QPainter>
#include <QPointer>
#include <QSurfaceFormat>
#include <QTimer>
#include <QWheelEvent>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace burnish::studio {

namespace {

using Clock = std::chrono::steady_clock;

// Auto-orbit frame interval: 30 frames per second when the renderer keeps up.
constexpr int kOrbitIntervalMs = 33;
// The camera "rests" this long after the last interaction; then the reference side is drawn with
// its full sample count (while moving it shows kMovingReferenceSamples, a software rasterizer
// cannot draw 16 passes per interactive frame).
constexpr int kRestMs = 300;
constexpr int kMovingReferenceSamples = 2;
// While the camera moves, frames are drawn at half size (RenderTarget::interactive) when the last full
// frame took longer than this: 60 frames a second.
constexpr double kInteractiveAboveMs = 1000.0 / 60.0;
// While a stroke paints, a dab redraw waits this long after the previous dab frame ended: each dab
// hands the renderer a new authored gloss, and its full re-bake of the 512² sample costs ~90 ms on
// llvmpipe here (a dab frame ~100 ms against ~12 ms for a plain redraw; test_viewport.cpp's dab
// test prints both). The gap leaves the GUI thread free for the brush's mouse events between
// bakes; the stroke's end (MaterialDocument::changed) draws the final frame at once.
constexpr int kDabRedrawIntervalMs = 60;
// How often the "baking … N%" note reads the bake's progress while it shows.
constexpr int kBakingLabelIntervalMs = 200;
// The renderer's largest reference sample count (renderer.cpp's kMaxReferenceSamples).
constexpr int kMaxReferenceSamples = 4096;
// The meter renders each side at this size, the whole object in view at any distance the control
// gives, like `burnish render --sequence` (render/shimmer.h's default 128²).
constexpr int kMeterSize = 128;
// Deltas averaged by the meter: about a second of auto-orbit.
constexpr int kMeterWindow = 30;
// Degrees of orbit per dragged pixel: a 900-pixel drag turns the object most of the way round.
constexpr float kOrbitDegreesPerPixel = 0.4f;
// Pitch stops short of the poles, where the orbit camera's up vector degenerates.
constexpr float kMaxPitch = 89.0f;
// One wheel notch (120 units) moves the camera by 2^(1/4): four notches double the distance.
constexpr float kWheelStopsPerNotch = 0.25f;
// A UV-pass pixel is on the object when its b channel (1 on the object, 0 cleared) passes 0.5.
constexpr float kCoveredThreshold = 0.5f;
// The divider's grab width in pixels.
constexpr int kHandleWidth = 7;

QSurfaceFormat viewportFormat() {
    QSurfaceFormat format = QSurfaceFormat::defaultFormat();
    // The renderer needs OpenGL 3.3 core (render/context.h); the default framebuffer needs no depth,
    // the renderer draws its passes into its own targets.
    format.setVersion(3, 3);
    format.setProfile(QSurfaceFormat::CoreProfile);
    return format;
}

// Whether Qt can make an OpenGL context on this platform (the offscreen platform cannot without an
// X display). BURNISH_VIEWPORT=gl|image forces one surface (to test both on one machine).
bool platformHasOpenGl() {
    static const bool has = [] {
        const QByteArray forced = qgetenv("BURNISH_VIEWPORT");
        if (forced == "gl") return true;
        if (forced == "image") return false;
        QOpenGLContext probe;
        probe.setFormat(viewportFormat());
        return probe.create() && probe.format().majorVersion() * 10 + probe.format().minorVersion() >= 33;
    }();
    return has;
}

// The light's direction from azimuth about +y (0 = +z) and elevation above the horizon.
glm::vec3 lightDirection(float azimuthDegrees, float elevationDegrees) {
    const float az = glm::radians(azimuthDegrees);
    const float el = glm::radians(elevationDegrees);
    return glm::vec3(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
}

} // namespace

// Everything that lives in the renderer's context.
struct Viewport::Engine {
    std::unique_ptr<render::GlContext> context;
    std::unique_ptr<render::Renderer> a;            // the document's method (and the reference, and picking)
    std::unique_ptr<render::Renderer> b;            // the split's other method
    std::optional<render::Framebuffer> imageTarget; // the headless surface's frame
    SceneFromDocument mapper;

    // Picking: the UV pass of the whole view, valid until the camera, mesh or size changes.
    std::vector<float> uv;
    int uvWidth = 0;
    int uvHeight = 0;
    bool uvValid = false;

    // Meter: the one shimmer measurement (render/shimmer.h), made anew when a setting changes.
    std::optional<render::ShimmerMeter> meter;

    bool moving = false;

    void resetMeter() { meter.reset(); }
};

// The QOpenGLWidget surface: the renderer wraps its context and draws into its framebuffer.
class Viewport::GlSurface : public QOpenGLWidget {
public:
    explicit GlSurface(Viewport* view)
        : QOpenGLWidget(view)
        , m_view(view) {
        setFormat(viewportFormat());
        // The viewport handles the mouse; the surface only shows the picture.
        setAttribute(Qt::WA_TransparentForMouseEvents);
    }
    ~GlSurface() override { release(); }

protected:
    void initializeGL() override {
        connect(context(), &QOpenGLContext::aboutToBeDestroyed, this, [this] { release(); });
        m_view->initializeRenderers(true);
    }
    void paintGL() override {
        const qreal dpr = devicePixelRatioF();
        m_view->drawInto(defaultFramebufferObject(), int(std::lround(width() * dpr)),
                         int(std::lround(height() * dpr)));
    }

private:
    void release() {
        if (!context()) return;
        makeCurrent();
        m_view->releaseRenderers();
        doneCurrent();
    }
    Viewport* m_view;
};

// The headless surface: the renderer draws in its own context and the frame is painted as an image.
class Viewport::ImageSurface : public QWidget {
public:
    explicit ImageSurface(Viewport* view)
        : QWidget(view)
        , m_view(view) {
        setAttribute(Qt::WA_TransparentForMouseEvents);
        setAttribute(Qt::WA_OpaquePaintEvent);
    }

    QImage render() {
        const qreal dpr = devicePixelRatioF();
        const int w = std::max(1, int(std::lround(width() * dpr)));
        const int h = std::max(1, int(std::lround(height() * dpr)));
        Engine& e = *m_view->m_engine;
        if (!m_view->makeCurrent()) return {};
        if (!e.imageTarget || e.imageTarget->width() != w || e.imageTarget->height() != h) {
            e.imageTarget.reset();
            auto fb = render::Framebuffer::create(w, h, render::ColorFormat::Rgba8, false);
            if (!fb) {
                m_view->setError(QString::fromStdString(fb.error()));
                return {};
            }
            e.imageTarget.emplace(std::move(fb).value());
        }
        m_view->drawInto(e.imageTarget->id(), w, h);
        const std::vector<std::uint8_t> rgba = e.imageTarget->readRgba8();
        QImage image(rgba.data(), w, h, w * 4, QImage::Format_RGBA8888);
        QImage copy = image.convertToFormat(QImage::Format_RGB32);
        copy.setDevicePixelRatio(dpr);
        return copy;
    }

protected:
    void paintEvent(QPaintEvent*) override {
        QPainter painter(this);
        const QImage frame = render();
        if (frame.isNull())
            painter.fillRect(rect(), Qt::black);
        else
            painter.drawImage(rect(), frame);
    }

private:
    Viewport* m_view;
};

// The A/B divider: drag it to move the split.
class Viewport::SplitHandle : public QWidget {
public:
    explicit SplitHandle(Viewport* view)
        : QWidget(view)
        , m_view(view) {
        setCursor(Qt::SplitHCursor);
        setToolTip("Drag to move the A/B split");
    }

protected:
    void paintEvent(QPaintEvent*) override {
        QPainter painter(this);
        painter.fillRect(QRect(width() / 2 - 1, 0, 2, height()), QColor(230, 230, 230, 200));
    }
    void mouseMoveEvent(QMouseEvent* event) override {
        if (!(event->buttons() & Qt::LeftButton)) return;
        const QPointF p = mapTo(m_view, event->position().toPoint());
        m_view->m_engine->moving = true;
        m_view->m_restTimer->start();
        m_view->setSplitPosition(float(p.x() / std::max(1, m_view->width())));
    }

private:
    Viewport* m_view;
};

Viewport::Viewport(MaterialDocument* doc, QWidget* parent)
    : QWidget(parent)
    , m_doc(doc)
    , m_engine(std::make_unique<Engine>()) {
    setObjectName("viewport");
    setMinimumSize(160, 120);
    setFocusPolicy(Qt::StrongFocus);
    if (platformHasOpenGl()) {
        m_glSurface = new GlSurface(this);
    } else {
        m_imageSurface = new ImageSurface(this);
        auto context = render::createHeadlessContext();
        if (context) {
            m_engine->context = std::move(context).value();
            initializeRenderers(false);
        } else {
            setError(QString::fromStdString(context.error()));
        }
    }
    m_handle = new SplitHandle(this);
    m_labelA = new QLabel(this);
    m_labelB = new QLabel(this);
    m_errorLabel = new QLabel(this);
    m_bakingLabel = new QLabel(this);
    for (QLabel* l : {m_labelA, m_labelB, m_errorLabel, m_bakingLabel}) {
        l->setStyleSheet("QLabel { background: rgba(20, 20, 22, 170); color: #e0e0e0; padding: 2px 6px; }");
        l->setAttribute(Qt::WA_TransparentForMouseEvents);
    }
    m_errorLabel->setWordWrap(true);
    m_errorLabel->setStyleSheet("QLabel { background: rgba(90, 20, 20, 220); color: white; padding: 6px; }");
    m_errorLabel->hide();
    m_bakingLabel->hide();
    m_bakingTimer = new QTimer(this);
    m_bakingTimer->setInterval(kBakingLabelIntervalMs);
    connect(m_bakingTimer, &QTimer::timeout, this, [this] { showBaking(m_bakingLabel->isVisible()); });

    m_orbitTimer = new QTimer(this);
    m_orbitTimer->setInterval(kOrbitIntervalMs);
    connect(m_orbitTimer, &QTimer::timeout, this, &Viewport::stepOrbit);
    m_restTimer = new QTimer(this);
    m_restTimer->setSingleShot(true);
    m_restTimer->setInterval(kRestMs);
    connect(m_restTimer, &QTimer::timeout, this, [this] {
        m_engine->moving = autoOrbit();
        requestUpdate();
    });
    // At rest a mixture filtered after shading is drawn a pass a frame, each frame showing the average
    // so far (RenderTarget::progressive), so the view answers between passes; the renderer starts
    // again by itself when anything drawn changes.
    m_passTimer = new QTimer(this);
    m_passTimer->setSingleShot(true);
    m_passTimer->setInterval(0);
    connect(m_passTimer, &QTimer::timeout, this, &Viewport::requestUpdate);
    connect(m_doc, &MaterialDocument::changed, this, [this] {
        m_dabPending = false; // the frame this requests shows every dab so far
        m_dabFrameRequested = false;
        resetShimmer();
        updateLabels();
        requestUpdate();
    });
    // Each dab of a stroke in progress (no changed() until the stroke ends): redraw now, or, while a
    // dab frame is still to draw or the gap after it runs, once that gap has passed.
    m_dabTimer = new QTimer(this);
    m_dabTimer->setSingleShot(true);
    m_dabTimer->setInterval(kDabRedrawIntervalMs);
    auto dabRedraw = [this] {
        m_dabPending = false;
        m_dabFrameRequested = true;
        resetShimmer();
        requestUpdate();
    };
    connect(m_dabTimer, &QTimer::timeout, this, [this, dabRedraw] {
        if (m_dabPending) dabRedraw();
    });
    connect(m_doc, &MaterialDocument::layersChanged, this, [this, dabRedraw](const TexelRect&) {
        if (m_dabFrameRequested || m_dabTimer->isActive())
            m_dabPending = true;
        else
            dabRedraw();
    });
    connect(this, &Viewport::frameRendered, this, [this] {
        if (!m_dabFrameRequested) return;
        m_dabFrameRequested = false;
        m_dabTimer->start();
    });
    updateLabels();
    layoutOverlays();
}

void Viewport::setLiveGloss(std::function<const LiveGlossBake*()> live) {
    m_liveGloss = std::move(live);
    liveGlossRebuilt();
}

void Viewport::liveGlossRebuilt() {
    m_liveGlossBase.reset();
    m_liveGlossDirty.clear();
}

void Viewport::liveGlossRebaked(const std::vector<TexelRect>& rects) {
    if (m_liveGlossDirty.size() < rects.size()) m_liveGlossDirty.resize(rects.size());
    for (size_t k = 0; k < rects.size(); ++k)
        m_liveGlossDirty[k].unite(rects[k]);
}

Viewport::~Viewport() {
    // The GL surface releases the renderers in its own context; it goes first, while the engine
    // still exists (children are otherwise deleted after the members). The headless context's are
    // released here.
    if (m_glSurface) {
        delete m_glSurface;
        m_glSurface = nullptr;
    } else if (m_engine->context) {
        if (makeCurrent()) releaseRenderers();
        m_engine->context.reset();
    }
}

QWidget* Viewport::surface() const {
    return m_glSurface ? static_cast<QWidget*>(m_glSurface) : static_cast<QWidget*>(m_imageSurface);
}

void Viewport::initializeRenderers(bool hostContext) {
    Engine& e = *m_engine;
    if (hostContext) e.context = render::wrapHostContext();
    if (!e.context) return;
    if (const Status s = e.context->makeCurrent(); !s) {
        setError(QString::fromStdString(s.error()));
        return;
    }
    m_contextDescription = QString::fromStdString(e.context->description());
    for (auto* r : {&e.a, &e.b}) {
        auto created = render::Renderer::create();
        if (!created) {
            setError("cannot create the renderer: " + QString::fromStdString(created.error()));
            return;
        }
        *r = std::move(created).value();
        // The view shows an object in a few hundred pixels: chains from their 2048² level up (a
        // bigger map's finer levels cost gigabytes of upload and are never sampled at that size).
        (*r)->setMaxTextureSize(kMaxViewTextureSize);
    }
    applyBackgroundBakes();
}

void Viewport::setBackgroundBakes(bool on) {
    m_backgroundBakes = on;
    applyBackgroundBakes();
}

void Viewport::applyBackgroundBakes() {
    Engine& e = *m_engine;
    // The renderers' bakes run on a worker; when one finishes, a frame is asked for on the GUI
    // thread, and that frame takes the bake in.
    QPointer<Viewport> self(this);
    auto ready = [self] {
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self] {
                if (self) self->requestUpdate();
            },
            Qt::QueuedConnection);
    };
    for (auto* r : {&e.a, &e.b})
        if (*r) (*r)->setBackgroundBakes(m_backgroundBakes, ready);
}

void Viewport::releaseRenderers() {
    Engine& e = *m_engine;
    e.a.reset();
    e.b.reset();
    e.imageTarget.reset();
    e.uvValid = false;
}

bool Viewport::makeCurrent() {
    Engine& e = *m_engine;
    if (m_glSurface) {
        if (!m_glSurface->context()) return false;
        m_glSurface->makeCurrent();
    }
    if (!e.context) return false;
    if (const Status s = e.context->makeCurrent(); !s) {
        setError(QString::fromStdString(s.error()));
        return false;
    }
    return e.a && e.b;
}

void Viewport::doneCurrent() {
    if (m_glSurface) m_glSurface->doneCurrent();
}

Result<render::Scene> Viewport::scene() {
    auto material = m_engine->mapper.material(*m_doc);
    if (!material) return Error{material.error()};
    render::Scene scene;
    scene.mesh = m_view.mesh;
    scene.objPath = m_view.objPath.toStdString();
    scene.camera.yawDegrees = m_view.yawDegrees;
    scene.camera.pitchDegrees = m_view.pitchDegrees;
    scene.camera.distance = cameraDistance();
    scene.camera.target = m_view.target;
    scene.light.direction = lightDirection(m_view.lightAzimuthDegrees, m_view.lightElevationDegrees);
    scene.exposure = m_view.exposure;
    scene.debugView = m_view.debugView;
    scene.material = std::move(material).value();
    if (m_view.filterAfterShading) {
        // At rest the reference side's count of passes averaged, added a pass a frame (drawInto);
        // while the camera moves one pass, drawn as any frame (half size when full frames are slow):
        // grainy, as an engine's frame before its temporal anti-aliasing.
        scene.material.mixtureFiltering = MixtureFiltering::Stochastic;
        scene.material.mixtureSamples = m_engine->moving ? 1 : m_view.referenceSamples;
    }
    applyEnvironment(m_doc->settings().environment, scene);
    return scene;
}

void Viewport::drawInto(unsigned framebuffer, int width, int height) {
    Engine& e = *m_engine;
    if (!e.a || !e.b) return;
    const auto start = Clock::now();
    auto current = scene();
    if (!current) {
        setError(QString::fromStdString(current.error()));
        return;
    }
    const render::Scene& scene = *current;

    render::RenderTarget left{framebuffer, width, height};
    // While the camera moves and full frames are slower than 60 a second, half-size frames (a quarter
    // of the fragments); the rest timer's frame is the full one.
    left.interactive = e.moving && m_fullFrameMs > kInteractiveAboveMs;
    // A pass a frame at rest, except beside the reference, which each frame would draw whole again.
    left.progressive = !m_grabbing && !(m_view.split && m_view.right.reference);
    render::RenderTarget right = left;
    if (m_view.split) {
        // The divider's column in pixels: the left side gets [0, splitX), the right [splitX, width).
        const int splitX = std::clamp(int(std::lround(m_view.splitPosition * float(width))), 0, width);
        left.scissorWidth = std::max(splitX, 1);
        left.scissorHeight = height;
        right.scissorX = splitX;
        right.scissorWidth = std::max(width - splitX, 1);
        right.scissorHeight = height;
    }
    // Painting: the gloss the stroke changed, from the paint tool's live bake, instead of a bake.
    Status status;
    if (const LiveGlossBake* live = m_liveGloss ? m_liveGloss() : nullptr;
        live && scene.material.glossMap && scene.material.glossMap != e.a->drawnGlossMap()) {
        // Only the rebaked rectangles when the drawn texture holds what this path made it last.
        const bool regions = m_liveGlossBase && e.a->drawnGlossMap() == m_liveGlossBase;
        const auto replaced = e.a->replaceGloss(scene.material, *live, regions ? &m_liveGlossDirty : nullptr);
        if (!replaced) status = Error{replaced.error()};
        if (replaced && *replaced) {
            m_liveGlossBase = scene.material.glossMap;
            m_liveGlossDirty.clear();
            ++m_liveGlossFrames;
        }
    }
    if (status) status = e.a->setScene(scene);
    // The drawn gloss moved on (a bake landed): the old base only held a snapshot buffer alive.
    if (m_liveGlossBase && e.a->drawnGlossMap() != m_liveGlossBase) m_liveGlossBase.reset();
    if (status) status = e.a->render(left);
    if (status && m_view.split) {
        if (m_view.right.reference) {
            const int samples = e.moving ? std::min(kMovingReferenceSamples, m_view.referenceSamples)
                                         : m_view.referenceSamples;
            status = e.a->renderReference(right, samples);
        } else {
            render::Scene other = scene;
            other.material.method = m_view.right.method;
            status = e.b->setScene(other);
            if (status) status = e.b->render(right);
        }
    }
    if (!status) {
        setError(QString::fromStdString(status.error()));
        return;
    }
    showBaking(e.a->bakePending() || (m_view.split && e.b->bakePending()));
    // A progressive frame short of its passes: the next one once the events queued are handled.
    if (!e.a->progressiveDone() || (m_view.split && !m_view.right.reference && !e.b->progressiveDone()))
        m_passTimer->start();
    m_frameMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (!left.interactive) m_fullFrameMs = m_frameMs;
    setError({});
    if (m_meterPending) {
        m_meterPending = false;
        meter();
    }
    emit frameRendered(m_frameMs);
}

void Viewport::meter() {
    // The measurement `burnish render --sequence` takes (render/shimmer.h): linear HDR luminance of
    // each side at kMeterSize², over the pixels the object covers in both frames (silhouette
    // dropped), the reference beside its own sampling noise. Only the deltas kept differ: the last
    // kMeterWindow.
    Engine& e = *m_engine;
    const render::Scene drawn = e.a->scene();
    render::Scene scene = drawn;
    scene.debugView = render::DebugView::None;
    // Without a split the meter compares with the ground truth, as `burnish render --sequence`.
    const bool reference = m_view.right.reference || !m_view.split;
    const int samples = m_view.referenceSamples;
    const bool noise = reference && samples >= 2;
    Result<render::ShimmerSample> sample = Error{"no B side"};
    if (reference) {
        sample = render::renderShimmerSample(*e.a, scene, kMeterSize, kMeterSize, samples,
                                             render::ImageKind::Hdr, noise);
    } else {
        render::ShimmerSample sides;
        render::Scene other = scene;
        other.material.method = m_view.right.method;
        auto a = e.a->setScene(scene) ? e.a->renderToImage(kMeterSize, kMeterSize, render::ImageKind::Hdr)
                                      : Result<std::vector<float>>(Error{"scene"});
        auto b = e.b->setScene(other) ? e.b->renderToImage(kMeterSize, kMeterSize, render::ImageKind::Hdr)
                                      : Result<std::vector<float>>(Error{"scene"});
        auto covered = render::objectCoverage(*e.a, scene, kMeterSize, kMeterSize);
        if (a && b && covered) {
            sides.method = std::move(a).value();
            sides.other = std::move(b).value();
            sides.covered = std::move(covered).value();
            sample = std::move(sides);
        }
    }
    // The renderers draw the view's scene again.
    (void)e.a->setScene(drawn);
    if (!sample) return;
    if (!e.meter) e.meter.emplace(kMeterSize, kMeterSize, reference ? samples : 0, kMeterWindow);
    if (!e.meter->add(*sample) || e.meter->methodDeltas().empty()) return;
    ShimmerReading r;
    r.a = e.meter->methodMean();
    r.b = e.meter->otherMean();
    r.noise = noise ? e.meter->noiseMean() : 0.0;
    r.reference = reference;
    r.ratio = r.a / std::max(r.b, render::kMinShimmer);
    r.deltas = int(e.meter->methodDeltas().size());
    m_shimmer = r;
    emit shimmerChanged();
}

QImage Viewport::grabFrame() {
    m_grabbing = true;
    // The widget must exist on screen for its context; grabFramebuffer() renders a fresh frame.
    QImage frame = m_glSurface ? m_glSurface->grabFramebuffer() : m_imageSurface->render();
    m_grabbing = false;
    return frame;
}

bool Viewport::addingPasses() const {
    const Engine& e = *m_engine;
    return m_view.filterAfterShading && e.a && !e.a->progressiveDone();
}

int Viewport::progressivePasses() const {
    const Engine& e = *m_engine;
    if (!m_view.filterAfterShading || !e.a) return 0;
    return e.a->progressivePasses();
}

std::optional<QPointF> Viewport::uvAt(QPoint widgetPos) {
    Engine& e = *m_engine;
    QWidget* s = surface();
    const qreal dpr = s->devicePixelRatioF();
    const int w = std::max(1, int(std::lround(s->width() * dpr)));
    const int h = std::max(1, int(std::lround(s->height() * dpr)));
    if (!e.uvValid || e.uvWidth != w || e.uvHeight != h) {
        auto current = scene();
        if (!current || !makeCurrent()) return std::nullopt;
        render::Scene pick = std::move(current).value();
        pick.debugView = render::DebugView::Uv;
        const Status set = e.a->setScene(pick);
        auto pass = set ? e.a->renderToImage(w, h, render::ImageKind::Hdr)
                        : Result<std::vector<float>>(Error{set.error()});
        doneCurrent();
        if (!pass) return std::nullopt;
        e.uv = std::move(pass).value();
        e.uvWidth = w;
        e.uvHeight = h;
        e.uvValid = true;
    }
    const QPoint surfacePos = s->mapFrom(this, widgetPos);
    const int x = int(std::floor(surfacePos.x() * dpr));
    const int y = int(std::floor(surfacePos.y() * dpr));
    if (x < 0 || y < 0 || x >= w || y >= h) return std::nullopt;
    const size_t p = (size_t(y) * size_t(w) + size_t(x)) * 4;
    if (!(e.uv[p + 2] > kCoveredThreshold)) return std::nullopt;
    return QPointF(e.uv[p], e.uv[p + 1]);
}

void Viewport::setViewSettings(const ViewSettings& view) {
    m_view = view;
    changed(true);
}

namespace {

// A mesh's bounding sphere: its box's centre and the farthest vertex from there (at least 1e-3: a
// mesh collapsed onto a point). Non-finite vertices are left out.
struct MeshBounds {
    glm::vec3 centre{0.0f};
    float radius = 1.0f;
};

MeshBounds boundsOf(const render::MeshData& mesh) {
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    bool any = false;
    auto finite = [](const glm::vec3& p) {
        return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    };
    for (const render::Vertex& v : mesh.vertices)
        if (finite(v.position)) {
            lo = glm::min(lo, v.position);
            hi = glm::max(hi, v.position);
            any = true;
        }
    if (!any) return {};
    MeshBounds b;
    b.centre = 0.5f * (lo + hi);
    b.radius = 1e-3f;
    for (const render::Vertex& v : mesh.vertices)
        if (finite(v.position)) b.radius = std::max(b.radius, glm::length(v.position - b.centre));
    return b;
}

} // namespace

float Viewport::meshRadius() {
    if (m_view.mesh != render::MeshKind::Obj) return 1.0f;
    if (m_radiusPath != m_view.objPath) { // a view set with an OBJ not measured yet
        m_radiusPath = m_view.objPath;
        const auto loaded = render::loadObjShared(m_view.objPath.toStdString());
        const MeshBounds b =
            loaded ? boundsOf(**loaded) : MeshBounds{}; // an unreadable OBJ fails to draw anyway
        m_objCentre = b.centre;
        m_objRadius = b.radius;
    }
    return m_objRadius;
}

glm::vec3 Viewport::meshCentre() {
    if (m_view.mesh != render::MeshKind::Obj) return glm::vec3(0.0f);
    (void)meshRadius(); // measures the OBJ when it was not yet
    return m_objCentre;
}

void Viewport::frameObject() {
    m_view.target = meshCentre();
    m_view.distance = ViewSettings{}.distance;
    changed(true);
    emit viewChanged();
}

float Viewport::cameraDistance() {
    return m_view.distance * meshRadius();
}

Status Viewport::setMesh(render::MeshKind mesh, const QString& objPath) {
    if (mesh == render::MeshKind::Obj) {
        // Shared with the renderer's upload (render::loadObjShared): the file is parsed once.
        auto loaded = render::loadObjShared(objPath.toStdString());
        if (!loaded) return Error{loaded.error()}; // it names the file
        const MeshBounds b = boundsOf(**loaded);
        m_radiusPath = objPath;
        m_objCentre = b.centre;
        m_objRadius = b.radius;
    }
    m_view.mesh = mesh;
    m_view.objPath = mesh == render::MeshKind::Obj ? objPath : QString();
    // Aimed at the mesh's centre: an OBJ modelled away from its origin (a hydrant standing on it) is
    // in view whole.
    m_view.target = meshCentre();
    changed(true);
    return {};
}

void Viewport::setDistance(float distance) {
    if (!std::isfinite(distance)) return;
    m_view.distance = std::clamp(distance, kMinDistance, kMaxDistance);
    changed(true);
}

void Viewport::setExposure(float stops) {
    if (!std::isfinite(stops)) return;
    m_view.exposure = stops;
    changed(false);
}

void Viewport::setLight(float azimuthDegrees, float elevationDegrees) {
    m_view.lightAzimuthDegrees = azimuthDegrees;
    m_view.lightElevationDegrees = std::clamp(elevationDegrees, -kMaxPitch, kMaxPitch);
    changed(false);
}

void Viewport::setDebugView(render::DebugView view) {
    m_view.debugView = view;
    changed(false);
}

void Viewport::setSplit(bool on) {
    m_view.split = on;
    changed(false);
}

void Viewport::setSplitPosition(float fraction) {
    // Each side keeps at least 5 % of the width, so the divider can always be grabbed again.
    m_view.splitPosition = std::clamp(fraction, 0.05f, 0.95f);
    layoutOverlays();
    requestUpdate();
    emit viewChanged();
}

void Viewport::setRightSide(const SplitSide& side) {
    m_view.right = side;
    changed(false);
}

void Viewport::setReferenceSamples(int samples) {
    m_view.referenceSamples = std::clamp(samples, 1, kMaxReferenceSamples);
    changed(false);
}

void Viewport::setFilterAfterShading(bool on) {
    m_view.filterAfterShading = on;
    changed(false);
}

void Viewport::orbit(float yawDegrees, float pitchDegrees) {
    m_view.yawDegrees = std::fmod(m_view.yawDegrees + yawDegrees, 360.0f);
    m_view.pitchDegrees = std::clamp(m_view.pitchDegrees + pitchDegrees, -kMaxPitch, kMaxPitch);
    changed(true);
}

void Viewport::setAutoOrbit(bool on) {
    if (on == autoOrbit()) return;
    // Turning on starts a new measurement; turning off keeps the last reading on show.
    if (on) {
        resetShimmer();
        m_orbitTimer->start();
    } else {
        m_orbitTimer->stop();
    }
    m_engine->moving = on;
    requestUpdate();
    emit viewChanged();
}

bool Viewport::autoOrbit() const {
    return m_orbitTimer->isActive();
}

void Viewport::stepOrbit() {
    m_view.yawDegrees = std::fmod(m_view.yawDegrees + kOrbitDegreesPerFrame, 360.0f);
    m_engine->uvValid = false;
    m_meterPending = true;
    requestUpdate();
    emit viewChanged();
}

void Viewport::resetShimmer() {
    m_engine->resetMeter();
    const bool had = m_shimmer.has_value();
    m_shimmer.reset();
    if (had) emit shimmerChanged();
}

void Viewport::setPaintMode(bool on) {
    m_paintMode = on;
    setCursor(on ? Qt::CrossCursor : Qt::ArrowCursor);
}

void Viewport::changed(bool camera) {
    if (camera) m_engine->uvValid = false;
    // A change of anything but the camera's yaw breaks the meter's frame-to-frame comparison.
    resetShimmer();
    updateLabels();
    layoutOverlays();
    requestUpdate();
    emit viewChanged();
}

void Viewport::requestUpdate() {
    if (QWidget* s = surface()) s->update();
}

void Viewport::setError(const QString& message) {
    if (message == m_error) return;
    m_error = message;
    m_errorLabel->setText(message);
    m_errorLabel->setVisible(!message.isEmpty());
    layoutOverlays();
    emit errorChanged(message);
}

// A method's name in the view's labels, as evaluate's reports name it: the mixture's with its K.
QString Viewport::methodLabel(Method method) const {
    const int lobes = method == Method::Mixture ? m_doc->settings().mixtureLobes : 0;
    return QString::fromStdString(variantLabel({method, FilterKernel::Box, lobes}));
}

// While a bake for the view runs on its worker, the view draws the last baked material: say so, with
// what is being baked, until the frame that takes the bake in.
void Viewport::showBaking(bool pending) {
    if (pending) {
        const NormalMap& map = *m_doc->maps().normal;
        const double done =
            std::max(m_engine->a->bakeProgress(), m_view.split ? m_engine->b->bakeProgress() : 0.0);
        m_bakingLabel->setText(QString("baking %1 for %2×%3… %4%")
                                   .arg(methodLabel(m_doc->settings().method))
                                   .arg(map.width)
                                   .arg(map.height)
                                   .arg(int(std::floor(100.0 * std::clamp(done, 0.0, 1.0)))));
        m_bakingLabel->adjustSize();
        // The fraction moves between frames: read again until the bake is taken in.
        if (!m_bakingTimer->isActive()) m_bakingTimer->start();
    } else {
        m_bakingTimer->stop();
    }
    if (pending == m_bakingLabel->isVisible()) return;
    m_bakingLabel->setVisible(pending);
    layoutOverlays();
}

bool Viewport::bakingShown() const {
    return m_bakingLabel->isVisible();
}

void Viewport::updateLabels() {
    const QString a = methodLabel(m_doc->settings().method);
    const QString b = m_view.right.reference ? QString("reference (%1 spp)").arg(m_view.referenceSamples)
                                             : methodLabel(m_view.right.method);
    m_labelA->setText("A: " + a);
    m_labelB->setText("B: " + b);
    m_labelA->adjustSize();
    m_labelB->adjustSize();
}

void Viewport::layoutOverlays() {
    if (QWidget* s = surface()) s->setGeometry(rect());
    const int splitX = int(std::lround(m_view.splitPosition * float(width())));
    m_handle->setVisible(m_view.split);
    m_labelA->setVisible(m_view.split);
    m_labelB->setVisible(m_view.split);
    m_handle->setGeometry(splitX - kHandleWidth / 2, 0, kHandleWidth, height());
    constexpr int kMargin = 6; // labels' distance from the view's edges and the divider
    m_labelA->move(std::max(kMargin, splitX - m_labelA->width() - kMargin), kMargin);
    m_labelB->move(std::min(splitX + kMargin, width() - m_labelB->width() - kMargin), kMargin);
    m_errorLabel->setGeometry(kMargin, height() - 80, width() - 2 * kMargin, 80 - kMargin);
    m_bakingLabel->move(kMargin, height() - m_bakingLabel->height() - kMargin);
    for (QWidget* w :
         {static_cast<QWidget*>(m_handle), static_cast<QWidget*>(m_labelA), static_cast<QWidget*>(m_labelB),
          static_cast<QWidget*>(m_errorLabel), static_cast<QWidget*>(m_bakingLabel)})
        w->raise();
}

void Viewport::resizeEvent(QResizeEvent* event) {
    QWidget::resizeEvent(event);
    m_engine->uvValid = false;
    layoutOverlays();
}

void Viewport::mousePressEvent(QMouseEvent* event) {
    m_lastMouse = event->position().toPoint();
    m_dragButton = event->button();
    if (m_paintMode && event->button() == Qt::LeftButton) {
        m_painting = true;
        if (const auto uv = uvAt(m_lastMouse)) emit paintAt(*uv, true);
        return;
    }
    m_engine->moving = true;
    m_restTimer->start();
}

void Viewport::mouseMoveEvent(QMouseEvent* event) {
    const QPoint pos = event->position().toPoint();
    const QPoint d = pos - m_lastMouse;
    m_lastMouse = pos;
    if (m_painting) {
        if (const auto uv = uvAt(pos)) emit paintAt(*uv, false);
        return;
    }
    if (m_dragButton == Qt::NoButton) return;
    m_engine->moving = true;
    m_restTimer->start();
    if (m_dragButton == Qt::LeftButton) {
        // Dragging right turns the object right: the camera goes the other way.
        orbit(-float(d.x()) * kOrbitDegreesPerPixel, float(d.y()) * kOrbitDegreesPerPixel);
        return;
    }
    // Pan: the target moves in the view plane so the point under the cursor follows it; at the
    // target's depth the view is 2·distance·tan(fov/2) tall.
    render::OrbitCamera camera;
    camera.yawDegrees = m_view.yawDegrees;
    camera.pitchDegrees = m_view.pitchDegrees;
    camera.distance = cameraDistance();
    camera.target = m_view.target;
    const glm::vec3 forward = glm::normalize(camera.target - camera.position());
    const glm::vec3 rightAxis = glm::normalize(glm::cross(forward, glm::vec3(0.0f, 1.0f, 0.0f)));
    const glm::vec3 upAxis = glm::cross(rightAxis, forward);
    const float unitsPerPixel = 2.0f * camera.distance * std::tan(glm::radians(camera.fovDegrees) * 0.5f) /
                                float(std::max(1, height()));
    m_view.target += (-float(d.x()) * rightAxis + float(d.y()) * upAxis) * unitsPerPixel;
    changed(true);
}

void Viewport::mouseReleaseEvent(QMouseEvent* event) {
    if (m_painting && event->button() == Qt::LeftButton) {
        m_painting = false;
        emit strokeFinished();
    }
    if (event->button() == m_dragButton) m_dragButton = Qt::NoButton;
}

void Viewport::wheelEvent(QWheelEvent* event) {
    const float notches = float(event->angleDelta().y()) / 120.0f;
    m_engine->moving = true;
    m_restTimer->start();
    setDistance(m_view.distance * std::exp2(-notches * kWheelStopsPerNotch));
    event->accept();
}

} // namespace burnish::studio
