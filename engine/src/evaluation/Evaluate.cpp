// SPDX-License-Identifier: MIT
/// @file
/// @brief Variants, the reference cache, the metrics and the per-case run (Evaluate.h).

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/core/Timer.h>
#include <lucent/evaluation/Evaluate.h>
#include <lucent/methods/Registry.h>
#include <lucent/methods/RenderImage.h>
#include <lucent/reference/PathTracer.h>

#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>

namespace lucent::evaluation {

namespace {

namespace fs = std::filesystem;

/// The "reference" method variant runs with the reference's seed plus this, so that its error
/// is the Monte Carlo noise of both estimates, not zero (seed 7 against the default 1).
constexpr int TEST_PT_SEED_OFFSET = 6;

/// Sends stderr to /dev/null while alive (the methods print per-pass logs), unless disabled.
class StderrSilencer {
public:
    explicit StderrSilencer(bool enabled) {
        if (!enabled)
            return;
        std::fflush(stderr);
        m_saved = dup(2);
        const int devNull = open("/dev/null", O_WRONLY);
        if (m_saved >= 0 && devNull >= 0)
            dup2(devNull, 2);
        if (devNull >= 0)
            close(devNull);
    }
    ~StderrSilencer() {
        if (m_saved < 0)
            return;
        std::fflush(stderr);
        dup2(m_saved, 2);
        close(m_saved);
    }
    StderrSilencer(const StderrSilencer&) = delete;
    StderrSilencer& operator=(const StderrSilencer&) = delete;

private:
    int m_saved = -1;
};

/// FNV-1a 64, fed piece by piece.
class Fnv1a {
public:
    void bytes(const void* data, size_t n) {
        const auto* p = static_cast<const uint8_t*>(data);
        for (size_t i = 0; i < n; ++i) {
            m_h ^= uint64_t(p[i]);
            m_h *= 1099511628211ull;
        }
    }
    template <typename T>
    void value(const T& v) {
        bytes(&v, sizeof v);
    }
    [[nodiscard]] uint64_t digest() const { return m_h; }

private:
    uint64_t m_h = 1469598103934665603ull;
};

std::string hex(uint64_t v) {
    char buf[20];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Variants

std::string knownVariants() {
    std::string s;
    for (const methods::MethodInfo* m : methods::all()) {
        s += (s.empty() ? "" : ", ") + m->name;
        std::string v;
        for (const methods::ParamPreset& p : m->variants)
            v += (v.empty() ? "[:" : "|:") + p.name;
        if (!v.empty())
            s += v + "]";
    }
    return s;
}

std::string defaultVariants() {
    std::string s;
    for (const methods::MethodInfo* m : methods::all())
        for (const std::string& v : m->evaluate)
            s += (s.empty() ? "" : ",") + m->name + (v.empty() ? "" : ":" + v);
    return s;
}

Variant parseVariant(const std::string& entry) {
    Variant v;
    v.name = entry;
    const size_t colon = entry.find(':');
    v.method = entry.substr(0, colon);
    const std::string suffix = colon == std::string::npos ? "" : entry.substr(colon + 1);
    if (!methods::exists(v.method))
        LUCENT_THROW(ValueError, "--methods: unknown method '", v.method, "' in '", entry,
                     "' (known: ", knownVariants(), ")");
    const methods::MethodInfo& info = methods::find(v.method);
    if (!suffix.empty()) {
        const auto it =
            std::find_if(info.variants.begin(), info.variants.end(),
                         [&](const methods::ParamPreset& p) { return p.name == suffix; });
        if (it == info.variants.end()) {
            std::string allowed;
            for (const methods::ParamPreset& p : info.variants)
                allowed += (allowed.empty() ? "" : ", ") + p.name;
            LUCENT_THROW(ValueError, "--methods: '", entry, "': unknown variant '", suffix, "' of ",
                         v.method, " (allowed: ", allowed.empty() ? "none" : allowed, ")");
        }
        v.variant = *it;
    }
    v.settings = info.quality;
    if (v.settings.empty())  // a method without quality levels runs once with its defaults
        v.settings.push_back({"-", {}, methods::Backend::Auto});
    return v;
}

std::vector<Variant> parseVariants(const std::string& list) {
    std::vector<Variant> out;
    std::string cur;
    for (char c : list + ",") {
        if (c == ',') {
            if (!cur.empty())
                out.push_back(parseVariant(cur));
            cur.clear();
        } else if (c != ' ') {
            cur += c;
        }
    }
    if (out.empty())
        LUCENT_THROW(ValueError, "--methods: no method given");
    return out;
}

// ---------------------------------------------------------------------------------------------
// Reference cache

uint64_t hashScene(const Scene& scene) {
    Fnv1a h;
    h.value(scene.eta);
    h.value(scene.environment);
    const Camera& c = scene.camera;
    h.value(c.position);
    h.value(c.target);
    h.value(c.up);
    h.value(c.orthographic);
    h.value(c.fovYDeg);
    h.value(c.orthoHeight);
    h.value(c.width);
    h.value(c.height);
    h.value(c.nearPlane);
    h.value(c.farPlane);
    h.value(scene.lights.size());
    for (const Light& l : scene.lights) {
        h.value(l.type);
        h.value(l.position);
        h.value(l.direction);
        h.value(l.intensity);
        h.value(l.spotOuterDeg);
        h.value(l.spotInnerDeg);
        h.value(l.radius);
    }
    h.value(scene.objects.size());
    for (const SceneObject& obj : scene.objects) {
        const TriangleMesh& m = obj.mesh;
        h.value(m.positions.size());
        h.bytes(m.positions.data(), m.positions.size() * sizeof(Point3f));
        h.value(m.triangles.size());
        h.bytes(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
        h.value(obj.material != nullptr);
        if (!obj.material)
            continue;
        const MaterialVolume& v = *obj.material;
        h.value(v.spec().origin);
        h.value(v.spec().voxelSize);
        h.value(v.spec().resolution);
        h.value(v.eta());
        const std::vector<uint8_t>& inside = v.insideMask();
        h.bytes(inside.data(), inside.size());
        for (int b = 0; b < v.brickCount(); ++b)
            h.bytes(v.brickData(b),
                    sizeof(float) * MaterialVolume::BRICK_VOXELS * MaterialVolume::COMPONENTS);
    }
    return h.digest();
}

double steadyMedian(std::vector<double> runsMs, int* dropped) {
    LUCENT_CHECK(!runsMs.empty(), "steady time: no timed runs");
    for (const double t : runsMs)
        LUCENT_CHECK(std::isfinite(t) && t >= 0.0, "steady time: a run took ", t, " ms");
    std::sort(runsMs.begin(), runsMs.end());
    const double limit = STEADY_RUN_FACTOR * runsMs.front();
    const size_t n = size_t(std::upper_bound(runsMs.begin(), runsMs.end(), limit) - runsMs.begin());
    if (dropped)
        *dropped = int(runsMs.size() - n);
    return n % 2 ? runsMs[n / 2] : 0.5 * (runsMs[n / 2 - 1] + runsMs[n / 2]);
}

int sppForNoiseFloor(int pilotSpp, double pilotFloor, double targetFloor, int maxSpp) {
    LUCENT_CHECK(pilotSpp > 0 && maxSpp > 0, "reference samples must be > 0, got ", pilotSpp,
                 " and ", maxSpp);
    LUCENT_CHECK(std::isfinite(targetFloor) && targetFloor > 0,
                 "the reference's target noise floor must be a number > 0, got ", targetFloor);
    LUCENT_CHECK(std::isfinite(pilotFloor) && pilotFloor >= 0,
                 "a reference's noise floor must be a finite number >= 0, got ", pilotFloor);
    if (pilotFloor <= targetFloor || maxSpp <= pilotSpp)
        return pilotSpp;
    const double ratio = pilotFloor / targetFloor;
    const double pilots = std::ceil(ratio * ratio);
    const double wanted = pilots * double(pilotSpp);
    return wanted >= double(maxSpp) ? maxSpp : int(wanted);
}

CachedReference referenceFor(const Scene& scene, const std::string& name, const std::string& dir,
                             const ReferenceSettings& options) {
    const int w = scene.camera.width, h = scene.camera.height;
    std::ostringstream stem;
    stem << name << "_ref_" << w << "x" << h << "_" << options.spp << "spp"
         << (options.subsurfaceOnly ? "_sss" : "");
    if (options.seed != ReferenceSettings{}.seed)
        stem << "_seed" << options.seed;
    const fs::path exr = fs::path(dir) / (stem.str() + ".exr");
    const fs::path keyFile = fs::path(dir) / (stem.str() + ".key");
    std::ostringstream key;
    key << "case=" << name << " scene-fnv1a=" << hex(hashScene(scene)) << " width=" << w
        << " height=" << h << " spp=" << options.spp << " seed=" << options.seed
        << " boundary=dielectric estimator=" << reference::REFERENCE_ESTIMATOR_VERSION
        << " subsurface-only=" << options.subsurfaceOnly << "\n";
    CachedReference ref;
    ref.path = exr.string();
    bool loaded = false;
    if (fs::exists(exr) && fs::exists(keyFile)) {
        std::ifstream in(keyFile);
        std::stringstream stored;
        stored << in.rdbuf();
        if (stored.str() == key.str()) {
            ref.mean = readExr(exr.string());
            ref.variance = readExr(exr.string(), "variance");
            ref.coverage = readExr(exr.string(), "coverage");
            ref.spp = options.spp;
            ref.cached = true;
            loaded = true;
        }
    }
    if (!loaded) {
        reference::ReferenceOptions opt;
        opt.spp = options.spp;
        opt.seed = uint64_t(options.seed);
        opt.subsurfaceOnly = options.subsurfaceOnly;
        const reference::ReferenceImage img = reference::renderReference(scene, opt);
        reference::writeReferenceExr(img, exr.string());
        writeFileAtomically(keyFile.string(), key.str());
        ref.mean = img.mean;
        ref.variance = img.variance;
        ref.coverage = img.coverage;
        ref.spp = img.spp;
        ref.seconds = img.seconds;
    }
    ref.mask = bench::maskFromImage(ref.coverage);
    // The floors: the reference against itself with its own variance.
    const bench::ErrorReport self =
        bench::compareImages(ref.mean, ref.mean, &ref.variance, nullptr, &ref.mask);
    const int lum = bench::ErrorReport::LUMINANCE;
    ref.blockRelL1Floor = self.blocks[lum].relL1Floor;
    ref.blockRelRmseFloor = self.blocks[lum].relRmseFloor;
    ref.pixelRelRmseFloor = self.channels[lum].relRmseFloor;
    ref.meanLuminance = self.channels[lum].meanReference;
    return ref;
}

// ---------------------------------------------------------------------------------------------
// Metrics

bool Metrics::meetsGoal() const {
    return blockRelL1() <= GOAL_BLOCK_REL_L1 &&
           std::abs(meanRatio() - 1.0) <= GOAL_MEAN_RATIO_TOLERANCE;
}

Metrics scoreImage(const ImageRgb& test, const CachedReference& reference) {
    Metrics m;
    m.report =
        bench::compareImages(test, reference.mean, &reference.variance, nullptr, &reference.mask);
    return m;
}

std::vector<size_t> paretoFront(const std::vector<double>& cost, const std::vector<double>& error) {
    LUCENT_CHECK(cost.size() == error.size(), "paretoFront: ", cost.size(), " costs but ",
                 error.size(), " errors");
    std::vector<size_t> order(cost.size());
    std::iota(order.begin(), order.end(), size_t(0));
    // Cheapest first, the smaller error first among equal costs, then the index (stable).
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return cost[a] != cost[b] ? cost[a] < cost[b] : error[a] < error[b];
    });
    std::vector<size_t> front;
    double best = INFINITY;
    for (size_t i : order)
        if (error[i] < best) {  // every cheaper-or-equal point has a larger error
            front.push_back(i);
            best = error[i];
        }
    return front;
}

// ---------------------------------------------------------------------------------------------
// Running

namespace {

/// Renders one setting of a variant (lucent/methods/RenderImage.h).
methods::RenderResult renderVariant(const Scene& scene, const Variant& v,
                                    const methods::ParamPreset& s, const RunOptions& options) {
    methods::ParamSet params = v.variant.values;
    params.merge(s.values);
    if (v.method == "reference")
        params.set("seed", options.refSeed + TEST_PT_SEED_OFFSET);
    methods::RenderOptions ro;
    ro.backend = s.backend != methods::Backend::Auto ? s.backend : v.variant.backend;
    ro.subsurfaceOnly = options.subsurfaceOnly;
    ro.log = options.methodLog;
    return methods::renderImage(scene, v.method, params, ro);
}

/// Wall and process CPU times of a render's runs, ms.
struct Timings {
    std::vector<double> wall, cpu;
    void append(const Timings& other) {
        wall.insert(wall.end(), other.wall.begin(), other.wall.end());
        cpu.insert(cpu.end(), other.cpu.begin(), other.cpu.end());
    }
};

/// Warm-up, then `repeats` timed renders. @return the last image; `times` gets each run's.
methods::RenderResult timedRender(const Scene& scene, const Variant& v,
                                  const methods::ParamPreset& s, const RunOptions& options,
                                  Timings& times) {
    StderrSilencer quiet(options.silenceMethods);
    // Warm-up (first-use costs: shader compilation, caches, thread pool).
    methods::RenderResult r = renderVariant(scene, v, s, options);
    for (int i = 0; i < std::max(options.repeats, 1); ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        const double c0 = processCpuMs();
        r = renderVariant(scene, v, s, options);
        times.cpu.push_back(processCpuMs() - c0);
        times.wall.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
    }
    return r;
}

}  // namespace

std::string fileSafe(std::string name) {
    for (char& c : name)
        if (c == ':' || c == '/' || c == ' ' || c == ',')
            c = '-';
    return name;
}

CaseRun evaluateCase(const EvalCase& evalCase, const std::vector<Variant>& variants,
                     const RunOptions& options) {
    const auto say = [&](const std::string& line) {
        if (options.progress)
            options.progress(line);
    };
    CaseRun run;
    run.reference = referenceFor(evalCase.scene, evalCase.name, options.outDir,
                                 {options.refSpp, options.subsurfaceOnly, options.refSeed});
    if (options.refFloor > 0) {
        // A stated-noise reference: the refSpp render is the pilot that says how many samples
        // the case needs (its own render, cached under its own spp, so a later run at another
        // target reuses whichever it has).
        const int spp = sppForNoiseFloor(options.refSpp, run.reference.blockRelL1Floor,
                                         options.refFloor, options.refMaxSpp);
        if (spp != options.refSpp) {
            char buf[256];
            std::snprintf(buf, sizeof buf,
                          "%s: pilot reference %d spp, block rel. L1 noise floor %.4f; %d spp "
                          "for a floor of %.4f",
                          evalCase.name.c_str(), options.refSpp, run.reference.blockRelL1Floor, spp,
                          options.refFloor);
            say(buf);
            run.reference = referenceFor(evalCase.scene, evalCase.name, options.outDir,
                                         {spp, options.subsurfaceOnly, options.refSeed});
        }
    }
    const CachedReference& ref = run.reference;
    if (options.writeImages) {
        ToneMap tm;
        tm.curve = ToneMap::Curve::Aces;
        writePng(ref.mean, ref.path.substr(0, ref.path.size() - 4) + ".png", tm);
    }
    {
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      "%s: reference %d spp%s, block rel. L1 noise floor %.4f (pixel rel. RMSE "
                      "floor %.4f)",
                      evalCase.name.c_str(), ref.spp,
                      ref.cached
                          ? " (cached)"
                          : (", " + std::to_string(int(std::lround(ref.seconds))) + " s").c_str(),
                      ref.blockRelL1Floor, ref.pixelRelRmseFloor);
        say(buf);
    }
    try {
        run.features = planner::analyzeScene(evalCase.scene);
    } catch (const Error& e) {
        say(evalCase.name + ": no scene features (" + e.what() + ")");
    }

