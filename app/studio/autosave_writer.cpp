#include "autosave_writer.h"

#include "project.h"

#include <QCoreApplication>
#include <QPointer>

namespace burnish::studio {

AutosaveWriter::AutosaveWriter(QObject* parent)
    : QObject(parent) {}

AutosaveWriter::~AutosaveWriter() {
    if (m_job.valid()) m_job.wait();
}

bool AutosaveWriter::start(Snapshot snapshot) {
    if (busy()) return false;
    const quint64 generation = ++m_generation;
    QPointer<AutosaveWriter> self(this);
    m_job = std::async(std::launch::async, [self, generation, s = std::move(snapshot)] {
        std::vector<const PaintLayer*> layers;
        for (const auto& layer : s.layers)
            layers.push_back(layer.get());
        Status st = saveProject(s.settings, s.copy, s.autosaveOf, layers);
        // The outcome is collected on the GUI thread; a writer gone by then (or one that waited for
        // it already) drops the call.
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, generation] {
                if (self) self->collect(generation);
            },
            Qt::QueuedConnection);
        return st;
    });
    return true;
}

Status AutosaveWriter::wait() {
    if (!m_job.valid()) return {};
    Status st = m_job.get(); // invalidates m_job: a late collect() for it finds nothing
    emit finished(st.ok(), st.ok() ? QString() : QString::fromStdString(st.error()));
    return st;
}

void AutosaveWriter::collect(quint64 generation) {
    if (generation != m_generation || !m_job.valid()) return;
    (void)wait();
}

} // namespace burnish::studio
