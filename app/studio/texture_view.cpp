#include "texture_view.h"

#include <QMouseEvent>
#include <QPainter>
#include <QWheelEvent>

#include <algorithm>
#include <cmath>

namespace burnish::studio {

namespace {
// Zoom limits: 1/64 shows a 16k map in 256 pixels; 64 makes one texel a large, pickable square.
constexpr double kMinZoom = 1.0 / 64.0;
constexpr double kMaxZoom = 64.0;
// One wheel notch (120 units) zooms by 2^(1/4): four notches double the size.
constexpr double kZoomPerNotch = 1.189207115002721;
// Box-filters `source` into `target` (smaller) over `targetRect`: each target pixel the mean of the
// source pixels its square covers (RGB32).
void minifyRegion(const QImage& source, QImage& target, const QRect& targetRect) {
    const QRect r = targetRect.intersected(target.rect());
    const int sw = source.width(), sh = source.height(), tw = target.width(), th = target.height();
    for (int y = r.top(); y <= r.bottom(); ++y) {
        const int sy0 = int(qint64(y) * sh / th), sy1 = std::max(sy0 + 1, int(qint64(y + 1) * sh / th));
        auto* out = reinterpret_cast<QRgb*>(target.scanLine(y));
        for (int x = r.left(); x <= r.right(); ++x) {
            const int sx0 = int(qint64(x) * sw / tw), sx1 = std::max(sx0 + 1, int(qint64(x + 1) * sw / tw));
            quint64 red = 0, green = 0, blue = 0;
            for (int v = sy0; v < sy1; ++v) {
                const auto* in = reinterpret_cast<const QRgb*>(source.constScanLine(v));
                for (int u = sx0; u < sx1; ++u) {
                    red += quint64(qRed(in[u]));
                    green += quint64(qGreen(in[u]));
                    blue += quint64(qBlue(in[u]));
                }
            }
            const quint64 n = quint64(sy1 - sy0) * quint64(sx1 - sx0);
            out[x] = qRgb(int((red + n / 2) / n), int((green + n / 2) / n), int((blue + n / 2) / n));
        }
    }
}

} // namespace

TextureView::TextureView(QWidget* parent)
    : QWidget(parent) {
    setMouseTracking(false);
    setFocusPolicy(Qt::WheelFocus);
    setMinimumSize(160, 160);
    setAttribute(Qt::WA_OpaquePaintEvent);
}

void TextureView::setImage(const QImage& image) {
    // A new size starts fitted again; the same size (another view of the map) keeps zoom and pan.
    if (image.size() != m_image.size()) m_fitted = true;
    m_image = image;
    if (m_fitted) fit();
    update();
}

void TextureView::setZoom(double zoom) {
    zoomAbout(zoom, QPointF(width() / 2.0, height() / 2.0));
}

void TextureView::fit() {
    if (m_image.isNull() || width() <= 0 || height() <= 0) return;
    // A margin of 16 pixels around the image so its edge is visible against the background.
    constexpr double kMargin = 16.0;
    const double zx = (width() - 2 * kMargin) / m_image.width();
    const double zy = (height() - 2 * kMargin) / m_image.height();
    m_zoom = std::clamp(std::min(zx, zy), kMinZoom, kMaxZoom);
    m_offset =
        QPointF((width() - m_image.width() * m_zoom) / 2.0, (height() - m_image.height() * m_zoom) / 2.0);
    emit zoomChanged(m_zoom);
    update();
}

QPointF TextureView::texelAt(const QPointF& widgetPos) const {
    return (widgetPos - m_offset) / m_zoom;
}

void TextureView::zoomAbout(double zoom, const QPointF& widgetPos) {
    zoom = std::clamp(zoom, kMinZoom, kMaxZoom);
    const QPointF texel = texelAt(widgetPos);
    m_zoom = zoom;
    m_offset = widgetPos - texel * m_zoom;
    m_fitted = false;
    emit zoomChanged(m_zoom);
    update();
}

void TextureView::paintEvent(QPaintEvent*) {
    QPainter p(this);
    p.fillRect(rect(), palette().color(QPalette::Base).darker(130));
    if (m_image.isNull()) return;
    const QRectF target(m_offset, QSizeF(m_image.width() * m_zoom, m_image.height() * m_zoom));
    // Smooth when minified (what a mip would show), nearest when magnified (texels stay crisp).
    p.setRenderHint(QPainter::SmoothPixmapTransform, m_zoom < 1.0);
    const QSize drawn(std::max(1, int(std::lround(target.width()))),
                      std::max(1, int(std::lround(target.height()))));
    if (m_zoom < 1.0 && drawn.width() * 2 < m_image.width()) {
        if (m_minifiedOf != m_image.cacheKey() || m_minified.size() != drawn) {
            m_minified = m_image.scaled(drawn, Qt::IgnoreAspectRatio, Qt::SmoothTransformation);
            m_minifiedOf = m_image.cacheKey();
        }
        p.drawImage(target, m_minified);
    } else {
        p.drawImage(target, m_image);
    }
    if (!m_overlay.isNull()) {
        if (m_zoom < 1.0 && drawn.width() * 2 < m_overlay.width() &&
            m_overlay.format() == QImage::Format_RGB32) {
            // Drawn from its minified copy: scaling the whole overlay on each paint of a stroke is what
            // an 8192² map cannot afford.
            if (!m_overlayMinifiedValid || m_overlayMinified.size() != drawn) {
                m_overlayMinified = QImage(drawn, QImage::Format_RGB32);
                minifyRegion(m_overlay, m_overlayMinified, m_overlayMinified.rect());
                m_overlayMinifiedValid = true;
            }
            p.drawImage(target, m_overlayMinified);
        } else {
            p.drawImage(target, m_overlay);
        }
    }
    p.setPen(QPen(palette().color(QPalette::Mid), 1.0));
    p.drawRect(target.adjusted(-0.5, -0.5, 0.5, 0.5));
    if (m_paintMode && m_cursor) {
        // The brush outline, dark and light so it shows on any gloss.
        p.setRenderHint(QPainter::Antialiasing);
        const double r = m_brushRadius * m_zoom;
        p.setBrush(Qt::NoBrush);
        p.setPen(QPen(QColor(0, 0, 0, 160), 3.0));
        p.drawEllipse(*m_cursor, r, r);
        p.setPen(QPen(QColor(255, 255, 255, 220), 1.0));
        p.drawEllipse(*m_cursor, r, r);
    }
}

void TextureView::setPaintMode(bool on) {
    m_paintMode = on;
    m_painting = false;
    setMouseTracking(on); // the outline follows the cursor without a button down
    if (!on) m_cursor.reset();
    update();
}

void TextureView::setBrushRadius(double texels) {
    m_brushRadius = texels;
    update();
}

void TextureView::setOverlay(const QImage& overlay) {
    m_overlay = overlay;
    m_overlayMinifiedValid = false;
    update();
}

void TextureView::overlayChanged(const QRect& texels) {
    if (m_overlayMinifiedValid && !m_overlay.isNull()) {
        // The drawn pixels whose squares hold an edited texel.
        const double sx = double(m_overlayMinified.width()) / m_overlay.width();
        const double sy = double(m_overlayMinified.height()) / m_overlay.height();
        const QRect r = texels.intersected(m_overlay.rect());
        const int x0 = int(std::floor(r.left() * sx)), y0 = int(std::floor(r.top() * sy));
        const int x1 = int(std::ceil((r.right() + 1) * sx)), y1 = int(std::ceil((r.bottom() + 1) * sy));
        minifyRegion(m_overlay, m_overlayMinified, QRect(x0, y0, x1 - x0, y1 - y0));
    }
    update();
}

void TextureView::wheelEvent(QWheelEvent* event) {
    const double notches = event->angleDelta().y() / 120.0;
    zoomAbout(m_zoom * std::pow(kZoomPerNotch, notches), event->position());
    event->accept();
}

void TextureView::mousePressEvent(QMouseEvent* event) {
    if (m_paintMode && event->button() == Qt::LeftButton) {
        m_painting = true;
        emit paintPressed(texelAt(event->position()));
        return;
    }
    if (event->button() == Qt::MiddleButton || event->button() == Qt::LeftButton) {
        m_panning = true;
        m_panStart = event->position();
        setCursor(Qt::ClosedHandCursor);
    }
}

void TextureView::mouseMoveEvent(QMouseEvent* event) {
    if (m_paintMode) {
        m_cursor = event->position();
        if (m_painting) emit paintMoved(texelAt(event->position()));
        update();
    }
    if (!m_panning) return;
    m_offset += event->position() - m_panStart;
    m_fitted = false;
    m_panStart = event->position();
    update();
}

void TextureView::mouseReleaseEvent(QMouseEvent* event) {
    if (m_painting && event->button() == Qt::LeftButton) {
        m_painting = false;
        emit paintReleased();
        return;
    }
    m_panning = false;
    unsetCursor();
}

void TextureView::mouseDoubleClickEvent(QMouseEvent*) {
    m_fitted = true;
    fit();
}

void TextureView::resizeEvent(QResizeEvent*) {
    if (m_fitted) fit();
}

} // namespace burnish::studio
