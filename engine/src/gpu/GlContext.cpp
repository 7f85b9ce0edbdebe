// SPDX-License-Identifier: MIT
/// @file
/// @brief EGL headless context (the only EGL code of the engine) and the KHR_debug log.

#include <lucent/core/Error.h>
#include <lucent/gpu/GlContext.h>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <cstdlib>
#include <cstring>
#include <sstream>
#include <utility>

namespace lucent::gpu {

// ---------------------------------------------------------------------------------------------
// GlDebugLog

namespace {

void GLAPIENTRY debugTrampoline(GLenum source, GLenum type, GLuint id, GLenum severity,
                                GLsizei /*length*/, const GLchar* message, const void* user) {
    static_cast<GlDebugLog*>(const_cast<void*>(user))->record(source, type, id, severity, message);
}

const char* sourceName(unsigned source) {
    switch (source) {
        case GL_DEBUG_SOURCE_API:
            return "api";
        case GL_DEBUG_SOURCE_WINDOW_SYSTEM:
            return "window-system";
        case GL_DEBUG_SOURCE_SHADER_COMPILER:
            return "shader-compiler";
        case GL_DEBUG_SOURCE_THIRD_PARTY:
            return "third-party";
        case GL_DEBUG_SOURCE_APPLICATION:
            return "application";
        default:
            return "other";
    }
}

}  // namespace

void GlDebugLog::install() {
    if (!epoxy_has_gl_extension("GL_KHR_debug") && epoxy_gl_version() < 43)
        return;
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(debugTrampoline, this);
    glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DONT_CARE, 0, nullptr, GL_TRUE);
    // Notifications (buffer placement hints...) are noise.
    glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DEBUG_SEVERITY_NOTIFICATION, 0, nullptr,
                          GL_FALSE);
    m_installed = true;
}

void GlDebugLog::uninstall() {
    if (!m_installed)
        return;
    glDebugMessageCallback(nullptr, nullptr);
    m_installed = false;
}

void GlDebugLog::record(unsigned source, unsigned type, unsigned id, unsigned severity,
                        const char* message) {
    std::ostringstream os;
    // Errors by type, not severity: Mesa reports every GLSL compiler diagnostic, warnings
    // ("`x' used uninitialized") included, with GL_DEBUG_SEVERITY_HIGH and type OTHER. Counting
    // those as errors made whichever test next checked the log fail for a warning in a shader
    // another test had compiled (RendererFixture.OccluderCastsShadowOnGround, session 2).
    (void)severity;
    const bool isError = type == GL_DEBUG_TYPE_ERROR || type == GL_DEBUG_TYPE_UNDEFINED_BEHAVIOR;
    os << (isError ? "GL error [" : "GL message [") << sourceName(source) << "] id " << id << ": "
       << (message ? message : "");
    std::lock_guard<std::mutex> lock(m_mutex);
    auto& list = isError ? m_errors : m_messages;
    if (list.size() < 1000)
        list.push_back(os.str());  // bounded: a per-frame error cannot flood
}

std::vector<std::string> GlDebugLog::takeErrors() {
    std::lock_guard<std::mutex> lock(m_mutex);
    return std::exchange(m_errors, {});
}

std::vector<std::string> GlDebugLog::takeMessages() {
    std::lock_guard<std::mutex> lock(m_mutex);
    return std::exchange(m_messages, {});
}

// ---------------------------------------------------------------------------------------------
// GlContext

struct GlContext::Egl {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
};

namespace {

std::string eglErrorString(EGLint e) {
    std::ostringstream os;
    os << "EGL error 0x" << std::hex << e;
    return os.str();
}

bool hasExtension(const char* list, const char* name) {
    if (!list)
        return false;
    const size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)); p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0'))
            return true;
    return false;
}

