// SPDX-License-Identifier: MIT
/// @file
/// @brief CombinedSubsurfaceProvider: SSLPV (late steps) + windowed image-space dipole on the GPU,
/// summed by shaders/combined_add.comp (docs/methods/combined.md).

#include <lucent/combined/CombinedProvider.h>

#include <lucent/core/Error.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Medium.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/sslpv/GridDiffusion.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lucent::combined {

struct CombinedSubsurfaceProvider::Impl {
    CombinedProviderSettings settings;
    sslpv::SslpvSubsurfaceProvider sslpv{
        sslpv::SslpvProviderOptions{.render = CombinedSettings::defaultSslpvOptions()}};
    dipole::DipoleSubsurfaceProvider dipole;
    gpu::GlProgram addProgram;
    /// combined_add.comp SURFACE_SCALE: the add pass with L̂ carried to the painted surface's
    /// material, a program of its own so that a volume that is not painted does not pay for it
    /// (llvmpipe runs a branch's body under a mask even when a uniform turns it off).
    gpu::GlProgram addScaleProgram;
    gpu::GlProgram localProgram;  ///< combined_add.comp LOCAL_ESTIMATE: L̂, f
    gpu::GlObject scratch;        ///< RGBA32F, the dipole part before it is added to the target
    int scratchW = 0, scratchH = 0;
    const MaterialVolume* volume = nullptr;
    float cellSize = 0.f;            ///< SSLPV Δx of the attached volume, 0 before one
    float extent = -1.f;             ///< objectExtent of the attached mesh, mm; < 0 before one
    std::vector<int> pendingBricks;  ///< dipole uploads waiting for a current context
    SslpvSurfaceKernel kernel;       ///< Kernel split: SSLPV's local kernel
    bool kernelDirty = true;         ///< material/split changed: recompute and re-upload
    gpu::GlObject kernelBuffer;      ///< SSBO vec4(outer, R_lpv rgb) per ring
    /// A paint stroke marks the kernel dirty: its frame keeps the old kernel (the mean material
    /// of a 128³ volume moves little per stroke) and the next frame recomputes it, so the
    /// stroke frame does not pay the half-space solve; the image converges to the same result.
    bool kernelDeferred = false;
    /// The kernel is dirty only because the material changed (a stroke), not the split: it is
    /// kept when the mean material is still close to `kernelMaterial` (kernelMaterialClose).
    bool kernelMaterialOnly = false;
    MaterialSample kernelMaterial;  ///< the surface material the kernel was computed for
    /// What meanIncidenceCosine reads: the mesh's positions and triangles (rest space), the
    /// lights (world space) and the transform between them.
    TriangleMesh incidenceMesh;
    std::vector<Light> lights;
    Mat4f objectFromWorld{1.f};
    /// meanIncidenceCosine of the mesh and lights: the kernel is lit at it, and solved again
    /// when it moves by a KERNEL_INCIDENCE_STEP.
    float incidence = 1.f;
    float kernelIncidence = 1.f;  ///< the incidence the kernel was solved at
    /// Recomputes `incidence`; marks the kernel dirty (not a material-only change) if it moved.
    void updateIncidence();
    /// The volume's surface shell one SSLPV cell deep (surfaceShell), whose mean material the
    /// kernel is solved for; the inside mask does not change under paint, so it is found once
    /// per volume and cell size (11.7 ms at 128³; the mean over it, per stroke, 1.5 ms).
    std::vector<Coord> shell;
    float shellDepth = -1.f;     ///< the cell size `shell` was found for; < 0: none
    uint64_t kernelVersion = 0;  ///< counts kernel recomputes (part of the L̂ key)
    /// L̂ = F_t/π ∫_{r≤r_s} R_lpv E dA (`local`) and the kernel's near fraction
    /// f = ∫_{r≤r_s} R_lpv E dA / ∫ R_lpv E dA (`fraction`, localSslpvFraction) per pixel
    /// (RGBA32F, a = the object's pixel). They depend
    /// on the G-buffer, the lights, η, the dipole's irradiance image and the kernel, not on the
    /// painted material or the dipole's progress: recomputed only when its key changes.
    gpu::GlObject local;
    gpu::GlObject fraction;
    std::vector<unsigned char> localKey;
    /// The albedo SSLPV's read-out sees per pixel (mode diffusion, Kernel split: the sample
    /// pass writes it, SslpvSubsurfaceProvider::setAlbedoOutput), which carries L̂ from the
    /// kernel's material to the painted surface (localScaleToSurfaceMaterial).
    gpu::GlObject albedo;
    int albedoW = 0, albedoH = 0;
    bool created = false;
    CombinedProviderStats stats;
    mutable gpu::GpuProfiler profiler;  ///< per-part GPU/CPU times (passTimes())
};

