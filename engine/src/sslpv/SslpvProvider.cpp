// SPDX-License-Identifier: MIT
/// @file
/// @brief SslpvSubsurfaceProvider: incremental CPU solve, grid upload to 3-D textures and the
/// per-pixel sample pass (SslpvProvider.h, docs/methods/sslpv.md "Live preview").

#include <lucent/sslpv/SslpvProvider.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Timer.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/Shader.h>
#include <lucent/mesh/Voxelize.h>

#include <epoxy/gl.h>
#include <shared/SslpvShared.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lucent::sslpv {

namespace {

// SH normalisation constants of Eq. 7, the values SslpvSolver::radiance uses (real orthonormal
// basis, docs/conventions.md): Y00 = 1/(2√π), K1 = √(3/(4π)).
constexpr float SH_Y00 = 0.282094791773878f;
constexpr float SH_K1 = 0.488602511902920f;

/// Coefficients of bands 0–1 uploaded (band 2 integrates to zero over the hemisphere, Eq. 7).
/// Bands 0 and 1 (the propagation modes read no more); mode diffusion also needs slot 4, the
/// surface flux's z (shared/SslpvShared.h).
constexpr int UPLOADED_COEFFS = 4;
constexpr int UPLOADED_COEFFS_DIFFUSION = LUCENT_SSLPV_DIFFUSION_FLUX_COEFF + 3;

void validateOptions(const SslpvProviderOptions& o) {
    LUCENT_CHECK(o.meshId >= -1, "SSLPV provider option 'meshId' must be >= -1, got ", o.meshId);
    LUCENT_CHECK(o.refineSteps >= 0 && o.refineSteps <= 4096,
                 "SSLPV provider option 'refineSteps' must be in [0, 4096], got ", o.refineSteps);
    // Everything else is checked by SslpvRenderer::setOptions / SslpvSolver::setOptions.
    SslpvRenderer probe(o.render);
}

static_assert(LUCENT_SSLPV_THIN_PASS_MAX_GROUPS == gpu::MAX_DISPATCH_GROUPS);

/// sslpv_sample.comp's two passes of one variant: every covered pixel, then the pixels of parts
/// thinner than half a cell that the first appended to the thin-part list (THIN_PASS=1).
struct SamplePasses {
    gpu::GlProgram pixels, thinParts;

    static SamplePasses compile(const gpu::ShaderLibrary& library,
                                std::vector<std::string> defines) {
        SamplePasses passes;
        passes.pixels = gpu::GlProgram::compute(library, "sslpv_sample.comp", defines);
        defines.emplace_back("THIN_PASS=1");
        passes.thinParts = gpu::GlProgram::compute(library, "sslpv_sample.comp", defines);
        return passes;
    }
    [[nodiscard]] bool isValid() const { return pixels.isValid(); }
    void destroy() {
        pixels.destroy();
        thinParts.destroy();
    }
};

/// A tiny homogeneous volume around the mesh: the internal RSM renderer needs a material to
/// run, but the injection texels depend only on mesh, lights and injectionResolution.
MaterialVolume rsmDummyVolume(const TriangleMesh& mesh) {
    return MaterialVolume(GridSpec::around(mesh.bounds(), GridSpec::MIN_RESOLUTION),
                          {Rgb(1.f), Rgb(0.5f), Rgb(0.f)});
}

}  // namespace

struct SslpvSubsurfaceProvider::Impl {
    SslpvProviderOptions opt;
    SslpvSolver solver;
    SslpvRenderer rsm;  ///< RSM injection texels (shared code with the CPU image path)
    TriangleMesh mesh;
    bool hasMesh = false;
    std::vector<Light> lights;
    Mat4f objectFromWorld{1.f};

