// End-to-end: `burnish evaluate` on a small synthetic normal map.
#include "cli_run.h"
#include "temp_dir.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

namespace {

using burnish::test::lineCount;
using burnish::test::runBurnish;

// A 32×32 bumpy map written as 8-bit PNG.
std::string writeBumpyMap(const burnish::test::TempDir& dir) {
    std::mt19937 rng(4);
    std::normal_distribution<float> g(0.0f, 0.25f);
    std::vector<float> px;
    for (int i = 0; i < 32 * 32; ++i) {
        float x = g(rng), y = g(rng), z = 1.0f;
        const float len = std::sqrt(x * x + y * y + z * z);
        px.insert(px.end(), {x / len * 0.5f + 0.5f, y / len * 0.5f + 0.5f, z / len * 0.5f + 0.5f});
    }
    const auto path = (dir / "bumpy.png").string();
    auto out = OIIO::ImageOutput::create(path);
    OIIO::ImageSpec spec(32, 32, 3, OIIO::TypeDesc::UINT8);
    out->open(path, spec);
    out->write_image(OIIO::TypeDesc::FLOAT, px.data());
    out->close();
    return path;
}

} // namespace

TEST(CliEvaluate, WritesTheReportAndNaiveIsWorst) {
    burnish::test::TempDir dir;
    const std::string in = writeBumpyMap(dir);
    const auto out = dir / "report";
    auto r = runBurnish("evaluate " + in + " --out " + out.string() + " --error-maps --bake-runs 1 --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* f :
         {"evaluate.md", "evaluate.json", "evaluate-error-per-mip.png", "evaluate-error-vs-cost.png"})
        EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
    EXPECT_TRUE(std::filesystem::exists(out / "errors" / "lean-s512-mip4.exr"));
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["costs"].size(), 9u);
    EXPECT_EQ(j["errors"].size(), 9u * 4u); // 9 methods (the mixture at its default K) × mips 1..4
    double naive = 0, lean = 0;
    for (const auto& e : j["errors"]) {
        ASSERT_TRUE(e["relative_l1"].is_number()) << e.dump();
        if (e["mip"] == 4 && e["method"] == "naive") naive = e["relative_l1"];
        if (e["mip"] == 4 && e["method"] == "lean") lean = e["relative_l1"];
    }
    EXPECT_GT(naive, lean);
    std::ifstream md(out / "evaluate.md");
    std::stringstream ss;
    ss << md.rdbuf();
    EXPECT_EQ(ss.str().find("nan"), std::string::npos);
    EXPECT_NE(ss.str().find("| variance-to-gloss |"), std::string::npos);
}

// --json without --out writes nothing, so a script runs it again; an explicit --out keeps the report and
// its refusal to replace one.
TEST(CliEvaluate, JsonWithoutOutWritesNothingAndRunsTwice) {
    burnish::test::TempDir dir;
    const std::string in = writeBumpyMap(dir);
    const auto previous = std::filesystem::current_path();
    std::filesystem::current_path(dir.path());
    const std::string command = "evaluate " + in + " --methods naive,vmf --bake-runs 1 --json";
    const auto first = runBurnish(command);
    const auto second = runBurnish(command);
    const bool wroteDefault = std::filesystem::exists(dir.path() / "burnish-evaluate");
    const auto withOut = runBurnish(command + " --out " + (dir.path() / "r").string());
    const auto again = runBurnish(command + " --out " + (dir.path() / "r").string());
    std::filesystem::current_path(previous);
    ASSERT_EQ(first.exitCode, 0) << first.err;
    ASSERT_EQ(second.exitCode, 0) << second.err;
    EXPECT_EQ(nlohmann::json::parse(first.out)["errors"].size(),
              nlohmann::json::parse(second.out)["errors"].size());
    EXPECT_FALSE(wroteDefault);
    ASSERT_EQ(withOut.exitCode, 0) << withOut.err;
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "r" / "evaluate.json"));
    EXPECT_NE(again.exitCode, 0);
    EXPECT_NE(again.err.find("refusing to replace"), std::string::npos) << again.err;
}

