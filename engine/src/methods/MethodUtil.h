// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Small helpers the method folders share (private to the methods module).

#include <lucent/core/Error.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Method.h>

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
    }

    void setScene(const SceneInputs& scene) override {
        LUCENT_CHECK(scene.material, info().name, ": the object needs a material volume");
        LUCENT_CHECK(m_provider, info().name, ": setScene before createGl");
        m_eta = std::clamp(scene.eta, 1.f, 3.f);
        m_meshId = scene.meshId;
        applySettings();
        if (scene.material != m_material) {
            m_provider->setMaterial(scene.material);  // full upload at the next frame
            m_material = scene.material;
        }
    }
    void materialChanged(const std::vector<int>& dirtyBricks) override {
        if (m_provider && m_material && !dirtyBricks.empty())
            m_provider->uploadBricks(dirtyBricks);
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

    /// Reads the parameters both pipelines share: spp-frame, seed and (offline) spp.
    void readSampleParams(const Params& p) {
        m_sppFrame = p.getInt("spp-frame");
        m_seed = uint32_t(p.getInt("seed"));
        if (!isLive())
            m_spp = p.getInt("spp");
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
    bool m_settingsSet = false;
    float m_eta = 1.3f;  ///< clamped to [1, 3]
    int m_meshId = -1;
    int m_spp = 256, m_sppFrame = 16;
    uint32_t m_seed = 1;
};

}  // namespace lucent::methods::detail
