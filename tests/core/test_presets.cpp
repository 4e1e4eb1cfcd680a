// Engine presets: the embedded set loads and validates, broken preset files give one clear line,
// and method compatibility is derived from what each method bakes.
#include <burnish/core/bake/presets.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace burnish {
namespace {

namespace fs = std::filesystem;

// A valid preset to break one field at a time.
const std::string kGood = R"({
  "schema": "burnish-preset", "version": 1, "name": "test", "title": "T", "description": "D",
  "conversion": "p = 8192^g", "gloss": "blackops", "method": "variance-to-gloss", "green": "opengl",
  "format": "png8",
  "parameters": [{"name": "metallic", "description": "m", "default": 0.0, "min": 0.0, "max": 1.0}],
  "files": [
    {"name": "normal", "dds": "bc5", "channels": [
      {"role": "normal", "channel": "normal.x"}, {"role": "normal", "channel": "normal.y"},
      {"role": "normal", "channel": "normal.z"}]},
    {"name": "gloss", "dds": "bc3", "channels": [
      {"parameter": "metallic"}, {"role": "gloss", "channel": "gloss"}, {"constant": 0.5}]}
  ]
})";

std::string replaced(std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

TEST(Presets, BuiltinsLoadAndValidate) {
    EXPECT_TRUE(builtinPresetErrors().empty()) << builtinPresetErrors().front();
    const std::set<std::string> expected{"blackops", "exp2",        "gltf", "unreal", "unity",  "godot",
                                         "filament", "toksvig-map", "lean", "clean",  "mixture"};
    const auto names = builtinPresetNames();
    EXPECT_EQ(std::set<std::string>(names.begin(), names.end()), expected);
    for (const auto& p : builtinPresets()) {
        EXPECT_EQ(p.origin, "built-in");
        EXPECT_FALSE(p.conversion.empty()) << p.name;
        EXPECT_TRUE(checkPresetMethod(p, p.method)) << p.name;
    }
}

TEST(Presets, BuiltinsCarryTheDocumentedChoices) {
    auto get = [](const char* name) { return findPreset(name).value(); };
    EXPECT_EQ(get("blackops").encoding.name(), "blackops");
    EXPECT_EQ(get("blackops").method, Method::VarianceToGloss);
    EXPECT_EQ(get("exp2").encoding.name(), "exp2");
    // exp2: the gloss in the normal map's alpha, one BC3 file.
    const Preset exp2 = get("exp2");
    ASSERT_EQ(exp2.files.size(), 1u);
    ASSERT_EQ(exp2.files[0].channels.size(), 4u);
    EXPECT_EQ(exp2.files[0].channels[3].role, "gloss");
    EXPECT_EQ(exp2.files[0].dds, DdsCompression::Bc3);
    EXPECT_EQ(exp2.format, ExportFormat::Dds);
    // glTF: R = 1, G = roughness, B = metallic.
    const Preset gltf = get("gltf");
    EXPECT_EQ(gltf.encoding.name(), "ggx-roughness");
    const auto& mr = gltf.files[1].channels;
    ASSERT_EQ(mr.size(), 3u);
    EXPECT_EQ(mr[0].kind, PresetChannel::Kind::Constant);
    EXPECT_EQ(mr[0].constant, 1.0);
    EXPECT_EQ(mr[1].role, "gloss");
    EXPECT_EQ(mr[2].parameter, "metallic");
    EXPECT_EQ(gltf.green, GreenConvention::OpenGL);
    EXPECT_EQ(get("unreal").green, GreenConvention::DirectX);
    // Unity: smoothness in A of the metallic texture, R = metallic.
    const Preset unity = get("unity");
    EXPECT_EQ(unity.encoding.name(), "smoothness");
    EXPECT_EQ(unity.files[1].channels[0].parameter, "metallic");
    EXPECT_EQ(unity.files[1].channels[3].role, "gloss");
    EXPECT_EQ(get("godot").encoding.name(), "ggx-roughness");
    EXPECT_EQ(get("filament").method, Method::Fitted);
    EXPECT_EQ(get("lean").method, Method::Lean);
    EXPECT_FALSE(exportFormatIsEightBit(get("lean").format));
    EXPECT_EQ(get("clean").method, Method::Clean);
    EXPECT_FALSE(exportFormatIsEightBit(get("clean").format));
}

TEST(Presets, EveryPresetFileIsEmbedded) {
    const fs::path dir = fs::path(BURNISH_SOURCE_DIR) / "resources" / "presets";
    const auto names = builtinPresetNames();
    int files = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        if (entry.path().extension() != ".json") continue;
        ++files;
        const auto loaded = loadPresetFile(entry.path());
        ASSERT_TRUE(loaded) << loaded.error();
        EXPECT_EQ(loaded->name, entry.path().stem().string());
        EXPECT_NE(std::find(names.begin(), names.end(), loaded->name), names.end())
            << entry.path() << " is not embedded (core/CMakeLists.txt and presets.cpp list the built-ins)";
        const auto builtin = findPreset(loaded->name);
        ASSERT_TRUE(builtin);
        EXPECT_EQ(builtin->files.size(), loaded->files.size());
    }
    EXPECT_EQ(size_t(files), names.size());
}

