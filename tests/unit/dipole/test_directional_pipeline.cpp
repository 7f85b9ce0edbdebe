// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/dipole/DirectionalPipeline.h>
#include <lucent/dipole/HalfSpace.h>
#include <lucent/mesh/Procedural.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

using namespace lucent;
using namespace lucent::dipole;

namespace {

Scene slab(float sigma_a, float sigma_s) {
    Scene s;
    SceneObject obj;
    obj.mesh = makeBox({60.f, 60.f, 20.f});
    MaterialSample m;
    m.sigma_s = Rgb(sigma_s);
    m.sigma_t = Rgb(sigma_a + sigma_s);
    obj.material = std::make_shared<MaterialVolume>(GridSpec::around(obj.mesh.bounds(), 32), m);
    s.objects.push_back(std::move(obj));
    Light l;
    l.type = Light::Type::Directional;
    l.direction = {0.f, 0.f, -1.f};
    l.intensity = Rgb(1.f);
    s.lights.push_back(l);
    s.camera.position = {0.f, 0.f, 80.f};
    s.camera.orthographic = true;
    s.camera.orthoHeight = 1.6f;
    s.camera.width = s.camera.height = 16;
    s.eta = 1.3f;
    return s;
}

}  // namespace

TEST(DirectionalPipeline, SlabAtNormalIncidenceMatchesQuadrature) {
    // Normal incidence on a face much wider than the profile: the estimate of
    // T₂₁(0) T₁₂(0) E ∫ S_d dA must match the radial quadrature within 4 standard errors
    // (spread over the 256 pixels, which use independent sample offsets). Published model
    // (normalisation off) against its quadrature; normalised model (the default target) against
    // the exact half-space's radiance along the normal (plus 6e-4: DirpoleEnergyTable's
    // interpolation; the exit table's nodes include t = 1, so it adds none there).
    const float sa = 0.05f, ss = 1.5f;
    for (bool normalised : {false, true}) {
        DirectionalSettings ds;
        ds.samplesPerPass = 32;
        ds.energyNormalised = normalised;
        DirectionalDipoleRenderer r(slab(sa, ss), ds);
        for (int i = 0; i < 4; ++i)
            r.addPass();
        EXPECT_EQ(r.passes(), 4);
        const ImageRgb L = r.radiance();
        double mean = 0.0, m2 = 0.0;
        for (const Rgb& v : L.pixels()) {
            mean += v.g;
            m2 += double(v.g) * v.g;
        }
        const double n = double(L.pixels().size());
        mean /= n;
        const double se = std::sqrt(std::max(0.0, m2 / n - mean * mean) / (n - 1));
        // Exact: S_d is radial at normal incidence, radial(r) = S_d·4πC_φ(1/η); the 60 mm face
        // is ≫ the profile, so the plane integral is the quadrature of the radial profile.
        const DirectionalDipole d(sa, ss, 1.3);
        const double cPhiInv = 0.25 * (1.0 - 2.0 * fresnelMoment(1, 1.0 / 1.3));
        // Normalised (exact target): the exact half-space's radiance along the normal, which
        // the exit-angle correction gives the model, per unit flux entering (T₁₂ of it).
        const double t = 1.0 - fresnelDielectric(1.0, 1.3);
        const double expected =
            normalised ? t * halfSpaceExitance(ss / (sa + ss), 1.3, 1.0, {1.0}).radiance[0]
                       : t * t * integrateProfile(d) / (4 * M_PI * cPhiInv);
        std::printf("directional pipeline (%s): mean %.6g, expected %.6g, standard error %.2g\n",
                    normalised ? "normalised" : "published", mean, expected, se);
        EXPECT_NEAR(mean, expected, 4 * se + (normalised ? 6e-4 : 1e-4) * expected) << "se " << se;
    }
}

TEST(DirectionalPipeline, EnergyNormalisationScalesEachChannelByTheTable) {
    // Same samples with and without the normalisation: every pixel's channel c is scaled by
    // DirpoleEnergyTable(η, target).scale(α′_c) and, with the exact target, by the exit-angle
    // correction DirpoleExitTable(η).correction(α′_c, t) along the view (the slab's face is seen
    // along its normal, t = 1). Float rounding: 1e-5 relative.
    Scene s = slab(0.f, 1.f);
    MaterialSample m;
    m.sigma_s = Rgb(1.5f, 1.2f, 0.9f);
    m.sigma_t = m.sigma_s + Rgb(0.01f, 0.1f, 0.6f);
    s.objects[0].material =
        std::make_shared<MaterialVolume>(GridSpec::around(s.objects[0].mesh.bounds(), 32), m);
    DirectionalSettings off;
    off.energyNormalised = false;
    DirectionalDipoleRenderer a(s, off);
    a.addPass();
    const DirpoleExitTable exit(1.3);
    for (EnergyTarget target : {EnergyTarget::ExactHalfSpace, EnergyTarget::BetterDipole}) {
        DirectionalSettings on;
        on.energyTarget = target;
        DirectionalDipoleRenderer b(s, on);
        b.addPass();
        const DirpoleEnergyTable table(1.3, target);
        int checked = 0;
        for (size_t i = 0; i < a.radiance().pixels().size(); ++i)
            for (int c = 0; c < 3; ++c) {
                const float va = a.radiance().pixels()[i][c], vb = b.radiance().pixels()[i][c];
                if (!(va > 0.f))
                    continue;
                const double alphaP = double(m.sigma_s[c]) / double(m.sigma_t[c]);
                const double want =
                    table.scale(alphaP) *
                    (target == EnergyTarget::ExactHalfSpace ? exit.correction(alphaP, 1.0) : 1.0);
                ASSERT_NEAR(double(vb) / double(va), want, 1e-5 * want)
                    << energyTargetName(target) << " pixel " << i << " c " << c;
                ++checked;
            }
        EXPECT_GT(checked, 600);
    }
}

TEST(DirectionalPipeline, ProgressiveAndErrors) {
    Scene s = slab(0.1f, 1.f);
    DirectionalDipoleRenderer r(s);
    EXPECT_EQ(r.radiance().at(3, 3), Rgb(0.f));  // no pass yet
    r.addPass();
    const Rgb one = r.radiance().at(3, 3);
    r.addPass();
    EXPECT_GT(one.r, 0.f);
    EXPECT_TRUE(isFinite(r.radiance().at(3, 3)));
    s.lights[0].type = Light::Type::Point;
    EXPECT_THROW(DirectionalDipoleRenderer{s}, ValueError);
    DirectionalSettings bad;
    bad.samplesPerPass = 0;
    EXPECT_THROW(DirectionalDipoleRenderer(slab(0.1f, 1.f), bad), ValueError);
}
