// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/dipole/ImageSpace.h>
#include <lucent/dipole/Sampling.h>

#include "DipoleTestUtil.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

using namespace lucent;
using namespace lucent::dipole;
using namespace lucent::dipole::testutil;

namespace {

constexpr float PIXEL_MM = 0.1f;

/// Plane z = 0 seen straight down by an orthographic (or perspective) camera; pixel (x, y) sees
/// the point ((x + ½ − w/2)·h, (h/2 − y − ½)·h, 0) in the orthographic case.
SurfaceBuffers makePlane(int w, int h, bool perspective,
                         const std::function<MaterialSample(float)>& materialAtX,
                         const std::function<float(float)>& irradianceAtX) {
    SurfaceBuffers b;
    b.resize(w, h);
    const float hw = 0.5f * w * PIXEL_MM, hh = 0.5f * h * PIXEL_MM;
    const float camZ = 20.f;
    const Mat4f view = glm::lookAt(glm::vec3(0, 0, camZ), glm::vec3(0), glm::vec3(0, 1, 0));
    if (perspective) {
        // Frustum whose footprint on z = 0 is the same 2hw × 2hh rectangle.
        const float fovY = 2.f * std::atan(hh / camZ);
        b.clipFromWorld = glm::perspective(fovY, float(w) / float(h), 0.1f, 100.f) * view;
        b.eye = {0, 0, camZ};
    } else {
        b.clipFromWorld = glm::ortho(-hw, hw, -hh, hh, 0.1f, 100.f) * view;
        b.orthographic = true;
        b.viewDirection = {0, 0, -1};
    }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = b.index(x, y);
            const Point3f p((x + 0.5f) * PIXEL_MM - hw, hh - (y + 0.5f) * PIXEL_MM, 0.f);
            b.position[i] = p;
            b.normal[i] = {0, 0, 1};
            b.covered[i] = 1;
            b.material[i] = materialAtX(p.x);
            b.irradiance[i] = Rgb(irradianceAtX(p.x));
        }
    return b;
}

MaterialSample rgbMaterial() {
    MaterialSample m;
    m.sigma_s = Rgb(2.f, 1.f, 0.5f);                 // σs′, mm⁻¹
    m.sigma_t = m.sigma_s + Rgb(0.05f, 0.1f, 0.2f);  // + σa
    return m;
}

}  // namespace

TEST(ImageSpace, UniformIrradianceOnPlaneIsUnbiased) {
    const int W = 160, H = 120;
    for (Model model : {Model::Dipole, Model::BetterDipole}) {
        const SurfaceBuffers b = makePlane(
            W, H, false, [](float) { return rgbMaterial(); }, [](float) { return 1.f; });
        GatherSettings gs;
        gs.model = model;
        gs.importanceSamples = 24;
        gs.uniformSamples = 8;
        const GatherResult g = gatherImageSpace(b, gs);
        const double hw = 0.5 * W * PIXEL_MM, hh = 0.5 * H * PIXEL_MM;
        const Boundary bd = Boundary::of(1.3);
        for (int c = 0; c < 3; ++c) {
            const MaterialSample m = rgbMaterial();
            const DipoleProfile p =
                DipoleProfile::make(model, m.sigma_t[c] - m.sigma_s[c], m.sigma_s[c], bd);
            expectUnbiased(
                g, b, block(W / 2 - 2, H / 2 - 2, 4, 4),
                [&](glm::dvec2 xo, int) { return exactBox(p, xo, -hw, hw, -hh, hh); }, c);
            // Near a corner of the image (2 mm from two edges): the missing surface is excluded.
            expectUnbiased(
                g, b, block(20, 20, 4, 4),
                [&](glm::dvec2 xo, int) { return exactBox(p, xo, -hw, hw, -hh, hh); }, c);
        }
    }
}

