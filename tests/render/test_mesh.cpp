// Meshes: generated sphere, plane and torus (unit normals, orthogonal tangents whose handedness
// agrees with the UV derivatives, outward winding, bounds), OBJ loading and its errors, and the
// GPU upload drawn headless.
#include <burnish/render/context.h>
#include <burnish/render/gpu_resources.h>
#include <burnish/render/mesh.h>
#include <burnish/render/program.h>

#include "temp_dir.h"

#include <burnish/core/util/files.h>
#include <burnish/core/util/numeric.h>

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

using namespace burnish;
using namespace burnish::render;

namespace {

// Unit vectors built in float: a few ulps of 1 (1.2e-7 each) after normalize and Gram–Schmidt.
constexpr float kUnitTolerance = 1e-5f;
// Cosines between a tangent and its normal: the same float rounding.
constexpr float kOrthogonalityTolerance = 1e-5f;
// Bounds of generated meshes come from float sin/cos of exact grid angles: a few ulps.
constexpr float kBoundsTolerance = 1e-5f;

// Per-triangle UV derivative directions (Lengyel): dP/du and dP/dv, or false when the UVs are
// degenerate.
bool uvDerivatives(const MeshData& mesh, size_t k, glm::vec3& dPdu, glm::vec3& dPdv) {
    const Vertex& a = mesh.vertices[mesh.indices[k]];
    const Vertex& b = mesh.vertices[mesh.indices[k + 1]];
    const Vertex& c = mesh.vertices[mesh.indices[k + 2]];
    const glm::vec3 e1 = b.position - a.position;
    const glm::vec3 e2 = c.position - a.position;
    const glm::vec2 d1 = b.uv - a.uv;
    const glm::vec2 d2 = c.uv - a.uv;
    const float det = d1.x * d2.y - d2.x * d1.y;
    if (std::abs(det) < 1e-12f) return false;
    dPdu = (e1 * d2.y - e2 * d1.y) / det;
    dPdv = (e2 * d1.x - e1 * d2.x) / det;
    return true;
}

// The invariants every mesh must keep; `outward` also checks that faces wind counter-clockwise
// seen from the side their vertex normals point to.
void expectValidMesh(const MeshData& mesh, bool outward = true) {
    ASSERT_FALSE(mesh.vertices.empty());
    ASSERT_FALSE(mesh.indices.empty());
    ASSERT_EQ(mesh.indices.size() % 3, 0u);
    for (const std::uint32_t index : mesh.indices)
        ASSERT_LT(index, mesh.vertices.size());
    int failures = 0;
    for (const Vertex& v : mesh.vertices) {
        const glm::vec3 t(v.tangent);
        EXPECT_NEAR(glm::length(v.normal), 1.0f, kUnitTolerance);
        EXPECT_NEAR(glm::length(t), 1.0f, kUnitTolerance);
        EXPECT_NEAR(glm::dot(v.normal, t), 0.0f, kOrthogonalityTolerance);
        EXPECT_TRUE(v.tangent.w == 1.0f || v.tangent.w == -1.0f) << v.tangent.w;
        EXPECT_TRUE(glm::all(glm::greaterThanEqual(v.position, mesh.boundsMin - kBoundsTolerance)));
        EXPECT_TRUE(glm::all(glm::lessThanEqual(v.position, mesh.boundsMax + kBoundsTolerance)));
        if (::testing::Test::HasFailure() && ++failures > 0) return; // one report, not thousands
    }
    for (size_t k = 0; k < mesh.indices.size(); k += 3) {
        glm::vec3 dPdu;
        glm::vec3 dPdv;
        const bool hasUv = uvDerivatives(mesh, k, dPdu, dPdv);
        const glm::vec3 p0 = mesh.vertices[mesh.indices[k]].position;
        const glm::vec3 faceNormal = glm::cross(mesh.vertices[mesh.indices[k + 1]].position - p0,
                                                mesh.vertices[mesh.indices[k + 2]].position - p0);
        for (size_t c = 0; c < 3; ++c) {
            const Vertex& v = mesh.vertices[mesh.indices[k + c]];
            if (outward) {
                EXPECT_GT(glm::dot(faceNormal, v.normal), 0.0f) << "triangle " << k / 3;
            }
            if (!hasUv) continue;
            // The stored frame agrees with this face's UV directions: t along +u, and the
            // bitangent w·(n × t) along +v.
            const glm::vec3 t(v.tangent);
            const glm::vec3 bitangent = v.tangent.w * glm::cross(v.normal, t);
            EXPECT_GT(glm::dot(t, dPdu), 0.0f) << "triangle " << k / 3;
            EXPECT_GT(glm::dot(bitangent, dPdv), 0.0f) << "triangle " << k / 3;
        }
        if (::testing::Test::HasFailure()) return;
    }
}

} // namespace

