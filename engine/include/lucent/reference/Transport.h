// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Radiative-transfer kernels of the reference path tracer, per colour channel or for
/// all three with hero-channel spectral MIS: null-collision (delta) tracking of free flights,
/// ratio-tracking transmittance, the analog medium walk and the full radiance estimator of one
/// ray. Exposed for the validation tests (tests/unit/reference) and used by PathTracer.h;
/// docs/reference.md has the model. Both colour modes share one implementation of each
/// estimator (Transport.cpp: templates over a channel policy).
///
///     VolumeScene scene(mesh, GridMedium::fromMaterial(vol, {}), lights);
///     TransportOptions opt{.boundary = BoundaryModel::Dielectric, .eta = 1.3f};
///     Pcg32 rng(pixelSeed(x, y, s, seed));
///     float L = estimateRadiance(scene, origin, dir, /*channel=*/s % 3, rng, opt);
///
/// Every function here is thread-safe for distinct `rng`s and never throws.

#include <lucent/core/Random.h>
#include <lucent/core/Types.h>
#include <lucent/reference/GridMedium.h>
#include <lucent/reference/MeshBoundary.h>
#include <lucent/reference/RefractionSearch.h>
#include <lucent/scene/Scene.h>

#include <cstdint>
#include <string>
#include <optional>
#include <vector>

namespace lucent::reference {

/// How light crosses the object's surface.
enum class BoundaryModel : uint8_t {
    Matched,  ///< η = 1: rays cross unchanged (exact)
    /// Smooth dielectric, exact: Fresnel reflection/refraction at every crossing, and
    /// next-event estimation through every refraction point that connects a light to the
    /// scattering point (RefractionSearch), so delta lights behind the surface are reached.
    Dielectric,
    /// Fast approximation of Dielectric, never ground truth: shadow rays go straight through
    /// the surface, weighted by the Fresnel transmittance (light arriving past the critical
    /// angle is lost). Kept for comparison (`--boundary straight`).
    Straight,
};

/// The name used on the command line and in reports: "matched", "dielectric", "straight".
const char* boundaryModelName(BoundaryModel model);
/// The model called `name` (boundaryModelName's names). @throw ValueError naming the three.
BoundaryModel parseBoundaryModel(const std::string& name);

/// Parameters of the estimators.
struct TransportOptions {
    BoundaryModel boundary = BoundaryModel::Dielectric;
    float eta = 1.3f;             ///< relative index of refraction inside/outside (Dielectric)
    bool subsurfaceOnly = false;  ///< drop the direct (camera-side) Fresnel surface reflection
    int maxScatter = 1 << 20;     ///< scattering events after which a path is cut (bias, docs)
    bool russianRoulette = true;  ///< unbiased weight-window roulette below weight 0.5
};

/// Mesh + medium + lights, prepared for tracing. Immutable; share between threads.
class VolumeScene {
public:
    /// @param environment radiance of a constant environment light, W/(mm²·sr) per channel,
    ///        seen wherever a ray leaves the scene (0: black background).
    /// @throw ValueError for an empty mesh, a light with non-finite/negative parameters or a
    ///        negative/non-finite environment radiance.
    VolumeScene(const TriangleMesh& mesh, GridMedium medium, std::vector<Light> lights,
                const Rgb& environment = Rgb(0.f));

