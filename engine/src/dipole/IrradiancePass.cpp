// SPDX-License-Identifier: MIT
/// @file
/// @brief Camera-view irradiance pass for the image-space dipole (Mertens et al. 2005 §5–6).

#include <lucent/core/Fresnel.h>
#include <lucent/dipole/IrradiancePass.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/reference/MeshBoundary.h>

#include <algorithm>
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
    const float ft = float(1.0 - fresnelDielectric(double(cosI), double(eta)));
    return incident * (ft * cosI);
}

MaterialSample materialInside(const MaterialVolume& volume, const Point3f& p, const Normal3f& n) {
    const GridSpec& spec = volume.spec();
    const float inset = 0.5f * spec.voxelSize;
    // Voxels cut by the surface may be masked out (their centre lies outside the mesh): step
    // inwards, up to 3 voxels.
    for (int step = 1; step <= 6; ++step) {
        const MaterialSample mat = volume.sample(p - float(step) * inset * n);
        if (mat.sigma_t != Rgb(0.f))
            return mat;
    }
    // A hole in the mask under the surface: the nearest painted voxel around, shell by shell.
    const Vector3f q = (p - inset * n - spec.origin) / spec.voxelSize;  // voxel units
    const Coord c0(glm::floor(q));
    for (int r = 1; r <= 4; ++r) {
        float best = INF;
        MaterialSample found;
        for (int dz = -r; dz <= r; ++dz)
            for (int dy = -r; dy <= r; ++dy)
                for (int dx = -r; dx <= r; ++dx) {
                    if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r)
                        continue;  // the shell only
                    const Coord c = c0 + Coord(dx, dy, dz);
                    if (!spec.contains(c))
                        continue;
                    const MaterialSample mat = volume.at(c);
                    if (mat.sigma_t == Rgb(0.f))
                        continue;
                    const Vector3f e = Vector3f(c) + Vector3f(0.5f) - q;
                    if (const float d2 = glm::dot(e, e); d2 < best) {
                        best = d2;
                        found = mat;
                    }
                }
        if (best < INF)
            return found;
    }
    return {};
}

