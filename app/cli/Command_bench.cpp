// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli bench sslpv`: timing of the SSLPV propagation (docs/benchmarks.md, SSLPV)
/// next to a memory-bandwidth floor measured in the same run.

#include "CliArgs.h"

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Timer.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/sslpv/SslpvGl.h>
#include <lucent/sslpv/SslpvProvider.h>
#include <lucent/sslpv/SslpvRenderer.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

/// Process CPU time (all threads), ms: unlike wall time, not inflated when the machine is
/// shared and this process waits for a core.
double cpuMs() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

/// The paper's configuration (§5, Table 1): every cell of the N³ grid is material and is
/// propagated (no sinks), light injected on the top face. Heterogeneous: per-cell σt, σs′, g
/// drawn from a seeded RNG, so the per-cell factor arrays are read every step.
CoarseMaterial benchMaterial(int n, bool heterogeneous) {
    CoarseMaterial m;
    m.spec.resolution = n;
    m.spec.voxelSize = 1.f;
    const size_t count = m.spec.voxelCount();
    m.insideFraction.assign(count, 1.f);
    Pcg32 rng(1234);
    for (int c = 0; c < 3; ++c) {
        m.sigma_t[c].assign(count, 1.f);
        m.sigma_s[c].assign(count, 0.8f);
        m.g[c].assign(count, 0.2f);
        if (heterogeneous)
            for (size_t k = 0; k < count; ++k) {
                m.sigma_t[c][k] = 0.5f + 1.5f * rng.uniform();
                m.sigma_s[c][k] = m.sigma_t[c][k] * rng.uniform();
                m.g[c][k] = 1.6f * rng.uniform() - 0.8f;
            }
    }
    m.homogeneous = !heterogeneous;
    return m;
}

int runFit(const Args& args);