/// Tries to create a 4.5 core context on `display` (already initialised). Returns
/// EGL_NO_CONTEXT and sets `why` on failure.
EGLContext createCoreContext(EGLDisplay display, bool debug, std::string& why) {
    const char* ext = eglQueryString(display, EGL_EXTENSIONS);
    if (!hasExtension(ext, "EGL_KHR_surfaceless_context")) {
        why = "no EGL_KHR_surfaceless_context";
        return EGL_NO_CONTEXT;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        why = "eglBindAPI(EGL_OPENGL_API) failed";
        return EGL_NO_CONTEXT;
    }
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!hasExtension(ext, "EGL_KHR_no_config_context") &&
        !hasExtension(ext, "EGL_MESA_configless_context")) {
        const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLint count = 0;
        if (!eglChooseConfig(display, attribs, &config, 1, &count) || count < 1) {
            why = "no EGL config with EGL_OPENGL_BIT";
            return EGL_NO_CONTEXT;
        }
    }
    for (int attempt = 0; attempt < 2; ++attempt) {
        const bool withDebug = debug && attempt == 0;
        const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                  4,
                                  EGL_CONTEXT_MINOR_VERSION,
                                  5,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                  EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                  EGL_CONTEXT_OPENGL_DEBUG,
                                  withDebug ? EGL_TRUE : EGL_FALSE,
                                  EGL_NONE};
        EGLContext ctx = eglCreateContext(display, config, EGL_NO_CONTEXT, attribs);
        if (ctx != EGL_NO_CONTEXT)
            return ctx;
        why = "eglCreateContext(4.5 core) failed: " + eglErrorString(eglGetError());
    }
    return EGL_NO_CONTEXT;
}

struct Candidate {
    std::string platform;
    EGLDisplay display;
};

std::vector<Candidate> candidateDisplays(const std::string& wanted, std::string& why) {
    std::vector<Candidate> out;
    const char* clientExt = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    const bool platformBase = hasExtension(clientExt, "EGL_EXT_platform_base");
    if ((wanted == "auto" || wanted == "surfaceless") && platformBase &&
        hasExtension(clientExt, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay d =
            eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (d != EGL_NO_DISPLAY)
            out.push_back({"surfaceless", d});
    }
    if ((wanted == "auto" || wanted == "device") && platformBase &&
        hasExtension(clientExt, "EGL_EXT_platform_device") &&
        hasExtension(clientExt, "EGL_EXT_device_enumeration")) {
        EGLDeviceEXT devices[16];
        EGLint count = 0;
        if (eglQueryDevicesEXT(16, devices, &count)) {
            for (EGLint i = 0; i < count; ++i) {
                EGLDisplay d =
                    eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
                if (d != EGL_NO_DISPLAY)
                    out.push_back({"device", d});
            }
        }
    }
    if (wanted == "auto" || wanted == "default") {
        EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
        if (d != EGL_NO_DISPLAY)
            out.push_back({"default", d});
    }
    if (out.empty())
        why = "no EGL display for platform '" + wanted +
              "' (client extensions: " + (clientExt ? clientExt : "none") + ")";
    return out;
}

}  // namespace

