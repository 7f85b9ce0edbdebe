// SPDX-License-Identifier: MIT
/// @file
/// @brief A live (app-preview) method instance keeps rendering when its parameters change at
/// run time, as the app's Render settings dock changes them: regression test for a new SSLPV
/// grid, which drops the SSLPV pass's material (SslpvProvider::setOptions) while the method
/// believed it still set, so every later frame threw "no material".

#include <lucent/core/Image.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/gpu/Shader.h>
#include <lucent/methods/Registry.h>
#include <lucent/scene/SceneFile.h>

#include "GlTestContext.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace lucent::methods {
namespace {

/// Sum of the subsurface radiance of one frame (finite and > 0 when the method's pass ran).
double frameSum(gpu::SceneRenderer& renderer) {
    renderer.render();
    const ImageRgb image = renderer.readRadiance();
    double sum = 0.0;
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x)
            for (int k = 0; k < 3; ++k)
                sum += double(image.at(x, y)[k]);
    return sum;
}

TEST(MethodsLive, GridChangeAtRunTimeKeepsRendering) {
    std::string reason;
    if (!lucent::test::sharedGlContext(&reason))
        GTEST_SKIP() << "no OpenGL 4.5 context: " << reason;
    Scene scene = loadScene(std::string(LUCENT_SOURCE_DIR) + "/resources/scenes/skin_sphere.json");
    scene.camera.width = 64;
    scene.camera.height = 48;
    for (const char* name : {"sslpv", "combined"}) {
        SCOPED_TRACE(name);
        const gpu::ShaderLibrary library;
        gpu::SceneRenderer renderer;
        renderer.create(library);
        std::unique_ptr<Method> method = create(name, {}, {Backend::Gl, /*live=*/true, {}});
        method->createGl(library);
        const int mesh = renderer.addMesh(scene.objects[0].mesh, method->surface(scene.eta));
        renderer.setLights(scene.lights);
        renderer.setCamera(scene.camera);
        gpu::DirectSettings settings;
        settings.subsurfaceOnly = true;  // the method's term alone
        renderer.setSettings(settings);
        SceneInputs inputs{&scene.objects[0].mesh, scene.objects[0].material.get(), scene.eta,
                           scene.lights, mesh};
        renderer.setSubsurfaceProvider(method->subsurfacePass());
        // As the app does every frame: the scene inputs, then the frame.
        method->setScene(inputs);
        const double at32 = frameSum(renderer);
        EXPECT_TRUE(std::isfinite(at32) && at32 > 0.0) << at32;
        for (int grid : {16, 32}) {
            ParamSet params;
            params.set("grid", grid);
            method->setParams(params);
            method->setScene(inputs);
            double sum = 0.0;
            ASSERT_NO_THROW(sum = frameSum(renderer)) << "grid " << grid;
            EXPECT_TRUE(std::isfinite(sum) && sum > 0.0) << "grid " << grid << ": " << sum;
        }
        renderer.setSubsurfaceProvider(nullptr);
        method->destroyGl();
        renderer.destroy();
    }
}

}  // namespace
}  // namespace lucent::methods