int runBench(const std::vector<std::string>& argv) {
    const Args args(argv,
                    {"grid", "steps", "sh", "threads", "repeats", "eta", "linear", "diffusion",
                     "iterations", "transport", "fit", "gain", "per-step", "per-step-transport"},
                    {"heterogeneous", "gl", "fp16", "dense", "json", "search", "solve-beta"});
    if (args.positional().size() == 1 && args.positional().front() == "sslpv-fit")
        return runFit(args);
    if (args.positional().size() != 1 || args.positional().front() != "sslpv")
        LUCENT_THROW(ValueError, "expected the benchmark name 'sslpv' or 'sslpv-fit' (see --help)");
    const int n = args.intOr("grid", 32, 4, 256);
    const int steps = args.intOr("steps", 8, 1, 4096);
    const int order = args.intOr("sh", 1, 1, 2);
    const int threads = args.intOr("threads", maxThreads(), 1, 256);
    const int repeats = args.intOr("repeats", 50, 3, 100000);
    const bool het = args.has("heterogeneous");
    const bool gl = args.has("gl");
    if (args.has("fp16") && !gl)
        LUCENT_THROW(ValueError, "--fp16 needs --gl");
    const ThreadLimit limit(threads);

    SslpvSolver solver({.order = order,
                        .maxSteps = steps,
                        .skipAccumulateSteps = 0,
                        .removeExitant = false,
                        .skipEmptySlices = !args.has("dense")});
    solver.setMaterial(benchMaterial(n, het), 1.3f);
    std::vector<SslpvInjectionSample> texels;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            texels.push_back({Point3f(x + 0.5f, y + 0.5f, float(n)), Normal3f(0, 0, 1),
                              glm::normalize(Vector3f(0.3f, 0.1f, -1.f)), Rgb(1.f)});
    solver.setInjectionSamples(std::move(texels));

    // Warm-up, then repeated re-propagations (what a paint stroke triggers).
    for (int i = 0; i < 3; ++i) {
        solver.markMaterialDirty();
        solver.solve();
    }
    std::vector<double> solveMs, stepsMs;
    const double cpu0 = cpuMs();
    for (int i = 0; i < repeats; ++i) {
        solver.markMaterialDirty();
        const Timer t;
        solver.solve();
        solveMs.push_back(t.elapsedMs());
        stepsMs.push_back(solver.stats().stepsMs);
    }
    const double cpuPerSolve = (cpuMs() - cpu0) / repeats;

    // Bandwidth floor, same run, same threads: the least traffic one step can have without the
    // stencil — stream the source planes into the destination (read + write) and add them into
    // the accumulation planes (read + read + write), plus reading the factor planes when
    // heterogeneous. Same plane sizes as the solver's grids.
    const size_t plane = size_t(n + 2) * (n + 2) * (n + 2);
    const size_t planes = size_t(3) * shCount(order);
    const size_t factorPlanes = het ? 3 * (order + 1) : 0;
    std::vector<float> src(plane * planes, 1.f), dst(plane * planes), acc(plane * planes),
        fac(std::max<size_t>(plane * factorPlanes, 1), 0.5f);
    std::vector<double> floorMs;
    volatile float sink = 0.f;
    for (int i = 0; i < repeats + 3; ++i) {
        const Timer t;
        for (int s = 0; s < steps; ++s) {
            parallelFor(
                0, int64_t(planes),
                [&](int64_t b, int64_t e) {
                    for (int64_t p = b; p < e; ++p) {
                        const float* __restrict a = &src[size_t(p) * plane];
                        float* __restrict d = &dst[size_t(p) * plane];
                        float* __restrict c = &acc[size_t(p) * plane];
                        std::memcpy(d, a, plane * sizeof(float));
                        for (size_t k = 0; k < plane; ++k)
                            c[k] += a[k];
                    }
                },
                1);
            if (het) {
                float f = 0.f;
                for (size_t k = 0; k < fac.size(); k += 16)
                    f += fac[k];  // one read per line
                sink = sink + f;
            }
            std::swap(src, dst);
        }
        if (i >= 3)
            floorMs.push_back(t.elapsedMs());
    }
    (void)sink;

    // GL compute path: the same propagation on the GPU (injection and factors from the CPU).
    double glGpuMs = 0.0, glCpuMs = 0.0;
    if (gl) {
        std::string reason;
        if (!gpu::GlContext::isHeadlessAvailable(&reason))
            LUCENT_THROW(GpuError, "--gl: no headless OpenGL 4.5 context: ", reason);
        auto ctx = gpu::GlContext::createHeadless();
        SslpvGlPropagator prop(args.has("fp16") ? SslpvGlStorage::Float16
                                                : SslpvGlStorage::Float32);
        const int glRepeats = std::max(3, std::min(repeats, 10));  // llvmpipe is slow
        prop.propagate(solver);                                    // warm-up (shader JIT)
        std::vector<double> g, c;
        for (int i = 0; i < glRepeats; ++i) {
            prop.propagate(solver);
            g.push_back(prop.timings().propagateGpuMs);
            c.push_back(prop.timings().uploadCpuMs + prop.timings().propagateCpuMs +
                        prop.timings().readbackCpuMs);
        }
        glGpuMs = median(g);
        glCpuMs = median(c);
        prop.destroy();
        std::printf("%sGL %s (%s): propagation %.3f ms GPU timer, %.3f ms with upload + readback\n",
                    args.has("json") ? "# " : "", ctx->renderer().c_str(),
                    args.has("fp16") ? "fp16" : "fp32", glGpuMs, glCpuMs);
    }

    const double msSolve = median(solveMs);
    const double msSteps = median(stepsMs);
    const double msPerStep = msSteps / steps;
    const double floorPerStep = median(floorMs) / steps;
    const double paperMs = 1.67;  // GTX 580, 32³, 8 steps, heterogeneous (Table 1, Fig. 6)
    if (args.has("json")) {
        std::printf(
            "{\"benchmark\": \"sslpv\", \"grid\": %d, \"steps\": %d, \"sh_order\": %d, "
            "\"heterogeneous\": %s, \"dense\": %s, \"threads\": %d, \"repeats\": %d, "
            "\"ms_per_solve\": %.4f, "
            "\"cpu_ms_per_solve\": %.4f, "
            "\"ms_propagation\": %.4f, \"ms_per_step\": %.5f, \"floor_ms_per_step\": %.5f, "
            "\"ratio_to_floor\": %.3f, \"gl_gpu_ms\": %.4f, \"gl_total_ms\": %.4f, "
            "\"paper_ms_gtx580_32_8_het\": %.2f}\n",
            n, steps, order, het ? "true" : "false", args.has("dense") ? "true" : "false", threads,
            repeats, msSolve, cpuPerSolve, msSteps, msPerStep, floorPerStep,
            msPerStep / floorPerStep, glGpuMs, glCpuMs, paperMs);
    } else {
        std::printf(
            "SSLPV CPU propagation: %d^3 cells, %d steps, SH order %d, %s, %s, %d "
            "thread(s)\n",
            n, steps, order, het ? "heterogeneous" : "homogeneous",
            args.has("dense") ? "dense" : "empty slices skipped", threads);
        std::printf("  median over %d solves after warm-up\n", repeats);
        std::printf("  solve (factors + propagation): %.3f ms wall, %.3f ms CPU (all threads)\n",
                    msSolve, cpuPerSolve);
        std::printf("  propagation steps:             %.3f ms (%.4f ms/step)\n", msSteps,
                    msPerStep);
        std::printf("  bandwidth floor:               %.4f ms/step  -> ratio %.2f\n", floorPerStep,
                    msPerStep / floorPerStep);
        std::printf("  paper (GTX 580, 32^3, 8 steps, heterogeneous): %.2f ms\n", paperMs);
    }
    return 0;
}

