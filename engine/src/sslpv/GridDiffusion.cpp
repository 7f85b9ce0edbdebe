// SPDX-License-Identifier: MIT
/// @file
/// @brief The diffusion approximation on the LPV grid (see GridDiffusion.h).

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/TableCache.h>
#include <lucent/core/Timer.h>
#include <lucent/dipole/HalfSpace.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/sslpv/GridDiffusion.h>

#include <shared/SslpvShared.h>

#include <algorithm>
#include <bit>
#include <cmath>

namespace lucent::sslpv {

namespace {

/// Unknowns per parallel block of the CG's vector passes; per-block partial sums keep the dot
/// products independent of the thread count (the result is bit-identical on 1 or 16 threads).
constexpr int64_t BLOCK = 4096;
/// Floor of σt′ (mm⁻¹): D = 1/(3σt′) stays finite in a painted vacuum.
constexpr float MIN_SIGMA_T = 1e-3f;

int64_t blockCount(size_t n) {
    return (int64_t(n) + BLOCK - 1) / BLOCK;
}

/// Where a plane source on the 1-D path from a cell's centre to the extrapolated boundary sends
/// its power, the part of φ it adds being 0 at both ends (GridDiffusion::solve): `fromBoundary`
/// and `fromCentre` its distances (mm) from the two ends, κ² = σa/D (mm⁻²). With φ″ = κ²φ away
/// from the source, each end receives sinh(κ·(the source's distance from the other end))/
/// sinh(κ·length) of it and the rest is absorbed in between; κ → 0 gives the linear shares.
/// The ratios are taken as e^(κ(x−L))(1 − e^(−2κx))/(1 − e^(−2κL)) so that no sinh overflows.
struct SegmentShares {
    float centre, boundary;
};
SegmentShares segmentShares(float fromBoundary, float fromCentre, float kappa2) {
    const double a = double(fromBoundary), b = double(fromCentre), len = a + b;
    const double k = std::sqrt(std::max(0.0, double(kappa2)));
    if (!(len > 0.0))
        return {1.f, 0.f};
    if (k * len < 1e-6)
        return {float(a / len), float(b / len)};
    const auto sinhRatio = [&](double x) {  // sinh(kx)/sinh(k·len), x ≤ len
        return x <= 0.0 ? 0.0
                        : std::exp(k * (x - len)) * std::expm1(-2.0 * k * x) /
                              std::expm1(-2.0 * k * len);
    };
    return {float(sinhRatio(a)), float(sinhRatio(b))};
}

}  // namespace

double diffuseFresnelReflectance(double eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta > 0.0 && eta <= 10.0,
                 "diffuse Fresnel reflectance: eta must be in (0, 10], got ", eta);
    // 2·C₁ of the light arriving at relative index η, i.e. leaving a medium of index 1/η
    // (dipole::fresnelMoment's convention; d'Eon 2012 Sec. 2): the same exact quadrature.
    return 2.0 * dipole::fresnelMoment(1, 1.0 / eta);
}

double diffusionBoundaryConstant(double eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "diffusion boundary constant: eta must be in [1, 3], got ", eta);
    const double fdr = diffuseFresnelReflectance(1.0 / eta);
    return (1.0 + fdr) / (1.0 - fdr);
}

double diffusionHalfSpaceReflectance(double albedo, double eta) {
    LUCENT_CHECK(std::isfinite(albedo) && albedo >= 0.0 && albedo <= 1.0,
                 "diffusion half-space reflectance: albedo must be in [0, 1], got ", albedo);
    // φ = C e^(−σtr z) + K e^(−z) with the Robin condition at z = 0; the removable singularity
    // of K at σtr = 1 cancels in φ(0)/(2A) (σt′ = 1, D = 1/3).
    const double A = diffusionBoundaryConstant(eta);
    const double str = std::sqrt(3.0 * (1.0 - albedo));
    return albedo / ((1.0 + str) * (1.0 + 2.0 * A * str / 3.0));
}

