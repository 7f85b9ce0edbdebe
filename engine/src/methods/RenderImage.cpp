// SPDX-License-Identifier: MIT
#include <lucent/methods/RenderImage.h>

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/methods/Registry.h>

namespace lucent::methods {

namespace {

void say(const Log& log, const std::string& message) {
    if (log)
        log(message);
}

/// The GL render: every object as a translucent surface (or the method's own surface), the
/// method's pass, frames until it converges.
void renderGl(const Scene& scene, const std::vector<Light>& lights, Method& method,
              const RenderOptions& options, RenderResult& out) {
    LUCENT_CHECK(!scene.objects.empty(), method.info().name, ": the scene has no object");
    std::unique_ptr<gpu::GlContext> own;
    gpu::GlContext* ctx = options.context;
    if (ctx) {
        ctx->makeCurrent();
    } else {
        own = gpu::GlContext::createHeadless();
        ctx = own.get();
    }
    out.device = ctx->renderer() + " (" + ctx->version() + ", EGL " + ctx->platform() + ")";
    const gpu::ShaderLibrary library;
    gpu::SceneRenderer renderer;
    const auto release = [&] {
        renderer.setSubsurfaceProvider(nullptr);
        method.destroyGl();
        renderer.destroy();
    };
    try {
        renderer.create(library);
        method.createGl(library);
        const gpu::SurfaceMaterial surface = method.surface();
        int objectMesh = -1;
        for (const SceneObject& object : scene.objects) {
            const int id = renderer.addMesh(object.mesh, surface);
            if (objectMesh < 0)
                objectMesh = id;  // the material volume belongs to objects[0]
        }
        renderer.setLights(lights);
        renderer.setCamera(scene.camera);
        gpu::DirectSettings settings;
        settings.subsurfaceOnly = options.subsurfaceOnly;
        renderer.setSettings(settings);
        SceneInputs inputs;
        inputs.mesh = &scene.objects[0].mesh;
        inputs.material = scene.objects[0].material.get();
        inputs.eta = scene.eta;
        inputs.lights = lights;
        inputs.meshId = objectMesh;
        method.setScene(inputs);
        method.cameraChanged(scene.camera);
        renderer.setSubsurfaceProvider(method.subsurfacePass());
        do {
            renderer.render();
            ++out.frames;
        } while (!method.converged());
        out.radiance = renderer.readRadiance();
        renderer.profiler().collect(/*wait=*/true);
        out.passes = renderer.profiler().latest();
        out.stats = method.stats();
    } catch (...) {
        release();
        throw;
    }
    release();
    out.glErrors = ctx->debugLog().takeErrors();
}

}  // namespace

RenderResult renderImage(const Scene& scene, const std::string& name, const ParamSet& params,
                         const RenderOptions& options) {
    const MethodInfo& info = find(name);
    const Timer timer;
    std::string reason;
    // Probe EGL only when GL could be chosen: the probe initialises a display (~0.3 s on
    // llvmpipe), which a method that prefers its CPU renderer (sslpv) would pay for nothing.
    const bool autoPicksCpu =
        options.backend == Backend::Auto && info.caps.cpu && info.caps.preferred == Backend::Cpu;
    const bool mayUseGl = info.caps.gl && options.backend != Backend::Cpu && !autoPicksCpu;
    const bool glAvailable =
        mayUseGl && (options.context || gpu::GlContext::isHeadlessAvailable(&reason));
    RenderResult out;
    out.backend = resolveBackend(info, options.backend, glAvailable, reason);
    if (options.backend == Backend::Auto && out.backend == Backend::Cpu && info.caps.gl &&
        info.caps.preferred == Backend::Gl)
        say(options.log, "no headless GL (" + reason + "); " + name + " on the CPU");
    std::unique_ptr<Method> method =
        create(name, params, {out.backend, /*live=*/false, options.log});
    // Skip the lights the objects do not need (never for the ground truth); the CPU renderers
    // take them from a copy of the scene, made only when a light is skipped.
    LightCulling lights = cullLights(scene.lights, objectBounds(scene),
                                     info.caps.groundTruth ? -1.f : options.lightSkipEpsilon);
    for (const std::string& s : lights.skipped)
        say(options.log, "skipped " + s);
    out.skippedLights = std::move(lights.skipped);
    if (out.backend == Backend::Gl) {
        renderGl(scene, lights.kept, *method, options, out);
    } else {
        CpuRequest request;
        request.subsurfaceOnly = options.subsurfaceOnly;
        request.progress = options.progress;
        out.device = "CPU";
        if (out.skippedLights.empty()) {
            out.radiance = method->renderCpu(scene, request);
        } else {
            Scene lit = scene;
            lit.lights = std::move(lights.kept);
            out.radiance = method->renderCpu(lit, request);
        }
        out.frames = 1;
        out.stats = method->stats();
    }
    const std::vector<std::string> unused = method->params().unused();
    if (!unused.empty()) {
        std::string list;
        for (const std::string& u : unused)
            list += (list.empty() ? "" : ", ") + u;
        say(options.log, name + " (" + backendName(out.backend) + ") does not use: " + list);
    }
    out.milliseconds = timer.elapsedMs();
    return out;
}

}  // namespace lucent::methods