// ---------------------------------------------------------------------------------------------
// `lucent-cli bench sslpv-fit`: the calibrated mode's fit (docs/methods/sslpv.md).

/// One thick-slab configuration of the fit.
struct FitCase {
    float albedo;   ///< α′ = σs′/σt (reduced)
    float cellMfp;  ///< Δx·σt: cell size in reduced mean free paths
};

/// Thick slab of the fit: an N³ grid of cell size Δx, the slab filling cells [1, N−2]³ (sinks
/// around it), σt = 1 mm⁻¹, σs′ = α′σt, g = 0, η. Unit-flux texels at normal incidence on the
/// central 8×8 cells of the top face (2×2 texels per cell). Returns the exitant radiance
/// integrated over the top face per unit incident flux, Σ_i L_o(x_i)·Δx² / Φ (mm²·sr⁻¹ /mm²:
/// sr⁻¹), at normal view without Fresnel T(ω_o) and without the gain (raw 1/η² only): by
/// superposition it equals L_o/E of a laterally infinite slab under uniform irradiance E.
double slabResponse(const FitCase& fc, int n, const SslpvOptions& base, float eta, int* stepsUsed) {
    const float h = fc.cellMfp;  // σt = 1 mm⁻¹
    CoarseMaterial m;
    m.spec.resolution = n;
    m.spec.voxelSize = h;
    m.spec.origin = Point3f(0.f);
    const size_t count = m.spec.voxelCount();
    m.insideFraction.assign(count, 0.f);
    for (int c = 0; c < 3; ++c) {
        m.sigma_t[c].assign(count, 1.f);
        m.sigma_s[c].assign(count, fc.albedo);
        m.g[c].assign(count, 0.f);
    }
    for (int z = 1; z < n - 1; ++z)
        for (int y = 1; y < n - 1; ++y)
            for (int x = 1; x < n - 1; ++x)
                m.insideFraction[m.spec.linearIndex({x, y, z})] = 1.f;
    m.homogeneous = true;
    const float zTop = float(n - 1) * h;
    std::vector<SslpvInjectionSample> texels;
    const int lo = n / 2 - 4;
    double phi = 0.0;
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) {
            texels.push_back(
                {Point3f((lo + 0.25f + 0.5f * i) * h, (lo + 0.25f + 0.5f * j) * h, zTop),
                 Normal3f(0, 0, 1), Vector3f(0, 0, -1), Rgb(1.f)});
            phi += 1.0;
        }
    SslpvSolver solver(base);
    solver.setMaterial(m, eta);
    solver.setInjectionSamples(std::move(texels));
    const SslpvStats& st = solver.solve();
    if (stepsUsed)
        *stepsUsed = st.stepsUsed;
    const float gain = base.calibration.gain[base.order - 1];
    double sum = 0.0;
    for (int y = 1; y < n - 1; ++y)
        for (int x = 1; x < n - 1; ++x)
            sum += double(solver
                              .radiance(Point3f((x + 0.5f) * h, (y + 0.5f) * h, zTop),
                                        Normal3f(0, 0, 1))
                              .y) *
                   double(solver.exitScale() / gain) * double(h) * double(h);
    return sum / phi;
}

