// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli reference`: the Monte Carlo ground truth of a scene as a linear EXR with
/// per-pixel variance and coverage layers (lucent/reference/PathTracer.h).

#include "CliArgs.h"

#include <lucent/core/Error.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/SceneFile.h>

#include <atomic>
#include <cctype>
#include <csignal>
#include <cstdio>
#include <filesystem>

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

int runReference(const std::vector<std::string>& argv) {
    const Args args(argv,
                    {"spp", "rse", "o", "output", "seed", "threads", "boundary", "max-scatter",
                     "majorant", "width", "height"},
                    {"subsurface-only", "per-channel", "quiet"});
    if (args.positional().size() != 1)
        LUCENT_THROW(ValueError, "expected exactly one SCENE.json (see --help)");
    const std::string out = args.value("o").value_or(args.valueOr("output", ""));
    if (out.empty())
        LUCENT_THROW(ValueError, "missing -o OUT.exr");
    // The output is always OpenEXR (linear radiance with variance layers): another extension
    // would name EXR bytes as something else.
    std::string ext = std::filesystem::path(out).extension().string();
    for (char& c : ext)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".exr")
        LUCENT_THROW(ValueError, "-o/--output '", out,
                     "': the reference writes OpenEXR (linear radiance with variance layers), "
                     "use a .exr name (render --method reference writes PNG)");
    if (!args.has("spp") && !args.has("rse"))
        LUCENT_THROW(ValueError, "give --spp N or --rse R (or both: R with N as the cap)");

    reference::ReferenceOptions opt;
    opt.targetRse = args.floatOr("rse", 0.f, 1e-5f, 1.f);
    opt.spp = args.intOr("spp", args.has("rse") ? 1 << 16 : 64, 3, 1 << 24);
    const std::string seed = args.valueOr("seed", "1");
    try {
        size_t used = 0;
        opt.seed = std::stoull(seed, &used);
        if (used != seed.size())
            throw std::invalid_argument(seed);
    } catch (const std::exception&) {
        LUCENT_THROW(ValueError, "--seed: expected a non-negative integer, got '", seed, "'");
    }
    opt.threads = args.intOr("threads", 0, 0, 1024);
    opt.boundary = reference::parseBoundaryModel(args.valueOr("boundary", "dielectric"));
    opt.subsurfaceOnly = args.has("subsurface-only");
    const std::string majorant = args.valueOr("majorant", "auto");
    if (majorant == "auto")
        opt.majorant = reference::MajorantMode::Auto;
    else if (majorant == "bricks")
        opt.majorant = reference::MajorantMode::Bricks;
    else if (majorant == "global")
        opt.majorant = reference::MajorantMode::Global;
    else
        LUCENT_THROW(ValueError, "--majorant: expected auto, bricks or global, got '", majorant,
                     "'");
    opt.spectralMis = !args.has("per-channel");
    opt.maxScatter = args.intOr("max-scatter", 1 << 20, 1, 1 << 30);
    const bool quiet = args.has("quiet");
    if (!quiet)
        opt.progress = printProgress;
    g_interrupted = false;
    opt.cancel = &g_interrupted;

    Scene scene = loadScene(args.positional().front());
    for (const std::string& w : scene.warnings)
        std::fprintf(stderr, "lucent-cli reference: warning: %s\n", w.c_str());
    scene.camera.width = args.intOr("width", scene.camera.width, 1, 16384);
    scene.camera.height = args.intOr("height", scene.camera.height, 1, 16384);
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
    return 0;
}

}  // namespace

const Command referenceCommand{
    "reference", "Monte Carlo ground truth of a scene (linear EXR with variance)",
    "usage: lucent-cli reference SCENE.json (--spp N | --rse R) -o OUT.exr [options]\n"
    "\n"
    "Volumetric path tracing of the painted material inside the mesh (null-collision tracking,\n"
    "per-brick majorants, HG phase, hero-channel spectral MIS; docs/reference.md).\n"
    "Writes linear RGB radiance with the layers 'variance' (per-pixel variance of the mean)\n"
    "and 'coverage' (1 where the object covers the pixel centre). Ctrl-C stops after the\n"
    "current tiles and writes the passes completed.\n"
    "\n"
    "  --spp N            samples per pixel (≥ 3; with --rse: the cap, default 65536)\n"
    "  --rse R            stop when the image relative standard error is ≤ R (e.g. 0.01)\n"
    "  -o, --output FILE  output EXR\n"
    "  --width, --height  override the scene camera's image size (pixels)\n"
    "  --seed S           random seed (default 1); same seed and spp → same image\n"
    "  --threads T        worker threads (default: all)\n"
    "  --boundary B       'dielectric' (default, exact: Fresnel and refraction at every crossing,\n"
    "                     η from the scene), 'matched' (η = 1) or 'straight' (fast approximation\n"
    "                     with straight shadow rays; not ground truth)\n"
    "  --subsurface-only  drop the direct Fresnel surface reflection\n"
    "  --majorant M       auto (default), bricks (per-brick majorants + DDA) or global\n"
    "  --per-channel      trace one channel per sample instead of hero-channel spectral MIS\n"
    "  --max-scatter K    cut paths after K scattering events (default 1048576)\n"
    "  --quiet            no progress bar\n",
    &runReference};

}  // namespace lucent::cli