void CombinedSubsurfaceProvider::Impl::updateIncidence() {
    // The lights in the mesh's rest space (a rigid map: the cosines are those of world space).
    std::vector<Light> local = lights;
    for (Light& l : local) {
        l.position = Point3f(objectFromWorld * glm::vec4(l.position, 1.f));
        l.direction = Mat3f(objectFromWorld) * l.direction;
    }
    incidence = meanIncidenceCosine(incidenceMesh, local, settings.eta);
    if (incidence != kernelIncidence) {
        kernelDirty = true;
        kernelMaterialOnly = false;
    }
}

bool kernelMaterialClose(const MaterialSample& now, const MaterialSample& was) {
    const float tol = KERNEL_MATERIAL_TOLERANCE;
    for (int c = 0; c < 3; ++c) {
        const float aNow = now.sigma_t[c] - now.sigma_s[c], aWas = was.sigma_t[c] - was.sigma_s[c];
        if (std::abs(aNow - aWas) > tol * std::abs(aWas) ||
            std::abs(now.sigma_s[c] - was.sigma_s[c]) > tol * std::abs(was.sigma_s[c]) ||
            std::abs(now.g[c] - was.g[c]) > tol)
            return false;
    }
    return true;
}

CombinedSubsurfaceProvider::CombinedSubsurfaceProvider() : m(std::make_unique<Impl>()) {
    applySplit();
}

CombinedSubsurfaceProvider::~CombinedSubsurfaceProvider() = default;

void CombinedSubsurfaceProvider::create(const gpu::ShaderLibrary& library) {
    if (m->created)
        return;
    m->sslpv.create(library);
    m->dipole.create(library);
    m->addProgram = gpu::GlProgram::compute(library, "combined_add.comp");
    m->addScaleProgram = gpu::GlProgram::compute(library, "combined_add.comp", {"SURFACE_SCALE"});
    m->localProgram = gpu::GlProgram::compute(library, "combined_add.comp", {"LOCAL_ESTIMATE"});
    m->created = true;
}

void CombinedSubsurfaceProvider::destroy() {
    m->sslpv.destroy();
    m->dipole.destroy();
    m->addProgram.destroy();
    m->addScaleProgram.destroy();
    m->localProgram.destroy();
    m->profiler.destroy();
    m->scratch.destroy();
    m->local.destroy();
    m->fraction.destroy();
    m->albedo.destroy();
    m->albedoW = m->albedoH = 0;
    m->localKey.clear();
    m->kernelBuffer.destroy();
    m->kernelDirty = true;
    m->kernelMaterialOnly = false;
    m->scratchW = m->scratchH = 0;
    m->created = false;
}

bool CombinedSubsurfaceProvider::isCreated() const {
    return m->created;
}

