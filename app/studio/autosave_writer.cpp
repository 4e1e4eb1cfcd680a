#include "autosave_writer.h"

#include "project.h"

#include <QCoreApplication>
#include <QPointer>

#include <chrono>

namespace burnish::studio {

AutosaveWriter::AutosaveWriter(QObject* parent)
    : QObject(parent) {}

AutosaveWriter::~AutosaveWriter() {
    if (m_job.valid()) m_job.wait();
    for (LayerCopy& c : m_layers)
        if (c.making.valid()) c.making.wait();
}

bool AutosaveWriter::start(Snapshot snapshot) {
    if (busy()) return false;
    const quint64 generation = ++m_generation;
    QPointer<AutosaveWriter> self(this);
    m_job = std::async(std::launch::async, [self, generation, s = std::move(snapshot)] {
        std::vector<const PaintLayer*> layers;
        for (const auto& layer : s.layers)
            layers.push_back(layer.get());
        Status st = saveProject(s.settings, s.copy, s.autosaveOf, layers, s.view);
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

namespace {

// Layers up to this many texels are copied at once; bigger ones get their copy's memory on a worker
// first (on these machines a fresh 8192² layer's page faults alone took over a second).
constexpr size_t kCopyAtOnceTexels = size_t(2048) * 2048;

std::shared_ptr<PaintLayer> emptyCopyOf(PaintLayerKind kind, int width, int height) {
    auto copy = std::make_shared<PaintLayer>();
    copy->kind = kind;
    copy->width = width;
    copy->height = height;
    copy->allocate(); // zero-filled: every page touched here
    return copy;
}

} // namespace

bool AutosaveWriter::syncLayer(const PaintLayer& layer, const TexelRect& stale) {
    if (busy() || !layer.allocated()) return false;
    LayerCopy& c = m_layers[size_t(layer.kind)];
    if (c.copy && (c.copy->width != layer.width || c.copy->height != layer.height)) c.copy.reset();
    if (!c.copy) {
        if (!c.making.valid()) {
            if (layer.texelCount() <= kCopyAtOnceTexels) {
                c.copy = emptyCopyOf(layer.kind, layer.width, layer.height);
            } else {
                c.making = std::async(std::launch::async, emptyCopyOf, layer.kind, layer.width, layer.height);
                return false;
            }
        } else {
            if (c.making.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return false;
            c.copy = c.making.get();
            if (c.copy->width != layer.width || c.copy->height != layer.height) {
                c.copy.reset(); // made for a layer of another size
                return false;
            }
        }
        c.whole = false;
    }
    if (!c.whole) {
        c.copy->value = layer.value; // into the touched pages: no allocation
        c.copy->coverage = layer.coverage;
        c.whole = true;
        return true;
    }
    const TexelRect r{std::max(stale.x0, 0), std::max(stale.y0, 0), std::min(stale.x1, layer.width),
                      std::min(stale.y1, layer.height)};
    if (r.empty()) return true;
    copyTexelRect(layer.value, c.copy->value, layer.width, r);
    copyTexelRect(layer.coverage, c.copy->coverage, layer.width, r);
    return true;
}

std::shared_ptr<const PaintLayer> AutosaveWriter::layerCopy(PaintLayerKind kind) const {
    return m_layers[size_t(kind)].copy;
}

void AutosaveWriter::forgetLayers() {
    for (LayerCopy& c : m_layers)
        c.whole = false;
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
