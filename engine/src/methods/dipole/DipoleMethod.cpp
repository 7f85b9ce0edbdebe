// SPDX-License-Identifier: MIT
/// @file
/// @brief `dipole` and `better-dipole`: the image-space dipole integration (Mertens et al. 2005)
/// of the classical dipole (Jensen et al. 2001) or the better dipole (d'Eon 2012);
/// docs/methods/dipole.md. GL: dipole::DipoleSubsurfaceProvider, progressive (frames of
/// `spp-frame` samples until `spp` or convergence). CPU: the image-space gather
/// (dipole::renderImageSpaceDipole), subsurface term only.

#include <lucent/core/Error.h>
#include <lucent/dipole/DipoleProvider.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Registry.h>

#include "../MethodUtil.h"

namespace lucent::methods {

namespace {

using detail::num;

class DipoleMethod final : public detail::ImageSpaceDipoleMethod<dipole::DipoleSubsurfaceProvider> {
public:
    DipoleMethod(const MethodInfo& info, const MethodContext& context, dipole::Model model)
        : ImageSpaceDipoleMethod(info, context), m_model(model) {}

    ImageRgb renderCpu(const Scene& scene, const CpuRequest& request) override {
        if (!request.subsurfaceOnly)
            note(info().name +
                 " on the CPU draws the subsurface term only (no surface reflection)");
        const int spp = params().getInt("spp");
        LUCENT_CHECK(spp <= 65536, info().name, ": spp: ", spp,
                     " is outside [1, 65536] on the CPU");
        dipole::GatherSettings gs;
        gs.model = m_model;
        gs.uniformSamples = spp / 4;
        gs.importanceSamples = spp - gs.uniformSamples;
        gs.seed = uint32_t(params().getInt("seed"));
        gs.maxRadius = params().getFloat("max-radius");
        dipole::LightViewSettings lv;
        lv.enabled = params().getBool("light-views");
        lv.resolution = params().getInt("light-view-res");
        std::vector<dipole::LightViewReport> reports;
        const dipole::GatherResult g = dipole::renderImageSpaceDipole(
            detail::withLayeredMaterial(scene, params()), gs, lv, &reports);
        const dipole::GatherStats& st = g.stats;
        m_cpuStats = {
            {"pixels", std::to_string(st.pixels)},
            {"eps", num(st.epsilon, "%.3g")},
            {"disc quantile", num(1.0 - st.epsilon)},
            {"disc radius mm", num(st.minRadius, "%.3g") + ".." + num(st.maxRadius, "%.3g")},
            {"light views gathered", std::to_string(st.lightViews)}};
        for (const dipole::LightViewReport& r : reports)
            m_cpuStats.push_back(
                {"light " + std::to_string(r.light) + " view",
                 std::string(r.used ? "gathered" : (r.built ? "skipped" : "not built")) +
                     " (back-lit flux fraction " + num(r.backlitFraction, "%.3g") + ")" +
                     (r.note.empty() ? "" : ": " + r.note)});
        return g.radiance;
    }

    [[nodiscard]] Stats stats() const override {
        if (backend() == Backend::Cpu)
            return m_cpuStats;
        if (!m_provider)
            return {};
        const dipole::ProviderStats& st = m_provider->stats();
        Stats s = progressStats("spp");
        s.push_back({"eps", num(st.epsilon, "%.3g")});
        s.push_back(
            {"disc radius mm", num(st.minRadius, "%.3g") + ".." + num(st.maxRadius, "%.3g")});
        s.push_back({"light views", std::to_string(st.lightViewsGathered) + " of " +
                                        std::to_string(st.lightViewsRendered) + " gathered"});
        for (size_t l = 0; l < st.backlitFractions.size(); ++l) {
            const float f = st.backlitFractions[l];
            s.push_back({"light " + std::to_string(l) + " view",
                         std::string(f < 0.f ? "not rendered"
                                     : f > m_provider->settings().lightViewThreshold ? "gathered"
                                                                                     : "skipped") +
                             " (back-lit flux fraction " + num(f, "%.3g") + ")"});
        }
        // GPU time of the last frame's passes (GL timer queries; 0: the pass did not run).
        s.push_back({"irradiance pass ms", num(st.passMs.irradiance, "%.2f")});
        s.push_back({"light views pass ms", num(st.passMs.lightViews, "%.2f")});
        s.push_back({"back-lit fractions pass ms", num(st.passMs.fractions, "%.2f")});
        s.push_back({"gather pass ms", num(st.passMs.gather, "%.2f")});
        s.push_back({"material update pass ms", num(st.passMs.materialUpdate, "%.2f")});
        s.push_back({"pixels restarted by the last stroke", std::to_string(st.pixelsRestarted)});
        s.push_back({"pixels looked up by the last stroke", std::to_string(st.pixelsLookedUp)});
        return s;
    }

private:
    void applyParams(const Params& p) override {
        if (backend() == Backend::Cpu)
            return;  // renderCpu reads its parameters
        readSampleParams(p);
        m_maxRadius = p.getFloat("max-radius");
        m_lightViews = p.getBool("light-views");
        m_lightViewRes = p.getInt("light-view-res");
        if (m_provider && m_settingsSet)
            applySettings();
    }

