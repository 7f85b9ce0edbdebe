// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli profile`: total diffuse reflectance per channel and the radial profile
/// R(r) of the dipole (Jensen 2001), better dipole (d'Eon 2012) or directional dipole
/// (Frisvad et al. 2014, normal incidence); optional JSON and a PNG plot of R(r)·r.

#include "CliCommon.h"

#include <lucent/bench/LinePlot.h>
#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/dipole/AnchorProfiles.h>
#include <lucent/dipole/HalfSpaceBeam.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/dipole/Sampling.h>
#include <lucent/sslpv/GridDiffusion.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace lucent::cli {

namespace {

/// Radius holding 99% of the widest channel's profile (Jensen-shaped sampler of the better
/// dipole's parameters; used for the table and plot range only).
double profileRange(const std::array<dipole::ScalarMedium, 3>& media) {
    double range = 0.0;
    for (const auto& m : media) {
        const dipole::DipoleSampler s(dipole::DipoleProfile::better(m.sigma_a, m.sigma_s, m.eta));
        if (s.isValid())
            range = std::max(range, s.quantile(0.99));
    }
    return range > 0.0 ? range : 1.0;
}

using Channels = std::array<dipole::NamedRadialProfile, 3>;

/// Line plot of R(r)·r for the three channels (red, green, blue curves), r in [0, rMax].
void writePlot(const std::string& path, const Channels& profiles, double rMax) {
    bench::LinePlot plot;
    const std::array<Rgb, 3> colours = {Rgb(0.85f, 0.1f, 0.1f), Rgb(0.1f, 0.6f, 0.1f),
                                        Rgb(0.1f, 0.2f, 0.9f)};
    const int samples = plot.width - 2 * plot.margin + 1;  // one per pixel column
    for (int c = 0; c < 3; ++c) {
        bench::LinePlot::Curve curve{std::vector<double>(size_t(samples)), colours[size_t(c)]};
        for (int i = 0; i < samples; ++i) {
            const double r = rMax * i / (samples - 1);
            // R·r is bounded at r = 0 for every model (Burley's and PBD's R are ∝ 1/r there).
            curve.values[size_t(i)] = r > 0.0 ? profiles[size_t(c)].R(r) * r : 0.0;
        }
        plot.curves.push_back(std::move(curve));
    }
    writePng(bench::renderLinePlot(plot), path);
}

/// ∫ R dA by quadrature (Profiles.h's integrateRadial), independent of the model's own total.
double quadratureTotal(const dipole::NamedRadialProfile& p, const dipole::ScalarMedium& m) {
    const double st = m.sigma_a + m.sigma_s;
    const auto thunk = [](const void* ctx, double r) {
        return (*static_cast<const std::function<double(double)>*>(ctx))(r);
    };
    return dipole::integrateRadial(thunk, &p.R, st > 0.0 ? 1.0 / st : 1.0);
}

struct ProfileOptions {
    // Defaults: Jensen et al. 2001 Table 2 marble (mm⁻¹), η = 1.5.
    std::string model = "dipole", sigmaA = "0.0021,0.0041,0.0071", sigmaS = "2.19,2.62,3.00", plot;
    float eta = 1.5f;
    int radii = 16;
    int64_t photons = 0;  // > 0: --against-exact
    bool json = false;
};

/// --against-exact: every radial model against the exact half-space under a pencil beam, per
/// channel (dipole.md §4b).
void runAgainstExact(const ProfileOptions& args, const std::array<dipole::ScalarMedium, 3>& media) {
    const double eta = media[0].eta;
    std::printf(
        "radial profiles against the exact half-space (pencil beam at normal incidence, "
        "eta %.4g, %lld photons per channel)\n",
        eta, static_cast<long long>(args.photons));
    std::printf(
        "shape error: share of the exitant light in the wrong ring (8 rings per decade, "
        "0.01-100 mfp)\n\n");
    std::printf("%-8s %-18s %8s %8s %8s %7s %7s\n", "channel", "model", "total", "shape", "floor",
                "r50", "r90");
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        const dipole::ScalarMedium& m = media[size_t(c)];
        const double st = m.sigma_a + m.sigma_s;
        if (!(st > 0.0) || !(m.sigma_s > 0.0)) {
            std::printf("%-8s (no scattering: every model is zero)\n", names[c]);
            continue;
        }
        const double albedo = std::min(m.sigma_s / st, 0.9999);
        if (m.sigma_s / st > 0.9999 * (1.0 + 1e-12))
            std::printf(
                "%-8s (albedo %.6f traced at 0.9999: the walk's length has no finite "
                "mean at 1)\n",
                names[c], m.sigma_s / st);
        const dipole::HalfSpaceBeamProfile exact =
            dipole::traceHalfSpaceBeam(albedo, eta, dipole::defaultBeamRings(), args.photons);
        std::printf("%-8s %-18s %8.4f %8s %8.4f %7s %7s   (alpha' %.4f, total %.4f +- %.4f)\n",
                    names[c], "exact", 1.0, "-", 0.0, "-", "-", albedo, exact.total,
                    exact.totalStdError);
        std::printf(
            "%-8s mean exit cosine of the exact light: %.3f within 0.1 mfp, %.3f at 0.1-1, "
            "%.3f at 1-10, %.3f over all\n",
            names[c], dipole::meanExitCosineWithin(exact, 0.0, 0.1),
            dipole::meanExitCosineWithin(exact, 0.1, 1.0),
            dipole::meanExitCosineWithin(exact, 1.0, 10.0), exact.meanExitCosine);
        // The lean of the exiting light along the flux on the surface, per unit J_t/J_n: what
        // the diffusion mode's P1 exit term assumes, against the walk (sslpv.md).
        const dipole::SurfaceLean near = dipole::surfaceLeanWithin(exact, 0.1, 1.0);
        const dipole::SurfaceLean far = dipole::surfaceLeanWithin(exact, 1.0, 10.0);
        const auto perUnit = [](const dipole::SurfaceLean& s) {
            return s.fluxRatio > 0.0 ? s.lean / s.fluxRatio : 0.0;
        };
        std::printf(
            "%-8s exit lean per unit J_t/J_n: exact %.3f at 0.1-1 mfp (J_t/J_n %.2f), %.3f at "
            "1-10 (%.2f); the diffusion read-out's P1 term %.3f\n",
            names[c], perUnit(near), near.fluxRatio, perUnit(far), far.fluxRatio,
            sslpv::surfaceFluxExitLean(albedo, eta));
        dipole::ScalarMedium traced = m;
        traced.sigma_a = st * (1.0 - albedo);
        traced.sigma_s = st * albedo;
        for (const dipole::ModelAgainstBeam& row : dipole::compareModelsWithBeam(traced, exact))
            std::printf("%-8s %-18s %8.4f %8.4f %8.4f %7.3f %7.3f\n", names[c], row.model.c_str(),
                        row.comparison.totalRatio, row.comparison.shapeError,
                        row.comparison.shapeErrorFloor, row.comparison.r50Ratio,
                        row.comparison.r90Ratio);
    }
    std::printf(
        "\ntotal: model / exact; r50, r90: radius holding 50 %% / 90 %% of the exitant "
        "light, model / exact\n");
}

