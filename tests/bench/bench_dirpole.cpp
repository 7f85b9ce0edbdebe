// SPDX-License-Identifier: MIT
/// @file
/// @brief Latency of the two interactive previews of issues 6 and 7 on the app's default scene
/// (makeDefaultScene: the 40 mm thin-thick shape, 128³ painted volume, two point lights) at the
/// app's render size (640×360 viewport at resolution scale 0.5 = 320×180), through
/// gpu::SceneRenderer on a headless context:
///  - dipole::DirpoleSubsurfaceProvider: a frame after a full reset (light moved; the same-run
///    baseline, as every restart was before), after a paint stroke, and an idle progressive
///    frame, each with the frame budgets off (every frame adds samplesPerFrame = 16 to every
///    texel, as before) and at their defaults;
///  - combined::CombinedSubsurfaceProvider: a stroke frame and an idle frame.
/// Wall time per frame (render + glFinish, stroke upload included) and the providers' own
/// per-pass GPU and CPU times as counters (ms; on llvmpipe a compute pass's CPU time holds
/// its execution, GPU timestamps are unreliable). Results: docs/methods/dipole.md §7,
/// docs/methods/combined.md.
///
///     build/ci/tests/bench/bench_dirpole [--benchmark_filter=Dirpole]
#include <lucent/combined/Combined.h>
#include <lucent/combined/CombinedProvider.h>
#include <lucent/dipole/DipoleProvider.h>
#include <lucent/dipole/DirpoleProvider.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/material/Brush.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Method.h>
#include <lucent/scene/SceneFile.h>

#include <benchmark/benchmark.h>
#include <epoxy/gl.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

using namespace lucent;