TEST(ImageSpace, ShadowEdgeMatchesHalfPlaneIntegral) {
    const int W = 160, H = 100;
    const SurfaceBuffers b = makePlane(
        W, H, false, [](float) { return rgbMaterial(); },
        [](float x) { return x < 0.f ? 1.f : 0.f; });
    GatherSettings gs;
    gs.importanceSamples = 24;
    gs.uniformSamples = 8;
    const GatherResult g = gatherImageSpace(b, gs);
    const double hw = 0.5 * W * PIXEL_MM, hh = 0.5 * H * PIXEL_MM;
    for (int c : {0, 2}) {
        const MaterialSample m = rgbMaterial();
        const DipoleProfile p =
            DipoleProfile::jensen(m.sigma_t[c] - m.sigma_s[c], m.sigma_s[c], 1.3);
        const auto exact = [&](glm::dvec2 xo, int) { return exactBox(p, xo, -hw, 0.0, -hh, hh); };
        // 4×4 blocks (the 16 distinct interleave shifts) starting 0.5 and 10.5 px into the
        // dark side and 8.5 px into the lit side.
        for (int col : {W / 2, W / 2 + 10, W / 2 - 12})
            expectUnbiased(g, b, block(col, H / 2 - 2, 4, 4), exact, c);
    }
}

TEST(ImageSpace, PerPixelMaterialAndFresnelExit) {
    const int W = 200, H = 60;
    MaterialSample a = rgbMaterial(), bm;
    bm.sigma_s = Rgb(0.5f);
    bm.sigma_t = Rgb(1.5f);  // α′ = 1/3
    const SurfaceBuffers b = makePlane(
        W, H, false, [&](float x) { return x < 0.f ? a : bm; }, [](float) { return 1.f; });
    GatherSettings gs;
    gs.importanceSamples = 32;
    gs.uniformSamples = 8;
    const GatherResult g = gatherImageSpace(b, gs);
    const double hw = 0.5 * W * PIXEL_MM, hh = 0.5 * H * PIXEL_MM;
    // Far from the material boundary each side integrates its own profile (§7: the profile is
    // the one at x_o; irradiance is uniform so the neighbour's material does not matter).
    const DipoleProfile pa = DipoleProfile::jensen(0.05, 2.0, 1.3),
                        pb = DipoleProfile::jensen(1.0, 0.5, 1.3);
    expectUnbiased(
        g, b, block(30, H / 2 - 2, 4, 4),
        [&](glm::dvec2 xo, int) { return exactBox(pa, xo, -hw, hw, -hh, hh); }, 0);
    expectUnbiased(
        g, b, block(W - 40, H / 2 - 2, 4, 4),
        [&](glm::dvec2 xo, int) { return exactBox(pb, xo, -hw, hw, -hh, hh); }, 0);
    // Eq. 3 at normal exit: L = (1 − ((η−1)/(η+1))²) B/π.
    const float ft = 1.f - std::pow((1.3f - 1.f) / (1.3f + 1.f), 2.f);
    for (int x : {10, 100, 190}) {
        const Rgb L = g.radiance.at(x, 30), B = g.exitance.at(x, 30);
        EXPECT_NEAR(L.r, ft * B.r / M_PI, 1e-6 * B.r);
    }
}

TEST(ImageSpace, PerspectiveAndJacobianOnAPlane) {
    // A perspective camera sees the same rectangle; on a plane the reconstructed surface point is
    // the tangent-plane point, so the Jacobian is exactly 1 and switching it changes nothing.
    const int W = 120, H = 120;
    const SurfaceBuffers b = makePlane(
        W, H, true, [](float) { return rgbMaterial(); }, [](float) { return 1.f; });
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            Point2f px;
            ASSERT_TRUE(b.project(b.position[b.index(x, y)], px));
            ASSERT_NEAR(px.x, x + 0.5f, 2e-3f);
            ASSERT_NEAR(px.y, y + 0.5f, 2e-3f);
        }
    GatherSettings gs;
    gs.importanceSamples = 16;
    gs.uniformSamples = 4;
    const GatherResult on = gatherImageSpace(b, gs);
    gs.jacobian = false;
    const GatherResult off = gatherImageSpace(b, gs);
    for (int x : {5, 60, 110})
        EXPECT_NEAR(on.exitance.at(x, 60).g, off.exitance.at(x, 60).g,
                    1e-4f * on.exitance.at(x, 60).g);
    const double hw = 0.5 * W * PIXEL_MM;
    const DipoleProfile p = DipoleProfile::jensen(0.1, 1.0, 1.3);
    expectUnbiased(
        on, b, block(W / 2 - 2, H / 2 - 2, 4, 4),
        [&](glm::dvec2 xo, int) { return exactBox(p, xo, -hw, hw, -hw, hw); }, 1);
}