/// The fit's target for the quantity of slabResponse(): Jensen et al. 2001's BSSRDF
/// S_d = F_t(ω_i) R_d F_t(ω_o)/π (Eq. 4 of the paper, seed 004 Table 1) integrated over the
/// surface for uniform normal irradiance gives L_o/E = F_t(0)·R_d·F_t(ω_o)/π; slabResponse()
/// leaves out F_t(ω_o), so the target is F_t(0)·R_d/π with R_d the classical dipole's total
/// diffuse reflectance.
double slabTarget(float albedo, float eta) {
    const dipole::ScalarMedium med = dipole::fromReduced(1.f, albedo, eta);
    const double rd = dipole::totalReflectance(dipole::Model::Dipole, med);
    constexpr double PI_D = 3.14159265358979323846;
    return (1.0 - dipole::fresnelReflectance(1.0, eta)) * rd / PI_D;
}

struct FitResult {
    double gain = 1.0;          ///< G minimising Σ log² (G·response/target)
    double rmsLog = 0.0;        ///< RMS of log(G·response/target)
    double maxAbsRel = 0.0;     ///< max |G·response/target − 1|
    std::vector<double> ratio;  ///< response/target per case
    std::vector<int> steps;
};

FitResult evaluateFit(const std::vector<FitCase>& cases, int n, const SslpvOptions& base,
                      float eta) {
    FitResult r;
    double sumLog = 0.0;
    for (const FitCase& fc : cases) {
        int steps = 0;
        const double resp = slabResponse(fc, n, base, eta, &steps);
        r.ratio.push_back(resp / slabTarget(fc.albedo, eta));
        r.steps.push_back(steps);
        sumLog += std::log(std::max(r.ratio.back(), 1e-30));
    }
    r.gain = std::exp(-sumLog / double(cases.size()));
    double ss = 0.0;
    for (double q : r.ratio) {
        const double l = std::log(std::max(q * r.gain, 1e-30));
        ss += l * l;
        r.maxAbsRel = std::max(r.maxAbsRel, std::abs(q * r.gain - 1.0));
    }
    r.rmsLog = std::sqrt(ss / double(cases.size()));
    return r;
}

