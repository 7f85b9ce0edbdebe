// SPDX-License-Identifier: MIT
/// @file
/// @brief PreviewRenderer: SceneRenderer + subsurface providers + brush overlay (GL via epoxy).

#include "PreviewRenderer.h"

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/dipole/DipoleProvider.h>
#include <lucent/dipole/DirpoleProvider.h>
#if LUCENT_APP_HAS_COMBINED
#include <lucent/combined/CombinedProvider.h>
#endif
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/gpu/Shader.h>
#include <lucent/sslpv/SslpvProvider.h>

#include <epoxy/gl.h>

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace lucent::app {

namespace {

using Method = RenderSettings::Method;

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

/// The single-scattering subsurface pass (shaders/preview_single_scatter.comp) and the two
/// RGBA32F 3-D textures of σt and σs′ it marches through (texels are voxels; only dirty 8³
/// bricks are re-uploaded).
class SingleScatterProvider final : public gpu::SubsurfaceProvider {
public:
    void create(const gpu::ShaderLibrary& lib) {
        m_program = gpu::GlProgram::compute(lib, "preview_single_scatter.comp", {"LOCAL_SIZE=8"});
    }
    void destroy() {
        m_program.destroy();
        glDeleteTextures(1, &m_texSigmaT);
        glDeleteTextures(1, &m_texSigmaS);
        m_texSigmaT = m_texSigmaS = 0;
        m_resolution = 0;
    }

    /// Uploads the whole volume (full) or the given bricks. @return bricks uploaded.
    int sync(const MaterialVolume& vol, bool full, const std::vector<int>& dirty) {
        const int res = vol.resolution();
        constexpr int B = MaterialVolume::BRICK, BV = MaterialVolume::BRICK_VOXELS;
        std::vector<int> bricks = dirty;
        if (full || res != m_resolution || m_texSigmaT == 0) {
            glDeleteTextures(1, &m_texSigmaT);
            glDeleteTextures(1, &m_texSigmaS);
            for (GLuint* tex : {&m_texSigmaT, &m_texSigmaS}) {
                glCreateTextures(GL_TEXTURE_3D, 1, tex);
                glTextureStorage3D(*tex, 1, GL_RGBA32F, res, res, res);
                for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
                    glTextureParameteri(*tex, w, GL_CLAMP_TO_BORDER);
                const float zero[4] = {0.f, 0.f, 0.f, 0.f};  // outside the grid: vacuum
                glTextureParameterfv(*tex, GL_TEXTURE_BORDER_COLOR, zero);
            }
            m_resolution = res;
            bricks.clear();
            for (int b = 0; b < vol.brickCount(); ++b)
                bricks.push_back(b);
        }
        std::vector<float> st(size_t(BV) * 4), ss(size_t(BV) * 4), cst, css;
        for (int b : bricks) {
            const float* d = vol.brickData(b);
            for (int v = 0; v < BV; ++v)
                for (int c = 0; c < 3; ++c) {
                    st[size_t(v) * 4 + size_t(c)] =
                        d[size_t(MaterialVolume::component(Channel::SigmaT, c)) * BV + size_t(v)];
                    ss[size_t(v) * 4 + size_t(c)] =
                        d[size_t(MaterialVolume::component(Channel::SigmaS, c)) * BV + size_t(v)];
                }
            const Coord o = vol.brickOrigin(b);
            const Coord size = glm::min(Coord(B), Coord(res) - o);
            const float* pt = st.data();
            const float* ps = ss.data();
            if (size != Coord(B)) {  // partial brick at the grid's far edge: compact the rows
                cst.clear();
                css.clear();
                for (int z = 0; z < size.z; ++z)
                    for (int y = 0; y < size.y; ++y)
                        for (int x = 0; x < size.x; ++x) {
                            const size_t v = size_t(MaterialVolume::voxelInBrick(x, y, z)) * 4;
                            cst.insert(cst.end(), st.begin() + long(v), st.begin() + long(v) + 4);
                            css.insert(css.end(), ss.begin() + long(v), ss.begin() + long(v) + 4);
                        }
                pt = cst.data();
                ps = css.data();
            }
            glTextureSubImage3D(m_texSigmaT, 0, o.x, o.y, o.z, size.x, size.y, size.z, GL_RGBA,
                                GL_FLOAT, pt);
            glTextureSubImage3D(m_texSigmaS, 0, o.x, o.y, o.z, size.x, size.y, size.z, GL_RGBA,
                                GL_FLOAT, ps);
        }
        return int(bricks.size());
    }

    /// Per-frame inputs.
    void setFrame(const Scene& scene, const MaterialVolume& vol, const RenderSettings& s) {
        m_scene = &scene;
        m_spec = vol.spec();
        m_settings = s;
    }

    void renderSubsurface(const gpu::GBufferView& g, unsigned target) override {
        const GLuint p = m_program.id();
        glUseProgram(p);
        const auto loc = [&](const char* n) { return glGetUniformLocation(p, n); };
        glUniform2i(loc("u_size"), g.width, g.height);
        glUniform3fv(loc("u_eye"), 1, glm::value_ptr(g.cameraPosition));
        glUniform1i(loc("u_steps"), std::clamp(m_settings.steps, 1, 512));
        glUniform1i(loc("u_lightSteps"), std::clamp(m_settings.lightSteps, 1, 128));
        glUniform1f(loc("u_eta"), m_scene->eta);
        glUniform3f(loc("u_ambient"), m_settings.ambient, m_settings.ambient, m_settings.ambient);
        glUniform1i(loc("u_meshId"), 1);  // object 0 only
        const int lightCount = std::min<int>(int(m_scene->lights.size()), 8);
        glUniform1i(loc("u_lightCount"), lightCount);
        char name[48];
        for (int i = 0; i < lightCount; ++i) {
            const Light& l = m_scene->lights[size_t(i)];
            const auto uni = [&](const char* base) {
                std::snprintf(name, sizeof name, "%s[%d]", base, i);
                return loc(name);
            };
            Rgb intensity = l.intensity;
            // Sphere light of radiance L, radius R: intensity L·πR² W/sr seen from afar.
            if (l.type == Light::Type::Sphere)
                intensity *= PI * l.radius * l.radius;
            const int type = l.type == Light::Type::Sphere ? 0 : int(l.type);
            glUniform1i(uni("u_lightType"), type);
            glUniform3f(uni("u_lightPos"), l.position.x, l.position.y, l.position.z);
            glUniform3f(uni("u_lightDir"), l.direction.x, l.direction.y, l.direction.z);
            glUniform3f(uni("u_lightI"), intensity.r, intensity.g, intensity.b);
            glUniform2f(uni("u_spotCos"), std::cos(glm::radians(l.spotOuterDeg)),
                        std::cos(glm::radians(l.spotInnerDeg)));
        }
        glUniform3f(loc("u_gridOrigin"), m_spec.origin.x, m_spec.origin.y, m_spec.origin.z);
        glUniform1f(loc("u_gridSize"), m_spec.voxelSize * float(m_spec.resolution));
        glUniform1f(loc("u_voxelSize"), m_spec.voxelSize);
        const GLint filter = m_settings.smoothVoxels ? GL_LINEAR : GL_NEAREST;
        for (GLuint tex : {m_texSigmaT, m_texSigmaS}) {
            glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, filter);
            glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, filter);
        }
        glBindTextureUnit(0, g.positionTexture);
        glBindTextureUnit(1, g.normalTexture);
        glBindTextureUnit(2, m_texSigmaT);
        glBindTextureUnit(3, m_texSigmaS);
        glBindImageTexture(0, target, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glDispatchCompute(GLuint((g.width + 7) / 8), GLuint((g.height + 7) / 8), 1);
        glUseProgram(0);
    }

private:
    gpu::GlProgram m_program;
    GLuint m_texSigmaT = 0, m_texSigmaS = 0;
    int m_resolution = 0;
    const Scene* m_scene = nullptr;
    GridSpec m_spec;
    RenderSettings m_settings;
};

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

/// Material hand-over of the brick-uploading providers (dipoles, directional dipole): the whole
/// volume when not synchronised (uploaded at the next frame), else the dirty bricks.
/// @return the bricks handed over.
template <class Provider>
int syncBricks(Provider& provider, bool& synced, MaterialVolume& vol,
               const std::vector<int>& dirty) {
    if (!synced) {
        provider.setMaterial(nullptr);
        provider.setMaterial(&vol);
        synced = true;
        return vol.brickCount();
    }
    if (!dirty.empty())
        provider.uploadBricks(dirty);
    return int(dirty.size());
}

SslpvProviderOptions sslpvOptions(const RenderSettings& s) {
    SslpvProviderOptions o;
    o.render.gridResolution = s.sslpvGrid;
    o.render.solver.maxSteps = std::clamp(s.sslpvSteps, 1, 512);
    o.render.solver.order = s.sslpvOrder == 2 ? 2 : 1;
    o.render.solver.mode = s.sslpvCalibrated ? SslpvMode::Calibrated : SslpvMode::Paper;
    o.backend = s.sslpvGlSolve ? SslpvBackend::Gl : SslpvBackend::Cpu;
    o.meshId = 0;
    return o;
}

bool sameSslpv(const SslpvProviderOptions& a, const SslpvProviderOptions& b) {
    return a.render.gridResolution == b.render.gridResolution &&
           a.render.solver.maxSteps == b.render.solver.maxSteps &&
           a.render.solver.order == b.render.solver.order &&
           a.render.solver.mode == b.render.solver.mode && a.backend == b.backend;
}

}  // namespace