    CoarseMaterial coarse;          ///< unmasked, incrementally updated
    std::vector<float> meshInside;  ///< mesh fraction per coarse cell (meshInsideFractions)
    GridSpec meshInsideSpec;
    bool meshInsideValid = false;
    float eta = 1.3f;
    bool etaSet = false;  ///< eta came from setMaterial (else updateMaterial uses volume.eta())
    bool hasMaterial = false;
    GridSpec volumeSpec;  ///< fine grid the coarse material was resampled from

    bool materialDirty = true;  ///< solver needs the (masked) coarse material
    /// With materialDirty: the solver's material is the masked coarse material except for
    /// changedCells (strokes since the last update), so only they are written into it.
    bool onlyCellsChanged = false;
    std::vector<int> changedCells;
    bool rsmDirty = true;
    bool glPropagateDirty = false;
    bool uploadDirty = true;

    // GL
    bool created = false;
    /// sslpv_sample.comp for the propagation modes, and with DIFFUSION=1 for mode diffusion
    /// (compiled at its first frame), with ALBEDO_OUT=1 too when an albedo output is set.
    SamplePasses program, diffusionProgram, diffusionAlbedoProgram;
    /// The thin-part pixel list (shared/SslpvShared.h): header, then one uint per pixel of the
    /// largest target so far.
    gpu::GlObject thinPixels;
    std::size_t thinPixelsCapacity = 0;
    unsigned albedoOutput = 0;                  ///< setAlbedoOutput's texture; 0: none
    std::optional<gpu::ShaderLibrary> library;  ///< create()'s, for diffusionProgram
    gpu::GlObject coeffTex[UPLOADED_COEFFS_DIFFUSION];
    int texRes = 0;
    gpu::GlObject timeQuery;
    bool queryPending = false;
    /// The solver's exit-angle table as an SSBO (mode diffusion), and the table it was made of.
    gpu::GlObject exitTableBuffer;
    std::shared_ptr<const dipole::DirpoleExitTable> exitTableUploaded;
    std::unique_ptr<SslpvGlPropagator> gl;
    std::vector<float> staging;
    std::vector<float> readoutAlpha;  ///< per cell, x fastest: SslpvSolver::readoutAlpha
    uint64_t readableVersion = 0;     ///< SslpvSolver::readableVersion() of `readoutAlpha`

    SslpvProviderTimings timings;
    SslpvProviderStats stats;

    explicit Impl(const SslpvProviderOptions& o) : opt(o), solver(o.render.solver) {
        SslpvRenderOptions ro = o.render;
        ro.gridResolution = 4;  // the RSM renderer's own grid is irrelevant: keep it tiny
        ro.solver.maxSteps = 0;
        ro.solver.mode = SslpvMode::Paper;  // it only ray-casts the RSM: no diffusion solve
        rsm.setOptions(ro);
    }

    [[nodiscard]] int gridResolution(const MaterialVolume& v) const {
        return std::min(opt.render.gridResolution, v.resolution());
    }

    [[nodiscard]] const SslpvGrid& sampledGrid() const {
        if (opt.backend == SslpvBackend::Gl && gl && !glPropagateDirty)
            return gl->accumulation();
        return solver.accumulation();
    }
};

SslpvSubsurfaceProvider::SslpvSubsurfaceProvider(const SslpvProviderOptions& options) {
    validateOptions(options);
    m = std::make_unique<Impl>(options);
}

SslpvSubsurfaceProvider::~SslpvSubsurfaceProvider() = default;

void SslpvSubsurfaceProvider::create() {
    create(gpu::ShaderLibrary());
}

void SslpvSubsurfaceProvider::create(const gpu::ShaderLibrary& library) {
    if (m->created)
        return;
    m->program = SamplePasses::compile(library, {});
    m->library = library;
    m->timeQuery = gpu::GlObject::create(gpu::GlObjectKind::Query, GL_TIME_ELAPSED);
    m->created = true;
    m->uploadDirty = true;
    if (m->opt.backend == SslpvBackend::Gl) {
        m->gl = std::make_unique<SslpvGlPropagator>(m->opt.glStorage);
        m->glPropagateDirty = true;
    }
}

