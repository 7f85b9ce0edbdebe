// SPDX-License-Identifier: MIT
#include <lucent/core/Fresnel.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>

#include "SslpvTestGrids.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace lucent;
using namespace lucent::sslpv;

namespace {

using test::ballTexels;

/// A ball of radius 0.35·N cells centred in an N³ grid of cell size h (mm), uniform material.
CoarseMaterial ballMaterial(int n, float h, Rgb sigma_t, Rgb sigma_s, Rgb g) {
    CoarseMaterial m = test::centredMaterial(n, h);
    const float radius = 0.35f * n * h;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Point3f p = m.spec.cellCenter({x, y, z});
                if (glm::length(p) > radius)
                    continue;
                const size_t k = m.spec.linearIndex({x, y, z});
                m.insideFraction[k] = 1.f;
                for (int c = 0; c < 3; ++c) {
                    m.sigma_t[c][k] = sigma_t[c];
                    m.sigma_s[c][k] = sigma_s[c];
                    m.g[c][k] = g[c];
                }
            }
    m.homogeneous = true;
    return m;
}

// Float sums over ≤ 64³ cells and ≤ 512 steps: relative rounding ~1e-6 per step; the matrices'
// flux conservation holds to ~1e-7 (SslpvTransfer.FluxIsConservedAcrossSixNeighbours).
constexpr float ENERGY_TOL = 2e-4f;

void expectBalance(const SslpvStats& st, const char* what) {
    for (int c = 0; c < 3; ++c) {
        const float sum = st.remaining[c] + st.exitant[c] + st.absorbed[c];
        EXPECT_NEAR(sum, st.injected[c], ENERGY_TOL * st.injected[c] + 1e-30f)
            << what << " channel " << c << ": remaining " << st.remaining[c] << " exitant "
            << st.exitant[c] << " absorbed " << st.absorbed[c];
    }
}

}  // namespace

TEST(SslpvSolver, InjectedFluxIsFresnelTransmitted) {
    // σt′ = 100 mm⁻¹: every refracted beam is opaque within its first half cell (e^−50), so
    // the injected flux is the Fresnel-transmitted flux alone.
    const CoarseMaterial m = ballMaterial(16, 1.f, Rgb(100.f), Rgb(90.f), Rgb(0.f));
    SslpvSolver solver({.order = 1, .maxSteps = 0});
    const float eta = 1.4f;
    solver.setMaterial(m, eta);
    const auto texels = ballTexels(m, Vector3f(0, 0, -1), Rgb(1.f, 2.f, 3.f));
    double expected = 0.0;
    for (const auto& t : texels)
        expected += (1.0 - fresnelDielectric(-glm::dot(t.direction, t.normal), eta)) * t.flux.x;
    solver.setInjectionSamples(texels);
    const SslpvStats& st = solver.solve();
    EXPECT_EQ(st.skippedTexels, 0);
    EXPECT_NEAR(st.injected.x, expected, 1e-5 * expected);
    EXPECT_NEAR(st.injected.z, 3.0 * expected, 3e-5 * expected);
}

TEST(SslpvSolver, InjectsOnlyTheFractionThatInteracts) {
    // A slab 10 cells thick (z cells 2..11, sinks around it) lit at normal incidence, η = 1 (no
    // Fresnel): of the light that enters, 1 − exp(−σt′·10h) interacts before it crosses; the
    // rest leaves through the bottom as a beam and is no subsurface light. The old injection
    // put all of it into the grid (injected = Φ whatever σt′), so an almost transparent
    // medium glowed like a dense one (stability matrix, σt′ = 10⁻⁴ mm⁻¹).
    const int n = 16;
    const float h = 1.f;
    CoarseMaterial m = test::centredMaterial(n, h);
    const Rgb sigma_t(0.01f, 0.1f, 1.f);
    for (int z = 2; z <= 11; ++z)
        for (int y = 1; y < n - 1; ++y)
            for (int x = 1; x < n - 1; ++x) {
                const size_t k = m.spec.linearIndex({x, y, z});
                m.insideFraction[k] = 1.f;
                for (int c = 0; c < 3; ++c) {
                    m.sigma_t[c][k] = sigma_t[c];
                    m.sigma_s[c][k] = 0.9f * sigma_t[c];
                }
            }
    m.homogeneous = true;
    std::vector<SslpvInjectionSample> texels;
    const float zTop = m.spec.origin.z + 12.f * h;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i)
            texels.push_back({Point3f(-1.f + 0.5f * float(i), -1.f + 0.5f * float(j), zTop),
                              Normal3f(0, 0, 1), Vector3f(0, 0, -1), Rgb(1.f)});
    SslpvSolver solver({.order = 1, .maxSteps = 0});
    solver.setMaterial(m, /*eta=*/1.f);
    solver.setInjectionSamples(texels);
    const SslpvStats& st = solver.solve();
    EXPECT_EQ(st.skippedTexels, 0);
    for (int c = 0; c < 3; ++c) {
        // The chord's optical depth by half-cell midpoint samples is exact here (the slab's
        // faces lie on cell faces); float rounding of the SH projection ~1e−6.
        const double expected = 16.0 * -std::expm1(-double(sigma_t[c]) * 10.0 * h);
        EXPECT_NEAR(st.injected[c], expected, 1e-5 * 16.0) << "channel " << c;
    }
}

