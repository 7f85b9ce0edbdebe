// SPDX-License-Identifier: MIT
/// @file
/// @brief GL side of dipole::DirpoleSubsurfaceProvider (the dirpole thesis §4): light-view and
/// cube-face G-buffers (shaders/dirpole_gbuffer.*), progressive gather
/// (shaders/dirpole_gather.comp) and the six-face combination (shaders/dirpole_combine.comp).

#include <lucent/dipole/DirpoleProvider.h>

#include "VolumeTextures.h"

#include <lucent/core/Error.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/GpuTimer.h>
#include <lucent/gpu/Shader.h>
#include <lucent/material/MaterialVolume.h>
#include <shared/DirpoleShared.h>
#include <shared/LightingShared.h>

#include <epoxy/gl.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

namespace lucent::dipole {

namespace {

void validateSettings(const DirpoleSettings& s) {
    detail::validateProgressiveSettings("DirpoleSettings", s.eta, s.samplesPerFrame, s.maxFrames,
                                        s.convergenceThreshold, s.meshId);
    LUCENT_CHECK(s.lightMapSize >= 16 && s.lightMapSize <= 4096,
                 "DirpoleSettings.lightMapSize must be in [16, 4096] (got ", s.lightMapSize, ")");
    LUCENT_CHECK(s.cubeMapSize >= 16 && s.cubeMapSize <= 4096,
                 "DirpoleSettings.cubeMapSize must be in [16, 4096] (got ", s.cubeMapSize, ")");
    const auto epsilonOk = [](float e) { return std::isfinite(e) && e >= 0.f && e <= 1e3f; };
    LUCENT_CHECK(epsilonOk(s.shrink),
                 "DirpoleSettings.shrink (epsilon_g) must be in [0, 1e3] mm (got ", s.shrink, ")");
    LUCENT_CHECK(epsilonOk(s.intrusion),
                 "DirpoleSettings.intrusion (epsilon_c) must be in [0, 1e3] mm (got ", s.intrusion,
                 ")");
    LUCENT_CHECK(epsilonOk(s.bias), "DirpoleSettings.bias (epsilon_b) must be in [0, 1e3] mm (got ",
                 s.bias, ")");
    LUCENT_CHECK(std::isfinite(s.slopeBias) && s.slopeBias >= 0.f && s.slopeBias <= 64.f,
                 "DirpoleSettings.slopeBias must be in [0, 64] (got ", s.slopeBias, ")");
    LUCENT_CHECK(s.frameSampleBudget >= 0,
                 "DirpoleSettings.frameSampleBudget must be >= 0 (0 = unlimited; got ",
                 s.frameSampleBudget, ")");
    LUCENT_CHECK(s.firstFrameSampleBudget >= 0,
                 "DirpoleSettings.firstFrameSampleBudget must be >= 0 (0 = unlimited; got ",
                 s.firstFrameSampleBudget, ")");
    LUCENT_CHECK(int64_t(s.maxFrames) * s.samplesPerFrame < (int64_t(1) << 24),
                 "DirpoleSettings: maxFrames x samplesPerFrame must be < 2^24 (per-texel sample "
                 "counts are stored as floats; got ",
                 s.maxFrames, " x ", s.samplesPerFrame, ")");
}

/// The settings the light-view and cube-face G-buffers depend on.
bool sameGeometry(const DirpoleSettings& a, const DirpoleSettings& b) {
    return a.lightMapSize == b.lightMapSize && a.cubeMapSize == b.cubeMapSize &&
           a.meshId == b.meshId;
}

/// The settings the accumulated sums (or their stopping rule) depend on: all but the budgets,
/// which only spread the same per-texel samples over frames.
bool sameAccumulation(const DirpoleSettings& a, const DirpoleSettings& b) {
    return sameGeometry(a, b) && a.eta == b.eta && a.samplesPerFrame == b.samplesPerFrame &&
           a.maxFrames == b.maxFrames && a.convergenceThreshold == b.convergenceThreshold &&
           a.gbufferShrink == b.gbufferShrink && a.shrink == b.shrink &&
           a.cubemapIntrusion == b.cubemapIntrusion && a.intrusion == b.intrusion &&
           a.shadowBias == b.shadowBias && a.bias == b.bias && a.slopeBias == b.slopeBias &&
           a.energyNormalised == b.energyNormalised && a.energyTarget == b.energyTarget &&
           a.seed == b.seed;
}

/// Words of the frame statistics SSBO (DirpoleFrameStats in dirpole_common.glsl).
enum FrameWord { MAX_CHANGE, MAX_MEAN, SAMPLED, COVERED, RESTARTED, LISTED, MIN_N, MAX_N, WORDS };

/// Samples per texel and light for a frame that samples `texels` texels: as many as `budget`
/// texel-samples allow (0 = unlimited), at least 1, at most samplesPerFrame.
int framePlanSamples(int budget, int64_t texels, int lights, int samplesPerFrame) {
    if (budget <= 0 || texels <= 0)
        return samplesPerFrame;
    const int64_t perSample = texels * std::max(lights, 1);
    return int(std::clamp<int64_t>(budget / perSample, 1, samplesPerFrame));
}

/// Cube faces +x −x +y −y +z −z: face f's camera sits on the +axis side, looking along −axis.
constexpr std::array<glm::vec3, 6> FACE_AXES = {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
                                                glm::vec3(0, 1, 0), glm::vec3(0, -1, 0),
                                                glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)};

/// Nodes of the energy-normalisation table in dirpole_gather.comp (shaders/shared/DirpoleShared.h).
constexpr int ENERGY_NODES = LUCENT_DIRPOLE_ENERGY_NODES;
static_assert(DirpoleExitTable::ALBEDO_NODES == LUCENT_DIRPOLE_EXIT_ALBEDO_NODES &&
                  DirpoleExitTable::COSINE_NODES == LUCENT_DIRPOLE_EXIT_COSINE_NODES &&
                  DirpoleIncidenceTable::ALBEDO_NODES == LUCENT_DIRPOLE_INCIDENCE_ALBEDO_NODES &&
                  DirpoleIncidenceTable::COSINE_NODES == LUCENT_DIRPOLE_INCIDENCE_COSINE_NODES,
              "the dirpole tables' layout is shared with GLSL (shaders/shared/DirpoleShared.h)");

Vector3f upFor(const Vector3f& forward) {
    return std::abs(forward.y) < 0.99f ? Vector3f(0, 1, 0) : Vector3f(1, 0, 0);
}

}  // namespace

