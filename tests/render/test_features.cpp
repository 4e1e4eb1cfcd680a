// Feature sets → defines → programs: a feature that is off leaves no define and no code (its
// uniforms and samplers are absent from the linked program); explain() reports what a program holds.
#include <burnish/render/context.h>
#include <burnish/render/features.h>
#include <burnish/render/program.h>
#include <burnish/render/shader_source.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

namespace {

using namespace burnish;
using namespace burnish::render;

std::unique_ptr<GlContext>& context() {
    static std::unique_ptr<GlContext> ctx;
    return ctx;
}

class FeaturesGl : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        auto created = createHeadlessContext();
        if (created)
            context() = std::move(created).value();
        else
            s_error = created.error();
    }
    static void TearDownTestSuite() {
        s_cache.reset();
        context().reset();
    }
    void SetUp() override {
        ASSERT_TRUE(context()) << "no headless OpenGL context: " << s_error;
        ASSERT_TRUE(context()->makeCurrent().ok());
        if (!s_cache) s_cache = std::make_unique<ProgramCache>();
    }

    const Program& material(const FeatureSet& f) {
        auto program = s_cache->get("material.vert", "material.frag", defines(f));
        EXPECT_TRUE(program.ok()) << program.error();
        if (!program) return s_empty;
        return **program;
    }

    static inline std::string s_error;
    static inline std::unique_ptr<ProgramCache> s_cache;
    static inline Program s_empty;
};

const std::string* defineValue(const ShaderDefines& defines, const std::string& name) {
    for (const auto& [n, v] : defines)
        if (n == name) return &v;
    return nullptr;
}

TEST(Features, DisabledFeaturesEmitNoDefine) {
    FeatureSet f;
    f.detailMap = false;
    f.environment = EnvironmentKind::Off;
    f.pointLights = 0;
    f.metalOnly = true;
    const ShaderDefines off = defines(f);
    EXPECT_EQ(defineValue(off, "HAS_DETAIL_MAP"), nullptr);
    EXPECT_EQ(defineValue(off, "HAS_AMBIENT"), nullptr);
    EXPECT_EQ(defineValue(off, "POINT_LIGHTS"), nullptr);
    EXPECT_EQ(defineValue(off, "HAS_DIFFUSE"), nullptr);
    EXPECT_EQ(defineValue(off, "REFERENCE_MODE"), nullptr);

    f.detailMap = true;
    f.environment = EnvironmentKind::ConstantAmbient;
    f.pointLights = 3;
    f.metalOnly = false;
    const ShaderDefines on = defines(f);
    ASSERT_NE(defineValue(on, "HAS_DETAIL_MAP"), nullptr);
    EXPECT_EQ(*defineValue(on, "HAS_DETAIL_MAP"), "1");
    ASSERT_NE(defineValue(on, "HAS_AMBIENT"), nullptr);
    ASSERT_NE(defineValue(on, "POINT_LIGHTS"), nullptr);
    EXPECT_EQ(*defineValue(on, "POINT_LIGHTS"), "3");
    ASSERT_NE(defineValue(on, "HAS_DIFFUSE"), nullptr);
}

TEST(Features, SwitchesNameTheChosenTerms) {
    FeatureSet f;
    f.method = Method::Lean;
    f.ndf = NdfTerm::Ggx;
    f.visibility = VisibilityTerm::SmithGgxCorrelated;
    const ShaderDefines d = defines(f);
    ASSERT_NE(defineValue(d, "METHOD"), nullptr);
    EXPECT_EQ(*defineValue(d, "METHOD"), "METHOD_LEAN");
    EXPECT_EQ(*defineValue(d, "NDF"), "NDF_GGX");
    EXPECT_EQ(*defineValue(d, "VISIBILITY"), "VISIBILITY_SMITH_GGX_CORRELATED");
    // The reference replaces the method by the finest normals and the base power.
    f.referenceMode = true;
    EXPECT_EQ(*defineValue(defines(f), "METHOD"), "METHOD_NAIVE");
    ASSERT_NE(defineValue(defines(f), "REFERENCE_MODE"), nullptr);
}

TEST(Features, AssembledSourceCarriesTheDefines) {
    FeatureSet f;
    f.detailMap = false;
    auto without = assembleShader("material.frag", defines(f));
    ASSERT_TRUE(without.ok()) << without.error();
    EXPECT_EQ(without->find("#define HAS_DETAIL_MAP"), std::string::npos);
    f.detailMap = true;
    auto with = assembleShader("material.frag", defines(f));
    ASSERT_TRUE(with.ok()) << with.error();
    EXPECT_NE(with->find("#define HAS_DETAIL_MAP 1"), std::string::npos);
}

TEST_F(FeaturesGl, DetailSamplerOnlyWithADetailMap) {
    FeatureSet f;
    f.detailMap = false;
    EXPECT_FALSE(material(f).hasUniform("uDetailMap"));
    f.detailMap = true;
    EXPECT_TRUE(material(f).hasUniform("uDetailMap"));
}

TEST_F(FeaturesGl, AmbientAndPointLightsOnlyWhenPresent) {
    FeatureSet f;
    EXPECT_FALSE(material(f).hasUniform("uAmbient"));
    EXPECT_FALSE(material(f).hasUniform("uPointLightPosition[0]"));
    f.environment = EnvironmentKind::ConstantAmbient;
    f.pointLights = 2;
    EXPECT_TRUE(material(f).hasUniform("uAmbient"));
    EXPECT_TRUE(material(f).hasUniform("uPointLightPosition[0]"));
}

