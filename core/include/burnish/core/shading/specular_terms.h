// The specular colour an artist picked (linear F0 of a metal or a dielectric) in each engine's own
// material parameters, with a warning wherever the engine's parameter cannot hold it. A preset names its
// engine's convention ("specular" in resources/presets/*.json); bake.json and `burnish gltf` record the
// values this gives.
#pragma once

#include <burnish/core/shading/color.h>
#include <burnish/core/shading/materials.h>
#include <burnish/core/util/result.h>

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace burnish {

enum class SpecularConvention {
    F0,            // the texture set's own shader takes F0 as it is (Black Ops, LEAN, CLEAN, the mixture)
    Gltf,          // glTF 2.0: metals baseColorFactor; dielectrics KHR_materials_specular at ior 1.5
    Unreal,        // Unreal Engine: BaseColor / Specular, F0 = 0.08·Specular
    UnityMetallic, // Unity Standard, metallic setup: dielectric F0 fixed at 0.04
    Godot,         // Godot StandardMaterial3D: albedo / metallic_specular, F0 = 0.16·specular²
    Filament,      // Filament lit model: baseColor / reflectance, F0 = 0.16·reflectance²
};

std::string_view specularConventionName(SpecularConvention c); // "f0", "gltf", "unreal", ...
Result<SpecularConvention> specularConventionFromName(std::string_view name);

/// The engine's parameters for `f0`, as JSON ({"BaseColor": [r, g, b], "Metallic": 1}, ...), and the
/// warnings: a dielectric colour a scalar parameter cannot hold (its Rec. 709 luminance is written), a
/// value above the parameter's range (clamped), a dielectric F0 the engine fixes (Unity's metallic setup).
struct SpecularTerms {
    nlohmann::json values = nlohmann::json::object();
    std::vector<std::string> warnings;
};

/// Unreal: DielectricSpecularToF0(Specular) = 0.08·Specular (ShadingCommon.ush), Specular in [0, 1].
double unrealSpecularFromF0(double f0);
/// Godot and Filament: F0 = 0.16·s² (Godot's F0(), Filament's "reflectance"), s in [0, 1].
double reflectanceFromF0(double f0);
/// glTF KHR_materials_specular: F0 = ((ior − 1)/(ior + 1))²·specularColorFactor, 0.04·factor at ior 1.5.
double gltfSpecularColorFactorFromF0(double f0);

SpecularTerms specularTerms(SpecularConvention convention, MaterialClass materialClass, const LinearRgb& f0);

} // namespace burnish
