// SPDX-License-Identifier: MIT
/// @file
/// @brief The radial exitance profile of a thick slab under a pencil beam at normal incidence:
/// exact (the reference path tracer's medium walk through a smooth dielectric boundary) against
/// calibrated SSLPV at several cell sizes. What the calibrated mode's spatial spread is, and the
/// data a profile fit needs (docs/methods/sslpv.md, "Limits of the calibration").
///
///     build/ci/tests/bench/sslpv_profile [walks=200000] [eta=1.3]
///
/// Prints per reduced albedo α′ (σt′ = 1 mm⁻¹, g = 0, η = 1.3 or as given) the radii (mm) that hold
/// 50 % and 90 % of the exitant flux within 12 mm of the beam, for the exact walk and for SSLPV at
/// Δx = 0.5, 1 and 2 mm, and SSLPV's total over the exact total (flux leaving the top face per
/// unit flux entering, within 12 mm).

#include <lucent/core/Fresnel.h>
#include <lucent/core/Random.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/reference/Transport.h>
#include <lucent/sslpv/SslpvCalibrationFit.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

using namespace lucent;
using namespace lucent::sslpv;

namespace {

constexpr double PI_D = 3.14159265358979323846;
float g_eta = 1.3f;             ///< relative index (second argument)
constexpr double R_MAX = 12.0;  ///< mm: the profile's extent
constexpr int BINS = 48;        ///< annuli of 0.25 mm

struct Profile {
    std::vector<double> flux = std::vector<double>(BINS, 0.0);  ///< per annulus, per unit flux
    [[nodiscard]] double total() const {
        double t = 0.0;
        for (double f : flux)
            t += f;
        return t;
    }
    /// Radius (mm) inside which `fraction` of the profile's flux lies (linear within a bin).
    [[nodiscard]] double radiusHolding(double fraction) const {
        const double want = fraction * total();
        double acc = 0.0;
        for (int i = 0; i < BINS; ++i) {
            if (acc + flux[i] >= want && flux[i] > 0.0)
                return (i + (want - acc) / flux[i]) * R_MAX / BINS;
            acc += flux[i];
        }
        return R_MAX;
    }
};

void addAt(Profile& p, double r, double w) {
    const int b = int(r / R_MAX * BINS);
    if (b >= 0 && b < BINS)
        p.flux[size_t(b)] += w;
}

/// Exact: walks from the top face's centre straight down (the refracted direction of normal
/// incidence), through a 60 × 60 × 30 mm box; flux leaving through the top face per unit
/// transmitted flux.
Profile exactProfile(float albedo, int walks) {
    const TriangleMesh box = makeBox(Vector3f(60.f, 60.f, 30.f));
    MaterialSample s;
    s.sigma_t = Rgb(1.f);
    s.sigma_s = Rgb(albedo);
    s.g = Rgb(0.f);
    const GridSpec spec = GridSpec::around(box.bounds(), 32);
    reference::GridMedium medium = reference::GridMedium::uniform(spec, toMedium(s), {});
    const reference::VolumeScene scene(box, std::move(medium), {});
    reference::TransportOptions opt;
    opt.boundary = reference::BoundaryModel::Dielectric;
    opt.eta = g_eta;
    Profile p;
    for (int i = 0; i < walks; ++i) {
        Pcg32 rng(uint64_t(i) * 2654435761u + 17u);
        const reference::WalkResult w = reference::walkMedium(
            scene, Point3f(0.f, 0.f, 15.f - 1e-4f), Vector3f(0, 0, -1), 1, rng, opt);
        if (w.escaped && w.position.z > 15.f - 1e-3f)
            addAt(p, std::hypot(double(w.position.x), double(w.position.y)), double(w.weight));
    }
    for (double& f : p.flux)
        f /= double(walks);
    return p;
}

/// Calibrated SSLPV: the fit's slab (cells [1, N−2]³ of an N³ grid, sinks around it), 2 × 2
/// unit-flux texels in the centre cell of the top face, propagated to 10⁻⁴; per top cell the
/// flux leaving, per unit transmitted flux (as the exact profile).
Profile sslpvProfile(float albedo, float dx, int n) {
    const CoarseMaterial m =
        sslpvThickSlab(n, dx, albedo, Point3f(-0.5f * float(n) * dx, -0.5f * float(n) * dx, 0.f));
    const float zTop = float(n - 1) * dx;
    std::vector<SslpvInjectionSample> texels;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i)
            texels.push_back(
                {Point3f((-0.25f + 0.5f * float(i)) * dx, (-0.25f + 0.5f * float(j)) * dx, zTop),
                 Normal3f(0, 0, 1), Vector3f(0, 0, -1), Rgb(0.25f)});
    SslpvOptions o{.order = 1, .maxSteps = 4096, .stopEpsilon = 1e-4f};
    o.mode = SslpvMode::Calibrated;
    SslpvSolver solver(o);
    solver.setMaterial(m, g_eta);
    solver.setInjectionSamples(texels);
    solver.solve();
    // Flux leaving per unit transmitted flux: L_o = exitScale·T(θ_o)·L_i integrated over the
    // outside hemisphere gives π·exitScale·L_i·(1 − F̄), F̄ the cosine-weighted mean Fresnel
    // reflectance; the texels carry unit incident flux, of which T(0) enters.
    double fbar = 0.0;
    constexpr int K = 2000;
    for (int i = 0; i < K; ++i) {
        const double mu = (i + 0.5) / K;
        fbar += 2.0 * double(fresnelDielectric(float(mu), g_eta)) * mu / K;
    }
    const double t0 = 1.0 - double(fresnelDielectric(1.f, g_eta));
    Profile p;
    for (int y = 1; y < n - 1; ++y)
        for (int x = 1; x < n - 1; ++x) {
            const Point3f c = m.spec.cellCenter({x, y, n - 2});
            const double L = double(solver.radiance(Point3f(c.x, c.y, zTop), Normal3f(0, 0, 1)).y) *
                             double(solver.exitScale());
            addAt(p, std::hypot(double(c.x), double(c.y)),
                  PI_D * L * (1.0 - fbar) / t0 * double(dx * dx));
        }
    return p;
}

}  // namespace

