// Meshes the renderer draws: generated primitives and OBJ files, each with per-vertex position,
// normal, tangent (xyz + handedness in w, MikkTSpace-style per-vertex averaging), and UV.
#pragma once

#include <burnish/core/util/result.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace burnish::render {

struct Vertex {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f, 0.0f, 1.0f};
    glm::vec4 tangent{1.0f, 0.0f, 0.0f, 1.0f}; // w = ±1: bitangent = w · cross(normal, tangent)
    glm::vec2 uv{0.0f};
};

struct MeshData {
    std::string name;
    std::vector<Vertex> vertices;
    std::vector<std::uint32_t> indices; // triangles
    glm::vec3 boundsMin{0.0f};
    glm::vec3 boundsMax{0.0f};
};

/// Unit-radius UV sphere; `uvRepeat` tiles the texture (u around, v pole to pole).
MeshData makeSphere(int segments = 96, int rings = 48, float uvRepeat = 2.0f);

/// Largest distance, in pixels, between the drawn sphere's silhouette and the true circle's.
inline constexpr double kSphereSilhouetteTolerancePixels = 0.5;
inline constexpr int kMinSphereSegments = 32;
inline constexpr int kMaxSphereSegments = 256;
/// Segments of the renderer's sphere (makeSphere's, rings half as many) when its silhouette is a
/// circle `radiusPixels` in radius on screen: the fewest, in steps of 16, whose polygon keeps within
/// kSphereSilhouetteTolerancePixels of the circle (its sagitta r(1 − cos(π/N))), at least
/// kMinSphereSegments, at most kMaxSphereSegments (a non-finite radius gets the most). A finer sphere
/// shows nothing more and costs shading: a rasteriser shades a triangle's edge blocks (llvmpipe's
/// 4×4, a GPU's 2×2 quads) once for each triangle that crosses them.
int sphereSegmentsForRadius(double radiusPixels);
/// The screen radius, in pixels, of the unit sphere at the origin seen from `eyeDistance` with a
/// vertical field of view of `fovYRadians` into a frame `heightPixels` tall: tan(asin(1/d)) /
/// tan(fov/2) · height/2. Infinite with the eye on or inside the sphere.
double sphereScreenRadius(double eyeDistance, double fovYRadians, int heightPixels);
/// A square plane in XZ (y = 0, normal +y) of side `size`, UV tiled `uvRepeat` times: seen at a
/// low angle it recedes into the distance and shows minification.
MeshData makePlane(float size = 40.0f, float uvRepeat = 40.0f, int subdivisions = 1);
/// Torus around y with major radius R and minor radius r.
MeshData makeTorus(float majorRadius = 0.7f, float minorRadius = 0.3f, int majorSegments = 96,
                   int minorSegments = 48, float uvRepeat = 2.0f);
/// An OBJ file (tinyobjloader), triangulated; missing normals are generated (area-weighted),
/// missing UVs are an error (a normal map needs them). Tangents are generated from UVs.
/// Errors: unreadable file, no triangles, non-finite positions.
Result<MeshData> loadObj(const std::filesystem::path& path);
/// loadObj's mesh, shared: the last two files parsed are kept (by path, modification time and size,
/// thread-safe), so a mesh read for its bounds, uploaded by the renderer and reopened is parsed once.
Result<std::shared_ptr<const MeshData>> loadObjShared(const std::filesystem::path& path);
/// OBJ files parsed so far in this process (what the cache could not answer).
std::uint64_t objFilesParsed();
/// Recomputes per-vertex tangents from positions, normals and UVs (Lengyel's method, then
/// Gram–Schmidt against the normal); degenerate UV triangles fall back to any orthonormal tangent.
void generateTangents(MeshData& mesh);

/// The mesh uploaded to a VAO (attribute 0 position, 1 normal, 2 tangent, 3 uv; Program binds
/// vertex inputs named aPosition, aNormal, aTangent, aUv to these locations).
/// upload() errors: an empty mesh, an index count not a multiple of 3, an index out of range.
class GpuMesh {
public:
    GpuMesh() = default;
    ~GpuMesh();
    GpuMesh(GpuMesh&& other) noexcept;
    GpuMesh& operator=(GpuMesh&& other) noexcept;
    GpuMesh(const GpuMesh&) = delete;
    GpuMesh& operator=(const GpuMesh&) = delete;

    static Result<GpuMesh> upload(const MeshData& mesh);
    void draw() const;
    int indexCount() const { return m_indexCount; }

private:
    unsigned m_vao = 0;
    unsigned m_vbo = 0;
    unsigned m_ebo = 0;
    int m_indexCount = 0;
};

} // namespace burnish::render
