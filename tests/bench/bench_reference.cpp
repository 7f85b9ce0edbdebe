// SPDX-License-Identifier: MIT
/// @file
/// @brief Reference path tracer throughput: camera paths per second and the time to reach 1 %
/// relative standard error, on homogeneous spheres (marble, skin1), the default scene (a
/// thin-and-thick back-lit shape with heterogeneous paint) and a sparse sphere (thin haze
/// around a dense core, "cored"), with and without majorant bricks,
/// on 1 and 2 threads, and with the matched boundary and the straight approximation. After
/// the runs a table prints each figure as a ratio against its baseline measured in the same
/// run (global majorant for bricks; 1 thread for 2 threads; for the exact dielectric `auto`
/// run, matched and straight: the speed-up of the exact estimator over them, < 1 when slower).
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
#include <ctime>
#include <map>
#include <memory>
#include <string>

using namespace lucent;
using namespace lucent::reference;

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

/// Sparse medium: a thin haze filling a 10 mm sphere around a dense marble core (r = 4 mm),
/// where per-brick majorants can skip most null collisions.
Scene coredScene() {
    Scene scene = sphereScene("marble");
    MaterialVolume& vol = *scene.objects.front().material;
    MaterialSample haze;
    haze.sigma_s = Rgb(0.02f);
    haze.sigma_t = Rgb(0.025f);
    const MaterialSample core = findPreset("marble").sample();
    const GridSpec& spec = vol.spec();
    for (int z = 0; z < spec.resolution; ++z)
        for (int y = 0; y < spec.resolution; ++y)
            for (int x = 0; x < spec.resolution; ++x) {
                const Coord c(x, y, z);
                vol.set(c, glm::length(spec.cellCenter(c)) < 4.f ? core : haze);
            }
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
    if (!s)
        s = std::make_unique<Scene>(name == "default" ? defaultScene()
                                    : name == "cored" ? coredScene()
                                                      : sphereScene(name));
    return *s;
}

struct Result {
    double pathsPerSecond = 0, secondsTo1Percent = 0, rse = 0;
    double cpuTo1Percent = 0;   ///< process CPU seconds to 1 % RSE (robust on a shared machine)
    double lookupsPerPath = 0;  ///< σt lookups per camera path (deterministic work measure)
};
std::map<std::string, Result> g_results;

/// Majorant and colour variants (dielectric boundary), and two boundary variants with the
/// default majorant: `matched` (η = 1) and `straight` (the approximation), to compare the exact
/// dielectric estimator (`auto`) with.
enum class Variant { Bricks, Global, Auto, PerChannel, Matched, Straight };
const char* variantName(Variant v) {
    switch (v) {
        case Variant::Bricks:
            return "bricks";
        case Variant::Global:
            return "global";
        case Variant::Auto:
            return "auto";
        case Variant::PerChannel:
            return "auto-per-channel";
        case Variant::Matched:
            return "matched";
        case Variant::Straight:
            return "straight";
    }
    return "?";
}

std::string key(const std::string& scene, Variant v, int threads) {
    return scene + "/" + variantName(v) + "/threads:" + std::to_string(threads);
}

