// SPDX-License-Identifier: MIT
/// @file
/// @brief What a paint stroke's frame costs in each live method, pass by pass: scripted strokes
/// into the default scene's volume (as soak_live), each followed by one live frame and then
/// idle frames, driven as the app drives a method (materialChanged with the dirty bricks, then
/// render) on a headless EGL context. A stroke is --stamps stamps of the app's starting brush (or
/// --brush-mm), half a radius apart along +x from a voxel of the surface shell. Prints, per method,
/// the median wall time of the stroke frame and of the idle frames (render() + glFinish) and the
/// method's own per-pass statistics of the stroke frame (the keys holding " ms"), so a slow pass
/// can be found without the app. Not a Google Benchmark: results in docs/benchmarks.md ("Stroke
/// frames of the image-space dipoles").
///
///     live_stroke_frames [--strokes N] [--idle K | --until-converged] [--methods a,b,...]
///                        [--size WxH] [--brush-mm R] [--stamps N] [--param key=value ...]
///                        [--scene FILE]

#include "LiveMethodHarness.h"

#include <lucent/core/Timer.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/material/Brush.h>

#include <CLI/CLI.hpp>
#include <epoxy/gl.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace lucent;

struct Options {
    int strokes = 12;
    int idle = 4;
    std::vector<std::string> methods;  // empty: every method with a GL pass
    int width = 640, height = 360;
    float brushRadius = startingBrush().radius;  ///< mm: the app's starting brush
    int stamps = 8;                              ///< per stroke, half a radius apart
    methods::ParamSet params;                    ///< --param key=value, for every method
    bool idlePasses = false;  ///< also the first idle frame's passes (deferred work)
    /// Idle frames after each stroke until the method has converged (at most 1000) instead of
    /// --idle: SSLPV's refinement of a propagation in flight, the dipoles' progressive samples.
    bool untilConverged = false;
    std::string scenePath;  ///< empty: the default scene
};

