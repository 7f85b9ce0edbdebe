// SPDX-License-Identifier: MIT
/// @file
/// @brief SslpvSubsurfaceProvider: same grid as the CPU SslpvRenderer, per-pixel GL radiance
/// against the CPU formula and the CPU image, incremental painting, and the GL backend.
#include <lucent/core/Fresnel.h>
#include <lucent/sslpv/SslpvProvider.h>

#include <lucent/core/Error.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/material/Brush.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/mesh/Voxelize.h>

#include "GlTestContext.h"
#include "ImageTestUtil.h"
#include "SslpvTestGrids.h"

#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

using namespace lucent;
using namespace lucent::sslpv;

namespace {

constexpr float RADIUS = 10.f;  // mm
constexpr int PIXELS = 64;

struct TestScene {
    TriangleMesh mesh;
    MaterialVolume volume;
    std::vector<Light> lights;
    Camera camera;
    float eta = 1.3f;
};

enum class Shape {
    Ball,       ///< makeSphere(RADIUS)
    ThinThick,  ///< makeThinThick, 20 mm high: its fins are under 1.3 mm thick, under a cell
};

/// A 10 mm ball (or the thin-thick shape) of skim-milk-like material in a 48³ volume with one
/// painted denser stroke (heterogeneous), lit by a point light from the upper left.
TestScene makeScene(Shape shape = Shape::Ball) {
    TestScene s;
    s.mesh = shape == Shape::Ball ? makeSphere(RADIUS, 4) : makeThinThick(2.f * RADIUS);
    const GridSpec spec = GridSpec::around(s.mesh.bounds(), 48);
    s.volume = MaterialVolume(spec, {Rgb(1.2f, 1.3f, 1.5f), Rgb(1.1f, 1.15f, 1.2f), Rgb(0.f)});
    s.volume.setInsideMask(voxelizeSolid(s.mesh, spec));
    BrushSettings brush;
    brush.radius = 4.f;
    brush.value = {Rgb(3.f, 2.f, 1.f), Rgb(1.f, 1.5f, 0.5f), Rgb(0.3f)};
    paintStroke(s.volume, brush, {Point3f(-6, 2, 5), Point3f(4, -3, 6)});
    (void)s.volume.takeDirtyBricks();
    Light bulb;
    bulb.type = Light::Type::Point;
    bulb.position = Point3f(-30, 30, 20);
    bulb.intensity = Rgb(4000.f);
    s.lights = {bulb};
    s.camera.position = Point3f(0, 0, 60);
    s.camera.target = Point3f(0, 0, 0);
    s.camera.width = s.camera.height = PIXELS;
    s.camera.fovYDeg = 25.f;
    return s;
}

SslpvProviderOptions providerOptions(SslpvMode mode = SslpvMode::Paper, int grid = 16) {
    SslpvProviderOptions o;
    o.render.solver.mode = mode;
    o.render.gridResolution = grid;
    o.render.injectionResolution = 64;
    o.render.solver.maxSteps = 16;
    if (mode == SslpvMode::Diffusion) {  // CG iterations to convergence, as the method runs it
        o.render.solver.maxSteps = 1024;
        o.render.solver.stopEpsilon = 1e-3f;
    }
    o.render.subsurface = true;
    o.render.direct = false;
    return o;
}

void setUp(SslpvSubsurfaceProvider& p, const TestScene& s) {
    p.setMesh(s.mesh);
    p.setLights(s.lights);
    p.setMaterial(s.volume, s.eta);
}

class SslpvProviderGl : public ::testing::Test {
protected:
    void SetUp() override {
        std::string reason;
        m_ctx = test::ownGlContext(reason);
        if (!m_ctx)
            GTEST_SKIP() << "no headless OpenGL 4.5 context: " << reason;
        m_renderer.create();
        gpu::DirectSettings ds;
        ds.shadows = false;
        ds.subsurfaceOnly = true;  // the radiance target then holds the provider's term alone
        m_renderer.setSettings(ds);
    }
    void TearDown() override {
        if (m_renderer.isCreated()) {
            m_renderer.setSubsurfaceProvider(nullptr);
            m_renderer.destroy();
        }
    }
    /// Renders one frame of `s` with provider `p` and returns the subsurface term.
    ImageRgb render(SslpvSubsurfaceProvider& p, const TestScene& s) {
        m_renderer.clearMeshes();
        m_renderer.addMesh(s.mesh);
        m_renderer.setLights(s.lights);
        m_renderer.setCamera(s.camera);
        m_renderer.setSubsurfaceProvider(&p);
        m_renderer.render();
        return m_renderer.readRadiance();
    }
    /// One RGBA32F G-buffer texture, top row first.
    std::vector<glm::vec4> readTexture(unsigned tex, int w, int h) const {
        std::vector<glm::vec4> gl(size_t(w) * h), out(size_t(w) * h);
        glGetTextureImage(tex, 0, GL_RGBA, GL_FLOAT, GLsizei(gl.size() * sizeof(glm::vec4)),
                          gl.data());
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                out[size_t(y) * w + x] = gl[size_t(h - 1 - y) * w + x];
        return out;
    }
    std::unique_ptr<gpu::GlContext> m_ctx;
    gpu::SceneRenderer m_renderer;
};

}  // namespace