struct PreviewRenderer::Impl {
    gpu::ShaderLibrary library;
    gpu::SceneRenderer renderer;
    SingleScatterProvider single;
    std::unique_ptr<SslpvSubsurfaceProvider> sslpv;
    SslpvProviderOptions sslpvOpts;
    std::unique_ptr<dipole::DipoleSubsurfaceProvider> dipole;
    std::unique_ptr<dipole::DirpoleSubsurfaceProvider> dirpole;
    bool dirpoleSynced = false;
#if LUCENT_APP_HAS_COMBINED
    std::unique_ptr<combined::CombinedSubsurfaceProvider> combined;
    bool combinedSynced = false, combinedMeshSet = false;
    float combinedEta = 0.f;
    std::vector<float> combinedLights;
#endif
    VolumeOverlay overlay;
    bool overlaySynced = false;
    gpu::GlProgram cursor;
    GLuint emptyVao = 0;
    bool created = false;
    bool meshUploaded = false;
    // Material synchronisation state per method (false: a full upload/resample is due).
    bool singleSynced = false, sslpvSynced = false, dipoleSynced = false;
    bool sslpvMeshSet = false;
    bool surfaceSet = false;                 ///< setSurfaceMaterial done for lastMethod
    float surfaceEta = 0.f, sslpvEta = 0.f;  ///< η the surface / SSLPV material was set with
    std::vector<float> lights, sslpvLights;
    Method lastMethod = Method::Direct;
    PreviewStats stats;

