// SPDX-License-Identifier: MIT
/// @file
/// @brief Active-brick propagation (SslpvOptions::skipEmptySlices) against the dense solve:
/// heterogeneous stress scenes, the default scene, a small lit region; bricks per step.

#include <lucent/sslpv/SslpvRenderer.h>
#include <lucent/sslpv/SslpvSolver.h>
#include <lucent/sslpv/Transfer.h>

#include <lucent/core/Error.h>
#include <lucent/core/Random.h>
#include <lucent/scene/SceneFile.h>

#include "SslpvTestGrids.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

using namespace lucent;
using namespace lucent::sslpv;

namespace {

/// Ball of radius 0.35·N cells in an N³ grid of cell size h, every inside cell with its own
/// σt = st·(0.5 + u), σs′ = min(ss·(0.5 + u′), σt) and g = clamp(g + 0.2(u″ − ½)) (seeded).
CoarseMaterial hetBall(int n, float h, float st, float ss, float g, uint64_t seed) {
    CoarseMaterial m = test::centredMaterial(n, h);
    Pcg32 rng(seed);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                if (glm::length(m.spec.cellCenter({x, y, z})) > 0.35f * n * h)
                    continue;
                const size_t k = m.spec.linearIndex({x, y, z});
                m.insideFraction[k] = 1.f;
                for (int c = 0; c < 3; ++c) {
                    m.sigma_t[c][k] = st * (0.5f + rng.uniform());
                    m.sigma_s[c][k] = std::min(ss * (0.5f + rng.uniform()), m.sigma_t[c][k]);
                    m.g[c][k] = std::clamp(g + 0.2f * (rng.uniform() - 0.5f), -0.99f, 0.99f);
                }
            }
    return m;
}

/// Directional light along `dir` onto the ball: 24² texels over its disc.
std::vector<SslpvInjectionSample> ballTexels(const CoarseMaterial& m, Vector3f dir) {
    return test::ballTexels(m, dir, Rgb(1.f, 0.7f, 0.4f), /*texels=*/24);
}

/// The grids must be identical: active bricks compute every non-zero cell with the same
/// arithmetic as the dense solve, every other cell is exactly zero in both. The energy sums
/// differ only by float reassociation (rows are split into different SIMD blocks): relative
/// ~1e-7 per addition over ≤ 24³ cells × 64 steps, bounded here by 1e-5 of the injected flux.
void expectSameSolve(const SslpvSolver& active, const SslpvSolver& dense, const std::string& what) {
    SCOPED_TRACE(what);
    EXPECT_EQ(active.accumulation().raw(), dense.accumulation().raw());
    EXPECT_EQ(active.exitant().raw(), dense.exitant().raw());
    EXPECT_EQ(active.propagation().raw(), dense.propagation().raw());
    const SslpvStats &a = active.stats(), &d = dense.stats();
    EXPECT_EQ(a.stepsUsed, d.stepsUsed);
    EXPECT_EQ(a.brickCount, d.brickCount);
    ASSERT_EQ(a.activeBricksPerStep.size(), size_t(a.stepsUsed));
    for (int k = 0; k < a.stepsUsed; ++k) {
        EXPECT_LE(a.activeBricksPerStep[size_t(k)], a.brickCount);
        EXPECT_EQ(d.activeBricksPerStep[size_t(k)], d.brickCount);
    }
    for (int c = 0; c < 3; ++c) {
        const float tol = 1e-5f * d.injected[c] + 1e-30f;
        EXPECT_EQ(a.injected[c], d.injected[c]);
        EXPECT_NEAR(a.remaining[c], d.remaining[c], tol);
        EXPECT_NEAR(a.exitant[c], d.exitant[c], tol);
        EXPECT_NEAR(a.absorbed[c], d.absorbed[c], tol);
    }
}

}  // namespace