DiffusionSlabExitance diffusionSlabExitance(double albedo, double eta, double opticalThickness) {
    LUCENT_CHECK(std::isfinite(albedo) && albedo >= 0.0 && albedo <= 1.0,
                 "diffusion slab exitance: albedo must be in [0, 1], got ", albedo);
    LUCENT_CHECK(std::isfinite(opticalThickness) && opticalThickness >= 0.0,
                 "diffusion slab exitance: optical thickness must be finite and >= 0, got ",
                 opticalThickness);
    DiffusionSlabExitance out;
    if (albedo == 0.0 || opticalThickness == 0.0)
        return out;
    // φ = C₁e^(−κz) + C₂e^(−κ(τ−z)) + K e^(−z) (σt′ = 1, D = 1/3, κ = √(3σa)), K = α′/(σa − D),
    // with φ = 2AD φ′ at z = 0 and φ = −2AD φ′ at z = τ: two linear equations in C₁, C₂. At
    // σa = D (α′ = 2/3) K is singular; its removable singularity is stepped over by moving α′ by
    // 10⁻⁷ (J is smooth in α′, so the error is of that order).
    const double A = diffusionBoundaryConstant(eta), D = 1.0 / 3.0, tau = opticalThickness;
    double a = albedo;
    if (std::abs((1.0 - a) - D) < 1e-7)
        a -= 2e-7;
    const double sa = std::max(1.0 - a, 1e-12), kappa = std::sqrt(sa / D);
    const double K = a / (sa - D), ek = std::exp(-kappa * tau), e1 = std::exp(-tau);
    const double p = 1.0 + 2.0 * A * D * kappa, m = 1.0 - 2.0 * A * D * kappa;
    // [p, m·ek; m·ek, p] [C₁; C₂] = [−K(1 + 2AD); −K e^(−τ)(1 − 2AD)]
    const double r0 = -K * (1.0 + 2.0 * A * D), r1 = -K * e1 * (1.0 - 2.0 * A * D);
    const double det = p * p - m * m * ek * ek;
    const double c1 = (r0 * p - m * ek * r1) / det, c2 = (p * r1 - m * ek * r0) / det;
    out.reflectance = (c1 + c2 * ek + K) / (2.0 * A);
    out.transmittance = (c1 * ek + c2 + K * e1) / (2.0 * A);
    return out;
}

double surfaceFluxExitLean(double albedo, double eta) {
    LUCENT_CHECK(std::isfinite(albedo) && albedo >= 0.0 && albedo <= 1.0,
                 "surface flux exit lean: albedo must be in [0, 1], got ", albedo);
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "surface flux exit lean: eta must be in [1, 3], got ", eta);
    const double A = diffusionBoundaryConstant(eta);
    const std::shared_ptr<const dipole::DirpoleExitTable> table =
        dipole::DirpoleExitTable::shared(eta);
    // Midpoint rule in t: the integrands are smooth but for T(t)'s kink at the critical angle
    // seen from inside, which t never reaches (light from outside always enters).
    constexpr int NODES = 2048;
    double lean = 0.0, flux = 0.0;
    for (int i = 0; i < NODES; ++i) {
        const double t = (i + 0.5) / NODES, sin2 = 1.0 - t * t;
        const double shape =
            (1.0 - double(fresnelDielectric(float(t), float(eta)))) * table->correction(albedo, t);
        const double mu = std::sqrt(std::max(0.0, 1.0 - sin2 / (eta * eta)));
        lean += t * shape * sin2 / (2.0 * A + 3.0 * mu);
        flux += t * shape;
    }
    return flux > 0.0 ? 1.5 / eta * lean / flux : 0.0;
}

static_assert(ExactReflectanceRatio::NODES == LUCENT_SSLPV_EXACT_TOTAL_NODES,
              "combined_add.comp reads the exact totals with the shared node count");

ExactReflectanceRatio::ExactReflectanceRatio(double eta) : m_eta(eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "exact reflectance ratio: eta must be in [1, 3], got ", eta);
    m_ratio.resize(NODES + 1);
    m_total.resize(NODES + 1);
    for (int i = 0; i <= NODES; ++i) {
        const double u = double(i) / NODES, albedo = 1.0 - u * u;
        const double model = diffusionHalfSpaceReflectance(albedo, eta);
        const double exact = dipole::halfSpaceReflectance(albedo, eta, 1.0);
        m_ratio[size_t(i)] = model > 1e-9 ? float(exact / model) : 1.f;
        m_total[size_t(i)] = float(exact);
    }
    // α′ = 0: both vanish; take the limit from the first node inside.
    m_ratio[NODES] = m_ratio[NODES - 1];
}

std::shared_ptr<const ExactReflectanceRatio> exactReflectanceRatio(double eta) {
    return sharedTable<ExactReflectanceRatio>(eta, [&] { return ExactReflectanceRatio(eta); });
}