TEST(Mesh, SphereIsAValidUnitSphere) {
    for (const auto& [segments, rings] : {std::pair{96, 48}, std::pair{7, 4}}) {
        SCOPED_TRACE("sphere " + std::to_string(segments) + "x" + std::to_string(rings));
        const MeshData sphere = makeSphere(segments, rings);
        expectValidMesh(sphere);
        EXPECT_EQ(sphere.vertices.size(), size_t((segments + 1) * (rings + 1)));
        // Two triangles per quad except at the poles, where one of them would be degenerate.
        EXPECT_EQ(sphere.indices.size(), size_t(3 * segments * (2 * rings - 2)));
        for (const Vertex& v : sphere.vertices) {
            EXPECT_NEAR(glm::length(v.position), 1.0f, kUnitTolerance);
            EXPECT_NEAR(glm::dot(v.position, v.normal), 1.0f, kUnitTolerance) << "normal = position";
            // This generator's frame is right-handed everywhere: v runs north, u east.
            EXPECT_EQ(v.tangent.w, 1.0f);
            if (::testing::Test::HasFailure()) return;
        }
        EXPECT_NEAR(sphere.boundsMin.y, -1.0f, kBoundsTolerance);
        EXPECT_NEAR(sphere.boundsMax.y, 1.0f, kBoundsTolerance);
        EXPECT_NEAR(sphere.boundsMax.x, 1.0f, kBoundsTolerance);
    }
}

// The renderer's sphere is tessellated for its size on screen: the fewest segments (in steps of 16)
// whose silhouette keeps within half a pixel of the circle, so no finer mesh costs shading for nothing.
TEST(Mesh, SphereSegmentsFollowTheSilhouetteTolerance) {
    const auto sagitta = [](double radius, int segments) {
        return radius * (1.0 - std::cos(kPi<double> / double(segments)));
    };
    int previous = 0;
    for (const double radius : {1.0, 10.0, 31.0, 100.0, 175.0, 349.7, 524.5, 1000.0, 4000.0}) {
        SCOPED_TRACE("radius " + std::to_string(radius));
        const int n = sphereSegmentsForRadius(radius);
        EXPECT_EQ(n % 16, 0);
        EXPECT_GE(n, kMinSphereSegments);
        EXPECT_LE(n, kMaxSphereSegments);
        EXPECT_GE(n, previous) << "a larger sphere never gets fewer segments";
        previous = n;
        if (n < kMaxSphereSegments) {
            EXPECT_LE(sagitta(radius, n), kSphereSilhouetteTolerancePixels);
        }
        if (n > kMinSphereSegments) {
            EXPECT_GT(sagitta(radius, n - 16), kSphereSilhouetteTolerancePixels) << "16 fewer would do";
        }
    }
    // The benchmark's view (1280x720, distance 3, 40°: a 350-pixel radius) and its half-size frame.
    EXPECT_EQ(sphereSegmentsForRadius(349.7), 64);
    EXPECT_EQ(sphereSegmentsForRadius(174.9), 48);
    // Degenerate radii: none or negative gets the fewest, NaN, infinite or absurd the most.
    EXPECT_EQ(sphereSegmentsForRadius(0.0), kMinSphereSegments);
    EXPECT_EQ(sphereSegmentsForRadius(-5.0), kMinSphereSegments);
    EXPECT_EQ(sphereSegmentsForRadius(std::numeric_limits<double>::quiet_NaN()), kMaxSphereSegments);
    EXPECT_EQ(sphereSegmentsForRadius(std::numeric_limits<double>::infinity()), kMaxSphereSegments);
    EXPECT_EQ(sphereSegmentsForRadius(1e12), kMaxSphereSegments);
}

