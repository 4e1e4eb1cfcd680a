// `burnish gltf`: a glTF 2.0 asset's normal-mapped materials baked (fitted roughness by default) and
// written back as glTF with KTX2 textures holding Burnish's own mip chains (core's jobs/gltf.h).
#include "command.h"
#include "common.h"

#include <burnish/core/jobs/gltf.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/shading/color.h>

#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

namespace burnish::cli {

namespace {

struct GltfCli {
    std::string normalMap; // --normal-map: a material of one map instead of an asset
    double roughness = 0.5;
    std::string specular = "0.04,0.04,0.04";
    std::string albedo = "0.5,0.5,0.5";
    bool dielectric = false;
    std::string name = "material";
    std::string input;
    std::string out;
    std::optional<std::string> method;
    std::string coding = "raw";
    std::string anisotropy = "off";
    int lobes = kDefaultMixtureLobes;
    bool force = false;
    bool allowImplausible = false;
    bool json = false;
};

int runGltf(const GltfCli& o) {
    if (o.input.empty() == o.normalMap.empty())
        return fail("give an input asset or --normal-map FILE (see 'burnish gltf --help')");
    if (o.out.empty()) return fail("no output folder given (--out DIR)");
    GltfOptions options;
    options.method = o.method;
    options.mixtureLobes = o.lobes;
    options.coding = o.coding == "bc" ? GltfTextureCoding::Bc : GltfTextureCoding::Raw;
    options.anisotropy = o.anisotropy == "on"     ? GltfAnisotropy::On
                         : o.anisotropy == "auto" ? GltfAnisotropy::Auto
                                                  : GltfAnisotropy::Off;
    options.overwrite = o.force ? Overwrite::Allow : Overwrite::Refuse;
    options.allowImplausible = o.allowImplausible;
    ProgressBar bar("gltf");
    options.progress = [&](double fraction, std::string_view stage) {
        bar.update(fraction, std::string(stage));
        return true;
    };
    Result<GltfResult> result = Error{""};
    if (!o.normalMap.empty()) {
        auto map = loadNormalMap(o.normalMap);
        if (!map) return fail(map.error());
        GltfMaterialSource m;
        m.name = o.name;
        m.normal = std::make_shared<const NormalMap>(std::move(map.value()));
        m.roughness = o.roughness;
        m.metal = !o.dielectric;
        const auto specular = parseLinearRgb(o.specular, "--specular");
        if (!specular) return fail(specular.error());
        const auto albedo = parseLinearRgb(o.albedo, "--albedo");
        if (!albedo) return fail(albedo.error());
        m.specular = {specular->r, specular->g, specular->b};
        m.albedo = {albedo->r, albedo->g, albedo->b};
        result = exportMaterialGltf(m, o.out, options);
    } else {
        result = processGltf(o.input, o.out, options);
    }
    bar.finish();
    if (!result) return fail(result.error());
    if (o.json) {
        std::puts(result->summary.dump(2).c_str());
        return 0;
    }
    if (result->materials.empty())
        std::printf("%s: no material has a normalTexture; copied unchanged to %s\n", o.input.c_str(),
                    result->asset.string().c_str());
    for (const GltfMaterialReport& m : result->materials) {
        std::printf("material %d '%s': %dx%d normal map, %d mips, border %s, scale %g, roughnessFactor %g%s: "
                    "mean roughness %.3f at mip 0, %.3f at 1x1\n",
                    m.index, m.name.c_str(), m.width, m.height, m.mipCount, m.border.c_str(), m.normalScale,
                    m.roughnessFactor, m.roughnessTexture ? " x texture" : "", m.meanRoughnessMip0,
                    m.meanRoughnessLast);
        if (!m.anisotropy.empty())
            std::printf("  anisotropy %s (relative L1 over mips 1-6: anisotropic %.4f, isotropic %.4f)\n",
                        m.anisotropy.c_str(), m.anisotropicError, m.isotropicError);
        if (!m.mixture.empty()) std::printf("  lobe mixture %s\n", m.mixture.c_str());
        for (const std::string& note : m.notes)
            std::printf("  note: %s\n", note.c_str());
    }
    std::printf("wrote %s (%zu files)\n", result->asset.string().c_str(), result->written.size());
    return 0;
}

const CommandRegistration registration{
    45, [](CLI::App& app) -> std::function<int()> {
        auto* cmd = app.add_subcommand(
            "gltf",
            "Bake a glTF 2.0 asset's normal-mapped materials into KTX2 textures with Burnish's own mips");
        auto o = std::make_shared<GltfCli>();
        cmd->add_option("input", o->input, "A glTF 2.0 asset: .gltf (with its files) or .glb");
        cmd->add_option("--normal-map", o->normalMap,
                        "Instead of an asset: a material of this normal map on a 2x2 quad, written as glTF");
        cmd->add_option("--roughness", o->roughness,
                        "With --normal-map: GGX perceptual roughness (default 0.5)");
        cmd->add_option("--specular", o->specular,
                        "With --normal-map: linear F0 r,g,b (a metal's base colour; a dielectric's "
                        "KHR_materials_specular colour at ior 1.5)");
        cmd->add_option("--albedo", o->albedo,
                        "With --normal-map and --dielectric: linear diffuse albedo r,g,b");
        cmd->add_flag("--dielectric", o->dielectric, "With --normal-map: a dielectric (default: a metal)");
        cmd->add_option("--name", o->name,
                        "With --normal-map: the material's name and the asset's file stem");
        cmd->add_option("--out", o->out,
                        "Output folder (created if missing): the asset, its KTX2 and PNG files");
        cmd->add_option(
            "--method", o->method,
            "Roughness method of the gltf preset (default fitted): naive, toksvig, vmf, "
            "variance-to-gloss, fitted, ...; or mixture: the fitted roughness and, beside it, the "
            "lobe mixture as BURNISH_lobe_mixture (RGBA16F KTX2 lobe textures that "
            "resources/three/burnish-mixture.js shades in three.js)");
        cmd->add_option("--lobes", o->lobes, "With --method mixture: lobes per texel, 1 to 4 (default 3)")
            ->check(CLI::Range(1, 4));
        cmd->add_option("--coding", o->coding,
                        "KTX2 payload: raw (default; normal RG8, metallicRoughness RGBA8) or bc (normal BC5, "
                        "metallicRoughness BC3, whose G has 6-bit endpoints)")
            ->check(CLI::IsMember({"raw", "bc"}));
        cmd->add_option(
               "--anisotropy", o->anisotropy,
               "KHR_materials_anisotropy from the anisotropic fit (method fitted, constant base roughness): "
               "off (default), auto (where it is closer to the truth than the isotropic fit, as the "
               "engines shade every texel with the extension on), on")
            ->check(CLI::IsMember({"off", "auto", "on"}));
        cmd->add_flag("--force", o->force, "Replace existing output files (still atomically, as a set)");
        cmd->add_flag("--allow-implausible", o->allowImplausible,
                      "Bake normal maps that do not look like tangent-space normal maps");
        cmd->add_flag("--json", o->json, "Print a machine-readable summary on stdout");
        cmd->footer(
            "Every material with a normalTexture gets a new normalTexture and metallicRoughnessTexture: the "
            "normal map baked with its UV set, scale and sampler wrap (repeat: wrap; clamp or mirrored: "
            "clamp), G = the baked GGX roughness with roughnessFactor and the material's roughness texture "
            "folded in (roughnessFactor becomes 1; R and B of its texture kept). Each is a KTX2 file with "
            "the whole mip chain to 1x1, referenced through the draft extension KHR_texture_ktx, and a PNG "
            "of mip 0 as the texture's source, which viewers without KTX2 support load instead. Everything "
            "else is carried over unchanged; external files are copied beside the output; a .glb stays a "
            ".glb. An asset without normal maps is copied unchanged (exit 0). With --method mixture a "
            "material "
            "of constant base roughness also gets BURNISH_lobe_mixture: K lobe textures (w, w*b.x, w*b.y, "
            "w*spread per texel, every mip) and the base roughness, which only a client with Burnish's "
            "three.js module reads; a material with a roughness texture gets the fitted lobe alone.");
        return [o]() { return runGltf(*o); };
    }};

} // namespace

} // namespace burnish::cli