int runFit(const Args& args) {
    const int n = args.intOr("grid", 48, 16, 128);
    const int order = args.intOr("sh", 1, 1, 2);
    const float eta = args.floatOr("eta", 1.3f, 1.f, 3.f);
    const std::vector<float> albedos = {0.3f, 0.5f, 0.7f, 0.8f, 0.9f, 0.95f, 0.99f};
    const std::vector<float> cells = {0.5f, 1.f, 2.f, 4.f};
    std::vector<FitCase> cases;
    for (float c : cells)
        for (float a : albedos)
            cases.push_back({a, c});
    SslpvOptions base{.order = order,
                      .maxSteps = 4096,
                      .skipAccumulateSteps = 2,
                      .removeExitant = true,
                      .stopEpsilon = 1e-4f,
                      .mode = SslpvMode::Calibrated};
    base.calibration = defaultSslpvCalibration();
    base.calibration.gain[0] = base.calibration.gain[1] = 1.f;  // fitted below
    const bool search = args.has("search");
    if (args.value("linear"))
        base.calibration.linear = args.floatOr("linear", 0.f, 0.f, 100.f);
    if (args.value("diffusion"))
        base.calibration.diffusion = args.floatOr("diffusion", 0.f, 0.f, 100.f);
    if (args.value("transport"))
        base.calibration.transport = args.floatOr("transport", 0.f, 0.f, 100.f);
    if (args.value("per-step"))
        base.calibration.perStep = args.floatOr("per-step", 0.f, 0.f, 100.f);
    if (args.value("per-step-transport"))
        base.calibration.perStepTransport = args.floatOr("per-step-transport", 0.f, 0.f, 100.f);
    // Which weight --search fits (the others stay as given).
    const std::string param = args.valueOr("fit", "transport");
    float SslpvCalibration::*fitted = &SslpvCalibration::transport;
    if (param == "linear")
        fitted = &SslpvCalibration::linear;
    else if (param == "diffusion")
        fitted = &SslpvCalibration::diffusion;
    else if (param != "transport")
        LUCENT_THROW(ValueError, "--fit: '", param, "' is not linear, transport or diffusion");

    if (args.has("solve-beta")) {
        // Per case, the per-step absorption β* at which the SSLPV response equals the target
        // with the gain given (default 1): bisection in log β over [1e-4, 20] (the response
        // falls monotonically with β). β is imposed through the linear weight alone,
        // linear = β/(σa·Δx). The table is what the calibration formula is fitted to.
        const float gain = args.floatOr("gain", 1.f, 1e-3f, 1e3f);
        std::printf(
            "| dx*sigma_t | alpha' | beta* | beta*/(1-alpha') | sigma_tr dx | steps |\n"
            "|---|---|---|---|---|---|\n");
        for (const FitCase& fc : cases) {
            const double target = slabTarget(fc.albedo, eta);
            double lo = std::log(1e-4), hi = std::log(20.0);
            int steps = 0;
            for (int it = 0; it < args.intOr("iterations", 10, 1, 40); ++it) {
                const double mid = 0.5 * (lo + hi);
                SslpvOptions o = base;
                o.calibration = SslpvCalibration{};
                o.calibration.linear =
                    float(std::exp(mid) / ((1.0 - fc.albedo) * double(fc.cellMfp)));
                const double resp = gain * slabResponse(fc, n, o, eta, &steps);
                (resp > target ? lo : hi) = mid;
            }
            const double beta = std::exp(0.5 * (lo + hi));
            std::printf("| %.2f | %.3f | %.5f | %.4f | %.4f | %d |\n", double(fc.cellMfp),
                        double(fc.albedo), beta, beta / (1.0 - fc.albedo),
                        std::sqrt(3.0 * (1.0 - fc.albedo)) * fc.cellMfp, steps);
            std::fflush(stdout);
        }
        return 0;
    }
    if (search) {
        // Golden-section search of the diffusion weight (log scale) at fixed linear weight: the
        // objective is the RMS log residual after the optimal gain.
        double a = std::log(0.02), b = std::log(5.0);
        const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
        auto f = [&](double x) {
            SslpvOptions o = base;
            o.calibration.*fitted = float(std::exp(x));
            const double v = evaluateFit(cases, n, o, eta).rmsLog;
            std::printf("# search: %s %.5f -> rms log %.5f\n", param.c_str(), std::exp(x), v);
            std::fflush(stdout);
            return v;
        };
        double c = b - phi * (b - a), d = a + phi * (b - a);
        double fc = f(c), fd = f(d);
        for (int it = 0; it < args.intOr("iterations", 12, 1, 100); ++it) {
            if (fc < fd) {
                b = d;
                d = c;
                fd = fc;
                c = b - phi * (b - a);
                fc = f(c);
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + phi * (b - a);
                fd = f(d);
            }
        }
        base.calibration.*fitted = float(std::exp(0.5 * (a + b)));
    }

    const FitResult r = evaluateFit(cases, n, base, eta);
    std::printf(
        "SSLPV calibrated-mode fit: thick slab %d^3 cells, SH order %d, eta %.2f, "
        "g = 0\n",
        n, order, double(eta));
    std::printf(
        "  model: beta = %.5f sigma_a dx + %.5f sigma_tr dx + %.5f (sigma_tr dx)^2 + "
        "%.5f sigma_a/sigma_t + %.5f sigma_tr/sigma_t, gain G = %.5f\n",
        double(base.calibration.linear), double(base.calibration.transport),
        double(base.calibration.diffusion), double(base.calibration.perStep),
        double(base.calibration.perStepTransport), r.gain);
    std::printf("  target: classical dipole F_t(0) R_d / pi (Jensen 2001)\n");
    std::printf(
        "| dx*sigma_t | alpha' | dipole R_d | target L/E (1/sr) | SSLPV G*L/E | "
        "residual | steps |\n|---|---|---|---|---|---|---|\n");
    for (size_t i = 0; i < cases.size(); ++i) {
        const double t = slabTarget(cases[i].albedo, eta);
        const double rd = dipole::totalReflectance(dipole::Model::Dipole,
                                                   dipole::fromReduced(1.f, cases[i].albedo, eta));
        std::printf("| %.2f | %.3f | %.4f | %.5f | %.5f | %+.1f %% | %d |\n",
                    double(cases[i].cellMfp), double(cases[i].albedo), rd, t,
                    r.ratio[i] * r.gain * t, 100.0 * (r.ratio[i] * r.gain - 1.0), r.steps[i]);
    }
    std::printf("  RMS log residual %.4f, max |residual| %.1f %%\n", r.rmsLog, 100.0 * r.maxAbsRel);
    return 0;
}

}  // namespace

