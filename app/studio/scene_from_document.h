// The material document as the renderer's material: the decoded maps, the method, the preset's gloss
// encoding, the base power, the specular colour, metal or dielectric, and the albedo.
#pragma once

#include "material_document.h"

#include <burnish/core/util/result.h>
#include <burnish/render/scene.h>

#include <memory>
#include <vector>

namespace burnish::studio {

/// The document's environment into the scene: Off, or the procedural studio or a file, prefiltered
/// or filtered-importance-sampled, with its rotation, intensity, lobe and sample count.
void applyEnvironment(const EnvironmentSettings& environment, render::Scene& scene);
/// Face size of the environment cube the viewport prefilters.
inline constexpr int kViewportEnvironmentFaceSize = 64;

/// Maps a MaterialDocument to render::MaterialSettings. The renderer keys its bake cache on the gloss
/// map's identity (its pointer), so the gloss handed over keeps its identity until its values change:
/// the document's composited authored gloss (painted layers over the gloss map or base gloss; a new
/// pointer after each change, the same one otherwise), or, where the document has none, the gloss
/// image converted once and kept between calls.
class SceneFromDocument {
public:
    /// The document's material. Errors: a gloss map or authored gloss whose size does not match the
    /// normal map (the message names both sizes).
    Result<render::MaterialSettings> material(const MaterialDocument& doc);

private:
    std::shared_ptr<const Image> m_glossImage;
    std::shared_ptr<const NormalMap> m_glossFor;
    std::shared_ptr<const std::vector<float>> m_gloss;
};

} // namespace burnish::studio