TEST(SslpvSolver, EnergyBalanceWithoutAbsorption) {
    // σa = 0 (σs′ = σt, absorption-only attenuation): injected = exitant + remaining.
    for (int order : {1, 2}) {
        const CoarseMaterial m = ballMaterial(24, 0.5f, Rgb(2.f), Rgb(2.f), Rgb(0.3f));
        SslpvSolver solver(
            {.order = order, .maxSteps = 40, .attenuation = SslpvAttenuation::Absorption});
        solver.setMaterial(m, 1.3f);
        solver.setInjectionSamples(ballTexels(m, Vector3f(0.3f, -0.2f, -1.f), Rgb(1.f)));
        const SslpvStats& st = solver.solve();
        EXPECT_EQ(st.stepsUsed, 40);
        EXPECT_GT(st.exitant.x, 0.5f * st.injected.x) << "light should leave a 8.4 mm ball";
        EXPECT_EQ(st.absorbed.x, 0.f);
        expectBalance(st, order == 1 ? "L1" : "L2");
        // Independent check of the bookkeeping: re-sum the grids themselves.
        const Rgb ex = solver.exitant().flux(), rem = solver.propagation().flux();
        EXPECT_NEAR(ex.x + rem.x, st.injected.x, ENERGY_TOL * st.injected.x);
    }
}

TEST(SslpvSolver, PartialSinksConserveFlux) {
    // Cells the surface cuts keep min(1, 2f) of their light (f = insideFraction), the rest
    // leaves: with σa = 0, injected = exitant + remaining still holds, and light held by
    // partial cells at the edge of the inside box must not be lost by the active box.
    for (int order : {1, 2}) {
        CoarseMaterial m = ballMaterial(24, 0.5f, Rgb(2.f), Rgb(2.f), Rgb(0.3f));
        const float radius = 0.35f * 24 * 0.5f;
        int partial = 0;
        for (int z = 0; z < 24; ++z)
            for (int y = 0; y < 24; ++y)
                for (int x = 0; x < 24; ++x) {
                    const float d = glm::length(m.spec.cellCenter({x, y, z})) - radius;
                    const float f = std::clamp(0.5f - d / 0.5f, 0.f, 1.f);  // ½ at the surface
                    const size_t k = m.spec.linearIndex({x, y, z});
                    m.insideFraction[k] = f;
                    for (int c = 0; c < 3; ++c) {
                        m.sigma_t[c][k] = 2.f;
                        m.sigma_s[c][k] = 2.f;
                        m.g[c][k] = 0.3f;
                    }
                    partial += f > 0.f && f < 0.5f;
                }
        ASSERT_GT(partial, 100);
        SslpvSolver solver(
            {.order = order, .maxSteps = 40, .attenuation = SslpvAttenuation::Absorption});
        solver.setMaterial(m, 1.3f);
        solver.setInjectionSamples(ballTexels(m, Vector3f(0.3f, -0.2f, -1.f), Rgb(1.f)));
        const SslpvStats& st = solver.solve();
        EXPECT_GT(st.exitant.x, 0.5f * st.injected.x);
        expectBalance(st, order == 1 ? "L1 partial sinks" : "L2 partial sinks");
        const Rgb ex = solver.exitant().flux(), rem = solver.propagation().flux();
        EXPECT_NEAR(ex.x + rem.x, st.injected.x, ENERGY_TOL * st.injected.x);
    }
}

TEST(SslpvSolver, VacuumPaperModeConservesFlux) {
    // Paper attenuation in a nearly empty ball (σt′ = 10⁻³ mm⁻¹, σs′ = 0; σt′ = 0 would inject
    // nothing, since no light interacts): all of the little injected is accounted for.
    const CoarseMaterial m = ballMaterial(20, 1.f, Rgb(1e-3f), Rgb(0.f), Rgb(0.f));
    SslpvSolver solver({.order = 1, .maxSteps = 16});
    solver.setMaterial(m, 1.5f);
    solver.setInjectionSamples(ballTexels(m, Vector3f(0, -1, 0), Rgb(1.f)));
    const SslpvStats& st = solver.solve();
    EXPECT_GT(st.injected.x, 0.f);
    expectBalance(st, "vacuum");
}

TEST(SslpvSolver, EnergyBalanceWithAbsorptionAndHeterogeneity) {
    CoarseMaterial m = ballMaterial(24, 1.f, Rgb(0.5f, 1.f, 2.f), Rgb(0.4f), Rgb(0.f, 0.5f, -0.5f));
    // Make the +x half four times as absorbing.
    for (int z = 0; z < 24; ++z)
        for (int y = 0; y < 24; ++y)
            for (int x = 12; x < 24; ++x) {
                const size_t k = m.spec.linearIndex({x, y, z});
                if (m.insideFraction[k] > 0.f)
                    for (int c = 0; c < 3; ++c)
                        m.sigma_t[c][k] *= 4.f;
            }
    m.homogeneous = false;
    for (auto att : {SslpvAttenuation::Extinction, SslpvAttenuation::Absorption}) {
        SslpvSolver solver({.order = 1, .maxSteps = 32, .attenuation = att});
        solver.setMaterial(m, 1.3f);
        solver.setInjectionSamples(ballTexels(m, Vector3f(0, 0, -1), Rgb(1.f)));
        const SslpvStats& st = solver.solve();
        EXPECT_GT(st.absorbed.x, 0.f);
        expectBalance(st, "heterogeneous");
        // More absorption on +x: less light leaves there than on −x.
        double plus = 0.0, minus = 0.0;
        for (int z = 0; z < 24; ++z)
            for (int y = 0; y < 24; ++y)
                for (int x = 0; x < 24; ++x) {
                    const float e = solver.exitant().at({x, y, z}, 1, 0);
                    (x >= 12 ? plus : minus) += e;
                }
        EXPECT_LT(plus, 0.8 * minus);
    }
}

