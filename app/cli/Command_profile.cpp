// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli profile`: total diffuse reflectance per channel and the radial profile
/// R(r) of the dipole (Jensen 2001), better dipole (d'Eon 2012) or directional dipole
/// (Frisvad et al. 2014, normal incidence); optional JSON and a PNG plot of R(r)·r.

#include "CliArgs.h"

#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/dipole/DipoleProvider.h>
#include <lucent/dipole/DirectionalPipeline.h>
#include <lucent/dipole/DirpoleProvider.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/dipole/Sampling.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/SceneRenderer.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

using dipole::Model;

/// The directional dipole is implemented as published (verified against the authors' reference
/// program), but the published model is not energy-conserving (docs/methods/dipole.md §1 and
/// §4), so every use of it says so.
void warnExperimentalDirpole() {
    std::fprintf(stderr,
                 "warning: the published Frisvad et al. 2014 directional dipole overestimates "
                 "total reflectance (1.34 at sigma_a = 0) and is +48..131%% against the "
                 "reference path tracer (docs/methods/dipole.md, sections 1 and 4)\n");
}

/// `--dirpole-normalise on|off` (default on): S_d scaled so that its normal-incidence total
/// equals the better dipole's (docs/methods/dipole.md §1, "Energy-normalised directional
/// dipole"); off selects the published model, with the warning above.
bool dirpoleNormalised(const Args& args) {
    const std::string norm = args.valueOr("dirpole-normalise", "on");
    LUCENT_CHECK(norm == "on" || norm == "off", "--dirpole-normalise: '", norm,
                 "' is not on or off");
    if (norm == "off")
        warnExperimentalDirpole();
    return norm == "on";
}

/// Radius holding 99% of the widest channel's profile (Jensen-shaped sampler of the better
/// dipole's parameters; used for the table and plot range only).
double profileRange(const std::array<dipole::ScalarMedium, 3>& media) {
    double range = 0.0;
    for (const auto& m : media) {
        const dipole::DipoleSampler s(dipole::DipoleProfile::better(m.sigma_a, m.sigma_s, m.eta));
        if (s.isValid())
            range = std::max(range, s.quantile(0.99));
    }
    return range > 0.0 ? range : 1.0;
}

/// Line plot of R(r)·r for the three channels (red, green, blue curves) on a white canvas.
void writePlot(const std::string& path, Model model,
               const std::array<dipole::ScalarMedium, 3>& media, double rMax) {
    const int W = 800, H = 500, margin = 40;
    ImageRgb img(W, H, Rgb(1.f));
    const int plotW = W - 2 * margin, plotH = H - 2 * margin;
    std::array<std::vector<double>, 3> ys;
    double yMax = 0.0;
    for (int c = 0; c < 3; ++c) {
        ys[size_t(c)].resize(size_t(plotW) + 1);
        for (int i = 0; i <= plotW; ++i) {
            const double r = rMax * i / plotW;
            const double v = dipole::radialProfile(model, media[size_t(c)], r) * r;
            ys[size_t(c)][size_t(i)] = v;
            yMax = std::max(yMax, v);
        }
    }
    if (!(yMax > 0.0))
        yMax = 1.0;
    // Axes (black): x along the bottom, y along the left.
    for (int x = margin; x <= W - margin; ++x)
        img.at(x, H - margin) = Rgb(0.f);
    for (int y = margin; y <= H - margin; ++y)
        img.at(margin, y) = Rgb(0.f);
    const std::array<Rgb, 3> colours = {Rgb(0.85f, 0.1f, 0.1f), Rgb(0.1f, 0.6f, 0.1f),
                                        Rgb(0.1f, 0.2f, 0.9f)};
    for (int c = 0; c < 3; ++c) {
        int prev = -1;
        for (int i = 0; i <= plotW; ++i) {
            const int y =
                H - margin - int(std::lround(ys[size_t(c)][size_t(i)] / yMax * (plotH - 1)));
            const int lo = prev < 0 ? y : std::min(prev, y), hi = prev < 0 ? y : std::max(prev, y);
            for (int yy = lo; yy <= hi; ++yy)
                for (int t = 0; t < 2; ++t)
                    img.at(std::min(W - 1, margin + i + t), std::clamp(yy, 0, H - 1)) =
                        colours[size_t(c)];
            prev = y;
        }
    }
    writePng(img, path);
}

