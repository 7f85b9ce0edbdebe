// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli render SCENE.json --method NAME -o out.png|out.exr`: one image of a scene
/// with any registered method (lucent/methods/RenderImage.h); argument parsing and printing
/// only.

#include "CliArgs.h"

#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/methods/Registry.h>
#include <lucent/methods/RenderImage.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/scene/SceneFile.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() &&
           s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

int runRender(const std::vector<std::string>& argv) {
    // The method decides which --NAME VALUE options are its parameters; Auto takes the
    // planner's instead.
    const std::string requested = Args::peek(argv, "method").value_or("direct");
    const bool autoMethod = requested == "auto";
    std::vector<std::string> valueOptions = {"method",   "o",       "output",  "width", "height",
                                             "exposure", "tonemap", "backend", "param"};
    if (autoMethod)
        valueOptions.insert(valueOptions.end(), {"budget-ms", "max-error", "models"});
    else
        for (const methods::ParamDescriptor& d : methods::find(requested).params)
            valueOptions.push_back(d.name);
    const Args args(argv, valueOptions, {"subsurface-only", "cpu", "gl"});
    if (args.positional().size() != 1)
        LUCENT_THROW(ValueError, "expected exactly one SCENE.json (see --help)");
    const std::string out = args.value("o").value_or(args.valueOr("output", ""));
    if (out.empty())
        LUCENT_THROW(ValueError, "missing -o/--output FILE (.png or .exr)");
    const bool exr = endsWith(out, ".exr");
    if (!exr && !endsWith(out, ".png"))
        LUCENT_THROW(ValueError, "-o/--output '", out, "': expected a .png or .exr file name");
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

    methods::RenderOptions options;
    options.backend = methods::parseBackend(args.valueOr("backend", "auto"));
    if (args.has("cpu") && args.has("gl"))
        LUCENT_THROW(ValueError, "--cpu and --gl exclude each other");
    if (args.has("cpu"))
        options.backend = methods::Backend::Cpu;
    if (args.has("gl"))
        options.backend = methods::Backend::Gl;
    options.subsurfaceOnly = args.has("subsurface-only");
    options.log = [](const std::string& m) { std::fprintf(stderr, "render: %s\n", m.c_str()); };
    options.progress = printProgressBar;

    Scene scene = loadScene(args.positional().front());
    for (const std::string& w : scene.warnings)
        std::fprintf(stderr, "lucent-cli render: warning: %s\n", w.c_str());
    scene.camera.width = args.intOr("width", scene.camera.width, 1, 16384);
    scene.camera.height = args.intOr("height", scene.camera.height, 1, 16384);

    std::string methodName = requested;
    methods::ParamSet params;
    if (autoMethod) {
        planner::Budget budget;
        budget.frameMs = args.floatOr("budget-ms", 1000.f, 1e-3f, 1e9f);
        budget.maxError = args.floatOr("max-error", 0.f, 0.f, 1e3f);
        std::string glReason;
        const bool gl = options.backend != methods::Backend::Cpu &&
                        gpu::GlContext::isHeadlessAvailable(&glReason);
        budget.directMs = 0;  // measured
        const planner::Models models = args.has("models")
                                           ? planner::loadModels(*args.value("models"))
                                           : planner::defaultModels();
        const planner::AutoChoice c =
            planner::chooseOffline(scene, models, budget, gl, options.log);
        std::fprintf(stderr, "render: auto: %s\n", c.plan.reason.c_str());
        methodName = c.method;
        params = c.params;
        if (options.backend == methods::Backend::Auto)
            options.backend = c.backend;
    }
    const methods::MethodInfo& method = methods::find(methodName);
    params.merge(methods::ParamSet::fromAssignments(args.values("param")));
    if (!autoMethod)
        for (const methods::ParamDescriptor& d : method.params)
            if (auto v = args.value(d.name))
                params.set(d.name, *v);
    const methods::RenderResult r = methods::renderImage(scene, method.name, params, options);
    if (method.caps.cpu && r.backend == methods::Backend::Cpu && options.progress)
        std::fputc('\n', stderr);
    std::fprintf(stderr, "render: %s on %s, %d frame(s), %.1f ms\n", method.name.c_str(),
                 r.device.c_str(), r.frames, r.milliseconds);
    for (const gpu::PassTiming& t : r.passes)
        std::fprintf(stderr, "  %-12s %8.2f ms GPU %8.2f ms CPU (last frame)\n", t.name.c_str(),
                     t.gpuMs, t.cpuMs);
    for (const methods::Stat& s : r.stats)
        std::fprintf(stderr, "  %s: %s\n", s.key.c_str(), s.value.c_str());
    for (const std::string& e : r.glErrors)
        std::fprintf(stderr, "%s\n", e.c_str());
    if (exr)
        writeExr(r.radiance, out);
    else
        writePng(r.radiance, out, tm);
    std::printf("wrote %s (%dx%d, method %s%s)\n", out.c_str(), r.radiance.width(),
                r.radiance.height(), method.name.c_str(),
                options.subsurfaceOnly ? ", subsurface only" : "");
    return 0;
}

}  // namespace

