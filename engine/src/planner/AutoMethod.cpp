// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/material/Resample.h>
#include <lucent/methods/Registry.h>
#include <lucent/planner/AutoMethod.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace lucent::planner {

namespace {

/// A candidate resolved against the registry, or why it cannot serve the scene.
struct Resolved : CandidateRun {
    std::string unusable;
};

/// The registry's method, variant and quality level of a candidate ("" or why not).
std::string resolveInRegistry(const std::string& method, const std::string& setting,
                              CandidateRun& r) {
    const size_t colon = method.find(':');
    r.method = method.substr(0, colon);
    r.variant = colon == std::string::npos ? "" : method.substr(colon + 1);
    if (!methods::exists(r.method))
        return "not in this build's method registry";
    const methods::MethodInfo& info = methods::find(r.method);
    if (!r.variant.empty()) {
        const auto v =
            std::find_if(info.variants.begin(), info.variants.end(),
                         [&](const methods::ParamPreset& p) { return p.name == r.variant; });
        if (v == info.variants.end())
            return "the registry has no variant '" + r.variant + "'";
        r.params = v->values;
        r.backend = v->backend;
    }
    const auto q = std::find_if(info.quality.begin(), info.quality.end(),
                                [&](const methods::ParamPreset& p) { return p.name == setting; });
    if (q == info.quality.end())
        return "the registry has no quality level '" + setting + "'";
    r.params.merge(q->values);
    return {};
}

/// Why SSLPV with a grid of `grid` cells would read nothing of object 0 ("" when it can): its
/// read-out takes light only from cells at least half inside, and from there into parts
/// thinner than half a cell (docs/methods/sslpv.md, "Parts thinner than half a cell"), so an
/// object thinner than half a cell everywhere renders black. Answers are kept per grid.
class SslpvReadability {
public:
    SslpvReadability(const Scene& scene, const SceneFeatures& features)
        : m_scene(scene), m_features(features) {}

    const std::string& unreadable(int grid) {
        const auto known = m_answers.find(grid);
        if (known != m_answers.end())
            return known->second;
        return m_answers[grid] = measure(grid);
    }

private:
    [[nodiscard]] std::string measure(int grid) const {
        const MaterialVolume& volume = *m_scene.objects.front().material;
        const int resolution = std::min(grid, volume.resolution());
        const double cellMm =
            double(volume.spec().voxelSize) * volume.resolution() / double(resolution);
        // A ball of radius √3 cells holds a whole cell of any grid, so a deep enough object is
        // readable without reading the mask (a depth read too deep only leaves a grid unskipped).
        if (m_features.maxDepthMm >= std::sqrt(3.0) * cellMm)
            return {};
        if (anyCoarseCellInside(volume, resolution, 0.5f))
            return {};
        return "the object is thinner than half a cell of grid " + std::to_string(resolution) +
               " everywhere (it would render black)";
    }

    const Scene& m_scene;
    const SceneFeatures& m_features;
    std::map<int, std::string> m_answers;
};

Resolved resolve(const CandidateModel& model, const Scene& scene, bool glAvailable,
                 methods::Backend required, SslpvReadability& sslpv) {
    Resolved r;
    r.unusable = resolveInRegistry(model.method, model.setting, r);
    if (!r.unusable.empty())
        return r;
    if (required != methods::Backend::Auto) {
        if (r.backend != methods::Backend::Auto && r.backend != required) {
            r.unusable = "the variant runs on another backend than the one required";
            return r;
        }
        r.backend = required;
    }
    const methods::MethodInfo& info = methods::find(r.method);
    methods::Backend used;
    try {
        used = methods::resolveBackend(info, r.backend, glAvailable, "no OpenGL 4.5 context");
    } catch (const Error& e) {
        r.unusable = e.what();
        return r;
    }
    const methods::LightMask handled =
        used == methods::Backend::Gl ? info.caps.glLights : info.caps.cpuLights;
    for (const Light& l : scene.lights)
        if (!(handled & methods::lightBit(l.type))) {
            r.unusable = std::string("ignores the scene's ") + lightTypeName(l.type) + " light";
            return r;
        }
    if (r.method == "sslpv")
        if (const std::string* grid = r.params.find("grid"))
            r.unusable = sslpv.unreadable(std::stoi(*grid));
    return r;
}

}  // namespace

AutoChoice chooseMethod(const Scene& scene, const Models& models, const Budget& budget,
                        bool glAvailable, const Plan* previous, methods::Backend backend) {
    AutoChoice choice;
    choice.features = analyzeScene(scene);
    choice.directMs = budget.directMs;
    std::vector<Candidate> candidates = toCandidates(models);
    std::vector<Resolved> resolved;
    SslpvReadability sslpv(scene, choice.features);
    for (size_t i = 0; i < candidates.size(); ++i) {
        resolved.push_back(resolve(models.candidates[i], scene, glAvailable, backend, sslpv));
        const std::string why = resolved.back().unusable;
        candidates[i].unusable = [why](const SceneFeatures&) { return why; };
    }
    choice.plan = plan(candidates, choice.features, budget, previous);
    if (!choice.plan.valid)
        LUCENT_THROW(ValueError, "Auto: no method can render this scene (", choice.plan.reason,
                     ")");
    const Resolved& r = resolved[choice.plan.choice];
    choice.method = r.method;
    choice.variant = r.variant;
    choice.setting = models.candidates[choice.plan.choice].setting;
    choice.params = r.params;
    choice.backend = r.backend;
    return choice;
}

AutoChoice chooseOffline(const Scene& scene, const Models& models, Budget budget, bool glAvailable,
                         const methods::Log& log) {
    if (budget.directMs <= 0) {
        if (glAvailable) {
            methods::RenderOptions o;
            o.log = log;
            budget.directMs = measureDirectMs(scene, o);
        } else {
            if (log && budget.maxError <= 0)
                log("no OpenGL: no Direct frame to scale the cost models with, so the choice is "
                    "by predicted error alone (give the Direct frame time to plan to a budget)");
            budget.directMs = 1.0;  // costs stay ratios; only their order is used below
            budget.directKnown = false;
            if (budget.maxError <= 0)
                budget.frameMs = std::numeric_limits<double>::infinity();
        }
    }
    return chooseMethod(scene, models, budget, glAvailable);
}

CandidateRun resolveCandidate(const std::string& method, const std::string& setting) {
    CandidateRun r;
    const std::string why = resolveInRegistry(method, setting, r);
    if (!why.empty())
        LUCENT_THROW(ValueError, "candidate '", method, " ", setting, "': ", why);
    return r;
}

methods::RenderResult renderCandidate(const Scene& scene, const std::string& method,
                                      const std::string& setting, methods::RenderOptions options) {
    const CandidateRun run = resolveCandidate(method, setting);
    if (options.backend == methods::Backend::Auto)
        options.backend = run.backend;
    options.progress = nullptr;
    return methods::renderImage(scene, run.method, run.params, options);
}

double measureDirectMs(const Scene& scene, const methods::RenderOptions& options) {
    methods::RenderOptions o = options;
    o.subsurfaceOnly = false;
    o.progress = nullptr;
    return methods::renderImage(scene, "direct", {}, o).milliseconds;
}

}  // namespace lucent::planner