int runProfile(const std::vector<std::string>& argv) {
    const Args args(argv, {"model", "sigma-a", "sigma-s", "eta", "plot", "radii"}, {"json"});
    const Model model = dipole::parseModel(args.valueOr("model", "dipole"));
    if (model == Model::Directional)
        warnExperimentalDirpole();
    // Defaults: Jensen et al. 2001 Table 2 marble (mm⁻¹), η = 1.5.
    const Rgb sigmaA = args.rgb("sigma-a", 0.f, 1e6f).value_or(Rgb(0.0021f, 0.0041f, 0.0071f));
    const Rgb sigmaS = args.rgb("sigma-s", 0.f, 1e6f).value_or(Rgb(2.19f, 2.62f, 3.00f));
    const float eta = args.floatOr("eta", 1.5f, 1.f, 3.f);
    const int radiiCount = args.intOr("radii", 16, 2, 1000);
    std::array<dipole::ScalarMedium, 3> media;
    for (int c = 0; c < 3; ++c)
        media[size_t(c)] = {double(sigmaA[c]), double(sigmaS[c]), double(eta)};

    std::array<double, 3> total{}, numeric{};
    for (int c = 0; c < 3; ++c) {
        total[size_t(c)] = dipole::totalReflectance(model, media[size_t(c)]);
        // Independent quadrature of the same profile (equals `total` for the directional model,
        // which has no closed form).
        numeric[size_t(c)] =
            model == Model::Directional
                ? total[size_t(c)]
                : dipole::integrateProfile(dipole::DipoleProfile::make(model, media[size_t(c)]));
    }
    const double rMax = profileRange(media);
    std::vector<double> radii(static_cast<size_t>(radiiCount));
    for (int i = 0; i < radiiCount; ++i)
        radii[size_t(i)] = rMax * std::pow(1e-3, 1.0 - double(i) / (radiiCount - 1));

    if (args.has("json")) {
        std::printf("{\n  \"model\": \"%s\",\n  \"eta\": %.9g,\n", dipole::modelName(model),
                    double(eta));
        std::printf(
            "  \"sigma_a\": [%.9g, %.9g, %.9g],\n  \"sigma_s_reduced\": [%.9g, %.9g, %.9g],\n",
            double(sigmaA.r), double(sigmaA.g), double(sigmaA.b), double(sigmaS.r),
            double(sigmaS.g), double(sigmaS.b));
        std::printf("  \"total_reflectance\": [%.9g, %.9g, %.9g],\n", total[0], total[1], total[2]);
        std::printf("  \"total_reflectance_quadrature\": [%.9g, %.9g, %.9g],\n", numeric[0],
                    numeric[1], numeric[2]);
        std::printf("  \"units\": {\"r\": \"mm\", \"R\": \"mm^-2\"},\n  \"profile\": [\n");
        for (size_t i = 0; i < radii.size(); ++i) {
            const double r = radii[i];
            std::printf("    {\"r\": %.9g, \"R\": [%.9g, %.9g, %.9g]}%s\n", r,
                        dipole::radialProfile(model, media[0], r),
                        dipole::radialProfile(model, media[1], r),
                        dipole::radialProfile(model, media[2], r), i + 1 < radii.size() ? "," : "");
        }
        std::printf("  ]\n}\n");
    } else {
        std::printf(
            "model %s, eta %.4g, sigma_a (%.6g, %.6g, %.6g) mm^-1, sigma_s' (%.6g, %.6g, %.6g) "
            "mm^-1\n",
            dipole::modelName(model), double(eta), double(sigmaA.r), double(sigmaA.g),
            double(sigmaA.b), double(sigmaS.r), double(sigmaS.g), double(sigmaS.b));
        std::printf("total diffuse reflectance %s: R %.6f  G %.6f  B %.6f\n",
                    model == Model::Directional ? "(quadrature)" : "(closed form)", total[0],
                    total[1], total[2]);
        if (model != Model::Directional)
            std::printf("total diffuse reflectance (quadrature):  R %.6f  G %.6f  B %.6f\n",
                        numeric[0], numeric[1], numeric[2]);
        std::printf("%14s %14s %14s %14s   (R(r) in mm^-2)\n", "r [mm]", "R", "G", "B");
        for (double r : radii)
            std::printf("%14.6g %14.6g %14.6g %14.6g\n", r,
                        dipole::radialProfile(model, media[0], r),
                        dipole::radialProfile(model, media[1], r),
                        dipole::radialProfile(model, media[2], r));
    }
    if (auto plot = args.value("plot")) {
        writePlot(*plot, model, media, rMax);
        std::fprintf(stderr, "wrote %s (R(r)*r for r in [0, %.4g] mm; red, green, blue channels)\n",
                     plot->c_str(), rMax);
    }
    return 0;
}

}  // namespace

