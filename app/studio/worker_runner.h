// One long job (a bake and export, a glTF asset) on a worker thread: its progress and outcome arrive
// on the GUI thread as signals, cancel() stops it at its next check, and a runner destroyed mid-job
// lets it finish into nothing (the job reports into a QPointer that is null by then).
#pragma once

#include <QObject>
#include <QString>

#include <atomic>
#include <functional>
#include <memory>
#include <string_view>
#include <utility>

namespace burnish::studio {

class WorkerRunner : public QObject {
    Q_OBJECT
public:
    explicit WorkerRunner(QObject* parent = nullptr);
    ~WorkerRunner() override;
    /// Asks the job to stop at its next check.
    void cancel() { m_cancel->store(true); }
    bool running() const { return m_running; }

    /// What the job calls with its fraction done and stage; false once cancel() was called.
    using Progress = std::function<bool(double fraction, std::string_view stage)>;
    /// The job: its outcome (ok, and the message finished carries).
    using Job = std::function<std::pair<bool, QString>(const Progress& progress)>;

signals:
    void progress(double fraction, const QString& stage);
    /// ok and the job's message, or the error ("cancelled" after cancel()).
    void finished(bool ok, const QString& message);

protected:
    /// Starts `job` on a new thread.
    void launch(Job job);

private:
    std::shared_ptr<std::atomic<bool>> m_cancel;
    bool m_running = false;
};

} // namespace burnish::studio
