// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Shared headless GL context for the gpu tests: created once per process; tests call
/// LUCENT_REQUIRE_GL() first, which GTEST_SKIPs with EGL's reason when no context can be made.

#include <lucent/gpu/GlContext.h>

#include <gtest/gtest.h>

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

}  // namespace lucent::gpu::test

/// Skips the current test, with EGL's reason, when no headless 4.5 context exists here.
#define LUCENT_REQUIRE_GL()                                                              \
    do {                                                                                 \
        std::string lucentGlReason_;                                                     \
        if (!::lucent::gpu::test::sharedContext(&lucentGlReason_))                       \
            GTEST_SKIP() << "no headless OpenGL 4.5 context (EGL): " << lucentGlReason_; \
    } while (false)