int main(int argc, char** argv) {
    const int walks = argc > 1 ? std::max(1000, std::atoi(argv[1])) : 200000;
    if (argc > 2)
        g_eta = std::clamp(float(std::atof(argv[2])), 1.f, 3.f);
    std::printf(
        "Thick slab, pencil beam at normal incidence, sigma_t' = 1/mm, g = 0, eta = %.2f; "
        "r50 / r90 (mm) of the exitant flux within %.0f mm\n",
        double(g_eta), R_MAX);
    std::printf(
        "| alpha' | exact r50 / r90 | SSLPV dx 0.5 | dx 1 | dx 2 | SSLPV total / exact "
        "(dx 0.5, 1, 2) |\n|---|---|---|---|---|---|\n");
    for (float albedo : {0.5f, 0.8f, 0.95f, 0.99f}) {
        const Profile ex = exactProfile(albedo, walks);
        std::printf("| %.2f | %.2f / %.2f |", double(albedo), ex.radiusHolding(0.5),
                    ex.radiusHolding(0.9));
        double ratio[3];
        int k = 0;
        for (float dx : {0.5f, 1.f, 2.f}) {
            const int n = std::min(96, std::max(16, int(2.0 * R_MAX / double(dx)) + 4));
            const Profile sp = sslpvProfile(albedo, dx, n);
            std::printf(" %.2f / %.2f |", sp.radiusHolding(0.5), sp.radiusHolding(0.9));
            ratio[k++] = sp.total() / ex.total();
        }
        std::printf(" %.2f, %.2f, %.2f |\n", ratio[0], ratio[1], ratio[2]);
        std::fflush(stdout);
    }
    return 0;
}
