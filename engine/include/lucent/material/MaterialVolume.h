// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The painted heterogeneous material of one object: a cubic, cell-centred voxel grid
/// in the object's rest space (millimetres), stored in 8³ bricks with dirty-brick tracking.
///
///     GridSpec spec = GridSpec::around(mesh.bounds(), 128);
///     MaterialVolume vol(spec, presetSample("marble"));
///     vol.setInsideMask(voxelizeSolid(mesh, spec));     // voxels outside the mesh masked out
///     vol.set({64, 64, 64}, sample);
///     for (int b : vol.takeDirtyBricks()) upload(b);
///
/// Voxel (i,j,k) covers [origin + (i,j,k)·h, origin + (i+1,j+1,k+1)·h); its centre is at
/// origin + (i+½, j+½, k+½)·h. Lookups between centres use the value of the containing voxel
/// (nearest / piecewise constant): the single interpolation rule every method uses.

#include <lucent/core/Types.h>
#include <lucent/material/Medium.h>

#include <cstdint>
#include <vector>

namespace lucent {

/// Placement and resolution of a cubic voxel grid.
struct GridSpec {
    Point3f origin{0.f};    ///< minimum corner, mm
    float voxelSize = 1.f;  ///< edge length h, mm
    int resolution = 128;   ///< voxels per axis

    static constexpr int MIN_RESOLUTION = 16;
    static constexpr int MAX_RESOLUTION = 256;
    static constexpr int DEFAULT_RESOLUTION = 128;

    /// Cubic grid covering `bounds` padded by `padVoxels` voxels on every side.
    /// @throw ValueError if bounds are empty/non-finite or resolution outside [16, 256].
    static GridSpec around(const Bounds3f& bounds, int resolution = DEFAULT_RESOLUTION,
                           float padVoxels = 1.5f);

    [[nodiscard]] Point3f cellCenter(const Coord& c) const {
        return origin + (Vector3f(c) + Vector3f(0.5f)) * voxelSize;
    }
    /// Voxel containing p (may be outside the grid; test with contains()).
    [[nodiscard]] Coord cellOf(const Point3f& p) const {
        return Coord(glm::floor((p - origin) / voxelSize));
    }
    [[nodiscard]] bool contains(const Coord& c) const {
        return c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x < resolution && c.y < resolution &&
               c.z < resolution;
    }
    [[nodiscard]] Bounds3f bounds() const {
        return {origin, origin + Vector3f(voxelSize * float(resolution))};
    }
    [[nodiscard]] size_t voxelCount() const { return size_t(resolution) * resolution * resolution; }
    /// Linear index, x fastest.
    [[nodiscard]] size_t linearIndex(const Coord& c) const {
        return (size_t(c.z) * resolution + c.y) * resolution + c.x;
    }
    bool operator==(const GridSpec&) const = default;
};

/// Which painted quantity a channel mask selects.
enum class Channel : uint8_t { SigmaT = 1, SigmaS = 2, G = 4 };
using ChannelMask = uint8_t;
inline constexpr ChannelMask ALL_CHANNELS = 7;

/// Brick-structured storage of σt, σs′, g (RGB each) for one object.
class MaterialVolume {
public:
    static constexpr int BRICK = 8;  ///< brick edge, voxels
    static constexpr int BRICK_VOXELS = BRICK * BRICK * BRICK;
    static constexpr int COMPONENTS = 9;  ///< σt rgb, σs′ rgb, g rgb

    /// Component index inside a brick: SigmaT → 0..2, SigmaS → 3..5, G → 6..8.
    static constexpr int component(Channel ch, int rgb) {
        return (ch == Channel::SigmaT ? 0 : ch == Channel::SigmaS ? 3 : 6) + rgb;
    }

    MaterialVolume() = default;
    /// All inside voxels start at `base` (sanitised); the inside mask starts all-true.
    /// @throw ValueError if spec.resolution is outside [1, 256], spec.voxelSize is not a
    /// positive finite number (mm) or spec.origin is not finite.
    MaterialVolume(const GridSpec& spec, const MaterialSample& base);

