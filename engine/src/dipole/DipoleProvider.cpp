// SPDX-License-Identifier: MIT
/// @file
/// @brief GL side of dipole::DipoleSubsurfaceProvider: material volume upload (per brick),
/// irradiance pass (shaders/dipole_irradiance.comp), progressive gather and resolve
/// (shaders/dipole_provider.comp).

#include <lucent/dipole/DipoleProvider.h>

#include <lucent/core/Error.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/Shader.h>
#include <lucent/material/MaterialVolume.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
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
    LUCENT_CHECK(std::isfinite(s.eta) && s.eta >= 1.f && s.eta <= 3.f,
                 "ProviderSettings.eta must be in [1, 3] (got ", s.eta, ")");
    LUCENT_CHECK(s.samplesPerFrame >= 1 && s.samplesPerFrame <= 4096,
                 "ProviderSettings.samplesPerFrame must be in [1, 4096] (got ", s.samplesPerFrame,
                 ")");
    LUCENT_CHECK(s.maxFrames >= 1 && s.maxFrames <= 1000000,
                 "ProviderSettings.maxFrames must be in [1, 1e6] (got ", s.maxFrames, ")");
    LUCENT_CHECK(std::isfinite(s.convergenceThreshold) && s.convergenceThreshold >= 0.f &&
                     s.convergenceThreshold < 1.f,
                 "ProviderSettings.convergenceThreshold must be in [0, 1) (got ",
                 s.convergenceThreshold, ")");
    LUCENT_CHECK(s.discQuantile > 0.f && s.discQuantile < 1.f,
                 "ProviderSettings.discQuantile must be in (0, 1)");
    LUCENT_CHECK(std::isfinite(s.maxJacobian) && s.maxJacobian >= 1.f,
                 "ProviderSettings.maxJacobian must be finite and >= 1");
    LUCENT_CHECK(s.interleave >= 1 && s.interleave <= 64,
                 "ProviderSettings.interleave must be in [1, 64]");
    LUCENT_CHECK(s.meshId >= -1, "ProviderSettings.meshId must be >= -1 (got ", s.meshId, ")");
}

bool sameSettings(const ProviderSettings& a, const ProviderSettings& b) {
    return a.model == b.model && a.eta == b.eta && a.samplesPerFrame == b.samplesPerFrame &&
           a.maxFrames == b.maxFrames && a.convergenceThreshold == b.convergenceThreshold &&
           a.discQuantile == b.discQuantile && a.jacobian == b.jacobian &&
           a.maxJacobian == b.maxJacobian && a.interleave == b.interleave && a.seed == b.seed &&
           a.shadows == b.shadows && a.meshId == b.meshId;
}

/// Seed of frame f's Cranley–Patterson table: frame 0 uses the settings' seed (so it equals the
/// CPU gather), later frames a Weyl step of it (independent tables through Pcg32's seeding).
uint32_t frameSeed(uint32_t seed, int frame) {
    return seed + 0x9E3779B9u * uint32_t(frame);
}

}  // namespace

struct DipoleSubsurfaceProvider::Impl {
    ProviderSettings settings;
    ProviderStats stats;
    bool created = false;
    gpu::GlProgram irradianceProgram, gatherProgram;

    // Per-pixel images (renderer size).
    int width = 0, height = 0;
    gpu::GlObject irradiance, sigmaT, sigmaS, accum;
    gpu::GlObject shiftBuffer, statsBuffer;

    // Material volume.
    const MaterialVolume* volume = nullptr;
    gpu::GlObject volumeSigmaT, volumeSigmaS;
    GridSpec uploadedSpec;
    uint64_t uploadedRevision = 0;
    bool volumeStale = true;  ///< full upload needed at the next frame

    // What the accumulation was computed for.
    bool needReset = true;
    Mat4f lastClip{0.f};
    Point3f lastEye{0.f};
    std::vector<unsigned char> lastLights;
    bool lastShadows = false;

    void requireCreated(const char* what) const {
        LUCENT_CHECK(created, "DipoleSubsurfaceProvider::", what, " before create()");
    }

    void destroyImages() {
        for (gpu::GlObject* o : {&irradiance, &sigmaT, &sigmaS, &accum})
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
        needReset = true;
    }

