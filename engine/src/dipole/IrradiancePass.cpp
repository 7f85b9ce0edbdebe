// SPDX-License-Identifier: MIT
/// @file
/// @brief Camera-view irradiance pass for the image-space dipole (seed 004 §5–6).

#include <lucent/dipole/IrradiancePass.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/reference/MeshBoundary.h>

#include <cmath>

namespace lucent::dipole {

Rgb lightIrradiance(const Light& light, const Point3f& p, const Normal3f& n, float eta) {
    Vector3f toLight;
    Rgb incident(0.f);  // irradiance on a surface facing the light, W/mm²
    if (light.type == Light::Type::Directional) {
        toLight = -glm::normalize(light.direction);
        incident = light.intensity;
    } else {
        const Vector3f d = light.position - p;
        const float dist2 = glm::dot(d, d);
        if (!(dist2 > 0.f))
            return Rgb(0.f);
        toLight = d / std::sqrt(dist2);
        Rgb intensity;  // W/sr
        if (light.type == Light::Type::Sphere)
            intensity = light.intensity * (PI * light.radius * light.radius);
        else
            intensity = light.intensityToward(-toLight);
        incident = intensity / dist2;
    }
    const float cosI = glm::dot(n, toLight);
    if (cosI <= 0.f)
        return Rgb(0.f);
    // Eq. 5: E = L_i F_t(η, ω_i) (N·ω_i), F_t = 1 − F_r for light arriving from outside.
    const float ft = float(1.0 - fresnelReflectance(cosI, eta));
    return incident * (ft * cosI);
}

SurfaceBuffers buildSurfaceBuffers(const Scene& scene, int objectIndex) {
    LUCENT_CHECK(objectIndex >= 0 && objectIndex < int(scene.objects.size()),
                 "buildSurfaceBuffers: scene has no object ", objectIndex);
    const SceneObject& obj = scene.objects[size_t(objectIndex)];
    LUCENT_CHECK(obj.material != nullptr, "buildSurfaceBuffers: object ", objectIndex,
                 " has no material");
    const Camera& cam = scene.camera;
    LUCENT_CHECK(cam.width >= 1 && cam.height >= 1,
                 "buildSurfaceBuffers: camera size must be positive");
    const MeshBoundary boundary(obj.mesh);
    const MaterialVolume& volume = *obj.material;
    const float inset = 0.5f * volume.spec().voxelSize;

    SurfaceBuffers buf;
    buf.resize(cam.width, cam.height);
    buf.clipFromWorld = cam.clipFromView() * cam.viewFromWorld();
    buf.orthographic = cam.orthographic;
    buf.eye = cam.position;
    buf.viewDirection = glm::normalize(cam.target - cam.position);

    parallelFor(0, cam.height, [&](int64_t y0, int64_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < cam.width; ++x) {
                Point3f o;
                Vector3f d;
                cam.generateRay(float(x) + 0.5f, float(y) + 0.5f, o, d);
                const auto hit = boundary.intersect(o, d, 0.f, INF);
                if (!hit || glm::dot(hit->normal, d) >= 0.f)
                    continue;  // miss or back face
                const size_t i = buf.index(x, y);
                const Point3f p = o + hit->t * d;
                const Normal3f n = hit->normal;
                buf.position[i] = p;
                buf.normal[i] = n;
                buf.covered[i] = 1;
                // Material just inside the surface. Voxels cut by the surface may be masked out
                // (their centre lies outside the mesh): step inwards, up to 3 voxels.
                MaterialSample mat;
                for (int step = 1; step <= 6; ++step) {
                    mat = volume.sample(p - float(step) * inset * n);
                    if (mat.sigma_t != Rgb(0.f))
                        break;
                }
                buf.material[i] = mat;
                Rgb e(0.f);
                const Point3f origin = p + boundary.offsetAt(p) * n;
                for (const Light& light : scene.lights) {
                    const Rgb el = lightIrradiance(light, p, n, scene.eta);
                    if (el == Rgb(0.f))
                        continue;
                    // Shadow ray towards the light against the object itself.
                    Vector3f toLight;
                    float tMax = INF;
                    if (light.type == Light::Type::Directional) {
                        toLight = -glm::normalize(light.direction);
                    } else {
                        toLight = light.position - origin;
                        tMax = glm::length(toLight);
                        toLight /= tMax;
                    }
                    if (!boundary.intersect(origin, toLight, 0.f, tMax))
                        e += el;
                }
                buf.irradiance[i] = e;
            }
    });
    return buf;
}

GatherResult renderImageSpaceDipole(const Scene& scene, GatherSettings settings) {
    settings.eta = scene.eta;
    return gatherImageSpace(buildSurfaceBuffers(scene), settings);
}

}  // namespace lucent::dipole
