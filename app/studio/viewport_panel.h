// The 3D viewport with its controls: mesh, distance, the A/B split (the document's method against
// another method or the reference), debug view, exposure, light direction, auto-orbit, and a status
// line with the live shimmer meter and the frame time.
#pragma once

#include "material_document.h"

#include <burnish/render/features.h>

#include <QWidget>

#include <vector>

class QCheckBox;
class QComboBox;
class QLabel;
class QSlider;

class QProgressDialog;
class QThread;

namespace burnish::studio {

class FlowLayout;
class Viewport;

class ViewportPanel : public QWidget {
    Q_OBJECT
public:
    /// Steps of the distance slider per doubling of the distance.
    static constexpr int kDistanceStepsPerOctave = 100;
    /// Exposure slider steps per stop.
    static constexpr int kExposureStepsPerStop = 10;

    explicit ViewportPanel(MaterialDocument* doc, QWidget* parent = nullptr);

    Viewport* viewport() const { return m_viewport; }
    QComboBox* meshCombo() const { return m_mesh; }
    QComboBox* methodACombo() const { return m_methodA; }
    QComboBox* methodBCombo() const { return m_methodB; }
    QComboBox* debugCombo() const { return m_debug; }
    QCheckBox* splitCheck() const { return m_split; }
    QCheckBox* orbitCheck() const { return m_orbit; }
    QCheckBox* afterShadingCheck() const { return m_afterShading; }
    QSlider* distanceSlider() const { return m_distance; }
    QLabel* shimmerLabel() const { return m_shimmer; }
    QLabel* frameLabel() const { return m_frame; }
    QLabel* distanceReadout() const { return m_distanceValue; }
    QLabel* exposureReadout() const { return m_exposureValue; }
    QLabel* lightReadout() const { return m_lightValue; }
    /// The height the control rows take at `width` (they wrap onto more rows when narrower).
    int controlsHeightForWidth(int width) const;
    /// Draws `kind` (an OBJ from `path`). A refused mesh leaves the drawn one and is said in
    /// errorOccurred (the window shows it); false then.
    bool loadMesh(render::MeshKind kind, const QString& path = {});
    /// Reads an OBJ on a worker thread (the studio: a 4-million-triangle file froze the window for
    /// seconds), with a progress dialog that can cancel after a moment; the mesh is drawn when it is
    /// read (render::loadObjShared: parsed once), and meshLoaded says how it ended. A newer load or a
    /// cancel drops an older one's result.
    void loadMeshInBackground(const QString& path);
    /// An OBJ read in the background is being read.
    bool meshLoading() const { return m_meshLoading; }
    /// OBJ files chosen in the mesh box are read in the background (the studio turns it on; tests that
    /// read the view right after a choice leave it off).
    void setBackgroundLoads(bool on) { m_backgroundMeshLoads = on; }
    bool backgroundLoads() const { return m_backgroundMeshLoads; }
    ~ViewportPanel() override;

signals:
    /// A refusal to show the user (a mesh that cannot be read): a title and the reason.
    void errorOccurred(const QString& title, const QString& message);
    /// A background OBJ read ended: drawn (ok), refused (errorOccurred said why) or cancelled.
    void meshLoaded(bool ok);

protected:
    /// Keeps the panel's minimum height at the control rows its width needs plus the view's
    /// minimum, so a tall neighbour can never squeeze the rows over the view.
    void resizeEvent(QResizeEvent* event) override;

private:
    void syncFromView();
    void syncFromDocument();
    void syncAfterShading(); // enabled while A or B draws the mixture
    void chooseMesh(int index);
    void chooseMethodB(int index);
    void updateShimmer();
    /// A background read of `path` ended (`error` empty: read); draws it from the cache.
    void finishMeshLoad(const QString& path, const QString& error);

    MaterialDocument* m_doc;
    Viewport* m_viewport;
    FlowLayout* m_controls = nullptr;
    QComboBox* m_mesh;
    QComboBox* m_methodA;
    QComboBox* m_methodB;
    QComboBox* m_debug;
    QCheckBox* m_split;
    QCheckBox* m_orbit;
    QCheckBox* m_afterShading;
    QSlider* m_distance;
    QSlider* m_exposure;
    QSlider* m_azimuth;
    QSlider* m_elevation;
    QLabel* m_distanceValue;
    QLabel* m_exposureValue;
    QLabel* m_lightValue;
    QLabel* m_shimmer;
    QLabel* m_frame;
    bool m_syncing = false;
    bool m_meshLoading = false;
    bool m_backgroundMeshLoads = false;
    quint64 m_meshGeneration = 0;        // the newest background read (older results are dropped)
    std::vector<QThread*> m_meshWorkers; // in flight, waited for by the destructor
    QProgressDialog* m_meshProgress = nullptr;
};

} // namespace burnish::studio