    /// One frame (PreviewRenderer::render).
    void renderFrame(PreviewFrame& f);
    /// After a frame of `method` threw: releases that method's provider and marks its inputs
    /// unsynchronised, so the method starts from scratch when it is next used.
    void dropFailedMethod(Method method);
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
        m->single.create(m->library);
        m->overlay.create(m->library);
        m->cursor = gpu::GlProgram::graphics(m->library, "post_fullscreen.vert",
                                             "preview_brush_cursor.frag");
        glCreateVertexArrays(1, &m->emptyVao);
    } catch (...) {
        destroy();
        throw;
    }
    m->meshUploaded = m->singleSynced = m->sslpvSynced = m->dipoleSynced = false;
    m->sslpvMeshSet = m->surfaceSet = m->overlaySynced = m->dirpoleSynced = false;
#if LUCENT_APP_HAS_COMBINED
    m->combinedSynced = m->combinedMeshSet = false;
    m->combinedLights.clear();
#endif
    m->lights.clear();
    m->sslpvLights.clear();
}

void PreviewRenderer::destroy() {
    if (!m->created)
        return;
    m->renderer.setSubsurfaceProvider(nullptr);
    m->renderer.destroy();
    m->single.destroy();
    m->overlay.destroy();
    m->overlaySynced = false;
    if (m->sslpv)
        m->sslpv->destroy();
    m->sslpv.reset();
    if (m->dipole)
        m->dipole->destroy();
    m->dipole.reset();
    if (m->dirpole)
        m->dirpole->destroy();
    m->dirpole.reset();
#if LUCENT_APP_HAS_COMBINED
    if (m->combined)
        m->combined->destroy();
    m->combined.reset();
#endif
    m->cursor.destroy();
    glDeleteVertexArrays(1, &m->emptyVao);
    m->emptyVao = 0;
    m->created = false;
}

