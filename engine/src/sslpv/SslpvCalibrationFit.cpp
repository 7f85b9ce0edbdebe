// SPDX-License-Identifier: MIT
#include <lucent/core/Fresnel.h>
#include <lucent/sslpv/SslpvCalibrationFit.h>

#include <lucent/core/Error.h>
#include <lucent/dipole/Profiles.h>

#include <algorithm>
#include <cmath>

namespace lucent::sslpv {

namespace {

void checkSettings(const SslpvCalibrationFitSettings& s) {
    LUCENT_CHECK(s.gridCells >= 16 && s.gridCells <= 128, "SSLPV fit: grid of ", s.gridCells,
                 " cells per axis is outside [16, 128]");
    LUCENT_CHECK(s.order == 1 || s.order == 2, "SSLPV fit: SH order ", s.order, " is not 1 or 2");
    LUCENT_CHECK(s.eta >= 1.f && s.eta <= 3.f, "SSLPV fit: eta ", s.eta, " is outside [1, 3]");
    LUCENT_CHECK(!s.cases.empty(), "SSLPV fit: no case to fit");
    for (const SslpvFitCase& c : s.cases)
        LUCENT_CHECK(
            c.albedo >= 0.f && c.albedo < 1.f && c.cellMfp > 0.f && std::isfinite(c.cellMfp),
            "SSLPV fit: case albedo ", c.albedo, ", cell ", c.cellMfp,
            " mfp: expected albedo in [0, 1) and a positive cell size");
    const SslpvCalibration& k = s.calibration;
    for (float w : {k.linear, k.transport, k.diffusion, k.perStep, k.perStepTransport})
        LUCENT_CHECK(w >= 0.f && std::isfinite(w), "SSLPV fit: weight ", w,
                     " is not a finite number >= 0");
}

/// The settings' weights with both gains 1: the response is measured before the gain.
SslpvOptions fitOptions(const SslpvCalibrationFitSettings& s) {
    SslpvOptions o = sslpvFitOptions(s.order);
    o.calibration = s.calibration;
    o.calibration.gain[0] = o.calibration.gain[1] = 1.f;  // fitted
    return o;
}

/// The rows of every case at `options` with the optimal gain.
SslpvCalibrationFit evaluateFit(const std::vector<SslpvFitCase>& cases, int n,
                                const SslpvOptions& options, float eta) {
    SslpvCalibrationFit r;
    r.calibration = options.calibration;
    double sumLog = 0.0;
    for (const SslpvFitCase& fc : cases) {
        SslpvFitRow row;
        row.fitCase = fc;
        row.dipoleReflectance = sslpvSlabDipoleReflectance(fc.albedo, eta);
        row.target = sslpvSlabTarget(fc.albedo, eta);
        SslpvStats stats;
        row.ratio = sslpvSlabResponse(fc, n, options, eta, &stats) / row.target;
        row.steps = stats.stepsUsed;
        sumLog += std::log(std::max(row.ratio, 1e-30));
        r.rows.push_back(row);
    }
    r.gain = std::exp(-sumLog / double(cases.size()));
    double ss = 0.0;
    for (SslpvFitRow& row : r.rows) {
        const double q = row.ratio * r.gain;
        const double l = std::log(std::max(q, 1e-30));
        ss += l * l;
        r.maxAbsRel = std::max(r.maxAbsRel, std::abs(q - 1.0));
        row.fitted = q * row.target;
        row.residual = q - 1.0;
    }
    r.rmsLog = std::sqrt(ss / double(cases.size()));
    r.calibration.gain[options.order - 1] = float(r.gain);
    return r;
}

float SslpvCalibration::*weightMember(SslpvFitWeight w) {
    switch (w) {
        case SslpvFitWeight::Linear:
            return &SslpvCalibration::linear;
        case SslpvFitWeight::Diffusion:
            return &SslpvCalibration::diffusion;
        case SslpvFitWeight::Transport:
            break;
    }
    return &SslpvCalibration::transport;
}

}  // namespace

std::vector<SslpvFitCase> sslpvFitCases() {
    const float albedos[] = {0.3f, 0.5f, 0.7f, 0.8f, 0.9f, 0.95f, 0.99f};
    const float cells[] = {0.5f, 1.f, 2.f, 4.f};
    std::vector<SslpvFitCase> cases;
    for (float c : cells)
        for (float a : albedos)
            cases.push_back({a, c});
    return cases;
}

SslpvOptions sslpvFitOptions(int order) {
    LUCENT_CHECK(order == 1 || order == 2, "SSLPV fit: SH order ", order, " is not 1 or 2");
    SslpvOptions o{.order = order,
                   .maxSteps = 4096,
                   .skipAccumulateSteps = 2,
                   .removeExitant = true,
                   .stopEpsilon = 1e-4f,
                   .mode = SslpvMode::Calibrated};
    o.calibration = defaultSslpvCalibration();
    o.calibration.gain[0] = o.calibration.gain[1] = 1.f;
    return o;
}

CoarseMaterial sslpvThickSlab(int n, float cellMm, float albedo, const Point3f& origin) {
    LUCENT_CHECK(n >= 3 && n <= 1024, "SSLPV slab: grid of ", n,
                 " cells per axis is outside [3, 1024]");
    LUCENT_CHECK(cellMm > 0.f && std::isfinite(cellMm), "SSLPV slab: cell size ", cellMm,
                 " mm is not positive");
    LUCENT_CHECK(albedo >= 0.f && albedo <= 1.f, "SSLPV slab: albedo ", albedo,
                 " is outside [0, 1]");
    CoarseMaterial m;
    m.spec.resolution = n;
    m.spec.voxelSize = cellMm;
    m.spec.origin = origin;
    const size_t count = m.spec.voxelCount();
    m.insideFraction.assign(count, 0.f);
    for (int c = 0; c < 3; ++c) {
        m.sigma_t[c].assign(count, 1.f);
        m.sigma_s[c].assign(count, albedo);
        m.g[c].assign(count, 0.f);
    }
    for (int z = 1; z < n - 1; ++z)
        for (int y = 1; y < n - 1; ++y)
            for (int x = 1; x < n - 1; ++x)
                m.insideFraction[m.spec.linearIndex({x, y, z})] = 1.f;
    m.homogeneous = true;
    return m;
}

double sslpvSlabResponse(const SslpvFitCase& fc, int n, const SslpvOptions& options, float eta,
                         SslpvStats* stats) {
    LUCENT_CHECK(n >= 16 && n <= 128, "SSLPV slab: grid of ", n,
                 " cells per axis is outside [16, 128]");
    LUCENT_CHECK(fc.cellMfp > 0.f && std::isfinite(fc.cellMfp), "SSLPV slab: cell size ",
                 fc.cellMfp, " mfp is not positive");
    const float h = fc.cellMfp;  // σt = 1 mm⁻¹
    const CoarseMaterial m = sslpvThickSlab(n, h, fc.albedo, Point3f(0.f));
    const float zTop = float(n - 1) * h;
    std::vector<SslpvInjectionSample> texels;
    const int lo = n / 2 - 4;
    double phi = 0.0;
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) {
            texels.push_back(
                {Point3f((lo + 0.25f + 0.5f * i) * h, (lo + 0.25f + 0.5f * j) * h, zTop),
                 Normal3f(0, 0, 1), Vector3f(0, 0, -1), Rgb(1.f)});
            phi += 1.0;
        }
    SslpvSolver solver(options);
    solver.setMaterial(m, eta);
    solver.setInjectionSamples(std::move(texels));
    const SslpvStats& st = solver.solve();
    if (stats)
        *stats = st;
    const float gain = options.calibration.gain[options.order - 1];
    double sum = 0.0;
    for (int y = 1; y < n - 1; ++y)
        for (int x = 1; x < n - 1; ++x)
            sum += double(solver
                              .radiance(Point3f((x + 0.5f) * h, (y + 0.5f) * h, zTop),
                                        Normal3f(0, 0, 1))
                              .y) *
                   double(solver.exitScale() / gain) * double(h) * double(h);
    return sum / phi;
}

