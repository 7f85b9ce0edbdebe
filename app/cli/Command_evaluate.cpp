// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli evaluate`: the run-time-vs-error chart of the translucency methods. For
/// each scene, a cached path-traced reference (with variance and coverage); for each method
/// variant and a few quality settings, in-process renders through the same functions as
/// `lucent-cli render` (median wall time of a few runs after a warm-up), relative RMSE of the
/// luminance against the reference over the object-covered pixels (lucent/bench/ErrorMetrics.h)
/// next to the reference's noise floor; writes results.csv, results.json and a log-x chart
/// runtime_vs_error.png drawn here (lines, markers, a 5×7 bitmap font).

#include "CliArgs.h"

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Presets.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/SceneFile.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace lucent::cli {

#ifdef LUCENT_CLI_HAS_PROFILE
/// Defined in Command_profile.cpp: the dipole family (as `lucent-cli render --method dipole`).
ImageRgb renderDipoleMethod(const Scene& scene, const std::string& model, bool subsurfaceOnly,
                            const Args& args);
#endif
/// Defined in Command_render.cpp: dipole + SSLPV (as `lucent-cli render --method combined`).
ImageRgb renderCombinedMethod(const Scene& scene, bool subsurfaceOnly, const Args& args);
#ifdef LUCENT_CLI_HAS_BENCH
/// Defined in Command_bench.cpp: SSLPV (as `lucent-cli render --method sslpv`).
ImageRgb renderSslpvMethod(const Scene& scene, bool subsurfaceOnly, const Args& args);
#endif

namespace {

namespace fs = std::filesystem;

/// The reference's seed; the "reference" method variant uses another one so that its error
/// is the Monte Carlo noise of both estimates, not zero.
constexpr int REFERENCE_SEED = 1;
constexpr int TEST_PT_SEED = 7;

// ---------------------------------------------------------------------------------------------
// Methods, variants and quality settings

/// The options the method functions read (a superset of theirs; see Command_render.cpp).
const std::vector<std::string> METHOD_VALUE_OPTIONS = {"spp",
                                                       "seed",
                                                       "grid",
                                                       "steps",
                                                       "sh",
                                                       "mode",
                                                       "attenuation",
                                                       "spp-frame",
                                                       "threads",
                                                       "boundary",
                                                       "dirpole-normalise"};
const std::vector<std::string> METHOD_FLAG_OPTIONS = {"cpu", "gl"};

/// One quality setting of a variant: a label and the method's command-line options.
struct Setting {
    std::string label;
    std::vector<std::string> argv;
};

/// A method with its variant suffix, e.g. "sslpv:paper".
struct Variant {
    std::string name;  ///< as given: "sslpv:paper"
    std::string method;
    std::string suffix;
    std::vector<std::string> extraArgv;  ///< from the suffix, e.g. --mode paper
    std::vector<Setting> settings;       ///< cheapest first
};

std::vector<Setting> sppSettings(const std::vector<int>& spps) {
    std::vector<Setting> out;
    for (int spp : spps)
        out.push_back({std::to_string(spp) + " spp", {"--spp", std::to_string(spp)}});
    return out;
}

/// Parses "method[:suffix]"; unknown names or suffixes throw ValueError naming the entry.
Variant parseVariant(const std::string& entry) {
    Variant v;
    v.name = entry;
    const size_t colon = entry.find(':');
    v.method = entry.substr(0, colon);
    v.suffix = colon == std::string::npos ? "" : entry.substr(colon + 1);
    auto badSuffix = [&](const char* allowed) {
        LUCENT_THROW(ValueError, "--methods: '", entry, "': unknown variant '", v.suffix, "' of ",
                     v.method, " (allowed: ", allowed, ")");
    };
    if (v.method == "direct") {
        if (!v.suffix.empty())
            badSuffix("none");
        v.settings = {{"-", {}}};
    } else if (v.method == "sslpv") {
        if (v.suffix == "paper" || v.suffix == "calibrated")
            v.extraArgv = {"--mode", v.suffix};
        else if (v.suffix == "gl")
            v.extraArgv = {"--gl"};
        else if (!v.suffix.empty())
            badSuffix("paper, calibrated, gl");
        // One propagation step moves light by one cell, so the step count follows the grid to
        // cover the same distance in mm (docs/methods/sslpv.md).
        for (int n : {16, 32, 64})
            v.settings.push_back({"grid " + std::to_string(n) + ", " + std::to_string(n) + " steps",
                                  {"--grid", std::to_string(n), "--steps", std::to_string(n)}});
    } else if (v.method == "dipole" || v.method == "better-dipole") {
        if (v.suffix == "cpu" || v.suffix == "gl")
            v.extraArgv = {"--" + v.suffix};
        else if (!v.suffix.empty())
            badSuffix("cpu, gl");
        v.settings = sppSettings({8, 32, 128});
    } else if (v.method == "dirpole") {
        // Default: the GPU pipeline with S_d energy-normalised to the better dipole's total
        // (docs/methods/dipole.md §1); raw: the published model as is; cpu: the CPU pipeline.
        if (v.suffix == "raw")
            v.extraArgv = {"--dirpole-normalise", "off"};
        else if (v.suffix == "cpu")
            v.extraArgv = {"--cpu"};
        else if (!v.suffix.empty())
            badSuffix("raw, cpu");
        v.settings = sppSettings({8, 32, 128});
    } else if (v.method == "combined") {
        if (v.suffix == "cpu")
            v.extraArgv = {"--cpu"};
        else if (!v.suffix.empty())
            badSuffix("cpu");
        v.settings = sppSettings({8, 32, 128});
    } else if (v.method == "reference") {
        if (!v.suffix.empty())
            badSuffix("none");
        v.settings = sppSettings({4, 16, 64});
    } else {
        LUCENT_THROW(ValueError, "--methods: unknown method '", v.method, "' in '", entry,
                     "' (known: direct, sslpv[:paper|:calibrated|:gl], dipole[:cpu|:gl], "
                     "better-dipole[:cpu|:gl], dirpole[:raw|:cpu], combined[:cpu], reference)");
    }
    return v;
}

/// Direct lighting through gpu::SceneRenderer on a headless context, as `lucent-cli render
/// --method direct` (Command_render.cpp renderWithGl without a subsurface provider).
ImageRgb renderDirectGl(const Scene& scene, bool subsurfaceOnly) {
    auto ctx = gpu::GlContext::createHeadless();
    gpu::SceneRenderer renderer;
    ImageRgb image;
    try {
        renderer.create();
        for (const SceneObject& object : scene.objects)
            renderer.addMesh(object.mesh);
        renderer.setLights(scene.lights);
        renderer.setCamera(scene.camera);
        gpu::DirectSettings settings;
        settings.subsurfaceOnly = subsurfaceOnly;
        renderer.setSettings(settings);
        renderer.render();
        image = renderer.readRadiance();
    } catch (...) {
        renderer.destroy();
        throw;
    }
    renderer.destroy();
    return image;
}

/// Renders one setting of a variant. @throw whatever the method throws (ValueError for an
/// option the binary does not support, GpuError without GL, ...).
ImageRgb renderVariant(const Scene& scene, const Variant& v, const Setting& s,
                       bool subsurfaceOnly) {
    std::vector<std::string> argv = v.extraArgv;
    argv.insert(argv.end(), s.argv.begin(), s.argv.end());
    const Args args(argv, METHOD_VALUE_OPTIONS, METHOD_FLAG_OPTIONS);
    if (v.method == "direct")
        return renderDirectGl(scene, subsurfaceOnly);
    if (v.method == "reference") {
        ReferenceOptions opt;
        opt.spp = args.intOr("spp", 16, 3, 1 << 24);
        opt.seed = TEST_PT_SEED;
        opt.subsurfaceOnly = subsurfaceOnly;
        return renderReference(scene, opt).mean;
    }
#ifdef LUCENT_CLI_HAS_BENCH
    if (v.method == "sslpv")
        return renderSslpvMethod(scene, subsurfaceOnly, args);
#endif
#ifdef LUCENT_CLI_HAS_PROFILE
    if (v.method == "dipole" || v.method == "better-dipole" || v.method == "dirpole")
        return renderDipoleMethod(scene, v.method, subsurfaceOnly, args);
#endif
    if (v.method == "combined")
        return renderCombinedMethod(scene, subsurfaceOnly, args);
    LUCENT_THROW(ValueError, "method ", v.method, " is not built into this lucent-cli");
}

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

// ---------------------------------------------------------------------------------------------
// Reference (cached)

/// FNV-1a 64 of a file's bytes: the cache key of a scene's content.
uint64_t hashFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in)
        LUCENT_THROW(IoError, path, ": cannot read");
    uint64_t h = 1469598103934665603ull;
    char c;
    while (in.get(c)) {
        h ^= uint64_t(uint8_t(c));
        h *= 1099511628211ull;
    }
    return h;
}