void runReference(benchmark::State& state, const std::string& scene, Variant v, int threads) {
    ReferenceOptions opt;
    opt.spp = SPP;
    opt.threads = threads;
    opt.majorant = v == Variant::Bricks   ? MajorantMode::Bricks
                   : v == Variant::Global ? MajorantMode::Global
                                          : MajorantMode::Auto;
    opt.spectralMis = v != Variant::PerChannel;
    opt.boundary = v == Variant::Matched    ? BoundaryModel::Matched
                   : v == Variant::Straight ? BoundaryModel::Straight
                                            : BoundaryModel::Dielectric;
    const Scene& s = sceneNamed(scene);
    ReferenceImage img;
    double seconds = 0;
    uint64_t paths = 0;
    double cpu = 0;
    for (auto _ : state) {
        const std::clock_t c0 = std::clock();
        img = renderReference(s, opt);
        cpu += double(std::clock() - c0) / CLOCKS_PER_SEC;
        seconds += img.seconds;
        paths += img.paths;
    }
    Result r;
    r.pathsPerSecond = double(paths) / seconds;
    r.rse = img.rse;
    // 1/√N law: RSE²·time is constant, so t(1 %) = t·(RSE/0.01)².
    r.secondsTo1Percent = img.seconds * double(img.rse / 0.01f) * double(img.rse / 0.01f);
    r.cpuTo1Percent = cpu * double(img.rse / 0.01f) * double(img.rse / 0.01f);
    r.lookupsPerPath = double(img.tentativeCollisions) / double(img.paths);
    g_results[key(scene, v, threads)] = r;
    state.counters["paths/s"] = r.pathsPerSecond;
    state.counters["RSE"] = r.rse;
    state.counters["s_to_1%RSE"] = r.secondsTo1Percent;
}

/// Speed-up of run a over baseline b: ratio of their times to 1 % RSE (CPU time, or wall time
/// for thread scaling).
std::string ratio(const std::string& a, const std::string& b, bool wall = false) {
    const auto ia = g_results.find(a), ib = g_results.find(b);
    if (ia == g_results.end() || ib == g_results.end())
        return "-";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2fx",
                  wall ? ib->second.secondsTo1Percent / ia->second.secondsTo1Percent
                       : ib->second.cpuTo1Percent / ia->second.cpuTo1Percent);
    return buf;
}

}  // namespace

int main(int argc, char** argv) {
    for (const char* scene : {"marble", "skin1", "default", "cored"}) {
        for (Variant v : {Variant::Bricks, Variant::Global})
            for (int threads : {1, 2})
                benchmark::RegisterBenchmark(
                    key(scene, v, threads).c_str(),
                    [=](benchmark::State& st) { runReference(st, scene, v, threads); })
                    ->Iterations(1)
                    ->Unit(benchmark::kMillisecond);
        for (Variant v : {Variant::Auto, Variant::PerChannel, Variant::Matched, Variant::Straight})
            benchmark::RegisterBenchmark(
                key(scene, v, 1).c_str(),
                [=](benchmark::State& st) { runReference(st, scene, v, 1); })
                ->Iterations(1)
                ->Unit(benchmark::kMillisecond);
    }
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();

    // Speed-ups: baseline time to 1 % RSE / this run's (work for equal quality).
    std::printf("\n%-34s %9s %10s %10s %7s %9s  %s\n", "run", "paths/s", "wall t(1%)", "CPU t(1%)",
                "RSE", "σt/path", "speed-up (CPU time to 1 % RSE; threads: wall)");
    for (const auto& [name, r] : g_results) {
        std::string vs;
        const std::string scene = name.substr(0, name.find('/'));
        if (name.find("/bricks/") != std::string::npos) {
            const std::string t = name.substr(name.rfind(':') + 1);
            vs = "vs global: " + ratio(name, key(scene, Variant::Global, std::stoi(t)));
        }
        if (name.find("threads:2") != std::string::npos) {
            std::string one = name;
            one.replace(one.size() - 1, 1, "1");
            vs += (vs.empty() ? "" : ", ") + std::string("vs 1 thread: ") +
                  ratio(name, one, /*wall=*/true);
        }
        if (name.find("/auto/") != std::string::npos)
            vs = "vs global: " + ratio(name, key(scene, Variant::Global, 1)) +
                 ", vs per-channel: " + ratio(name, key(scene, Variant::PerChannel, 1)) +
                 ", vs matched: " + ratio(name, key(scene, Variant::Matched, 1)) +
                 ", vs straight: " + ratio(name, key(scene, Variant::Straight, 1));
        std::printf("%-34s %9.4g %10.4g %10.4g %7.4f %9.4g  %s\n", name.c_str(), r.pathsPerSecond,
                    r.secondsTo1Percent, r.cpuTo1Percent, r.rse, r.lookupsPerPath, vs.c_str());
    }
    return 0;
}
