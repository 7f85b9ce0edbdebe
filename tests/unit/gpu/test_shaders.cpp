// SPDX-License-Identifier: MIT
/// @file
/// @brief Shader library, #include preprocessor (line mapping), compile errors with file and line,
/// the embedded shaders, and the C++/GLSL shared layouts.

#include "GlTestContext.h"

#include <lucent/core/Error.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/Shader.h>
#include <shared/LightingShared.h>

#include <epoxy/gl.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

using namespace lucent;
using namespace lucent::gpu;
namespace fs = std::filesystem;

namespace {

/// A fresh shader directory under the test output dir with the given files.
std::string makeShaderDir(const std::string& name,
                          const std::vector<std::pair<std::string, std::string>>& files) {
    const fs::path dir = fs::path(LUCENT_TEST_OUTPUT_DIR) / "gpu" / name;
    fs::remove_all(dir);
    for (const auto& [path, text] : files) {
        fs::create_directories((dir / path).parent_path());
        std::ofstream(dir / path) << text;
    }
    return dir.string();
}

/// Line (1-based) of the first occurrence of `needle` in `text`, 0 if absent.
int lineOf(const std::string& text, const std::string& needle) {
    const size_t pos = text.find(needle);
    if (pos == std::string::npos)
        return 0;
    return 1 + int(std::count(text.begin(), text.begin() + long(pos), '\n'));
}

const char* MAIN_COMP =
    "#version 450 core\n"                      // 1
    "// main\n"                                // 2
    "#include \"common/a.glsl\"\n"             // 3
    "layout(local_size_x = 1) in;\n"           // 4
    "void main() { float x = helperA(); }\n";  // 5

}  // namespace

TEST(ShaderPreprocess, ResolvesIncludesWithLineDirectives) {
    const std::string dir = makeShaderDir(
        "resolve", {{"main.comp", MAIN_COMP},
                    {"common/a.glsl",
                     "#pragma once\n#include \"b.glsl\"\nfloat helperA() { return helperB(); }\n"},
                    {"common/b.glsl", "#pragma once\nfloat helperB() { return 2.0; }\n"}});
    const ShaderLibrary lib(dir);
    const PreprocessedShader pre = preprocessShader(lib, "main.comp", {"FOO=3", "BAR"});
    ASSERT_EQ(pre.files.size(), 3u);
    EXPECT_EQ(pre.files[0], "main.comp");
    EXPECT_EQ(pre.files[1], "common/a.glsl");
    EXPECT_EQ(pre.files[2], "common/b.glsl");  // found next to a.glsl, not at the root
    const std::string& s = pre.source;
    EXPECT_EQ(s.rfind("#version 450 core\n", 0), 0u);
    EXPECT_NE(s.find("#define FOO 3\n"), std::string::npos);
    EXPECT_NE(s.find("#define BAR\n"), std::string::npos);
    // b.glsl starts with "#line 1 2"; a.glsl resumes at its line 3 after the include.
    EXPECT_NE(s.find("#line 1 2\n"), std::string::npos);
    EXPECT_NE(s.find("#line 3 1\nfloat helperA()"), std::string::npos) << s;
    EXPECT_NE(s.find("#line 4 0\nlayout(local_size_x = 1) in;"), std::string::npos) << s;
    EXPECT_LT(lineOf(s, "helperB() { return"), lineOf(s, "float helperA()"));
    EXPECT_EQ(s.find("#include"), std::string::npos);
    EXPECT_EQ(s.find("#pragma once"), std::string::npos);
}

TEST(ShaderPreprocess, PragmaOnceAndCplusplusBlocks) {
    const std::string dir = makeShaderDir(
        "once", {{"s.frag",
                  "#version 450 core\n#include \"shared/h.h\"\n#include \"shared/h.h\"\n"
                  "void main() {}\n"},
                 {"shared/h.h",
                  "#pragma once\n#ifdef __cplusplus\n#include <glm/glm.hpp>\n"
                  "#if 1\nint cppOnly;\n#endif\n#else\nconst int GLSL_ONLY = 1;\n"
                  "#endif\n#ifndef __cplusplus\nconst int ALSO_GLSL = 2;\n#endif\n"}});
    const PreprocessedShader pre = preprocessShader(ShaderLibrary(dir), "s.frag");
    const std::string& s = pre.source;
    EXPECT_EQ(std::count(pre.files.begin(), pre.files.end(), "shared/h.h"), 1);
    size_t n = 0;
    for (size_t p = 0; (p = s.find("GLSL_ONLY", p)) != std::string::npos; ++p)
        ++n;
    EXPECT_EQ(n, 1u) << "included once despite two #include lines";
    EXPECT_NE(s.find("ALSO_GLSL"), std::string::npos);
    EXPECT_EQ(s.find("glm"), std::string::npos);
    EXPECT_EQ(s.find("cppOnly"), std::string::npos);
    EXPECT_EQ(s.find("__cplusplus"), std::string::npos);
}

