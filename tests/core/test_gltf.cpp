// `burnish gltf`'s core: a glTF asset's normal-mapped materials baked into KTX2 textures with Burnish's
// own mips, everything else carried over, and bad assets refused in one line with nothing written.
#include <burnish/core/io/image.h>
#include <burnish/core/io/ktx2.h>
#include <burnish/core/jobs/bake_job.h>
#include <burnish/core/jobs/gltf.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/lobe_mixture.h>

#include "temp_dir.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace burnish {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kData = BURNISH_TEST_DATA_DIR;

json readJson(const fs::path& p) {
    auto bytes = readFile(p);
    EXPECT_TRUE(bytes) << p;
    return json::parse(bytes ? *bytes : std::string("{}"));
}

void writeText(const fs::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
}

// The test plane beside a copy of a real normal map, optionally edited.
fs::path planeAsset(const fs::path& dir, const std::function<void(json&)>& edit = {}) {
    fs::create_directories(dir);
    fs::copy_file(kData / "trak-treadplate1_nm.png", dir / "normal.png",
                  fs::copy_options::overwrite_existing);
    json doc = readJson(kData / "gltf" / "plane.gltf");
    if (edit) edit(doc);
    writeText(dir / "plane.gltf", doc.dump());
    return dir / "plane.gltf";
}

void writeRgb(const fs::path& p, int w, int h, const std::vector<float>& rgb) {
    auto out = OIIO::ImageOutput::create(p.string());
    ASSERT_TRUE(out && out->open(p.string(), OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::UINT8)) &&
                out->write_image(OIIO::TypeDesc::FLOAT, rgb.data()) && out->close());
}

// The test plane whose material also has a grey 16×16 metallicRoughness texture.
fs::path texturedPlaneAsset(const fs::path& dir) {
    fs::create_directories(dir);
    writeRgb(dir / "mr.png", 16, 16, std::vector<float>(16 * 16 * 3, 0.5f));
    return planeAsset(dir, [](json& d) {
        d["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", 1}};
        d["textures"].push_back({{"source", 1}});
        d["images"].push_back({{"uri", "mr.png"}});
    });
}

// The KTX2 file a material's texture (by role) points at through KHR_texture_ktx.
Ktx2Texture materialKtx(const fs::path& out, const json& doc, const std::string& slot) {
    const json& m = doc["materials"][0];
    const int texture = slot == "normal"
                            ? m["normalTexture"]["index"].get<int>()
                            : m["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"].get<int>();
    const int image = doc["textures"][size_t(texture)]["extensions"]["KHR_texture_ktx"]["source"];
    auto bytes = readFile(out / doc["images"][size_t(image)]["uri"].get<std::string>());
    EXPECT_TRUE(bytes);
    auto ktx = decodeKtx2(bytes ? *bytes : std::string());
    EXPECT_TRUE(ktx) << (ktx ? "" : ktx.error());
    return ktx ? *ktx : Ktx2Texture{};
}