struct DirpoleSubsurfaceProvider::Impl {
    Impl(ProviderStats& st, detail::VolumeTextures& v) : stats(st), volume(v) {}
    DirpoleSettings settings;
    ProviderStats& stats;            ///< the base class's
    detail::VolumeTextures& volume;  ///< the material, 3-D textures (the base class's)
    gpu::GlProgram gbufferProgram, prepareProgram, gatherProgram, combineProgram;
    gpu::GlProgram coverProgram;    ///< dirpole_compact.comp over the grid: covered texels
    gpu::GlProgram compactProgram;  ///< dirpole_compact.comp FROM_LIST: the gather's work list
    gpu::GlObject fbo, statsBuffer;
    gpu::GlObject coveredList;  ///< SSBO, one uint per face texel: the covered texels
    gpu::GlObject workList;     ///< SSBO, one uint per face texel: the texels the gather samples
    DirpoleStats passStats;
    mutable gpu::GpuProfiler profiler;  ///< GL_TIMESTAMP pairs per pass (passTimes())

    // Light-view G-buffers (one layer per light) and cube faces (6 layers).
    gpu::GlObject lightPosition, lightNormal, lightDepth;
    int lightMapSize = 0, lightLayers = 0;
    gpu::GlObject facePosition, faceNormal, faceDepth, accum;
    gpu::GlObject faceSigmaT, faceSigmaS;  ///< the material each texel's sum was computed for
    int faceSize = 0;
    std::vector<Mat4f> lightClip;
    std::array<Mat4f, 6> faceClip{};
    std::array<Point3f, 6> faceEye{};
    float faceNear = 1.f, faceFar = 2.f;
    bool haveGeometry = false;
    /// DirpoleEnergyTable nodes for `energyEta` (uniform in s = √(1 − α′)), as uniforms.
    std::vector<float> energyNodes;
    float energyEta = 0.f;
    EnergyTarget energyTarget = EnergyTarget::ExactHalfSpace;
    /// DirpoleExitTable for `exitEta` (the exact target's exit-angle correction), an SSBO.
    gpu::GlObject exitTable;
    float exitEta = 0.f;
    /// DirpoleIncidenceTable for `incidenceEta` (its incidence correction), an SSBO.
    gpu::GlObject incidenceTable;
    float incidenceEta = 0.f, incidenceMinCosine = 0.f;

    // What the G-buffers and the accumulation were computed for.
    bool needGeometry = true;      ///< re-render the light and cube G-buffers
    bool needClear = true;         ///< clear every texel's sum, count and material
    bool needMaterialPass = true;  ///< run the prepare pass (material may have changed)
    std::vector<unsigned char> lastLights;
    std::vector<uint64_t> lastMeshes;  // (vertex array, revision) of the rasterised meshes
    /// Fewest and most samples of a covered texel (exact: from the prepare pass after a
    /// restart, then advanced with each frame's plan), and the covered texels.
    int minN = 0, maxN = 0, covered = 0;
    /// The level at which the accumulation converged (threshold or maxFrames), −1: not yet.
    int convergedLevel = -1;

