// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief CPU version of the directional-dipole pipeline (the dirpole thesis §4): for every pixel
/// the camera sees (x_o), points are sampled in the light's view around x_o (shrunk towards the
/// inside, the dirpole thesis §4.3.1) — importance-sampled with the better dipole's exact sampler
/// (Mertens et al. 2005 §4) instead of the dirpole thesis's uniform disc — and the directional
/// dipole S_d(x_i, ω₁₂; x_o) (Frisvad et al. 2014) is accumulated over the lit points x_i; passes
/// accumulate progressively while the scene is static. The light-view G-buffer of the GPU method is
/// replaced on the CPU by one Embree ray per sample (an exact "G-buffer" at infinite resolution).
///
///     DirectionalDipoleRenderer r(scene);         // directional lights only
///     for (int i = 0; i < 8; ++i) r.addPass();     // progressive refinement
///     ImageRgb L = r.radiance();                   // W/(mm²·sr), mean of the passes so far

#include <lucent/core/Image.h>
#include <lucent/dipole/ImageSpace.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/scene/Scene.h>

#include <memory>

namespace lucent::dipole {

struct DirectionalSettings {
    int samplesPerPass = 16;     ///< disc samples per pixel and light per pass, ≥ 1
    float discQuantile = 0.99f;  ///< disc radius: this quantile of the widest channel's profile
    float shrink = 0.05f;        ///< ε_g of the dirpole thesis §4.3.1, mm
    uint32_t seed = 1;
    /// Scale S_d per channel by DirpoleEnergyTable::scale(α′) so that its normal-incidence
    /// total equals the energy target's ρ(α′, η) (docs/methods/dipole.md §1); false: the
    /// published model (total 1.34 at σa = 0, η = 1).
    bool energyNormalised = true;
    EnergyTarget energyTarget = EnergyTarget::ExactHalfSpace;  ///< when energyNormalised
};

class DirectionalDipoleRenderer {
public:
    /// Builds the camera buffers (buildSurfaceBuffers) and the ray-casting structure.
    /// @throw ValueError if the scene has no object/material, a light is not directional, or
    /// the settings are out of range (the message names the field).
    explicit DirectionalDipoleRenderer(const Scene& scene,
                                       const DirectionalSettings& settings = {});
    ~DirectionalDipoleRenderer();
    DirectionalDipoleRenderer(const DirectionalDipoleRenderer&) = delete;
    DirectionalDipoleRenderer& operator=(const DirectionalDipoleRenderer&) = delete;

    /// Accumulates one more pass (new disc samples; deterministic per pass index).
    void addPass();
    [[nodiscard]] int passes() const;
    /// Mean subsurface radiance T₂₁(ω_o) Σ_i E⊥ T₁₂(ω_i) S_d ΔA⊥ over the passes, W/(mm²·sr).
    [[nodiscard]] ImageRgb radiance() const;
    [[nodiscard]] const SurfaceBuffers& buffers() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace lucent::dipole