bool PreviewRenderer::wantsAnotherFrame() const {
    if (!m->created)
        return false;
    const Method last = m->lastMethod;
    if (last == Method::Dipole || last == Method::BetterDipole)
        return m->dipole && !m->dipole->stats().converged;
    if (last == Method::DirectionalDipole)
        return m->dirpole && !m->dirpole->stats().converged;
#if LUCENT_APP_HAS_COMBINED
    if (last == Method::Combined)
        return m->combined && !m->combined->stats().converged;
#endif
    return false;
}

bool PreviewRenderer::hasMethod(RenderSettings::Method method) {
    return method != Method::Combined || LUCENT_APP_HAS_COMBINED != 0;
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
        m->dropFailedMethod(f.settings.method);
        throw;
    }
}

void PreviewRenderer::Impl::dropFailedMethod(Method method) {
    // The provider of the failed frame may be half-updated: the next frame that uses the method
    // builds it again from the scene (a full material, mesh and light sync).
    renderer.setSubsurfaceProvider(nullptr);
    switch (method) {
        case Method::Direct:
        case Method::SingleScattering:
            singleSynced = false;
            break;
        case Method::Sslpv:
            if (sslpv)
                sslpv->destroy();
            sslpv.reset();
            sslpvSynced = sslpvMeshSet = false;
            sslpvLights.clear();
            break;
        case Method::Dipole:
        case Method::BetterDipole:
            if (dipole)
                dipole->destroy();
            dipole.reset();
            dipoleSynced = false;
            break;
        case Method::DirectionalDipole:
            if (dirpole)
                dirpole->destroy();
            dirpole.reset();
            dirpoleSynced = false;
            break;
        case Method::Combined:
#if LUCENT_APP_HAS_COMBINED
            if (combined)
                combined->destroy();
            combined.reset();
            combinedSynced = combinedMeshSet = false;
            combinedLights.clear();
#endif
            break;
    }
    overlaySynced = false;
    surfaceSet = false;
}