namespace {

/// The irradiance pass proper for an arbitrary view `cam` (the scene camera or a light's).
SurfaceBuffers renderView(const Scene& scene, const SceneObject& obj,
                          const reference::MeshBoundary& boundary, const Camera& cam) {
    const MaterialVolume& volume = *obj.material;

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
                buf.material[i] = materialInside(volume, p, n);
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

const SceneObject& checkedObject(const Scene& scene, int objectIndex, const char* who) {
    LUCENT_CHECK(objectIndex >= 0 && objectIndex < int(scene.objects.size()), who,
                 ": scene has no object ", objectIndex);
    const SceneObject& obj = scene.objects[size_t(objectIndex)];
    LUCENT_CHECK(obj.material != nullptr, who, ": object ", objectIndex, " has no material");
    return obj;
}

}  // namespace

Camera lightViewCamera(const Light& light, const Bounds3f& bounds, int resolution) {
    LUCENT_CHECK(resolution >= 16 && resolution <= 4096,
                 "light view: resolution must be in [16, 4096] (got ", resolution, ")");
    const Point3f centre = bounds.center();
    const float radius = std::max(1e-3f, 0.5f * glm::length(bounds.hi - bounds.lo));
    Camera cam;
    cam.width = cam.height = resolution;
    Vector3f forward;
    if (light.type == Light::Type::Directional) {
        forward = glm::normalize(light.direction);
        cam.orthographic = true;
        cam.orthoHeight = 2.f * radius * 1.02f;  // 2 % margin
        cam.position = centre - forward * (2.f * radius);
        cam.nearPlane = 0.5f * radius;
        cam.farPlane = 4.f * radius;
    } else {
        const Vector3f toCentre = centre - light.position;
        const float dist = glm::length(toCentre);
        LUCENT_CHECK(dist > radius * 1.02f,
                     "light view: the light lies inside the object's bounding sphere (distance ",
                     dist, " mm, radius ", radius,
                     " mm); no perspective light view frames the object");
        forward = toCentre / dist;
        cam.position = light.position;
        // Field of view framing the bounding sphere: half-angle asin(radius/dist), 2 % margin.
        cam.fovYDeg = 2.f * std::asin(std::min(0.999f, radius * 1.02f / dist)) * 180.f / PI;
        cam.nearPlane = std::max(1e-3f, 0.5f * (dist - radius));
        cam.farPlane = dist + 2.f * radius;
    }
    cam.target = cam.position + forward;
    // Any up vector not parallel to the view direction.
    cam.up = std::abs(forward.y) < 0.9f ? Vector3f(0.f, 1.f, 0.f) : Vector3f(1.f, 0.f, 0.f);
    return cam;
}

SurfaceBuffers buildSurfaceBuffers(const Scene& scene, int objectIndex) {
    const SceneObject& obj = checkedObject(scene, objectIndex, "buildSurfaceBuffers");
    const Camera& cam = scene.camera;
    LUCENT_CHECK(cam.width >= 1 && cam.height >= 1,
                 "buildSurfaceBuffers: camera size must be positive");
    const reference::MeshBoundary boundary(obj.mesh);
    return renderView(scene, obj, boundary, cam);
}

SurfaceBuffers buildLightViewBuffers(const Scene& scene, int lightIndex, int resolution,
                                     int objectIndex) {
    const SceneObject& obj = checkedObject(scene, objectIndex, "buildLightViewBuffers");
    LUCENT_CHECK(lightIndex >= 0 && lightIndex < int(scene.lights.size()),
                 "buildLightViewBuffers: scene has no light ", lightIndex);
    LUCENT_CHECK(resolution >= 16 && resolution <= 4096,
                 "buildLightViewBuffers: resolution must be in [16, 4096] (got ", resolution, ")");
    const reference::MeshBoundary boundary(obj.mesh);
    const Camera cam =
        lightViewCamera(scene.lights[size_t(lightIndex)], boundary.bounds(), resolution);
    return renderView(scene, obj, boundary, cam);
}

ImageSpaceViews buildImageSpaceViews(const Scene& scene, const GatherSettings& settings,
                                     const LightViewSettings& lv, int objectIndex) {
    LUCENT_CHECK(lv.resolution >= 16 && lv.resolution <= 4096,
                 "LightViewSettings.resolution must be in [16, 4096] (got ", lv.resolution, ")");
    LUCENT_CHECK(lv.threshold >= 0.0 && lv.threshold < 1.0,
                 "LightViewSettings.threshold must be in [0, 1) (got ", lv.threshold, ")");
    const SceneObject& obj = checkedObject(scene, objectIndex, "buildImageSpaceViews");
    LUCENT_CHECK(scene.camera.width >= 1 && scene.camera.height >= 1,
                 "buildImageSpaceViews: camera size must be positive");
    const reference::MeshBoundary boundary(obj.mesh);
    ImageSpaceViews views;
    views.camera = renderView(scene, obj, boundary, scene.camera);
    for (int l = 0; l < int(scene.lights.size()); ++l) {
        LightViewReport rep;
        rep.light = l;
        if (!lv.enabled) {
            rep.note = "light views disabled";
            views.reports.push_back(rep);
            continue;
        }
        Camera cam;
        try {
            cam = lightViewCamera(scene.lights[size_t(l)], boundary.bounds(), lv.resolution);
        } catch (const ValueError& e) {
            rep.note = e.what();
            views.reports.push_back(rep);
            continue;
        }
        SurfaceBuffers view = renderView(scene, obj, boundary, cam);
        rep.built = true;
        rep.backlitFraction = backlitFluxFraction(views.camera, view, settings);
        rep.used = lv.gatherAll || rep.backlitFraction > lv.threshold;
        if (rep.used)
            views.lights.push_back(std::move(view));
        views.reports.push_back(rep);
    }
    return views;
}

GatherResult renderImageSpaceDipole(const Scene& scene, GatherSettings settings,
                                    const LightViewSettings& lightViews,
                                    std::vector<LightViewReport>* reports) {
    settings.eta = scene.eta;
    const ImageSpaceViews views = buildImageSpaceViews(scene, settings, lightViews);
    if (reports)
        *reports = views.reports;
    return gatherImageSpace(views.camera, views.lights, settings);
}

}  // namespace lucent::dipole