struct Reference {
    ImageRgb mean, variance, coverage;
    int spp = 0;
    double seconds = 0.0;  ///< render time (0 when loaded from the cache)
    bool cached = false;
    std::string path;
};

/// @param overrides the --presets/--etas overrides applied to the scene ("" for none): part of
/// the cache key, since the scene file alone no longer determines the image.
Reference referenceFor(const Scene& scene, const std::string& scenePath, const std::string& stem,
                       const std::string& overrides, const fs::path& dir, int spp,
                       bool subsurfaceOnly) {
    const int w = scene.camera.width, h = scene.camera.height;
    std::ostringstream name;
    name << stem << "_ref_" << w << "x" << h << "_" << spp << "spp"
         << (subsurfaceOnly ? "_sss" : "");
    const fs::path exr = dir / (name.str() + ".exr");
    const fs::path keyFile = dir / (name.str() + ".key");
    std::ostringstream key;
    key << "scene-fnv1a=" << std::hex << hashFile(scenePath) << std::dec << " width=" << w
        << " height=" << h << " spp=" << spp << " seed=" << REFERENCE_SEED
        << " boundary=dielectric estimator=" << REFERENCE_ESTIMATOR_VERSION
        << " subsurface-only=" << subsurfaceOnly << (overrides.empty() ? "" : " " + overrides)
        << "\n";
    Reference ref;
    ref.path = exr.string();
    if (fs::exists(exr) && fs::exists(keyFile)) {
        std::ifstream in(keyFile);
        std::stringstream stored;
        stored << in.rdbuf();
        if (stored.str() == key.str()) {
            ref.mean = readExr(exr.string());
            ref.variance = readExr(exr.string(), "variance");
            ref.coverage = readExr(exr.string(), "coverage");
            ref.spp = spp;
            ref.cached = true;
            return ref;
        }
    }
    ReferenceOptions opt;
    opt.spp = spp;
    opt.seed = REFERENCE_SEED;
    opt.subsurfaceOnly = subsurfaceOnly;
    const ReferenceImage img = renderReference(scene, opt);
    writeReferenceExr(img, exr.string());
    writeFileAtomically(keyFile.string(), key.str());
    ref.mean = img.mean;
    ref.variance = img.variance;
    ref.coverage = img.coverage;
    ref.spp = img.spp;
    ref.seconds = img.seconds;
    return ref;
}