TEST(Gltf, APlaneGetsKtx2TexturesEqualToTheBakeOfItsMapAndKeepsEverythingElse) {
    test::TempDir dir;
    const fs::path asset = planeAsset(dir.path() / "in");
    auto r = processGltf(asset, dir.path() / "out");
    ASSERT_TRUE(r) << r.error();
    ASSERT_EQ(r->materials.size(), 1u);
    EXPECT_EQ(r->materials[0].mipCount, 10);
    EXPECT_EQ(r->materials[0].border, "wrap");
    const json in = readJson(asset), out = readJson(r->asset);

    // Untouched: the other material, the mesh, the unknown extension, the first material's extras.
    EXPECT_EQ(out["materials"][1], in["materials"][1]);
    EXPECT_EQ(out["meshes"], in["meshes"]);
    EXPECT_EQ(out["accessors"], in["accessors"]);
    EXPECT_EQ(out["extensions"], in["extensions"]);
    EXPECT_EQ(out["materials"][0]["extras"]["author"], "test");
    EXPECT_EQ(out["materials"][0]["pbrMetallicRoughness"]["metallicFactor"], 1.0);
    EXPECT_FALSE(out["materials"][0]["pbrMetallicRoughness"].contains("roughnessFactor"));
    const auto& used = out["extensionsUsed"];
    EXPECT_NE(std::find(used.begin(), used.end(), "KHR_texture_ktx"), used.end());
    EXPECT_NE(std::find(used.begin(), used.end(), "EXT_unknown_to_burnish"), used.end());
    EXPECT_FALSE(out.contains("extensionsRequired")); // the PNG source keeps every viewer working

    // The same textures as a plain bake of the map at the same options, code for code.
    BakeJobSpec spec;
    spec.input = (dir.path() / "in" / "normal.png").string();
    spec.out = (dir.path() / "bake").string();
    spec.preset = "gltf";
    spec.power = GlossEncoding::ggxRoughness().power(0.5);
    spec.format = "png8";
    auto job = resolveBakeJob(spec);
    ASSERT_TRUE(job) << job.error();
    auto baked = runBakeJob(*job);
    ASSERT_TRUE(baked) << baked.error();
    const Ktx2Texture normal = materialKtx(dir.path() / "out", out, "normal");
    const Ktx2Texture mr = materialKtx(dir.path() / "out", out, "metallicRoughness");
    EXPECT_EQ(normal.format, Ktx2Format::Rg8);
    EXPECT_EQ(mr.format, Ktx2Format::Rgba8);
    ASSERT_EQ(normal.levels.size(), 10u);
    ASSERT_EQ(mr.levels.size(), 10u);
    size_t differing = 0;
    for (const auto& file : baked->exported.files) {
        const bool isNormal = file.name == "normal";
        for (size_t k = 0; k < file.paths.size(); ++k) {
            auto image = readImage(dir.path() / "bake" / file.paths[k]);
            ASSERT_TRUE(image);
            const std::string& level = isNormal ? normal.levels[k] : mr.levels[k];
            for (size_t i = 0; i < image->texelCount(); ++i)
                for (int c : isNormal ? std::vector<int>{0, 1} : std::vector<int>{1}) {
                    const int code =
                        int(std::lround(image->pixels[i * size_t(image->channels) + size_t(c)] * 255.0f));
                    const int stored = static_cast<unsigned char>(level[i * (isNormal ? 2 : 4) + size_t(c)]);
                    differing += code != stored;
                }
            if (!isNormal) // R and B: 1 where the material had no texture (metallicFactor keeps its meaning)
                for (size_t i = 0; i < image->texelCount(); ++i) {
                    EXPECT_EQ(static_cast<unsigned char>(level[i * 4]), 255);
                    EXPECT_EQ(static_cast<unsigned char>(level[i * 4 + 2]), 255);
                }
        }
    }
    EXPECT_EQ(differing, 0u);
    // The PNG fallback is mip 0 of the same bake.
    const int pngImage =
        out["textures"][out["materials"][0]["normalTexture"]["index"].get<size_t>()]["source"];
    auto fallback = readImage(dir.path() / "out" / out["images"][size_t(pngImage)]["uri"].get<std::string>());
    ASSERT_TRUE(fallback);
    EXPECT_EQ(fallback->width, 512);
    EXPECT_EQ(fallback->channels, 3);
}

TEST(Gltf, ScaleFactorAndRoughnessTextureAreFoldedIn) {
    test::TempDir dir;
    // A flat normal map's roughness is the base roughness: roughnessFactor × the texture's G.
    std::vector<float> mrTexels;
    for (int i = 0; i < 64 * 64; ++i)
        mrTexels.insert(mrTexels.end(), {0.25f, 0.6f, 0.8f});
    fs::create_directories(dir.path() / "in");
    writeRgb(dir.path() / "in" / "mr.png", 64, 64, mrTexels);
    const fs::path asset = planeAsset(dir.path() / "in", [](json& doc) {
        doc["materials"][0]["normalTexture"]["scale"] = 0.0; // flattens the map
        doc["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", 1}};
        doc["textures"].push_back({{"source", 1}});
        doc["images"].push_back({{"uri", "mr.png"}});
    });
    auto r = processGltf(asset, dir.path() / "out");
    ASSERT_TRUE(r) << r.error();
    ASSERT_EQ(r->materials.size(), 1u);
    EXPECT_TRUE(r->materials[0].roughnessTexture);
    EXPECT_FALSE(r->materials[0].notes.empty()); // 64² resampled to 512²
    EXPECT_NEAR(r->materials[0].meanRoughnessMip0, 0.5 * 0.6, 0.01);
    EXPECT_NEAR(r->materials[0].meanRoughnessLast, 0.5 * 0.6, 0.01);
    const json out = readJson(r->asset);
    EXPECT_FALSE(out["materials"][0]["normalTexture"].contains("scale"));
    const Ktx2Texture mr = materialKtx(dir.path() / "out", out, "metallicRoughness");
    for (const std::string& level : mr.levels)
        for (size_t i = 0; i < level.size(); i += 4) {
            ASSERT_NEAR(static_cast<unsigned char>(level[i]), 64, 1);      // R kept
            ASSERT_NEAR(static_cast<unsigned char>(level[i + 2]), 204, 1); // B (metallic) kept
        }
    // A scaled-down map is smoother than the full one.
    test::TempDir other;
    auto full = processGltf(planeAsset(other.path() / "in"), other.path() / "out");
    ASSERT_TRUE(full);
    auto half = processGltf(
        planeAsset(other.path() / "in2", [](json& d) { d["materials"][0]["normalTexture"]["scale"] = 0.5; }),
        other.path() / "out2");
    ASSERT_TRUE(half);
    EXPECT_LT(half->materials[0].meanRoughnessLast, full->materials[0].meanRoughnessLast);
}

