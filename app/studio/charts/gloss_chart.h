// The glossiness chart (after Lagarde 2011's chart for artists): the current preset's gloss encoding
// from g = 0 to 1 in steps of 0.1 as a row of spheres rendered live by the renderer with the
// material's specular colour, each labelled with g and its Blinn-Phong power; the current gloss
// marked; a click on a sphere picks its gloss (one undo step on the document).
//
// The spheres are drawn in an OpenGL 3.3 core context current in the GUI thread: Qt's own
// (QOffscreenSurface + QOpenGLContext) where the platform has one, else the renderer's headless
// context (EGL surfaceless or OSMesa, e.g. under the offscreen platform). With neither, the chart
// says so in place of the spheres.
#pragma once

#include "material_document.h"

#include <burnish/core/util/result.h>

#include <QImage>
#include <QWidget>

#include <array>
#include <memory>

namespace burnish::studio {

class GlossChart : public QWidget {
    Q_OBJECT
public:
    /// Spheres at g = 0, 0.1, …, 1.
    static constexpr int kSpheres = 11;
    /// Side of each sphere image in pixels.
    static constexpr int kSphereSize = 96;

    explicit GlossChart(MaterialDocument* doc, QWidget* parent = nullptr);
    ~GlossChart() override;

    /// The gloss value of sphere i: i/10.
    static double glossAt(int i) { return double(i) / double(kSpheres - 1); }
    /// Where sphere i is drawn, in widget coordinates.
    QRect sphereRect(int i) const;
    /// The last rendered image of sphere i (null before the first render or when GL is missing).
    const QImage& sphereImage(int i) const { return m_images[size_t(i)]; }

    /// Renders every sphere now for the current document (the chart does this by itself, deferred,
    /// when the colour, class, albedo or preset change). Fails when no OpenGL context is available
    /// or the renderer reports an error; the message is also shown in the chart.
    Status renderSpheres();
    /// Whether an OpenGL context could be made (tries once, on first use).
    bool glAvailable();
    /// Why the spheres are missing (empty while they are drawn); "" before the first attempt.
    QString glMessage() const { return m_message; }
    /// Which context draws the spheres, e.g. "Qt OpenGL 4.5 (Core Profile) Mesa …".
    QString contextDescription() const { return m_contextDescription; }
    /// Number of complete renders so far (each renders every sphere).
    int renderCount() const { return m_renderCount; }

    QSize sizeHint() const override;
    QSize minimumSizeHint() const override;

signals:
    /// Every sphere was rendered (or the render failed: glMessage() says why).
    void spheresRendered();

protected:
    void paintEvent(QPaintEvent* event) override;
    void mousePressEvent(QMouseEvent* event) override;
    void showEvent(QShowEvent* event) override;

private:
    struct Gl;
    /// The document state the spheres depend on (the gloss only moves the marker).
    QString renderKey() const;
    void onDocumentChanged();
    void scheduleRender();

    MaterialDocument* m_doc;
    std::unique_ptr<Gl> m_gl;
    std::array<QImage, kSpheres> m_images;
    QString m_message;
    QString m_contextDescription;
    QString m_renderedKey;
    bool m_renderPending = false;
    int m_renderCount = 0;
};

} // namespace burnish::studio