// ---------------------------------------------------------------------------------------------
// Scene overrides (--presets, --etas): every scene × preset × η is evaluated as its own case

/// Replaces every object's material by the uniform preset, on the grid the scene file gave
/// (GridSpec::around the mesh at the object's resolution, as SceneFile builds a preset material).
void applyPreset(Scene& scene, const MaterialPreset& preset) {
    for (SceneObject& obj : scene.objects) {
        const int res = obj.material ? obj.material->resolution() : obj.materialSource.resolution;
        obj.material = std::make_shared<MaterialVolume>(GridSpec::around(obj.mesh.bounds(), res),
                                                        preset.sample());
        obj.materialSource.vdbFile.clear();
        obj.materialSource.uniform = false;
        obj.materialSource.preset = preset.name;
        obj.materialSource.value = preset.sample();
        obj.materialSource.resolution = res;
    }
}

/// "--etas 1.3,1": each a finite relative index in [1, 3] (the range the methods accept).
std::vector<float> parseEtas(const std::vector<std::string>& items) {
    std::vector<float> out;
    for (const std::string& item : items) {
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (end == item.c_str() || *end != '\0' || !std::isfinite(v) || v < 1.0 || v > 3.0)
            LUCENT_THROW(ValueError, "--etas: '", item,
                         "' is not a relative index of refraction in [1, 3]");
        out.push_back(float(v));
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// Results

struct Result {
    std::string scene;
    std::string variant;
    std::string setting;
    int quality = 0;  ///< index of the setting, cheapest first
    double msMedian = 0.0;
    double msMin = 0.0;
    int runs = 0;
    ChannelError lum;  ///< luminance errors and the reference noise floor
    /// Σ lum(test) / Σ lum(reference) over the compared pixels: the overall brightness bias
    /// (1 = unbiased on average), to tell a scale error from a shape error.
    double meanRatio = 0.0;
    size_t pixels = 0;
};

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string jsonEscape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '"' || c == '\\')
            out += '\\';
        if (uint8_t(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", unsigned(c));
            out += buf;
            continue;
        }
        out += c;
    }
    return out;
}

