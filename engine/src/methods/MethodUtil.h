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
/// when the shown mesh moves, progressive frames until the provider has converged. Subclasses
/// give the provider its settings in applySettings() (also called by setScene, for η and the
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
    /// Sets the provider's settings from the parameters, m_eta and m_meshId, only when they
    /// changed (every change restarts the accumulation); sets m_settingsSet.
    virtual void applySettings() = 0;

    std::unique_ptr<Provider> m_provider;
    const MaterialVolume* m_material = nullptr;
    bool m_settingsSet = false;
    float m_eta = 1.3f;  ///< clamped to [1, 3]
    int m_meshId = -1;
};

}  // namespace lucent::methods::detail