double sslpvSlabDipoleReflectance(float albedo, float eta) {
    return dipole::totalReflectance(dipole::Model::Dipole, dipole::fromReduced(1.f, albedo, eta));
}

double sslpvSlabTarget(float albedo, float eta) {
    constexpr double PI_D = 3.14159265358979323846;
    return (1.0 - fresnelDielectric(1.0, eta)) * sslpvSlabDipoleReflectance(albedo, eta) / PI_D;
}

SslpvCalibrationFit fitSslpvCalibration(const SslpvCalibrationFitSettings& s) {
    checkSettings(s);
    LUCENT_CHECK(s.iterations >= 1 && s.iterations <= 100, "SSLPV fit: ", s.iterations,
                 " search iterations is outside [1, 100]");
    SslpvOptions base = fitOptions(s);
    if (s.search) {
        // Golden-section search of one weight (log scale) with the others fixed: the objective
        // is the RMS log residual after the optimal gain.
        float SslpvCalibration::*fitted = weightMember(*s.search);
        double a = std::log(0.02), b = std::log(5.0);
        const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
        auto f = [&](double x) {
            SslpvOptions o = base;
            o.calibration.*fitted = float(std::exp(x));
            const double v = evaluateFit(s.cases, s.gridCells, o, s.eta).rmsLog;
            if (s.onSearchStep)
                s.onSearchStep(std::exp(x), v);
            return v;
        };
        double c = b - phi * (b - a), d = a + phi * (b - a);
        double fc = f(c), fd = f(d);
        for (int it = 0; it < s.iterations; ++it) {
            if (fc < fd) {
                b = d;
                d = c;
                fd = fc;
                c = b - phi * (b - a);
                fc = f(c);
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + phi * (b - a);
                fd = f(d);
            }
        }
        base.calibration.*fitted = float(std::exp(0.5 * (a + b)));
    }
    return evaluateFit(s.cases, s.gridCells, base, s.eta);
}