namespace {

constexpr int WIDTH = 320, HEIGHT = 180;  // 640×360 at the app's resolution scale 0.5

gpu::GlContext* context() {
    static std::unique_ptr<gpu::GlContext> ctx = [] {
        std::string reason;
        return gpu::GlContext::isHeadlessAvailable(&reason) ? gpu::GlContext::createHeadless()
                                                            : nullptr;
    }();
    return ctx.get();
}

/// The default scene at the app's render size, its object in `renderer` (with the surface
/// reflection, as the app shows it). @return the object's mesh id.
int loadDefaultScene(Scene& scene, gpu::SceneRenderer& renderer) {
    scene = makeDefaultScene();
    scene.camera.width = WIDTH;
    scene.camera.height = HEIGHT;
    renderer.create();
    const int id = renderer.addMesh(scene.objects[0].mesh, methods::translucentSurface());
    renderer.setLights(scene.lights);
    renderer.setCamera(scene.camera);
    return id;
}

/// A paint stroke like the app harness's (radius 5 mm, 16 mm across the front of the object at
/// its centre), alternating between a darker and a lighter skin so every stroke changes the
/// material. @return the dirty bricks (taken).
std::vector<int> paintStroke(MaterialVolume& vol, const TriangleMesh& mesh, int i) {
    float zFront = -1e9f;  // the front surface near the centre line
    for (const Point3f& p : mesh.positions)
        if (std::abs(p.x) < 8.f && std::abs(p.y) < 2.f)
            zFront = std::max(zFront, p.z);
    BrushSettings brush;
    brush.radius = 5.f;
    brush.value = vol.at(Coord(vol.resolution() / 2));
    brush.value.sigma_t *= (i % 2) ? 0.7f : 1.4f;
    brush.value.sigma_s *= (i % 2) ? 0.7f : 1.4f;
    lucent::paintStroke(vol, brush, {{-8.f, 0.f, zFront}, {8.f, 0.f, zFront}});
    return vol.takeDirtyBricks();
}

/// Renders one frame and waits for it. @return wall ms.
double timedFrame(gpu::SceneRenderer& renderer) {
    const auto t0 = std::chrono::steady_clock::now();
    renderer.render();
    glFinish();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// Mean GPU and CPU ms per named pass over the iterations, as benchmark counters.
class PassTotals {
public:
    void add(const std::vector<gpu::PassTiming>& passes) {
        for (const gpu::PassTiming& t : passes) {
            auto it = std::find(m_names.begin(), m_names.end(), t.name);
            const size_t j = size_t(it - m_names.begin());
            if (it == m_names.end()) {
                m_names.push_back(t.name);
                m_gpu.push_back(0.0);
                m_cpu.push_back(0.0);
            }
            m_gpu[j] += t.gpuMs;
            m_cpu[j] += t.cpuMs;
        }
    }
    void report(benchmark::State& state, int iterations) const {
        const double n = std::max(iterations, 1);
        for (size_t j = 0; j < m_names.size(); ++j) {
            state.counters[m_names[j] + "_gpu_ms"] = m_gpu[j] / n;
            state.counters[m_names[j] + "_cpu_ms"] = m_cpu[j] / n;
        }
    }

private:
    std::vector<std::string> m_names;
    std::vector<double> m_gpu, m_cpu;
};

/// A stroke (`paint`: takes the dirty bricks and hands them to the provider) and the next frame.
/// @return wall ms of both.
template <class Paint>
double timedStroke(gpu::SceneRenderer& renderer, Paint&& paint) {
    const auto t0 = std::chrono::steady_clock::now();
    paint();
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return ms + timedFrame(renderer);
}

enum class DirpoleCase { Reset, Stroke, Idle };

/// Arg 0: case (0 reset, 1 stroke, 2 idle), arg 1: 1 = default frame budgets, 0 = none.
void BM_DirpoleFrame(benchmark::State& state) {
    if (!context()) {
        state.SkipWithError("no headless OpenGL");
        return;
    }
    const auto kind = DirpoleCase(state.range(0));
    const bool budgets = state.range(1) != 0;
    Scene scene;
    gpu::SceneRenderer renderer;
    const int meshId = loadDefaultScene(scene, renderer);
    dipole::DirpoleSubsurfaceProvider provider;
    provider.create();
    dipole::DirpoleSettings ds;  // the app's: η of the scene, 16 samples per frame, mesh 0
    ds.eta = scene.eta;
    ds.samplesPerFrame = 16;
    ds.meshId = meshId;
    if (kind == DirpoleCase::Idle) {  // never converges: every frame is a progressive one
        ds.convergenceThreshold = 0.f;
        ds.maxFrames = 1 << 16;
    } else {
        ds.maxFrames = 8;  // converged at 128 samples per texel: keeps the set-up short
    }
    if (!budgets)
        ds.frameSampleBudget = ds.firstFrameSampleBudget = 0;
    provider.setSettings(ds);
    MaterialVolume& vol = *scene.objects[0].material;
    provider.setMaterial(&vol);
    renderer.setSubsurfaceProvider(&provider);
    renderer.render();  // programs, uploads, first frame
    std::vector<Light> lights = scene.lights;
    PassTotals passes;
    double sampled = 0.0, k = 0.0;
    int i = 0;
    for (auto _ : state) {
        if (kind != DirpoleCase::Idle)
            for (int f = 0; f < 200 && !provider.stats().converged; ++f)
                renderer.render();  // untimed: the stroke or reset starts from a converged image
        double ms = 0.0;
        if (kind == DirpoleCase::Reset) {
            lights[0].position.x += (i % 2) ? -0.01f : 0.01f;  // any light change: full reset
            renderer.setLights(lights);
            ms = timedFrame(renderer);
        } else if (kind == DirpoleCase::Stroke) {
            ms = timedStroke(renderer, [&] {
                provider.uploadBricks(paintStroke(vol, scene.objects[0].mesh, i));
            });
        } else {
            ms = timedFrame(renderer);
        }
        state.SetIterationTime(ms / 1e3);
        passes.add(provider.passTimes());
        sampled += provider.dirpoleStats().texelsSampled;
        k += provider.dirpoleStats().samplesThisFrame;
        ++i;
    }
    const double n = std::max(i, 1);
    passes.report(state, i);
    state.counters["texels_sampled"] = sampled / n;
    state.counters["k"] = k / n;
    state.counters["texels_covered"] = provider.dirpoleStats().texelsCovered;
    renderer.setSubsurfaceProvider(nullptr);
    provider.destroy();
    renderer.destroy();
}

/// The default scene in `renderer` with `provider` attached and one frame rendered: the app's
/// settings (default split, 16 dipole samples per frame) after `adjust`.
template <class Adjust>
void startCombined(Scene& scene, gpu::SceneRenderer& renderer,
                   combined::CombinedSubsurfaceProvider& provider, Adjust&& adjust) {
    const int meshId = loadDefaultScene(scene, renderer);
    provider.create();
    combined::CombinedProviderSettings cs;
    cs.eta = scene.eta;
    cs.meshId = meshId;
    cs.dipole.samplesPerFrame = 16;
    adjust(cs);
    provider.setSettings(cs);
    provider.setMesh(scene.objects[0].mesh);
    provider.setLights(scene.lights);
    provider.setMaterial(*scene.objects[0].material, scene.eta);
    renderer.setSubsurfaceProvider(&provider);
    renderer.render();
}

/// Arg 0: 1 = stroke frames, 0 = idle (progressive) frames.
void BM_CombinedFrame(benchmark::State& state) {
    if (!context()) {
        state.SkipWithError("no headless OpenGL");
        return;
    }
    const bool stroke = state.range(0) != 0;
    Scene scene;
    gpu::SceneRenderer renderer;
    combined::CombinedSubsurfaceProvider provider;
    startCombined(scene, renderer, provider, [&](combined::CombinedProviderSettings& cs) {
        if (stroke)
            cs.dipole.maxFrames = 8;
        else
            cs.dipole.convergenceThreshold = 0.f, cs.dipole.maxFrames = 1 << 16;
    });
    MaterialVolume& vol = *scene.objects[0].material;
    PassTotals passes;
    int i = 0;
    for (auto _ : state) {
        double ms = 0.0;
        if (stroke) {
            for (int f = 0; f < 200 && !provider.stats().converged; ++f)
                renderer.render();
            ms = timedStroke(renderer, [&] {
                provider.updateMaterial(vol, paintStroke(vol, scene.objects[0].mesh, i));
            });
        } else {
            ms = timedFrame(renderer);
        }
        state.SetIterationTime(ms / 1e3);
        passes.add(provider.passTimes());
        ++i;
    }
    passes.report(state, i);
    renderer.setSubsurfaceProvider(nullptr);
    provider.destroy();
    renderer.destroy();
}

/// A frame after the lights change: arg 0 scales both lights' intensity (the L̂ image is
/// recomputed, the kernel is not: the mean incidence is unchanged), arg 1 swings the first light
/// between two places whose mean incidence differs by at least one KERNEL_INCIDENCE_STEP, so the
/// kernel is solved again as well (docs/methods/combined.md, "The kernel lit at the scene's
/// incidence"). The difference of the two is the cost of the re-solve.
void BM_CombinedLightChange(benchmark::State& state) {
    if (!context()) {
        state.SkipWithError("no headless OpenGL");
        return;
    }
    const bool moveIncidence = state.range(0) != 0;
    Scene scene;
    gpu::SceneRenderer renderer;
    combined::CombinedSubsurfaceProvider provider;
    startCombined(scene, renderer, provider,
                  [](combined::CombinedProviderSettings& cs) { cs.dipole.maxFrames = 8; });
    std::vector<Light> lights[2] = {scene.lights, scene.lights};
    if (moveIncidence) {
        // The first light brought close to the object's centre: a cap met at grazing angles.
        const Bounds3f b = scene.objects[0].mesh.bounds();
        const Point3f c = b.center();
        Light& l = lights[1].front();
        l.position =
            c + 0.6f * (l.position - c) * (glm::length(b.extent()) / glm::length(l.position - c));
    } else {
        for (Light& l : lights[1])
            l.intensity *= 0.9f;
    }
    const float mu[2] = {
        combined::meanIncidenceCosine(scene.objects[0].mesh, lights[0], scene.eta),
        combined::meanIncidenceCosine(scene.objects[0].mesh, lights[1], scene.eta)};
    if ((mu[0] != mu[1]) != moveIncidence) {
        state.SkipWithError("the two light sets' mean incidence is not as the case needs");
        return;
    }
    PassTotals passes;
    int i = 0;
    for (auto _ : state) {
        for (int f = 0; f < 200 && !provider.stats().converged; ++f)
            renderer.render();
        const std::vector<Light>& next = lights[(i + 1) % 2];
        const double ms = timedStroke(renderer, [&] {
            renderer.setLights(next);
            provider.setLights(next);
        });
        state.SetIterationTime(ms / 1e3);
        passes.add(provider.passTimes());
        ++i;
    }
    passes.report(state, i);
    state.counters["incidence_a"] = mu[0];
    state.counters["incidence_b"] = mu[1];
    renderer.setSubsurfaceProvider(nullptr);
    provider.destroy();
    renderer.destroy();
}

}  // namespace

// Baseline first: a full reset without budgets is what every restart cost before.
BENCHMARK(BM_DirpoleFrame)
    ->ArgNames({"case", "budgets"})
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({2, 0})
    ->Args({2, 1})
    ->UseManualTime()
    ->Iterations(6)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CombinedFrame)
    ->ArgNames({"stroke"})
    ->Arg(1)
    ->Arg(0)
    ->UseManualTime()
    ->Iterations(6)
    ->Unit(benchmark::kMillisecond);

BENCHMARK(BM_CombinedLightChange)
    ->ArgNames({"incidence_moves"})
    ->Arg(0)
    ->Arg(1)
    ->UseManualTime()
    ->Iterations(6)
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