    void fillSettings(dipole::ProviderSettings& ps) const override {
        ps.model = m_model;
        ps.maxRadius = m_maxRadius;
        ps.lightViews = m_lightViews;
        ps.lightViewResolution = m_lightViewRes;
        ps.interactiveFirstFrame = isLive();  // the app: bounded frames from the first one
    }

    dipole::Model m_model;
    int m_lightViewRes = 512;
    float m_maxRadius = 0.f;
    bool m_lightViews = true;
    Stats m_cpuStats;
};

/// The parameters both dipoles share.
std::vector<ParamDescriptor> dipoleParams() {
    return {
        {"spp",
         ParamType::Int,
         "samples per pixel in all (GL: frames of spp-frame up to this or convergence)",
         1,
         1 << 24,
         {},
         "256",
         "32",
         "",
         ParamScope::Offline},
        {"spp-frame", ParamType::Int, "GL: samples per pixel and frame", 1, 4096, {}, "16"},
        {"seed", ParamType::Int, "sample sequence", 0, 1 << 30, {}, "1"},
        {"light-views",
         ParamType::Bool,
         "gather light-view irradiance images too (back-lit thin parts; docs/methods/dipole.md "
         "section 3d)",
         0,
         0,
         {},
         "on"},
        {"light-view-res", ParamType::Int, "texels per side of a light view", 16, 4096, {}, "512"},
        {"max-radius",
         ParamType::Float,
         "mm; > 0: only r <= this is gathered (0: unlimited)",
         0,
         1e6,
         {},
         "0"},
    };
}

MethodEntry dipoleEntry(dipole::Model model) {
    MethodEntry e;
    MethodInfo& i = e.info;
    const bool better = model == dipole::Model::BetterDipole;
    i.name = better ? "better-dipole" : "dipole";
    i.title = better ? "Better dipole" : "Dipole";
    i.summary = better ? "image-space better dipole (d'Eon 2012; Mertens et al. 2005)"
                       : "image-space dipole (Jensen et al. 2001; Mertens et al. 2005)";
    i.docs = "docs/methods/dipole.md";
    i.caps.gl = true;
    i.caps.cpu = true;
    i.caps.progressive = true;
    i.params = dipoleParams();
    for (ParamDescriptor& d : detail::layeredParams())
        i.params.push_back(std::move(d));
    // surface: the surface voxel's medium instead of the layered read-out (the papers' model).
    i.variants = {{"cpu", {}, Backend::Cpu},
                  {"gl", {}, Backend::Gl},
                  {"surface", ParamSet::fromAssignments({"layered=off"}), Backend::Auto}};
    for (int spp : {8, 32, 128})
        i.quality.push_back({std::to_string(spp) + " spp",
                             ParamSet::fromAssignments({"spp=" + std::to_string(spp)}),
                             Backend::Auto});
    i.evaluate = {""};
    e.create = [model](const MethodInfo& info, const MethodContext& context) {
        return std::unique_ptr<Method>(new DipoleMethod(info, context, model));
    };
    return e;
}

}  // namespace

MethodEntry dipoleMethod() {
    return dipoleEntry(dipole::Model::Dipole);
}

MethodEntry betterDipoleMethod() {
    return dipoleEntry(dipole::Model::BetterDipole);
}

}  // namespace lucent::methods
