// SPDX-License-Identifier: MIT
/// @file
/// @brief `combined`: the image-space dipole for the transport within the split radius r_s and
/// SSLPV beyond it (docs/methods/combined.md). GL: combined::CombinedSubsurfaceProvider
/// (progressive dipole part); CPU: combined::renderCombined (subsurface term only).

#include <lucent/combined/Combined.h>
#include <lucent/combined/CombinedProvider.h>
#include <lucent/core/Error.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Registry.h>

#include "../MethodUtil.h"
#include "../sslpv/SslpvSettings.h"

#include <algorithm>

namespace lucent::methods {

namespace {

using detail::num;

class CombinedMethod final : public Method {
public:
    using Method::Method;

    void createGl(const gpu::ShaderLibrary& library) override {
        m_provider = std::make_unique<combined::CombinedSubsurfaceProvider>();
        m_provider->create(library);
        m_meshSet = m_lightsSet = m_materialSet = m_settingsSet = false;
    }
    void destroyGl() override {
        if (m_provider)
            m_provider->destroy();
        m_provider.reset();
    }

    void setScene(const SceneInputs& scene) override {
        LUCENT_CHECK(scene.mesh && scene.material,
                     "combined: the object needs a mesh and a material volume");
        LUCENT_CHECK(m_provider, "combined: setScene before createGl");
        const float eta = std::clamp(scene.eta, 1.f, 3.f);
        m_eta = eta;
        m_meshId = scene.meshId;
        applySettings();
        if (!m_meshSet || scene.mesh != m_scene.mesh) {
            m_provider->setMesh(*scene.mesh);  // rest space, as SSLPV
            m_meshSet = true;
        }
        if (!m_lightsSet || !detail::sameLights(scene.lights, m_scene.lights)) {
            m_provider->setLights(scene.lights);
            m_lightsSet = true;
        }
        if (!m_materialSet || scene.material != m_scene.material || eta != m_materialEta) {
            m_provider->setMaterial(*scene.material, eta);
            m_materialSet = true;
            m_materialEta = eta;
        }
        m_scene = scene;
    }
    void materialChanged(const std::vector<int>& dirtyBricks) override {
        if (m_provider && m_materialSet && !dirtyBricks.empty())
            m_provider->updateMaterial(*m_scene.material, dirtyBricks);
    }

    gpu::SubsurfaceProvider* subsurfacePass() override { return m_provider.get(); }
    [[nodiscard]] bool converged() const override {
        return !m_provider || m_provider->stats().converged;
    }

    ImageRgb renderCpu(const Scene& scene, const CpuRequest&) override {
        const int spp = params().getInt("spp");
        LUCENT_CHECK(spp <= 65536, "combined: spp: ", spp, " is outside [1, 65536] on the CPU");
        combined::CombinedSettings cs;
        cs.splitRadius = m_settings.splitRadius;
        cs.mode = m_settings.mode;
        cs.dipoleLightViews = m_settings.dipole.lightViews;
        cs.autoSkipSslpv = m_settings.autoSkipSslpv;
        cs.farTolerance = m_settings.farTolerance;
        cs.sslpv = m_settings.sslpv.render;
        cs.dipole.model = m_settings.dipole.model;
        cs.dipole.uniformSamples = spp / 4;
        cs.dipole.importanceSamples = spp - cs.dipole.uniformSamples;
        cs.dipole.seed = m_settings.dipole.seed;
        const combined::CombinedResult r = combined::renderCombined(scene, cs);
        m_cpuStats = planStats(r.plan);
        return r.radiance;
    }