TEST(SslpvSolver, HeterogeneousPathMatchesHomogeneousPath) {
    const CoarseMaterial hom = ballMaterial(20, 1.f, Rgb(1.f), Rgb(0.7f), Rgb(0.4f));
    CoarseMaterial het = hom;
    // One cell differs by a float ulp-scale amount: forces the per-cell factor arrays.
    het.g[0][het.spec.linearIndex({10, 10, 10})] = std::nextafter(0.4f, 1.f);
    const auto texels = ballTexels(hom, Vector3f(1, 1, -1), Rgb(1.f));
    SslpvSolver a({.maxSteps = 24}), b({.maxSteps = 24});
    a.setMaterial(hom, 1.3f);
    b.setMaterial(het, 1.3f);
    a.setInjectionSamples(texels);
    b.setInjectionSamples(texels);
    a.solve();
    b.solve();
    const float peak = a.accumulation().maxAbs();
    ASSERT_GT(peak, 0.f);
    const auto& ra = a.accumulation().raw();
    const auto& rb = b.accumulation().raw();
    ASSERT_EQ(ra.size(), rb.size());
    float worst = 0.f;
    for (size_t k = 0; k < ra.size(); ++k)
        worst = std::max(worst, std::abs(ra[k] - rb[k]));
    EXPECT_LT(worst, 1e-5f * peak);  // float rounding only; the ulp change is ~1e-7
}

TEST(SslpvSolver, DeterministicAcrossThreadCounts) {
    const CoarseMaterial m = ballMaterial(20, 1.f, Rgb(1.f), Rgb(0.7f), Rgb(0.4f));
    const auto texels = ballTexels(m, Vector3f(0, 1, -1), Rgb(1.f));
    std::vector<float> results[2];
    for (int t = 1; t <= 2; ++t) {
        ThreadLimit limit(t);
        SslpvSolver s({.maxSteps = 16});
        s.setMaterial(m, 1.3f);
        s.setInjectionSamples(texels);
        s.solve();
        results[t - 1] = s.accumulation().raw();
    }
    EXPECT_EQ(results[0], results[1]);  // each cell is written by exactly one task
}

TEST(SslpvSolver, StopsWhenRemainingEnergyIsSmall) {
    const CoarseMaterial m = ballMaterial(16, 1.f, Rgb(1.f), Rgb(0.8f), Rgb(0.f));
    SslpvSolver solver({.maxSteps = 512, .stopEpsilon = 1e-3f});
    solver.setMaterial(m, 1.3f);
    solver.setInjectionSamples(ballTexels(m, Vector3f(0, 0, -1), Rgb(1.f)));
    const SslpvStats& st = solver.solve();
    EXPECT_LT(st.stepsUsed, 512);
    EXPECT_GT(st.stepsUsed, 2);
    for (int c = 0; c < 3; ++c)
        EXPECT_LE(st.remaining[c], 1e-3f * st.injected[c]);
}

TEST(SslpvSolver, IncrementalDirtyFlags) {
    const CoarseMaterial m = ballMaterial(16, 1.f, Rgb(1.f), Rgb(0.8f), Rgb(0.f));
    SslpvSolver solver({.maxSteps = 8});
    EXPECT_THROW(solver.solve(), ValueError);
    solver.setMaterial(m, 1.3f);
    solver.setInjectionSamples(ballTexels(m, Vector3f(0, 0, -1), Rgb(1.f)));
    EXPECT_TRUE(solver.isDirty());
    const SslpvStats first = solver.solve();
    EXPECT_TRUE(first.reinjected && first.repropagated);
    EXPECT_FALSE(solver.isDirty());
    const SslpvStats idle = solver.solve();
    EXPECT_FALSE(idle.reinjected || idle.repropagated);
    // Painting σs′: material edited in place → propagation only (σt would also inject the
    // beams through it again: PaintingSigmaTReinjectsTheChordsThroughIt).
    const Rgb before = solver.accumulation().flux();
    for (auto& v : solver.material().sigma_s[0])
        v *= 0.5f;
    solver.markMaterialDirty();
    const SslpvStats painted = solver.solve();
    EXPECT_FALSE(painted.reinjected);
    EXPECT_TRUE(painted.repropagated);
    EXPECT_NE(solver.accumulation().flux().x, before.x);  // red changed
    EXPECT_NEAR(solver.accumulation().flux().y, before.y, 1e-6f * before.y);
    // Lights moved → re-inject.
    solver.setInjectionSamples(ballTexels(m, Vector3f(1, 0, 0), Rgb(1.f)));
    EXPECT_TRUE(solver.solve().reinjected);
}

TEST(SslpvSolver, RejectsBadInput) {
    CoarseMaterial m = ballMaterial(16, 1.f, Rgb(1.f), Rgb(0.8f), Rgb(0.f));
    SslpvSolver solver;
    EXPECT_THROW(solver.setMaterial(m, 0.5f), ValueError);
    CoarseMaterial nan = m;
    nan.sigma_t[1][100] = std::nanf("");
    EXPECT_THROW(solver.setMaterial(nan, 1.3f), ValueError);
    CoarseMaterial shortArr = m;
    shortArr.g[2].pop_back();
    EXPECT_THROW(solver.setMaterial(shortArr, 1.3f), ValueError);
    EXPECT_THROW(solver.setOptions({.order = 3}), ValueError);
    EXPECT_THROW(solver.setOptions({.maxSteps = -1}), ValueError);
    EXPECT_THROW(solver.setOptions({.stopEpsilon = 2.f}), ValueError);
    EXPECT_THROW(solver.setOptions({.brickStopEpsilon = -1e-3f}), ValueError);
    EXPECT_THROW(solver.markMaterialCellsDirty({0}), ValueError);  // no material yet
    solver.setMaterial(m, 1.3f);
    EXPECT_THROW(solver.markMaterialCellsDirty({int(m.spec.voxelCount())}), ValueError);
    solver.material().g[0][7] = 2.f;
    EXPECT_THROW(solver.markMaterialCellsDirty({7}), ValueError);
}

