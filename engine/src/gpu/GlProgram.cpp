// SPDX-License-Identifier: MIT
/// @file
/// @brief GlProgram: compile and link preprocessed shaders; logs mapped to FILE:LINE.

#include <lucent/core/Error.h>
#include <lucent/gpu/Shader.h>

#include "GlObjectCount.h"

#include <epoxy/gl.h>

#include <utility>

namespace lucent::gpu {

namespace {

std::string shaderLog(GLuint shader) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, GLsizei(log.size()), nullptr, log.data());
    log.resize(std::char_traits<char>::length(log.c_str()));
    return log;
}

std::string programLog(GLuint program) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program, GLsizei(log.size()), nullptr, log.data());
    log.resize(std::char_traits<char>::length(log.c_str()));
    return log;
}

GLuint compileStage(const ShaderLibrary& library, GLenum stage, const std::string& path,
                    const std::vector<std::string>& defines) {
    const PreprocessedShader pre = preprocessShader(library, path, defines);
    GLuint shader = glCreateShader(stage);
    if (!shader)
        LUCENT_THROW(GpuError, "glCreateShader failed for '", path, "'");
    const char* text = pre.source.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        const std::string log = pre.mapLog(shaderLog(shader));
        glDeleteShader(shader);
        LUCENT_THROW(GpuError, "shader '", path, "' (from ", library.origin(),
                     ") failed to compile:\n", log);
    }
    return shader;
}

GLuint linkProgram(const std::vector<GLuint>& shaders, const std::string& name) {
    GLuint program = glCreateProgram();
    for (GLuint s : shaders)
        glAttachShader(program, s);
    glLinkProgram(program);
    for (GLuint s : shaders) {
        glDetachShader(program, s);
        glDeleteShader(s);
    }
    GLint ok = GL_FALSE;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        const std::string log = programLog(program);
        glDeleteProgram(program);
        LUCENT_THROW(GpuError, "program '", name, "' failed to link:\n", log);
    }
    return program;
}

}  // namespace

GlProgram::GlProgram(GlProgram&& other) noexcept
    : m_id(std::exchange(other.m_id, 0u)), m_name(std::move(other.m_name)) {}

GlProgram& GlProgram::operator=(GlProgram&& other) noexcept {
    if (this != &other) {
        if (m_id)
            detail::countLeaked();
        m_id = std::exchange(other.m_id, 0u);
        m_name = std::move(other.m_name);
    }
    return *this;
}

GlProgram::~GlProgram() {
    if (m_id)
        detail::countLeaked();  // no GL call without a known-current context
}

GlProgram GlProgram::graphics(const ShaderLibrary& library, const std::string& vertexPath,
                              const std::string& fragmentPath,
                              const std::vector<std::string>& defines) {
    GLuint vs = compileStage(library, GL_VERTEX_SHADER, vertexPath, defines);
    GLuint fs = 0;
    try {
        fs = compileStage(library, GL_FRAGMENT_SHADER, fragmentPath, defines);
    } catch (...) {
        glDeleteShader(vs);
        throw;
    }
    GlProgram p;
    p.m_name = vertexPath + " + " + fragmentPath;
    p.m_id = linkProgram({vs, fs}, p.m_name);
    detail::countCreated();
    return p;
}

GlProgram GlProgram::compute(const ShaderLibrary& library, const std::string& computePath,
                             const std::vector<std::string>& defines) {
    GLuint cs = compileStage(library, GL_COMPUTE_SHADER, computePath, defines);
    GlProgram p;
    p.m_name = computePath;
    p.m_id = linkProgram({cs}, p.m_name);
    detail::countCreated();
    return p;
}

int GlProgram::uniformLocation(const char* name) const {
    return m_id ? glGetUniformLocation(m_id, name) : -1;
}

void GlProgram::destroy() {
    if (!m_id)
        return;
    glDeleteProgram(m_id);
    m_id = 0;
    detail::countDestroyed();
}

}  // namespace lucent::gpu
