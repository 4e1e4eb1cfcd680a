#include <burnish/render/mesh.h>

#include <burnish/core/util/files.h>

#include <burnish/core/util/numeric.h>

#include <epoxy/gl.h>

#include <glm/geometric.hpp>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <utility>
#include <vector>

namespace burnish::render {

namespace {

constexpr float kTwoPi = 2.0f * kPi<float>;

void computeBounds(MeshData& mesh) {
    if (mesh.vertices.empty()) {
        mesh.boundsMin = mesh.boundsMax = glm::vec3(0.0f);
        return;
    }
    mesh.boundsMin = mesh.boundsMax = mesh.vertices.front().position;
    for (const Vertex& vertex : mesh.vertices) {
        mesh.boundsMin = glm::min(mesh.boundsMin, vertex.position);
        mesh.boundsMax = glm::max(mesh.boundsMax, vertex.position);
    }
}

// A unit vector perpendicular to unit n.
// Duff et al. 2017, "Building an Orthonormal Basis, Revisited", listing 3
glm::vec3 anyTangent(const glm::vec3& n) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    return glm::vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

// A UV repeat that is finite and positive; anything else tiles once.
float sanitizeRepeat(float uvRepeat) {
    return std::isfinite(uvRepeat) && uvRepeat > 0.0f ? uvRepeat : 1.0f;
}

} // namespace

MeshData makeSphere(int segments, int rings, float uvRepeat) {
    // Fewer than 3 segments or 2 rings encloses no volume.
    segments = std::max(segments, 3);
    rings = std::max(rings, 2);
    uvRepeat = sanitizeRepeat(uvRepeat);
    MeshData mesh;
    mesh.name = "sphere";
    // Ring i at polar angle θ = π·i/rings from +y; segment j at azimuth φ = 2π·j/segments. The seam
    // column j = segments duplicates j = 0 with u = uvRepeat. z = −sin θ sin φ makes u run so that
    // the tangent frame is right-handed (w = +1) with v pointing north.
    for (int i = 0; i <= rings; ++i) {
        const float theta = kPi<float> * float(i) / float(rings);
        const float sinTheta = std::sin(theta);
        const float cosTheta = i == 0 ? 1.0f : (i == rings ? -1.0f : std::cos(theta));
        for (int j = 0; j <= segments; ++j) {
            const float phi = kTwoPi * float(j) / float(segments);
            Vertex vertex;
            vertex.normal = glm::vec3(sinTheta * std::cos(phi), cosTheta, -sinTheta * std::sin(phi));
            vertex.position = vertex.normal;
            vertex.uv = glm::vec2(float(j) / float(segments), 1.0f - float(i) / float(rings)) * uvRepeat;
            mesh.vertices.push_back(vertex);
        }
    }
    const auto at = [&](int i, int j) { return std::uint32_t(i * (segments + 1) + j); };
    for (int i = 0; i < rings; ++i) {
        for (int j = 0; j < segments; ++j) {
            // The pole rows have one vertex per column at the same point: skip the degenerate half.
            if (i != 0) mesh.indices.insert(mesh.indices.end(), {at(i, j), at(i + 1, j), at(i, j + 1)});
            if (i != rings - 1) {
                mesh.indices.insert(mesh.indices.end(), {at(i, j + 1), at(i + 1, j), at(i + 1, j + 1)});
            }
        }
    }
    generateTangents(mesh);
    computeBounds(mesh);
    return mesh;
}

int sphereSegmentsForRadius(double radiusPixels) {
    if (!(radiusPixels < 1e9)) return kMaxSphereSegments; // NaN, infinite or absurdly large
    if (!(radiusPixels > kSphereSilhouetteTolerancePixels)) return kMinSphereSegments;
    // r(1 − cos(π/N)) <= ε  ⇔  N >= π / acos(1 − ε/r)
    const double needed = kPi<double> / std::acos(1.0 - kSphereSilhouetteTolerancePixels / radiusPixels);
    const double steps = std::ceil(std::min(needed, double(kMaxSphereSegments)) / 16.0);
    return std::clamp(int(steps) * 16, kMinSphereSegments, kMaxSphereSegments);
}

double sphereScreenRadius(double eyeDistance, double fovYRadians, int heightPixels) {
    if (!(eyeDistance > 1.0)) return std::numeric_limits<double>::infinity();
    // The silhouette is the cone of half-angle asin(1/d) about the eye's line to the centre.
    const double tanCone = 1.0 / std::sqrt(eyeDistance * eyeDistance - 1.0);
    const double tanHalfFov = std::tan(0.5 * std::clamp(fovYRadians, 1e-3, kPi<double> - 1e-3));
    return tanCone / tanHalfFov * 0.5 * double(std::max(heightPixels, 1));
}

MeshData makePlane(float size, float uvRepeat, int subdivisions) {
    size = std::isfinite(size) && size > 0.0f ? size : 1.0f;
    uvRepeat = sanitizeRepeat(uvRepeat);
    subdivisions = std::max(subdivisions, 1);
    MeshData mesh;
    mesh.name = "plane";
    // x to the right, v away from a viewer looking down −z: u along +x, v along −z, w = +1.
    for (int row = 0; row <= subdivisions; ++row) {
        const float t = float(row) / float(subdivisions); // 0 at z = −size/2 (far), 1 at +size/2
        for (int column = 0; column <= subdivisions; ++column) {
            const float s = float(column) / float(subdivisions);
            Vertex vertex;
            vertex.position = glm::vec3((s - 0.5f) * size, 0.0f, (t - 0.5f) * size);
            vertex.normal = glm::vec3(0.0f, 1.0f, 0.0f);
            vertex.uv = glm::vec2(s, 1.0f - t) * uvRepeat;
            mesh.vertices.push_back(vertex);
        }
    }
    const auto at = [&](int row, int column) { return std::uint32_t(row * (subdivisions + 1) + column); };
    for (int row = 0; row < subdivisions; ++row) {
        for (int column = 0; column < subdivisions; ++column) {
            // Counter-clockwise seen from +y.
            mesh.indices.insert(mesh.indices.end(),
                                {at(row, column), at(row + 1, column), at(row + 1, column + 1)});
            mesh.indices.insert(mesh.indices.end(),
                                {at(row, column), at(row + 1, column + 1), at(row, column + 1)});
        }
    }
    generateTangents(mesh);
    computeBounds(mesh);
    return mesh;
}

MeshData makeTorus(float majorRadius, float minorRadius, int majorSegments, int minorSegments,
                   float uvRepeat) {
    majorRadius = std::isfinite(majorRadius) && majorRadius > 0.0f ? majorRadius : 0.7f;
    minorRadius = std::isfinite(minorRadius) && minorRadius > 0.0f ? minorRadius : 0.3f;
    majorSegments = std::max(majorSegments, 3);
    minorSegments = std::max(minorSegments, 3);
    uvRepeat = sanitizeRepeat(uvRepeat);
    // v tiles around the tube as often as keeps texels roughly square on the outer equator,
    // rounded so the tube's seam still tiles.
    const float vRepeat = std::max(1.0f, std::round(uvRepeat * minorRadius / (majorRadius + minorRadius)));
    MeshData mesh;
    mesh.name = "torus";
    // φ around y (u), ψ around the tube (v, starting on the outer equator and rising).
    for (int j = 0; j <= majorSegments; ++j) {
        const float phi = kTwoPi * float(j) / float(majorSegments);
        for (int i = 0; i <= minorSegments; ++i) {
            const float psi = kTwoPi * float(i) / float(minorSegments);
            const float ring = majorRadius + minorRadius * std::cos(psi);
            Vertex vertex;
            vertex.position =
                glm::vec3(ring * std::cos(phi), minorRadius * std::sin(psi), -ring * std::sin(phi));
            vertex.normal =
                glm::vec3(std::cos(psi) * std::cos(phi), std::sin(psi), -std::cos(psi) * std::sin(phi));
            vertex.uv = glm::vec2(float(j) / float(majorSegments) * uvRepeat,
                                  float(i) / float(minorSegments) * vRepeat);
            mesh.vertices.push_back(vertex);
        }
    }
    const auto at = [&](int j, int i) { return std::uint32_t(j * (minorSegments + 1) + i); };
    for (int j = 0; j < majorSegments; ++j) {
        for (int i = 0; i < minorSegments; ++i) {
            mesh.indices.insert(mesh.indices.end(), {at(j, i), at(j + 1, i), at(j, i + 1)});
            mesh.indices.insert(mesh.indices.end(), {at(j, i + 1), at(j + 1, i), at(j + 1, i + 1)});
        }
    }
    generateTangents(mesh);
    computeBounds(mesh);
    return mesh;
}

void generateTangents(MeshData& mesh) {
    const size_t count = mesh.vertices.size();
    std::vector<glm::vec3> sdirs(count, glm::vec3(0.0f));
    std::vector<glm::vec3> tdirs(count, glm::vec3(0.0f));
    for (size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
        const std::uint32_t i0 = mesh.indices[k];
        const std::uint32_t i1 = mesh.indices[k + 1];
        const std::uint32_t i2 = mesh.indices[k + 2];
        if (i0 >= count || i1 >= count || i2 >= count) continue;
        const Vertex& v0 = mesh.vertices[i0];
        const Vertex& v1 = mesh.vertices[i1];
        const Vertex& v2 = mesh.vertices[i2];
        // Lengyel 2001, "Computing Tangent Space Basis Vectors for an Arbitrary Mesh":
        // [T B] = [e1 e2]·[[du1 du2] [dv1 dv2]]⁻¹
        const glm::vec3 e1 = v1.position - v0.position;
        const glm::vec3 e2 = v2.position - v0.position;
        const float du1 = v1.uv.x - v0.uv.x;
        const float dv1 = v1.uv.y - v0.uv.y;
        const float du2 = v2.uv.x - v0.uv.x;
        const float dv2 = v2.uv.y - v0.uv.y;
        const float det = du1 * dv2 - du2 * dv1;
        // A triangle with (near-)collinear UVs has no UV gradient: it contributes nothing. 1e-12 is
        // far below the UV area of any real triangle (a 1/65536-texel triangle has 1e-10) yet keeps
        // 1/det finite.
        if (!(std::abs(det) > 1e-12f)) continue;
        const float r = 1.0f / det;
        const glm::vec3 sdir = (e1 * dv2 - e2 * dv1) * r;
        const glm::vec3 tdir = (e2 * du1 - e1 * du2) * r;
        if (!std::isfinite(sdir.x + sdir.y + sdir.z + tdir.x + tdir.y + tdir.z)) continue;
        for (const std::uint32_t index : {i0, i1, i2}) {
            sdirs[index] += sdir;
            tdirs[index] += tdir;
        }
    }
    for (size_t v = 0; v < count; ++v) {
        Vertex& vertex = mesh.vertices[v];
        glm::vec3 n = vertex.normal;
        const float lenN = glm::length(n);
        // A zero or non-finite normal has no frame to build: use +z, the Vertex default.
        n = std::isfinite(lenN) && lenN > 0.0f ? n / lenN : glm::vec3(0.0f, 0.0f, 1.0f);
        // Gram–Schmidt: remove the normal's component from the accumulated u direction.
        glm::vec3 t = sdirs[v] - n * glm::dot(n, sdirs[v]);
        const float lenT = glm::length(t);
        // A tangent shorter than 1e-6 of a unit is direction noise (the u direction was parallel
        // to the normal or absent): any tangent is as good.
        const bool degenerate =
            !(std::isfinite(lenT) && lenT > 1e-6f * std::max(1.0f, glm::length(sdirs[v])));
        t = degenerate ? anyTangent(n) : t / lenT;
        // Handedness: does the UV v direction agree with cross(n, t)?
        const float w = !degenerate && glm::dot(glm::cross(n, t), tdirs[v]) < 0.0f ? -1.0f : 1.0f;
        vertex.normal = n;
        vertex.tangent = glm::vec4(t, w);
    }
}

namespace {

// The OBJ files parsed last, by path and the file's time and size: the studio reads a mesh for its
// bounds and the renderer uploads it, and a project reopens it; each parse of a big file took seconds.
struct ObjCacheEntry {
    std::filesystem::path path;
    std::filesystem::file_time_type time;
    std::uintmax_t size = 0;
    std::shared_ptr<const MeshData> mesh;
};
constexpr size_t kObjCacheEntries = 2;
std::mutex g_objCacheMutex;
std::vector<ObjCacheEntry> g_objCache; // newest last
std::atomic<std::uint64_t> g_objParses{0};

Result<MeshData> parseObj(const std::filesystem::path& path);

} // namespace

std::uint64_t objFilesParsed() {
    return g_objParses.load();
}

Result<std::shared_ptr<const MeshData>> loadObjShared(const std::filesystem::path& path) {
    if (const Status st = requireRegularFile(path, "mesh"); !st) return Error{st.error()};
    std::error_code ec;
    const std::filesystem::path key = std::filesystem::weakly_canonical(path, ec);
    const auto time = std::filesystem::last_write_time(path, ec);
    const auto size = ec ? std::uintmax_t(0) : std::filesystem::file_size(path, ec);
    const bool cacheable = !ec;
    if (cacheable) {
        const std::lock_guard<std::mutex> lock(g_objCacheMutex);
        for (const ObjCacheEntry& e : g_objCache)
            if (e.path == key && e.time == time && e.size == size) return e.mesh;
    }
    auto parsed = parseObj(path);
    if (!parsed) return Error{parsed.error()};
    auto mesh = std::make_shared<const MeshData>(std::move(parsed).value());
    if (cacheable) {
        const std::lock_guard<std::mutex> lock(g_objCacheMutex);
        g_objCache.erase(std::remove_if(g_objCache.begin(), g_objCache.end(),
                                        [&](const ObjCacheEntry& e) { return e.path == key; }),
                         g_objCache.end());
        g_objCache.push_back({key, time, size, mesh});
        if (g_objCache.size() > kObjCacheEntries) g_objCache.erase(g_objCache.begin());
    }
    return mesh;
}

Result<MeshData> loadObj(const std::filesystem::path& path) {
    auto shared = loadObjShared(path);
    if (!shared) return Error{shared.error()};
    return **shared;
}

namespace {

Result<MeshData> parseObj(const std::filesystem::path& path) {
    ++g_objParses;
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warning;
    std::string error;
    const std::string baseDir = path.parent_path().string() + "/";
    const bool loaded = tinyobj::LoadObj(&attrib, &shapes, &materials, &warning, &error,
                                         path.string().c_str(), baseDir.c_str(), /*triangulate=*/true);
    if (!loaded) {
        std::string why = error.empty() ? std::string("unreadable OBJ") : error;
        std::replace(why.begin(), why.end(), '\n', ' ');
        while (!why.empty() && why.back() == ' ')
            why.pop_back();
        return Error{"cannot read '" + path.string() + "': " + why};
    }
    const size_t positionCount = attrib.vertices.size() / 3;
    const size_t normalCount = attrib.normals.size() / 3;
    const size_t uvCount = attrib.texcoords.size() / 2;
    for (const float x : attrib.vertices) {
        if (!std::isfinite(x)) return Error{"'" + path.string() + "': a vertex position is not finite"};
    }
    // A texture coordinate too large for a float (fuzzing found "vt 2000…0" with 100 digits) would
    // reach the shader as Inf.
    for (const float x : attrib.texcoords) {
        if (!std::isfinite(x)) return Error{"'" + path.string() + "': a texture coordinate is not finite"};
    }

    // Every corner's (position, normal, uv) indices; normals are generated when any corner lacks one.
    bool allNormals = true;
    size_t triangleCount = 0;
    for (const auto& shape : shapes) {
        triangleCount += shape.mesh.indices.size() / 3;
        for (const auto& index : shape.mesh.indices) {
            if (index.vertex_index < 0 || size_t(index.vertex_index) >= positionCount) {
                return Error{"'" + path.string() + "': a face refers to a vertex that does not exist"};
            }
            if (index.texcoord_index < 0 || size_t(index.texcoord_index) >= uvCount) {
                return Error{"'" + path.string() +
                             "': faces without texture coordinates (a normal map needs UVs)"};
            }
            if (index.normal_index < 0 || size_t(index.normal_index) >= normalCount) allNormals = false;
        }
    }
    if (triangleCount == 0) return Error{"'" + path.string() + "': no triangles"};

    MeshData mesh;
    mesh.name = path.stem().string();
    std::map<std::tuple<int, int, int>, std::uint32_t> corners;
    std::vector<int> positionOf; // OBJ position index of each output vertex
    for (const auto& shape : shapes) {
        for (size_t k = 0; k + 2 < shape.mesh.indices.size(); k += 3) {
            for (size_t c = 0; c < 3; ++c) {
                const auto& index = shape.mesh.indices[k + c];
                const int normalIndex = allNormals ? index.normal_index : -1;
                const auto key = std::make_tuple(index.vertex_index, normalIndex, index.texcoord_index);
                auto [it, inserted] = corners.emplace(key, std::uint32_t(mesh.vertices.size()));
                if (inserted) {
                    Vertex vertex;
                    const size_t p = size_t(index.vertex_index);
                    vertex.position = glm::vec3(attrib.vertices[3 * p], attrib.vertices[3 * p + 1],
                                                attrib.vertices[3 * p + 2]);
                    if (allNormals) {
                        const size_t n = size_t(index.normal_index);
                        vertex.normal = glm::vec3(attrib.normals[3 * n], attrib.normals[3 * n + 1],
                                                  attrib.normals[3 * n + 2]);
                    }
                    const size_t t = size_t(index.texcoord_index);
                    vertex.uv = glm::vec2(attrib.texcoords[2 * t], attrib.texcoords[2 * t + 1]);
                    mesh.vertices.push_back(vertex);
                    positionOf.push_back(index.vertex_index);
                }
                mesh.indices.push_back(it->second);
            }
        }
    }

    if (!allNormals) {
        // Area-weighted smooth normals per OBJ position, so UV seams do not split the shading:
        // the cross product of two edges has length twice the triangle's area.
        std::vector<glm::vec3> sums(positionCount, glm::vec3(0.0f));
        for (size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
            const glm::vec3& p0 = mesh.vertices[mesh.indices[k]].position;
            const glm::vec3& p1 = mesh.vertices[mesh.indices[k + 1]].position;
            const glm::vec3& p2 = mesh.vertices[mesh.indices[k + 2]].position;
            const glm::vec3 areaNormal = glm::cross(p1 - p0, p2 - p0);
            for (size_t c = 0; c < 3; ++c)
                sums[size_t(positionOf[mesh.indices[k + c]])] += areaNormal;
        }
        for (size_t v = 0; v < mesh.vertices.size(); ++v) {
            mesh.vertices[v].normal = sums[size_t(positionOf[v])];
        }
    }
    // generateTangents normalizes the normals (zero ones, from degenerate faces only, become +z).
    generateTangents(mesh);
    computeBounds(mesh);
    return mesh;
}

} // namespace

// ---------------------------------------------------------------------------------------------
// GpuMesh

GpuMesh::~GpuMesh() {
    if (m_vao) glDeleteVertexArrays(1, &m_vao);
    if (m_vbo) glDeleteBuffers(1, &m_vbo);
    if (m_ebo) glDeleteBuffers(1, &m_ebo);
}

GpuMesh::GpuMesh(GpuMesh&& other) noexcept
    : m_vao(std::exchange(other.m_vao, 0u))
    , m_vbo(std::exchange(other.m_vbo, 0u))
    , m_ebo(std::exchange(other.m_ebo, 0u))
    , m_indexCount(std::exchange(other.m_indexCount, 0)) {}

GpuMesh& GpuMesh::operator=(GpuMesh&& other) noexcept {
    if (this != &other) {
        if (m_vao) glDeleteVertexArrays(1, &m_vao);
        if (m_vbo) glDeleteBuffers(1, &m_vbo);
        if (m_ebo) glDeleteBuffers(1, &m_ebo);
        m_vao = std::exchange(other.m_vao, 0u);
        m_vbo = std::exchange(other.m_vbo, 0u);
        m_ebo = std::exchange(other.m_ebo, 0u);
        m_indexCount = std::exchange(other.m_indexCount, 0);
    }
    return *this;
}

Result<GpuMesh> GpuMesh::upload(const MeshData& mesh) {
    if (mesh.vertices.empty() || mesh.indices.empty()) return Error{"mesh '" + mesh.name + "' is empty"};
    if (mesh.indices.size() % 3 != 0)
        return Error{"mesh '" + mesh.name + "': index count is not a multiple of 3"};
    for (const std::uint32_t index : mesh.indices) {
        if (index >= mesh.vertices.size()) return Error{"mesh '" + mesh.name + "': index out of range"};
    }
    // glDrawElements takes a GLsizei count.
    if (mesh.indices.size() > size_t(std::numeric_limits<GLsizei>::max())) {
        return Error{"mesh '" + mesh.name + "' has too many indices"};
    }
    GLint previousVao = 0;
    glGetIntegerv(GL_VERTEX_ARRAY_BINDING, &previousVao);
    GpuMesh gpu;
    glGenVertexArrays(1, &gpu.m_vao);
    glBindVertexArray(gpu.m_vao);
    glGenBuffers(1, &gpu.m_vbo);
    glBindBuffer(GL_ARRAY_BUFFER, gpu.m_vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(mesh.vertices.size() * sizeof(Vertex)), mesh.vertices.data(),
                 GL_STATIC_DRAW);
    glGenBuffers(1, &gpu.m_ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gpu.m_ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(mesh.indices.size() * sizeof(std::uint32_t)),
                 mesh.indices.data(), GL_STATIC_DRAW);
    const auto attribute = [](GLuint location, GLint size, size_t offset) {
        glEnableVertexAttribArray(location);
        glVertexAttribPointer(location, size, GL_FLOAT, GL_FALSE, GLsizei(sizeof(Vertex)),
                              reinterpret_cast<const void*>(offset));
    };
    attribute(0, 3, offsetof(Vertex, position));
    attribute(1, 3, offsetof(Vertex, normal));
    attribute(2, 4, offsetof(Vertex, tangent));
    attribute(3, 2, offsetof(Vertex, uv));
    glBindVertexArray(GLuint(previousVao));
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    if (glGetError() == GL_OUT_OF_MEMORY) return Error{"mesh '" + mesh.name + "': out of GPU memory"};
    gpu.m_indexCount = int(mesh.indices.size());
    return gpu;
}

void GpuMesh::draw() const {
    if (!m_vao || m_indexCount == 0) return;
    glBindVertexArray(m_vao);
    glDrawElements(GL_TRIANGLES, m_indexCount, GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
}

} // namespace burnish::render