// A GLB of the plane with the normal map inside its binary chunk.
std::string glbOf(const fs::path& gltf, const fs::path& png) {
    json doc = readJson(gltf);
    auto image = readFile(png);
    EXPECT_TRUE(image);
    const std::string& uri = doc["buffers"][0]["uri"];
    std::string bin;
    { // decode the data URI's base64 with the KTX-free helper of the standard library: none; do it here.
        const std::string b64 = uri.substr(uri.find(',') + 1);
        int val = 0, bits = -8;
        for (unsigned char c : b64) {
            const int d = std::isupper(c)   ? c - 'A'
                          : std::islower(c) ? c - 'a' + 26
                          : std::isdigit(c) ? c - '0' + 52
                          : c == '+'        ? 62
                          : c == '/'        ? 63
                                            : -1;
            if (d < 0) break;
            val = (val << 6) + d;
            bits += 6;
            if (bits >= 0) {
                bin.push_back(char((val >> bits) & 0xFF));
                bits -= 8;
            }
        }
    }
    const size_t imageOffset = (bin.size() + 3) / 4 * 4;
    bin.resize(imageOffset, '\0');
    bin += *image;
    while (bin.size() % 4)
        bin.push_back('\0');
    doc["buffers"][0].erase("uri");
    doc["buffers"][0]["byteLength"] = bin.size();
    doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", imageOffset}, {"byteLength", image->size()}});
    doc["images"][0] = {{"bufferView", doc["bufferViews"].size() - 1}, {"mimeType", "image/png"}};
    std::string text = doc.dump();
    while (text.size() % 4)
        text.push_back(' ');
    auto put = [](std::string& s, std::uint32_t v) {
        for (int i = 0; i < 4; ++i)
            s.push_back(char((v >> (8 * i)) & 0xFF));
    };
    std::string glb;
    put(glb, 0x46546C67);
    put(glb, 2);
    put(glb, std::uint32_t(12 + 8 + text.size() + 8 + bin.size()));
    put(glb, std::uint32_t(text.size()));
    put(glb, 0x4E4F534A);
    glb += text;
    put(glb, std::uint32_t(bin.size()));
    put(glb, 0x004E4942);
    glb += bin;
    return glb;
}

TEST(Gltf, AGlbComesOutAsAGlbWithEveryImageInside) {
    test::TempDir dir;
    const fs::path gltf = planeAsset(dir.path() / "in");
    writeText(dir.path() / "in" / "plane.glb", glbOf(gltf, dir.path() / "in" / "normal.png"));
    fs::remove(dir.path() / "in" / "normal.png"); // nothing outside the GLB
    auto r = processGltf(dir.path() / "in" / "plane.glb", dir.path() / "out");
    ASSERT_TRUE(r) << r.error();
    EXPECT_EQ(r->asset.extension(), ".glb");
    EXPECT_EQ(r->written.size(), 1u);
    EXPECT_TRUE(r->materials[0].files.empty());
    auto bytes = readFile(r->asset);
    ASSERT_TRUE(bytes);
    // Parse the output container and decode the normal texture's KTX2 from its binary chunk.
    auto u32 = [&](size_t at) {
        std::uint32_t v = 0;
        for (int i = 3; i >= 0; --i)
            v = (v << 8) | static_cast<unsigned char>((*bytes)[at + size_t(i)]);
        return v;
    };
    ASSERT_EQ(u32(8), bytes->size());
    const std::uint32_t jsonLength = u32(12);
    const json doc = json::parse(bytes->substr(20, jsonLength));
    const std::string bin = bytes->substr(20 + jsonLength + 8, u32(20 + jsonLength));
    EXPECT_EQ(doc["buffers"][0]["byteLength"], bin.size());
    const int texture = doc["materials"][0]["normalTexture"]["index"];
    const int image = doc["textures"][size_t(texture)]["extensions"]["KHR_texture_ktx"]["source"];
    const json& view = doc["bufferViews"][doc["images"][size_t(image)]["bufferView"].get<size_t>()];
    EXPECT_EQ(doc["images"][size_t(image)]["mimeType"], "image/ktx2");
    auto ktx = decodeKtx2(
        std::string_view(bin).substr(view["byteOffset"].get<size_t>(), view["byteLength"].get<size_t>()));
    ASSERT_TRUE(ktx) << ktx.error();
    EXPECT_EQ(ktx->levels.size(), 10u);
    // The original mesh data still reads where it was.
    EXPECT_EQ(doc["bufferViews"][0],
              json({{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}, {"target", 34962}}));
}

