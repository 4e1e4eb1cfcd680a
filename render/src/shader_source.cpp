#include <burnish/render/shader_source.h>

#include <algorithm>
#include <set>
#include <sstream>

namespace burnish::resources {
extern const std::pair<std::string_view, std::string_view> kShaderFiles[];
extern const int kShaderFilesCount;
} // namespace burnish::resources

namespace burnish::render {

namespace {

// GLSL 3.30 core: the lowest version the renderer targets (every feature it uses exists there).
constexpr std::string_view kVersionLine = "#version 330 core\n";

// Source-string numbers in #line directives identify the file in compiler messages: 0 is the
// assembled preamble, 1.. the embedded files in table order, so an error "1:42" maps back to a name.
int fileNumber(std::string_view name) {
    for (int i = 0; i < resources::kShaderFilesCount; ++i) {
        if (resources::kShaderFiles[i].first == name) return i + 1;
    }
    return 0;
}

// The quoted file name of an `#include "name"` line, or nothing when the line is not an include.
std::optional<std::string> includeTarget(std::string_view line) {
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos || line.substr(first, 8) != "#include") return std::nullopt;
    const size_t open = line.find('"', first + 8);
    const size_t close = open == std::string_view::npos ? open : line.find('"', open + 1);
    if (close == std::string_view::npos) return std::string();
    return std::string(line.substr(open + 1, close - open - 1));
}

Status splice(std::string_view name, std::string& out, std::set<std::string>& done,
              std::vector<std::string>& stack) {
    const auto source = shaderSource(name);
    if (!source) return Error{"no shader file named '" + std::string(name) + "'"};
    done.insert(std::string(name));
    stack.emplace_back(name);
    const int number = fileNumber(name);
    out += "#line 1 " + std::to_string(number) + "\n";
    std::istringstream lines{std::string(*source)};
    std::string line;
    int lineNo = 0;
    while (std::getline(lines, line)) {
        ++lineNo;
        const auto target = includeTarget(line);
        if (!target) {
            out += line;
            out += '\n';
            continue;
        }
        const std::string where = std::string(name) + ":" + std::to_string(lineNo);
        if (target->empty()) return Error{where + ": malformed #include (expected #include \"file\")"};
        if (std::find(stack.begin(), stack.end(), *target) != stack.end()) {
            return Error{where + ": include cycle through '" + *target + "'"};
        }
        if (!shaderSource(*target))
            return Error{where + ": no shader file named '" + *target + "' to include"};
        if (!done.count(*target)) {
            if (auto status = splice(*target, out, done, stack); !status) return status;
        }
        // Back in the including file: the next line is lineNo + 1.
        out += "#line " + std::to_string(lineNo + 1) + " " + std::to_string(number) + "\n";
    }
    stack.pop_back();
    return {};
}

} // namespace

std::optional<std::string_view> shaderSource(std::string_view name) {
    for (int i = 0; i < resources::kShaderFilesCount; ++i) {
        if (resources::kShaderFiles[i].first == name) return resources::kShaderFiles[i].second;
    }
    return std::nullopt;
}

std::vector<std::string> shaderSourceNames() {
    std::vector<std::string> names;
    for (int i = 0; i < resources::kShaderFilesCount; ++i)
        names.emplace_back(resources::kShaderFiles[i].first);
    std::sort(names.begin(), names.end());
    return names;
}

Result<std::string> assembleShader(std::string_view name, const ShaderDefines& defines) {
    std::string out(kVersionLine);
    for (const auto& [key, value] : defines)
        out += "#define " + key + " " + value + "\n";
    std::set<std::string> done;
    std::vector<std::string> stack;
    if (auto status = splice(name, out, done, stack); !status) return Error{status.error()};
    return out;
}

} // namespace burnish::render