    // The Direct render of the same frame: the unit of cost, at least 3 timed runs (a single
    // one on a loaded box can be off by 2x) before the case's methods and as many after them,
    // so that a burst of load during one bracket moves the median, not every cost ratio of the
    // case (2026-12-06: one case's three runs before read 145 ms of CPU where other runs of it
    // read 33-40 ms); a "direct" variant's runs join them below. steadyMedian leaves out runs
    // that compiled shaders (3x the others, at random, on llvmpipe).
    const Variant directUnit = parseVariant("direct");
    RunOptions unitOptions = options;
    unitOptions.repeats = std::max(options.repeats, 3);
    const auto timeDirectUnit = [&](Timings& times) {
        try {
            timedRender(evalCase.scene, directUnit, directUnit.settings.front(), unitOptions,
                        times);
        } catch (const std::exception& e) {
            run.skipped.push_back(evalCase.name + ": direct (cost unit): " + e.what());
        }
    };
    Timings directTimes;
    timeDirectUnit(directTimes);
    const double unitCpuMsBefore = directTimes.cpu.empty() ? 0.0 : steadyMedian(directTimes.cpu);

    for (const Variant& v : variants) {
        const int n = std::min(options.levels, int(v.settings.size()));
        // The previous (coarser) setting's image and its result, for blockRelL1ToFiner.
        ImageRgb coarserImage;
        constexpr size_t NONE = size_t(-1);
        size_t coarserResult = NONE;
        for (int q = 0; q < n; ++q) {
            const methods::ParamPreset& s = v.settings[size_t(q)];
            const std::string label = evalCase.name + ": " + v.name + " (" + s.name + ")";
            Result r;
            r.caseName = evalCase.name;
            r.group = evalCase.group;
            r.variant = v.name;
            r.setting = s.name;
            r.quality = q;
            Timings times;
            methods::RenderResult image;
            try {
                image = timedRender(evalCase.scene, v, s, options, times);
            } catch (const std::exception& e) {
                run.skipped.push_back(label + ": " + e.what());
                say("skipping " + run.skipped.back());
                break;  // the other settings of this variant would fail the same way
            }
            try {
                r.metrics = scoreImage(image.radiance, ref);
            } catch (const ValueError& e) {  // size mismatch, a non-finite pixel
                run.skipped.push_back(label + ": " + e.what());
                say("skipping " + run.skipped.back());
                coarserResult = NONE;
                continue;
            }
            if (coarserResult != NONE)
                run.results[coarserResult].blockRelL1ToFiner =
                    bench::compareImages(coarserImage, image.radiance, nullptr, nullptr, &ref.mask)
                        .blocks[bench::ErrorReport::LUMINANCE]
                        .relL1;
            r.backend = methods::backendName(image.backend);
            r.msMedian = steadyMedian(times.wall);
            r.msMin = *std::min_element(times.wall.begin(), times.wall.end());
            r.cpuMsMedian = steadyMedian(times.cpu);
            r.runs = int(times.wall.size());
            if (v.method == "direct" && v.variant.values.empty() && s.values.empty())
                directTimes.append(times);
            r.noiseFloor = ref.blockRelL1Floor;
            r.features = run.features;
            if (options.writeImages) {
                const std::string file =
                    fileSafe(evalCase.name + "_" + v.name + "_q" + std::to_string(q));
                r.image = (fs::path(options.outDir) / (file + ".exr")).string();
                writeExr(image.radiance, r.image);
                ToneMap tm;
                tm.curve = ToneMap::Curve::Aces;
                writePng(image.radiance, (fs::path(options.outDir) / (file + ".png")).string(), tm);
            }
            char buf[320];
            std::snprintf(buf, sizeof buf,
                          "  %-18s %-22s %9.1f ms  block rel. L1 %.4f, rel. RMSE %.4f, p95 %.3f, "
                          "mean ratio %.3f",
                          v.name.c_str(), s.name.c_str(), r.msMedian, r.metrics.blockRelL1(),
                          r.metrics.blockRelRmse(), r.metrics.p95(), r.metrics.meanRatio());
            say(buf);
            coarserImage = std::move(image.radiance);
            coarserResult = run.results.size();
            run.results.push_back(std::move(r));
        }
    }
    Timings directAfter;
    if (unitCpuMsBefore > 0.0)
        timeDirectUnit(directAfter);
    if (!directAfter.cpu.empty()) {
        const double before = unitCpuMsBefore, after = steadyMedian(directAfter.cpu);
        if (std::max(before, after) > STEADY_RUN_FACTOR * std::min(before, after)) {
            char buf[200];
            std::snprintf(buf, sizeof buf,
                          "  warning: the Direct render took %.1f ms of CPU before the methods "
                          "and %.1f ms after (the box's load changed, or every run of one "
                          "bracket compiled shaders): this case's cost ratios are uncertain",
                          before, after);
            say(buf);
        }
        directTimes.append(directAfter);
    }
    int droppedWall = 0, droppedCpu = 0;
    run.directMs = directTimes.wall.empty() ? 0.0 : steadyMedian(directTimes.wall, &droppedWall);
    run.directCpuMs = directTimes.cpu.empty() ? 0.0 : steadyMedian(directTimes.cpu, &droppedCpu);
    for (Result& r : run.results) {
        r.directMs = run.directMs;
        r.costRatio = run.directMs > 0.0 ? r.msMedian / run.directMs : 0.0;
        r.directCpuMs = run.directCpuMs;
        r.cpuCostRatio = run.directCpuMs > 0.0 ? r.cpuMsMedian / run.directCpuMs : 0.0;
    }
    {
        char buf[240];
        std::snprintf(buf, sizeof buf,
                      "  Direct render (the unit of cost): %.1f ms wall, %.1f ms CPU, median of "
                      "%zu runs",
                      run.directMs, run.directCpuMs, directTimes.wall.size());
        std::string line = buf;
        if (droppedWall > 0 || droppedCpu > 0) {
            std::snprintf(buf, sizeof buf,
                          " less %d (wall) and %d (CPU) slower than %.1fx the fastest, left out",
                          droppedWall, droppedCpu, STEADY_RUN_FACTOR);
            line += buf;
        }
        say(line);
    }
    return run;
}

}  // namespace lucent::evaluation