TEST(Gltf, BcCodingWritesBc5AndBc3Chains) {
    test::TempDir dir;
    GltfOptions o;
    o.coding = GltfTextureCoding::Bc;
    auto r = processGltf(planeAsset(dir.path() / "in"), dir.path() / "out", o);
    ASSERT_TRUE(r) << r.error();
    const json out = readJson(r->asset);
    EXPECT_EQ(materialKtx(dir.path() / "out", out, "normal").format, Ktx2Format::Bc5);
    const Ktx2Texture mr = materialKtx(dir.path() / "out", out, "metallicRoughness");
    EXPECT_EQ(mr.format, Ktx2Format::Bc3);
    EXPECT_EQ(mr.levels.size(), 10u);
}

TEST(Gltf, AnAssetWithoutNormalMapsIsCopiedUnchanged) {
    test::TempDir dir;
    const fs::path asset =
        planeAsset(dir.path() / "in", [](json& d) { d["materials"][0].erase("normalTexture"); });
    auto r = processGltf(asset, dir.path() / "out");
    ASSERT_TRUE(r) << r.error();
    EXPECT_TRUE(r->materials.empty());
    EXPECT_EQ(readJson(r->asset), readJson(asset));
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "normal.png")); // its images are carried over
}

TEST(Gltf, BadAssetsAreRefusedInOneLineAndNothingIsWritten) {
    test::TempDir dir;
    auto refused = [&](const fs::path& asset, const std::string& needle) {
        const fs::path out = dir.path() / "out-refused";
        auto r = processGltf(asset, out);
        ASSERT_FALSE(r) << needle;
        EXPECT_NE(r.error().find(needle), std::string::npos) << r.error();
        EXPECT_EQ(r.error().find('\n'), std::string::npos) << r.error();
        EXPECT_TRUE(!fs::exists(out) || fs::is_empty(out)) << needle;
    };
    writeText(dir.path() / "text.gltf", "this is not json");
    refused(dir.path() / "text.gltf", "not valid JSON");
    refused(planeAsset(dir.path() / "v1", [](json& d) { d["asset"]["version"] = "1.0"; }),
            "glTF version 1.0");
    refused(planeAsset(dir.path() / "noasset", [](json& d) { d.erase("asset"); }), "no asset.version");
    refused(planeAsset(dir.path() / "missing", [](json& d) { d["images"][0]["uri"] = "gone.png"; }),
            "gone.png");
    refused(
        planeAsset(dir.path() / "escape", [](json& d) { d["images"][0]["uri"] = "../escape/normal.png"; }),
        "outside the asset's folder");
    refused(planeAsset(dir.path() / "abs", [](json& d) { d["images"][0]["uri"] = "/etc/passwd"; }),
            "outside");
    refused(
        planeAsset(dir.path() / "http", [](json& d) { d["images"][0]["uri"] = "http://example.com/n.png"; }),
        "has a scheme");
    refused(planeAsset(dir.path() / "short", [](json& d) { d["buffers"][0]["byteLength"] = 100000; }),
            "less than its byteLength");
    refused(
        planeAsset(dir.path() / "view",
                   [](json& d) {
                       d["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 200}, {"byteLength", 100}});
                       d["images"][0] = {{"bufferView", 5}, {"mimeType", "image/png"}};
                   }),
        "runs past the end of buffer 0");
    refused(
        planeAsset(dir.path() / "uv", [](json& d) { d["materials"][0]["normalTexture"]["texCoord"] = 1; }),
        "TEXCOORD_1");
    refused(planeAsset(dir.path() / "tex", [](json& d) { d["materials"][0]["normalTexture"]["index"] = 7; }),
            "texture 7 does not exist");
    // A height map (grey) is not a normal map.
    std::vector<float> grey(32 * 32 * 3, 0.5f);
    for (size_t i = 0; i < grey.size(); ++i)
        grey[i] = float((i / 3) % 7) / 7.0f;
    const fs::path heights = planeAsset(dir.path() / "height");
    writeRgb(dir.path() / "height" / "normal.png", 32, 32, grey);
    refused(heights, "normal map");
    // A set already there is kept unless asked.
    const fs::path asset = planeAsset(dir.path() / "twice");
    ASSERT_TRUE(processGltf(asset, dir.path() / "twice-out"));
    const auto before = readFile(dir.path() / "twice-out" / "plane.gltf");
    auto again = processGltf(asset, dir.path() / "twice-out");
    ASSERT_FALSE(again);
    EXPECT_EQ(*readFile(dir.path() / "twice-out" / "plane.gltf"), *before);
    GltfOptions force;
    force.overwrite = Overwrite::Allow;
    EXPECT_TRUE(processGltf(asset, dir.path() / "twice-out", force));
}

} // namespace
} // namespace burnish