TEST(Mesh, SphereScreenRadiusIsTheSilhouetteConesProjection) {
    // Distance 3, 40° vertical field of view, 720 pixels: tan(asin(1/3)) / tan(20°) · 360.
    const double expected = (1.0 / std::sqrt(8.0)) / std::tan(kPi<double> / 9.0) * 360.0;
    EXPECT_NEAR(sphereScreenRadius(3.0, 40.0 * kPi<double> / 180.0, 720), expected, 1e-9);
    EXPECT_NEAR(expected, 349.7, 0.1);
    // Twice the frame, twice the radius; farther, smaller.
    EXPECT_NEAR(sphereScreenRadius(3.0, 0.7, 1440), 2.0 * sphereScreenRadius(3.0, 0.7, 720), 1e-9);
    EXPECT_LT(sphereScreenRadius(6.0, 0.7, 720), sphereScreenRadius(3.0, 0.7, 720));
    // The eye on or inside the sphere sees it fill everything; NaN distances too.
    EXPECT_TRUE(std::isinf(sphereScreenRadius(1.0, 0.7, 720)));
    EXPECT_TRUE(std::isinf(sphereScreenRadius(0.5, 0.7, 720)));
    EXPECT_TRUE(std::isinf(sphereScreenRadius(std::numeric_limits<double>::quiet_NaN(), 0.7, 720)));
    EXPECT_TRUE(std::isfinite(sphereScreenRadius(3.0, 0.0, 0)));
}

TEST(Mesh, SphereUvRepeatScalesUvs) {
    const MeshData sphere = makeSphere(8, 4, 3.0f);
    float maxU = 0.0f;
    float maxV = 0.0f;
    for (const Vertex& v : sphere.vertices) {
        maxU = std::max(maxU, v.uv.x);
        maxV = std::max(maxV, v.uv.y);
    }
    EXPECT_FLOAT_EQ(maxU, 3.0f);
    EXPECT_FLOAT_EQ(maxV, 3.0f);
}

TEST(Mesh, PlaneBoundsFrameAndWinding) {
    const MeshData plane = makePlane(40.0f, 10.0f, 4);
    expectValidMesh(plane);
    EXPECT_EQ(plane.vertices.size(), 25u);
    EXPECT_EQ(plane.indices.size(), 4u * 4u * 6u);
    EXPECT_EQ(plane.boundsMin, glm::vec3(-20.0f, 0.0f, -20.0f));
    EXPECT_EQ(plane.boundsMax, glm::vec3(20.0f, 0.0f, 20.0f));
    for (const Vertex& v : plane.vertices) {
        EXPECT_EQ(v.normal, glm::vec3(0.0f, 1.0f, 0.0f));
        EXPECT_NEAR(v.tangent.x, 1.0f, kUnitTolerance) << "u runs along +x";
        EXPECT_EQ(v.tangent.w, 1.0f);
        EXPECT_GE(v.uv.x, 0.0f);
        EXPECT_LE(v.uv.x, 10.0f);
    }
}

TEST(Mesh, TorusBoundsAndFrame) {
    constexpr float kMajor = 0.7f;
    constexpr float kMinor = 0.3f;
    const MeshData torus = makeTorus(kMajor, kMinor, 32, 16);
    expectValidMesh(torus);
    // The grid contains φ = 0, π/2, π, 3π/2 and ψ = 0, π/2, π: the extremes are vertices.
    EXPECT_NEAR(torus.boundsMax.x, kMajor + kMinor, kBoundsTolerance);
    EXPECT_NEAR(torus.boundsMin.x, -(kMajor + kMinor), kBoundsTolerance);
    EXPECT_NEAR(torus.boundsMax.z, kMajor + kMinor, kBoundsTolerance);
    EXPECT_NEAR(torus.boundsMin.z, -(kMajor + kMinor), kBoundsTolerance);
    EXPECT_NEAR(torus.boundsMax.y, kMinor, kBoundsTolerance);
    EXPECT_NEAR(torus.boundsMin.y, -kMinor, kBoundsTolerance);
    for (const Vertex& v : torus.vertices) {
        // Every point lies on the tube: distance r from the core circle of radius R.
        const glm::vec2 radial(v.position.x, v.position.z);
        const float ringDistance = glm::length(radial) - kMajor;
        EXPECT_NEAR(std::hypot(ringDistance, v.position.y), kMinor, kBoundsTolerance);
    }
}