    [[nodiscard]] const GridSpec& spec() const { return m_spec; }
    [[nodiscard]] int resolution() const { return m_spec.resolution; }
    [[nodiscard]] int bricksPerAxis() const { return m_bricksPerAxis; }
    [[nodiscard]] int brickCount() const {
        return m_bricksPerAxis * m_bricksPerAxis * m_bricksPerAxis;
    }

    //! @{ \name Per-object scalars
    [[nodiscard]] float eta() const { return m_eta; }
    /// @param eta relative index of refraction, [1, 3]. @throw ValueError otherwise.
    void setEta(float eta);
    [[nodiscard]] const MaterialSample& base() const { return m_base; }
    /// Sets the base (sanitised): the value voxels get when they become inside, and the target
    /// of BrushMode::ResetToBase. Painted voxels are unchanged (PaintSession::applyPreset also
    /// repaints the interior).
    void setBase(const MaterialSample& base);
    //! @}

    //! @{ \name Voxel access
    /// Painted value at voxel c; zero for masked-out voxels. Precondition: spec().contains(c).
    [[nodiscard]] MaterialSample at(const Coord& c) const;
    /// Nearest-voxel lookup at a world (rest-space) point; zero outside the grid or mask.
    [[nodiscard]] MaterialSample sample(const Point3f& p) const;
    /// Sets voxel c (sanitised), marks its brick dirty; ignored for masked-out voxels.
    void set(const Coord& c, const MaterialSample& s);
    /// Raw component access (no sanitising, no dirty marking): for bulk operations.
    [[nodiscard]] float component(const Coord& c, int comp) const;
    //! @}

    //! @{ \name Inside mask
    [[nodiscard]] bool isInside(const Coord& c) const {
        return m_inside[m_spec.linearIndex(c)] != 0;
    }
    /// Replaces the mask (voxelCount() bytes, x fastest, nonzero = inside); outside voxels are
    /// zeroed, inside voxels that were outside get the base value. Marks all bricks dirty.
    void setInsideMask(const std::vector<uint8_t>& inside);
    [[nodiscard]] const std::vector<uint8_t>& insideMask() const { return m_inside; }
    /// FNV-1a 64 of the inside mask and every stored value: equal volumes of one grid hash
    /// equally, so a saved copy can be checked against the volume it came from.
    [[nodiscard]] uint64_t contentHash() const;
    /// True if any voxel of brick b is inside.
    [[nodiscard]] bool brickHasInside(int b) const { return m_brickInside[b] != 0; }
    //! @}

    //! @{ \name Brick storage (SoA per brick: component-major, then x fastest within the brick)
    [[nodiscard]] Coord brickOrigin(int b) const;
    [[nodiscard]] int brickIndexOf(const Coord& c) const;
    [[nodiscard]] const float* brickData(int b) const {
        return &m_data[size_t(b) * BRICK_VOXELS * COMPONENTS];
    }
    float* brickData(int b) { return &m_data[size_t(b) * BRICK_VOXELS * COMPONENTS]; }
    static constexpr int voxelInBrick(int x, int y, int z) { return (z * BRICK + y) * BRICK + x; }
    //! @}

    //! @{ \name Dirty tracking
    void markBrickDirty(int b) {
        m_dirty[b] = 1;
        ++m_revision;
    }
    void markAllDirty();
    [[nodiscard]] bool isBrickDirty(int b) const { return m_dirty[b] != 0; }
    /// Indices of dirty bricks; clears the flags.
    std::vector<int> takeDirtyBricks();
    /// Increases on every modification; lets caches know the material changed.
    [[nodiscard]] uint64_t revision() const { return m_revision; }
    //! @}

    /// Dense copy of one component, x fastest (voxelCount() floats).
    [[nodiscard]] std::vector<float> denseComponent(int comp) const;

    /// True when every inside voxel holds the same value (homogeneous fast paths).
    [[nodiscard]] bool isHomogeneous() const;

private:
    GridSpec m_spec;
    int m_bricksPerAxis = 0;
    float m_eta = 1.3f;
    MaterialSample m_base;
    std::vector<float> m_data;      // brickCount × COMPONENTS × BRICK_VOXELS
    std::vector<uint8_t> m_inside;  // voxelCount, dense
    std::vector<uint8_t> m_brickInside;
    std::vector<uint8_t> m_dirty;
    uint64_t m_revision = 0;
};

}  // namespace lucent