TEST(ImageSpace, BadInputIsAClearError) {
    SurfaceBuffers b = makePlane(
        8, 8, false, [](float) { return rgbMaterial(); }, [](float) { return 1.f; });
    GatherSettings gs;
    gs.model = Model::Directional;
    EXPECT_THROW(gatherImageSpace(b, gs), ValueError);
    gs.model = Model::Dipole;
    gs.eta = 0.5f;
    EXPECT_THROW(gatherImageSpace(b, gs), ValueError);
    gs.eta = 1.3f;
    b.material[3].sigma_s = Rgb(NAN);
    EXPECT_THROW(gatherImageSpace(b, gs), ValueError);
    b.material[3] = rgbMaterial();
    b.irradiance.pop_back();
    EXPECT_THROW(gatherImageSpace(b, gs), ValueError);
    b.irradiance.push_back(Rgb(1.f));
    EXPECT_NO_THROW(gatherImageSpace(b, gs));
    // σt = 0 (no medium) renders black, not NaN.
    for (auto& m : b.material)
        m = MaterialSample{};
    const GatherResult g = gatherImageSpace(b, gs);
    EXPECT_EQ(g.exitance.at(4, 4), Rgb(0.f));
}

TEST(ImageSpace, JacobianOnASphereMatchesSurfaceIntegral) {
    // Sphere of radius 4 mm seen orthographically along −z, 0.04 mm pixels, E = 1 on every
    // visible point. Exact B(x_o) = ∫ R_d(|x − x_o|) dA over the visible hemisphere z > 0
    // (spherical quadrature). At a pixel whose normal is 60° from the view direction the
    // tangent plane and the surface differ; the Eq. 9 Jacobian must restore the surface measure.
    const float rad = 4.f, pix = 0.04f;
    const int W = 220, H = 220;
    SurfaceBuffers b;
    b.resize(W, H);
    const float hw = 0.5f * W * pix;
    b.clipFromWorld = glm::ortho(-hw, hw, -hw, hw, 0.1f, 100.f) *
                      glm::lookAt(glm::vec3(0, 0, 20), glm::vec3(0), glm::vec3(0, 1, 0));
    b.orthographic = true;
    b.viewDirection = {0, 0, -1};
    MaterialSample m;
    m.sigma_s = Rgb(4.f);
    m.sigma_t = Rgb(4.2f);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const float px = (x + 0.5f) * pix - hw, py = hw - (y + 0.5f) * pix;
            const float z2 = rad * rad - px * px - py * py;
            if (z2 <= 0.f)
                continue;
            const size_t i = b.index(x, y);
            b.position[i] = {px, py, std::sqrt(z2)};
            b.normal[i] = b.position[i] / rad;
            b.covered[i] = 1;
            b.material[i] = m;
            b.irradiance[i] = Rgb(1.f);
        }
    const DipoleProfile p = DipoleProfile::jensen(0.2, 4.0, 1.3);
    const auto exactSphere = [&](glm::dvec3 xo) {
        // Midpoint rule in (θ, φ) over the hemisphere; R_d varies on the scale z_r ≈ 0.24 mm,
        // i.e. 0.06 rad of θ: 1600 × 3200 cells resolve it to < 1e-4.
        const int nt = 1600, np = 3200;
        double s = 0.0;
        for (int i = 0; i < nt; ++i) {
            const double th = (i + 0.5) * (M_PI / 2) / nt;
            const double st = std::sin(th), ct = std::cos(th);
            for (int j = 0; j < np; ++j) {
                const double ph = (j + 0.5) * 2 * M_PI / np;
                const glm::dvec3 x(rad * st * std::cos(ph), rad * st * std::sin(ph), rad * ct);
                s += p.Rd(glm::length(x - xo)) * rad * rad * st;
            }
        }
        return s * (M_PI / 2 / nt) * (2 * M_PI / np);
    };
    GatherSettings gs;
    gs.importanceSamples = 48;
    gs.uniformSamples = 16;
    const GatherResult on = gatherImageSpace(b, gs);
    gs.jacobian = false;
    const GatherResult off = gatherImageSpace(b, gs);
    // Pixels around x = 4·sin 60° mm on the y = 0 row (normal 60° from the view direction).
    const int px0 = int((rad * std::sin(M_PI / 3) + hw) / pix) - 2, py0 = H / 2 - 2;
    const Point3f c = b.position[b.index(px0 + 2, py0 + 2)];
    const double exact = exactSphere(glm::dvec3(c));
    double meanOn = 0.0, meanOff = 0.0;
    for (const auto& q : block(px0, py0, 4, 4)) {
        meanOn += on.exitance.at(q.x, q.y).g / 16.0;
        meanOff += off.exitance.at(q.x, q.y).g / 16.0;
    }
    std::printf("sphere at 60 deg: exact %.5f, with Jacobian %.5f, without %.5f\n", exact, meanOn,
                meanOff);
    // Measured: exact 0.4127, with the Jacobian −0.9 %, without −2.0 %. The residual is the
    // method's own approximation (tangent-plane samples, distance through the reconstructed
    // tangent planes, the block spanning ±0.08 mm): 3 % accepts it; leaving the Jacobian out
    // must be strictly worse.
    EXPECT_NEAR(meanOn, exact, 0.03 * exact);
    EXPECT_GT(std::abs(meanOff - exact), std::abs(meanOn - exact));
}

