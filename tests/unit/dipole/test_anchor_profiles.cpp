// SPDX-License-Identifier: MIT
// The pencil-beam Monte Carlo of the half-space (HalfSpaceBeam.h) against the adding–doubling
// total and the closed-form single scattering, and the anchor profiles (AnchorProfiles.h)
// against their own closed forms.
#include <lucent/core/Error.h>
#include <lucent/core/Quadrature.h>
#include <lucent/dipole/AnchorProfiles.h>
#include <lucent/dipole/HalfSpace.h>
#include <lucent/dipole/HalfSpaceBeam.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace lucent;
using namespace lucent::dipole;

namespace {

double ringedTotal(const std::function<double(double)>& f, double scale) {
    // ∫ f dA over [10⁻⁹, 10⁴]·scale with the comparison's own ring rule: 13 decades in rings.
    HalfSpaceBeamProfile grid;
    for (int i = 0; i <= 13 * 8; ++i)
        grid.ringEdges.push_back(scale * std::pow(10.0, -9.0 + i / 8.0));
    grid.ringFlux.assign(grid.ringEdges.size(), 1.0);
    grid.ringStdError.assign(grid.ringEdges.size(), 0.0);
    grid.total = 1.0;
    const RadialComparison c = compareRadial(grid, f, 1.0);
    double sum = 0.0;
    for (double v : c.ringFlux)
        sum += v;
    return sum;
}

}  // namespace

TEST(HalfSpaceBeam, TotalAgreesWithAddingDoubling) {
    // Two independent solvers of the same transport: the walk's total and the adding–doubling
    // reflectance at normal incidence. Tolerance: 4 standard errors of the walk plus the
    // solver's own 3·10⁻⁵ (HalfSpace.NodeCountConverges).
    struct Case {
        double albedo, eta;
    };
    for (const Case c : {Case{0.5, 1.0}, Case{0.9, 1.3}, Case{0.99, 1.3}, Case{0.95, 1.5}}) {
        const HalfSpaceBeamProfile mc =
            traceHalfSpaceBeam(c.albedo, c.eta, defaultBeamRings(), 1 << 18);
        const double ad = halfSpaceReflectance(c.albedo, c.eta);
        EXPECT_NEAR(mc.total, ad, 4.0 * mc.totalStdError + 3e-5)
            << "albedo " << c.albedo << " eta " << c.eta << " (walk " << mc.total << " ± "
            << mc.totalStdError << ")";
        double sum = mc.beyond;
        for (double v : mc.ringFlux)
            sum += v;
        EXPECT_NEAR(sum, mc.total, 1e-12);
    }
}

TEST(HalfSpaceBeam, FirstScatterRingsMatchTheClosedFormSingleScattering) {
    // Light that scattered once leaves at its first return: its ring fluxes have a closed form
    // (PhotonBeamProfile::single, a 1-D integral), which checks the walk's geometry, Fresnel
    // and ring binning ring by ring. 4 standard errors per ring (plus 10⁻⁶ of the quadrature).
    for (double eta : {1.0, 1.3}) {
        const double albedo = 0.8;
        const HalfSpaceBeamProfile mc =
            traceHalfSpaceBeam(albedo, eta, defaultBeamRings(), 1 << 19, 7);
        const PhotonBeamProfile model(1.0 - albedo, albedo, eta);
        HalfSpaceBeamProfile single = mc;
        single.ringFlux = mc.singleRingFlux;
        const RadialComparison c = compareRadial(
            single, [&](double r) { return model.single(r); }, model.singleTotal());
        double mcSum = 0.0, modelSum = 0.0, mcVar = 0.0;
        for (size_t i = 0; i < c.ringFlux.size(); ++i) {
            mcVar += mc.singleRingStdError[i] * mc.singleRingStdError[i];
            EXPECT_NEAR(mc.singleRingFlux[i], c.ringFlux[i],
                        4.0 * mc.singleRingStdError[i] + 1e-6 * model.singleTotal())
                << "eta " << eta << " ring " << i << " (outer edge " << mc.ringEdges[i] << " mfp)";
            mcSum += mc.singleRingFlux[i];
            modelSum += c.ringFlux[i];
        }
        // Nearly all first-scatter light leaves within 100 mfp.
        EXPECT_NEAR(modelSum, model.singleTotal(), 1e-6 * model.singleTotal()) << "eta " << eta;
        // The rings are disjoint (a photon lands in one), so their errors add in quadrature
        // (a slight overestimate: the counts are negatively correlated).
        EXPECT_NEAR(mcSum, modelSum, 4.0 * std::sqrt(mcVar)) << "eta " << eta;
    }
}

