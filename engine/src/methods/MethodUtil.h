// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Small helpers the method folders share (private to the methods module).

#include <lucent/core/Error.h>
#include <lucent/dipole/LayeredMaterial.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Method.h>
#include <lucent/scene/Scene.h>

#include <algorithm>

#include <cstdio>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace lucent::methods::detail {

/// printf-style formatting of one number for Stats values and log lines.
inline std::string num(double v, const char* format = "%.4g") {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

/// Whether two light lists are equal field by field (a change re-injects / restarts).
inline bool sameLights(const std::vector<Light>& a, const std::vector<Light>& b) {
    if (a.size() != b.size())
        return false;
    for (size_t i = 0; i < a.size(); ++i) {
        const Light& x = a[i];
        const Light& y = b[i];
        if (x.type != y.type || x.position != y.position || x.direction != y.direction ||
            x.intensity != y.intensity || x.spotOuterDeg != y.spotOuterDeg ||
            x.spotInnerDeg != y.spotInnerDeg || x.radius != y.radius)
            return false;
    }
    return true;
}

/// The parameters of the methods that read a half-space medium under each surface point (the
/// dipoles, the directional dipole).
inline std::vector<ParamDescriptor> layeredParams() {
    return {{"layered",
             ParamType::Bool,
             "read the material under each surface point as the homogeneous half-space that "
             "returns as much light (docs/methods/dipole.md, \"Layered material\"); off: the "
             "surface voxel's medium, as the papers",
             0,
             0,
             {},
             "on"},
            // Live: 8 voxels keep a stroke's update of a 128³ volume near 11 ms
            // (docs/benchmarks.md, "Layered read-out").
            {"layered-depth",
             ParamType::Int,
             "voxels: how deep under the surface the layered read-out looks (below that the "
             "medium is taken to continue)",
             1,
             256,
             {},
             "16",
             "",
             "8"}};
}

/// The layered read-out's settings from the parameters.
inline dipole::LayeredReadoutSettings layeredSettings(const Params& p) {
    dipole::LayeredReadoutSettings s;
    s.maxDepthVoxels = p.getInt("layered-depth");
    return s;
}

/// `scene` with object 0's material as the half-space methods read it when the parameter
/// `layered` is on (dipole::layeredEquivalent, a copy); the scene itself otherwise.
inline Scene withLayeredMaterial(const Scene& scene, const Params& p) {
    if (!p.getBool("layered") || scene.objects.empty() || !scene.objects.front().material)
        return scene;
    Scene out = scene;
    out.objects.front().material = std::make_shared<MaterialVolume>(
        dipole::layeredEquivalent(*scene.objects.front().material,
                                  std::clamp(double(scene.eta), 1.0, 3.0), layeredSettings(p)));
    return out;
}

/// A registry factory for method class M (constructed from the info and the context).
template <class M>
std::unique_ptr<Method> make(const MethodInfo& info, const MethodContext& context) {
    return std::make_unique<M>(info, context);
}

/// The GL lifecycle the image-space dipole passes share (dipole::DipoleSubsurfaceProvider and
/// dipole::DirpoleSubsurfaceProvider): the provider made by createGl, the material volume bound
/// once (a full upload at the next frame) and then updated brick by brick, the gather restarted
/// when the shown mesh moves, progressive frames until the provider has converged; the sample
/// schedule (spp-frame, seed, offline spp) and the "set only when changed" rule. Subclasses add
/// their own settings in fillSettings() (applied by applyParams and by setScene, for η and the
/// mesh id).
template <class Provider>
class ImageSpaceDipoleMethod : public Method {
public:
    using Method::Method;

    void createGl(const gpu::ShaderLibrary& library) override {
        m_provider = std::make_unique<Provider>();
        m_provider->create(library);
        m_material = nullptr;
        m_settingsSet = false;
    }
    void destroyGl() override {
        if (m_provider)
            m_provider->destroy();
        m_provider.reset();
        m_material = nullptr;
        m_seen = dipole::LayeredReadout();  // a volume's worth of memory; rebuilt by setScene
    }

    void setScene(const SceneInputs& scene) override {
        LUCENT_CHECK(scene.material, info().name, ": the object needs a material volume");
        LUCENT_CHECK(m_provider, info().name, ": setScene before createGl");
        m_eta = std::clamp(scene.eta, 1.f, 3.f);
        m_meshId = scene.meshId;
        applySettings();
        const bool etaChanged = m_layered && m_seenEta != m_eta;
        if (scene.material != m_material || etaChanged) {
            m_material = scene.material;
            bindMaterial();  // full upload at the next frame
        }
    }
    void materialChanged(const std::vector<int>& dirtyBricks) override {
        if (!m_provider || !m_material || dirtyBricks.empty())
            return;
        if (!m_layered)
            return m_provider->uploadBricks(dirtyBricks);
        // The read-out of the columns through the painted bricks changed with them.
        m_provider->uploadBricks(m_seen.update(*m_material, dirtyBricks));
    }
    void geometryChanged() override {
        if (m_provider)
            m_provider->reset();
    }

    gpu::SubsurfaceProvider* subsurfacePass() override { return m_provider.get(); }
    [[nodiscard]] bool converged() const override {
        return !m_provider || m_provider->stats().converged;
    }

protected:
    using Settings = std::decay_t<decltype(std::declval<const Provider&>().settings())>;

    /// The provider's settings from the parameters, m_eta and m_meshId: fill `s` (a copy of the
    /// provider's) with what the method owns; applySettings() sets it when it changed.
    virtual void fillSettings(Settings& s) const = 0;

    /// Reads the parameters both pipelines share: spp-frame, seed, (offline) spp and layered.
    void readSampleParams(const Params& p) {
        m_sppFrame = p.getInt("spp-frame");
        m_seed = uint32_t(p.getInt("seed"));
        if (!isLive())
            m_spp = p.getInt("spp");
        const bool layered = p.getBool("layered");
        const int depth = p.getInt("layered-depth");
        if (layered != m_layered || depth != m_layeredSettings.maxDepthVoxels) {
            m_layered = layered;
            m_layeredSettings = layeredSettings(p);
            if (m_provider && m_material)
                bindMaterial();
        }
    }

    /// Gives the provider the material it reads: the volume itself, or its layered read-out
    /// (rebuilt: a new volume, η or setting).
    void bindMaterial() {
        m_provider->setMaterial(nullptr);  // the next attach uploads everything
        if (m_layered) {
            m_seen = dipole::LayeredReadout(*m_material, double(m_eta), m_layeredSettings);
            m_seenEta = m_eta;
            m_provider->setMaterial(&m_seen.volume());
        } else {
            m_seen = dipole::LayeredReadout();
            m_provider->setMaterial(m_material);
        }
    }

    /// Sets the provider's settings (fillSettings on the shared sample schedule), only when they
    /// changed: every change restarts the accumulation.
    void applySettings() {
        Settings s = m_provider->settings();
        s.eta = m_eta;
        s.meshId = m_meshId;
        s.seed = m_seed;
        s.samplesPerFrame = m_sppFrame;
        if (!isLive()) {  // offline: whole frames of spp-frame samples up to spp (or convergence)
            s.samplesPerFrame = std::min(m_sppFrame, m_spp);
            s.maxFrames = (m_spp + s.samplesPerFrame - 1) / s.samplesPerFrame;
        }
        fillSettings(s);
        if (!m_settingsSet || !(s == m_provider->settings()))
            m_provider->setSettings(s);
        m_settingsSet = true;
    }

    /// The progress lines both pipelines report; `samplesLabel` names what a sample counts.
    [[nodiscard]] Stats progressStats(const std::string& samplesLabel) const {
        const auto& st = m_provider->stats();
        return {{"frames", std::to_string(st.frames)},
                {"samples per frame", std::to_string(m_provider->settings().samplesPerFrame)},
                {samplesLabel, std::to_string(st.samplesPerPixel)},
                {"last change", num(st.lastChange, "%.2e")},
                {"converged", st.converged ? "yes" : "no"},
                {"last upload bricks", std::to_string(st.lastUploadBricks)}};
    }

    std::unique_ptr<Provider> m_provider;
    const MaterialVolume* m_material = nullptr;
    bool m_layered = true;
    dipole::LayeredReadoutSettings m_layeredSettings;
    dipole::LayeredReadout m_seen;  ///< the layered read-out of *m_material the provider reads
    float m_seenEta = 0.f;
    bool m_settingsSet = false;
    float m_eta = 1.3f;  ///< clamped to [1, 3]
    int m_meshId = -1;
    int m_spp = 256, m_sppFrame = 16;
    uint32_t m_seed = 1;
};

}  // namespace lucent::methods::detail