TEST(SslpvProvider, SolvesTheSameGridAsTheCpuRenderer) {
    const TestScene s = makeScene();
    SslpvSubsurfaceProvider p(providerOptions());
    setUp(p, s);
    const SslpvStats st = p.update();
    SslpvRenderer r(providerOptions().render);
    r.setMesh(s.mesh);
    r.setLights(s.lights);
    r.setMaterial(s.volume, s.eta);
    const SslpvStats rs = r.update();
    // Same resample, inside mask, RSM texels and solver: identical inputs, identical grids.
    EXPECT_EQ(st.injectedTexels, rs.injectedTexels);
    EXPECT_GT(st.injectedTexels, 100);
    EXPECT_EQ(p.solver().accumulation().raw(), r.solver().accumulation().raw());
    EXPECT_GT(p.solver().accumulation().maxAbs(), 0.f);
}

// A new grid resolution needs the material again (the app kept rendering without it and every
// frame failed with "no material"): hasMaterial() tells the caller, and a setMaterial() at the
// new resolution solves the same grid as a provider made with it.
TEST(SslpvProvider, NewGridResolutionAsksForTheMaterialAgain) {
    const TestScene s = makeScene();
    SslpvSubsurfaceProvider p(providerOptions());
    EXPECT_FALSE(p.hasMaterial());
    setUp(p, s);
    EXPECT_TRUE(p.hasMaterial());
    (void)p.update();
    SslpvProviderOptions finer = providerOptions();
    finer.render.gridResolution = 32;
    p.setOptions(finer);
    EXPECT_FALSE(p.hasMaterial());
    EXPECT_THROW(p.update(), ValueError);
    p.setMaterial(s.volume, s.eta);
    ASSERT_TRUE(p.hasMaterial());
    SslpvProviderOptions fewerSteps = finer;
    fewerSteps.render.solver.maxSteps = 8;
    p.setOptions(fewerSteps);  // other options keep the material
    EXPECT_TRUE(p.hasMaterial());
    p.setOptions(finer);
    ASSERT_TRUE(p.hasMaterial());
    (void)p.update();
    SslpvSubsurfaceProvider fresh(finer);
    setUp(fresh, s);
    (void)fresh.update();
    EXPECT_EQ(p.solver().accumulation().raw(), fresh.solver().accumulation().raw());
}