TEST(Presets, ValidPresetParses) {
    const auto p = parsePreset(kGood, "'good.json'");
    ASSERT_TRUE(p) << p.error();
    EXPECT_EQ(p->files.size(), 2u);
    EXPECT_EQ(p->files[1].channels[2].constant, 0.5);
    EXPECT_EQ(p->parameters.at(0).name, "metallic");
}

TEST(Presets, BrokenPresetsGiveOneClearLine) {
    struct Case {
        std::string json;
        std::string expected;
    };
    const std::vector<Case> cases{
        {"{ \"schema\": ", "invalid JSON"},
        // A number beyond a double (found by fuzz_preset): an error, not an escaping exception.
        {replaced(kGood, "{\"constant\": 0.5}", "{\"constant\": 6e666}"), "invalid JSON"},
        {"[1, 2]", "top level must be a JSON object"},
        {replaced(kGood, "\"version\": 1", "\"version\": 2"), "version 2 is newer"},
        {replaced(kGood, "\"version\": 1", "\"version\": 1, \"colour\": 3"), "unknown field 'colour'"},
        {replaced(kGood, "\"title\": \"T\", ", ""), "missing field 'title'"},
        {replaced(kGood, "\"variance-to-gloss\"", "\"magic\""), "unknown method 'magic'"},
        {replaced(kGood, "\"gloss\": \"blackops\"", "\"gloss\": \"shiny\""),
         "unknown gloss encoding 'shiny'"},
        {replaced(kGood, "\"png8\"", "\"jpeg\""), "unknown format 'jpeg'"},
        {replaced(kGood, "\"bc5\"", "\"bc7\""), "unknown DDS compression 'bc7'"},
        {replaced(kGood, "\"green\": \"opengl\"", "\"green\": \"up\""), "'green'"},
        {replaced(kGood, "{\"constant\": 0.5}", "{\"constant\": 1.5}"), "must lie in [0, 1]"},
        {replaced(kGood, "{\"constant\": 0.5}",
                  "{\"constant\": 0.5}, {\"constant\": 0.5}, {\"constant\": 0.5}"),
         "1 to 4 channels"},
        {replaced(kGood, "\"bc3\"", "\"bc4\""), "bc4 holds exactly one channel"},
        {replaced(kGood, "{\"parameter\": \"metallic\"}", "{\"parameter\": \"shine\"}"),
         "unknown parameter 'shine'"},
        {replaced(kGood, "\"name\": \"gloss\"", "\"name\": \"normal\""), "duplicate file name 'normal'"},
        {replaced(kGood, "\"name\": \"gloss\"", "\"name\": \"../gloss\""), "must be 1-64 letters"},
        {replaced(kGood, "\"channel\": \"gloss\"", "\"channel\": \"gloss.x\""), "has no channel 'gloss.x'"},
        {replaced(kGood, "{\"role\": \"gloss\", \"channel\": \"gloss\"}",
                  "{\"role\": \"lean-b\", \"channel\": \"B.x\"}"),
         "cannot store method variance-to-gloss"},
        {replaced(kGood, "{\"constant\": 0.5}", "{\"constant\": 0.5, \"parameter\": \"metallic\"}"),
         "exactly one of"},
        {replaced(kGood, "\"default\": 0.0", "\"default\": 2.0"), "'default' must lie in [min, max]"},
    };
    for (const auto& c : cases) {
        const auto p = parsePreset(c.json, "'broken.json'");
        ASSERT_FALSE(p) << "accepted a preset that should fail with: " << c.expected;
        EXPECT_NE(p.error().find(c.expected), std::string::npos) << p.error();
        EXPECT_NE(p.error().find("'broken.json'"), std::string::npos)
            << "error does not name the file: " << p.error();
        EXPECT_EQ(p.error().find('\n'), std::string::npos) << "error is not one line: " << p.error();
    }
}

