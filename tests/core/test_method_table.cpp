// The method table (methods.h): every method has one row, every texture role one row in role order,
// names round-trip, and what the bake, presets, evaluate and the shaders do agrees with the rows.
#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/eval/evaluate_report.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/sample_maps.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

using namespace burnish;

namespace {

std::string readSource(const std::string& relative) {
    std::ifstream in(std::filesystem::path(BURNISH_SOURCE_DIR) / relative);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

} // namespace

TEST(MethodTable, EveryMethodHasOneRowWithAUniqueNameThatRoundTrips) {
    std::set<std::string> names;
    for (Method m : allMethods()) {
        const MethodSpec& spec = methodSpec(m);
        EXPECT_EQ(spec.method, m);
        EXPECT_TRUE(names.insert(std::string(spec.name)).second) << spec.name;
        const auto parsed = methodFromName(spec.name);
        ASSERT_TRUE(parsed) << parsed.error();
        EXPECT_EQ(*parsed, m);
        EXPECT_FALSE(spec.description.empty());
        EXPECT_FALSE(spec.shader.empty());
        EXPECT_GT(spec.storage.textureFetches, 0);
        EXPECT_GT(spec.storage.bytesPerTexel, 0.0);
        // The row's storage is the method's with its default parameters.
        EXPECT_EQ(methodStorage(m, {}).textureFetches, spec.storage.textureFetches) << spec.name;
        EXPECT_EQ(methodStorage(m, {}).bytesPerTexel, spec.storage.bytesPerTexel) << spec.name;
        ASSERT_FALSE(spec.textures.empty());
        EXPECT_EQ(spec.textures.front().role, TextureRole::Normal) << spec.name;
    }
    EXPECT_EQ(names.size(), 9u);
    EXPECT_FALSE(methodFromName("lean2"));
}

TEST(MethodTable, TextureRowsAreInRoleOrderAndRoleNamesRoundTrip) {
    std::set<std::string> names;
    for (int r = 0; r < kTextureRoleCount; ++r) {
        const TextureRole role = TextureRole(r);
        EXPECT_EQ(textureSpec(role).role, role);
        const std::string_view name = roleName(role);
        EXPECT_TRUE(names.insert(std::string(name)).second) << name;
        ASSERT_TRUE(roleFromName(name));
        EXPECT_EQ(*roleFromName(name), role);
        EXPECT_FALSE(textureSpec(role).channels.empty());
    }
    EXPECT_FALSE(roleFromName("Normal"));
    EXPECT_FALSE(roleFromName(""));
}

TEST(MethodTable, ChannelDecodesFollowTheScales) {
    const ChannelScales scales{4.0, 0.5, 2.0};
    auto eq = [](ChannelDecodeRule r, double scale, double bias) {
        return r.scale == scale && r.bias == bias;
    };
    EXPECT_TRUE(eq(channelDecode(ChannelRange::Unit, scales), 1.0, 0.0));
    EXPECT_TRUE(eq(channelDecode(ChannelRange::Signed, scales), 2.0, -1.0));
    EXPECT_TRUE(eq(channelDecode(ChannelRange::Slope, scales), 8.0, -4.0));
    EXPECT_TRUE(eq(channelDecode(ChannelRange::Moment, scales), 0.5, 0.0));
    EXPECT_TRUE(eq(channelDecode(ChannelRange::SignedMoment, scales), 1.0, -0.5));
    EXPECT_TRUE(eq(channelDecode(ChannelRange::Variance, scales), 2.0, 0.0));
    // Every channel that flips with the green convention decodes symmetrically (bias = −scale/2).
    for (int r = 0; r < kTextureRoleCount; ++r)
        for (const ChannelSpec& c : textureSpec(TextureRole(r)).channels)
            if (c.flipsWithGreen) {
                const ChannelDecodeRule d = channelDecode(c.range, scales);
                EXPECT_EQ(d.bias, -0.5 * d.scale) << c.name;
            }
}

TEST(MethodTable, OnlyTheSlopeMethodsStoreSlopesAndHaveNoGlossTexture) {
    for (Method m : allMethods()) {
        const bool slope = m == Method::Lean || m == Method::Clean || m == Method::Mixture;
        EXPECT_EQ(storesSlopes(m), slope) << methodName(m);
        EXPECT_EQ(hasTexture(m, TextureRole::Gloss), !slope) << methodName(m);
        EXPECT_TRUE(hasTexture(m, TextureRole::Normal)) << methodName(m);
        EXPECT_EQ(methodSpec(m).unnormalizedNormal, m == Method::Toksvig) << methodName(m);
        EXPECT_EQ(methodSpec(m).adjustsGloss,
                  m == Method::VarianceToGloss || m == Method::Vmf || m == Method::Fitted)
            << methodName(m);
    }
}

TEST(MethodTable, TheBakeProducesExactlyTheRowsTextures) {
    const NormalMap map = makeSampleNormalMap(SampleMapKind::Bumpy, 16);
    for (Method m : allMethods()) {
        BakeOptions options;
        options.method = m;
        const auto out = bake(map, options);
        ASSERT_TRUE(out) << out.error();
        const MethodSpec& spec = methodSpec(m);
        // The row's textures this bake writes (the mixture's lobes up to its default count).
        std::vector<TextureRole> baked;
        for (const MethodTexture& t : spec.textures)
            if (bakesTexture(m, t.role, options.params)) baked.push_back(t.role);
        EXPECT_EQ(baked.size() == spec.textures.size(), m != Method::Mixture) << spec.name;
        ASSERT_EQ(out->textures.size(), baked.size()) << spec.name;
        for (size_t i = 0; i < baked.size(); ++i) {
            const BakedTexture& t = out->textures[i];
            const TextureSpec& row = textureSpec(baked[i]);
            EXPECT_EQ(t.role, row.role);
            EXPECT_EQ(t.needsHighPrecision, row.needsHighPrecision);
            ASSERT_EQ(t.decode.size(), row.channels.size());
            EXPECT_EQ(t.channels, int(row.channels.size()));
            for (size_t c = 0; c < row.channels.size(); ++c)
                EXPECT_EQ(t.decode[c].name, row.channels[c].name);
            EXPECT_EQ(t.description.find('{'), std::string::npos) << "placeholder left: " << t.description;
        }
    }
}

TEST(MethodTable, EachMethodsGlslMacroIsDefinedAsItsEnumValue) {
    const std::string methods = readSource("resources/shaders/methods.glsl");
    ASSERT_FALSE(methods.empty());
    for (Method m : allMethods()) {
        const std::string line =
            "#define " + std::string(methodSpec(m).glslMacro) + " " + std::to_string(int(m)) + "\n";
        EXPECT_NE(methods.find(line), std::string::npos) << line;
    }
}

TEST(MethodTable, SamplersAreDeclaredByTheShaders) {
    const std::string frag = readSource("resources/shaders/material.frag");
    const std::string methods = readSource("resources/shaders/methods.glsl");
    ASSERT_FALSE(frag.empty());
    ASSERT_FALSE(methods.empty());
    const std::string all = frag + methods;
    for (int r = 0; r < kTextureRoleCount; ++r) {
        const TextureSpec& row = textureSpec(TextureRole(r));
        if (!row.sampler.empty()) { // declared as a uniform ("uniform sampler2D <name>;") in a shader
            EXPECT_NE(all.find("uniform sampler2D " + std::string(row.sampler) + ";"), std::string::npos)
                << row.sampler;
        }
    }
}