// Live refinement (SslpvProviderOptions::refineSteps): a change's frame runs `maxSteps` steps;
// while light is in flight each idle frame carries the propagation on by as many, and once
// refined the grid is bit for bit the solve of the whole step count at once. A stroke starts
// again from its own first frame.
TEST(SslpvProvider, IdleFramesCarryTheStrokesPropagationOnToTheLongerSolve) {
    TestScene s = makeScene();
    s.volume = MaterialVolume(s.volume.spec(),  // a bright medium: light travels for long
                              {Rgb(1.f), Rgb(0.995f, 0.99f, 0.98f), Rgb(0.f)});
    s.volume.setInsideMask(voxelizeSolid(s.mesh, s.volume.spec()));
    SslpvProviderOptions o = providerOptions(SslpvMode::Calibrated);
    o.render.solver.maxSteps = 32;
    o.render.solver.brickStopEpsilon = 1e-4f;  // the live defaults
    o.refineSteps = 1024;
    SslpvSubsurfaceProvider p(o);
    setUp(p, s);
    (void)p.update();
    EXPECT_EQ(p.solver().stats().stepsUsed, 32);
    EXPECT_FALSE(p.converged());
    int frames = 0;
    while (p.refine())
        ASSERT_LT(++frames, 100);
    EXPECT_TRUE(p.converged());
    EXPECT_FALSE(p.refine());
    const int steps = p.solver().stats().stepsUsed;
    EXPECT_GT(steps, 64) << "the bright ball keeps light in flight beyond two frames";
    EXPECT_LT(steps, 1024) << "the per-brick stop ends it";
    EXPECT_EQ(frames, (steps - 32 + 31) / 32);
    EXPECT_EQ(p.stats().refinements, frames);
    EXPECT_EQ(p.stats().solves, 1);

    SslpvProviderOptions once = o;
    once.render.solver.maxSteps = 1024;
    once.refineSteps = 0;
    SslpvSubsurfaceProvider whole(once);
    setUp(whole, s);
    (void)whole.update();
    EXPECT_TRUE(whole.converged());
    EXPECT_EQ(whole.solver().stats().stepsUsed, steps);
    EXPECT_EQ(p.solver().accumulation().raw(), whole.solver().accumulation().raw());

    // A stroke: its frame runs 32 steps again, then the idle frames carry it on.
    BrushSettings brush;
    brush.radius = 3.f;
    brush.value = {Rgb(2.f), Rgb(0.5f), Rgb(0.f)};
    paintStroke(s.volume, brush, {Point3f(0, 0, 9), Point3f(3, 0, 8)});
    p.updateMaterial(s.volume, s.volume.takeDirtyBricks());
    EXPECT_FALSE(p.refine()) << "a change is solved first, by update()";
    (void)p.update();
    EXPECT_EQ(p.solver().stats().stepsUsed, 32);
    EXPECT_FALSE(p.converged());
    while (p.refine()) {
    }
    EXPECT_TRUE(p.converged());

    // Off: a change's frame is the last.
    o.refineSteps = 0;
    SslpvSubsurfaceProvider off(o);
    setUp(off, s);
    (void)off.update();
    EXPECT_TRUE(off.converged());
    EXPECT_FALSE(off.refine());
    EXPECT_EQ(off.solver().stats().stepsUsed, 32);
    o.refineSteps = 5000;
    EXPECT_THROW(SslpvSubsurfaceProvider{o}, ValueError);
}

TEST(SslpvProvider, RejectsBadInput) {
    SslpvProviderOptions o = providerOptions();
    o.meshId = -2;
    EXPECT_THROW(SslpvSubsurfaceProvider{o}, ValueError);
    o = providerOptions();
    o.render.gridResolution = 2;
    EXPECT_THROW(SslpvSubsurfaceProvider{o}, ValueError);
    SslpvSubsurfaceProvider p(providerOptions());
    EXPECT_THROW(p.update(), ValueError);  // no mesh, no material
    const TestScene s = makeScene();
    EXPECT_THROW(p.setMaterial(s.volume, 0.5f), ValueError);
    EXPECT_THROW(p.setObjectFromWorld(Mat4f(0.f)), ValueError);
}

