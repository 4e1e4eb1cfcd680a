// The picked specular colour in each engine's terms (shading/specular_terms.h), and its way through a
// bake job into bake.json.
#include <burnish/core/jobs/bake_job.h>
#include <burnish/core/jobs/bake_ninja.h>
#include <burnish/core/shading/specular_terms.h>
#include <burnish/core/util/files.h>

#include "temp_dir.h"

#include <gtest/gtest.h>

#include <cmath>

namespace burnish {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

bool warnsOf(const SpecularTerms& t, const std::string& needle) {
    for (const std::string& w : t.warnings)
        if (w.find(needle) != std::string::npos) return true;
    return false;
}

TEST(SpecularTerms, MetalsAreTheirBaseColourInEveryEngine) {
    const LinearRgb gold{1.0, 0.766, 0.336};
    const auto gltf = specularTerms(SpecularConvention::Gltf, MaterialClass::Metal, gold);
    EXPECT_EQ(gltf.values["baseColorFactor"], json({1.0, 0.766, 0.336, 1.0}));
    EXPECT_EQ(gltf.values["metallicFactor"], 1.0);
    EXPECT_TRUE(gltf.warnings.empty());
    EXPECT_EQ(specularTerms(SpecularConvention::Unreal, MaterialClass::Metal, gold).values["BaseColor"],
              json({1.0, 0.766, 0.336}));
    EXPECT_EQ(specularTerms(SpecularConvention::UnityMetallic, MaterialClass::Metal, gold).values["Albedo"],
              json({1.0, 0.766, 0.336}));
    EXPECT_EQ(specularTerms(SpecularConvention::Godot, MaterialClass::Metal, gold).values["albedo_color"],
              json({1.0, 0.766, 0.336}));
    EXPECT_EQ(specularTerms(SpecularConvention::Filament, MaterialClass::Metal, gold).values["baseColor"],
              json({1.0, 0.766, 0.336}));
    // A "metal" as dark as water is exported as asked, with a word (the material table's ranges).
    const auto dark = specularTerms(SpecularConvention::Gltf, MaterialClass::Metal, LinearRgb::grey(0.003));
    EXPECT_TRUE(warnsOf(dark, "lies in the material table's")) << dark.warnings.size();
}

TEST(SpecularTerms, DielectricsTakeEachEnginesParameterAndSayWhereItCannotHold) {
    const LinearRgb water = LinearRgb::grey(0.02);
    // glTF: F0 = 0.04 · specularColorFactor at ior 1.5.
    const auto gltf = specularTerms(SpecularConvention::Gltf, MaterialClass::Dielectric, water);
    EXPECT_NEAR(gltf.values["KHR_materials_specular"]["specularColorFactor"][0].get<double>(), 0.5, 1e-15);
    EXPECT_EQ(gltf.values["KHR_materials_ior"]["ior"], 1.5);
    EXPECT_EQ(gltf.values["metallicFactor"], 0.0);
    // Unreal: F0 = 0.08 · Specular; Godot and Filament: F0 = 0.16 · s².
    EXPECT_NEAR(specularTerms(SpecularConvention::Unreal, MaterialClass::Dielectric, water)
                    .values["Specular"]
                    .get<double>(),
                0.25, 1e-15);
    EXPECT_NEAR(specularTerms(SpecularConvention::Godot, MaterialClass::Dielectric, LinearRgb::grey(0.04))
                    .values["metallic_specular"]
                    .get<double>(),
                0.5, 1e-15);
    EXPECT_NEAR(std::pow(specularTerms(SpecularConvention::Filament, MaterialClass::Dielectric, water)
                             .values["reflectance"]
                             .get<double>(),
                         2) *
                    0.16,
                0.02, 1e-15);
    // Past the range: Unreal's Specular holds F0 up to 0.08, Godot's and Filament's up to 0.16.
    const auto diamond = LinearRgb::grey(0.17);
    const auto unreal = specularTerms(SpecularConvention::Unreal, MaterialClass::Dielectric, diamond);
    EXPECT_EQ(unreal.values["Specular"], 1.0);
    EXPECT_TRUE(warnsOf(unreal, "clamped"));
    EXPECT_TRUE(
        warnsOf(specularTerms(SpecularConvention::Filament, MaterialClass::Dielectric, diamond), "clamped"));
    EXPECT_FALSE(
        warnsOf(specularTerms(SpecularConvention::Unreal, MaterialClass::Dielectric, water), "clamped"));
    // A tinted dielectric in a scalar parameter: its luminance, said so; glTF keeps the colour.
    const LinearRgb tinted{0.02, 0.03, 0.06};
    const auto scalar = specularTerms(SpecularConvention::Unreal, MaterialClass::Dielectric, tinted);
    EXPECT_NEAR(scalar.values["Specular"].get<double>(), luminance(tinted) / 0.08, 1e-15);
    EXPECT_TRUE(warnsOf(scalar, "luminance"));
    EXPECT_FALSE(
        warnsOf(specularTerms(SpecularConvention::Gltf, MaterialClass::Dielectric, tinted), "luminance"));
    // Unity's metallic setup fixes 0.04: said so, the specular setup's colour recorded.
    const auto unity = specularTerms(SpecularConvention::UnityMetallic, MaterialClass::Dielectric, water);
    EXPECT_TRUE(warnsOf(unity, "fixes a dielectric's F0 at 0.04"));
    EXPECT_EQ(unity.values["SpecularSetupColor"], json({0.02, 0.02, 0.02}));
    EXPECT_FALSE(warnsOf(
        specularTerms(SpecularConvention::UnityMetallic, MaterialClass::Dielectric, LinearRgb::grey(0.04)),
        "fixes"));
    EXPECT_EQ(specularTerms(SpecularConvention::F0, MaterialClass::Dielectric, water).values["f0"],
              json({0.02, 0.02, 0.02}));
}

TEST(SpecularTerms, PresetsNameTheirEnginesConvention) {
    EXPECT_EQ(findPreset("gltf")->specular, SpecularConvention::Gltf);
    EXPECT_EQ(findPreset("unreal")->specular, SpecularConvention::Unreal);
    EXPECT_EQ(findPreset("unity")->specular, SpecularConvention::UnityMetallic);
    EXPECT_EQ(findPreset("godot")->specular, SpecularConvention::Godot);
    EXPECT_EQ(findPreset("filament")->specular, SpecularConvention::Filament);
    EXPECT_EQ(findPreset("blackops")->specular, SpecularConvention::F0);
    const std::string text = R"({"schema": "burnish-preset", "version": 1, "name": "x", "title": "x",
        "description": "x", "conversion": "x", "gloss": "blackops", "method": "naive", "green": "opengl",
        "specular": "photoshop", "format": "png8", "files": [{"name": "n", "description": "n",
        "channels": [{"role": "normal", "channel": "normal.x"}]}]})";
    auto bad = parsePreset(text, "x.json");
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().find("unknown specular convention 'photoshop'"), std::string::npos) << bad.error();
}