TEST(HalfSpaceBeam, ExitDirectionsAgreeWithAddingDoubling) {
    // Where the light leaves towards: the walk's flux-weighted mean outside cosine against the
    // adding–doubling radiance L(t) (2π∫L t² dt / R, the exit cosines carried through its solve
    // exactly, 32 Gauss–Legendre nodes in t). Every weight is ≤ 1 and a cosine's variance ≤ ¼,
    // so the walk's standard error is ≤ ½/√(N·total): 4 of those.
    for (double eta : {1.0, 1.3}) {
        const double albedo = 0.9;
        const int64_t n = 1 << 18;
        const HalfSpaceBeamProfile mc = traceHalfSpaceBeam(albedo, eta, defaultBeamRings(), n, 5);
        const QuadratureRule g = gaussLegendre(32).mappedTo(0.0, 1.0);
        const HalfSpaceExitance ad = halfSpaceExitance(albedo, eta, 1.0, g.x);
        double cos2 = 0.0;
        for (size_t i = 0; i < g.x.size(); ++i)
            cos2 += g.w[i] * 2.0 * M_PI * ad.radiance[i] * g.x[i] * g.x[i];
        EXPECT_NEAR(mc.meanExitCosine, cos2 / ad.reflectance,
                    4.0 * 0.5 / std::sqrt(double(n) * mc.total))
            << "eta " << eta;
        // Light leaving within 0.1 mfp of the entry went nearly straight down and up (a path
        // that scattered about one mfp deep and exits that close must climb steeply): it leaves
        // closer to the normal than the average (measured 0.75 against 0.65–0.68).
        EXPECT_GT(meanExitCosineWithin(mc, 0.0, 0.1), mc.meanExitCosine + 0.03) << "eta " << eta;
        EXPECT_EQ(meanExitCosineWithin(mc, 200.0, 300.0), 0.0);  // no ring there
    }
}

TEST(HalfSpaceBeam, TheLayerUnderTheSurfaceCarriesTheExitantFlux) {
    // Nothing enters the boundary but the beam at the origin, so the net outward flux through
    // the thin layer under the surface is what leaves there: the layer's track-length estimate
    // of J_n, summed over the rings from 3 to 30 mfp, against the exitant flux of the same
    // rings. The layer's average differs from the surface's value by what the layer absorbs
    // (depth·σa·φ ≈ 0.05·0.01·2A J_n, under 0.3 %) and by the sideways divergence of J_t in it
    // (depth·∇_t·J_t, ~1 % this far out; 2–4 % within 0.3 mfp of the beam at α′ = 0.9, where
    // J_t/J_n and 1/r are larger); the noise is 0.3 %: 2 %. The flux along the surface points
    // away from the beam and the light leaving leans the same way.
    for (double eta : {1.0, 1.3}) {
        const HalfSpaceBeamProfile mc =
            traceHalfSpaceBeam(0.99, eta, defaultBeamRings(), 1 << 18, 9);
        double exitant = 0.0, layer = 0.0;
        for (size_t i = 1; i < mc.ringEdges.size(); ++i)
            if (mc.ringEdges[i - 1] >= 3.0 && mc.ringEdges[i] <= 30.0) {
                exitant += mc.ringFlux[i];
                layer += mc.ringLayerNormalFlux[i];
            }
        std::printf("eta %.1f: layer J_n / exitant flux over 3-30 mfp: %.4f\n", eta,
                    layer / exitant);
        EXPECT_NEAR(layer / exitant, 1.0, 0.02) << "eta " << eta;
        const SurfaceLean far = surfaceLeanWithin(mc, 1.0, 10.0);
        EXPECT_GT(far.fluxRatio, 0.3) << "eta " << eta;
        EXPECT_GT(far.lean, 0.02) << "eta " << eta;
        EXPECT_EQ(surfaceLeanWithin(mc, 200.0, 300.0).fluxRatio, 0.0);  // no ring there
    }
}

