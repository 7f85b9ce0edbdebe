// SPDX-License-Identifier: MIT
/// @file
/// @brief GL backbone: frame time of the direct-lighting renderer at 640×360 (headless EGL).
/// Baseline measured in the same run: the empty-scene frame (same passes and clears, no
/// geometry: the fixed cost of the fullscreen shade and tone-map passes at this size). After the
/// runs, each case is printed as a ratio to it. Per-pass GPU times (timestamp queries, ms) are
/// counters. Run: LP_NUM_THREADS=2 ./build/ci/tests/bench/bench_gpu

#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/mesh/Procedural.h>

#include <benchmark/benchmark.h>
#include <epoxy/gl.h>

#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

using namespace lucent;
using namespace lucent::gpu;

namespace {

GlContext* context() {
    static std::unique_ptr<GlContext> ctx = [] {
        try {
            auto c = GlContext::createHeadless();
            std::printf("GL_RENDERER: %s\n", c->renderer().c_str());
            return c;
        } catch (const std::exception& e) {
            std::printf("no headless GL context: %s\n", e.what());
            return std::unique_ptr<GlContext>();
        }
    }();
    return ctx.get();
}

enum class Mode { Empty, Static, Deforming };

/// One frame per iteration (render + glFinish) at 640×360: a torus (16 k triangles) on a ground
/// box, lit by a point light (6 shadow faces) and a spot light (1 shadow layer), 1024² shadows.
void frameBenchmark(benchmark::State& state, Mode mode) {
    if (!context()) {
        state.SkipWithError("no headless GL context");
        return;
    }
    SceneRenderer r;
    r.create();
    const TriangleMesh torus = makeTorus(25.f, 9.f, 128, 64);
    TriangleMesh ground = makeBox(Vector3f(160.f, 2.f, 160.f));
    for (auto& p : ground.positions)
        p.y -= 36.f;
    if (mode != Mode::Empty) {
        r.addMesh(torus, {Rgb(0.7f, 0.5f, 0.4f), Rgb(0.04f), 48.f});
        r.addMesh(ground, {Rgb(0.6f), Rgb(0.f), 1.f});
    }
    Light point;
    point.position = {-40.f, 60.f, 40.f};
    point.intensity = Rgb(30000.f);
    Light spot;
    spot.type = Light::Type::Spot;
    spot.position = {50.f, 40.f, 60.f};
    spot.direction = glm::normalize(Vector3f(-50.f, -40.f, -60.f));
    spot.intensity = Rgb(20000.f);
    r.setLights({point, spot});
    Camera cam;
    cam.position = {0.f, 25.f, 90.f};
    cam.target = {0.f, 0.f, 0.f};
    cam.width = 640;
    cam.height = 360;
    r.setCamera(cam);
    r.render();  // warm-up: target allocation, shader compilation inside the driver
    glFinish();

    TriangleMesh deformed = torus;
    int frame = 0;
    const char* passes[] = {"shadows", "gbuffer", "shade", "tonemap"};
    double passMs[4] = {0.0, 0.0, 0.0, 0.0};
    for (auto _ : state) {
        if (mode == Mode::Deforming) {
            const float s = 1.f + 0.05f * float(frame++ % 8);
            for (size_t i = 0; i < torus.positions.size(); ++i)
                deformed.positions[i] = torus.positions[i] * Vector3f(1.f, s, 1.f);
            r.updateMesh(0, deformed);
        }
        r.render();
        glFinish();
        r.profiler().collect(/*wait=*/true);
        for (int k = 0; k < 4; ++k)
            if (const PassTiming* t = r.profiler().find(passes[k]))
                passMs[k] += t->gpuMs;
    }
    const double n = double(std::max<benchmark::IterationCount>(state.iterations(), 1));
    for (int k = 0; k < 4; ++k)
        state.counters[std::string(passes[k]) + "_ms"] = passMs[k] / n;
    r.destroy();
}

/// Console output plus a record of each run's real time per iteration (ms).
class RatioReporter : public benchmark::ConsoleReporter {
public:
    RatioReporter() : ConsoleReporter(OO_Tabular) {}
    void ReportRuns(const std::vector<Run>& runs) override {
        for (const Run& run : runs)
            if (run.iterations > 0 && !run.error_occurred)
                m_ms.emplace_back(run.run_name.function_name,
                                  run.real_accumulated_time / double(run.iterations) * 1e3);
        ConsoleReporter::ReportRuns(runs);
    }
    std::vector<std::pair<std::string, double>> m_ms;  ///< in run order; the baseline first
};

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    const char* names[] = {"direct640x360/empty_baseline", "direct640x360/static_mesh",
                           "direct640x360/deforming_mesh"};
    const Mode modes[] = {Mode::Empty, Mode::Static, Mode::Deforming};
    for (int i = 0; i < 3; ++i)
        benchmark::RegisterBenchmark(names[i], frameBenchmark, modes[i])
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->MinTime(2.0);
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    if (!reporter.m_ms.empty() && reporter.m_ms.front().first == names[0]) {
        const double base = reporter.m_ms.front().second;
        std::printf("\nratio to the empty-scene frame (%.2f ms):\n", base);
        for (const auto& [name, ms] : reporter.m_ms)
            std::printf("  %-32s %8.2f ms  %6.2fx  (%.1f fps)\n", name.c_str(), ms, ms / base,
                        1e3 / ms);
    }
    benchmark::Shutdown();
    return 0;
}
