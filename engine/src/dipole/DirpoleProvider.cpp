// SPDX-License-Identifier: MIT
/// @file
/// @brief GL side of dipole::DirpoleSubsurfaceProvider (seed 001 §4): light-view and cube-face
/// G-buffers (shaders/dirpole_gbuffer.*), progressive gather (shaders/dirpole_gather.comp) and
/// the six-face combination (shaders/dirpole_combine.comp).

#include <lucent/dipole/DirpoleProvider.h>

#include "VolumeTextures.h"

#include <lucent/core/Error.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/Shader.h>
#include <lucent/material/MaterialVolume.h>
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
}

bool sameSettings(const DirpoleSettings& a, const DirpoleSettings& b) {
    return a.eta == b.eta && a.samplesPerFrame == b.samplesPerFrame && a.maxFrames == b.maxFrames &&
           a.convergenceThreshold == b.convergenceThreshold && a.lightMapSize == b.lightMapSize &&
           a.cubeMapSize == b.cubeMapSize && a.gbufferShrink == b.gbufferShrink &&
           a.shrink == b.shrink && a.cubemapIntrusion == b.cubemapIntrusion &&
           a.intrusion == b.intrusion && a.shadowBias == b.shadowBias && a.bias == b.bias &&
           a.slopeBias == b.slopeBias && a.energyNormalised == b.energyNormalised &&
           a.seed == b.seed && a.meshId == b.meshId;
}

/// Cube faces +x −x +y −y +z −z: face f's camera sits on the +axis side, looking along −axis.
constexpr std::array<glm::vec3, 6> FACE_AXES = {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
                                                glm::vec3(0, 1, 0), glm::vec3(0, -1, 0),
                                                glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)};

/// Nodes of the energy-normalisation table in dirpole_gather.comp (ENERGY_NODES there).
constexpr int ENERGY_NODES = 256;

Vector3f upFor(const Vector3f& forward) {
    return std::abs(forward.y) < 0.99f ? Vector3f(0, 1, 0) : Vector3f(1, 0, 0);
}

}  // namespace

struct DirpoleSubsurfaceProvider::Impl {
    Impl(ProviderStats& st, detail::VolumeTextures& v) : stats(st), volume(v) {}
    DirpoleSettings settings;
    ProviderStats& stats;            ///< the base class's
    detail::VolumeTextures& volume;  ///< the material, 3-D textures (the base class's)
    gpu::GlProgram gbufferProgram, gatherProgram, combineProgram;
    gpu::GlObject fbo, statsBuffer;

    // Light-view G-buffers (one layer per light) and cube faces (6 layers).
    gpu::GlObject lightPosition, lightNormal, lightDepth;
    int lightMapSize = 0, lightLayers = 0;
    gpu::GlObject facePosition, faceNormal, faceDepth, accum;
    int faceSize = 0;
    std::vector<Mat4f> lightClip;
    std::array<Mat4f, 6> faceClip{};
    std::array<Point3f, 6> faceEye{};
    float faceNear = 1.f, faceFar = 2.f;
    bool haveGeometry = false;
    /// DirpoleEnergyTable nodes for `energyEta` (uniform in s = √(1 − α′)), as uniforms.
    std::vector<float> energyNodes;
    float energyEta = 0.f;

    // What the accumulation was computed for.
    bool needReset = true;
    std::vector<unsigned char> lastLights;
    std::vector<uint64_t> lastMeshes;  // (vertex array, revision) of the rasterised meshes

    /// Restart at the next frame; `converged` is cleared at once so that callers polling it
    /// schedule that frame.
    void markReset() {
        needReset = true;
        stats.converged = false;
    }