void PreviewRenderer::Impl::renderFrame(PreviewFrame& f) {
    Impl& r = *this;
    const RenderSettings& s = f.settings;
    gpu::SceneRenderer& sr = r.renderer;
    sr.setSubsurfaceProvider(nullptr);
    if (f.sceneReplaced) {
        sr.clearMeshes();
        r.meshUploaded = r.singleSynced = r.sslpvSynced = r.dipoleSynced = false;
        r.sslpvMeshSet = r.surfaceSet = r.overlaySynced = r.dirpoleSynced = false;
#if LUCENT_APP_HAS_COMBINED
        r.combinedSynced = r.combinedMeshSet = false;
        r.combinedLights.clear();
#endif
        r.lights.clear();
        r.sslpvLights.clear();
    }
    const bool haveMesh = f.shownMesh && !f.shownMesh->isEmpty();
    if (haveMesh && !r.meshUploaded) {
        sr.addMesh(*f.shownMesh);
        r.meshUploaded = true;
    } else if (haveMesh && f.meshChanged) {
        sr.updateMesh(0, *f.shownMesh);
        if (r.dipole)
            r.dipole->reset();  // G-buffer changed without a camera/light/material change
    }
    std::vector<Light> lights = f.scene->lights;
    if (lights.size() > size_t(gpu::SceneRenderer::MAX_LIGHTS))
        lights.resize(size_t(gpu::SceneRenderer::MAX_LIGHTS));
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

    // Material: the dirty bricks go to the active method; the others re-sync in full later.
    Timer uploadTimer;
    MaterialVolume* vol = f.volume;
    const bool dirty = !f.dirtyBricks.empty();
    int bricksUsed = 0;
    gpu::SubsurfaceProvider* provider = nullptr;
    std::ostringstream detail;
    const Method method = haveMesh && vol && hasMethod(s.method) ? s.method : Method::Direct;
    if (method != Method::SingleScattering && dirty)
        r.singleSynced = false;
    if (method != Method::Sslpv && dirty)
        r.sslpvSynced = false;
    const bool isDipole = method == Method::Dipole || method == Method::BetterDipole;
    if (!isDipole && dirty)
        r.dipoleSynced = false;
    if (method != Method::DirectionalDipole && dirty)
        r.dirpoleSynced = false;
#if LUCENT_APP_HAS_COMBINED
    if (method != Method::Combined && dirty)
        r.combinedSynced = false;
#endif
    const float eta = std::clamp(f.scene->eta, 1.f, 3.f);

    switch (method) {
        case Method::Direct:
            break;
        case Method::SingleScattering:
            bricksUsed = r.single.sync(*vol, !r.singleSynced, f.dirtyBricks);
            r.singleSynced = true;
            r.single.setFrame(*f.scene, *vol, s);
            provider = &r.single;
            break;
        case Method::Sslpv: {
            const SslpvProviderOptions o = sslpvOptions(s);
            if (!r.sslpv || o.backend != r.sslpvOpts.backend) {
                if (r.sslpv)
                    r.sslpv->destroy();
                r.sslpv = std::make_unique<SslpvSubsurfaceProvider>(o);
                r.sslpv->create(r.library);
                r.sslpvOpts = o;
                r.sslpvSynced = r.sslpvMeshSet = false;
                r.sslpvLights.clear();
            } else if (!sameSslpv(o, r.sslpvOpts)) {
                r.sslpv->setOptions(o);
                r.sslpvOpts = o;
            }
            if (!r.sslpvMeshSet) {
                r.sslpv->setMesh(f.scene->objects[0].mesh);  // rest space
                r.sslpvMeshSet = true;
            }
            if (key != r.sslpvLights) {
                r.sslpv->setLights(lights);
                r.sslpvLights = key;
            }
            // A new grid resolution drops the provider's material (SslpvProvider.h, setOptions).
            if (!r.sslpvSynced || !r.sslpv->hasMaterial() || r.sslpvEta != f.scene->eta) {
                r.sslpvEta = f.scene->eta;
                r.sslpv->setMaterial(*vol, std::clamp(f.scene->eta, 1.f, 3.f));
                r.sslpvSynced = true;
                bricksUsed = vol->brickCount();
            } else if (dirty) {
                r.sslpv->updateMaterial(*vol, f.dirtyBricks);
                bricksUsed = int(f.dirtyBricks.size());
            }
            provider = r.sslpv.get();
            break;
        }
        case Method::Dipole:
        case Method::BetterDipole: {
            if (!r.dipole) {
                r.dipole = std::make_unique<dipole::DipoleSubsurfaceProvider>();
                r.dipole->create(r.library);
                r.dipoleSynced = false;
            }
            dipole::ProviderSettings ps = r.dipole->settings();
            const dipole::Model model =
                method == Method::Dipole ? dipole::Model::Dipole : dipole::Model::BetterDipole;
            const int spp = std::clamp(s.dipoleSpp, 1, 4096);
            if (ps.model != model || ps.eta != eta || ps.samplesPerFrame != spp) {
                ps.model = model;
                ps.eta = eta;
                ps.samplesPerFrame = spp;
                r.dipole->setSettings(ps);
            }
            bricksUsed = syncBricks(*r.dipole, r.dipoleSynced, *vol, f.dirtyBricks);
            provider = r.dipole.get();
            break;
        }
        case Method::DirectionalDipole: {
            if (!r.dirpole) {
                r.dirpole = std::make_unique<dipole::DirpoleSubsurfaceProvider>();
                r.dirpole->create(r.library);
                r.dirpoleSynced = false;
            }
            dipole::DirpoleSettings ps = r.dirpole->settings();
            const int spp = std::clamp(s.dirpoleSpp, 1, 4096);
            if (ps.eta != eta || ps.samplesPerFrame != spp || ps.meshId != 0) {
                ps.eta = eta;
                ps.samplesPerFrame = spp;
                ps.meshId = 0;  // object 0: the only mesh uploaded
                r.dirpole->setSettings(ps);
            }
            bricksUsed = syncBricks(*r.dirpole, r.dirpoleSynced, *vol, f.dirtyBricks);
            provider = r.dirpole.get();
            break;
        }
        case Method::Combined: {
#if LUCENT_APP_HAS_COMBINED
            if (!r.combined) {
                r.combined = std::make_unique<combined::CombinedSubsurfaceProvider>();
                r.combined->create(r.library);
                r.combinedSynced = r.combinedMeshSet = false;
                r.combinedLights.clear();
            }
            combined::CombinedProviderSettings cs = r.combined->settings();
            const int spp = std::clamp(s.dipoleSpp, 1, 4096);
            // The dock's SSLPV grid, steps, order and solve apply to the SSLPV part; its mode
            // stays the module's (Calibrated, what the split was evaluated with).
            SslpvProviderOptions so = sslpvOptions(s);
            so.render.solver.mode = cs.sslpv.render.solver.mode;
            so.render.direct = cs.sslpv.render.direct;
            so.render.subsurface = cs.sslpv.render.subsurface;
            if (cs.splitRadius != s.combinedSplitRadius || cs.eta != eta || cs.meshId != 0 ||
                cs.dipole.samplesPerFrame != spp || !sameSslpv(so, cs.sslpv)) {
                // A new SSLPV grid drops the SSLPV part's material: set it again below.
                if (so.render.gridResolution != cs.sslpv.render.gridResolution)
                    r.combinedSynced = false;
                cs.splitRadius = s.combinedSplitRadius;
                cs.eta = eta;
                cs.meshId = 0;
                cs.dipole.samplesPerFrame = spp;
                cs.sslpv.render.gridResolution = so.render.gridResolution;
                cs.sslpv.render.solver.maxSteps = so.render.solver.maxSteps;
                cs.sslpv.render.solver.order = so.render.solver.order;
                cs.sslpv.backend = so.backend;
                r.combined->setSettings(cs);
            }
            if (!r.combinedMeshSet) {
                r.combined->setMesh(f.scene->objects[0].mesh);  // rest space, as SSLPV
                r.combinedMeshSet = true;
            }
            if (key != r.combinedLights) {
                r.combined->setLights(lights);
                r.combinedLights = key;
            }
            if (!r.combinedSynced || r.combinedEta != eta) {
                r.combined->setMaterial(*vol, eta);
                r.combinedSynced = true;
                r.combinedEta = eta;
                bricksUsed = vol->brickCount();
            } else if (dirty) {
                r.combined->updateMaterial(*vol, f.dirtyBricks);
                bricksUsed = int(f.dirtyBricks.size());
            }
            provider = r.combined.get();
#endif
            break;
        }
    }
    if (f.sceneReplaced && r.dipole && !isDipole)
        r.dipole->setMaterial(nullptr);  // the old volume is gone: never keep a dangling pointer
    if (f.sceneReplaced && r.dirpole && method != Method::DirectionalDipole)
        r.dirpole->setMaterial(nullptr);
#if LUCENT_APP_HAS_COMBINED
    if (f.sceneReplaced && r.combined && method != Method::Combined) {
        r.combined->destroy();  // its dipole part points at the old volume
        r.combined.reset();
    }
#endif
    if (haveMesh && (method != r.lastMethod || !r.surfaceSet || r.surfaceEta != f.scene->eta)) {
        r.surfaceEta = f.scene->eta;
        // Direct: an opaque grey Lambert + Blinn-Phong surface. Subsurface methods: the object
        // is translucent, so the light that is not reflected at the surface enters the medium
        // and comes back through the provider's term; only the specular Fresnel reflection
        // stays, with the normal-incidence reflectance R0 = ((η−1)/(η+1))² (Schlick 1994, eq. 24).
        gpu::SurfaceMaterial surface;
        if (method != Method::Direct) {
            const float eta = std::clamp(f.scene->eta, 1.f, 3.f);
            const float r0 = (eta - 1.f) * (eta - 1.f) / ((eta + 1.f) * (eta + 1.f));
            surface.diffuseAlbedo = Rgb(0.f);
            surface.specularAlbedo = Rgb(r0);
        }
        sr.setSurfaceMaterial(0, surface);
        r.surfaceSet = true;
    }
    r.lastMethod = method;
    const double uploadMs = uploadTimer.elapsedMs();
    if (bricksUsed > 0) {
        r.stats.bricksUploaded = bricksUsed;
        r.stats.uploadMs = uploadMs;
    }

    sr.setSubsurfaceProvider(provider);
    sr.renderToFramebuffer(f.framebuffer, f.framebufferWidth, f.framebufferHeight);
    sr.setSubsurfaceProvider(nullptr);
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
    if (method == Method::Sslpv && r.sslpv) {
        const SslpvProviderTimings& t = r.sslpv->timings();
        const SslpvProviderStats& st = r.sslpv->stats();
        r.stats.sslpvIncrementalUpdates = st.incrementalUpdates;
        r.stats.sslpvFullResamples = st.fullResamples;
        char line[320];
        std::snprintf(line, sizeof line,
                      "SSLPV %d³ (%s): resample %.2f ms (%zu cells), inject %.2f ms, propagate "
                      "%.2f ms, upload %.2f ms, sample %.2f ms GPU; last update %.2f ms; "
                      "%d incremental / %d full updates",
                      r.sslpvOpts.render.gridResolution,
                      r.sslpvOpts.backend == SslpvBackend::Gl ? "GL solve" : "CPU solve",
                      t.resampleMs, st.lastResampledCells, t.injectMs, t.propagateMs, t.uploadMs,
                      t.sampleGpuMs, t.lastUpdateMs, st.incrementalUpdates, st.fullResamples);
        detail << line;
    } else if (isDipole && r.dipole) {
        const dipole::ProviderStats& st = r.dipole->stats();
        char line[200];
        std::snprintf(line, sizeof line,
                      "%s: %d frames, %d spp accumulated, last change %.2g%s; last upload %d "
                      "bricks",
                      method == Method::Dipole ? "dipole" : "better dipole", st.frames,
                      st.samplesPerPixel, double(st.lastChange), st.converged ? " (converged)" : "",
                      st.lastUploadBricks);
        detail << line;
    } else if (method == Method::DirectionalDipole && r.dirpole) {
        const dipole::ProviderStats& st = r.dirpole->stats();
        char line[200];
        std::snprintf(line, sizeof line,
                      "directional dipole: %d frames, %d samples per texel and light, last "
                      "change %.2g%s; last upload %d bricks",
                      st.frames, st.samplesPerPixel, double(st.lastChange),
                      st.converged ? " (converged)" : "", st.lastUploadBricks);
        detail << line;
    }
#if LUCENT_APP_HAS_COMBINED
    else if (method == Method::Combined && r.combined) {
        const combined::CombinedProviderStats& st = r.combined->stats();
        char line[240];
        std::snprintf(line, sizeof line,
                      "combined: r_s = %.3g mm (%.3g SSLPV cells), dipole %d frames / %d spp%s, "
                      "SSLPV %d incremental / %d full updates",
                      double(st.plan.splitRadius),
                      st.plan.cellSize > 0.f ? double(st.plan.splitRadius / st.plan.cellSize) : 0.0,
                      st.dipole.frames, st.dipole.samplesPerPixel,
                      st.converged ? " (converged)" : "", st.sslpv.incrementalUpdates,
                      st.sslpv.fullResamples);
        detail << line;
    }
#endif
    r.stats.methodDetail = detail.str();
}

}  // namespace lucent::app
