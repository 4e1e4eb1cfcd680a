// The material document as the renderer's material: the decoded maps, the method, the preset's gloss
// encoding, the base power, the specular colour, metal or dielectric, and the albedo.
#pragma once

#include "material_document.h"

#include <burnish/core/result.h>
#include <burnish/render/scene.h>

#include <memory>
#include <vector>

namespace burnish::studio {

/// The document's environment into the scene: Off, or the procedural studio or a file, prefiltered
/// or filtered-importance-sampled, with its rotation, intensity, lobe and sample count.
void applyEnvironment(const EnvironmentSettings& environment, render::Scene& scene);
/// Face size of the environment cube the viewport prefilters.
inline constexpr int kViewportEnvironmentFaceSize = 64;

/// Maps a MaterialDocument to render::MaterialSettings. Keeps the converted gloss map between calls,
/// so the renderer (which keys its bake cache on the map's identity) bakes again only when the
/// document's gloss image itself changed.
class SceneFromDocument {
public:
    /// The document's material. Errors: a gloss map whose size does not match the normal map (the
    /// message names both sizes).
    Result<render::MaterialSettings> material(const MaterialDocument& doc);

private:
    std::shared_ptr<const Image> m_glossImage;
    std::shared_ptr<const NormalMap> m_glossFor;
    std::shared_ptr<const std::vector<float>> m_gloss;
};

} // namespace burnish::studio
