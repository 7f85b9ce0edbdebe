// SPDX-License-Identifier: MIT
/// @file
/// @brief Soak test of the live preview (issue 16 §6, benchmark-only): scripted strokes into
/// the default scene's 128³ volume, each followed by one live frame of a method from the
/// registry, driven as the app drives it (lucent/methods/Method.h: materialChanged with the
/// dirty bricks, then render) on a headless EGL context. Per method it reports resident memory
/// (/proc/self/statm) at the start, middle and end, the growth per stroke (least-squares slope
/// after a warm-up), the live GL objects (the gpu module's counter, and textures, buffers and
/// framebuffers found by glIsTexture/glIsBuffer/glIsFramebuffer over the first ids) and every
/// GL error (glGetError and the KHR_debug log). Not in CTest: results in docs/benchmarks.md.
///
///     soak_live [--strokes N] [--seconds S] [--methods a,b,...] [--size WxH]
///
/// N strokes per method (10000), or as many as fit in S seconds (120), whichever comes first.
/// "Start" is after WARMUP_STROKES strokes, "middle" at half the strokes or half the time.
/// Exit status 1 when a method leaks GL objects, grows by more than GROWTH_LIMIT bytes per
/// stroke or reports a GL error.

#include <lucent/core/Timer.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/material/Brush.h>

#include "LiveMethodHarness.h"

#include <CLI/CLI.hpp>
#include <epoxy/gl.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace lucent;

/// Growth per stroke above which a method is reported as leaking: 10 strokes a second for an
/// 8-hour day at this rate would hold 288 000 strokes × 1 KiB ≈ 0.3 GB.
constexpr double GROWTH_LIMIT_BYTES_PER_STROKE = 1024.0;
/// GL names probed with glIs*: far above what one renderer and one method hold (a few hundred),
/// so that a leak growing past the counter's view still shows.
constexpr unsigned PROBED_GL_IDS = 20000;
/// Strokes before the "start" figures: the GPU profiler makes its timer queries in the first
/// frames (10 of them, once), and the allocator's pools fill.
constexpr int WARMUP_STROKES = 20;

long long residentBytes() {
    std::ifstream statm("/proc/self/statm");
    long long size = 0, resident = 0;
    statm >> size >> resident;
    return resident * sysconf(_SC_PAGESIZE);
}

struct GlNames {
    int textures = 0, buffers = 0, framebuffers = 0;
};
GlNames probeGlNames() {
    GlNames n;
    for (unsigned id = 1; id <= PROBED_GL_IDS; ++id) {
        n.textures += glIsTexture(id) ? 1 : 0;
        n.buffers += glIsBuffer(id) ? 1 : 0;
        n.framebuffers += glIsFramebuffer(id) ? 1 : 0;
    }
    return n;
}

/// Least-squares slope of y over x.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
    const double n = double(x.size());
    if (n < 2)
        return 0.0;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        sx += x[i];
        sy += y[i];
        sxx += x[i] * x[i];
        sxy += x[i] * y[i];
    }
    const double d = n * sxx - sx * sx;
    return d > 0 ? (n * sxy - sx * sy) / d : 0.0;
}

struct Options {
    int strokes = 10000;
    double seconds = 120.0;
    std::vector<std::string> methods;  // empty: every method with a GL pass
    int width = 160, height = 120;
};

struct Result {
    std::string method;
    int strokes = 0;
    double seconds = 0.0;
    long long rssStart = 0, rssMiddle = 0, rssEnd = 0;
    double bytesPerStroke = 0.0;
    size_t glObjectsStart = 0, glObjectsEnd = 0;
    GlNames namesStart, namesEnd;
    int glErrors = 0;
};

