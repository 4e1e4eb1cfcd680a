#include "worker_runner.h"

#include <QCoreApplication>
#include <QPointer>
#include <QThread>

namespace burnish::studio {

WorkerRunner::WorkerRunner(QObject* parent)
    : QObject(parent)
    , m_cancel(std::make_shared<std::atomic<bool>>(false)) {}

WorkerRunner::~WorkerRunner() {
    m_cancel->store(true);
}

void WorkerRunner::launch(Job job) {
    m_cancel = std::make_shared<std::atomic<bool>>(false);
    m_running = true;
    QPointer<WorkerRunner> self(this);
    auto cancel = m_cancel;
    QThread* worker = QThread::create([self, cancel, job = std::move(job)] {
        const auto [ok, message] = job([&](double fraction, std::string_view stage) {
            const QString text = QString::fromUtf8(stage.data(), qsizetype(stage.size()));
            QMetaObject::invokeMethod(
                QCoreApplication::instance(),
                [self, fraction, text] {
                    if (self) emit self->progress(fraction, text);
                },
                Qt::QueuedConnection);
            return !cancel->load();
        });
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, ok = ok, message = message] {
                if (!self) return;
                self->m_running = false;
                emit self->finished(ok, message);
            },
            Qt::QueuedConnection);
    });
    connect(worker, &QThread::finished, worker, &QObject::deleteLater);
    worker->start();
}

} // namespace burnish::studio
