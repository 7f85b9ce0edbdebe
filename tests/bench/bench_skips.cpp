// SPDX-License-Identifier: MIT
/// @file
/// @brief The engine's skips (issue 15, "skip what a scene doesn't need") measured on and off in
/// one process: the same scene, the median of `--repeats` runs each, the saving as a ratio and
/// the change in the answer. Not a Google Benchmark: it prints the table of docs/benchmarks.md,
/// "Skips". CPU paths only (SSLPV solver, image-space dipole, SSLPV's CPU renderImage), so it
/// runs without GL.
///
///     bench_skips [--repeats 7] [--only "combined SSLPV"]

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/combined/Combined.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Image.h>
#include <lucent/core/Timer.h>
#include <lucent/dipole/ImageSpace.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Presets.h>
#include <lucent/methods/RenderImage.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/LightReach.h>
#include <lucent/scene/Scene.h>
#include <lucent/sslpv/SslpvBench.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

using namespace lucent;

namespace {

/// One row of the table: the skip on and off, median ms each, and what changed in the answer.
struct Row {
    std::string skip, scene;
    double onMs = 0.0, offMs = 0.0;
    std::string fired, error;
};

/// Median wall time of `repeats` calls of `run` (after one warm-up call).
double medianOf(int repeats, const std::function<void()>& run) {
    run();
    std::vector<double> ms;
    for (int i = 0; i < repeats; ++i) {
        const Timer t;
        run();
        ms.push_back(t.elapsedMs());
    }
    return medianMs(ms);
}

std::string fmt(const char* f, double a, double b = 0.0) {
    char buf[160];
    std::snprintf(buf, sizeof buf, f, a, b);
    return buf;
}

/// Largest |a − b| over two grids' raw data, relative to the largest |b|.
double maxRelDiff(const std::vector<float>& a, const std::vector<float>& b) {
    double d = 0.0, m = 0.0;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
        d = std::max(d, double(std::abs(a[i] - b[i])));
        m = std::max(m, double(std::abs(b[i])));
    }
    return m > 0.0 ? d / m : d;
}

/// Median ms of a re-propagation (material marked dirty, then solve()).
double repropagateMs(sslpv::SslpvSolver& solver, int repeats) {
    return medianOf(repeats, [&] {
        solver.markMaterialDirty();
        solver.solve();
    });
}

sslpv::SslpvSolver makeSolver(const sslpv::SslpvBenchSetup& s, sslpv::SslpvOptions o) {
    o.removeExitant = s.sinks;
    sslpv::SslpvSolver solver(o);
    solver.setMaterial(s.material, s.eta);
    solver.setInjectionSamples(s.texels);
    return solver;
}

/// SslpvOptions::skipEmptySlices (active bricks) on and off; re-propagates each run.
Row sslpvBricks(sslpv::SslpvBenchScene scene, int steps, int repeats) {
    const sslpv::SslpvBenchSetup s = sslpv::makeSslpvBenchSetup(scene, 32, /*het=*/true);
    sslpv::SslpvSolver on = makeSolver(s, {.maxSteps = steps, .skipEmptySlices = true});
    sslpv::SslpvSolver off = makeSolver(s, {.maxSteps = steps, .skipEmptySlices = false});
    Row r{"SSLPV active bricks", "", 0, 0, "", ""};
    r.scene = std::string(sslpv::sslpvBenchSceneName(scene)) + " 32³ het, " +
              std::to_string(steps) + " steps";
    r.onMs = repropagateMs(on, repeats);
    r.offMs = repropagateMs(off, repeats);
    r.fired = fmt("%.0f%% of the dense cells computed",
                  100.0 * double(on.stats().cellsComputed) / double(off.stats().cellsComputed));
    r.error =
        fmt("max |Δ| %.1g (exact)", maxRelDiff(on.accumulation().raw(), off.accumulation().raw()));
    return r;
}

