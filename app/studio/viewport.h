// The studio's 3D viewport: render/'s Renderer (the same one `burnish render` runs headless) drawing
// the document's material live, with an orbit camera, a distance control, an A/B split against a
// second method or the supersampled reference, the debug views, a live shimmer meter while the
// camera auto-orbits, and UV picking for painting on the preview.
//
// Where the platform gives Qt an OpenGL context (xcb, wayland, Windows, macOS), the picture comes
// from a QOpenGLWidget whose context the renderer wraps (wrapHostContext) and whose framebuffer it
// draws into. Where it does not (the offscreen platform of the tests and CI), the same code draws
// in a headless EGL/OSMesa context of the renderer's own and the frame is shown as an image.
#pragma once

#include "material_document.h"

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/util/result.h>
#include <burnish/render/features.h>
#include <burnish/render/scene.h>

#include <glm/vec3.hpp>

#include <QImage>
#include <QPointF>
#include <QString>
#include <QWidget>

#include <functional>
#include <memory>
#include <optional>
#include <vector>

class QLabel;
class QTimer;

namespace burnish::studio {

/// What the right side of the A/B split shows: another method, or the supersampled ground truth.
struct SplitSide {
    bool reference = false;
    Method method = Method::Naive; // when !reference
    friend bool operator==(const SplitSide&, const SplitSide&) = default;
};

/// The viewport's own state (not the material's: none of it is saved or undone).
struct ViewSettings {
    render::MeshKind mesh = render::MeshKind::Sphere;
    QString objPath; // for MeshKind::Obj
    float yawDegrees = 30.0f;
    float pitchDegrees = 20.0f;
    float distance = 3.0f; // camera distance from the target, in units of the sphere's radius
    glm::vec3 target{0.0f};
    float exposure = 0.0f;               // stops
    float lightAzimuthDegrees = 35.0f;   // about +y, 0 = towards +z (the camera at yaw 0)
    float lightElevationDegrees = 45.0f; // above the horizon
    render::DebugView debugView = render::DebugView::None;
    bool split = false;
    float splitPosition = 0.5f; // the divider, as a fraction of the width from the left
    SplitSide right;
    int referenceSamples = 16; // samples per pixel of the reference side at rest (1..4096)
    /// The mixture filtered after shading (render::MaterialSettings::mixtureFiltering, stochastic):
    /// at rest the average of referenceSamples passes, while the camera moves one pass. On by default:
    /// a pass costs what a frame of hardware-filtered moments costs (52 ms a frame either way at
    /// 1280×720 on llvmpipe), and between texels it keeps the mixture's lead that merging each slot's
    /// lobes loses (evaluate --between-texels, s = 256, mip 3: brick 0.134 against 0.274).
    bool filterAfterShading = true;
};

/// The live shimmer meter: render/shimmer.h's measurement, the one `burnish render --sequence`
/// takes — mean |ΔY| of linear HDR luminance per object pixel between consecutive auto-orbit frames
/// at 128² — averaged over the last frames, for each side.
struct ShimmerReading {
    double a = 0.0;         // the document's method
    double b = 0.0;         // the split's right side (the reference when it shows one)
    double noise = 0.0;     // beside the reference, its own sampling noise (ShimmerReport::referenceNoise)
    bool reference = false; // whether b is the reference
    double ratio = 0.0;     // a / b, b floored at render::kMinShimmer
    int deltas = 0;         // frame-to-frame changes averaged
};

class Viewport : public QWidget {
    Q_OBJECT
public:
    /// The largest baked level the view uploads (render::Renderer::setMaxTextureSize).
    static constexpr int kMaxViewTextureSize = 2048;
    /// Camera distance range of the distance control: close enough to fill the view with the sphere,
    /// far enough that a 512² map is far below a pixel.
    static constexpr float kMinDistance = 1.5f;
    static constexpr float kMaxDistance = 200.0f;
    /// Orbit step per auto-orbit frame, degrees: a slow orbit, as `burnish render --sequence` uses.
    static constexpr float kOrbitDegreesPerFrame = 0.5f;

    explicit Viewport(MaterialDocument* doc, QWidget* parent = nullptr);
    ~Viewport() override;

    MaterialDocument* document() const { return m_doc; }
    const ViewSettings& viewSettings() const { return m_view; }
    void setViewSettings(const ViewSettings& view);