/// CSV field: quoted when it holds a comma or a quote.
std::string csvField(const std::string& s) {
    if (s.find_first_of(",\"") == std::string::npos)
        return s;
    std::string out = "\"";
    for (char c : s)
        out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

std::string fmt(double v, const char* f = "%.6g") {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

std::string toCsv(const std::vector<Result>& results) {
    std::string s =
        "scene,method,setting,quality,ms_median,ms_min,runs,rel_rmse,rel_rmse_floor,"
        "rmse,mean_rel_error,mean_reference,mean_ratio,pixels\n";
    for (const Result& r : results)
        s += csvField(r.scene) + "," + csvField(r.variant) + "," + csvField(r.setting) + "," +
             std::to_string(r.quality) + "," + fmt(r.msMedian) + "," + fmt(r.msMin) + "," +
             std::to_string(r.runs) + "," + fmt(r.lum.relRmse) + "," + fmt(r.lum.relRmseFloor) +
             "," + fmt(r.lum.rmse) + "," + fmt(r.lum.meanRelError) + "," +
             fmt(r.lum.meanReference) + "," + fmt(r.meanRatio) + "," + std::to_string(r.pixels) +
             "\n";
    return s;
}

struct RunInfo {
    std::vector<std::string> scenes;
    int width = 0, height = 0, refSpp = 0, repeats = 0;
    bool subsurfaceOnly = false;
    std::vector<std::string> skipped;
};

std::string toJson(const std::vector<Result>& results, const RunInfo& info) {
    std::ostringstream s;
    s << "{\n  \"width\": " << info.width << ",\n  \"height\": " << info.height
      << ",\n  \"ref_spp\": " << info.refSpp << ",\n  \"repeats\": " << info.repeats
      << ",\n  \"subsurface_only\": " << (info.subsurfaceOnly ? "true" : "false")
      << ",\n  \"metric\": \"relative RMSE of luminance over object-covered pixels\",\n"
      << "  \"scenes\": [";
    for (size_t i = 0; i < info.scenes.size(); ++i)
        s << (i ? ", " : "") << "\"" << jsonEscape(info.scenes[i]) << "\"";
    s << "],\n  \"skipped\": [";
    for (size_t i = 0; i < info.skipped.size(); ++i)
        s << (i ? ", " : "") << "\"" << jsonEscape(info.skipped[i]) << "\"";
    s << "],\n  \"results\": [\n";
    for (size_t i = 0; i < results.size(); ++i) {
        const Result& r = results[i];
        s << "    {\"scene\": \"" << jsonEscape(r.scene) << "\", \"method\": \""
          << jsonEscape(r.variant) << "\", \"setting\": \"" << jsonEscape(r.setting)
          << "\", \"quality\": " << r.quality << ", \"ms_median\": " << fmt(r.msMedian)
          << ", \"ms_min\": " << fmt(r.msMin) << ", \"runs\": " << r.runs
          << ", \"rel_rmse\": " << fmt(r.lum.relRmse)
          << ", \"rel_rmse_floor\": " << fmt(r.lum.relRmseFloor)
          << ", \"rmse\": " << fmt(r.lum.rmse)
          << ", \"mean_rel_error\": " << fmt(r.lum.meanRelError)
          << ", \"mean_reference\": " << fmt(r.lum.meanReference)
          << ", \"mean_ratio\": " << fmt(r.meanRatio) << ", \"pixels\": " << r.pixels << "}"
          << (i + 1 < results.size() ? "," : "") << "\n";
    }
    s << "  ]\n}\n";
    return s.str();
}

void writeText(const fs::path& path, const std::string& text) {
    writeFileAtomically(path.string(), text);
}

// ---------------------------------------------------------------------------------------------
// Chart: drawn into an ImageRgb (values are linear; colours are given in sRGB and converted so
// that writePng's sRGB encoding with the clamp curve returns them unchanged).

/// 5×7 glyphs, one byte per row, bit 4 = leftmost pixel. Lowercase letters draw as capitals.
struct Glyph {
    char c;
    std::array<uint8_t, 7> rows;
};
constexpr Glyph FONT[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
};
constexpr int GLYPH_ADVANCE = 6;  ///< 5 columns + 1 of spacing, in font pixels

class Canvas {
public:
    Canvas(int w, int h) : m_image(w, h, Rgb(1.f)) {}

    /// sRGB [0,1] → linear (IEC 61966-2-1), so that writePng reproduces the colour.
    static Rgb srgb(float r, float g, float b) {
        auto lin = [](float c) {
            return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
        };
        return {lin(r), lin(g), lin(b)};
    }

    void pixel(int x, int y, const Rgb& c) {
        if (x >= 0 && y >= 0 && x < m_image.width() && y < m_image.height())
            m_image.at(x, y) = c;
    }
    void rect(int x0, int y0, int x1, int y1, const Rgb& c) {
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x)
                pixel(x, y, c);
    }
    /// Line of `thickness` px; with dash > 0, `dash` px on, `dash` px off.
    void line(double x0, double y0, double x1, double y1, const Rgb& c, int thickness = 1,
              int dash = 0) {
        const double len = std::hypot(x1 - x0, y1 - y0);
        const int n = std::max(1, int(std::ceil(len * 2.0)));
        const int lo = -(thickness - 1) / 2, hi = thickness / 2;
        for (int i = 0; i <= n; ++i) {
            const double t = double(i) / n;
            if (dash > 0 && int(t * len / dash) % 2 == 1)
                continue;
            const int x = int(std::lround(x0 + (x1 - x0) * t));
            const int y = int(std::lround(y0 + (y1 - y0) * t));
            rect(x + lo, y + lo, x + hi, y + hi, c);
        }
    }
    /// Marker of the given shape (0 circle, 1 square, 2 triangle, 3 diamond) and radius.
    void marker(double cx, double cy, int shape, int r, const Rgb& fill, const Rgb& edge) {
        for (int pass = 0; pass < 2; ++pass) {
            const int rr = pass == 0 ? r + 1 : r;  // edge first, then the fill one pixel inside
            const Rgb& c = pass == 0 ? edge : fill;
            for (int dy = -rr; dy <= rr; ++dy)
                for (int dx = -rr; dx <= rr; ++dx) {
                    bool in = false;
                    switch (shape % 4) {
                        case 0:
                            in = dx * dx + dy * dy <= rr * rr;
                            break;
                        case 1:
                            in = true;
                            break;
                        case 2:
                            in = dy >= -rr && 2 * std::abs(dx) <= dy + rr;
                            break;
                        default:
                            in = std::abs(dx) + std::abs(dy) <= rr;
                            break;
                    }
                    if (in)
                        pixel(int(std::lround(cx)) + dx, int(std::lround(cy)) + dy, c);
                }
        }
    }
    /// Text with its top-left corner at (x, y), `scale` px per font pixel.
    void text(int x, int y, const std::string& s, const Rgb& c, int scale = 2) {
        for (size_t i = 0; i < s.size(); ++i) {
            char ch = s[i];
            if (ch >= 'a' && ch <= 'z')
                ch = char(ch - 'a' + 'A');
            for (const Glyph& g : FONT) {
                if (g.c != ch)
                    continue;
                for (int row = 0; row < 7; ++row)
                    for (int col = 0; col < 5; ++col)
                        if (g.rows[size_t(row)] & (0x10 >> col))
                            rect(x + (int(i) * GLYPH_ADVANCE + col) * scale, y + row * scale,
                                 x + (int(i) * GLYPH_ADVANCE + col) * scale + scale - 1,
                                 y + row * scale + scale - 1, c);
                break;
            }
        }
    }
    static int textWidth(const std::string& s, int scale = 2) {
        return int(s.size()) * GLYPH_ADVANCE * scale - scale;
    }
    const ImageRgb& image() const { return m_image; }

private:
    ImageRgb m_image;
};

/// A chart axis mapping data values to pixels, linear or logarithmic (base 10).
struct Axis {
    double lo = 0.0, hi = 1.0;
    bool log = false;
    double p0 = 0.0, p1 = 1.0;  ///< pixel positions of lo and hi

    [[nodiscard]] double map(double v) const {
        const double t = log ? (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo))
                             : (v - lo) / (hi - lo);
        return p0 + t * (p1 - p0);
    }
    /// Major ticks: decades (log) or 1/2/5 × 10^k steps (linear).
    [[nodiscard]] std::vector<double> ticks() const {
        std::vector<double> out;
        if (log) {
            for (double d = std::pow(10.0, std::floor(std::log10(lo))); d <= hi * 1.0001; d *= 10)
                if (d >= lo * 0.9999)
                    out.push_back(d);
            return out;
        }
        const double raw = (hi - lo) / 6.0;
        const double mag = std::pow(10.0, std::floor(std::log10(raw)));
        const double step = raw / mag < 1.5 ? mag : raw / mag < 3.5 ? 2 * mag : 5 * mag;
        for (double v = std::ceil(lo / step) * step; v <= hi * 1.0001; v += step)
            out.push_back(std::abs(v) < 1e-12 ? 0.0 : v);
        return out;
    }
    /// Minor ticks of a log axis: 2..9 × 10^k.
    [[nodiscard]] std::vector<double> minorTicks() const {
        std::vector<double> out;
        if (!log)
            return out;
        for (double d = std::pow(10.0, std::floor(std::log10(lo))); d <= hi; d *= 10)
            for (int k = 2; k <= 9; ++k)
                if (d * k >= lo && d * k <= hi)
                    out.push_back(d * k);
        return out;
    }
};

