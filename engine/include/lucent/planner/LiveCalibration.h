// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Measuring the live costs (LiveCosts.h) on this machine, headlessly: the app's default
/// scene at the app's default preview settings, each candidate driven through the method
/// registry as the live preview drives it after a paint stroke, timed from the stroke to the
/// finished frame, as a ratio to the render of a Direct frame timed just before it.
///
///     LiveCalibration c = calibrateLiveCosts({.strokes = 8});
///     saveLiveCosts(c.costs, userLiveCostsPath());    // the app plans with it from now on
///
/// Why: the shipped ratios are llvmpipe's on a 2-core box. On a machine with a GPU or more
/// cores the methods do not all speed up alike (SSLPV's CPU propagation against an image-space
/// gather on the GPU), so the planner would mispredict which candidates fit the frame budget.
///
/// What is timed, per stroke (as the app's harness `lucent --benchmark --live-costs` times it,
/// app/gui/main.cpp): 17 cursor samples along a horizontal line of 1/8 of the viewport's width
/// (80 px at 640×360), each ray-picked against the mesh (lucent/mesh/MeshPicker.h) and stamped
/// with the Tools dock's default brush and History recording; then the frame: the dirty bricks
/// to the method (Method::materialChanged), gpu::SceneRenderer's passes into a framebuffer of
/// the viewport's size, the renderer's timer queries collected and glFinish. The unit is the
/// same frame of the Direct method without the stroke (the harness's Direct `paintGL`). What
/// the app adds and this does not: Qt's event loop and window swap (3–5 ms a frame on llvmpipe
/// under Xvfb, docs/benchmarks.md "App latency") and the viewport's QPainter overlay.
///
/// Needs a headless OpenGL 4.5 context (gpu::GlContext::createHeadless), made and released on
/// the calling thread: it may run on a worker thread while another thread renders with its
/// own context (the app).

#include <lucent/planner/LiveCosts.h>

#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace lucent::planner {

struct LiveCalibrationProgress {
    int done = 0;      ///< timed runs finished (one Direct run and one candidate run per entry)
    int total = 0;     ///< rounds × entries × 2
    std::string next;  ///< what runs next ("direct", "dirpole 128 spp"); "" when done
};

struct LiveCalibrationOptions {
    /// The viewport in widget pixels: the harness's `--viewport 640x360` (docs/planner.md).
    int viewportWidth = 640, viewportHeight = 360;
    /// Rendered pixels per viewport pixel per axis: the app's default "half resolution"
    /// (RenderSettings::resolutionScale), in (0, 1].
    float resolutionScale = 0.5f;
    int strokes = 8;        ///< timed strokes per run (the harness's 8), ≥ 1
    int warmupStrokes = 1;  ///< untimed strokes before them (History's first allocations), ≥ 0
    /// Frames after the method is made and before the first stroke (the harness's 15 idle
    /// frames: a progressive method refines meanwhile, as while the artist looks), ≥ 0.
    int idleFrames = 15;
    /// Each entry is measured this many times (a Direct run just before each); the ratio is the
    /// median over rounds: on a shared machine the load drifts, and a pair measured together
    /// sees the same load. ≥ 1.
    int rounds = 3;
    /// The candidates (method and setting; the ratio is ignored); empty: defaultLiveCosts().
    std::vector<LiveCost> candidates;
    std::string command = "lucent-cli bench calibrate";  ///< named in LiveCosts::source
    /// Checked before every frame: set → stop, release the context and return cancelled.
    const std::atomic<bool>* cancel = nullptr;
    /// After every run (and once before the first); called on the calibrating thread.
    std::function<void(const LiveCalibrationProgress&)> progress;
};

/// One candidate as measured.
struct LiveCalibrationRow {
    LiveCost cost;          ///< strokeRatio: the median over rounds of stroke → frame / unit
    double strokeMs = 0.0;  ///< stroke → frame, ms: median over rounds of each run's median
    double directMs = 0.0;  ///< its unit, ms: median over rounds of the Direct runs' medians
    std::vector<double> roundRatios;  ///< per round
    int strokesTimed = 0;             ///< strokes timed over all rounds
};

struct LiveCalibration {
    /// The measured table: source (command, viewport, renderer, date), directMs (median of
    /// every Direct run), date, renderer, cpuThreads and one entry per candidate in the order
    /// asked; no entries when cancelled.
    LiveCosts costs;
    std::vector<LiveCalibrationRow> rows;  ///< the entries measured (all unless cancelled)
    bool cancelled = false;
};

/// Measures the live costs (see the file comment).
/// @throw ValueError for options out of range or a candidate the registry cannot resolve;
/// GpuError when no headless context can be made or a render fails.
LiveCalibration calibrateLiveCosts(const LiveCalibrationOptions& options = {});

}  // namespace lucent::planner
