// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Image-space integration of the dipole BSSRDF on the CPU (Mertens et al. 2005
/// §5–7): for each visible surface point x_o, importance samples of R_d(r)·r (§4) and uniform
/// disc samples are placed on the tangent plane of x_o, projected into the camera's irradiance
/// image, and combined with the balance heuristic (§6.1); per-pixel Cranley–Patterson shifts from
/// a k×k table give interleaved sampling (§6.1); the material comes from the pixel (§7).
/// Light-view irradiance images (§7.1) are combined with the camera's by the balance heuristic
/// over images, and GatherSettings::maxRadius restricts the gather to a local window
/// (docs/methods/dipole.md §3d).
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
/// pass: the visible surface point, its normal, the Fresnel-transmitted irradiance E (Mertens et
/// al. 2005 Eq. 5) and the painted material there.
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
    float maxRadius = 0.f;  ///< mm; > 0: the gather only integrates r ≤ maxRadius (0 = unlimited)
    bool jacobian = true;   ///< apply the Eq. 9 area Jacobian (the paper omits it)
    float maxJacobian = 8.f;  ///< clamp of the Jacobian at grazing angles
    int interleave = 4;       ///< k: k×k table of per-pixel sample-set shifts (§6.1)
    uint32_t seed = 1;        ///< decorrelates the shift table
};

/// What a gather did (for the CLI and the docs' "skip what the scene does not need").
struct GatherStats {
    /// ε = 1 − discQuantile: the fraction of the widest channel's virtual-source mass beyond
    /// R′ (an upper bound of the mixture's), i.e. the energy the uniform disc leaves out.
    double epsilon = 0.0;
    /// Disc radius min(R′, maxRadius) over the covered pixels, mm (0 when none is covered).
    double minRadius = 0.0, maxRadius = 0.0;
    int pixels = 0;      ///< covered pixels gathered
    int lightViews = 0;  ///< light-view irradiance images combined with the camera's
};

/// Output of the gather.
struct GatherResult {
    ImageRgb exitance;  ///< B(x_o) of Eq. 4, W/mm² (0 where uncovered)
    ImageRgb radiance;  ///< F_t(η, ω_o) B(x_o)/π (Eq. 3), W/(mm²·sr)
    GatherStats stats;
};

/// One view's share of a pixel's sample budget in the multi-view gather (docs/methods/dipole.md
/// §3d): the camera and the gathered light views split the N = importance + uniform samples
/// per pixel instead of each drawing all N, so a frame costs about the same with light views.
struct ViewSamples {
    int importance = 0;               ///< importance samples of this view (channels round robin)
    int uniform = 0;                  ///< uniform disc samples of this view
    std::array<int, 3> perChannel{};  ///< filled by the gather: importance samples per channel
};
/// Stratified allocation: samples g = 0 … N−1 (the importance samples first, then the uniform
/// ones) go to view g mod `views`; a view left with none (N < views) draws one importance
/// sample, so every view keeps its support and the balance heuristic stays unbiased.
/// @throw ValueError unless 0 <= view < views and the counts are >= 0.
ViewSamples viewSamples(int importance, int uniform, int views, int view);

/// The k×k table of Cranley–Patterson shifts (5 numbers per cell) both gathers use.
std::vector<std::array<float, 5>> interleaveShifts(const GatherSettings& settings);
/// Checks settings and buffers. @throw ValueError naming the field. @return the boundary terms.
Boundary validateGather(const SurfaceBuffers& buffers, const GatherSettings& settings);
/// L = F_t(η, ω_o) B/π per covered pixel (Eq. 3), into result.radiance.
void exitanceToRadiance(const SurfaceBuffers& buffers, float eta, GatherResult& result);

/// CPU image-space gather (parallel over rows; deterministic for a given seed).
/// @throw ValueError for invalid buffers or settings (message names the field).
GatherResult gatherImageSpace(const SurfaceBuffers& buffers, const GatherSettings& settings);

/// Fraction of the lit flux in `lightView` (Σ E·dA over its covered texels) that falls on
/// surface points the camera does not see but that lie within the gather's disc radius
/// min(R′, maxRadius) of the camera-visible point in front of them along the camera ray
/// ("back-lit": thin parts lit from behind). 0 when no texel is lit. The light view is only
/// worth gathering when this is > 0 (criterion of buildImageSpaceViews()).
double backlitFluxFraction(const SurfaceBuffers& camera, const SurfaceBuffers& lightView,
                           const GatherSettings& settings);

/// The gather over several irradiance images (Mertens et al. 2005 §7.1): for each camera pixel x_o
/// the per-pixel sample budget is split over the images (the camera's `buffers`, then each of
/// `lightViews`, e.g. from buildLightViewBuffers(); viewSamples()) and the images are combined
/// with the multi-sample balance heuristic in surface-area measure: a surface point x reached
/// through image k is weighted by 1/Σ_j q_j(x), q_j = (Σ_t n_jt p_t(r′_j))/J_j(x) over the
/// images j in which x is visible (n_jt: image j's samples of technique t; the tangent-plane
/// point r′_j is where image j's ray through x meets the tangent plane, J_j = |dA_x/dA_p′| of
/// Eq. 9 for image j). Light images must hold the same E (all lights,
/// shadowed) as the camera's. With no light views this is exactly gatherImageSpace(buffers).
/// @throw ValueError for invalid buffers (the message names the light view) or settings.
GatherResult gatherImageSpace(const SurfaceBuffers& buffers,
                              const std::vector<SurfaceBuffers>& lightViews,
                              const GatherSettings& settings);

}  // namespace lucent::dipole