TEST(ImageSpace, LocalRadiusWindowIntegratesOnlyTheDisc) {
    // GatherSettings::maxRadius (the combined mode's local part): for a uniform irradiance the
    // windowed estimator equals ∫₀^maxRadius R_d 2πr dr, within 4 standard errors of the
    // 16 interleave shifts (+1e-3 relative for float positions and the Simpson reference).
    const int W = 160, H = 120;
    const SurfaceBuffers b = makePlane(
        W, H, false, [](float) { return rgbMaterial(); }, [](float) { return 1.f; });
    for (Model model : {Model::Dipole, Model::BetterDipole})
        for (float window : {0.4f, 1.5f}) {
            GatherSettings gs;
            gs.model = model;
            gs.importanceSamples = 24;
            gs.uniformSamples = 8;
            gs.maxRadius = window;
            const GatherResult g = gatherImageSpace(b, gs);
            EXPECT_FLOAT_EQ(float(g.stats.maxRadius), window);  // R′ ≫ 1.5 mm: the window wins
            EXPECT_NEAR(g.stats.epsilon, 0.01, 1e-7);
            EXPECT_EQ(g.stats.pixels, W * H);
            const Boundary bd = Boundary::of(1.3);
            for (int c = 0; c < 3; ++c) {
                const MaterialSample m = rgbMaterial();
                const DipoleProfile p =
                    DipoleProfile::make(model, m.sigma_t[c] - m.sigma_s[c], m.sigma_s[c], bd);
                const double exact = radialIntegral(p, window);
                expectUnbiased(
                    g, b, block(W / 2 - 2, H / 2 - 2, 4, 4), [&](glm::dvec2, int) { return exact; },
                    c);
            }
        }
    GatherSettings bad;
    bad.maxRadius = -1.f;
    EXPECT_THROW(gatherImageSpace(b, bad), ValueError);
}

TEST(ImageSpace, GrazingOwnPixelIntegratesItsFootprint) {
    // Issue 6: see testutil::GrazingPixel (the old look-up fallback gave R_d(0)·strip).
    expectGrazingPixelUnbiased(
        [](const SurfaceBuffers& b, const GatherSettings& gs) { return gatherImageSpace(b, gs); },
        "CPU");
}