std::vector<SslpvBetaRow> solveSslpvBeta(const SslpvCalibrationFitSettings& s, double gain,
                                         int iterations,
                                         const std::function<void(const SslpvBetaRow&)>& onRow) {
    checkSettings(s);
    LUCENT_CHECK(gain >= 1e-3 && gain <= 1e3, "SSLPV fit: gain ", gain,
                 " is outside [0.001, 1000]");
    LUCENT_CHECK(iterations >= 1 && iterations <= 40, "SSLPV fit: ", iterations,
                 " bisection iterations is outside [1, 40]");
    const SslpvOptions base = fitOptions(s);
    std::vector<SslpvBetaRow> rows;
    for (const SslpvFitCase& fc : s.cases) {
        const double target = sslpvSlabTarget(fc.albedo, s.eta);
        double lo = std::log(1e-4), hi = std::log(20.0);
        SslpvBetaRow row;
        row.fitCase = fc;
        for (int it = 0; it < iterations; ++it) {
            const double mid = 0.5 * (lo + hi);
            SslpvOptions o = base;
            o.calibration = SslpvCalibration{};
            o.calibration.linear = float(std::exp(mid) / ((1.0 - fc.albedo) * double(fc.cellMfp)));
            SslpvStats stats;
            const double resp = gain * sslpvSlabResponse(fc, s.gridCells, o, s.eta, &stats);
            row.steps = stats.stepsUsed;
            (resp > target ? lo : hi) = mid;
        }
        row.beta = std::exp(0.5 * (lo + hi));
        row.betaPerAbsorption = row.beta / (1.0 - fc.albedo);
        row.transportCell = std::sqrt(3.0 * (1.0 - fc.albedo)) * fc.cellMfp;
        if (onRow)
            onRow(row);
        rows.push_back(row);
    }
    return rows;
}

}  // namespace lucent::sslpv
