// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Every refracted light path from a source outside a flat-faceted dielectric object to a
/// point inside it: the exact "manifold" connection of the reference path tracer's next-event
/// estimation through a smooth dielectric boundary (docs/reference.md, "Refracted next-event
/// estimation").
///
///     RefractionSearch search(mesh);
///     search.forEachFromPoint(lightPos, x, eta, [&](const Refraction& r) {
///         // visibility of x → r.p (inside) and r.p → light (outside) is the caller's job
///     });
///
/// The boundary is the mesh with its flat (geometric) face normals, exactly as the path tracer
/// sees it. On a plane, light from a point (or a direction) reaches an inside point through at
/// most one refraction point (Fermat: the optical path length is strictly convex on a plane), so
/// the set of solutions is one candidate per face. A bounding-volume hierarchy whose nodes carry
/// a cone of their faces' normals prunes, conservatively, every node in which no face normal can
/// equal the generalised half-vector h = ωi − η·ωt of Snell's law (Hanika, Droske & Fascione
/// 2015, Eq. 3 for the half-vector constraint); the leaves solve each face exactly. The search is
/// therefore complete: it returns every refraction point, not only the one nearest a seed.

#include <lucent/core/Types.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/reference/MeshBoundary.h>

#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

namespace lucent::reference {

/// One light path source → p (refraction into the object) → x, on the plane of one face.
struct Refraction {
    Point3f p{0.f};             ///< refraction point on the face (mm)
    Normal3f normal{0.f};       ///< unit outward face normal
    uint32_t face = 0;          ///< triangle index
    Vector3f incident{0.f};     ///< unit travel direction of the light outside, arriving at p
    Vector3f transmitted{0.f};  ///< unit travel direction inside, from p towards x
    float cosI = 0.f;           ///< cosine of incidence (outside), > 0
    float cosT = 0.f;           ///< cosine of refraction (inside), > 0
    float distOutside = 0.f;    ///< |source − p| in mm (INF for a direction)
    float distInside = 0.f;     ///< |p − x| in mm
    float fresnelTransmittance = 0.f;  ///< 1 − F(cosI) (exact unpolarised Fresnel)
    /// Irradiance at x, perpendicular to `transmitted`, per unit source strength, before
    /// Fresnel and medium attenuation: per unit intensity (W/sr) for a point source, in mm⁻²;
    /// per unit irradiance for a direction, dimensionless. Flux conservation through the
    /// refracting plane (docs/reference.md):
    ///   point:     1 / [(d₁ + s/η)·(d₁·cosθt/cosθi + s·cosθi/(η·cosθt))],  d₁ = distOutside,
    ///              s = distInside (the sagittal and tangential widths of the refracted pencil)
    ///   direction: cosθi / cosθt.
    float irradianceGain = 0.f;
};

/// Conservative search structure over a closed triangle mesh (outward counter-clockwise faces).
/// Immutable after construction; every query is thread-safe.
class RefractionSearch {
public:
    /// @throw ValueError for an empty mesh, out-of-range indices or non-finite vertices.
    explicit RefractionSearch(const TriangleMesh& mesh);
    ~RefractionSearch();
    RefractionSearch(RefractionSearch&&) noexcept;
    RefractionSearch& operator=(RefractionSearch&&) noexcept;
    RefractionSearch(const RefractionSearch&) = delete;
    RefractionSearch& operator=(const RefractionSearch&) = delete;

    /// Calls `visit(const Refraction&)` for every face f and point p ∈ f such that light leaving
    /// the point `source` (outside f's plane) refracts at p into the object (relative index
    /// `eta` = η_inside/η_outside, any positive value but 1) and travels straight to `x` (inside
    /// f's plane). Occlusion of either segment by other faces is NOT tested.
    /// This is the complete search (a traversal of the whole hierarchy); sample() is the fast,
    /// equally unbiased estimator the path tracer uses.
    template <typename Visit>
    void forEachFromPoint(const Point3f& source, const Point3f& x, float eta, Visit&& visit) const {
        search(source, /*isDirection=*/false, x, eta, &invokeUnweighted<Visit>, erase(visit));
    }
    /// Same for light travelling along the unit direction `travel` (a directional source).
    template <typename Visit>
    void forEachFromDirection(const Vector3f& travel, const Point3f& x, float eta,
                              Visit&& visit) const {
        search(travel, /*isDirection=*/true, x, eta, &invokeUnweighted<Visit>, erase(visit));
    }

    /// Unbiased stochastic version of forEachFromPoint: calls `visit(const Refraction&, float
    /// weight)` so that for any function c of a refraction, E[Σ weight·c(r)] = Σ over all
    /// refractions of c(r). A deterministic local search finds the face that holds the
    /// refraction point by casting rays from x through `boundary` (the same mesh) towards the
    /// point solved on the current face's plane, starting with the straight segment towards the
    /// source, then tests the one-rings of the solutions it finds (weight 1). With probability
    /// 1/64, decided by `u` ∈ [0, 1), the complete search adds the solutions the local search
    /// did not test (weight 64).
    /// `straightHit`: the face that the straight segment from x towards the source meets
    /// first, if the caller has already cast that ray (NO_FACE: cast it here).
    template <typename Visit>
    void sampleFromPoint(const Point3f& source, const Point3f& x, float eta,
                         const MeshBoundary& boundary, float u, Visit&& visit,
                         uint32_t straightHit = NO_FACE) const {
        sample(source, /*isDirection=*/false, x, eta, boundary, straightHit, u,
               &invokeWeighted<Visit>, erase(visit));
    }
    /// sampleFromPoint for light travelling along the unit direction `travel`.
    template <typename Visit>
    void sampleFromDirection(const Vector3f& travel, const Point3f& x, float eta,
                             const MeshBoundary& boundary, float u, Visit&& visit,
                             uint32_t straightHit = NO_FACE) const {
        sample(travel, /*isDirection=*/true, x, eta, boundary, straightHit, u,
               &invokeWeighted<Visit>, erase(visit));
    }

    /// "No face" for the optional face arguments.
    static constexpr uint32_t NO_FACE = ~0u;

    /// Faces whose refraction point was computed, by all queries of the calling thread so far
    /// (a thread-local work measure for tests and benchmarks).
    [[nodiscard]] static uint64_t facesTested();
    /// Complete searches run by the calling thread so far (forEach…, and sample()'s completion
    /// or fallback).
    [[nodiscard]] static uint64_t completeSearches();

private:
    using Callback = void (*)(void* user, const Refraction&, float weight);
    template <typename Visit>
    static void* erase(Visit& visit) {
        return const_cast<void*>(static_cast<const void*>(&visit));
    }
    template <typename Visit>
    static void invokeUnweighted(void* user, const Refraction& r, float /*weight*/) {
        (*static_cast<std::remove_reference_t<Visit>*>(user))(r);
    }
    template <typename Visit>
    static void invokeWeighted(void* user, const Refraction& r, float weight) {
        (*static_cast<std::remove_reference_t<Visit>*>(user))(r, weight);
    }
    void search(const Vector3f& source, bool isDirection, const Point3f& x, float eta,
                Callback callback, void* user) const;
    void sample(const Vector3f& source, bool isDirection, const Point3f& x, float eta,
                const MeshBoundary& boundary, uint32_t straightHit, float u, Callback callback,
                void* user) const;

    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace lucent::reference