TEST(ShaderPreprocess, ErrorsNameTheFileAndLine) {
    const std::string dir = makeShaderDir(
        "errors", {{"missing.comp", "#version 450 core\n\n#include \"nothere.glsl\"\n"},
                   {"cycle.comp", "#version 450 core\n#include \"x.glsl\"\n"},
                   {"x.glsl", "#include \"y.glsl\"\n"},
                   {"y.glsl", "#include \"x.glsl\"\n"},
                   {"noversion.comp", "void main() {}\n"}});
    const ShaderLibrary lib(dir);
    try {
        (void)preprocessShader(lib, "missing.comp");
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("missing.comp:3"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("nothere.glsl"), std::string::npos) << e.what();
    }
    EXPECT_THROW((void)preprocessShader(lib, "cycle.comp"), ValueError);
    EXPECT_THROW((void)preprocessShader(lib, "noversion.comp"), ValueError);
    EXPECT_THROW((void)lib.read("absent.glsl"), IoError);
    EXPECT_FALSE(lib.exists("../escape.glsl"));
    EXPECT_THROW(ShaderLibrary("/definitely/not/a/dir"), IoError);
}

TEST(ShaderPreprocess, MapsDriverLogsToFiles) {
    PreprocessedShader pre;
    pre.files = {"main.frag", "common/lighting.glsl"};
    // Mesa, NVIDIA and glslang log formats.
    const std::string mapped = pre.mapLog(
        "1:12(5): error: `foo' undeclared\n0(7) : error C1008: undefined variable\n"
        "ERROR: 1:3: 'x' : syntax error\n9:1(1): error: unknown id stays\n");
    EXPECT_NE(mapped.find("common/lighting.glsl:12(5): error: `foo' undeclared"), std::string::npos)
        << mapped;
    EXPECT_NE(mapped.find("main.frag(7) : error C1008"), std::string::npos) << mapped;
    EXPECT_NE(mapped.find("ERROR: common/lighting.glsl:3: 'x'"), std::string::npos) << mapped;
    EXPECT_NE(mapped.find("9:1(1): error: unknown id stays"), std::string::npos) << mapped;
}

TEST(ShaderLibrary, EmbeddedAndEnvironmentOverride) {
    const auto files = ShaderLibrary::embeddedFiles();
    EXPECT_NE(std::find(files.begin(), files.end(), "direct_shade.frag"), files.end());
    EXPECT_NE(std::find(files.begin(), files.end(), "shared/LightingShared.h"), files.end());
    const std::string dir = makeShaderDir("override", {{"direct_shade.frag", "// live edit\n"}});
    ::setenv("LUCENT_SHADER_DIR", dir.c_str(), 1);
    const ShaderLibrary live;
    ::unsetenv("LUCENT_SHADER_DIR");
    EXPECT_EQ(live.read("direct_shade.frag"), "// live edit\n");
    EXPECT_EQ(live.origin(), dir);
    const ShaderLibrary embedded;
    EXPECT_NE(embedded.read("direct_shade.frag").find("#version 450"), std::string::npos);
    ShaderLibrary mem;
    mem.setFile("direct_shade.frag", "// in memory\n");
    EXPECT_EQ(mem.read("direct_shade.frag"), "// in memory\n");
}