    /// Writes bricks of the volume into the 3-D textures (texels inside the grid only).
    void writeBricks(const std::vector<int>& bricks) {
        const MaterialVolume& v = *volume;
        const int res = v.resolution(), B = MaterialVolume::BRICK;
        std::vector<float> t(size_t(MaterialVolume::BRICK_VOXELS) * 4);
        std::vector<float> s(t.size());
        glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
        glPixelStorei(GL_UNPACK_IMAGE_HEIGHT, 0);
        glPixelStorei(GL_UNPACK_SKIP_PIXELS, 0);
        glPixelStorei(GL_UNPACK_SKIP_ROWS, 0);
        glPixelStorei(GL_UNPACK_SKIP_IMAGES, 0);
        for (int b : bricks) {
            const Coord o = v.brickOrigin(b);
            const int nx = std::min(B, res - o.x), ny = std::min(B, res - o.y),
                      nz = std::min(B, res - o.z);
            if (nx <= 0 || ny <= 0 || nz <= 0)
                continue;
            const float* data = v.brickData(b);  // component-major, then x fastest
            size_t k = 0;
            for (int z = 0; z < nz; ++z)
                for (int y = 0; y < ny; ++y)
                    for (int x = 0; x < nx; ++x, ++k) {
                        const int vi = MaterialVolume::voxelInBrick(x, y, z);
                        const bool inside = v.isInside(o + Coord(x, y, z));
                        for (int c = 0; c < 3; ++c) {
                            const float st = data[MaterialVolume::component(Channel::SigmaT, c) *
                                                      MaterialVolume::BRICK_VOXELS +
                                                  vi];
                            const float ss = data[MaterialVolume::component(Channel::SigmaS, c) *
                                                      MaterialVolume::BRICK_VOXELS +
                                                  vi];
                            // Masked-out voxels read as zero, like MaterialVolume::at().
                            t[4 * k + size_t(c)] = inside ? st : 0.f;
                            s[4 * k + size_t(c)] = inside ? ss : 0.f;
                        }
                        t[4 * k + 3] = inside ? 1.f : 0.f;
                        s[4 * k + 3] = 0.f;
                    }
            glTextureSubImage3D(volumeSigmaT.id(), 0, o.x, o.y, o.z, nx, ny, nz, GL_RGBA, GL_FLOAT,
                                t.data());
            glTextureSubImage3D(volumeSigmaS.id(), 0, o.x, o.y, o.z, nx, ny, nz, GL_RGBA, GL_FLOAT,
                                s.data());
        }
        stats.lastUploadBricks = int(bricks.size());
        uploadedRevision = v.revision();
        needReset = true;
    }

    void uploadAll() {
        volumeSigmaT.destroy();
        volumeSigmaS.destroy();
        volumeStale = false;
        if (!volume)
            return;
        const int res = volume->resolution();
        volumeSigmaT = gpu::createTexture3D(GL_RGBA32F, res, res, res, /*linear=*/false);
        volumeSigmaS = gpu::createTexture3D(GL_RGBA32F, res, res, res, /*linear=*/false);
        uploadedSpec = volume->spec();
        std::vector<int> all(size_t(volume->brickCount()));
        for (int b = 0; b < volume->brickCount(); ++b)
            all[size_t(b)] = b;
        writeBricks(all);
        ++stats.fullUploads;
    }

    void resetAccumulation() {
        if (stats.frames > 0 || stats.converged)
            ++stats.resets;
        stats.frames = 0;
        stats.samplesPerPixel = 0;
        stats.lastChange = 1.f;
        stats.converged = false;
        needReset = false;
    }

