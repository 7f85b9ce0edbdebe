// SPDX-License-Identifier: MIT
/// @file
/// @brief GL side of dipole::DipoleSubsurfaceProvider: material volume upload (per brick),
/// irradiance pass (shaders/dipole_irradiance.comp), progressive gather and resolve
/// (shaders/dipole_provider.comp).

#include <lucent/dipole/DipoleProvider.h>

#include "VolumeTextures.h"

#include <lucent/core/Error.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/Shader.h>
#include <lucent/material/MaterialVolume.h>

#include <epoxy/gl.h>
#include <shared/DipoleShared.h>
#include <shared/LightingShared.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

namespace lucent::dipole {

GatherSettings ProviderSettings::gatherSettings() const {
    GatherSettings gs;
    gs.model = model;
    gs.eta = eta;
    gs.uniformSamples = samplesPerFrame / 4;
    gs.importanceSamples = samplesPerFrame - gs.uniformSamples;
    gs.discQuantile = discQuantile;
    gs.maxRadius = maxRadius;
    gs.jacobian = jacobian;
    gs.maxJacobian = maxJacobian;
    gs.interleave = interleave;
    gs.seed = seed;
    return gs;
}

namespace {

void validateSettings(const ProviderSettings& s) {
    LUCENT_CHECK(s.model == Model::Dipole || s.model == Model::BetterDipole,
                 "ProviderSettings.model: only dipole and better-dipole run in image space (got ",
                 modelName(s.model), ")");
    detail::validateProgressiveSettings("ProviderSettings", s.eta, s.samplesPerFrame, s.maxFrames,
                                        s.convergenceThreshold, s.meshId);
    LUCENT_CHECK(s.discQuantile > 0.f && s.discQuantile < 1.f,
                 "ProviderSettings.discQuantile must be in (0, 1)");
    LUCENT_CHECK(std::isfinite(s.maxRadius) && s.maxRadius >= 0.f,
                 "ProviderSettings.maxRadius must be finite and >= 0 mm (0 = unlimited; got ",
                 s.maxRadius, ")");
    LUCENT_CHECK(std::isfinite(s.maxJacobian) && s.maxJacobian >= 1.f,
                 "ProviderSettings.maxJacobian must be finite and >= 1");
    LUCENT_CHECK(s.interleave >= 1 && s.interleave <= 64,
                 "ProviderSettings.interleave must be in [1, 64]");
    LUCENT_CHECK(s.lightViewResolution >= 16 && s.lightViewResolution <= 4096,
                 "ProviderSettings.lightViewResolution must be in [16, 4096] (got ",
                 s.lightViewResolution, ")");
    LUCENT_CHECK(std::isfinite(s.lightViewThreshold) && s.lightViewThreshold >= 0.f &&
                     s.lightViewThreshold < 1.f,
                 "ProviderSettings.lightViewThreshold must be in [0, 1) (got ",
                 s.lightViewThreshold, ")");
    LUCENT_CHECK(s.previewSamples >= 0 && s.previewSamples <= 4096,
                 "ProviderSettings.previewSamples must be in [0, 4096] (got ", s.previewSamples,
                 ")");
}

bool sameSettings(const ProviderSettings& a, const ProviderSettings& b) {
    return a.model == b.model && a.eta == b.eta && a.samplesPerFrame == b.samplesPerFrame &&
           a.maxFrames == b.maxFrames && a.convergenceThreshold == b.convergenceThreshold &&
           a.discQuantile == b.discQuantile && a.maxRadius == b.maxRadius &&
           a.jacobian == b.jacobian && a.maxJacobian == b.maxJacobian &&
           a.interleave == b.interleave && a.seed == b.seed && a.shadows == b.shadows &&
           a.meshId == b.meshId && a.lightViews == b.lightViews &&
           a.lightViewResolution == b.lightViewResolution &&
           a.lightViewThreshold == b.lightViewThreshold;  // preview settings: no restart
}

/// The camera of a G-buffer as a view (clip matrix, centre of projection, orthographic flag and
/// the direction it looks): an orthographic clip matrix has a constant w row.
struct CameraView {
    Mat4f clip{1.f};
    Point3f eye{0.f};
    bool ortho = false;
    Vector3f forward{0.f, 0.f, -1.f};
};

CameraView cameraView(const gpu::GBufferView& g) {
    CameraView v;
    v.clip = g.clipFromWorld;
    const Mat4f worldFromView = glm::inverse(g.viewFromWorld);
    const Mat4f clipFromView = g.clipFromWorld * worldFromView;
    v.ortho = std::abs(clipFromView[2][3]) < 1e-6f;
    v.forward = glm::normalize(-Vector3f(worldFromView[2]));
    v.eye = g.cameraPosition;
    return v;
}

/// The scene light a GpuLight was made from, as far as the light-view camera needs it (sphere
/// lights arrive as points).
Light sceneLight(const gpu::shared::GpuLight& gl) {
    Light l;
    const int type = int(gl.positionType.w + 0.5f);
    l.type = type == LUCENT_LIGHT_DIRECTIONAL ? Light::Type::Directional
             : type == LUCENT_LIGHT_SPOT      ? Light::Type::Spot
                                              : Light::Type::Point;
    l.position = Point3f(gl.positionType);
    l.direction = Vector3f(gl.directionCosOuter);
    return l;
}

/// Work (pixels × samples × (1 + gathered views)) of one part of an interactive frame: a 16-spp
/// camera-only frame at 320×180, the app's default render size (docs/methods/dipole.md §3c).
constexpr double INTERACTIVE_PART_WORK = 320.0 * 180.0 * 16.0;

/// std430 element of dipole_provider.comp's LightViewBlock.
struct GpuLightView {
    glm::mat4 clipFromWorld;
    glm::vec4 eyeOrtho;
    glm::vec4 viewDir;
};
static_assert(sizeof(GpuLightView) == 96, "std430 LightView stride");

/// Seed of frame f's Cranley–Patterson table: frame 0 uses the settings' seed (so it equals the
/// CPU gather), later frames a Weyl step of it (independent tables through Pcg32's seeding). It
/// also seeds the per-pixel shifts of frames ≥ 1 (dipole_provider.comp, u_pixelShifts).
uint32_t frameSeed(uint32_t seed, int frame) {
    return seed + 0x9E3779B9u * uint32_t(frame);
}

/// Seed of the c-th catch-up frame since create() (material-only restarts): a stream apart from
/// frameSeed's, so that a restarted pixel never repeats the samples it was given before.
uint32_t catchUpSeed(uint32_t seed, uint32_t c) {
    return ~seed + 0x85EBCA6Bu * (c + 1u);
}

/// dipole_material_update.comp's UpdateBlock: four count words, then the list.
constexpr size_t UPDATE_HEADER_WORDS = 4;
enum UpdateWord { LISTED = 0, RESTARTED = 1, MIN_FRAMES = 2 };

}  // namespace

struct DipoleSubsurfaceProvider::Impl {
    Impl(ProviderStats& st, detail::VolumeTextures& v) : stats(st), volume(v) {}
    ProviderSettings settings;
    ProviderStats& stats;            ///< the base class's
    detail::VolumeTextures& volume;  ///< the material, 3-D textures (the base class's)
    gpu::GlProgram irradianceProgram, gatherProgram;
    /// dipole_provider.comp with MULTI_VIEW=0: the camera-only gather (no light view gathered),
    /// without the view-combination code, which slows the whole loop ≈ 2× on llvmpipe.
    gpu::GlProgram cameraGatherProgram;
    /// dipole_provider.comp with RESOLVE_ONLY=1: the stored mean only, no gather code.
    gpu::GlProgram resolveProgram;
    /// dipole_material_update.comp: material-only restarts (docs/methods/dipole.md §3c): with
    /// SCAN=1 the pass over every pixel that lists the ones to look up, without it the look-up
    /// over that list.
    gpu::GlProgram materialScanProgram, materialUpdateProgram;
    gpu::GlObject reachBuffer;  ///< the bricks the look-up must read again (bindReachedBricks)
    size_t reachBufferBytes = 0;
    std::vector<uint32_t> reached;

