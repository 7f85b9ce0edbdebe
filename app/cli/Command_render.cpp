// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli render SCENE.json --method NAME -o out.png|out.exr`: headless GL render of
/// a scene with one of the interactive methods. Methods are rows of METHODS below: to add one,
/// write a `ImageRgb renderX(const RenderRequest&)` function (usually renderWithGl() plus a
/// SubsurfaceProvider factory) and add a row.

#include "CliArgs.h"

#include <lucent/combined/Combined.h>
#include <lucent/combined/CombinedProvider.h>
#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/scene/SceneFile.h>

#include <cstdio>
#include <functional>
#include <memory>
#include <string>

namespace lucent::cli {

namespace {

/// What every method receives.
struct RenderRequest {
    const Scene& scene;   ///< camera width/height already overridden by --width/--height
    bool subsurfaceOnly;  ///< --subsurface-only: only the subsurface term (see docs/gpu.md)
    const Args& args;     ///< for method-specific options
};

/// Builds a method's subsurface pass once the GL context is current (may return nullptr).
using ProviderFactory =
    std::function<std::unique_ptr<gpu::SubsurfaceProvider>(const RenderRequest&)>;

/// Headless render through gpu::SceneRenderer: direct lighting plus the provider's subsurface
/// term. Prints the renderer and the per-pass GPU timings. Returns linear radiance.
ImageRgb renderWithGl(const RenderRequest& req, const ProviderFactory& makeProvider) {
    auto ctx = gpu::GlContext::createHeadless();
    std::fprintf(stderr, "render: %s (%s, EGL %s)\n", ctx->renderer().c_str(),
                 ctx->version().c_str(), ctx->platform().c_str());
    gpu::SceneRenderer renderer;
    std::unique_ptr<gpu::SubsurfaceProvider> provider;
    ImageRgb image;
    try {
        renderer.create();
        for (const SceneObject& object : req.scene.objects)
            renderer.addMesh(object.mesh);
        renderer.setLights(req.scene.lights);
        renderer.setCamera(req.scene.camera);
        gpu::DirectSettings settings;
        settings.subsurfaceOnly = req.subsurfaceOnly;
        renderer.setSettings(settings);
        if (makeProvider)
            provider = makeProvider(req);
        renderer.setSubsurfaceProvider(provider.get());
        renderer.render();
        image = renderer.readRadiance();
        renderer.profiler().collect(/*wait=*/true);
    } catch (...) {
        provider.reset();
        renderer.destroy();
        throw;
    }
    for (const gpu::PassTiming& t : renderer.profiler().latest())
        std::fprintf(stderr, "  %-12s %8.2f ms GPU %8.2f ms CPU\n", t.name.c_str(), t.gpuMs,
                     t.cpuMs);
    provider.reset();
    renderer.destroy();
    for (const std::string& e : ctx->debugLog().takeErrors())
        std::fprintf(stderr, "%s\n", e.c_str());
    return image;
}

ImageRgb renderDirect(const RenderRequest& req) {
    // Direct lighting has no subsurface term: with --subsurface-only the object is black.
    return renderWithGl(req, {});
}

#ifdef LUCENT_CLI_HAS_REFERENCE
}  // namespace
/// Defined in Command_reference.cpp: the Monte Carlo path tracer (--spp, --seed, --threads,
/// --boundary).
ImageRgb renderReferenceMethod(const Scene& scene, bool subsurfaceOnly, const Args& args);
namespace {
ImageRgb renderReferencePt(const RenderRequest& req) {
    return renderReferenceMethod(req.scene, req.subsurfaceOnly, req.args);
}
#endif

#ifdef LUCENT_CLI_HAS_PROFILE
}  // namespace
/// Defined in Command_profile.cpp: the dipole family (GPU image-space provider, or the CPU
/// with --cpu / without EGL; --spp, --spp-frame, --seed).
ImageRgb renderDipoleMethod(const Scene& scene, const std::string& model, bool subsurfaceOnly,
                            const Args& args);
namespace {
ImageRgb renderDipole(const RenderRequest& req) {
    return renderDipoleMethod(req.scene, "dipole", req.subsurfaceOnly, req.args);
}
ImageRgb renderBetterDipole(const RenderRequest& req) {
    return renderDipoleMethod(req.scene, "better-dipole", req.subsurfaceOnly, req.args);
}
ImageRgb renderDirpole(const RenderRequest& req) {
    return renderDipoleMethod(req.scene, "dirpole", req.subsurfaceOnly, req.args);
}
#endif

#ifdef LUCENT_CLI_HAS_BENCH
}  // namespace
/// Defined in Command_bench.cpp: SSLPV on the CPU (--grid, --steps, --sh).
ImageRgb renderSslpvMethod(const Scene& scene, bool subsurfaceOnly, const Args& args);
namespace {
ImageRgb renderSslpvCpu(const RenderRequest& req) {
    return renderSslpvMethod(req.scene, req.subsurfaceOnly, req.args);
}
#endif

}  // namespace

/// Combined mode (docs/methods/combined.md): windowed dipole + late-step SSLPV, on the GL
/// providers (or the CPU with --cpu / without EGL; subsurface term only). Also used by
/// `lucent-cli evaluate`.
ImageRgb renderCombinedMethod(const Scene& scene, bool subsurfaceOnly, const Args& a) {
    const float rs = a.has("split-radius") ? a.floatOr("split-radius", 0.f, 0.f, 1e30f) : -1.f;
    const std::string model = a.valueOr("model", "dipole");
    const dipole::Model m = dipole::parseModel(model);
    LUCENT_CHECK(m != dipole::Model::Directional,
                 "--model: combined uses dipole or better-dipole (got '", model, "')");
    SslpvRenderOptions so = combined::CombinedSettings::defaultSslpvOptions();
    so.gridResolution = a.intOr("grid", 32, 4, 256);
    so.solver.maxSteps = a.intOr("steps", 32, 0, 4096);
    so.solver.order = a.intOr("sh", 1, 1, 2);
    const uint32_t seed = uint32_t(a.intOr("seed", 1, 0, 1 << 30));
    const std::string split = a.valueOr("split", "kernel");
    LUCENT_CHECK(split == "kernel" || split == "steps", "--split: '", split,
                 "' is not kernel or steps");
    const combined::SplitMode mode =
        split == "kernel" ? combined::SplitMode::Kernel : combined::SplitMode::Steps;
    const std::string lightViews = a.valueOr("light-views", "off");
    LUCENT_CHECK(lightViews == "on" || lightViews == "off",
                 "--light-views must be on or off (got '", lightViews, "')");
    std::string reason;
    if (!a.has("cpu") && gpu::GlContext::isHeadlessAvailable(&reason)) {
        combined::CombinedProviderSettings ps;
        ps.splitRadius = rs;
        ps.mode = mode;
        ps.dipole.model = m;
        ps.dipole.seed = seed;
        ps.dipole.samplesPerFrame = a.intOr("spp-frame", 16, 1, 4096);
        ps.dipole.lightViews = lightViews == "on";
        ps.sslpv.render = so;
        return combined::renderCombinedGl(scene, ps, a.intOr("spp", 256, 1, 1 << 24),
                                          subsurfaceOnly);
    }
    if (!a.has("cpu"))
        std::fprintf(stderr, "render: no headless GL (%s); combined on the CPU\n", reason.c_str());
    combined::CombinedSettings cs;
    cs.splitRadius = rs;
    cs.mode = mode;
    cs.dipoleLightViews = lightViews == "on";
    cs.sslpv = so;
    cs.dipole.model = m;
    const int spp = a.intOr("spp", 32, 1, 65536);
    cs.dipole.uniformSamples = spp / 4;
    cs.dipole.importanceSamples = spp - cs.dipole.uniformSamples;
    cs.dipole.seed = seed;
    const combined::CombinedResult r = combined::renderCombined(scene, cs);
    std::fprintf(stderr,
                 "combined (CPU, subsurface only): r_s %.3g mm = %.2f cells of %.3g mm, SSLPV "
                 "skips %d of %d steps\n",
                 double(r.plan.splitRadius), double(r.plan.splitRadius / r.plan.cellSize),
                 double(r.plan.cellSize), r.plan.skipSteps, so.solver.maxSteps);
    return r.radiance;
}

namespace {
ImageRgb renderCombinedMode(const RenderRequest& req) {
    return renderCombinedMethod(req.scene, req.subsurfaceOnly, req.args);
}

struct RenderMethod {
    const char* name;
    const char* summary;
    ImageRgb (*render)(const RenderRequest&);
};

// The --method table. Add a row per method.
const RenderMethod METHODS[] = {
    {"direct", "opaque surface, direct lighting (Lambert + Blinn-Phong) with shadow maps",
     &renderDirect},
#ifdef LUCENT_CLI_HAS_REFERENCE
    {"reference",
     "CPU Monte Carlo path tracer (ground truth; --spp, --seed, --threads, --boundary)",
     &renderReferencePt},
#endif
#ifdef LUCENT_CLI_HAS_PROFILE
    {"dipole", "image-space Jensen dipole (Mertens 2005; GL, or --cpu; --spp, --seed)",
     &renderDipole},
    {"better-dipole", "image-space better dipole (d'Eon 2012; GL, or --cpu; --spp, --seed)",
     &renderBetterDipole},
    {"dirpole",
     "directional dipole pipeline (Frisvad 2014, seed 001 §4; GL, or --cpu: directional lights "
     "only; --spp, --spp-frame, --seed)",
     &renderDirpole},
#endif
#ifdef LUCENT_CLI_HAS_BENCH
    {"sslpv", "CPU subsurface light propagation volumes (Borlum 2011; --grid, --steps, --sh)",
     &renderSslpvCpu},
#endif
    {"combined",
     "local dipole (r <= r_s) + SSLPV beyond (GL, or --cpu; --split-radius, --spp, --grid)",
     &renderCombinedMode},
};

const RenderMethod& findMethod(const std::string& name) {
    for (const RenderMethod& m : METHODS)
        if (name == m.name)
            return m;
    std::string known;
    for (const RenderMethod& m : METHODS)
        known += std::string(known.empty() ? "" : ", ") + m.name;
    LUCENT_THROW(ValueError, "--method: unknown method '", name, "' (known: ", known, ")");
}

bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() &&
           s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

int runRender(const std::vector<std::string>& argv) {
    const Args args(
        argv,
        {"method",  "o",     "output",      "width",       "height",         "exposure",
         "tonemap", "spp",   "seed",        "threads",     "boundary",       "grid",
         "steps",   "sh",    "attenuation", "spp-frame",   "mode",           "split-radius",
         "model",   "split", "max-radius",  "light-views", "light-view-res", "dirpole-normalise"},
        {"subsurface-only", "cpu", "gl"});
    if (args.positional().size() != 1)
        LUCENT_THROW(ValueError, "expected exactly one SCENE.json (see --help)");
    const std::string out = args.value("o").value_or(args.valueOr("output", ""));
    if (out.empty())
        LUCENT_THROW(ValueError, "missing -o/--output FILE (.png or .exr)");
    const bool exr = endsWith(out, ".exr");
    if (!exr && !endsWith(out, ".png"))
        LUCENT_THROW(ValueError, "-o/--output '", out, "': expected a .png or .exr file name");
    const RenderMethod& method = findMethod(args.valueOr("method", "direct"));
    ToneMap tm;
    tm.exposure = args.floatOr("exposure", 1.f, 0.f, 1e6f);
    const std::string curve = args.valueOr("tonemap", "aces");
    if (curve == "clamp")
        tm.curve = ToneMap::Curve::Clamp;
    else if (curve == "reinhard")
        tm.curve = ToneMap::Curve::Reinhard;
    else if (curve == "aces")
        tm.curve = ToneMap::Curve::Aces;
    else
        LUCENT_THROW(ValueError, "--tonemap: '", curve, "' is not one of clamp, reinhard, aces");

    Scene scene = loadScene(args.positional().front());
    for (const std::string& w : scene.warnings)
        std::fprintf(stderr, "lucent-cli render: warning: %s\n", w.c_str());
    scene.camera.width = args.intOr("width", scene.camera.width, 1, 16384);
    scene.camera.height = args.intOr("height", scene.camera.height, 1, 16384);
    const RenderRequest req{scene, args.has("subsurface-only"), args};
    const ImageRgb image = method.render(req);
    if (exr)
        writeExr(image, out);
    else
        writePng(image, out, tm);
    std::printf("wrote %s (%dx%d, method %s%s)\n", out.c_str(), image.width(), image.height(),
                method.name, req.subsurfaceOnly ? ", subsurface only" : "");
    return 0;
}

}  // namespace

extern const Command renderCommand;
const Command renderCommand{
    "render", "headless GL render of a scene (direct lighting, interactive methods)",
    "usage: lucent-cli render SCENE.json [--method NAME] -o OUT.png|OUT.exr\n"
    "                         [--width W] [--height H] [--subsurface-only]\n"
    "                         [--exposure E] [--tonemap clamp|reinhard|aces]\n"
    "\n"
    "Renders the scene through an offscreen OpenGL 4.5 context (EGL, no display needed).\n"
    "\n"
    "  --method NAME      direct (default): opaque surface, Lambert + Blinn-Phong, shadow maps\n"
    "                     reference: CPU path tracer (no GL), with --spp N (64), --seed S,\n"
    "                     --threads T, --boundary dielectric|matched|straight (docs/reference.md)\n"
    "                     dipole, better-dipole: GPU image-space dipole accumulated over\n"
    "                     frames of --spp-frame M (16) up to --spp N (256) samples per pixel,\n"
    "                     --seed S, plus the specular surface reflection; --cpu (or no EGL):\n"
    "                     CPU gather, subsurface term only, --spp N (32)\n"
    "                     (camera + light-view irradiance images, --light-views on|off,\n"
    "                     --light-view-res N (512); --max-radius MM: only r <= MM)\n"
    "                     dirpole: GPU directional-dipole pipeline (light G-buffers, cube\n"
    "                     faces) over frames of --spp-frame M (16) up to --spp N (256) disc\n"
    "                     samples per cube texel and light, --seed S, plus the specular\n"
    "                     reflection; --cpu (or no EGL): CPU pipeline, directional lights,\n"
    "                     subsurface term only, --spp N (32) (docs/methods/dipole.md),\n"
    "                     --dirpole-normalise on|off (on: S_d scaled to the better\n"
    "                     dipole's total, docs/methods/dipole.md §1)\n"
    "                     sslpv: CPU SSLPV with --grid N (32), --steps K (32), --sh 1|2,\n"
    "                     --mode calibrated|paper (calibrated), with paper:\n"
    "                     --attenuation absorption|extinction (absorption); --gl: the GL\n"
    "                     live-preview provider through the GPU scene renderer\n"
    "                     (docs/methods/sslpv.md)\n"
    "                     combined: dipole for r <= --split-radius MM (default 4 SSLPV\n"
    "                     cells), calibrated SSLPV (--grid N, --steps K, --sh) beyond it;\n"
    "                     --split kernel (default: SSLPV minus its own local kernel) or\n"
    "                     steps (SSLPV skips its first r_s/cell steps);\n"
    "                     --model dipole|better-dipole, --spp N, --spp-frame M, --seed S,\n"
    "                     --light-views on|off (the dipole part's; default off: on\n"
    "                     counts back-lit light twice);\n"
    "                     --cpu: CPU gather + CPU SSLPV, subsurface only\n"
    "                     (docs/methods/combined.md)\n"
    "  -o, --output FILE  .exr: linear radiance W/(mm^2 sr), 32-bit float;\n"
    "                     .png: 8-bit sRGB after --exposure and --tonemap (default aces)\n"
    "  --width, --height  override the scene camera's image size (pixels)\n"
    "  --subsurface-only  keep only the subsurface term of the method; for direct, which has\n"
    "                     none, the image is black\n"
    "\n"
    "GL_RENDERER and per-pass GPU/CPU timings go to stderr. LUCENT_SHADER_DIR=DIR loads the\n"
    "shaders from DIR instead of the embedded copies; LUCENT_EGL_PLATFORM=surfaceless|device\n"
    "forces an EGL platform.\n",
    &runRender};

}  // namespace lucent::cli
