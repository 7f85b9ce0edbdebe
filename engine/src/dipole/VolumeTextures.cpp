// SPDX-License-Identifier: MIT
/// @file
/// @brief The material 3-D textures and accumulation bookkeeping shared by the two GL dipole
/// providers (VolumeTextures.h).

#include "VolumeTextures.h"

#include <lucent/core/Error.h>
#include <lucent/material/MaterialVolume.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lucent::dipole {

MaterialSubsurfaceProvider::MaterialSubsurfaceProvider(const char* name)
    : m_volume(std::make_unique<detail::VolumeTextures>(name)) {}

MaterialSubsurfaceProvider::~MaterialSubsurfaceProvider() = default;

void MaterialSubsurfaceProvider::create(const gpu::ShaderLibrary& library) {
    if (m_created)
        return;
    try {
        createGl(library);
    } catch (...) {
        destroyGl();  // frees what was created before the failure
        throw;
    }
    m_created = true;
    m_volume->destroy();  // full upload at the next frame
    restart();
}

void MaterialSubsurfaceProvider::destroy() {
    if (!m_created)
        return;
    destroyGl();
    m_volume->destroy();
    m_created = false;
}

void MaterialSubsurfaceProvider::requireCreated(const char* what) const {
    LUCENT_CHECK(m_created, m_volume->owner(), "::", what, " before create()");
}

void MaterialSubsurfaceProvider::setMaterial(const MaterialVolume* volume) {
    if (m_volume->attach(volume))
        restart();
}

void MaterialSubsurfaceProvider::uploadBricks(const std::vector<int>& bricks) {
    requireCreated("uploadBricks");
    if (m_volume->uploadBricks(bricks, m_stats))
        restart();
}

void MaterialSubsurfaceProvider::syncMaterial(MaterialVolume& volume) {
    if (m_volume->sync(volume, m_stats))
        restart();
}

void MaterialSubsurfaceProvider::reset() {
    invalidateCaches();
    restart();
}

}  // namespace lucent::dipole

namespace lucent::dipole::detail {

bool VolumeTextures::attach(const MaterialVolume* volume) {
    if (volume == m_volume && !m_stale)
        return false;
    m_volume = volume;
    m_stale = true;
    return true;
}

bool VolumeTextures::uploadBricks(const std::vector<int>& bricks, ProviderStats& stats) {
    LUCENT_CHECK(m_volume != nullptr, m_owner,
                 "::uploadBricks: no material volume attached (call setMaterial first)");
    for (int b : bricks)
        LUCENT_CHECK(b >= 0 && b < m_volume->brickCount(), m_owner, "::uploadBricks: brick ", b,
                     " outside [0, ", m_volume->brickCount(), ")");
    if (m_stale || !(m_volume->spec() == m_spec)) {
        uploadAll(stats);  // first upload or a new grid: everything
        return true;
    }
    if (bricks.empty())
        return false;
    writeBricks(bricks, stats);
    return true;
}

bool VolumeTextures::sync(MaterialVolume& volume, ProviderStats& stats) {
    const bool attached = attach(&volume);
    const std::vector<int> dirty = volume.takeDirtyBricks();
    if (m_stale)
        return uploadBricks({}, stats) || attached;  // full upload; covers the dirty list
    return (!dirty.empty() && uploadBricks(dirty, stats)) || attached;
}

bool VolumeTextures::syncForFrame(ProviderStats& stats) {
    if (m_volume ? (m_stale || !(m_volume->spec() == m_spec) || m_volume->revision() != m_revision)
                 : m_stale) {
        uploadAll(stats);
        return true;
    }
    return false;
}

void VolumeTextures::destroy() {
    m_sigmaT.destroy();
    m_sigmaS.destroy();
    m_stale = true;
}

bool VolumeTextures::hasMaterial() const {
    return m_volume != nullptr && m_sigmaT.isValid();
}

void VolumeTextures::bind(const gpu::GlProgram& p, int unitSigmaT, int unitSigmaS) const {
    glBindTextureUnit(GLuint(unitSigmaT), m_sigmaT.id());
    glBindTextureUnit(GLuint(unitSigmaS), m_sigmaS.id());
    const bool has = hasMaterial();
    glUniform1i(p.uniformLocation("u_hasMaterial"), has ? 1 : 0);
    glUniform3f(p.uniformLocation("u_gridOrigin"), m_spec.origin.x, m_spec.origin.y,
                m_spec.origin.z);
    glUniform1f(p.uniformLocation("u_voxelSize"), m_spec.voxelSize);
    glUniform1i(p.uniformLocation("u_resolution"), has ? m_spec.resolution : 0);
}

void VolumeTextures::writeBricks(const std::vector<int>& bricks, ProviderStats& stats) {
    const MaterialVolume& v = *m_volume;
    const int res = v.resolution(), B = MaterialVolume::BRICK;
    std::vector<float> t(size_t(MaterialVolume::BRICK_VOXELS) * 4), s(t.size());
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
        if (!m_written.all) {
            if (m_written.bricksPerAxis != v.bricksPerAxis()) {
                m_written.bricksPerAxis = v.bricksPerAxis();
                m_written.written.assign(size_t(v.brickCount()), 0);
            }
            m_written.written[size_t(b)] = 1;
        }
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
                        // Masked-out voxels read as zero ("no material"), like
                        // MaterialVolume::at().
                        t[4 * k + size_t(c)] = inside ? st : 0.f;
                        s[4 * k + size_t(c)] = inside ? ss : 0.f;
                    }
                    t[4 * k + 3] = inside ? 1.f : 0.f;
                    s[4 * k + 3] = 0.f;
                }
        glTextureSubImage3D(m_sigmaT.id(), 0, o.x, o.y, o.z, nx, ny, nz, GL_RGBA, GL_FLOAT,
                            t.data());
        glTextureSubImage3D(m_sigmaS.id(), 0, o.x, o.y, o.z, nx, ny, nz, GL_RGBA, GL_FLOAT,
                            s.data());
    }
    stats.lastUploadBricks = int(bricks.size());
    m_revision = v.revision();
}

