#include "charts/gloss_chart.h"

#include <burnish/core/shading/color.h>
#include <burnish/core/util/numeric.h>
#include <burnish/render/context.h>
#include <burnish/render/renderer.h>

#include <QGuiApplication>
#include <QMouseEvent>
#include <QOffscreenSurface>
#include <QOpenGLContext>
#include <QPainter>
#include <QSurfaceFormat>
#include <QTimer>

#include <algorithm>
#include <cmath>

namespace burnish::studio {

namespace {

// Layout in pixels: room for the title above and two label lines (g, power) under each sphere.
constexpr int kMargin = 10;
constexpr int kGap = 8;
constexpr int kTitleHeight = 22;
constexpr int kLabelHeight = 34;
// The accent of the current value, as in the specular chart.
const QColor kCurrentColour(255, 230, 120);

QString powerText(double n) {
    // A roughness of 0 is a mirror: its power is clamped to the largest a formula takes.
    if (n >= kMaxPower) return QString("∞");
    return n >= 1e4 ? QString::number(n, 'e', 1) : QString::number(n, 'g', n < 10 ? 2 : 4);
}

} // namespace

/// The OpenGL context and renderer the spheres are drawn with.
struct GlossChart::Gl {
    bool tried = false;
    std::unique_ptr<QOffscreenSurface> surface;
    std::unique_ptr<QOpenGLContext> qtContext;
    std::unique_ptr<render::GlContext> context; // the wrapped Qt context, or the headless one
    std::unique_ptr<render::Renderer> renderer;
    QOpenGLContext* previous = nullptr;
    QSurface* previousSurface = nullptr;

    Status makeCurrent() {
        previous = QOpenGLContext::currentContext();
        previousSurface = previous ? previous->surface() : nullptr;
        if (qtContext && !qtContext->makeCurrent(surface.get()))
            return Error{"cannot make Qt's OpenGL context current"};
        return context->makeCurrent();
    }
    /// Gives the thread back to the context that was current before makeCurrent().
    void release() {
        if (previous && previous != qtContext.get())
            previous->makeCurrent(previousSurface);
        else if (qtContext)
            qtContext->doneCurrent();
        previous = nullptr;
        previousSurface = nullptr;
    }

    /// Qt's context on an offscreen surface, else the renderer's headless one; then the renderer.
    Status create() {
        std::string qtError;
        QSurfaceFormat format;
        // The renderer's minimum (render/context.h): OpenGL 3.3 core.
        format.setVersion(3, 3);
        format.setProfile(QSurfaceFormat::CoreProfile);
        qtContext = std::make_unique<QOpenGLContext>();
        qtContext->setFormat(format);
        surface = std::make_unique<QOffscreenSurface>();
        if (qtContext->create()) {
            surface->setFormat(qtContext->format());
            surface->create();
            context = render::wrapHostContext();
            if (const Status st = makeCurrent(); !st) {
                qtError = st.error();
                release();
                context.reset();
            }
        } else {
            qtError = "the Qt platform '" + QGuiApplication::platformName().toStdString() + "' has no OpenGL";
        }
        if (!context) {
            qtContext.reset();
            surface.reset();
            auto headless = render::createHeadlessContext();
            if (!headless)
                return Error{"no OpenGL 3.3 context for the sphere previews: " + qtError +
                             "; headless: " + headless.error()};
            context = std::move(headless.value());
            previous = nullptr;
        }
        auto created = render::Renderer::create();
        if (!created) {
            release();
            return Error{"the renderer cannot start: " + created.error()};
        }
        renderer = std::move(created.value());
        release();
        return {};
    }

    ~Gl() {
        if (renderer && context && makeCurrent()) {
            renderer.reset(); // its GL objects go while their context is current
            release();
        }
        renderer.reset();
        context.reset();
        qtContext.reset();
        surface.reset();
    }
};

GlossChart::GlossChart(MaterialDocument* doc, QWidget* parent)
    : QWidget(parent)
    , m_doc(doc)
    , m_gl(std::make_unique<Gl>()) {
    setObjectName("glossChart");
    setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Fixed);
    setMinimumHeight(minimumSizeHint().height());
    connect(m_doc, &MaterialDocument::changed, this, &GlossChart::onDocumentChanged);
}

GlossChart::~GlossChart() = default;