ExactSlabRatio::ExactSlabRatio(double eta) : m_eta(eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "exact slab ratio: eta must be in [1, 3], got ", eta);
    constexpr int NA = ALBEDO_NODES + 1, NT = THICKNESS_NODES + 1;
    m_ratio.assign(size_t(NA * NT), 1.f);
    const double logSpan = std::log(double(MAX_THICKNESS) / double(MIN_THICKNESS));
    parallelFor(
        0, NA * NT,
        [&](int64_t begin, int64_t end) {
            for (int64_t index = begin; index < end; ++index) {
                const int i = int(index / NT), j = int(index % NT);
                const double u = double(i) / ALBEDO_NODES, albedo = 1.0 - u * u;
                const double tau = double(MIN_THICKNESS) * std::exp(logSpan * j / THICKNESS_NODES);
                const dipole::SlabExitance exact = dipole::slabExitance(albedo, eta, tau);
                const DiffusionSlabExitance model = diffusionSlabExitance(albedo, eta, tau);
                const double m = model.reflectance + model.transmittance;
                if (m > 1e-9)
                    m_ratio[size_t(index)] = float((exact.reflectance + exact.transmittance) / m);
            }
        },
        1);
    // α′ = 0: both vanish; take the limit from the last node inside.
    for (int j = 0; j < NT; ++j)
        m_ratio[size_t(ALBEDO_NODES * NT + j)] = m_ratio[size_t((ALBEDO_NODES - 1) * NT + j)];
}

float ExactSlabRatio::operator()(float albedo, float opticalThickness) const {
    constexpr int NT = THICKNESS_NODES + 1;
    const float u = std::sqrt(1.f - std::clamp(albedo, 0.f, 1.f)) * float(ALBEDO_NODES);
    const float tau = std::isnan(opticalThickness)
                          ? MAX_THICKNESS
                          : std::clamp(opticalThickness, MIN_THICKNESS, MAX_THICKNESS);
    const float v = std::log(tau / MIN_THICKNESS) / std::log(MAX_THICKNESS / MIN_THICKNESS) *
                    float(THICKNESS_NODES);
    const int i = std::min(int(u), ALBEDO_NODES - 1), j = std::min(int(v), THICKNESS_NODES - 1);
    const float fu = u - float(i), fv = v - float(j);
    const auto at = [&](int a, int t) { return m_ratio[size_t(a * NT + t)]; };
    return (1.f - fu) * ((1.f - fv) * at(i, j) + fv * at(i, j + 1)) +
           fu * ((1.f - fv) * at(i + 1, j) + fv * at(i + 1, j + 1));
}

std::shared_ptr<const ExactSlabRatio> exactSlabRatio(double eta) {
    return sharedTable<ExactSlabRatio>(eta, [&] { return ExactSlabRatio(eta); });
}

namespace {

/// Linear interpolation of a table at u_i = i/(size − 1) in u = √(1 − α′).
float interpolateInU(const std::vector<float>& table, float albedo) {
    const float u = std::sqrt(1.f - std::clamp(albedo, 0.f, 1.f)) * float(table.size() - 1);
    const size_t i = std::min(size_t(u), table.size() - 2);
    const float f = u - float(i);
    return (1.f - f) * table[i] + f * table[i + 1];
}

}  // namespace

float ExactReflectanceRatio::operator()(float albedo) const {
    return interpolateInU(m_ratio, albedo);
}

float ExactReflectanceRatio::exactTotal(float albedo) const {
    return interpolateInU(m_total, albedo);
}