namespace burnish {
namespace {

TEST(Gltf, AMaterialExportsWithItsSpecularColourInGltfTerms) {
    test::TempDir dir;
    auto map = loadNormalMap(kData / "trak-rust1_nm.png");
    ASSERT_TRUE(map);
    GltfMaterialSource m;
    m.name = "iron";
    m.normal = std::make_shared<const NormalMap>(std::move(map.value()));
    m.roughness = 0.35;
    m.specular = {0.56, 0.57, 0.58};
    auto metal = exportMaterialGltf(m, dir.path() / "metal");
    ASSERT_TRUE(metal) << metal.error();
    const json a = readJson(metal->asset);
    EXPECT_EQ(metal->asset.filename(), "iron.gltf");
    const json& pbr = a["materials"][0]["pbrMetallicRoughness"];
    EXPECT_EQ(pbr["baseColorFactor"], json({0.56, 0.57, 0.58, 1.0}));
    EXPECT_EQ(pbr["metallicFactor"], 1.0);
    EXPECT_FALSE(pbr.contains("roughnessFactor"));
    EXPECT_NEAR(metal->materials[0].meanRoughnessMip0, 0.35, 0.002);
    // Only the baked textures: the 16-bit source's images and textures are pruned, no file of them written.
    EXPECT_EQ(a["textures"].size(), 2u);
    EXPECT_EQ(a["images"].size(), 4u);
    EXPECT_EQ(a["materials"][0]["normalTexture"]["index"], 0);
    EXPECT_EQ(pbr["metallicRoughnessTexture"]["index"], 1);
    EXPECT_FALSE(fs::exists(dir.path() / "metal" / "normal.png"));
    EXPECT_EQ(metal->written.size(), 5u);
    EXPECT_EQ(materialKtx(dir.path() / "metal", a, "normal").levels.size(), 10u);

    // A dielectric: F0 through KHR_materials_specular at ior 1.5; painted roughness per texel.
    m.metal = false;
    m.specular = {0.02, 0.03, 0.04};
    m.albedo = {0.3, 0.2, 0.1};
    auto texels = std::make_shared<std::vector<float>>(m.normal->texelCount(), 0.2f);
    for (size_t i = 0; i < texels->size() / 2; ++i)
        (*texels)[i] = 0.8f;
    m.roughnessTexels = texels;
    auto dielectric = exportMaterialGltf(m, dir.path() / "dielectric");
    ASSERT_TRUE(dielectric) << dielectric.error();
    const json d = readJson(dielectric->asset);
    const json& ext = d["materials"][0]["extensions"];
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(ext["KHR_materials_specular"]["specularColorFactor"][size_t(c)].get<double>() * 0.04,
                    m.specular[size_t(c)], 1e-12);
    EXPECT_EQ(ext["KHR_materials_ior"]["ior"], 1.5);
    EXPECT_EQ(d["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"], json({0.3, 0.2, 0.1, 1.0}));
    EXPECT_NEAR(dielectric->materials[0].meanRoughnessMip0, 0.5, 0.01); // half 0.8, half 0.2
    EXPECT_TRUE(dielectric->materials[0].roughnessTexture);

    EXPECT_TRUE(dielectric->materials[0].notes.empty() ||
                dielectric->materials[0].notes[0].find("material table") == std::string::npos);
    // A "metal" as dark as water: written as asked, and said.
    m.metal = true;
    m.roughnessTexels = nullptr;
    m.specular = {0.003, 0.003, 0.003};
    auto dark = exportMaterialGltf(m, dir.path() / "dark");
    ASSERT_TRUE(dark) << dark.error();
    ASSERT_FALSE(dark->materials[0].notes.empty());
    EXPECT_NE(dark->materials[0].notes.back().find("lies in the material table's"), std::string::npos);
    EXPECT_EQ(dark->summary["materials"][0]["notes"].back(), dark->materials[0].notes.back());
    m.metal = false;

    // Refusals.
    m.roughnessTexels = std::make_shared<std::vector<float>>(3, 0.5f);
    EXPECT_FALSE(exportMaterialGltf(m, dir.path() / "bad"));
    m.roughnessTexels = nullptr;
    m.roughness = std::nan("");
    EXPECT_FALSE(exportMaterialGltf(m, dir.path() / "bad"));
    m.roughness = 0.5;
    m.specular = {1.5, 0, 0};
    EXPECT_FALSE(exportMaterialGltf(m, dir.path() / "bad"));
    m.normal = nullptr;
    EXPECT_FALSE(exportMaterialGltf(m, dir.path() / "bad"));
    EXPECT_FALSE(fs::exists(dir.path() / "bad"));
}

} // namespace
} // namespace burnish

