#include <burnish/render/program.h>

#include <epoxy/gl.h>

#include <glm/gtc/type_ptr.hpp>

#include <regex>
#include <sstream>
#include <vector>

namespace burnish::render {

namespace {

std::string shaderInfoLog(GLuint shader) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 0)), '\0');
    if (length > 0) glGetShaderInfoLog(shader, length, nullptr, log.data());
    return log.c_str(); // drop the terminating NUL GL counts in the length
}

std::string programInfoLog(GLuint program) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 0)), '\0');
    if (length > 0) glGetProgramInfoLog(program, length, nullptr, log.data());
    return log.c_str();
}

// Replaces the source-string numbers of a driver's info log by file names and joins its lines
// into one (errors are one line). assembleShader numbers the embedded files in #line directives
// as 1 + their index in shaderSourceNames(); 0 is the assembled preamble (`#version` and the
// defines), named `zeroName`. Handles Mesa's "N:L(C): error", NVIDIA's "N(L) : error" and
// AMD/Intel's "ERROR: N:L: ".
std::string mapInfoLog(const std::string& log, const std::string& zeroName) {
    static const std::regex kMesaOrAmd(R"(^(\s*(?:ERROR|WARNING): )?(\d+):(\d+))");
    static const std::regex kNvidia(R"(^(\s*)(\d+)\((\d+)\))");
    const std::vector<std::string> names = shaderSourceNames();
    auto nameOf = [&](const std::string& number) -> std::string {
        // More digits than any table holds: not a source number, leave it.
        if (number.size() > 6) return number;
        const size_t n = std::stoul(number);
        if (n == 0) return zeroName;
        return n <= names.size() ? names[n - 1] : number;
    };
    std::istringstream lines(log);
    std::string line;
    std::string out;
    while (std::getline(lines, line)) {
        while (!line.empty() && (line.back() == '\r' || line.back() == ' '))
            line.pop_back();
        if (line.empty()) continue;
        std::smatch match;
        if (std::regex_search(line, match, kMesaOrAmd)) {
            line = match[1].str() + nameOf(match[2].str()) + ":" + match[3].str() + match.suffix().str();
        } else if (std::regex_search(line, match, kNvidia)) {
            line =
                match[1].str() + nameOf(match[2].str()) + "(" + match[3].str() + ")" + match.suffix().str();
        }
        if (!out.empty()) out += "; ";
        out += line;
    }
    return out.empty() ? "(the driver gave no log)" : out;
}

Result<GLuint> compileStage(GLenum stage, const std::string& source, const std::string& name,
                            const std::string& zeroName) {
    const GLuint shader = glCreateShader(stage);
    if (shader == 0) return Error{name + ": glCreateShader failed"};
    const char* text = source.c_str();
    const GLint length = GLint(source.size());
    glShaderSource(shader, 1, &text, &length);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        const std::string log = shaderInfoLog(shader);
        glDeleteShader(shader);
        return Error{name + ": compile failed: " + mapInfoLog(log, zeroName)};
    }
    return shader;
}

Result<GLuint> linkProgram(const std::string& vertexSource, const std::string& fragmentSource,
                           const std::string& vertexName, const std::string& fragmentName,
                           const std::string& zeroName) {
    auto vertex = compileStage(GL_VERTEX_SHADER, vertexSource, vertexName, zeroName);
    if (!vertex) return Error{vertex.error()};
    auto fragment = compileStage(GL_FRAGMENT_SHADER, fragmentSource, fragmentName, zeroName);
    if (!fragment) {
        glDeleteShader(*vertex);
        return Error{fragment.error()};
    }
    const GLuint program = glCreateProgram();
    glAttachShader(program, *vertex);
    glAttachShader(program, *fragment);
    // The mesh attribute layout of GpuMesh; shaders may also say it with layout(location).
    glBindAttribLocation(program, 0, "aPosition");
    glBindAttribLocation(program, 1, "aNormal");
    glBindAttribLocation(program, 2, "aTangent");
    glBindAttribLocation(program, 3, "aUv");
    glLinkProgram(program);
    glDetachShader(program, *vertex);
    glDetachShader(program, *fragment);
    glDeleteShader(*vertex);
    glDeleteShader(*fragment);
    GLint ok = GL_FALSE;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        const std::string log = programInfoLog(program);
        glDeleteProgram(program);
        return Error{vertexName + " + " + fragmentName + ": link failed: " + mapInfoLog(log, zeroName)};
    }
    return program;
}

} // namespace