std::string tickLabel(double v) {
    if (v == 0.0)
        return "0";
    const double a = std::abs(v);
    if (a >= 1e5 || a < 1e-3)
        return fmt(v, "%.0e");
    return fmt(v, "%g");
}

/// Method colours (sRGB, the Tableau 10 palette), in the order the methods were given.
Rgb methodColour(size_t i) {
    static constexpr float PALETTE[][3] = {{0.122f, 0.467f, 0.706f}, {1.000f, 0.498f, 0.055f},
                                           {0.173f, 0.627f, 0.173f}, {0.839f, 0.153f, 0.157f},
                                           {0.580f, 0.404f, 0.741f}, {0.549f, 0.337f, 0.294f},
                                           {0.890f, 0.467f, 0.761f}, {0.498f, 0.498f, 0.498f},
                                           {0.737f, 0.741f, 0.133f}, {0.090f, 0.745f, 0.812f}};
    const float* c = PALETTE[i % 10];
    return Canvas::srgb(c[0], c[1], c[2]);
}

void drawChart(const std::vector<Result>& results, const std::vector<std::string>& variants,
               const std::vector<std::string>& scenes, const RunInfo& info, const fs::path& out) {
    constexpr int W = 1100, H = 680, LEFT = 100, RIGHT = 300, TOP = 60, BOTTOM = 80;
    Canvas cv(W, H);
    const Rgb black(0.f), grid = Canvas::srgb(0.88f, 0.88f, 0.88f),
                          axisGrey = Canvas::srgb(0.35f, 0.35f, 0.35f), white(1.f);

    double xMin = INFINITY, xMax = 0.0, yMin = INFINITY, yMax = 0.0, floorMax = 0.0;
    for (const Result& r : results) {
        xMin = std::min(xMin, std::max(r.msMedian, 1e-3));
        xMax = std::max(xMax, std::max(r.msMedian, 1e-3));
        yMin = std::min(yMin, r.lum.relRmse);
        yMax = std::max(yMax, r.lum.relRmse);
        floorMax = std::max(floorMax, r.lum.relRmseFloor);
    }
    if (results.empty()) {
        xMin = 1.0, xMax = 10.0, yMin = 0.0, yMax = 1.0;
    }
    Axis x;
    x.log = true;
    x.lo = std::pow(10.0, std::floor(std::log10(xMin)));
    x.hi = std::pow(10.0, std::ceil(std::log10(xMax)));
    if (x.hi <= x.lo)
        x.hi = x.lo * 10.0;
    x.p0 = LEFT;
    x.p1 = W - RIGHT;
    Axis y;
    // Log y when the errors span more than a factor 20 (e.g. an unfitted method far off while
    // the others are near the noise floor); linear from 0 otherwise.
    const double yLowest = std::min(yMin, floorMax > 0.0 ? floorMax : yMin);
    y.log = yLowest > 0.0 && yMax / yLowest > 20.0;
    if (y.log) {
        // Bounds on the 1-2-5 sequence around the data.
        const double dLo = std::pow(10.0, std::floor(std::log10(yLowest)));
        y.lo = yLowest >= 5 * dLo ? 5 * dLo : yLowest >= 2 * dLo ? 2 * dLo : dLo;
        const double dHi = std::pow(10.0, std::floor(std::log10(yMax)));
        y.hi = yMax <= dHi ? dHi : yMax <= 2 * dHi ? 2 * dHi : yMax <= 5 * dHi ? 5 * dHi : 10 * dHi;
    } else {
        y.lo = 0.0;
        y.hi = std::max(yMax, floorMax) * 1.1;
        if (y.hi <= 0.0)
            y.hi = 1.0;
    }
    y.p0 = H - BOTTOM;
    y.p1 = TOP;

    // Grid, ticks and tick labels.
    for (double t : x.minorTicks())
        cv.line(x.map(t), y.p1, x.map(t), y.p0, grid);
    for (double t : y.minorTicks())
        cv.line(x.p0, y.map(t), x.p1, y.map(t), grid);
    for (double t : x.ticks()) {
        const double px = x.map(t);
        cv.line(px, y.p1, px, y.p0, Canvas::srgb(0.75f, 0.75f, 0.75f));
        cv.line(px, y.p0, px, y.p0 + 6, black);
        const std::string l = tickLabel(t);
        cv.text(int(px) - Canvas::textWidth(l) / 2, int(y.p0) + 12, l, black);
    }
    for (double t : y.ticks()) {
        const double py = y.map(t);
        cv.line(x.p0, py, x.p1, py, Canvas::srgb(0.75f, 0.75f, 0.75f));
        cv.line(x.p0 - 6, py, x.p0, py, black);
        const std::string l = tickLabel(t);
        cv.text(int(x.p0) - 10 - Canvas::textWidth(l), int(py) - 7, l, black);
    }
    cv.line(x.p0, y.p0, x.p1, y.p0, black, 2);
    cv.line(x.p0, y.p0, x.p0, y.p1, black, 2);
    const std::string xLabel = "render time (ms, log scale)";
    cv.text(int((x.p0 + x.p1) / 2) - Canvas::textWidth(xLabel) / 2, H - 36, xLabel, black);
    const std::string yLabel =
        std::string("relative RMSE of luminance") + (y.log ? " (log scale)" : "");
    cv.text(LEFT - 80, TOP - 26, yLabel, black);
    std::ostringstream title;
    title << "run time vs error: " << info.width << "x" << info.height << ", reference "
          << info.refSpp << " spp" << (info.subsurfaceOnly ? ", subsurface only" : "");
    cv.text(LEFT, 12, title.str(), black);

    // Reference noise floor (the largest over the scenes): errors below it are not resolved.
    if (floorMax > 0.0 && floorMax >= y.lo && floorMax <= y.hi) {
        cv.line(x.p0, y.map(floorMax), x.p1, y.map(floorMax), axisGrey, 1, 6);
        const std::string l = "reference noise floor (largest of the scenes)";
        cv.text(int(x.p1) - Canvas::textWidth(l, 1) - 4, int(y.map(floorMax)) - 10, l, axisGrey, 1);
    }

    // Series: per scene and method, points in quality order joined by lines.
    auto clampY = [&](double v) { return std::clamp(v, y.lo > 0 ? y.lo : v, y.hi); };
    for (size_t si = 0; si < scenes.size(); ++si)
        for (size_t vi = 0; vi < variants.size(); ++vi) {
            std::vector<const Result*> pts;
            for (const Result& r : results)
                if (r.scene == scenes[si] && r.variant == variants[vi])
                    pts.push_back(&r);
            std::sort(pts.begin(), pts.end(),
                      [](const Result* a, const Result* b) { return a->quality < b->quality; });
            const Rgb c = methodColour(vi);
            for (size_t i = 1; i < pts.size(); ++i)
                cv.line(x.map(std::max(pts[i - 1]->msMedian, 1e-3)),
                        y.map(clampY(pts[i - 1]->lum.relRmse)),
                        x.map(std::max(pts[i]->msMedian, 1e-3)), y.map(clampY(pts[i]->lum.relRmse)),
                        c, 2);
            for (const Result* r : pts)
                cv.marker(x.map(std::max(r->msMedian, 1e-3)), y.map(clampY(r->lum.relRmse)),
                          int(si), 5, c, black);
        }

    // Legend: colours = methods, marker shapes = scenes.
    int ly = TOP;
    const int lx = W - RIGHT + 30;
    cv.text(lx, ly, "method", black);
    ly += 26;
    for (size_t vi = 0; vi < variants.size(); ++vi) {
        cv.line(lx, ly + 7, lx + 30, ly + 7, methodColour(vi), 3);
        cv.marker(lx + 15, ly + 7, 0, 4, methodColour(vi), black);
        cv.text(lx + 40, ly, variants[vi], black);
        ly += 24;
    }
    ly += 14;
    cv.text(lx, ly, "scene", black);
    ly += 26;
    for (size_t si = 0; si < scenes.size(); ++si) {
        cv.marker(lx + 15, ly + 7, int(si), 5, white, black);
        cv.text(lx + 40, ly, scenes[si], black);
        ly += 24;
    }
    ly += 14;
    cv.text(lx, ly, "lines: quality order", axisGrey, 1);
    cv.text(lx, ly + 12, "(grid / spp increasing)", axisGrey, 1);

    ToneMap tm;
    tm.curve = ToneMap::Curve::Clamp;
    writePng(cv.image(), out.string(), tm);
}

