// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The GPU directional-dipole pipeline of the dirpole thesis §4 (Frisvad et al. 2014 BSSRDF)
/// as a gpu::SubsurfaceProvider: live, progressive subsurface radiance for gpu::SceneRenderer.
///
/// Passes (context current; docs/methods/dipole.md, "GPU directional-dipole pipeline"):
///  1. light-view G-buffer per light (after a reset only; the dirpole thesis §4.1 step 1): world
///  positions
///     and normals of the object seen from the light (directional: orthographic over the
///     object's bounding sphere; point/spot: perspective from the light);
///  2. cube-face G-buffers (after a reset only; §4.1 step 2): the object rasterised by six
///     orthographic cameras around its bounding-box centre (positions, normals, depth);
///  3. gather (every frame until converged; §4.1 step 2): per cube-face fragment x_o, new disc
///     samples around x_o in each light's view add Σ E⊥ T₁₂(ω_i) S_d(x_i, ω₁₂; x_o) ΔA⊥ to a
///     running sum (x_i, n_i from the light G-buffer texel hit by the sample); after a restart a
///     prepare pass first restarts the texels whose material changed, and the gather runs over
///     a list of the texels to sample (dirpole_prepare.comp, dirpole_compact.comp);
///  4. combination (every frame; §4.1 step 3): each camera pixel averages the faces that see
///     it (depth test) and multiplies by T₂₁(ω_o) into the renderer's subsurface texture.
/// The three artefact fixes of §4.3 (G-buffer shrink ε_g, cube-map intrusion ε_c, world-space
/// shadow bias ε_b) are switchable in DirpoleSettings.
///
/// The cube faces are view-independent (only T₂₁ depends on the eye, §4.1): moving the camera
/// keeps the accumulation; lights, settings or mesh uploads restart it.
///
/// Interactive painting (docs/methods/dipole.md §7, "Latency"): what a reset re-renders depends
/// on what changed. The light and cube-face G-buffers depend on the lights, the rasterised
/// meshes and the map sizes only, so a material change (setMaterial, uploadBricks,
/// syncMaterial, reset) keeps them. A face texel's running sum depends on the material only
/// through σt, σs′ at x_o (the gather reads x_o's material), so every frame first compares each
/// texel's material with the one its sum was computed for and restarts only the texels whose
/// material changed (a paint stroke restarts the texels under the stroke; the rest keep their
/// converged sums). Samples are counted per texel (the sample sequence is indexed by the
/// texel's own count), so the image after N samples per texel does not depend on how the N
/// samples were spread over frames; a frame adds at most `samplesPerFrame` per texel and at
/// most a budget of texel-samples in total (a small one on the first frame after a restart).
///
/// Usage (the same pattern as dipole::DipoleSubsurfaceProvider):
/// @code
///   dipole::DirpoleSubsurfaceProvider dp;
///   dp.create();                                   // compiles the programs (context current)
///   int id = renderer.addMesh(mesh, surface);
///   dipole::DirpoleSettings s;  s.eta = eta;  s.meshId = id;
///   dp.setSettings(s);
///   dp.setMaterial(&volume);                       // non-owning; full upload at the next frame
///   renderer.setSubsurfaceProvider(&dp);
///   // each frame: dp.syncMaterial(volume) after painting (uploads only the dirty bricks)
///   renderer.render();  if (!dp.stats().converged) scheduleNextFrame();
///   renderer.setSubsurfaceProvider(nullptr);  dp.destroy();
/// @endcode
/// Units: mm, mm⁻¹, irradiance W/mm², intensity W/sr, radiance W/(mm²·sr).

#include <lucent/dipole/DipoleProvider.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/gpu/GpuTimer.h>
#include <lucent/gpu/SceneRenderer.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace lucent {
class MaterialVolume;
}

namespace lucent::dipole {

/// Settings of the directional-dipole provider. Changing any of them restarts the accumulation.
struct DirpoleSettings {
    float eta = 1.3f;          ///< relative index of the object, [1, 3]
    int samplesPerFrame = 16;  ///< disc samples per cube-face texel, light and frame, [1, 4096]
    int maxFrames = 64;        ///< accumulation stops after this many frames, [1, 1e6]
    /// Stop when max_texels |C̄_N − C̄_{N−1}| < this × max_texels C̄_N (per channel), [0, 1).
    float convergenceThreshold = 1e-3f;
    int lightMapSize = 512;  ///< light-view G-buffer texels per side, [16, 4096]
    int cubeMapSize = 256;   ///< texels per side of each of the six cube faces, [16, 4096]
    /// Seed 001 §4.3.1: x′_o = x_o − ε_g (n_o − ω_l(ω_l·n_o)) before the light G-buffer lookup.
    bool gbufferShrink = true;
    float shrink = 0.05f;  ///< ε_g, mm, [0, 1e3] (the CPU pipeline's DirectionalSettings::shrink)
    /// Seed 001 §4.3.2: the cube faces are looked up at x′_o = x_o − ε_c n_o.
    bool cubemapIntrusion = true;
    float intrusion = 0.05f;  ///< ε_c, mm, [0, 1e3]
    /// Seed 001 §4.3.3: a face sees x_o iff its depth, in world units along the face axis, is
    /// at most the stored depth + ε_b (without the fix: + 1e-4 × the face's depth range).
    bool shadowBias = true;
    float bias = 0.3f;  ///< ε_b, mm, [0, 1e3]; about 2 cube texels of a 20 mm object
    /// Slope-scaled addition to ε_b (an extension of §4.3.3, on with shadowBias): + slopeBias ×
    /// face texel × tan θ, θ ≤ 84° the angle between n_o and the face axis (faces seeing x_o at
    /// more than 84° never count), [0, 64].
    float slopeBias = 1.f;
    /// Scale S_d per channel by DirpoleEnergyTable::scale(α′) (normal-incidence total = the
    /// energy target's ρ(α′, η), docs/methods/dipole.md §1), as DirectionalSettings; false: the
    /// published model.
    bool energyNormalised = true;
    EnergyTarget energyTarget = EnergyTarget::ExactHalfSpace;  ///< when energyNormalised
    uint32_t seed = 1;  ///< sample sequence (per texel Cranley–Patterson offsets)
    /// Most texel-samples a frame adds (Σ over the texels it samples of k × lights), ≥ 0;
    /// 0 = unlimited. The frame's k = clamp(budget / (texels × lights), 1, samplesPerFrame).
    /// Bounds a frame's gather cost (llvmpipe, 2 loaded cores: ≈ 0.2–0.4 µs per texel-sample,
    /// 2^18 ≈ 50–100 ms; docs/methods/dipole.md §7); the image after N samples per texel is
    /// the same for any budget, so changing it restarts nothing.
    int frameSampleBudget = 1 << 18;
    /// The budget of the first frame after any restart (material, lights, settings), ≥ 0, 0 =
    /// unlimited: a small first frame keeps stroke → frame latency low; later frames use
    /// frameSampleBudget. Changing it restarts nothing.
    int firstFrameSampleBudget = 1 << 16;
    /// SceneRenderer mesh id (addMesh's return) holding the material: only it is rasterised into
    /// the light and cube G-buffers and only its pixels get the term. −1: every mesh.
    int meshId = -1;

