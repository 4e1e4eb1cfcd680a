// Writes a window's autosave copy on a worker thread, one write at a time, so the GUI never waits on
// a painted layer's EXR: the window hands over a snapshot (settings and copies of the painted layers)
// and hears the outcome through finished.
#pragma once

#include "material_document.h"
#include "project.h"

#include <burnish/core/util/result.h>

#include <QObject>
#include <QString>

#include <array>
#include <future>
#include <memory>
#include <optional>
#include <vector>

namespace burnish::studio {

class AutosaveWriter : public QObject {
    Q_OBJECT
public:
    /// What one autosave writes: saveProject(settings, copy, autosaveOf, layers).
    struct Snapshot {
        MaterialSettings settings;
        QString copy;
        QString autosaveOf;
        std::vector<std::shared_ptr<const PaintLayer>> layers; // painted ones only
        std::optional<ProjectView> view;                       // the 3D view's mesh and camera
    };

    explicit AutosaveWriter(QObject* parent = nullptr);
    /// Waits for a write in flight: a copy is never left half-way by the window going.
    ~AutosaveWriter() override;

    bool busy() const { return m_job.valid(); }
    /// Brings the writer's own copy of `layer` (kept between autosaves) up to date: the texels in
    /// `stale` (those edited since the last call), or all of it the first time and after forgetLayers()
    /// or a size change. A copy of a big layer (over 2048²) is allocated on a worker thread first, its
    /// pages touched there: false until it is ready (try again later). Only while no write runs.
    bool syncLayer(const PaintLayer& layer, const TexelRect& stale);
    /// The copy syncLayer() keeps for `kind` (null before the first).
    std::shared_ptr<const PaintLayer> layerCopy(PaintLayerKind kind) const;
    /// The next syncLayer() copies whole layers (the document's layers were replaced).
    void forgetLayers();
    /// Starts writing `snapshot`; false (nothing started) while another write is in flight.
    bool start(Snapshot snapshot);
    /// Waits for the write in flight and returns its outcome (ok when none is running). finished is
    /// emitted for it here, not later.
    Status wait();

signals:
    /// A write ended: ok, or the error (one line).
    void finished(bool ok, const QString& error);

private:
    /// Collects the finished write of generation `generation` (a queued call from the worker).
    void collect(quint64 generation);

    std::future<Status> m_job;
    quint64 m_generation = 0;
    struct LayerCopy {
        std::shared_ptr<PaintLayer> copy;
        bool whole = false; // equal to the layer but for the stale texels
        std::future<std::shared_ptr<PaintLayer>> making;
    };
    std::array<LayerCopy, 2> m_layers; // by PaintLayerKind
};

} // namespace burnish::studio