QSize GlossChart::sizeHint() const {
    return {kMargin * 2 + kSpheres * kSphereSize + (kSpheres - 1) * kGap, minimumSizeHint().height()};
}

QSize GlossChart::minimumSizeHint() const {
    return {kMargin * 2 + kSpheres * 40, kTitleHeight + kSphereSize + kLabelHeight + kMargin};
}

QRect GlossChart::sphereRect(int i) const {
    // Spheres shrink (never grow) when the widget is narrower than the row.
    const int available = width() - 2 * kMargin - (kSpheres - 1) * kGap;
    const int side = std::clamp(available / kSpheres, 16, kSphereSize);
    const int row = kSpheres * side + (kSpheres - 1) * kGap;
    const int left = std::max(kMargin, (width() - row) / 2);
    return {left + i * (side + kGap), kTitleHeight, side, side};
}

QString GlossChart::renderKey() const {
    const MaterialSettings& s = m_doc->settings();
    return QString("%1 %2 %3 %4 %5 %6 %7 %8")
        .arg(s.preset)
        .arg(int(s.materialClass))
        .arg(s.specular.r, 0, 'g', 17)
        .arg(s.specular.g, 0, 'g', 17)
        .arg(s.specular.b, 0, 'g', 17)
        .arg(s.albedo.r, 0, 'g', 17)
        .arg(s.albedo.g, 0, 'g', 17)
        .arg(s.albedo.b, 0, 'g', 17);
}

void GlossChart::onDocumentChanged() {
    if (renderKey() != m_renderedKey) scheduleRender();
    update(); // the current-gloss marker
}

void GlossChart::showEvent(QShowEvent* event) {
    QWidget::showEvent(event);
    if (renderKey() != m_renderedKey) scheduleRender();
}

void GlossChart::scheduleRender() {
    // Hidden charts wait for showEvent; several edits in one event-loop turn give one render.
    if (!isVisible() || m_renderPending) return;
    m_renderPending = true;
    QTimer::singleShot(0, this, [this] {
        m_renderPending = false;
        if (renderKey() != m_renderedKey) (void)renderSpheres(); // a failure shows in the chart
    });
}

bool GlossChart::glAvailable() {
    if (!m_gl->tried) {
        m_gl->tried = true;
        if (const Status st = m_gl->create(); !st) {
            m_message = QString::fromStdString(st.error());
        } else {
            m_contextDescription =
                QString::fromStdString(std::string(render::contextKindName(m_gl->context->kind())) + ": " +
                                       m_gl->context->description());
        }
    }
    return m_gl->renderer != nullptr;
}

Status GlossChart::renderSpheres() {
    if (!glAvailable()) {
        update();
        emit spheresRendered();
        return Error{m_message.toStdString()};
    }
    const MaterialSettings& s = m_doc->settings();
    const Preset& preset = m_doc->preset();
    render::Scene scene;
    scene.mesh = render::MeshKind::Sphere;
    // A little ambient so the unlit side reads as a sphere, not as the background.
    scene.environment = render::EnvironmentKind::ConstantAmbient;
    scene.material.specularColor = glm::vec3(float(s.specular.r), float(s.specular.g), float(s.specular.b));
    scene.material.albedo = glm::vec3(float(s.albedo.r), float(s.albedo.g), float(s.albedo.b));
    scene.material.metal = s.materialClass == MaterialClass::Metal;
    scene.material.glossEncoding = preset.encoding;
    // No normal map: the chart shows the encoding's lobes themselves, not a map's prefiltering.
    scene.material.normalMap = nullptr;

    if (const Status st = m_gl->makeCurrent(); !st) {
        m_gl->release();
        m_message = "cannot draw the spheres: " + QString::fromStdString(st.error());
        update();
        emit spheresRendered();
        return st;
    }
    Status result;
    std::array<QImage, kSpheres> images;
    for (int i = 0; i < kSpheres && result; ++i) {
        scene.material.setGloss(glossAt(i));
        if (const Status st = m_gl->renderer->setScene(scene); !st) {
            result = st;
            break;
        }
        auto pixels = m_gl->renderer->renderToImage(kSphereSize, kSphereSize, render::ImageKind::Display);
        if (!pixels) {
            result = Error{pixels.error()};
            break;
        }
        QImage image(kSphereSize, kSphereSize, QImage::Format_RGB32);
        const std::vector<float>& rgba = pixels.value();
        for (int y = 0; y < kSphereSize; ++y) {
            auto* line = reinterpret_cast<QRgb*>(image.scanLine(y));
            for (int x = 0; x < kSphereSize; ++x) {
                const size_t k = 4 * (size_t(y) * kSphereSize + size_t(x));
                // Display images are sRGB-encoded in [0, 1]; saturate also turns a stray NaN into 0.
                line[x] = qRgb(int(std::lround(255.0 * saturate(rgba[k]))),
                               int(std::lround(255.0 * saturate(rgba[k + 1]))),
                               int(std::lround(255.0 * saturate(rgba[k + 2]))));
            }
        }
        images[size_t(i)] = image;
    }
    m_gl->release();
    if (!result) {
        m_message = "cannot draw the spheres: " + QString::fromStdString(result.error());
    } else {
        m_images = images;
        m_message.clear();
        m_renderedKey = renderKey();
        ++m_renderCount;
    }
    update();
    emit spheresRendered();
    return result;
}