namespace burnish {
namespace {

// The test plane with a 128² map of grooves along y: slopes across them only, 0.6·sin(2πx/6), so every
// footprint past mip 0 spreads one way and the anisotropic fit is clearly the closer one.
fs::path groovedPlaneAsset(const fs::path& dir) {
    const fs::path asset = planeAsset(dir);
    std::vector<float> rgb(128 * 128 * 3);
    for (int y = 0; y < 128; ++y)
        for (int x = 0; x < 128; ++x) {
            const glm::vec3 n =
                glm::normalize(glm::vec3(0.6f * std::sin(2.0f * 3.14159265f * x / 6.0f), 0.0f, 1.0f));
            for (int c = 0; c < 3; ++c)
                rgb[3 * size_t(y * 128 + x) + size_t(c)] = 0.5f * n[c] + 0.5f;
        }
    writeRgb(dir / "normal.png", 128, 128, rgb);
    return asset;
}

TEST(Gltf, AnisotropyIsWrittenWhereTheAnisotropicFitIsCloser) {
    test::TempDir dir;
    GltfOptions o;
    o.anisotropy = GltfAnisotropy::Auto;
    // Grooves: the anisotropic fit is closer (evaluate --anisotropic says the same). (The tread plate, this
    // test's map before the fitted lobe's chain became the box one, is a near tie there: anisotropic 0.0511,
    // isotropic 0.0502 over mips 1-6, so Auto leaves it off.)
    auto r = processGltf(groovedPlaneAsset(dir.path() / "in"), dir.path() / "out", o);
    ASSERT_TRUE(r) << r.error();
    ASSERT_EQ(r->materials[0].anisotropy, "on");
    EXPECT_LT(r->materials[0].anisotropicError, r->materials[0].isotropicError);
    const json a = readJson(r->asset);
    const json& ext = a["materials"][0]["extensions"]["KHR_materials_anisotropy"];
    EXPECT_EQ(ext["anisotropyStrength"], 1.0);
    const auto& used = a["extensionsUsed"];
    EXPECT_NE(std::find(used.begin(), used.end(), "KHR_materials_anisotropy"), used.end());
    const int image = a["textures"][ext["anisotropyTexture"]["index"].get<size_t>()]["extensions"]
                       ["KHR_texture_ktx"]["source"];
    auto bytes = readFile(dir.path() / "out" / a["images"][size_t(image)]["uri"].get<std::string>());
    ASSERT_TRUE(bytes);
    auto ktx = decodeKtx2(*bytes);
    ASSERT_TRUE(ktx) << ktx.error();
    EXPECT_EQ(ktx->format, Ktx2Format::Rgba8);
    ASSERT_EQ(ktx->levels.size(), 8u);
    // Level 0 is the base lobe, round; coarser levels hold unit directions and some strength.
    for (size_t i = 0; i < ktx->levels[0].size(); i += 4)
        ASSERT_EQ(static_cast<unsigned char>(ktx->levels[0][i + 2]), 0);
    int strong = 0;
    for (size_t k = 1; k < ktx->levels.size(); ++k)
        for (size_t i = 0; i < ktx->levels[k].size(); i += 4) {
            const double x = static_cast<unsigned char>(ktx->levels[k][i]) / 127.5 - 1.0;
            const double y = static_cast<unsigned char>(ktx->levels[k][i + 1]) / 127.5 - 1.0;
            ASSERT_NEAR(std::hypot(x, y), 1.0, 0.02);
            strong += static_cast<unsigned char>(ktx->levels[k][i + 2]) > 25;
        }
    EXPECT_GT(strong, 0);

    // Off by default; On writes it where Auto would not; a material with a roughness texture says why not.
    auto off = processGltf(planeAsset(dir.path() / "in2"), dir.path() / "out2");
    ASSERT_TRUE(off);
    EXPECT_TRUE(off->materials[0].anisotropy.empty());
    EXPECT_FALSE(readJson(off->asset)["materials"][0].contains("extensions"));
    const fs::path textured = texturedPlaneAsset(dir.path() / "in3");
    auto withTexture = processGltf(textured, dir.path() / "out3", o);
    ASSERT_TRUE(withTexture);
    EXPECT_EQ(withTexture->materials[0].anisotropy.rfind("off: ", 0), 0u);
}

} // namespace
} // namespace burnish

