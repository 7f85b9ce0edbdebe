// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Exact reference integrals and unbiasedness checks shared by the dipole image tests,
/// and the headless-GL fixture of the two GL providers' tests.

#include "GlTestContext.h"

#include <lucent/core/Image.h>
#include <lucent/dipole/ImageSpace.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/scene/Scene.h>

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace lucent::dipole::testutil {

/// ∫₀^R R_d(r) 2πr dr by Simpson in r = R u² (dense near the peak).
inline double radialIntegral(const DipoleProfile& p, double R) {
    if (!(R > 0.0))
        return 0.0;
    const int n = 200;
    double s = 0.0;
    for (int i = 0; i <= n; ++i) {
        const double u = double(i) / n, r = R * u * u;
        const double f = p.Rd(r) * 2 * M_PI * r * 2 * R * u;
        s += f * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    return s / (3.0 * n);
}

/// Exact B(x_o) = ∫ R_d E dA for E = 1 on the box [x0,x1]×[y0,y1] (0 elsewhere): polar rays
/// from x_o, each meets the convex box in one interval [t0, t1].
inline double exactBox(const DipoleProfile& p, glm::dvec2 xo, double x0, double x1, double y0,
                       double y1) {
    const int rays = 2000;
    double sum = 0.0;
    for (int k = 0; k < rays; ++k) {
        const double phi = 2 * M_PI * (k + 0.5) / rays;
        const glm::dvec2 d(std::cos(phi), std::sin(phi));
        double t0 = 0.0, t1 = 1e30;
        const double lo[2] = {x0, y0}, hi[2] = {x1, y1};
        for (int a = 0; a < 2; ++a) {
            if (std::abs(d[a]) < 1e-15) {
                if (xo[a] < lo[a] || xo[a] > hi[a])
                    t1 = -1.0;
                continue;
            }
            double ta = (lo[a] - xo[a]) / d[a], tb = (hi[a] - xo[a]) / d[a];
            if (ta > tb)
                std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        if (t1 > t0)
            sum += radialIntegral(p, t1) - radialIntegral(p, t0);
    }
    return sum / rays;  // (1/2π)∫dφ ∫ R_d 2πr dr
}

/// Compares the gathered exitance of channel c over a set of pixels with the exact value:
/// the mean difference must be within 4 standard errors of the per-pixel spread (the pixels
/// use distinct interleaved shifts), plus 1e-3 relative for float positions and quadrature.
inline void expectUnbiased(const GatherResult& g, const SurfaceBuffers& b,
                           const std::vector<glm::ivec2>& pixels,
                           const std::function<double(glm::dvec2, int)>& exact, int c) {
    double sum = 0.0, sum2 = 0.0, ref = 0.0;
    for (const auto& px : pixels) {
        const Point3f p = b.position[b.index(px.x, px.y)];
        const double e = exact({p.x, p.y}, c);
        const double d = double(g.exitance.at(px.x, px.y)[c]) - e;
        sum += d;
        sum2 += d * d;
        ref += e;
    }
    const double n = double(pixels.size()), mean = sum / n;
    const double se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
    EXPECT_NEAR(mean, 0.0, 4 * se + 1e-3 * ref / n) << "channel " << c << " ref " << ref / n;
}

inline std::vector<glm::ivec2> block(int x0, int y0, int w, int h) {
    std::vector<glm::ivec2> v;
    for (int y = y0; y < y0 + h; ++y)
        for (int x = x0; x < x0 + w; ++x)
            v.push_back({x, y});
    return v;
}

/// A skin-like medium: σs′ = 1.2, 1.6, 2.0 mm⁻¹, σa = 0.02, 0.08, 0.2 mm⁻¹ (σt = σs′ + σa).
inline MaterialSample skinMaterial() {
    MaterialSample m;
    m.sigma_s = Rgb(1.2f, 1.6f, 2.0f);
    m.sigma_t = m.sigma_s + Rgb(0.02f, 0.08f, 0.2f);
    return m;
}

/// A 10 mm sphere (makeSphere(10, subdivisions)) of skinMaterial() on a 32³ grid, lit by a point
/// light of 1000 W/sr at (25, 20, 25) mm, seen by the default perspective camera from
/// (0, 0, 40) mm at w×h pixels.
inline Scene pointLitSphere(int subdivisions, int w, int h) {
    Scene s;
    SceneObject obj;
    obj.mesh = makeSphere(10.f, subdivisions);
    obj.material =
        std::make_shared<MaterialVolume>(GridSpec::around(obj.mesh.bounds(), 32), skinMaterial());
    s.objects.push_back(std::move(obj));
    Light l;
    l.position = {25.f, 20.f, 25.f};
    l.intensity = Rgb(1000.f);
    s.lights.push_back(l);
    s.camera.position = {0.f, 0.f, 40.f};
    s.camera.width = w;
    s.camera.height = h;
    return s;
}

/// How boxScene() lays out its box, light and camera.
struct BoxLayout {
    Vector3f size;                            ///< box extent, mm, centred at the origin
    int grid = 32;                            ///< volume cells along the box's longest axis
    Vector3f lightDirection{0.f, 0.f, -1.f};  ///< directional light of 1 W/mm², travel direction
    float cameraHeight = 50.f;                ///< mm above the origin on +z, looking down −z
    float viewHeight = 10.f;                  ///< orthographic view height, mm
    int pixels = 100;                         ///< square image, pixels per side
};

/// A box of material `m` (GridSpec::around its bounds), one directional light and an
/// orthographic camera looking straight down at its +z face: the slab scenes of the
/// irradiance, light-view, provider and combined tests (η left at the Scene default).
inline Scene boxScene(const MaterialSample& m, const BoxLayout& b) {
    Scene s;
    SceneObject obj;
    obj.mesh = makeBox(b.size);
    obj.material = std::make_shared<MaterialVolume>(GridSpec::around(obj.mesh.bounds(), b.grid), m);
    s.objects.push_back(std::move(obj));
    Light l;
    l.type = Light::Type::Directional;
    l.direction = b.lightDirection;
    l.intensity = Rgb(1.f);
    s.lights.push_back(l);
    s.camera.position = {0.f, 0.f, b.cameraHeight};
    s.camera.target = {0.f, 0.f, 0.f};
    s.camera.orthographic = true;
    s.camera.orthoHeight = b.viewHeight;
    s.camera.width = b.pixels;
    s.camera.height = b.pixels;
    return s;
}

/// Headless context + gpu::SceneRenderer + one subsurface provider (DipoleSubsurfaceProvider
/// or DirpoleSubsurfaceProvider) for one scene: every test skips cleanly without EGL and fails
/// on any GL error the debug log recorded.
template <class Provider, class Settings>
class GlProviderFixture : public ::testing::Test {
protected:
    void SetUp() override {
        std::string reason;
        ctx = ::lucent::test::ownGlContext(reason);
        if (!ctx)
            GTEST_SKIP() << "no headless GL: " << reason;
        renderer.create();
        provider.create();
    }
    void TearDown() override {
        if (!ctx)
            return;
        renderer.setSubsurfaceProvider(nullptr);
        provider.destroy();
        renderer.destroy();
        for (const std::string& e : ctx->debugLog().takeErrors())
            ADD_FAILURE() << e;  // no GL errors in any test
    }
    /// objects[0]'s mesh, the scene's lights and camera, the subsurface term only; then the
    /// provider with `settings` (settings.meshId = the mesh's id when `ownMeshId`) and
    /// objects[0]'s material. @return the mesh id.
    int loadScene(const Scene& s, Settings settings, bool ownMeshId) {
        const int id = renderer.addMesh(s.objects[0].mesh);
        renderer.setLights(s.lights);
        renderer.setCamera(s.camera);
        gpu::DirectSettings direct;
        direct.subsurfaceOnly = true;
        renderer.setSettings(direct);
        if (ownMeshId)
            settings.meshId = id;
        provider.setSettings(settings);
        provider.setMaterial(s.objects[0].material.get());
        renderer.setSubsurfaceProvider(&provider);
        return id;
    }
    /// Renders until the provider converges (at most `limit` frames).
    void renderUntilConverged(int limit) {
        for (int i = 0; i < limit && !provider.stats().converged; ++i)
            renderer.render();
    }

    std::unique_ptr<gpu::GlContext> ctx;
    gpu::SceneRenderer renderer;
    Provider provider;
};

/// Issue 6 (an edge pixel 9× the reference in the windowed gather): a pixel seen at grazing
/// incidence (cos α = 0.05 < the look-up's 0.1 fallback) covers a strip h × h/cos α of its own
/// tangent plane. A sample p′ landing in x_o's own pixel lies on that pixel's tangent plane, so
/// the eye ray through p′ meets it at p′ (r = r′); the old fallback took the pixel's point,
/// r = 0, and weighted R_d(0) over the whole strip. One covered pixel (1×1 image, orthographic,
/// plane z = 0, material rgbMaterial-like, uniform E = 1): the estimator's expectation is exactly
///   B = ∫_{|x| ≤ h/2, |y| ≤ h/(2 cos α), r ≤ window} R_d(r) dA   (Mertens et al. 2005 Eq. 4, J =
///   1).
struct GrazingPixel {
    static constexpr float H = 0.1f, COS_A = 0.05f, WINDOW = 1.5f;  // mm, -, mm

    static MaterialSample material() {
        MaterialSample m;
        m.sigma_s = Rgb(2.f, 1.f, 0.5f);                 // σs′, mm⁻¹
        m.sigma_t = m.sigma_s + Rgb(0.05f, 0.1f, 0.2f);  // + σa
        return m;
    }

    static SurfaceBuffers buffers() {
        const float sinA = std::sqrt(1.f - COS_A * COS_A);
        SurfaceBuffers b;
        b.resize(1, 1);
        const glm::vec3 eye = 20.f * glm::vec3(0.f, -sinA, COS_A);  // looks along (0, sin, −cos)
        b.clipFromWorld = glm::ortho(-0.5f * H, 0.5f * H, -0.5f * H, 0.5f * H, 0.1f, 100.f) *
                          glm::lookAt(eye, glm::vec3(0.f), glm::vec3(0.f, 0.f, 1.f));
        b.orthographic = true;
        b.viewDirection = -glm::normalize(eye);
        b.position[0] = Point3f(0.f);
        b.normal[0] = {0.f, 0.f, 1.f};
        b.covered[0] = 1;
        b.material[0] = material();
        b.irradiance[0] = Rgb(1.f);
        return b;
    }

    /// The exact B of channel c: the camera's up vector on the plane is (0, cos α, sin α), so
    /// image v = y cos α, u = x; midpoint rule on a 64 × 4096 grid over the strip (cells
    /// 1.6e-3 × 4.9e-4 mm ≪ z_r ≥ 0.49 mm).
    static double exact(int c) {
        const MaterialSample m = material();
        const DipoleProfile p = DipoleProfile::make(Model::Dipole, m.sigma_t[c] - m.sigma_s[c],
                                                    m.sigma_s[c], Boundary::of(1.3));
        const double halfX = 0.5 * H, halfY = 0.5 * H / COS_A;
        const int nx = 64, ny = 4096;
        const double dx = 2.0 * halfX / nx, dy = 2.0 * halfY / ny;
        double sum = 0.0;
        for (int i = 0; i < nx; ++i)
            for (int j = 0; j < ny; ++j) {
                const double r = std::hypot(-halfX + (i + 0.5) * dx, -halfY + (j + 0.5) * dy);
                if (r <= WINDOW)
                    sum += p.Rd(r) * dx * dy;
            }
        return sum;
    }
};

/// Runs `gather` on GrazingPixel with 32 seeds (independent shift tables: 32 independent
/// estimates of 1536 + 512 samples, of which only the strip's ≈ 6 % count) and expects their
/// mean within 4 standard errors + 1e-3 relative (float positions, midpoint reference) of the
/// exact B, per channel (as expectUnbiased).
inline void expectGrazingPixelUnbiased(
    const std::function<GatherResult(const SurfaceBuffers&, const GatherSettings&)>& gather,
    const char* what) {
    const SurfaceBuffers b = GrazingPixel::buffers();
    const int seeds = 32;
    std::array<double, 3> sum{}, sum2{};
    for (int s = 1; s <= seeds; ++s) {
        GatherSettings gs;
        gs.model = Model::Dipole;
        gs.importanceSamples = 1536;
        gs.uniformSamples = 512;
        gs.maxRadius = GrazingPixel::WINDOW;
        gs.seed = uint32_t(s);
        const Rgb v = gather(b, gs).exitance.at(0, 0);
        for (int c = 0; c < 3; ++c) {
            sum[size_t(c)] += v[c];
            sum2[size_t(c)] += double(v[c]) * v[c];
        }
    }
    for (int c = 0; c < 3; ++c) {
        const double mean = sum[size_t(c)] / seeds, exact = GrazingPixel::exact(c);
        const double se =
            std::sqrt(std::max(0.0, sum2[size_t(c)] / seeds - mean * mean) / (seeds - 1));
        std::printf("%s grazing pixel, channel %d: gathered %.5g +- %.2g, exact %.5g\n", what, c,
                    mean, se, exact);
        EXPECT_NEAR(mean, exact, 4.0 * se + 1e-3 * exact) << what << " channel " << c;
    }
}

}  // namespace lucent::dipole::testutil