TEST(Mesh, GenerateTangentsHandlesMirroredAndDegenerateUvs) {
    // Two triangles in the xy plane (normal +z): one with u along +x, v along +y (w = +1), one
    // mirrored in v (w = −1), and one whose UVs are all equal (any orthonormal tangent).
    MeshData mesh;
    auto add = [&](glm::vec3 p, glm::vec2 uv) {
        Vertex v;
        v.position = p;
        v.normal = glm::vec3(0.0f, 0.0f, 1.0f);
        v.uv = uv;
        mesh.vertices.push_back(v);
        return std::uint32_t(mesh.vertices.size() - 1);
    };
    mesh.indices = {add({0, 0, 0}, {0, 0}),       add({1, 0, 0}, {1, 0}),       add({0, 1, 0}, {0, 1}),
                    add({2, 0, 0}, {0, 1}),       add({3, 0, 0}, {1, 1}),       add({2, 1, 0}, {0, 0}),
                    add({4, 0, 0}, {0.5f, 0.5f}), add({5, 0, 0}, {0.5f, 0.5f}), add({4, 1, 0}, {0.5f, 0.5f})};
    generateTangents(mesh);
    mesh.boundsMin = glm::vec3(0.0f);
    mesh.boundsMax = glm::vec3(5.0f, 1.0f, 0.0f);
    expectValidMesh(mesh);
    EXPECT_EQ(mesh.vertices[0].tangent, glm::vec4(1.0f, 0.0f, 0.0f, 1.0f));
    EXPECT_EQ(mesh.vertices[3].tangent, glm::vec4(1.0f, 0.0f, 0.0f, -1.0f));
    EXPECT_NEAR(glm::length(glm::vec3(mesh.vertices[6].tangent)), 1.0f, kUnitTolerance);
}

namespace {

// A unit quad in the xy plane, facing +z, u along +x and v along +y; `normals` adds vn lines.
std::string quadObj(bool normals, bool uvs) {
    std::string obj = "# test quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    if (uvs) obj += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
    if (normals) obj += "vn 0 0 1\n";
    if (normals && uvs) return obj + "f 1/1/1 2/2/1 3/3/1 4/4/1\n";
    if (uvs) return obj + "f 1/1 2/2 3/3 4/4\n";
    return obj + "f 1 2 3 4\n";
}

} // namespace

TEST(Mesh, ObjQuadLoadsWithAndWithoutNormals) {
    test::TempDir dir;
    for (const bool normals : {true, false}) {
        SCOPED_TRACE(normals ? "with normals" : "normals generated");
        const auto path = dir / (normals ? "quad_n.obj" : "quad.obj");
        ASSERT_TRUE(writeFileAtomic(path, quadObj(normals, true)));
        auto mesh = loadObj(path);
        ASSERT_TRUE(mesh) << mesh.error();
        expectValidMesh(*mesh);
        EXPECT_EQ(mesh->vertices.size(), 4u) << "shared corners are one vertex";
        EXPECT_EQ(mesh->indices.size(), 6u) << "the quad is triangulated";
        EXPECT_EQ(mesh->boundsMin, glm::vec3(0.0f));
        EXPECT_EQ(mesh->boundsMax, glm::vec3(1.0f, 1.0f, 0.0f));
        for (const Vertex& v : mesh->vertices) {
            EXPECT_NEAR(v.normal.z, 1.0f, kUnitTolerance);
            EXPECT_NEAR(v.tangent.x, 1.0f, kUnitTolerance);
            EXPECT_EQ(v.tangent.w, 1.0f);
            // The UV of each corner is its position (the file says so).
            EXPECT_EQ(v.uv, glm::vec2(v.position.x, v.position.y));
        }
    }
}

