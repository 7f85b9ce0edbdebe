// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Shader sources and programs: the shader library (files embedded at build time, or a
/// directory on disk for live editing), the `#include "..."` preprocessor with line mapping,
/// and GlProgram (compile/link with errors reported as FILE:LINE).
///
/// Usage:
/// @code
///   lucent::gpu::ShaderLibrary lib;      // embedded shaders/, or $LUCENT_SHADER_DIR if set
///   auto prog = lucent::gpu::GlProgram::compute(lib, "sslpv_propagate.comp", {"LOCAL_SIZE=8"});
///   glUseProgram(prog.id());  ...  prog.destroy();   // explicit, with the context current
/// @endcode
/// Preprocessing rules (docs/gpu.md): `#include "path"` resolves relative to the including file,
/// then to the library root; `#pragma once` includes a file once; blocks under
/// `#ifdef __cplusplus` (or `#if defined(__cplusplus)`) are dropped and their `#else` branch
/// kept, so shaders/shared/*.h headers compile as C++ and GLSL. Included text is wrapped in
/// `#line` directives so compiler logs map back to the original file and line.

#include <map>
#include <string>
#include <vector>

namespace lucent::gpu {

/// Read-only set of shader files addressed by paths relative to the shader root
/// ("common/lighting.glsl", "mesh_gbuffer.vert").
class ShaderLibrary {
public:
    /// The embedded shaders, unless the environment variable LUCENT_SHADER_DIR names a
    /// directory, in which case files are read from there at each load (live editing).
    ShaderLibrary();
    /// Files read from `directory` (no embedded fallback). @throw IoError if it is not a directory.
    explicit ShaderLibrary(const std::string& directory);

    /// Adds or replaces an in-memory file (takes precedence over disk and embedded files).
    void setFile(const std::string& path, const std::string& text);

    /// Text of `path`. @throw IoError naming the path (and the directory searched) when absent.
    [[nodiscard]] std::string read(const std::string& path) const;
    [[nodiscard]] bool exists(const std::string& path) const;
    /// Where files come from: "embedded" or the directory.
    [[nodiscard]] std::string origin() const;
    /// Every embedded shader path (sorted); empty when reading from a directory.
    [[nodiscard]] static std::vector<std::string> embeddedFiles();

private:
    std::string m_directory;  ///< empty: embedded
    std::map<std::string, std::string> m_memory;
};

/// How included files are marked in the preprocessed text.
enum class LineDirectives {
    Numeric,   ///< `#line N id` (core GLSL); logs map back through PreprocessedShader::files
    CppStyle,  ///< `#line N "path"` with GL_GOOGLE_cpp_style_line_directive (glslangValidator)
};

/// Result of preprocessing one stage file.
struct PreprocessedShader {
    std::string source;              ///< text to hand to glShaderSource
    std::vector<std::string> files;  ///< source-string id → path (0 is the stage file)

    /// Rewrites compiler log locations "ID:LINE" / "ID(LINE)" (Mesa, NVIDIA, glslang forms)
    /// into "path:LINE" / "path(LINE)".
    [[nodiscard]] std::string mapLog(const std::string& log) const;
};

/// Resolves includes of `path`. `defines` ("NAME" or "NAME=VALUE") are inserted after the
/// `#version` line. @throw IoError for a missing file (naming the including file and line),
/// ValueError for an include cycle, a missing #version or an unsupported `#elif` on __cplusplus.
PreprocessedShader preprocessShader(const ShaderLibrary& library, const std::string& path,
                                    const std::vector<std::string>& defines = {},
                                    LineDirectives style = LineDirectives::Numeric);

/// A linked GL program. Move-only; created and destroyed explicitly with a current context (the
/// destructor makes no GL call: a program still alive there is counted as leaked, see
/// gpu/GlResources.h liveGlObjectCount()).
class GlProgram {
public:
    GlProgram() = default;
    GlProgram(GlProgram&& other) noexcept;
    GlProgram& operator=(GlProgram&& other) noexcept;
    GlProgram(const GlProgram&) = delete;
    GlProgram& operator=(const GlProgram&) = delete;
    ~GlProgram();

    /// Vertex + fragment program. @throw GpuError "<file>:<line>: error ..." on compile/link
    /// errors.
    static GlProgram graphics(const ShaderLibrary& library, const std::string& vertexPath,
                              const std::string& fragmentPath,
                              const std::vector<std::string>& defines = {});
    /// Compute program. @throw GpuError with mapped file and line on compile/link errors.
    static GlProgram compute(const ShaderLibrary& library, const std::string& computePath,
                             const std::vector<std::string>& defines = {});

    [[nodiscard]] unsigned id() const { return m_id; }
    [[nodiscard]] bool isValid() const { return m_id != 0; }
    /// Uniform location, -1 when the uniform is absent or optimised away.
    [[nodiscard]] int uniformLocation(const char* name) const;
    /// Deletes the program (context current). Idempotent.
    void destroy();

private:
    unsigned m_id = 0;
    std::string m_name;
};

}  // namespace lucent::gpu
