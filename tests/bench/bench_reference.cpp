// SPDX-License-Identifier: MIT
/// @file
/// @brief Reference path tracer throughput: camera paths per second and the time to reach 1 %
/// relative standard error, on homogeneous spheres (marble, skin1) and the default scene (a
/// thin-and-thick back-lit shape with heterogeneous paint), with and without majorant bricks,
/// on 1 and 2 threads. After the runs a table prints each figure as a ratio against its
/// baseline measured in the same run (global majorant for bricks; 1 thread for 2 threads).
///
///     bench_reference [--benchmark_filter=...]
///
/// Time to 1 % RSE is extrapolated from each run with the 1/√N law (RSE² · time is constant):
/// t(1 %) = t · (RSE / 0.01)².

#include <lucent/material/Presets.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/mesh/Voxelize.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/SceneFile.h>

#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>

using namespace lucent;

namespace {

constexpr int IMAGE = 40;  // pixels per side
constexpr int SPP = 24;

Scene sphereScene(const std::string& preset) {
    Scene scene;
    SceneObject obj;
    obj.mesh = makeSphere(/*radius=*/10.f, /*subdivisions=*/4);
    const MaterialPreset& p = findPreset(preset);
    const GridSpec spec = GridSpec::around(obj.mesh.bounds(), 64);
    obj.material = std::make_shared<MaterialVolume>(spec, p.sample());
    obj.material->setInsideMask(voxelizeSolid(obj.mesh, spec));
    scene.objects.push_back(std::move(obj));
    Light key;
    key.type = Light::Type::Point;
    key.position = {30.f, 30.f, 30.f};
    key.intensity = Rgb(2000.f);  // W/sr: ≈ 0.74 W/mm² at the sphere
    scene.lights.push_back(key);
    scene.camera.position = {0.f, 0.f, 45.f};
    scene.camera.fovYDeg = 30.f;
    scene.camera.width = scene.camera.height = IMAGE;
    scene.eta = p.eta;
    return scene;
}

Scene defaultScene() {
    Scene scene = makeDefaultScene();
    const float aspect = float(scene.camera.width) / float(scene.camera.height);
    scene.camera.height = IMAGE;
    scene.camera.width = std::max(1, int(float(IMAGE) * aspect));
    return scene;
}

const Scene& sceneNamed(const std::string& name) {
    static std::map<std::string, std::unique_ptr<Scene>> cache;
    auto& s = cache[name];
    if (!s) s = std::make_unique<Scene>(name == "default" ? defaultScene() : sphereScene(name));
    return *s;
}

struct Result {
    double pathsPerSecond = 0, secondsTo1Percent = 0, rse = 0;
};
std::map<std::string, Result> g_results;

std::string key(const std::string& scene, bool bricks, int threads) {
    return scene + (bricks ? "/bricks" : "/global") + "/threads:" + std::to_string(threads);
}

void runReference(benchmark::State& state, const std::string& scene, bool bricks, int threads) {
    ReferenceOptions opt;
    opt.spp = SPP;
    opt.threads = threads;
    opt.majorant = bricks ? MajorantMode::Bricks : MajorantMode::Global;
    const Scene& s = sceneNamed(scene);
    ReferenceImage img;
    double seconds = 0;
    uint64_t paths = 0;
    for (auto _ : state) {
        img = renderReference(s, opt);
        seconds += img.seconds;
        paths += img.paths;
    }
    Result r;
    r.pathsPerSecond = double(paths) / seconds;
    r.rse = img.rse;
    r.secondsTo1Percent = img.seconds * double(img.rse / 0.01f) * double(img.rse / 0.01f);
    g_results[key(scene, bricks, threads)] = r;
    state.counters["paths/s"] = r.pathsPerSecond;
    state.counters["RSE"] = r.rse;
    state.counters["s_to_1%RSE"] = r.secondsTo1Percent;
}

}  // namespace

int main(int argc, char** argv) {
    for (const char* scene : {"marble", "skin1", "default"})
        for (bool bricks : {true, false})
            for (int threads : {1, 2})
                benchmark::RegisterBenchmark(key(scene, bricks, threads).c_str(),
                                             [=](benchmark::State& st) {
                                                 runReference(st, scene, bricks, threads);
                                             })
                    ->Iterations(1)
                    ->Unit(benchmark::kMillisecond);
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();

    std::printf("\n%-34s %12s %12s %10s %14s %14s\n", "run", "paths/s", "t(1% RSE) s", "RSE",
                "vs global", "vs 1 thread");
    for (const auto& [name, r] : g_results) {
        std::string vsGlobal = "-", vsOne = "-";
        const auto pos = name.find("/bricks/");
        if (pos != std::string::npos) {
            std::string other = name;
            other.replace(pos, 8, "/global/");
            if (auto it = g_results.find(other); it != g_results.end())
                vsGlobal = std::to_string(r.pathsPerSecond / it->second.pathsPerSecond) + "x";
        }
        const auto tpos = name.find("threads:2");
        if (tpos != std::string::npos) {
            std::string other = name;
            other.replace(tpos, 9, "threads:1");
            if (auto it = g_results.find(other); it != g_results.end())
                vsOne = std::to_string(r.pathsPerSecond / it->second.pathsPerSecond) + "x";
        }
        std::printf("%-34s %12.4g %12.4g %10.4f %14s %14s\n", name.c_str(), r.pathsPerSecond,
                    r.secondsTo1Percent, r.rse, vsGlobal.c_str(), vsOne.c_str());
    }
    return 0;
}
