// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Engine-side painting operations on a MaterialVolume: spherical brush stamps, strokes
/// along a polyline, whole-interior fills. Every operation keeps σs′ ≤ σt (sanitize()), marks
/// the bricks it touches dirty and, when given an open History stroke, records their "before"
/// state so the edit can be undone bit-exactly.
///
///     BrushSettings brush;
///     brush.radius = 4.f;                          // mm
///     brush.mode = BrushMode::Add;
///     brush.channels = uint8_t(Channel::SigmaT);
///     brush.value.sigma_t = Rgb(0.5f);            // mm⁻¹ added at the centre (× strength)
///     history.beginStroke(vol);
///     paintStroke(vol, brush, {p0, p1, p2}, &history);
///     history.endStroke(vol);
///
/// A voxel is *touched* by a stamp when it is inside the mask and its centre lies strictly
/// within the radius: |centre − p| < radius. Its weight is w = strength · falloff(|centre − p| /
/// r). Per selected component v (σt, σs′ or g, per RGB channel), with brush value u:
///     Set        v ← v + w (u − v)
///     Add        v ← v + w u
///     Subtract   v ← v − w u
///     Multiply   v ← v (1 + w (u − 1))           (u is a factor)
///     Smooth     v ← v + w (m − v), m = mean of the inside voxels of the 3×3×3 neighbourhood,
///                read before the stamp (order-independent)
///     ResetToBase v ← v + w (base − v)
/// then the voxel is sanitised (σt ∈ [0, SIGMA_MAX], 0 ≤ σs′ ≤ σt, |g| ≤ 0.99).

#include <lucent/core/Types.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Medium.h>

#include <cstdint>
#include <vector>

namespace lucent {

class History;

/// Radial falloff of a brush, t = distance / radius ∈ [0, 1).
enum class Falloff : uint8_t {
    Constant,  ///< 1
    Linear,    ///< 1 − t
    Smooth,    ///< 1 − (3t² − 2t³)  (smoothstep)
    Gaussian,  ///< exp(−t² / (2·(1/3)²)), i.e. the edge at 3σ (weight ≈ 0.011 there)
};

enum class BrushMode : uint8_t { Set, Add, Subtract, Multiply, Smooth, ResetToBase };

/// Every brush parameter, with units.
struct BrushSettings {
    float radius = 5.f;  ///< mm, (0, MAX_RADIUS]
    Falloff falloff = Falloff::Smooth;
    float strength = 1.f;  ///< [0, 1]
    BrushMode mode = BrushMode::Set;
    ChannelMask channels = ALL_CHANNELS;  ///< which of σt, σs′, g are painted (Channel bits)
    /// Set: target value (σ in mm⁻¹, g in [−0.99, 0.99]); Add/Subtract: amount (σ in mm⁻¹,
    /// g unitless); Multiply: factor per component (≥ 0); Smooth/ResetToBase: unused.
    MaterialSample value;
    float spacing = 0.25f;  ///< stroke stamp spacing as a fraction of the radius

    static constexpr float MAX_RADIUS = 1e4f;    ///< mm
    static constexpr float MIN_SPACING = 0.01f;  ///< × radius
    static constexpr float MAX_SPACING = 10.f;   ///< × radius
    static constexpr float MAX_FACTOR = 1e3f;    ///< largest Multiply factor
    static constexpr size_t MAX_STAMPS_PER_STROKE = 100000;
};

/// The brush a painting session starts with: the app's Tools dock shows it at start-up, and the
/// live-cost calibration (lucent/planner/LiveCalibration.h) strokes with it to time what the
/// artist's first strokes cost. Radius 3 mm, smooth falloff, strength 0.5, Set σt = 1 mm⁻¹,
/// σs′ = 0.8 mm⁻¹ and g = 0 on every channel, the default spacing.
BrushSettings startingBrush();

/// Falloff weight at t = distance / radius; 0 for t ≥ 1. Precondition: t ≥ 0.
float falloffWeight(Falloff falloff, float t);

/// Checks every field of `brush`. @throw ValueError naming the field when NaN/Inf/out of range.
void validateBrush(const BrushSettings& brush);

/// Applies one stamp centred at `center` (mm, rest space).
/// @param history when non-null and a stroke is open, touched bricks are recorded before they
///        change.
/// @return number of voxels touched.
/// @throw ValueError for invalid settings or a non-finite centre.
size_t stamp(MaterialVolume& volume, const BrushSettings& brush, const Point3f& center,
             History* history = nullptr);

/// Stamp positions along a polyline at arc lengths 0, s, 2s, … ≤ length, s = spacing·radius.
/// A single-point path gives one stamp. @throw ValueError on an empty/non-finite path or when
/// more than MAX_STAMPS_PER_STROKE stamps would be needed.
std::vector<Point3f> strokeStamps(const std::vector<Point3f>& path, const BrushSettings& brush);

/// Applies strokeStamps(path, brush) in order. @return number of voxel updates.
size_t paintStroke(MaterialVolume& volume, const BrushSettings& brush,
                   const std::vector<Point3f>& path, History* history = nullptr);

/// Sets the selected channels of every inside voxel to `value` (sanitised).
/// @throw ValueError if `value` has NaN/Inf or negative σ.
void fillInterior(MaterialVolume& volume, const MaterialSample& value,
                  ChannelMask channels = ALL_CHANNELS, History* history = nullptr);

}  // namespace lucent
