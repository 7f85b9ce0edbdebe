// SPDX-License-Identifier: MIT
/// @file
/// @brief CPU SSLPV renderer: RSM injection texels, solver driving, ray-cast shading.

#include <lucent/core/Fresnel.h>
#include <lucent/sslpv/SslpvRenderer.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Timer.h>
#include <lucent/material/Resample.h>
#include <lucent/mesh/RayCaster.h>
#include <lucent/mesh/Voxelize.h>

#include <algorithm>
#include <cmath>

namespace lucent::sslpv {
namespace {

/// Orthonormal basis (right, up) of the plane perpendicular to `forward`.
void planeBasis(const Vector3f& forward, Vector3f& right, Vector3f& up) {
    const Vector3f a = std::abs(forward.y) < 0.9f ? Vector3f(0, 1, 0) : Vector3f(1, 0, 0);
    right = glm::normalize(glm::cross(forward, a));
    up = glm::cross(right, forward);
}

/// Perspective RSM from `origin` along `forward` (§3.1): Φ_p = I(ω_p)·Δω_p with Δω_p from
/// rsmTexelSolidAngle (the near-plane-corrected formula of the SSLPV project page errata).
void perspectiveRsm(const RayCaster& mesh, const Light& light, const Point3f& origin,
                    const Vector3f& forward, float tanHalf, int res, const Rgb& scale,
                    std::vector<SslpvInjectionSample>& out) {
    Vector3f right, up;
    planeBasis(forward, right, up);
    std::vector<std::vector<SslpvInjectionSample>> rows(static_cast<size_t>(res));
    parallelFor(
        0, res,
        [&](int64_t b, int64_t e) {
            for (int64_t y = b; y < e; ++y) {
                for (int x = 0; x < res; ++x) {
                    const float u = tanHalf * (2.f * (float(x) + 0.5f) / float(res) - 1.f);
                    const float v = tanHalf * (2.f * (float(y) + 0.5f) / float(res) - 1.f);
                    const Vector3f r = forward + u * right + v * up;  // near plane at 1
                    const float len = glm::length(r);
                    const Vector3f d = r / len;
                    const float cosTheta = 1.f / len;
                    const auto hit = mesh.intersect(origin, d, 0.f, INF);
                    if (!hit)
                        continue;
                    const Rgb I =
                        light.type == Light::Type::Sphere ? scale : light.intensityToward(d);
                    const float dOmega =
                        rsmTexelSolidAngle(tanHalf, /*aspect=*/1.f, res, res, cosTheta);
                    rows[size_t(y)].push_back({hit->position, hit->shadingNormal, d, I * dOmega});
                }
            }
        },
        /*grain=*/4);
    for (auto& r : rows)
        out.insert(out.end(), r.begin(), r.end());
}

std::vector<SslpvInjectionSample> buildRsmSamples(const RayCaster& mesh, const Light& light,
                                                  int res) {
    std::vector<SslpvInjectionSample> out;
    LUCENT_CHECK(isFinite(light.intensity) && light.intensity.x >= 0.f &&
                     light.intensity.y >= 0.f && light.intensity.z >= 0.f,
                 "SSLPV: light intensity must be finite and >= 0");
    const Bounds3f b = mesh.bounds();
    const Point3f centre = b.center();
    const float radius = 0.5f * glm::length(b.extent()) * 1.001f;
    if (light.type == Light::Type::Directional) {
        LUCENT_CHECK(glm::length(light.direction) > 0.f && isFinite(light.direction),
                     "SSLPV: directional light needs a non-zero direction");
        const Vector3f d = glm::normalize(light.direction);
        Vector3f right, up;
        planeBasis(d, right, up);
        const float pitch = 2.f * radius / float(res);
        const Point3f start = centre - 2.f * radius * d;
        // Orthographic RSM: texel area pitch² perpendicular to the light, Φ_p = E·pitch².
        const Rgb flux = light.intensity * (pitch * pitch);
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                const Point3f o = start + ((float(x) + 0.5f) * pitch - radius) * right +
                                  ((float(y) + 0.5f) * pitch - radius) * up;
                if (const auto hit = mesh.intersect(o, d, 0.f, INF))
                    out.push_back({hit->position, hit->shadingNormal, d, flux});
            }
        return out;
    }
    LUCENT_CHECK(isFinite(light.position), "SSLPV: light position is not finite");
    Rgb sphereIntensity(0.f);
    if (light.type == Light::Type::Sphere) {
        LUCENT_CHECK(std::isfinite(light.radius) && light.radius >= 0.f,
                     "SSLPV: sphere light radius must be >= 0 mm");
        sphereIntensity = light.intensity * (PI * light.radius * light.radius);  // L·πr², W/sr
    }
    const Vector3f toCentre = centre - light.position;
    const float dist = glm::length(toCentre);
    if (dist > 1.05f * radius) {
        // One map aimed at the bounding sphere, half-angle asin(R/dist).
        const float sinHalf = radius / dist;
        const float tanHalf = sinHalf / std::sqrt(std::max(1e-12f, 1.f - sinHalf * sinHalf));
        perspectiveRsm(mesh, light, light.position, toCentre / dist, tanHalf, res, sphereIntensity,
                       out);
    } else {
        // Light inside or near the bounding sphere: cube map, six 90° faces.
        const Vector3f axes[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                  {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
        for (const Vector3f& f : axes)
            perspectiveRsm(mesh, light, light.position, f, 1.f, res, sphereIntensity, out);
    }
    return out;
}

}  // namespace

SslpvRenderer::SslpvRenderer(const SslpvRenderOptions& options) {
    setOptions(options);
}
SslpvRenderer::~SslpvRenderer() = default;

void SslpvRenderer::setOptions(const SslpvRenderOptions& o) {
    LUCENT_CHECK(o.gridResolution >= 4 && o.gridResolution <= 256,
                 "SSLPV option 'gridResolution' must be in [4, 256], got ", o.gridResolution);
    LUCENT_CHECK(o.injectionResolution >= 8 && o.injectionResolution <= 4096,
                 "SSLPV option 'injectionResolution' must be in [8, 4096], got ",
                 o.injectionResolution);
    LUCENT_CHECK(std::isfinite(o.specularWeight) && o.specularWeight >= 0.f,
                 "SSLPV option 'specularWeight' must be finite and >= 0");
    LUCENT_CHECK(std::isfinite(o.shininess) && o.shininess >= 1.f && o.shininess <= 1e4f,
                 "SSLPV option 'shininess' must be in [1, 10000]");
    LUCENT_CHECK(isFinite(o.diffuseReflectance) &&
                     glm::all(glm::greaterThanEqual(o.diffuseReflectance, Rgb(0.f))) &&
                     glm::all(glm::lessThanEqual(o.diffuseReflectance, Rgb(1.f))),
                 "SSLPV option 'diffuseReflectance' must be in [0, 1]");
    // Only solver settings trigger re-propagation (shading options do not).
    const SslpvOptions& a = o.solver;
    const SslpvOptions& b = m_solver.options();
    if (a.order != b.order || a.maxSteps != b.maxSteps ||
        a.skipAccumulateSteps != b.skipAccumulateSteps || a.removeExitant != b.removeExitant ||
        a.attenuation != b.attenuation || a.stopEpsilon != b.stopEpsilon ||
        a.brickStopEpsilon != b.brickStopEpsilon || a.skipEmptySlices != b.skipEmptySlices ||
        a.mode != b.mode || a.diffusionExactTotal != b.diffusionExactTotal ||
        a.diffusionSlabTotal != b.diffusionSlabTotal ||
        a.diffusionExitTable != b.diffusionExitTable ||
        a.diffusionSurfaceFlux != b.diffusionSurfaceFlux ||
        a.diffusionEntryDepth != b.diffusionEntryDepth ||
        a.calibration.linear != b.calibration.linear ||
        a.calibration.transport != b.calibration.transport ||
        a.calibration.diffusion != b.calibration.diffusion ||
        a.calibration.perStep != b.calibration.perStep ||
        a.calibration.perStepTransport != b.calibration.perStepTransport ||
        a.calibration.gain[0] != b.calibration.gain[0] ||
        a.calibration.gain[1] != b.calibration.gain[1])
        m_solver.setOptions(a);
    if (o.injectionResolution != m_opt.injectionResolution)
        m_rsmDirty = true;
    if (o.gridResolution != m_opt.gridResolution)
        m_materialDirty = true;
    m_opt = o;
}

void SslpvRenderer::setMesh(const TriangleMesh& mesh) {
    m_rays = std::make_unique<RayCaster>(mesh);
    m_mesh = mesh;
    m_rsmDirty = true;
    m_materialDirty = true;  // the inside mask follows the mesh
}

void SslpvRenderer::setLights(const std::vector<Light>& lights) {
    m_lights = lights;
    m_rsmDirty = true;
}

void SslpvRenderer::setMaterial(const MaterialVolume& volume, float eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.f && eta <= 3.f,
                 "SSLPV: eta must be in [1, 3], got ", eta);
    const Timer t;
    m_coarse = resampleForPropagation(volume, std::min(m_opt.gridResolution, volume.resolution()));
    m_timings.resampleMs = t.elapsedMs();
    m_eta = eta;
    m_hasMaterial = true;
    m_materialDirty = true;
}

std::vector<float> meshInsideFractions(const TriangleMesh& mesh, const GridSpec& spec,
                                       int subdivisions) {
    LUCENT_CHECK(subdivisions >= 1 && subdivisions <= 8,
                 "SSLPV: mesh inside fractions: subdivisions must be in [1, 8], got ",
                 subdivisions);
    GridSpec fine = spec;
    fine.resolution = spec.resolution * subdivisions;
    fine.voxelSize = spec.voxelSize / float(subdivisions);
    const std::vector<uint8_t> inside = voxelizeSolid(mesh, fine);
    std::vector<float> f(spec.voxelCount(), 0.f);
    const float w = 1.f / float(subdivisions * subdivisions * subdivisions);
    for (int z = 0; z < fine.resolution; ++z)
        for (int y = 0; y < fine.resolution; ++y)
            for (int x = 0; x < fine.resolution; ++x)
                if (inside[fine.linearIndex({x, y, z})])
                    f[spec.linearIndex({x / subdivisions, y / subdivisions, z / subdivisions})] +=
                        w;
    return f;
}

void SslpvRenderer::applyInsideMask() {
    // Cells count as inside only as far as the mesh agrees: the painted volume's own mask may
    // be all-inside when no mesh was voxelised into it. The mesh's own fraction per cell
    // (4³ sub-cells) keeps the partial cells the solver's partial sinks need.
    const std::vector<float> inside = meshInsideFractions(m_mesh, m_coarse.spec);
    for (size_t k = 0; k < inside.size(); ++k)
        m_coarse.insideFraction[k] = std::min(m_coarse.insideFraction[k], inside[k]);
}

const SslpvStats& SslpvRenderer::update() {
    LUCENT_CHECK(m_rays != nullptr, "SSLPV renderer: no mesh (call setMesh first)");
    LUCENT_CHECK(m_hasMaterial, "SSLPV renderer: no material (call setMaterial first)");
    if (m_materialDirty) {
        applyInsideMask();
        m_solver.setMaterial(m_coarse, m_eta);
        m_materialDirty = false;
    }
    if (m_rsmDirty) {
        const Timer t;
        std::vector<SslpvInjectionSample> samples;
        for (const Light& l : m_lights) {
            auto s = buildRsmSamples(*m_rays, l, m_opt.injectionResolution);
            samples.insert(samples.end(), s.begin(), s.end());
        }
        m_solver.setInjectionSamples(std::move(samples));
        m_timings.rsmMs = t.elapsedMs();
        m_rsmDirty = false;
    }
    const SslpvStats& st = m_solver.solve();
    if (st.reinjected)
        m_timings.injectMs = st.injectMs;
    if (st.repropagated)
        m_timings.propagateMs = st.propagateMs;
    return st;
}

ImageRgb SslpvRenderer::render(const Camera& camera) {
    LUCENT_CHECK(
        camera.width > 0 && camera.height > 0 && camera.width <= 16384 && camera.height <= 16384,
        "SSLPV render: camera size ", camera.width, "x", camera.height, " is invalid");
    update();
    const Timer timer;
    ImageRgb img(camera.width, camera.height);
    const RayCaster& rays = *m_rays;
    const float eps = 1e-4f * std::max(1.f, glm::length(rays.bounds().extent()));
    const float shininess = m_opt.shininess;
    const float specNorm = (shininess + 8.f) / (8.f * PI);  // energy-normalised Blinn–Phong
    parallelFor(
        0, camera.height,
        [&](int64_t y0, int64_t y1) {
            for (int64_t y = y0; y < y1; ++y)
                for (int x = 0; x < camera.width; ++x) {
                    Point3f o;
                    Vector3f d;
                    camera.generateRay(float(x) + 0.5f, float(y) + 0.5f, o, d);
                    const auto hit = rays.intersect(o, d, 0.f, INF);
                    if (!hit)
                        continue;
                    Normal3f n = hit->shadingNormal;
                    const Vector3f wo = -d;
                    if (glm::dot(n, wo) <= 0.f)
                        n = hit->geometricNormal;
                    const float cosO = glm::dot(n, wo);
                    if (cosO <= 0.f)
                        continue;  // seen from inside: no exterior radiance
                    Rgb L(0.f);
                    if (m_opt.subsurface) {
                        // Eq. 4/7: L_o = T(ω_i, ω_o) L_i with T = 1 − F_r(cos θ_o, η);
                        // calibrated mode also scales by G/η² (SslpvSolver::exitScale), the
                        // diffusion mode by the exact exit-angle distribution.
                        L += m_solver.exitantRadiance(hit->position, n, cosO, wo);
                    }
                    if (m_opt.direct) {
                        const Point3f p = hit->position + eps * hit->geometricNormal;
                        for (const Light& light : m_lights) {
                            Vector3f wl;
                            float dist = INF;
                            Rgb E(0.f);  // irradiance on a surface facing the light, W/mm²
                            if (light.type == Light::Type::Directional) {
                                wl = -glm::normalize(light.direction);
                                E = light.intensity;
                            } else {
                                const Vector3f toL = light.position - p;
                                dist = glm::length(toL);
                                if (!(dist > 0.f))
                                    continue;
                                wl = toL / dist;
                                const Rgb I =
                                    light.type == Light::Type::Sphere
                                        ? light.intensity * (PI * light.radius * light.radius)
                                        : light.intensityToward(-wl);
                                E = I / (dist * dist);
                            }
                            const float cosL = glm::dot(n, wl);
                            if (cosL <= 0.f)
                                continue;
                            if (rays.occluded(p, wl, 0.f, dist * (1.f - 1e-4f)))
                                continue;
                            const Vector3f hv = glm::normalize(wl + wo);
                            const float cosH = std::max(0.f, glm::dot(n, hv));
                            // Fresnel-weighted Blinn–Phong (the paper's "basic Phong" direct
                            // term, §5) plus an optional Lambertian lobe.
                            const float spec = m_opt.specularWeight *
                                               fresnelDielectric(glm::dot(wl, hv), m_eta) *
                                               specNorm * std::pow(cosH, shininess);
                            L += (Rgb(spec) + m_opt.diffuseReflectance * INV_PI) * E * cosL;
                        }
                    }
                    img.at(x, int(y)) = L;
                }
        },
        /*grain=*/4);
    m_timings.shadeMs = timer.elapsedMs();
    return img;
}

ImageRgb renderSslpv(const Scene& scene, const SslpvRenderOptions& options,
                     SslpvRenderTimings* timings, SslpvStats* stats) {
    LUCENT_CHECK(!scene.objects.empty(), "SSLPV render: the scene has no object");
    const SceneObject& obj = scene.objects.front();
    LUCENT_CHECK(obj.material != nullptr, "SSLPV render: the object has no material volume");
    SslpvRenderer r(options);
    r.setMesh(obj.mesh);
    r.setLights(scene.lights);
    r.setMaterial(*obj.material, scene.eta);
    ImageRgb img = r.render(scene.camera);
    if (timings)
        *timings = r.timings();
    if (stats)
        *stats = r.solver().stats();
    return img;
}

}  // namespace lucent::sslpv
