// SPDX-License-Identifier: MIT
/// @file
/// @brief Headless measurement of the live costs (LiveCalibration.h has the contract).

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/gpu/Shader.h>
#include <lucent/material/Brush.h>
#include <lucent/material/History.h>
#include <lucent/mesh/MeshPicker.h>
#include <lucent/methods/Registry.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/LiveCalibration.h>
#include <lucent/scene/LightReach.h>
#include <lucent/scene/SceneFile.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>
#include <thread>

namespace lucent::planner {

namespace {

// The harness's stroke (app/gui/main.cpp timeMethod, Viewport::strokeBetween): 16 segments,
// 80 px long, the k-th stroke 4·(k − 4) px below the centre, at its 640×360 viewport. Kept as
// fractions of the viewport so that a smaller test viewport strokes the same part of the view.
constexpr int STROKE_SEGMENTS = 16;
constexpr float STROKE_LENGTH_OF_WIDTH = 80.f / 640.f;
constexpr float STROKE_STEP_OF_HEIGHT = 4.f / 360.f;
constexpr int STROKE_ROWS = 8;
/// RenderSettings::exposureStops' default (the tone map is part of every frame).
constexpr float PREVIEW_EXPOSURE_STOPS = 2.f;

std::string utcNow(const char* format) {
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    gmtime_r(&now, &utc);
    char text[64];
    std::strftime(text, sizeof text, format, &utc);
    return text;
}

/// The live preview of the default scene, driven as app/gui/PreviewRenderer.cpp drives it: one
/// SceneRenderer for the whole run, one method instance at a time (made through the registry
/// with live = true), every frame setScene / materialChanged / cameraChanged, the method's
/// surface, its subsurface pass, and the tone map into a framebuffer of the viewport's size.
class LivePreview {
public:
    explicit LivePreview(const LiveCalibrationOptions& o)
        : m_scene(makeDefaultScene()),
          m_volume(*m_scene.objects[0].material),
          m_mesh(m_scene.objects[0].mesh),
          m_viewportW(o.viewportWidth),
          m_viewportH(o.viewportHeight) {
        // The viewport's camera (Viewport::onSceneReplaced and its frame: the scene's eye and
        // target, near and far from the orbit distance) at the render size.
        Camera& c = m_scene.camera;
        const float distance = glm::length(c.position - c.target);
        c.nearPlane = std::max(1e-3f, distance * 0.01f);
        c.farPlane = distance * 100.f + 1.f;
        c.width = std::max(1, int(std::ceil(float(m_viewportW) * o.resolutionScale)));
        c.height = std::max(1, int(std::ceil(float(m_viewportH) * o.resolutionScale)));
        m_pickCamera = c;  // picking works in viewport pixels
        m_pickCamera.width = m_viewportW;
        m_pickCamera.height = m_viewportH;
        std::vector<Light> lights = m_scene.lights;
        if (lights.size() > size_t(gpu::SceneRenderer::MAX_LIGHTS))
            lights.resize(size_t(gpu::SceneRenderer::MAX_LIGHTS));
        m_lights = cullLights(lights, m_mesh.bounds()).kept;
    }

    void create() {
        m_renderer.create(m_library);
        m_renderer.addMesh(m_mesh);
        m_renderer.setLights(m_lights);
        m_renderer.setCamera(m_scene.camera);
        gpu::DirectSettings ds = m_renderer.settings();
        ds.toneMap.exposure = std::exp2(PREVIEW_EXPOSURE_STOPS);
        ds.toneMap.curve = ToneMap::Curve::Reinhard;
        ds.reuseUnchangedPasses = true;
        m_renderer.setSettings(ds);
        m_colour = gpu::createTexture2D(GL_RGBA8, m_viewportW, m_viewportH);
        m_framebuffer = gpu::GlObject::create(gpu::GlObjectKind::Framebuffer);
        glNamedFramebufferTexture(m_framebuffer.id(), GL_COLOR_ATTACHMENT0, m_colour.id(), 0);
        if (glCheckNamedFramebufferStatus(m_framebuffer.id(), GL_FRAMEBUFFER) !=
            GL_FRAMEBUFFER_COMPLETE)
            LUCENT_THROW(GpuError, "live-cost calibration: the viewport framebuffer is incomplete");
    }

    /// Frees every GL object (context current). Idempotent.
    void destroy() {
        m_renderer.setSubsurfaceProvider(nullptr);
        dropMethod();
        m_framebuffer.destroy();
        m_colour.destroy();
        m_renderer.destroy();
    }

    /// A fresh instance of `name` (the preview makes one whenever the method changes).
    void useMethod(const std::string& name, const methods::ParamSet& params) {
        dropMethod();
        m_method = methods::create(name, params, {methods::Backend::Gl, /*live=*/true, {}});
        m_method->createGl(m_library);
        m_method->setScene(inputs());
        m_renderer.setSurfaceMaterial(0, m_method->surface());
        (void)m_volume.takeDirtyBricks();  // setScene handed over the whole volume
    }

