#include "gltf_import.h"

#include <burnish/core/bake/presets.h>

#include <burnish/core/prefilter/gloss.h>

#include <algorithm>

namespace burnish::studio {

std::optional<std::string> gltfMethodFor(const MaterialDocument& doc) {
    if (doc.settings().method == Method::Mixture) return std::string("mixture");
    if (doc.settings().preset != "gltf") return std::nullopt;
    const auto preset = findPreset("gltf");
    if (preset && checkPresetMethod(*preset, doc.settings().method))
        return std::string(methodName(doc.settings().method));
    return std::nullopt;
}

void setGltfMethod(const MaterialDocument& doc, GltfOptions& options) {
    options.method = gltfMethodFor(doc);
    options.mixtureLobes = doc.settings().mixtureLobes;
}

QString gltfSummaryText(const GltfResult& result) {
    QString text;
    if (result.materials.empty()) text = "No material has a normal map: the asset was copied unchanged.\n";
    for (const GltfMaterialReport& m : result.materials) {
        text += QString("Material %1 '%2': %3×%4 normal map, %5 mips, roughness %6 at mip 0 → %7 at 1×1\n")
                    .arg(m.index)
                    .arg(QString::fromStdString(m.name))
                    .arg(m.width)
                    .arg(m.height)
                    .arg(m.mipCount)
                    .arg(m.meanRoughnessMip0, 0, 'f', 3)
                    .arg(m.meanRoughnessLast, 0, 'f', 3);
        if (!m.mixture.empty()) text += "  Lobe mixture: " + QString::fromStdString(m.mixture) + "\n";
        for (const std::string& note : m.notes)
            text += "  Note: " + QString::fromStdString(note) + "\n";
    }
    text += QString("Wrote %1 (%2 files).")
                .arg(QString::fromStdString(result.asset.string()))
                .arg(result.written.size());
    return text;
}

GltfMaterialSource gltfMaterialSourceFor(const MaterialDocument& doc, const std::string& name) {
    const MaterialSettings& s = doc.settings();
    const GlossEncoding roughness = GlossEncoding::ggxRoughness();
    GltfMaterialSource m;
    m.name = name;
    m.normal = doc.maps().normal;
    m.roughness = roughness.value(doc.power());
    if (const auto authored = doc.authoredGloss()) {
        const GlossEncoding& encoding = doc.preset().encoding;
        auto texels = std::make_shared<std::vector<float>>(authored->size());
        for (size_t i = 0; i < authored->size(); ++i)
            (*texels)[i] =
                float(roughness.value(encoding.power(std::clamp(double((*authored)[i]), 0.0, 1.0))));
        m.roughnessTexels = std::move(texels);
    }
    m.metal = s.materialClass == MaterialClass::Metal;
    m.specular = {std::clamp(s.specular.r, 0.0, 1.0), std::clamp(s.specular.g, 0.0, 1.0),
                  std::clamp(s.specular.b, 0.0, 1.0)};
    m.albedo = {std::clamp(s.albedo.r, 0.0, 1.0), std::clamp(s.albedo.g, 0.0, 1.0),
                std::clamp(s.albedo.b, 0.0, 1.0)};
    return m;
}

void GltfRunner::start(const QString& input, const QString& outDir, GltfOptions options) {
    run([input,
         outDir](const GltfOptions& o) { return processGltf(input.toStdString(), outDir.toStdString(), o); },
        std::move(options));
}

void GltfRunner::startExport(GltfMaterialSource material, const QString& outDir, GltfOptions options) {
    run([material = std::move(material),
         outDir](const GltfOptions& o) { return exportMaterialGltf(material, outDir.toStdString(), o); },
        std::move(options));
}

void GltfRunner::run(std::function<Result<GltfResult>(const GltfOptions&)> job, GltfOptions options) {
    launch([job = std::move(job), options = std::move(options)](const Progress& progress) mutable {
        options.progress = progress;
        auto result = job(options);
        return result ? std::pair{true, gltfSummaryText(*result)}
                      : std::pair{false, QString::fromStdString(result.error())};
    });
}

} // namespace burnish::studio
