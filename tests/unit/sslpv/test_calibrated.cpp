// SPDX-License-Identifier: MIT
/// @file
/// @brief Calibrated SSLPV mode: folded factors follow the documented model, thick-slab
/// reflectance stays within the fit's residual band against the classical dipole, energy never
/// grows, extreme inputs stay finite (docs/methods/sslpv.md, "Calibrated mode").

#include <lucent/sslpv/SslpvSolver.h>

#include <lucent/core/Error.h>
#include <lucent/sslpv/SslpvCalibrationFit.h>

#include "SslpvTestGrids.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace lucent;
using namespace lucent::sslpv;

namespace {

CoarseMaterial ball(int n, float h, float st, float ss, float g) {
    CoarseMaterial m = test::centredMaterial(n, h, st, ss, g);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                if (glm::length(m.spec.cellCenter({x, y, z})) <= 0.35f * n * h)
                    m.insideFraction[m.spec.linearIndex({x, y, z})] = 1.f;
    m.homogeneous = true;
    return m;
}

std::vector<SslpvInjectionSample> topTexels(const CoarseMaterial& m) {
    const float r = 0.35f * m.spec.resolution * m.spec.voxelSize;
    std::vector<SslpvInjectionSample> out;
    for (int j = -6; j <= 6; ++j)
        for (int i = -6; i <= 6; ++i) {
            const float s = i * r / 7.f, t = j * r / 7.f;
            if (s * s + t * t >= r * r)
                continue;
            const Point3f p(s, t, std::sqrt(r * r - s * s - t * t));
            out.push_back({p, glm::normalize(p), Vector3f(0, 0, -1), Rgb(1.f)});
        }
    return out;
}

SslpvOptions calibrated(int order, int steps) {
    SslpvOptions o;
    o.order = order;
    o.maxSteps = steps;
    o.mode = SslpvMode::Calibrated;
    return o;
}

}  // namespace

