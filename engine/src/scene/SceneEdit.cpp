// SPDX-License-Identifier: MIT
/// @file
/// @brief Scene edits: light type conversion at equal irradiance, mesh edit + re-voxelise.

#include <lucent/scene/SceneEdit.h>

#include <lucent/core/Error.h>
#include <lucent/mesh/MeshEdit.h>
#include <lucent/mesh/Voxelize.h>

#include <algorithm>
#include <cmath>

namespace lucent {

Light convertLight(const Light& light, Light::Type type, const Point3f& target,
                   float objectRadius) {
    if (light.type == type)
        return light;
    const float handleDistance = 1.5f * objectRadius;  // where the app draws its handle
    // Where the light is (p), the unit axis from it to the target (w), its distance (d), and
    // the irradiance E it gives there at normal incidence (W/mm²).
    Point3f p = light.position;
    Vector3f w{0.f, -1.f, 0.f};
    float d = handleDistance;
    Rgb irradiance{0.f};
    const float dirLength = glm::length(light.direction);
    const Vector3f ownDir = dirLength > 0.f ? light.direction / dirLength : w;
    if (light.type == Light::Type::Directional) {
        w = ownDir;
        p = target - d * w;
        irradiance = light.intensity;
    } else {
        const Vector3f toTarget = target - light.position;
        const float distance = glm::length(toTarget);
        if (distance > 1e-4f * objectRadius) {
            w = toTarget / distance;
            d = distance;
        } else {  // a light at the target has no direction to it: step back along its own
            w = light.type == Light::Type::Spot ? ownDir : w;
            p = target - d * w;
        }
        // Radiant intensity toward the target (W/sr): a spot's on-axis value; a uniform sphere
        // of radiance L and radius R seen from outside: I = L·πR².
        Rgb intensity = light.intensity;
        if (light.type == Light::Type::Sphere)
            intensity = light.intensity * (PI * light.radius * light.radius);
        irradiance = intensity / (d * d);  // inverse-square law
    }
    Light out = light;
    out.type = type;
    switch (type) {
        case Light::Type::Point:
            out.position = p;
            out.intensity = irradiance * (d * d);
            break;
        case Light::Type::Spot: {
            out.position = p;
            out.direction = w;
            out.intensity = irradiance * (d * d);
            // Half-angle under which the object's bounding sphere is seen from the light.
            const float alphaDeg = glm::degrees(std::asin(std::min(1.f, objectRadius / d)));
            out.spotInnerDeg = std::clamp(alphaDeg, 1.f, 80.f);
            out.spotOuterDeg = out.spotInnerDeg + 5.f;
            break;
        }
        case Light::Type::Directional:
            out.direction = w;
            out.intensity = irradiance;
            break;
        case Light::Type::Sphere: {
            out.position = p;
            out.radius = std::min(0.1f * objectRadius, 0.5f * d);
            // E = πL·R²/d²  ⇒  L = E·d² / (πR²).
            out.intensity = irradiance * (d * d / (PI * out.radius * out.radius));
            break;
        }
    }
    return out;
}

void editObjectMesh(SceneObject& object, MeshEditKind kind, const MeshEditParams& params) {
    if (object.mesh.isEmpty() || !object.material)
        LUCENT_THROW(ValueError, "the scene has no mesh to edit");
    const TriangleMesh& mesh = object.mesh;
    TriangleMesh edited;
    switch (kind) {
        case MeshEditKind::Decimate:
            if (!(params.decimateFraction > 0.0 && params.decimateFraction < 1.0))
                LUCENT_THROW(ValueError, "decimate: the fraction of triangles kept (",
                             params.decimateFraction, ") must lie in (0, 1)");
            edited = decimate(mesh, std::max<size_t>(4, size_t(params.decimateFraction *
                                                               double(mesh.triangleCount()))));
            break;
        case MeshEditKind::Subdivide:
            edited = subdivideLoop(mesh, params.subdivideIterations);
            break;
        case MeshEditKind::Smooth:
            edited = smoothLaplacian(mesh, params.smoothIterations);
            break;
        case MeshEditKind::FillHoles:
            // Default: holes up to a tenth of the object's diagonal (mm).
            edited = fillHoles(mesh, params.maxHoleMm > 0.0
                                         ? float(params.maxHoleMm)
                                         : 0.1f * glm::length(mesh.bounds().extent()));
            break;
    }
    const GridSpec spec = object.material->spec();
    const Bounds3f grid = spec.bounds(), b = edited.bounds();
    if (!grid.contains(b.lo) || !grid.contains(b.hi))
        LUCENT_THROW(ValueError, "the edited mesh leaves the material grid");
    object.material->setInsideMask(voxelizeSolid(edited, spec));
    object.mesh = std::move(edited);
}

}  // namespace lucent
