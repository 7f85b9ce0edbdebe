// SPDX-License-Identifier: MIT
/// @file
/// @brief `dirpole`: the directional dipole BSSRDF (Frisvad et al. 2014) through the GPU pipeline
/// of Frisvad et al. 2014 §4 (light-view and cube-face G-buffers, progressive gather;
/// dipole::DirpoleSubsurfaceProvider), or on the CPU (dipole::DirectionalDipoleRenderer:
/// directional lights only, subsurface term only). docs/methods/dipole.md.

#include <lucent/core/Error.h>
#include <lucent/dipole/DirectionalPipeline.h>
#include <lucent/dipole/DirpoleProvider.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Registry.h>

#include "../MethodUtil.h"

#include <algorithm>

namespace lucent::methods {

namespace {

using detail::num;

/// The published model is not energy-conserving (docs/methods/dipole.md §1 and §4): every use
/// of it says so.
constexpr const char* EXPERIMENTAL_WARNING =
    "warning: the published Frisvad et al. 2014 directional dipole overestimates total "
    "reflectance (1.34 at sigma_a = 0) and is +48..131% against the reference path tracer "
    "(docs/methods/dipole.md, sections 1 and 4)";

class DirpoleMethod final
    : public detail::ImageSpaceDipoleMethod<dipole::DirpoleSubsurfaceProvider> {
public:
    using ImageSpaceDipoleMethod::ImageSpaceDipoleMethod;

    ImageRgb renderCpu(const Scene& scene, const CpuRequest& request) override {
        if (!request.subsurfaceOnly)
            note("dirpole on the CPU draws the subsurface term only (no surface reflection)");
        const int spp = params().getInt("spp");
        LUCENT_CHECK(spp <= 65536, "dirpole: spp: ", spp, " is outside [1, 65536] on the CPU");
        dipole::DirectionalSettings ds;
        ds.samplesPerPass = spp;
        ds.seed = uint32_t(params().getInt("seed"));
        ds.energyNormalised = params().getBool("dirpole-normalise");
        // The CPU pipeline handles directional lights only: drop the others, loudly.
        Scene directional = scene;
        directional.lights.clear();
        for (const Light& l : scene.lights) {
            if (l.type == Light::Type::Directional)
                directional.lights.push_back(l);
            else
                note("dirpole ignores a non-directional light (type " +
                     std::to_string(int(l.type)) + ")");
        }
        LUCENT_CHECK(!directional.lights.empty(), "dirpole: the scene has no directional light");
        dipole::DirectionalDipoleRenderer renderer(directional, ds);
        renderer.addPass();
        m_cpuStats = {{"passes", std::to_string(renderer.passes())},
                      {"disc samples per pixel and light", std::to_string(spp)}};
        return renderer.radiance();
    }

    [[nodiscard]] Stats stats() const override {
        if (backend() == Backend::Cpu)
            return m_cpuStats;
        if (!m_provider)
            return {};
        const dipole::ProviderStats& st = m_provider->stats();
        const dipole::DirpoleStats& ds = m_provider->dirpoleStats();
        return {{"frames", std::to_string(st.frames)},
                {"samples per frame", std::to_string(m_provider->settings().samplesPerFrame)},
                {"samples per texel and light", std::to_string(st.samplesPerPixel)},
                {"last change", num(st.lastChange, "%.2e")},
                {"converged", st.converged ? "yes" : "no"},
                {"last upload bricks", std::to_string(st.lastUploadBricks)},
                {"texels covered", std::to_string(ds.texelsCovered)},
                {"texels sampled", std::to_string(ds.texelsSampled)},
                {"texels restarted", std::to_string(ds.texelsRestarted)}};
    }

private:
    void applyParams(const Params& p) override {
        if (!p.getBool("dirpole-normalise"))
            note(EXPERIMENTAL_WARNING);
        if (backend() == Backend::Cpu)
            return;  // renderCpu reads the rest
        m_sppFrame = p.getInt("spp-frame");
        m_seed = uint32_t(p.getInt("seed"));
        m_normalised = p.getBool("dirpole-normalise");
        if (!isLive())
            m_spp = p.getInt("spp");
        if (m_provider && m_settingsSet)
            applySettings();
    }

    /// The provider's settings; set only when they changed (a change restarts the gather).
    void applySettings() override {
        dipole::DirpoleSettings ds = m_provider->settings();
        ds.eta = m_eta;
        ds.samplesPerFrame = m_sppFrame;
        if (!isLive()) {
            // Offline: whole frames of spp-frame samples up to spp (the frame budgets bound
            // interactive frames only; the image after N samples per texel is the same
            // either way).
            ds.samplesPerFrame = std::min(m_sppFrame, m_spp);
            ds.maxFrames = (m_spp + ds.samplesPerFrame - 1) / ds.samplesPerFrame;
            ds.frameSampleBudget = ds.firstFrameSampleBudget = 0;
        }
        ds.seed = m_seed;
        ds.energyNormalised = m_normalised;
        ds.meshId = m_meshId;
        const dipole::DirpoleSettings& old = m_provider->settings();
        const bool changed =
            !m_settingsSet || ds.eta != old.eta || ds.samplesPerFrame != old.samplesPerFrame ||
            ds.maxFrames != old.maxFrames || ds.seed != old.seed ||
            ds.energyNormalised != old.energyNormalised || ds.meshId != old.meshId ||
            ds.frameSampleBudget != old.frameSampleBudget ||
            ds.firstFrameSampleBudget != old.firstFrameSampleBudget;
        if (changed)
            m_provider->setSettings(ds);
        m_settingsSet = true;
    }

    int m_spp = 256, m_sppFrame = 16;
    uint32_t m_seed = 1;
    bool m_normalised = true;
    Stats m_cpuStats;
};

}  // namespace

MethodEntry dirpoleMethod() {
    MethodEntry e;
    MethodInfo& i = e.info;
    i.name = "dirpole";
    i.title = "Directional dipole";
    i.summary = "directional dipole (Frisvad et al. 2014), GPU pipeline of its section 4";
    i.docs = "docs/methods/dipole.md";
    i.caps.gl = true;
    i.caps.cpu = true;
    i.caps.progressive = true;
    i.caps.cpuLights = lightBit(Light::Type::Directional);
    i.params = {
        {"spp",
         ParamType::Int,
         "disc samples per cube texel and light in all (GL; CPU: per pixel and light)",
         1,
         1 << 24,
         {},
         "256",
         "32",
         "",
         ParamScope::Offline},
        {"spp-frame",
         ParamType::Int,
         "GL: disc samples per cube texel, light and frame",
         1,
         4096,
         {},
         "16"},
        {"seed", ParamType::Int, "sample sequence", 0, 1 << 30, {}, "1"},
        {"dirpole-normalise",
         ParamType::Bool,
         "S_d scaled to the better dipole's normal-incidence total (docs/methods/dipole.md "
         "section 1); off: the published model",
         0,
         0,
         {},
         "on"},
    };
    // Default: the GPU pipeline, energy-normalised; raw: the published S_d; cpu: the CPU
    // pipeline (directional lights only).
    i.variants = {{"raw", ParamSet::fromAssignments({"dirpole-normalise=off"}), Backend::Auto},
                  {"cpu", {}, Backend::Cpu}};
    for (int spp : {8, 32, 128})
        i.quality.push_back({std::to_string(spp) + " spp",
                             ParamSet::fromAssignments({"spp=" + std::to_string(spp)}),
                             Backend::Auto});
    i.evaluate = {""};
    e.create = detail::make<DirpoleMethod>;
    return e;
}

}  // namespace lucent::methods
