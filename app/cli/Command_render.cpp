// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli render SCENE.json --method NAME -o out.png|out.exr`: one image of a scene
/// with any registered method (lucent/methods/RenderImage.h); argument parsing and printing
/// only.

#include "CliCommon.h"

#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/methods/Registry.h>
#include <lucent/methods/RenderImage.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/LevelCheck.h>
#include <lucent/scene/SceneFile.h>

#include <algorithm>
#include <map>
#include <memory>
#include <cstdio>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() &&
           s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

struct RenderOptions {
    std::string scene, method = "direct", output, backend = "auto";
    int width = 0, height = 0;
    float exposure = 1.f, budgetMs = 1000.f, maxError = 0.f;
    planner::LevelTolerance levelTolerance;
    planner::OwnReferenceOptions measureOptions;
    bool measure = false;
    ToneMap::Curve curve = ToneMap::Curve::Aces;
    std::string models;
    std::vector<std::string> assignments;             ///< --param NAME=VALUE
    std::map<std::string, std::string> methodParams;  ///< --NAME VALUE, every method's names
    bool subsurfaceOnly = false, cpu = false, gl = false, allLights = false;
    const CLI::App* app = nullptr;
    bool has(const std::string& option) const { return app->count(option) > 0; }
};

void runRender(const RenderOptions& args) {
    // The method decides which --NAME VALUE options are its parameters; Auto takes the
    // planner's instead.
    const std::string& requested = args.method;
    const bool autoMethod = requested == "auto";
    if (!autoMethod) {
        const methods::MethodInfo& info = methods::find(requested);  // lists the valid names
        for (const char* option :
             {"--budget-ms", "--max-error", "--models", "--level-tolerance", "--level-relative",
              "--no-level-check", "--measure", "--measure-width", "--measure-spp"})
            if (args.has(option))
                LUCENT_THROW(ValueError, option, " applies to --method auto only");
        for (const auto& [name, value] : args.methodParams)
            if (std::none_of(info.params.begin(), info.params.end(),
                             [&](const methods::ParamDescriptor& d) { return d.name == name; }))
                LUCENT_THROW(ValueError, "--", name, " is not a parameter of method ", info.name,
                             " (lucent-cli methods ", info.name, " lists them)");
    } else if (!args.methodParams.empty()) {
        LUCENT_THROW(ValueError, "--", args.methodParams.begin()->first,
                     ": --method auto chooses the parameters itself");
    }
    const std::string& out = args.output;
    const bool exr = endsWith(out, ".exr");
    if (!exr && !endsWith(out, ".png"))
        LUCENT_THROW(ValueError, "-o/--output '", out, "': expected a .png or .exr file name");
    ToneMap tm;
    tm.exposure = args.exposure;
    tm.curve = args.curve;

    methods::RenderOptions options;
    options.backend = methods::parseBackend(args.backend);
    if (args.cpu)
        options.backend = methods::Backend::Cpu;
    if (args.gl)
        options.backend = methods::Backend::Gl;
    options.subsurfaceOnly = args.subsurfaceOnly;
    if (args.allLights)
        options.lightSkipEpsilon = -1.f;
    options.log = [](const std::string& m) { std::fprintf(stderr, "render: %s\n", m.c_str()); };
    options.progress = printProgressBar;

    Scene scene = loadScene(args.scene);
    for (const std::string& w : scene.warnings)
        std::fprintf(stderr, "lucent-cli render: warning: %s\n", w.c_str());
    overrideImageSize(*args.app, args.width, args.height, scene.camera.width, scene.camera.height);

    std::string methodName = requested;
    methods::ParamSet params;
    if (autoMethod) {
        planner::Budget budget;
        budget.frameMs = args.budgetMs;
        budget.maxError = args.maxError;
        std::string glReason;
        const bool gl = options.backend != methods::Backend::Cpu &&
                        gpu::GlContext::isHeadlessAvailable(&glReason);
        if (args.measure && !gl)  // the Direct frame, the costs' unit, renders with GL only
            LUCENT_THROW(ValueError,
                         "--measure renders the candidates and the Direct frame with OpenGL, "
                         "which is not available (",
                         options.backend == methods::Backend::Cpu ? "--cpu" : glReason, ")");
        budget.directMs = 0;  // measured
        const planner::Models models =
            args.has("--models") ? planner::loadModels(args.models) : planner::defaultModels();
        planner::AutoChoice c = planner::chooseOffline(scene, models, budget, gl, options.log);
        if (args.measure) {  // measured errors tell the levels apart: no level check after
            planner::OwnReferenceOptions mo = args.measureOptions;
            mo.render.log = options.log;
            mo.render.subsurfaceOnly = options.subsurfaceOnly;
            mo.render.backend = options.backend;
            c = planner::chooseByMeasuring(scene, models, c, budget, gl, mo, options.log).choice;
        } else if (!args.levelTolerance.off()) {
            planner::LevelCheckOptions lo;
            lo.tolerance = args.levelTolerance;
            lo.render.log = options.log;
            lo.render.subsurfaceOnly = options.subsurfaceOnly;
            lo.render.backend = options.backend;
            planner::runLevelCheck(scene, models, c, lo);
        }
        std::fprintf(stderr, "render: auto: %s\n", c.plan.reason.c_str());
        methodName = c.method;
        params = c.params;
        if (options.backend == methods::Backend::Auto)
            options.backend = c.backend;
    }
    const methods::MethodInfo& method = methods::find(methodName);
    params.merge(methods::ParamSet::fromAssignments(args.assignments));
    for (const auto& [name, value] : args.methodParams)
        params.set(name, value);
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
}

}  // namespace

void addRenderCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* sub = addCommand(
        cli, "render", "one image of a scene with any translucency method (lucent-cli methods)",
        "usage: lucent-cli render SCENE.json [--method NAME] -o OUT.png|OUT.exr\n"
        "                         [--NAME VALUE | --param NAME=VALUE ...]\n"
        "                         [--backend auto|gl|cpu | --gl | --cpu]\n"
        "                         [--width W] [--height H] [--subsurface-only] [--all-lights]\n"
        "                         [--exposure E] [--tonemap clamp|reinhard|aces]\n"
        "       lucent-cli render SCENE.json --method auto [--budget-ms B | --max-error E]\n"
        "                         [--models F] [--level-tolerance T] [--level-relative K]\n"
        "                         [--no-level-check | --measure [--measure-width W]\n"
        "                         [--measure-spp N]] -o OUT ...\n",
        "Renders the scene with a registered method (`lucent-cli methods` lists them and their\n"
        "parameters). GL methods run through an offscreen OpenGL 4.5 context (EGL, no display\n"
        "needed); without one, a method with a CPU renderer falls back to it (said on stderr).\n"
        "The device, per-pass GPU/CPU timings and the method's statistics go to stderr.\n");
    sub->footer(
        "LUCENT_SHADER_DIR=DIR loads the shaders from DIR instead of the embedded copies;\n"
        "LUCENT_EGL_PLATFORM=surfaceless|device forces an EGL platform.");
    auto args = std::make_shared<RenderOptions>();
    args->app = sub;
    addSceneArgument(*sub, args->scene);
    sub->add_option("--method", args->method,
                    "a method of `lucent-cli methods` (default direct); `lucent-cli methods "
                    "NAME` lists its parameters and defaults; auto: the planner chooses method "
                    "and setting from the scene's features and its fitted cost and error models, "
                    "and says why on stderr (`lucent-cli plan SCENE` shows every candidate)")
        ->type_name("NAME");
    sub->add_option("-o,--output", args->output,
                    ".exr: linear radiance W/(mm^2 sr), 32-bit float; .png: 8-bit sRGB after "
                    "--exposure and --tonemap")
        ->type_name("FILE")
        ->required();
    sub->add_option("--param", args->assignments,
                    "a parameter of the method, the same as --NAME VALUE (repeatable)")
        ->type_name("NAME=VALUE")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    CLI::Option* backend =
        sub->add_option("--backend", args->backend,
                        "auto (default: the method's own choice, GL falling back to the CPU), gl "
                        "or cpu")
            ->type_name("B")
            ->check(CLI::IsMember({"auto", "gl", "cpu"}));
    CLI::Option* gl = sub->add_flag("--gl", args->gl, "short for --backend gl")->excludes(backend);
    sub->add_flag("--cpu", args->cpu, "short for --backend cpu")->excludes(backend)->excludes(gl);
    addImageSizeOptions(*sub, args->width, args->height);
    sub->add_flag("--subsurface-only", args->subsurfaceOnly,
                  "keep only the subsurface term of the method; for direct, which has none, the "
                  "image is black");
    sub->add_flag("--all-lights", args->allLights,
                  "render every light: without it, lights that miss the object or give it at "
                  "most 1/1024 of the strongest light's irradiance are skipped (said on stderr; "
                  "the reference method never skips)");
    sub->add_option("--exposure", args->exposure, "PNG: exposure multiplier (default 1)")
        ->type_name("E")
        ->check(finiteRange(0, 1e6));
    addChoiceOption<ToneMap::Curve>(*sub, "--tonemap", args->curve,
                                    {{"clamp", ToneMap::Curve::Clamp},
                                     {"reinhard", ToneMap::Curve::Reinhard},
                                     {"aces", ToneMap::Curve::Aces}},
                                    "PNG: tone curve (default aces)");
    const char* autoGroup = "Options of --method auto";
    sub->add_option("--budget-ms", args->budgetMs, "time the render may take (default 1000 ms)")
        ->type_name("B")
        ->check(finiteRange(1e-3, 1e9))
        ->group(autoGroup);
    sub->add_option("--max-error", args->maxError,
                    "instead: the cheapest method predicted at or under block error E")
        ->type_name("E")
        ->check(finiteRange(0, 1e3))
        ->group(autoGroup);
    sub->add_option("--models", args->models, "a models file (default: the built-in ones)")
        ->type_name("F")
        ->check(existingFile())
        ->group(autoGroup);
    addLevelCheckOptions(*sub, args->levelTolerance, autoGroup);
    addMeasureOptions(*sub, args->measure, args->measureOptions, autoGroup);
    // Every method's parameters as --NAME VALUE; runRender() rejects those the chosen method
    // lacks. (The method's own ranges are checked by the engine, which knows them.)
    std::map<std::string, std::string> users;
    std::map<std::string, std::string> help;
    for (const methods::MethodInfo* m : methods::all())
        for (const methods::ParamDescriptor& d : m->params) {
            users[d.name] += (users[d.name].empty() ? "" : ", ") + m->name;
            help.emplace(d.name, d.help);
        }
    for (const auto& [name, methodsList] : users)
        sub->add_option_function<std::string>(
               "--" + name,
               [args, name = name](const std::string& v) { args->methodParams[name] = v; },
               help[name] + " (" + methodsList + ")")
            ->type_name("VALUE")
            ->group("Method parameters (lucent-cli methods NAME: types, ranges, defaults)");
    sub->callback([args] { runRender(*args); });
}

}  // namespace lucent::cli