void GridDiffusion::setMaterial(const CoarseMaterial& m, float eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.f && eta <= 3.f,
                 "grid diffusion: eta must be in [1, 3], got ", eta);
    const GridSpec& s = m.spec;
    LUCENT_CHECK(s.resolution >= 1 && std::isfinite(s.voxelSize) && s.voxelSize > 0.f,
                 "grid diffusion: invalid grid (resolution ", s.resolution, ", voxel size ",
                 s.voxelSize, " mm)");
    const size_t count = s.voxelCount();
    LUCENT_CHECK(m.insideFraction.size() == count, "grid diffusion: insideFraction has ",
                 m.insideFraction.size(), " values, expected ", count);
    for (int c = 0; c < 3; ++c)
        LUCENT_CHECK(m.sigma_t[c].size() == count && m.sigma_s[c].size() == count,
                     "grid diffusion: sigma_t/sigma_s of channel ", c, " have ",
                     m.sigma_t[c].size(), "/", m.sigma_s[c].size(), " values, expected ", count);

    const int n = s.resolution;
    const float dx = s.voxelSize;
    auto inside = [&](int x, int y, int z) {
        return x >= 0 && y >= 0 && z >= 0 && x < n && y < n && z < n &&
               m.insideFraction[s.linearIndex({x, y, z})] >= 0.5f;
    };

    // Unknowns: the medium cells in spec order.
    std::vector<int32_t> compact(count, -1);
    std::vector<uint32_t> cells;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                if (inside(x, y, z)) {
                    const size_t k = s.linearIndex({x, y, z});
                    compact[k] = int32_t(cells.size());
                    cells.push_back(uint32_t(k));
                }
    const bool sameMedium = m_hasMaterial && s == m_spec && compact == m_compact;
    const size_t unknowns = cells.size();
    const uint32_t sentinel = uint32_t(unknowns);

    m_boundaryA = diffusionBoundaryConstant(eta);
    const float twoA = float(2.0 * m_boundaryA);
    for (int c = 0; c < 3; ++c) {
        m_sigmaA[c].resize(unknowns);
        m_diffusivity[c].resize(unknowns);
        for (size_t u = 0; u < unknowns; ++u) {
            const size_t k = cells[u];
            const float st = m.sigma_t[c][k], ss = m.sigma_s[c][k];
            LUCENT_CHECK(std::isfinite(st) && st >= 0.f && std::isfinite(ss) && ss >= 0.f,
                         "grid diffusion: cell ", k, " channel ", c, " has sigma_t=", st,
                         " sigma_s=", ss, " (need finite values >= 0 mm^-1)");
            const float stc = std::max(st, MIN_SIGMA_T);
            // σa times the cell's medium fraction: a partial cell at the surface holds only
            // that much medium (its control volume ends at the surface, see δ below).
            m_sigmaA[c][u] = std::max(0.f, st - ss) * std::clamp(m.insideFraction[k], 0.5f, 1.f);
            m_diffusivity[c][u] = 1.f / (3.f * stc);
        }
    }

    const int dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int f = 0; f < 6; ++f)
        m_neighbour[f].assign(unknowns, sentinel);
    for (int c = 0; c < 3; ++c) {
        for (int f = 0; f < 6; ++f)
            m_conductance[c][f].assign(unknowns, 0.f);
        m_diagonal[c].assign(unknowns, 0.f);
        m_boundaryConductance[c].assign(unknowns, 0.f);
    }
    auto fraction = [&](int x, int y, int z) {
        if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n)
            return 0.f;
        return m.insideFraction[s.linearIndex({x, y, z})];
    };
    // Depth of each boundary cell's centre under the surface (mm): the mean of its boundary
    // faces' δ; exitance() extrapolates φ over it. (Interior cells are not read out: φ peaks
    // under the surface where the source does, so a linear extrapolation from a cell 1.5Δx deep
    // overestimated J by up to 25 % in the lit half-space test.)
    m_depth.assign(unknowns, 0.5f * dx);
    m_normal.assign(unknowns, Vector3f(0.f));
    std::vector<float> depthSum(unknowns, 0.f);
    m_boundaryArea.assign(unknowns, 0.f);
    m_boundaryFaces.assign(unknowns, 0);
    for (size_t u = 0; u < unknowns; ++u) {
        const size_t k = cells[u];
        const int x = int(k % size_t(n)), y = int((k / size_t(n)) % size_t(n)),
                  z = int(k / (size_t(n) * size_t(n)));
        // Staircase area correction: 1/|n|₁ for the local normal (the inside fraction's
        // gradient); 1 where the gradient vanishes (a shell thinner than the stencil).
        const float gx = fraction(x + 1, y, z) - fraction(x - 1, y, z);
        const float gy = fraction(x, y + 1, z) - fraction(x, y - 1, z);
        const float gz = fraction(x, y, z + 1) - fraction(x, y, z - 1);
        const float glen = std::sqrt(gx * gx + gy * gy + gz * gz);
        const float areaScale =
            glen > 1e-3f ? glen / (std::abs(gx) + std::abs(gy) + std::abs(gz)) : 1.f;
        if (glen > 1e-3f)
            m_normal[u] = Vector3f(-gx, -gy, -gz) / glen;
        // The distance from the centre to the surface along its normal n, for every boundary face
        // of the cell: along n's dominant axis a the surface lies (f_i − ½ + f_j)Δx from the
        // centre, j the neighbour across it (exact for a plane that crosses the two cells' edges
        // parallel to a: a prism's volume is its height at the centroid), so along n it lies
        // |n_a| times that. The staircase's faces across the other axes (its steps) take the same
        // δ: the light leaves through the surface, not through the step's own face. Where the
        // gradient vanishes (a shell thinner than the stencil) each face keeps its own axis's.
        float normalDelta = 0.f;
        if (glen > 1e-3f) {
            const Vector3f& nrm = m_normal[u];
            const int a = std::abs(nrm.x) >= std::abs(nrm.y)
                              ? (std::abs(nrm.x) >= std::abs(nrm.z) ? 0 : 2)
                              : (std::abs(nrm.y) >= std::abs(nrm.z) ? 1 : 2);
            Coord across(x, y, z);
            across[a] += nrm[a] > 0.f ? 1 : -1;
            const float along = std::clamp(
                fraction(x, y, z) - 0.5f + fraction(across.x, across.y, across.z), 0.05f, 1.5f);
            normalDelta = std::max(along * std::abs(nrm[a]), 0.05f) * dx;
        }
        for (int f = 0; f < 6; ++f) {
            const int nx = x + dirs[f][0], ny = y + dirs[f][1], nz = z + dirs[f][2];
            const bool interior = inside(nx, ny, nz);
            if (interior)
                m_neighbour[f][u] = uint32_t(compact[s.linearIndex({nx, ny, nz})]);
            for (int c = 0; c < 3; ++c) {
                const float di = m_diffusivity[c][u];
                float g;
                if (interior) {
                    const float dj = m_diffusivity[c][m_neighbour[f][u]];
                    g = dx * (2.f * di * dj / (di + dj));  // Δx² · D_face / Δx
                    m_conductance[c][f][u] = g;
                } else {
                    // Robin: J = φ_b/(2A) and J = D (φ − φ_b)/δ → J = φ/(2A + δ/D), δ the
                    // distance from the centre to the surface (normalDelta above). Without a
                    // normal, along the face's axis: the inside length in this cell beyond its
                    // centre, (f_i − ½)Δx, plus the neighbour's, f_j Δx (½Δx, the cell face,
                    // when f_i = 1 and f_j = 0).
                    const float delta =
                        normalDelta > 0.f
                            ? normalDelta
                            : std::clamp(fraction(x, y, z) - 0.5f + fraction(nx, ny, nz), 0.05f,
                                         1.5f) *
                                  dx;
                    g = areaScale * dx * dx / (twoA + delta / di);
                    m_boundaryConductance[c][u] += g;
                    if (c == 0) {
                        depthSum[u] += delta;
                        m_boundaryArea[u] += areaScale * dx * dx;
                        m_boundaryFaces[u] |= uint8_t(1u << f);
                    }
                }
                m_diagonal[c][u] += g;
            }
        }
        for (int c = 0; c < 3; ++c)
            m_diagonal[c][u] += m_sigmaA[c][u] * dx * dx * dx;
    }
    m_boundary.assign(count, 0);
    for (size_t u = 0; u < unknowns; ++u)
        if (m_boundaryFaces[u] != 0) {
            m_depth[u] = depthSum[u] / float(std::popcount(m_boundaryFaces[u]));
            m_boundary[cells[u]] = 1;
        }

    for (auto& direct : m_directExitance)
        direct.clear();  // the next solve's
    if (!sameMedium || m_fraction != m.insideFraction) {
        m_fraction = m.insideFraction;
        m_chord.clear();  // chordLength() marches again
    }
    m_phiValid = m_phiValid && sameMedium;
    if (!m_phiValid)
        for (int c = 0; c < 3; ++c)
            m_phi[c].assign(unknowns + 1, 0.f);
    m_spec = s;
    m_eta = eta;
    m_compact = std::move(compact);
    m_cells = std::move(cells);
    m_hasMaterial = true;
}

