// SPDX-License-Identifier: MIT
/// @file
/// @brief `sslpv`: subsurface light propagation volumes (Børlum et al. 2011;
/// docs/methods/sslpv.md). CPU: SslpvRenderer's ray-cast image (its own ray-traced direct
/// term). GL: SslpvSubsurfaceProvider per G-buffer pixel, the propagation on the CPU solver or
/// on the GPU (parameter `propagation`); incremental resampling of the painted bricks.

#include <lucent/core/Error.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Registry.h>
#include <lucent/sslpv/SslpvProvider.h>
#include <lucent/sslpv/SslpvRenderer.h>

#include "../MethodUtil.h"
#include "SslpvSettings.h"

#include <algorithm>

namespace lucent::methods {

namespace {

using detail::num;

class SslpvMethod final : public Method {
public:
    using Method::Method;

    void createGl(const gpu::ShaderLibrary& library) override {
        m_library = &library;
        makeProvider();
    }
    void destroyGl() override {
        if (m_provider)
            m_provider->destroy();
        m_provider.reset();
        m_library = nullptr;
    }

    void setScene(const SceneInputs& scene) override {
        LUCENT_CHECK(scene.mesh && scene.material, "sslpv: the object needs a mesh and a material");
        LUCENT_CHECK(m_provider, "sslpv: setScene before createGl");
        const float eta = std::clamp(scene.eta, 1.f, 3.f);
        if (!m_meshSet || scene.mesh != m_scene.mesh) {
            m_provider->setMesh(*scene.mesh);  // rest space
            m_meshSet = true;
        }
        if (!m_lightsSet || !detail::sameLights(scene.lights, m_scene.lights)) {
            m_provider->setLights(scene.lights);
            m_lightsSet = true;
        }
        if (!m_materialSet || scene.material != m_scene.material || eta != m_eta) {
            m_provider->setMaterial(*scene.material, eta);
            m_materialSet = true;
            m_eta = eta;
        }
        m_scene = scene;
    }
    void materialChanged(const std::vector<int>& dirtyBricks) override {
        if (m_provider && m_materialSet && !dirtyBricks.empty())
            m_provider->updateMaterial(*m_scene.material, dirtyBricks);
    }

    gpu::SubsurfaceProvider* subsurfacePass() override { return m_provider.get(); }

    /// Live modes paper and calibrated refine over idle frames while light is in flight
    /// (parameter refine-steps); every other use is done after one frame.
    [[nodiscard]] bool converged() const override {
        return backend() == Backend::Cpu || !m_provider || m_provider->converged();
    }

    /// The CPU renderer (SslpvRenderer) of the whole scene; the subsurface term whatever the
    /// request (CpuRequest::subsurfaceOnly changes nothing, see below).
    ImageRgb renderCpu(const Scene& scene, const CpuRequest& /*request*/) override {
        sslpv::SslpvRenderOptions opt = m_options.render;
        // The translucent-surface rule of every method (methods::translucentSurface): the
        // smooth boundary reflects the scene's delta lights as deltas no camera ray meets, so
        // the paper's Phong direct term (Børlum 2011 §5) is not drawn; subsurface only.
        opt.direct = false;
        sslpv::SslpvRenderTimings t;
        sslpv::SslpvStats st;
        ImageRgb image = sslpv::renderSslpv(scene, opt, &t, &st);
        m_cpuStats = {
            {"mode", params().getChoice("mode")},         {"steps", std::to_string(st.stepsUsed)},
            {"injected W (green)", num(st.injected.y)},   {"exitant W (green)", num(st.exitant.y)},
            {"remaining W (green)", num(st.remaining.y)}, {"rsm ms", num(t.rsmMs, "%.2f")},
            {"resample ms", num(t.resampleMs, "%.2f")},   {"inject ms", num(t.injectMs, "%.2f")},
            {"propagate ms", num(t.propagateMs, "%.2f")}, {"shade ms", num(t.shadeMs, "%.2f")}};
        return image;
    }