    // Per-pixel images (renderer size).
    int width = 0, height = 0;
    gpu::GlObject irradiance, sigmaT, sigmaS, accum;
    gpu::GlObject shiftBuffer, statsBuffer, radiusBuffer;
    gpu::GlObject updateBuffer;  ///< UpdateBlock: counts + one word per pixel
    gpu::GlObject lookupBuffer;  ///< LookupBlock: count + one word per pixel

    // Material-only restarts (docs/methods/dipole.md §3c): a material change restarts only the
    // pixels whose material changed, which then catch up to the others' frame count.
    bool needMaterialUpdate = false;
    int listed = 0;              ///< pixels in the catch-up list
    int catchUpLevel = 0;        ///< frames the listed pixels catch up to
    int catchUpLeft = 0;         ///< catch-up frames still to run (0: none pending)
    uint32_t catchUpFrames = 0;  ///< catch-up frames run since create() (their seeds)
    /// The whole-image accumulation's own convergence (stats.converged is also false while
    /// restarted pixels catch up).
    bool imageConverged = false;

    // Light views (Mertens et al. 2005 §7.1): scratch images of one view, then the gathered views
    // as layers of three arrays, with their cameras and descriptors (LightViewBlock).
    gpu::GlProgram lightGbufferProgram, lightStatsProgram;
    /// dipole_irradiance.comp with LIGHT_VIEW=1: E only (no material, no R′).
    gpu::GlProgram lightIrradianceProgram;
    gpu::GlObject fbo, viewBuffer, partialBuffer;
    int lvSize = 0, lvLayers = 0;
    gpu::GlObject lvPosition, lvNormal, lvIrradiance;  // 2-D arrays, layer l = light l's view
    gpu::GlObject scratchPosition, scratchNormal, scratchE, scratchDepth;

    /// Light l's view (layer l). Kept while `lvKey` (what the views depend on) is unchanged.
    struct ViewSlot {
        bool done = false;      ///< rendered (or found impossible) for the current key
        bool rendered = false;  ///< has a view (false: light inside the bounding sphere)
        Camera camera;
        Mat4f clip{1.f};
    };
    std::vector<ViewSlot> lvSlots;
    std::vector<int> lvGathered;  ///< layers gathered (back-lit fraction > threshold), in order
    /// What the light views depend on: meshes (revisions, geometry), lights, shadow maps and the
    /// view settings — neither the camera nor the material (docs/methods/dipole.md §3d).
    struct ViewKey {
        std::vector<unsigned char> lights;
        std::vector<uint64_t> meshes;
        unsigned shadowMaps = 0;
        bool shadows = false;
        float eta = 0.f;
        int resolution = 0, meshId = -2;
        bool operator==(const ViewKey&) const = default;
    };
    ViewKey lvKey;
    bool lvKeyValid = false;
    /// The back-lit fractions and the gathered set are up to date for this accumulation (else
    /// the camera-only estimator is accumulated, §3c "Bounded restarts").
    bool viewsReady = false;
    bool everRendered = false;  ///< a frame was drawn since create(): restarts are interactive
    /// This accumulation began with an interactive restart: frames with light views are
    /// split into 1 + views parts (one dispatch per provider frame, ProviderStats::frameParts).
    bool interactiveAccum = false;
    int part = 0;               ///< next part of the current frame
    bool viewWorkDone = false;  ///< the last updateViews() rendered a view or the fractions

    // GPU timestamps of the passes (ProviderStats::passMs), resolved at the end of a frame.
    std::vector<gpu::GlObject> timerQueries;
    std::vector<std::pair<size_t, float*>> pendingTimes;  ///< (begin query, output)
    size_t nextQuery = 0;

    // What the accumulation was computed for.
    bool needReset = true;
    Mat4f lastClip{0.f};
    Point3f lastEye{0.f};
    std::vector<unsigned char> lastLights;
    bool lastShadows = false;
    std::vector<uint64_t> lastMeshes;

    void destroyImages() {
        for (gpu::GlObject* o :
             {&irradiance, &sigmaT, &sigmaS, &accum, &updateBuffer, &lookupBuffer})
            o->destroy();
        width = height = 0;
    }