/// SslpvOptions::stopEpsilon = 1e-4 against running all maxSteps.
Row sslpvEarlyStop(int repeats) {
    const sslpv::SslpvBenchSetup s =
        sslpv::makeSslpvBenchSetup(sslpv::SslpvBenchScene::Sphere, 32, /*het=*/false);
    const float eps = 1e-4f;
    sslpv::SslpvSolver on = makeSolver(s, {.maxSteps = 512, .stopEpsilon = eps});
    sslpv::SslpvSolver off = makeSolver(s, {.maxSteps = 512});
    Row r{"SSLPV early stop (ε = 1e-4)", "sphere 32³ hom, 512 steps", 0, 0, "", ""};
    r.onMs = repropagateMs(on, repeats);
    r.offMs = repropagateMs(off, repeats);
    r.fired = fmt("%.0f of %.0f steps", on.stats().stepsUsed, off.stats().stepsUsed);
    const Rgb a = on.accumulation().flux(), b = off.accumulation().flux();
    double rel = 0.0;
    for (int c = 0; c < 3; ++c)
        rel = std::max(rel, double(std::abs(a[c] - b[c]) / b[c]));
    r.error = fmt("accumulated flux −%.2g rel.; max |Δ| %.2g", rel,
                  maxRelDiff(on.accumulation().raw(), off.accumulation().raw()));
    return r;
}

/// The solver's dirty flags: solve() with nothing changed against a forced re-propagation.
Row sslpvUnchanged(int repeats) {
    const sslpv::SslpvBenchSetup s =
        sslpv::makeSslpvBenchSetup(sslpv::SslpvBenchScene::Sphere, 32, /*het=*/true);
    sslpv::SslpvSolver solver = makeSolver(s, {.maxSteps = 32});
    solver.solve();
    const std::vector<float> before = solver.accumulation().raw();
    Row r{"SSLPV unchanged inputs (dirty flags)",
          "sphere 32³ het, 32 steps, idle frame",
          0,
          0,
          "",
          ""};
    r.onMs = medianOf(repeats, [&] { solver.solve(); });
    const bool idle = !solver.stats().repropagated && !solver.stats().reinjected;
    r.offMs = repropagateMs(solver, repeats);
    r.fired = idle ? "no re-injection, no re-propagation" : "DID NOT FIRE";
    r.error = fmt("max |Δ| %.1g (exact)", maxRelDiff(solver.accumulation().raw(), before));
    return r;
}

/// A 30×30×1 mm slab (skin-like σ, a 64-cell grid), a directional light, an orthographic
/// camera looking down at its top face with 200² pixels over `viewMm`.
Scene slab(Vector3f lightDirection, float viewMm) {
    MaterialSample m;
    m.sigma_s = Rgb(2.f, 1.f, 0.5f);
    m.sigma_t = m.sigma_s + Rgb(0.05f, 0.1f, 0.2f);
    Scene s;
    SceneObject obj;
    obj.mesh = makeBox({30.f, 30.f, 1.f});
    obj.material = std::make_shared<MaterialVolume>(GridSpec::around(obj.mesh.bounds(), 64), m);
    s.objects.push_back(std::move(obj));
    Light l;
    l.type = Light::Type::Directional;
    l.direction = lightDirection;
    l.intensity = Rgb(1.f);
    s.lights.push_back(l);
    s.camera.position = {0.f, 0.f, 50.f};
    s.camera.target = {0.f, 0.f, 0.f};
    s.camera.orthographic = true;
    s.camera.orthoHeight = viewMm;
    s.camera.width = s.camera.height = 200;
    return s;
}

/// Over the central 40×40 pixels (green), B_exact the half-space value: "mean |B/B_exact − 1|
/// (mean B/B_exact − 1)", i.e. the spread and the bias.
std::string centreError(const ImageRgb& b, double exact) {
    double sum = 0.0, signedSum = 0.0;
    for (int y = 80; y < 120; ++y)
        for (int x = 80; x < 120; ++x) {
            const double e = double(b.at(x, y).g) / exact - 1.0;
            sum += std::abs(e);
            signedSum += e;
        }
    return fmt("%.4f (%+.4f)", sum / 1600.0, signedSum / 1600.0);
}