TEST_F(FeaturesGl, MetalOnlyHasNoDiffuseAlbedo) {
    FeatureSet f;
    f.metalOnly = false;
    EXPECT_TRUE(material(f).hasUniform("uAlbedo"));
    f.metalOnly = true;
    EXPECT_FALSE(material(f).hasUniform("uAlbedo"));
}

TEST_F(FeaturesGl, EachMethodSamplesOnlyItsTextures) {
    FeatureSet f;
    f.method = Method::Naive;
    EXPECT_TRUE(material(f).hasUniform("uNormalMap"));
    EXPECT_FALSE(material(f).hasUniform("uGlossMap")); // constant base power: no gloss texture
    EXPECT_FALSE(material(f).hasUniform("uLeanB"));
    f.method = Method::ToksvigMap;
    EXPECT_TRUE(material(f).hasUniform("uToksvigMap"));
    f.method = Method::VarianceToGloss;
    EXPECT_TRUE(material(f).hasUniform("uGlossMap"));
    EXPECT_FALSE(material(f).hasUniform("uToksvigMap"));
    f.method = Method::Lean;
    EXPECT_TRUE(material(f).hasUniform("uLeanB"));
    EXPECT_TRUE(material(f).hasUniform("uLeanM"));
    EXPECT_FALSE(material(f).hasUniform("uNormalMap")); // LEAN's normal is the one of slope B
    f.method = Method::Clean;
    EXPECT_TRUE(material(f).hasUniform("uClean"));
    EXPECT_FALSE(material(f).hasUniform("uLeanM"));
    // A gloss map brings the gloss texture to the methods that otherwise use the base power.
    f.method = Method::Naive;
    f.glossMap = true;
    EXPECT_TRUE(material(f).hasUniform("uGlossMap"));
}

TEST_F(FeaturesGl, EveryTermAndViewCompiles) {
    FeatureSet base;
    base.environment = EnvironmentKind::ConstantAmbient;
    base.pointLights = 1;
    for (Method m : allMethods()) {
        FeatureSet f = base;
        f.method = m;
        f.detailMap = true;
        f.diffuseAa = true;
        EXPECT_TRUE(material(f).valid()) << methodName(m);
    }
    for (NdfTerm t : {NdfTerm::BlinnPhong, NdfTerm::Beckmann, NdfTerm::Ggx}) {
        FeatureSet f = base;
        f.ndf = t;
        EXPECT_TRUE(material(f).valid()) << ndfTermName(t);
    }
    for (FresnelTerm t :
         {FresnelTerm::None, FresnelTerm::Schlick, FresnelTerm::SchlickSg, FresnelTerm::SchlickSgQuadratic}) {
        FeatureSet f = base;
        f.fresnel = t;
        EXPECT_TRUE(material(f).valid()) << fresnelTermName(t);
    }
    for (VisibilityTerm t :
         {VisibilityTerm::None, VisibilityTerm::Kelemen, VisibilityTerm::SchlickSmith,
          VisibilityTerm::CookTorrance, VisibilityTerm::SmithBeckmann, VisibilityTerm::SmithGgxCorrelated}) {
        FeatureSet f = base;
        f.visibility = t;
        EXPECT_TRUE(material(f).valid()) << visibilityTermName(t);
    }
    for (SpecularAa aa : {SpecularAa::KaplanyanValient, SpecularAa::TokuyoshiKaplanyan}) {
        FeatureSet f = base;
        f.specularAa = aa;
        f.method = Method::Lean; // the slope methods take the AA as added variance
        EXPECT_TRUE(material(f).valid()) << specularAaName(aa);
    }
    for (DebugView v :
         {DebugView::LightingOnly, DebugView::DiffuseOnly, DebugView::SpecularOnly, DebugView::Power,
          DebugView::Normals, DebugView::MipLevel, DebugView::Variance, DebugView::ErrorHeatmap}) {
        FeatureSet f = base;
        f.debugView = v;
        EXPECT_TRUE(material(f).valid()) << debugViewName(v);
    }
    FeatureSet noMap = base;
    noMap.normalMap = false;
    EXPECT_TRUE(material(noMap).valid());
    EXPECT_FALSE(material(noMap).hasUniform("uNormalMap"));
}

TEST_F(FeaturesGl, UbershaderHoldsEveryFeature) {
    auto program = s_cache->get("material.vert", "material.frag", ubershaderDefines());
    ASSERT_TRUE(program.ok()) << program.error();
    for (const char* name : {"uDetailMap", "uLeanB", "uLeanM", "uClean", "uToksvigMap", "uGlossMap",
                             "uNormalMap", "uAlbedo", "uAmbient", "uMethod", "uHasDetailMap"})
        EXPECT_TRUE((*program)->hasUniform(name)) << name;
}

TEST_F(FeaturesGl, ExplainListsFeaturesDefinesAndActiveUniforms) {
    FeatureSet f;
    f.method = Method::Lean;
    f.detailMap = true;
    f.metalOnly = true;
    const std::string text = explain(f, material(f));
    EXPECT_NE(text.find("method: lean"), std::string::npos) << text;
    EXPECT_NE(text.find("detail map: yes"), std::string::npos) << text;
    EXPECT_NE(text.find("metal only: yes"), std::string::npos) << text;
    EXPECT_NE(text.find("METHOD METHOD_LEAN"), std::string::npos) << text;
    EXPECT_NE(text.find("HAS_DETAIL_MAP 1"), std::string::npos) << text;
    EXPECT_NE(text.find("sampler2D uDetailMap"), std::string::npos) << text;
    EXPECT_NE(text.find("sampler2D uLeanB"), std::string::npos) << text;
    // Queried from the program, not from the feature list: metal-only has no albedo uniform.
    EXPECT_EQ(text.find("uAlbedo"), std::string::npos) << text;
}

} // namespace