    /// Material-only restart at the next frame (the texels whose material changed restart);
    /// `converged` is cleared at once so that callers polling it schedule that frame.
    void markRestart() {
        detail::restartAccumulation(stats);
        needMaterialPass = true;
    }
    /// Everything restarts at the next frame (settings, lights, meshes).
    /// The exact target's tables apply (exit angle, incidence).
    [[nodiscard]] bool exactTarget() const {
        return settings.energyNormalised && settings.energyTarget == EnergyTarget::ExactHalfSpace;
    }

    /// `buffer` becomes an immutable SSBO holding `values`.
    static void replaceTableBuffer(gpu::GlObject& buffer, const std::vector<float>& values) {
        buffer.destroy();
        buffer = gpu::createBuffer(values.size() * sizeof(float), values.data(), 0);
    }

    void markFullRestart() {
        markRestart();
        needClear = true;
    }

    void destroyMaps() {
        for (gpu::GlObject* o :
             {&lightPosition, &lightNormal, &lightDepth, &facePosition, &faceNormal, &faceDepth,
              &accum, &faceSigmaT, &faceSigmaS, &coveredList, &workList})
            o->destroy();
        lightMapSize = lightLayers = faceSize = 0;
    }

    void ensureMaps(int lights) {
        const int layers = std::max(lights, 1);
        if (lightMapSize != settings.lightMapSize || lightLayers != layers) {
            for (gpu::GlObject* o : {&lightPosition, &lightNormal, &lightDepth})
                o->destroy();
            const int n = settings.lightMapSize;
            lightPosition = gpu::createTexture2DArray(GL_RGBA32F, n, n, layers);
            lightNormal = gpu::createTexture2DArray(GL_RGBA32F, n, n, layers);
            lightDepth = gpu::createTexture2D(GL_DEPTH_COMPONENT32F, n, n);
            lightMapSize = n;
            lightLayers = layers;
        }
        if (faceSize != settings.cubeMapSize) {
            for (gpu::GlObject* o :
                 {&facePosition, &faceNormal, &faceDepth, &accum, &faceSigmaT, &faceSigmaS})
                o->destroy();
            const int n = settings.cubeMapSize;
            facePosition = gpu::createTexture2DArray(GL_RGBA32F, n, n, 6);
            faceNormal = gpu::createTexture2DArray(GL_RGBA32F, n, n, 6);
            faceDepth = gpu::createTexture2DArray(GL_DEPTH_COMPONENT32F, n, n, 6);
            accum = gpu::createTexture2DArray(GL_RGBA32F, n, n, 6);
            faceSigmaT = gpu::createTexture2DArray(GL_RGBA32F, n, n, 6);
            faceSigmaS = gpu::createTexture2DArray(GL_RGBA32F, n, n, 6);
            for (gpu::GlObject* o : {&coveredList, &workList}) {
                o->destroy();
                *o = gpu::createBuffer(size_t(6) * size_t(n) * size_t(n) * sizeof(uint32_t),
                                       nullptr, 0);
            }
            faceSize = n;
            needClear = true;
        }
    }

    /// Every texel: no samples, no material (the prepare pass stores it).
    void clearAccumulation() {
        const float zero[4] = {0.f, 0.f, 0.f, 0.f};
        for (const gpu::GlObject* o : {&accum, &faceSigmaT, &faceSigmaS})
            if (o->isValid())
                glClearTexImage(o->id(), 0, GL_RGBA, GL_FLOAT, zero);
        minN = maxN = covered = 0;
        convergedLevel = -1;
        needClear = false;
        needMaterialPass = true;
        if (!haveGeometry)
            return;
        // The covered texels, which every per-texel pass runs over (dirpole_compact.comp).
        covered = listTexels(coverProgram, coveredList, 0xffffffffu);
    }

    [[nodiscard]] bool rasterised(int mesh) const {
        return settings.meshId < 0 || settings.meshId == mesh;
    }

    void drawObject(const gpu::GBufferView& g) const {
        for (size_t i = 0; i < g.meshes.size(); ++i) {
            if (!rasterised(int(i)) || g.meshes[i].indexCount == 0)
                continue;
            glBindVertexArray(g.meshes[i].vertexArray);
            glDrawElements(GL_TRIANGLES, g.meshes[i].indexCount, GL_UNSIGNED_INT, nullptr);
        }
    }