TEST_F(SslpvProviderGl, PixelsMatchCpuFormulaAndCpuImage) {
    // Mode diffusion too: its accumulation grid goes through the same upload and shader, with
    // only boundary cells readable (SslpvSolver::isReadable, the texture's alpha). The
    // thin-thick shape (grid 32, 0.74 mm cells) thins from 1.3 mm to nothing toward its fins'
    // rims, where no cell is half inside: both read-outs take those from their neighbours
    // (SslpvSolver::thinPartCoefficients). Without that 172 of its 2344 covered pixels were
    // black; now only the fins' last tips are (8 pixels), where the 48³ volume has no inside
    // voxel in any of the eight cells around the read-out's point: no material to read.
    for (const auto& [mode, shape] :
         {std::pair{SslpvMode::Paper, Shape::Ball}, std::pair{SslpvMode::Calibrated, Shape::Ball},
          std::pair{SslpvMode::Diffusion, Shape::Ball},
          std::pair{SslpvMode::Paper, Shape::ThinThick},
          std::pair{SslpvMode::Diffusion, Shape::ThinThick}}) {
        SCOPED_TRACE(std::string(mode == SslpvMode::Paper        ? "paper"
                                 : mode == SslpvMode::Calibrated ? "calibrated"
                                                                 : "diffusion") +
                     (shape == Shape::Ball ? ", ball" : ", thin-thick"));
        const TestScene s = makeScene(shape);
        const int grid = shape == Shape::Ball ? 16 : 32;
        SslpvSubsurfaceProvider p(providerOptions(mode, grid));
        p.create();
        setUp(p, s);
        const ImageRgb gl = render(p, s);
        const float peak = test::largestValue(gl);
        ASSERT_GT(peak, 0.f);

        // (1) The CPU formula (SslpvSolver::exitantRadiance: radiance, Fresnel T and in mode
        // diffusion the exit-angle table and the surface flux's term, as SslpvRenderer) evaluated
        // at the G-buffer's own positions and normals. Differences are float rounding only: u = (p
        // − dΔx n − o)/Δx is off by a few ulp of 16 (≈ 1e-5 in the trilinear weights) and the
        // weighted sums by ~1e-6 relative; the largest coefficient gradient of this grid is under
        // 10× the local value per cell, so |ΔL| ≲ 1e-4·|L| + 1e-6·peak.
        const gpu::GBufferView g = m_renderer.gbuffer();
        const auto pos = readTexture(g.positionTexture, g.width, g.height);
        const auto nrm = readTexture(g.normalTexture, g.width, g.height);
        int covered = 0, black = 0;
        double worst = 0.0;
        for (int y = 0; y < PIXELS; ++y)
            for (int x = 0; x < PIXELS; ++x) {
                const glm::vec4 P = pos[size_t(y) * PIXELS + x];
                Rgb expected(0.f);
                if (P.w > 0.5f) {
                    const Normal3f n = glm::normalize(Vector3f(nrm[size_t(y) * PIXELS + x]));
                    const Vector3f wo = glm::normalize(s.camera.position - Point3f(P));
                    const float cosO = glm::dot(n, wo);
                    if (cosO > 0.f) {
                        ++covered;
                        expected = p.solver().exitantRadiance(Point3f(P), n, cosO, wo);
                        if (expected == Rgb(0.f) && shape == Shape::ThinThick) {
                            ++black;
                            const GridSpec& grid = p.solver().spec();
                            const Vector3f u =
                                (Point3f(P) - 0.5f * grid.voxelSize * n - grid.origin) /
                                    grid.voxelSize -
                                Vector3f(0.5f);
                            const Coord i0(glm::floor(u));
                            for (int k = 0; k < 8; ++k)
                                EXPECT_EQ(p.solver().readoutAlpha(
                                              i0 + Coord(k & 1, (k >> 1) & 1, (k >> 2) & 1)),
                                          0.f)
                                    << "black pixel " << x << "," << y << " with material";
                        }
                    }
                }
                for (int c = 0; c < 3; ++c) {
                    const float d = std::abs(gl.at(x, y)[c] - expected[c]);
                    worst = std::max(worst, double(d) / double(peak));
                    ASSERT_LE(d, 1e-4f * std::abs(expected[c]) + 1e-6f * peak)
                        << "pixel " << x << "," << y << " channel " << c;
                }
            }
        EXPECT_GT(covered, PIXELS * PIXELS / 4);
        EXPECT_LE(black, covered / 100);
        std::printf(
            "[sslpv provider] GL vs CPU formula at G-buffer samples: max |diff| = %.2e peak\n",
            worst);

        // (2) Against the CPU SslpvRenderer's image (ray cast, subsurface term only). Raster and
        // ray hits lie on the same triangles; they differ by the precision of the hardware's
        // attribute interpolation, which GL leaves to the implementation: llvmpipe matches to
        // ~1e-6 of the scene size, an NVIDIA H100 to ~1e-4 (measured). A position error ε
        // changes the trilinearly blended grid radiance by at most |L|·ε/h (h = cell size =
        // extent/32), so ε = 1e-4·extent gives 3.2e-3·|L|; bound 4e-3·|L| + 1e-5·peak. Pixels
        // at the silhouette are skipped (coverage differs there: pixel centre vs ray).
        SslpvRenderer cpu(providerOptions(mode, grid).render);
        cpu.setMesh(s.mesh);
        cpu.setLights(s.lights);
        cpu.setMaterial(s.volume, s.eta);
        const ImageRgb ref = cpu.render(s.camera);
        int compared = 0;
        for (int y = 1; y + 1 < PIXELS; ++y)
            for (int x = 1; x + 1 < PIXELS; ++x) {
                bool interior = true;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx)
                        interior = interior && pos[size_t(y + dy) * PIXELS + x + dx].w > 0.5f;
                if (!interior)
                    continue;
                ++compared;
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(gl.at(x, y)[c], ref.at(x, y)[c],
                                4e-3f * std::abs(ref.at(x, y)[c]) + 1e-5f * peak)
                        << "pixel " << x << "," << y << " channel " << c;
            }
        EXPECT_GT(compared, PIXELS * PIXELS / 5);
        p.destroy();
    }
}