/// `render --method sslpv --gl`: gpu::SceneRenderer with SslpvSubsurfaceProvider (the live
/// preview path; same grid and Eq. 5–7 as the CPU image). The direct term is the renderer's
/// shadow-mapped Blinn–Phong (specular albedo F_r(0, η), no diffuse), not the CPU ray tracer's.
ImageRgb renderSslpvGl(const Scene& scene, const SslpvRenderOptions& opt, bool subsurfaceOnly) {
    LUCENT_CHECK(!scene.objects.empty() && scene.objects[0].material != nullptr,
                 "--method sslpv --gl: the scene needs an object with a material volume");
    std::string reason;
    if (!gpu::GlContext::isHeadlessAvailable(&reason))
        LUCENT_THROW(GpuError, "--gl: no headless OpenGL 4.5 context: ", reason);
    auto ctx = gpu::GlContext::createHeadless();
    gpu::SceneRenderer renderer;
    SslpvSubsurfaceProvider provider(SslpvProviderOptions{.render = opt});
    ImageRgb image;
    try {
        renderer.create();
        provider.create();
        gpu::SurfaceMaterial surface;
        surface.diffuseAlbedo = opt.diffuseReflectance;
        surface.specularAlbedo = Rgb(opt.specularWeight * dielectricReflectance(1.f, scene.eta));
        surface.shininess = opt.shininess;
        renderer.addMesh(scene.objects[0].mesh, surface);
        renderer.setLights(scene.lights);
        renderer.setCamera(scene.camera);
        gpu::DirectSettings settings;
        settings.subsurfaceOnly = subsurfaceOnly;
        renderer.setSettings(settings);
        provider.setMesh(scene.objects[0].mesh);
        provider.setLights(scene.lights);
        provider.setMaterial(*scene.objects[0].material, scene.eta);
        renderer.setSubsurfaceProvider(&provider);
        renderer.render();
        image = renderer.readRadiance();
    } catch (...) {
        renderer.setSubsurfaceProvider(nullptr);
        provider.destroy();
        renderer.destroy();
        throw;
    }
    const SslpvProviderTimings& t = provider.timings();
    const SslpvStats& st = provider.solver().stats();
    std::fprintf(stderr,
                 "sslpv --gl (%s): %d steps, injected %.4g W (green)\n"
                 "  resample %.2f ms, rsm %.2f ms, inject %.2f ms, propagate %.2f ms, upload "
                 "%.2f ms, sample %.2f ms (CPU issue)\n",
                 ctx->renderer().c_str(), st.stepsUsed, double(st.injected.y), t.resampleMs,
                 t.rsmMs, t.injectMs, t.propagateMs, t.uploadMs, t.sampleCpuMs);
    renderer.setSubsurfaceProvider(nullptr);
    provider.destroy();
    renderer.destroy();
    return image;
}

/// `lucent-cli render --method sslpv` (Command_render.cpp): the CPU SSLPV renderer (--gl: the
/// GL provider path above).
ImageRgb renderSslpvMethod(const Scene& scene, bool subsurfaceOnly, const Args& args) {
    SslpvRenderOptions opt;
    opt.gridResolution = args.intOr("grid", 32, 4, 256);
    opt.solver.maxSteps = args.intOr("steps", 32, 0, 4096);
    opt.solver.order = args.intOr("sh", 1, 1, 2);
    opt.direct = !subsurfaceOnly;
    // --mode calibrated (default): the fitted per-step absorption and radiance gain
    // (SslpvCalibration, `lucent-cli bench sslpv-fit`). --mode paper: §3.2.1 with
    // --attenuation; absorption-only by default (within −15 %…+22 % of diffusion on thick slabs
    // for α′ ≥ 0.5, where the paper's literal extinction is 5–50× too dark;
    // docs/methods/sslpv.md).
    const std::string mode = args.valueOr("mode", "calibrated");
    if (mode == "calibrated") {
        opt.solver.mode = SslpvMode::Calibrated;
        if (args.has("attenuation"))
            LUCENT_THROW(ValueError, "--attenuation applies to --mode paper only");
    } else if (mode == "paper") {
        opt.solver.mode = SslpvMode::Paper;
        const std::string att = args.valueOr("attenuation", "absorption");
        if (att == "extinction")
            opt.solver.attenuation = SslpvAttenuation::Extinction;
        else if (att == "absorption")
            opt.solver.attenuation = SslpvAttenuation::Absorption;
        else
            LUCENT_THROW(ValueError, "--attenuation: '", att, "' is not absorption or extinction");
    } else {
        LUCENT_THROW(ValueError, "--mode: '", mode, "' is not paper or calibrated");
    }
    if (args.has("gl"))
        return renderSslpvGl(scene, opt, subsurfaceOnly);
    SslpvRenderTimings t;
    SslpvStats st;
    ImageRgb image = renderSslpv(scene, opt, &t, &st);
    std::fprintf(stderr,
                 "sslpv (%s): %d steps, injected %.4g W (green), exitant %.4g W, "
                 "remaining %.4g W\n"
                 "  rsm %.2f ms, resample %.2f ms, inject %.2f ms, propagate %.2f ms, "
                 "shade %.2f ms (CPU)\n",
                 mode.c_str(), st.stepsUsed, double(st.injected.y), double(st.exitant.y),
                 double(st.remaining.y), t.rsmMs, t.resampleMs, t.injectMs, t.propagateMs,
                 t.shadeMs);
    return image;
}

