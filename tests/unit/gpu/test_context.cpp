// SPDX-License-Identifier: MIT
/// @file
/// @brief Headless EGL context, KHR_debug log, resources, timers.

#include "GlTestContext.h"

#include <lucent/core/Error.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/GpuTimer.h>

#include <epoxy/gl.h>

#include <random>
#include <thread>

using namespace lucent;
using namespace lucent::gpu;

TEST(GlContext, CreatesHeadless45CoreContext) {
    LUCENT_REQUIRE_GL();
    GlContext* ctx = test::sharedGlContext();
    EXPECT_FALSE(ctx->renderer().empty());
    EXPECT_GE(epoxy_gl_version(), 45) << ctx->version();
    GLint profile = 0;
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
    std::printf("[ info ] GL_RENDERER = %s, GL_VERSION = %s, EGL platform = %s\n",
                ctx->renderer().c_str(), ctx->version().c_str(), ctx->platform().c_str());
}

TEST(GlContext, RejectsUnknownPlatform) {
    GlContextOptions opts;
    opts.platform = "wayland-please";
    if (std::getenv("LUCENT_EGL_PLATFORM"))
        GTEST_SKIP() << "LUCENT_EGL_PLATFORM overrides";
    EXPECT_THROW(GlContext::createHeadless(opts), ValueError);
}

TEST(GlContext, DebugLogCollectsErrors) {
    LUCENT_REQUIRE_GL();
    GlContext* ctx = test::sharedGlContext();
    if (!ctx->debugLog().isInstalled())
        GTEST_SKIP() << "KHR_debug not available";
    ctx->debugLog().takeErrors();
    glBindBuffer(GL_ARRAY_BUFFER, 987654u);  // not a buffer name: GL_INVALID_OPERATION
    const auto errors = ctx->debugLog().takeErrors();
    ASSERT_FALSE(errors.empty());
    EXPECT_NE(errors.front().find("GL error"), std::string::npos) << errors.front();
    while (glGetError() != GL_NO_ERROR) {
    }
    EXPECT_TRUE(ctx->debugLog().takeErrors().empty());  // take clears
}

TEST(GlContext, DebugLogKeepsCompilerWarningsOutOfErrors) {
    LUCENT_REQUIRE_GL();
    GlContext* ctx = test::sharedGlContext();
    if (!ctx->debugLog().isInstalled())
        GTEST_SKIP() << "KHR_debug not available";
    test::drainGlDebugLog();
    // Compiles, with a warning on Mesa ("`x' used uninitialized"), which Mesa sends through
    // KHR_debug with GL_DEBUG_SEVERITY_HIGH and type OTHER: a message, not an error. Mesa's
    // shader cache skips the compiler, and so its warnings, for a source it has seen before:
    // a random comment makes this source new on every run.
    const std::string source = "#version 450 core\n// run " +
                               std::to_string(std::random_device{}()) +
                               "\nlayout(local_size_x = 1) in;\n"
                               "layout(std430, binding = 0) buffer B { float v[]; };\n"
                               "void main() { float x; v[0] = x; }\n";
    bool ok = false;
    const std::string log = test::compileStage(GL_COMPUTE_SHADER, source, ok);
    ASSERT_TRUE(ok) << log;
    const auto errors = ctx->debugLog().takeErrors();
    EXPECT_TRUE(errors.empty()) << errors.front();
    // (Whether a driver also sends the warning as a message is its choice: not checked.)
    test::drainGlDebugLog();
}

TEST(GlContext, CheckGlErrorThrowsWithLocation) {
    LUCENT_REQUIRE_GL();
    glEnable(0x1234);  // invalid enum
    try {
        checkGlError("test-site");
        FAIL() << "expected GpuError";
    } catch (const GpuError& e) {
        EXPECT_NE(std::string(e.what()).find("test-site"), std::string::npos);
    }
    test::sharedGlContext()->debugLog().takeErrors();
}