namespace {

/// Detaches `provider` from `renderer` and frees both (the GL context current).
template <class Provider>
void releaseGlRender(gpu::SceneRenderer& renderer, Provider& provider) {
    renderer.setSubsurfaceProvider(nullptr);
    provider.destroy();
    renderer.destroy();
}

/// Epilogue of a finished GL render: the last frame's pass timings to stderr, `provider` and
/// `renderer` freed, then the GL errors the context's debug log collected, to stderr.
template <class Provider>
void finishGlRender(gpu::GlContext& ctx, gpu::SceneRenderer& renderer, Provider& provider) {
    for (const gpu::PassTiming& t : renderer.profiler().latest())
        std::fprintf(stderr, "  %-12s %8.2f ms GPU %8.2f ms CPU (last frame)\n", t.name.c_str(),
                     t.gpuMs, t.cpuMs);
    releaseGlRender(renderer, provider);
    for (const std::string& e : ctx.debugLog().takeErrors())
        std::fprintf(stderr, "%s\n", e.c_str());
}

/// The image-space dipoles through gpu::SceneRenderer and dipole::DipoleSubsurfaceProvider on a
/// headless context: frames of `--spp-frame` samples are accumulated until `--spp` samples per
/// pixel or convergence. Unless subsurface-only, the renderer adds the direct surface reflection:
/// diffuse 0 (the dipole replaces it) and a normalised Blinn-Phong lobe of albedo
/// F_r(η, normal incidence) with shadow maps.
ImageRgb renderDipoleGl(const Scene& scene, Model model, bool subsurfaceOnly, int spp, int sppFrame,
                        uint32_t seed, float maxRadius, bool lightViews, int lightViewRes) {
    LUCENT_CHECK(!scene.objects.empty() && scene.objects[0].material != nullptr, "--method ",
                 dipole::modelName(model), ": the scene needs an object with a material volume");
    auto ctx = gpu::GlContext::createHeadless();
    std::fprintf(stderr, "render: %s (%s, EGL %s), GPU image-space %s\n", ctx->renderer().c_str(),
                 ctx->version().c_str(), ctx->platform().c_str(), dipole::modelName(model));
    gpu::SceneRenderer renderer;
    dipole::DipoleSubsurfaceProvider provider;
    ImageRgb image;
    double totalMs = 0.0;
    try {
        renderer.create();
        provider.create();
        const int materialMesh = dipole::addTranslucentScene(renderer, scene, subsurfaceOnly);
        dipole::ProviderSettings ps;
        ps.model = model;
        ps.eta = scene.eta;
        ps.samplesPerFrame = std::min(sppFrame, spp);
        ps.maxFrames = (spp + ps.samplesPerFrame - 1) / ps.samplesPerFrame;
        ps.seed = seed;
        ps.meshId = materialMesh;
        ps.maxRadius = maxRadius;
        ps.lightViews = lightViews;
        ps.lightViewResolution = lightViewRes;
        provider.setSettings(ps);
        provider.setMaterial(scene.objects[0].material.get());
        renderer.setSubsurfaceProvider(&provider);
        const auto t0 = std::chrono::steady_clock::now();
        do {
            renderer.render();
        } while (!provider.stats().converged);
        image = renderer.readRadiance();
        totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                      .count();
        renderer.profiler().collect(/*wait=*/true);
    } catch (...) {
        releaseGlRender(renderer, provider);
        throw;
    }
    const dipole::ProviderStats& st = provider.stats();
    std::fprintf(stderr,
                 "  %d frames x %d spp = %d samples per pixel, last change %.2e of the peak, "
                 "%.1f ms per frame\n",
                 st.frames, provider.settings().samplesPerFrame, st.samplesPerPixel,
                 double(st.lastChange), totalMs / std::max(st.frames, 1));
    std::fprintf(stderr,
                 "  gather: eps = %.3g (discQuantile %.4g), disc radius %.3g..%.3g mm, %d of %d "
                 "light view(s) gathered\n",
                 double(st.epsilon), 1.0 - double(st.epsilon), double(st.minRadius),
                 double(st.maxRadius), st.lightViewsGathered, st.lightViewsRendered);
    for (size_t l = 0; l < st.backlitFractions.size(); ++l)
        std::fprintf(stderr, "  light %zu view: %s (back-lit flux fraction %.3g)\n", l,
                     st.backlitFractions[l] < 0.f ? "not rendered"
                     : st.backlitFractions[l] > provider.settings().lightViewThreshold ? "gathered"
                                                                                       : "skipped",
                     double(st.backlitFractions[l]));
    finishGlRender(*ctx, renderer, provider);
    return image;
}

}  // namespace