    [[nodiscard]] Stats stats() const override {
        Stats s{{"sslpv part", m_diffusionPart ? "diffusion" : "calibrated"}};
        if (backend() == Backend::Cpu) {
            s.insert(s.end(), m_cpuStats.begin(), m_cpuStats.end());
            return s;
        }
        if (!m_provider)
            return s;
        const combined::CombinedProviderStats& st = m_provider->stats();
        const Stats plan = planStats(st.plan);
        s.insert(s.end(), plan.begin(), plan.end());
        s.push_back({"dipole frames", std::to_string(st.dipole.frames)});
        s.push_back({"dipole spp", std::to_string(st.dipole.samplesPerPixel)});
        s.push_back({"converged", st.converged ? "yes" : "no"});
        s.push_back({"sslpv incremental updates", std::to_string(st.sslpv.incrementalUpdates)});
        s.push_back({"sslpv full resamples", std::to_string(st.sslpv.fullResamples)});
        s.push_back({"sslpv steps",
                     std::to_string(m_provider->sslpvProvider().solver().stats().stepsUsed)});
        s.push_back({"sslpv refinements", std::to_string(st.sslpv.refinements)});
        s.push_back({"kernels kept after strokes", std::to_string(st.kernelsKept)});
        // The last frame's parts (sslpv, dipole, kernel, local, add): GPU and issuing CPU time.
        for (const gpu::PassTiming& t : m_provider->passTimes()) {
            s.push_back({t.name + " gpu ms", num(float(t.gpuMs), "%.2f")});
            s.push_back({t.name + " cpu ms", num(float(t.cpuMs), "%.2f")});
        }
        return s;
    }

private:
    Stats planStats(const combined::SplitPlan& plan) const {
        return {{"r_s mm", num(plan.splitRadius, "%.3g")},
                {"r_s cells", plan.cellSize > 0.f ? num(plan.splitRadius / plan.cellSize, "%.2f")
                                                  : std::string("0")},
                {"cell mm", num(plan.cellSize, "%.3g")},
                {"sslpv", plan.sslpvSkipped ? std::string("skipped (far share ") +
                                                  num(float(plan.farShare), "%.2g") + ")"
                                            : std::string(plan.sslpvOn ? "on" : "off")},
                {"sslpv skips steps", std::to_string(plan.skipSteps) + " of " +
                                          std::to_string(m_settings.sslpv.render.solver.maxSteps)}};
    }

    void applyParams(const Params& p) override {
        combined::CombinedProviderSettings s;  // the module's defaults (camera-only dipole)
        s.splitRadius = p.getFloat("split-radius");
        s.mode = p.getChoice("split") == "steps" ? combined::SplitMode::Steps
                                                 : combined::SplitMode::Kernel;
        s.dipole.model = p.getChoice("model") == "better-dipole" ? dipole::Model::BetterDipole
                                                                 : dipole::Model::Dipole;
        s.dipole.seed = uint32_t(p.getInt("seed"));
        s.dipole.lightViews = p.getBool("light-views");
        s.autoSkipSslpv = p.getBool("auto-skip");
        s.sslpv.render.gridResolution = p.getInt("grid");
        s.sslpv.render.solver.maxSteps = p.getInt("steps");
        s.sslpv.render.solver.stopEpsilon = float(p.getFloat("stop"));
        s.sslpv.render.solver.brickStopEpsilon = float(p.getFloat("brick-stop"));
        if (isLive())
            s.sslpv.refineSteps = p.getInt("refine-steps");
        s.sslpv.render.solver.order = p.getInt("sh");
        // auto: the diffusion part, unless the split or the propagation asked for need
        // propagation steps (docs/methods/combined.md, "The SSLPV part").
        const bool gl = backend() == Backend::Gl && p.getChoice("propagation") == "gl";
        const std::string& part = p.getChoice("sslpv-mode");
        m_diffusionPart =
            part == "diffusion" || (part == "auto" && s.mode == combined::SplitMode::Kernel && !gl);
        if (m_diffusionPart) {
            LUCENT_CHECK(s.mode == combined::SplitMode::Kernel,
                         "combined: sslpv-mode diffusion needs split kernel (the steps split "
                         "skips propagation steps, which diffusion does not have)");
            detail::useDiffusionMode(s.sslpv, p, "combined: sslpv-mode diffusion", gl);
            // Within the split radius the light is the dipole's: measured with the entry
            // sources at their depth, the front-lit and painted cases read 1–6 % brighter
            // (docs/methods/combined.md, "The diffusion part's entry sources").
            s.sslpv.render.solver.diffusionEntryDepth = false;
        }
        if (backend() == Backend::Gl) {
            s.sslpv.backend = p.getChoice("propagation") == "gl" ? sslpv::SslpvBackend::Gl
                                                                 : sslpv::SslpvBackend::Cpu;
            s.dipole.samplesPerFrame = p.getInt("spp-frame");
            if (!isLive())
                m_spp = p.getInt("spp");
        }
        m_settings = s;
        if (m_provider && m_settingsSet)
            applySettings();
    }