double halfSpaceGreen(double R) {
    // F_t ∫₀^R R_d(r) 2πr dr of the green channel (trapezoid in r, 1 µm steps).
    const dipole::DipoleProfile p = dipole::DipoleProfile::jensen(0.1, 1.0, 1.3);
    double sum = 0.0;
    const double h = 1e-3;
    for (double r = 0.5 * h; r < R; r += h)
        sum += p.Rd(r) * 2.0 * M_PI * r * h;
    return (1.0 - fresnelDielectric(1.0, 1.3)) * sum;
}

dipole::GatherSettings gather() {
    dipole::GatherSettings gs;
    gs.importanceSamples = 24;
    gs.uniformSamples = 8;
    return gs;
}

/// LightViewSettings::threshold (skip on) against gatherAll, front-lit slab (fraction 0).
Row dipoleLightViews(int repeats) {
    const Scene s = slab({0.f, 0.f, -1.f}, 40.f);
    dipole::LightViewSettings all;
    all.gatherAll = true;
    dipole::GatherResult on, off;
    std::vector<dipole::LightViewReport> rep;
    Row r{"dipole light view when nothing is back-lit",
          "front-lit slab, 200², view 512²",
          0,
          0,
          "",
          ""};
    r.onMs = medianOf(repeats, [&] { on = dipole::renderImageSpaceDipole(s, gather(), {}, &rep); });
    const bool skipped = rep.at(0).built && !rep[0].used;
    r.offMs = medianOf(repeats, [&] { off = dipole::renderImageSpaceDipole(s, gather(), all); });
    const double exact = halfSpaceGreen(15.0);
    r.fired = skipped ? fmt("back-lit fraction %.2g: view not gathered", rep[0].backlitFraction)
                      : "DID NOT FIRE";
    r.error = "centre mean |B/B_exact − 1| (bias): " + centreError(on.exitance, exact) + " on, " +
              centreError(off.exitance, exact) + " off";
    return r;
}

/// GatherSettings::maxRadius = 1 mm (the max-radius cut-off) against the unlimited gather.
Row dipoleMaxRadius(int repeats) {
    const Scene s = slab({0.f, 0.f, -1.f}, 40.f);
    dipole::LightViewSettings none;
    none.enabled = false;
    const dipole::ImageSpaceViews views = dipole::buildImageSpaceViews(s, gather(), none);
    dipole::GatherSettings cut = gather(), full = gather();
    const float radius = 1.f;
    cut.maxRadius = radius;
    dipole::GatherResult on, off;
    Row r{"dipole max-radius cut-off (1 mm)", "front-lit slab, 200², camera only", 0, 0, "", ""};
    r.onMs = medianOf(repeats, [&] { on = dipole::gatherImageSpace(views.camera, cut); });
    r.offMs = medianOf(repeats, [&] { off = dipole::gatherImageSpace(views.camera, full); });
    r.fired = fmt("disc radius %.2f mm (R′ %.2f mm)", on.stats.maxRadius, off.stats.maxRadius);
    const double exact = halfSpaceGreen(15.0), kept = halfSpaceGreen(radius);
    r.error = fmt(
        "green −%.3f rel. (tail beyond 1 mm: %.3f)",
        1.0 -
            [&] {
                double a = 0.0, b = 0.0;
                for (int y = 80; y < 120; ++y)
                    for (int x = 80; x < 120; ++x) {
                        a += on.exitance.at(x, y).g;
                        b += off.exitance.at(x, y).g;
                    }
                return a / b;
            }(),
        1.0 - kept / exact);
    return r;
}