TEST(GlProgram, CompileErrorReportsIncludedFileAndLine) {
    LUCENT_REQUIRE_GL();
    const std::string dir = makeShaderDir(
        "broken", {{"main.comp", MAIN_COMP},
                   {"common/a.glsl",
                    "#pragma once\n#include \"b.glsl\"\nfloat helperA() { return helperB(); }\n"},
                   {"common/b.glsl",
                    "#pragma once\n"               // 1
                    "float helperB() {\n"          // 2
                    "    return undefinedName;\n"  // 3  <- error here
                    "}\n"}});
    try {
        (void)GlProgram::compute(ShaderLibrary(dir), "main.comp");
        FAIL() << "the broken shader compiled";
    } catch (const GpuError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("main.comp"), std::string::npos) << msg;
        // Mesa: "common/b.glsl:3(12): error"; NVIDIA: "common/b.glsl(3) : error".
        const bool mapped = msg.find("common/b.glsl:3") != std::string::npos ||
                            msg.find("common/b.glsl(3)") != std::string::npos;
        EXPECT_TRUE(mapped) << msg;
    }
    // An error in the stage file itself maps to the stage file's own line.
    const std::string dir2 = makeShaderDir(
        "broken2", {{"main.comp",
                     "#version 450 core\n#include \"ok.glsl\"\nlayout(local_size_x = 1) in;\n"
                     "void main() {\n  int y = ;\n}\n"},
                    {"ok.glsl", "const int OK = 1;\n"}});
    try {
        (void)GlProgram::compute(ShaderLibrary(dir2), "main.comp");
        FAIL();
    } catch (const GpuError& e) {
        const std::string msg = e.what();
        EXPECT_TRUE(msg.find("main.comp:5") != std::string::npos ||
                    msg.find("main.comp(5)") != std::string::npos)
            << msg;
    }
    test::sharedGlContext()->debugLog().takeErrors();
}

TEST(GlProgram, EveryEmbeddedStageCompiles) {
    LUCENT_REQUIRE_GL();
    const ShaderLibrary lib;
    int stages = 0;
    for (const std::string& path : ShaderLibrary::embeddedFiles()) {
        const std::string ext = fs::path(path).extension().string();
        GLenum type = 0;
        if (ext == ".vert")
            type = GL_VERTEX_SHADER;
        if (ext == ".frag")
            type = GL_FRAGMENT_SHADER;
        if (ext == ".geom")
            type = GL_GEOMETRY_SHADER;
        if (ext == ".comp")
            type = GL_COMPUTE_SHADER;
        if (!type)
            continue;
        const PreprocessedShader pre = preprocessShader(lib, path);
        bool ok = false;
        const std::string log = test::compileStage(type, pre.source, ok);
        EXPECT_TRUE(ok) << path << ":\n" << pre.mapLog(log);
        if (ok && !log.empty())  // compiled with diagnostics (warnings): shown, not a failure
            std::printf("[ info ] %s compiles with:\n%s", path.c_str(), pre.mapLog(log).c_str());
        ++stages;
    }
    EXPECT_GE(stages, 6);
    // Leave the shared context's log empty: the compiler's diagnostics reach it as messages
    // (errors, when a stage failed, are reported above).
    test::drainGlDebugLog();
}

TEST(GlProgram, SharedStructLayoutsMatchGlsl) {
    LUCENT_REQUIRE_GL();
    GlProgram prog =
        GlProgram::graphics(ShaderLibrary(), "post_fullscreen.vert", "direct_shade.frag");
    auto blockSize = [&](GLenum iface, const char* name) {
        const GLuint index = glGetProgramResourceIndex(prog.id(), iface, name);
        EXPECT_NE(index, GL_INVALID_INDEX) << name;
        const GLenum prop = GL_BUFFER_DATA_SIZE;
        GLint size = -1;
        glGetProgramResourceiv(prog.id(), iface, index, 1, &prop, 1, nullptr, &size);
        return size;
    };
    // std140 UBO: its size must equal the C++ mirror.
    EXPECT_EQ(blockSize(GL_UNIFORM_BLOCK, "FrameBlock"), GLint(sizeof(shared::FrameUniforms)));
    // std430 SSBO of runtime-sized arrays: the minimum size is one element.
    EXPECT_EQ(blockSize(GL_SHADER_STORAGE_BLOCK, "LightBlock"), GLint(sizeof(shared::GpuLight)));
    EXPECT_EQ(blockSize(GL_SHADER_STORAGE_BLOCK, "ShadowLayerBlock"),
              GLint(sizeof(shared::GpuShadowLayer)));
    EXPECT_EQ(blockSize(GL_SHADER_STORAGE_BLOCK, "SurfaceBlock"),
              GLint(sizeof(shared::GpuSurface)));
    prog.destroy();
}

