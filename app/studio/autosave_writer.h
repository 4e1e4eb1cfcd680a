// Writes a window's autosave copy on a worker thread, one write at a time, so the GUI never waits on
// a painted layer's EXR: the window hands over a snapshot (settings and copies of the painted layers)
// and hears the outcome through finished.
#pragma once

#include "material_document.h"

#include <burnish/core/util/result.h>

#include <QObject>
#include <QString>

#include <future>
#include <memory>
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
    };

    explicit AutosaveWriter(QObject* parent = nullptr);
    /// Waits for a write in flight: a copy is never left half-way by the window going.
    ~AutosaveWriter() override;

    bool busy() const { return m_job.valid(); }
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
};

} // namespace burnish::studio