TEST(SpecularTerms, ABakeRecordsTheColourInTheEnginesTermsInBakeJson) {
    test::TempDir dir;
    auto run = [&](const std::string& preset, const std::string& specular, std::optional<std::string> cls) {
        BakeJobSpec spec;
        spec.input = "sample:hammered";
        spec.out = (dir.path() / (preset + "-" + specular)).string();
        spec.preset = preset;
        spec.specular = specular;
        spec.materialClass = cls;
        auto job = resolveBakeJob(spec);
        EXPECT_TRUE(job) << job.error();
        auto done = runBakeJob(*job);
        EXPECT_TRUE(done) << done.error();
        return json::parse(*readFile(fs::path(spec.out) / "bake.json"));
    };
    // Iron in glTF: a metal whose F0 is the base colour, metallic stored as 1.
    const json iron = run("gltf", "iron", std::nullopt);
    EXPECT_EQ(iron["material"]["name"], "iron");
    EXPECT_EQ(iron["material"]["class"], "metal");
    EXPECT_EQ(iron["material"]["engine"]["convention"], "gltf");
    EXPECT_EQ(iron["material"]["engine"]["values"]["baseColorFactor"][0], iron["material"]["f0Linear"][0]);
    EXPECT_EQ(iron["parameters"]["metallic"], 1.0);
    // A custom dielectric in Unreal and Unity.
    const json unreal = run("unreal", "0.05,0.05,0.05", "dielectric");
    EXPECT_NEAR(unreal["material"]["engine"]["values"]["Specular"].get<double>(), 0.625, 1e-12);
    const json unity = run("unity", "0.05,0.05,0.05", "dielectric");
    EXPECT_EQ(unity["parameters"]["metallic"], 0.0);
    EXPECT_EQ(unity["material"]["engine"]["warnings"].size(), 1u);

    // Refusals name the option.
    BakeJobSpec spec;
    spec.input = "sample:hammered";
    spec.out = (dir.path() / "x").string();
    spec.preset = "gltf";
    spec.specular = "unobtainium";
    EXPECT_NE(resolveBakeJob(spec).error().find("--specular 'unobtainium'"), std::string::npos);
    spec.specular = "1.5,0,0";
    EXPECT_NE(resolveBakeJob(spec).error().find("[0, 1]"), std::string::npos);
    spec.specular = "iron";
    spec.materialClass = "dielectric";
    EXPECT_NE(resolveBakeJob(spec).error().find("--material-class"), std::string::npos);
    spec.specular = std::nullopt;
    EXPECT_FALSE(resolveBakeJob(spec));
    spec.specular = "0.04,0.04,0.04";
    spec.materialClass = "plastic";
    EXPECT_FALSE(resolveBakeJob(spec));
}

} // namespace
} // namespace burnish
