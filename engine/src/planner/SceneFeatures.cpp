// SPDX-License-Identifier: MIT
/// @file
/// @brief Scene features for the Auto planner (SceneFeatures.h has the definitions).

#include <lucent/core/Error.h>
#include <lucent/material/Procedural.h>
#include <lucent/planner/SceneFeatures.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lucent::planner {

namespace {

constexpr double PI_D = 3.14159265358979323846;

/// Irradiance (luminance, W/mm²) the light gives a surface facing it at `p`, and the unit
/// direction from `p` toward the light.
double irradianceAt(const Light& light, const Point3f& p, Vector3f& towardLight) {
    if (light.type == Light::Type::Directional) {
        towardLight = -glm::normalize(light.direction);
        return double(luminance(light.intensity));
    }
    const Vector3f d = light.position - p;
    const double dist2 = std::max(double(glm::dot(d, d)), 1e-12);
    towardLight = glm::normalize(d);
    if (light.type == Light::Type::Sphere)  // a sphere light seen from afar: intensity L·πr²
        return double(luminance(light.intensity)) * PI_D * double(light.radius) *
               double(light.radius) / dist2;
    return double(luminance(light.intensityToward(-towardLight))) / dist2;
}

}  // namespace

SceneFeatures analyzeScene(const Scene& scene) {
    LUCENT_CHECK(!scene.objects.empty() && scene.objects.front().material,
                 "analyzeScene: the scene has no object with a material");
    const SceneObject& object = scene.objects.front();
    const MaterialVolume& volume = *object.material;
    const GridSpec& spec = volume.spec();
    SceneFeatures f;
    f.eta = double(scene.eta);
    f.lights = int(scene.lights.size());
    const Bounds3f bounds = object.mesh.bounds();
    f.sizeMm = double(glm::length(bounds.extent()));

    // Medium statistics over inside voxels (luminance-weighted channels).
    const std::vector<uint8_t>& inside = volume.insideMask();
    double sumT = 0, sumT2 = 0, sumA = 0, sumA2 = 0, sumAbsorb = 0, sumG = 0;
    const int n = spec.resolution;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Coord c(x, y, z);
                if (!inside[spec.linearIndex(c)])
                    continue;
                const MaterialSample s = volume.at(c);
                const double t = double(luminance(s.sigma_t));
                const double sc = double(luminance(s.sigma_s));
                const double a = t > 0 ? sc / t : 0.0;
                sumT += t;
                sumT2 += t * t;
                sumA += a;
                sumA2 += a * a;
                sumAbsorb += std::max(0.0, t - sc);
                sumG += std::abs(double(luminance(s.g)));
                ++f.insideVoxels;
            }
    LUCENT_CHECK(f.insideVoxels > 0, "analyzeScene: the object's volume has no inside voxel");
    const double count = double(f.insideVoxels);
    f.meanSigmaT = sumT / count;
    f.meanFreePathMm = f.meanSigmaT > 0 ? 1.0 / f.meanSigmaT : f.sizeMm;
    f.opticalSize = f.sizeMm / std::max(f.meanFreePathMm, 1e-12);
    f.albedo = sumA / count;
    const double varT = std::max(0.0, sumT2 / count - f.meanSigmaT * f.meanSigmaT);
    f.sigmaTVariation = f.meanSigmaT > 0 ? std::sqrt(varT) / f.meanSigmaT : 0.0;
    f.albedoVariation = std::sqrt(std::max(0.0, sumA2 / count - f.albedo * f.albedo));
    f.meanAbsG = sumG / count;
    const double sigmaA = sumAbsorb / count;
    const double sigmaTr = std::sqrt(3.0 * sigmaA * f.meanSigmaT);
    f.diffusionLengthMm = sigmaTr > 0 ? std::min(1.0 / sigmaTr, f.sizeMm) : f.sizeMm;

    // Thickness: depth of each inside voxel below the surface of the inside mask.
    const std::vector<float> depth = distanceToSurface(volume);
    size_t thin = 0;
    for (size_t i = 0; i < depth.size(); ++i) {
        if (!inside[i])
            continue;
        f.maxDepthMm = std::max(f.maxDepthMm, double(depth[i]));
        thin += double(depth[i]) <= f.diffusionLengthMm ? 1 : 0;
    }
    f.thinFraction = double(thin) / count;

    // Light from behind, as the camera sees the object.
    const Point3f centre = bounds.center();
    const Vector3f towardCamera = glm::normalize(scene.camera.position - centre);
    double total = 0, behind = 0;
    for (const Light& light : scene.lights) {
        Vector3f towardLight;
        const double e = irradianceAt(light, centre, towardLight);
        if (!(e > 0) || !std::isfinite(e))
            continue;
        total += e;
        behind += e * std::max(0.0, -double(glm::dot(towardLight, towardCamera)));
    }
    f.backLitFraction = total > 0 ? behind / total : 0.0;

    const double radius = 0.5 * f.sizeMm;
    f.curvature = radius > 0 ? f.diffusionLengthMm / radius : 0.0;

    // Pixels covered by the projected bounding sphere.
    const Camera& cam = scene.camera;
    double radiusPx = 0;
    if (cam.orthographic) {
        radiusPx = radius / double(cam.orthoHeight) * double(cam.height);
    } else {
        const double dist = std::max(double(glm::length(cam.position - centre)), radius + 1e-6);
        const double halfAngle = std::asin(std::min(1.0, radius / dist));
        const double halfFov = 0.5 * double(cam.fovYDeg) * PI_D / 180.0;
        radiusPx = std::tan(halfAngle) / std::tan(halfFov) * 0.5 * double(cam.height);
    }
    f.imagePixels = double(cam.width) * double(cam.height);
    f.pixelsCovered = std::min(PI_D * radiusPx * radiusPx, f.imagePixels);
    return f;
}

SceneClass classify(const SceneFeatures& f) {
    SceneClass c;
    c.backLit = f.backLitFraction > 0.5;
    c.thinParts = f.thinFraction > 0.25;
    c.heterogeneous = f.sigmaTVariation > 0.1 || f.albedoVariation > 0.05;
    c.dielectric = f.eta > 1.01;
    return c;
}

std::string describe(const SceneClass& c, double eta) {
    std::string s = c.thinParts ? "thin parts" : "thick";
    s += c.backLit ? ", back-lit" : ", front-lit";
    if (c.dielectric && eta > 0) {
        char buf[32];
        std::snprintf(buf, sizeof buf, ", η %.2g", eta);
        s += buf;
    } else {
        s += c.dielectric ? ", dielectric" : ", index-matched";
    }
    s += c.heterogeneous ? ", heterogeneous" : ", homogeneous";
    return s;
}

}  // namespace lucent::planner