TEST(SslpvSolver, CellsEditedInPlaceSolveAsANewMaterial) {
    // A stroke's cells written through material() and named to markMaterialCellsDirty refold
    // only their rows' factors, and the solve equals one of a solver handed the whole material
    // bit for bit (the rows are folded by the same calls as a full refold). Three strokes in a
    // row, the second before a solve, then one that makes the material homogeneous again.
    // (Without incremental re-injection, which matches a full one only to float rounding.)
    CoarseMaterial m = ballMaterial(20, 1.f, Rgb(1.f, 1.2f, 1.5f), Rgb(0.8f, 1.f, 1.2f), Rgb(0.f));
    m.sigma_t[0][m.spec.linearIndex({10, 10, 10})] = 3.f;  // heterogeneous from the start
    m.homogeneous = false;
    const SslpvOptions o{.maxSteps = 24, .incrementalInjection = false};
    SslpvSolver live(o);
    live.setMaterial(m, 1.3f);
    const auto texels = ballTexels(m, Vector3f(0.3f, 0, -1), Rgb(1.f));
    live.setInjectionSamples(texels);
    live.solve();
    const auto stroke = [&](Coord c, float st, bool solve) {
        std::vector<int> cells;
        for (int dz = 0; dz < 2; ++dz)
            for (int dx = 0; dx < 3; ++dx) {
                const int k = int(m.spec.linearIndex(c + Coord(dx, 0, dz)));
                cells.push_back(k);
                for (CoarseMaterial* mat : {&m, &live.material()})
                    for (int ch = 0; ch < 3; ++ch) {
                        mat->sigma_t[ch][size_t(k)] = st;
                        mat->sigma_s[ch][size_t(k)] = 0.5f * st;
                    }
            }
        live.markMaterialCellsDirty(cells);
        if (solve)
            live.solve();
    };
    const auto expectAsNew = [&](const char* what, bool rowsOnly) {
        SCOPED_TRACE(what);
        SslpvSolver fresh(o);
        fresh.setMaterial(m, 1.3f);
        fresh.setInjectionSamples(texels);
        fresh.solve();
        EXPECT_EQ(live.accumulation().raw(), fresh.accumulation().raw());
        if (rowsOnly) {
            EXPECT_GT(live.stats().refoldedRows, 0);
            EXPECT_LT(live.stats().refoldedRows, 20 * 20 / 10);
        }
    };
    stroke({6, 8, 12}, 4.f, true);
    expectAsNew("one stroke", true);
    stroke({9, 12, 5}, 0.5f, false);
    stroke({12, 6, 9}, 2.f, true);
    expectAsNew("two strokes, one solve", true);
    // Back to one material everywhere inside: the solver finds it homogeneous again.
    for (CoarseMaterial* mat : {&m, &live.material()})
        for (int ch = 0; ch < 3; ++ch)
            for (size_t k = 0; k < m.spec.voxelCount(); ++k) {
                mat->sigma_t[ch][k] = 1.f;
                mat->sigma_s[ch][k] = 0.8f;
            }
    std::vector<int> all(m.spec.voxelCount());
    for (size_t k = 0; k < all.size(); ++k)
        all[k] = int(k);
    live.markMaterialCellsDirty(all);
    live.solve();
    expectAsNew("homogeneous again", false);
    EXPECT_EQ(live.stats().refoldedRows, 0);
}

TEST(SslpvSolver, RadianceFacesTheLight) {
    // A ball lit from +z: the radiance estimate (Eq. 7) is larger on the lit side than on the
    // far side, finite and non-negative everywhere.
    const CoarseMaterial m = ballMaterial(24, 1.f, Rgb(0.5f), Rgb(0.45f), Rgb(0.f));
    SslpvSolver solver({.maxSteps = 32});
    solver.setMaterial(m, 1.3f);
    solver.setInjectionSamples(ballTexels(m, Vector3f(0, 0, -1), Rgb(1.f)));
    solver.solve();
    const float r = 0.35f * 24.f - 0.3f;
    const Rgb top = solver.radiance(Point3f(0, 0, r), Normal3f(0, 0, 1));
    const Rgb side = solver.radiance(Point3f(r, 0, 0), Normal3f(1, 0, 0));
    const Rgb bottom = solver.radiance(Point3f(0, 0, -r), Normal3f(0, 0, -1));
    EXPECT_GT(top.x, side.x);
    EXPECT_GT(side.x, bottom.x);
    EXPECT_GT(bottom.x, 0.f);
    EXPECT_TRUE(isFinite(top));
}

