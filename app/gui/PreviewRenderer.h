// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The viewport's rendering, outside the widget: gpu::SceneRenderer (direct lighting,
/// shadow maps, tone map) with the subsurface pass of the chosen translucency method, the volume
/// overlay and the brush-cursor overlay. The method is a lucent::methods::Method made through
/// the engine's registry by name (methods::create(name, params, {Backend::Gl, live=true}); the
/// lifecycle in lucent/methods/Method.h), so every method with a GL pass is a preview method and
/// this file names none of them. Every shader comes from the engine's shader library. Plain C++
/// and GL (epoxy): the Qt widget only hands it a current context, its framebuffer and the
/// frame's inputs.
///
/// Paint strokes: the renderer keeps the shadow maps, the G-buffer and the direct-lighting term
/// while lights, camera and mesh are unchanged, so a stroke frame runs only the subsurface pass,
/// a one-fetch shading pass and the tone map (RenderSettings::reusePasses).
///
/// Auto (AUTO_METHOD): the planner chooses the method from the scene's features, the shipped
/// error models and the live preview's measured stroke → frame costs (planner/LiveCosts.h):
/// the shipped table, or the user's calibration once useLiveCosts installs it (the app does at
/// start-up and after Edit ▸ Preferences ▸ Calibrate Live Costs).
/// The unit of those costs, the render of a Direct frame, is timed here on the viewport's own
/// passes: once per scene and render size, the preview shows Direct for four frames and
/// plans with the median of the last three. It re-plans when the scene changes (a new scene,
/// paint, lights, η, camera), at most twice a second, with the planner's hysteresis: painting
/// does not make the preview switch methods back and forth.
///
/// Material edits: the caller passes the volume's dirty bricks (MaterialVolume::takeDirtyBricks)
/// once per frame; the active method consumes them incrementally (Method::materialChanged).
/// Only the active method exists: choosing another one, or a new scene, makes a fresh instance
/// that synchronises everything.

#include <lucent/core/Image.h>
#include <lucent/core/Types.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/methods/Method.h>
#include <lucent/methods/Params.h>
#include <lucent/planner/LiveCosts.h>
#include <lucent/planner/Models.h>
#include <lucent/scene/Scene.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lucent::gpu {
class ShaderLibrary;
}
namespace lucent::planner {
struct AutoChoice;
}  // namespace lucent::planner