    bool operator==(const DirpoleSettings&) const = default;
};

/// What the directional-dipole provider did (beyond ProviderStats), for tests and timings.
struct DirpoleStats {
    int geometryRenders = 0;   ///< light-view + cube-face G-buffer renders so far
    int texelsCovered = 0;     ///< covered cube-face texels (as of the last prepare pass)
    int texelsRestarted = 0;   ///< texels the last frame restarted (material changed), or 0
    int texelsSampled = 0;     ///< texels the last frame added samples to (its work list)
    int samplesThisFrame = 0;  ///< k of the last frame (per texel and light)
    int minSamples = 0;        ///< fewest samples of any covered texel after the last frame
    int maxSamples = 0;        ///< most samples of any covered texel after the last frame
};

/// gpu::SubsurfaceProvider running the dirpole thesis §4 on the GPU, progressively. Create/destroy
/// explicitly with a current GL 4.5 context (the renderer's).
class DirpoleSubsurfaceProvider final : public MaterialSubsurfaceProvider {
public:
    DirpoleSubsurfaceProvider();
    ~DirpoleSubsurfaceProvider() override;
    DirpoleSubsurfaceProvider(const DirpoleSubsurfaceProvider&) = delete;
    DirpoleSubsurfaceProvider& operator=(const DirpoleSubsurfaceProvider&) = delete;

    /// @throw ValueError naming the field (η ∉ [1,3], counts or sizes out of range, negative or
    /// non-finite ε).
    void setSettings(const DirpoleSettings& settings);
    [[nodiscard]] const DirpoleSettings& settings() const;

    // create, destroy, setMaterial, uploadBricks, syncMaterial, reset and stats():
    // MaterialSubsurfaceProvider.
    // stats(): frames (since the last restart), samplesPerPixel (the fewest samples per cube
    // texel and light of any covered texel), lastChange, converged, resets, lastUploadBricks,
    // fullUploads as for the image-space dipole. setSettings (with a change), setMaterial,
    // uploadBricks and reset() clear `converged` at once, so a caller that renders while
    // !converged picks the change up. A material change restarts only the texels whose
    // material changed (see the file comment): `resets` counts it, `frames` restarts at 0.

    /// Counters of the passes (geometry renders, restarted and sampled texels).
    [[nodiscard]] const DirpoleStats& dirpoleStats() const;
    /// GPU and CPU time of the passes ("geometry": light-view and cube-face G-buffers,
    /// "prepare": per-texel material check, "compact": the gather's work list, "gather",
    /// "combine") in the most recent frame whose timer queries are available (context current:
    /// may wait for the last frame's). On llvmpipe the CPU time of a compute pass includes its
    /// execution (dispatches run synchronously); rasterisation runs at the next flush.
    [[nodiscard]] std::vector<gpu::PassTiming> passTimes() const;

    /// GL names of the intermediate textures (valid after a frame; tests and debugging).
    struct DebugTextures {
        unsigned lightPosition = 0;  ///< RGBA32F 2-D array, one layer per light: xyz mm, a cover
        unsigned lightNormal = 0;    ///< RGBA32F 2-D array: outward unit normal
        unsigned facePosition = 0;   ///< RGBA32F 2-D array, 6 layers (+x −x +y −y +z −z)
        unsigned faceNormal = 0;     ///< RGBA32F 2-D array, 6 layers
        unsigned faceDepth = 0;      ///< DEPTH_COMPONENT32F 2-D array, 6 layers
        /// RGBA32F 2-D array, 6 layers: rgb Σ over the texel's samples of the one-sample
        /// estimate of C (W/mm²/sr), a = the texel's sample count N (mean = rgb / a)
        unsigned accumulation = 0;
    };
    [[nodiscard]] DebugTextures debugTextures() const;

    /// gpu::SubsurfaceProvider: one progressive step (see the file comment).
    void renderSubsurface(const gpu::GBufferView& gbuffer, unsigned targetTexture) override;

private:
    void restart() override;
    /// Compiles dirpole_gbuffer.{vert,frag}, dirpole_prepare.comp, dirpole_compact.comp (two
    /// variants), dirpole_gather.comp and dirpole_combine.comp.
    void createGl(const gpu::ShaderLibrary& library) override;
    void destroyGl() override;
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace lucent::dipole