double median(std::vector<double> v) {
    if (v.empty())
        return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

void profile(const std::string& name, const Options& opt) {
    bench::LiveMethodHarness live(
        name, opt.width, opt.height, opt.params,
        opt.scenePath.empty() ? makeDefaultScene() : loadScene(opt.scenePath));
    MaterialVolume& volume = live.volume;
    const methods::Method& method = *live.method;
    const GridSpec spec = volume.spec();
    // Stroke starts: every 7th inside voxel of the surface shell (an axis neighbour outside),
    // where the app's brush paints.
    std::vector<Coord> inside;
    size_t count = 0;
    const auto outside = [&](int x, int y, int z) {
        return x < 0 || y < 0 || z < 0 || x >= spec.resolution || y >= spec.resolution ||
               z >= spec.resolution || !volume.isInside({x, y, z});
    };
    for (int z = 0; z < spec.resolution; ++z)
        for (int y = 0; y < spec.resolution; ++y)
            for (int x = 0; x < spec.resolution; ++x)
                if (volume.isInside({x, y, z}) &&
                    (outside(x - 1, y, z) || outside(x + 1, y, z) || outside(x, y - 1, z) ||
                     outside(x, y + 1, z) || outside(x, y, z - 1) || outside(x, y, z + 1)) &&
                    count++ % 7 == 0)
                    inside.push_back({x, y, z});

    const auto frame = [&live] {
        Timer t;
        live.renderer.render();
        glFinish();
        return t.elapsedMs();
    };
    // Two warm-up strokes: llvmpipe compiles the preview programs on first use.
    std::vector<double> strokeMs, idleMs, idleFrames;
    std::map<std::string, std::vector<double>> passes, firstIdlePasses;
    uint32_t lcg = 12345;
    for (int s = -2; s < opt.strokes; ++s) {
        lcg = lcg * 1664525u + 1013904223u;
        const Coord start = inside[(lcg >> 8) % inside.size()];
        BrushSettings brush = startingBrush();
        brush.radius = opt.brushRadius;
        brush.strength = 1.f;
        brush.value = {Rgb(1.f + float((s + 7) % 7)), Rgb(0.5f), Rgb(0.f)};
        for (int k = 0; k < opt.stamps; ++k)
            stamp(volume, brush,
                  spec.cellCenter(start) + Vector3f(0.5f * float(k) * brush.radius, 0, 0), nullptr);
        Timer t;
        live.strokeFrame();
        glFinish();
        const double ms = t.elapsedMs();
        if (s < 0)
            continue;
        strokeMs.push_back(ms);
        const auto keep = [&method](std::map<std::string, std::vector<double>>& into) {
            for (const methods::Stat& stat : method.stats())
                if (stat.key.find(" ms") != std::string::npos || stat.key.rfind("pixels", 0) == 0)
                    into[stat.key].push_back(std::atof(stat.value.c_str()));
        };
        keep(passes);
        int i = 0;
        for (; opt.untilConverged ? !method.converged() && i < 1000 : i < opt.idle; ++i) {
            idleMs.push_back(frame());
            if (i == 0)
                keep(firstIdlePasses);
        }
        idleFrames.push_back(double(i));
    }
    std::printf("| %s | %.1f | %.1f |", name.c_str(), median(strokeMs), median(idleMs));
    if (opt.untilConverged)
        std::printf(" idle frames to converge %g;", median(idleFrames));
    for (const auto& [key, values] : passes)
        std::printf(" %s %.4g;", key.c_str(), median(values));
    if (opt.idlePasses) {
        std::printf(" | first idle frame:");
        for (const auto& [key, values] : firstIdlePasses)
            std::printf(" %s %.4g;", key.c_str(), median(values));
    }
    std::printf("\n");
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
    Options opt;
    std::string size = "640x360", methodList;
    CLI::App app{"A stroke's live frame pass by pass, per method (headless EGL)"};
    app.add_option("--strokes", opt.strokes, "measured strokes per method")
        ->check(CLI::PositiveNumber);
    app.add_option("--idle", opt.idle, "idle frames after each stroke")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--size", size, "viewport WxH");
    app.add_option("--brush-mm", opt.brushRadius, "brush radius, mm (default: the app's)")
        ->check(CLI::PositiveNumber);
    app.add_option("--stamps", opt.stamps, "stamps per stroke, half a radius apart")
        ->check(CLI::PositiveNumber);
    app.add_flag("--idle-passes", opt.idlePasses,
                 "also print the passes of the first idle frame after each stroke");
    app.add_flag("--until-converged", opt.untilConverged,
                 "idle frames after each stroke until the method has converged (at most 1000; "
                 "replaces --idle)");
    app.add_option("--scene", opt.scenePath, "scene file (default: the app's default scene)")
        ->check(CLI::ExistingFile);
    std::vector<std::string> assignments;
    app.add_option("--param", assignments, "a method parameter, key=value (repeatable)");
    app.add_option("--methods", methodList,
                   "comma-separated registry names (default: every GL method)");
    CLI11_PARSE(app, argc, argv);
    try {
        opt.params = methods::ParamSet::fromAssignments(assignments);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "live_stroke_frames: %s\n", e.what());
        return 2;
    }
    if (std::sscanf(size.c_str(), "%dx%d", &opt.width, &opt.height) != 2 || opt.width < 8 ||
        opt.height < 8) {
        std::fprintf(stderr, "live_stroke_frames: --size must be WxH, at least 8x8\n");
        return 2;
    }
    std::stringstream list(methodList);
    for (std::string m; std::getline(list, m, ',');)
        opt.methods.push_back(m);
    if (opt.methods.empty())
        for (const methods::MethodInfo* info : methods::all())
            if (info->caps.gl)
                opt.methods.push_back(info->name);
    std::unique_ptr<gpu::GlContext> ctx = gpu::GlContext::createHeadless();
    std::printf("live_stroke_frames: %s, %dx%d, %d strokes, %d idle frames after each\n",
                ctx->renderer().c_str(), opt.width, opt.height, opt.strokes, opt.idle);
    std::printf(
        "| method | stroke frame ms (median) | idle frame ms | stroke frame's passes (ms) |\n");
    std::printf("|---|---|---|---|\n");
    for (const std::string& name : opt.methods)
        profile(name, opt);
    return 0;
}