VolumeTextures::WrittenBricks VolumeTextures::takeWrittenBricks() {
    WrittenBricks w = std::move(m_written);
    m_written = WrittenBricks{};
    return w;
}

void VolumeTextures::uploadAll(ProviderStats& stats) {
    m_sigmaT.destroy();
    m_sigmaS.destroy();
    m_stale = false;
    // Everything may have changed, also where no brick is written (a material removed).
    m_written.all = true;
    if (!m_volume)
        return;
    const int res = m_volume->resolution();
    m_sigmaT = gpu::createTexture3D(GL_RGBA32F, res, res, res, /*linear=*/false);
    m_sigmaS = gpu::createTexture3D(GL_RGBA32F, res, res, res, /*linear=*/false);
    m_spec = m_volume->spec();
    std::vector<int> all(size_t(m_volume->brickCount()));
    for (int b = 0; b < m_volume->brickCount(); ++b)
        all[size_t(b)] = b;
    writeBricks(all, stats);
    ++stats.fullUploads;
}

void restartAccumulation(ProviderStats& stats) {
    if (stats.frames > 0 || stats.converged || stats.preview)  // shown work is discarded
        ++stats.resets;
    stats.frames = 0;
    stats.samplesPerPixel = 0;
    stats.lastChange = 1.f;
    stats.converged = false;
}

void finishFrame(ProviderStats& stats, unsigned statsBuffer, int samplesPerFrame, int maxFrames,
                 float convergenceThreshold) {
    ++stats.frames;
    stats.samplesPerPixel = stats.frames * samplesPerFrame;
    // Two words: synchronous, but the next pass needs the dispatch done anyway.
    uint32_t words[2] = {0u, 0u};
    glGetNamedBufferSubData(statsBuffer, 0, sizeof(words), words);
    float maxChange = 0.f, maxMean = 0.f;
    std::memcpy(&maxChange, &words[0], sizeof(float));
    std::memcpy(&maxMean, &words[1], sizeof(float));
    if (stats.frames > 1)
        stats.lastChange = maxMean > 0.f ? maxChange / maxMean : 0.f;
    const bool black = !(maxMean > 0.f);  // nothing lit: more samples change nothing
    stats.converged = stats.frames >= maxFrames || black ||
                      (stats.frames > 1 && stats.lastChange < convergenceThreshold);
}

void validateProgressiveSettings(const char* type, float eta, int samplesPerFrame, int maxFrames,
                                 float convergenceThreshold, int meshId) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.f && eta <= 3.f, type,
                 ".eta must be in [1, 3] (got ", eta, ")");
    LUCENT_CHECK(samplesPerFrame >= 1 && samplesPerFrame <= 4096, type,
                 ".samplesPerFrame must be in [1, 4096] (got ", samplesPerFrame, ")");
    LUCENT_CHECK(maxFrames >= 1 && maxFrames <= 1000000, type,
                 ".maxFrames must be in [1, 1e6] (got ", maxFrames, ")");
    LUCENT_CHECK(std::isfinite(convergenceThreshold) && convergenceThreshold >= 0.f &&
                     convergenceThreshold < 1.f,
                 type, ".convergenceThreshold must be in [0, 1) (got ", convergenceThreshold, ")");
    LUCENT_CHECK(meshId >= -1, type, ".meshId must be >= -1 (got ", meshId, ")");
}

}  // namespace lucent::dipole::detail