namespace lucent::app {

/// The method selector's "Auto" entry: not a registry method; the Auto planner
/// (lucent/planner/AutoMethod.h) chooses one for the scene and PreviewRenderer runs that.
inline constexpr const char* AUTO_METHOD = "auto";

/// Preview method and its parameters.
struct RenderSettings {
    /// AUTO_METHOD, or the registry name of a method with a GL pass (lucent/methods/Registry.h).
    /// Auto by default: the planner picks a method that shows paint for the scene (SSLPV Paper
    /// 32³, the default before issue 17, hid a dark stroke).
    std::string method = AUTO_METHOD;
    /// The method's parameters (ParamDescriptor names); unset ones take their live defaults.
    methods::ParamSet params;
    float exposureStops = 2.f;  ///< log2 of the exposure multiplier (Reinhard tone curve)
    bool turntable = false;     ///< rotate the camera at 30°/s
    /// Preview pixels per widget pixel per axis (1, ½, ¼); the image is upscaled bilinearly by
    /// the tone-map pass.
    float resolutionScale = 0.5f;
    /// Animated twist of the mesh (engine lucent/mesh/Deform.h), display only. The posed mesh
    /// is re-uploaded every frame; the subsurface passes look the material up at the posed
    /// surface (small twists only). Painting is paused while it runs.
    bool deform = false;
    /// Show only the subsurface term (debug view; gpu::DirectSettings::subsurfaceOnly).
    bool subsurfaceOnly = false;
    /// Reuse the G-buffer and the direct-lighting term while their inputs are unchanged
    /// (gpu::DirectSettings::reuseUnchangedPasses); false only to measure the gain.
    bool reusePasses = true;
    // Volume overlay (drawn over the tone-mapped image, inside the object's box only)
    bool volumeOverlay = false;   ///< ray-march the painted volume over the viewport
    int overlayChannel = 0;       ///< 0 σt, 1 σs′, 2 g (the slice view's colour maps)
    float overlayOpacity = 0.5f;  ///< overlay opacity in [0, 1]
};

/// Per-frame numbers for the Statistics dock.
struct PreviewStats {
    /// (pass, GPU ms, CPU ms) of the renderer's last collected frame.
    struct Pass {
        std::string name;
        double gpuMs = 0.0, cpuMs = 0.0;
    };
    std::vector<Pass> passes;
    std::string method;  ///< registry name of the method the last frame used
    /// With Auto: the planner's one-line reason for its choice (planner::Plan::reason), and
    /// the choice ("dipole 32 spp"); empty otherwise.
    std::string autoReason, autoChoice;
    /// With Auto: which live costs the plan used (LiveCostTable::label).
    std::string liveCosts;
    methods::Stats methodStats;  ///< its Method::stats() (SSLPV timings, dipole progress)
    /// Lights the frame left out, and why (cullLights, lucent/scene/LightReach.h).
    std::vector<std::string> skippedLights;
    int bricksUploaded = 0;  ///< bricks consumed by the last material update
    double uploadMs = 0.0;   ///< CPU ms of the last material update
    /// The method's stat `key` ("" when it has none).
    [[nodiscard]] std::string methodStat(const std::string& key) const;
    /// Frames since create() that reused the shadow maps, the G-buffer and the direct-lighting
    /// term (gpu::DirectSettings::reuseUnchangedPasses; a paint stroke reuses all three).
    long long shadowsReused = 0, gbufferReused = 0, directReused = 0;
};

/// What one frame needs. Positions in mm; the camera's width/height are the render size.
struct PreviewFrame {
    const Scene* scene = nullptr;
    MaterialVolume* volume = nullptr;         ///< the painted volume of object 0 (may be null)
    const TriangleMesh* shownMesh = nullptr;  ///< rest or posed mesh of object 0
    bool meshChanged = false;                 ///< shownMesh differs from the last frame's
    bool sceneReplaced = false;               ///< new scene: full re-synchronisation
    std::vector<int> dirtyBricks;             ///< painted since the last frame
    Camera camera;
    RenderSettings settings;
    std::optional<Point3f> cursor;  ///< brush cursor centre on the surface, mm
    float brushRadius = 0.f;        ///< mm
    unsigned framebuffer = 0;       ///< destination (Qt: defaultFramebufferObject())
    int framebufferWidth = 0, framebufferHeight = 0;
    /// The app's per-frame time outside render() (ViewportStats::hostMs; 0: not measured). Auto
    /// adds it to live costs measured without it (planner::LiveCosts::hostIncluded).
    double hostMs = 0.0;
};

/// The live costs Auto plans with, and the live models made from them.
struct LiveCostTable {
    planner::LiveCostsInUse inUse;  ///< the costs, whether calibrated, the file and any warning
    planner::Models models;         ///< planner::liveModels(defaultModels(), inUse.costs)
    std::string label;              ///< planner::describeLiveCosts(inUse)
};

class PreviewRenderer {
public:
    PreviewRenderer();
    ~PreviewRenderer();
    PreviewRenderer(const PreviewRenderer&) = delete;
    PreviewRenderer& operator=(const PreviewRenderer&) = delete;

    /// Compiles every program (GL 4.5 core context current). @throw GpuError with file:line.
    void create();
    /// Frees every GL object (context current). Idempotent.
    void destroy();
    [[nodiscard]] bool isCreated() const;

