// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Random.h>
#include <lucent/dipole/Sampling.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace lucent;
using namespace lucent::dipole;

namespace {
/// Composite Simpson rule of f on [a, b] with n (even) intervals.
template <typename F>
double simpson(const F& f, double a, double b, int n) {
    const double h = (b - a) / n;
    double s = f(a) + f(b);
    for (int i = 1; i < n; ++i)
        s += f(a + i * h) * (i % 2 ? 4.0 : 2.0);
    return s * h / 3.0;
}
/// χ² critical value at upper-tail probability 1e-3 (Wilson–Hilferty, z = 3.0902).
double chi2Critical(int dof) {
    const double k = dof, z = 3.0902;
    const double t = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
    return k * t * t * t;
}
/// χ² statistic of n samples of `s` (seeded Pcg32) in the bins [edges[k], edges[k+1]) against
/// the bin probabilities `expected`.
double chiSquare(const DipoleSampler& s, const std::vector<double>& edges,
                 const std::vector<double>& expected, int n, uint64_t seed) {
    const int bins = int(expected.size());
    std::vector<int> counts(size_t(bins), 0);
    Pcg32 rng(seed);
    for (int i = 0; i < n; ++i) {
        const double r = s.sample(rng.uniform(), rng.uniform());
        const int k = int(std::upper_bound(edges.begin(), edges.end(), r) - edges.begin()) - 1;
        ++counts[size_t(std::clamp(k, 0, bins - 1))];
    }
    double chi2 = 0.0;
    for (int k = 0; k < bins; ++k) {
        const double e = expected[size_t(k)] * n;
        chi2 += (counts[size_t(k)] - e) * (counts[size_t(k)] - e) / e;
    }
    return chi2;
}
}  // namespace

TEST(DipoleSampling, NewtonConvergesEverywhere) {
    const std::vector<double> sigmaZ = {0.0, 1e-6, 1e-3, 0.5, 1.0, 30.0, 1e3, 1e6};
    const std::vector<double> xis = {
        0.0, 1e-15, 1e-6, 0.1, 0.5, 0.9, 0.999999, 1.0 - 1e-12, std::nextafter(1.0, 0.0)};
    for (double c : sigmaZ)
        for (double xi : xis) {
            int it = 0;
            const double v = solveLogU(c, xi, &it);
            ASSERT_TRUE(std::isfinite(v)) << c << " " << xi;
            ASSERT_GE(v, 0.0);
            ASSERT_LE(it, 60) << c << " " << xi;
            // Residual of σz(u−1) + log u + log(1−ξ) relative to its terms (double round-off).
            const double L = -std::log1p(-xi);
            const double g = c * std::expm1(v) + v - L;
            ASSERT_LE(std::abs(g), 1e-13 * std::max(1.0, L + c * std::expm1(v))) << c << " " << xi;
        }
    EXPECT_THROW(solveLogU(-1.0, 0.5), ValueError);
    EXPECT_THROW(solveLogU(1.0, 1.0), ValueError);
}

TEST(DipoleSampling, PdfIsNormalisedAndEqualsJensenProfile) {
    const DipoleProfile p = DipoleProfile::jensen(0.032, 0.74, 1.3);
    const DipoleSampler s(p);
    const double rho = p.totalReflectance();
    for (double r : {0.0, 0.01, 0.5, 3.0, 40.0})
        EXPECT_NEAR(s.pdfArea(r), p.Rd(r) / rho, 1e-12 * p.Rd(r) / rho);
    const double total = integrateRadial(
        [](const void* c, double r) { return static_cast<const DipoleSampler*>(c)->pdfArea(r); },
        &s, p.zr());
    EXPECT_NEAR(total, 1.0, 1e-8);
    EXPECT_NEAR(s.cdf(s.quantile(0.73)), 0.73, 1e-10);
}

TEST(DipoleSampling, ChiSquareAgainstNormalisedProfile) {
    // Histogram of sampled radii vs bin probabilities from quadrature of R_d(r)·2πr/ρ.
    for (const auto& [sa, ss] :
         {std::pair{0.0021, 2.19}, std::pair{0.5, 0.3}, std::pair{0.0, 1.0}}) {
        const DipoleProfile p = DipoleProfile::jensen(sa, ss, 1.3);
        const DipoleSampler s(p);
        const double rho = p.totalReflectance();
        const int bins = 40, n = 200000;
        std::vector<double> edges(bins + 1);
        for (int k = 0; k < bins; ++k)
            edges[k] = s.quantile(double(k) / bins);
        edges[bins] = INFINITY;
        std::vector<double> expected(bins);
        double acc = 0.0;
        for (int k = 0; k + 1 < bins; ++k) {
            expected[k] = simpson([&](double r) { return p.Rd(r) * 2 * M_PI * r / rho; }, edges[k],
                                  edges[k + 1], 2000);
            acc += expected[k];
        }
        expected[bins - 1] = 1.0 - acc;
        // df = bins − 1, significance 1e-3 (seeded: deterministic).
        EXPECT_LT(chiSquare(s, edges, expected, n, 7), chi2Critical(bins - 1))
            << "sa " << sa << " ss " << ss;
    }
}