TEST(SslpvBricks, EqualDenseOnHeterogeneousStressScenes) {
    struct Case {
        const char* name;
        float st, ss, g, cell;
        int steps;
    };
    const Case cases[] = {
        {"sigma_t->0", 1e-9f, 0.f, 0.f, 1.f, 40},    {"sigma_t=1e4", 1e4f, 5e3f, 0.f, 1.f, 12},
        {"sigma_s=sigma_t", 3.f, 3.f, 0.f, 1.f, 40}, {"g=+0.99", 1.f, 1.f, 0.95f, 1.f, 24},
        {"g=-0.99", 1.f, 1.f, -0.95f, 1.f, 24},      {"cell=1e-3mm", 1.f, 0.9f, 0.f, 1e-3f, 24},
        {"cell=1e3mm", 1.f, 0.9f, 0.f, 1e3f, 24},    {"1 step", 1.f, 0.9f, 0.5f, 1.f, 1},
        {"marble-like", 2.f, 1.9f, 0.2f, 0.7f, 64},
    };
    for (const Case& c : cases)
        for (int order : {1, 2})
            for (bool sinks : {true, false})
                for (SslpvMode mode : {SslpvMode::Paper, SslpvMode::Calibrated}) {
                    const int n = order == 1 ? 22 : 14;  // L2 is ~6× slower per cell
                    const CoarseMaterial m = hetBall(n, c.cell, c.st, c.ss, c.g, 17);
                    SslpvOptions o{.order = order,
                                   .maxSteps = c.steps,
                                   .skipAccumulateSteps = 2,
                                   .removeExitant = sinks,
                                   .attenuation = SslpvAttenuation::Absorption};
                    o.mode = mode;
                    SslpvSolver active(o);
                    o.skipEmptySlices = false;
                    SslpvSolver dense(o);
                    for (SslpvSolver* s : {&active, &dense})
                        s->setMaterial(m, 1.3f);
                    // Several lights in turn: the grids keep stale values between solves.
                    for (Vector3f dir :
                         {Vector3f(0, 0, -1), Vector3f(1, 0.3f, 0.2f), Vector3f(0.1f, -1, 0.4f)}) {
                        const auto texels = ballTexels(m, dir);
                        for (SslpvSolver* s : {&active, &dense}) {
                            s->setInjectionSamples(texels);
                            s->solve();
                        }
                        expectSameSolve(active, dense,
                                        std::string(c.name) + " order " + std::to_string(order) +
                                            (sinks ? " sinks" : " no sinks") +
                                            (mode == SslpvMode::Paper ? " paper" : " calibrated"));
                    }
                }
}

TEST(SslpvBricks, EqualDenseOnTheDefaultScene) {
    const std::filesystem::path file = std::filesystem::path(LUCENT_SCENES_DIR) / "minimal.json";
    if (!std::filesystem::exists(file))
        GTEST_SKIP() << file << " not found";
    const Scene scene = loadScene(file.string());
    // 48³: dense rows (the box, ≈ 46 cells) end in the kernel's scalar tail where the active
    // runs use vectors, and vice versa, so this also checks both paths agree bit for bit.
    for (int order : {1, 2}) {
        SslpvRenderOptions ro;
        ro.gridResolution = order == 1 ? 48 : 32;
        ro.injectionResolution = 96;
        ro.solver.order = order;
        ro.solver.maxSteps = order == 1 ? 32 : 12;
        ro.solver.mode = SslpvMode::Calibrated;
        SslpvRenderer active(ro);
        ro.solver.skipEmptySlices = false;
        SslpvRenderer dense(ro);
        for (SslpvRenderer* r : {&active, &dense}) {
            r->setMesh(scene.objects[0].mesh);
            r->setLights(scene.lights);
            r->setMaterial(*scene.objects[0].material, scene.eta);
            r->update();
        }
        expectSameSolve(active.solver(), dense.solver(),
                        "minimal.json order " + std::to_string(order));
        EXPECT_GT(active.solver().stats().injected.y, 0.f);
        // A point light lights one side of the sphere: early steps skip most bricks.
        EXPECT_LT(active.solver().stats().activeBricksPerStep.front(),
                  active.solver().stats().brickCount / 2);
    }
}