    [[nodiscard]] const MeshBoundary& boundary() const { return m_boundary; }
    [[nodiscard]] const RefractionSearch& refractions() const { return m_refractions; }
    [[nodiscard]] const GridMedium& medium() const { return m_medium; }
    [[nodiscard]] const std::vector<Light>& lights() const { return m_lights; }
    [[nodiscard]] const Rgb& environment() const { return m_environment; }

private:
    MeshBoundary m_boundary;
    RefractionSearch m_refractions;
    GridMedium m_medium;
    std::vector<Light> m_lights;
    Rgb m_environment{0.f};
};

/// Counters of the work a walk did (to measure the majorant grid's effect).
struct TrackingStats {
    uint64_t tentativeCollisions = 0;  ///< σt lookups by delta and ratio tracking
    uint64_t realCollisions = 0;
};

/// Delta (Woodcock) tracking along o + t·d, t ∈ [0, tMax], channel ch: returns the distance of
/// the first real collision, or nothing if the ray reaches tMax. `d` unit.
std::optional<float> sampleFreeFlight(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                                      float tMax, int ch, Pcg32& rng,
                                      TrackingStats* stats = nullptr);

/// Ratio-tracking estimate of the transmittance exp(−∫₀^tMax σt) along o + t·d (unbiased;
/// exact for a homogeneous medium with the fast path). `d` unit.
float estimateTransmittance(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                            float tMax, int ch, Pcg32& rng, TrackingStats* stats = nullptr);

/// Where an analog medium walk ended.
struct WalkResult {
    bool escaped = false;     ///< left the object (false: absorbed, cut or lost)
    Point3f position{0.f};    ///< exit point on the surface (mm)
    Vector3f direction{0.f};  ///< direction after leaving (outside the object)
    float weight = 0.f;       ///< product of single-scattering albedos (and roulette factors)
    int scatterCount = 0;     ///< real scattering events
};

/// Random walk inside the object from `p` (inside, or on the surface with `d` pointing in)
/// along `d` until the path leaves through the boundary: delta tracking for free flights,
/// HG scattering, weight ×= σs/σt per collision, Fresnel reflection/refraction at the surface
/// for the Dielectric model. No light is gathered: it measures where flux goes.
WalkResult walkMedium(const VolumeScene& scene, const Point3f& p, const Vector3f& d, int ch,
                      Pcg32& rng, const TransportOptions& options, TrackingStats* stats = nullptr);

/// Transmittance from p to the light sample at distance `dist` along unit `wi` (INF for a
/// directional light), through every stretch of the object the segment crosses, times the
/// Fresnel transmittance 1 − F at each surface crossing unless the boundary is Matched: the
/// straight shadow connection of the Straight approximation (docs/reference.md); the exact
/// Dielectric model connects through RefractionSearch instead. `pInside`: p is inside.
float shadowTransmittance(const VolumeScene& scene, const Point3f& p, const Vector3f& wi,
                          float dist, bool pInside, int ch, Pcg32& rng,
                          const TransportOptions& options, TrackingStats* stats = nullptr);

/// Radiance (W/(mm²·sr), channel ch) arriving at `o` from direction −d: camera-side surface
/// reflection, subsurface transport with next-event estimation to every light, light seen
/// directly or through the unscattered medium, the environment where a ray leaves the scene.
/// With the Dielectric boundary, next-event estimation covers the light that reaches the last
/// scattering event through one refraction, the path itself every other chain of reflections
/// and refractions that ends on a sphere light or the environment (docs/reference.md).
float estimateRadiance(const VolumeScene& scene, const Point3f& o, const Vector3f& d, int ch,
                       Pcg32& rng, const TransportOptions& options, TrackingStats* stats = nullptr);

/// Ratio-tracking transmittance of all three channels at once against the common majorant
/// (GridMedium::ANY_CHANNEL): Tc = Π (1 − σt,c/σ̄), unbiased per channel.
Rgb estimateTransmittanceRgb(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                             float tMax, Pcg32& rng, TrackingStats* stats = nullptr);

/// RGB radiance arriving at `o` from −d with hero-channel spectral MIS: the path is sampled
/// with channel `hero`'s coefficients (null-collision tracking against the common majorant,
/// HG with g_hero) and every channel's contribution is weighted by the one-sample balance
/// heuristic over the three channels' sampling techniques (Wilkie et al. 2014; Miller,
/// Georgiev & Jarosz 2019, Sec. 5). Unbiased in every channel for any hero; the renderer
/// stratifies hero = sample index mod 3. Same light transport as estimateRadiance.
Rgb estimateRadianceRgb(const VolumeScene& scene, const Point3f& o, const Vector3f& d, int hero,
                        Pcg32& rng, const TransportOptions& options,
                        TrackingStats* stats = nullptr);

}  // namespace lucent::reference