    /// Renders one frame into frame.framebuffer (context current). @throw lucent::Error.
    void render(PreviewFrame& frame);
    /// True while a progressive method still refines, or while Auto waits for its Direct frame
    /// measurement (another frame is useful when idle).
    [[nodiscard]] bool wantsAnotherFrame() const;
    /// True while Auto times the Direct frames it plans with (the frames then show Direct; the
    /// next frames finish the measurement).
    [[nodiscard]] bool isPlanning() const;
    /// Auto plans with `ms` as its Direct frame instead of timing one (> 0; 0 times again):
    /// a choice that does not depend on the machine's load, for tests and benchmarks.
    void pinAutoDirectMs(double ms);
    /// With Auto: the plan the last frame used (null before one, or with a fixed method).
    [[nodiscard]] const planner::AutoChoice* autoChoice() const;
    /// With Auto: the planner's pick before the level check's decision (planner/LevelCheck.h)
    /// replaced its level (the same as autoChoice() when none applies; null before a plan).
    [[nodiscard]] const planner::AutoChoice* autoPlannedChoice() const;
    /// What a level check of Auto's pick found: `planned` → `kept` of `method` (model name,
    /// "sslpv:diffusion"), made for `sceneClass`.
    struct AutoLevelDecision {
        std::string method, planned, kept;
        std::string note;  ///< planner::LevelCheck::note
        planner::SceneClass sceneClass;
    };
    /// From the next plan on, a pick of decision.method at decision.planned in a scene of its
    /// class renders at decision.kept (the plan's reason says why), until another decision for
    /// that pick replaces it or the scene is replaced. Painting keeps it (no switch back and
    /// forth while the artist paints); the viewport checks again when the painting pauses.
    void setAutoLevelDecision(const AutoLevelDecision& decision);
    /// Forgets every level decision: the picks render at their own levels from now on.
    void clearAutoLevelDecisions();
    /// Whether a decision for `planned` (an autoPlannedChoice()) is held.
    [[nodiscard]] bool hasAutoLevelDecisionFor(const planner::AutoChoice& planned) const;
    /// The Direct frame Auto last planned with, ms (0 before one was timed or pinned).
    [[nodiscard]] double autoDirectMs() const;
    /// The live preview's candidates Auto plans with: the live costs in use (stroke → frame)
    /// with the shipped error models (planner/LiveCosts.h). Thread-safe; the reference stays
    /// valid for the process's life (a plan or a measurement on a worker thread may hold it
    /// while useLiveCosts installs another table).
    [[nodiscard]] static const planner::Models& liveModels();
    /// The live costs in use (the shipped table until useLiveCosts), with the same guarantees.
    [[nodiscard]] static const LiveCostTable& liveCostTable();
    /// Every PreviewRenderer's Auto plans with `inUse`'s costs from its next frame on, from
    /// scratch (hysteresis does not keep a choice made with other costs, and measured errors
    /// made against the old models are dropped). Call on the UI thread.
    static void useLiveCosts(const planner::LiveCostsInUse& inUse);
    /// How long measured errors hold (setMeasuredModels).
    enum class MeasuredHold {
        /// Until anything the plan depends on changes (scene, paint, lights, η, view): the
        /// Reference dock's measurement of its view ("errors measured on this view").
        ThisView,
        /// Through paint and view changes, until the scene, its lights or η change: Auto's own
        /// measurement (AutoMeasurer), which measures again once the artist pauses, so the
        /// preview does not fall back to the models' pick (another method) while painting
        /// ("errors measured on this scene").
        ThisScene,
    };
    /// Auto plans with `models` instead of liveModels() from the next frame on (the same
    /// candidates in the same order: liveModels() with this scene's measured errors,
    /// planner::measuredModels with MeasuredParts::ErrorsOnly), as long as `hold` says.
    /// `errorMargin`: the reference's noise floor (planner::Budget::errorMargin: errors closer
    /// than it count as equal). Null: the shipped models again.
    void setMeasuredModels(std::shared_ptr<const planner::Models> models, double errorMargin = 0.0,
                           MeasuredHold hold = MeasuredHold::ThisView);
    /// Whether the last plan was made with measured models.
    [[nodiscard]] bool usesMeasuredModels() const;
    /// Whether measured models are set (the next plan uses them), and how long they hold.
    [[nodiscard]] bool hasMeasuredModels() const;
    [[nodiscard]] MeasuredHold measuredHold() const;
    [[nodiscard]] const PreviewStats& stats() const;
    /// The last frame's linear radiance at render resolution (camera width × height),
    /// W/(mm²·sr), before tone mapping and overlays, top row first (for EXR export). Reads the
    /// GPU back on demand (context current). @throw lucent::Error before the first frame.
    [[nodiscard]] ImageRgb linearImage() const;
    /// Whether `name` is a preview method: a registered method with a GL pass.
    [[nodiscard]] static bool isPreviewMethod(const std::string& name);
    /// The preview methods' registry entries, in the registry's order (the method selector).
    [[nodiscard]] static std::vector<const methods::MethodInfo*> previewMethods();
    /// The shaders every pass and method is compiled from (embedded, or $LUCENT_SHADER_DIR).
    /// An in-memory file set here (ShaderLibrary::setFile) is used by the programs compiled
    /// after it, e.g. a method's pass created when the method is next selected.
    [[nodiscard]] gpu::ShaderLibrary& shaderLibrary();

private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace lucent::app
