// A linked GLSL program (RAII), compiled from embedded shader files with injected defines, and a
// cache keyed by file names and defines so each feature set is compiled once.
#pragma once

#include <burnish/core/util/result.h>
#include <burnish/render/shader_source.h>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>

namespace burnish::render {

class Program {
public:
    Program() = default;
    ~Program();
    Program(Program&& other) noexcept;
    Program& operator=(Program&& other) noexcept;
    Program(const Program&) = delete;
    Program& operator=(const Program&) = delete;

    /// Compiles and links embedded files `vertexName` and `fragmentName` with `defines`.
    /// A compile or link error names the file and carries the driver's info log, its lines joined
    /// by "; " and its source numbers replaced by file names ("material.frag: compile failed:
    /// common_color.glsl:12(3): error: ..."). Vertex inputs named aPosition, aNormal, aTangent and
    /// aUv are bound to GpuMesh's attribute locations 0–3.
    static Result<Program> fromFiles(std::string_view vertexName, std::string_view fragmentName,
                                     const ShaderDefines& defines = {});
    /// The same from complete sources (already with #version); `label` names them in errors.
    static Result<Program> fromSources(const std::string& vertexSource, const std::string& fragmentSource,
                                       std::string_view label);

    unsigned id() const { return m_id; }
    bool valid() const { return m_id != 0; }
    void use() const;

    /// Uniform setters; they make the program current (glUseProgram) first. A name the program
    /// does not use (optimized away) is ignored.
    void set(const char* name, int value) const;
    void set(const char* name, float value) const;
    void set(const char* name, const glm::vec2& value) const;
    void set(const char* name, const glm::vec3& value) const;
    void set(const char* name, const glm::vec4& value) const;
    void set(const char* name, const glm::mat3& value) const;
    void set(const char* name, const glm::mat4& value) const;
    /// Whether the linked program has an active uniform of that name.
    bool hasUniform(const char* name) const;

private:
    explicit Program(unsigned id)
        : m_id(id) {}
    int location(const char* name) const;

    unsigned m_id = 0;
    mutable std::unordered_map<std::string, int> m_locations;
};

/// One program per (vertex file, fragment file, defines); compiled on first request.
class ProgramCache {
public:
    Result<const Program*> get(const std::string& vertexName, const std::string& fragmentName,
                               const ShaderDefines& defines);
    size_t size() const { return m_programs.size(); }
    /// Number of compilations done (a cache hit does not count).
    size_t compileCount() const { return m_compiles; }
    void clear();

private:
    std::map<std::string, std::unique_ptr<Program>> m_programs;
    size_t m_compiles = 0;
};

} // namespace burnish::render