TEST(SslpvBricks, SmallLitRegionActivatesOnlyItsNeighbourhood) {
    // Every cell material, no sinks (the paper's set-up), 40³; one unit texel at normal
    // incidence lands in cell (21, 21, 39), inside brick (5, 5) of the top slice.
    const int n = 40;
    CoarseMaterial m = hetBall(n, 1.f, 1.f, 0.8f, 0.3f, 5);
    std::fill(m.insideFraction.begin(), m.insideFraction.end(), 1.f);
    for (int c = 0; c < 3; ++c)
        for (size_t k = 0; k < m.spec.voxelCount(); ++k)
            if (m.sigma_t[c][k] == 0.f) {
                m.sigma_t[c][k] = 1.f;
                m.sigma_s[c][k] = 0.8f;
            }
    const float top = m.spec.origin.z + n;
    const std::vector<SslpvInjectionSample> spot = {
        {Point3f(m.spec.origin.x + 21.5f, m.spec.origin.y + 21.5f, top), Normal3f(0, 0, 1),
         Vector3f(0, 0, -1), Rgb(1.f)}};
    SslpvOptions o{.maxSteps = 8, .skipAccumulateSteps = 0, .removeExitant = false};
    SslpvSolver active(o);
    o.skipEmptySlices = false;
    SslpvSolver dense(o);
    for (SslpvSolver* s : {&active, &dense}) {
        s->setMaterial(m, 1.3f);
        s->setInjectionSamples(spot);
        s->solve();
    }
    expectSameSolve(active, dense, "spot");
    const SslpvStats& st = active.stats();
    EXPECT_EQ(st.brickCount, 10 * 10 * 40);
    // Step 1: the lit brick, its four neighbours in the slice and the one below (none above).
    EXPECT_EQ(st.activeBricksPerStep[0], 6);
    // After k steps light reaches at most k cells from (21, 21): x, y ∈ [21 − k, 21 + k], so
    // the active bricks lie within ⌈(k + 1 + 4)/4⌉ bricks of it per side and k + 1 slices.
    for (int k = 1; k <= 8; ++k) {
        const int lo = (21 - (k - 1)) / 4 - 1, hi = (21 + (k - 1)) / 4 + 1;
        EXPECT_LE(st.activeBricksPerStep[size_t(k - 1)], (hi - lo + 1) * (hi - lo + 1) * (k + 1))
            << "step " << k;
    }
    EXPECT_LT(st.cellsComputed * 10, dense.stats().cellsComputed);
}
TEST(SslpvBricks, StepMatchesBruteForceGather) {
    // Independent of the kernel: one step recomputed cell by cell from §4's gather
    // c_d,i = Σ_o Σ_j M_o[i][j] c_{d+o,j}, then sinks and the folded factors, for rows longer
    // than one 32-cell SIMD block (a 46-cell box in a 48³ grid), active and dense.
    const int n = 48;
    CoarseMaterial m = hetBall(n, 1.f, 1.f, 0.9f, 0.2f, 3);
    for (int z = 0; z < n; ++z)  // a ball of radius 0.47·N
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                m.insideFraction[m.spec.linearIndex({x, y, z})] =
                    glm::length(m.spec.cellCenter({x, y, z})) <= 0.47f * n ? 1.f : 0.f;
    for (int c = 0; c < 3; ++c)
        for (size_t k = 0; k < m.spec.voxelCount(); ++k)
            if (m.insideFraction[k] > 0.f && m.sigma_t[c][k] == 0.f) {
                m.sigma_t[c][k] = 1.f;
                m.sigma_s[c][k] = 0.9f;
            }
    const auto texels = ballTexels(m, Vector3f(0.3f, 0.2f, -1.f));
    const auto& M = propagationMatrices(1);
    const Coord off[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (bool dense : {false, true}) {
        SslpvOptions o{.maxSteps = 1, .skipAccumulateSteps = 0};
        o.skipEmptySlices = !dense;
        SslpvSolver one(o);
        o.maxSteps = 2;
        SslpvSolver two(o);
        for (SslpvSolver* s : {&one, &two}) {
            s->setMaterial(m, 1.3f);
            s->setInjectionSamples(texels);
            s->solve();
        }
        const SslpvGrid& src = one.propagation();
        std::vector<float> fac[2] = {two.foldedFactorPlane(0, 0), two.foldedFactorPlane(0, 1)};
        int bad = 0;
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const Coord d(x, y, z);
                    const size_t k = src.index(d);
                    const bool inside = two.isInside(d);
                    for (int i = 0; i < 4; ++i) {
                        double c = 0.0, mag = 0.0;
                        for (int nb = 0; nb < 6; ++nb) {
                            const Coord s = d + off[nb];
                            if (glm::any(glm::lessThan(s, Coord(0))) ||
                                glm::any(glm::greaterThanEqual(s, Coord(n))))
                                continue;  // the zero border
                            for (int j = 0; j < 4; ++j) {
                                c += M[nb].at(i, j) * src.at(s, 0, j);
                                mag += std::abs(M[nb].at(i, j) * src.at(s, 0, j));
                            }
                        }
                        // float sums of ≤ 24 terms: relative 1e-6 of the terms' magnitude.
                        const double tol = 1e-6 * mag + 1e-30;
                        const double expExit = one.exitant().at(d, 0, i) + (inside ? 0.0 : c);
                        const double expProp = inside ? c * fac[i == 0 ? 0 : 1][k] : 0.0;
                        if (std::abs(two.exitant().at(d, 0, i) - expExit) >
                                tol + 1e-6 * std::abs(expExit) ||
                            std::abs(two.propagation().at(d, 0, i) - expProp) > tol)
                            ++bad;
                    }
                }
        EXPECT_EQ(bad, 0) << (dense ? "dense" : "active");
    }
}