TEST(HalfSpaceBeam, DeterministicAndRefusesBadInput) {
    const std::vector<double> rings = defaultBeamRings();
    const HalfSpaceBeamProfile a = traceHalfSpaceBeam(0.9, 1.3, rings, 50000, 3);
    const HalfSpaceBeamProfile b = traceHalfSpaceBeam(0.9, 1.3, rings, 50000, 3);
    EXPECT_EQ(a.ringFlux, b.ringFlux);
    EXPECT_EQ(a.total, b.total);
    EXPECT_NE(traceHalfSpaceBeam(0.9, 1.3, rings, 50000, 4).total, a.total);
    EXPECT_THROW(traceHalfSpaceBeam(1.0, 1.3, rings, 100), ValueError);
    EXPECT_THROW(traceHalfSpaceBeam(std::nan(""), 1.3, rings, 100), ValueError);
    EXPECT_THROW(traceHalfSpaceBeam(0.5, 0.9, rings, 100), ValueError);
    EXPECT_THROW(traceHalfSpaceBeam(0.5, 1.3, rings, 0), ValueError);
    EXPECT_THROW(traceHalfSpaceBeam(0.5, 1.3, {1.0, 0.5}, 100), ValueError);
    EXPECT_THROW(traceHalfSpaceBeam(0.5, 1.3, {}, 100), ValueError);
    EXPECT_THROW(compareRadial(
                     a, [](double) { return 1.0; }, 0.0),
                 ValueError);
    EXPECT_THROW(compareRadial(
                     a, [](double) { return std::nan(""); }, 1.0),
                 ValueError);
}

TEST(HalfSpaceBeam, APerfectModelReadsTheNoiseFloor) {
    // The exact profile's own rings as a model (piecewise constant in area): its shape error is
    // 0 against itself, and a second walk with another seed reads about the floor.
    const std::vector<double> rings = defaultBeamRings();
    const HalfSpaceBeamProfile a = traceHalfSpaceBeam(0.9, 1.3, rings, 1 << 17, 1);
    const HalfSpaceBeamProfile b = traceHalfSpaceBeam(0.9, 1.3, rings, 1 << 17, 2);
    const auto asModel = [](const HalfSpaceBeamProfile& p) {
        return [&p](double r) {
            const auto it = std::upper_bound(p.ringEdges.begin(), p.ringEdges.end(), r);
            if (it == p.ringEdges.end())
                return 0.0;
            const size_t i = size_t(it - p.ringEdges.begin());
            const double inner = i == 0 ? 0.0 : p.ringEdges[i - 1];
            return p.ringFlux[i] / (M_PI * (p.ringEdges[i] * p.ringEdges[i] - inner * inner));
        };
    };
    const RadialComparison self = compareRadial(a, asModel(a), a.total);
    EXPECT_LT(self.shapeError, 1e-3);  // only the quadrature of a step function inside rings
    const RadialComparison other = compareRadial(a, asModel(b), b.total);
    // Two noisy profiles: expected √2 × the floor; 3× bounds it with margin.
    EXPECT_LT(other.shapeError, 3.0 * other.shapeErrorFloor) << other.shapeErrorFloor;
    EXPECT_GT(other.shapeErrorFloor, 0.0);
}