const Command renderCommand{
    "render", "one image of a scene with any translucency method (lucent-cli methods)",
    "usage: lucent-cli render SCENE.json [--method NAME] -o OUT.png|OUT.exr\n"
    "                         [--NAME VALUE | --param NAME=VALUE ...]\n"
    "                         [--backend auto|gl|cpu | --gl | --cpu]\n"
    "                         [--width W] [--height H] [--subsurface-only]\n"
    "       lucent-cli render SCENE.json --method auto [--budget-ms B | --max-error E]\n"
    "                         [--models F] -o OUT ...\n"
    "                         [--exposure E] [--tonemap clamp|reinhard|aces]\n"
    "\n"
    "Renders the scene with a registered method (`lucent-cli methods` lists them and their\n"
    "parameters). GL methods run through an offscreen OpenGL 4.5 context (EGL, no display\n"
    "needed); without one, a method with a CPU renderer falls back to it (said on stderr).\n"
    "\n"
    "  --method NAME      a method of `lucent-cli methods` (default direct);\n"
    "                     `lucent-cli methods NAME` lists its parameters and defaults;\n"
    "                     auto: the planner chooses method and setting from the scene's\n"
    "                     features and its fitted cost and error models, and says why on\n"
    "                     stderr (`lucent-cli plan SCENE` shows every candidate)\n"
    "  --budget-ms B      auto: time the render may take (default 1000 ms)\n"
    "  --max-error E      auto: the cheapest method predicted at or under block error E\n"
    "  --models F         auto: a models file (default: the built-in ones)\n"
    "  --NAME VALUE       a parameter of the method, e.g. --spp 64 --seed 3; the same as\n"
    "  --param NAME=VALUE (repeatable)\n"
    "  --backend B        auto (default: the method's own choice, GL falling back to the CPU),\n"
    "                     gl or cpu; --gl and --cpu are short for --backend gl|cpu\n"
    "  -o, --output FILE  .exr: linear radiance W/(mm^2 sr), 32-bit float;\n"
    "                     .png: 8-bit sRGB after --exposure and --tonemap (default aces)\n"
    "  --width, --height  override the scene camera's image size (pixels)\n"
    "  --subsurface-only  keep only the subsurface term of the method; for direct, which has\n"
    "                     none, the image is black\n"
    "\n"
    "The device, per-pass GPU/CPU timings and the method's statistics go to stderr.\n"
    "LUCENT_SHADER_DIR=DIR loads the shaders from DIR instead of the embedded copies;\n"
    "LUCENT_EGL_PLATFORM=surfaceless|device forces an EGL platform.\n",
    &runRender};

}  // namespace lucent::cli
