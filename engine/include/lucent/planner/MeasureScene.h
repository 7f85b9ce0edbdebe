// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Measuring the Auto planner's candidates on one scene instead of predicting them:
/// each candidate rendered through methods::renderImage on the scene's camera, its wall time
/// as a ratio to a Direct render of the same frame (the models' cost unit) and, when a
/// reference image of that frame is given, its 4×4-block relative L1 against it (the metric
/// the models predict and the app's Reference dock reports). Then the models with those
/// numbers in place of their predictions, so plan() chooses by what this scene measured.
///
///     SceneMeasurement m = measureCandidates(scene, models, {.reference = &ref, .mask = &mask});
///     AutoChoice c = chooseMethod(scene, measuredModels(models, m), budget, true);
///
/// The costs are offline renders to convergence (context creation included), the unit the
/// offline models (Models.h) use; the live preview's stroke costs (LiveCosts.h) are another
/// quantity and are not what this measures.

#include <lucent/core/Image.h>
#include <lucent/methods/RenderImage.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/Models.h>
#include <lucent/scene/Scene.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace lucent::planner {

/// One candidate measured on the scene.
struct CandidateMeasurement {
    std::string method;      ///< as in the models: registry name[:variant]
    std::string setting;     ///< quality level name
    double ms = 0.0;         ///< wall time of its renderImage call
    double costRatio = 0.0;  ///< ms / the Direct render's ms
    /// 4×4-block relative L1 of luminance against the reference over the mask (net of the
    /// reference's noise with MeasureOptions::netOfNoise); < 0 when no reference was given.
    double blockRelL1 = -1.0;
    /// Why it was not measured ("" when it was): the registry cannot resolve it, the render
    /// threw. Its other fields are then 0 / -1.
    std::string failed;
    ImageRgb radiance;  ///< its render (linear, the camera's size; empty when it failed)
    [[nodiscard]] bool ok() const { return failed.empty(); }
};

struct SceneMeasurement {
    double directMs = 0.0;  ///< the Direct render of the frame (the cost unit)
    std::vector<CandidateMeasurement> candidates;  ///< in the order asked for
    bool cancelled = false;  ///< stopped through MeasureOptions::cancel before the last one
};

struct MeasureOptions {
    /// The exact image of scene.camera's frame (same size), linear; null: no error measured.
    const ImageRgb* reference = nullptr;
    /// The reference's per-pixel variance (may be null): compareImages' noise floor.
    const ImageRgb* referenceVariance = nullptr;
    /// Pixels compared (width·height bytes; null: every pixel).
    const std::vector<uint8_t>* mask = nullptr;
    /// Record each error with the reference's noise floor removed in quadrature (the
    /// evaluation's block_rel_l1, what the models are fitted on) instead of as read (the
    /// Reference dock's number). Needs referenceVariance.
    bool netOfNoise = false;
    /// Indices into models.candidates to measure (empty: all of them).
    std::vector<size_t> which;
    methods::RenderOptions render;  ///< backend, context, log
    /// Checked between renders: set → stop and return what was measured (cancelled = true).
    const std::atomic<bool>* cancel = nullptr;
    /// After the Direct render (done 0) and each candidate: done of total.
    std::function<void(size_t done, size_t total, const CandidateMeasurement* last)> progress;
};

/// Renders the Direct frame, then each candidate of `models` (resolveCandidate: its variant's
/// parameters and backend unless options.render.backend says otherwise), timing each.
/// @throw ValueError if the reference's size differs from the camera's, an index is out of
/// range; GpuError/Error from the Direct render (without it there is no unit).
SceneMeasurement measureCandidates(const Scene& scene, const Models& models,
                                   const MeasureOptions& options = {});

/// Measuring a scene without a reference at hand (Auto measuring on its own): the exact
/// reference of the frame is rendered first, at a small size, then every candidate against it.
struct OwnReferenceOptions {
    /// Pixels across of the reference and the renders; the height follows the camera's aspect.
    /// Small, as the level check's frame: the measurement ranks whole images, and the
    /// reference's cost grows with the pixels.
    int width = 64;
    /// The reference's samples per pixel: at 64 px its noise floor (the block error a perfect
    /// image reads) is 0.02–0.05 on the shipped scenes at 128, far under the differences
    /// between methods it has to tell apart (docs/planner.md, "Auto measuring on its own").
    int referenceSpp = 128;
    int referenceThreads = 0;       ///< the path tracer's worker threads (0: all)
    std::vector<size_t> which;      ///< as MeasureOptions::which
    methods::RenderOptions render;  ///< as MeasureOptions::render
    const std::atomic<bool>* cancel = nullptr;
};

struct OwnReferenceMeasurement {
    SceneMeasurement measurement;  ///< the candidates against the reference below
    int width = 0, height = 0;     ///< the frame measured
    double referenceSeconds = 0.0;
    int referenceSpp = 0;
    /// The reference's own block error (bench::ErrorReport noise floor of luminance blocks):
    /// measured errors closer than this cannot be told apart.
    double referenceNoise = 0.0;
};

/// Renders the exact reference of scene.camera's frame at options.width (reference::
/// renderReference, dielectric boundary, seed 1), then measureCandidates against it over the
/// pixels it covers.
/// @throw ValueError for a width < 8 or spp < 3; what renderReference and measureCandidates
/// throw.
OwnReferenceMeasurement measureWithOwnReference(const Scene& scene, const Models& models,
                                                const OwnReferenceOptions& options = {});

/// Which predictions measuredModels replaces.
enum class MeasuredParts {
    CostsAndErrors,  ///< both (an offline plan: the measured costs are offline renders)
    /// The errors only: for the live preview, whose costs are stroke → frame times
    /// (LiveCosts.h), another quantity than the offline render times measured here, while a
    /// measured error is the error of the image the live method converges to.
    ErrorsOnly,
};

/// `models` with every measured candidate's prediction replaced by the measurement: a cost
/// model with only the intercept log(costRatio) (CostsAndErrors), and, when the error was
/// measured, an error model with only log(blockRelL1) (a measured error of 0 is clamped to
/// 1e-6: the log-linear model needs a positive value). Candidates not measured (or failed)
/// keep their models.
Models measuredModels(const Models& models, const SceneMeasurement& measurement,
                      MeasuredParts parts = MeasuredParts::CostsAndErrors);

/// Auto measuring on its own (`lucent-cli plan --measure`, `render --method auto --measure`):
/// the candidates `planned` found usable and within its budget (every usable one when none
/// fits) measured against an exact reference of the frame (measureWithOwnReference), then the
/// plan made again with their measured errors in place of the predictions. The costs stay the
/// models' (MeasuredParts::ErrorsOnly: the measured renders are of the small frame), scaled by
/// the Direct frame `planned` was made with. A cancelled measurement keeps `planned`.
struct MeasuredChoice {
    AutoChoice choice;
    OwnReferenceMeasurement measurement;
};
/// @throw what measureWithOwnReference and chooseOffline throw.
MeasuredChoice chooseByMeasuring(const Scene& scene, const Models& models,
                                 const AutoChoice& planned, const Budget& budget, bool glAvailable,
                                 const OwnReferenceOptions& options, const methods::Log& log);

}  // namespace lucent::planner
