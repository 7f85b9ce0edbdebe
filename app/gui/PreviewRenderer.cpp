// SPDX-License-Identifier: MIT
/// @file
/// @brief PreviewRenderer: SceneRenderer + the chosen method's subsurface pass (through the
/// methods registry) + volume and brush overlays (GL via epoxy).

#include "PreviewRenderer.h"

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/gpu/Shader.h>
#include <lucent/methods/Registry.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/LevelCheck.h>
#include <lucent/planner/LiveCosts.h>
#include <lucent/scene/LightReach.h>

#include <epoxy/gl.h>

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <deque>
#include <mutex>

namespace lucent::app {

namespace {

/// Flattened light parameters, to detect changes (setLights re-renders the shadow maps).
std::vector<float> lightsKey(const std::vector<Light>& lights) {
    std::vector<float> k;
    for (const Light& l : lights)
        k.insert(k.end(), {float(int(l.type)), l.position.x, l.position.y, l.position.z,
                           l.direction.x, l.direction.y, l.direction.z, l.intensity.r,
                           l.intensity.g, l.intensity.b, l.spotOuterDeg, l.spotInnerDeg, l.radius});
    return k;
}

/// sRGB EOTF (IEC 61966-2-1), display value → linear.
float srgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

/// The volume overlay (shaders/preview_volume_overlay.frag): one R32F 3-D texture holding, per
/// voxel, the selected channel's mean over R, G, B (inside voxels) or −3·10³⁸ (outside), and
/// the channel's value range over the inside voxels, kept exact under incremental updates with
/// a per-brick minimum/maximum. Only dirty 8³ bricks are re-uploaded while the channel stays.
class VolumeOverlay {
public:
    static constexpr float OUTSIDE = -3.0e38f;

    void create(const gpu::ShaderLibrary& lib) {
        m_program =
            gpu::GlProgram::graphics(lib, "post_fullscreen.vert", "preview_volume_overlay.frag");
    }
    void destroy() {
        m_program.destroy();
        glDeleteTextures(1, &m_texture);
        m_texture = 0;
        m_resolution = 0;
        m_channel = -1;
    }