const GridDiffusionStats& GridDiffusion::solve(const std::array<std::vector<float>, 3>& source,
                                               const GridDiffusionOptions& o) {
    return solve(GridDiffusionSource{source, {}, {}}, o);
}

const GridDiffusionStats& GridDiffusion::solve(const GridDiffusionSource& source,
                                               const GridDiffusionOptions& o) {
    LUCENT_CHECK(m_hasMaterial, "grid diffusion: solve() before setMaterial()");
    LUCENT_CHECK(o.maxIterations >= 0 && o.maxIterations <= 1000000,
                 "grid diffusion: maxIterations must be in [0, 1000000], got ", o.maxIterations);
    LUCENT_CHECK(std::isfinite(o.tolerance) && o.tolerance >= 0.0 && o.tolerance <= 1.0,
                 "grid diffusion: tolerance must be in [0, 1], got ", o.tolerance);
    const size_t count = m_spec.voxelCount();
    for (int c = 0; c < 3; ++c) {
        LUCENT_CHECK(source.power[c].size() == count, "grid diffusion: source of channel ", c,
                     " has ", source.power[c].size(), " values, expected ", count);
        const bool noEntry = source.entry[c].empty() && source.entryDepth[c].empty();
        LUCENT_CHECK(
            noEntry || (source.entry[c].size() == count && source.entryDepth[c].size() == count),
            "grid diffusion: entry source of channel ", c, " has ", source.entry[c].size(),
            " values and depths ", source.entryDepth[c].size(), ", expected none or ", count);
    }
    const Timer timer;
    const size_t nu = m_cells.size();
    const int64_t blocks = blockCount(nu);
    m_stats = {};
    m_stats.cells = nu;
    m_stats.warmStart = m_phiValid;
    const float dx3 = m_spec.voxelSize * m_spec.voxelSize * m_spec.voxelSize;

    std::vector<float> b(nu), r(nu), z(nu), p(nu + 1, 0.f), ap(nu);
    std::vector<double> partA(static_cast<size_t>(blocks)), partB(static_cast<size_t>(blocks));
    for (int c = 0; c < 3; ++c) {
        const float* __restrict diag = m_diagonal[c].data();
        const float* cond[6];
        const uint32_t* nbr[6];
        for (int f = 0; f < 6; ++f) {
            cond[f] = m_conductance[c][f].data();
            nbr[f] = m_neighbour[f].data();
        }
        float* __restrict x = m_phi[c].data();
        // A·v for v with a zero sentinel at index nu; per-block partial sums of w·(A·v).
        auto applyA = [&](const float* v, float* out, const float* dotWith) {
            parallelFor(0, blocks, [&](int64_t b0, int64_t b1) {
                for (int64_t bl = b0; bl < b1; ++bl) {
                    const int64_t i0 = bl * BLOCK, i1 = std::min<int64_t>(i0 + BLOCK, int64_t(nu));
                    double dot = 0.0;
                    for (int64_t i = i0; i < i1; ++i) {
                        float s = diag[i] * v[i];
                        for (int f = 0; f < 6; ++f)
                            s -= cond[f][i] * v[nbr[f][i]];
                        out[i] = s;
                        dot += double(dotWith[i]) * double(s);
                    }
                    partA[size_t(bl)] = dot;
                }
            });
            double sum = 0.0;
            for (double d : partA)
                sum += d;
            return sum;
        };

        double sourceSum = 0.0, directSum = 0.0, segmentAbsorbed = 0.0;
        const bool withEntry = !source.entry[c].empty();
        if (withEntry)
            m_directExitance[c].assign(nu, 0.f);
        else
            m_directExitance[c].clear();  // exitance() reads none
        const float twoA = float(2.0 * m_boundaryA);
        for (size_t u = 0; u < nu; ++u) {
            const float q = source.power[c][m_cells[u]];
            LUCENT_CHECK(std::isfinite(q) && q >= 0.f, "grid diffusion: source at cell ",
                         m_cells[u], " channel ", c, " is ", q, " (need finite, >= 0 W)");
            b[u] = q;
            sourceSum += q;
            if (!withEntry || m_boundaryFaces[u] == 0)
                continue;
            const float entry = source.entry[c][m_cells[u]],
                        moment = source.entryDepth[c][m_cells[u]];
            LUCENT_CHECK(
                std::isfinite(entry) && entry >= 0.f && std::isfinite(moment) && moment >= 0.f,
                "grid diffusion: entry source at cell ", m_cells[u], " channel ", c, " is ", entry,
                " W at ", moment, " W·mm (need finite, >= 0)");
            // Faces on both sides of an axis: a layer one cell thick (see solve's comment).
            const uint8_t faces = m_boundaryFaces[u];
            const bool opposed = (faces & 3u) == 3u || (faces & 12u) == 12u || (faces & 48u) == 48u;
            if (opposed || !(entry > 0.f))
                continue;
            // The source's place on the path from the centre to the extrapolated boundary
            // (solve's comment): the shares that reach the centre and the boundary, the rest
            // absorbed on the way.
            const float reach = twoA * m_diffusivity[c][u];
            const float depth = std::min(moment / entry, m_depth[u]);
            const SegmentShares shares = segmentShares(depth + reach, m_depth[u] - depth,
                                                       m_sigmaA[c][u] / m_diffusivity[c][u]);
            const float placed = std::min(entry, q);
            const float direct = placed * shares.boundary;
            const float absorbedOnTheWay = placed * (1.f - shares.boundary - shares.centre);
            b[u] = q - direct - absorbedOnTheWay;
            m_directExitance[c][u] = direct / m_boundaryArea[u];
            directSum += direct;
            segmentAbsorbed += absorbedOnTheWay;
        }
        m_stats.source[c] = sourceSum;
        m_stats.directExit[c] = directSum;
        if (nu == 0)
            continue;
        if (!(sourceSum - directSum - segmentAbsorbed > 0.0)) {
            std::fill(m_phi[c].begin(), m_phi[c].end(), 0.f);
            m_stats.exitant[size_t(c)] = directSum;
            m_stats.absorbed[size_t(c)] = segmentAbsorbed;
            continue;
        }
        // Conjugate gradients with residual replacement: the recurrence r ← r − αAp drifts from
        // the true b − Ax in float arithmetic, so each round starts from the true residual and
        // the solve ends only when the true residual meets the target (or iterations run out).
        const double target = o.tolerance * sourceSum;
        x[nu] = 0.f;
        int it = 0;
        double rAbs = 0.0;
        for (int round = 0; round < 8; ++round) {
            applyA(x, ap.data(), x);  // A x (x: the warm start, 0, or the last round's answer)
            double rz = 0.0;
            rAbs = 0.0;
            for (size_t u = 0; u < nu; ++u) {
                r[u] = b[u] - ap[u];
                z[u] = r[u] / diag[u];
                p[u] = z[u];
                rz += double(r[u]) * double(z[u]);
                rAbs += std::abs(double(r[u]));
            }
            p[nu] = 0.f;
            if (it >= o.maxIterations || rAbs <= target || !(rz > 0.0))
                break;
            // Within a round aim a little below the target so the true residual meets it.
            while (it < o.maxIterations && rAbs > 0.5 * target && rz > 0.0) {
                const double pAp = applyA(p.data(), ap.data(), p.data());
                if (!(pAp > 0.0))
                    break;
                const float alpha = float(rz / pAp);
                parallelFor(0, blocks, [&](int64_t b0, int64_t b1) {
                    for (int64_t bl = b0; bl < b1; ++bl) {
                        const int64_t i0 = bl * BLOCK,
                                      i1 = std::min<int64_t>(i0 + BLOCK, int64_t(nu));
                        double rzPart = 0.0, absPart = 0.0;
                        for (int64_t i = i0; i < i1; ++i) {
                            x[i] += alpha * p[i];
                            r[i] -= alpha * ap[i];
                            z[i] = r[i] / diag[i];
                            rzPart += double(r[i]) * double(z[i]);
                            absPart += std::abs(double(r[i]));
                        }
                        partA[size_t(bl)] = rzPart;
                        partB[size_t(bl)] = absPart;
                    }
                });
                double rzNew = 0.0;
                rAbs = 0.0;
                for (int64_t bl = 0; bl < blocks; ++bl) {
                    rzNew += partA[size_t(bl)];
                    rAbs += partB[size_t(bl)];
                }
                const float beta = float(rzNew / rz);
                rz = rzNew;
                for (size_t u = 0; u < nu; ++u)
                    p[u] = z[u] + beta * p[u];
                ++it;
            }
        }
        // Negative φ can only come from an unconverged iterate; it has no physical meaning.
        for (size_t u = 0; u < nu; ++u)
            x[u] = std::max(0.f, x[u]);
        m_stats.iterations[size_t(c)] = it;
        m_stats.residual[size_t(c)] = rAbs / sourceSum;
        double absorbed = segmentAbsorbed, exitant = directSum;
        for (size_t u = 0; u < nu; ++u) {
            absorbed += double(m_sigmaA[c][u]) * dx3 * double(x[u]);
            exitant += double(m_boundaryConductance[c][u]) * double(x[u]);
        }
        m_stats.absorbed[size_t(c)] = absorbed;
        m_stats.exitant[size_t(c)] = exitant;
    }
    m_phiValid = true;
    m_stats.ms = timer.elapsedMs();
    return m_stats;
}

