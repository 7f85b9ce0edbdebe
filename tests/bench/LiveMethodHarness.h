// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief A live method from the registry on the default scene, driven as the app drives it
/// (lucent/methods/Method.h: setScene, cameraChanged, then materialChanged with the dirty bricks
/// before each render), for the benchmark-only live harnesses (soak_live, live_stroke_frames).
/// A current GL context is needed for the whole lifetime.

#include <lucent/gpu/SceneRenderer.h>
#include <lucent/gpu/Shader.h>
#include <lucent/methods/Registry.h>
#include <lucent/scene/SceneFile.h>

#include <memory>
#include <string>
#include <utility>

namespace lucent::bench {

struct LiveMethodHarness {
    /// `scene` (by default makeDefaultScene()) at width×height, method `name` with its live
    /// defaults (and `params`) on the GL backend, and one first frame (every upload and program
    /// in place; dirty bricks taken).
    LiveMethodHarness(const std::string& name, int width, int height,
                      const methods::ParamSet& params = {}, Scene scene_ = makeDefaultScene())
        : scene(std::move(scene_)), volume(*scene.objects[0].material) {
        scene.camera.width = width;
        scene.camera.height = height;
        renderer.create(library);
        method = methods::create(name, params, {methods::Backend::Gl, /*live=*/true, {}});
        method->createGl(library);
        const int mesh = renderer.addMesh(scene.objects[0].mesh, method->surface());
        renderer.setLights(scene.lights);
        renderer.setCamera(scene.camera);
        renderer.setSubsurfaceProvider(method->subsurfacePass());
        method->setScene({&scene.objects[0].mesh, &volume, scene.eta, scene.lights, mesh});
        method->cameraChanged(scene.camera);
        renderer.render();
        (void)volume.takeDirtyBricks();
    }
    ~LiveMethodHarness() {
        renderer.setSubsurfaceProvider(nullptr);
        method->destroyGl();
        renderer.destroy();
    }
    LiveMethodHarness(const LiveMethodHarness&) = delete;
    LiveMethodHarness& operator=(const LiveMethodHarness&) = delete;

    /// What the app does after a stroke: the dirty bricks to the method, then a frame.
    void strokeFrame() {
        method->materialChanged(volume.takeDirtyBricks());
        renderer.render();
    }

    Scene scene;
    MaterialVolume& volume;  ///< objects[0]'s painted volume
    const gpu::ShaderLibrary library;
    gpu::SceneRenderer renderer;
    std::unique_ptr<methods::Method> method;
};

}  // namespace lucent::bench