TEST_F(SslpvProviderGl, ThinPartListIsKeptAndResetAcrossFrames) {
    // The thin parts' pixels go through a list the sample pass fills and a second, indirect
    // dispatch reads (shaders/sslpv_sample.comp, THIN_PASS). The list is made once for the
    // target's size and emptied before each frame: steady frames create no GL object, raise no
    // GL error and read the same image (PixelsMatchCpuFormulaAndCpuImage checks one frame's
    // thin pixels against the CPU read-out).
    const TestScene s = makeScene(Shape::ThinThick);
    for (SslpvMode mode : {SslpvMode::Paper, SslpvMode::Diffusion}) {
        SslpvSubsurfaceProvider p(providerOptions(mode, 32));
        p.create();
        setUp(p, s);
        const ImageRgb first = render(p, s);
        m_renderer.render();  // the GPU profiler pools its queries from the second frame on
        const size_t created = gpu::createdGlObjectCount();
        for (int frame = 0; frame < 4; ++frame) {
            m_renderer.render();
            EXPECT_EQ(test::largestDifference(first, m_renderer.readRadiance()), 0.f)
                << "frame " << frame;
        }
        EXPECT_EQ(gpu::createdGlObjectCount(), created);
        EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
        p.destroy();
    }
}

TEST_F(SslpvProviderGl, PaintingUpdatesIncrementallyAndMatchesFromScratch) {
    TestScene s = makeScene();
    SslpvSubsurfaceProvider p(providerOptions());
    p.create();
    setUp(p, s);
    const ImageRgb before = render(p, s);
    EXPECT_EQ(p.stats().fullResamples, 1);
    EXPECT_FALSE(p.isDirty());

    // A stroke of strongly absorbing material near the lit side.
    BrushSettings brush;
    brush.radius = 3.f;
    brush.value = {Rgb(6.f), Rgb(0.5f), Rgb(0.f)};
    paintStroke(s.volume, brush, {Point3f(-5, 5, 4), Point3f(-2, 7, 3)});
    const std::vector<int> dirty = s.volume.takeDirtyBricks();
    ASSERT_FALSE(dirty.empty());
    p.updateMaterial(s.volume, dirty);
    EXPECT_TRUE(p.isDirty());
    const ImageRgb after = render(p, s);
    EXPECT_EQ(p.stats().fullResamples, 1);  // only the incremental path ran
    EXPECT_EQ(p.stats().incrementalUpdates, 1);
    // The stroke's cells went into the solver's material in place, and only their rows'
    // factors were refolded (the scene's first stroke made the material heterogeneous).
    EXPECT_EQ(p.stats().inPlaceUpdates, 1);
    EXPECT_GT(p.solver().stats().refoldedRows, 0);
    EXPECT_LT(p.solver().stats().refoldedRows, 16 * 16 / 2);
    EXPECT_GT(p.stats().lastResampledCells, 0u);
    EXPECT_LT(p.stats().lastResampledCells, size_t(16 * 16 * 16) / 4);
    EXPECT_GT(test::largestDifference(before, after),
              1e-3f * test::largestValue(before));  // the paint shows

    // From scratch: a new provider resampling the painted volume fully gives the same frame
    // (bit-identical coarse grid ⇒ identical solve, upload and shader arithmetic).
    SslpvSubsurfaceProvider fresh(providerOptions());
    fresh.create();
    setUp(fresh, s);
    const ImageRgb scratch = render(fresh, s);
    EXPECT_EQ(p.coarseMaterial().sigma_t[0], fresh.coarseMaterial().sigma_t[0]);
    EXPECT_EQ(p.solver().accumulation().raw(), fresh.solver().accumulation().raw());
    EXPECT_EQ(test::largestDifference(after, scratch), 0.f);
    std::printf(
        "[sslpv provider] stroke: %zu bricks -> %zu cells; resample %.2f ms, propagate "
        "%.2f ms, upload %.2f ms, sample %.2f ms CPU\n",
        dirty.size(), p.stats().lastResampledCells, p.timings().resampleMs, p.timings().propagateMs,
        p.timings().uploadMs, p.timings().sampleCpuMs);
    fresh.destroy();
    p.destroy();
}