    /// Uploads the whole volume (full, new channel or size) or the given bricks.
    void sync(const MaterialVolume& vol, int channel, bool full, const std::vector<int>& dirty) {
        const int res = vol.resolution();
        constexpr int B = MaterialVolume::BRICK, BV = MaterialVolume::BRICK_VOXELS;
        std::vector<int> bricks = dirty;
        if (full || res != m_resolution || channel != m_channel || m_texture == 0) {
            if (res != m_resolution || m_texture == 0) {
                glDeleteTextures(1, &m_texture);
                glCreateTextures(GL_TEXTURE_3D, 1, &m_texture);
                glTextureStorage3D(m_texture, 1, GL_R32F, res, res, res);
                glTextureParameteri(m_texture, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
                glTextureParameteri(m_texture, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
                m_resolution = res;
            }
            m_channel = channel;
            bricks.resize(size_t(vol.brickCount()));
            for (int b = 0; b < vol.brickCount(); ++b)
                bricks[size_t(b)] = b;
            m_brickMin.assign(size_t(vol.brickCount()), INF);
            m_brickMax.assign(size_t(vol.brickCount()), -INF);
        }
        const Channel ch = channel == 1   ? Channel::SigmaS
                           : channel == 2 ? Channel::G
                                          : Channel::SigmaT;
        const size_t c0 = size_t(MaterialVolume::component(ch, 0)) * BV;
        const size_t c1 = size_t(MaterialVolume::component(ch, 1)) * BV;
        const size_t c2 = size_t(MaterialVolume::component(ch, 2)) * BV;
        std::vector<float> values;
        values.reserve(size_t(BV));
        const std::vector<uint8_t>& inside = vol.insideMask();
        // Default unpack state, whatever a provider or Qt left: client memory, tight rows.
        glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
        glPixelStorei(GL_UNPACK_IMAGE_HEIGHT, 0);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        for (int b : bricks) {
            const float* d = vol.brickData(b);
            const Coord o = vol.brickOrigin(b);
            const Coord size = glm::min(Coord(B), Coord(res) - o);
            float lo = INF, hi = -INF;
            values.clear();
            for (int z = 0; z < size.z; ++z)
                for (int y = 0; y < size.y; ++y)
                    for (int x = 0; x < size.x; ++x) {
                        const Coord c = o + Coord(x, y, z);
                        const size_t v = size_t(MaterialVolume::voxelInBrick(x, y, z));
                        float value = OUTSIDE;
                        if (inside[vol.spec().linearIndex(c)]) {
                            value = (d[c0 + v] + d[c1 + v] + d[c2 + v]) / 3.f;
                            lo = std::min(lo, value);
                            hi = std::max(hi, value);
                        }
                        values.push_back(value);
                    }
            m_brickMin[size_t(b)] = lo;
            m_brickMax[size_t(b)] = hi;
            glTextureSubImage3D(m_texture, 0, o.x, o.y, o.z, size.x, size.y, size.z, GL_RED,
                                GL_FLOAT, values.data());
        }
        m_range = {INF, -INF};
        for (size_t b = 0; b < m_brickMin.size(); ++b) {
            m_range.x = std::min(m_range.x, m_brickMin[b]);
            m_range.y = std::max(m_range.y, m_brickMax[b]);
        }
        if (m_range.x > m_range.y)
            m_range = {0.f, 0.f};  // nothing inside: as the slice view
    }

    /// Blends the overlay over `framebuffer` (the tone-mapped image). `box`: the object's box.
    void draw(unsigned framebuffer, int width, int height, const Camera& camera,
              const GridSpec& spec, const Bounds3f& box, const RenderSettings& s,
              unsigned gbufferPosition, GLuint vao) {
        glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
        glViewport(0, 0, width, height);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glEnable(GL_BLEND);
        glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        const GLuint p = m_program.id();
        glUseProgram(p);
        const auto loc = [&](const char* n) { return glGetUniformLocation(p, n); };
        const Mat4f worldFromClip =
            glm::inverse(gpu::cameraClipFromView(camera) * gpu::cameraViewFromWorld(camera));
        glUniformMatrix4fv(loc("u_worldFromClip"), 1, GL_FALSE, glm::value_ptr(worldFromClip));
        glUniform2f(loc("u_viewport"), float(width), float(height));
        glUniform3fv(loc("u_boxMin"), 1, glm::value_ptr(box.lo));
        glUniform3fv(loc("u_boxMax"), 1, glm::value_ptr(box.hi));
        glUniform3fv(loc("u_gridOrigin"), 1, glm::value_ptr(spec.origin));
        glUniform1f(loc("u_voxelSize"), spec.voxelSize);
        glUniform1i(loc("u_resolution"), spec.resolution);
        glUniform2f(loc("u_range"), m_range.x, m_range.y);
        glUniform1f(loc("u_opacity"), std::clamp(s.overlayOpacity, 0.f, 1.f));
        // One sample per voxel along the grid's diagonal at most (√3·resolution).
        glUniform1i(loc("u_maxSteps"), int(std::ceil(1.7321f * float(spec.resolution))));
        glBindTextureUnit(0, m_texture);
        glBindTextureUnit(1, gbufferPosition);
        glBindVertexArray(vao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glBindVertexArray(0);
        glBindTextureUnit(0, 0);
        glBindTextureUnit(1, 0);
        glUseProgram(0);
        glDisable(GL_BLEND);
    }

private:
    gpu::GlProgram m_program;
    GLuint m_texture = 0;
    int m_resolution = 0;
    int m_channel = -1;
    std::vector<float> m_brickMin, m_brickMax;
    glm::vec2 m_range{0.f};
};

/// Whether two cameras give the same frame.
bool sameCamera(const Camera& a, const Camera& b) {
    return a.position == b.position && a.target == b.target && a.up == b.up &&
           a.fovYDeg == b.fovYDeg && a.width == b.width && a.height == b.height;
}

}  // namespace

std::string PreviewStats::methodStat(const std::string& key) const {
    for (const methods::Stat& s : methodStats)
        if (s.key == key)
            return s.value;
    return {};
}

struct PreviewRenderer::Impl {
    gpu::ShaderLibrary library;
    gpu::SceneRenderer renderer;
    /// The active method (Gl backend, live) and what it was made for.
    std::unique_ptr<methods::Method> method;
    methods::ParamSet methodParams;  ///< the values last given to method->setParams
    /// Set until the method's first frame: setScene hands it the whole volume, so that frame's
    /// dirty bricks are not handed over a second time.
    bool methodFresh = false;
    VolumeOverlay overlay;
    bool overlaySynced = false;
    gpu::GlProgram cursor;
    GLuint emptyVao = 0;
    bool created = false;
    bool meshUploaded = false;
    bool surfaceSet = false;  ///< setSurfaceMaterial done for the active method
    std::vector<float> lights;
    PreviewStats stats;
    /// Auto: the last choice and what it was planned for.
    struct AutoState {
        bool valid = false;
        planner::AutoChoice choice;
        double directMs = 0.0;  ///< the Direct frame's render at directWidth × directHeight
        int directWidth = 0, directHeight = 0;
        /// Render times of the Direct frames shown while measuring (the first after a change
        /// builds shadow maps and G-buffer and is not counted), and for which size.
        std::vector<double> directSamples;
        int samplesWidth = 0, samplesHeight = 0;
        double pinnedDirectMs = 0.0;  ///< > 0: plan with this, time nothing
        bool measuring = false;       ///< this frame renders Direct to time it
        bool stale = true;            ///< the scene changed since the last plan
        Camera camera;                ///< the frame planned for
        std::vector<float> lights;    ///< lightsKey of the frame planned for
        float eta = 0.f;
        Timer sincePlan;
        /// setMeasuredModels: plan with these while `measuredHold` allows (null: liveModels()),
        /// ties within `measuredMargin` (the reference's noise).
        std::shared_ptr<const planner::Models> measured;
        double measuredMargin = 0.0;
        MeasuredHold measuredHold = MeasuredHold::ThisView;
        const LiveCostTable* liveCosts = nullptr;  ///< the table the last plan used
        bool planMeasured = false;                 ///< the current choice was made with `measured`
        /// The planner's pick before a level decision applied (`choice` after it); the next
        /// plan's hysteresis compares with this, so a decision never feeds a further step down.
        planner::AutoChoice planned;
        /// Level decisions (setAutoLevelDecision), one per method and planned level.
        std::vector<AutoLevelDecision> levels;
        /// The models `planned` was chosen from: the measured ones (shared), or the live table's
        /// (not owned: a table lives for the process's life, liveCostTable()).
        std::shared_ptr<const planner::Models> plannedWith;
    } autoPlan;

    /// The decision held for `planned` (one at most), or null.
    const AutoLevelDecision* levelDecisionFor(const planner::AutoChoice& planned) const {
        for (const AutoLevelDecision& d : autoPlan.levels)
            if (d.method == planned.candidate() && d.planned == planned.setting &&
                d.sceneClass == planned.plan.sceneClass)
                return &d;
        return nullptr;
    }

    /// autoPlan.choice: the planned pick, at the level a decision for it keeps (none when the
    /// plan used errors measured against a reference: they tell the levels apart already).
    void applyLevelDecisions() {
        AutoState& a = autoPlan;
        if (!a.valid || !a.plannedWith)
            return;
        a.choice = a.planned;
        if (a.planMeasured)
            return;
        if (const AutoLevelDecision* d = levelDecisionFor(a.planned)) {
            planner::LevelCheck check;
            check.setting = d->kept;
            check.note = d->note;
            planner::applyLevelCheck(a.choice, *a.plannedWith, check);
        }
    }

    /// One frame (PreviewRenderer::render).
    void renderFrame(PreviewFrame& f);
    /// The instance of `name` with `params`: the active one (new parameters applied), or a new
    /// one (the old one's GL objects freed) when the name differs or none is active.
    methods::Method& useMethod(const std::string& name, const methods::ParamSet& params);
    /// Frees the active method's GL objects and forgets it (the next frame makes it afresh).
    void dropMethod();
    /// Auto: the planner's choice for frame `f` (re-planned when the scene changed, at most
    /// every AUTO_REPLAN_MS), or nullptr while the Direct frame it needs is being measured
    /// (the frame then renders Direct and renderFrame times it).
    /// @throw ValueError when no candidate can render the scene.
    /// `lights`: the frame's lights after the light skip, `lightKey` their lightsKey.
    const planner::AutoChoice* planAuto(const PreviewFrame& f, const std::vector<Light>& lights,
                                        const std::vector<float>& lightKey);
};

PreviewRenderer::PreviewRenderer() : m(std::make_unique<Impl>()) {}

PreviewRenderer::~PreviewRenderer() = default;

bool PreviewRenderer::isCreated() const {
    return m->created;
}

void PreviewRenderer::create() {
    destroy();
    m->created = true;  // so that destroy() frees what was made if a program fails below
    try {
        m->renderer.create(m->library);
        m->overlay.create(m->library);
        m->cursor = gpu::GlProgram::graphics(m->library, "post_fullscreen.vert",
                                             "preview_brush_cursor.frag");
        glCreateVertexArrays(1, &m->emptyVao);
    } catch (...) {
        destroy();
        throw;
    }
    m->meshUploaded = m->surfaceSet = m->overlaySynced = false;
    m->lights.clear();
}

void PreviewRenderer::destroy() {
    if (!m->created)
        return;
    m->renderer.setSubsurfaceProvider(nullptr);
    m->dropMethod();
    m->renderer.destroy();
    m->overlay.destroy();
    m->overlaySynced = false;
    m->cursor.destroy();
    glDeleteVertexArrays(1, &m->emptyVao);
    m->emptyVao = 0;
    m->created = false;
}

bool PreviewRenderer::wantsAnotherFrame() const {
    return m->created && ((m->method && !m->method->converged()) || isPlanning());
}

namespace {

/// Every table installed in this process, the current one last. Kept to exit (each a few kB; a
/// calibration is a rare manual act) so that a reference handed out stays valid on any thread.
struct LiveCostTables {
    std::mutex mutex;
    std::deque<LiveCostTable> all;
    std::atomic<const LiveCostTable*> current{nullptr};

    LiveCostTables() {  // the shipped table until useLiveCosts installs another
        planner::LiveCostsInUse shipped;
        shipped.costs = planner::defaultLiveCosts();
        add(shipped);
    }

    const LiveCostTable& add(const planner::LiveCostsInUse& inUse) {
        const std::lock_guard lock(mutex);
        LiveCostTable& t = all.emplace_back();
        t.inUse = inUse;
        t.models = planner::liveModels(planner::defaultModels(), inUse.costs);
        t.label = planner::describeLiveCosts(inUse);
        current = &t;  // deque::emplace_back keeps references to the others valid
        return t;
    }
};

LiveCostTables& liveCostTables() {
    static LiveCostTables tables;
    return tables;
}

}  // namespace

const LiveCostTable& PreviewRenderer::liveCostTable() {
    return *liveCostTables().current.load();
}

const planner::Models& PreviewRenderer::liveModels() {
    return liveCostTable().models;
}

void PreviewRenderer::useLiveCosts(const planner::LiveCostsInUse& inUse) {
    liveCostTables().add(inUse);
}

void PreviewRenderer::setMeasuredModels(std::shared_ptr<const planner::Models> models,
                                        double errorMargin, MeasuredHold hold) {
    LUCENT_CHECK(!models || models->candidates.size() == liveModels().candidates.size(),
                 "measured models must have the live candidates (", liveModels().candidates.size(),
                 "), got ", models ? models->candidates.size() : 0);
    LUCENT_CHECK(errorMargin >= 0 && std::isfinite(errorMargin),
                 "the measured errors' margin must be finite and >= 0, got ", errorMargin);
    m->autoPlan.measured = std::move(models);
    m->autoPlan.measuredMargin = errorMargin;
    m->autoPlan.measuredHold = hold;
    m->autoPlan.planMeasured = false;
    // Plan again at the next frame, from scratch: the measurements replace the predictions,
    // and hysteresis would keep a choice made on predictions.
    m->autoPlan.valid = false;
}

bool PreviewRenderer::usesMeasuredModels() const {
    return m->autoPlan.valid && m->autoPlan.planMeasured;
}

bool PreviewRenderer::hasMeasuredModels() const {
    return m->autoPlan.measured != nullptr;
}

PreviewRenderer::MeasuredHold PreviewRenderer::measuredHold() const {
    return m->autoPlan.measuredHold;
}

const planner::AutoChoice* PreviewRenderer::autoChoice() const {
    return m->autoPlan.valid ? &m->autoPlan.choice : nullptr;
}

const planner::AutoChoice* PreviewRenderer::autoPlannedChoice() const {
    return m->autoPlan.valid ? &m->autoPlan.planned : nullptr;
}

void PreviewRenderer::setAutoLevelDecision(const AutoLevelDecision& decision) {
    std::vector<AutoLevelDecision>& levels = m->autoPlan.levels;
    std::erase_if(levels, [&](const AutoLevelDecision& d) {
        return d.method == decision.method && d.planned == decision.planned &&
               d.sceneClass == decision.sceneClass;
    });
    levels.push_back(decision);
    m->applyLevelDecisions();  // the next frame renders with it
}

void PreviewRenderer::clearAutoLevelDecisions() {
    m->autoPlan.levels.clear();
    m->applyLevelDecisions();
}

bool PreviewRenderer::hasAutoLevelDecisionFor(const planner::AutoChoice& planned) const {
    return m->levelDecisionFor(planned) != nullptr;
}

double PreviewRenderer::autoDirectMs() const {
    return m->autoPlan.directMs;
}

bool PreviewRenderer::isPlanning() const {
    return m->autoPlan.measuring;
}

void PreviewRenderer::pinAutoDirectMs(double ms) {
    LUCENT_CHECK(ms >= 0 && std::isfinite(ms), "pinAutoDirectMs: ", ms, " ms");
    m->autoPlan.pinnedDirectMs = ms;
    m->autoPlan.directMs = 0.0;  // plan again with it
    m->autoPlan.valid = false;
}

bool PreviewRenderer::isPreviewMethod(const std::string& name) {
    return methods::exists(name) && methods::find(name).caps.gl;
}

std::vector<const methods::MethodInfo*> PreviewRenderer::previewMethods() {
    std::vector<const methods::MethodInfo*> out;
    for (const methods::MethodInfo* info : methods::all())
        if (info->caps.gl)
            out.push_back(info);
    return out;
}

gpu::ShaderLibrary& PreviewRenderer::shaderLibrary() {
    return m->library;
}

const PreviewStats& PreviewRenderer::stats() const {
    return m->stats;
}

ImageRgb PreviewRenderer::linearImage() const {
    LUCENT_CHECK(m->created, "PreviewRenderer::linearImage before create()");
    return m->renderer.readRadiance();
}

void PreviewRenderer::render(PreviewFrame& f) {
    LUCENT_CHECK(m->created, "PreviewRenderer::render before create()");
    try {
        m->renderFrame(f);
    } catch (...) {
        // The failed frame's method may be half-updated: the next frame that uses it builds it
        // again from the scene (a full material, mesh and light sync).
        m->renderer.setSubsurfaceProvider(nullptr);
        m->dropMethod();
        m->overlaySynced = false;
        throw;
    }
}

void PreviewRenderer::Impl::dropMethod() {
    if (method)
        method->destroyGl();
    method.reset();
    surfaceSet = false;
}

methods::Method& PreviewRenderer::Impl::useMethod(const std::string& name,
                                                  const methods::ParamSet& params) {
    if (method && method->info().name == name) {
        if (params.toString() != methodParams.toString()) {
            method->setParams(params);  // the method decides what a change restarts
            methodParams = params;
        }
        return *method;
    }
    dropMethod();
    LUCENT_CHECK(isPreviewMethod(name), "'", name, "' is not a preview method (no GL pass)");
    std::unique_ptr<methods::Method> made =
        methods::create(name, params, {methods::Backend::Gl, /*live=*/true, {}});
    made->createGl(library);
    method = std::move(made);
    methodParams = params;
    methodFresh = true;
    return *method;
}

const planner::AutoChoice* PreviewRenderer::Impl::planAuto(const PreviewFrame& f,
                                                           const std::vector<Light>& lights,
                                                           const std::vector<float>& lightKey) {
    // Re-plan at most twice a second: a stroke or an orbit changes the features a little every
    // frame, and the hysteresis keeps the choice anyway unless the scene class changes.
    constexpr double AUTO_REPLAN_MS = 500.0;
    AutoState& a = autoPlan;
    // Direct frames of this size timed before a plan: its render time is the unit of the live
    // costs (planner/LiveCosts.h), measured here on the viewport's own context and passes, as
    // the app's latency harness measures it: the median, the statistic the harness divides by
    // (the fastest of three read 10–15 % lower, which let SSLPV 64³ at 64 ms "fit" 50 ms); the
    // first frame is not counted (it builds shadow maps and the G-buffer). Nine frames, not
    // three: right after start one frame in three or four takes 1.3–2× the others, and the
    // median of three read the default scene's unit anywhere from 4.9 to 7.3 ms in six starts
    // on the idle box, so Auto's pick there changed from start to start (docs/planner.md).
    constexpr size_t DIRECT_SAMPLES = 9;
    a.measuring = false;
    if (f.sceneReplaced) {  // another mesh: another Direct frame, and no choice to keep
        a.directMs = 0.0;
        a.directSamples.clear();
        a.valid = false;
        a.levels.clear();  // checked on another scene
    }
    const LiveCostTable& table = PreviewRenderer::liveCostTable();
    if (a.liveCosts != &table) {  // other live costs: plan from scratch with them
        a.liveCosts = &table;
        a.valid = false;
        a.measured.reset();  // measured errors sit in a copy of the old live models
    }
    const bool otherScene = f.sceneReplaced || lightKey != a.lights || f.scene->eta != a.eta;
    if (otherScene || !f.dirtyBricks.empty() || !sameCamera(f.camera, a.camera)) {
        a.stale = true;
        // Measured on a scene (or view) that is no longer shown. Auto's own measurement holds
        // through paint and orbits (it measures again once the artist pauses).
        if (otherScene || a.measuredHold == MeasuredHold::ThisView)
            a.measured.reset();
    }
    const bool sized =
        a.directMs > 0.0 && a.directWidth == f.camera.width && a.directHeight == f.camera.height;
    if (sized && a.valid && (!a.stale || a.sincePlan.elapsedMs() < AUTO_REPLAN_MS) &&
        !f.sceneReplaced)
        return &a.choice;
    if (!sized && a.pinnedDirectMs > 0) {
        a.directMs = a.pinnedDirectMs;
        a.directWidth = f.camera.width;
        a.directHeight = f.camera.height;
    } else if (!sized) {
        if (a.samplesWidth != f.camera.width || a.samplesHeight != f.camera.height) {
            a.directSamples.clear();
            a.samplesWidth = f.camera.width;
            a.samplesHeight = f.camera.height;
        }
        if (a.directSamples.size() < DIRECT_SAMPLES + 1) {
            a.measuring = true;  // renderFrame renders Direct and appends its time
            return nullptr;
        }
        a.directMs = medianMs({a.directSamples.begin() + 1, a.directSamples.end()});
        a.directWidth = a.samplesWidth;
        a.directHeight = a.samplesHeight;
        a.directSamples.clear();
    }
    Scene scene = *f.scene;  // the viewport's camera and lights: the features see them
    scene.camera = f.camera;
    scene.lights = lights;
    planner::Budget budget;  // the planner's live frame budget (50 ms) and hysteresis
    budget.directMs = a.directMs;
    if (a.measured)  // errors closer than the reference's noise cannot be told apart
        budget.errorMargin = a.measuredMargin;
    // A headless calibration's ratios leave out the app's own share of a frame (event loop,
    // swap): add what this viewport measures (docs/planner.md, "Calibrating on this machine").
    if (!table.inUse.costs.hostIncluded)
        budget.hostMs = std::max(0.0, f.hostMs);
    // The previous plan of the same scene, for hysteresis (a new scene plans from scratch):
    // the pick before any level decision.
    const planner::Plan previous = a.planned.plan;
    const bool hasPrevious = a.valid && !f.sceneReplaced;
    const planner::Models& models = a.measured ? *a.measured : table.models;
    a.choice = planner::chooseMethod(scene, models, budget, /*glAvailable=*/true,
                                     hasPrevious ? &previous : nullptr, methods::Backend::Gl);
    a.planned = a.choice;
    a.plannedWith = a.measured ? a.measured
                               : std::shared_ptr<const planner::Models>(
                                     std::shared_ptr<const planner::Models>(), &table.models);
    a.planMeasured = a.measured != nullptr;
    a.valid = true;
    applyLevelDecisions();
    a.stale = false;
    a.camera = f.camera;
    a.lights = lightKey;
    a.eta = f.scene->eta;
    a.sincePlan.reset();
    return &a.choice;
}

void PreviewRenderer::Impl::renderFrame(PreviewFrame& f) {
    Timer frameTimer;  // Auto's Direct frame measurement
    Impl& r = *this;
    const RenderSettings& s = f.settings;
    gpu::SceneRenderer& sr = r.renderer;
    sr.setSubsurfaceProvider(nullptr);
    if (f.sceneReplaced) {
        sr.clearMeshes();
        // The method holds the old scene's volume: a new instance synchronises the new one.
        r.dropMethod();
        r.meshUploaded = r.overlaySynced = false;
        r.lights.clear();
    }
    const bool haveMesh = f.shownMesh && !f.shownMesh->isEmpty();
    bool geometryChanged = false;
    if (haveMesh && !r.meshUploaded) {
        sr.addMesh(*f.shownMesh);
        r.meshUploaded = true;
    } else if (haveMesh && f.meshChanged) {
        sr.updateMesh(0, *f.shownMesh);
        geometryChanged = true;  // the G-buffer changed without a camera/light/material change
    }
    std::vector<Light> lights = f.scene->lights;
    if (lights.size() > size_t(gpu::SceneRenderer::MAX_LIGHTS))
        lights.resize(size_t(gpu::SceneRenderer::MAX_LIGHTS));
    // Lights that miss the shown mesh or give it less than LIGHT_SKIP_EPSILON of the strongest
    // light's irradiance cost shadow maps and the method's per-light work for nothing.
    LightCulling culling = cullLights(lights, haveMesh ? f.shownMesh->bounds() : Bounds3f{});
    lights = std::move(culling.kept);
    r.stats.skippedLights = std::move(culling.skipped);
    std::vector<float> key = lightsKey(lights);
    if (key != r.lights) {
        sr.setLights(lights);
        r.lights = key;
    }
    sr.setCamera(f.camera);
    gpu::DirectSettings ds = sr.settings();
    ds.toneMap.exposure = std::exp2(s.exposureStops);
    ds.toneMap.curve = ToneMap::Curve::Reinhard;
    ds.reuseUnchangedPasses = s.reusePasses;
    ds.subsurfaceOnly = s.subsurfaceOnly;
    // Background: the radiance that displays as the app's dark grey (0.16, 0.17, 0.19) after
    // this tone map (inverse sRGB OETF, inverse Reinhard c/(1+c), divided by the exposure).
    const auto bg = [&](float display) {
        const float lin = srgbToLinear(display);
        return lin / (1.f - lin) / ds.toneMap.exposure;
    };
    ds.background = Rgb(bg(0.16f), bg(0.17f), bg(0.19f));
    sr.setSettings(ds);

    // The method: the chosen one when there is an object to render, else the opaque surface.
    // Its scene inputs each frame (it re-synchronises only what changed), then the dirty bricks.
    Timer uploadTimer;
    MaterialVolume* vol = f.volume;
    const bool dirty = !f.dirtyBricks.empty();
    const bool canRender = haveMesh && vol;
    std::string name = canRender ? s.method : std::string("direct");
    methods::ParamSet params = canRender ? s.params : methods::ParamSet();
    r.stats.autoReason.clear();
    r.stats.autoChoice.clear();
    r.stats.liveCosts.clear();
    if (name == AUTO_METHOD) {
        if (const planner::AutoChoice* choice = r.planAuto(f, lights, key)) {
            name = choice->method;
            params = choice->params;
            const char* measured = !r.autoPlan.planMeasured ? ""
                                   : r.autoPlan.measuredHold == MeasuredHold::ThisScene
                                       ? "errors measured on this scene: "
                                       : "errors measured on this view: ";
            r.stats.autoReason = measured + choice->plan.reason;
            r.stats.liveCosts = r.autoPlan.liveCosts ? r.autoPlan.liveCosts->label : "";
            r.stats.autoChoice = choice->method +
                                 (choice->variant.empty() ? "" : ":" + choice->variant) + " " +
                                 choice->setting;
        } else {  // the plan waits for the Direct frame's measurement: Direct meanwhile
            name = "direct";
            params = {};
        }
    } else {
        r.autoPlan.valid = false;  // Auto chosen again later: plan afresh
        r.autoPlan.measuring = false;
    }
    const bool changedMethod = !r.method || r.method->info().name != name;
    methods::Method& method = r.useMethod(name, params);
    int bricksUsed = 0;
    if (canRender) {
        methods::SceneInputs in;
        in.mesh = &f.scene->objects[0].mesh;  // rest space (SSLPV's grid lives there)
        in.material = vol;
        in.eta = f.scene->eta;
        in.lights = lights;
        in.meshId = 0;  // object 0: the only mesh uploaded
        method.setScene(in);
        if (r.methodFresh) {
            bricksUsed = vol->brickCount();  // setScene handed over the whole volume
        } else if (dirty) {
            method.materialChanged(f.dirtyBricks);
            bricksUsed = int(f.dirtyBricks.size());
        }
        if (geometryChanged && !r.methodFresh)
            method.geometryChanged();
        method.cameraChanged(f.camera);
    }
    r.methodFresh = false;
    if (haveMesh && (changedMethod || !r.surfaceSet)) {
        // The method's surface in the direct pass: none for a translucent object whatever η
        // (methods::translucentSurface), Direct's opaque grey otherwise.
        sr.setSurfaceMaterial(0, method.surface());
        r.surfaceSet = true;
    }
    const double uploadMs = uploadTimer.elapsedMs();
    if (bricksUsed > 0) {
        r.stats.bricksUploaded = bricksUsed;
        r.stats.uploadMs = uploadMs;
    }

    sr.setSubsurfaceProvider(method.subsurfacePass());
    sr.renderToFramebuffer(f.framebuffer, f.framebufferWidth, f.framebufferHeight);
    sr.setSubsurfaceProvider(nullptr);
    if (r.autoPlan.measuring && name == "direct") {
        glFinish();  // the frame's whole (software) rasterisation, as the harness times it
        r.autoPlan.directSamples.push_back(frameTimer.elapsedMs());
    }
    const gpu::PassReuseCounters& reuse = sr.reuseCounters();
    r.stats.shadowsReused = reuse.shadowsReused;
    r.stats.gbufferReused = reuse.gbufferReused;
    r.stats.directReused = reuse.directReused;

    // Volume overlay over the tone-mapped image (its own brick sync: the dirty bricks of this
    // frame, or everything when it was off while the volume changed).
    if (dirty && !s.volumeOverlay)
        r.overlaySynced = false;
    if (s.volumeOverlay && haveMesh && vol) {
        const int channel = std::clamp(s.overlayChannel, 0, 2);
        r.overlay.sync(*vol, channel, !r.overlaySynced, f.dirtyBricks);
        r.overlaySynced = true;
        Bounds3f box = vol->spec().bounds();
        const Bounds3f meshBox = f.shownMesh->bounds();
        box.lo = glm::max(box.lo, meshBox.lo);
        box.hi = glm::min(box.hi, meshBox.hi);
        if (!box.isEmpty())
            r.overlay.draw(f.framebuffer, f.framebufferWidth, f.framebufferHeight, f.camera,
                           vol->spec(), box, s, sr.gbuffer().positionTexture, r.emptyVao);
    }

    // Brush cursor over the tone-mapped image.
    if (f.cursor && f.brushRadius > 0.f && haveMesh) {
        glBindFramebuffer(GL_FRAMEBUFFER, f.framebuffer);
        glViewport(0, 0, f.framebufferWidth, f.framebufferHeight);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glEnable(GL_BLEND);
        glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        glUseProgram(r.cursor.id());
        glUniform4f(r.cursor.uniformLocation("u_brush"), f.cursor->x, f.cursor->y, f.cursor->z,
                    f.brushRadius);
        glBindTextureUnit(0, sr.gbuffer().positionTexture);
        glBindVertexArray(r.emptyVao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glBindVertexArray(0);
        glUseProgram(0);
        glDisable(GL_BLEND);
    }

    // Statistics of this frame: the caller finishes the frame anyway (the viewport calls
    // glFinish), so waiting for the timer queries here costs nothing and shows the passes of
    // the frame just drawn instead of one or two frames back.
    sr.profiler().collect(/*wait=*/true);
    r.stats.passes.clear();
    for (const gpu::PassTiming& t : sr.profiler().latest())
        r.stats.passes.push_back({t.name, t.gpuMs, t.cpuMs});
    r.stats.method = name;
    r.stats.methodStats = method.stats();
}

}  // namespace lucent::app