void SslpvSubsurfaceProvider::destroy() {
    m->program.destroy();
    m->diffusionProgram.destroy();
    m->diffusionAlbedoProgram.destroy();
    m->thinPixels.destroy();
    m->thinPixelsCapacity = 0;
    for (auto& t : m->coeffTex)
        t.destroy();
    m->texRes = 0;
    if (m->queryPending) {
        GLuint64 ns = 0;
        glGetQueryObjectui64v(m->timeQuery.id(), GL_QUERY_RESULT, &ns);
        m->queryPending = false;
    }
    m->timeQuery.destroy();
    m->exitTableBuffer.destroy();
    m->exitTableUploaded.reset();
    if (m->gl) {
        m->gl->destroy();
        m->gl.reset();
    }
    m->created = false;
}

bool SslpvSubsurfaceProvider::isCreated() const {
    return m->created;
}

void SslpvSubsurfaceProvider::setOptions(const SslpvProviderOptions& o) {
    validateOptions(o);
    const SslpvProviderOptions old = m->opt;
    m->opt = o;
    // Any solver setting (order, steps, sinks, attenuation, mode, calibration) re-propagates.
    m->solver.setOptions(o.render.solver);
    m->glPropagateDirty = o.backend == SslpvBackend::Gl;
    m->uploadDirty = true;
    if (o.render.injectionResolution != old.render.injectionResolution) {
        SslpvRenderOptions ro = m->rsm.options();
        ro.injectionResolution = o.render.injectionResolution;
        m->rsm.setOptions(ro);
        m->rsmDirty = true;
    }
    if (o.render.gridResolution != old.render.gridResolution)
        m->hasMaterial = false;  // needs setMaterial() again (a new coarse grid)
    if (o.backend != old.backend || o.glStorage != old.glStorage) {
        if (m->gl && m->created) {
            m->gl->destroy();
            m->gl.reset();
        }
        if (o.backend == SslpvBackend::Gl && m->created)
            m->gl = std::make_unique<SslpvGlPropagator>(o.glStorage);
        m->glPropagateDirty = o.backend == SslpvBackend::Gl;
        m->uploadDirty = true;
    }
}

const SslpvProviderOptions& SslpvSubsurfaceProvider::options() const {
    return m->opt;
}

void SslpvSubsurfaceProvider::setMesh(const TriangleMesh& mesh) {
    m->rsm.setMesh(mesh);  // validates and builds the ray caster
    m->mesh = mesh;
    m->hasMesh = true;
    m->meshInsideValid = false;
    m->materialDirty = true;
    m->onlyCellsChanged = false;
    m->rsmDirty = true;
}

void SslpvSubsurfaceProvider::setLights(const std::vector<Light>& lights) {
    m->rsm.setLights(lights);
    m->lights = lights;
    m->rsmDirty = true;
}

void SslpvSubsurfaceProvider::setObjectFromWorld(const Mat4f& objectFromWorld) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            LUCENT_CHECK(std::isfinite(objectFromWorld[c][r]),
                         "SSLPV provider: objectFromWorld is not finite");
    LUCENT_CHECK(std::abs(glm::determinant(Mat3f(objectFromWorld))) > 1e-12f,
                 "SSLPV provider: objectFromWorld is not invertible");
    m->objectFromWorld = objectFromWorld;
}

void SslpvSubsurfaceProvider::setMaterial(const MaterialVolume& volume, float eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.f && eta <= 3.f,
                 "SSLPV provider: eta must be in [1, 3], got ", eta);
    const Timer t;
    m->coarse = resampleForPropagation(volume, m->gridResolution(volume));
    m->timings.resampleMs = t.elapsedMs();
    m->stats.lastResampledCells = m->coarse.spec.voxelCount();
    ++m->stats.fullResamples;
    if (eta != m->eta)
        m->rsmDirty = true;  // the injection's Fresnel transmission depends on η
    m->eta = eta;
    m->etaSet = true;
    m->volumeSpec = volume.spec();
    m->hasMaterial = true;
    m->materialDirty = true;
    m->onlyCellsChanged = false;
}

