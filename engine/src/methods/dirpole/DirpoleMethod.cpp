// SPDX-License-Identifier: MIT
/// @file
/// @brief `dirpole`: the directional dipole BSSRDF (Frisvad et al. 2014) through the GPU pipeline
/// of Frisvad et al. 2014 §4 (light-view and cube-face G-buffers, progressive gather;
/// dipole::DirpoleSubsurfaceProvider), or on the CPU (dipole::DirectionalDipoleRenderer:
/// directional lights only, subsurface term only). docs/methods/dipole.md.

#include <lucent/core/Error.h>
#include <lucent/dipole/DirectionalPipeline.h>
#include <lucent/dipole/DirpoleProvider.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Registry.h>

#include "../MethodUtil.h"

namespace lucent::methods {

namespace {

using detail::num;

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
        ds.energyTarget = dipole::parseEnergyTarget(params().getChoice("dirpole-energy"));
        // The CPU pipeline handles directional lights only: drop the others, loudly.
        Scene directional = detail::withLayeredMaterial(scene, params());
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
        const dipole::DirpoleStats& ds = m_provider->dirpoleStats();
        Stats s = progressStats("samples per texel and light");
        s.push_back({"texels covered", std::to_string(ds.texelsCovered)});
        s.push_back({"texels sampled", std::to_string(ds.texelsSampled)});
        s.push_back({"texels restarted", std::to_string(ds.texelsRestarted)});
        return s;
    }

private:
    void applyParams(const Params& p) override {
        if (!p.getBool("dirpole-normalise"))
            note(dipole::PUBLISHED_DIRPOLE_WARNING);
        if (backend() == Backend::Cpu)
            return;  // renderCpu reads the rest
        readSampleParams(p);
        m_normalised = p.getBool("dirpole-normalise");
        m_energyTarget = dipole::parseEnergyTarget(p.getChoice("dirpole-energy"));
        if (m_provider && m_settingsSet)
            applySettings();
    }

    void fillSettings(dipole::DirpoleSettings& ds) const override {
        ds.energyNormalised = m_normalised;
        ds.energyTarget = m_energyTarget;
        // Offline, the frame budgets are off: they bound interactive frames only, and the image
        // after N samples per texel is the same either way.
        if (!isLive())
            ds.frameSampleBudget = ds.firstFrameSampleBudget = 0;
    }

    bool m_normalised = true;
    dipole::EnergyTarget m_energyTarget = dipole::EnergyTarget::ExactHalfSpace;
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
         "S_d scaled to the normal-incidence total of dirpole-energy (docs/methods/dipole.md "
         "section 1); off: the published model",
         0,
         0,
         {},
         "on"},
        {"dirpole-energy",
         ParamType::Choice,
         "the total S_d is normalised to: exact (the half-space's transport solution, "
         "adding-doubling) or better-dipole (d'Eon 2012's closed form)",
         0,
         0,
         {"exact", "better-dipole"},
         "exact"},
    };
    for (ParamDescriptor& d : detail::layeredParams())
        i.params.push_back(std::move(d));
    // Default: the GPU pipeline, energy-normalised to the exact half-space; better: normalised
    // to the better dipole (the default before 2026-12-04); raw: the published S_d; cpu: the
    // CPU pipeline (directional lights only); surface: the surface voxel's medium instead of
    // the layered read-out.
    i.variants = {
        {"raw", ParamSet::fromAssignments({"dirpole-normalise=off"}), Backend::Auto},
        {"better", ParamSet::fromAssignments({"dirpole-energy=better-dipole"}), Backend::Auto},
        {"cpu", {}, Backend::Cpu},
        {"surface", ParamSet::fromAssignments({"layered=off"}), Backend::Auto}};
    for (int spp : {8, 32, 128})
        i.quality.push_back({std::to_string(spp) + " spp",
                             ParamSet::fromAssignments({"spp=" + std::to_string(spp)}),
                             Backend::Auto});
    i.evaluate = {""};
    e.create = detail::make<DirpoleMethod>;
    return e;
}

}  // namespace lucent::methods