    /// One frame with the bricks painted since the last one. @return its time, ms.
    double frame() {
        Timer t;
        m_method->setScene(inputs());  // unchanged: synchronises nothing
        const std::vector<int> dirty = m_volume.takeDirtyBricks();
        if (!dirty.empty())
            m_method->materialChanged(dirty);
        m_method->cameraChanged(m_scene.camera);
        m_renderer.setSubsurfaceProvider(m_method->subsurfacePass());
        m_renderer.renderToFramebuffer(m_framebuffer.id(), m_viewportW, m_viewportH);
        m_renderer.setSubsurfaceProvider(nullptr);
        m_renderer.profiler().collect(/*wait=*/true);  // PreviewRenderer's statistics
        glFinish();  // the frame's whole (software) rasterisation, as the viewport times it
        return t.elapsedMs();
    }

    /// Stroke number `k`: cursor samples along its line, each picked and stamped as
    /// Viewport::strokeBetween does, into one History step.
    void stroke(int k) {
        const float length = STROKE_LENGTH_OF_WIDTH * float(m_viewportW);
        const float cx = 0.5f * float(m_viewportW);
        const float y = 0.5f * float(m_viewportH) + STROKE_STEP_OF_HEIGHT * float(m_viewportH) *
                                                        float(k % STROKE_ROWS - STROKE_ROWS / 2);
        bool open = false;
        Point3f last{0.f};
        // Stamps every spacing·radius mm towards the hit, never closer than half a voxel
        // (Viewport::continueStroke).
        const float spacing =
            std::max(m_brush.spacing * m_brush.radius, 0.5f * m_volume.spec().voxelSize);
        for (int i = 0; i <= STROKE_SEGMENTS; ++i) {
            const float x = cx - 0.5f * length + length * float(i) / float(STROKE_SEGMENTS);
            Point3f origin;
            Vector3f direction;
            m_pickCamera.generateRay(x, y, origin, direction);
            const std::optional<PickHit> hit = pickMesh(m_mesh, origin, direction);
            if (!hit)
                continue;
            const Point3f target = hit->position;  // depth below the surface 0
            if (!open) {
                validateBrush(m_brush);
                m_history.beginStroke(m_volume);
                open = true;
                last = target;
                stamp(m_volume, m_brush, last, &m_history);
                continue;
            }
            for (Vector3f seg = target - last; glm::length(seg) >= spacing; seg = target - last) {
                last += glm::normalize(seg) * spacing;
                stamp(m_volume, m_brush, last, &m_history);
            }
        }
        if (!open)
            LUCENT_THROW(ValueError, "live-cost calibration: stroke ", k,
                         " misses the default scene's object (viewport ", m_viewportW, "x",
                         m_viewportH, ")");
        m_history.endStroke(m_volume);
    }

private:
    methods::SceneInputs inputs() const { return {&m_mesh, &m_volume, m_scene.eta, m_lights, 0}; }
    void dropMethod() {
        if (m_method)
            m_method->destroyGl();
        m_method.reset();
    }

