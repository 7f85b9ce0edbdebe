// SPDX-License-Identifier: MIT
/// @file
/// @brief SSLPV's mode `diffusion` (GridDiffusion): the diffuse Fresnel moments against their
/// identities, the discrete solve against the closed form of a lit half-space (and its order of
/// convergence), energy balance, warm starts, and bad input (docs/methods/sslpv.md, "Diffusion
/// mode").

#include <lucent/sslpv/GridDiffusion.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Parallel.h>
#include <lucent/dipole/HalfSpace.h>

#include "SslpvTestGrids.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <tuple>

using namespace lucent;
using namespace lucent::sslpv;

namespace {

/// A homogeneous box of N³ cells of h mm, every cell inside, lit from above (+z) at normal
/// incidence by irradiance E = 1 W/mm² (4 texels per top cell).
struct LitBox {
    CoarseMaterial material;
    std::vector<SslpvInjectionSample> texels;
};

/// `topFraction` < 1: the surface lies inside the top layer of cells, whose inside fraction it
/// is (below ½ those cells are not medium and the surface is in the layer's neighbour's reach).
LitBox litBox(int n, float h, float sigmaT, float sigmaS, float topFraction = 1.f) {
    LitBox b;
    b.material = test::centredMaterial(n, h, sigmaT, sigmaS, 0.f);
    std::fill(b.material.insideFraction.begin(), b.material.insideFraction.end(), 1.f);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            b.material.insideFraction[b.material.spec.linearIndex({x, y, n - 1})] = topFraction;
    b.material.homogeneous = true;
    const float top = 0.5f * float(n) * h - (1.f - topFraction) * h;
    const float pitch = 0.5f * h;
    for (int j = 0; j < 2 * n; ++j)
        for (int i = 0; i < 2 * n; ++i)
            b.texels.push_back(
                {Point3f(-top + (float(i) + 0.5f) * pitch, -top + (float(j) + 0.5f) * pitch, top),
                 Normal3f(0, 0, 1), Vector3f(0, 0, -1), Rgb(pitch * pitch)});
    return b;
}

/// litBox with only its top `layers` layers of cells medium: a slab over the whole grid, lit
/// from above, its far face at the empty cells beneath.
LitBox litSlab(int n, float h, float sigmaT, float sigmaS, int layers) {
    LitBox b = litBox(n, h, sigmaT, sigmaS);
    for (int z = 0; z < n - layers; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                b.material.insideFraction[b.material.spec.linearIndex({x, y, z})] = 0.f;
    return b;
}

/// The exitance J = φ(0)/(2A) of a half-space under the collimated first-scattering source
/// α′σt′·E_t·e^(−σt′z), E_t = (1 − F(1, η))·E: the diffusion equation's closed form
/// φ = C e^(−σtr z) + K e^(−σt′ z), K = α′σt′E_t/(σa − Dσt′²), C from φ(0) = 2AD φ′(0).
double halfSpaceExitance(double sigmaT, double sigmaS, double eta, double E = 1.0) {
    const double sa = sigmaT - sigmaS, D = 1.0 / (3.0 * sigmaT);
    const double str = std::sqrt(sa / D);
    const double A = diffusionBoundaryConstant(eta);
    const double Et = (1.0 - fresnelDielectric(1.0, eta)) * E;
    const double K = (sigmaS / sigmaT) * sigmaT * Et / (sa - D * sigmaT * sigmaT);
    const double C = -K * (1.0 + 2.0 * A * D * sigmaT) / (1.0 + 2.0 * A * D * str);
    return (C + K) / (2.0 * A);
}

/// The box solved in mode diffusion to an unbalanced power of 10⁻⁷.
std::unique_ptr<SslpvSolver> solvedBox(const LitBox& box, float eta, bool exactTotal,
                                       bool exitTable = true, bool slabTotal = false) {
    SslpvOptions o;
    o.mode = SslpvMode::Diffusion;
    o.diffusionExactTotal = exactTotal;
    o.diffusionSlabTotal = slabTotal;
    o.diffusionExitTable = exitTable;
    o.maxSteps = 4096;
    o.stopEpsilon = 1e-7f;
    auto s = std::make_unique<SslpvSolver>(o);
    s->setMaterial(box.material, eta);
    s->setInjectionSamples(box.texels);
    s->solve();
    return s;
}

/// The solver's exitance at the centre of the top face: radiance() returns
/// L_i = η²·J/(π(1 − F_dr(η))).
double solvedTopExitance(const LitBox& box, float eta, float topFraction = 1.f,
                         bool exactTotal = false) {
    const std::unique_ptr<SslpvSolver> solver = solvedBox(box, eta, exactTotal);
    const SslpvSolver& s = *solver;
    const float h = box.material.spec.voxelSize;
    const float top = 0.5f * float(box.material.spec.resolution) * h - (1.f - topFraction) * h;
    const Rgb L = s.radiance(Point3f(0.f, 0.f, top), Normal3f(0, 0, 1));
    return double(L.y) * PI * (1.0 - diffuseFresnelReflectance(eta)) / (double(eta) * eta);
}

}  // namespace

TEST(GridDiffusion, DiffuseFresnelMomentsObeyTheirIdentities) {
    EXPECT_NEAR(diffuseFresnelReflectance(1.0), 0.0, 1e-12);
    EXPECT_NEAR(diffusionBoundaryConstant(1.0), 1.0, 1e-12);
    for (double eta : {1.1, 1.3, 1.5, 2.5}) {
        // Reciprocity: what a Lambertian field loses into the medium from outside equals what
        // leaves from inside, scaled by η²: 1 − F_dr(1/η) = (1 − F_dr(η))/η². (The quadrature
        // rule meets the square-root edge at the critical angle: 10⁻⁶, not machine precision.)
        EXPECT_NEAR(1.0 - diffuseFresnelReflectance(1.0 / eta),
                    (1.0 - diffuseFresnelReflectance(eta)) / (eta * eta), 1e-5)
            << eta;
    }
    // Egan & Hilgeman's fit (Jensen et al. 2001, Eq. 13 form) of F_dr,int at η = 1.3: 0.4447
    // (the fit is good to about 1 %).
    EXPECT_NEAR(diffuseFresnelReflectance(1.0 / 1.3), 0.4447, 0.005);
}

TEST(GridDiffusion, LitHalfSpaceConvergesToTheClosedFormAtSecondOrder) {
    // σt′ = 2 mm⁻¹, α′ = 0.8: diffusion length 1/σtr = 0.65 mm, so the 8 mm box's centre is
    // 6 diffusion lengths from every other face (their effect e^−6 ≈ 0.25 % of the flux there,
    // less at the top face's centre). Cells of 0.5 and 0.25 mean free paths.
    for (const float eta : {1.f, 1.3f}) {
        const double exact = halfSpaceExitance(2.0, 1.6, eta);
        const double coarse = solvedTopExitance(litBox(32, 0.25f, 2.f, 1.6f), eta);
        const double fine = solvedTopExitance(litBox(64, 0.125f, 2.f, 1.6f), eta);
        const double eCoarse = std::abs(coarse / exact - 1.0), eFine = std::abs(fine / exact - 1.0);
        SCOPED_TRACE(testing::Message() << "eta " << eta << ": exact " << exact << ", grid 32 "
                                        << coarse << ", grid 64 " << fine);
        // Cell-centred finite volumes with exact cell integrals of the source: second order, so
        // halving the cell must cut the error by about 4 (at least 3 allowing for the lateral
        // faces' share); the fine grid within 1 %.
        EXPECT_LT(eFine, 0.01);
        EXPECT_LT(eFine, eCoarse / 3.0);
    }
}

TEST(GridDiffusion, ThinLitSlabConvergesToTheModelsClosedForm) {
    // A slab of optical thickness 1 (σt′ = 2 mm⁻¹, α′ = 0.8, 0.5 mm thick) over the whole grid,
    // lit from above at normal incidence: both faces' exitance at the centre against the
    // model's closed form (diffusionSlabExitance) times the transmitted irradiance. 4 and 8
    // cells through the slab; the slab is 16 diffusion lengths of its lowest lateral mode wide,
    // so its edges do not reach the centre. So a thin part's error on the suite is the model's
    // (docs/methods/sslpv.md, "The model's own error on thin layers"), not the solve's.
    constexpr float SIGMA_T = 2.f, SIGMA_S = 1.6f, ETA = 1.4f, THICKNESS = 0.5f, WIDTH = 8.f;
    const DiffusionSlabExitance model =
        diffusionSlabExitance(SIGMA_S / SIGMA_T, ETA, SIGMA_T * THICKNESS);
    const double transmitted = 1.0 - fresnelDielectric(1.0, double(ETA));
    double error[2][2] = {};
    for (int level = 0; level < 2; ++level) {
        const int layers = 4 << level, n = int(WIDTH / THICKNESS) * layers;
        const float h = THICKNESS / float(layers);
        const LitBox box = litSlab(n, h, SIGMA_T, SIGMA_S, layers);
        const std::unique_ptr<SslpvSolver> solver = solvedBox(box, ETA, false);
        const float top = 0.5f * float(n) * h, bottom = top - THICKNESS;
        const double toExitance = PI * (1.0 - diffuseFresnelReflectance(ETA)) / (double(ETA) * ETA);
        const double reflected =
            double(solver->radiance(Point3f(0.f, 0.f, top), Normal3f(0, 0, 1)).y) * toExitance;
        const double throughSlab =
            double(solver->radiance(Point3f(0.f, 0.f, bottom), Normal3f(0, 0, -1)).y) * toExitance;
        error[level][0] = reflected / (model.reflectance * transmitted) - 1.0;
        error[level][1] = throughSlab / (model.transmittance * transmitted) - 1.0;
        SCOPED_TRACE(testing::Message()
                     << layers << " layers: R " << reflected << " T " << throughSlab << " against "
                     << model.reflectance * transmitted << ", "
                     << model.transmittance * transmitted);
        EXPECT_LT(std::abs(error[level][0]), level == 0 ? 0.05 : 0.02);
        EXPECT_LT(std::abs(error[level][1]), level == 0 ? 0.05 : 0.02);
    }
    std::printf("thin slab: R error %.4f -> %.4f, T error %.4f -> %.4f\n", error[0][0], error[1][0],
                error[0][1], error[1][1]);
}

TEST(GridDiffusion, ThinSlabNormalisedToTheExactSlabSendsOutItsTotal) {
    // The slab of ThinLitSlabConvergesToTheModelsClosedForm (τ = 1, α′ = 0.8, η = 1.4) with 4
    // cells through it: normalised to the exact slab of its thickness, its two faces send out
    // the exact slab's R + T (to the solve's 0.7 % and the table's interpolation); normalised to
    // the half-space, 9 % more — the excess the slab normalisation removes.
    constexpr float SIGMA_T = 2.f, SIGMA_S = 1.6f, ETA = 1.4f, THICKNESS = 0.5f;
    constexpr int LAYERS = 4, N = 64;
    const float h = THICKNESS / float(LAYERS);
    const LitBox box = litSlab(N, h, SIGMA_T, SIGMA_S, LAYERS);
    const dipole::SlabExitance exact =
        dipole::slabExitance(SIGMA_S / SIGMA_T, ETA, SIGMA_T * THICKNESS);
    const double transmitted = 1.0 - fresnelDielectric(1.0, double(ETA));
    const double expected = (exact.reflectance + exact.transmittance) * transmitted;
    const float top = 0.5f * float(N) * h, bottom = top - THICKNESS;
    const double toExitance = PI * (1.0 - diffuseFresnelReflectance(ETA)) / (double(ETA) * ETA);
    double total[2] = {};
    for (const bool slab : {false, true}) {
        const std::unique_ptr<SslpvSolver> solver = solvedBox(box, ETA, true, false, slab);
        total[slab] = (double(solver->radiance(Point3f(0.f, 0.f, top), Normal3f(0, 0, 1)).y) +
                       double(solver->radiance(Point3f(0.f, 0.f, bottom), Normal3f(0, 0, -1)).y)) *
                      toExitance;
    }
    SCOPED_TRACE(testing::Message()
                 << "half-space " << total[0] << ", slab " << total[1] << ", exact " << expected);
    std::printf("slab normalisation: half-space %.4f, slab %.4f of the exact total\n",
                total[0] / expected, total[1] / expected);
    EXPECT_NEAR(total[1] / expected, 1.0, 0.015);
    EXPECT_GT(total[0] / expected, 1.05);
}

TEST(GridDiffusion, ModelsSlabClosedFormHasTheHalfSpaceAndEnergyLimits) {
    for (double eta : {1.0, 1.4})
        for (double a : {0.3, 2.0 / 3.0, 0.84, 0.99}) {
            const DiffusionSlabExitance thick = diffusionSlabExitance(a, eta, 400.0);
            // 10⁻⁶: at α′ = 2/3 the closed form steps over its removable singularity by 2·10⁻⁷.
            EXPECT_NEAR(thick.reflectance, diffusionHalfSpaceReflectance(a, eta), 1e-6) << a;
            EXPECT_LT(thick.transmittance, 1e-9);
            // Continuous in α′ through the removable singularity at 2/3.
            const DiffusionSlabExitance s = diffusionSlabExitance(a, eta, 1.0);
            const DiffusionSlabExitance near = diffusionSlabExitance(a + 1e-5, eta, 1.0);
            EXPECT_NEAR(s.transmittance, near.transmittance, 1e-4) << a;
        }
    // No absorption: what scatters (1 − e^(−τ) of the transmitted beam) all leaves.
    for (double tau : {0.2, 1.0, 6.0}) {
        const DiffusionSlabExitance s = diffusionSlabExitance(1.0, 1.4, tau);
        EXPECT_NEAR(s.reflectance + s.transmittance, 1.0 - std::exp(-tau), 1e-6) << tau;
    }
    EXPECT_THROW(diffusionSlabExitance(0.5, 1.3, -1.0), ValueError);
    EXPECT_THROW(diffusionSlabExitance(NAN, 1.3, 1.0), ValueError);
}

TEST(GridDiffusion, SlabRatioIsTheHalfSpacesWhenThickAndBelowItWhenThin) {
    // At the table's thickest node the slab is the half-space (to the tables' interpolation,
    // 2·10⁻³); a layer of τ = 0.8 at α′ = 0.84 sends out 10 % less in transport than in the model
    // (docs/methods/sslpv.md, "The model's own error on thin layers"); at the nodes the table is
    // the ratio itself.
    for (const double eta : {1.0, 1.4}) {
        const std::shared_ptr<const ExactSlabRatio> slab = exactSlabRatio(eta);
        const std::shared_ptr<const ExactReflectanceRatio> halfSpace = exactReflectanceRatio(eta);
        for (const float a : {0.5f, 0.84f, 0.96f})
            EXPECT_NEAR((*slab)(a, 1000.f), (*halfSpace)(a), 2e-3) << "eta " << eta << " a " << a;
        const auto ratioAt = [&](double a, double tau) {
            const dipole::SlabExitance e = dipole::slabExitance(a, eta, tau);
            const DiffusionSlabExitance m = diffusionSlabExitance(a, eta, tau);
            return (e.reflectance + e.transmittance) / (m.reflectance + m.transmittance);
        };
        // Node: u = 12/32 (α′ = 0.859375), τ = (1/32)·1024^(16/32) = 1.
        EXPECT_NEAR((*slab)(0.859375f, 1.f), ratioAt(0.859375, 1.0), 1e-5) << eta;
        if (eta > 1.0) {
            EXPECT_NEAR((*slab)(0.84f, 0.8f), ratioAt(0.84, 0.8), 3e-3);
        }
    }
    EXPECT_LT((*exactSlabRatio(1.4))(0.84f, 0.8f), 0.92f);
    EXPECT_THROW(ExactSlabRatio(0.5), ValueError);
}

TEST(GridDiffusion, ChordLengthIsThePartsThicknessAlongTheNormal) {
    // A slab 6 cells thick whose faces cut the cells (fractions 0.7 on top, 0.3 beneath at the
    // bottom: 5 + 0.7 + 0.3 = 6 cells of medium), and a ball: the chord from a face's centre is the
    // slab's thickness, from the ball's top its diameter, each to the march's half-cell step
    // interpolated (a tenth of a cell here).
    constexpr int N = 24;
    constexpr float H = 0.5f;
    CoarseMaterial m = test::centredMaterial(N, H, 1.f, 0.8f, 0.f);
    for (int z = 0; z < N; ++z)
        for (int y = 0; y < N; ++y)
            for (int x = 0; x < N; ++x) {
                float f = 0.f;
                if (z >= 10 && z <= 14)
                    f = 1.f;
                else if (z == 15)
                    f = 0.7f;
                else if (z == 9)
                    f = 0.3f;
                m.insideFraction[m.spec.linearIndex({x, y, z})] = f;
            }
    GridDiffusion d;
    d.setMaterial(m, 1.3f);
    EXPECT_NEAR(d.chordLength(m.spec.linearIndex({N / 2, N / 2, 15})), 6.f * H, 0.1f * H);
    EXPECT_NEAR(d.chordLength(m.spec.linearIndex({N / 2, N / 2, 10})), 6.f * H, 0.1f * H);
    EXPECT_EQ(d.chordLength(m.spec.linearIndex({N / 2, N / 2, 12})), 0.f);  // interior

    // The ball: radius 8 cells about the grid's centre, each cell's fraction from 4³ sub-cells.
    CoarseMaterial ball = test::centredMaterial(N, H, 1.f, 0.8f, 0.f);
    const float radius = 8.f;  // cells
    for (int z = 0; z < N; ++z)
        for (int y = 0; y < N; ++y)
            for (int x = 0; x < N; ++x) {
                int in = 0;
                for (int k = 0; k < 64; ++k) {
                    const Vector3f p(float(x) + (float(k % 4) + 0.5f) / 4.f - 0.5f * N,
                                     float(y) + (float(k / 4 % 4) + 0.5f) / 4.f - 0.5f * N,
                                     float(z) + (float(k / 16) + 0.5f) / 4.f - 0.5f * N);
                    in += glm::dot(p, p) < radius * radius;
                }
                ball.insideFraction[ball.spec.linearIndex({x, y, z})] = float(in) / 64.f;
            }
    GridDiffusion b;
    b.setMaterial(ball, 1.3f);
    // The column through the centre (cells N/2 − 1 and N/2 straddle it): its topmost medium cell.
    int top = N - 1;
    while (!b.isMedium(ball.spec.linearIndex({N / 2, N / 2, top})) && top > 0)
        --top;
    ASSERT_TRUE(b.isBoundary(ball.spec.linearIndex({N / 2, N / 2, top})));
    EXPECT_NEAR(b.chordLength(ball.spec.linearIndex({N / 2, N / 2, top})), 2.f * radius * H,
                0.5f * H);
}

TEST(GridDiffusion, ASourceAboveTheCellCentreIsPlacedAtItsDepth) {
    // A non-absorbing slab L = 3 cells thick over the whole 32² face of the grid, cells of
    // Δx = 1 mm and σt′ = 5 mm⁻¹ (5 mean free paths), a plane source of 1 W per front cell at
    // depth z̄ = 0.2 mm. In one dimension φ is linear between the extrapolated boundaries
    // (2AD outside each face), and the discretisation is exact for a linear φ once the source
    // sits at its depth: the centre column transmits T = (z̄ + 2AD)/(L + 4AD) of it and
    // reflects 1 − T (16 cells from the slab's edges, which leak e^(−16π/L)-small). With the
    // source at the cell centre, ½Δx deep, T would be 55 % higher.
    constexpr int N = 32;
    constexpr float H = 1.f, SIGMA_T = 5.f, ETA = 1.3f, DEPTH = 0.2f;
    CoarseMaterial m = test::centredMaterial(N, H, SIGMA_T, SIGMA_T, 0.f);
    for (int z = 0; z < 3; ++z)
        for (int y = 0; y < N; ++y)
            for (int x = 0; x < N; ++x)
                m.insideFraction[m.spec.linearIndex({x, y, z})] = 1.f;
    GridDiffusionSource q;
    for (int c = 0; c < 3; ++c) {
        q.power[c].assign(m.spec.voxelCount(), 0.f);
        q.entry[c] = q.entryDepth[c] = q.power[c];
        for (int y = 0; y < N; ++y)
            for (int x = 0; x < N; ++x) {
                const size_t k = m.spec.linearIndex({x, y, 0});
                q.power[c][k] = q.entry[c][k] = 1.f;
                q.entryDepth[c][k] = DEPTH;
            }
    }
    const double zb = 2.0 * diffusionBoundaryConstant(ETA) / (3.0 * SIGMA_T), L = 3.0 * H;
    const double transmitted = (DEPTH + zb) / (L + 2.0 * zb);
    const size_t front = m.spec.linearIndex({N / 2, N / 2, 0}),
                 back = m.spec.linearIndex({N / 2, N / 2, 2});
    GridDiffusion d;
    d.setMaterial(m, ETA);
    const GridDiffusionStats& stats = d.solve(q, {.maxIterations = 4096, .tolerance = 1e-7});
    EXPECT_NEAR(d.exitance(back, 1) * H * H / transmitted, 1.0, 1e-4);
    EXPECT_NEAR(d.exitance(front, 1) * H * H / (1.0 - transmitted), 1.0, 1e-4);
    // Power: the direct part, (δ − z̄)/(δ + 2AD) = 0.35 of it, counts as exitant; nothing is
    // absorbed.
    EXPECT_GT(stats.directExit[1], 0.3 * stats.source[1]);
    EXPECT_NEAR(stats.exitant[1] / stats.source[1], 1.0, 1e-5);

    // A source at or below the centre stays there: the same as no entry part at all.
    const double centred = (0.5 * H + zb) / (L + 2.0 * zb);
    for (const float depth : {0.5f * H, 0.7f * H}) {
        for (int c = 0; c < 3; ++c)
            for (float& v : q.entryDepth[c])
                v = v > 0.f ? depth : 0.f;
        d.solve(q, {.maxIterations = 4096, .tolerance = 1e-7});
        EXPECT_NEAR(d.exitance(back, 1) * H * H / centred, 1.0, 1e-4) << depth;
    }
    d.solve(q.power, {.maxIterations = 4096, .tolerance = 1e-7});
    EXPECT_NEAR(d.exitance(back, 1) * H * H / centred, 1.0, 1e-4);
    EXPECT_GT(centred / transmitted, 1.5);

    // A layer one cell thick: its one read-out value stands for both faces, so the entry part
    // stays at the centre (the same answer as without it).
    for (int z = 1; z < 3; ++z)
        for (int y = 0; y < N; ++y)
            for (int x = 0; x < N; ++x)
                m.insideFraction[m.spec.linearIndex({x, y, z})] = 0.f;
    d.setMaterial(m, ETA);
    for (int c = 0; c < 3; ++c)
        for (float& v : q.entryDepth[c])
            v = v > 0.f ? DEPTH : 0.f;
    const float withEntry =
        (d.solve(q, {.maxIterations = 4096, .tolerance = 1e-7}), d.exitance(front, 1));
    const float without =
        (d.solve(q.power, {.maxIterations = 4096, .tolerance = 1e-7}), d.exitance(front, 1));
    EXPECT_EQ(withEntry, without);
    EXPECT_EQ(d.stats().directExit[1], 0.0);
}

TEST(GridDiffusion, CoarseCellsReadTheLitHalfSpaceWithTheSourceAtItsDepth) {
    // Cells of 2 mean free paths (σt′ = 2 mm⁻¹, Δx = 1 mm), η = 1.3: the light scattered first in
    // a top cell lies 0.34 mm under the surface on average, the cells' centres 0.5 mm. Placed at
    // its depth (with what the way to the surface absorbs) the light reads 8.3 % and 2.4 % under
    // the closed form at α′ = 0.95 and 0.99 (measured 2026-12-07); at the cell centre 16 % and
    // 6.7 %.
    // The rest is the coarse cells' own discretisation (cells of ½ mfp: 0.9 % and 0.4 %).
    const float limits[2][2] = {{0.95f, 0.9f}, {0.99f, 0.96f}};
    for (const auto& [albedo, lowest] : limits) {
        const double exact = halfSpaceExitance(2.0, 2.0 * albedo, 1.3);
        const double j = solvedTopExitance(litBox(32, 1.f, 2.f, 2.f * albedo), 1.3f);
        EXPECT_GT(j / exact, lowest) << "albedo " << albedo;
        EXPECT_LT(j / exact, 1.0) << "albedo " << albedo;
    }
}

TEST(GridDiffusion, ASurfaceInsideACellIsWhereTheInsideFractionSaysItIs) {
    // The same half-space with its surface at 3/4, 0.6 and 0.3 of the top layer's height (the
    // mesh cuts the cells there). The Robin condition sits δ = (f_i − ½ + f_j)Δx from the
    // centre, a partial cell absorbs by its fraction and the source is integrated over the
    // exact chord per cell; with the boundary at the cell face instead the three read
    // 1.07 / 0.86 / 0.93 of the closed form (measured 2026-12-04). Grid 32 (½ mfp cells): within
    // 2 %, the full-cell case's own discretisation error being 2.7 %.
    const double exact = halfSpaceExitance(2.0, 1.6, 1.3);
    for (const float f : {0.75f, 0.6f, 0.3f}) {
        const double j = solvedTopExitance(litBox(32, 0.25f, 2.f, 1.6f, f), 1.3f, f);
        EXPECT_NEAR(j / exact, 1.0, 0.02) << "top layer inside fraction " << f;
    }
}

TEST(GridDiffusion, NormalisedExitanceReadsTheExactHalfSpace) {
    // The closed form used for the ratio is the one the solve converges to.
    for (const double eta : {1.0, 1.3})
        for (const double albedo : {0.3, 0.8, 0.99})
            EXPECT_NEAR(diffusionHalfSpaceReflectance(albedo, eta),
                        halfSpaceExitance(1.0, albedo, eta) / (1.0 - fresnelDielectric(1.0, eta)),
                        1e-9)
                << eta << " " << albedo;
    // α′ = 0.8, η = 1.3: the model is 6 % above transport (0.192 vs 0.181 per unit entered).
    // Normalised, grid 64 reads the exact total less the discretisation's 0.75 %: within 1.5 %.
    const ExactReflectanceRatio ratio(1.3);
    EXPECT_NEAR(ratio(1.f), 1.f, 1e-3f);
    // Built once per process and η: solvers share it.
    EXPECT_EQ(exactReflectanceRatio(1.3).get(), exactReflectanceRatio(1.3).get());
    EXPECT_EQ((*exactReflectanceRatio(1.3))(0.8f), ratio(0.8f));
    EXPECT_LT(ratio(0.8f), 0.96f);
    const double exact = dipole::halfSpaceReflectance(0.8, 1.3, 1.0) *
                         (1.0 - fresnelDielectric(1.0, 1.3));  // per unit incident
    const double solved = solvedTopExitance(litBox(64, 0.125f, 2.f, 1.6f), 1.3f, 1.f, true);
    EXPECT_NEAR(solved / exact, 1.0, 0.015);
}

TEST(GridDiffusion, LightLeavesAtTheExactHalfSpacesExitAngles) {
    // The lit half-space of the test above (α′ = 0.8, η = 1.3, grid 64 of ¼-mfp cells), seen
    // along outside cosines t: the exact half-space (adding–doubling, normal incidence) sends
    // L(t) = ρ_t·radiance(t) per unit incident irradiance, ρ_t = 1 − F(1, η) the part that
    // enters. With the exit-angle table the solver's exitantRadiance is that, less the
    // discretisation's 0.75 % of the total and the table's bilinear interpolation (1.5 %, as
    // the total). The diffuse exit misses it (by 6 % along the normal at this albedo), so the
    // test fails without the table.
    const LitBox box = litBox(64, 0.125f, 2.f, 1.6f);
    const std::vector<double> cosines = {1.0, 0.6, 0.2};
    const dipole::HalfSpaceExitance exact = dipole::halfSpaceExitance(0.8, 1.3, 1.0, cosines);
    const double entered = 1.0 - fresnelDielectric(1.0, 1.3);
    const float top = 0.5f * 64.f * 0.125f;
    double worstDiffuse = 0.0;
    for (const bool table : {true, false}) {
        const std::unique_ptr<SslpvSolver> solver =
            solvedBox(box, 1.3f, /*exactTotal=*/true, table);
        const SslpvSolver& s = *solver;
        EXPECT_EQ(s.exitTable() != nullptr, table);
        for (size_t i = 0; i < cosines.size(); ++i) {
            const double want = exact.radiance[i] * entered;
            const float t = float(cosines[i]);
            const double got = s.exitantRadiance(Point3f(0.f, 0.f, top), Normal3f(0, 0, 1), t,
                                                 Vector3f(std::sqrt(1.f - t * t), 0.f, t))
                                   .y;
            std::printf("exit %s, t = %.1f: solved / exact %.4f\n", table ? "table" : "diffuse",
                        cosines[i], got / want);
            if (table)
                EXPECT_NEAR(got / want, 1.0, 0.015) << "t = " << cosines[i];
            else
                worstDiffuse = std::max(worstDiffuse, std::abs(got / want - 1.0));
        }
    }
    EXPECT_GT(worstDiffuse, 0.03);
    // Seen from behind or along the surface: nothing.
    SslpvSolver s(SslpvOptions{});
    EXPECT_EQ(s.exitantRadiance(Point3f(0.f), Normal3f(0, 0, 1), 0.f, Vector3f(1, 0, 0)), Rgb(0.f));
}

TEST(GridDiffusion, SurfaceFluxIsFicksLawAlongTheBoundary) {
    // The lit box of the tests above (σt′ = 2 mm⁻¹, α′ = 0.8, η = 1.3, cells of ½ mfp; 33 of
    // them, so a cell is centred on the axis) under irradiance E(x) = 1 + βx. Far from the side
    // faces the solution is (1 + βx)·φ₁(z) — x-linear terms have no Laplacian — so along the top
    // face J(x) = (1 + βx)·J₁ and Fick's law on the boundary, φ_b = 2A·J, gives the closed form J_t
    // = −D ∂φ_b/∂x = −2AD·β·J₁ along x, none along y. Then P1's exit term: seen at the centre from
    // azimuths −x and +x at the same outside cosine t, the light leaving toward −x (with the flow)
    // over the light toward +x is (1 + a)/(1 − a), a = 3·2ADβ·sin θ_i/(2A + 3μ), sin θ_i = √(1 −
    // t²)/η, μ = cos θ_i.
    const float beta = 0.05f;  // mm⁻¹: E from 0.8 to 1.2 across the box
    LitBox box = litBox(33, 0.25f, 2.f, 1.6f);
    for (SslpvInjectionSample& t : box.texels)
        t.flux *= 1.f + beta * t.position.x;
    const float eta = 1.3f;
    const std::unique_ptr<SslpvSolver> solver = solvedBox(box, eta, /*exactTotal=*/true);
    const GridDiffusion& d = solver->diffusion();
    const double A = diffusionBoundaryConstant(eta), D = 1.0 / 6.0;
    const GridSpec& spec = box.material.spec;
    // The side faces are 6.4 diffusion lengths from the axis: their effect on the gradient
    // there is e^−6.4·(E(4) − E(−4))/(βl_d) ≈ 0.5 % of it, and grows as e^(|x|/l_d) away from
    // it (3 % at 0.9 mm), so the cells next to the axis are compared. The LSQ gradient of a
    // linear field is exact, so 1 % holds that and the solve's tolerance.
    for (int ix : {15, 16, 17}) {
        const size_t k = spec.linearIndex({ix, 16, 32});
        const float x = spec.cellCenter({ix, 16, 32}).x;
        const double J = d.exitance(k, 1);
        const Vector3f Jt = d.surfaceFlux(k)[1];
        const double want = -2.0 * A * D * beta * J / (1.0 + beta * x);
        std::printf("surface flux at x = %+.3f mm: solved / closed form %.4f (y %.1e, z %.1e)\n", x,
                    Jt.x / want, Jt.y / want, Jt.z / want);
        EXPECT_NEAR(Jt.x / want, 1.0, 0.01) << "x = " << x;
        EXPECT_NEAR(Jt.y / want, 0.0, 1e-3) << "x = " << x;
        EXPECT_NEAR(Jt.z / want, 0.0, 1e-3) << "x = " << x;
    }
    // Interior and outside cells carry none.
    EXPECT_EQ(d.surfaceFlux(spec.linearIndex({16, 16, 16}))[1], Vector3f(0.f));

    const float top = 0.5f * 33.f * 0.25f;
    for (const float t : {0.8f, 0.4f}) {
        const float s = std::sqrt(1.f - t * t);
        const Rgb toMinus = solver->exitantRadiance(Point3f(0.f, 0.f, top), Normal3f(0, 0, 1), t,
                                                    Vector3f(-s, 0.f, t));
        const Rgb toPlus = solver->exitantRadiance(Point3f(0.f, 0.f, top), Normal3f(0, 0, 1), t,
                                                   Vector3f(s, 0.f, t));
        const double sinI = double(s) / eta, mu = std::sqrt(1.0 - sinI * sinI);
        const double a = 3.0 * 2.0 * A * D * beta * sinI / (2.0 * A + 3.0 * mu);
        std::printf("exit at t = %.1f: toward -x / toward +x %.5f, P1 closed form %.5f\n", t,
                    toMinus.y / toPlus.y, (1.0 + a) / (1.0 - a));
        EXPECT_NEAR(toMinus.y / toPlus.y, (1.0 + a) / (1.0 - a), 0.02 * a);
        // Odd in the azimuth: the pair's mean is the light without the term.
        const Rgb toSide = solver->exitantRadiance(Point3f(0.f, 0.f, top), Normal3f(0, 0, 1), t,
                                                   Vector3f(0.f, s, t));
        EXPECT_NEAR(0.5 * (toMinus.y + toPlus.y) / toSide.y, 1.0, 1e-4);
    }
    // Over the whole exit hemisphere the light leans along the flow by surfaceFluxExitLean per
    // unit J_t/J_n (the quantity the exact pencil-beam walk is compared with): the read-out's
    // ⟨ω_o·t̂⟩, t̂ = −x̂, by the midpoint rule in t and φ (64 × 64 nodes: 10⁻³ of it).
    double lean = 0.0, flux = 0.0;
    for (int i = 0; i < 64; ++i) {
        const float t = (float(i) + 0.5f) / 64.f, s = std::sqrt(1.f - t * t);
        for (int j = 0; j < 64; ++j) {
            const float phi = 2.f * float(PI) * (float(j) + 0.5f) / 64.f;
            const Vector3f wo(s * std::cos(phi), s * std::sin(phi), t);
            const double L =
                solver->exitantRadiance(Point3f(0.f, 0.f, top), Normal3f(0, 0, 1), t, wo).y;
            lean += L * t * double(-wo.x);
            flux += L * t;
        }
    }
    const double ratio = 2.0 * A * D * beta;  // |J_t|/J_n on the axis
    std::printf(
        "lean over the hemisphere per unit J_t/J_n: read-out %.5f, surfaceFluxExitLean %.5f\n",
        lean / flux / ratio, surfaceFluxExitLean(0.8, eta));
    EXPECT_NEAR(lean / flux / ratio / surfaceFluxExitLean(0.8, eta), 1.0, 0.01);
}

TEST(GridDiffusion, TheSurfaceFluxTermIsLimitedWhereTheGradientIsSteep) {
    // A shadow's edge on cells much larger than the diffusion length (σt′ = 2 mm⁻¹, α′ = 0.2,
    // 2 mm cells: l_d = 0.39 mm): half the top face lit, η = 1. Beyond the edge the exitance
    // falls by ~40× per cell, so the least-squares gradient makes |J_t| larger than any radiance
    // field allows (|J| ≤ φ, i.e. |J_t| ≤ J_n√(4A² − 1)); unlimited, P1's term would multiply
    // the light leaving along the flow (toward the shadow) by 1 + 3|J_t|sin θ_i/(J_n(2A + 3μ)) —
    // several times. The read-out limits J_t to the bound, so that factor never exceeds its value
    // at the bound.
    LitBox box = litBox(16, 2.f, 2.f, 0.4f);
    std::erase_if(box.texels, [](const SslpvInjectionSample& t) { return t.position.x > 0.f; });
    const std::unique_ptr<SslpvSolver> solver = solvedBox(box, 1.f, /*exactTotal=*/true);
    const GridDiffusion& d = solver->diffusion();
    const GridSpec& spec = box.material.spec;
    const double A = d.boundaryConstant(), limit = std::sqrt(4.0 * A * A - 1.0);
    double steepest = 0.0;
    for (int x = 0; x < 16; ++x) {
        const size_t k = spec.linearIndex({x, 8, 15});
        if (d.exitance(k, 1) > 0.f)
            steepest = std::max(
                steepest, double(glm::length(d.surfaceFlux(k)[1])) / (d.exitance(k, 1) * limit));
    }
    std::printf("steepest |J_t| / bound: %.2f\n", steepest);
    ASSERT_GT(steepest, 1.5);  // the case exercises the limit

    const float top = 0.5f * 16.f * 2.f, t = 0.3f, sinO = std::sqrt(1.f - t * t);
    const double sinI = sinO, mu = t;  // η = 1: no bending
    const double bound = 1.0 + 3.0 * limit * sinI / (2.0 * A + 3.0 * mu);
    int compared = 0;
    for (int x = 0; x < 16; ++x) {
        const Point3f p(spec.cellCenter({x, 8, 15}).x, spec.cellCenter({x, 8, 15}).y, top);
        const Rgb along = solver->exitantRadiance(p, Normal3f(0, 0, 1), t, Vector3f(sinO, 0.f, t));
        const Rgb side = solver->exitantRadiance(p, Normal3f(0, 0, 1), t, Vector3f(0.f, sinO, t));
        if (!(side.y > 0.f))
            continue;
        ++compared;
        EXPECT_TRUE(std::isfinite(along.y));
        EXPECT_LE(along.y / side.y, bound * (1.0 + 1e-4)) << "cell x = " << x;
    }
    EXPECT_GT(compared, 8);
}

TEST(GridDiffusion, AStrokeWalksOnlyTheBeamsThroughItAndGivesTheSameAnswer) {
    // The lit box under oblique light (every beam crosses several columns), then three
    // "strokes": σs′ or σt′ changed in a 3-cell block. With incremental injection only the
    // beams whose walked segment meets the changed block are walked again (old deposits taken
    // away, new ones added); without it every beam is. The two must agree to float rounding of
    // the source (~10⁻⁶ relative) and the solve's tolerance (10⁻⁷ of the source): 10⁻⁴ on
    // every boundary cell's exitance. A new shape walks everything.
    LitBox box = litBox(24, 0.25f, 1.5f, 1.2f);
    const Vector3f oblique = glm::normalize(Vector3f(0.45f, 0.25f, -1.f));
    for (SslpvInjectionSample& t : box.texels)
        t.direction = oblique;
    SslpvOptions o;
    o.mode = SslpvMode::Diffusion;
    o.maxSteps = 4096;
    o.stopEpsilon = 1e-7f;
    SslpvOptions full = o;
    full.incrementalInjection = false;
    SslpvSolver a(o), b(full);
    CoarseMaterial m = box.material;
    for (SslpvSolver* s : {&a, &b}) {
        s->setMaterial(m, 1.3f);
        s->setInjectionSamples(box.texels);
        s->solve();
    }
    const GridSpec& spec = m.spec;
    const auto block = [&](Coord at, bool extinction, float value) {
        for (int z = at.z; z < at.z + 3; ++z)
            for (int y = at.y; y < at.y + 3; ++y)
                for (int x = at.x; x < at.x + 3; ++x)
                    for (int ch = 0; ch < 3; ++ch) {
                        const size_t k = spec.linearIndex({x, y, z});
                        if (extinction)
                            m.sigma_t[ch][k] = value;
                        else
                            m.sigma_s[ch][k] = std::min(value, m.sigma_t[ch][k]);
                    }
    };
    const std::vector<std::tuple<Coord, bool, float>> strokes = {
        {{10, 10, 20}, false, 0.3f}, {{4, 15, 21}, true, 4.f}, {{11, 9, 19}, false, 1.4f}};
    for (const auto& [at, extinction, value] : strokes) {
        block(at, extinction, value);
        a.setMaterial(m, 1.3f);
        b.setMaterial(m, 1.3f);
        const SslpvStats sa = a.solve();
        const SslpvStats sb = b.solve();
        EXPECT_GT(sa.rewalkedTexels, 0);
        EXPECT_LT(sa.rewalkedTexels, sa.injectedTexels / 2) << "a stroke walks a few beams";
        EXPECT_EQ(sb.rewalkedTexels, 0);
        EXPECT_EQ(sa.injectedTexels, sb.injectedTexels);
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(sa.injected[ch] / sb.injected[ch], 1.0, 1e-5);
        double worst = 0.0;
        for (size_t k = 0; k < spec.voxelCount(); ++k)
            if (a.diffusion().isBoundary(k))
                for (int ch = 0; ch < 3; ++ch) {
                    const double ja = a.diffusion().exitance(k, ch),
                                 jb = b.diffusion().exitance(k, ch);
                    if (jb > 1e-6)
                        worst = std::max(worst, std::abs(ja / jb - 1.0));
                }
        std::printf("stroke: %d of %d beams walked again; exitance max rel. diff %.2e\n",
                    sa.rewalkedTexels, sa.injectedTexels, worst);
        EXPECT_LT(worst, 1e-4);
    }
    // Another shape: a full walk.
    m.insideFraction[spec.linearIndex({12, 12, 23})] = 0.f;
    a.setMaterial(m, 1.3f);
    EXPECT_EQ(a.solve().rewalkedTexels, 0);
}

TEST(GridDiffusion, PowerBalancesAndWarmStartsReachTheSameAnswer) {
    LitBox box = litBox(24, 0.25f, 1.5f, 1.4f);
    SslpvOptions o;
    o.mode = SslpvMode::Diffusion;
    o.maxSteps = 4096;
    o.stopEpsilon = 1e-6f;
    SslpvSolver s(o);
    s.setMaterial(box.material, 1.3f);
    s.setInjectionSamples(box.texels);
    const SslpvStats& st = s.solve();
    const GridDiffusionStats& ds = s.diffusion().stats();
    EXPECT_FALSE(ds.warmStart);
    for (int c = 0; c < 3; ++c) {
        // Interacting power = first-collision absorption + diffusion absorption + exitance.
        EXPECT_NEAR(st.absorbed[c] + st.exitant[c], st.injected[c], 2e-5 * st.injected[c]);
        EXPECT_LT(ds.residual[size_t(c)], 1e-6);
    }
    const Rgb before = s.radiance(Point3f(0.f, 0.f, 3.f), Normal3f(0, 0, 1));
    const int coldIterations = ds.iterations[1];

    // Paint a darker core, then restore it: the second restore solve starts from the painted
    // answer and ends at the unpainted one.
    const GridSpec& spec = box.material.spec;
    for (int z = 0; z < spec.resolution; ++z)
        for (int y = 0; y < spec.resolution; ++y)
            for (int x = 0; x < spec.resolution; ++x)
                if (glm::length(spec.cellCenter({x, y, z})) < 1.f)
                    s.material().sigma_s[1][spec.linearIndex({x, y, z})] = 0.5f;
    s.markMaterialDirty();
    s.solve();
    EXPECT_TRUE(s.diffusion().stats().warmStart);
    EXPECT_LT(s.radiance(Point3f(0.f, 0.f, 3.f), Normal3f(0, 0, 1)).y, before.y);
    s.setMaterial(box.material, 1.3f);
    s.solve();
    EXPECT_TRUE(s.diffusion().stats().warmStart);
    EXPECT_LT(s.diffusion().stats().iterations[1], coldIterations);
    EXPECT_NEAR(s.radiance(Point3f(0.f, 0.f, 3.f), Normal3f(0, 0, 1)).y, before.y,
                1e-4f * before.y);
}

TEST(GridDiffusion, TheAnswerIsTheSameOnAnyThreadCount) {
    // The beams are walked in parallel and the CG's dot products summed per block; both are
    // ordered so that the result does not depend on the threads (docs/methods/sslpv.md).
    LitBox box = litBox(24, 0.25f, 1.5f, 1.2f);
    box.material.homogeneous = false;
    for (size_t k = 0; k < box.material.spec.voxelCount(); k += 7)
        box.material.sigma_t[0][k] = 3.f;  // heterogeneous, so each beam differs
    auto solveWith = [&](int threads) {
        const ThreadLimit limit(threads);
        SslpvOptions o;
        o.mode = SslpvMode::Diffusion;
        SslpvSolver s(o);
        s.setMaterial(box.material, 1.3f);
        s.setInjectionSamples(box.texels);
        s.solve();
        return s.accumulation().raw();
    };
    const std::vector<float> one = solveWith(1);
    EXPECT_EQ(one, solveWith(2));
    EXPECT_EQ(one, solveWith(4));
}

TEST(GridDiffusion, ExtremeMaterialStaysFiniteAndBadInputIsRefused) {
    for (const float st : {1e-4f, 1e4f})
        for (const float albedo : {0.f, 0.5f, 1.f}) {
            LitBox box = litBox(12, 0.5f, st, albedo * st);
            SslpvOptions o;
            o.mode = SslpvMode::Diffusion;
            SslpvSolver s(o);
            s.setMaterial(box.material, 2.5f);
            s.setInjectionSamples(box.texels);
            const SslpvStats& stats = s.solve();
            EXPECT_TRUE(s.accumulation().isFinite()) << st << " " << albedo;
            for (int c = 0; c < 3; ++c)
                EXPECT_LE(stats.exitant[c], stats.injected[c] * 1.001f + 1e-9f)
                    << st << " " << albedo;
        }
    GridDiffusion d;
    EXPECT_THROW(d.solve(GridDiffusionSource{}, {}), ValueError);
    LitBox box = litBox(4, 1.f, 1.f, 0.5f);
    EXPECT_THROW(d.setMaterial(box.material, 0.5f), ValueError);
    d.setMaterial(box.material, 1.3f);
    std::array<std::vector<float>, 3> q;
    for (auto& v : q)
        v.assign(box.material.spec.voxelCount(), 0.f);
    q[1][5] = -1.f;
    EXPECT_THROW(d.solve(q, {}), ValueError);
    q[1][5] = std::nanf("");
    EXPECT_THROW(d.solve(q, {}), ValueError);
    // Entry parts: given, both arrays must be whole; their values finite and >= 0.
    q[1][5] = 0.f;
    GridDiffusionSource entry{q, q, {}};
    EXPECT_THROW(d.solve(entry, {}), ValueError);
    entry.entryDepth = q;
    EXPECT_NO_THROW(d.solve(entry, {}));
    entry.entry[1][5] = -1.f;  // cell 5 is a boundary cell (its −z face is the grid's edge)
    EXPECT_THROW(d.solve(entry, {}), ValueError);
    entry.entry[1][5] = 0.f;
    entry.entryDepth[1][5] = std::nanf("");
    EXPECT_THROW(d.solve(entry, {}), ValueError);
    box.material.sigma_t[2][3] = std::numeric_limits<float>::infinity();
    EXPECT_THROW(d.setMaterial(box.material, 1.3f), ValueError);
}