namespace {

/// Σ c00 over the cells with x ≥ xFrom of a grid (band 0 of channel `ch`), flux units.
double fluxFrom(const SslpvGrid& g, int ch, int xFrom) {
    const int n = g.resolution();
    double sum = 0.0;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = xFrom; x < n; ++x)
                sum += double(g.plane(ch, 0)[g.index({x, y, z})]);
    return sum * 2.0 * std::sqrt(3.14159265358979323846);
}

}  // namespace

TEST(SslpvBricks, BrickStopDropsAtMostWhatItCounts) {
    // SslpvOptions::brickStopEpsilon against the exact solve of as many steps. The stop sets to
    // zero bricks whose every value is under d = ε·max(injected)/(2√π·cells that hold light), so
    // what it drops per cell and step is at most 2√π·d in flux: in all at most
    // ε·max(injected)·(cells computed)/(cells that hold light). Dropped light would only have
    // been split between the sinks, absorption and the grid (energy never grows, as for the
    // global stop: EarlyStopDropsAtMostTheFluxLeftInTheGrid), so the exact solve's exitant flux
    // exceeds the stopped one's by between 0 and the dropped flux, and its accumulation by at
    // most (steps)·(dropped flux). Rounding: 2e-4 of the injected flux (float sums).
    const float eps = 1e-4f;
    for (SslpvMode mode : {SslpvMode::Paper, SslpvMode::Calibrated})
        for (int order : {1, 2}) {
            SCOPED_TRACE(std::string(mode == SslpvMode::Paper ? "paper" : "calibrated") +
                         " order " + std::to_string(order));
            const int n = order == 1 ? 24 : 16;
            const CoarseMaterial m = hetBall(n, 1.f, 2.f, 1.2f, 0.2f, 23);
            SslpvOptions o{.order = order, .maxSteps = 400, .skipAccumulateSteps = 2};
            o.mode = mode;
            SslpvSolver exact(o);
            o.brickStopEpsilon = eps;
            SslpvSolver stopped(o);
            const auto texels = ballTexels(m, Vector3f(0.2f, 0.1f, -1.f));
            for (SslpvSolver* s : {&exact, &stopped}) {
                s->setMaterial(m, 1.3f);
                s->setInjectionSamples(texels);
                s->solve();
            }
            const SslpvStats &a = stopped.stats(), &b = exact.stats();
            EXPECT_EQ(b.stepsUsed, 400);
            EXPECT_LT(a.stepsUsed, 400) << "every brick dark: the solve ends";
            EXPECT_LT(a.cellsComputed * 2, b.cellsComputed);
            int64_t lightCells = 0;
            for (float f : m.insideFraction)
                lightCells += f > 0.f;
            const float brightest = std::max({a.injected.x, a.injected.y, a.injected.z});
            const Rgb accA = stopped.accumulation().flux(), accB = exact.accumulation().flux();
            for (int c = 0; c < 3; ++c) {
                SCOPED_TRACE("channel " + std::to_string(c));
                const float tol = 2e-4f * a.injected[c];
                EXPECT_EQ(a.injected[c], b.injected[c]);
                EXPECT_EQ(b.dropped[c], 0.f);
                EXPECT_GT(a.dropped[c], 0.f);
                EXPECT_LE(a.dropped[c],
                          eps * brightest * float(a.cellsComputed) / float(lightCells));
                EXPECT_GE(b.exitant[c] - a.exitant[c], -tol);
                EXPECT_LE(b.exitant[c] - a.exitant[c], a.dropped[c] + tol);
                EXPECT_GE(accB[c] - accA[c], -tol);
                EXPECT_LE(accB[c] - accA[c], float(b.stepsUsed) * a.dropped[c] + tol);
            }
            // Off, the stop changes nothing: the exact solve's grids bit for bit.
            o.brickStopEpsilon = 0.f;
            stopped.setOptions(o);
            stopped.solve();
            EXPECT_EQ(stopped.accumulation().raw(), exact.accumulation().raw());
        }
}