    /// Mesh choice; an OBJ is read first and refused (nothing changes) when it cannot be drawn. The
    /// camera then aims at the new mesh's centre (an OBJ's bounds, not its origin).
    Status setMesh(render::MeshKind mesh, const QString& objPath = {});
    void setDistance(float distance); // clamped to [kMinDistance, kMaxDistance]
    /// The camera's distance from the orbit's centre in world units: the view's distance (in radii)
    /// times the mesh's radius — 1 for the built-in meshes, an OBJ's farthest vertex from the
    /// origin — so the closest distance keeps the camera outside any mesh.
    float cameraDistance();
    /// The mesh's radius the distance counts in (see cameraDistance): its farthest vertex from its
    /// centre (1 for the built-in meshes).
    float meshRadius();
    /// The centre of the mesh's bounding box (the origin for the built-in meshes): where a new mesh
    /// and frameObject() aim the camera.
    glm::vec3 meshCentre();
    /// Frames the object: the camera aims at its centre from the default distance (View ▸ Frame
    /// Object, Shift+F), its direction kept.
    void frameObject();
    void setExposure(float stops);
    void setLight(float azimuthDegrees, float elevationDegrees);
    void setDebugView(render::DebugView view);
    void setSplit(bool on);
    void setSplitPosition(float fraction); // clamped to [0.05, 0.95]
    void setRightSide(const SplitSide& side);
    void setReferenceSamples(int samples); // clamped to 1..4096
    void setFilterAfterShading(bool on);
    void orbit(float yawDegrees, float pitchDegrees);

    /// Auto-orbit: the camera turns kOrbitDegreesPerFrame per frame and the shimmer meter runs.
    void setAutoOrbit(bool on);
    bool autoOrbit() const;
    /// One auto-orbit frame now: turns the camera and marks the next frame for the meter.
    void stepOrbit();
    /// The meter's reading; none before two metered frames.
    std::optional<ShimmerReading> shimmer() const { return m_shimmer; }
    void resetShimmer();
    /// The scene of the current view and document, as the view draws it. Errors: the document's maps
    /// do not fit together.
    Result<render::Scene> scene();

    /// Renders a fresh frame and returns it as shown (both sides of a split, without the labels). A
    /// mixture filtered after shading is drawn with all its passes, not a pass a frame.
    QImage grabFrame();
    /// The passes in the average side A shows of a mixture filtered after shading at rest, which grows
    /// by one a frame up to the reference's count (0 when the view filters no mixture after shading).
    int progressivePasses() const;
    /// Whether side A's last frame added a pass to an average that still lacks some.
    bool addingPasses() const;
    /// The texture coordinate under a widget position: (u, v) wrapped into [0, 1)² as the renderer
    /// samples the maps (v = 0 at the bottom row of the image: image pixel (u·width, (1 − v)·height)),
    /// or nothing off the object or when nothing can be drawn. Reads back a UV pass of the whole
    /// view once per camera change.
    std::optional<QPointF> uvAt(QPoint widgetPos);

    /// Paint mode: left-button presses and drags on the object emit paintAt() instead of orbiting.
    void setPaintMode(bool on);
    /// Bakes for the view run on a worker (render::Renderer::setBackgroundBakes): a method, gloss or
    /// map change never blocks the GUI thread on a big map; the last bake stays drawn until the
    /// new one is in. The studio turns it on; tests that read the frame right after a change leave
    /// it off.
    void setBackgroundBakes(bool on);
    /// Painting: where the view takes the painted gloss from instead of baking it again. `live`
    /// returns the paint tool's live gloss bake when it holds every stroke so far (else null); each
    /// region it rebakes is passed to liveGlossRebaked. A frame then uploads only those texels of
    /// the drawn gloss texture (render::Renderer::replaceGloss), or its whole chain once after the
    /// view baked otherwise; where the live chain cannot stand for the view's bake (another method
    /// or kernel, a reference or second method beside), the view bakes as before.
    void setLiveGloss(std::function<const LiveGlossBake*()> live);
    void liveGlossRebaked(const std::vector<TexelRect>& rects);
    /// The live bake was made anew: the next frame takes its whole chain.
    void liveGlossRebuilt();
    /// Frames whose gloss came from the live bake (replaceGloss), whole chains and regions.
    int liveGlossFrames() const { return m_liveGlossFrames; }
    /// Whether the view says a bake is running (the last baked material is drawn meanwhile).
    bool bakingShown() const;
    bool paintMode() const { return m_paintMode; }

