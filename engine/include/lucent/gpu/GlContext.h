// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Headless OpenGL 4.5 core contexts through EGL (no X, no window), and the KHR_debug
/// message log that works in any current context (ours or one made current by Qt).
///
/// Usage:
/// @code
///   auto ctx = lucent::gpu::GlContext::createHeadless();   // throws GpuError if impossible
///   ctx->makeCurrent();
///   std::cout << ctx->renderer();                           // "llvmpipe (LLVM 15.0.6, 256 bits)"
///   ... GL calls (through libepoxy) ...
///   for (auto& m : ctx->debugLog().takeErrors()) std::cerr << m << '\n';
/// @endcode
/// The engine's GL code only needs *a* current 4.5 core context: epoxy resolves functions
/// against whatever context is current, so the same renderers run inside a QOpenGLWidget.

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace lucent::gpu {

/// Collects KHR_debug messages of the context that was current when install() was called.
/// Errors (GL_DEBUG_TYPE_ERROR, or high severity) are kept apart from other messages.
class GlDebugLog {
public:
    GlDebugLog() = default;
    GlDebugLog(const GlDebugLog&) = delete;
    GlDebugLog& operator=(const GlDebugLog&) = delete;
    ~GlDebugLog() = default;

    /// Installs the debug callback (glDebugMessageCallback) on the current context and enables
    /// synchronous output. Precondition: a GL 4.3+ context is current; the log must outlive it
    /// or uninstall() must be called while it is current.
    void install();
    /// Removes the callback from the current context.
    void uninstall();
    /// Whether install() succeeded (the context supports KHR_debug).
    [[nodiscard]] bool isInstalled() const { return m_installed; }

    /// Returns and clears the collected error messages ("GL error [api] id 1282: ..."): the
    /// messages of type GL_DEBUG_TYPE_ERROR or GL_DEBUG_TYPE_UNDEFINED_BEHAVIOR, whatever their
    /// severity (shader compiler warnings, which Mesa sends with high severity, are not errors).
    std::vector<std::string> takeErrors();
    /// Returns and clears the other messages (warnings, performance, notifications excluded).
    std::vector<std::string> takeMessages();

    /// Called by the GL callback; public only for the C trampoline.
    void record(unsigned source, unsigned type, unsigned id, unsigned severity,
                const char* message);

private:
    std::mutex m_mutex;
    std::vector<std::string> m_errors;
    std::vector<std::string> m_messages;
    bool m_installed = false;
};

/// Options for a headless context.
struct GlContextOptions {
    /// EGL platform: "auto" tries EGL_MESA_platform_surfaceless, then EGL_EXT_platform_device
    /// (first device that yields a 4.5 core context), then the default display.
    /// Also "surfaceless" or "device". The environment variable LUCENT_EGL_PLATFORM overrides.
    std::string platform = "auto";
    bool debug = true;  ///< request a debug context and install the KHR_debug log
};

/// A headless EGL OpenGL 4.5 core-profile context (surfaceless make-current). Move-free:
/// owned through std::unique_ptr. Destroying it releases the context (never while another
/// thread has it current).
class GlContext {
public:
    /// Creates the context and makes it current on the calling thread.
    /// @throw GpuError with the reason (no EGL display, no 4.5 core context, ...).
    static std::unique_ptr<GlContext> createHeadless(const GlContextOptions& options = {});

    /// Whether a headless context can be created here; on failure `reason` says why. Cheap
    /// after the first call (the answer is cached). Used by tests to GTEST_SKIP cleanly. The
    /// calling thread's current EGL context, if any, is current again on return.
    static bool isHeadlessAvailable(std::string* reason = nullptr);

    ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    /// Makes this context current on the calling thread. @throw GpuError on failure.
    void makeCurrent();
    /// Releases the calling thread's current context.
    void doneCurrent();

    /// GL_RENDERER, GL_VENDOR, GL_VERSION strings of this context.
    [[nodiscard]] const std::string& renderer() const { return m_renderer; }
    [[nodiscard]] const std::string& vendor() const { return m_vendor; }
    [[nodiscard]] const std::string& version() const { return m_version; }
    /// The EGL platform actually used ("surfaceless", "device", "default").
    [[nodiscard]] const std::string& platform() const { return m_platform; }

    /// The debug log (installed when options.debug was set and KHR_debug is present).
    GlDebugLog& debugLog() { return *m_debugLog; }

private:
    GlContext() = default;
    struct Egl;
    std::unique_ptr<Egl> m_egl;
    std::unique_ptr<GlDebugLog> m_debugLog;
    std::string m_renderer;
    std::string m_vendor;
    std::string m_version;
    std::string m_platform;
};

/// Throws GpuError naming `where` if glGetError() reports an error (drains all pending errors).
void checkGlError(const char* where);

}  // namespace lucent::gpu