TEST(SslpvBricks, BrickStopIsLocalPaintDoesNotEndThePropagationElsewhere) {
    // Why the live preview can stop per brick where it could not stop globally (the method's
    // `steps` parameter): two separate balls of a bright medium, each lit from above; an
    // absorber is painted into ball A (σs′ lowered, σt kept, so the injection does not change).
    // Ball B's light never meets the paint. With the per-brick stop its bricks carry on until
    // their own light is dark, so B's accumulation is bit for bit what it was; the global stop
    // (stopEpsilon at the same ε) ends the whole solve sooner once A absorbs, and B dims (by
    // 2.7·10⁻⁴ here: the global stop's loss is bounded by ε too, but it is taken from light
    // that the stroke never touched).
    const int n = 48;
    const Point3f centres[2] = {Point3f(-12.f, 0.f, 0.f), Point3f(12.f, 0.f, 0.f)};
    const float radius = 9.f;
    auto material = [&](float albedoA) {
        CoarseMaterial m = test::centredMaterial(n, 1.f);
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const Point3f p = m.spec.cellCenter({x, y, z});
                    for (int b = 0; b < 2; ++b) {
                        if (glm::length(p - centres[b]) > radius)
                            continue;
                        const size_t k = m.spec.linearIndex({x, y, z});
                        m.insideFraction[k] = 1.f;
                        for (int c = 0; c < 3; ++c) {
                            m.sigma_t[c][k] = 1.f;
                            m.sigma_s[c][k] = b == 0 ? albedoA : 0.99f;
                        }
                    }
                }
        return m;
    };
    std::vector<SslpvInjectionSample> tops;  // 1 mm² texels over each ball's upper cap
    for (const Point3f& c : centres)
        for (float u = -6.5f; u <= 6.5f; u += 1.f)
            for (float v = -6.5f; v <= 6.5f; v += 1.f) {
                const Point3f p = c + Vector3f(u, v, std::sqrt(radius * radius - u * u - v * v));
                tops.push_back({p, glm::normalize(p - c), Vector3f(0, 0, -1), Rgb(1.f)});
            }
    const float eps = 1e-4f;
    // B's cells: x ≥ 24 (the balls are 6 cells apart at x = 20..27).
    auto ballB = [&](const SslpvSolver& s) {
        std::vector<float> out;
        const SslpvGrid& g = s.accumulation();
        for (int ch = 0; ch < 3; ++ch)
            for (int i = 0; i < g.coeffCount(); ++i)
                for (int z = 0; z < n; ++z)
                    for (int y = 0; y < n; ++y)
                        for (int x = 24; x < n; ++x)
                            out.push_back(g.plane(ch, i)[g.index({x, y, z})]);
        return out;
    };
    double sumB[2][2] = {};  // [global, local][before, after]
    std::vector<float> localB[2];
    int steps[2][2] = {};
    for (int painted = 0; painted < 2; ++painted) {
        const CoarseMaterial m = material(painted ? 0.2f : 0.99f);
        SslpvOptions o{.maxSteps = 400, .skipAccumulateSteps = 0};
        o.mode = SslpvMode::Calibrated;
        o.brickStopEpsilon = eps;
        SslpvSolver local(o);
        o.brickStopEpsilon = 0.f;
        o.stopEpsilon = eps;
        SslpvSolver global(o);
        for (SslpvSolver* s : {&local, &global}) {
            s->setMaterial(m, 1.f);
            s->setInjectionSamples(tops);
            s->solve();
        }
        ASSERT_LT(local.stats().stepsUsed, 400);
        localB[painted] = ballB(local);
        sumB[0][painted] = fluxFrom(global.accumulation(), 1, 24);
        sumB[1][painted] = fluxFrom(local.accumulation(), 1, 24);
        steps[0][painted] = global.stats().stepsUsed;
        steps[1][painted] = local.stats().stepsUsed;
    }
    std::printf(
        "[sslpv bricks] paint in ball A: ball B's accumulation x %.6f with the global "
        "stop (steps %d -> %d), x %.6f with the per-brick stop (steps %d -> %d)\n",
        sumB[0][1] / sumB[0][0], steps[0][0], steps[0][1], sumB[1][1] / sumB[1][0], steps[1][0],
        steps[1][1]);
    EXPECT_EQ(localB[1], localB[0]);
    EXPECT_LT(sumB[0][1] / sumB[0][0], 1.0 - 1e-5);
}