    /// The provider's settings from the parameters and the scene; set only when they changed.
    void applySettings() {
        combined::CombinedProviderSettings s = m_settings;
        s.eta = m_eta;
        s.meshId = m_meshId;
        s.dipole.interactiveFirstFrame = isLive();  // the app: bounded frames from the first one
        if (!isLive()) {  // frames of spp-frame dipole samples up to spp (or convergence)
            s.dipole.samplesPerFrame = std::min(s.dipole.samplesPerFrame, m_spp);
            s.dipole.maxFrames = (m_spp + s.dipole.samplesPerFrame - 1) / s.dipole.samplesPerFrame;
        }
        const combined::CombinedProviderSettings& o = m_provider->settings();
        const bool changed =
            !m_settingsSet || s.splitRadius != o.splitRadius || s.mode != o.mode ||
            s.eta != o.eta || s.meshId != o.meshId || s.dipole.model != o.dipole.model ||
            s.dipole.seed != o.dipole.seed || s.dipole.lightViews != o.dipole.lightViews ||
            s.autoSkipSslpv != o.autoSkipSslpv ||
            s.dipole.samplesPerFrame != o.dipole.samplesPerFrame ||
            s.dipole.maxFrames != o.dipole.maxFrames ||
            s.sslpv.render.gridResolution != o.sslpv.render.gridResolution ||
            s.sslpv.render.solver.mode != o.sslpv.render.solver.mode ||
            s.sslpv.render.injectionResolution != o.sslpv.render.injectionResolution ||
            s.sslpv.render.solver.maxSteps != o.sslpv.render.solver.maxSteps ||
            s.sslpv.render.solver.stopEpsilon != o.sslpv.render.solver.stopEpsilon ||
            s.sslpv.render.solver.brickStopEpsilon != o.sslpv.render.solver.brickStopEpsilon ||
            s.sslpv.refineSteps != o.sslpv.refineSteps ||
            s.sslpv.render.solver.order != o.sslpv.render.solver.order ||
            s.sslpv.backend != o.sslpv.backend;
        // A new SSLPV grid drops the SSLPV part's material (SslpvProvider::setOptions): the
        // next setScene hands it the volume again.
        if (m_settingsSet && s.sslpv.render.gridResolution != o.sslpv.render.gridResolution)
            m_materialSet = false;
        if (changed)
            m_provider->setSettings(s);
        m_settingsSet = true;
    }