TEST(SslpvCalibrated, FoldedFactorsFollowTheModel) {
    // Band-l factor exp(−β)·((1 − s′) + s′g^l), β = U σaΔx + T σ_trΔx + K (σ_trΔx)² + P σa/σt + Q
    // σ_tr/σt, σ_tr = √(3σaσt), s′ = 1 − exp(−σs′Δx); polynomial exp ~2e-7 relative.
    for (float h : {0.1f, 1.f, 7.f}) {
        CoarseMaterial m = ball(16, h, 0.8f, 0.5f, 0.3f);
        m.sigma_t[1][m.spec.linearIndex({8, 8, 8})] = 3.f;  // heterogeneous path
        m.homogeneous = false;
        SslpvOptions o = calibrated(1, 1);
        o.calibration.linear = 0.3f;
        o.calibration.transport = 0.7f;
        o.calibration.diffusion = 0.05f;
        o.calibration.perStep = 0.4f;
        o.calibration.perStepTransport = 0.2f;
        SslpvSolver solver(o);
        solver.setMaterial(m, 1.3f);
        solver.solve();
        for (int c = 0; c < 3; ++c) {
            const Coord cell = (c == 1) ? Coord(8, 8, 8) : Coord(7, 8, 8);
            const size_t k = m.spec.linearIndex(cell);
            const double st = m.sigma_t[c][k], ss = m.sigma_s[c][k], g = m.g[c][k];
            const double sa = st - ss, tr = std::sqrt(3.0 * sa * st);
            const double beta = 0.3 * sa * h + 0.7 * tr * h + 0.05 * tr * tr * h * h +
                                0.4 * sa / st + 0.2 * tr / st;
            const double a = std::exp(-beta), s = 1.0 - std::exp(-ss * h);
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

TEST(SslpvCalibrated, ExitScaleIsGainOverEtaSquared) {
    const CoarseMaterial m = ball(8, 1.f, 1.f, 0.9f, 0.f);
    SslpvSolver paper({.order = 1, .maxSteps = 2});
    paper.setMaterial(m, 1.5f);
    // Eq. 4 with the radiance scaling at refraction (the paper had L_o = T·L_i, η² too bright).
    EXPECT_FLOAT_EQ(paper.exitScale(), 1.f / (1.5f * 1.5f));
    for (int order : {1, 2}) {
        SslpvSolver cal(calibrated(order, 2));
        cal.setMaterial(m, 1.5f);
        const SslpvCalibration d = defaultSslpvCalibration();
        EXPECT_FLOAT_EQ(cal.exitScale(), d.gain[order - 1] / (1.5f * 1.5f));
    }
}

TEST(SslpvCalibrated, RejectsBadCalibration) {
    SslpvOptions o = calibrated(1, 4);
    o.calibration.transport = -1.f;
    EXPECT_THROW(SslpvSolver{o}, ValueError);
    o = calibrated(1, 4);
    o.calibration.gain[1] = 0.f;
    EXPECT_THROW(SslpvSolver{o}, ValueError);
    o = calibrated(1, 4);
    o.calibration.diffusion = std::nanf("");
    EXPECT_THROW(SslpvSolver{o}, ValueError);
}

TEST(SslpvCalibrated, ThickSlabWithinFitResidualBand) {
    // The documented fit (docs/methods/sslpv.md, "Calibrated mode", `lucent-cli bench
    // sslpv-fit`, 48³, η = 1.3): its largest |residual| over α′ ∈ [0.3, 0.99] and
    // Δx·σt ∈ {0.5, 1, 2, 4} is 26.1 % for SH order 1 and 17.7 % for order 2 (bench
    // sslpv-fit --sh 2). These cases must stay inside that band (the defaults are the fit's
    // constants) and reproduce their printed residual to RESIDUAL_REPRO (float sums in a
    // different order than the fit's run: ~1e-5; 0.5 % allows for the stop criterion's step
    // count moving by one).
    struct Case {
        int order;
        float albedo, cellMfp;
        double fitResidual;  ///< printed by `lucent-cli bench sslpv-fit [--sh 2]`
    };
    constexpr double FIT_MAX_RESIDUAL[2] = {0.261, 0.177};
    constexpr double RESIDUAL_REPRO = 0.005;
    const Case cases[] = {{1, 0.3f, 1.f, +0.247},  {1, 0.5f, 1.f, -0.015},  {1, 0.8f, 1.f, -0.036},
                          {1, 0.95f, 2.f, -0.037}, {1, 0.99f, 1.f, +0.034}, {2, 0.5f, 1.f, -0.077},
                          {2, 0.9f, 2.f, -0.003}};
    for (const Case& c : cases) {
        SslpvOptions o = calibrated(c.order, 4096);
        o.stopEpsilon = 1e-4f;
        // The fit's slab (lucent/sslpv/SslpvCalibrationFit.h), measured with the shipped gain.
        SslpvStats st;
        const double resp = sslpvSlabResponse({c.albedo, c.cellMfp}, 48, o, 1.3f, &st) *
                            double(o.calibration.gain[c.order - 1]);
        const double residual = resp / sslpvSlabTarget(c.albedo, 1.3f) - 1.0;
        SCOPED_TRACE("order " + std::to_string(c.order) + " albedo " + std::to_string(c.albedo) +
                     " cell " + std::to_string(c.cellMfp));
        EXPECT_LE(std::abs(residual), FIT_MAX_RESIDUAL[c.order - 1]);
        EXPECT_NEAR(residual, c.fitResidual, RESIDUAL_REPRO);
        // Energy never grows: all flux is accounted for and none is created.
        EXPECT_LE(st.exitant.y + st.remaining.y, st.injected.y * (1.f + 2e-4f));
    }
}

TEST(SslpvCalibrated, EnergyNeverGrowsAndStressCasesStayFinite) {
    struct Stress {
        const char* name;
        float st, ss, g, eta, cell;
        int steps;
    };
    const Stress cases[] = {
        {"sigma_t->0", 1e-9f, 0.f, 0.f, 1.3f, 1.f, 64},
        {"sigma_a=0", 2.f, 2.f, 0.f, 1.3f, 1.f, 64},
        {"sigma_t=1e4", 1e4f, 5e3f, 0.f, 1.3f, 1.f, 16},
        {"g=+0.99", 1.f, 0.99f, 0.99f, 1.3f, 1.f, 64},
        {"g=-0.99", 1.f, 0.99f, -0.99f, 1.3f, 1.f, 64},
        {"eta=1", 1.f, 0.5f, 0.f, 1.f, 1.f, 32},
        {"eta=3", 1.f, 0.5f, 0.f, 3.f, 1.f, 32},
        {"cell=1e-3mm", 1.f, 0.9f, 0.f, 1.3f, 1e-3f, 32},
        {"cell=1e3mm", 1.f, 0.9f, 0.f, 1.3f, 1e3f, 32},
        {"512 steps", 1.f, 0.999f, 0.f, 1.3f, 1.f, 512},
    };
    for (const Stress& sc : cases)
        for (int order : {1, 2}) {
            SCOPED_TRACE(std::string(sc.name) + " order " + std::to_string(order));
            const CoarseMaterial m = ball(16, sc.cell, sc.st, sc.ss, sc.g);
            SslpvSolver solver(calibrated(order, sc.steps));
            solver.setMaterial(m, sc.eta);
            solver.setInjectionSamples(topTexels(m));
            const SslpvStats& st = solver.solve();
            EXPECT_TRUE(solver.accumulation().isFinite());
            EXPECT_TRUE(solver.propagation().isFinite());
            EXPECT_TRUE(solver.exitant().isFinite());
            EXPECT_GT(st.injected.x, 0.f);
            // Per-step factors are ≤ 1 (β ≥ 0), so the balance holds with absorbed ≥ 0.
            EXPECT_GE(st.absorbed.x, 0.f);
            const float sum = st.remaining.x + st.exitant.x + st.absorbed.x;
            EXPECT_NEAR(sum, st.injected.x, 2e-4f * st.injected.x);
            EXPECT_LE(st.remaining.x + st.exitant.x, st.injected.x * (1.f + 2e-4f));
            const Rgb L = solver.radiance(Point3f(0, 0, 0.3f * 16 * sc.cell), Normal3f(0, 0, 1));
            EXPECT_TRUE(isFinite(L * solver.exitScale()));
        }
}