// A fin thinner than half a cell has no cell of its own (insideFraction < ½), so the read-out's
// depths find nothing there; it rendered black. It is read from the readable cells within two
// cells, Gaussian-weighted by distance (in cells) and scaled by 2f, f the fin's inside fraction
// (SslpvSolver::thinPartCoefficients): checked against that rule evaluated here from the grid.
TEST(SslpvSolver, ThinPartsReadTheirNeighboursScaledByTheirThickness) {
    constexpr int N = 24;
    // The fin: the cells z = 12 (z ∈ [0, 1] mm), y 8…15, x 20…23, just past the ball's +x side
    // (radius 8.4 cells; its cells reach x = 19). Read on its top face, 1 mm past the ball.
    for (float f : {0.f, 0.2f, 0.4f}) {
        CoarseMaterial m = ballMaterial(N, 1.f, Rgb(0.5f), Rgb(0.45f), Rgb(0.f));
        for (int y = 8; y < 16; ++y)
            for (int x = 20; x < N; ++x)
                m.insideFraction[m.spec.linearIndex({x, y, 12})] = f;
        SslpvSolver solver({.maxSteps = 32});
        solver.setMaterial(m, 1.3f);
        solver.setInjectionSamples(ballTexels(m, Vector3f(0, 0, -1), Rgb(1.f)));
        solver.solve();
        const Point3f p(8.5f, 0.5f, f);
        const Rgb read = solver.radiance(p, Normal3f(0, 0, 1));
        ASSERT_TRUE(isFinite(read));
        if (f == 0.f) {
            EXPECT_EQ(read, Rgb(0.f)) << "no fin, nothing to read";
            continue;
        }
        // The depth-½ point p − ½·n is in cell (20, 12, 11); its eight cells' largest inside
        // fraction is the fin's f. Paper mode, n = +z: L = (2/Δx²)(Y00·c00 + ½·K1·c10), Eq. 7.
        const Vector3f u = (p - Vector3f(0, 0, 0.5f) - m.spec.origin) - Vector3f(0.5f);
        float wsum = 0.f;
        Rgb c00(0.f), c10(0.f);
        for (int z = 9; z <= 13; ++z)
            for (int y = 10; y <= 14; ++y)
                for (int x = 18; x <= 22; ++x) {
                    if (!solver.isReadable({x, y, z}))
                        continue;
                    const Vector3f d = u - Vector3f(x, y, z);
                    const float w = std::exp(-glm::dot(d, d));
                    wsum += w;
                    for (int c = 0; c < 3; ++c) {
                        c00[c] += w * solver.accumulation().at({x, y, z}, c, 0);
                        c10[c] += w * solver.accumulation().at({x, y, z}, c, 2);
                    }
                }
        ASSERT_GT(wsum, 0.f);
        const float Y00 = 0.5f / std::sqrt(PI), K1 = std::sqrt(3.f / (4.f * PI));
        for (int c = 0; c < 3; ++c) {
            const float expected = 2.f * f * 2.f * (Y00 * c00[c] + 0.5f * K1 * c10[c]) / wsum;
            EXPECT_GT(read[c], 0.f);
            EXPECT_NEAR(read[c], expected, 1e-4f * expected) << "f " << f << " channel " << c;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Stress (issue E): extreme parameters never produce NaN/Inf and never create energy.

struct StressCase {
    const char* name;
    float sigma_t, sigma_s, g, eta, cell;
    int steps;
    Vector3f dir;
};

TEST(SslpvSolver, StressExtremeParameters) {
    const StressCase cases[] = {
        {"sigma_t->0", 1e-9f, 0.f, 0.f, 1.3f, 1.f, 64, {0, 0, -1}},
        {"sigma_t=1e4", 1e4f, 5e3f, 0.f, 1.3f, 1.f, 64, {0, 0, -1}},
        {"sigma_s=sigma_t", 3.f, 3.f, 0.f, 1.3f, 1.f, 64, {0, 0, -1}},
        {"g=+0.99", 1.f, 1.f, 0.99f, 1.3f, 1.f, 64, {0, 0, -1}},
        {"g=-0.99", 1.f, 1.f, -0.99f, 1.3f, 1.f, 64, {0, 0, -1}},
        {"eta=1", 1.f, 0.5f, 0.f, 1.f, 1.f, 32, {0, 0, -1}},
        {"eta=2.5", 1.f, 0.5f, 0.f, 2.5f, 1.f, 32, {0, 0, -1}},
        {"grazing", 1.f, 0.9f, 0.f, 1.3f, 1.f, 32, {1, 0, -1e-3f}},
        {"cell=1e-3mm", 1.f, 0.9f, 0.f, 1.3f, 1e-3f, 32, {0, 0, -1}},
        {"cell=1e3mm", 1.f, 0.9f, 0.f, 1.3f, 1e3f, 32, {0, 0, -1}},
        {"1 step", 1.f, 0.9f, 0.5f, 1.3f, 1.f, 1, {0, 0, -1}},
        // Nearly transparent and lossless (σs′ = σt′): the little that interacts (1 − e^−τ of
        // each beam) must stay bounded over 512 steps. (σt′ = 0 injects nothing at all.)
        {"512 steps", 1e-3f, 1e-3f, 0.f, 1.3f, 1.f, 512, {0, 0, -1}},
    };
    for (const StressCase& sc : cases) {
        for (int order : {1, 2}) {
            const CoarseMaterial m =
                ballMaterial(16, sc.cell, Rgb(sc.sigma_t), Rgb(sc.sigma_s), Rgb(sc.g));
            SslpvSolver solver({.order = order,
                                .maxSteps = sc.steps,
                                .skipAccumulateSteps = 0,
                                .attenuation = SslpvAttenuation::Absorption});
            solver.setMaterial(m, sc.eta);
            solver.setInjectionSamples(ballTexels(m, sc.dir, Rgb(1.f), 32));
            const SslpvStats& st = solver.solve();
            SCOPED_TRACE(std::string(sc.name) + " order " + std::to_string(order));
            EXPECT_TRUE(solver.accumulation().isFinite());
            EXPECT_TRUE(solver.propagation().isFinite());
            EXPECT_TRUE(solver.exitant().isFinite());
            EXPECT_GT(st.injected.x, 0.f);
            // Energy never grows: what is left plus what left never exceeds the injection,
            // and every part of the balance is accounted for.
            EXPECT_LE(st.remaining.x, st.injected.x * (1.f + ENERGY_TOL));
            expectBalance(st, sc.name);
            const Rgb L = solver.radiance(Point3f(0, 0, 0.3f * 16 * sc.cell), Normal3f(0, 0, 1));
            EXPECT_TRUE(isFinite(L));
        }
    }
}

TEST(SslpvSolver, LightInsideTheBoundingBoxAndEmptyInputs) {
    const CoarseMaterial m = ballMaterial(16, 1.f, Rgb(1.f), Rgb(0.5f), Rgb(0.f));
    SslpvSolver solver({.maxSteps = 8});
    solver.setMaterial(m, 1.3f);
    // No samples: a valid, dark solution.
    solver.setInjectionSamples({});
    EXPECT_EQ(solver.solve().injected.x, 0.f);
    // Samples from a light inside the grid's box (rays leaving the centre hit the surface
    // from inside: back-facing, skipped) and degenerate ones (NaN, zero flux).
    std::vector<SslpvInjectionSample> s;
    s.push_back({Point3f(0, 0, 5.5f), Normal3f(0, 0, 1), Vector3f(0, 0, 1), Rgb(1.f)});
    s.push_back({Point3f(std::nanf("")), Normal3f(0, 0, 1), Vector3f(0, 0, -1), Rgb(1.f)});
    s.push_back({Point3f(0, 0, 5.5f), Normal3f(0, 0, 1), Vector3f(0, 0, -1), Rgb(0.f)});
    s.push_back({Point3f(0, 0, 5.5f), Normal3f(0, 0, 1), Vector3f(0, 0, -1), Rgb(1.f)});
    solver.setInjectionSamples(s);
    const SslpvStats& st = solver.solve();
    EXPECT_EQ(st.injectedTexels, 1);
    EXPECT_EQ(st.skippedTexels, 3);
    EXPECT_TRUE(solver.accumulation().isFinite());
}

TEST(SslpvSolver, FoldedFactorsMatchBeerAndEq3) {
    // Factor of band l: exp(−σatt·Δx)·((1 − s′) + s′ g^l), s′ = 1 − exp(−σs′Δx). The solver's
    // polynomial exp is accurate to ~2e-7 relative (Taylor remainder + float rounding).
    for (float h : {0.1f, 1.f, 7.f}) {
        CoarseMaterial m = ballMaterial(16, h, Rgb(0.8f, 2.f, 0.05f), Rgb(0.5f, 1.5f, 0.f),
                                        Rgb(0.3f, -0.6f, 0.9f));
        m.sigma_t[0][m.spec.linearIndex({8, 8, 8})] = 3.f;  // heterogeneous path
        for (auto att : {SslpvAttenuation::Extinction, SslpvAttenuation::Absorption}) {
            SslpvSolver solver({.maxSteps = 1, .attenuation = att});
            solver.setMaterial(m, 1.3f);
            solver.solve();
            for (int c = 0; c < 3; ++c) {
                const Coord cell = (c == 0) ? Coord(8, 8, 8) : Coord(7, 8, 8);
                const size_t k = m.spec.linearIndex(cell);
                const double st = m.sigma_t[c][k], ss = m.sigma_s[c][k], g = m.g[c][k];
                const double a =
                    std::exp(-(att == SslpvAttenuation::Extinction ? st : st - ss) * h);
                const double s = 1.0 - std::exp(-ss * h);
                const size_t pk = solver.injection().index(cell);
                for (int l = 0; l < 3; ++l) {
                    const double expected = a * ((1.0 - s) + s * std::pow(g, l));
                    EXPECT_NEAR(solver.foldedFactorPlane(c, l)[pk], expected,
                                1e-6 * std::abs(expected) + 1e-12)
                        << "h " << h << " channel " << c << " band " << l;
                }
            }
        }
    }
}

TEST(SslpvSolver, SliceSkippingIsExact) {
    // Skipped slices must equal what dense computation gives (zeros), also across repeated
    // solves where the ping-pong grids hold stale values from the previous light.
    CoarseMaterial m = ballMaterial(24, 1.f, Rgb(0.7f), Rgb(0.6f), Rgb(0.3f));
    m.sigma_t[1][m.spec.linearIndex({12, 12, 12})] = 2.f;
    for (bool sinks : {true, false}) {
        SslpvSolver skip({.maxSteps = 6, .removeExitant = sinks, .skipEmptySlices = true});
        SslpvSolver dense({.maxSteps = 6, .removeExitant = sinks, .skipEmptySlices = false});
        for (SslpvSolver* s : {&skip, &dense})
            s->setMaterial(m, 1.3f);
        for (Vector3f dir : {Vector3f(0, 0, -1), Vector3f(0, 0, 1), Vector3f(0.2f, 0, -1)}) {
            const auto texels = ballTexels(m, dir, Rgb(1.f));
            for (SslpvSolver* s : {&skip, &dense}) {
                s->setInjectionSamples(texels);
                s->solve();
            }
            EXPECT_EQ(skip.accumulation().raw(), dense.accumulation().raw());
            EXPECT_EQ(skip.exitant().raw(), dense.exitant().raw());
            EXPECT_EQ(skip.propagation().raw(), dense.propagation().raw());
            EXPECT_EQ(skip.stats().exitant.x, dense.stats().exitant.x);
        }
    }
}

TEST(SslpvSolver, EarlyStopDropsAtMostTheFluxLeftInTheGrid) {
    // The early stop (stopEpsilon, docs/benchmarks.md "Skips") against the same solve run to
    // maxSteps. After the stop the grid's flux R (≤ ε·injected) would only have been split
    // between the sinks, absorption and the grid (energy never grows), so the full solve's exitant
    // flux exceeds the early one by between 0 and R; and each dropped step would have added the
    // grid's flux at that step (≤ R, non-increasing) to the accumulation, so the accumulation the
    // renderer reads loses at most (full steps − early steps)·R. Rounding: ENERGY_TOL.
    const CoarseMaterial m =
        ballMaterial(16, 1.f, Rgb(1.f, 1.2f, 1.5f), Rgb(0.95f, 1.f, 1.f), Rgb(0.f));
    const float eps = 1e-3f;
    SslpvSolver early({.maxSteps = 256, .stopEpsilon = eps});
    SslpvSolver full({.maxSteps = 256});
    for (SslpvSolver* s : {&early, &full}) {
        s->setMaterial(m, 1.3f);
        s->setInjectionSamples(ballTexels(m, Vector3f(0, 0, -1), Rgb(1.f)));
    }
    const SslpvStats a = early.solve();
    const SslpvStats b = full.solve();
    ASSERT_GT(b.stepsUsed, a.stepsUsed) << "the stop did not fire";
    EXPECT_EQ(b.stepsUsed, 256);
    const Rgb accEarly = early.accumulation().flux(), accFull = full.accumulation().flux();
    const float dropped = float(b.stepsUsed - a.stepsUsed);
    for (int c = 0; c < 3; ++c) {
        SCOPED_TRACE("channel " + std::to_string(c));
        const float tol = ENERGY_TOL * a.injected[c];
        EXPECT_EQ(a.injected[c], b.injected[c]);
        EXPECT_LE(a.remaining[c], eps * a.injected[c]);
        EXPECT_GE(b.exitant[c] - a.exitant[c], -tol);
        EXPECT_LE(b.exitant[c] - a.exitant[c], a.remaining[c] + tol);
        EXPECT_GE(accFull[c] - accEarly[c], -ENERGY_TOL * accFull[c]);
        EXPECT_LE(accFull[c] - accEarly[c], dropped * a.remaining[c] + ENERGY_TOL * accFull[c]);
    }
}

namespace {

/// Flux-weighted spatial variance (cells², summed over x, y, z) of the propagation grid after
/// `steps` steps of one texel injected at the centre of an N³ block of non-absorbing medium
/// with σs′ = σt (mm⁻¹) and cells of 1 mm, no sinks, nothing accumulated. The light cannot
/// reach the grid's border within N/2 steps.
double spreadAfter(int steps, float sigma_s) {
    constexpr int n = 48;
    CoarseMaterial m = test::centredMaterial(n, 1.f, sigma_s, sigma_s, 0.f);
    std::fill(m.insideFraction.begin(), m.insideFraction.end(), 1.f);
    m.homogeneous = true;
    SslpvOptions o;
    o.maxSteps = steps;
    o.removeExitant = false;
    o.skipAccumulateSteps = 0;
    o.attenuation = SslpvAttenuation::Absorption;
    SslpvSolver s(o);
    s.setMaterial(m, 1.f);
    SslpvInjectionSample t;
    t.position = Point3f(0.3f);
    t.direction = Vector3f(0, 0, -1);
    t.flux = Rgb(1.f);
    s.setInjectionSamples({t});
    s.solve();
    double w = 0, mean[3] = {}, sq = 0;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const double v = s.propagation().at({x, y, z}, 0, 0);
                const double p[3] = {double(x), double(y), double(z)};
                w += v;
                for (int a = 0; a < 3; ++a) {
                    mean[a] += v * p[a];
                    sq += v * p[a] * p[a];
                }
            }
    return sq / w - (mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]) / (w * w);
}

}  // namespace

// The lattice's own transport (docs/methods/sslpv.md, "Numerical diffusion"): each step moves
// light one cell to a face neighbour and re-projects it onto the SH basis, so the light keeps
// little of its direction whatever the medium. The spread grows by d⟨r²⟩/dn cells² per step.
// A memoryless nearest-neighbour walk grows by exactly 1 cell² per step; with σs′Δx = 8 Eq. 3
// leaves e⁻⁸ of the dipole band, so the lattice must be that walk (to 1 %, the residual memory).
// Without any scattering the propagation itself keeps a direction correlation r per step, and
// the spread grows by (1 + r)/(1 − r): measured 1.352 (r = 0.15), i.e. a transport mean free
// path of 0.68 cells however thin the medium is, against 1/σs′ in the medium it stands for.
TEST(SslpvSolver, LatticeTransportMeanFreePathIsAboutHalfACell) {
    const double memoryless = (spreadAfter(24, 8.f) - spreadAfter(8, 8.f)) / 16.0;
    EXPECT_NEAR(memoryless, 1.0, 0.01);
    const double unscattered = (spreadAfter(24, 1e-4f) - spreadAfter(8, 1e-4f)) / 16.0;
    // Measured 1.352; any change of the propagation matrices or of Eq. 3's folding moves it.
    EXPECT_NEAR(unscattered, 1.352, 0.01);
}

// The consequence (issue 14, the back-lit cases of docs/evaluation.md): the transmission of a
// non-absorbing slab 5 mm thick (σs′ = 0.8 mm⁻¹, 4 mean free paths, η = 1, one texel at normal
// incidence) falls as the grid is refined, because the lattice is optically 1/(0.68 σs′Δx)
// times thicker than the medium: 0.222 / 0.143 / 0.080 of the light leaves through the back at
// Δx = 1 / ½ / ¼ mm (diffusion theory: about 0.3, (z₀ + z_b)/(L + 2z_b) with z₀ = 1/σs′ and
// Milne's z_b = 0.71/σs′). A convergent transport would give one value, within 10 %. Disabled while
// it fails (run it with
// --gtest_also_run_disabled_tests); the method change it needs is in docs/methods/sslpv.md.
TEST(SslpvSolver, DISABLED_SlabTransmissionConvergesAsTheGridIsRefined) {
    std::vector<double> transmitted;
    for (float h : {1.f, 0.5f, 0.25f}) {
        constexpr int n = 64;
        const int cells = int(std::lround(5.f / h));
        CoarseMaterial m = test::centredMaterial(n, h, 0.8f, 0.8f, 0.f);
        const int z0 = (n - cells) / 2, z1 = z0 + cells - 1;
        for (int z = z0; z <= z1; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x)
                    m.insideFraction[m.spec.linearIndex({x, y, z})] = 1.f;
        m.homogeneous = true;
        SslpvOptions o;
        o.maxSteps = 4096;
        o.stopEpsilon = 1e-4f;
        o.attenuation = SslpvAttenuation::Absorption;
        SslpvSolver s(o);
        s.setMaterial(m, 1.f);
        SslpvInjectionSample t;
        t.position = Point3f(0.01f, 0.01f, m.spec.origin.z + float(z1 + 1) * h);
        t.direction = Vector3f(0, 0, -1);
        t.flux = Rgb(1.f);
        s.setInjectionSamples({t});
        s.solve();
        double top = 0, bottom = 0;  // c00 removed in the sink layers above and below
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                top += s.exitant().at({x, y, z1 + 1}, 0, 0);
                bottom += s.exitant().at({x, y, z0 - 1}, 0, 0);
            }
        transmitted.push_back(bottom / (top + bottom));
    }
    EXPECT_NEAR(transmitted[1], transmitted[0], 0.1 * transmitted[0]);
    EXPECT_NEAR(transmitted[2], transmitted[0], 0.1 * transmitted[0]);
}