TEST(SslpvBricks, ContinuedPropagationIsOneLongerSolve) {
    // SslpvSolver::continuePropagation, the live preview's idle frames: a solve of a few steps
    // carried on, chunk by chunk, must run exactly the steps of one solve with the larger step
    // limit — the same grids bit for bit, the same energy sums, the same stopping step — with
    // each stop rule (none, the global stop, the per-brick stop), in both modes and orders.
    // A bright heterogeneous ball (σs′ = σt in most cells) keeps light in flight for long.
    struct Stop {
        const char* name;
        float global, brick;
    };
    const Stop stops[] = {
        {"no stop", 0.f, 0.f}, {"global stop", 1e-3f, 0.f}, {"brick stop", 0.f, 1e-4f}};
    const int limit = 150;
    for (const Stop& stop : stops)
        for (SslpvMode mode : {SslpvMode::Paper, SslpvMode::Calibrated})
            for (int order : {1, 2})
                for (int chunk : {1, 32}) {
                    SCOPED_TRACE(std::string(stop.name) +
                                 (mode == SslpvMode::Paper ? " paper" : " calibrated") + " order " +
                                 std::to_string(order) + " chunk " + std::to_string(chunk));
                    const int n = order == 1 ? 20 : 12;
                    const CoarseMaterial m = hetBall(n, 1.f, 1.f, 1.2f, 0.3f, 29);
                    SslpvOptions o{.order = order,
                                   .maxSteps = limit,
                                   .skipAccumulateSteps = 2,
                                   .attenuation = SslpvAttenuation::Absorption};
                    o.mode = mode;
                    o.stopEpsilon = stop.global;
                    o.brickStopEpsilon = stop.brick;
                    SslpvSolver whole(o);
                    o.maxSteps = chunk;
                    SslpvSolver chunked(o);
                    const auto texels = ballTexels(m, Vector3f(0.3f, -0.2f, -1.f));
                    for (SslpvSolver* s : {&whole, &chunked}) {
                        s->setMaterial(m, 1.3f);
                        s->setInjectionSamples(texels);
                        s->solve();
                    }
                    ASSERT_EQ(chunked.stats().stepsUsed, chunk);
                    ASSERT_TRUE(chunked.propagationInFlight());
                    int calls = 0;
                    while (chunked.propagationInFlight() && chunked.stats().stepsUsed < limit) {
                        const int more =
                            std::min(chunk + calls % 3, limit - chunked.stats().stepsUsed);
                        const SslpvStats& st = chunked.continuePropagation(more);
                        EXPECT_TRUE(st.repropagated);
                        EXPECT_FALSE(st.reinjected);
                        ASSERT_LT(++calls, 1000);
                    }
                    const SslpvStats &a = chunked.stats(), &b = whole.stats();
                    EXPECT_EQ(a.stepsUsed, b.stepsUsed);
                    EXPECT_EQ(chunked.accumulation().raw(), whole.accumulation().raw());
                    EXPECT_EQ(chunked.exitant().raw(), whole.exitant().raw());
                    EXPECT_EQ(chunked.propagation().raw(), whole.propagation().raw());
                    EXPECT_EQ(a.activeBricksPerStep, b.activeBricksPerStep);
                    EXPECT_EQ(a.cellsComputed, b.cellsComputed);
                    for (int c = 0; c < 3; ++c) {
                        EXPECT_EQ(a.injected[c], b.injected[c]);
                        EXPECT_EQ(a.remaining[c], b.remaining[c]);
                        EXPECT_EQ(a.exitant[c], b.exitant[c]);
                        EXPECT_EQ(a.absorbed[c], b.absorbed[c]);
                        EXPECT_EQ(a.dropped[c], b.dropped[c]);
                    }
                    EXPECT_EQ(chunked.propagationInFlight(), whole.propagationInFlight());
                    if (stop.global == 0.f && stop.brick == 0.f)
                        EXPECT_EQ(b.stepsUsed, limit) << "no stop: the light is still in flight";
                    else
                        EXPECT_LT(b.stepsUsed, limit) << "a stop rule ended the solve";
                }
}