bool SslpvSubsurfaceProvider::hasMaterial() const {
    return m->hasMaterial;
}

void SslpvSubsurfaceProvider::updateMaterial(const MaterialVolume& volume,
                                             const std::vector<int>& dirtyBricks) {
    if (!m->hasMaterial || !(volume.spec() == m->volumeSpec) ||
        m->coarse.spec.resolution != m->gridResolution(volume)) {
        setMaterial(volume, m->etaSet ? m->eta : volume.eta());
        return;
    }
    if (dirtyBricks.empty())
        return;
    const Timer t;
    const bool onlyCells = !m->materialDirty || m->onlyCellsChanged;
    if (!onlyCells)
        m->changedCells.clear();  // the whole material goes to the solver anyway
    m->stats.lastResampledCells = updateCoarseMaterial(m->coarse, volume, dirtyBricks,
                                                       onlyCells ? &m->changedCells : nullptr);
    m->timings.resampleMs = t.elapsedMs();
    ++m->stats.incrementalUpdates;
    m->materialDirty = true;
    m->onlyCellsChanged = onlyCells;
}

const SslpvStats& SslpvSubsurfaceProvider::update() {
    LUCENT_CHECK(m->hasMesh, "SSLPV provider: no mesh (call setMesh first)");
    LUCENT_CHECK(m->hasMaterial, "SSLPV provider: no material (call setMaterial first)");
    Impl& s = *m;
    const bool wasDirty = s.materialDirty || s.rsmDirty || s.solver.isDirty();
    if (s.materialDirty) {
        // Cells count as inside only as far as the mesh agrees (as SslpvRenderer, with the
        // mesh's partial cells for the solver's partial sinks).
        bool onlyCells = s.onlyCellsChanged && s.meshInsideValid &&
                         s.meshInsideSpec == s.coarse.spec && s.solver.hasMaterial() &&
                         s.solver.spec() == s.coarse.spec;
        if (!s.meshInsideValid || !(s.meshInsideSpec == s.coarse.spec)) {
            s.meshInside = meshInsideFractions(s.mesh, s.coarse.spec);
            s.meshInsideSpec = s.coarse.spec;
            s.meshInsideValid = true;
        }
        // A stroke: its cells' σ and g go into the solver's material in place (copying,
        // masking and checking all ten 64³ arrays took 5 ms of a stroke), unless it changed
        // which cells are inside.
        CoarseMaterial& current = s.solver.material();
        for (size_t i = 0; onlyCells && i < s.changedCells.size(); ++i) {
            const size_t k = size_t(s.changedCells[i]);
            onlyCells =
                std::min(s.coarse.insideFraction[k], s.meshInside[k]) == current.insideFraction[k];
        }
        if (onlyCells) {
            for (const int cell : s.changedCells) {
                const size_t k = size_t(cell);
                for (int c = 0; c < 3; ++c) {
                    current.sigma_t[c][k] = s.coarse.sigma_t[c][k];
                    current.sigma_s[c][k] = s.coarse.sigma_s[c][k];
                    current.g[c][k] = s.coarse.g[c][k];
                }
            }
            current.homogeneous = s.coarse.homogeneous;
            s.solver.markMaterialCellsDirty(s.changedCells);
            ++s.stats.inPlaceUpdates;
        } else {
            CoarseMaterial masked = s.coarse;
            for (size_t k = 0; k < s.meshInside.size(); ++k)
                masked.insideFraction[k] = std::min(masked.insideFraction[k], s.meshInside[k]);
            s.solver.setMaterial(std::move(masked), s.eta);
        }
        s.changedCells.clear();
        s.onlyCellsChanged = false;
        s.materialDirty = false;
    }
    const bool rsmRebuilt = s.rsmDirty;
    if (s.rsmDirty) {
        // The internal renderer's tiny material only lets it run; its RSM texels are reused.
        SslpvRenderOptions ro = s.rsm.options();
        if (ro.injectionResolution != s.opt.render.injectionResolution) {
            ro.injectionResolution = s.opt.render.injectionResolution;
            s.rsm.setOptions(ro);
        }
        s.rsm.setMaterial(rsmDummyVolume(s.mesh), s.eta);
        s.rsm.update();
        s.timings.rsmMs = s.rsm.timings().rsmMs;
        s.solver.setInjectionSamples(s.rsm.solver().injectionSamples());
        s.rsmDirty = false;
    }
    const SslpvStats& st = s.solver.solve();
    if (wasDirty) {
        ++s.stats.solves;
        if (st.reinjected)
            s.timings.injectMs = st.injectMs;
        if (st.repropagated) {
            if (s.opt.backend == SslpvBackend::Cpu)
                s.timings.propagateMs = st.propagateMs;
            s.glPropagateDirty = s.opt.backend == SslpvBackend::Gl;
        }
        s.uploadDirty = true;
        // (Mode diffusion re-injects on every material change, from the RSM it already has.)
        s.timings.lastUpdateMs = s.timings.resampleMs + (rsmRebuilt ? s.timings.rsmMs : 0.0) +
                                 (st.reinjected ? st.injectMs : 0.0) +
                                 (st.repropagated ? st.propagateMs : 0.0);
    }
    return st;
}

