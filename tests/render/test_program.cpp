// Shader assembly (defines after #version, includes spliced once with #line) and programs: compile
// errors that name the file, link errors, uniforms, and the per-define-set program cache.
#include <burnish/render/context.h>
#include <burnish/render/program.h>
#include <burnish/render/shader_source.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <sstream>
#include <vector>

using namespace burnish;
using namespace burnish::render;

namespace {

std::vector<std::string> splitLines(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
        lines.push_back(line);
    return lines;
}

size_t countOf(const std::string& text, const std::string& needle) {
    size_t count = 0;
    for (size_t pos = text.find(needle); pos != std::string::npos; pos = text.find(needle, pos + 1))
        ++count;
    return count;
}

// The number assembleShader gives a file in #line directives: 1 + its index in the sorted table.
int fileNumber(const std::string& name) {
    const auto names = shaderSourceNames();
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : int(it - names.begin()) + 1;
}

// 1-based line of the first line of embedded file `name` that starts with `prefix`, or 0.
int lineStartingWith(const std::string& name, const std::string& prefix) {
    const auto source = shaderSource(name);
    if (!source) return 0;
    const auto lines = splitLines(std::string(*source));
    for (size_t i = 0; i < lines.size(); ++i) {
        if (lines[i].rfind(prefix, 0) == 0) return int(i) + 1;
    }
    return 0;
}

std::unique_ptr<GlContext>& programContext() {
    static std::unique_ptr<GlContext> context;
    return context;
}

class ProgramGl : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        auto created = createHeadlessContext();
        if (created) {
            programContext() = std::move(created).value();
        } else {
            s_error = created.error();
        }
    }
    static void TearDownTestSuite() { programContext().reset(); }
    void SetUp() override {
        ASSERT_TRUE(programContext()) << "no headless OpenGL context: " << s_error;
        const Status status = programContext()->makeCurrent();
        ASSERT_TRUE(status) << status.error();
    }
    static inline std::string s_error;
};

} // namespace

TEST(ShaderAssembly, DefinesFollowVersionInOrder) {
    auto source = assembleShader("tonemap.frag", {{"TONEMAP_NONE", "1"}, {"EXTRA", "2"}});
    ASSERT_TRUE(source) << source.error();
    const auto lines = splitLines(*source);
    ASSERT_GE(lines.size(), 3u);
    EXPECT_EQ(lines[0], "#version 330 core");
    EXPECT_EQ(lines[1], "#define TONEMAP_NONE 1");
    EXPECT_EQ(lines[2], "#define EXTRA 2");
}

TEST(ShaderAssembly, IncludeIsExpandedOnceWithLineDirectives) {
    ASSERT_GT(fileNumber("common_color.glsl"), 0);
    ASSERT_GT(fileNumber("tonemap.frag"), 0);
    const int includeLine = lineStartingWith("tonemap.frag", "#include \"common_color.glsl\"");
    ASSERT_GT(includeLine, 0) << "tonemap.frag includes common_color.glsl";

    auto source = assembleShader("tonemap.frag");
    ASSERT_TRUE(source) << source.error();
    EXPECT_EQ(source->find("#include"), std::string::npos) << "every include is expanded";
    // common_color.glsl's functions appear once (spliced once), and before their use in main().
    EXPECT_EQ(countOf(*source, "vec3 tonemapFilmic(vec3 x)"), 1u);
    EXPECT_EQ(countOf(*source, "float linearToSrgb(float L)"), 1u);
    EXPECT_LT(source->find("vec3 tonemapFilmic(vec3 x)"), source->find("void main()"));
    // #line directives: the included file starts at its line 1, and the includer resumes on the
    // line after its #include, each with its own file number.
    const std::string enterInclude = "#line 1 " + std::to_string(fileNumber("common_color.glsl")) + "\n";
    const std::string resume =
        "#line " + std::to_string(includeLine + 1) + " " + std::to_string(fileNumber("tonemap.frag")) + "\n";
    EXPECT_EQ(countOf(*source, enterInclude), 1u) << *source;
    EXPECT_EQ(countOf(*source, resume), 1u) << *source;
    EXPECT_LT(source->find(enterInclude), source->find(resume));
}

TEST(ShaderAssembly, UnknownFileIsAnError) {
    auto source = assembleShader("no_such_file.frag");
    ASSERT_FALSE(source);
    EXPECT_NE(source.error().find("no_such_file.frag"), std::string::npos) << source.error();
}

TEST_F(ProgramGl, UnknownFileFailsProgramCreation) {
    auto program = Program::fromFiles("fullscreen.vert", "no_such_file.frag");
    ASSERT_FALSE(program);
    EXPECT_NE(program.error().find("no_such_file.frag"), std::string::npos) << program.error();
}