    Scene m_scene;
    MaterialVolume& m_volume;
    const TriangleMesh& m_mesh;
    int m_viewportW, m_viewportH;
    Camera m_pickCamera;
    std::vector<Light> m_lights;
    BrushSettings m_brush = startingBrush();  // the Tools dock's, at mouse pressure 1
    History m_history;
    gpu::ShaderLibrary m_library;
    gpu::SceneRenderer m_renderer;
    std::unique_ptr<methods::Method> m_method;
    gpu::GlObject m_colour, m_framebuffer;
};

struct Run {
    double directFrameMs = 0.0;  ///< Direct: the median stroke frame (no stroke)
    double strokeMs = 0.0;       ///< a candidate: the median stroke → frame
    int strokes = 0;
};

void validate(const LiveCalibrationOptions& o) {
    if (o.viewportWidth < 16 || o.viewportHeight < 16 || o.viewportWidth > 16384 ||
        o.viewportHeight > 16384)
        LUCENT_THROW(ValueError,
                     "live-cost calibration: the viewport must be 16–16384 pixels a "
                     "side, got ",
                     o.viewportWidth, "x", o.viewportHeight);
    if (!(o.resolutionScale > 0.f && o.resolutionScale <= 1.f))
        LUCENT_THROW(ValueError, "live-cost calibration: resolution scale must be in (0, 1], got ",
                     o.resolutionScale);
    if (o.strokes < 1 || o.warmupStrokes < 0 || o.idleFrames < 0 || o.rounds < 1)
        LUCENT_THROW(ValueError,
                     "live-cost calibration: strokes and rounds must be ≥ 1, warm-up "
                     "strokes and idle frames ≥ 0");
}

}  // namespace

LiveCalibration calibrateLiveCosts(const LiveCalibrationOptions& o) {
    validate(o);
    const std::vector<LiveCost> entries =
        o.candidates.empty() ? defaultLiveCosts().entries : o.candidates;
    std::vector<CandidateRun> runs;  // resolved before any GL work: a bad name fails at once
    for (const LiveCost& e : entries)
        runs.push_back(resolveCandidate(e.method, e.setting));

    gpu::GlContextOptions contextOptions;
    contextOptions.debug = false;  // the app's context has no synchronous debug output either
    const std::unique_ptr<gpu::GlContext> context = gpu::GlContext::createHeadless(contextOptions);
    LivePreview preview(o);
    LiveCalibration result;
    const auto cancelled = [&o] { return o.cancel && o.cancel->load(); };
    LiveCalibrationProgress progress;
    progress.total = o.rounds * int(entries.size()) * 2;
    const auto report = [&](const std::string& next) {
        progress.next = next;
        if (o.progress)
            o.progress(progress);
    };
    int strokeNumber = 0;
    // One run: the method made afresh, its idle frames, then warm-up and timed strokes.
    // @return false when cancelled.
    const auto timeRun = [&](const std::string& method, const methods::ParamSet& params,
                             bool isDirect, Run& run) {
        preview.useMethod(method, params);
        for (int i = 0; i <= o.idleFrames; ++i) {  // the first settles (as the harness's)
            if (cancelled())
                return false;
            preview.frame();
        }
        std::vector<double> frameMs, strokeMs;
        for (int s = 0; s < o.warmupStrokes + o.strokes; ++s) {
            if (cancelled())
                return false;
            Timer t;
            preview.stroke(strokeNumber++);
            const double frame = preview.frame();
            if (s < o.warmupStrokes)
                continue;
            frameMs.push_back(frame);
            strokeMs.push_back(t.elapsedMs());
        }
        run.directFrameMs = isDirect ? medianMs(frameMs) : 0.0;
        run.strokeMs = medianMs(strokeMs);
        run.strokes = int(strokeMs.size());
        return true;
    };

    std::vector<std::vector<double>> ratios(entries.size()), strokeMs(entries.size()),
        unitMs(entries.size());
    std::vector<double> allUnits;
    std::vector<int> strokes(entries.size(), 0);
    try {
        preview.create();
        for (int round = 0; round < o.rounds && !result.cancelled; ++round)
            for (size_t i = 0; i < entries.size() && !result.cancelled; ++i) {
                const std::string label = entries[i].method + " " + entries[i].setting;
                report("direct (before " + label + ")");
                Run unit, run;
                if (!timeRun("direct", {}, true, unit)) {
                    result.cancelled = true;
                    break;
                }
                ++progress.done;
                report(label);
                if (!timeRun(runs[i].method, runs[i].params, false, run)) {
                    result.cancelled = true;
                    break;
                }
                ++progress.done;
                if (!(unit.directFrameMs > 0))
                    LUCENT_THROW(GpuError,
                                 "live-cost calibration: the Direct frame took no "
                                 "measurable time");
                ratios[i].push_back(run.strokeMs / unit.directFrameMs);
                strokeMs[i].push_back(run.strokeMs);
                unitMs[i].push_back(unit.directFrameMs);
                allUnits.push_back(unit.directFrameMs);
                strokes[i] += run.strokes;
            }
        preview.destroy();
    } catch (...) {
        preview.destroy();
        throw;
    }
    report("");
    if (result.cancelled)
        return result;

    LiveCosts& c = result.costs;
    c.directMs = medianMs(allUnits);
    c.date = utcNow("%Y-%m-%d");
    c.renderer = context->renderer();
    c.cpuThreads = int(std::thread::hardware_concurrency());
    c.source = o.command + " (headless, app default render settings, viewport " +
               std::to_string(o.viewportWidth) + "x" + std::to_string(o.viewportHeight) + " at " +
               std::to_string(int(std::lround(100 * o.resolutionScale))) + " %, " +
               context->renderer() + " — " + context->version() + ", " +
               std::to_string(c.cpuThreads) + " threads, median of " + std::to_string(o.rounds) +
               (o.rounds == 1 ? " round, " : " rounds, ") + utcNow("%Y-%m-%d %H:%M UTC") + ")";
    for (size_t i = 0; i < entries.size(); ++i) {
        LiveCalibrationRow row;
        row.cost = {entries[i].method, entries[i].setting, medianMs(ratios[i])};
        row.strokeMs = medianMs(strokeMs[i]);
        row.directMs = medianMs(unitMs[i]);
        row.roundRatios = ratios[i];
        row.strokesTimed = strokes[i];
        c.entries.push_back(row.cost);
        result.rows.push_back(std::move(row));
    }
    return result;
}

}  // namespace lucent::planner