void GlossChart::mousePressEvent(QMouseEvent* event) {
    if (event->button() != Qt::LeftButton) return;
    for (int i = 0; i < kSpheres; ++i) {
        // The labels under a sphere belong to it too.
        if (sphereRect(i).adjusted(0, 0, 0, kLabelHeight).contains(event->position().toPoint())) {
            m_doc->setGloss(glossAt(i));
            return;
        }
    }
}

void GlossChart::paintEvent(QPaintEvent*) {
    QPainter p(this);
    p.setRenderHint(QPainter::Antialiasing);
    const QColor text = palette().color(QPalette::WindowText);
    const QColor dim = palette().color(QPalette::Mid);
    const Preset& preset = m_doc->preset();
    const GlossEncoding& enc = preset.encoding;
    const double g = m_doc->settings().gloss;

    p.setPen(text);
    p.drawText(QRect(kMargin, 0, width() - 2 * kMargin, kTitleHeight), Qt::AlignLeft | Qt::AlignVCenter,
               QString("%1 — preset %2: %3; n is the Blinn-Phong power. Click a sphere to pick its %4.")
                   .arg(glossQuantity(enc), QString::fromStdString(preset.name),
                        QString::fromStdString(enc.formula()), glossQuantity(enc, false)));

    const QFontMetrics fm(font());
    for (int i = 0; i < kSpheres; ++i) {
        const QRect r = sphereRect(i);
        if (!m_images[size_t(i)].isNull())
            p.drawImage(r, m_images[size_t(i)]);
        else
            p.fillRect(r, palette().color(QPalette::Base));
        const double gi = glossAt(i);
        const bool current = std::abs(gi - g) < 0.5 / double(kSpheres - 1);
        p.setPen(QPen(current ? kCurrentColour : dim, current ? 2.0 : 1.0));
        p.drawRect(QRectF(r).adjusted(-1, -1, 1, 1));
        p.setPen(current ? kCurrentColour : text);
        p.drawText(QRect(r.left() - kGap / 2, r.bottom() + 3, r.width() + kGap, fm.height()),
                   Qt::AlignHCenter,
                   QString("%1 %2")
                       .arg(QString::fromUtf8(enc.symbol().data(), qsizetype(enc.symbol().size())))
                       .arg(gi, 0, 'f', 1));
        p.setPen(dim);
        p.drawText(QRect(r.left() - kGap / 2, r.bottom() + 3 + fm.height(), r.width() + kGap, fm.height()),
                   Qt::AlignHCenter, "n " + powerText(enc.power(gi)));
    }
    // The exact current gloss: a marker between the spheres' centres.
    const QRect first = sphereRect(0);
    const QRect last = sphereRect(kSpheres - 1);
    const double x = first.center().x() + g * (last.center().x() - first.center().x());
    p.setPen(QPen(kCurrentColour, 2.0));
    p.drawLine(QPointF(x, kTitleHeight - 5), QPointF(x, kTitleHeight - 1));

    if (!m_message.isEmpty()) {
        // No spheres: say why over the row, in full.
        const QRect row(first.left(), first.top(), last.right() - first.left(), first.height());
        p.fillRect(row, QColor(30, 30, 32, 220));
        p.setPen(QColor(255, 170, 120));
        p.drawText(row.adjusted(8, 4, -8, -4), Qt::AlignCenter | Qt::TextWordWrap, m_message);
    }
}

} // namespace burnish::studio
