// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The fit of the calibrated SSLPV mode against the classical dipole on thick slabs
/// (docs/methods/sslpv.md, "Calibrated mode"), run by `lucent-cli bench sslpv-fit`; the CLI
/// parses the arguments and prints the tables.
///
///     SslpvCalibrationFitSettings s;          // 48³, SH order 1, η = 1.3, the shipped weights
///     s.search = SslpvFitWeight::Transport;   // optional: golden-section search of one weight
///     SslpvCalibrationFit fit = fitSslpvCalibration(s);
///     // fit.calibration.gain[0]: the optimal gain; fit.rows[i].residual per case

#include <lucent/sslpv/SslpvSolver.h>

#include <functional>
#include <optional>
#include <vector>

namespace lucent::sslpv {

/// One thick-slab configuration of the fit.
struct SslpvFitCase {
    float albedo = 0.5f;  ///< α′ = σs′/σt (reduced), [0, 1)
    float cellMfp = 1.f;  ///< Δx·σt: cell size in reduced mean free paths (σt = 1 mm⁻¹), > 0
};

/// The documented cases: cell sizes {0.5, 1, 2, 4} mfp (outer) × α′ ∈ {0.3, 0.5, 0.7, 0.8, 0.9,
/// 0.95, 0.99} (inner).
std::vector<SslpvFitCase> sslpvFitCases();

/// The solver settings of the fit for an SH order: calibrated mode, sinks around the slab, run
/// until the flux left is < 10⁻⁴ of the injection (at most 4096 steps), the shipped weights
/// with both gains 1. @param order 1 or 2. @throw ValueError otherwise.
SslpvOptions sslpvFitOptions(int order);

/// The fit's thick slab as a coarse material: an N³ grid of `cellMm` cells from `origin`, the
/// slab filling cells [1, N−2]³ (sinks around it), σt = 1 mm⁻¹, σs′ = α′, g = 0, homogeneous.
/// @param gridCells N, [3, 1024]. @param cellMm cell size, mm, > 0. @param albedo α′, [0, 1].
/// @throw ValueError for out-of-range arguments.
CoarseMaterial sslpvThickSlab(int gridCells, float cellMm, float albedo, const Point3f& origin);

/// Thick slab on an N³ grid of cell size Δx = cellMfp mm, the slab filling cells [1, N−2]³
/// (sinks around it), σt = 1 mm⁻¹, σs′ = α′σt, g = 0, η. Unit-flux texels at normal incidence
/// on the central 8×8 cells of the top face (2×2 texels per cell).
/// @return the exitant radiance integrated over the top face per unit incident flux,
/// Σ_i L_o(x_i)·Δx² / Φ (sr⁻¹), at normal view without Fresnel T(ω_o) and without the gain of
/// `options.calibration` (raw 1/η² only): by superposition it equals L_o/E of a laterally
/// infinite slab under uniform irradiance E.
/// @param gridCells N, [16, 128]. @param eta relative index of refraction, [1, 3].
/// @param stats if not null, receives the solve's statistics (steps taken, energy bookkeeping).
/// @throw ValueError for out-of-range arguments.
double sslpvSlabResponse(const SslpvFitCase& fitCase, int gridCells, const SslpvOptions& options,
                         float eta, SslpvStats* stats = nullptr);

/// Total diffuse reflectance R_d of the classical dipole (Jensen et al. 2001) for σt = 1 mm⁻¹,
/// reduced albedo α′ and relative index η.
double sslpvSlabDipoleReflectance(float albedo, float eta);

/// The fit's target for sslpvSlabResponse(): Jensen et al. 2001's BSSRDF S_d = F_t R_d F_t/π
/// (Eq. 4 of the paper; Mertens et al. 2005, Table 1) integrated over the surface for uniform
/// normal irradiance gives L_o/E = F_t(0)·R_d·F_t(ω_o)/π; the response leaves out F_t(ω_o), so
/// the target is F_t(0)·R_d/π (sr⁻¹).
double sslpvSlabTarget(float albedo, float eta);

/// The per-step absorption weights that `SslpvCalibrationFitSettings::search` can fit.
enum class SslpvFitWeight { Linear, Transport, Diffusion };

/// Settings of fitSslpvCalibration() and solveSslpvBeta().
struct SslpvCalibrationFitSettings {
    int gridCells = 48;  ///< N of the slab grid, [16, 128]
    int order = 1;       ///< SH order, 1 or 2
    float eta = 1.3f;    ///< relative index of refraction, [1, 3]
    /// The per-step absorption weights (≥ 0); the gains are ignored (fitted). Default: the
    /// shipped constants.
    SslpvCalibration calibration = defaultSslpvCalibration();
    std::vector<SslpvFitCase> cases = sslpvFitCases();  ///< not empty
    /// fitSslpvCalibration(): fit this weight by golden-section search (log scale over
    /// [0.02, 5]) minimising the RMS log residual; the others stay as given.
    std::optional<SslpvFitWeight> search;
    int iterations = 12;  ///< golden-section iterations, [1, 100]
    /// Called after each objective evaluation of the search: the weight tried and its RMS log
    /// residual.
    std::function<void(double weight, double rmsLog)> onSearchStep;
};

/// One case of the fit's table.
struct SslpvFitRow {
    SslpvFitCase fitCase;
    double dipoleReflectance = 0.0;  ///< R_d of the classical dipole
    double target = 0.0;             ///< sslpvSlabTarget(), sr⁻¹
    double ratio = 0.0;              ///< response / target, before the gain
    double fitted = 0.0;             ///< G·response, sr⁻¹
    double residual = 0.0;           ///< G·response/target − 1
    int steps = 0;                   ///< propagation steps of the solve
};

/// Result of fitSslpvCalibration().
struct SslpvCalibrationFit {
    /// The weights used (the searched one replaced by the search's result) with the fitted
    /// gain in gain[order − 1].
    SslpvCalibration calibration;
    double gain = 1.0;       ///< G minimising Σ log²(G·response/target): the geometric mean
    double rmsLog = 0.0;     ///< RMS of log(G·response/target) over the cases
    double maxAbsRel = 0.0;  ///< max |G·response/target − 1|
    std::vector<SslpvFitRow> rows;  ///< one per case, in the settings' order
};

/// Evaluates (and with `search`, first fits one weight of) the calibrated mode on the thick
/// slabs of `settings.cases` and fits the radiance gain.
/// @throw ValueError for out-of-range settings.
SslpvCalibrationFit fitSslpvCalibration(const SslpvCalibrationFitSettings& settings);

/// One row of solveSslpvBeta().
struct SslpvBetaRow {
    SslpvFitCase fitCase;
    double beta = 0.0;               ///< β*: per-step absorption at which gain·response = target
    double betaPerAbsorption = 0.0;  ///< β*/(1 − α′)
    double transportCell = 0.0;      ///< σ_tr·Δx = √(3(1 − α′))·Δx
    int steps = 0;                   ///< propagation steps of the last bisection solve
};

/// Per case, the per-step absorption β* at which the SSLPV response times `gain` equals the
/// target: bisection in log β over [10⁻⁴, 20] (the response falls monotonically with β), β
/// imposed through the linear weight alone (linear = β/(σa·Δx), every other weight 0). The
/// table is what the calibration formula is fitted to. `settings.calibration`, `search` and
/// `onSearchStep` are not used.
/// @param gain radiance gain, [10⁻³, 10³]. @param iterations bisection steps, [1, 40].
/// @param onRow if set, called with each row as soon as it is known (the run takes minutes).
/// @throw ValueError for out-of-range arguments.
std::vector<SslpvBetaRow> solveSslpvBeta(
    const SslpvCalibrationFitSettings& settings, double gain, int iterations,
    const std::function<void(const SslpvBetaRow&)>& onRow = {});

}  // namespace lucent::sslpv