TEST(DipoleSampling, UnbiasedForUniformIrradiance) {
    Pcg32 rng(11);
    // (a) Jensen with its own sampler: R_d/pdf = ρ for every sample (exact importance sampling).
    {
        const DipoleProfile p = DipoleProfile::jensen(0.0021, 2.19, 1.3);
        const DipoleSampler s(p);
        for (int i = 0; i < 1000; ++i) {
            const double r = s.sample(rng.uniform(), rng.uniform());
            ASSERT_NEAR(p.Rd(r) / s.pdfArea(r), p.totalReflectance(), 1e-9);
        }
    }
    // (b) Better dipole with the flux-shaped sampler, (c) MIS of importance + uniform disc on a
    // lit disc of radius R′: the mean equals the exact integral within 4 standard errors.
    for (Model m : {Model::Dipole, Model::BetterDipole}) {
        const DipoleProfile p = DipoleProfile::make(m, {0.01, 1.0, 1.4});
        const DipoleSampler s(p);
        const double R = s.quantile(0.9);
        const int nImp = 4, nUni = 2, rounds = 50000;
        const double pUni = 1.0 / (M_PI * R * R);
        double sum = 0.0, sum2 = 0.0, sumPlain = 0.0, sumPlain2 = 0.0;
        for (int k = 0; k < rounds; ++k) {
            double est = 0.0;
            for (int i = 0; i < nImp + nUni; ++i) {
                double r;
                if (i < nImp) {
                    r = s.sample(rng.uniform(), rng.uniform());
                } else {
                    r = R * std::sqrt(double(rng.uniform()));
                }
                const double f = r < R ? p.Rd(r) : 0.0;
                const double pu = r < R ? pUni : 0.0;
                est += f / (nImp * s.pdfArea(r) + nUni * pu);  // balance heuristic
            }
            sum += est;
            sum2 += est * est;
            const double r = s.sample(rng.uniform(), rng.uniform());
            const double plain = p.Rd(r) / s.pdfArea(r);
            sumPlain += plain;
            sumPlain2 += plain * plain;
        }
        const double mean = sum / rounds, se = std::sqrt((sum2 / rounds - mean * mean) / rounds);
        const double exactDisc =
            simpson([&](double r) { return p.Rd(r) * 2 * M_PI * r; }, 0.0, R, 20000);
        EXPECT_NEAR(mean, exactDisc, 4 * se + 1e-9 * exactDisc) << modelName(m);
        const double mp = sumPlain / rounds,
                     sp = std::sqrt(std::max(0.0, sumPlain2 / rounds - mp * mp) / rounds);
        EXPECT_NEAR(mp, p.totalReflectance(), 4 * sp + 1e-9) << modelName(m);
    }
}

TEST(DipoleSampling, StressExtremeParameters) {
    for (double sa : {0.0, 1e-6, 1.0, 1e6})
        for (double ss : {1e-6, 1.0, 1e6})
            for (double eta : {1.0, 2.5}) {
                const DipoleSampler s(DipoleProfile::better(sa, ss, eta));
                for (double xi : {0.0, 0.5, std::nextafter(1.0, 0.0)}) {
                    const double r = s.sample(0.3, xi), r2 = s.sample(0.99, xi);
                    ASSERT_TRUE(std::isfinite(r) && r >= 0.0) << sa << " " << ss << " " << xi;
                    ASSERT_TRUE(std::isfinite(r2) && r2 >= 0.0);
                    const double pdf = s.pdfArea(r);
                    ASSERT_TRUE(std::isfinite(pdf) && pdf >= 0.0);
                }
            }
}

TEST(DipoleSampling, TruncatedSamplerIsTheConditionedMixture) {
    // The window r ≤ R of the combined mode: samples never exceed R, the renormalised pdf
    // integrates to 1 on the disc, the histogram follows R_d(r)·2πr restricted to [0, R]
    // (χ², 40 equal-probability bins, significance 1e-3), and Jensen's R_d/pdf is the constant
    // ∫_{r≤R} R_d dA (exact importance sampling of the truncated profile).
    for (const auto& [sa, ss] : {std::pair{0.0021, 2.19}, std::pair{0.5, 0.3}}) {
        const DipoleProfile p = DipoleProfile::jensen(sa, ss, 1.3);
        const DipoleSampler full(p);
        const double R = full.quantile(0.6);  // keeps 60 % of the mass
        const DipoleSampler s = full.truncated(R);
        EXPECT_NEAR(s.keptMass(), 0.6, 1e-9);
        EXPECT_EQ(s.pdfArea(1.0001 * R), 0.0);
        EXPECT_NEAR(s.cdf(R), 1.0, 1e-12);
        const double area =
            simpson([&](double r) { return s.pdfArea(r) * 2 * M_PI * r; }, 0.0, R, 20000);
        EXPECT_NEAR(area, 1.0, 1e-6);
        const double exactWindow =
            simpson([&](double r) { return p.Rd(r) * 2 * M_PI * r; }, 0.0, R, 20000);
        const int bins = 40, n = 200000;
        std::vector<double> edges(bins + 1);
        for (int k = 0; k < bins; ++k)
            edges[k] = s.quantile(double(k) / bins);
        edges[bins] = R;
        std::vector<double> expected(bins);
        for (int k = 0; k < bins; ++k)
            expected[k] = simpson([&](double r) { return p.Rd(r) * 2 * M_PI * r; }, edges[k],
                                  edges[k + 1], 2000) /
                          exactWindow;
        Pcg32 rng(13);
        for (int i = 0; i < 20000; ++i) {
            const double r = s.sample(rng.uniform(), rng.uniform());
            ASSERT_LE(r, R);
            ASSERT_NEAR(p.Rd(r) / s.pdfArea(r), exactWindow, 1e-6 * exactWindow);
        }
        EXPECT_LT(chiSquare(s, edges, expected, n, 13), chi2Critical(bins - 1))
            << "sa " << sa << " ss " << ss;
        // No window (0 or ∞) is the untruncated sampler.
        EXPECT_EQ(full.truncated(0.0).pdfArea(2.0), full.pdfArea(2.0));
        EXPECT_EQ(full.truncated(INFINITY).sample(0.3, 0.7), full.sample(0.3, 0.7));
    }
}
