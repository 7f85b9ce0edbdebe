// SPDX-License-Identifier: MIT
/// @file
/// @brief Irradiance bounds of a light over an object's bounding sphere, and the lights a
/// preview may skip (see the header).

#include <lucent/scene/LightReach.h>

#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>

namespace lucent {

namespace {

/// The smallest spot half-angle the GL renderer draws (SceneRenderer clamps the outer cone to
/// [0.1°, 89.9°]); a narrower cone here would skip a spot the preview still shows.
constexpr float MIN_SPOT_OUTER_DEG = 0.1f;

/// I/d² for a distance interval [near, far] (near may be 0: no upper bound; far 0, a light at
/// the centre of a point-sized object: no lower bound either).
void inverseSquare(const Rgb& intensity, float near, float far, LightReach& out) {
    out.most = near > 0.f ? intensity / (near * near) : Rgb(INF);
    out.least = far > 0.f ? intensity / (far * far) : Rgb(0.f);
}

}  // namespace

LightReach lightReach(const Light& light, const Point3f& centre, float radius) {
    LightReach r;
    const Rgb black(0.f);
    if (glm::all(glm::equal(light.intensity, black))) {
        r.misses = true;
        return r;
    }
    if (light.type == Light::Type::Directional) {
        r.most = r.least = light.intensity;
        return r;
    }
    const Vector3f toCentre = centre - light.position;
    const float distance = glm::length(toCentre);
    const float near = std::max(distance - radius, 0.f);
    const float far = distance + radius;
    switch (light.type) {
        case Light::Type::Point:
            inverseSquare(light.intensity, near, far, r);
            break;
        case Light::Type::Spot: {
            inverseSquare(light.intensity, near, far, r);
            if (distance <= radius) {  // the apex is inside the sphere: some of it is lit
                r.least = black;
                break;
            }
            // The sphere subtends a cone of half-angle α = asin(R/D) around the direction to
            // its centre, at angle φ from the spot's axis: it is outside the outer cone when
            // φ − α ≥ θ_outer, and inside the full-intensity inner cone when φ + α ≤ θ_inner.
            const float axisLength = glm::length(light.direction);
            if (!(axisLength > 0.f))
                break;  // no axis: no cone to test (the renderer refuses such a light)
            const float cosPhi =
                std::clamp(glm::dot(toCentre / distance, light.direction / axisLength), -1.f, 1.f);
            const float phi = std::acos(cosPhi);
            const float alpha = std::asin(std::min(radius / distance, 1.f));
            const float outer = glm::radians(std::max(light.spotOuterDeg, MIN_SPOT_OUTER_DEG));
            const float inner = glm::radians(std::min(light.spotInnerDeg, light.spotOuterDeg));
            if (phi - alpha >= outer) {
                r = LightReach{};
                r.misses = true;
            } else if (!(phi + alpha <= inner)) {
                r.least = black;  // the falloff reaches part of the sphere
            }
            break;
        }
        case Light::Type::Sphere: {
            // A sphere of radiance L and radius ρ seen head-on from distance d ≥ ρ: E = πL ρ²/d²
            // (the projected solid angle of the disc it subtends is π sin²θ, sin θ = ρ/d); at
            // most πL, its value on the emitter's surface.
            const float rho2 = light.radius * light.radius;
            const auto head = [&](float d) {
                return d * d > rho2 ? (PI * light.intensity) * (rho2 / (d * d))
                                    : PI * light.intensity;
            };
            r.most = head(near);
            r.least = head(far);
            break;
        }
        case Light::Type::Directional:
            break;  // handled above
    }
    return r;
}

LightCulling cullLights(const std::vector<Light>& lights, const Bounds3f& bounds, float epsilon) {
    LUCENT_CHECK(std::isfinite(epsilon), "cullLights: epsilon must be finite (got ", epsilon, ")");
    LightCulling out;
    if (bounds.isEmpty() || epsilon < 0.f || lights.empty()) {
        out.kept = lights;
        return out;
    }
    const Point3f centre = bounds.center();
    const float radius = 0.5f * glm::length(bounds.extent());
    std::vector<LightReach> reach;
    reach.reserve(lights.size());
    Rgb strongest(0.f);  // per channel: the largest guaranteed irradiance of any light
    for (const Light& l : lights) {
        reach.push_back(lightReach(l, centre, radius));
        strongest = glm::max(strongest, reach.back().least);
    }
    for (size_t i = 0; i < lights.size(); ++i) {
        const LightReach& r = reach[i];
        std::string why;
        if (r.misses) {
            why =
                lights[i].type == Light::Type::Spot ? "its cone misses the object" : "it is black";
        } else if (glm::all(glm::lessThanEqual(r.most, epsilon * strongest))) {
            // NaN bounds compare false: such a light is kept and refused downstream.
            why = "it gives the object at most " + std::to_string(epsilon) +
                  " of the strongest light's irradiance";
        }
        if (why.empty())
            out.kept.push_back(lights[i]);
        else
            out.skipped.push_back("light " + std::to_string(i) + " (" +
                                  lightTypeName(lights[i].type) + "): " + why);
    }
    if (out.kept.empty()) {  // nothing would be lit: keep the scene as given
        out.kept = lights;
        out.skipped.clear();
    }
    return out;
}

Bounds3f objectBounds(const Scene& scene) {
    Bounds3f b;
    for (const SceneObject& o : scene.objects)
        b.expand(o.mesh.bounds());
    return b;
}

}  // namespace lucent
