// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Image-space integration of the dipole BSSRDF on the CPU (Mertens et al. 2005, seed 004
/// §5–7): for each visible surface point x_o, importance samples of R_d(r)·r (§4) and uniform
/// disc samples are placed on the tangent plane of x_o, projected into the camera's irradiance
/// image, and combined with the balance heuristic (§6.1); per-pixel Cranley–Patterson shifts from
/// a k×k table give interleaved sampling (§6.1); the material comes from the pixel (§7).
///
///     SurfaceBuffers buf;                       // filled by a rasteriser / ray caster
///     buf.resize(640, 360); ...                 // position, normal, irradiance, material
///     GatherSettings gs; gs.model = Model::BetterDipole; gs.eta = 1.3f;
///     GatherResult g = gatherImageSpace(buf, gs);   // g.radiance = F_t(ω_o) B/π
///
/// Units: positions mm, irradiance W/mm², exitance B W/mm², radiance W/(mm²·sr).

#include <lucent/core/Image.h>
#include <lucent/core/Types.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/material/Medium.h>

#include <array>
#include <cstdint>
#include <vector>

namespace lucent::dipole {

/// What the camera sees, one entry per pixel (row 0 = top row), as produced by the irradiance
/// pass: the visible surface point, its normal, the Fresnel-transmitted irradiance E (seed 004
/// Eq. 5) and the painted material there.
struct SurfaceBuffers {
    int width = 0;
    int height = 0;
    std::vector<Point3f> position;         ///< mm, world space
    std::vector<Normal3f> normal;          ///< unit, outward
    std::vector<Rgb> irradiance;           ///< E(x) of Eq. 5, W/mm² per channel
    std::vector<MaterialSample> material;  ///< reduced σt, σs′ (mm⁻¹) at the surface point
    std::vector<uint8_t> covered;          ///< nonzero where the object is visible
    Mat4f clipFromWorld{1.f};              ///< the projection that produced the buffers
    Point3f eye{0.f};                      ///< perspective: centre of projection (mm)
    bool orthographic = false;
    Vector3f viewDirection{0.f, 0.f, -1.f};  ///< orthographic: direction the camera looks

    /// Allocates every buffer for w×h pixels, all uncovered. @throw ValueError if w or h ∉ [1,
    /// 16384].
    void resize(int w, int h);
    [[nodiscard]] size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
    /// Continuous pixel coordinates of a world point (x right, y down, pixel centres at +0.5).
    /// @return false if the point is behind the camera or outside the image.
    [[nodiscard]] bool project(const Point3f& p, Point2f& pixel) const;
    /// Unit direction from a surface point towards the camera.
    [[nodiscard]] Vector3f towardEye(const Point3f& p) const;
    /// @throw ValueError naming the first inconsistent buffer size or bad pixel value.
    void validate() const;
};

/// Parameters of the gather.
struct GatherSettings {
    Model model = Model::Dipole;  ///< Dipole or BetterDipole (the directional dipole needs
                                  ///< incident directions: light-view pipeline, not this one)
    float eta = 1.3f;             ///< relative index of the object, [1, 3]
    int importanceSamples = 16;   ///< per pixel, split over the three channels' samplers
    int uniformSamples = 4;       ///< per pixel, uniform on the disc of radius R′
    float discQuantile = 0.99f;   ///< R′ = this quantile of the widest channel's virtual source
    bool jacobian = true;         ///< apply the Eq. 9 area Jacobian (the paper omits it)
    float maxJacobian = 8.f;      ///< clamp of the Jacobian at grazing angles
    int interleave = 4;           ///< k: k×k table of per-pixel sample-set shifts (§6.1)
    uint32_t seed = 1;            ///< decorrelates the shift table
};

/// Output of the gather.
struct GatherResult {
    ImageRgb exitance;  ///< B(x_o) of Eq. 4, W/mm² (0 where uncovered)
    ImageRgb radiance;  ///< F_t(η, ω_o) B(x_o)/π (Eq. 3), W/(mm²·sr)
};

/// The k×k table of Cranley–Patterson shifts (5 numbers per cell) both gathers use.
std::vector<std::array<float, 5>> interleaveShifts(const GatherSettings& settings);
/// Checks settings and buffers. @throw ValueError naming the field. @return the boundary terms.
Boundary validateGather(const SurfaceBuffers& buffers, const GatherSettings& settings);
/// L = F_t(η, ω_o) B/π per covered pixel (Eq. 3), into result.radiance.
void exitanceToRadiance(const SurfaceBuffers& buffers, float eta, GatherResult& result);

/// CPU image-space gather (parallel over rows; deterministic for a given seed).
/// @throw ValueError for invalid buffers or settings (message names the field).
GatherResult gatherImageSpace(const SurfaceBuffers& buffers, const GatherSettings& settings);

}  // namespace lucent::dipole