// ---------------------------------------------------------------------------------------------

/// Tone mapping of the PNG previews written next to each EXR (as `lucent-cli render`).
ToneMap previewToneMap() {
    ToneMap tm;
    tm.curve = ToneMap::Curve::Aces;
    return tm;
}

std::vector<std::string> splitComma(const std::string& s) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : s + ",") {
        if (c == ',') {
            if (!cur.empty())
                out.push_back(cur);
            cur.clear();
        } else if (c != ' ') {
            cur += c;
        }
    }
    return out;
}

int runEvaluate(const std::vector<std::string>& argv) {
    const Args args(
        argv,
        {"methods", "ref-spp", "width", "height", "out", "repeats", "levels", "presets", "etas"},
        {"subsurface-only", "json", "verbose"});
    if (args.positional().empty())
        LUCENT_THROW(ValueError, "expected at least one SCENE.json (see --help)");
    const auto outDir = args.value("out");
    if (!outDir || outDir->empty())
        LUCENT_THROW(ValueError, "missing --out DIR");
    std::vector<Variant> variants;
    for (const std::string& name :
         splitComma(args.valueOr("methods",
                                 "direct,sslpv:paper,sslpv:calibrated,dipole,"
                                 "better-dipole,dirpole,combined")))
        variants.push_back(parseVariant(name));
    if (variants.empty())
        LUCENT_THROW(ValueError, "--methods: no method given");
    RunInfo info;
    info.refSpp = args.intOr("ref-spp", 256, 3, 1 << 20);
    info.repeats = args.intOr("repeats", 3, 1, 1000);
    const int levels = args.intOr("levels", 3, 1, 16);
    info.subsurfaceOnly = args.has("subsurface-only");
    const bool json = args.has("json");
    const bool verbose = args.has("verbose");
    FILE* log = json ? stderr : stdout;  // progress; with --json stdout holds the JSON only

    const fs::path dir(*outDir);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
        LUCENT_THROW(IoError, "--out ", dir.string(), ": cannot create the directory (",
                     ec.message(), ")");

    // Load every scene first: a bad file fails before any long render.
    std::vector<Scene> scenes;
    std::vector<std::string> stems;
    for (const std::string& path : args.positional()) {
        Scene scene = loadScene(path);
        scene.camera.width = args.intOr("width", scene.camera.width, 1, 16384);
        scene.camera.height = args.intOr("height", scene.camera.height, 1, 16384);
        std::string stem = fs::path(path).stem().string();
        if (std::find(stems.begin(), stems.end(), stem) != stems.end())
            LUCENT_THROW(ValueError, path, ": another scene has the same name '", stem,
                         "' (the outputs in --out are named after it)");
        scenes.push_back(std::move(scene));
        stems.push_back(stem);
    }
    info.width = scenes.front().camera.width;
    info.height = scenes.front().camera.height;

    // Cases: every scene × --presets × --etas (an empty list keeps the scene's own value),
    // named "<stem>[-<preset>][-eta<η>]"; the overridden scenes are built one at a time.
    std::vector<const MaterialPreset*> presets;
    for (const std::string& name : splitComma(args.valueOr("presets", "")))
        presets.push_back(&findPreset(name));  // ValueError listing the valid names
    const std::vector<float> etas = parseEtas(splitComma(args.valueOr("etas", "")));
    if (args.value("presets") && presets.empty())
        LUCENT_THROW(ValueError, "--presets: no preset given");
    if (args.value("etas") && etas.empty())
        LUCENT_THROW(ValueError, "--etas: no value given");
    struct Case {
        size_t file = 0;
        const MaterialPreset* preset = nullptr;
        float eta = 0.f;  ///< 0: the scene's own
        std::string name, overrides;
    };
    std::vector<Case> cases;
    for (size_t fi = 0; fi < scenes.size(); ++fi)
        for (size_t pi = 0; pi < std::max<size_t>(presets.size(), 1); ++pi)
            for (size_t ei = 0; ei < std::max<size_t>(etas.size(), 1); ++ei) {
                Case c;
                c.file = fi;
                c.name = stems[fi];
                if (!presets.empty()) {
                    c.preset = presets[pi];
                    c.name.append("-").append(c.preset->name);
                    c.overrides.append("preset=").append(c.preset->name);
                }
                if (!etas.empty()) {
                    c.eta = etas[ei];
                    c.name.append("-eta").append(fmt(c.eta, "%g"));
                    c.overrides.append(c.overrides.empty() ? "eta=" : " eta=")
                        .append(fmt(c.eta, "%.9g"));
                }
                info.scenes.push_back(c.name);
                cases.push_back(std::move(c));
            }

    std::vector<Result> results;
    for (const Case& c : cases) {
        Scene scene = scenes[c.file];  // shares the file's material unless a preset replaces it
        if (c.preset)
            applyPreset(scene, *c.preset);
        if (c.eta > 0.f)
            scene.eta = c.eta;
        const Reference ref = referenceFor(scene, args.positional()[c.file], c.name, c.overrides,
                                           dir, info.refSpp, info.subsurfaceOnly);
        const std::vector<uint8_t> mask = maskFromImage(ref.coverage);
        writePng(ref.mean, ref.path.substr(0, ref.path.size() - 4) + ".png", previewToneMap());
        std::fprintf(log, "%s: reference %s (%d spp%s)\n", c.name.c_str(), ref.path.c_str(),
                     ref.spp,
                     ref.cached ? ", cached" : (", " + fmt(ref.seconds, "%.1f") + " s").c_str());
        std::fflush(log);
        for (const Variant& v : variants) {
            const int n = std::min(levels, int(v.settings.size()));
            for (int q = 0; q < n; ++q) {
                const Setting& s = v.settings[size_t(q)];
                Result r;
                r.scene = c.name;
                r.variant = v.name;
                r.setting = s.label;
                r.quality = q;
                ImageRgb image;
                std::vector<double> ms;
                try {
                    StderrSilencer quiet(!verbose);
                    // Warm-up (first-use costs: shader compilation, caches, thread pool).
                    image = renderVariant(scene, v, s, info.subsurfaceOnly);
                    for (int i = 0; i < info.repeats; ++i) {
                        const auto t0 = std::chrono::steady_clock::now();
                        image = renderVariant(scene, v, s, info.subsurfaceOnly);
                        ms.push_back(std::chrono::duration<double, std::milli>(
                                         std::chrono::steady_clock::now() - t0)
                                         .count());
                    }
                } catch (const std::exception& e) {
                    const std::string why =
                        c.name + ": " + v.name + " (" + s.label + "): " + e.what();
                    std::fprintf(stderr, "evaluate: skipping %s\n", why.c_str());
                    info.skipped.push_back(why);
                    break;  // the other settings of this variant would fail the same way
                }
                if (image.width() != ref.mean.width() || image.height() != ref.mean.height()) {
                    const std::string why = c.name + ": " + v.name + " (" + s.label +
                                            "): image size differs from the reference";
                    std::fprintf(stderr, "evaluate: skipping %s\n", why.c_str());
                    info.skipped.push_back(why);
                    break;
                }
                ErrorReport rep;
                try {
                    rep = compareImages(image, ref.mean, &ref.variance, nullptr, &mask);
                } catch (const ValueError& e) {  // e.g. a non-finite pixel in the method's image
                    const std::string why =
                        c.name + ": " + v.name + " (" + s.label + "): " + e.what();
                    std::fprintf(stderr, "evaluate: skipping %s\n", why.c_str());
                    info.skipped.push_back(why);
                    continue;
                }
                r.lum = rep.channels[ErrorReport::LUMINANCE];
                r.pixels = rep.pixelCount;
                double sumTest = 0.0, sumRef = 0.0;
                for (size_t i = 0; i < mask.size(); ++i)
                    if (mask[i]) {
                        sumTest += luminance(image.pixels()[i]);
                        sumRef += luminance(ref.mean.pixels()[i]);
                    }
                r.meanRatio = sumRef > 0.0 ? sumTest / sumRef : 0.0;
                r.msMedian = median(ms);
                r.msMin = *std::min_element(ms.begin(), ms.end());
                r.runs = int(ms.size());
                std::string file = c.name + "_" + v.name + "_q" + std::to_string(q) + ".exr";
                std::replace(file.begin(), file.end(), ':', '-');
                writeExr(image, (dir / file).string());
                writePng(image, (dir / (file.substr(0, file.size() - 4) + ".png")).string(),
                         previewToneMap());
                std::fprintf(
                    log, "  %-18s %-22s %10.1f ms   rel. RMSE %.4f (floor %.4f), mean ratio %.3f\n",
                    v.name.c_str(), s.label.c_str(), r.msMedian, r.lum.relRmse, r.lum.relRmseFloor,
                    r.meanRatio);
                std::fflush(log);
                results.push_back(r);
            }
        }
    }

    writeText(dir / "results.csv", toCsv(results));
    const std::string jsonText = toJson(results, info);
    writeText(dir / "results.json", jsonText);
    std::vector<std::string> names;
    for (const Variant& v : variants)
        names.push_back(v.name);
    drawChart(results, names, info.scenes, info, dir / "runtime_vs_error.png");
    if (info.scenes.size() > 1)  // one chart per scene as well (the combined one gets busy)
        for (const std::string& stem : info.scenes) {
            std::vector<Result> mine;
            for (const Result& r : results)
                if (r.scene == stem)
                    mine.push_back(r);
            drawChart(mine, names, {stem}, info, dir / ("runtime_vs_error_" + stem + ".png"));
        }
    if (json)
        std::fputs(jsonText.c_str(), stdout);
    else
        std::printf("wrote %s, %s, %s (%zu results, %zu skipped)\n",
                    (dir / "results.csv").string().c_str(), (dir / "results.json").string().c_str(),
                    (dir / "runtime_vs_error.png").string().c_str(), results.size(),
                    info.skipped.size());
    return 0;
}

}  // namespace