    void destroyMaps() {
        for (gpu::GlObject* o : {&lightPosition, &lightNormal, &lightDepth, &facePosition,
                                 &faceNormal, &faceDepth, &accum})
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
            for (gpu::GlObject* o : {&facePosition, &faceNormal, &faceDepth, &accum})
                o->destroy();
            const int n = settings.cubeMapSize;
            facePosition = gpu::createTexture2DArray(GL_RGBA32F, n, n, 6);
            faceNormal = gpu::createTexture2DArray(GL_RGBA32F, n, n, 6);
            faceDepth = gpu::createTexture2DArray(GL_DEPTH_COMPONENT32F, n, n, 6);
            accum = gpu::createTexture2DArray(GL_RGBA32F, n, n, 6);
            faceSize = n;
        }
    }

    void resetAccumulation() {
        detail::restartAccumulation(stats);
        needReset = false;
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
                // Orthographic, covering the object's bounding sphere (seed 001 §4.1 step 1).
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

    /// Seed 001 §4.1 step 2 accumulation: one more frame of disc samples per face texel.
    void gather(const gpu::GBufferView& g) {
        const uint32_t zero[2] = {0u, 0u};
        glNamedBufferSubData(statsBuffer.id(), 0, sizeof(zero), zero);
        const gpu::GlProgram& p = gatherProgram;
        glUseProgram(p.id());
        glBindTextureUnit(0, facePosition.id());
        glBindTextureUnit(1, faceNormal.id());
        glBindTextureUnit(2, lightPosition.id());
        glBindTextureUnit(3, lightNormal.id());
        glBindImageTexture(0, accum.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_BINDING_LIGHTS, g.lightBuffer);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, statsBuffer.id());
        volume.bind(p, 6, 7);
        if (!lightClip.empty())
            glUniformMatrix4fv(0, GLsizei(lightClip.size()), GL_FALSE, &lightClip[0][0][0]);
        glUniform1i(p.uniformLocation("u_lightCount"), int(lightClip.size()));
        glUniform1i(p.uniformLocation("u_faceSize"), faceSize);
        glUniform1i(p.uniformLocation("u_lightMapSize"), lightMapSize);
        glUniform1f(p.uniformLocation("u_eta"), settings.eta);
        const Boundary bd = Boundary::of(settings.eta);
        glUniform3f(p.uniformLocation("u_boundary"), float(bd.fdr), float(bd.c1), float(bd.c2));
        glUniform3f(p.uniformLocation("u_moments"), float(bd.c1), float(bd.c2),
                    float(fresnelMoment(1, 1.0 / settings.eta)));
        if (settings.energyNormalised && energyEta != settings.eta) {
            // DirpoleEnergyTable::scale resampled at ENERGY_NODES nodes uniform in
            // s = √(1 − α′) (smooth in s; linear interpolation error < 1e-4 relative).
            const DirpoleEnergyTable table(settings.eta);  // ≈ 40 ms, once per η
            energyNodes.resize(ENERGY_NODES);
            for (int i = 0; i < ENERGY_NODES; ++i) {
                const double si = double(i) / (ENERGY_NODES - 1);
                energyNodes[size_t(i)] = float(table.scale(1.0 - si * si));
            }
            energyEta = settings.eta;
        }
        glUniform1i(p.uniformLocation("u_energyNormalised"), settings.energyNormalised ? 1 : 0);
        if (settings.energyNormalised)
            glUniform1fv(p.uniformLocation("u_energyScale"), GLsizei(energyNodes.size()),
                         energyNodes.data());
        glUniform1i(p.uniformLocation("u_samples"), settings.samplesPerFrame);
        glUniform1i(p.uniformLocation("u_framesBefore"), stats.frames);
        glUniform1f(p.uniformLocation("u_shrink"), settings.gbufferShrink ? settings.shrink : 0.f);
        glUniform1ui(p.uniformLocation("u_seed"), settings.seed);
        const unsigned groups = unsigned(faceSize + 7) / 8;
        glDispatchCompute(groups, groups, 6);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                        GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        glUseProgram(0);
        detail::finishFrame(stats, statsBuffer.id(), settings.samplesPerFrame, settings.maxFrames,
                            settings.convergenceThreshold);
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
        glUniform1i(p.uniformLocation("u_frames"), haveGeometry ? stats.frames : 0);
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
        glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
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
    m->gatherProgram = gpu::GlProgram::compute(library, "dirpole_gather.comp");
    m->combineProgram = gpu::GlProgram::compute(library, "dirpole_combine.comp");
    m->fbo = gpu::GlObject::create(gpu::GlObjectKind::Framebuffer);
    const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(m->fbo.id(), 2, bufs);
    m->statsBuffer =
        gpu::createBuffer(2 * sizeof(uint32_t), nullptr, GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
}

void DirpoleSubsurfaceProvider::destroyGl() {
    for (gpu::GlProgram* p : {&m->gbufferProgram, &m->gatherProgram, &m->combineProgram})
        p->destroy();
    for (gpu::GlObject* o : {&m->fbo, &m->statsBuffer})
        o->destroy();
    m->destroyMaps();
    m->needReset = true;
}

void DirpoleSubsurfaceProvider::setSettings(const DirpoleSettings& settings) {
    validateSettings(settings);
    if (!sameSettings(settings, m->settings))
        m->markReset();
    m->settings = settings;
}

const DirpoleSettings& DirpoleSubsurfaceProvider::settings() const {
    return m->settings;
}

void DirpoleSubsurfaceProvider::restart() {
    m->markReset();
}

DirpoleSubsurfaceProvider::DebugTextures DirpoleSubsurfaceProvider::debugTextures() const {
    return {m->lightPosition.id(), m->lightNormal.id(), m->facePosition.id(),
            m->faceNormal.id(),    m->faceDepth.id(),   m->accum.id()};
}

void DirpoleSubsurfaceProvider::renderSubsurface(const gpu::GBufferView& g, unsigned target) {
    requireCreated("renderSubsurface");
    Impl& r = *m;
    // Material: a new grid or unreported edits (revision moved) re-upload everything.
    if (r.volume.syncForFrame(r.stats))
        r.markReset();
    // Lights (the renderer's SSBO, 64 bytes each) and the rasterised meshes' uploads. The
    // camera is not compared: the cube faces do not depend on it (seed 001 §4.1).
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
        r.needReset = true;
        r.lastLights = lightBytes;
        r.lastMeshes = std::move(meshes);
    }
    if (r.needReset) {
        r.resetAccumulation();
        std::vector<gpu::shared::GpuLight> lights(static_cast<size_t>(lightCount));
        if (!lights.empty())
            std::memcpy(lights.data(), lightBytes.data(), lightBytes.size());
        r.renderGeometry(g, lights);
    }
    if (!r.haveGeometry)
        r.stats.converged = true;  // nothing to rasterise: black until something changes
    if (!r.stats.converged)
        r.gather(g);
    if (r.haveGeometry)
        r.combine(g, target);
    gpu::checkGlError("DirpoleSubsurfaceProvider::renderSubsurface");
}

}  // namespace lucent::dipole