/// The light skip (RenderOptions::lightSkipEpsilon) against every light rendered: the SSLPV CPU
/// render of the 10 mm skin1 sphere lit by its sun, plus a spot aimed away from it and a point
/// light at half the skip threshold (a fill light nobody can see), each injected into the
/// grid when the skip is off.
Row lightSkip(int repeats) {
    Scene scene;  // resources/scenes/skin_sphere.json at 64² (the file's sun, η 1.4)
    scene.objects.push_back(makeObject(makeSphere(10.f, 4), 48, findPreset("skin1").sample()));
    scene.eta = 1.4f;
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = glm::normalize(Vector3f(-0.8f, -0.3f, -0.5f));
    sun.intensity = Rgb(3.f);
    scene.lights.push_back(sun);
    scene.camera.width = scene.camera.height = 64;
    Light away;
    away.type = Light::Type::Spot;
    away.position = Point3f(0.f, 40.f, 0.f);
    away.direction = Vector3f(0.f, 1.f, 0.f);
    away.intensity = Rgb(5e4f);
    scene.lights.push_back(away);
    Light dim;
    dim.position = Point3f(30.f, 10.f, 20.f);
    const Bounds3f b = objectBounds(scene);
    const float near = glm::length(dim.position - b.center()) - 0.5f * glm::length(b.extent());
    dim.intensity = Rgb(0.5f * LIGHT_SKIP_EPSILON * 3.f * near * near);
    scene.lights.push_back(dim);
    const methods::ParamSet grid = methods::ParamSet::fromAssignments({"grid=32"});
    methods::RenderOptions on, off;
    on.backend = off.backend = methods::Backend::Cpu;
    off.lightSkipEpsilon = -1.f;
    methods::RenderResult a, c;
    Row r{"lights that miss the object or give < ε",
          "skin1 sphere 64², SSLPV CPU 32³, sun + spot "
          "aimed away + point light at ε/2",
          0,
          0,
          "",
          ""};
    r.onMs = medianOf(repeats, [&] { a = methods::renderImage(scene, "sslpv", grid, on); });
    r.offMs = medianOf(repeats, [&] { c = methods::renderImage(scene, "sslpv", grid, off); });
    float moved = 0.f, peak = 0.f;
    for (int y = 0; y < a.radiance.height(); ++y)
        for (int x = 0; x < a.radiance.width(); ++x)
            for (int k = 0; k < 3; ++k) {
                moved = std::max(moved, std::abs(a.radiance.at(x, y)[k] - c.radiance.at(x, y)[k]));
                peak = std::max(peak, c.radiance.at(x, y)[k]);
            }
    r.fired = std::to_string(a.skippedLights.size()) + " of 3 lights skipped";
    r.error = fmt("largest pixel change %.2g of the peak (bound ε = %.2g)", moved / peak,
                  double(LIGHT_SKIP_EPSILON));
    return r;
}

