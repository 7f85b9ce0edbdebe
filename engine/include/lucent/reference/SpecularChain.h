// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Specular chains: light that reaches a point inside the object from a point or
/// directional light through several reflections and refractions at the smooth, flat-faceted
/// surface, without scattering in between (docs/reference.md, "Chains of surface events").
///
///     SpecularChainTracer tracer(boundary, eta);
///     std::optional<SpecularChain> seed = tracer.sampleSeed(x, rng);      // random chain type
///     std::optional<SpecularChain> c = tracer.connect(x, *seed, light);   // exact solution
///
/// A chain is traced backwards from x (where the light ends) with ray differentials, so that
/// one trace gives the chain's end ray, its derivatives with respect to the direction at x
/// (for Newton's method, in the spirit of manifold next-event estimation: Hanika, Droske &
/// Fascione 2015) and the irradiance gain of the light's pencil at x (étendue conservation).
/// Which chains exist is found by random seeds, and their probability is estimated without
/// bias by repeated trials (specular manifold sampling: Zeltner, Georgiev & Jakob 2020, Sec. 4.3).

#include <lucent/core/Random.h>
#include <lucent/core/Types.h>
#include <lucent/reference/MeshBoundary.h>

#include <array>
#include <cstdint>
#include <optional>

namespace lucent::reference {

/// One chain, from the inside point x outwards to the light (the reverse of the light's way).
struct SpecularChain {
    static constexpr int MAX_EVENTS = 24;
    int events = 0;
    std::array<uint32_t, MAX_EVENTS> faces{};  ///< triangle of each surface event
    /// Per event: true for a reflection (on either side), false for a refraction.
    std::array<bool, MAX_EVENTS> reflects{};
    std::array<Point3f, MAX_EVENTS> points{};  ///< event positions (mm)
    /// The segment that ends at event i (segment 0 starts at x) lies inside the object.
    std::array<bool, MAX_EVENTS> insideBefore{};
    Vector3f directionAtX{0.f};    ///< unit, from x towards points[0]
    Vector3f finalDirection{0.f};  ///< unit, the last segment's direction, towards the light
    /// Product over the events of the Fresnel reflectance F (reflections) or transmittance
    /// 1 − F (refractions), exact and unpolarised (reciprocal, so the same either way).
    double fresnel = 1.0;
    /// Irradiance at x across the light's direction per unit source strength (per W/sr for a
    /// point source, mm⁻²; per W/mm² for a directional one), before Fresnel and medium
    /// attenuation: η_x²·dΩ_x/dA⊥ (point) or η_x²·dΩ_x/dΩ (direction), from the ray
    /// differentials of the backward trace (étendue n²·dA·dΩ is conserved along the chain).
    double irradianceGain = 0.0;
    float distanceToSource = 0.f;  ///< last event to a point source (mm); INF for a direction

    /// Same chain: the same faces and kinds of event, in order.
    [[nodiscard]] bool sameAs(const SpecularChain& other) const;
    /// Same kinds of event (reflection or refraction), in order: the same chain type.
    [[nodiscard]] bool sameKinds(const SpecularChain& other) const;
    /// A single refraction: the chains RefractionSearch finds.
    [[nodiscard]] bool isSingleRefraction() const { return events == 1 && !reflects[0]; }
    /// Total length (mm) of the segments inside the object, starting from x.
    [[nodiscard]] float insideLength(const Point3f& x) const;
};

/// A point or directional light as the end of a chain.
struct ChainSource {
    Vector3f value{0.f};  ///< position (mm) or unit travel direction of the light
    bool isDirection = false;
};

/// Traces chains on one closed mesh with relative index `eta` inside. Thread-safe.
class SpecularChainTracer {
public:
    /// @param boundary the object's surface (kept by reference: it must outlive the tracer).
    SpecularChainTracer(const MeshBoundary& boundary, float eta);

    /// A random chain type from x: a direction drawn uniformly on the sphere, then at each
    /// surface event a reflection with probability ½ (1 under total internal reflection),
    /// otherwise a refraction, until the ray leaves the scene. Nothing when the walk fails
    /// (more than MAX_EVENTS events, a numerical leak).
    [[nodiscard]] std::optional<SpecularChain> sampleSeed(const Point3f& x, Pcg32& rng) const;

    /// The chain with the seed's kinds of event that connects x to the source exactly, found by
    /// Newton's method on the direction at x starting from the seed's (the faces may change on
    /// the way); nothing when it does not converge, a refraction meets total internal
    /// reflection, or the light is occluded.
    [[nodiscard]] std::optional<SpecularChain> connect(const Point3f& x, const SpecularChain& seed,
                                                       const ChainSource& source) const;

    /// Traces backwards from x along unit v with the given kinds of event (the chain's
    /// `reflects`, `events` used as the kinds to follow) and fills in the chain, its end ray
    /// and the irradiance gain for `source`; nothing if the trace does not follow the kinds.
    [[nodiscard]] std::optional<SpecularChain> trace(const Point3f& x, const Vector3f& v,
                                                     const SpecularChain& kinds,
                                                     const ChainSource& source) const;

private:
    const MeshBoundary* m_boundary;
    float m_eta;
};

}  // namespace lucent::reference