    void runIrradiance(const gpu::GBufferView& g) {
        const gpu::GlProgram& p = irradianceProgram;
        glUseProgram(p.id());
        glBindTextureUnit(0, g.positionTexture);
        glBindTextureUnit(1, g.normalTexture);
        glBindTextureUnit(2, g.shadowMapTexture);
        glBindTextureUnit(3, volumeSigmaT.id());
        glBindTextureUnit(4, volumeSigmaS.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, g.lightBuffer);  // LUCENT_BINDING_LIGHTS
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, g.shadowLayerBuffer);  // SHADOW_LAYERS
        glBindImageTexture(0, irradiance.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(1, sigmaT.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(2, sigmaS.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glUniform2i(p.uniformLocation("u_size"), g.width, g.height);
        glUniform1i(p.uniformLocation("u_lightCount"), g.lightBuffer ? g.lightCount : 0);
        const bool shadows =
            settings.shadows && g.shadows && g.shadowMapTexture != 0 && g.shadowLayerBuffer != 0;
        glUniform1i(p.uniformLocation("u_shadows"), shadows ? 1 : 0);
        glUniform1f(p.uniformLocation("u_eta"), settings.eta);
        const bool hasMaterial = volume != nullptr && volumeSigmaT.isValid();
        glUniform1i(p.uniformLocation("u_hasMaterial"), hasMaterial ? 1 : 0);
        glUniform3f(p.uniformLocation("u_gridOrigin"), uploadedSpec.origin.x, uploadedSpec.origin.y,
                    uploadedSpec.origin.z);
        glUniform1f(p.uniformLocation("u_voxelSize"), uploadedSpec.voxelSize);
        glUniform1i(p.uniformLocation("u_resolution"), hasMaterial ? uploadedSpec.resolution : 0);
        const Boundary boundary = Boundary::of(settings.eta);
        glUniform1i(p.uniformLocation("u_model"), settings.model == Model::Dipole ? 0 : 1);
        glUniform3f(p.uniformLocation("u_boundary"), float(boundary.fdr), float(boundary.c1),
                    float(boundary.c2));
        glUniform1f(p.uniformLocation("u_discQuantile"), settings.discQuantile);
        glUniform1i(p.uniformLocation("u_meshId"), settings.meshId);
        glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }

    void runGather(const gpu::GBufferView& g, unsigned target, bool gather) {
        const GatherSettings gs = settings.gatherSettings();
        if (gather) {
            GatherSettings frameGs = gs;
            frameGs.seed = frameSeed(settings.seed, stats.frames);
            const auto shifts = interleaveShifts(frameGs);
            std::vector<glm::vec4> data(2 * shifts.size());
            for (size_t c = 0; c < shifts.size(); ++c) {
                data[2 * c] = {shifts[c][0], shifts[c][1], shifts[c][2], shifts[c][3]};
                data[2 * c + 1] = {shifts[c][4], 0.f, 0.f, 0.f};
            }
            glNamedBufferSubData(shiftBuffer.id(), 0, GLsizeiptr(data.size() * sizeof(data[0])),
                                 data.data());
            const uint32_t zero[2] = {0u, 0u};
            glNamedBufferSubData(statsBuffer.id(), 0, sizeof(zero), zero);
        }
        const gpu::GlProgram& p = gatherProgram;
        glUseProgram(p.id());
        glBindTextureUnit(0, g.positionTexture);
        glBindTextureUnit(1, g.normalTexture);
        glBindTextureUnit(2, irradiance.id());
        glBindTextureUnit(3, sigmaT.id());
        glBindTextureUnit(4, sigmaS.id());
        glBindImageTexture(0, accum.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(1, target, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, shiftBuffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, statsBuffer.id());

        // Camera from the G-buffer matrices: an orthographic clip matrix has a constant w row.
        const Mat4f clipFromView = g.clipFromWorld * glm::inverse(g.viewFromWorld);
        const bool ortho = std::abs(clipFromView[2][3]) < 1e-6f;
        const Mat4f worldFromView = glm::inverse(g.viewFromWorld);
        const Vector3f forward = glm::normalize(-Vector3f(worldFromView[2]));
        glUniformMatrix4fv(p.uniformLocation("u_clipFromWorld"), 1, GL_FALSE,
                           &g.clipFromWorld[0][0]);
        glUniform3f(p.uniformLocation("u_eye"), g.cameraPosition.x, g.cameraPosition.y,
                    g.cameraPosition.z);
        glUniform3f(p.uniformLocation("u_viewDir"), forward.x, forward.y, forward.z);
        glUniform1i(p.uniformLocation("u_ortho"), ortho ? 1 : 0);
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
        glUniform1i(p.uniformLocation("u_gather"), gather ? 1 : 0);
        glUniform1i(p.uniformLocation("u_framesBefore"), stats.frames);
        glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                        GL_BUFFER_UPDATE_BARRIER_BIT);
        glUseProgram(0);
        if (!gather)
            return;
        ++stats.frames;
        stats.samplesPerPixel = stats.frames * settings.samplesPerFrame;
        // Two words: synchronous, but the shading pass needs this dispatch done anyway.
        uint32_t words[2] = {0u, 0u};
        glGetNamedBufferSubData(statsBuffer.id(), 0, sizeof(words), words);
        float maxChange = 0.f, maxMean = 0.f;
        std::memcpy(&maxChange, &words[0], sizeof(float));
        std::memcpy(&maxMean, &words[1], sizeof(float));
        if (stats.frames > 1)
            stats.lastChange = maxMean > 0.f ? maxChange / maxMean : 0.f;
        const bool black = !(maxMean > 0.f);  // nothing lit: more samples change nothing
        stats.converged = stats.frames >= settings.maxFrames || black ||
                          (stats.frames > 1 && stats.lastChange < settings.convergenceThreshold);
    }
};

DipoleSubsurfaceProvider::DipoleSubsurfaceProvider() : m(std::make_unique<Impl>()) {}

DipoleSubsurfaceProvider::~DipoleSubsurfaceProvider() = default;

void DipoleSubsurfaceProvider::create(const gpu::ShaderLibrary& library) {
    if (m->created)
        return;
    try {
        m->irradianceProgram = gpu::GlProgram::compute(library, "dipole_irradiance.comp");
        m->gatherProgram = gpu::GlProgram::compute(library, "dipole_provider.comp");
        // Largest shift table: interleave 64 → 64² cells × 2 vec4.
        m->shiftBuffer =
            gpu::createBuffer(64 * 64 * 2 * sizeof(glm::vec4), nullptr, GL_DYNAMIC_STORAGE_BIT);
        m->statsBuffer = gpu::createBuffer(2 * sizeof(uint32_t), nullptr,
                                           GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
    } catch (...) {
        m->created = true;
        destroy();
        throw;
    }
    m->created = true;
    m->volumeStale = true;
    m->needReset = true;
}

void DipoleSubsurfaceProvider::destroy() {
    if (!m->created)
        return;
    m->irradianceProgram.destroy();
    m->gatherProgram.destroy();
    for (gpu::GlObject* o : {&m->shiftBuffer, &m->statsBuffer, &m->volumeSigmaT, &m->volumeSigmaS})
        o->destroy();
    m->destroyImages();
    m->volumeStale = true;
    m->created = false;
}

bool DipoleSubsurfaceProvider::isCreated() const {
    return m->created;
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

void DipoleSubsurfaceProvider::setMaterial(const MaterialVolume* volume) {
    if (volume == m->volume && !m->volumeStale)
        return;
    m->volume = volume;
    m->volumeStale = true;
    m->needReset = true;
}

void DipoleSubsurfaceProvider::uploadBricks(const std::vector<int>& bricks) {
    m->requireCreated("uploadBricks");
    LUCENT_CHECK(m->volume != nullptr,
                 "DipoleSubsurfaceProvider::uploadBricks: no material "
                 "volume attached (call setMaterial first)");
    for (int b : bricks)
        LUCENT_CHECK(b >= 0 && b < m->volume->brickCount(),
                     "DipoleSubsurfaceProvider::uploadBricks: brick ", b, " outside [0, ",
                     m->volume->brickCount(), ")");
    if (m->volumeStale || !(m->volume->spec() == m->uploadedSpec)) {
        m->uploadAll();  // first upload or a new grid: everything
        return;
    }
    if (bricks.empty())
        return;
    m->writeBricks(bricks);
}

void DipoleSubsurfaceProvider::syncMaterial(MaterialVolume& volume) {
    setMaterial(&volume);
    const std::vector<int> dirty = volume.takeDirtyBricks();
    if (m->volumeStale)
        uploadBricks({});  // full upload; the dirty list is covered by it
    else if (!dirty.empty())
        uploadBricks(dirty);
}

void DipoleSubsurfaceProvider::reset() {
    m->needReset = true;
}

const ProviderStats& DipoleSubsurfaceProvider::stats() const {
    return m->stats;
}

DipoleSubsurfaceProvider::DebugTextures DipoleSubsurfaceProvider::debugTextures() const {
    return {m->irradiance.id(), m->sigmaT.id(),       m->sigmaS.id(),
            m->accum.id(),      m->volumeSigmaT.id(), m->volumeSigmaS.id()};
}

void DipoleSubsurfaceProvider::renderSubsurface(const gpu::GBufferView& g, unsigned target) {
    m->requireCreated("renderSubsurface");
    Impl& r = *m;
    r.ensureImages(g.width, g.height);
    // Material: a changed grid or changes nobody reported (revision moved without
    // uploadBricks) re-upload everything; reported bricks were uploaded already.
    if (r.volume && (r.volumeStale || !(r.volume->spec() == r.uploadedSpec) ||
                     r.volume->revision() != r.uploadedRevision))
        r.uploadAll();
    else if (!r.volume && r.volumeStale)
        r.uploadAll();
    // Camera and lights: compare with the accumulated frame's (the light SSBO is tiny).
    std::vector<unsigned char> lights(size_t(std::max(g.lightCount, 0)) * 64);
    if (!lights.empty() && g.lightBuffer)
        glGetNamedBufferSubData(g.lightBuffer, 0, GLsizeiptr(lights.size()), lights.data());
    if (g.clipFromWorld != r.lastClip || g.cameraPosition != r.lastEye || lights != r.lastLights ||
        g.shadows != r.lastShadows) {
        r.needReset = true;
        r.lastClip = g.clipFromWorld;
        r.lastEye = g.cameraPosition;
        r.lastLights = std::move(lights);
        r.lastShadows = g.shadows;
    }
    if (r.needReset) {
        r.resetAccumulation();
        r.runIrradiance(g);
    }
    r.runGather(g, target, /*gather=*/!r.stats.converged);
    gpu::checkGlError("DipoleSubsurfaceProvider::renderSubsurface");
}

}  // namespace lucent::dipole