TEST(GlContext, SecondContextOnAnotherThread) {
    LUCENT_REQUIRE_GL();
    std::string renderer;
    std::string error;
    std::thread worker([&] {
        try {
            auto ctx = GlContext::createHeadless();
            renderer = ctx->renderer();
        } catch (const std::exception& e) {
            error = e.what();
        }
    });
    worker.join();
    EXPECT_TRUE(error.empty()) << error;
    EXPECT_EQ(renderer, test::sharedGlContext()->renderer());
}

TEST(GlContext, AvailabilityProbeKeepsTheCurrentContext) {
    LUCENT_REQUIRE_GL();
    // The probe creates and destroys a context of its own; first call in this process (nothing
    // else in test_gpu probes), so it really runs here. The shared context must stay current:
    // a GL object created before the probe is still a live name of the current context after.
    GlObject buf = createBuffer(16, nullptr, GL_DYNAMIC_STORAGE_BIT);
    std::string reason;
    EXPECT_TRUE(GlContext::isHeadlessAvailable(&reason)) << reason;
    EXPECT_TRUE(glIsBuffer(buf.id()));
    buf.destroy();
    EXPECT_TRUE(test::sharedGlContext()->debugLog().takeErrors().empty());
}

TEST(GlResources, ExplicitDestroyAndLeakAccounting) {
    LUCENT_REQUIRE_GL();
    const size_t live0 = liveGlObjectCount();
    const size_t leaked0 = leakedGlObjectCount();
    {
        const float data[4] = {1.f, 2.f, 3.f, 4.f};
        GlObject buf = createBuffer(sizeof(data), data, GL_DYNAMIC_STORAGE_BIT);
        GlObject tex = createTexture2D(GL_RGBA32F, 8, 4);
        EXPECT_TRUE(glIsBuffer(buf.id()));
        EXPECT_EQ(liveGlObjectCount(), live0 + 2);
        float back[4] = {};
        glGetNamedBufferSubData(buf.id(), 0, sizeof(back), back);
        EXPECT_EQ(back[2], 3.f);
        GlObject moved = std::move(buf);
        EXPECT_FALSE(buf.isValid());
        moved.destroy();
        moved.destroy();  // idempotent
        tex.destroy();
    }
    EXPECT_EQ(liveGlObjectCount(), live0);
    EXPECT_EQ(leakedGlObjectCount(), leaked0);
    { GlObject forgotten = createTexture2D(GL_R8, 2, 2); }  // destructor: no GL call, counted
    EXPECT_EQ(leakedGlObjectCount(), leaked0 + 1);
    EXPECT_THROW(createTexture2D(GL_RGBA8, 0, 4), ValueError);
}

TEST(GpuProfiler, TimesNestedPasses) {
    LUCENT_REQUIRE_GL();
    GpuProfiler prof;
    GlObject tex = createTexture2D(GL_RGBA32F, 512, 512);
    GlObject fbo = GlObject::create(GlObjectKind::Framebuffer);
    glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT0, tex.id(), 0);
    prof.beginFrame();
    {
        auto outer = prof.scope("outer");
        for (int i = 0; i < 20; ++i) {
            auto inner = prof.scope("clear");
            const float c[4] = {float(i), 0.f, 0.f, 1.f};
            glClearNamedFramebufferfv(fbo.id(), GL_COLOR, 0, c);
        }
    }
    prof.endFrame(/*wait=*/true);
    ASSERT_EQ(prof.latest().size(), 21u);
    const PassTiming* outer = prof.find("outer");
    ASSERT_NE(outer, nullptr);
    EXPECT_EQ(outer->depth, 0);
    EXPECT_EQ(prof.latest()[1].depth, 1);
    double innerSum = 0.0;
    for (size_t i = 1; i < prof.latest().size(); ++i)
        innerSum += prof.latest()[i].gpuMs;
    EXPECT_GE(outer->gpuMs, 0.0);
    // Timestamps are monotonic: the outer interval contains every inner one.
    EXPECT_GE(outer->gpuMs + 1e-3, innerSum);
    EXPECT_GE(outer->cpuMs, 0.0);
    EXPECT_THROW(prof.end(), ValueError);
    prof.destroy();
    fbo.destroy();
    tex.destroy();
}