void runProfile(const ProfileOptions& args) {
    if (args.model == "dirpole")
        std::fprintf(stderr, "%s\n", dipole::PUBLISHED_DIRPOLE_WARNING);
    const Rgb sigmaA = parseRgb("--sigma-a", args.sigmaA, 0.f, 1e6f);
    const Rgb sigmaS = parseRgb("--sigma-s", args.sigmaS, 0.f, 1e6f);
    const float eta = args.eta;
    const int radiiCount = args.radii;
    std::array<dipole::ScalarMedium, 3> media;
    for (int c = 0; c < 3; ++c)
        media[size_t(c)] = {double(sigmaA[c]), double(sigmaS[c]), double(eta)};
    if (args.photons > 0)
        return runAgainstExact(args, media);

    Channels profiles;
    std::array<double, 3> total{}, numeric{};
    for (int c = 0; c < 3; ++c) {
        profiles[size_t(c)] = dipole::makeRadialProfile(args.model, media[size_t(c)]);
        total[size_t(c)] = profiles[size_t(c)].total;
        // Independent quadrature of the same profile (for the directional dipole, which has no
        // closed form, the total is this quadrature too).
        numeric[size_t(c)] = quadratureTotal(profiles[size_t(c)], media[size_t(c)]);
    }
    const double rMax = profileRange(media);
    std::vector<double> radii(static_cast<size_t>(radiiCount));
    for (int i = 0; i < radiiCount; ++i)
        radii[size_t(i)] = rMax * std::pow(1e-3, 1.0 - double(i) / (radiiCount - 1));

    if (args.json) {
        std::printf("{\n  \"model\": \"%s\",\n  \"eta\": %.9g,\n", args.model.c_str(), double(eta));
        std::printf(
            "  \"sigma_a\": [%.9g, %.9g, %.9g],\n  \"sigma_s_reduced\": [%.9g, %.9g, %.9g],\n",
            double(sigmaA.r), double(sigmaA.g), double(sigmaA.b), double(sigmaS.r),
            double(sigmaS.g), double(sigmaS.b));
        std::printf("  \"total_reflectance\": [%.9g, %.9g, %.9g],\n", total[0], total[1], total[2]);
        std::printf("  \"total_reflectance_quadrature\": [%.9g, %.9g, %.9g],\n", numeric[0],
                    numeric[1], numeric[2]);
        std::printf("  \"units\": {\"r\": \"mm\", \"R\": \"mm^-2\"},\n  \"profile\": [\n");
        for (size_t i = 0; i < radii.size(); ++i) {
            const double r = radii[i];
            std::printf("    {\"r\": %.9g, \"R\": [%.9g, %.9g, %.9g]}%s\n", r, profiles[0].R(r),
                        profiles[1].R(r), profiles[2].R(r), i + 1 < radii.size() ? "," : "");
        }
        std::printf("  ]\n}\n");
    } else {
        std::printf(
            "model %s, eta %.4g, sigma_a (%.6g, %.6g, %.6g) mm^-1, sigma_s' (%.6g, %.6g, %.6g) "
            "mm^-1\n",
            args.model.c_str(), double(eta), double(sigmaA.r), double(sigmaA.g), double(sigmaA.b),
            double(sigmaS.r), double(sigmaS.g), double(sigmaS.b));
        std::printf("total diffuse reflectance (the model's):  R %.6f  G %.6f  B %.6f\n", total[0],
                    total[1], total[2]);
        std::printf("total diffuse reflectance (quadrature):   R %.6f  G %.6f  B %.6f\n",
                    numeric[0], numeric[1], numeric[2]);
        std::printf("%14s %14s %14s %14s   (R(r) in mm^-2)\n", "r [mm]", "R", "G", "B");
        for (double r : radii)
            std::printf("%14.6g %14.6g %14.6g %14.6g\n", r, profiles[0].R(r), profiles[1].R(r),
                        profiles[2].R(r));
    }
    if (!args.plot.empty()) {
        writePlot(args.plot, profiles, rMax);
        std::fprintf(stderr, "wrote %s (R(r)*r for r in [0, %.4g] mm; red, green, blue channels)\n",
                     args.plot.c_str(), rMax);
    }
}

}  // namespace

void addProfileCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* sub = addCommand(
        cli, "profile", "diffuse reflectance profile R(r) of a radial model",
        "usage: lucent-cli profile [--model NAME] [--sigma-a R,G,B]\n"
        "                          [--sigma-s R,G,B] [--eta E] [--radii N] [--json]\n"
        "                          [--plot out.png] [--against-exact N]\n",
        "Prints the total diffuse reflectance per channel (the model's own: closed form where it\n"
        "has one; and by quadrature of R(r)), at normal incidence, and R(r) in\n"
        "mm^-2 at N radii spaced geometrically up to the radius holding 99% of the profile.\n"
        "With --against-exact N it instead traces the exact half-space under a pencil beam\n"
        "(N photons per channel) and compares every radial model with it, Christensen-Burley\n"
        "and photon beam diffusion included; it also prints how far the exiting light leans\n"
        "along the flux on the surface, per unit J_t/J_n, against the P1 term of SSLPV's\n"
        "diffusion read-out.\n");
    auto args = std::make_shared<ProfileOptions>();
    sub->add_option("--model", args->model,
                    "dipole (Jensen 2001, default), better-dipole (d'Eon 2012), dirpole (Frisvad "
                    "2014, as published), dirpole-normalised (scaled to the exact half-space "
                    "total), burley (Christensen-Burley 2015 searchlight fit), photon-beam (Habel "
                    "et al. 2013), photon-beam-ms (its multiple scattering alone)")
        ->type_name("NAME")
        ->check(CLI::IsMember(dipole::radialProfileNames()));
    sub->add_option("--sigma-a", args->sigmaA,
                    "absorption coefficient, mm^-1 (default marble 0.0021,0.0041,0.0071)")
        ->type_name("R,G,B");
    sub->add_option("--sigma-s", args->sigmaS,
                    "reduced scattering coefficient sigma_s', mm^-1 (default 2.19,2.62,3.00)")
        ->type_name("R,G,B");
    sub->add_option("--eta", args->eta, "relative index of refraction (default 1.5)")
        ->type_name("E")
        ->check(finiteRange(1, 3));
    sub->add_option("--radii", args->radii, "number of radii (default 16)")
        ->type_name("N")
        ->check(CLI::Range(2, 1000));
    sub->add_flag("--json", args->json, "machine-readable output");
    sub->add_option("--against-exact", args->photons,
                    "trace the exact half-space under a pencil beam with N photons per channel "
                    "and compare every radial model with it: total, shape error (light in the "
                    "wrong ring), radii holding 50 and 90 % (e.g. 1000000)")
        ->type_name("N")
        ->check(CLI::Range(int64_t(1000), int64_t(10000000000LL)));
    sub->add_option("--plot", args->plot, "write a PNG plot of R(r)*r per channel")
        ->type_name("out.png");
    sub->callback([args] { runProfile(*args); });
}

}  // namespace lucent::cli