void CombinedSubsurfaceProvider::setSettings(const CombinedProviderSettings& settings) {
    LUCENT_CHECK(!std::isnan(settings.splitRadius),
                 "CombinedProviderSettings.splitRadius is NaN (mm; < 0: default, +inf: dipole)");
    LUCENT_CHECK(settings.eta >= 1.f && settings.eta <= 3.f,
                 "CombinedProviderSettings.eta must be in [1, 3] (got ", settings.eta, ")");
    LUCENT_CHECK(settings.meshId >= -1, "CombinedProviderSettings.meshId must be >= -1");
    LUCENT_CHECK(std::isfinite(settings.farTolerance) && settings.farTolerance >= 0.f,
                 "CombinedProviderSettings.farTolerance must be finite and >= 0 (got ",
                 settings.farTolerance, ")");
    const CombinedProviderSettings old = m->settings;
    m->settings = settings;
    try {
        applySplit();
    } catch (...) {
        m->settings = old;
        applySplit();
        throw;
    }
}

const CombinedProviderSettings& CombinedSubsurfaceProvider::settings() const {
    return m->settings;
}

void CombinedSubsurfaceProvider::applySplit() {
    const CombinedProviderSettings& s = m->settings;
    const sslpv::SslpvOptions& so = s.sslpv.render.solver;
    // Before a material is attached Δx is unknown: plan with a unit cell (replanned later).
    LUCENT_CHECK(s.localSamples >= 1 && s.localSamples <= 4096,
                 "CombinedProviderSettings.localSamples must be in [1, 4096] (got ", s.localSamples,
                 ")");
    SplitPlan plan = planSplit(s.splitRadius, m->cellSize > 0.f ? m->cellSize : 1.f,
                               so.skipAccumulateSteps, so.maxSteps, s.mode);
    // The automatic skip needs the object: decided once both mesh and material are attached.
    if (s.autoSkipSslpv && m->volume != nullptr && m->extent >= 0.f && plan.dipoleOn &&
        plan.sslpvOn)
        applyFarSkip(plan,
                     volumeFarShare(s.dipole.model, *m->volume, s.eta, plan.splitRadius, m->extent),
                     s.farTolerance);
    sslpv::SslpvProviderOptions lo = s.sslpv;
    lo.render.solver.skipAccumulateSteps = plan.skipSteps;
    lo.meshId = s.meshId;
    dipole::ProviderSettings dp = s.dipole;
    dp.eta = s.eta;
    dp.meshId = s.meshId;
    dp.maxRadius = plan.dipoleMaxRadius();
    m->sslpv.setOptions(lo);    // validates; re-propagates only when the options changed
    m->dipole.setSettings(dp);  // validates; restarts the accumulation only on a change
    m->stats.plan = plan;
    m->kernelDirty = true;
    m->kernelMaterialOnly = false;
}

void CombinedSubsurfaceProvider::setMesh(const TriangleMesh& mesh) {
    m->sslpv.setMesh(mesh);
    m->dipole.reset();  // the G-buffer changes in ways camera/lights/material do not reveal
    m->incidenceMesh.positions = mesh.positions;
    m->incidenceMesh.triangles = mesh.triangles;
    m->updateIncidence();
    const float extent = objectExtent(mesh);
    if (extent != m->extent) {
        m->extent = extent;
        if (m->settings.autoSkipSslpv)
            applySplit();  // the far share depends on the extent
    }
}

void CombinedSubsurfaceProvider::setLights(const std::vector<Light>& lights) {
    m->sslpv.setLights(lights);
    m->lights = lights;
    m->updateIncidence();
}

void CombinedSubsurfaceProvider::setObjectFromWorld(const Mat4f& objectFromWorld) {
    m->sslpv.setObjectFromWorld(objectFromWorld);
    m->objectFromWorld = objectFromWorld;
    m->updateIncidence();
}

void CombinedSubsurfaceProvider::setMaterial(const MaterialVolume& volume, float eta) {
    m->sslpv.setMaterial(volume, eta);
    m->dipole.setMaterial(&volume);
    m->volume = &volume;
    m->shellDepth = -1.f;      // another volume or mask: find the surface shell again
    m->pendingBricks.clear();  // the dipole uploads the whole volume at the next frame
    m->cellSize = sslpvCellSize(volume, m->settings.sslpv.render.gridResolution);
    m->settings.eta = eta;
    applySplit();
    m->updateIncidence();  // its weights are the irradiance transmitted at η
}