TEST(CliEvaluate, BadInputGivesOneLine) {
    burnish::test::TempDir dir;
    auto missing = runBurnish("evaluate " + (dir / "missing.png").string());
    EXPECT_NE(missing.exitCode, 0);
    EXPECT_EQ(lineCount(missing.err), 1) << missing.err;
    EXPECT_EQ(missing.err.rfind("burnish: error:", 0), 0u) << missing.err;

    const std::string in = writeBumpyMap(dir);
    auto badMethod = runBurnish("evaluate " + in + " --methods naive,shiny --out " + (dir / "o").string());
    EXPECT_NE(badMethod.exitCode, 0);
    EXPECT_NE(badMethod.err.find("unknown method 'shiny'"), std::string::npos) << badMethod.err;
    EXPECT_EQ(lineCount(badMethod.err), 1);

    auto badMip = runBurnish("evaluate " + in + " --first-mip 9 --last-mip 9 --out " + (dir / "o").string());
    EXPECT_NE(badMip.exitCode, 0);
    EXPECT_EQ(lineCount(badMip.err), 1) << badMip.err;
}

namespace {

// A one-channel float EXR of `value` everywhere, 32×32 like the bumpy map.
std::string writeConstantGloss(const burnish::test::TempDir& dir, float value) {
    const auto path = (dir / "gloss.exr").string();
    std::vector<float> px(32 * 32, value);
    auto out = OIIO::ImageOutput::create(path);
    out->open(path, OIIO::ImageSpec(32, 32, 1, OIIO::TypeDesc::FLOAT));
    out->write_image(OIIO::TypeDesc::FLOAT, px.data());
    out->close();
    return path;
}

} // namespace

TEST(CliEvaluate, ConstantGlossMapEqualsItsPower) {
    burnish::test::TempDir dir;
    const std::string in = writeBumpyMap(dir);
    // exp2: n = exp2(10g + 1), so g = 0.5 is exactly 64, in float storage too.
    const std::string gloss = writeConstantGloss(dir, 0.5f);
    const std::string common =
        "evaluate " + in + " --bake-runs 1 --json --methods naive,variance-to-gloss,lean";
    auto withPower = runBurnish(common + " --power 64 --out " + (dir / "a").string());
    auto withGloss =
        runBurnish(common + " --gloss " + gloss + " --gloss-encoding exp2 --out " + (dir / "b").string());
    ASSERT_EQ(withPower.exitCode, 0) << withPower.err;
    ASSERT_EQ(withGloss.exitCode, 0) << withGloss.err;
    const auto a = nlohmann::json::parse(withPower.out);
    const auto b = nlohmann::json::parse(withGloss.out);
    EXPECT_EQ(b["base_powers"][0], 64.0);
    ASSERT_EQ(a["errors"].size(), b["errors"].size());
    // Per-texel sums of identical powers: the same numbers up to double rounding of the mean 1/s.
    constexpr double kSameNumbers = 1e-12;
    for (size_t i = 0; i < a["errors"].size(); ++i) {
        EXPECT_EQ(a["errors"][i]["method"], b["errors"][i]["method"]);
        EXPECT_NEAR(a["errors"][i]["relative_l1"].get<double>(), b["errors"][i]["relative_l1"].get<double>(),
                    kSameNumbers)
            << a["errors"][i].dump();
        EXPECT_NEAR(a["errors"][i]["energy_ratio"].get<double>(),
                    b["errors"][i]["energy_ratio"].get<double>(), kSameNumbers)
            << a["errors"][i].dump();
    }
    EXPECT_TRUE(b.contains("authored_gloss"));
    EXPECT_FALSE(a.contains("authored_gloss"));

    auto both = runBurnish(common + " --power 64 --gloss " + gloss + " --out " + (dir / "c").string());
    EXPECT_NE(both.exitCode, 0);
    EXPECT_EQ(lineCount(both.err), 1) << both.err;
    EXPECT_NE(both.err.find("--power or --gloss"), std::string::npos) << both.err;
}