    /// Whether the picture comes from a QOpenGLWidget (else the headless context's images).
    bool usesOpenGlWidget() const { return m_glSurface != nullptr; }
    /// The context the renderer draws in ("host, OpenGL 4.5 (Core Profile) Mesa ...").
    QString contextDescription() const { return m_contextDescription; }
    /// Wall time of the last visible frame (both sides, GPU work included), ms.
    double frameMs() const { return m_frameMs; }
    /// The last rendering error; empty when the last frame drew.
    QString lastError() const { return m_error; }

    /// Draws the current frame into `framebuffer` (w × h pixels) with the renderer's context
    /// current. Used by the surfaces; public only for them.
    void drawInto(unsigned framebuffer, int width, int height);
    /// Creates the renderers in the current context; the surfaces call it once.
    void initializeRenderers(bool hostContext);
    /// Releases every GL object (the context must be current).
    void releaseRenderers();

signals:
    /// A frame was drawn (its wall time in ms).
    void frameRendered(double ms);
    /// The meter has a new reading.
    void shimmerChanged();
    /// Rendering failed (the message) or recovered (empty).
    void errorChanged(const QString& message);
    /// The camera or another view setting changed (the panel follows it).
    void viewChanged();
    /// Paint mode: the left button is down on the object at `uv` (see uvAt); `strokeStart` on press.
    void paintAt(QPointF uv, bool strokeStart);
    /// Paint mode: the left button was released.
    void strokeFinished();

protected:
    void mousePressEvent(QMouseEvent* event) override;
    void mouseMoveEvent(QMouseEvent* event) override;
    void mouseReleaseEvent(QMouseEvent* event) override;
    void wheelEvent(QWheelEvent* event) override;
    void resizeEvent(QResizeEvent* event) override;

private:
    struct Engine;
    class GlSurface;
    class ImageSurface;
    class SplitHandle;

    /// Makes the renderer's context current; false when there is none.
    bool makeCurrent();
    void doneCurrent();
    QWidget* surface() const;
    void changed(bool camera);
    void requestUpdate();
    void applyBackgroundBakes();
    void setError(const QString& message);
    void layoutOverlays();
    void updateLabels();
    QString methodLabel(Method method) const;
    void showBaking(bool pending);
    void meter();

    MaterialDocument* m_doc;
    ViewSettings m_view;
    QString m_radiusPath;        // the OBJ meshRadius was measured for
    glm::vec3 m_objCentre{0.0f}; // its bounding box's centre
    float m_objRadius = 1.0f;    // its farthest vertex from that centre
    std::unique_ptr<Engine> m_engine;
    GlSurface* m_glSurface = nullptr;
    ImageSurface* m_imageSurface = nullptr;
    SplitHandle* m_handle = nullptr;
    QLabel* m_labelA = nullptr;
    QLabel* m_labelB = nullptr;
    QLabel* m_errorLabel = nullptr;
    QLabel* m_bakingLabel = nullptr; // "baking … 40%" while a background bake for the view runs
    QTimer* m_bakingTimer = nullptr; // reads the bake's progress into the label while it shows
    QTimer* m_orbitTimer = nullptr;
    QTimer* m_restTimer = nullptr;
    QTimer* m_passTimer = nullptr; // the next pass of a progressive frame, once events are handled
    bool m_grabbing = false;       // grabFrame's frame: every pass at once
    QTimer* m_dabTimer = nullptr;  // throttles redraws during a stroke (kDabRedrawIntervalMs)
    // The live gloss (setLiveGloss): its source, the values the drawn gloss texture was last made
    // from by it, and per level the texels rebaked since.
    std::function<const LiveGlossBake*()> m_liveGloss;
    std::shared_ptr<const std::vector<float>> m_liveGlossBase;
    std::vector<TexelRect> m_liveGlossDirty;
    int m_liveGlossFrames = 0;
    bool m_dabPending = false;        // a dab arrived while m_dabTimer ran: redraw when it fires
    bool m_dabFrameRequested = false; // a dab redraw is requested and not drawn yet
    QString m_contextDescription;
    QString m_error;
    double m_frameMs = 0.0;
    double m_fullFrameMs = 0.0; // the last frame drawn at full size
    bool m_paintMode = false;
    bool m_backgroundBakes = false;
    bool m_painting = false;
    bool m_meterPending = false;
    std::optional<ShimmerReading> m_shimmer;
    QPoint m_lastMouse;
    Qt::MouseButton m_dragButton = Qt::NoButton;
};

} // namespace burnish::studio