    [[nodiscard]] Stats stats() const override {
        if (backend() == Backend::Cpu)
            return m_cpuStats;
        if (!m_provider)
            return {};
        const sslpv::SslpvProviderTimings& t = m_provider->timings();
        const sslpv::SslpvProviderStats& st = m_provider->stats();
        return {{"grid", std::to_string(m_options.render.gridResolution)},
                {"propagation", m_options.backend == sslpv::SslpvBackend::Gl ? "GL" : "CPU"},
                {"steps", std::to_string(m_provider->solver().stats().stepsUsed)},
                {"refinements", std::to_string(st.refinements)},
                {"injected W (green)", num(m_provider->solver().stats().injected.y)},
                {"resample ms", num(t.resampleMs, "%.2f")},
                {"resampled cells", std::to_string(st.lastResampledCells)},
                {"rsm ms", num(t.rsmMs, "%.2f")},
                {"inject ms", num(t.injectMs, "%.2f")},
                {"propagate ms", num(t.propagateMs, "%.2f")},
                {"upload ms", num(t.uploadMs, "%.2f")},
                {"sample ms (CPU issue)", num(t.sampleCpuMs, "%.2f")},
                {"sample ms (GPU)", num(t.sampleGpuMs, "%.2f")},
                {"last update ms", num(t.lastUpdateMs, "%.2f")},
                {"incremental updates", std::to_string(st.incrementalUpdates)},
                {"full resamples", std::to_string(st.fullResamples)}};
    }

private:
    void applyParams(const Params& p) override {
        sslpv::SslpvProviderOptions o;
        o.render.gridResolution = p.getInt("grid");
        o.render.solver.maxSteps = p.getInt("steps");
        if (isLive()) {  // the app's range (each step re-propagates on a stroke)
            o.render.solver.maxSteps = std::clamp(o.render.solver.maxSteps, 1, 512);
            // Idle frames carry a stroke's propagation on, `steps` per frame, while light is
            // in flight: a stroke's frame stays bounded and the picture still converges (a
            // high-albedo medium keeps 13 % of its light in flight after 32 steps).
            o.refineSteps = p.getInt("refine-steps");
        }
        // Run to convergence: a fixed step count leaves light in flight in a high-albedo
        // medium (13 % of the injected flux at grid 32 after 32 steps on the marble sphere),
        // and what has not reached the accumulation grid is missing from the image. The GL
        // propagation runs as many steps as the CPU solve used (SslpvGl.h).
        o.render.solver.stopEpsilon = float(p.getFloat("stop"));
        o.render.solver.brickStopEpsilon = float(p.getFloat("brick-stop"));
        o.render.solver.order = p.getInt("sh");
        // calibrated: the fitted per-step absorption and radiance gain (SslpvCalibration,
        // docs/methods/sslpv.md); paper: §3.2.1 with `attenuation` (absorption-only by default
        // offline: within −15 %…+22 % of diffusion on thick slabs for α′ ≥ 0.5, where the
        // paper's literal extinction is 5–50× too dark).
        const std::string& mode = p.getChoice("mode");
        if (mode == "diffusion") {
            o.render.solver.diffusionExactTotal = p.getBool("diffusion-normalise");
            o.render.solver.diffusionExitTable = p.getChoice("diffusion-exit") == "exact";
            o.render.solver.diffusionSurfaceFlux = p.getBool("diffusion-flux");
            o.render.solver.diffusionEntryDepth = p.getBool("diffusion-entry");
            o.render.solver.diffusionSlabTotal = p.getBool("diffusion-slab");
            LUCENT_CHECK(!p.isGiven("attenuation"),
                         "sslpv: attenuation applies to mode paper only");
            detail::useDiffusionMode(
                o, p, "sslpv: mode diffusion",
                backend() == Backend::Gl && p.getChoice("propagation") != "cpu");
        } else if (mode == "calibrated") {
            o.render.solver.mode = sslpv::SslpvMode::Calibrated;
            LUCENT_CHECK(!p.isGiven("attenuation"),
                         "sslpv: attenuation applies to mode paper only");
        } else {
            o.render.solver.mode = sslpv::SslpvMode::Paper;
            o.render.solver.attenuation = p.getChoice("attenuation") == "extinction"
                                              ? sslpv::SslpvAttenuation::Extinction
                                              : sslpv::SslpvAttenuation::Absorption;
        }
        if (backend() == Backend::Gl)
            o.backend = p.getChoice("propagation") == "gl" ? sslpv::SslpvBackend::Gl
                                                           : sslpv::SslpvBackend::Cpu;
        const bool recreate = m_provider && o.backend != m_options.backend;
        // A new grid drops the provider's material (SslpvProvider::setOptions): the next
        // setScene hands it the volume again (a live instance's grid changes at run time).
        if (o.render.gridResolution != m_options.render.gridResolution)
            m_materialSet = false;
        m_options = o;
        if (recreate) {  // a new provider, fully re-synchronised at the next setScene
            const gpu::ShaderLibrary* library = m_library;
            destroyGl();
            createGl(*library);
        } else if (m_provider) {
            m_provider->setOptions(m_options);
        }
    }

    void makeProvider() {
        m_provider = std::make_unique<sslpv::SslpvSubsurfaceProvider>(m_options);
        m_provider->create(*m_library);
        m_meshSet = m_lightsSet = m_materialSet = false;
    }

