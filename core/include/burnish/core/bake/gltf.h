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
// The output folder gets one set (util/files.h's FileSet): the asset file is renamed last.
#pragma once

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/util/files.h>
#include <burnish/core/util/result.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
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

/// The name of the draft extension that points a texture at a KTX2 image of any payload.
inline constexpr std::string_view kKhrTextureKtx = "KHR_texture_ktx";

struct GltfOptions {
    /// A method the gltf preset stores (normal + one roughness channel); the preset's default when unset.
    std::optional<std::string> method;
    GltfTextureCoding coding = GltfTextureCoding::Raw;
    Overwrite overwrite = Overwrite::Refuse;
    bool allowImplausible = false;
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

} // namespace burnish