/// The combined method's automatic SSLPV skip (CombinedSettings::autoSkipSslpv): a strongly
/// absorbing 10 mm sphere (σa = 2, σs′ = 1 mm⁻¹, 1/σ_tr = 0.24 mm) at the combined defaults
/// (Kernel split, SSLPV 32³, r_s = 4 cells): the dipole's far share is ≈ 10⁻¹¹, so SSLPV, its
/// kernel and the local estimate are left out.
Row combinedFarSkip(int repeats) {
    Scene scene;
    MaterialSample absorbing;
    absorbing.sigma_s = Rgb(1.f);
    absorbing.sigma_t = Rgb(3.f);
    scene.objects.push_back(makeObject(makeSphere(10.f, 4), 32, absorbing));
    Light l;
    l.position = {25.f, 20.f, 25.f};
    l.intensity = Rgb(1000.f);
    scene.lights.push_back(l);
    scene.camera.position = {0.f, 0.f, 40.f};
    scene.camera.width = scene.camera.height = 64;
    combined::CombinedSettings on, off;
    off.autoSkipSslpv = false;
    combined::CombinedResult a, c;
    Row r{"SSLPV part of the combined method when the dipole's far share <= 1e-3",
          "absorbing sphere (σa 2, σs′ 1 mm⁻¹) 64², combined defaults (kernel split, 32³, "
          "r_s 4 cells)",
          0,
          0,
          "",
          ""};
    r.onMs = medianOf(repeats, [&] { a = combined::renderCombined(scene, on); });
    r.offMs = medianOf(repeats, [&] { c = combined::renderCombined(scene, off); });
    float moved = 0.f, peak = 0.f;
    double sumA = 0.0, sumC = 0.0;
    for (int y = 0; y < a.radiance.height(); ++y)
        for (int x = 0; x < a.radiance.width(); ++x) {
            moved = std::max(
                moved, std::abs(luminance(a.radiance.at(x, y)) - luminance(c.radiance.at(x, y))));
            peak = std::max(peak, luminance(c.radiance.at(x, y)));
            sumA += double(luminance(a.radiance.at(x, y)));
            sumC += double(luminance(c.radiance.at(x, y)));
        }
    r.fired = a.plan.sslpvSkipped ? fmt("SSLPV skipped, far share %.2g", a.plan.farShare)
                                  : std::string("did not fire");
    // Which answer is right: a path-traced reference (cheap in this absorbing medium).
    reference::ReferenceOptions ro;
    ro.spp = 256;
    ro.subsurfaceOnly = true;
    ro.seed = 7;
    const reference::ReferenceImage ref = reference::renderReference(scene, ro);
    const std::vector<uint8_t> mask = bench::maskFromImage(ref.coverage);
    const auto relRmse = [&](const ImageRgb& img) {
        return bench::compareImages(img, ref.mean, &ref.variance, nullptr, &mask).channels[3];
    };
    r.error = fmt("largest pixel change %.2g of the peak, image sum %+.1f %%", moved / peak,
                  100.0 * (sumA - sumC) / sumC) +
              fmt("; rel. RMSE vs %.0f spp path-traced (floor %.3f): ", double(ref.spp),
                  relRmse(a.radiance).relRmseFloor) +
              fmt("on %.3f, off %.3f", relRmse(a.radiance).relRmse, relRmse(c.radiance).relRmse);
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    int repeats = 7;
    std::string only;  // run only the rows whose skip name contains this
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--repeats" && i + 1 < argc)
            repeats = std::max(1, std::atoi(argv[++i]));
        else if (a == "--only" && i + 1 < argc)
            only = argv[++i];
        else {
            std::fprintf(stderr, "usage: bench_skips [--repeats N] [--only SUBSTRING]\n");
            return 2;
        }
    }
    using Sslpv = sslpv::SslpvBenchScene;
    const std::vector<std::pair<std::string, std::function<Row()>>> builders = {
        {"empty bricks", [&] { return sslpvBricks(Sslpv::Sphere, 8, repeats); }},
        {"empty bricks", [&] { return sslpvBricks(Sslpv::Sphere, 32, repeats); }},
        {"empty bricks", [&] { return sslpvBricks(Sslpv::Spot, 8, repeats); }},
        {"early stop", [&] { return sslpvEarlyStop(repeats); }},
        {"unchanged inputs", [&] { return sslpvUnchanged(repeats); }},
        {"light views", [&] { return dipoleLightViews(repeats); }},
        {"max radius", [&] { return dipoleMaxRadius(repeats); }},
        {"lights", [&] { return lightSkip(repeats); }},
        {"combined SSLPV", [&] { return combinedFarSkip(repeats); }},
    };
    std::vector<Row> rows;
    for (const auto& [name, build] : builders)
        if (only.empty() || name.find(only) != std::string::npos)
            rows.push_back(build());
    std::printf(
        "| skip | scene | on ms | off ms | off/on | fired | answer "
        "|\n|---|---|---|---|---|---|---|\n");
    for (const Row& r : rows)
        std::printf("| %s | %s | %.3g | %.3g | %.2f× | %s | %s |\n", r.skip.c_str(),
                    r.scene.c_str(), r.onMs, r.offMs, r.offMs / r.onMs, r.fired.c_str(),
                    r.error.c_str());
    return 0;
}
