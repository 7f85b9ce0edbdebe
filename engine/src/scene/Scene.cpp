// SPDX-License-Identifier: MIT
/// @file
/// @brief Light falloff, camera matrices / primary rays, and objects made from a mesh.

#include <lucent/scene/Scene.h>

#include <lucent/mesh/Voxelize.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>

namespace lucent {

Rgb Light::intensityToward(const Vector3f& towardSurface) const {
    switch (type) {
        case Type::Point:
            return intensity;
        case Type::Spot: {
            // Smoothstep between the outer and inner cone cosines (the spot falloff of pbrt-v4
            // SpotLight::I, lights.cpp: SmoothStep(cosFalloffEnd, cosFalloffStart, cosθ)).
            const float cosTheta = glm::dot(glm::normalize(direction), towardSurface);
            const float cosOuter = std::cos(glm::radians(spotOuterDeg));
            const float cosInner = std::cos(glm::radians(spotInnerDeg));
            if (cosTheta <= cosOuter)
                return Rgb(0.f);
            if (cosTheta >= cosInner || cosInner <= cosOuter)
                return intensity;
            const float t = (cosTheta - cosOuter) / (cosInner - cosOuter);
            return intensity * (t * t * (3.f - 2.f * t));
        }
        case Type::Directional:
        case Type::Sphere:
            break;  // not point-like: no intensity (see Light docs)
    }
    return Rgb(0.f);
}

const char* lightTypeName(Light::Type type) {
    switch (type) {
        case Light::Type::Point:
            return "point";
        case Light::Type::Spot:
            return "spot";
        case Light::Type::Directional:
            return "directional";
        case Light::Type::Sphere:
            return "sphere";
    }
    return "unknown";
}

Mat4f Camera::viewFromWorld() const {
    // Right-handed view space: camera at the origin looking down −z, +y up (OpenGL).
    return glm::lookAtRH(position, target, up);
}

Mat4f Camera::clipFromView() const {
    const float aspect = float(width) / float(height);
    if (orthographic) {
        const float hh = 0.5f * orthoHeight, hw = hh * aspect;
        return glm::orthoRH_NO(-hw, hw, -hh, hh, nearPlane, farPlane);
    }
    return glm::perspectiveRH_NO(glm::radians(fovYDeg), aspect, nearPlane, farPlane);
}

void Camera::generateRay(float px, float py, Point3f& origin, Vector3f& direction) const {
    // Pixel → normalised device coordinates: x right, y up, (0,0) the image's top-left corner.
    const float ndcX = 2.f * px / float(width) - 1.f;
    const float ndcY = 1.f - 2.f * py / float(height);
    const Vector3f forward = glm::normalize(target - position);
    const Vector3f right = glm::normalize(glm::cross(forward, up));
    const Vector3f trueUp = glm::cross(right, forward);
    const float aspect = float(width) / float(height);
    if (orthographic) {
        const float hh = 0.5f * orthoHeight;
        origin = position + right * (ndcX * hh * aspect) + trueUp * (ndcY * hh);
        direction = forward;
        return;
    }
    const float tanHalf = std::tan(0.5f * glm::radians(fovYDeg));
    origin = position;
    direction =
        glm::normalize(forward + right * (ndcX * tanHalf * aspect) + trueUp * (ndcY * tanHalf));
}

SceneObject makeObject(TriangleMesh mesh, int resolution, const MaterialSample& base) {
    const GridSpec spec = GridSpec::around(mesh.bounds(), resolution);
    SceneObject obj;
    obj.material = std::make_shared<MaterialVolume>(spec, base);
    obj.material->setInsideMask(voxelizeSolid(mesh, spec));
    obj.mesh = std::move(mesh);
    obj.materialSource.uniform = true;
    obj.materialSource.value = base;
    obj.materialSource.resolution = resolution;
    return obj;
}

}  // namespace lucent
