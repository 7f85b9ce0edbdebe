// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Shared headless GL context for the gpu tests: created once per process; tests call
/// LUCENT_REQUIRE_GL() first, which GTEST_SKIPs with EGL's reason when no context can be made.

#include <lucent/gpu/GlContext.h>

#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>

namespace lucent::gpu::test {

/// The process-wide test context (nullptr when unavailable; `reason` then says why).
inline GlContext* sharedContext(std::string* reason = nullptr) {
    static std::string why;
    static std::unique_ptr<GlContext> ctx = [] {
        try {
            return GlContext::createHeadless();
        } catch (const std::exception& e) {
            why = e.what();
            return std::unique_ptr<GlContext>();
        }
    }();
    if (reason)
        *reason = why;
    if (ctx)
        ctx->makeCurrent();
    return ctx.get();
}

/// Empties the shared context's debug log (errors and messages), e.g. before a test whose own GL
/// calls are then judged by the log, or after one that provoked diagnostics on purpose.
inline void drainDebugLog() {
    if (GlContext* ctx = sharedContext()) {
        ctx->debugLog().takeErrors();
        ctx->debugLog().takeMessages();
    }
}

/// Compiles `source` as a shader stage of `type` (GL_COMPUTE_SHADER...) in the current context,
/// deletes it, and returns its info log; `ok` receives GL_COMPILE_STATUS.
inline std::string compileStage(unsigned type, const std::string& source, bool& ok) {
    const GLuint sh = glCreateShader(type);
    const char* text = source.c_str();
    glShaderSource(sh, 1, &text, nullptr);
    glCompileShader(sh);
    GLint status = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &status);
    GLint length = 0;
    glGetShaderiv(sh, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetShaderInfoLog(sh, GLsizei(log.size()), nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    glDeleteShader(sh);
    ok = status != 0;
    return log;
}

}  // namespace lucent::gpu::test

/// Skips the current test, with EGL's reason, when no headless 4.5 context exists here.
#define LUCENT_REQUIRE_GL()                                                              \
    do {                                                                                 \
        std::string lucentGlReason_;                                                     \
        if (!::lucent::gpu::test::sharedContext(&lucentGlReason_))                       \
            GTEST_SKIP() << "no headless OpenGL 4.5 context (EGL): " << lucentGlReason_; \
    } while (false)
