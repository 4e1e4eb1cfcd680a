// A glTF 2.0 asset (.gltf with its files, or .glb) through Burnish: every material with a
// normalTexture is baked from that normal map (its UV set, its `scale`, its sampler's wrap mode as the
// border) with the gltf preset's method, and gets
//   - a new normalTexture: the baked mean normals, and
//   - a new metallicRoughnessTexture whose G at every mip is the baked GGX perceptual roughness,
//     with the material's roughnessFactor and roughness texture folded in (roughnessFactor becomes 1;
//     R and B of its own texture kept, box-filtered per mip; 1 where it had none),
// each as a KTX 2.0 file holding Burnish's whole mip chain to 1×1 (io/ktx2.h), referenced through the
// draft extension KHR_texture_ktx, with a PNG of mip 0 as the texture's `source` so every viewer that
// does not read KTX2 still loads the asset. Everything else — meshes, nodes, animations, other
// materials and textures, extras, unknown extensions — is carried over unchanged; external files are
// copied beside the output. A .glb comes out as a .glb with every new image in its binary chunk.
// The output folder gets one set (util/files.h's FileSet): the asset file is renamed last, and files
// beside it that the asset it replaces named and this one does not are removed.
#pragma once

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/normal_map.h>
#include <burnish/core/prefilter/normal_pyramid.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/result.h>

#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish {

/// How the KTX2 files store their texels.
enum class GltfTextureCoding {
    Raw, // normals RG8 (z rebuilt by the client), metallicRoughness RGBA8
    Bc,  // normals BC5, metallicRoughness BC3 (its G through 6-bit colour endpoints)
};

/// Whether a material gets KHR_materials_anisotropy from the anisotropic fit (method fitted, a constant
/// base roughness): Auto where the fit, as the engines shade every texel with the extension on, is
/// closer to the truth than the isotropic fit over levels 1-6; On always; Off never.
enum class GltfAnisotropy { Off, Auto, On };

/// The name of the draft extension that points a texture at a KTX2 image of any payload.
inline constexpr std::string_view kKhrTextureKtx = "KHR_texture_ktx";

/// Burnish's material extension for the lobe mixture (method "mixture"): {"lobes": K, "roughnessFactor":
/// the base perceptual roughness the lobes widen, "spreadScale": mixtureGgxLobe's c, "lobeTextures": K
/// textureInfos, each an RGBA16F KTX2 chain of mixtureGgxTexel's (w, w·b.x, w·b.y, w·(tr M − 2v)) in the
/// normal texture's UV set and transform}. resources/three/burnish-mixture.js shades it in three.js;
/// other clients ignore it and read the fitted lobe's roughness written beside it.
inline constexpr std::string_view kBurnishLobeMixture = "BURNISH_lobe_mixture";

struct GltfOptions {
    /// A method the gltf preset stores (normal + one roughness channel); the preset's default when unset.
    /// "mixture": the fitted lobe as that, and BURNISH_lobe_mixture beside it (a constant base roughness).
    std::optional<std::string> method;
    /// The mixture's lobes per texel (1..kMaxMixtureLobes), for method "mixture".
    int mixtureLobes = kDefaultMixtureLobes;
    GltfTextureCoding coding = GltfTextureCoding::Raw;
    GltfAnisotropy anisotropy = GltfAnisotropy::Off;
    Overwrite overwrite = Overwrite::Refuse;
    bool allowImplausible = false;
    /// Removes the textures Burnish's replaced (a material's old normal and roughness textures) when no
    /// textureInfo names them any more, and the images then no texture reads, renumbering the rest. For
    /// sources Burnish wrote itself (exportMaterialGltf): an asset of others may name textures or images
    /// in ways this does not know (every key ending in "Texture" with an "index" counts as a use).
    bool pruneReplaced = false;
    /// Called with the fraction done and the stage ("reading", "baking <material>", "writing");
    /// returning false cancels before the next stage ("cancelled", nothing written).
    std::function<bool(double fraction, std::string_view stage)> progress;
};