namespace {

/// `--method dirpole` on the GPU: seed 001 §4 through dipole::DirpoleSubsurfaceProvider (any
/// light type), frames of `--spp-frame` disc samples per cube texel and light until `--spp` or
/// convergence; the direct surface reflection as renderDipoleGl unless subsurface-only.
ImageRgb renderDirpoleGl(const Scene& scene, bool subsurfaceOnly, const Args& args, uint32_t seed) {
    LUCENT_CHECK(!scene.objects.empty() && scene.objects[0].material != nullptr,
                 "--method dirpole: the scene needs an object with a material volume");
    const int spp = args.intOr("spp", 256, 1, 1 << 24);
    dipole::DirpoleSettings ds;
    ds.eta = scene.eta;
    ds.samplesPerFrame = std::min(args.intOr("spp-frame", 16, 1, 4096), spp);
    ds.maxFrames = (spp + ds.samplesPerFrame - 1) / ds.samplesPerFrame;
    ds.seed = seed;
    ds.energyNormalised = dirpoleNormalised(args);
    // Offline: whole frames of --spp-frame samples (the frame budgets bound interactive frames
    // only; the image after N samples per texel is the same either way).
    ds.frameSampleBudget = ds.firstFrameSampleBudget = 0;
    auto ctx = gpu::GlContext::createHeadless();
    std::fprintf(stderr, "render: %s (%s, EGL %s), GPU directional-dipole pipeline\n",
                 ctx->renderer().c_str(), ctx->version().c_str(), ctx->platform().c_str());
    gpu::SceneRenderer renderer;
    dipole::DirpoleSubsurfaceProvider provider;
    ImageRgb image;
    const auto start = std::chrono::steady_clock::now();
    try {
        renderer.create();
        provider.create();
        const gpu::SurfaceMaterial surface{
            Rgb(0.f), Rgb(float(dipole::fresnelReflectance(1.0, scene.eta))), 64.f};
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            const int id = renderer.addMesh(scene.objects[i].mesh, surface);
            if (i == 0)
                ds.meshId = id;  // the volume belongs to objects[0]
        }
        renderer.setLights(scene.lights);
        renderer.setCamera(scene.camera);
        gpu::DirectSettings direct;
        direct.subsurfaceOnly = subsurfaceOnly;
        renderer.setSettings(direct);
        provider.setSettings(ds);
        provider.setMaterial(scene.objects[0].material.get());
        renderer.setSubsurfaceProvider(&provider);
        while (!provider.stats().converged)
            renderer.render();
        image = renderer.readRadiance();
        renderer.profiler().collect(/*wait=*/true);
    } catch (...) {
        releaseGlRender(renderer, provider);
        throw;
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const dipole::ProviderStats& st = provider.stats();
    std::fprintf(stderr,
                 "  %d frames x %d disc samples per cube texel and light, last change %.2e of "
                 "the peak, %.1f ms per frame (first frame builds the light and cube G-buffers)\n",
                 st.frames, ds.samplesPerFrame, double(st.lastChange), ms / std::max(st.frames, 1));
    finishGlRender(*ctx, renderer, provider);
    return image;
}

}  // namespace