float GridDiffusion::fluence(size_t cell, int channel) const {
    if (!isMedium(cell) || channel < 0 || channel > 2)
        return 0.f;
    return m_phi[size_t(channel)][size_t(m_compact[cell])];
}

float GridDiffusion::exitance(size_t cell, int channel) const {
    if (!isMedium(cell) || channel < 0 || channel > 2)
        return 0.f;
    const size_t u = size_t(m_compact[cell]);
    const float d = m_diffusivity[size_t(channel)][u];
    const std::vector<float>& direct = m_directExitance[size_t(channel)];
    return m_phi[size_t(channel)][u] * d / (float(2.0 * m_boundaryA) * d + m_depth[u]) +
           (u < direct.size() ? direct[u] : 0.f);
}

std::array<Vector3f, 3> GridDiffusion::surfaceFlux(size_t cell) const {
    std::array<Vector3f, 3> flux{Vector3f(0.f), Vector3f(0.f), Vector3f(0.f)};
    if (!isBoundary(cell))
        return flux;
    const size_t u = size_t(m_compact[cell]);
    const Vector3f n = m_normal[u];
    if (n == Vector3f(0.f))
        return flux;
    // Tangent basis of the surface; the exitance's gradient in it by weighted least squares
    // over the neighbouring boundary cells (their exitance is already the surface's: each is
    // φ extrapolated over its own depth δ̄), weights 1/|d|² so the face neighbours lead. The
    // normal matrix is the same for the three channels; only the right-hand sides differ.
    const Vector3f t1 = glm::normalize(std::abs(n.x) < 0.9f ? glm::cross(n, Vector3f(1, 0, 0))
                                                            : glm::cross(n, Vector3f(0, 1, 0)));
    const Vector3f t2 = glm::cross(n, t1);
    const int res = m_spec.resolution;
    const Coord c(int(cell % size_t(res)), int((cell / size_t(res)) % size_t(res)),
                  int(cell / (size_t(res) * size_t(res))));
    double j0[3], b1[3] = {}, b2[3] = {};
    for (int ch = 0; ch < 3; ++ch)
        j0[ch] = exitance(cell, ch);
    double a11 = 0.0, a12 = 0.0, a22 = 0.0;
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const Coord q = c + Coord(dx, dy, dz);
                if (q == c || !m_spec.contains(q))
                    continue;
                const size_t k = m_spec.linearIndex(q);
                if (!isBoundary(k))
                    continue;
                const Vector3f d = m_spec.voxelSize * Vector3f(float(dx), float(dy), float(dz));
                const double u1 = glm::dot(d, t1), u2 = glm::dot(d, t2);
                const double w = 1.0 / double(glm::dot(d, d));
                a11 += w * u1 * u1;
                a12 += w * u1 * u2;
                a22 += w * u2 * u2;
                for (int ch = 0; ch < 3; ++ch) {
                    const double dj = double(exitance(k, ch)) - j0[ch];
                    b1[ch] += w * u1 * dj;
                    b2[ch] += w * u2 * dj;
                }
            }
    const double det = a11 * a22 - a12 * a12;
    if (!(det > 1e-6 * (a11 + a22) * (a11 + a22)))
        return flux;
    for (int ch = 0; ch < 3; ++ch) {
        const double g1 = (a22 * b1[ch] - a12 * b2[ch]) / det,
                     g2 = (a11 * b2[ch] - a12 * b1[ch]) / det;
        const float scale = -float(2.0 * m_boundaryA) * m_diffusivity[size_t(ch)][u];
        flux[size_t(ch)] = scale * (float(g1) * t1 + float(g2) * t2);
    }
    return flux;
}