SslpvOptions refinedSolverOptions(const SslpvProviderOptions& options) {
    SslpvOptions o = options.render.solver;
    o.maxSteps = std::max(o.maxSteps, options.refineSteps);
    return o;
}

bool SslpvSubsurfaceProvider::isDirty() const {
    return m->materialDirty || m->rsmDirty || m->solver.isDirty() || m->uploadDirty ||
           m->glPropagateDirty;
}

bool SslpvSubsurfaceProvider::converged() const {
    const Impl& s = *m;
    return !(s.opt.refineSteps > 0 && !s.materialDirty && !s.rsmDirty &&
             s.solver.propagationInFlight() && s.solver.stats().stepsUsed < s.opt.refineSteps);
}

bool SslpvSubsurfaceProvider::refine() {
    Impl& s = *m;
    if (converged())
        return false;
    // The same chunk as a change's frame, so an idle frame costs what a stroke's does.
    const int steps = std::min(std::max(s.opt.render.solver.maxSteps, 1),
                               s.opt.refineSteps - s.solver.stats().stepsUsed);
    const SslpvStats& st = s.solver.continuePropagation(steps);
    ++s.stats.refinements;
    if (s.opt.backend == SslpvBackend::Cpu)
        s.timings.propagateMs = st.propagateMs;
    // The GL propagator re-runs the CPU solve's step count from the injection (SslpvGl.h).
    s.glPropagateDirty = s.opt.backend == SslpvBackend::Gl;
    s.uploadDirty = true;
    return true;
}