/// The CPU gather's ε, sample radius and light-view decisions, to stderr.
void printGatherStats(const dipole::GatherStats& st,
                      const std::vector<dipole::LightViewReport>& reports) {
    std::fprintf(stderr,
                 "  gather: %d pixels, eps = %.3g (discQuantile %.4g), disc radius %.3g..%.3g mm, "
                 "%d light view(s) gathered\n",
                 st.pixels, st.epsilon, 1.0 - st.epsilon, st.minRadius, st.maxRadius,
                 st.lightViews);
    for (const dipole::LightViewReport& r : reports)
        std::fprintf(stderr, "  light %d view: %s (back-lit flux fraction %.3g)%s%s\n", r.light,
                     r.used ? "gathered" : (r.built ? "skipped" : "not built"), r.backlitFraction,
                     r.note.empty() ? "" : ": ", r.note.c_str());
}

/// `lucent-cli render --method dipole|better-dipole|dirpole` (declared in Command_render.cpp).
/// dipole, better-dipole: GPU image-space gather through gpu::SceneRenderer when a headless GL
/// context can be created (--spp N total samples per pixel, default 256; --spp-frame M per
/// frame, default 16; --seed S), with the direct surface reflection unless subsurface-only;
/// otherwise, or with --cpu, the CPU image-space gather (--spp N, default 32; subsurface only).
/// dirpole: the GPU directional-dipole pipeline (dipole::DirpoleSubsurfaceProvider; --spp N disc
/// samples per cube texel and light, default 256; --spp-frame M per frame, default 16; any light
/// type) when a headless GL context can be created; otherwise, or with --cpu, the CPU pipeline
/// (--spp N disc samples per pixel, directional lights only, subsurface term only).
/// Radiance W/(mm²·sr).
ImageRgb renderDipoleMethod(const Scene& scene, const std::string& model, bool subsurfaceOnly,
                            const Args& args) {
    const Model m = dipole::parseModel(model);
    const int seed = args.intOr("seed", 1, 0, 1 << 30);
    // Light-view irradiance images (seed 004 §7.1): --light-views on|off; --max-radius MM.
    const std::string lightViews = args.valueOr("light-views", "on");
    LUCENT_CHECK(lightViews == "on" || lightViews == "off",
                 "--light-views must be on or off (got '", lightViews, "')");
    const float maxRadius = args.floatOr("max-radius", 0.f, 0.f, 1e6f);
    const int lightViewRes = args.intOr("light-view-res", 512, 16, 4096);
    if (m == Model::Directional && !args.has("cpu")) {
        std::string reason;
        if (gpu::GlContext::isHeadlessAvailable(&reason))
            return renderDirpoleGl(scene, subsurfaceOnly, args, uint32_t(seed));
        std::fprintf(stderr, "render: no headless GL (%s); using the CPU directional pipeline\n",
                     reason.c_str());
    }
    if (m != Model::Directional && !args.has("cpu")) {
        std::string reason;
        if (gpu::GlContext::isHeadlessAvailable(&reason))
            return renderDipoleGl(scene, m, subsurfaceOnly, args.intOr("spp", 256, 1, 1 << 24),
                                  args.intOr("spp-frame", 16, 1, 4096), uint32_t(seed), maxRadius,
                                  lightViews == "on", lightViewRes);
        std::fprintf(stderr, "render: no headless GL (%s); using the CPU gather\n", reason.c_str());
    }
    const int spp = args.intOr("spp", 32, 1, 65536);
    if (!subsurfaceOnly)
        std::fprintf(stderr,
                     "render: method %s on the CPU draws the subsurface term only (no surface "
                     "reflection)\n",
                     model.c_str());
    if (m == Model::Directional) {
        dipole::DirectionalSettings ds;
        ds.samplesPerPass = spp;
        ds.seed = uint32_t(seed);
        ds.energyNormalised = dirpoleNormalised(args);
        // The directional pipeline handles directional lights only: drop the others, loudly.
        Scene directional = scene;
        directional.lights.clear();
        for (const Light& l : scene.lights) {
            if (l.type == Light::Type::Directional)
                directional.lights.push_back(l);
            else
                std::fprintf(stderr, "render: dirpole ignores a non-directional light (type %d)\n",
                             int(l.type));
        }
        if (directional.lights.empty())
            LUCENT_THROW(ValueError, "--method dirpole: the scene has no directional light");
        dipole::DirectionalDipoleRenderer renderer(directional, ds);
        renderer.addPass();
        return renderer.radiance();
    }
    dipole::GatherSettings gs;
    gs.model = m;
    gs.uniformSamples = spp / 4;
    gs.importanceSamples = spp - gs.uniformSamples;
    gs.seed = uint32_t(seed);
    gs.maxRadius = maxRadius;
    dipole::LightViewSettings lv;
    lv.enabled = lightViews == "on";
    lv.resolution = lightViewRes;
    std::vector<dipole::LightViewReport> reports;
    const dipole::GatherResult g = dipole::renderImageSpaceDipole(scene, gs, lv, &reports);
    printGatherStats(g.stats, reports);
    return g.radiance;
}

