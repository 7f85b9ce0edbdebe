// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief "Auto": the method and setting the planner chooses for a scene, resolved to a
/// registry name and parameter values that lucent::methods can render.
///
///     AutoChoice c = chooseMethod(scene, defaultModels(), {.frameMs = 50, .directMs = d}, true);
///     std::cerr << c.plan.reason << "\n";
///     RenderResult r = methods::renderImage(scene, c.method, c.params, {.backend = c.backend});
///
/// A candidate is left out, with the reason in the plan, when the registry no longer has its
/// method, variant or quality level, when it needs GL and there is none, or when the scene has
/// a light type the method's backend ignores.

#include <lucent/methods/RenderImage.h>
#include <lucent/planner/Models.h>
#include <lucent/planner/Planner.h>
#include <lucent/scene/Scene.h>

#include <string>

namespace lucent::planner {

/// A candidate of the models ("sslpv:paper", "grid 32") as the registry runs it.
struct CandidateRun {
    std::string method;        ///< registry name, e.g. "sslpv"
    std::string variant;       ///< evaluation variant ("" for the method as is)
    methods::ParamSet params;  ///< the variant's values, then the quality level's
    methods::Backend backend = methods::Backend::Auto;  ///< the variant's
};

/// @throw ValueError if the registry has no such method, variant or quality level.
CandidateRun resolveCandidate(const std::string& method, const std::string& setting);
/// Renders a candidate of the models on `scene`: resolveCandidate's method and parameters, on
/// options.backend, or the variant's backend when that is Auto; no progress callback.
/// @throw ValueError as resolveCandidate; what methods::renderImage throws.
methods::RenderResult renderCandidate(const Scene& scene, const std::string& method,
                                      const std::string& setting,
                                      methods::RenderOptions options = {});

struct AutoChoice {
    std::string method;        ///< registry name, e.g. "dirpole"
    std::string variant;       ///< evaluation variant ("" for the method as is)
    std::string setting;       ///< quality level name
    methods::ParamSet params;  ///< the variant's values, then the quality level's
    methods::Backend backend = methods::Backend::Auto;
    SceneFeatures features;
    /// The models' name of the candidate: "method[:variant]" ("sslpv:diffusion").
    [[nodiscard]] std::string candidate() const {
        return variant.empty() ? method : method + ":" + variant;
    }
    double directMs = 0.0;  ///< the Direct frame time planned with (Budget::directMs)
    Plan plan;
};

/// Plans `scene` with `models` (the scene's features are measured here).
/// @param glAvailable whether GL methods can run (a headless context or the app's viewport).
/// @param backend Auto: each candidate's variant decides (offline); Gl or Cpu: every candidate
///        runs there (the live preview: Gl), and one whose variant needs the other is left out.
/// @throw ValueError if the scene cannot be analysed (no object with a material) or no
///        candidate can render it (the message lists why each was left out).
AutoChoice chooseMethod(const Scene& scene, const Models& models, const Budget& budget,
                        bool glAvailable, const Plan* previous = nullptr,
                        methods::Backend backend = methods::Backend::Auto);

/// chooseMethod for an offline render (the CLI's `plan` and `render --method auto`): when
/// budget.directMs ≤ 0 it is measured (measureDirectMs). Without GL there is no Direct frame to
/// scale the cost models with: the choice is then by predicted error alone (or, under an error
/// target, by cost ratio), said through `log`.
AutoChoice chooseOffline(const Scene& scene, const Models& models, Budget budget, bool glAvailable,
                         const methods::Log& log);

/// Wall time of one Direct render of `scene`'s frame through methods::renderImage (context
/// creation included): the unit of the models' cost ratios, which the evaluation measures the
/// same way. Budget::directMs for an offline render.
double measureDirectMs(const Scene& scene, const methods::RenderOptions& options);

}  // namespace lucent::planner