void SslpvSubsurfaceProvider::renderSubsurface(const gpu::GBufferView& g, unsigned target) {
    LUCENT_CHECK(m->created, "SSLPV provider: create() was not called");
    Impl& s = *m;
    const int solves = s.stats.solves;
    update();
    if (s.stats.solves == solves)  // nothing changed: carry a propagation in flight on
        refine();
    if (s.opt.backend == SslpvBackend::Gl && s.glPropagateDirty) {
        if (!s.gl)
            s.gl = std::make_unique<SslpvGlPropagator>(s.opt.glStorage);
        const Timer t;
        s.gl->propagate(s.solver);
        s.timings.propagateMs = t.elapsedMs();
        s.glPropagateDirty = false;
        s.uploadDirty = true;
    }
    const GridSpec& spec = s.solver.spec();
    const int N = spec.resolution;
    if (s.uploadDirty || s.texRes != N) {
        const Timer t;
        if (s.texRes != N) {
            for (auto& tex : s.coeffTex) {
                tex.destroy();
                tex = gpu::createTexture3D(GL_RGBA32F, N, N, N, /*linear=*/false);
            }
            s.texRes = N;
        }
        if (s.opt.backend == SslpvBackend::Gl && s.gl) {
            // The GL grid goes to the textures on the GPU: no read-back, no CPU upload.
            const unsigned ids[UPLOADED_COEFFS] = {s.coeffTex[0].id(), s.coeffTex[1].id(),
                                                   s.coeffTex[2].id(), s.coeffTex[3].id()};
            s.gl->writeTextures(ids);
            s.timings.uploadMs = t.elapsedMs();
            s.timings.lastUpdateMs += s.timings.uploadMs;
            s.uploadDirty = false;
            ++s.stats.uploads;
        }
    }
    if (s.uploadDirty) {
        const Timer t;
        const SslpvGrid& grid = s.sampledGrid();
        const size_t cells = spec.voxelCount();
        s.staging.resize(4 * cells);
        // Bands 0 and 1; mode diffusion's slot 4 too (the surface flux's z). An order-2 grid
        // of the propagation modes has band 2 there, which the sample pass does not read.
        const bool diffusion = s.solver.options().mode == SslpvMode::Diffusion;
        const int uploaded =
            std::min(grid.coeffCount(), diffusion ? UPLOADED_COEFFS_DIFFUSION : UPLOADED_COEFFS);
        // The read-out's alphas (texture 0's) only when they may have changed (a stroke keeps
        // them), then each texture's texels slice by slice on the worker threads: the
        // repacking took 3.3 of the 5.6 ms of a 64³ upload on one thread.
        if (s.readoutAlpha.size() != cells || s.readableVersion != s.solver.readableVersion()) {
            s.readoutAlpha.resize(cells);
            parallelFor(0, N, [&](int64_t z0, int64_t z1) {
                for (int z = int(z0); z < int(z1); ++z)
                    for (int y = 0; y < N; ++y)
                        for (int x = 0; x < N; ++x)
                            s.readoutAlpha[(size_t(z) * N + size_t(y)) * N + size_t(x)] =
                                s.solver.readoutAlpha({x, y, z});
            });
            s.readableVersion = s.solver.readableVersion();
        }
        for (int i = 0; i < uploaded; ++i) {
            const float* planes[3] = {grid.plane(0, i), grid.plane(1, i), grid.plane(2, i)};
            parallelFor(0, N, [&](int64_t z0, int64_t z1) {
                for (int z = int(z0); z < int(z1); ++z)
                    for (int y = 0; y < N; ++y) {
                        const size_t row = (size_t(z) * N + size_t(y)) * N;
                        const size_t pi = grid.index({0, y, z});
                        for (int x = 0; x < N; ++x) {
                            float* dst = &s.staging[4 * (row + size_t(x))];
                            dst[0] = planes[0][pi + size_t(x)];
                            dst[1] = planes[1][pi + size_t(x)];
                            dst[2] = planes[2][pi + size_t(x)];
                            dst[3] = i == 0 ? s.readoutAlpha[row + size_t(x)] : 0.f;
                        }
                    }
            });
            glTextureSubImage3D(s.coeffTex[i].id(), 0, 0, 0, 0, N, N, N, GL_RGBA, GL_FLOAT,
                                s.staging.data());
        }
        s.timings.uploadMs = t.elapsedMs();
        s.timings.lastUpdateMs += s.timings.uploadMs;
        s.uploadDirty = false;
        ++s.stats.uploads;
    }

    // GPU time of the previous sample pass, when available (no stall).
    if (s.queryPending) {
        GLint available = 0;
        glGetQueryObjectiv(s.timeQuery.id(), GL_QUERY_RESULT_AVAILABLE, &available);
        if (available) {
            GLuint64 ns = 0;
            glGetQueryObjectui64v(s.timeQuery.id(), GL_QUERY_RESULT, &ns);
            s.timings.sampleGpuMs = double(ns) * 1e-6;
            s.queryPending = false;
        }
    }
    const Timer t;
    const bool query = !s.queryPending;
    if (query)
        glBeginQuery(GL_TIME_ELAPSED, s.timeQuery.id());
    const bool diffusion = s.solver.options().mode == SslpvMode::Diffusion;
    const bool albedoOut = diffusion && s.albedoOutput != 0;
    if (diffusion && !albedoOut && !s.diffusionProgram.isValid())
        s.diffusionProgram = SamplePasses::compile(*s.library, {"DIFFUSION=1"});
    if (albedoOut && !s.diffusionAlbedoProgram.isValid())
        s.diffusionAlbedoProgram =
            SamplePasses::compile(*s.library, {"DIFFUSION=1", "ALBEDO_OUT=1"});
    const SamplePasses& passes =
        albedoOut ? s.diffusionAlbedoProgram : (diffusion ? s.diffusionProgram : s.program);

    // The thin-part list: grown to this target's pixels (never shrunk, so a steady frame
    // creates no GL object), its header reset to no pixels and no groups.
    LUCENT_CHECK(g.width <= 0xffff && g.height <= 0xffff,
                 "SSLPV sample pass: a target of at most 65535 × 65535 pixels, got ", g.width,
                 " × ", g.height);
    const std::size_t pixelCount = std::size_t(g.width) * std::size_t(g.height);
    if (pixelCount > s.thinPixelsCapacity) {
        s.thinPixels.destroy();
        s.thinPixels =
            gpu::createBuffer((LUCENT_SSLPV_THIN_PIXELS_HEADER_UINTS + pixelCount) * sizeof(GLuint),
                              nullptr, GL_DYNAMIC_STORAGE_BIT);
        s.thinPixelsCapacity = pixelCount;
    }
    const GLuint emptyList[LUCENT_SSLPV_THIN_PIXELS_HEADER_UINTS] = {0, 1, 1, 0};
    glNamedBufferSubData(s.thinPixels.id(), 0, sizeof(emptyList), emptyList);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_SSLPV_BINDING_THIN_PIXELS, s.thinPixels.id());

    if (albedoOut)
        glBindImageTexture(1, s.albedoOutput, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindTextureUnit(0, g.positionTexture);
    glBindTextureUnit(1, g.normalTexture);
    for (int i = 0; i < UPLOADED_COEFFS_DIFFUSION; ++i)
        glBindTextureUnit(GLuint(2 + i), s.coeffTex[i].id());
    glBindImageTexture(0, target, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    // Perspective unless the clip matrix's w row ignores the position (orthographic).
    const Mat4f& clip = g.clipFromWorld;
    const bool ortho = clip[0][3] == 0.f && clip[1][3] == 0.f && clip[2][3] == 0.f;
    const Mat4f& v = g.viewFromWorld;
    const Vector3f forward = -Vector3f(v[0][2], v[1][2], v[2][2]);  // −(view z) in world
    // Non-null only after a diffusion solve with the exit table on (SslpvSolver::exitTable).
    const std::shared_ptr<const dipole::DirpoleExitTable>& table = s.solver.exitTable();
    const bool exitCorrection = table != nullptr;
    if (exitCorrection) {
        if (table != s.exitTableUploaded) {
            s.exitTableBuffer.destroy();
            s.exitTableBuffer = gpu::createBuffer(table->values().size() * sizeof(float),
                                                  table->values().data(), 0);
            s.exitTableUploaded = table;
        }
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_SSLPV_BINDING_EXIT_TABLE,
                         s.exitTableBuffer.id());
    }
    const bool surfaceFlux = diffusion && s.solver.surfaceFluxReadout();
    // Both passes take the same uniforms.
    auto setUniforms = [&](const gpu::GlProgram& program) {
        const GLuint p = program.id();
        glProgramUniformMatrix4fv(p, program.uniformLocation("u_objectFromWorld"), 1, GL_FALSE,
                                  &s.objectFromWorld[0][0]);
        glProgramUniform3f(p, program.uniformLocation("u_eye"), g.cameraPosition.x,
                           g.cameraPosition.y, g.cameraPosition.z);
        glProgramUniform3f(p, program.uniformLocation("u_forward"), forward.x, forward.y,
                           forward.z);
        glProgramUniform1i(p, program.uniformLocation("u_ortho"), ortho ? 1 : 0);
        glProgramUniform2i(p, program.uniformLocation("u_size"), g.width, g.height);
        glProgramUniform1i(p, program.uniformLocation("u_meshId"), s.opt.meshId);
        glProgramUniform3f(p, program.uniformLocation("u_origin"), spec.origin.x, spec.origin.y,
                           spec.origin.z);
        glProgramUniform1f(p, program.uniformLocation("u_h"), spec.voxelSize);
        glProgramUniform1i(p, program.uniformLocation("u_res"), N);
        glProgramUniform1f(p, program.uniformLocation("u_eta"), s.eta);
        glProgramUniform1f(p, program.uniformLocation("u_exitScale"), s.solver.exitScale());
        glProgramUniform1f(p, program.uniformLocation("u_Y00"), SH_Y00);
        glProgramUniform1f(p, program.uniformLocation("u_K1"), SH_K1);
        glProgramUniform1i(p, program.uniformLocation("u_exitCorrection"), exitCorrection ? 1 : 0);
        glProgramUniform1i(p, program.uniformLocation("u_surfaceFlux"), surfaceFlux ? 1 : 0);
        glProgramUniform1f(
            p, program.uniformLocation("u_twoA"),
            surfaceFlux ? float(2.0 * s.solver.diffusion().boundaryConstant()) : 0.f);
    };
    setUniforms(passes.pixels);
    setUniforms(passes.thinParts);
    glUseProgram(passes.pixels.id());
    glDispatchCompute(unsigned(g.width + 7) / 8, unsigned(g.height + 7) / 8, 1);
    // The thin pass reads the list the first wrote, and its group count as its arguments; the
    // next frame empties it with glNamedBufferSubData (the thin pass only reads it). One barrier
    // for the three: llvmpipe makes each a full finish.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT |
                    GL_BUFFER_UPDATE_BARRIER_BIT);
    glUseProgram(passes.thinParts.id());
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, s.thinPixels.id());
    glDispatchComputeIndirect(0);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
    // The target is written with imageStore: visible to texture fetches (the shade pass), image
    // loads, framebuffer clears/draws (the next frame's clear) and glGetTexImage read-backs
    // (GL 4.5 §7.13.2), also when the provider is used without gpu::SceneRenderer.
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                    GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    glUseProgram(0);
    if (query) {
        glEndQuery(GL_TIME_ELAPSED);
        s.queryPending = true;
    }
    s.timings.sampleCpuMs = t.elapsedMs();
    ++s.stats.frames;
}

void SslpvSubsurfaceProvider::setAlbedoOutput(unsigned texture) {
    m->albedoOutput = texture;
}

const SslpvSolver& SslpvSubsurfaceProvider::solver() const {
    return m->solver;
}
const SslpvGrid& SslpvSubsurfaceProvider::accumulation() const {
    return m->sampledGrid();
}
const CoarseMaterial& SslpvSubsurfaceProvider::coarseMaterial() const {
    return m->coarse;
}
float SslpvSubsurfaceProvider::eta() const {
    return m->eta;
}
const SslpvProviderTimings& SslpvSubsurfaceProvider::timings() const {
    return m->timings;
}
const SslpvProviderStats& SslpvSubsurfaceProvider::stats() const {
    return m->stats;
}

}  // namespace lucent::sslpv
