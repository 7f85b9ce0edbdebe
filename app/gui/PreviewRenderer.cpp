// SPDX-License-Identifier: MIT
/// @file
/// @brief PreviewRenderer: SceneRenderer + subsurface providers + brush overlay (GL via epoxy).

#include "PreviewRenderer.h"

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/dipole/DipoleProvider.h>
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
        m->cursor = gpu::GlProgram::graphics(m->library, "post_fullscreen.vert",
                                             "preview_brush_cursor.frag");
        glCreateVertexArrays(1, &m->emptyVao);
    } catch (...) {
        destroy();
        throw;
    }
    m->meshUploaded = m->singleSynced = m->sslpvSynced = m->dipoleSynced = false;
    m->sslpvMeshSet = m->surfaceSet = false;
    m->lights.clear();
    m->sslpvLights.clear();
}

void PreviewRenderer::destroy() {
    if (!m->created)
        return;
    m->renderer.setSubsurfaceProvider(nullptr);
    m->renderer.destroy();
    m->single.destroy();
    if (m->sslpv)
        m->sslpv->destroy();
    m->sslpv.reset();
    if (m->dipole)
        m->dipole->destroy();
    m->dipole.reset();
    m->cursor.destroy();
    glDeleteVertexArrays(1, &m->emptyVao);
    m->emptyVao = 0;
    m->created = false;
}

bool PreviewRenderer::wantsAnotherFrame() const {
    const bool dipole = m->lastMethod == Method::Dipole || m->lastMethod == Method::BetterDipole;
    return m->created && dipole && m->dipole && !m->dipole->stats().converged;
}

const PreviewStats& PreviewRenderer::stats() const {
    return m->stats;
}

void PreviewRenderer::render(PreviewFrame& f) {
    LUCENT_CHECK(m->created, "PreviewRenderer::render before create()");
    Impl& r = *m;
    const RenderSettings& s = f.settings;
    gpu::SceneRenderer& sr = r.renderer;
    sr.setSubsurfaceProvider(nullptr);
    if (f.sceneReplaced) {
        sr.clearMeshes();
        r.meshUploaded = r.singleSynced = r.sslpvSynced = r.dipoleSynced = false;
        r.sslpvMeshSet = r.surfaceSet = false;
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
    const Method method = haveMesh && vol ? s.method : Method::Direct;
    if (method != Method::SingleScattering && dirty)
        r.singleSynced = false;
    if (method != Method::Sslpv && dirty)
        r.sslpvSynced = false;
    const bool isDipole = method == Method::Dipole || method == Method::BetterDipole;
    if (!isDipole && dirty)
        r.dipoleSynced = false;

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
            if (!r.sslpvSynced || r.sslpvEta != f.scene->eta) {
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
            const float eta = std::clamp(f.scene->eta, 1.f, 3.f);
            const int spp = std::clamp(s.dipoleSpp, 1, 4096);
            if (ps.model != model || ps.eta != eta || ps.samplesPerFrame != spp) {
                ps.model = model;
                ps.eta = eta;
                ps.samplesPerFrame = spp;
                r.dipole->setSettings(ps);
            }
            if (!r.dipoleSynced) {
                r.dipole->setMaterial(nullptr);
                r.dipole->setMaterial(vol);  // whole volume uploaded at the next frame
                r.dipoleSynced = true;
                bricksUsed = vol->brickCount();
            } else if (dirty) {
                r.dipole->uploadBricks(f.dirtyBricks);
                bricksUsed = int(f.dirtyBricks.size());
            }
            provider = r.dipole.get();
            break;
        }
    }
    if (f.sceneReplaced && r.dipole && !isDipole)
        r.dipole->setMaterial(nullptr);  // the old volume is gone: never keep a dangling pointer
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

    // Statistics.
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
    }
    r.stats.methodDetail = detail.str();
}

}  // namespace lucent::app
