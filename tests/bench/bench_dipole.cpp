// SPDX-License-Identifier: MIT
/// @file
/// @brief Image-space dipole gather on the CPU (Mertens et al. 2005 §5–6): time at 640×360 and
/// 1280×720 for 8…256 samples per pixel on a lit sphere, against two baselines measured in the same
/// run: the camera-view irradiance pass (one primary + one shadow ray per pixel, Embree) and a
/// single R_d evaluation per pixel-sample (the arithmetic floor of the gather). Variants: camera
/// image only, camera + light views (shared budget, as the renderer gathers), the combined mode's
/// local-radius window, the better dipole; GL compute (camera only). `--light-view-cost`: the
/// light views' share of a frame (back-lit scene, CPU and GL). Results:
/// docs/benchmarks.md, "Dipoles".
#include <lucent/core/Fresnel.h>
#include <lucent/dipole/DipoleProvider.h>
#include <lucent/dipole/GpuGather.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/dipole/LayeredMaterial.h>
#include <lucent/material/Brush.h>
#include <lucent/material/Procedural.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/Shader.h>
#include <lucent/dipole/Sampling.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/SceneFile.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

using namespace lucent;
using namespace lucent::dipole;

namespace {

Scene sphereScene(int w, int h) {
    Scene s;
    SceneObject obj;
    obj.mesh = makeSphere(10.f, 5);
    MaterialSample m;  // marble-like (Jensen 2001), scaled to a 20 mm object: σs′ ≈ 2 mm⁻¹
    m.sigma_s = Rgb(2.19f, 2.62f, 3.00f);
    m.sigma_t = m.sigma_s + Rgb(0.0021f, 0.0041f, 0.0071f);
    obj.material = std::make_shared<MaterialVolume>(GridSpec::around(obj.mesh.bounds(), 64), m);
    s.objects.push_back(std::move(obj));
    Light l;
    l.type = Light::Type::Point;
    l.position = {30.f, 30.f, 30.f};
    l.intensity = Rgb(2000.f);
    s.lights.push_back(l);
    s.camera.position = {0.f, 0.f, 45.f};
    s.camera.width = w;
    s.camera.height = h;
    s.eta = 1.3f;
    return s;
}

const SurfaceBuffers& buffers(int w) {
    static std::map<int, SurfaceBuffers> cache;
    auto it = cache.find(w);
    if (it == cache.end())
        it = cache.emplace(w, buildSurfaceBuffers(sphereScene(w, w * 9 / 16))).first;
    return it->second;
}

/// The camera image plus the light views the renderer would gather (buildImageSpaceViews with the
/// default LightViewSettings: 512² views, skip criterion), per image width.
const ImageSpaceViews& views(int w) {
    static std::map<int, ImageSpaceViews> cache;
    auto it = cache.find(w);
    if (it == cache.end()) {
        GatherSettings gs;
        gs.eta = 1.3f;
        it = cache
                 .emplace(w,
                          buildImageSpaceViews(sphereScene(w, w * 9 / 16), gs, LightViewSettings{}))
                 .first;
    }
    return it->second;
}

/// The local-radius window of the combined mode (docs/methods/combined.md): r ≤ 4 cells of a
/// 32³ SSLPV grid over the 20 mm sphere, 4 · 20/32 = 2.5 mm.
constexpr float WINDOW_RADIUS_MM = 2.5f;

size_t coveredPixels(const SurfaceBuffers& b) {
    size_t n = 0;
    for (uint8_t c : b.covered)
        n += c != 0;
    return n;
}

void BM_IrradiancePass(benchmark::State& state) {
    const int w = int(state.range(0));
    const Scene scene = sphereScene(w, w * 9 / 16);
    for (auto _ : state)
        benchmark::DoNotOptimize(buildSurfaceBuffers(scene));
    state.counters["Mpix/s"] = benchmark::Counter(double(w) * (w * 9 / 16) / 1e6,
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

void BM_ProfileFloor(benchmark::State& state) {
    // One R_d evaluation + one pdf evaluation per pixel-sample, 3 channels, no image access.
    const int w = int(state.range(0)), spp = int(state.range(1));
    const size_t n = coveredPixels(buffers(w)) * size_t(spp);
    const DipoleProfile p = DipoleProfile::jensen(0.0021, 2.19, 1.3);
    const DipoleSampler s(p);
    for (auto _ : state) {
        double acc = 0.0;
        for (size_t i = 0; i < n; ++i) {
            const double r = 1e-3 * double(i % 4096);
            acc += 3.0 * p.Rd(r) / s.pdfArea(r);
        }
        benchmark::DoNotOptimize(acc);
    }
    state.counters["Msamples/s"] =
        benchmark::Counter(double(n) / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}

/// Gather variants (third argument of BM_Gather / BM_GpuGather).
enum GatherMode : int {
    CAMERA = 0,       ///< dipole, camera irradiance image only (Mertens et al. 2005 as published)
    BETTER = 1,       ///< better dipole, camera only
    LIGHT_VIEWS = 2,  ///< dipole, camera + light views sharing the per-pixel budget (§3d)
    WINDOW = 3,       ///< dipole, camera only, r ≤ WINDOW_RADIUS_MM (combined mode's local part)
};

void BM_Gather(benchmark::State& state) {
    const int w = int(state.range(0)), spp = int(state.range(1));
    const auto mode = GatherMode(state.range(2));
    const SurfaceBuffers& b = buffers(w);
    GatherSettings gs;
    gs.model = mode == BETTER ? Model::BetterDipole : Model::Dipole;
    gs.uniformSamples = spp / 4;  // ¼ uniform disc samples, ¾ importance (balance heuristic)
    gs.importanceSamples = spp - gs.uniformSamples;
    if (mode == WINDOW)
        gs.maxRadius = WINDOW_RADIUS_MM;
    if (mode == LIGHT_VIEWS) {
        const ImageSpaceViews& v = views(w);
        state.counters["light views"] = double(v.lights.size());
        for (auto _ : state)
            benchmark::DoNotOptimize(gatherImageSpace(v.camera, v.lights, gs));
    } else {
        for (auto _ : state)
            benchmark::DoNotOptimize(gatherImageSpace(b, gs));
    }
    const double samples = double(coveredPixels(b)) * spp;
    state.counters["Msamples/s"] =
        benchmark::Counter(samples / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_GpuGather(benchmark::State& state) {
    // The same gather as a GL compute shader (llvmpipe on the CI box: CPU again, but SIMD).
    std::string reason;
    if (!gpu::GlContext::isHeadlessAvailable(&reason)) {
        state.SkipWithError(("no headless GL: " + reason).c_str());
        return;
    }
    static std::unique_ptr<gpu::GlContext> ctx = gpu::GlContext::createHeadless();
    const int w = int(state.range(0)), spp = int(state.range(1));
    const SurfaceBuffers& b = buffers(w);
    GatherSettings gs;
    gs.uniformSamples = spp / 4;
    gs.importanceSamples = spp - gs.uniformSamples;
    if (GatherMode(state.range(2)) == WINDOW)
        gs.maxRadius = WINDOW_RADIUS_MM;
    GpuGather gather{gpu::ShaderLibrary{}};
    for (auto _ : state)
        benchmark::DoNotOptimize(gather.run(b, gs));
    gather.destroy();
    const double samples = double(coveredPixels(b)) * spp;
    state.counters["Msamples/s"] =
        benchmark::Counter(samples / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

BENCHMARK(BM_IrradiancePass)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ProfileFloor)
    ->Args({640, 32})
    ->Args({1280, 32})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
/// Camera-only and light-view rows interleaved per size and spp, so that a load change on the
/// shared box hits both sides of the ratio alike.
void gatherArgs(benchmark::internal::Benchmark* b) {
    for (int w : {640, 1280}) {
        for (int spp : {8, 32, 128, 256})
            for (int mode : {CAMERA, LIGHT_VIEWS})
                b->Args({w, spp, mode});
        for (int mode : {BETTER, WINDOW})
            b->Args({w, 32, mode});
    }
}
BENCHMARK(BM_Gather)
    ->Apply(gatherArgs)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
namespace {

/// The evaluation suite's layer-over-core sphere (10 mm, a 1 mm layer over a core of α′ 0.5).
const MaterialVolume& layeredSphere(int resolution) {
    static std::map<int, SceneObject> cache;
    auto it = cache.find(resolution);
    if (it == cache.end()) {
        SceneObject o = makeObject(makeSphere(10.f, 4), resolution,
                                   MaterialSample{Rgb(1.f), Rgb(0.5f), Rgb(0.f)});
        ProceduralFill fill;
        fill.pattern = ProceduralPattern::Layered;
        fill.amplitude = 0.f;
        fill.layers = {{1.f, MaterialSample{Rgb(4.002f), Rgb(4.f), Rgb(0.f)}},
                       {1.f, MaterialSample{Rgb(1.f), Rgb(0.5f), Rgb(0.f)}}};
        fillProcedural(*o.material, fill);
        it = cache.emplace(resolution, std::move(o)).first;
    }
    return *it->second.material;
}

/// Baseline: copying the volume (what the read-out does before it rewrites the surface band).
void BM_VolumeCopy(benchmark::State& state) {
    const MaterialVolume& v = layeredSphere(int(state.range(0)));
    for (auto _ : state) {
        MaterialVolume copy = v;
        benchmark::DoNotOptimize(copy.brickData(0));
    }
}

/// The layered read-out (LayeredMaterial.h): a full build, as when a method is given a volume.
void BM_LayeredReadoutBuild(benchmark::State& state) {
    const MaterialVolume& v = layeredSphere(int(state.range(0)));
    LayeredReadoutSettings settings;
    settings.maxDepthVoxels = int(state.range(1));
    (void)layeredEquivalent(v, 1.3);  // the exact-total table, once per process
    for (auto _ : state)
        benchmark::DoNotOptimize(LayeredReadout(v, 1.3, settings).volume().brickData(0));
}

/// One live stroke: a 2 mm brush over 4 mm of the surface, then the read-out's update.
void BM_LayeredReadoutStroke(benchmark::State& state) {
    MaterialVolume v = layeredSphere(int(state.range(0)));
    LayeredReadoutSettings settings;
    settings.maxDepthVoxels = int(state.range(1));
    LayeredReadout seen(v, 1.3, settings);
    BrushSettings brush;
    brush.radius = 2.f;
    brush.value = MaterialSample{Rgb(3.f), Rgb(0.5f), Rgb(0.f)};
    size_t bricks = 0;
    for (auto _ : state) {
        state.PauseTiming();
        (void)v.takeDirtyBricks();
        paintStroke(v, brush, {Point3f(-6.f, 0.f, 8.f), Point3f(-2.f, 3.f, 9.f)});
        const std::vector<int> dirty = v.takeDirtyBricks();
        state.ResumeTiming();
        bricks = seen.update(v, dirty).size();
    }
    state.counters["bricks_rewritten"] = double(bricks);
    state.counters["bricks_total"] = double(v.brickCount());
}

/// The first stroke on a homogeneous volume (the app's default scene at start): the read-out
/// was the volume itself; the update pays the smoothed inside mask once.
void BM_LayeredReadoutFirstStroke(benchmark::State& state) {
    const int resolution = int(state.range(0));
    const SceneObject o =
        makeObject(makeSphere(10.f, 4), resolution, MaterialSample{Rgb(1.f), Rgb(0.9f), Rgb(0.f)});
    LayeredReadoutSettings settings;
    settings.maxDepthVoxels = int(state.range(1));
    BrushSettings brush;
    brush.radius = 2.f;
    brush.value = MaterialSample{Rgb(3.f), Rgb(0.5f), Rgb(0.f)};
    size_t bricks = 0;
    for (auto _ : state) {
        state.PauseTiming();
        MaterialVolume v = *o.material;
        LayeredReadout seen(v, 1.3, settings);
        (void)v.takeDirtyBricks();
        paintStroke(v, brush, {Point3f(-6.f, 0.f, 8.f), Point3f(-2.f, 3.f, 9.f)});
        const std::vector<int> dirty = v.takeDirtyBricks();
        state.ResumeTiming();
        bricks = seen.update(v, dirty).size();
    }
    state.counters["bricks_rewritten"] = double(bricks);
}

}  // namespace

BENCHMARK(BM_LayeredReadoutFirstStroke)
    ->ArgsProduct({{128}, {8}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_VolumeCopy)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LayeredReadoutBuild)
    ->ArgsProduct({{64, 128}, {16, 48}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_LayeredReadoutStroke)
    ->ArgsProduct({{64, 128}, {8, 16, 48}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_GpuGather)
    ->ArgsProduct({{640, 1280}, {8, 32, 128, 256}, {CAMERA}})
    ->ArgsProduct({{640, 1280}, {32}, {WINDOW}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

namespace {

/// `bench_dipole --reference-error`: radiance of the centre of a lit slab face, image-space
/// dipole / better dipole vs the reference path tracer (subsurface only, dielectric boundary).
int referenceError(float eta) {
    // Jensen 2001 skin1 (mm⁻¹), g = 0 so σs = σs′; 60×60×20 mm box, face at z = 10 mm.
    MaterialSample m;
    m.sigma_s = Rgb(0.74f, 0.88f, 1.01f);
    m.sigma_t = m.sigma_s + Rgb(0.032f, 0.17f, 0.48f);
    Scene s;
    SceneObject obj;
    obj.mesh = makeBox({60.f, 60.f, 20.f});
    obj.material = std::make_shared<MaterialVolume>(GridSpec::around(obj.mesh.bounds(), 32), m);
    s.objects.push_back(std::move(obj));
    Light l;
    l.type = Light::Type::Directional;
    l.direction = {0.f, 0.f, -1.f};
    l.intensity = Rgb(1.f);  // W/mm²
    s.lights.push_back(l);
    s.camera.position = {0.f, 0.f, 80.f};
    s.camera.orthographic = true;
    s.eta = eta;
    // Reference: 8×8 pixels over the central 0.8 mm.
    Scene ref = s;
    ref.camera.orthoHeight = 0.8f;
    ref.camera.width = ref.camera.height = 8;
    reference::ReferenceOptions opt;
    opt.spp = 3 * 2048;
    opt.subsurfaceOnly = true;
    const reference::ReferenceImage pt = reference::renderReference(ref, opt);
    Rgb ptMean(0.f), ptVar(0.f);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            ptMean += pt.mean.at(x, y) / 64.f;
            ptVar += pt.variance.at(x, y) / (64.f * 64.f);
        }
    std::printf(
        "reference path tracer: %d spp, %.1f s: L = (%.5f, %.5f, %.5f) ± (%.5f, %.5f, %.5f) W/(mm² "
        "sr)\n",
        pt.spp, pt.seconds, ptMean.r, ptMean.g, ptMean.b, std::sqrt(ptVar.r), std::sqrt(ptVar.g),
        std::sqrt(ptVar.b));
    // Image-space gather: 400×400 pixels over the central 40 mm (0.1 mm pixels).
    s.camera.orthoHeight = 40.f;
    s.camera.width = s.camera.height = 400;
    for (Model model : {Model::Dipole, Model::BetterDipole}) {
        GatherSettings gs;
        gs.model = model;
        gs.importanceSamples = 96;
        gs.uniformSamples = 32;
        const GatherResult g = renderImageSpaceDipole(s, gs);
        Rgb mean(0.f);
        for (int y = 196; y < 204; ++y)
            for (int x = 196; x < 204; ++x)
                mean += g.radiance.at(x, y) / 64.f;
        std::printf(
            "%-14s image-space: L = (%.5f, %.5f, %.5f), relative error vs reference (%+.1f%%, "
            "%+.1f%%, %+.1f%%)\n",
            modelName(model), mean.r, mean.g, mean.b, 100.f * (mean.r / ptMean.r - 1.f),
            100.f * (mean.g / ptMean.g - 1.f), 100.f * (mean.b / ptMean.b - 1.f));
    }
    // Directional dipole at normal incidence, semi-infinite plane, uniform E:
    // L = T₂₁ T₁₂ E ∫ S_d dA. The radial profile is R = S_d·4πC_φ(1/η) (Profiles.h), so
    // ∫ S_d dA = ρ/(π(1 − 2C₁(1/η))) (Frisvad et al. 2014's 1/(4C_φ(1/η)) exitance→radiance
    // factor; it is 1 at η = 1).
    const double ft = 1.0 - fresnelDielectric(1.0, eta);
    const double toRadiance =
        1.0 / (3.14159265358979323846 * (1.0 - 2.0 * fresnelMoment(1, 1.0 / double(eta))));
    Rgb dir;
    for (int c = 0; c < 3; ++c) {
        const double rho =
            totalReflectance(Model::Directional, fromReduced(m.sigma_t[c], m.sigma_s[c], eta));
        dir[c] = float(ft * ft * rho * toRadiance);
    }
    std::printf(
        "%-14s plane, closed: L = (%.5f, %.5f, %.5f), relative error vs reference (%+.1f%%, "
        "%+.1f%%, %+.1f%%)\n",
        "dirpole", dir.r, dir.g, dir.b, 100.f * (dir.r / ptMean.r - 1.f),
        100.f * (dir.g / ptMean.g - 1.f), 100.f * (dir.b / ptMean.b - 1.f));
    // Energy-normalised directional dipole (docs/methods/dipole.md §1): S_d ×
    // dirpoleEnergyScale(α′, η, target), α′ = σs′/σt′ (g = 0 here, so σs′ = σs); the exact
    // target (the renderers' default) also applies the exit-angle correction along the view
    // (the normal here, t = 1).
    const DirpoleExitTable exit(eta);
    for (EnergyTarget target : {EnergyTarget::ExactHalfSpace, EnergyTarget::BetterDipole}) {
        Rgb dirN;
        for (int c = 0; c < 3; ++c) {
            const double alphaP = double(m.sigma_s[c] / m.sigma_t[c]);
            const double correction =
                target == EnergyTarget::ExactHalfSpace ? exit.correction(alphaP, 1.0) : 1.0;
            dirN[c] = dir[c] * float(dirpoleEnergyScale(alphaP, eta, target) * correction);
        }
        std::printf(
            "%-14s normalised (%s):   L = (%.5f, %.5f, %.5f), relative error vs reference "
            "(%+.1f%%, %+.1f%%, %+.1f%%)\n",
            "dirpole", energyTargetName(target), dirN.r, dirN.g, dirN.b,
            100.f * (dirN.r / ptMean.r - 1.f), 100.f * (dirN.g / ptMean.g - 1.f),
            100.f * (dirN.b / ptMean.b - 1.f));
    }
    return 0;
}

double medianOf(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

template <class F>
double wallMs(F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// `bench_dipole --light-view-cost`: cost of gathering the light views (Mertens et al. 2005 §7.1,
/// docs/methods/dipole.md §3d) on the back-lit thin/thick scene at 256×192, CPU gather (32 spp)
/// and GL provider (16 spp per frame), relative to the camera-only gather measured in the same
/// run. "full set per view" gives every view the whole per-pixel budget (importance and uniform
/// counts × views), which is exactly the sample and visibility-test work of the scheme before
/// the budget split (every view drew all N samples); "split budget" is viewSamples().
int lightViewCost() {
    Scene scene =
        loadScene(std::string(LUCENT_SOURCE_DIR) + "/resources/scenes/backlit_thin_thick.json");
    scene.camera.width = 256;
    scene.camera.height = 192;
    GatherSettings gs;
    gs.eta = scene.eta;
    gs.importanceSamples = 24;
    gs.uniformSamples = 8;
    const ImageSpaceViews views = buildImageSpaceViews(scene, gs, LightViewSettings{});
    const int viewCount = 1 + int(views.lights.size());
    GatherSettings full = gs;
    full.importanceSamples *= viewCount;
    full.uniformSamples *= viewCount;
    std::printf("back-lit thin/thick, 256x192, %d view(s) (camera + %d light views)\n", viewCount,
                viewCount - 1);
    const int reps = 5;
    std::vector<double> tCam, tSplit, tFull;
    for (int r = 0; r < reps; ++r) {  // interleaved, median of 5
        tCam.push_back(
            wallMs([&] { benchmark::DoNotOptimize(gatherImageSpace(views.camera, gs)); }));
        tSplit.push_back(wallMs(
            [&] { benchmark::DoNotOptimize(gatherImageSpace(views.camera, views.lights, gs)); }));
        tFull.push_back(wallMs(
            [&] { benchmark::DoNotOptimize(gatherImageSpace(views.camera, views.lights, full)); }));
    }
    const double cam = medianOf(tCam);
    std::printf("CPU gather, 32 spp (median of %d):\n", reps);
    std::printf("  camera only                 %8.1f ms   1.00x\n", cam);
    std::printf("  light views, split budget   %8.1f ms   %.2fx\n", medianOf(tSplit),
                medianOf(tSplit) / cam);
    std::printf("  light views, full set/view  %8.1f ms   %.2fx\n", medianOf(tFull),
                medianOf(tFull) / cam);

    std::string reason;
    if (!gpu::GlContext::isHeadlessAvailable(&reason)) {
        std::printf("GL provider: skipped (no headless GL: %s)\n", reason.c_str());
        return 0;
    }
    const auto ctx = gpu::GlContext::createHeadless();
    gpu::SceneRenderer renderer;
    renderer.create();
    DipoleSubsurfaceProvider provider;
    provider.create();
    const int mesh = renderer.addMesh(scene.objects[0].mesh);
    renderer.setLights(scene.lights);
    renderer.setCamera(scene.camera);
    gpu::DirectSettings ds;
    ds.subsurfaceOnly = true;
    renderer.setSettings(ds);
    provider.setMaterial(scene.objects[0].material.get());
    renderer.setSubsurfaceProvider(&provider);
    struct Config {
        const char* name;
        bool lightViews;
        int spf;
    };
    const Config configs[3] = {{"camera only                ", false, 16},
                               {"light views, split budget  ", true, 16},
                               {"light views, full set/view ", true, 16 * viewCount}};
    std::vector<double> frameMs[3];
    for (int round = 0; round < 2; ++round)
        for (int c = 0; c < 3; ++c) {
            ProviderSettings ps;
            ps.eta = scene.eta;
            ps.meshId = mesh;
            ps.samplesPerFrame = configs[c].spf;
            ps.lightViews = configs[c].lightViews;
            ps.maxFrames = 1000;
            ps.convergenceThreshold = 0.f;
            provider.setSettings(ps);
            provider.reset();
            renderer.render();           // reset frame: irradiance pass and light views (not timed)
            for (int f = 0; f < 4; ++f)  // the stats read-back waits for the dispatch
                frameMs[c].push_back(wallMs([&] { renderer.render(); }));
        }
    const double camGl = medianOf(frameMs[0]);
    std::printf("GL provider (%s), 16 spp per frame, whole frame (median of 8 frames):\n",
                ctx->renderer().c_str());
    for (int c = 0; c < 3; ++c)
        std::printf("  %s%8.1f ms   %.2fx\n", configs[c].name, medianOf(frameMs[c]),
                    medianOf(frameMs[c]) / camGl);
    renderer.setSubsurfaceProvider(nullptr);
    provider.destroy();
    renderer.destroy();
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i)
        if (std::string(argv[i]) == "--light-view-cost")
            return lightViewCost();
    for (int i = 1; i < argc; ++i)
        if (std::string(argv[i]) == "--reference-error") {
            for (float eta : {1.0f, 1.3f}) {
                std::printf("eta = %.2f\n", double(eta));
                referenceError(eta);
            }
            return 0;
        }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
