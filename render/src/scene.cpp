#include <burnish/render/scene.h>

#include <burnish/core/prefilter/sample_maps.h>
#include <burnish/core/shading/materials.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace burnish::render {

glm::vec3 OrbitCamera::position() const {
    const float yaw = glm::radians(yawDegrees);
    // ±89.9°: the view matrix's up vector (+y) must not be parallel to the view direction.
    const float pitch = glm::radians(std::clamp(pitchDegrees, -89.9f, 89.9f));
    const float d = std::max(distance, 1e-3f); // a camera at the target has no view direction
    return target +
           d * glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
}

glm::mat4 OrbitCamera::view() const {
    return glm::lookAt(position(), target, glm::vec3(0.0f, 1.0f, 0.0f));
}

glm::mat4 OrbitCamera::projection(float aspect, float sceneRadius) const {
    const float d = std::max(distance, 1e-3f);
    const float r = std::max(sceneRadius, 1e-3f);
    // Near at 1/1000 of the camera distance (at least 1 mm) keeps 24-bit depth sufficient for the
    // plane seen at a grazing angle; far past the whole scene.
    const float zNear = std::max(d * 1e-3f, 1e-3f);
    const float zFar = d + 2.0f * r + 1.0f;
    return glm::perspective(fovYRadians(), std::max(aspect, 1e-3f), zNear, zFar);
}

float OrbitCamera::fovYRadians() const {
    // 1°..170°: a valid perspective (tan finite and positive).
    return glm::radians(std::clamp(fovDegrees, 1.0f, 170.0f));
}

Result<glm::vec3> calibratedSpecularColor(std::string_view name) {
    const MaterialTable& table = builtinMaterialTable();
    const Material* material = table.find(name);
    if (!material) return Error{"no calibrated material named '" + std::string(name) + "'"};
    const LinearRgb f0 = material->f0();
    return glm::vec3(float(f0.r), float(f0.g), float(f0.b));
}

Scene Scene::sample(int mapSize) {
    Scene scene;
    scene.material.normalMap =
        std::make_shared<const NormalMap>(makeSampleNormalMap(SampleMapKind::Hammered, std::max(mapSize, 1)));
    return scene;
}

FeatureSet Scene::features() const {
    FeatureSet f;
    f.mesh = mesh;
    f.pointLights = std::clamp(int(pointLights.size()), 0, kMaxPointLights);
    f.environment = environment;
    const bool hasNormalMap = material.normalMap && material.normalMap->texelCount() > 0;
    f.normalMap = hasNormalMap;
    f.detailMap = hasNormalMap && material.detailMap && material.detailMap->texelCount() > 0;
    // The gloss map is baked with the normal map (same size); without one there is nothing to bake.
    f.glossMap = hasNormalMap && material.glossMap != nullptr;
    f.specularTexture =
        material.specularMap && material.specularMap->width > 0 && material.specularMap->height > 0;
    f.metalOnly = material.metal;
    f.method = material.method;
    f.ndf = material.ndf;
    f.fresnel = material.fresnel;
    f.visibility = material.visibility;
    f.diffuseAa = material.diffuseAa;
    f.specularAa = material.specularAa;
    f.debugView = debugView;
    return f;
}

std::uint64_t estimatedRenderBytes(const RenderMemoryInput& in) {
    constexpr double kProcess = 220e6, kPerTexel = 80.0, kMixture = 340.0, kSlopeMoments = 90.0,
                     kReference = 40.0, kPerPixel = 45.0;
    double perTexel = kPerTexel;
    if (in.everyMethod || in.method == Method::Mixture)
        perTexel += kMixture;
    else if (in.method == Method::Lean || in.method == Method::Clean)
        perTexel += kSlopeMoments;
    if (in.reference) perTexel += kReference;
    return std::uint64_t(kProcess + perTexel * double(in.mapTexels) +
                         kPerPixel * double(std::max(in.frameWidth, 0)) *
                             double(std::max(in.frameHeight, 0)));
}

} // namespace burnish::render
