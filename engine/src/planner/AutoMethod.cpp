// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/methods/Registry.h>
#include <lucent/planner/AutoMethod.h>

#include <algorithm>
#include <limits>

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

Resolved resolve(const CandidateModel& model, const Scene& scene, bool glAvailable,
                 methods::Backend required) {
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
    for (size_t i = 0; i < candidates.size(); ++i) {
        resolved.push_back(resolve(models.candidates[i], scene, glAvailable, backend));
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