namespace burnish {
namespace {

TEST(Gltf, ReplacingAnAssetRemovesTheFilesOnlyItNamed) {
    test::TempDir dir;
    const fs::path asset = planeAsset(dir.path() / "in");
    GltfOptions aniso;
    aniso.anisotropy = GltfAnisotropy::On;
    auto first = processGltf(asset, dir.path() / "out", aniso);
    ASSERT_TRUE(first) << first.error();
    ASSERT_TRUE(fs::exists(dir.path() / "out" / "plane_material0_anisotropy.ktx2"));
    writeText(dir.path() / "out" / "notes.txt", "the artist's own file");
    GltfOptions plain;
    plain.overwrite = Overwrite::Allow;
    auto second = processGltf(asset, dir.path() / "out", plain);
    ASSERT_TRUE(second) << second.error();
    EXPECT_FALSE(fs::exists(dir.path() / "out" / "plane_material0_anisotropy.ktx2"));
    EXPECT_FALSE(fs::exists(dir.path() / "out" / "plane_material0_anisotropy.png"));
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "notes.txt")); // never named by the asset: kept
    for (const std::string& name : second->written)
        EXPECT_TRUE(fs::exists(dir.path() / "out" / name)) << name;
    size_t entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path() / "out"))
        ++entries;
    EXPECT_EQ(entries, second->written.size() + 1);
}

} // namespace
} // namespace burnish