TEST(BurleyProfile, IntegratesToTheSurfaceAlbedo) {
    const BurleyProfile b(0.6, 0.7);
    EXPECT_NEAR(ringedTotal([&](double r) { return b.R(r); }, 0.7), 0.6, 1e-6);
    EXPECT_DOUBLE_EQ(b.reflectanceBeyond(0.0), 0.6);
    const QuadratureRule g = gaussLegendre(64).mappedTo(2.0, 40.0);
    double between = 0.0;  // ∫_2^40 R 2πr dr
    for (size_t i = 0; i < g.x.size(); ++i)
        between += g.w[i] * b.R(g.x[i]) * 2.0 * M_PI * g.x[i];
    EXPECT_NEAR(b.reflectanceBeyond(2.0) - b.reflectanceBeyond(40.0), between, 1e-10);
    // Eq. 5 at its minimum-cubic point A = 0.8: s = 1.05; A = 0.2: 1.65 + 7·0.216.
    EXPECT_DOUBLE_EQ(burleySearchlightScale(0.8), 1.05);
    EXPECT_NEAR(burleySearchlightScale(0.2), 1.85 - 0.2 + 7 * 0.216, 1e-12);
    // The searchlight anchor takes the exact half-space total as A and d = ℓ / s(A).
    const BurleyProfile s = BurleyProfile::searchlight(0.032, 0.74, 1.3);
    const double A = halfSpaceReflectance(0.74 / 0.772, 1.3);
    EXPECT_NEAR(s.totalReflectance(), A, 1e-12);
    EXPECT_NEAR(s.d(), 1.0 / (0.772 * burleySearchlightScale(A)), 1e-12);
    EXPECT_TRUE(BurleyProfile::searchlight(0.5, 0.0, 1.3).isZero());
    EXPECT_EQ(BurleyProfile::searchlight(0.5, 0.0, 1.3).R(1.0), 0.0);
    EXPECT_THROW(BurleyProfile(1.2, 1.0), ValueError);
    EXPECT_THROW(BurleyProfile(0.5, 0.0), ValueError);
    EXPECT_THROW(BurleyProfile::searchlight(-1.0, 1.0, 1.3), ValueError);
    EXPECT_THROW(burleySearchlightScale(std::nan("")), ValueError);
}

TEST(PhotonBeamProfile, TotalsMatchTheirClosedFormAndQuadrature) {
    // The multiple-scattering part's total is closed form; the profile is a quadrature over
    // depth: their agreement checks the depth integral at every radius scale. The single
    // part against its own 1-D total. 10⁻⁴: the log-depth rule's measured accuracy.
    for (double eta : {1.0, 1.3, 2.0})
        for (double albedo : {0.3, 0.9, 0.999}) {
            const double st = 2.0;  // mm⁻¹: lengths in mm, not mfp
            const PhotonBeamProfile p(st * (1.0 - albedo), st * albedo, eta);
            EXPECT_NEAR(ringedTotal([&](double r) { return p.multiple(r); }, 1.0 / st),
                        p.multipleTotal(), 1e-4 * p.multipleTotal())
                << "albedo " << albedo << " eta " << eta;
            EXPECT_NEAR(ringedTotal([&](double r) { return p.single(r); }, 1.0 / st),
                        p.singleTotal(), 1e-4 * p.singleTotal())
                << "albedo " << albedo << " eta " << eta;
        }
    // σtr → 0 (no absorption): the C_φ term's limit.
    const PhotonBeamProfile lossless(0.0, 1.0, 1.3);
    EXPECT_TRUE(std::isfinite(lossless.multipleTotal()));
    EXPECT_GT(lossless.multipleTotal(), 0.5);
    EXPECT_TRUE(PhotonBeamProfile(1.0, 0.0, 1.3).isZero());
    EXPECT_EQ(PhotonBeamProfile(1.0, 0.0, 1.3).R(0.5), 0.0);
    EXPECT_THROW(PhotonBeamProfile(0.1, 1.0, 0.5), ValueError);
    EXPECT_THROW(PhotonBeamProfile(std::nan(""), 1.0, 1.3), ValueError);
}