    void ensureImages(int w, int h) {
        if (w == width && h == height && accum.isValid())
            return;
        destroyImages();
        width = w;
        height = h;
        irradiance = gpu::createTexture2D(GL_RGBA32F, w, h);
        sigmaT = gpu::createTexture2D(GL_RGBA32F, w, h);
        sigmaS = gpu::createTexture2D(GL_RGBA32F, w, h);
        accum = gpu::createTexture2D(GL_RGBA32F, w, h);
        // The catch-up list packs a pixel as x | y << 16 (dipole_material_update.comp).
        LUCENT_ASSERT(w < 65536 && h < 65536);
        updateBuffer =
            gpu::createBuffer((UPDATE_HEADER_WORDS + size_t(w) * size_t(h)) * sizeof(uint32_t),
                              nullptr, GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
        lookupBuffer =
            gpu::createBuffer((UPDATE_HEADER_WORDS + size_t(w) * size_t(h)) * sizeof(uint32_t),
                              nullptr, GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
        needReset = true;
    }

    void resetAccumulation() {
        detail::restartAccumulation(stats);
        (void)volume.takeWrittenBricks();  // every pixel looks its material up again
        needReset = false;
        part = 0;
        needMaterialUpdate = false;
        listed = catchUpLeft = 0;
        imageConverged = false;
        stats.pixelsRestarted = 0;
    }

    /// A material change (setMaterial, uploadBricks, syncMaterial, an unreported edit): the
    /// pixels whose material changed restart at the next frame once the accumulation runs the
    /// full estimator (light views joined; its frame 0 may still be under way); before that,
    /// everything restarts.
    void materialChanged() {
        if (needReset || !everRendered || !viewsReady || width == 0) {
            needReset = true;
            return;
        }
        needMaterialUpdate = true;
        stats.converged = false;  // callers poll it to schedule the next frame
    }

    /// What the material look-up and R′ read (dipole_irradiance.comp, dipole_material_update.comp):
    /// the model, its boundary terms, the disc quantile, the local window and the mesh.
    void setProfileUniforms(const gpu::GlProgram& p, int meshId) const {
        const Boundary boundary = Boundary::of(settings.eta);
        glUniform1i(p.uniformLocation("u_model"), settings.model == Model::Dipole ? 0 : 1);
        glUniform3f(p.uniformLocation("u_boundary"), float(boundary.fdr), float(boundary.c1),
                    float(boundary.c2));
        glUniform1f(p.uniformLocation("u_discQuantile"), settings.discQuantile);
        glUniform1f(p.uniformLocation("u_maxRadius"), settings.maxRadius);
        glUniform1i(p.uniformLocation("u_meshId"), meshId);
    }

    /// The bricks a pixel's material look-up must read again: those within one brick of a brick
    /// written since the last update (the look-up reads at most LUCENT_DIPOLE_MATERIAL_REACH
    /// voxels from the pixel's own), one word per brick in reachBuffer, bound to binding 6; or
    /// u_reachAll after a full upload.
    void bindReachedBricks(const gpu::GlProgram& p) {
        static_assert(LUCENT_DIPOLE_MATERIAL_REACH <= MaterialVolume::BRICK,
                      "a written brick's neighbours must cover the look-up's reach");
        const detail::VolumeTextures::WrittenBricks w = volume.takeWrittenBricks();
        const int n = std::max(w.bricksPerAxis, 1);
        glUniform1i(p.uniformLocation("u_reachAll"), w.all ? 1 : 0);
        glUniform1i(p.uniformLocation("u_bricksPerAxis"), n);
        glUniform1i(p.uniformLocation("u_brick"), MaterialVolume::BRICK);
        reached.assign(size_t(n) * size_t(n) * size_t(n), 0u);
        if (!w.all && !w.written.empty())
            for (int bz = 0; bz < n; ++bz)
                for (int by = 0; by < n; ++by)
                    for (int bx = 0; bx < n; ++bx) {
                        if (!w.written[size_t((bz * n + by) * n + bx)])
                            continue;
                        for (int z = std::max(bz - 1, 0); z <= std::min(bz + 1, n - 1); ++z)
                            for (int y = std::max(by - 1, 0); y <= std::min(by + 1, n - 1); ++y)
                                for (int x = std::max(bx - 1, 0); x <= std::min(bx + 1, n - 1); ++x)
                                    reached[size_t((z * n + y) * n + x)] = 1u;
                    }
        const size_t bytes = reached.size() * sizeof(uint32_t);
        if (reachBufferBytes != bytes) {
            reachBuffer = gpu::createBuffer(bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
            reachBufferBytes = bytes;
        }
        glNamedBufferSubData(reachBuffer.id(), 0, GLsizeiptr(bytes), reached.data());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, reachBuffer.id());
    }

    /// dipole_material_update.comp: restarts the pixels whose material changed, lists the pixels
    /// behind the accumulation's frame count and sets up their catch-up. Its SCAN pass lists the
    /// pixels whose look-up reaches a changed voxel; the look-up runs over that list only.
    void updateMaterial(const gpu::GBufferView& g) {
        glBindTextureUnit(0, g.positionTexture);
        glBindTextureUnit(1, g.normalTexture);
        glBindImageTexture(0, accum.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(1, sigmaT.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(2, sigmaS.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, radiusBuffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, updateBuffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, lookupBuffer.id());
        const uint32_t init[UPDATE_HEADER_WORDS] = {0u, 0u, 0xffffffffu, 0u};
        glNamedBufferSubData(updateBuffer.id(), 0, sizeof(init), init);
        const uint32_t none[UPDATE_HEADER_WORDS] = {};
        glNamedBufferSubData(lookupBuffer.id(), 0, sizeof(none), none);
        const auto use = [&](const gpu::GlProgram& p) {  // what both passes read
            glUseProgram(p.id());
            volume.bind(p, 3, 4);
            glUniform2i(p.uniformLocation("u_size"), g.width, g.height);
            setProfileUniforms(p, settings.meshId);
            glUniform1i(p.uniformLocation("u_level"), stats.frames);
        };
        use(materialScanProgram);
        bindReachedBricks(materialScanProgram);
        glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        uint32_t lookups = 0;
        glGetNamedBufferSubData(lookupBuffer.id(), 0, sizeof(lookups), &lookups);
        stats.pixelsLookedUp = int(lookups);
        if (lookups > 0) {
            use(materialUpdateProgram);
            gpu::dispatchLine((lookups + 63u) / 64u);
        }
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                        GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        glUseProgram(0);
        uint32_t counts[UPDATE_HEADER_WORDS] = {};
        glGetNamedBufferSubData(updateBuffer.id(), 0, sizeof(counts), counts);
        float r[2] = {0.f, 0.f};
        glGetNamedBufferSubData(radiusBuffer.id(), 0, sizeof(r), r);
        stats.minRadius = r[1] > 0.f ? r[0] : 0.f;
        stats.maxRadius = r[1];
        needMaterialUpdate = false;
        // Painting is interactive use: from here on the whole-image frames are split into
        // bounded parts (a first accumulation that began in the CLI's way is not).
        interactiveAccum = true;
        stats.pixelsRestarted = int(counts[RESTARTED]);
        listed = int(counts[LISTED]);
        catchUpLevel = stats.frames;
        catchUpLeft = listed > 0 ? std::max(catchUpLevel - int(counts[MIN_FRAMES]), 0) : 0;
        stats.converged = catchUpLeft == 0 && imageConverged;
    }

    /// Opens a timed pass: a GL_TIMESTAMP query now; closePass() stores its duration in `out`.
    size_t openPass() {
        if (nextQuery + 2 > timerQueries.size())
            return SIZE_MAX;
        glQueryCounter(timerQueries[nextQuery].id(), GL_TIMESTAMP);
        nextQuery += 2;
        return nextQuery - 2;
    }
    void closePass(size_t begin, float* out) {
        if (begin == SIZE_MAX)
            return;
        glQueryCounter(timerQueries[begin + 1].id(), GL_TIMESTAMP);
        pendingTimes.emplace_back(begin, out);
    }
    /// Reads the frame's timestamps (waits for its passes, which the gather's statistics
    /// read-back did already).
    void resolvePassTimes() {
        for (const auto& [begin, out] : pendingTimes) {
            GLuint64 t0 = 0, t1 = 0;
            glGetQueryObjectui64v(timerQueries[begin].id(), GL_QUERY_RESULT, &t0);
            glGetQueryObjectui64v(timerQueries[begin + 1].id(), GL_QUERY_RESULT, &t1);
            *out += float(double(t1 - t0) * 1e-6);
        }
        pendingTimes.clear();
        nextQuery = 0;
    }

    /// dipole_irradiance.comp over one view's (position, normal) images: E, σt, σs′ and R′.
    /// `radiusStats`: also the min/max of R′ over the object's pixels into stats.
    /// `outT` = 0: a light view (lightIrradianceProgram, E only; the gather takes the profile
    /// from x_o's material).
    void runIrradianceOn(const gpu::GBufferView& g, unsigned position, unsigned normal, int w,
                         int h, int meshId, unsigned outE, unsigned outT, unsigned outS,
                         bool radiusStats) {
        const bool lightView = outT == 0;
        const gpu::GlProgram& p = lightView ? lightIrradianceProgram : irradianceProgram;
        glUseProgram(p.id());
        glBindTextureUnit(0, position);
        glBindTextureUnit(1, normal);
        glBindTextureUnit(2, g.shadowMapTexture);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, g.lightBuffer);  // LUCENT_BINDING_LIGHTS
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, g.shadowLayerBuffer);  // SHADOW_LAYERS
        glBindImageTexture(0, outE, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        if (!lightView) {
            volume.bind(p, 3, 4);
            const uint32_t init[2] = {0x7f7fffffu, 0u};  // FLT_MAX, 0 (uint order of floats ≥ 0)
            glNamedBufferSubData(radiusBuffer.id(), 0, sizeof(init), init);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, radiusBuffer.id());
            glBindImageTexture(1, outT, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
            glBindImageTexture(2, outS, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        }
        glUniform2i(p.uniformLocation("u_size"), w, h);
        glUniform1i(p.uniformLocation("u_lightCount"), g.lightBuffer ? g.lightCount : 0);
        const bool shadows =
            settings.shadows && g.shadows && g.shadowMapTexture != 0 && g.shadowLayerBuffer != 0;
        glUniform1i(p.uniformLocation("u_shadows"), shadows ? 1 : 0);
        glUniform1f(p.uniformLocation("u_eta"), settings.eta);
        setProfileUniforms(p, meshId);
        glDispatchCompute(unsigned(w + 7) / 8, unsigned(h + 7) / 8, 1);
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                        GL_BUFFER_UPDATE_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
        if (!radiusStats)
            return;
        float r[2] = {0.f, 0.f};
        glGetNamedBufferSubData(radiusBuffer.id(), 0, sizeof(r), r);
        stats.epsilon = 1.f - settings.discQuantile;
        stats.minRadius = r[1] > 0.f ? r[0] : 0.f;
        stats.maxRadius = r[1];
    }

    void runIrradiance(const gpu::GBufferView& g) {
        runIrradianceOn(g, g.positionTexture, g.normalTexture, g.width, g.height, settings.meshId,
                        irradiance.id(), sigmaT.id(), sigmaS.id(), /*radiusStats=*/true);
    }

    void ensureLightViews(int size, int layers) {
        if (size != lvSize) {
            for (gpu::GlObject* o :
                 {&scratchPosition, &scratchNormal, &scratchE, &scratchDepth, &partialBuffer})
                o->destroy();
            for (gpu::GlObject* o : {&scratchPosition, &scratchNormal, &scratchE})
                *o = gpu::createTexture2D(GL_RGBA32F, size, size);
            scratchDepth = gpu::createTexture2D(GL_DEPTH_COMPONENT32F, size, size);
            const int groups = (size + 7) / 8;
            partialBuffer = gpu::createBuffer(size_t(groups) * size_t(groups) * 2 * sizeof(float),
                                              nullptr, GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
            glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT0, scratchPosition.id(), 0);
            glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT1, scratchNormal.id(), 0);
            glNamedFramebufferTexture(fbo.id(), GL_DEPTH_ATTACHMENT, scratchDepth.id(), 0);
            if (glCheckNamedFramebufferStatus(fbo.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
                LUCENT_THROW(GpuError,
                             "DipoleSubsurfaceProvider: incomplete light-view framebuffer (", size,
                             " texels)");
        }
        if (size != lvSize || layers > lvLayers) {
            for (gpu::GlObject* o : {&lvPosition, &lvNormal, &lvIrradiance})
                o->destroy();
            lvLayers = std::max(layers, 1);
            for (gpu::GlObject* o : {&lvPosition, &lvNormal, &lvIrradiance})
                *o = gpu::createTexture2DArray(GL_RGBA32F, size, size, lvLayers);
        }
        lvSize = size;
    }

    /// The object (settings.meshId's mesh, or every mesh) from clipFromWorld into the scratch
    /// position/normal images (dirpole_gbuffer.*: position + coverage, outward normal).
    void rasterise(const gpu::GBufferView& g, const Mat4f& clipFromWorld) {
        glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
        glViewport(0, 0, lvSize, lvSize);
        const float zero[4] = {0.f, 0.f, 0.f, 0.f};
        const float one = 1.f;
        glClearNamedFramebufferfv(fbo.id(), GL_COLOR, 0, zero);
        glClearNamedFramebufferfv(fbo.id(), GL_COLOR, 1, zero);
        glClearNamedFramebufferfv(fbo.id(), GL_DEPTH, 0, &one);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDepthMask(GL_TRUE);
        glDisable(GL_CULL_FACE);
        glDisable(GL_BLEND);
        glUseProgram(lightGbufferProgram.id());
        glUniformMatrix4fv(0, 1, GL_FALSE, &clipFromWorld[0][0]);
        for (size_t i = 0; i < g.meshes.size(); ++i) {
            if ((settings.meshId >= 0 && int(i) != settings.meshId) || g.meshes[i].indexCount == 0)
                continue;
            glBindVertexArray(g.meshes[i].vertexArray);
            glDrawElements(GL_TRIANGLES, g.meshes[i].indexCount, GL_UNSIGNED_INT, nullptr);
        }
        glBindVertexArray(0);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }

    /// dipole_lightview.comp on light view `layer`: backlitFluxFraction() against the camera.
    float backlitFraction(const gpu::GBufferView& g, int layer) {
        const Camera& cam = lvSlots[size_t(layer)].camera;
        const Mat4f& clip = lvSlots[size_t(layer)].clip;
        const gpu::GlProgram& p = lightStatsProgram;
        glUseProgram(p.id());
        glUniform1i(p.uniformLocation("u_layer"), layer);
        glBindTextureUnit(0, lvPosition.id());
        glBindTextureUnit(1, lvNormal.id());
        glBindTextureUnit(2, lvIrradiance.id());
        glBindTextureUnit(3, g.positionTexture);
        glBindTextureUnit(4, g.normalTexture);
        glBindTextureUnit(5, sigmaS.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, partialBuffer.id());
        const CameraView c = cameraView(g);
        const Mat4f clips[2] = {c.clip, clip};
        const glm::vec4 eyes[2] = {glm::vec4(c.eye, c.ortho ? 1.f : 0.f),
                                   glm::vec4(cam.position, cam.orthographic ? 1.f : 0.f)};
        const Vector3f dirs[2] = {c.forward, glm::normalize(cam.target - cam.position)};
        const glm::ivec2 sizes[2] = {{g.width, g.height}, {lvSize, lvSize}};
        glUniformMatrix4fv(p.uniformLocation("u_clip"), 2, GL_FALSE, &clips[0][0][0]);
        glUniform4fv(p.uniformLocation("u_eyeOrtho"), 2, &eyes[0][0]);
        glUniform3fv(p.uniformLocation("u_dir"), 2, &dirs[0][0]);
        glUniform2iv(p.uniformLocation("u_size"), 2, &sizes[0][0]);
        const int groups = (lvSize + 7) / 8;
        glDispatchCompute(unsigned(groups), unsigned(groups), 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        std::vector<glm::vec2> partial(size_t(groups) * size_t(groups));
        glGetNamedBufferSubData(partialBuffer.id(), 0,
                                GLsizeiptr(partial.size() * sizeof(glm::vec2)), partial.data());
        double total = 0.0, back = 0.0;
        for (const glm::vec2& v : partial) {
            total += double(v.x);
            back += double(v.y);
        }
        return total > 0.0 ? float(back / total) : 0.f;
    }

    /// What the light views of frame `g` depend on (ViewKey).
    ViewKey viewKey(const gpu::GBufferView& g, const std::vector<unsigned char>& lights) const {
        ViewKey k;
        k.lights = lights;
        for (const gpu::GBufferView::MeshGeometry& m : g.meshes)
            k.meshes.insert(k.meshes.end(),
                            {m.revision, uint64_t(m.vertexArray), uint64_t(m.indexCount)});
        k.shadowMaps = g.shadowMapTexture;
        k.shadows = settings.shadows && g.shadows;
        k.eta = settings.eta;
        k.resolution = settings.lightViewResolution;
        k.meshId = settings.meshId;
        return k;
    }

    /// Seed 004 §7.1: brings the light views up to date for this accumulation. Views whose
    /// inputs (ViewKey) changed are re-rendered (the object rasterised from the light, its E
    /// with all lights and the shadow maps, into layer l of the view arrays); then every view's
    /// back-lit flux fraction is computed against the camera (needs the camera's R′: after
    /// runIrradiance) and those above the threshold are gathered. `all` false: at most one
    /// view or the fraction pass per call (bounded interactive frames); returns whether the
    /// views are ready (fractions done).
    bool updateViews(const gpu::GBufferView& g, bool all) {
        viewWorkDone = false;
        const int lightCount = g.lightBuffer ? std::max(g.lightCount, 0) : 0;
        Bounds3f bounds;
        for (size_t i = 0; i < g.meshes.size(); ++i)
            if (settings.meshId < 0 || int(i) == settings.meshId)
                bounds.expand(g.meshes[i].bounds);
        lvGathered.clear();
        stats.lightViewsGathered = 0;
        stats.backlitFractions.assign(size_t(lightCount), -1.f);
        if (!settings.lightViews || lightCount == 0 || bounds.isEmpty() ||
            lastLights.size() < size_t(lightCount) * sizeof(gpu::shared::GpuLight)) {
            stats.lightViewsRendered = 0;
            return true;
        }
        const ViewKey key = viewKey(g, lastLights);
        if (!lvKeyValid || !(key == lvKey)) {
            lvKey = key;
            lvKeyValid = true;
            lvSlots.assign(size_t(lightCount), ViewSlot{});
            ensureLightViews(settings.lightViewResolution, lightCount);
        }
        // 1. Views to (re-)render.
        const size_t t0 = openPass();
        bool renderedOne = false;
        for (int l = 0; l < lightCount; ++l) {
            ViewSlot& slot = lvSlots[size_t(l)];
            if (slot.done)
                continue;
            if (renderedOne && !all)
                break;
            slot.done = true;
            gpu::shared::GpuLight gl;
            std::memcpy(&gl, lastLights.data() + size_t(l) * sizeof(gl), sizeof(gl));
            try {
                slot.camera = lightViewCamera(sceneLight(gl), bounds, lvSize);
            } catch (const ValueError&) {
                continue;  // light inside the bounding sphere: no view (fraction stays −1)
            }
            slot.clip = slot.camera.clipFromView() * slot.camera.viewFromWorld();
            rasterise(g, slot.clip);
            runIrradianceOn(g, scratchPosition.id(), scratchNormal.id(), lvSize, lvSize, -1,
                            scratchE.id(), 0, 0, /*radiusStats=*/false);
            // imageStore (E) and framebuffer writes → copies (texture update).
            glMemoryBarrier(GL_ALL_BARRIER_BITS);
            const std::pair<unsigned, unsigned> copies[3] = {
                {scratchPosition.id(), lvPosition.id()},
                {scratchNormal.id(), lvNormal.id()},
                {scratchE.id(), lvIrradiance.id()}};
            for (const auto& [src, dst] : copies)
                glCopyImageSubData(src, GL_TEXTURE_2D, 0, 0, 0, 0, dst, GL_TEXTURE_2D_ARRAY, 0, 0,
                                   0, l, lvSize, lvSize, 1);
            slot.rendered = true;
            renderedOne = viewWorkDone = true;
            ++stats.lightViewPasses;
        }
        if (renderedOne)
            closePass(t0, &stats.passMs.lightViews);
        stats.lightViewsRendered = 0;
        for (const ViewSlot& slot : lvSlots)
            stats.lightViewsRendered += slot.rendered ? 1 : 0;
        const bool pending =
            std::any_of(lvSlots.begin(), lvSlots.end(), [](const ViewSlot& v) { return !v.done; });
        if (pending || (renderedOne && !all))
            return false;  // the fractions in the next frame
        // 2. Back-lit fractions (they depend on the camera and R′, i.e. the material).
        const size_t t1 = openPass();
        viewWorkDone = true;
        std::vector<GpuLightView> views;
        for (int l = 0; l < lightCount; ++l) {
            const ViewSlot& slot = lvSlots[size_t(l)];
            if (!slot.rendered)
                continue;
            const float f = backlitFraction(g, l);
            stats.backlitFractions[size_t(l)] = f;
            if (!(f > settings.lightViewThreshold))
                continue;
            lvGathered.push_back(l);
            views.push_back(
                {slot.clip, glm::vec4(slot.camera.position, slot.camera.orthographic ? 1.f : 0.f),
                 glm::vec4(glm::normalize(slot.camera.target - slot.camera.position), float(l))});
        }
        closePass(t1, &stats.passMs.fractions);
        stats.lightViewsGathered = int(lvGathered.size());
        if (!views.empty())
            glNamedBufferSubData(viewBuffer.id(), 0, GLsizeiptr(views.size() * sizeof(views[0])),
                                 views.data());
        return true;
    }

    /// The RESOLVE_ONLY program over every pixel: each pixel's mean Σ_f B_f / N (N in the
    /// accumulation's alpha) times the exit Fresnel (η, camera).
    void resolveAll(const gpu::GBufferView& g, unsigned target) const {
        const gpu::GlProgram& p = resolveProgram;
        glUseProgram(p.id());
        bindFrameImages(g, target);
        const CameraView cv = cameraView(g);
        glUniform3f(p.uniformLocation("u_eye"), g.cameraPosition.x, g.cameraPosition.y,
                    g.cameraPosition.z);
        glUniform3f(p.uniformLocation("u_viewDir"), cv.forward.x, cv.forward.y, cv.forward.z);
        glUniform1i(p.uniformLocation("u_ortho"), cv.ortho ? 1 : 0);
        glUniform2i(p.uniformLocation("u_size"), g.width, g.height);
        glUniform1f(p.uniformLocation("u_eta"), settings.eta);
        glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }

    /// The images and buffers every dipole_provider.comp program reads or writes.
    void bindFrameImages(const gpu::GBufferView& g, unsigned target) const {
        glBindTextureUnit(0, g.positionTexture);
        glBindTextureUnit(1, g.normalTexture);
        glBindTextureUnit(2, irradiance.id());
        glBindTextureUnit(3, sigmaT.id());
        glBindTextureUnit(4, sigmaS.id());
        glBindImageTexture(0, accum.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(1, target, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, shiftBuffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, statsBuffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, viewBuffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, updateBuffer.id());
        glBindTextureUnit(5, lvPosition.id());
        glBindTextureUnit(6, lvNormal.id());
        glBindTextureUnit(7, lvIrradiance.id());
    }

    /// Uploads the k×k Cranley–Patterson table of the frame seeded `seed` (Mertens et al. 2005
    /// §6.2; `gs` gives k and the sample counts).
    void uploadShifts(GatherSettings gs, uint32_t seed) const {
        gs.seed = seed;
        const auto shifts = interleaveShifts(gs);
        std::vector<glm::vec4> data(2 * shifts.size());
        for (size_t c = 0; c < shifts.size(); ++c) {
            data[2 * c] = {shifts[c][0], shifts[c][1], shifts[c][2], shifts[c][3]};
            data[2 * c + 1] = {shifts[c][4], 0.f, 0.f, 0.f};
        }
        glNamedBufferSubData(shiftBuffer.id(), 0, GLsizeiptr(data.size() * sizeof(data[0])),
                             data.data());
    }

    /// A gather program's inputs for a frame of `gs` with `views` light views gathered.
    void setGatherUniforms(const gpu::GlProgram& p, const gpu::GBufferView& g,
                           const GatherSettings& gs, int views) const {
        glUniform1i(p.uniformLocation("u_lightViews"), views);
        glUniform1i(p.uniformLocation("u_lightViewSize"), lvSize);
        const CameraView cv = cameraView(g);
        glUniformMatrix4fv(p.uniformLocation("u_clipFromWorld"), 1, GL_FALSE,
                           &g.clipFromWorld[0][0]);
        glUniform3f(p.uniformLocation("u_eye"), g.cameraPosition.x, g.cameraPosition.y,
                    g.cameraPosition.z);
        glUniform3f(p.uniformLocation("u_viewDir"), cv.forward.x, cv.forward.y, cv.forward.z);
        glUniform1i(p.uniformLocation("u_ortho"), cv.ortho ? 1 : 0);
        glUniform2i(p.uniformLocation("u_size"), g.width, g.height);
        glUniform1i(p.uniformLocation("u_model"), gs.model == Model::Dipole ? 0 : 1);
        const Boundary boundary = Boundary::of(gs.eta);
        glUniform3f(p.uniformLocation("u_boundary"), float(boundary.fdr), float(boundary.c1),
                    float(boundary.c2));
        glUniform1f(p.uniformLocation("u_eta"), gs.eta);
        glUniform1i(p.uniformLocation("u_nImp"), gs.importanceSamples);
        glUniform1i(p.uniformLocation("u_nUni"), gs.uniformSamples);
        glUniform1i(p.uniformLocation("u_jacobian"), gs.jacobian ? 1 : 0);
        glUniform1f(p.uniformLocation("u_maxJacobian"), gs.maxJacobian);
        glUniform1i(p.uniformLocation("u_interleave"), gs.interleave);
        glUniform1f(p.uniformLocation("u_maxRadius"), gs.maxRadius);
    }

    /// A frame's gather settings: the settings', or a preview's previewSamples per pixel.
    [[nodiscard]] GatherSettings frameGatherSettings(bool preview) const {
        ProviderSettings frameSettings = settings;
        if (preview)
            frameSettings.samplesPerFrame = settings.previewSamples;
        return frameSettings.gatherSettings();
    }

    /// The gather program for `views` gathered light views.
    [[nodiscard]] const gpu::GlProgram& gatherProgramFor(int views) const {
        return views == 0 ? cameraGatherProgram : gatherProgram;
    }

    /// One frame of the gather (`gather`) or only the resolve of the stored mean. `preview`:
    /// the camera image only with settings.previewSamples samples, not accumulated (the next
    /// frame overwrites it: stats.frames stays 0).
    void runGather(const gpu::GBufferView& g, unsigned target, bool gather, bool preview) {
        const size_t t0 = openPass();
        const GatherSettings gs = frameGatherSettings(preview);
        // Light views join once their fractions are known (camera-only estimator before).
        const int views = viewsReady && !preview ? int(lvGathered.size()) : 0;
        // Interactive accumulations split a frame into parts over interleaved work groups, one
        // per provider frame, each about one camera-only 16-spp frame at 320×180 (the app's
        // default size; 80–130 ms on llvmpipe under load): a light view's visibility and density
        // tests make the samples of a frame with views ≈ (1 + views)× dearer (§3d).
        const double work = double(g.width) * double(g.height) *
                            double(gs.importanceSamples + gs.uniformSamples) * double(1 + views);
        const int parts =
            interactiveAccum && !preview && gather
                ? std::clamp(int(std::ceil(work / INTERACTIVE_PART_WORK - 1e-9)), 1, 64)
                : 1;
        stats.frameParts = parts;
        if (gather && part == 0) {
            uploadShifts(gs, frameSeed(settings.seed, stats.frames));
            const uint32_t zero[2] = {0u, 0u};
            glNamedBufferSubData(statsBuffer.id(), 0, sizeof(zero), zero);
        }
        if (!gather || parts > 1)
            // Every pixel's current mean first; with parts, part `part`'s rows then gather
            // (they overwrite their pixels).
            resolveAll(g, target);
        if (gather) {
            const gpu::GlProgram& p = gatherProgramFor(views);
            glUseProgram(p.id());
            bindFrameImages(g, target);
            setGatherUniforms(p, g, gs, views);
            // Frames after the first rotate each pixel's samples by its own hash: with the k×k
            // table alone, pixels k apart share every frame's samples and the mean keeps a
            // k-periodic error (the waffle of issue 17). Frame 0 (and a preview) keeps the CPU
            // gather's table.
            glUniform1i(p.uniformLocation("u_pixelShifts"), !preview && stats.frames > 0);
            glUniform1ui(p.uniformLocation("u_frameSeed"), frameSeed(settings.seed, stats.frames));
            glUniform1i(p.uniformLocation("u_gather"), 1);
            glUniform1i(p.uniformLocation("u_framesBefore"), stats.frames);
            glUniform1i(p.uniformLocation("u_parts"), parts);
            glUniform1i(p.uniformLocation("u_part"), part);
            glUniform1i(p.uniformLocation("u_listCount"), 0);
            glUniform1i(p.uniformLocation("u_listPreview"), 0);
            const unsigned groupsX = unsigned(g.width + 7) / 8,
                           groupsY = unsigned(g.height + 7) / 8;
            const unsigned rows =
                parts > 1
                    ? (groupsY > unsigned(part)
                           ? (groupsY - unsigned(part) + unsigned(parts) - 1) / unsigned(parts)
                           : 0u)
                    : groupsY;
            if (rows > 0)
                glDispatchCompute(groupsX, rows, 1);
            glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                            GL_BUFFER_UPDATE_BARRIER_BIT);
        }
        glUseProgram(0);
        closePass(t0, &stats.passMs.gather);
        if (!gather || preview)
            return;
        if (++part < parts)
            return;  // the frame is complete after its last part
        part = 0;
        detail::finishFrame(stats, statsBuffer.id(), settings.samplesPerFrame, settings.maxFrames,
                            settings.convergenceThreshold);
        imageConverged = stats.converged;
    }

    /// Catch-up after a material-only restart: `frames` frames of the full estimator for the
    /// listed pixels (each gathers while it has fewer than catchUpLevel frames; seeds of their
    /// own stream), then every pixel's mean. The whole-image accumulation (stats.frames, its
    /// parts and convergence test) waits until the listed pixels have caught up. `preview`
    /// (frames = 1, a stroke's frame): instead, a camera-only estimate with
    /// settings.previewSamples samples for the listed pixels without a frame, shown until the
    /// first catch-up frame replaces it (as a full restart's preview, §3c "Bounded restarts").
    void runCatchUp(const gpu::GBufferView& g, unsigned target, int frames, bool preview) {
        const size_t t0 = openPass();
        const GatherSettings gs = frameGatherSettings(preview);
        const int views = preview ? 0 : int(lvGathered.size());
        const gpu::GlProgram& p = gatherProgramFor(views);
        for (int f = 0; f < frames; ++f) {
            const uint32_t seed = catchUpSeed(settings.seed, catchUpFrames++);
            uploadShifts(gs, seed);
            glUseProgram(p.id());
            bindFrameImages(g, target);
            setGatherUniforms(p, g, gs, views);
            glUniform1i(p.uniformLocation("u_pixelShifts"), 1);
            glUniform1ui(p.uniformLocation("u_frameSeed"), seed);
            glUniform1i(p.uniformLocation("u_gather"), 1);
            glUniform1i(p.uniformLocation("u_framesBefore"), catchUpLevel);
            glUniform1i(p.uniformLocation("u_parts"), 1);
            glUniform1i(p.uniformLocation("u_part"), 0);
            glUniform1i(p.uniformLocation("u_listCount"), listed);
            glUniform1i(p.uniformLocation("u_level"), catchUpLevel);
            glUniform1i(p.uniformLocation("u_listPreview"), preview ? 1 : 0);
            gpu::dispatchLine(unsigned(listed + 63) / 64);
            glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
        }
        resolveAll(g, target);
        glUseProgram(0);
        closePass(t0, &stats.passMs.gather);
        if (preview)
            return;
        catchUpLeft = std::max(catchUpLeft - frames, 0);
        if (catchUpLeft == 0)
            stats.converged = imageConverged;
    }
};

DipoleSubsurfaceProvider::DipoleSubsurfaceProvider()
    : MaterialSubsurfaceProvider("DipoleSubsurfaceProvider"),
      m(std::make_unique<Impl>(m_stats, *m_volume)) {}

DipoleSubsurfaceProvider::~DipoleSubsurfaceProvider() = default;

void DipoleSubsurfaceProvider::createGl(const gpu::ShaderLibrary& library) {
    m->irradianceProgram = gpu::GlProgram::compute(library, "dipole_irradiance.comp");
    m->gatherProgram = gpu::GlProgram::compute(library, "dipole_provider.comp");
    m->cameraGatherProgram =
        gpu::GlProgram::compute(library, "dipole_provider.comp", {"MULTI_VIEW=0"});
    m->resolveProgram = gpu::GlProgram::compute(library, "dipole_provider.comp",
                                                {"MULTI_VIEW=0", "RESOLVE_ONLY=1"});
    m->materialScanProgram =
        gpu::GlProgram::compute(library, "dipole_material_update.comp", {"SCAN=1"});
    m->materialUpdateProgram = gpu::GlProgram::compute(library, "dipole_material_update.comp");
    // Largest shift table: interleave 64 → 64² cells × 2 vec4.
    m->shiftBuffer =
        gpu::createBuffer(64 * 64 * 2 * sizeof(glm::vec4), nullptr, GL_DYNAMIC_STORAGE_BIT);
    m->statsBuffer =
        gpu::createBuffer(2 * sizeof(uint32_t), nullptr, GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
    m->radiusBuffer =
        gpu::createBuffer(2 * sizeof(uint32_t), nullptr, GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
    // The light-view G-buffer shaders are the directional-dipole provider's (same content:
    // position + coverage, outward normal; uniform location 0 = clipFromWorld).
    m->lightGbufferProgram =
        gpu::GlProgram::graphics(library, "dirpole_gbuffer.vert", "dirpole_gbuffer.frag");
    m->lightStatsProgram = gpu::GlProgram::compute(library, "dipole_lightview.comp");
    m->lightIrradianceProgram =
        gpu::GlProgram::compute(library, "dipole_irradiance.comp", {"LIGHT_VIEW=1"});
    m->timerQueries.clear();
    for (int i = 0; i < 8; ++i)  // 4 passes × (begin, end) timestamps
        m->timerQueries.push_back(gpu::GlObject::create(gpu::GlObjectKind::Query, GL_TIMESTAMP));
    m->fbo = gpu::GlObject::create(gpu::GlObjectKind::Framebuffer);
    const GLenum drawBuffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(m->fbo.id(), 2, drawBuffers);
    m->viewBuffer = gpu::createBuffer(LUCENT_MAX_LIGHTS * sizeof(GpuLightView), nullptr,
                                      GL_DYNAMIC_STORAGE_BIT);
}

void DipoleSubsurfaceProvider::destroyGl() {
    m->irradianceProgram.destroy();
    m->gatherProgram.destroy();
    m->cameraGatherProgram.destroy();
    m->resolveProgram.destroy();
    m->materialScanProgram.destroy();
    m->materialUpdateProgram.destroy();
    m->reachBuffer.destroy();
    m->reachBufferBytes = 0;
    m->lightGbufferProgram.destroy();
    m->lightStatsProgram.destroy();
    m->lightIrradianceProgram.destroy();
    for (gpu::GlObject* o :
         {&m->shiftBuffer, &m->statsBuffer, &m->radiusBuffer, &m->fbo, &m->viewBuffer,
          &m->partialBuffer, &m->lvPosition, &m->lvNormal, &m->lvIrradiance, &m->scratchPosition,
          &m->scratchNormal, &m->scratchE, &m->scratchDepth})
        o->destroy();
    for (gpu::GlObject& q : m->timerQueries)
        q.destroy();
    m->timerQueries.clear();
    m->pendingTimes.clear();
    m->nextQuery = 0;
    m->lvSize = m->lvLayers = 0;
    m->lvSlots.clear();
    m->lvGathered.clear();
    m->lvKeyValid = m->viewsReady = m->everRendered = false;
    m->destroyImages();
}

void DipoleSubsurfaceProvider::setSettings(const ProviderSettings& settings) {
    validateSettings(settings);
    if (!sameSettings(settings, m->settings))
        m->needReset = true;
    m->settings = settings;
}

const ProviderSettings& DipoleSubsurfaceProvider::settings() const {
    return m->settings;
}

void DipoleSubsurfaceProvider::restart() {
    // The base class calls this for material changes (and reset(), after invalidateCaches()).
    m->materialChanged();
}

void DipoleSubsurfaceProvider::invalidateCaches() {
    m->lvKeyValid = false;  // every light view is re-rendered at the next restart
    m->needReset = true;    // reset(): G-buffer content changed, not only the material
}

std::vector<SurfaceBuffers> DipoleSubsurfaceProvider::debugLightViews() const {
    std::vector<SurfaceBuffers> views;
    const int n = m->lvSize;
    std::vector<glm::vec4> pos(size_t(n) * size_t(n)), nrm(pos.size()), e(pos.size());
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    const GLsizei bytes = GLsizei(pos.size() * sizeof(glm::vec4));
    if (!m->viewsReady)
        return views;  // none joined the gather yet
    for (const int layer : m->lvGathered) {
        const Camera& cam = m->lvSlots[size_t(layer)].camera;
        const GLint z = GLint(layer);
        glGetTextureSubImage(m->lvPosition.id(), 0, 0, 0, z, n, n, 1, GL_RGBA, GL_FLOAT, bytes,
                             pos.data());
        glGetTextureSubImage(m->lvNormal.id(), 0, 0, 0, z, n, n, 1, GL_RGBA, GL_FLOAT, bytes,
                             nrm.data());
        glGetTextureSubImage(m->lvIrradiance.id(), 0, 0, 0, z, n, n, 1, GL_RGBA, GL_FLOAT, bytes,
                             e.data());
        SurfaceBuffers b;
        b.resize(n, n);
        b.clipFromWorld = cam.clipFromView() * cam.viewFromWorld();
        b.eye = cam.position;
        b.orthographic = cam.orthographic;
        b.viewDirection = glm::normalize(cam.target - cam.position);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const size_t gi = size_t(n - 1 - y) * size_t(n) + size_t(x), i = b.index(x, y);
                if (pos[gi].w == 0.f)
                    continue;
                b.covered[i] = 1;
                b.position[i] = Point3f(pos[gi]);
                b.normal[i] = glm::normalize(Normal3f(nrm[gi]));
                b.irradiance[i] = Rgb(e[gi]);
            }
        views.push_back(std::move(b));
    }
    gpu::checkGlError("DipoleSubsurfaceProvider::debugLightViews");
    return views;
}

DipoleSubsurfaceProvider::DebugTextures DipoleSubsurfaceProvider::debugTextures() const {
    return {m->irradiance.id(), m->sigmaT.id(),     m->sigmaS.id(),
            m->accum.id(),      m->volume.sigmaT(), m->volume.sigmaS()};
}

void DipoleSubsurfaceProvider::renderSubsurface(const gpu::GBufferView& g, unsigned target) {
    requireCreated("renderSubsurface");
    Impl& r = *m;
    r.ensureImages(g.width, g.height);
    // Material: a changed grid or changes nobody reported (revision moved without
    // uploadBricks) re-upload everything; reported bricks were uploaded already.
    if (r.volume.syncForFrame(r.stats))
        r.materialChanged();
    // Camera and lights: compare with the accumulated frame's (the light SSBO is tiny).
    std::vector<unsigned char> lights(size_t(std::max(g.lightCount, 0)) * 64);
    if (!lights.empty() && g.lightBuffer)
        glGetNamedBufferSubData(g.lightBuffer, 0, GLsizeiptr(lights.size()), lights.data());
    // Meshes: an upload (updateMesh) changes what the G-buffer and the light views show even
    // when nobody called reset().
    std::vector<uint64_t> meshes;
    for (const gpu::GBufferView::MeshGeometry& mg : g.meshes)
        meshes.insert(meshes.end(),
                      {mg.revision, uint64_t(mg.vertexArray), uint64_t(mg.indexCount)});
    if (g.clipFromWorld != r.lastClip || g.cameraPosition != r.lastEye || lights != r.lastLights ||
        g.shadows != r.lastShadows || meshes != r.lastMeshes) {
        r.needReset = true;
        r.lastClip = g.clipFromWorld;
        r.lastEye = g.cameraPosition;
        r.lastLights = std::move(lights);
        r.lastShadows = g.shadows;
        r.lastMeshes = std::move(meshes);
    }
    r.stats.passMs = {};
    bool preview = false, viewFrame = false, materialFrame = false;
    if (r.needReset) {
        // Interactive restart (docs/methods/dipole.md §3c "Bounded restarts"): something was
        // shown and is now discarded. The first frame is a cheap camera-only preview; the light
        // views catch up in the following frames.
        const bool interactive =
            (r.everRendered || r.settings.interactiveFirstFrame) && r.settings.previewSamples > 0;
        r.resetAccumulation();
        r.interactiveAccum = interactive;
        const size_t t0 = r.openPass();
        r.runIrradiance(g);
        r.closePass(t0, &r.stats.passMs.irradiance);
        r.viewsReady = false;
        r.stats.lightViewsGathered = 0;
        if (interactive) {
            preview = true;
            ++r.stats.previewFrames;
        } else {
            r.viewsReady = r.updateViews(g, /*all=*/true);
        }
    } else if (r.needMaterialUpdate) {
        // Material-only restart (§3c): the pixels whose material changed restart and catch up;
        // the others keep their sums, the light views and their fractions stay as they are.
        const size_t t0 = r.openPass();
        r.updateMaterial(g);
        r.closePass(t0, &r.stats.passMs.materialUpdate);
        materialFrame = true;
    } else if (!r.viewsReady) {
        r.viewsReady = r.updateViews(g, /*all=*/false);
        viewFrame = r.viewWorkDone;
        if (r.viewsReady && !r.lvGathered.empty() && r.stats.frames > 0) {
            // The light views join: restart with the full estimator (camera-only frames lack
            // the hidden irradiance; mixing them in would bias the mean). Not a reset of the
            // caller's (stats.resets unchanged).
            r.stats.frames = r.stats.samplesPerPixel = 0;
            r.stats.lastChange = 1.f;
            r.part = 0;
        }
    }
    // A pending frame does either light-view work or gather work, each bounded; the preview
    // stays on screen meanwhile. While the views are pending the refinement may not end (a
    // back-lit object can be black in the camera image), nor grow past maxFrames.
    // The stroke's frame shows a camera-only preview of the restarted pixels (its latency is the
    // material update and that; previewSamples 0: one catch-up frame instead); idle frames
    // catch up by as many frames as fit one interactive part's work.
    const bool strokePreview = materialFrame && r.listed > 0 && r.settings.previewSamples > 0;
    if (r.catchUpLeft > 0 || strokePreview) {
        const double work =
            double(r.listed) * double(r.settings.samplesPerFrame) * double(1 + r.lvGathered.size());
        const int frames =
            materialFrame
                ? 1
                : std::clamp(int(INTERACTIVE_PART_WORK / std::max(work, 1.0)), 1, r.catchUpLeft);
        r.runCatchUp(g, target, frames, strokePreview);
        preview = strokePreview;
    } else {
        const bool gather = !r.stats.converged && !viewFrame &&
                            (r.viewsReady || r.stats.frames < r.settings.maxFrames);
        r.runGather(g, target, gather, preview);
    }
    r.stats.pixelsCatchingUp = r.catchUpLeft > 0 ? r.listed : 0;
    if (!r.viewsReady)
        r.stats.converged = false;
    r.stats.preview = preview || !r.viewsReady;
    r.stats.viewsPending = !r.viewsReady;
    r.everRendered = true;
    r.resolvePassTimes();
    gpu::checkGlError("DipoleSubsurfaceProvider::renderSubsurface");
}

}  // namespace lucent::dipole
