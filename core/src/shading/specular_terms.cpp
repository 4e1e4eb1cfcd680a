#include <burnish/core/shading/specular_terms.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace burnish {

namespace {

constexpr std::array<std::pair<SpecularConvention, std::string_view>, 6> kNames = {{
    {SpecularConvention::F0, "f0"},
    {SpecularConvention::Gltf, "gltf"},
    {SpecularConvention::Unreal, "unreal"},
    {SpecularConvention::UnityMetallic, "unity-metallic"},
    {SpecularConvention::Godot, "godot"},
    {SpecularConvention::Filament, "filament"},
}};

bool grey(const LinearRgb& c) {
    const double hi = std::max({c.r, c.g, c.b}), lo = std::min({c.r, c.g, c.b});
    return hi - lo <= 0.01 * std::max(hi, 1e-6);
}

nlohmann::json rgb(const LinearRgb& c) {
    return {c.r, c.g, c.b};
}

std::string f0Text(const LinearRgb& c) {
    return fmt::format("({:.4g}, {:.4g}, {:.4g})", c.r, c.g, c.b);
}

} // namespace

std::string_view specularConventionName(SpecularConvention c) {
    for (const auto& [value, name] : kNames)
        if (value == c) return name;
    return "f0";
}

Result<SpecularConvention> specularConventionFromName(std::string_view name) {
    std::string known;
    for (const auto& [value, n] : kNames) {
        if (n == name) return value;
        known += (known.empty() ? "" : ", ") + std::string(n);
    }
    return Error{fmt::format("unknown specular convention '{}' (known: {})", name, known)};
}

double unrealSpecularFromF0(double f0) {
    return f0 / 0.08;
}

double reflectanceFromF0(double f0) {
    return std::sqrt(std::max(f0, 0.0) / 0.16);
}

double gltfSpecularColorFactorFromF0(double f0) {
    return f0 / 0.04;
}

SpecularTerms specularTerms(SpecularConvention convention, MaterialClass materialClass, const LinearRgb& f0) {
    SpecularTerms t;
    const bool metal = materialClass == MaterialClass::Metal;
    // A colour the material table puts in the other class (or in neither) is exported as asked, with a word.
    const F0Class found = classifyF0(builtinMaterialTable(), f0).f0Class;
    if (found != (metal ? F0Class::Metal : F0Class::Dielectric))
        t.warnings.push_back(fmt::format("F0 {} of a {} lies in the material table's {} range", f0Text(f0),
                                         toString(materialClass), toString(found)));
    nlohmann::json& v = t.values;
    // A scalar parameter of a coloured dielectric F0: its luminance, said so.
    auto scalar = [&](const char* parameter) {
        if (!grey(f0))
            t.warnings.push_back(
                fmt::format("{} is one number: the dielectric F0 {} is written as its luminance {:.4g}",
                            parameter, f0Text(f0), luminance(f0)));
        return luminance(f0);
    };
    auto clamped = [&](double value, const char* parameter, double f0Max) {
        if (value > 1.0)
            t.warnings.push_back(fmt::format("{} holds F0 up to {:g}: {:.4g} is clamped to 1 (F0 {:g})",
                                             parameter, f0Max, value, f0Max));
        return std::min(value, 1.0);
    };
    switch (convention) {
    case SpecularConvention::F0:
        v["f0"] = rgb(f0);
        break;
    case SpecularConvention::Gltf:
        if (metal) {
            v["baseColorFactor"] = {f0.r, f0.g, f0.b, 1.0};
            v["metallicFactor"] = 1.0;
        } else {
            v["metallicFactor"] = 0.0;
            v["KHR_materials_specular"] = {
                {"specularColorFactor",
                 {gltfSpecularColorFactorFromF0(f0.r), gltfSpecularColorFactorFromF0(f0.g),
                  gltfSpecularColorFactorFromF0(f0.b)}}};
            v["KHR_materials_ior"] = {{"ior", 1.5}};
        }
        break;
    case SpecularConvention::Unreal:
        if (metal) {
            v["BaseColor"] = rgb(f0);
            v["Metallic"] = 1.0;
        } else {
            v["Metallic"] = 0.0;
            v["Specular"] =
                clamped(unrealSpecularFromF0(scalar("Unreal's Specular")), "Unreal's Specular", 0.08);
        }
        break;
    case SpecularConvention::UnityMetallic:
        if (metal) {
            v["Albedo"] = rgb(f0);
            v["Metallic"] = 1.0;
        } else {
            v["Metallic"] = 0.0;
            // The specular setup takes the colour as it is; the metallic setup this preset writes cannot.
            v["SpecularSetupColor"] = rgb(f0);
            if (std::abs(f0.r - 0.04) > 0.002 || std::abs(f0.g - 0.04) > 0.002 ||
                std::abs(f0.b - 0.04) > 0.002)
                t.warnings.push_back(fmt::format(
                    "Unity's metallic setup fixes a dielectric's F0 at 0.04: F0 {} needs the specular setup "
                    "(Standard (Specular setup), Specular colour as recorded)",
                    f0Text(f0)));
        }
        break;
    case SpecularConvention::Godot:
    case SpecularConvention::Filament: {
        const bool godot = convention == SpecularConvention::Godot;
        const char* parameter = godot ? "Godot's metallic_specular" : "Filament's reflectance";
        if (metal) {
            v[godot ? "albedo_color" : "baseColor"] = rgb(f0);
            v[godot ? "metallic" : "metallic"] = 1.0;
        } else {
            v["metallic"] = 0.0;
            v[godot ? "metallic_specular" : "reflectance"] =
                clamped(reflectanceFromF0(scalar(parameter)), parameter, 0.16);
        }
        break;
    }
    }
    return t;
}

} // namespace burnish
