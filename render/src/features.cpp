#include <burnish/render/features.h>

#include <burnish/render/program.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <sstream>

namespace burnish::render {

namespace {

// Every enumeration the shader switches on, with its numbered constants. The numbers are part of
// the contract with material.frag (which #if-tests them) and with the ubershader's int uniforms.
// METHOD_* are int(burnish::Method), defined by methods.glsl (the twin of methods.h), so they are
// named here (by the method table's glslMacro) but not injected.
const char* const kNdfDefines[] = {"NDF_BLINN_PHONG", "NDF_BECKMANN", "NDF_GGX"};
const char* const kFresnelDefines[] = {"FRESNEL_NONE", "FRESNEL_SCHLICK", "FRESNEL_SCHLICK_SG",
                                       "FRESNEL_SCHLICK_SG_QUADRATIC"};
const char* const kVisibilityDefines[] = {"VISIBILITY_NONE",           "VISIBILITY_KELEMEN",
                                          "VISIBILITY_SCHLICK_SMITH",  "VISIBILITY_COOK_TORRANCE",
                                          "VISIBILITY_SMITH_BECKMANN", "VISIBILITY_SMITH_GGX_CORRELATED"};
const char* const kSpecularAaDefines[] = {"SPECULAR_AA_NONE", "SPECULAR_AA_KAPLANYAN_VALIENT",
                                          "SPECULAR_AA_TOKUYOSHI_KAPLANYAN"};
// In EnvironmentKind's order; material.frag includes env_lighting.glsl only for the last two.
const char* const kEnvironmentDefines[] = {"ENVIRONMENT_OFF", "ENVIRONMENT_CONSTANT_AMBIENT",
                                           "ENVIRONMENT_PREFILTERED", "ENVIRONMENT_FIS"};
const char* const kDebugDefines[] = {
    "DEBUG_NONE",    "DEBUG_LIGHTING_ONLY", "DEBUG_DIFFUSE_ONLY", "DEBUG_SPECULAR_ONLY", "DEBUG_POWER",
    "DEBUG_NORMALS", "DEBUG_MIP_LEVEL",     "DEBUG_VARIANCE",     "DEBUG_ERROR_HEATMAP", "DEBUG_UV"};

std::string methodDefine(Method method) {
    return std::string(methodSpec(method).glslMacro);
}

template <size_t N> void addConstants(ShaderDefines& out, const char* const (&names)[N]) {
    for (size_t i = 0; i < N; ++i)
        out.emplace_back(names[i], std::to_string(i));
}

void addConstantTables(ShaderDefines& out) {
    addConstants(out, kNdfDefines);
    addConstants(out, kFresnelDefines);
    addConstants(out, kVisibilityDefines);
    addConstants(out, kSpecularAaDefines);
    addConstants(out, kDebugDefines);
    addConstants(out, kEnvironmentDefines);
}

void flag(ShaderDefines& out, const char* name, bool on) {
    if (on) out.emplace_back(name, "1");
}

std::string glTypeName(GLenum type) {
    switch (type) {
    case GL_FLOAT:
        return "float";
    case GL_FLOAT_VEC2:
        return "vec2";
    case GL_FLOAT_VEC3:
        return "vec3";
    case GL_FLOAT_VEC4:
        return "vec4";
    case GL_INT:
        return "int";
    case GL_BOOL:
        return "bool";
    case GL_FLOAT_MAT3:
        return "mat3";
    case GL_FLOAT_MAT4:
        return "mat4";
    case GL_SAMPLER_2D:
        return "sampler2D";
    case GL_SAMPLER_CUBE:
        return "samplerCube";
    default:
        return "type 0x" + [&] {
            std::ostringstream s;
            s << std::hex << type;
            return s.str();
        }();
    }
}

} // namespace

std::string_view meshKindName(MeshKind kind) {
    switch (kind) {
    case MeshKind::Sphere:
        return "sphere";
    case MeshKind::Plane:
        return "plane";
    case MeshKind::Torus:
        return "torus";
    case MeshKind::Obj:
        return "obj";
    }
    return "sphere";
}

std::string_view environmentName(EnvironmentKind kind) {
    switch (kind) {
    case EnvironmentKind::Off:
        return "off";
    case EnvironmentKind::ConstantAmbient:
        return "constant ambient";
    case EnvironmentKind::Prefiltered:
        return "prefiltered";
    case EnvironmentKind::FilteredImportanceSampling:
        return "filtered importance sampling";
    }
    return "off";
}

std::string_view debugViewName(DebugView view) {
    switch (view) {
    case DebugView::None:
        return "none";
    case DebugView::LightingOnly:
        return "lighting-only";
    case DebugView::DiffuseOnly:
        return "diffuse-only";
    case DebugView::SpecularOnly:
        return "specular-only";
    case DebugView::Power:
        return "power";
    case DebugView::Normals:
        return "normals";
    case DebugView::MipLevel:
        return "mip-level";
    case DebugView::Variance:
        return "variance";
    case DebugView::ErrorHeatmap:
        return "error-heatmap";
    case DebugView::Uv:
        return "uv";
    }
    return "none";
}

ShaderDefines defines(const FeatureSet& f) {
    ShaderDefines out;
    addConstantTables(out);
    // The reference draws the finest normals with the base power: no method's lobe.
    out.emplace_back("METHOD", methodDefine(f.referenceMode ? Method::Naive : f.method));
    out.emplace_back("NDF", kNdfDefines[int(f.ndf)]);
    out.emplace_back("FRESNEL", kFresnelDefines[int(f.fresnel)]);
    out.emplace_back("VISIBILITY", kVisibilityDefines[int(f.visibility)]);
    out.emplace_back("SPECULAR_AA",
                     kSpecularAaDefines[int(f.referenceMode ? SpecularAa::None : f.specularAa)]);
    out.emplace_back("DEBUG_VIEW", kDebugDefines[int(f.debugView)]);
    out.emplace_back("ENVIRONMENT", kEnvironmentDefines[int(f.environment)]);
    const int lights = std::clamp(f.pointLights, 0, kMaxPointLights);
    if (lights > 0) out.emplace_back("POINT_LIGHTS", std::to_string(lights));
    flag(out, "HAS_AMBIENT", f.environment == EnvironmentKind::ConstantAmbient);
    flag(out, "HAS_NORMAL_MAP", f.normalMap);
    flag(out, "HAS_DETAIL_MAP", f.detailMap && f.normalMap);
    flag(out, "HAS_GLOSS_MAP", f.glossMap);
    flag(out, "HAS_SPECULAR_MAP", f.specularTexture);
    flag(out, "HAS_DIFFUSE", !f.metalOnly);
    flag(out, "HAS_DIFFUSE_AA", f.diffuseAa && !f.metalOnly && !f.referenceMode);
    flag(out, "REFERENCE_MODE", f.referenceMode);
    return out;
}

ShaderDefines ubershaderDefines() {
    ShaderDefines out;
    addConstantTables(out);
    out.emplace_back("UBERSHADER", "1");
    out.emplace_back("POINT_LIGHTS", std::to_string(kMaxPointLights));
    for (const char* name : {"HAS_AMBIENT", "HAS_NORMAL_MAP", "HAS_DETAIL_MAP", "HAS_GLOSS_MAP",
                             "HAS_SPECULAR_MAP", "HAS_DIFFUSE", "HAS_DIFFUSE_AA"})
        out.emplace_back(name, "1");
    return out;
}

std::vector<std::string> activeUniforms(const Program& program) {
    std::vector<std::string> out;
    if (!program.valid()) return out;
    GLint count = 0, maxLength = 0;
    glGetProgramiv(program.id(), GL_ACTIVE_UNIFORMS, &count);
    glGetProgramiv(program.id(), GL_ACTIVE_UNIFORM_MAX_LENGTH, &maxLength);
    std::string name(size_t(std::max(maxLength, 1)), '\0');
    for (GLint i = 0; i < count; ++i) {
        GLsizei length = 0;
        GLint size = 0;
        GLenum type = 0;
        glGetActiveUniform(program.id(), GLuint(i), GLsizei(name.size()), &length, &size, &type, name.data());
        out.push_back(glTypeName(type) + " " + name.substr(0, size_t(length)));
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::string explain(const FeatureSet& f, const Program& program) {
    std::ostringstream s;
    s << "features:\n";
    s << "  mesh: " << meshKindName(f.mesh) << "\n";
    s << "  point lights: " << f.pointLights << "\n";
    s << "  environment: " << environmentName(f.environment) << "\n";
    s << "  normal map: " << (f.normalMap ? "yes" : "no") << "\n";
    s << "  detail map: " << (f.detailMap ? "yes" : "no") << "\n";
    s << "  gloss map: " << (f.glossMap ? "yes" : "no") << "\n";
    s << "  specular colour: " << (f.specularTexture ? "texture" : "constant") << "\n";
    s << "  metal only: " << (f.metalOnly ? "yes (no diffuse code)" : "no") << "\n";
    s << "  method: " << (f.referenceMode ? "reference (finest mip, base power)" : methodName(f.method))
      << "\n";
    s << "  ndf: " << ndfTermName(f.ndf) << "\n";
    s << "  fresnel: " << fresnelTermName(f.fresnel) << "\n";
    s << "  visibility: " << visibilityTermName(f.visibility) << "\n";
    s << "  diffuse aa: " << (f.diffuseAa ? "on" : "off") << "\n";
    s << "  specular aa: " << specularAaName(f.specularAa) << "\n";
    s << "  debug view: " << debugViewName(f.debugView) << "\n";
    s << "defines:\n";
    for (const auto& [name, value] : defines(f)) {
        // The numbered constant tables are the same for every program; list only the switches.
        if (name.find('_') != std::string::npos &&
            value.find_first_not_of("0123456789") == std::string::npos && name.rfind("HAS_", 0) != 0 &&
            name != "POINT_LIGHTS" && name != "REFERENCE_MODE")
            continue;
        s << "  " << name << " " << value << "\n";
    }
    const auto uniforms = activeUniforms(program);
    s << "active uniforms (" << uniforms.size() << "):\n";
    for (const auto& u : uniforms)
        s << "  " << u << "\n";
    return s.str();
}

} // namespace burnish::render