float GridDiffusion::chordLength(size_t cell) const {
    if (!isBoundary(cell))
        return 0.f;
    const int n = m_spec.resolution;
    const float dx = m_spec.voxelSize;
    if (m_chord.empty()) {
        const auto fraction = [&](int x, int y, int z) {
            if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n)
                return 0.f;
            return m_fraction[m_spec.linearIndex({x, y, z})];
        };
        const auto trilinear = [&](const Vector3f& p) {
            const int x = int(std::floor(p.x)), y = int(std::floor(p.y)), z = int(std::floor(p.z));
            const float fx = p.x - float(x), fy = p.y - float(y), fz = p.z - float(z);
            float f = 0.f;
            for (int c = 0; c < 8; ++c) {
                const int ox = c & 1, oy = (c >> 1) & 1, oz = (c >> 2) & 1;
                f += (ox ? fx : 1.f - fx) * (oy ? fy : 1.f - fy) * (oz ? fz : 1.f - fz) *
                     fraction(x + ox, y + oy, z + oz);
            }
            return f;
        };
        m_chord.assign(m_cells.size(), 0.f);
        constexpr float STEP = 0.5f;  // cells
        const float longest = std::sqrt(3.f) * float(n) + 1.f;
        parallelFor(0, int64_t(m_cells.size()), [&](int64_t begin, int64_t end) {
            for (int64_t index = begin; index < end; ++index) {
                const size_t u = size_t(index), k = m_cells[u];
                if (m_boundaryFaces[u] == 0)
                    continue;
                const Vector3f centre(float(k % size_t(n)), float((k / size_t(n)) % size_t(n)),
                                      float(k / (size_t(n) * size_t(n))));
                const Vector3f& nrm = m_normal[u];
                if (nrm == Vector3f(0.f)) {
                    m_chord[u] = std::max(m_fraction[k], 0.5f) * dx;
                    continue;
                }
                float before = std::max(m_fraction[k], 0.5f), d = 0.f, crossing = longest;
                while (d < longest) {
                    d += STEP;
                    const float f = trilinear(centre - d * nrm);
                    if (f < 0.5f) {
                        crossing = d - STEP * (1.f - (before - 0.5f) / std::max(before - f, 1e-6f));
                        break;
                    }
                    before = f;
                }
                m_chord[u] = m_depth[u] + crossing * dx;
            }
        });
    }
    return m_chord[size_t(m_compact[cell])];
}

}  // namespace lucent::sslpv