// Modes Paper and Calibrated weigh each beam by its chord's interacting fraction 1 − e^−τ (σt
// along it), so painting σt on an optically thin part changes the light that enters. A stroke
// used to re-propagate the old injection: a thin ball (σt 0.05 mm⁻¹, 16 cells of 1 mm) painted
// 20× denser in red kept injecting 34 W of red where a fresh solve injects 92 W. Now the beams
// whose chord meets the changed cells are injected again, replacing their deposits: the
// incremental solve equals a fresh one to float rounding.
TEST(SslpvSolver, PaintingSigmaTReinjectsTheChordsThroughIt) {
    for (const SslpvMode mode : {SslpvMode::Paper, SslpvMode::Calibrated}) {
        CoarseMaterial m = ballMaterial(16, 1.f, Rgb(0.05f), Rgb(0.04f), Rgb(0.f));
        m.homogeneous = false;
        const auto texels = ballTexels(m, Vector3f(0.2f, 0.1f, -1.f), Rgb(1.f));
        SslpvSolver painted({.maxSteps = 8, .mode = mode});
        painted.setMaterial(m, 1.3f);
        painted.setInjectionSamples(texels);
        const SslpvStats first = painted.solve();
        // A stroke: a 4×4×4 block of red absorber where the light enters (the incremental
        // path: far less than an eighth of the cells).
        for (int z = 10; z < 14; ++z)
            for (int y = 6; y < 10; ++y)
                for (int x = 6; x < 10; ++x)
                    painted.material().sigma_t[0][m.spec.linearIndex({x, y, z})] *= 50.f;
        painted.markMaterialDirty();
        const SslpvStats after = painted.solve();
        EXPECT_TRUE(after.reinjected);
        EXPECT_GT(after.rewalkedTexels, 0);
        EXPECT_LT(after.rewalkedTexels, first.injectedTexels);  // only the chords near it
        SslpvSolver fresh({.maxSteps = 8, .mode = mode});
        fresh.setMaterial(painted.material(), 1.3f);
        fresh.setInjectionSamples(texels);
        const SslpvStats reference = fresh.solve();
        std::printf("mode %d: injected red %.4g -> %.4g (fresh %.4g), %d beams again\n", int(mode),
                    double(first.injected.x), double(after.injected.x),
                    double(reference.injected.x), after.rewalkedTexels);
        EXPECT_GT(reference.injected.x, 1.05f * first.injected.x);  // the stroke matters
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(after.injected[c], reference.injected[c], 1e-5f * reference.injected[c]);
            EXPECT_NEAR(painted.accumulation().flux()[c], fresh.accumulation().flux()[c],
                        1e-5f * fresh.accumulation().flux()[c]);
        }
        // σs′ alone does not touch the chords: no beam is injected again.
        for (auto& v : painted.material().sigma_s[1])
            v *= 0.5f;
        painted.markMaterialDirty();
        const SslpvStats scattering = painted.solve();
        EXPECT_FALSE(scattering.reinjected);
        EXPECT_EQ(scattering.rewalkedTexels, 0);
    }
}
