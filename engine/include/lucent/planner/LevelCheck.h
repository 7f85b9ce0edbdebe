// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Skip a quality level the scene does not need: once the models have chosen a method
/// at some level (a grid, a sample count), render that level and the method's next cheaper one
/// on a small frame of the scene; when the two images differ by at most a tolerance (4×4-block
/// relative L1 of luminance, the metric the models predict; LevelTolerance in Planner.h), the
/// cheaper level is as good as far as can be told, so it is taken and the one below it is
/// tried, the differences summed so the image kept never drifts further than the tolerance
/// from the chosen one.
///
///     AutoChoice c = chooseOffline(scene, defaultModels(), budget, gl, log);
///     LevelCheck k = checkLevels(scene, defaultModels(), c);
///     applyLevelCheck(c, defaultModels(), k);  // setting, params and reason follow the check
///
/// Why a measurement and not the models: the models predict each level's error from the
/// scene's features, and over the evaluation suite the ratio between two adjacent levels'
/// errors is not predictable from them (leave-one-out RMS of its log 0.42–0.44 against a
/// spread of 0.42–0.48; docs/planner.md, "Levels the scene does not need"), so Auto took grid
/// 64 where grid 32 reads the same. The difference between the two images is what the finer
/// level buys, and it is measured on the scene itself, in one render per level.

#include <lucent/methods/RenderImage.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/Models.h>
#include <lucent/scene/Scene.h>

#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace lucent::planner {

struct LevelCheckOptions {
    /// Summed block relative L1 between adjacent levels up to which the cheaper level is taken,
    /// at the chosen candidate's predicted error (AutoChoice::plan.chosen.error); off(): no
    /// check.
    LevelTolerance tolerance;
    /// Width of the check frame in pixels (the height follows the camera's aspect): the
    /// evaluation suite's 64 gives 16 × 16 blocks across the frame.
    int width = 64;
    methods::RenderOptions render;  ///< backend, context, log (the choice's backend if Auto)
    /// Checked between renders: set → stop, keep what was decided so far.
    const std::atomic<bool>* cancel = nullptr;
};

/// One comparison of a level with the next finer one.
struct LevelStep {
    std::string coarser, finer;  ///< quality level names
    double difference = 0.0;     ///< block relative L1 of the coarser image against the finer
    bool taken = false;          ///< the summed difference stayed within the tolerance
};

struct LevelCheck {
    std::string setting;           ///< the level kept (the choice's when nothing was taken)
    std::vector<LevelStep> steps;  ///< finest first
    /// One clause for the plan's reason, e.g. "grid 32: grid 64 changes the image by 1.1 %
    /// (≤ 2 %)"; "" when no cheaper level was compared.
    std::string note;
};

/// The rule alone. `levels` cheapest first; `chosen` an index into it; differenceToNext(i)
/// the block relative L1 of level i against level i + 1, or < 0 when unknown (the walk stops).
/// @return the cheapest level reached from `chosen` downwards while the summed differences stay
/// ≤ tolerance; `steps` (may be null) gets each comparison made, finest first.
size_t coarsestEquivalentLevel(const std::vector<std::string>& levels, size_t chosen,
                               const std::function<double(size_t)>& differenceToNext,
                               double tolerance, std::vector<LevelStep>* steps = nullptr);

/// The levels of `method` ("sslpv:diffusion") that `models` holds, in the registry's quality
/// order (cheapest first). Empty when the registry has no such method.
std::vector<std::string> modelLevels(const Models& models, const std::string& method);

/// Renders the choice's level and, while the rule keeps stepping down, each cheaper level of
/// its method (modelLevels) on `scene` with its camera narrowed to options.width pixels, and
/// compares them over the pixels either image covers.
/// @throw ValueError if a tolerance is negative or not finite, or options.width < 8; Error
/// from the renders.
LevelCheck checkLevels(const Scene& scene, const Models& models, const AutoChoice& choice,
                       const LevelCheckOptions& options = {});

/// `choice` at the level the check kept: its setting and params resolved again, the plan's
/// choice and prediction those of that level's candidate in `models`, and the plan's reason
/// led by what runs: "sslpv:diffusion grid 32 by the level check: grid 64 changes the image
/// by 2.3 % (at most 6.5 %); the models' pick: sslpv:diffusion grid 64: …" (a kept level: the
/// models' reason, then "; level check: " and the note). @throw ValueError if the registry has
/// no such level.
void applyLevelCheck(AutoChoice& choice, const Models& models, const LevelCheck& check);

/// checkLevels, then applyLevelCheck. The check only saves time: when one of its renders fails,
/// `choice` stays as the models planned it and options.render.log (if set) says why.
/// @throw ValueError for bad options (as checkLevels).
void runLevelCheck(const Scene& scene, const Models& models, AutoChoice& choice,
                   const LevelCheckOptions& options = {});

}  // namespace lucent::planner