Program::~Program() {
    if (m_id != 0) glDeleteProgram(m_id);
}

Program::Program(Program&& other) noexcept
    : m_id(other.m_id)
    , m_locations(std::move(other.m_locations)) {
    other.m_id = 0;
    other.m_locations.clear();
}

Program& Program::operator=(Program&& other) noexcept {
    if (this != &other) {
        if (m_id != 0) glDeleteProgram(m_id);
        m_id = other.m_id;
        m_locations = std::move(other.m_locations);
        other.m_id = 0;
        other.m_locations.clear();
    }
    return *this;
}

Result<Program> Program::fromFiles(std::string_view vertexName, std::string_view fragmentName,
                                   const ShaderDefines& defines) {
    auto vertexSource = assembleShader(vertexName, defines);
    if (!vertexSource) return Error{vertexSource.error()};
    auto fragmentSource = assembleShader(fragmentName, defines);
    if (!fragmentSource) return Error{fragmentSource.error()};
    auto id = linkProgram(*vertexSource, *fragmentSource, std::string(vertexName), std::string(fragmentName),
                          "<defines>");
    if (!id) return Error{id.error()};
    return Program(*id);
}

Result<Program> Program::fromSources(const std::string& vertexSource, const std::string& fragmentSource,
                                     std::string_view label) {
    const std::string name(label);
    auto id = linkProgram(vertexSource, fragmentSource, name + " (vertex)", name + " (fragment)", name);
    if (!id) return Error{id.error()};
    return Program(*id);
}

void Program::use() const {
    glUseProgram(m_id);
}

int Program::location(const char* name) const {
    if (m_id == 0) return -1;
    const auto found = m_locations.find(name);
    if (found != m_locations.end()) return found->second;
    const int location = glGetUniformLocation(m_id, name);
    m_locations.emplace(name, location);
    return location;
}

bool Program::hasUniform(const char* name) const {
    return location(name) >= 0;
}

void Program::set(const char* name, int value) const {
    if (const int at = location(name); at >= 0) {
        use();
        glUniform1i(at, value);
    }
}

void Program::set(const char* name, float value) const {
    if (const int at = location(name); at >= 0) {
        use();
        glUniform1f(at, value);
    }
}

void Program::set(const char* name, const glm::vec2& value) const {
    if (const int at = location(name); at >= 0) {
        use();
        glUniform2fv(at, 1, glm::value_ptr(value));
    }
}

void Program::set(const char* name, const glm::vec3& value) const {
    if (const int at = location(name); at >= 0) {
        use();
        glUniform3fv(at, 1, glm::value_ptr(value));
    }
}

void Program::set(const char* name, const glm::vec4& value) const {
    if (const int at = location(name); at >= 0) {
        use();
        glUniform4fv(at, 1, glm::value_ptr(value));
    }
}

void Program::set(const char* name, const glm::mat3& value) const {
    if (const int at = location(name); at >= 0) {
        use();
        glUniformMatrix3fv(at, 1, GL_FALSE, glm::value_ptr(value));
    }
}

void Program::set(const char* name, const glm::mat4& value) const {
    if (const int at = location(name); at >= 0) {
        use();
        glUniformMatrix4fv(at, 1, GL_FALSE, glm::value_ptr(value));
    }
}

Result<const Program*> ProgramCache::get(const std::string& vertexName, const std::string& fragmentName,
                                         const ShaderDefines& defines) {
    // NUL and newline cannot occur in file names or define names: the key is unambiguous.
    std::string key = vertexName + '\0' + fragmentName + '\0';
    for (const auto& [name, value] : defines)
        key += name + '=' + value + '\n';
    if (const auto found = m_programs.find(key); found != m_programs.end()) return found->second.get();
    ++m_compiles;
    auto program = Program::fromFiles(vertexName, fragmentName, defines);
    if (!program) return Error{program.error()};
    auto stored = std::make_unique<Program>(std::move(program).value());
    const Program* pointer = stored.get();
    m_programs.emplace(std::move(key), std::move(stored));
    return pointer;
}

void ProgramCache::clear() {
    m_programs.clear();
}

} // namespace burnish::render