TEST(CliEvaluate, MixtureFilteringStochasticIsRecordedAndChangesOnlyTheMixtureBetweenTexels) {
    burnish::test::TempDir dir;
    const std::string in = writeBumpyMap(dir);
    auto run = [&](const std::string& filtering) {
        auto r = runBurnish(
            "evaluate " + in + " --out " + (dir / filtering).string() +
            " --methods lean,mixture --between-texels --bake-runs 1 --json --mixture-filtering " + filtering);
        EXPECT_EQ(r.exitCode, 0) << r.err;
        return nlohmann::json::parse(r.out);
    };
    const auto moments = run("moments"), stochastic = run("stochastic");
    EXPECT_EQ(moments["mixture_filtering"], "moments");
    EXPECT_EQ(stochastic["mixture_filtering"], "stochastic");
    ASSERT_EQ(moments["errors"].size(), stochastic["errors"].size());
    int changed = 0;
    for (size_t i = 0; i < moments["errors"].size(); ++i) {
        const auto &a = moments["errors"][i], &b = stochastic["errors"][i];
        const bool mixtureBetween = a["method"] == "mixture" && a["between_texels"] == true;
        if (mixtureBetween)
            changed += a["relative_l1"] != b["relative_l1"];
        else
            EXPECT_EQ(a["relative_l1"], b["relative_l1"]) << a.dump();
    }
    EXPECT_GT(changed, 0);
    std::ifstream md(dir / "stochastic" / "evaluate.md");
    std::stringstream ss;
    ss << md.rdbuf();
    EXPECT_NE(ss.str().find("filtered after shading"), std::string::npos);
    auto bad =
        runBurnish("evaluate " + in + " --out " + (dir / "bad").string() + " --mixture-filtering bilinear");
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.err.find("--mixture-filtering"), std::string::npos) << bad.err;
}

TEST(CliEvaluate, EnergySplitSaysWhereLeansEnergyGoes) {
    burnish::test::TempDir dir;
    const std::string in = writeBumpyMap(dir);
    const std::string common =
        "evaluate " + in + " --bake-runs 1 --power 256 --methods lean,mixture --energy-split";
    auto r = runBurnish(common + " --steep-deg 20 --json --out " + (dir / "a").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["steep_deg"], 20.0);
    ASSERT_EQ(j["lean_energy_split"].size(), 4u); // mips 1..4
    for (const auto& e : j["lean_energy_split"]) {
        for (const char* key : {"energy", "cosine", "shape", "steep", "steep_normals", "steep_truth"})
            ASSERT_TRUE(e[key].is_number()) << e.dump();
        const double product =
            e["cosine"].get<double>() * e["shape"].get<double>() * e["steep"].get<double>();
        EXPECT_NEAR(product, e["energy"].get<double>(), 1e-12) << e.dump();
        // With σ = 0.25 slopes, about 1 normal in 4 tilts past 20°.
        EXPECT_GT(e["steep_normals"].get<double>(), 0.1);
        EXPECT_LT(e["steep_normals"].get<double>(), 0.5);
    }
    std::ifstream md(dir / "a" / "evaluate.md");
    std::stringstream ss;
    ss << md.rdbuf();
    EXPECT_NE(ss.str().find("Where LEAN's energy goes"), std::string::npos);
    EXPECT_NE(ss.str().find("| mixture-k3 energy |"), std::string::npos);

    const std::string gloss = writeConstantGloss(dir, 0.5f);
    auto withGloss = runBurnish("evaluate " + in + " --bake-runs 1 --methods lean --energy-split --gloss " +
                                gloss + " --out " + (dir / "b").string());
    EXPECT_NE(withGloss.exitCode, 0);
    EXPECT_EQ(lineCount(withGloss.err), 1) << withGloss.err;
    EXPECT_NE(withGloss.err.find("authored gloss"), std::string::npos) << withGloss.err;
    auto badAngle = runBurnish(common + " --steep-deg 90 --out " + (dir / "c").string());
    EXPECT_NE(badAngle.exitCode, 0);
    EXPECT_NE(badAngle.err.find("--steep-deg"), std::string::npos) << badAngle.err;
}

