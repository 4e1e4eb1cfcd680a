#include "scene_from_document.h"

#include <burnish/core/bake/bake.h>

#include <string>

namespace burnish::studio {

namespace {

glm::vec3 toVec3(const LinearRgb& c) {
    return glm::vec3(float(c.r), float(c.g), float(c.b));
}

} // namespace

void applyEnvironment(const EnvironmentSettings& e, render::Scene& scene) {
    if (e.choice == EnvironmentChoice::Off) {
        scene.environment = render::EnvironmentKind::Off;
        return;
    }
    scene.environment =
        e.fis ? render::EnvironmentKind::FilteredImportanceSampling : render::EnvironmentKind::Prefiltered;
    render::EnvironmentMap& map = scene.environmentMap;
    map.source = e.choice == EnvironmentChoice::File ? render::EnvironmentSourceKind::File
                                                     : render::EnvironmentSourceKind::ProceduralStudio;
    map.path = e.choice == EnvironmentChoice::File ? e.path.toStdString() : std::string();
    // 64² faces: a source change re-prefilters in a fraction of a second (about 0.1 s of CPU for the
    // procedural studio; 128² costs about 8× as much).
    map.faceSize = kViewportEnvironmentFaceSize;
    map.rotationDegrees = float(e.rotationDegrees);
    map.intensity = float(e.intensity);
    map.lobe = e.lobe;
    map.fisSamples = e.fisSamples;
    map.backgroundFaceSize = render::kBackdropFaceSize; // built once per source
    scene.environmentBackground = e.background;
}

Result<render::MaterialSettings> SceneFromDocument::material(const MaterialDocument& doc) {
    const MaterialSettings& s = doc.settings();
    const LoadedMaps& maps = doc.maps();
    render::MaterialSettings m;
    m.specularColor = toVec3(s.specular);
    m.metal = s.materialClass == MaterialClass::Metal;
    m.albedo = toVec3(s.albedo);
    m.glossEncoding = doc.preset().encoding;
    m.basePower = doc.power();
    m.method = s.method;
    m.methodParams.mixtureLobes = s.mixtureLobes;
    m.normalMap = maps.normal;
    m.detailMap = maps.detail;

    if (const auto authored = doc.authoredGloss()) {
        // Painted layers composited over the gloss map (or the base gloss) by the document, already
        // one value per normal-map texel in the preset's encoding: no conversion to cache.
        if (!maps.normal) return Error{"an authored gloss needs a normal map"};
        if (authored->size() != maps.normal->texelCount())
            return Error{"the authored gloss has " + std::to_string(authored->size()) + " texels, the " +
                         std::to_string(maps.normal->width) + "x" + std::to_string(maps.normal->height) +
                         " normal map " + std::to_string(maps.normal->texelCount())};
        m_glossImage.reset();
        m_glossFor.reset();
        m_gloss = authored;
    } else if (!maps.gloss) {
        m_glossImage.reset();
        m_glossFor.reset();
        m_gloss.reset();
    } else if (maps.gloss != m_glossImage || maps.normal != m_glossFor) {
        if (!maps.normal) return Error{"a gloss map needs a normal map"};
        auto gloss = glossFromImage(*maps.gloss, maps.normal->width, maps.normal->height);
        if (!gloss) return Error{"gloss map: " + gloss.error()};
        m_gloss = std::make_shared<const std::vector<float>>(std::move(gloss).value());
        m_glossImage = maps.gloss;
        m_glossFor = maps.normal;
    }
    m.glossMap = m_gloss;
    return m;
}

} // namespace burnish::studio