TEST(Presets, UnknownPresetListsTheKnownOnes) {
    const auto p = findPreset("crysis");
    ASSERT_FALSE(p);
    EXPECT_NE(p.error().find("unknown preset 'crysis'"), std::string::npos);
    for (const auto& name : builtinPresetNames())
        EXPECT_NE(p.error().find(name), std::string::npos) << name;
}

TEST(Presets, MissingPresetFileIsAClearError) {
    const auto p = findPreset("/nonexistent/folder/preset.json");
    ASSERT_FALSE(p);
    EXPECT_NE(p.error().find("/nonexistent/folder/preset.json"), std::string::npos) << p.error();
}

TEST(Presets, MethodCompatibilityFollowsTheBakedRoles) {
    const Preset lean = findPreset("lean").value();
    EXPECT_EQ(compatibleMethods(lean), std::vector<Method>{Method::Lean});
    const Status vmf = checkPresetMethod(lean, Method::Vmf);
    ASSERT_FALSE(vmf);
    EXPECT_NE(vmf.error().find("methods that fit: lean"), std::string::npos) << vmf.error();

    const Preset gltf = findPreset("gltf").value();
    const auto fits = compatibleMethods(gltf);
    for (Method m : {Method::Naive, Method::Toksvig, Method::VarianceToGloss, Method::Vmf})
        EXPECT_NE(std::find(fits.begin(), fits.end(), m), fits.end()) << methodName(m);
    // toksvig-map bakes a Toksvig texture no gloss preset stores: refused rather than dropped.
    const Status toksvigMap = checkPresetMethod(gltf, Method::ToksvigMap);
    ASSERT_FALSE(toksvigMap);
    EXPECT_NE(toksvigMap.error().find("'toksvig'"), std::string::npos) << toksvigMap.error();
    EXPECT_FALSE(checkPresetMethod(gltf, Method::Lean));
}

TEST(Presets, MethodChannelsComeFromTheMethodTable) {
    // A channel the method's row does not list is refused, naming the ones it has; a role the row
    // lists but the preset drops is refused too.
    Preset lean = findPreset("lean").value();
    ASSERT_TRUE(checkPresetMethod(lean, Method::Lean));
    Preset renamed = lean;
    bool changed = false;
    for (auto& file : renamed.files)
        for (auto& ch : file.channels)
            if (ch.role == "lean-m" && ch.channel == "M.yy") ch.channel = "M.zz", changed = true;
    ASSERT_TRUE(changed);
    const Status bad = checkPresetMethod(renamed, Method::Lean);
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().find("has no channel 'M.zz' (it has M.xx, M.yy, M.xy)"), std::string::npos)
        << bad.error();
    Preset dropped = lean;
    std::erase_if(dropped.files, [](const PresetFile& f) {
        return std::any_of(f.channels.begin(), f.channels.end(),
                           [](const auto& c) { return c.role == "lean-m"; });
    });
    const Status missing = checkPresetMethod(dropped, Method::Lean);
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().find("stores none of its 'lean-m' texture"), std::string::npos)
        << missing.error();
}

TEST(Presets, FormatAndCompressionNames) {
    for (ExportFormat f : allExportFormats())
        EXPECT_EQ(exportFormatFromName(exportFormatName(f)).value(), f);
    for (DdsCompression c : allDdsCompressions())
        EXPECT_EQ(ddsCompressionFromName(ddsCompressionName(c)).value(), c);
    const auto bad = exportFormatFromName("webp");
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().find("exr-half"), std::string::npos);
    EXPECT_TRUE(exportFormatIsEightBit(ExportFormat::Png8));
    EXPECT_TRUE(exportFormatIsEightBit(ExportFormat::Dds));
    EXPECT_FALSE(exportFormatIsEightBit(ExportFormat::Png16));
}

} // namespace
} // namespace burnish
