// A 2D view of one texture: a QImage drawn with zoom (wheel, about the cursor) and pan (drag);
// nearest-neighbour when magnified so texels stay visible. The painting tools will draw on it.
#pragma once

#include <QImage>
#include <QPointF>
#include <QWidget>

#include <algorithm>
#include <cmath>
#include <optional>

namespace burnish::studio {

/// A value in [0, 1] (clamped) as the 8-bit code the views show it with.
inline uchar toByte(double v) {
    return uchar(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
}

class TextureView : public QWidget {
    Q_OBJECT
public:
    explicit TextureView(QWidget* parent = nullptr);

    void setImage(const QImage& image);
    const QImage& image() const { return m_image; }
    /// Screen pixels per texel.
    double zoom() const { return m_zoom; }
    void setZoom(double zoom);
    /// Fits the image into the view, centred.
    void fit();
    /// The texel under a widget position (may lie outside the image).
    QPointF texelAt(const QPointF& widgetPos) const;

    QSize sizeHint() const override { return {640, 640}; }

    /// Paint mode (paint_tool.h): the left button paints (paintPressed/Moved/Released with texel
    /// positions), the middle button pans, and the brush outline follows the cursor.
    void setPaintMode(bool on);
    bool paintMode() const { return m_paintMode; }
    /// Radius of the brush outline, in texels.
    void setBrushRadius(double texels);
    /// An image drawn over the texture, stretched to the texture's rectangle (the paint tool's
    /// painted layer and over-shine warnings); a null image draws nothing.
    void setOverlay(const QImage& overlay);
    const QImage& overlay() const { return m_overlay; }
    /// The overlay to edit in place (a stroke's dab changes a few texels of what may be an 8192² image:
    /// no copy); call overlayChanged() with the texels edited.
    QImage& overlayForEdit() { return m_overlay; }
    /// Redraws the overlay's texels inside `texels` after an edit through overlayForEdit().
    void overlayChanged(const QRect& texels);

signals:
    void zoomChanged(double zoom);
    void paintPressed(QPointF texel);
    void paintMoved(QPointF texel);
    void paintReleased();

protected:
    void paintEvent(QPaintEvent* event) override;
    void wheelEvent(QWheelEvent* event) override;
    void mousePressEvent(QMouseEvent* event) override;
    void mouseMoveEvent(QMouseEvent* event) override;
    void mouseReleaseEvent(QMouseEvent* event) override;
    void mouseDoubleClickEvent(QMouseEvent* event) override;
    void resizeEvent(QResizeEvent* event) override;

private:
    void zoomAbout(double zoom, const QPointF& widgetPos);

    QImage m_image;
    // The image smoothly minified to its drawn size, made once per image and size: scaling an
    // 8192² image on every paint took most of a paint's time.
    QImage m_minified;
    qint64 m_minifiedOf = 0; // m_image.cacheKey() it was made from
    double m_zoom = 1.0;
    QPointF m_offset;     // widget position of the image's top-left corner
    bool m_fitted = true; // follows the view size until the user zooms or pans
    bool m_panning = false;
    QPointF m_panStart;
    bool m_paintMode = false;
    bool m_painting = false;
    double m_brushRadius = 16.0;
    std::optional<QPointF> m_cursor; // widget position of the brush outline
    QImage m_overlay;
    // The overlay box-filtered to its drawn size, kept up to date rectangle by rectangle while painting.
    QImage m_overlayMinified;
    bool m_overlayMinifiedValid = false;
};

} // namespace burnish::studio