extern const Command benchCommand;
const Command benchCommand{
    "bench", "time the SSLPV propagation against a bandwidth floor; fit its calibrated mode",
    "usage: lucent-cli bench sslpv [--grid N] [--steps K] [--sh 1|2] [--heterogeneous]\n"
    "                              [--dense] [--threads T] [--repeats R] [--gl [--fp16]]\n"
    "                              [--json]\n"
    "\n"
    "Times repeated SSLPV solves (per-cell factors + propagation) on an N^3 grid whose cells\n"
    "are all material (the paper's set-up, light injected on one face), after 3 warm-up\n"
    "solves, and prints medians next to a memory-bandwidth floor measured in the same run\n"
    "(streaming the same planes: copy + accumulate, per step).\n"
    "\n"
    "  --grid N          cells per axis, [4, 256] (default 32)\n"
    "  --steps K         propagation steps, [1, 4096] (default 8)\n"
    "  --sh 1|2          spherical-harmonics order: 4 or 9 coefficients (default 1)\n"
    "  --heterogeneous   random per-cell material (per-cell factor arrays)\n"
    "  --dense           compute every cell every step (no empty-slice skipping: the\n"
    "                    paper's dense GPU work)\n"
    "  --threads T       worker threads (default: all)\n"
    "  --repeats R       timed solves (default 50)\n"
    "  --gl              also time the GL 4.5 compute propagation (headless EGL context;\n"
    "                    GPU timer queries), fp32 grids\n"
    "  --fp16            with --gl: fp16 grids\n"
    "  --json            one JSON object: ms_per_solve, ms_propagation, ms_per_step,\n"
    "                    floor_ms_per_step, ratio_to_floor (gl_gpu_ms, gl_total_ms: 0 without "
    "--gl)\n"
    "\n"
    "usage: lucent-cli bench sslpv-fit [--grid N] [--sh 1|2] [--eta E] [--linear U]\n"
    "                                  [--transport T] [--diffusion K] [--per-step P]\n"
    "                                  [--per-step-transport Q]\n"
    "                                  [--search [--fit linear|transport|diffusion]]\n"
    "                                  [--solve-beta [--gain G]] [--iterations I]\n"
    "\n"
    "Fit of the calibrated SSLPV mode (docs/methods/sslpv.md): thick slabs (N^3 grid, default\n"
    "48) for alpha' in {0.3 .. 0.99} and cell sizes {0.5, 1, 2, 4} mean free paths; per-step\n"
    "absorption beta = U sigma_a dx + T sigma_tr dx + K (sigma_tr dx)^2 + P sigma_a/sigma_t\n"
    "+ Q sigma_tr/sigma_t (each weight defaults to the shipped constant); prints the optimal\n"
    "radiance gain G and the residual of each case against the classical dipole.\n"
    "  --search       fit one weight (default transport) by golden-section search (log scale\n"
    "                 over [0.02, 5], I iterations, default 12) minimising the RMS log residual\n"
    "  --solve-beta   per case, bisect the per-step absorption beta* that matches the dipole\n"
    "                 with gain G (default 1), I iterations (default 10): the fit data\n",
    &runBench};

}  // namespace lucent::cli
