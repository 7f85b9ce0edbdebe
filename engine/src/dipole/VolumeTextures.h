// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Internal to the dipole module: what DipoleSubsurfaceProvider and
/// DirpoleSubsurfaceProvider share — the painted material as two RGBA32F 3-D textures uploaded
/// brick by brick (σt rgb + inside flag in a; σs′ rgb), with the attach/upload/sync rules of
/// their public setMaterial/uploadBricks/syncMaterial, and the progressive-accumulation
/// bookkeeping of ProviderStats (restart, per-frame convergence from the two statistics words).
///
///     VolumeTextures vt("DipoleSubsurfaceProvider");
///     if (vt.attach(&volume)) restart();          // setMaterial
///     if (vt.syncForFrame()) restart();           // at each frame: unreported edits, new grid
///     vt.bind(program, 3, 4);                     // units + u_hasMaterial, u_gridOrigin, ...
///
/// Units: σ in mm⁻¹, grid origin and voxel size in mm. GL calls need the context current.

#include <lucent/dipole/DipoleProvider.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/Shader.h>
#include <lucent/material/MaterialVolume.h>

#include <cstdint>
#include <string>
#include <vector>

namespace lucent::dipole::detail {

/// The attached MaterialVolume as 3-D textures; counts uploads into a ProviderStats.
class VolumeTextures {
public:
    /// @param owner class name used in error messages.
    explicit VolumeTextures(std::string owner) : m_owner(std::move(owner)) {}

    /// Attaches `volume` (non-owning; nullptr = none). @return true when it changed (or a
    /// full upload was pending): the whole volume is uploaded at the next syncForFrame().
    bool attach(const MaterialVolume* volume);
    /// Uploads bricks of the attached volume (everything when none was uploaded yet or the grid
    /// changed). @return true when something was written (the caller restarts its accumulation).
    /// @throw ValueError for a brick index out of range or no attached volume.
    bool uploadBricks(const std::vector<int>& bricks, ProviderStats& stats);
    /// attach(&volume), then the bricks volume.takeDirtyBricks() returns (a full upload covers
    /// them). @return true when anything changed.
    bool sync(MaterialVolume& volume, ProviderStats& stats);
    /// Before a frame: a full upload when attach() asked for one, the grid changed or the
    /// volume's revision moved without uploadBricks() (edits nobody reported).
    /// @return true when it uploaded.
    bool syncForFrame(ProviderStats& stats);
    /// Frees the textures; the next syncForFrame() uploads everything again.
    void destroy();

    /// Binds the two textures to units `unitSigmaT`, `unitSigmaS` and sets the uniforms
    /// u_hasMaterial, u_gridOrigin, u_voxelSize, u_resolution of `program` (in use).
    void bind(const gpu::GlProgram& program, int unitSigmaT, int unitSigmaS) const;

    /// The bricks uploaded since the last call, and forgets them: a flag per brick of the
    /// attached volume (MaterialVolume's brick order), or `all` after a full upload or a
    /// material removed. A pixel whose material look-up reads no voxel of a written brick looks
    /// up the same material as before.
    struct WrittenBricks {
        bool all = false;
        int bricksPerAxis = 0;
        std::vector<uint8_t> written;
    };
    WrittenBricks takeWrittenBricks();

    [[nodiscard]] bool hasMaterial() const;
    [[nodiscard]] const std::string& owner() const { return m_owner; }
    [[nodiscard]] const MaterialVolume* volume() const { return m_volume; }
    [[nodiscard]] unsigned sigmaT() const { return m_sigmaT.id(); }
    [[nodiscard]] unsigned sigmaS() const { return m_sigmaS.id(); }

private:
    void writeBricks(const std::vector<int>& bricks, ProviderStats& stats);
    void uploadAll(ProviderStats& stats);

    std::string m_owner;
    const MaterialVolume* m_volume = nullptr;
    gpu::GlObject m_sigmaT, m_sigmaS;
    GridSpec m_spec;
    uint64_t m_revision = 0;
    bool m_stale = true;  ///< full upload at the next syncForFrame()
    WrittenBricks m_written;
};

/// ProviderStats after a reset: no frames, not converged (counts a restart if any work is lost:
/// accumulated frames or a preview frame).
void restartAccumulation(ProviderStats& stats);

/// Finishes one accumulated frame: frames, samplesPerPixel, lastChange from the two statistics
/// words the gather wrote (float bits of max |mean change| and max mean, read back from
/// `statsBuffer`), and converged (maxFrames, black image, or change below the threshold).
void finishFrame(ProviderStats& stats, unsigned statsBuffer, int samplesPerFrame, int maxFrames,
                 float convergenceThreshold);

/// Checks the settings both providers share. @throw ValueError naming `type`.field.
void validateProgressiveSettings(const char* type, float eta, int samplesPerFrame, int maxFrames,
                                 float convergenceThreshold, int meshId);

}  // namespace lucent::dipole::detail