// gpu::dispatchLine folds a line of work groups longer than one dispatch dimension allows
// (65535 on llvmpipe) into x and z, and common/dispatch.glsl's lineGroup() unfolds it: every
// entry of a list of 64 × (65535 + 100) is visited exactly once (the folded dispatch's spare
// groups beyond the line do nothing), and a short line is one plain dispatch.
TEST(GlProgram, DispatchLineVisitsALongListOnce) {
    LUCENT_REQUIRE_GL();
    ShaderLibrary library;  // the embedded common/dispatch.glsl
    library.setFile("test_line.comp",
                    "#version 450 core\n"
                    "#include \"common/dispatch.glsl\"\n"
                    "layout(local_size_x = 64) in;\n"
                    "layout(std430, binding = 0) buffer Hits { uint b_hits[]; };\n"
                    "uniform uint u_count;\n"
                    "void main() {\n"
                    "    uint i = lineGroup() * 64u + gl_LocalInvocationIndex;\n"
                    "    if (i < u_count) atomicAdd(b_hits[i], 1u);\n"
                    "}\n");
    GlProgram prog = GlProgram::compute(library, "test_line.comp");
    for (const unsigned groups : {MAX_DISPATCH_GROUPS + 100u, 3u}) {
        SCOPED_TRACE(std::to_string(groups) + " groups");
        const unsigned count = groups * 64u - 5u;
        std::vector<uint32_t> hits(count, 0u);
        GlObject buffer = createBuffer(hits.size() * sizeof(uint32_t), hits.data(),
                                       GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
        glUseProgram(prog.id());
        glUniform1ui(prog.uniformLocation("u_count"), count);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffer.id());
        dispatchLine(groups);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));
        glGetNamedBufferSubData(buffer.id(), 0, GLsizeiptr(hits.size() * sizeof(uint32_t)),
                                hits.data());
        size_t wrong = 0;
        for (const uint32_t h : hits)
            wrong += h != 1u;
        EXPECT_EQ(wrong, 0u);
        buffer.destroy();
    }
    glUseProgram(0);
    prog.destroy();
}

namespace {
/// Runs a shell command, returns (exit status, stdout+stderr).
std::pair<int, std::string> runCommand(const std::string& cmd) {
    std::string out;
    FILE* pipe = ::popen((cmd + " 2>&1").c_str(), "r");
    if (!pipe)
        return {-1, out};
    char buf[512];
    while (std::fgets(buf, sizeof(buf), pipe))
        out += buf;
    const int status = ::pclose(pipe);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}
}  // namespace

TEST(ShaderValidation, GlslangReportsOriginalFileAndLine) {
    const std::string validator = LUCENT_GLSLANG_VALIDATOR;
    if (validator.empty() || validator.find("NOTFOUND") != std::string::npos ||
        !std::filesystem::exists(validator))
        GTEST_SKIP() << "glslangValidator not installed (package glslang-tools)";
    const std::string dir = makeShaderDir(
        "validate", {{"good.comp", MAIN_COMP},
                     {"common/a.glsl",
                      "#pragma once\n#include \"b.glsl\"\nfloat helperA() { return helperB(); }\n"},
                     {"common/b.glsl", "#pragma once\nfloat helperB() { return 2.0; }\n"},
                     {"bad.frag",
                      "#version 450 core\n#include \"common/c.glsl\"\nout vec4 o;\n"
                      "void main() { o = vec4(c()); }\n"},
                     {"common/c.glsl", "float c() {\n  return 1.0 +;\n}\n"}});
    const std::string tool = LUCENT_SHADER_PREPROCESS;
    const std::string outDir = dir + "/out";
    auto validate = [&](const std::string& name) {
        const auto [rc, log] = runCommand(tool + " --root " + dir + " --validate --output " +
                                          outDir + "/" + name + " " + name);
        EXPECT_EQ(rc, 0) << log;
        return runCommand(validator + " " + outDir + "/" + name);
    };
    const auto [goodRc, goodLog] = validate("good.comp");
    EXPECT_EQ(goodRc, 0) << goodLog;
    const auto [badRc, badLog] = validate("bad.frag");
    EXPECT_NE(badRc, 0);
    EXPECT_NE(badLog.find("common/c.glsl:2"), std::string::npos) << badLog;
    // A missing include fails in the preprocessor with the including file and line.
    const auto [missRc, missLog] =
        runCommand(tool + " --root " + dir + " --validate --output " + outDir + "/x.comp x.comp");
    EXPECT_NE(missRc, 0) << missLog;
}