size_t CombinedSubsurfaceProvider::syncMaterial(MaterialVolume& volume) {
    const std::vector<int> bricks = volume.takeDirtyBricks();
    if (!bricks.empty() || m->volume != &volume)
        updateMaterial(volume, bricks);
    return bricks.size();
}

void CombinedSubsurfaceProvider::updateMaterial(const MaterialVolume& volume,
                                                const std::vector<int>& dirtyBricks) {
    if (m->volume != &volume || !(volume.spec() == m->volume->spec())) {
        setMaterial(volume, m->settings.eta);
        return;
    }
    if (dirtyBricks.empty())
        return;
    m->sslpv.updateMaterial(volume, dirtyBricks);
    m->pendingBricks.insert(m->pendingBricks.end(), dirtyBricks.begin(), dirtyBricks.end());
    if (!m->kernelDirty) {
        m->kernelDeferred = true;  // the mean material may have changed: next frame
        m->kernelMaterialOnly = true;
    }
    m->kernelDirty = true;
    if (m->settings.autoSkipSslpv && m->extent >= 0.f) {
        // A stroke may paint a material whose light travels further (or less far): the skip is
        // decided again over the whole volume (one profile per run of equal voxels).
        SplitPlan& plan = m->stats.plan;
        const bool was = plan.sslpvOn;
        if (plan.sslpvSkipped || plan.sslpvOn) {
            const sslpv::SslpvOptions& so = m->settings.sslpv.render.solver;
            SplitPlan fresh = planSplit(m->settings.splitRadius, m->cellSize,
                                        so.skipAccumulateSteps, so.maxSteps, m->settings.mode);
            if (fresh.dipoleOn && fresh.sslpvOn)
                applyFarSkip(fresh,
                             volumeFarShare(m->settings.dipole.model, volume, m->settings.eta,
                                            fresh.splitRadius, m->extent),
                             m->settings.farTolerance);
            plan = fresh;
        }
        if (was != plan.sslpvOn)
            m->kernelDeferred = false;  // the split changed: the kernel is due this frame
    }
}