    /// Renders the object into layer `layer` of (position, normal) with depth `depth` (a 2-D
    /// texture when depthLayer < 0, else that layer of a 2-D array).
    void rasterise(const gpu::GBufferView& g, const Mat4f& clipFromWorld, GLuint position,
                   GLuint normal, int layer, GLuint depth, int depthLayer, int size) {
        glNamedFramebufferTextureLayer(fbo.id(), GL_COLOR_ATTACHMENT0, position, 0, layer);
        glNamedFramebufferTextureLayer(fbo.id(), GL_COLOR_ATTACHMENT1, normal, 0, layer);
        if (depthLayer < 0)
            glNamedFramebufferTexture(fbo.id(), GL_DEPTH_ATTACHMENT, depth, 0);
        else
            glNamedFramebufferTextureLayer(fbo.id(), GL_DEPTH_ATTACHMENT, depth, 0, depthLayer);
        if (glCheckNamedFramebufferStatus(fbo.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            LUCENT_THROW(GpuError, "DirpoleSubsurfaceProvider: incomplete G-buffer framebuffer (",
                         size, " texels)");
        glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
        glViewport(0, 0, size, size);
        const float zero[4] = {0.f, 0.f, 0.f, 0.f};
        const float one = 1.f;
        glClearNamedFramebufferfv(fbo.id(), GL_COLOR, 0, zero);
        glClearNamedFramebufferfv(fbo.id(), GL_COLOR, 1, zero);
        glClearNamedFramebufferfv(fbo.id(), GL_DEPTH, 0, &one);
        glUniformMatrix4fv(0, 1, GL_FALSE, &clipFromWorld[0][0]);
        drawObject(g);
    }

    /// Seed 001 §4.1 steps 1–2 geometry: light-view G-buffers and cube-face G-buffers + depth.
    void renderGeometry(const gpu::GBufferView& g, const std::vector<gpu::shared::GpuLight>& ls) {
        Bounds3f b;
        for (size_t i = 0; i < g.meshes.size(); ++i)
            if (rasterised(int(i)))
                b.expand(g.meshes[i].bounds);
        haveGeometry = !b.isEmpty();
        if (!haveGeometry)
            return;
        ensureMaps(int(ls.size()));
        ++passStats.geometryRenders;
        needClear = true;  // the texels now stand for other surface points
        const Point3f c = b.center();
        const float R = std::max(0.5f * glm::length(b.extent()), 1e-3f);  // bounding sphere
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDepthMask(GL_TRUE);
        glDisable(GL_CULL_FACE);
        glDisable(GL_BLEND);
        glUseProgram(gbufferProgram.id());
        // Step 1: one light-view G-buffer per light.
        lightClip.assign(ls.size(), Mat4f(1.f));
        for (size_t l = 0; l < ls.size(); ++l) {
            const int type = int(ls[l].positionType.w + 0.5f);
            if (type == LUCENT_LIGHT_DIRECTIONAL) {
                // Orthographic, covering the object's bounding sphere (the dirpole thesis §4.1 step
                // 1).
                const Vector3f dir = glm::normalize(Vector3f(ls[l].directionCosOuter));
                const Mat4f view = glm::lookAt(c - dir * (2.f * R), c, upFor(dir));
                lightClip[l] = glm::ortho(-R, R, -R, R, 0.5f * R, 3.5f * R) * view;
            } else {
                // Perspective from the light, the cone just containing the bounding sphere;
                // a light inside it sees at most a 170° cone (documented limitation).
                const Point3f p(ls[l].positionType);
                const float d = glm::length(c - p);
                const Vector3f dir = d > 0.f ? (c - p) / d : Vector3f(0, 0, -1);
                const float half = d > R * 1.0001f
                                       ? std::min(std::asin(R / d) * 1.02f, glm::radians(85.f))
                                       : glm::radians(85.f);
                const float near = std::max(d - R, 1e-3f * R) * 0.99f;
                const Mat4f view = glm::lookAt(p, p + dir, upFor(dir));
                lightClip[l] = glm::perspective(2.f * half, 1.f, near, (d + R) * 1.01f) * view;
            }
            rasterise(g, lightClip[l], lightPosition.id(), lightNormal.id(), int(l),
                      lightDepth.id(), -1, lightMapSize);
        }
        // Step 2: six orthographic faces around the bounding-box centre.
        faceNear = R;
        faceFar = 3.f * R;
        for (int f = 0; f < 6; ++f) {
            const Vector3f forward = -FACE_AXES[size_t(f)];
            faceEye[size_t(f)] = c + FACE_AXES[size_t(f)] * (2.f * R);
            const Mat4f view = glm::lookAt(faceEye[size_t(f)], c, upFor(forward));
            faceClip[size_t(f)] = glm::ortho(-R, R, -R, R, faceNear, faceFar) * view;
            rasterise(g, faceClip[size_t(f)], facePosition.id(), faceNormal.id(), f, faceDepth.id(),
                      f, faceSize);
        }
        glBindVertexArray(0);
        glUseProgram(0);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }

    /// Binds the frame-statistics SSBO with its words reset (min word = UINT32_MAX).
    void resetFrameStats() {
        std::array<uint32_t, WORDS> words{};
        words[MIN_N] = 0xffffffffu;
        glNamedBufferSubData(statsBuffer.id(), 0, sizeof(words), words.data());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, statsBuffer.id());
    }
    [[nodiscard]] std::array<uint32_t, WORDS> readFrameStats() const {
        // Eight words, synchronous: the CPU plans the next pass from them.
        std::array<uint32_t, WORDS> words{};
        glGetNamedBufferSubData(statsBuffer.id(), 0, sizeof(words), words.data());
        return words;
    }

    /// dirpole_prepare.comp: restarts the texels whose material changed (docs/methods/dipole.md
    /// §7, "Latency") and counts. @return the statistics words.
    std::array<uint32_t, WORDS> prepare() {
        const gpu::GlProgram& p = prepareProgram;
        glUseProgram(p.id());
        resetFrameStats();
        glBindTextureUnit(0, facePosition.id());
        glBindTextureUnit(1, faceNormal.id());
        glBindImageTexture(0, accum.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(1, faceSigmaT.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(2, faceSigmaS.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, coveredList.id());
        volume.bind(p, 6, 7);
        glUniform1ui(p.uniformLocation("u_sourceCount"), uint32_t(covered));
        gpu::dispatchLine(unsigned(covered + 63) / 64);
        // The gather reads the stored material as textures and the accumulator as an image;
        // the CPU reads the counts.
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                        GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        glUseProgram(0);
        return readFrameStats();
    }

    /// dirpole_compact.comp: the covered texels with fewer than `target` samples into `out`,
    /// with `program` = coverProgram (over the face grid) or compactProgram (over the covered
    /// list). @return their number.
    int listTexels(const gpu::GlProgram& program, const gpu::GlObject& out, uint32_t target) {
        const bool fromList = &program == &compactProgram;
        glUseProgram(program.id());
        resetFrameStats();
        glBindTextureUnit(0, facePosition.id());
        glBindTextureUnit(1, accum.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, out.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, coveredList.id());
        glUniform1i(program.uniformLocation("u_faceSize"), faceSize);
        glUniform1ui(program.uniformLocation("u_sourceCount"), uint32_t(covered));
        glUniform1ui(program.uniformLocation("u_target"), target);
        const unsigned groups = unsigned(faceSize + 7) / 8;
        if (fromList)
            gpu::dispatchLine(unsigned(covered + 63) / 64);
        else
            glDispatchCompute(groups, groups, 6);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        glUseProgram(0);
        return int(readFrameStats()[LISTED]);
    }

    /// Seed 001 §4.1 step 2 accumulation: each of the `listed` texels of the work list with
    /// fewer than `target` samples gets min(k, target − N) more. @return the statistics words.
    std::array<uint32_t, WORDS> gather(const gpu::GBufferView& g, int k, int target, int listed) {
        const gpu::GlProgram& p = gatherProgram;
        glUseProgram(p.id());
        resetFrameStats();
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, workList.id());
        glUniform1ui(p.uniformLocation("u_listed"), uint32_t(listed));
        glBindTextureUnit(0, facePosition.id());
        glBindTextureUnit(1, faceNormal.id());
        glBindTextureUnit(2, lightPosition.id());
        glBindTextureUnit(3, lightNormal.id());
        glBindTextureUnit(4, faceSigmaT.id());
        glBindTextureUnit(5, faceSigmaS.id());
        glBindImageTexture(0, accum.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_BINDING_LIGHTS, g.lightBuffer);
        if (!lightClip.empty())
            glUniformMatrix4fv(0, GLsizei(lightClip.size()), GL_FALSE, &lightClip[0][0][0]);
        glUniform1i(p.uniformLocation("u_lightCount"), int(lightClip.size()));
        glUniform1i(p.uniformLocation("u_lightMapSize"), lightMapSize);
        glUniform1f(p.uniformLocation("u_eta"), settings.eta);
        const Boundary bd = Boundary::of(settings.eta);
        glUniform3f(p.uniformLocation("u_boundary"), float(bd.fdr), float(bd.c1), float(bd.c2));
        glUniform3f(p.uniformLocation("u_moments"), float(bd.c1), float(bd.c2),
                    float(fresnelMoment(1, 1.0 / settings.eta)));
        if (settings.energyNormalised &&
            (energyEta != settings.eta || energyTarget != settings.energyTarget)) {
            // DirpoleEnergyTable::scale resampled at ENERGY_NODES nodes uniform in
            // s = √(1 − α′) (smooth in s; linear interpolation error < 1e-4 relative).
            // ≈ 150 ms, once per η, target and process
            const DirpoleEnergyTable& table =
                *DirpoleEnergyTable::shared(settings.eta, settings.energyTarget);
            energyNodes.resize(ENERGY_NODES);
            for (int i = 0; i < ENERGY_NODES; ++i) {
                const double si = double(i) / (ENERGY_NODES - 1);
                energyNodes[size_t(i)] = float(table.scale(1.0 - si * si));
            }
            energyEta = settings.eta;
            energyTarget = settings.energyTarget;
        }
        // The exact target's incidence correction k(α′, μ₀) per light sample.
        const bool incidenceCorrection = exactTarget();
        if (incidenceCorrection && incidenceEta != settings.eta) {
            const DirpoleIncidenceTable& table = *DirpoleIncidenceTable::shared(settings.eta);
            replaceTableBuffer(incidenceTable, table.values());
            incidenceEta = settings.eta;
            incidenceMinCosine = float(table.minCosine());
        }
        glUniform1i(p.uniformLocation("u_incidenceCorrection"), incidenceCorrection ? 1 : 0);
        if (incidenceCorrection) {
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_DIRPOLE_BINDING_INCIDENCE_TABLE,
                             incidenceTable.id());
            glUniform1f(p.uniformLocation("u_incidenceMinCosine"), incidenceMinCosine);
        }
        glUniform1i(p.uniformLocation("u_energyNormalised"), settings.energyNormalised ? 1 : 0);
        if (settings.energyNormalised)
            glUniform1fv(p.uniformLocation("u_energyScale"), GLsizei(energyNodes.size()),
                         energyNodes.data());
        glUniform1ui(p.uniformLocation("u_k"), uint32_t(k));
        glUniform1ui(p.uniformLocation("u_target"), uint32_t(target));
        glUniform1f(p.uniformLocation("u_shrink"), settings.gbufferShrink ? settings.shrink : 0.f);
        glUniform1ui(p.uniformLocation("u_seed"), settings.seed);
        gpu::dispatchLine(unsigned(listed + 63) / 64);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                        GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        glUseProgram(0);
        return readFrameStats();
    }

    /// One frame of the progressive accumulation: after a restart the prepare pass first (it
    /// restarts the texels whose material changed and counts), then the frame's plan (target
    /// count and k), the work list, the gather and the statistics.
    void accumulate(const gpu::GBufferView& g) {
        const int spf = settings.samplesPerFrame;
        const int maxSamples = settings.maxFrames * spf;
        const int lights = std::max(int(lightClip.size()), 1);
        passStats.texelsRestarted = passStats.texelsSampled = passStats.samplesThisFrame = 0;
        if (needMaterialPass) {
            std::array<uint32_t, WORDS> prep{};
            {
                const auto scope = profiler.scope("prepare");
                prep = prepare();
            }
            needMaterialPass = false;
            LUCENT_ASSERT(int(prep[COVERED]) == covered);
            passStats.texelsRestarted = int(prep[RESTARTED]);
            minN = covered > 0 ? int(prep[MIN_N]) : 0;
            maxN = int(prep[MAX_N]);
        }
        passStats.texelsCovered = covered;
        passStats.minSamples = minN;
        passStats.maxSamples = maxN;
        if (covered == 0) {
            stats.converged = true;  // no covered texel: black until something changes
            return;
        }
        const bool catchUp = minN < maxN;
        if (!catchUp && (maxN >= maxSamples || maxN == convergedLevel)) {
            // Every texel is at a level that already converged (e.g. a stroke that changed no
            // face texel's material): nothing to add.
            stats.converged = true;
            return;
        }
        // Catch-up: only the texels behind the most sampled ones (restarted by a material
        // change) sample, up to that level; else every texel advances by k.
        int listed = 0;
        {
            const auto scope = profiler.scope("compact");
            listed = listTexels(compactProgram, workList, catchUp ? uint32_t(maxN) : 0xffffffffu);
        }
        const int budget =
            stats.frames == 0 ? settings.firstFrameSampleBudget : settings.frameSampleBudget;
        int k = framePlanSamples(budget, listed, lights, spf);
        const int target = catchUp ? maxN : std::min(maxN + k, maxSamples);
        if (!catchUp)
            k = target - maxN;
        std::array<uint32_t, WORDS> words{};
        {
            const auto scope = profiler.scope("gather");
            words = gather(g, k, target, listed);
        }
        float maxChange = 0.f, maxMean = 0.f;
        std::memcpy(&maxChange, &words[MAX_CHANGE], sizeof(float));
        std::memcpy(&maxMean, &words[MAX_MEAN], sizeof(float));
        const int before = maxN;
        minN = std::min(minN + k, target);  // every listed texel got min(k, target − N)
        maxN = target;
        passStats.texelsSampled = int(words[SAMPLED]);
        passStats.samplesThisFrame = k;
        passStats.minSamples = minN;
        passStats.maxSamples = maxN;
        ++stats.frames;
        stats.samplesPerPixel = minN;
        if (catchUp) {
            // Converged again once the restarted texels reach the level that had converged.
            stats.converged = minN == target && target == convergedLevel;
            return;
        }
        // Every texel advanced by k: the largest change of a texel's mean, relative to the
        // brightest mean. Adding k samples at count N moves a mean by ≈ (k/(N + k))·σ/√k ∝ √k,
        // so the change is scaled by √(samplesPerFrame/k) to the step the threshold is meant
        // for: a smaller budget stops at about the same sample count, not earlier.
        if (before > 0)
            stats.lastChange =
                maxMean > 0.f ? maxChange / maxMean * std::sqrt(float(spf) / float(k)) : 0.f;
        const bool done = target >= maxSamples || !(maxMean > 0.f) ||
                          (before > 0 && stats.lastChange < settings.convergenceThreshold);
        if (done) {
            convergedLevel = target;
            stats.converged = true;
        }
    }

    /// Seed 001 §4.1 step 3: six-face combination with the depth test, times T₂₁.
    void combine(const gpu::GBufferView& g, unsigned target) {
        const gpu::GlProgram& p = combineProgram;
        glUseProgram(p.id());
        glBindTextureUnit(0, g.positionTexture);
        glBindTextureUnit(1, g.normalTexture);
        glBindTextureUnit(2, faceDepth.id());
        glBindTextureUnit(3, accum.id());
        glBindImageTexture(0, target, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glUniformMatrix4fv(20, 6, GL_FALSE, &faceClip[0][0][0]);
        std::array<glm::vec3, 6> axes{};
        for (size_t f = 0; f < 6; ++f)
            axes[f] = -FACE_AXES[f];
        glUniform3fv(p.uniformLocation("u_faceEye"), 6, &faceEye[0][0]);
        glUniform3fv(p.uniformLocation("u_faceAxis"), 6, &axes[0][0]);
        glUniform2f(p.uniformLocation("u_faceNearFar"), faceNear, faceFar);
        glUniform1i(p.uniformLocation("u_faceSize"), faceSize);
        glUniform1f(p.uniformLocation("u_intrusion"),
                    settings.cubemapIntrusion ? settings.intrusion : 0.f);
        // Without the §4.3.3 fix the test is a bare depth compare, with the float round-off of
        // the face's depth range as the only margin.
        glUniform1f(p.uniformLocation("u_bias"),
                    settings.shadowBias ? settings.bias : 1e-4f * (faceFar - faceNear));
        glUniform1f(p.uniformLocation("u_slopeBias"),
                    settings.shadowBias ? settings.slopeBias : 0.f);
        glUniform1f(p.uniformLocation("u_faceTexel"), (faceFar - faceNear) / float(faceSize));
        glUniform1f(p.uniformLocation("u_eta"), settings.eta);
        // Camera from the G-buffer matrices: an orthographic clip matrix has a constant w row.
        const Mat4f clipFromView = g.clipFromWorld * glm::inverse(g.viewFromWorld);
        const bool ortho = std::abs(clipFromView[2][3]) < 1e-6f;
        const Vector3f forward = glm::normalize(-Vector3f(glm::inverse(g.viewFromWorld)[2]));
        glUniform3f(p.uniformLocation("u_eye"), g.cameraPosition.x, g.cameraPosition.y,
                    g.cameraPosition.z);
        glUniform3f(p.uniformLocation("u_viewDir"), forward.x, forward.y, forward.z);
        glUniform1i(p.uniformLocation("u_ortho"), ortho ? 1 : 0);
        glUniform2i(p.uniformLocation("u_size"), g.width, g.height);
        glUniform1i(p.uniformLocation("u_meshId"), settings.meshId);
        // The exact target's exit-angle correction: c(α′, t) at x_o's material (docs/methods/
        // dipole.md §1), so the light leaves with the half-space's angular distribution.
        const bool exitCorrection = exactTarget();
        if (exitCorrection && exitEta != settings.eta) {
            // ≈ 0.1 s, once per η and process
            replaceTableBuffer(exitTable, DirpoleExitTable::shared(settings.eta)->values());
            exitEta = settings.eta;
        }
        glUniform1i(p.uniformLocation("u_exitCorrection"), exitCorrection ? 1 : 0);
        if (exitCorrection) {
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_DIRPOLE_BINDING_EXIT_TABLE,
                             exitTable.id());
            volume.bind(p, 6, 7);
        }
        glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
        // The target (imageStore) is read by the shading pass (texture fetch) and cleared by
        // the renderer at the next frame (framebuffer clear or texture update, GL 4.5 §7.13.2).
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                        GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
        glUseProgram(0);
    }
};

DirpoleSubsurfaceProvider::DirpoleSubsurfaceProvider()
    : MaterialSubsurfaceProvider("DirpoleSubsurfaceProvider"),
      m(std::make_unique<Impl>(m_stats, *m_volume)) {}

DirpoleSubsurfaceProvider::~DirpoleSubsurfaceProvider() = default;

void DirpoleSubsurfaceProvider::createGl(const gpu::ShaderLibrary& library) {
    m->gbufferProgram =
        gpu::GlProgram::graphics(library, "dirpole_gbuffer.vert", "dirpole_gbuffer.frag");
    m->prepareProgram = gpu::GlProgram::compute(library, "dirpole_prepare.comp");
    m->coverProgram = gpu::GlProgram::compute(library, "dirpole_compact.comp");
    m->compactProgram = gpu::GlProgram::compute(library, "dirpole_compact.comp", {"FROM_LIST"});
    m->gatherProgram = gpu::GlProgram::compute(library, "dirpole_gather.comp");
    m->combineProgram = gpu::GlProgram::compute(library, "dirpole_combine.comp");
    m->fbo = gpu::GlObject::create(gpu::GlObjectKind::Framebuffer);
    const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(m->fbo.id(), 2, bufs);
    m->statsBuffer = gpu::createBuffer(WORDS * sizeof(uint32_t), nullptr,
                                       GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
    m->needGeometry = true;
}

void DirpoleSubsurfaceProvider::destroyGl() {
    for (gpu::GlProgram* p : {&m->gbufferProgram, &m->prepareProgram, &m->coverProgram,
                              &m->compactProgram, &m->gatherProgram, &m->combineProgram})
        p->destroy();
    for (gpu::GlObject* o : {&m->fbo, &m->statsBuffer, &m->exitTable, &m->incidenceTable})
        o->destroy();
    m->exitEta = m->incidenceEta = 0.f;
    m->destroyMaps();
    m->profiler.destroy();
    m->needGeometry = true;
    m->markFullRestart();
}

void DirpoleSubsurfaceProvider::setSettings(const DirpoleSettings& settings) {
    validateSettings(settings);
    if (!sameGeometry(settings, m->settings))
        m->needGeometry = true;
    if (!sameAccumulation(settings, m->settings))
        m->markFullRestart();
    m->settings = settings;
}

const DirpoleSettings& DirpoleSubsurfaceProvider::settings() const {
    return m->settings;
}

void DirpoleSubsurfaceProvider::restart() {
    // setMaterial, uploadBricks, syncMaterial, reset(): the G-buffers depend on the lights,
    // meshes (revisions are compared each frame) and map sizes only; the prepare pass restarts
    // the texels whose material changed.
    m->markRestart();
}

const DirpoleStats& DirpoleSubsurfaceProvider::dirpoleStats() const {
    return m->passStats;
}

std::vector<gpu::PassTiming> DirpoleSubsurfaceProvider::passTimes() const {
    if (!m_created)
        return {};
    m->profiler.collect(/*wait=*/true);
    return m->profiler.latest();
}

DirpoleSubsurfaceProvider::DebugTextures DirpoleSubsurfaceProvider::debugTextures() const {
    return {m->lightPosition.id(), m->lightNormal.id(), m->facePosition.id(),
            m->faceNormal.id(),    m->faceDepth.id(),   m->accum.id()};
}

void DirpoleSubsurfaceProvider::renderSubsurface(const gpu::GBufferView& g, unsigned target) {
    requireCreated("renderSubsurface");
    Impl& r = *m;
    gpu::GpuProfiler::FrameScope frame(r.profiler);  // cancelled if a pass throws
    // Material: a new grid or unreported edits (revision moved) re-upload everything; the
    // prepare pass then finds the texels whose material changed.
    if (r.volume.syncForFrame(r.stats))
        r.markRestart();
    // Lights (the renderer's SSBO, 64 bytes each) and the rasterised meshes' uploads. The
    // camera is not compared: the cube faces do not depend on it (the dirpole thesis §4.1).
    const int lightCount = std::clamp(g.lightBuffer ? g.lightCount : 0, 0, LUCENT_MAX_LIGHTS);
    std::vector<unsigned char> lightBytes(size_t(lightCount) * sizeof(gpu::shared::GpuLight));
    if (!lightBytes.empty())
        glGetNamedBufferSubData(g.lightBuffer, 0, GLsizeiptr(lightBytes.size()), lightBytes.data());
    std::vector<uint64_t> meshes;
    for (size_t i = 0; i < g.meshes.size(); ++i)
        if (r.rasterised(int(i)))
            meshes.insert(meshes.end(),
                          {uint64_t(i), g.meshes[i].vertexArray, g.meshes[i].revision});
    if (lightBytes != r.lastLights || meshes != r.lastMeshes) {
        r.needGeometry = true;
        r.markFullRestart();
        r.lastLights = lightBytes;
        r.lastMeshes = std::move(meshes);
    }
    if (r.needGeometry) {
        const auto scope = r.profiler.scope("geometry");
        std::vector<gpu::shared::GpuLight> lights(static_cast<size_t>(lightCount));
        if (!lights.empty())
            std::memcpy(lights.data(), lightBytes.data(), lightBytes.size());
        r.renderGeometry(g, lights);
        r.needGeometry = false;
    }
    if (r.needClear)
        r.clearAccumulation();
    if (!r.haveGeometry)
        r.stats.converged = true;  // nothing to rasterise: black until something changes
    if (r.haveGeometry && (!r.stats.converged || r.needMaterialPass))
        r.accumulate(g);
    if (r.haveGeometry) {
        const auto scope = r.profiler.scope("combine");
        r.combine(g, target);
    }
    frame.end();
    gpu::checkGlError("DirpoleSubsurfaceProvider::renderSubsurface");
}

}  // namespace lucent::dipole
