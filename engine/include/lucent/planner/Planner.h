// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The Auto planner: from predicted cost and error of each candidate (a method at one
/// setting) for a scene, pick the one with the least predicted error that fits the frame
/// budget, or the cheapest one under an error target; explain the choice in one line; keep it
/// while the scene's class does not change (no flicker while painting).
///
///     std::vector<Candidate> candidates = ...;          // models: lucent/planner/Models.h
///     Plan p = plan(candidates, analyzeScene(scene), {.frameMs = 50, .directMs = 8});
///     std::cout << p.reason;   // "dipole 16 spp: thick, front-lit, η 1.3, homogeneous; ..."
///     ... the scene changes ...
///     p = plan(candidates, analyzeScene(scene), budget, &p);  // hysteresis against p
///
/// Cost is predicted as a ratio to the Direct render of the same frame (so a model measured
/// on one machine carries to another: Budget::directMs is this machine's Direct frame).

#include <lucent/planner/SceneFeatures.h>

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

namespace lucent::planner {

/// One method at one setting, with its predictions for a scene.
struct Candidate {
    std::string method;   ///< registry name, e.g. "dipole"
    std::string setting;  ///< e.g. "16 spp", "grid 32"
    /// Predicted frame time as a ratio to the Direct render of the same frame (≥ 1 normally).
    std::function<double(const SceneFeatures&)> costRatio;
    /// Predicted error (4×4-block relative L1 against the exact reference, ≥ 0).
    std::function<double(const SceneFeatures&)> error;
    /// Why the candidate cannot serve this scene at all ("" when it can), e.g. a method
    /// without a light type the scene uses.
    std::function<std::string(const SceneFeatures&)> unusable;
};

struct Budget {
    double frameMs = 50.0;  ///< time per frame the preview may take (may be +∞: no limit)
    double directMs = 5.0;  ///< this machine's Direct render of the frame (> 0)
    /// false when no Direct frame could be measured (no GL) and directMs is 1 as a stand-in:
    /// the reason then gives costs as ratios to the Direct frame, not as times.
    bool directKnown = true;
    /// Time every frame costs outside the renderer that the cost models leave out (ms, ≥ 0):
    /// the app's event loop and buffer swap when its live costs were measured headless
    /// (LiveCosts::hostIncluded false). Added to every candidate's predicted time. 0 when
    /// directKnown is false (costs are then ratios).
    double hostMs = 0.0;
    /// If > 0: the cheapest candidate whose predicted error is at most this, instead of the
    /// most accurate within frameMs.
    double maxError = 0.0;
    /// A new best replaces the previous choice of the same scene class only if its predicted
    /// error is lower by more than this fraction (or the previous no longer fits).
    double hysteresis = 0.15;
    /// Within the frame budget, predicted errors within this fraction of the least are equal
    /// and the cheapest of them wins: the models predict errors to a factor of 1.5–2
    /// (docs/planner.md), and more samples of a progressive method that buy a predicted 2 %
    /// cost twice the time for an error the measurement cannot tell apart (the suite's
    /// 8/32/128 spp rows).
    double errorTolerance = 0.1;
    /// …plus this absolute block error (≥ 0). Errors measured against a Monte Carlo reference
    /// closer than its noise floor cannot be told apart: Auto measuring on its own sets the
    /// reference's floor here (chooseByMeasuring, MeasureScene.h). 0 for predictions.
    double errorMargin = 0.0;
    /// When nothing fits frameMs (a slow machine, a large viewport), the budget becomes the
    /// fastest candidate's time × (1 + this) and the least error within that is chosen: the
    /// frame is late either way, and the fastest alone can be several times as wrong as a
    /// candidate 20 % slower (SSLPV 16³ at 0.61 against the directional dipole at 0.24 on the
    /// default scene at 1920×1080). 0: the fastest.
    double overrunTolerance = 0.5;
};

/// How far a cheaper quality level's image may differ from the chosen level's for the level
/// check (LevelCheck.h) to take it: the larger of an absolute block relative L1 and a fraction
/// of the chosen candidate's predicted error, summed over the steps down.
struct LevelTolerance {
    /// 2 %: below what an artist sees side by side (a just-noticeable luminance step is 1–2 %),
    /// and about the evaluation suite's median reference noise floor (0.016).
    double absolute = 0.02;
    /// × the chosen candidate's predicted error. A cheaper image within the chosen one's own
    /// error of it is, by the triangle inequality, at most twice that error from the exact
    /// one: the factor to which the models predict errors (Budget::errorTolerance). And where
    /// refining moves the image less than the error left, that error is the method's, not
    /// the level's (docs/planner.md, "Levels the scene does not need").
    double relative = 1.0;
    [[nodiscard]] double at(double predictedError) const {
        return std::max(absolute, relative * std::max(predictedError, 0.0));
    }
    [[nodiscard]] bool off() const { return !(absolute > 0) && !(relative > 0); }
    /// The absolute part alone: a cheaper level is taken only where the picture does not
    /// change visibly. The app's live preview uses it: the relative part admits a coarser
    /// grid whose cell-sized patches an artist sees at the viewport's size although its block
    /// error against the exact image is as small (docs/planner.md, "The level check in the
    /// app").
    [[nodiscard]] static LevelTolerance visibleOnly() { return {LevelTolerance{}.absolute, 0.0}; }
};

/// One scored candidate.
struct Option {
    size_t index = 0;  ///< into the candidate list
    double ms = 0.0;   ///< predicted frame time
    double error = 0.0;
    bool fits = false;  ///< within the budget (time, or error under maxError)
};

struct Plan {
    bool valid = false;  ///< false only when no candidate is usable
    size_t choice = 0;   ///< index into the candidate list
    Option chosen;
    SceneClass sceneClass;
    /// One line: the choice, the scene class, prediction vs budget, and what was passed over.
    std::string reason;
    std::vector<Option> options;  ///< every usable candidate, best first
    bool kept = false;            ///< the previous choice was kept (hysteresis)
};

/// Plans a frame. `previous` (may be null): the last plan, for hysteresis.
/// @throw ValueError if budget.directMs ≤ 0 or frameMs ≤ 0 (or NaN), or a prediction is not
/// finite.
Plan plan(const std::vector<Candidate>& candidates, const SceneFeatures& features,
          const Budget& budget, const Plan* previous = nullptr);

}  // namespace lucent::planner