/// What happened to one material with a normal map.
struct GltfMaterialReport {
    int index = 0;
    std::string name;
    int width = 0, height = 0; // the normal map's
    int mipCount = 0;
    std::string border;             // "wrap" or "clamp"
    double normalScale = 1.0;       // the normalTexture's scale baked in
    double roughnessFactor = 1.0;   // the factor folded in
    bool roughnessTexture = false;  // a roughness texture folded in
    double meanRoughnessMip0 = 0.0; // mean stored roughness of the finest level
    double meanRoughnessLast = 0.0; // ... and of the 1×1 level
    /// "on", or "off: " and why; empty when not asked (GltfAnisotropy::Off, or a method other than fitted).
    std::string anisotropy;
    /// "on, K lobes", or "off: " and why; empty unless method "mixture" was asked.
    std::string mixture;
    /// The isotropic and anisotropic fits' mean relative L1 over levels 1-6 (when the anisotropy was fitted).
    double isotropicError = 0.0, anisotropicError = 0.0;
    std::vector<std::string> files; // files written for it (empty inside a .glb)
    std::vector<std::string> notes; // what the reader should know (a mirrored wrap baked as clamp, ...)
};

struct GltfResult {
    std::filesystem::path asset; // the written .gltf or .glb
    std::vector<GltfMaterialReport> materials;
    std::vector<std::string> copied;  // external files carried over, as written
    std::vector<std::string> written; // every file written, names in the output folder
    nlohmann::json summary;           // all of the above as JSON (`burnish gltf --json`)
};

/// Processes `input` into the folder `outDir` (created when missing). An asset without any normal
/// map is copied unchanged, its report holding no materials. Errors, one line each, and nothing
/// written: not JSON or not glTF 2.0, a broken GLB container, a missing or unreadable image or buffer,
/// a URI outside the asset's folder or of a scheme other than data:, a data URI or buffer shorter than
/// its byteLength says, a bufferView past its buffer, a normal map on a UV set a mesh using
/// the material lacks, a roughness texture on another UV set or transform than the normal map, an
/// implausible normal map (unless allowImplausible), existing output files (unless Overwrite::Allow),
/// "cancelled".
Result<GltfResult> processGltf(const std::filesystem::path& input, const std::filesystem::path& outDir,
                               const GltfOptions& options = {});

/// One material as the studio holds it, for exportMaterialGltf.
struct GltfMaterialSource {
    std::string name = "material"; // the asset's file stem and the material's name
    std::shared_ptr<const NormalMap> normal;
    /// GGX perceptual roughness: one value, or one per texel of the normal map (painted layers).
    double roughness = 0.5;
    std::shared_ptr<const std::vector<float>> roughnessTexels;
    bool metal = true;
    /// Linear F0 (the specular colour) and linear diffuse albedo (dielectrics).
    std::array<double, 3> specular{0.04, 0.04, 0.04};
    std::array<double, 3> albedo{0.5, 0.5, 0.5};
    BorderMode border = BorderMode::Wrap;
};

/// The material on a 2×2 quad (positions, normals, UVs, tangents) as a glTF asset, baked as processGltf
/// bakes one: a metal's specular colour is its baseColorFactor (metallicFactor 1); a dielectric's is
/// KHR_materials_specular's specularColorFactor = F0 / 0.04 at KHR_materials_ior's ior 1.5 (so
/// ((ior − 1)/(ior + 1))² · specularColorFactor = F0), its albedo the baseColorFactor (metallicFactor 0).
/// The source asset (16-bit PNG normal and roughness textures) is made in a private temporary folder.
/// Errors: no normal map, roughness texels of the wrong count or not finite, a roughness or colour
/// outside [0, 1] (a dielectric F0 up to 1 too), and processGltf's.
Result<GltfResult> exportMaterialGltf(const GltfMaterialSource& material, const std::filesystem::path& outDir,
                                      const GltfOptions& options = {});

} // namespace burnish