TEST(Mesh, ObjErrors) {
    test::TempDir dir;
    auto missing = loadObj(dir / "absent.obj");
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().find("absent.obj"), std::string::npos) << missing.error();

    const auto noUv = dir / "no_uv.obj";
    ASSERT_TRUE(writeFileAtomic(noUv, quadObj(true, false)));
    auto noUvMesh = loadObj(noUv);
    ASSERT_FALSE(noUvMesh);
    EXPECT_NE(noUvMesh.error().find("texture coordinates"), std::string::npos) << noUvMesh.error();

    const auto empty = dir / "points.obj";
    ASSERT_TRUE(writeFileAtomic(empty, std::string("v 0 0 0\nv 1 0 0\n")));
    auto emptyMesh = loadObj(empty);
    ASSERT_FALSE(emptyMesh);
    EXPECT_NE(emptyMesh.error().find("no triangles"), std::string::npos) << emptyMesh.error();

    // A texture coordinate beyond float's range (a fuzzing find) is refused, never Inf in a vertex.
    const auto huge = dir / "huge_uv.obj";
    ASSERT_TRUE(writeFileAtomic(huge, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 2" +
                                          std::string(100, '0') + " 1\nf 1/1 2/2 3/3\n"));
    auto hugeMesh = loadObj(huge);
    ASSERT_FALSE(hugeMesh);
    EXPECT_NE(hugeMesh.error().find("texture coordinate is not finite"), std::string::npos)
        << hugeMesh.error();
}

TEST(Mesh, GpuMeshUploadsAndDraws) {
    auto context = createHeadlessContext();
    ASSERT_TRUE(context) << context.error();
    EXPECT_FALSE(GpuMesh::upload(MeshData{}));
    MeshData bad = makePlane(1.0f, 1.0f, 1);
    bad.indices.back() = std::uint32_t(bad.vertices.size());
    EXPECT_FALSE(GpuMesh::upload(bad));

    const MeshData sphere = makeSphere(24, 12);
    auto gpu = GpuMesh::upload(sphere);
    ASSERT_TRUE(gpu) << gpu.error();
    EXPECT_EQ(gpu->indexCount(), int(sphere.indices.size()));
    // The unit sphere scaled to half the viewport, coloured by its normal's z (attribute 1): the
    // centre faces the viewer (+z), the corners stay clear.
    const std::string vertex = "#version 330 core\nin vec3 aPosition;\nin vec3 aNormal;\nout float vFacing;\n"
                               "void main() { vFacing = aNormal.z; gl_Position = vec4(0.5 * aPosition.xy, "
                               "-0.5 * aPosition.z, 1.0); }\n";
    const std::string fragment = "#version 330 core\nin float vFacing;\nout vec4 c;\nvoid main() { c = "
                                 "vec4(vFacing, 1.0, 0.0, 1.0); }\n";
    auto program = Program::fromSources(vertex, fragment, "mesh test");
    ASSERT_TRUE(program) << program.error();
    constexpr int kSize = 32;
    auto fb = Framebuffer::create(kSize, kSize, ColorFormat::Rgba32f);
    ASSERT_TRUE(fb) << fb.error();
    fb->bind();
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    program->use();
    gpu->draw();
    glDisable(GL_DEPTH_TEST);
    const auto pixels = fb->readRgbaFloat();
    const auto at = [&](int x, int y, int c) { return pixels[size_t((y * kSize + x) * 4 + c)]; };
    // Centre: the nearest point of the sphere, normal ≈ +z (the facet normal is interpolated
    // between vertices at most 360/24 = 15° apart: cos 15° ≈ 0.966).
    constexpr float kFacetCosine = 0.96f;
    EXPECT_EQ(at(kSize / 2, kSize / 2, 1), 1.0f) << "centre covered";
    EXPECT_GT(at(kSize / 2, kSize / 2, 0), kFacetCosine)
        << "the front half is the one kept by the depth test";
    EXPECT_EQ(at(0, 0, 1), 0.0f) << "corner clear";
    EXPECT_EQ(at(kSize - 1, kSize - 1, 1), 0.0f) << "corner clear";
}