TEST(SslpvBricks, OnlyAPropagationInFlightCanBeContinued) {
    const CoarseMaterial m = hetBall(16, 1.f, 1.f, 0.98f, 0.f, 31);
    SslpvOptions o{.maxSteps = 8};
    SslpvSolver s(o);
    EXPECT_FALSE(s.propagationInFlight());  // nothing solved yet
    EXPECT_THROW(s.continuePropagation(8), ValueError);
    s.setMaterial(m, 1.3f);
    s.setInjectionSamples(ballTexels(m, Vector3f(0, 0, -1)));
    EXPECT_FALSE(s.propagationInFlight());
    s.solve();
    EXPECT_TRUE(s.propagationInFlight());
    EXPECT_THROW(s.continuePropagation(0), ValueError);
    // A changed input makes the propagation start again: nothing to carry on until solved.
    s.setMaterial(m, 1.4f);
    EXPECT_FALSE(s.propagationInFlight());
    EXPECT_THROW(s.continuePropagation(8), ValueError);
    s.solve();
    EXPECT_EQ(s.stats().stepsUsed, 8);
    s.continuePropagation(8);
    EXPECT_EQ(s.stats().stepsUsed, 16);
    // Stopped by a stop rule (all light gone): nothing in flight.
    o.maxSteps = 4096;
    o.brickStopEpsilon = 1e-3f;
    s.setOptions(o);
    s.solve();
    EXPECT_LT(s.stats().stepsUsed, 4096);
    EXPECT_FALSE(s.propagationInFlight());
    // Mode diffusion solves, it does not step.
    o.mode = SslpvMode::Diffusion;
    o.maxSteps = 1;
    s.setOptions(o);
    s.solve();
    EXPECT_FALSE(s.propagationInFlight());
}
