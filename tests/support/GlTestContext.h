// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The one headless-GL fixture of the test suite (tests/support/, on every test's include
/// path). Two kinds of context:
/// - sharedGlContext(): one per process, made current on each call; for tests whose GL state
///   does not outlive them (they delete what they create). LUCENT_REQUIRE_GL() skips without it.
/// - ownGlContext(): a fresh context for one test or fixture, for tests that judge state a
///   shared context would carry over (object names, debug-log contents, allocation limits).
/// Without EGL (no libEGL, no render node, no 4.5 core profile) both return nullptr and give
/// EGL's reason; the tests then GTEST_SKIP with it, so the suite runs on a machine without GL.

#include <lucent/gpu/GlContext.h>

#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>
#include <string>

namespace lucent::test {

/// The process-wide test context, current on this thread; nullptr when none can be made
/// (`reason` then says why).
inline gpu::GlContext* sharedGlContext(std::string* reason = nullptr) {
    static std::string why;
    static std::unique_ptr<gpu::GlContext> ctx = [] {
        try {
            return gpu::GlContext::createHeadless();
        } catch (const std::exception& e) {
            why = e.what();
            return std::unique_ptr<gpu::GlContext>();
        }
    }();
    if (reason)
        *reason = why;
    if (ctx)
        ctx->makeCurrent();
    return ctx.get();
}

/// A new headless context, current on this thread, owned by the caller; nullptr when none can be
/// made (`reason` then says why).
inline std::unique_ptr<gpu::GlContext> ownGlContext(std::string& reason) {
    if (!gpu::GlContext::isHeadlessAvailable(&reason))
        return nullptr;
    return gpu::GlContext::createHeadless();
}

/// Empties the shared context's debug log (errors and messages), e.g. before a test whose own GL
/// calls are then judged by the log, or after one that provoked diagnostics on purpose.
inline void drainGlDebugLog() {
    if (gpu::GlContext* ctx = sharedGlContext()) {
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

}  // namespace lucent::test

/// Skips the current test, with EGL's reason, when no headless 4.5 context exists here; the
/// shared context is current afterwards.
#define LUCENT_REQUIRE_GL()                                                              \
    do {                                                                                 \
        std::string lucentGlReason_;                                                     \
        if (!::lucent::test::sharedGlContext(&lucentGlReason_))                          \
            GTEST_SKIP() << "no headless OpenGL 4.5 context (EGL): " << lucentGlReason_; \
    } while (false)

/// Declares `std::unique_ptr<gpu::GlContext> var`, a context of the test's own, or skips the
/// current test with EGL's reason.
#define LUCENT_OWN_GL_CONTEXT(var)                                                              \
    std::string var##Reason_;                                                                   \
    std::unique_ptr<::lucent::gpu::GlContext> var = ::lucent::test::ownGlContext(var##Reason_); \
    if (!var)                                                                                   \
    GTEST_SKIP() << "no headless OpenGL 4.5 context (EGL): " << var##Reason_
