// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief One offline render API for every method: renderImage(scene, method, params). It owns
/// what every front end would otherwise repeat: the headless GL context, the gpu::SceneRenderer
/// set-up (the translucent-surface rule for every object, lights, camera), driving a
/// progressive method until it converges, the GL→CPU fallback, and collecting timings and the
/// method's statistics.
///
///     Scene scene = loadScene("resources/scenes/minimal.json");
///     ParamSet p;  p.set("spp", 64);
///     RenderResult r = renderImage(scene, "dipole", p);          // GL, else the CPU gather
///     writeExr(r.radiance, "dipole.exr");                          // W/(mm²·sr)
///
/// Units: radiance W/(mm²·sr); times in ms.

#include <lucent/core/Image.h>
#include <lucent/gpu/GpuTimer.h>
#include <lucent/methods/Method.h>
#include <lucent/scene/LightReach.h>
#include <lucent/scene/Scene.h>

#include <functional>
#include <string>
#include <vector>

namespace lucent::gpu {
class GlContext;
}

namespace lucent::methods {

/// How to render.
struct RenderOptions {
    Backend backend = Backend::Auto;
    bool subsurfaceOnly = false;  ///< only the subsurface term (no surface reflection)
    Log log;  ///< notes for the user (fallbacks, ignored parameters); may be empty
    /// Progress of long CPU renders (fraction in [0, 1], a short status); may be empty.
    std::function<void(double fraction, const std::string& status)> progress;
    /// Render GL methods in this context (made current; e.g. a test's shared context) instead
    /// of a new headless one. Not owned.
    gpu::GlContext* context = nullptr;
    /// Lights that miss every object or give it at most this fraction of the strongest light's
    /// irradiance are not rendered (cullLights, lucent/scene/LightReach.h); < 0 renders every
    /// light (the skip off). The ground truth (Capabilities::groundTruth) renders every light.
    float lightSkipEpsilon = LIGHT_SKIP_EPSILON;
};

/// What a render produced.
struct RenderResult {
    ImageRgb radiance;              ///< linear W/(mm²·sr), camera width × height, top row first
    Backend backend = Backend::Gl;  ///< the backend used (Gl or Cpu)
    std::string device;             ///< Gl: "GL_RENDERER (GL_VERSION, EGL platform)"; Cpu: "CPU"
    int frames = 0;                 ///< renderer frames (Gl) or CPU renders (1)
    double milliseconds = 0.0;      ///< wall time of the whole call (context creation included)
    std::vector<gpu::PassTiming> passes;  ///< Gl: the last frame's renderer passes
    Stats stats;                          ///< the method's statistics after the last frame
    std::vector<std::string> glErrors;    ///< Gl: errors the context's debug log collected
    /// The lights left out and why (cullLights), one line each; also sent to options.log.
    std::vector<std::string> skippedLights;
};

/// Renders scene.camera's image with `method` (registry name) and `params` (unset ones take
/// their defaults for the backend used). Parameters the method does not use on that backend
/// are reported through options.log.
/// @throw ValueError for an unknown method or parameter, or a scene the method cannot render;
/// GpuError when the method needs GL and no headless context can be created.
RenderResult renderImage(const Scene& scene, const std::string& method, const ParamSet& params,
                         const RenderOptions& options = {});

}  // namespace lucent::methods