std::unique_ptr<GlContext> GlContext::createHeadless(const GlContextOptions& options) {
    std::string platform = options.platform;
    if (const char* env = std::getenv("LUCENT_EGL_PLATFORM"); env && *env)
        platform = env;
    LUCENT_CHECK(platform == "auto" || platform == "surfaceless" || platform == "device" ||
                     platform == "default",
                 "EGL platform '", platform, "' is not one of auto, surfaceless, device, default");
    if (!epoxy_has_egl())
        LUCENT_THROW(GpuError, "cannot create an OpenGL context: libEGL is not available");

    std::string why;
    std::vector<Candidate> candidates = candidateDisplays(platform, why);
    std::vector<std::string> failures;
    for (const Candidate& c : candidates) {
        EGLint major = 0;
        EGLint minor = 0;
        if (!eglInitialize(c.display, &major, &minor)) {
            failures.push_back(c.platform + ": eglInitialize failed (" +
                               eglErrorString(eglGetError()) + ")");
            continue;
        }
        std::string reason;
        EGLContext ctx = createCoreContext(c.display, options.debug, reason);
        if (ctx == EGL_NO_CONTEXT) {
            failures.push_back(c.platform + ": " + reason);
            eglTerminate(c.display);
            continue;
        }
        if (!eglMakeCurrent(c.display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
            failures.push_back(c.platform + ": surfaceless eglMakeCurrent failed (" +
                               eglErrorString(eglGetError()) + ")");
            eglDestroyContext(c.display, ctx);
            eglTerminate(c.display);
            continue;
        }
        std::unique_ptr<GlContext> out(new GlContext());
        out->m_egl = std::make_unique<Egl>();
        out->m_egl->display = c.display;
        out->m_egl->context = ctx;
        out->m_platform = c.platform;
        auto str = [](GLenum name) {
            const GLubyte* s = glGetString(name);
            return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
        };
        out->m_renderer = str(GL_RENDERER);
        out->m_vendor = str(GL_VENDOR);
        out->m_version = str(GL_VERSION);
        out->m_debugLog = std::make_unique<GlDebugLog>();
        if (epoxy_gl_version() < 45) {
            const std::string v = out->m_version;
            out.reset();
            failures.push_back(c.platform + ": context version " + v + " < 4.5");
            continue;
        }
        if (options.debug)
            out->m_debugLog->install();
        return out;
    }
    std::ostringstream os;
    os << "cannot create a headless OpenGL 4.5 core context through EGL";
    if (!why.empty())
        os << ": " << why;
    for (const auto& f : failures)
        os << "; " << f;
    LUCENT_THROW(GpuError, os.str());
}

bool GlContext::isHeadlessAvailable(std::string* reason) {
    static int cached = -1;  // -1 unknown, 0 no, 1 yes
    static std::string cachedReason;
    if (cached < 0) {
        // The probe makes its context current and releases it: the caller's current EGL
        // context (e.g. a renderer's, created before the probe) is made current again after.
        const EGLDisplay prevDisplay = eglGetCurrentDisplay();
        const EGLContext prevContext = eglGetCurrentContext();
        const EGLSurface prevDraw = eglGetCurrentSurface(EGL_DRAW);
        const EGLSurface prevRead = eglGetCurrentSurface(EGL_READ);
        try {
            auto ctx = createHeadless(GlContextOptions{"auto", false});
            cached = 1;
        } catch (const Error& e) {
            cached = 0;
            cachedReason = e.what();
        }
        if (prevContext != EGL_NO_CONTEXT)
            eglMakeCurrent(prevDisplay, prevDraw, prevRead, prevContext);
    }
    if (reason)
        *reason = cachedReason;
    return cached == 1;
}

GlContext::~GlContext() {
    if (!m_egl)
        return;
    if (eglGetCurrentContext() == m_egl->context) {
        if (m_debugLog)
            m_debugLog->uninstall();
        eglMakeCurrent(m_egl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    eglDestroyContext(m_egl->display, m_egl->context);
    // The display is not terminated: EGL displays are shared per platform/device within the
    // process, and terminating would invalidate other GlContext objects on the same display.
}

void GlContext::makeCurrent() {
    if (!eglMakeCurrent(m_egl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, m_egl->context))
        LUCENT_THROW(GpuError, "eglMakeCurrent failed: ", eglErrorString(eglGetError()));
}

void GlContext::doneCurrent() {
    eglMakeCurrent(m_egl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

void checkGlError(const char* where) {
    GLenum first = glGetError();
    if (first == GL_NO_ERROR)
        return;
    for (int i = 0; i < 32 && glGetError() != GL_NO_ERROR; ++i) {
    }
    std::ostringstream os;
    os << "OpenGL error 0x" << std::hex << first << " in " << where;
    LUCENT_THROW(GpuError, os.str());
}

}  // namespace lucent::gpu