extern const Command profileCommand;
const Command profileCommand{
    "profile", "diffuse reflectance profile R(r) of a dipole model",
    "usage: lucent-cli profile [--model dipole|better-dipole|dirpole] [--sigma-a R,G,B]\n"
    "                          [--sigma-s R,G,B] [--eta E] [--radii N] [--json] [--plot out.png]\n"
    "\n"
    "Prints the total diffuse reflectance per channel (closed form and quadrature for the two\n"
    "dipoles; quadrature for the directional dipole, at normal incidence) and R(r) in mm^-2 at\n"
    "N radii (default 16) spaced geometrically up to the radius holding 99% of the profile.\n"
    "\n"
    "  --model     dipole (Jensen 2001), better-dipole (d'Eon 2012), dirpole (Frisvad 2014)\n"
    "  --sigma-a   absorption coefficient, mm^-1 (default marble 0.0021,0.0041,0.0071)\n"
    "  --sigma-s   reduced scattering coefficient sigma_s', mm^-1 (default 2.19,2.62,3.00)\n"
    "  --eta       relative index of refraction, [1, 3] (default 1.5)\n"
    "  --json      machine-readable output\n"
    "  --plot      write a PNG plot of R(r)*r per channel\n",
    &runProfile};

}  // namespace lucent::cli
