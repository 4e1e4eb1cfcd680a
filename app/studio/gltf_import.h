// File ▸ Process glTF Asset… (a glTF 2.0 asset's normal-mapped materials through core's processGltf,
// the same as `burnish gltf`) and File ▸ Export glTF… (the current material on a quad through core's
// exportMaterialGltf, as `burnish gltf --normal-map`), each on a worker thread with progress that can
// cancel; the result is summarised in one message.
#pragma once

#include "material_document.h"
#include "worker_runner.h"

#include <burnish/core/jobs/gltf.h>

#include <QObject>
#include <QString>

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace burnish::studio {

/// The document's method when its preset is gltf (what the viewport shows is what the asset gets),
/// else none: the gltf preset's default (fitted), whatever another preset's method is. The lobe mixture,
/// under any preset, is "mixture": the fitted lobe and BURNISH_lobe_mixture beside it.
std::optional<std::string> gltfMethodFor(const MaterialDocument& doc);
/// Sets options' method (gltfMethodFor) and, for the mixture, the document's lobe count.
void setGltfMethod(const MaterialDocument& doc, GltfOptions& options);

/// The document's material as exportMaterialGltf takes it: its normal map, its base gloss or authored
/// gloss per texel (a gloss map, painted layers) as GGX perceptual roughness through the powers they
/// stand for, dielectric or metal, its specular colour and albedo, named `name`.
GltfMaterialSource gltfMaterialSourceFor(const MaterialDocument& doc, const std::string& name);

/// What one processed asset comes to, for the message after it: one line per material.
QString gltfSummaryText(const GltfResult& result);

/// Runs one processGltf or exportMaterialGltf on a worker thread (WorkerRunner); finished carries
/// gltfSummaryText of the result.
class GltfRunner : public WorkerRunner {
    Q_OBJECT
public:
    using WorkerRunner::WorkerRunner;
    void start(const QString& input, const QString& outDir, GltfOptions options);
    /// exportMaterialGltf of `material` into `outDir`.
    void startExport(GltfMaterialSource material, const QString& outDir, GltfOptions options);

private:
    void run(std::function<Result<GltfResult>(const GltfOptions&)> job, GltfOptions options);
};

} // namespace burnish::studio