TEST_F(SslpvProviderGl, ModeSwitchReadsTheNewModesCells) {
    // The upload keeps the readable flags between uploads (a stroke leaves them); a switch to
    // mode diffusion, which reads boundary cells only, must take its own: the frame after the
    // switch equals a fresh diffusion provider's bit for bit.
    const TestScene s = makeScene();
    SslpvSubsurfaceProvider p(providerOptions(SslpvMode::Paper));
    p.create();
    setUp(p, s);
    (void)render(p, s);
    p.setOptions(providerOptions(SslpvMode::Diffusion));
    const ImageRgb switched = render(p, s);
    SslpvSubsurfaceProvider fresh(providerOptions(SslpvMode::Diffusion));
    fresh.create();
    setUp(fresh, s);
    const ImageRgb expected = render(fresh, s);
    ASSERT_GT(test::largestValue(expected), 0.f);
    EXPECT_EQ(test::largestDifference(switched, expected), 0.f);
    fresh.destroy();
    p.destroy();
}

TEST_F(SslpvProviderGl, GlBackendMatchesCpuBackend) {
    const TestScene s = makeScene();
    SslpvSubsurfaceProvider cpu(providerOptions());
    cpu.create();
    setUp(cpu, s);
    const ImageRgb a = render(cpu, s);
    SslpvProviderOptions o = providerOptions();
    o.backend = SslpvBackend::Gl;
    SslpvSubsurfaceProvider gl(o);
    gl.create();
    setUp(gl, s);
    const ImageRgb b = render(gl, s);
    // The GL propagation matches the CPU grid to 1e-4 of its peak (test_gl.cpp, fp32); the
    // sample pass is linear in the coefficients with weights summing to 1, so the images agree
    // to 1e-4 of the peak of the image (plus the float rounding bound of the sample pass).
    const float peak = test::largestValue(a);
    ASSERT_GT(peak, 0.f);
    EXPECT_LT(test::largestDifference(a, b), 2e-4f * peak);
    gl.destroy();
    cpu.destroy();
}

TEST_F(SslpvProviderGl, StrokeToFrameTimingsAt32) {
    // The live-preview configuration: 128³ painted volume, 32³ LPV, 32 steps, 256² pixels.
    // Prints the per-pass breakdown recorded in docs/benchmarks.md (SSLPV section).
    TestScene s = makeScene();
    const GridSpec spec = GridSpec::around(s.mesh.bounds(), 128);
    s.volume = MaterialVolume(spec, {Rgb(1.2f, 1.3f, 1.5f), Rgb(1.1f, 1.15f, 1.2f), Rgb(0.f)});
    s.volume.setInsideMask(voxelizeSolid(s.mesh, spec));
    (void)s.volume.takeDirtyBricks();
    s.camera.width = s.camera.height = 256;
    SslpvProviderOptions o;
    o.render.gridResolution = 32;
    o.render.injectionResolution = 128;
    o.render.solver.maxSteps = 32;
    SslpvSubsurfaceProvider p(o);
    p.create();
    setUp(p, s);
    const double fullResampleMs = p.timings().resampleMs;
    const ImageRgb before = render(p, s);
    BrushSettings brush;
    brush.radius = 3.f;  // mm: ≈ 2.4 LPV cells
    brush.value = {Rgb(6.f), Rgb(0.5f), Rgb(0.f)};
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    paintStroke(s.volume, brush, {Point3f(-5, 5, 4), Point3f(-2, 7, 3)});
    p.updateMaterial(s.volume, s.volume.takeDirtyBricks());
    m_renderer.render();
    glFinish();
    const double frameMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    m_renderer.render();  // picks up the GPU time of the previous sample pass
    glFinish();
    const SslpvProviderTimings& t = p.timings();
    std::printf(
        "[sslpv provider 32^3] full resample %.1f ms | stroke: %zu cells resampled "
        "%.2f ms, propagate %.2f ms (%d steps), upload %.2f ms, sample %.2f ms CPU "
        "%.2f ms GPU; stroke->frame %.1f ms (incl. brush, G-buffer, shading)\n",
        fullResampleMs, p.stats().lastResampledCells, t.resampleMs, t.propagateMs,
        p.solver().stats().stepsUsed, t.uploadMs, t.sampleCpuMs, t.sampleGpuMs, frameMs);
    EXPECT_EQ(p.stats().fullResamples, 1);
    EXPECT_EQ(p.stats().incrementalUpdates, 1);
    EXPECT_GT(test::largestDifference(before, m_renderer.readRadiance()), 0.f);
    p.destroy();
}