TEST_F(ProgramGl, CompilesAndFindsUniforms) {
    auto program = Program::fromFiles("fullscreen.vert", "tonemap.frag");
    ASSERT_TRUE(program) << program.error();
    EXPECT_TRUE(program->valid());
    EXPECT_TRUE(program->hasUniform("uExposure"));
    EXPECT_TRUE(program->hasUniform("uHdr"));
    EXPECT_FALSE(program->hasUniform("uNotThere"));
    // Setting a uniform the program lacks is ignored (no GL error, no crash).
    program->set("uNotThere", 1.0f);
}

TEST_F(ProgramGl, ErrorInTheMainFileNamesIt) {
    // A define that breaks tonemap.frag's own `#if TONEMAP_NONE` line.
    const int ifLine = lineStartingWith("tonemap.frag", "#if TONEMAP_NONE");
    ASSERT_GT(ifLine, 0);
    auto program = Program::fromFiles("fullscreen.vert", "tonemap.frag", {{"TONEMAP_NONE", "("}});
    ASSERT_FALSE(program);
    const std::string& error = program.error();
    EXPECT_EQ(error.rfind("tonemap.frag: compile failed: ", 0), 0u) << error;
    // The log's source number is replaced by the file name, with the file's own line number.
    EXPECT_NE(error.find("tonemap.frag:" + std::to_string(ifLine)), std::string::npos) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << "errors are one line";
}

TEST_F(ProgramGl, ErrorInAnIncludedFileNamesTheIncludedFile) {
    // `clamp01` defined away: common_color.glsl's first definition becomes `float )(float x)`.
    const int firstUse = lineStartingWith("common_color.glsl", "float clamp01(");
    ASSERT_GT(firstUse, 0);
    auto program = Program::fromFiles("fullscreen.vert", "tonemap.frag", {{"clamp01", ")"}});
    ASSERT_FALSE(program);
    const std::string& error = program.error();
    EXPECT_EQ(error.rfind("tonemap.frag: compile failed: ", 0), 0u) << error;
    EXPECT_NE(error.find("common_color.glsl:" + std::to_string(firstUse)), std::string::npos) << error;
}

TEST_F(ProgramGl, FromSourcesErrorsCarryTheLabel) {
    const std::string vertex = "#version 330 core\nvoid main() { gl_Position = vec4(0.0); }\n";
    const std::string broken = "#version 330 core\nout vec4 c;\nvoid main() { c = vec4(1.0) }\n";
    auto program = Program::fromSources(vertex, broken, "inline test");
    ASSERT_FALSE(program);
    EXPECT_NE(program.error().find("inline test"), std::string::npos) << program.error();
    EXPECT_NE(program.error().find("compile failed"), std::string::npos) << program.error();
}

TEST_F(ProgramGl, LinkErrorIsReported) {
    // Each stage compiles on its own, but a vertex stage without main() cannot be linked.
    const std::string vertex = "#version 330 core\nvoid notMain() { gl_Position = vec4(0.0); }\n";
    const std::string fragment = "#version 330 core\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n";
    auto program = Program::fromSources(vertex, fragment, "unlinked");
    ASSERT_FALSE(program);
    EXPECT_NE(program.error().find("link failed"), std::string::npos) << program.error();
    EXPECT_NE(program.error().find("unlinked"), std::string::npos) << program.error();
}

TEST_F(ProgramGl, CacheCompilesOncePerDefineSet) {
    ProgramCache cache;
    auto first = cache.get("fullscreen.vert", "tonemap.frag", {});
    ASSERT_TRUE(first) << first.error();
    auto again = cache.get("fullscreen.vert", "tonemap.frag", {});
    ASSERT_TRUE(again) << again.error();
    EXPECT_EQ(*first, *again) << "the same define set returns the same program";
    EXPECT_EQ(cache.compileCount(), 1u);
    EXPECT_EQ(cache.size(), 1u);

    auto other = cache.get("fullscreen.vert", "tonemap.frag", {{"TONEMAP_NONE", "1"}});
    ASSERT_TRUE(other) << other.error();
    EXPECT_NE(*other, *first) << "another define set is another program";
    EXPECT_EQ(cache.compileCount(), 2u);
    EXPECT_EQ(cache.size(), 2u);
    auto otherAgain = cache.get("fullscreen.vert", "tonemap.frag", {{"TONEMAP_NONE", "1"}});
    ASSERT_TRUE(otherAgain);
    EXPECT_EQ(*otherAgain, *other);
    EXPECT_EQ(cache.compileCount(), 2u);

    // A failing define set is not cached.
    auto broken = cache.get("fullscreen.vert", "tonemap.frag", {{"TONEMAP_NONE", "("}});
    EXPECT_FALSE(broken);
    EXPECT_EQ(cache.size(), 2u);

    cache.clear();
    EXPECT_EQ(cache.size(), 0u);
}