    sslpv::SslpvProviderOptions m_options;
    const gpu::ShaderLibrary* m_library = nullptr;
    std::unique_ptr<sslpv::SslpvSubsurfaceProvider> m_provider;
    SceneInputs m_scene;
    float m_eta = 0.f;
    bool m_meshSet = false, m_lightsSet = false, m_materialSet = false;
    Stats m_cpuStats;
};

}  // namespace

MethodEntry sslpvMethod() {
    MethodEntry e;
    MethodInfo& i = e.info;
    i.name = "sslpv";
    i.title = "SSLPV";
    i.summary = "subsurface light propagation volumes (Borlum et al. 2011)";
    i.docs = "docs/methods/sslpv.md";
    i.caps.gl = true;
    i.caps.cpu = true;
    i.caps.preferred = Backend::Cpu;  // offline: the CPU ray-cast image with its own direct term
    // Live modes paper and calibrated carry a propagation in flight on over idle frames.
    i.caps.progressive = true;
    i.params = {
        {"grid", ParamType::Int, "LPV cells per axis", 4, 256, {}, "32"},
        // Live: 32 steps per frame and no global stop, because the stop rule is global: paint
        // that absorbs in one place ends the propagation sooner everywhere, and the far side of
        // the object dimmed with each stroke (test AppPaint.StrokeChangesSslpvPixelsNearTheStroke).
        // Idle frames carry the propagation on until the per-brick stop (local) ends it
        // (refine-steps). Offline: to convergence in one solve.
        {"steps",
         ParamType::Int,
         "maximum propagation steps; fewer once converged (see stop; live preview: steps per "
         "frame, at most 512, carried on over idle frames up to refine-steps)",
         0,
         4096,
         {},
         "1024",
         "",
         "32"},
        {"sh",
         ParamType::Int,
         "spherical-harmonics order: 1 (4 coefficients) or 2 (9)",
         1,
         2,
         {},
         "1"},
        {"mode",
         ParamType::Choice,
         "calibrated: fitted per-step absorption and gain; paper: the paper's transfer (section "
         "3.2.1); diffusion: the diffusion equation solved on the same grid instead of the "
         "propagation (steps: CG iterations; stop: unbalanced power, default 0.001)",
         0,
         0,
         {"calibrated", "paper", "diffusion"},
         "calibrated",
         "",
         "paper"},
        {"diffusion-normalise",
         ParamType::Bool,
         "mode diffusion: scale the exitance to the exact half-space's total at each surface "
         "cell's albedo (off: the diffusion model's own; the other modes ignore it)",
         0,
         0,
         {},
         "on"},
        {"diffusion-exit",
         ParamType::Choice,
         "mode diffusion: the light leaves each surface point with the exact half-space's "
         "distribution over exit angles at its albedo (exact) or as a Fresnel-weighted diffuse "
         "source (diffuse, the diffusion model's own); the other modes ignore it",
         0,
         0,
         {"exact", "diffuse"},
         "exact"},
        {"diffusion-flux",
         ParamType::Bool,
         "mode diffusion: the light leaving each surface point also follows the flux along the "
         "surface there (P1's J.w term: back-lit rims); off: the exitance only; the other modes "
         "ignore it",
         0,
         0,
         {},
         "on"},
        {"diffusion-slab",
         ParamType::Bool,
         "mode diffusion, with diffusion-normalise: scale each surface cell's exitance to the "
         "exact slab as thick as the part it lies on (measured along its normal) instead of the "
         "half-space, so thin parts do not send out too much (off: the half-space's scale "
         "everywhere); the other modes ignore it",
         0,
         0,
         {},
         "on"},
        {"diffusion-entry",
         ParamType::Bool,
         "mode diffusion: the light scattered first in the cell where a beam enters is placed at "
         "its depth under the surface (off: at the cell's centre, half a cell deep, which sends "
         "too much light through thin layers of cells coarser than a mean free path); the other "
         "modes ignore it",
         0,
         0,
         {},
         "on"},
        {"attenuation",
         ParamType::Choice,
         "mode paper only: per-step attenuation",
         0,
         0,
         {"absorption", "extinction"},
         "absorption",
         "",
         "extinction"},
        {"propagation",
         ParamType::Choice,
         "GL backend: where the propagation steps run (cpu: SslpvSolver; gl: compute shaders)",
         0,
         0,
         {"cpu", "gl"},
         "cpu"},
    };
    // After "steps": its stop rules and live refinement.
    const std::vector<ParamDescriptor> stops =
        detail::propagationStopParams("", "modes paper and calibrated: ");
    i.params.insert(std::find_if(i.params.begin(), i.params.end(),
                                 [](const ParamDescriptor& d) { return d.name == "steps"; }) +
                        1,
                    stops.begin(), stops.end());
    // The paper variant pins the attenuation it is evaluated with (the offline default): the
    // live preview's own default is the paper's literal extinction, 0.06 of the brightness on
    // backlit_thin_thick at grid 64, so Auto's live "sslpv:paper" showed another picture than
    // the one its error models were measured on.
    i.variants = {{"paper", ParamSet::fromAssignments({"mode=paper", "attenuation=absorption"}),
                   Backend::Auto},
                  {"calibrated", ParamSet::fromAssignments({"mode=calibrated"}), Backend::Auto},
                  {"diffusion", ParamSet::fromAssignments({"mode=diffusion"}), Backend::Auto},
                  {"gl", {}, Backend::Gl}};
    // Every level propagates to convergence (parameter stop; the step count is only a bound), so
    // the levels differ by the grid alone (docs/methods/sslpv.md, "Convergence").
    for (int n : {16, 32, 64})
        i.quality.push_back({"grid " + std::to_string(n),
                             ParamSet::fromAssignments({"grid=" + std::to_string(n)}),
                             Backend::Auto});
    i.evaluate = {"paper", "calibrated", "diffusion"};
    e.create = detail::make<SslpvMethod>;
    return e;
}

}  // namespace lucent::methods