namespace burnish {
namespace {

// --method mixture: the fitted lobe as ever, and BURNISH_lobe_mixture beside it: K RGBA16F KTX2 chains to
// 1×1 in the normal texture's UV set, whose level 0 is each finest normal's own base lobe (share 1 in one
// slot, no spread) and whose levels above are the mixture's stored lobes (weights summing to 1).
TEST(Gltf, TheMixtureRidesBesideTheFittedLobeAsRgba16fLobeChains) {
    test::TempDir dir;
    GltfOptions o;
    o.method = "mixture";
    o.mixtureLobes = 2;
    auto r = processGltf(planeAsset(dir.path() / "in"), dir.path() / "out", o);
    ASSERT_TRUE(r) << r.error();
    EXPECT_EQ(r->materials[0].mixture, "on, 2 lobes");
    EXPECT_EQ(r->summary["method"], "mixture");
    const json a = readJson(r->asset);
    const json& m = a["materials"][0];
    ASSERT_TRUE(m["extensions"].contains("BURNISH_lobe_mixture")) << m.dump();
    const json& ext = m["extensions"]["BURNISH_lobe_mixture"];
    EXPECT_EQ(ext["lobes"], 2);
    EXPECT_DOUBLE_EQ(ext["roughnessFactor"].get<double>(), 0.5); // plane.gltf's
    EXPECT_DOUBLE_EQ(ext["spreadScale"].get<double>(), kMixtureGgxSpreadScale);
    ASSERT_EQ(ext["lobeTextures"].size(), 2u);
    const auto& used = a["extensionsUsed"];
    EXPECT_NE(std::find(used.begin(), used.end(), "BURNISH_lobe_mixture"), used.end());
    // The fitted lobe's textures are the plain fitted export's, byte for byte.
    GltfOptions fitted;
    auto plain = processGltf(planeAsset(dir.path() / "in2"), dir.path() / "out2", fitted);
    ASSERT_TRUE(plain) << plain.error();
    const json p = readJson(plain->asset);
    EXPECT_EQ(materialKtx(dir.path() / "out", a, "metallicRoughness").levels,
              materialKtx(dir.path() / "out2", p, "metallicRoughness").levels);
    EXPECT_EQ(materialKtx(dir.path() / "out", a, "normal").levels,
              materialKtx(dir.path() / "out2", p, "normal").levels);

    std::vector<Ktx2Texture> lobes;
    for (const json& info : ext["lobeTextures"]) {
        const json& t = a["textures"][info["index"].get<size_t>()];
        EXPECT_FALSE(t.contains("source")); // no PNG can hold these values
        const int image = t["extensions"]["KHR_texture_ktx"]["source"];
        auto bytes = readFile(dir.path() / "out" / a["images"][size_t(image)]["uri"].get<std::string>());
        ASSERT_TRUE(bytes);
        auto ktx = decodeKtx2(*bytes);
        ASSERT_TRUE(ktx) << ktx.error();
        EXPECT_EQ(ktx->format, Ktx2Format::Rgba16f);
        ASSERT_EQ(ktx->levels.size(), 10u); // 512² to 1×1
        lobes.push_back(*ktx);
    }
    auto texel = [&](size_t lobe, size_t k, size_t i) {
        std::array<double, 4> t{};
        for (size_t c = 0; c < 4; ++c) {
            Imath::half h;
            std::uint16_t bits;
            std::memcpy(&bits, lobes[lobe].levels[k].data() + (i * 4 + c) * 2, 2);
            h.setBits(bits);
            t[c] = double(float(h));
        }
        return t;
    };
    const double alpha0 = 0.25; // roughness 0.5
    for (size_t k = 0; k < 10; ++k) {
        const size_t n = lobes[0].levels[k].size() / 8;
        double widened = 0.0;
        for (size_t i = 0; i < n; ++i) {
            const auto t0 = texel(0, k, i), t1 = texel(1, k, i);
            ASSERT_NEAR(t0[0] + t1[0], 1.0, 2e-3) << "level " << k << " texel " << i;
            for (const auto& t : {t0, t1}) {
                const MixtureGgxLobe l = mixtureGgxLobe(t, t0[0] + t1[0], alpha0);
                ASSERT_TRUE(std::isfinite(l.alpha) && l.alpha >= alpha0 - 1e-9);
                if (k == 0 && t[0] > 0.0) {
                    ASSERT_EQ(t[0], 1.0); // one finest normal, whole
                    // No spread: w·S = |w·b|² to half-float precision.
                    ASSERT_NEAR(t[3], t[1] * t[1] + t[2] * t[2], 2e-3 * (1.0 + t[3])) << i;
                }
                widened += l.share * (l.alpha - alpha0);
            }
        }
        // The treads' slopes widen the lobes at every level above the finest, not at it.
        if (k == 0) {
            EXPECT_LT(widened / double(n), 1e-3);
        }
        if (k >= 2) {
            EXPECT_GT(widened / double(n), 1e-3) << "level " << k;
        }
    }

    // A material of one map (the studio's export, whose replaced textures are pruned and the rest
    // renumbered): the lobe textures still name the mixture's textures.
    auto map = loadNormalMap(kData / "trak-rust1_nm.png");
    ASSERT_TRUE(map) << map.error();
    GltfMaterialSource source;
    source.name = "rust";
    source.normal = std::make_shared<const NormalMap>(std::move(*map));
    auto exported = exportMaterialGltf(source, dir.path() / "material", o);
    ASSERT_TRUE(exported) << exported.error();
    const json e = readJson(exported->asset);
    EXPECT_EQ(e["materials"][0]["extras"]["burnish"]["method"], "mixture");
    const json& lobeInfos = e["materials"][0]["extensions"]["BURNISH_lobe_mixture"]["lobeTextures"];
    ASSERT_EQ(lobeInfos.size(), 2u);
    for (size_t l = 0; l < 2; ++l) {
        const size_t index = lobeInfos[l]["index"].get<size_t>();
        ASSERT_LT(index, e["textures"].size());
        EXPECT_EQ(e["textures"][index]["name"], fmt::format("rust mixtureLobe{} (Burnish)", l));
    }

    // A material with a roughness texture: the fitted lobe alone, and why.
    const fs::path textured = texturedPlaneAsset(dir.path() / "in3");
    auto withTexture = processGltf(textured, dir.path() / "out3", o);
    ASSERT_TRUE(withTexture) << withTexture.error();
    EXPECT_EQ(withTexture->materials[0].mixture.rfind("off: ", 0), 0u);
    const json t = readJson(withTexture->asset);
    EXPECT_FALSE(t["materials"][0].contains("extensions") &&
                 t["materials"][0]["extensions"].contains("BURNISH_lobe_mixture"));
}

} // namespace
} // namespace burnish
