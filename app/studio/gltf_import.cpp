#include "gltf_import.h"

#include <burnish/core/bake/presets.h>

#include <QCoreApplication>
#include <QPointer>
#include <QThread>

namespace burnish::studio {

std::optional<std::string> gltfMethodFor(const MaterialDocument& doc) {
    if (doc.settings().preset != "gltf") return std::nullopt;
    const auto preset = findPreset("gltf");
    if (preset && checkPresetMethod(*preset, doc.settings().method))
        return std::string(methodName(doc.settings().method));
    return std::nullopt;
}

QString gltfSummaryText(const GltfResult& result) {
    QString text;
    if (result.materials.empty()) text = "No material has a normal map: the asset was copied unchanged.\n";
    for (const GltfMaterialReport& m : result.materials)
        text += QString("Material %1 '%2': %3×%4 normal map, %5 mips, roughness %6 at mip 0 → %7 at 1×1%8\n")
                    .arg(m.index)
                    .arg(QString::fromStdString(m.name))
                    .arg(m.width)
                    .arg(m.height)
                    .arg(m.mipCount)
                    .arg(m.meanRoughnessMip0, 0, 'f', 3)
                    .arg(m.meanRoughnessLast, 0, 'f', 3)
                    .arg(m.notes.empty() ? QString() : " (" + QString::fromStdString(m.notes.front()) + ")");
    text += QString("Wrote %1 (%2 files).")
                .arg(QString::fromStdString(result.asset.string()))
                .arg(result.written.size());
    return text;
}

GltfRunner::GltfRunner(QObject* parent)
    : QObject(parent)
    , m_cancel(std::make_shared<std::atomic<bool>>(false)) {}

GltfRunner::~GltfRunner() {
    m_cancel->store(true); // a running job stops at its next check and reports into a null QPointer
}

void GltfRunner::start(const QString& input, const QString& outDir, GltfOptions options) {
    m_cancel = std::make_shared<std::atomic<bool>>(false);
    m_running = true;
    QPointer<GltfRunner> self(this);
    auto cancel = m_cancel;
    QThread* worker = QThread::create([self, cancel, input, outDir, options = std::move(options)]() mutable {
        options.progress = [&](double fraction, std::string_view stage) {
            const QString text = QString::fromUtf8(stage.data(), qsizetype(stage.size()));
            QMetaObject::invokeMethod(
                QCoreApplication::instance(),
                [self, fraction, text] {
                    if (self) emit self->progress(fraction, text);
                },
                Qt::QueuedConnection);
            return !cancel->load();
        };
        auto result = processGltf(input.toStdString(), outDir.toStdString(), options);
        const bool ok = result.ok();
        const QString message = ok ? gltfSummaryText(*result) : QString::fromStdString(result.error());
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, ok, message] {
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