extern const Command evaluateCommand;
const Command evaluateCommand{
    "evaluate", "run time vs error of the methods against the path-traced reference (chart)",
    "usage: lucent-cli evaluate SCENE.json [SCENE2.json ...] --out DIR\n"
    "                           [--methods M1,M2,...] [--ref-spp N] [--width W] [--height H]\n"
    "                           [--repeats R] [--levels L] [--presets P1,P2,...]\n"
    "                           [--etas E1,E2,...] [--subsurface-only] [--json] [--verbose]\n"
    "\n"
    "For each scene: the path-traced reference with variance and coverage (seed 1, dielectric\n"
    "boundary), cached in DIR and reused when the scene file and the parameters match; then\n"
    "each method at a few quality settings, rendered in-process with the functions of\n"
    "`lucent-cli render`. Time: median wall time of R runs after one warm-up, of the whole\n"
    "method call (GL context creation included for the GL methods; scene loading and file\n"
    "writing excluded). Error: relative RMSE of the luminance against the reference over the\n"
    "object-covered pixels, next to the reference's noise floor (docs/reference.md).\n"
    "Writes DIR/results.csv, DIR/results.json, DIR/runtime_vs_error.png (all scenes; with\n"
    "several scenes also DIR/runtime_vs_error_<scene>.png) and, per render, an EXR\n"
    "and a PNG preview (ACES tone map).\n"
    "\n"
    "  --methods LIST    comma-separated (default direct,sslpv:paper,sslpv:calibrated,dipole,\n"
    "                    better-dipole,dirpole,combined). Methods and their quality settings:\n"
    "                      direct                  one setting\n"
    "                      sslpv[:paper|:calibrated|:gl]   grid 16/32/64, steps = grid\n"
    "                      dipole, better-dipole [:cpu|:gl]   8/32/128 spp\n"
    "                      dirpole[:raw|:cpu]      8/32/128 spp (GPU pipeline, energy-normalised\n"
    "                                              S_d; raw: the published S_d unscaled;\n"
    "                                              cpu: CPU pipeline, directional lights)\n"
    "                      combined[:cpu]          dipole + SSLPV 32^3, 8/32/128 spp\n"
    "                      reference               path tracer, seed 7, 4/16/64 spp\n"
    "                    A variant this binary or scene cannot render is skipped with a message.\n"
    "  --ref-spp N       reference samples per pixel (default 256)\n"
    "  --width, --height override the scenes' image size (pixels)\n"
    "  --repeats R       timed runs per setting (default 3)\n"
    "  --levels L        at most L quality settings per method, cheapest first (default 3)\n"
    "  --presets LIST    evaluate every scene once per material preset (e.g. skin1,marble,\n"
    "                    wholemilk): the objects' material becomes that uniform preset on the\n"
    "                    scene's grid\n"
    "  --etas LIST       evaluate every scene (and preset) once per relative index of\n"
    "                    refraction in [1, 3] (e.g. 1.3,1; 1 = index-matched boundary).\n"
    "                    Cases are named <scene>[-<preset>][-eta<E>] in the outputs; the\n"
    "                    overrides are part of the reference cache key\n"
    "  --subsurface-only reference and methods without the surface reflection\n"
    "  --json            print results.json to stdout (progress goes to stderr)\n"
    "  --verbose         keep the methods' own logs on stderr\n",
    &runEvaluate};

}  // namespace lucent::cli