TEST(CliEvaluate, GgxTruthWithTheFloorAndThePresetsBrdf) {
    burnish::test::TempDir dir;
    const std::string in = writeBumpyMap(dir);
    // --preset gltf takes the GGX truth: only the methods with a GGX form, the fitted lobe among them and
    // the mixture as an engine shades its lobes, and the floor beside it, which the fit reaches to 2 %.
    auto r = runBurnish("evaluate " + in + " --preset gltf --floor --power 256 --bake-runs 1 --json --out " +
                        (dir / "g").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["brdf"], "ggx");
    std::map<std::string, std::map<int, double>> rows;
    for (const auto& e : j["errors"])
        rows[e["variant"].get<std::string>()][e["mip"].get<int>()] = e["relative_l1"].get<double>();
    EXPECT_FALSE(rows.count("lean"));
    EXPECT_FALSE(rows.count("clean"));
    ASSERT_TRUE(rows.count("mixture-k3"));
    // Its cost row is what burnish gltf --method mixture stores: the normal and three RGBA16F lobe textures.
    for (const auto& c : j["costs"])
        if (c["variant"] == "mixture-k3") {
            EXPECT_EQ(c["texture_fetches"], 4);
            EXPECT_EQ(c["bytes_per_texel"], 25.0);
            EXPECT_NE(c["storage"].get<std::string>().find("3 lobes (w, w.b, w.S) RGBA16F"),
                      std::string::npos);
        }
    ASSERT_TRUE(rows.count("fitted") && rows.count("one-lobe floor") && rows.count("naive") &&
                rows.count("vmf"));
    for (const auto& [mip, fitted] : rows["fitted"]) {
        EXPECT_LE(fitted, rows["naive"][mip] + 1e-12) << mip;
        EXPECT_LE(fitted, rows["vmf"][mip] + 1e-12) << mip;
        EXPECT_LE(fitted, 1.02 * rows["one-lobe floor"][mip]) << mip;
    }
    // Blinn-Phong without a preset; --brdf overrides the preset's.
    r = runBurnish("evaluate " + in +
                   " --preset gltf --brdf blinn-phong --methods lean --bake-runs 1 --json --out " +
                   (dir / "b").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["brdf"], "blinn-phong");
    EXPECT_EQ(nlohmann::json::parse(r.out)["truth_normals"], "texels");
    // GGX sees the finest normals as the engine magnifies them, unless told texels; the naive row (no
    // fit) differs between the two truths, and the report says which it used.
    EXPECT_EQ(j["truth_normals"], "bilinear");
    r = runBurnish("evaluate " + in +
                   " --preset gltf --truth-normals texels --power 256 --bake-runs 1 --json --out " +
                   (dir / "t").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto texels = nlohmann::json::parse(r.out);
    EXPECT_EQ(texels["truth_normals"], "texels");
    for (const auto& e : texels["errors"])
        if (e["variant"] == "naive")
            EXPECT_NE(e["relative_l1"].get<double>(), rows["naive"][e["mip"].get<int>()]);
    // The anisotropic fit's row beside the isotropic one; Blinn-Phong has none (one line, nothing written).
    r = runBurnish("evaluate " + in +
                   " --preset gltf --anisotropic --methods fitted --bake-runs 1 --json --out " +
                   (dir / "a").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    bool anisotropicRow = false;
    const auto withAnisotropic = nlohmann::json::parse(r.out);
    for (const auto& e : withAnisotropic["errors"])
        anisotropicRow |= e["variant"] == "fitted anisotropic" && e["relative_l1"].get<double>() >= 0.0;
    EXPECT_TRUE(anisotropicRow);
    // Whether the extension pays, from the same rows: the means over the (power, mip) cases.
    const auto& verdict = withAnisotropic["anisotropic_verdict"];
    ASSERT_TRUE(verdict.is_object()) << r.out.substr(0, 400);
    double fittedSum = 0.0, anisotropicSum = 0.0;
    int cases = 0;
    for (const auto& e : withAnisotropic["errors"])
        if (!e["between_texels"].get<bool>()) {
            if (e["variant"] == "fitted") fittedSum += e["relative_l1"].get<double>(), ++cases;
            if (e["variant"] == "fitted anisotropic") anisotropicSum += e["relative_l1"].get<double>();
        }
    EXPECT_EQ(verdict["cases"].get<int>(), cases);
    EXPECT_NEAR(verdict["fitted_mean"].get<double>(), fittedSum / cases, 1e-12);
    EXPECT_NEAR(verdict["anisotropic_mean"].get<double>(), anisotropicSum / cases, 1e-12);
    EXPECT_EQ(verdict["anisotropic_better"].get<bool>(), anisotropicSum < fittedSum);
    r = runBurnish("evaluate " + in + " --brdf blinn-phong --anisotropic --out " + (dir / "ab").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(lineCount(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("GGX"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "ab" / "evaluate.json"));
    r = runBurnish("evaluate " + in + " --truth-normals bicubic --out " + (dir / "x").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("--truth-normals"), std::string::npos) << r.err;
    // A slope-space method has no GGX form: one line, nothing written.
    r = runBurnish("evaluate " + in + " --brdf ggx --methods lean --out " + (dir / "l").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("no GGX form"), std::string::npos) << r.err;
    EXPECT_EQ(lineCount(r.err), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "l" / "evaluate.json"));
    r = runBurnish("evaluate " + in + " --brdf phong --out " + (dir / "p").string());
    EXPECT_NE(r.exitCode, 0);
}