void CombinedSubsurfaceProvider::renderSubsurface(const gpu::GBufferView& g,
                                                  unsigned targetTexture) {
    LUCENT_CHECK(m->created, "CombinedSubsurfaceProvider: create() was not called");
    const SplitPlan& plan = m->stats.plan;
    gpu::GpuProfiler::FrameScope frame(m->profiler);  // cancelled if a part throws
    // The Kernel split with the diffusion part on a painted volume: the sample pass also writes
    // the albedo it reads, and L̂ is carried to the material there (localScaleToSurfaceMaterial).
    // A homogeneous volume reads the kernel's own material everywhere (the factor is 1):
    // skipped, which saves the image write and the lookups (docs/benchmarks.md).
    const bool albedoScale = plan.sslpvOn && plan.dipoleOn && plan.mode == SplitMode::Kernel &&
                             m->sslpv.options().render.solver.mode == sslpv::SslpvMode::Diffusion &&
                             !m->sslpv.coarseMaterial().homogeneous;
    if (albedoScale && (m->albedoW != g.width || m->albedoH != g.height)) {
        m->albedo.destroy();
        m->albedo = gpu::createTexture2D(GL_RGBA32F, g.width, g.height);
        m->albedoW = g.width;
        m->albedoH = g.height;
    }
    m->sslpv.setAlbedoOutput(albedoScale ? m->albedo.id() : 0);
    if (plan.sslpvOn) {
        const auto scope = m->profiler.scope("sslpv");
        m->sslpv.renderSubsurface(g, targetTexture);  // writes the covered pixels of meshId
    }
    if (plan.dipoleOn) {
        m->profiler.begin("dipole");
        if (!m->pendingBricks.empty()) {
            std::sort(m->pendingBricks.begin(), m->pendingBricks.end());
            m->pendingBricks.erase(std::unique(m->pendingBricks.begin(), m->pendingBricks.end()),
                                   m->pendingBricks.end());
            m->dipole.uploadBricks(m->pendingBricks);
            m->pendingBricks.clear();
        }
        if (m->scratchW != g.width || m->scratchH != g.height) {
            for (gpu::GlObject* o : {&m->scratch, &m->local, &m->fraction}) {
                o->destroy();
                *o = gpu::createTexture2D(GL_RGBA32F, g.width, g.height);
            }
            m->localKey.clear();
            m->scratchW = g.width;
            m->scratchH = g.height;
        }
        // The last frame's add pass read the scratch image (imageLoad); the dipole wrote it
        // with imageStore: both finish before the clear (GL 4.5 §7.13.2).
        glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        const float zero[4] = {0.f, 0.f, 0.f, 0.f};
        glClearTexImage(m->scratch.id(), 0, GL_RGBA, GL_FLOAT, zero);
        m->dipole.renderSubsurface(g, m->scratch.id());
        m->profiler.end();
        // Skipped SSLPV (applyFarSkip): nothing to subtract from, so no kernel either.
        const bool kernel = plan.mode == SplitMode::Kernel && plan.sslpvOn;
        const bool deferKernel = m->kernelDeferred && m->kernelBuffer.isValid();
        m->kernelDeferred = false;
        if (kernel && (m->kernelDirty || !m->kernelBuffer.isValid()) && m->volume && !deferKernel) {
            const auto scope = m->profiler.scope("kernel");
            // SSLPV's local kernel for the material of the volume's surface cells
            // (docs/methods/combined.md, "Painted volumes: the kernel of the surface cells").
            if (m->shellDepth != plan.cellSize) {
                m->shell = surfaceShell(*m->volume, plan.cellSize);
                m->shellDepth = plan.cellSize;
            }
            const MaterialSample surface = surfaceMaterial(*m->volume, m->shell);
            if (m->kernelMaterialOnly && m->kernelBuffer.isValid() &&
                kernelMaterialClose(surface, m->kernelMaterial)) {
                ++m->stats.kernelsKept;  // a stroke that hardly moved the mean: kernel and L̂ stay
            } else {
                m->kernel = computeSslpvSurfaceKernel(
                    surface, m->settings.eta, sslpv::refinedSolverOptions(m->sslpv.options()),
                    plan.cellSize, plan.splitRadius, m->incidence);
                m->kernelMaterial = surface;
                m->kernelIncidence = m->incidence;
                std::vector<glm::vec4> rings;
                for (size_t b = 0; b < m->kernel.ringOuter.size(); ++b)
                    rings.emplace_back(m->kernel.ringOuter[b], m->kernel.ringValue[b]);
                m->kernelBuffer.destroy();
                m->kernelBuffer =
                    gpu::createBuffer(rings.size() * sizeof(glm::vec4), rings.data(), 0);
                ++m->kernelVersion;
            }
            m->kernelDirty = false;
            m->kernelMaterialOnly = false;
        }
        const bool subtract = kernel && m->kernelBuffer.isValid();
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT |
                        GL_TEXTURE_FETCH_BARRIER_BIT);
        if (subtract)
            updateLocalEstimate(g);
        // target = max(0, target + scratch − min(L̂, f·target)) (shaders/combined_add.comp).
        const auto scope = m->profiler.scope("add");
        const bool scaleLocal = subtract && albedoScale;
        const gpu::GlProgram& p = scaleLocal ? m->addScaleProgram : m->addProgram;
        glUseProgram(p.id());
        glUniform2i(p.uniformLocation("u_size"), g.width, g.height);
        glUniform1i(p.uniformLocation("u_kernel"), subtract ? 1 : 0);
        if (scaleLocal) {
            const std::shared_ptr<const sslpv::ExactReflectanceRatio> table =
                sslpv::exactReflectanceRatio(m->settings.eta);
            const std::vector<float>& totals = table->exactTotals();
            glUniform1fv(p.uniformLocation("u_exactTotal"), GLsizei(totals.size()), totals.data());
            // The kernel's terms once per frame (localScaleToSurfaceMaterial's denominators).
            const KernelSurfaceTerms k =
                kernelSurfaceTerms(m->kernelMaterial, m->settings.eta, plan.splitRadius, *table);
            glUniform3f(p.uniformLocation("u_kernelTotal"), k.exactTotal.r, k.exactTotal.g,
                        k.exactTotal.b);
            glUniform3f(p.uniformLocation("u_kernelNearShare"), k.nearShare.r, k.nearShare.g,
                        k.nearShare.b);
            glUniform1f(p.uniformLocation("u_boundaryA"), k.boundaryA);
            glUniform1f(p.uniformLocation("u_splitRadius"), plan.splitRadius);
            // The disc around x_o is found as the local estimate finds it: the G-buffer and the
            // camera's projection (shaders/combined_add.comp, projectTop).
            glUniformMatrix4fv(p.uniformLocation("u_clipFromWorld"), 1, GL_FALSE,
                               &g.clipFromWorld[0][0]);
            glBindTextureUnit(0, g.positionTexture);
            glBindTextureUnit(1, g.normalTexture);
            glBindImageTexture(4, m->albedo.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
            // The material around x_o: the dipole part's per-pixel σt′ and σs′, written by its
            // irradiance pass (discMeanMaterial).
            const dipole::DipoleSubsurfaceProvider::DebugTextures material =
                m->dipole.debugTextures();
            glBindImageTexture(5, material.sigmaT, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
            glBindImageTexture(6, material.sigmaS, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        }
        glBindImageTexture(0, targetTexture, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(1, m->scratch.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        glBindImageTexture(2, m->local.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        glBindImageTexture(3, m->fraction.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
        // The target is read by the shading pass (texture fetch) and cleared by the renderer
        // at the next frame (framebuffer clear or texture update), as the SSLPV provider does.
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                        GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
        glUseProgram(0);
    }
    frame.end();
    ++m->stats.frames;
    m->stats.dipole = m->dipole.stats();
    m->stats.sslpv = m->sslpv.stats();
    // Only the Kernel split with SSLPV on has a kernel to wait for (a skipped SSLPV has none).
    const bool kernelNeeded = plan.mode == SplitMode::Kernel && plan.sslpvOn;
    // SSLPV's live refinement (SslpvProviderOptions::refineSteps) changes the image on idle
    // frames until its stop rules end it.
    m->stats.converged =
        (!plan.sslpvOn || m->sslpv.converged()) &&
        (!plan.dipoleOn || (m->stats.dipole.converged && (!kernelNeeded || !m->kernelDirty)));
}

void CombinedSubsurfaceProvider::updateLocalEstimate(const gpu::GBufferView& g) {
    // Key: everything L̂ depends on (the G-buffer's camera and size, the meshes' uploads, the
    // lights and shadows, η, the split, the irradiance image and the kernel). The dipole's
    // irradiance E (shaders/dipole_irradiance.comp) does not depend on the painted material.
    const SplitPlan& plan = m->stats.plan;
    const unsigned irradiance = m->dipole.debugTextures().irradiance;
    std::vector<unsigned char> key;
    const auto put = [&key](const void* data, size_t bytes) {
        const auto* b = static_cast<const unsigned char*>(data);
        key.insert(key.end(), b, b + bytes);
    };
    put(&g.clipFromWorld, sizeof(g.clipFromWorld));
    put(&g.viewFromWorld, sizeof(g.viewFromWorld));
    put(&g.cameraPosition, sizeof(g.cameraPosition));
    const int ints[7] = {g.width,
                         g.height,
                         int(irradiance),
                         m->settings.localSamples,
                         m->settings.meshId,
                         g.shadows ? 1 : 0,
                         m->settings.dipole.shadows ? 1 : 0};
    put(ints, sizeof(ints));
    const float floats[2] = {m->settings.eta, plan.splitRadius};
    put(floats, sizeof(floats));
    const uint32_t seed = m->settings.dipole.seed;
    put(&seed, sizeof(seed));
    put(&m->kernelVersion, sizeof(m->kernelVersion));
    for (const gpu::GBufferView::MeshGeometry& mesh : g.meshes)
        put(&mesh.revision, sizeof(mesh.revision));
    const int lightCount = g.lightBuffer ? std::max(g.lightCount, 0) : 0;
    std::vector<unsigned char> lights(size_t(lightCount) * 64);  // GpuLight, 64 bytes each
    if (!lights.empty())
        glGetNamedBufferSubData(g.lightBuffer, 0, GLsizeiptr(lights.size()), lights.data());
    key.insert(key.end(), lights.begin(), lights.end());
    if (key == m->localKey)
        return;
    const auto scope = m->profiler.scope("local");
    const gpu::GlProgram& p = m->localProgram;
    glUseProgram(p.id());
    // Camera from the G-buffer matrices as dipole::DipoleSubsurfaceProvider does.
    const Mat4f worldFromView = glm::inverse(g.viewFromWorld);
    const Mat4f clipFromView = g.clipFromWorld * worldFromView;
    const bool ortho = std::abs(clipFromView[2][3]) < 1e-6f;
    const Vector3f forward = glm::normalize(-Vector3f(worldFromView[2]));
    glUniform2i(p.uniformLocation("u_size"), g.width, g.height);
    glUniform1i(p.uniformLocation("u_ringCount"), int(m->kernel.ringOuter.size()));
    glUniform1f(p.uniformLocation("u_splitRadius"), plan.splitRadius);
    glUniform1i(p.uniformLocation("u_samples"), m->settings.localSamples);
    glUniform1ui(p.uniformLocation("u_seed"), m->settings.dipole.seed);
    glUniform1i(p.uniformLocation("u_meshId"), m->settings.meshId);
    glUniformMatrix4fv(p.uniformLocation("u_clipFromWorld"), 1, GL_FALSE, &g.clipFromWorld[0][0]);
    glUniform3f(p.uniformLocation("u_eye"), g.cameraPosition.x, g.cameraPosition.y,
                g.cameraPosition.z);
    glUniform3f(p.uniformLocation("u_viewDir"), forward.x, forward.y, forward.z);
    glUniform1i(p.uniformLocation("u_ortho"), ortho ? 1 : 0);
    glUniform1f(p.uniformLocation("u_eta"), m->settings.eta);
    glBindTextureUnit(0, g.positionTexture);
    glBindTextureUnit(1, g.normalTexture);
    glBindTextureUnit(2, irradiance);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, m->kernelBuffer.id());
    glBindImageTexture(2, m->local.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(3, m->fraction.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    glUseProgram(0);
    m->localKey = std::move(key);
    ++m->stats.localEstimates;
}

const CombinedProviderStats& CombinedSubsurfaceProvider::stats() const {
    return m->stats;
}

std::vector<gpu::PassTiming> CombinedSubsurfaceProvider::passTimes() const {
    if (!m->created)
        return {};
    m->profiler.collect(/*wait=*/true);
    return m->profiler.latest();
}

const sslpv::SslpvSubsurfaceProvider& CombinedSubsurfaceProvider::sslpvProvider() const {
    return m->sslpv;
}

const dipole::DipoleSubsurfaceProvider& CombinedSubsurfaceProvider::dipoleProvider() const {
    return m->dipole;
}

const SslpvSurfaceKernel& CombinedSubsurfaceProvider::kernel() const {
    return m->kernel;
}

const MaterialSample& CombinedSubsurfaceProvider::kernelMaterial() const {
    return m->kernelMaterial;
}

float CombinedSubsurfaceProvider::kernelIncidence() const {
    return m->kernelIncidence;
}

}  // namespace lucent::combined
