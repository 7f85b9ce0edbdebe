// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli reference`: the Monte Carlo ground truth of a scene as a linear EXR with
/// per-pixel variance and coverage layers (lucent/reference/PathTracer.h).

#include "CliCommon.h"

#include <lucent/core/Error.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/SceneFile.h>

#include <atomic>
#include <cctype>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace lucent::cli {

namespace {

std::atomic<bool> g_interrupted{false};

extern "C" void onInterrupt(int) {
    g_interrupted = true;
}

/// The reference's progress as the CLI's progress bar.
void printProgress(const reference::ReferenceProgress& p) {
    double frac = double(p.spp) / double(std::max(1, p.maxSpp));
    if (p.targetRse > 0.f && std::isfinite(p.rse) && p.rse > 0.f)
        // Error ∝ 1/√N: the fraction of the samples still needed is (rse/target)².
        frac = std::max(frac,
                        std::min(1.0, double(p.targetRse * p.targetRse) / double(p.rse * p.rse)));
    char status[128];
    int n = std::snprintf(status, sizeof status, "%6d spp  RSE %.4f", p.spp, double(p.rse));
    if (p.targetRse > 0.f)
        n += std::snprintf(status + n, sizeof status - size_t(n), " (target %.4f)",
                           double(p.targetRse));
    std::snprintf(status + n, sizeof status - size_t(n), "  %.1f s", p.elapsedMs * 1e-3);
    printProgressBar(frac, status);
}

struct ReferenceCliOptions {
    std::string scene, output, boundary = "dielectric";
    int spp = 64, threads = 0, maxScatter = 1 << 20, width = 0, height = 0;
    float rse = 0.f;
    uint64_t seed = 1;
    reference::MajorantMode majorant = reference::MajorantMode::Auto;
    bool subsurfaceOnly = false, perChannel = false, quiet = false;
    const CLI::App* app = nullptr;
    bool has(const std::string& option) const { return app->count(option) > 0; }
};

void runReference(const ReferenceCliOptions& args) {
    const std::string& out = args.output;
    // The output is always OpenEXR (linear radiance with variance layers): another extension
    // would name EXR bytes as something else.
    std::string ext = std::filesystem::path(out).extension().string();
    for (char& c : ext)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".exr")
        LUCENT_THROW(ValueError, "-o/--output '", out,
                     "': the reference writes OpenEXR (linear radiance with variance layers), "
                     "use a .exr name (render --method reference writes PNG)");

    reference::ReferenceOptions opt;
    opt.targetRse = args.rse;
    opt.spp = args.has("--spp") ? args.spp : args.has("--rse") ? 1 << 16 : 64;
    opt.seed = args.seed;
    opt.threads = args.threads;
    opt.boundary = reference::parseBoundaryModel(args.boundary);
    opt.subsurfaceOnly = args.subsurfaceOnly;
    opt.majorant = args.majorant;
    opt.spectralMis = !args.perChannel;
    opt.maxScatter = args.maxScatter;
    const bool quiet = args.quiet;
    if (!quiet)
        opt.progress = printProgress;
    g_interrupted = false;
    opt.cancel = &g_interrupted;

    Scene scene = loadScene(args.scene);
    for (const std::string& w : scene.warnings)
        std::fprintf(stderr, "lucent-cli reference: warning: %s\n", w.c_str());
    overrideImageSize(*args.app, args.width, args.height, scene.camera.width, scene.camera.height);
    auto previous = std::signal(SIGINT, onInterrupt);
    reference::ReferenceImage img;
    try {
        img = reference::renderReference(scene, opt);
    } catch (...) {
        std::signal(SIGINT, previous);
        throw;
    }
    std::signal(SIGINT, previous);
    if (!quiet)
        std::fputc('\n', stderr);
    if (img.spp == 0)
        LUCENT_THROW(Cancelled, "interrupted before the first pass finished");
    reference::writeReferenceExr(img, out);
    std::printf("%s: %dx%d, %d spp, RSE %.4f, %.2f s, %.3g paths/s%s\n", out.c_str(),
                img.mean.width(), img.mean.height(), img.spp, double(img.rse), img.seconds,
                img.seconds > 0 ? double(img.paths) / img.seconds : 0.0,
                img.cancelled ? " (interrupted: partial)" : "");
}

}  // namespace

void addReferenceCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* sub = addCommand(
        cli, "reference", "Monte Carlo ground truth of a scene (linear EXR with variance)",
        "usage: lucent-cli reference SCENE.json (--spp N | --rse R) -o OUT.exr [options]\n",
        "Volumetric path tracing of the painted material inside the mesh (null-collision\n"
        "tracking, per-brick majorants, HG phase, hero-channel spectral MIS;\n"
        "docs/reference.md).\n"
        "Writes linear RGB radiance with the layers 'variance' (per-pixel variance of the mean)\n"
        "and 'coverage' (1 where the object covers the pixel centre). Ctrl-C stops after the\n"
        "current tiles and writes the passes completed.\n");
    auto args = std::make_shared<ReferenceCliOptions>();
    args->app = sub;
    addSceneArgument(*sub, args->scene);
    CLI::Option* spp = sub->add_option("--spp", args->spp,
                                       "samples per pixel, >= 3 (default 64; with --rse: the "
                                       "cap, default 65536)")
                           ->type_name("N")
                           ->check(CLI::Range(3, 1 << 24));
    CLI::Option* rse =
        sub->add_option("--rse", args->rse,
                        "stop when the image relative standard error is <= R (e.g. 0.01)")
            ->type_name("R")
            ->check(finiteRange(1e-5, 1));
    sub->add_option("-o,--output", args->output, "output EXR")->type_name("FILE")->required();
    addImageSizeOptions(*sub, args->width, args->height);
    sub->add_option("--seed", args->seed,
                    "random seed (default 1); same seed and spp -> same image")
        ->type_name("S");
    sub->add_option("--threads", args->threads, "worker threads (default 0: all)")
        ->type_name("T")
        ->check(CLI::Range(0, 1024));
    sub->add_option("--boundary", args->boundary,
                    "'dielectric' (default, exact: Fresnel and refraction at every crossing, eta "
                    "from the scene), 'matched' (eta = 1) or 'straight' (fast approximation with "
                    "straight shadow rays; not ground truth)")
        ->type_name("B");
    sub->add_flag("--subsurface-only", args->subsurfaceOnly,
                  "drop the direct Fresnel surface reflection");
    addChoiceOption<reference::MajorantMode>(
        *sub, "--majorant", args->majorant,
        {{"auto", reference::MajorantMode::Auto},
         {"bricks", reference::MajorantMode::Bricks},
         {"global", reference::MajorantMode::Global}},
        "auto (default), bricks (per-brick majorants + DDA) or global");
    sub->add_flag("--per-channel", args->perChannel,
                  "trace one channel per sample instead of hero-channel spectral MIS");
    sub->add_option("--max-scatter", args->maxScatter,
                    "cut paths after K scattering events (default 1048576)")
        ->type_name("K")
        ->check(CLI::Range(1, 1 << 30));
    sub->add_flag("--quiet", args->quiet, "no progress bar");
    sub->callback([args, spp, rse] {
        if (!spp->count() && !rse->count())
            LUCENT_THROW(ValueError, "give --spp N or --rse R (or both: R with N as the cap)");
        runReference(*args);
    });
}

}  // namespace lucent::cli