/// The strokes of one method (the harness lives in here: its teardown's GL errors count too).
void soakStrokes(bench::LiveMethodHarness& live, const Options& opt, Result& r,
                 const std::function<int()>& glErrors) {
    MaterialVolume& volume = live.volume;
    const GridSpec spec = volume.spec();
    std::vector<Coord> inside;  // stroke starts: every 61st inside voxel
    size_t count = 0;
    for (int z = 0; z < spec.resolution; ++z)
        for (int y = 0; y < spec.resolution; ++y)
            for (int x = 0; x < spec.resolution; ++x)
                if (volume.isInside({x, y, z}) && count++ % 61 == 0)
                    inside.push_back({x, y, z});

    r.glErrors += glErrors();

    std::vector<double> at, rss;
    Timer clock;
    uint32_t lcg = 12345;
    for (int s = 0; s < opt.strokes && clock.elapsedMs() < opt.seconds * 1000.0; ++s) {
        // A stroke: four stamps along +x from a random inside voxel, then one live frame.
        lcg = lcg * 1664525u + 1013904223u;
        const Coord start = inside[(lcg >> 8) % inside.size()];
        BrushSettings brush;
        brush.radius = 3.f * spec.voxelSize;
        brush.mode = BrushMode::Set;
        brush.value = {Rgb(1.f + float(s % 7)), Rgb(0.5f), Rgb(0.1f * float(s % 3))};
        for (int k = 0; k < 4; ++k)
            stamp(volume, brush, spec.cellCenter(start) + Vector3f(float(k) * spec.voxelSize, 0, 0),
                  nullptr);
        live.strokeFrame();
        r.glErrors += glErrors();
        r.strokes = s + 1;
        if (s + 1 == WARMUP_STROKES) {
            r.rssStart = residentBytes();
            r.glObjectsStart = gpu::liveGlObjectCount();
            r.namesStart = probeGlNames();
        }
        if (s % 50 == 0) {
            at.push_back(double(s));
            rss.push_back(double(residentBytes()));
            if (r.rssMiddle == 0 && clock.elapsedMs() >= opt.seconds * 500.0)
                r.rssMiddle = residentBytes();
        }
        if (s == opt.strokes / 2)
            r.rssMiddle = residentBytes();
    }
    r.seconds = clock.elapsedMs() / 1000.0;
    r.rssEnd = residentBytes();
    r.glObjectsEnd = gpu::liveGlObjectCount();
    r.namesEnd = probeGlNames();
    // Growth after a warm-up of the first tenth (allocator pools and driver caches fill).
    const size_t skip = at.size() / 10;
    r.bytesPerStroke = slope(std::vector<double>(at.begin() + long(skip), at.end()),
                             std::vector<double>(rss.begin() + long(skip), rss.end()));
}

Result soak(const std::string& name, const Options& opt, gpu::GlContext& ctx) {
    Result r;
    r.method = name;
    const std::function<int()> glErrors = [&ctx] {
        int n = 0;
        while (glGetError() != GL_NO_ERROR)
            ++n;
        return n + int(ctx.debugLog().takeErrors().size());
    };
    {
        bench::LiveMethodHarness live(name, opt.width, opt.height);
        soakStrokes(live, opt, r, glErrors);
    }
    r.glErrors += glErrors();
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    Options opt;
    std::string size = std::to_string(opt.width) + "x" + std::to_string(opt.height);
    std::string methodList;
    CLI::App app{"Soak of the live preview: scripted strokes per live method (headless EGL)"};
    app.add_option("--strokes", opt.strokes, "strokes per method, at most")
        ->check(CLI::Range(WARMUP_STROKES + 1, 100000000));
    app.add_option("--seconds", opt.seconds, "seconds per method, at most")
        ->check(CLI::PositiveNumber);
    app.add_option("--size", size, "viewport WxH");
    app.add_option("--methods", methodList,
                   "comma-separated registry names (default: every GL method)");
    CLI11_PARSE(app, argc, argv);
    if (std::sscanf(size.c_str(), "%dx%d", &opt.width, &opt.height) != 2 || opt.width < 8 ||
        opt.height < 8) {
        std::fprintf(stderr, "soak_live: --size must be WxH, at least 8x8\n");
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
    std::printf("soak_live: %s, %dx%d, up to %d strokes or %.0f s per method\n",
                ctx->renderer().c_str(), opt.width, opt.height, opt.strokes, opt.seconds);
    std::printf(
        "| method | strokes | s | RSS start MiB | middle | end | bytes/stroke (slope) | "
        "GL objects start → end | textures/buffers/FBOs start → end | GL errors |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    bool ok = true;
    const auto mib = [](long long b) { return double(b) / (1024.0 * 1024.0); };
    for (const std::string& name : opt.methods) {
        const Result r = soak(name, opt, *ctx);
        std::printf(
            "| %s | %d | %.0f | %.1f | %.1f | %.1f | %.0f | %zu → %zu | %d/%d/%d → "
            "%d/%d/%d | %d |\n",
            r.method.c_str(), r.strokes, r.seconds, mib(r.rssStart), mib(r.rssMiddle),
            mib(r.rssEnd), r.bytesPerStroke, r.glObjectsStart, r.glObjectsEnd,
            r.namesStart.textures, r.namesStart.buffers, r.namesStart.framebuffers,
            r.namesEnd.textures, r.namesEnd.buffers, r.namesEnd.framebuffers, r.glErrors);
        std::fflush(stdout);
        const bool namesGrew = r.namesEnd.textures > r.namesStart.textures ||
                               r.namesEnd.buffers > r.namesStart.buffers ||
                               r.namesEnd.framebuffers > r.namesStart.framebuffers;
        ok = ok && r.glErrors == 0 && r.glObjectsEnd <= r.glObjectsStart && !namesGrew &&
             r.bytesPerStroke < GROWTH_LIMIT_BYTES_PER_STROKE;
    }
    std::printf("live GL objects after every method was destroyed: %zu (leaked: %zu)\n",
                gpu::liveGlObjectCount(), gpu::leakedGlObjectCount());
    ok = ok && gpu::liveGlObjectCount() == 0 && gpu::leakedGlObjectCount() == 0;
    std::printf("%s\n", ok ? "soak_live: no growth, no GL error" : "soak_live: FAILED");
    return ok ? 0 : 1;
}