    combined::CombinedProviderSettings m_settings;
    std::unique_ptr<combined::CombinedSubsurfaceProvider> m_provider;
    SceneInputs m_scene;
    float m_eta = 1.3f, m_materialEta = 0.f;
    int m_meshId = 0, m_spp = 256;
    bool m_diffusionPart = false;  ///< the SSLPV part is the diffusion mode (sslpv-mode)
    bool m_meshSet = false, m_lightsSet = false, m_materialSet = false, m_settingsSet = false;
    Stats m_cpuStats;
};

}  // namespace

MethodEntry combinedMethod() {
    MethodEntry e;
    MethodInfo& i = e.info;
    i.name = "combined";
    i.title = "Combined";
    i.summary = "local dipole (r <= r_s) + SSLPV beyond (Mertens et al. 2005; Borlum et al. 2011)";
    i.docs = "docs/methods/combined.md";
    i.caps.gl = true;
    i.caps.cpu = true;
    i.caps.progressive = true;
    i.params = {
        {"split-radius", ParamType::Float, "r_s, mm (< 0: 4 SSLPV cells)", -1, 1e30, {}, "-1"},
        {"split",
         ParamType::Choice,
         "kernel: SSLPV minus its own local kernel; steps: SSLPV skips its first r_s/cell steps",
         0,
         0,
         {"kernel", "steps"},
         "kernel"},
        {"model",
         ParamType::Choice,
         "the dipole part's profile",
         0,
         0,
         {"dipole", "better-dipole"},
         "dipole"},
        {"grid", ParamType::Int, "the SSLPV part's cells per axis", 4, 256, {}, "32"},
        // As the sslpv method's: a fixed step count leaves a high-albedo medium's far light in
        // flight (the marble sphere: block rel. L1 0.197 at 32 steps, 0.094 at 400), so
        // offline the SSLPV part runs to the stop; live, a change's frame runs 32 steps and
        // idle frames carry the propagation on (refine-steps) to the per-brick stop.
        {"steps",
         ParamType::Int,
         "maximum SSLPV propagation steps; fewer once converged (see stop; live preview: steps "
         "per frame, carried on over idle frames up to refine-steps); the diffusion part: "
         "conjugate-gradient iterations, 1024 unless given",
         0,
         4096,
         {},
         "1024",
         "",
         "32"},
        {"sh", ParamType::Int, "SSLPV spherical-harmonics order", 1, 2, {}, "1"},
        {"sslpv-mode",
         ParamType::Choice,
         "the SSLPV part: diffusion (the diffusion equation on the same grid, "
         "docs/methods/sslpv.md), calibrated (propagation with the fitted per-step absorption "
         "and gain) or auto (diffusion, unless split steps or propagation gl need propagation "
         "steps: calibrated)",
         0,
         0,
         {"auto", "diffusion", "calibrated"},
         "auto"},
        {"propagation",
         ParamType::Choice,
         "GL backend: where the SSLPV part's propagation steps run (cpu: SslpvSolver; gl: "
         "compute shaders)",
         0,
         0,
         {"cpu", "gl"},
         "cpu"},
        {"seed", ParamType::Int, "the dipole part's sample sequence", 0, 1 << 30, {}, "1"},
        {"spp",
         ParamType::Int,
         "dipole samples per pixel in all",
         1,
         1 << 24,
         {},
         "256",
         "32",
         "",
         ParamScope::Offline},
        {"spp-frame", ParamType::Int, "GL: dipole samples per pixel and frame", 1, 4096, {}, "16"},
        {"light-views",
         ParamType::Bool,
         "the dipole part's light views (on counts back-lit light twice)",
         0,
         0,
         {},
         "off"},
        // Off in the live preview: deciding it scans every inside voxel after each stroke
        // (≈ 35 ms at 128³ for one material, ≈ 1.3 s when every voxel differs), more than a
        // stroke's frame budget; offline renders pay it once.
        {"auto-skip",
         ParamType::Bool,
         "leave SSLPV out when the dipole's share beyond r_s (within the object) is <= 1e-3",
         0,
         0,
         {},
         "on",
         "",
         "off"},
    };
    // After "steps": its stop rules and live refinement.
    const std::vector<ParamDescriptor> stops =
        detail::propagationStopParams("the SSLPV part: ", "");
    i.params.insert(std::find_if(i.params.begin(), i.params.end(),
                                 [](const ParamDescriptor& d) { return d.name == "steps"; }) +
                        1,
                    stops.begin(), stops.end());
    i.variants = {
        {"cpu", {}, Backend::Cpu},
        {"calibrated", ParamSet::fromAssignments({"sslpv-mode=calibrated"}), Backend::Auto}};
    for (int spp : {8, 32, 128})
        i.quality.push_back({std::to_string(spp) + " spp",
                             ParamSet::fromAssignments({"spp=" + std::to_string(spp)}),
                             Backend::Auto});
    i.evaluate = {""};
    e.create = detail::make<CombinedMethod>;
    return e;
}

}  // namespace lucent::methods
