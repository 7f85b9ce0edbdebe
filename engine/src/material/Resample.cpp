// SPDX-License-Identifier: MIT
/// @file
/// @brief Transmittance-preserving resampling to a coarse grid (Resample.h, docs/material.md),
/// full and incremental (dirty bricks). Both paths evaluate every coarse cell with the same
/// function, reading the brick storage directly, so they agree bit for bit.
#include <lucent/material/Resample.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/material/BoundarySkin.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace lucent {

namespace {

struct Overlap {
    int fine;       ///< fine voxel index along the axis
    double length;  ///< overlap with the coarse cell, in fine voxels (0, 1]
};

/// ln((Σ w_i e^{−τ_i}) / Σ w_i), evaluated with the smallest τ factored out so that optically
/// thick cells do not underflow to ln 0. Terms with τ_i = τ_min use e^{−0} = 1 exactly without
/// calling exp (identical result, and the common case in homogeneous regions).
double logMeanTransmittance(const double* tau, const double* w, size_t count) {
    double tmin = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < count; ++i)
        tmin = std::min(tmin, tau[i]);
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < count; ++i) {
        const double d = tau[i] - tmin;
        num += w[i] * (d == 0.0 ? 1.0 : std::exp(-d));
        den += w[i];
    }
    return -tmin + std::log(num / den);
}

/// A sample's nine values in the bricks' component order (MaterialVolume::component).
void componentsOf(const MaterialSample& s, float (&out)[MaterialVolume::COMPONENTS]) {
    for (int c = 0; c < 3; ++c) {
        out[MaterialVolume::component(Channel::SigmaT, c)] = s.sigma_t[c];
        out[MaterialVolume::component(Channel::SigmaS, c)] = s.sigma_s[c];
        out[MaterialVolume::component(Channel::G, c)] = s.g[c];
    }
}

/// Per-thread buffers of CellEvaluator::evaluate.
struct Scratch {
    std::vector<double> tau, w;
    std::vector<float> window;  ///< masked σt of the cell's fine window, 3 channels
};

/// Everything the per-cell evaluation needs: overlap lists and brick-address tables.
class CellEvaluator {
public:
    /// Largest fine window (voxels) copied to Scratch::window; larger ones read the bricks.
    static constexpr size_t MAX_WINDOW = size_t(1) << 15;

    CellEvaluator(const MaterialVolume& volume, int resolution) : m_n(volume.resolution()) {
        const int n = m_n;
        m_ratio = double(n) / double(resolution);
        m_h = volume.spec().voxelSize;
        m_H = m_ratio * m_h;  // coarse cell edge, mm
        m_cellVolume = m_ratio * m_ratio * m_ratio;
        // 1-D overlaps of fine voxels [i, i+1) with coarse cells [I·r, (I+1)·r), r = n/res.
        m_lists.resize(size_t(resolution));
        m_coarseLo.assign(size_t(n), resolution);
        m_coarseHi.assign(size_t(n), -1);
        for (int I = 0; I < resolution; ++I) {
            const double a = I * m_ratio, b = (I + 1) * m_ratio;
            for (int i = int(std::floor(a)); i < n && double(i) < b; ++i) {
                const double len = std::min(double(i + 1), b) - std::max(double(i), a);
                if (len > 1e-12) {
                    m_lists[size_t(I)].push_back({i, len});
                    m_coarseLo[size_t(i)] = std::min(m_coarseLo[size_t(i)], I);
                    m_coarseHi[size_t(i)] = std::max(m_coarseHi[size_t(i)], I);
                }
            }
        }
        // Brick addressing, SoA per brick (MaterialVolume.h): a voxel's component `comp` lives
        // at brickBase + comp·BRICK_VOXELS + voxelInBrick; split per axis so that the address
        // of (x,y,z) is ax[x] + ay[y] + az[z].
        const int B = MaterialVolume::BRICK;
        const size_t brickFloats =
            size_t(MaterialVolume::BRICK_VOXELS) * MaterialVolume::COMPONENTS;
        const size_t bpa = size_t(volume.bricksPerAxis());
        m_addr[0].resize(size_t(n));
        m_addr[1].resize(size_t(n));
        m_addr[2].resize(size_t(n));
        for (int i = 0; i < n; ++i) {
            const size_t bi = size_t(i / B), li = size_t(i % B);
            m_addr[0][size_t(i)] = bi * brickFloats + li;
            m_addr[1][size_t(i)] = bi * bpa * brickFloats + li * B;
            m_addr[2][size_t(i)] = bi * bpa * bpa * brickFloats + li * B * B;
        }
        m_data = volume.brickData(0);
        m_inside = volume.insideMask().data();
        m_volume = &volume;
        m_nearInside = bricksNearInside(volume);
    }

    /// The boundary skin's value at masked-out voxel (x,y,z) (BoundarySkin.h), if it has one:
    /// the material continues into the voxels the mesh only partly fills, as the reference's
    /// medium does (GridMedium::fromMaterial), and the renderers bound it by the mesh.
    [[nodiscard]] std::optional<MaterialSample> skin(int x, int y, int z) const {
        const Coord c(x, y, z);
        if (!m_nearInside[size_t(m_volume->brickIndexOf(c))] || !hasInsideNeighbour(x, y, z))
            return std::nullopt;
        return skinValue(*m_volume, c);
    }

    /// Whether a voxel of the 3³ block around (x,y,z) is inside: the cheap test most masked-out
    /// voxels near an object fail, before skinValue's own.
    [[nodiscard]] bool hasInsideNeighbour(int x, int y, int z) const {
        const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, m_n - 1);
        const int y0 = std::max(y - 1, 0), y1 = std::min(y + 1, m_n - 1);
        const int z0 = std::max(z - 1, 0), z1 = std::min(z + 1, m_n - 1);
        for (int zz = z0; zz <= z1; ++zz)
            for (int yy = y0; yy <= y1; ++yy) {
                const uint8_t* row = m_inside + (size_t(zz) * m_n + size_t(yy)) * m_n;
                for (int xx = x0; xx <= x1; ++xx)
                    if (row[xx])
                        return true;
            }
        return false;
    }

    /// Whether brick b holds an inside voxel and a masked-out voxel lies in it or next to it:
    /// only then can a stroke in it change a skin value (BoundarySkin.h), which may sit one voxel
    /// outside the brick.
    [[nodiscard]] bool brickTouchesSkin(const Coord& o) const {
        const int B = MaterialVolume::BRICK;
        bool inside = false, outside = false;
        for (int z = std::max(o.z - 1, 0); z <= std::min(o.z + B, m_n - 1); ++z)
            for (int y = std::max(o.y - 1, 0); y <= std::min(o.y + B, m_n - 1); ++y)
                for (int x = std::max(o.x - 1, 0); x <= std::min(o.x + B, m_n - 1); ++x) {
                    const bool in = m_inside[(size_t(z) * m_n + size_t(y)) * m_n + size_t(x)] != 0;
                    const bool ownVoxel = x >= o.x && y >= o.y && z >= o.z && x < o.x + B &&
                                          y < o.y + B && z < o.z + B;
                    inside = inside || (in && ownVoxel);
                    outside = outside || !in;
                    if (inside && outside)
                        return true;
                }
        return false;
    }

    [[nodiscard]] int coarseLo(int fine) const { return m_coarseLo[size_t(fine)]; }
    [[nodiscard]] int coarseHi(int fine) const { return m_coarseHi[size_t(fine)]; }

    /// Fine value of component `comp` at (x,y,z): the painted value inside the mask, the skin's
    /// next to it, zero elsewhere.
    [[nodiscard]] float fine(int comp, int x, int y, int z) const {
        if (!m_inside[(size_t(z) * m_n + size_t(y)) * m_n + size_t(x)]) {
            const std::optional<MaterialSample> s = skin(x, y, z);
            if (!s)
                return 0.f;
            float value[MaterialVolume::COMPONENTS];
            componentsOf(*s, value);
            return value[comp];
        }
        return m_data[m_addr[0][size_t(x)] + m_addr[1][size_t(y)] + m_addr[2][size_t(z)] +
                      size_t(comp) * MaterialVolume::BRICK_VOXELS];
    }

    /// The fraction of coarse cell (I,J,K) in inside voxels (the skin left out).
    [[nodiscard]] float maskFraction(int I, int J, int K) const {
        double insideVol = 0.0;
        for (const Overlap& z : m_lists[size_t(K)])
            for (const Overlap& y : m_lists[size_t(J)]) {
                const size_t row = (size_t(z.fine) * m_n + size_t(y.fine)) * m_n;
                for (const Overlap& x : m_lists[size_t(I)])
                    if (m_inside[row + size_t(x.fine)])
                        insideVol += x.length * y.length * z.length;
            }
        return float(insideVol / m_cellVolume);
    }

    /// Evaluates coarse cell (I,J,K) into `out` (the arithmetic, its order included, of the
    /// original dense implementation: results are bit-identical to it).
    void evaluate(int I, int J, int K, CoarseMaterial& out, Scratch& scratch) const {
        std::vector<double>& tau = scratch.tau;
        std::vector<double>& w = scratch.w;
        const auto& LX = m_lists[size_t(I)];
        const auto& LY = m_lists[size_t(J)];
        const auto& LZ = m_lists[size_t(K)];
        const size_t ci = out.spec.linearIndex({I, J, K});
        const int cST = MaterialVolume::component(Channel::SigmaT, 0);
        const int cSS = MaterialVolume::component(Channel::SigmaS, 0);
        const int cG = MaterialVolume::component(Channel::G, 0);
        // Volume-weighted sums for inside fraction, albedo and g. The same sweep copies the
        // window's masked σt into scratch.window (x fastest) for the column sums below, when
        // the window is small (it always is for the LPV grids: ⌈n/res⌉+1 voxels per axis).
        const size_t nx = LX.size(), ny = LY.size(), nz = LZ.size();
        const size_t windowVoxels = nx * ny * nz;
        const bool gathered = windowVoxels <= MAX_WINDOW;
        if (gathered)
            scratch.window.assign(3 * windowVoxels, 0.f);
        float* win = scratch.window.data();
        double insideVol = 0.0, sumSt[3] = {}, sumSs[3] = {}, sumSsG[3] = {};
        size_t k = 0;
        for (const Overlap& z : LZ)
            for (const Overlap& y : LY) {
                const size_t row = (size_t(z.fine) * m_n + size_t(y.fine)) * m_n;
                const size_t rowAddr = m_addr[1][size_t(y.fine)] + m_addr[2][size_t(z.fine)];
                for (const Overlap& x : LX) {
                    const size_t wk = k++;
                    float value[MaterialVolume::COMPONENTS];
                    if (m_inside[row + size_t(x.fine)]) {
                        const float* v = m_data + rowAddr + m_addr[0][size_t(x.fine)];
                        for (int comp = 0; comp < MaterialVolume::COMPONENTS; ++comp)
                            value[comp] = v[size_t(comp) * MaterialVolume::BRICK_VOXELS];
                    } else if (const std::optional<MaterialSample> s =
                                   skin(x.fine, y.fine, z.fine)) {
                        componentsOf(*s, value);
                    } else {
                        continue;
                    }
                    const double wv = x.length * y.length * z.length;
                    insideVol += wv;
                    for (int c = 0; c < 3; ++c) {
                        const float st = value[cST + c];
                        const float ss = value[cSS + c];
                        const float gg = value[cG + c];
                        if (gathered)
                            win[size_t(c) * windowVoxels + wk] = st;
                        sumSt[c] += wv * st;
                        sumSs[c] += wv * ss;
                        sumSsG[c] += wv * ss * gg;
                    }
                }
            }
        out.insideFraction[ci] = float(insideVol / m_cellVolume);
        if (insideVol == 0.0) {
            // No inside fine voxel: every masked σt is 0, so each τ is 0, ln T̄ = ln(Σw/Σw) =
            // 0 and σt,eff = σs′ = g = 0 exactly, as the general path below computes.
            for (int c = 0; c < 3; ++c)
                out.sigma_t[c][ci] = out.sigma_s[c][ci] = out.g[c][ci] = 0.f;
            return;
        }
        for (int c = 0; c < 3; ++c) {
            // Mean transmittance across the cell along each axis: every fine column parallel
            // to the axis contributes exp(−τ), τ = Σ σt·(overlap length)·h (Beer–Lambert),
            // weighted by its cross-section overlap.
            double logT[3];
            for (int axis = 0; axis < 3; ++axis) {
                const auto& LA = axis == 0 ? LX : axis == 1 ? LY : LZ;  // along
                const auto& LU = axis == 0 ? LY : LX;                   // across 1
                const auto& LV = axis == 2 ? LY : LZ;                   // across 2
                tau.clear();
                w.clear();
                // Window strides of the along/across axes (x fastest, then y, then z).
                const size_t stride[3] = {1, nx, nx * ny};
                const size_t sA = stride[axis], sU = stride[axis == 0 ? 1 : 0],
                             sV = stride[axis == 2 ? 1 : 2];
                const float* wc = win + size_t(c) * windowVoxels;
                for (size_t iv = 0; iv < LV.size(); ++iv) {
                    const Overlap& v = LV[iv];
                    for (size_t iu = 0; iu < LU.size(); ++iu) {
                        const Overlap& u = LU[iu];
                        double t = 0.0;
                        if (gathered) {
                            const float* col = wc + iu * sU + iv * sV;
                            for (size_t ia = 0; ia < LA.size(); ++ia)
                                t += double(col[ia * sA]) * LA[ia].length;
                        } else {
                            for (const Overlap& a : LA) {
                                Coord q;
                                q[axis] = a.fine;
                                q[axis == 0 ? 1 : 0] = u.fine;
                                q[axis == 2 ? 1 : 2] = v.fine;
                                t += double(fine(cST + c, q.x, q.y, q.z)) * a.length;
                            }
                        }
                        tau.push_back(t * m_h);
                        w.push_back(u.length * v.length);
                    }
                }
                logT[axis] = logMeanTransmittance(tau.data(), w.data(), tau.size());
            }
            // Mean of the three axes' transmittances, again in log space.
            const double negLog[3] = {-logT[0], -logT[1], -logT[2]};
            const double ones[3] = {1.0, 1.0, 1.0};
            const double logMean = logMeanTransmittance(negLog, ones, 3);
            // exp(−σt,eff·H) = T̄  ⇒  σt,eff = −ln T̄ / H.
            const double sigmaT = std::max(0.0, -logMean / m_H);
            const double albedo = sumSt[c] > 0.0 ? sumSs[c] / sumSt[c] : 0.0;
            out.sigma_t[c][ci] = float(std::min(sigmaT, double(SIGMA_MAX)));
            out.sigma_s[c][ci] = std::min(float(albedo * sigmaT), out.sigma_t[c][ci]);
            out.g[c][ci] = sumSs[c] > 0.0 ? float(sumSsG[c] / sumSs[c]) : 0.f;
        }
    }

private:
    int m_n;
    double m_ratio = 1.0, m_h = 1.0, m_H = 1.0, m_cellVolume = 1.0;
    std::vector<std::vector<Overlap>> m_lists;
    std::vector<int> m_coarseLo, m_coarseHi;  ///< coarse cells overlapping fine index i
    std::vector<size_t> m_addr[3];
    const float* m_data = nullptr;
    const uint8_t* m_inside = nullptr;
    const MaterialVolume* m_volume = nullptr;
    std::vector<uint8_t> m_nearInside;  ///< bricksNearInside: per brick, whether skin may be in it
};

/// Homogeneous when every cell holding material is identical.
bool isHomogeneous(const CoarseMaterial& out) {
    const size_t cells = out.spec.voxelCount();
    bool homogeneous = true;
    bool haveRef = false;
    size_t ref = 0;
    for (size_t i = 0; i < cells && homogeneous; ++i) {
        if (out.insideFraction[i] <= 0.f)
            continue;
        if (!haveRef) {
            ref = i;
            haveRef = true;
            continue;
        }
        if (out.insideFraction[i] != out.insideFraction[ref])
            homogeneous = false;
        for (int c = 0; c < 3; ++c)
            if (out.sigma_t[c][i] != out.sigma_t[c][ref] ||
                out.sigma_s[c][i] != out.sigma_s[c][ref] || out.g[c][i] != out.g[c][ref])
                homogeneous = false;
    }
    return homogeneous;
}

GridSpec coarseSpec(const MaterialVolume& volume, int resolution) {
    const GridSpec& fineSpec = volume.spec();
    GridSpec spec;
    spec.origin = fineSpec.origin;
    spec.resolution = resolution;
    spec.voxelSize = fineSpec.voxelSize * float(volume.resolution()) / float(resolution);
    return spec;
}

}  // namespace

CoarseMaterial resampleForPropagation(const MaterialVolume& volume, int resolution) {
    LUCENT_CHECK(volume.brickCount() > 0, "resampleForPropagation: the material volume is empty");
    const int n = volume.resolution();
    LUCENT_CHECK(resolution >= 1 && resolution <= n,
                 "resampleForPropagation: resolution = ", resolution, " is outside [1, ", n, "]");
    CoarseMaterial out;
    out.spec = coarseSpec(volume, resolution);
    const size_t cells = out.spec.voxelCount();
    for (int c = 0; c < 3; ++c) {
        out.sigma_t[c].assign(cells, 0.f);
        out.sigma_s[c].assign(cells, 0.f);
        out.g[c].assign(cells, 0.f);
    }
    out.insideFraction.assign(cells, 0.f);

    const CellEvaluator eval(volume, resolution);
    // One task per (J,K) row of cells: fine enough to balance the two halves of an object.
    const int64_t rows = int64_t(resolution) * resolution;
    parallelFor(
        0, rows,
        [&](int64_t rb, int64_t re) {
            Scratch scratch;
            for (int64_t r = rb; r < re; ++r) {
                const int J = int(r % resolution), K = int(r / resolution);
                for (int I = 0; I < resolution; ++I)
                    eval.evaluate(I, J, K, out, scratch);
            }
        },
        4);
    out.homogeneous = isHomogeneous(out);
    return out;
}

bool anyCoarseCellInside(const MaterialVolume& volume, int resolution, float fraction) {
    LUCENT_CHECK(volume.brickCount() > 0, "anyCoarseCellInside: the material volume is empty");
    LUCENT_CHECK(resolution >= 1 && resolution <= volume.resolution(),
                 "anyCoarseCellInside: resolution = ", resolution, " is outside [1, ",
                 volume.resolution(), "]");
    const CellEvaluator eval(volume, resolution);
    for (int K = 0; K < resolution; ++K)
        for (int J = 0; J < resolution; ++J)
            for (int I = 0; I < resolution; ++I)
                if (eval.maskFraction(I, J, K) >= fraction)
                    return true;
    return false;
}

size_t updateCoarseMaterial(CoarseMaterial& coarse, const MaterialVolume& volume,
                            const std::vector<int>& dirtyBricks, std::vector<int>* recomputed) {
    LUCENT_CHECK(volume.brickCount() > 0, "updateCoarseMaterial: the material volume is empty");
    const int res = coarse.spec.resolution;
    LUCENT_CHECK(res >= 1 && res <= volume.resolution(), "updateCoarseMaterial: coarse resolution ",
                 res, " is outside [1, ", volume.resolution(), "]");
    LUCENT_CHECK(coarse.spec == coarseSpec(volume, res),
                 "updateCoarseMaterial: the coarse grid was not resampled from this volume "
                 "(spec.origin/voxelSize differ)");
    const size_t cells = coarse.spec.voxelCount();
    for (int c = 0; c < 3; ++c)
        LUCENT_CHECK(coarse.sigma_t[c].size() == cells && coarse.sigma_s[c].size() == cells &&
                         coarse.g[c].size() == cells,
                     "updateCoarseMaterial: coarse sigma_t/sigma_s/g[", c, "] has the wrong size");
    LUCENT_CHECK(coarse.insideFraction.size() == cells,
                 "updateCoarseMaterial: coarse insideFraction has the wrong size");
    if (dirtyBricks.empty())
        return 0;

    const CellEvaluator eval(volume, res);
    // Coarse cells overlapping any dirty brick (each brick covers an 8³ fine box) and, where the
    // brick meets the skin, the voxels next to it, whose skin values read the brick's voxels.
    std::vector<uint8_t> mark(cells, 0);
    const int B = MaterialVolume::BRICK;
    const int n = volume.resolution();
    for (int b : dirtyBricks) {
        LUCENT_CHECK(b >= 0 && b < volume.brickCount(), "updateCoarseMaterial: dirty brick index ",
                     b, " is outside [0, ", volume.brickCount(), ")");
        const Coord o = volume.brickOrigin(b);
        const int margin = eval.brickTouchesSkin(o) ? 1 : 0;
        Coord lo, hi;
        for (int a = 0; a < 3; ++a) {
            const int f0 = std::max(o[a] - margin, 0), f1 = std::min(o[a] + B + margin, n) - 1;
            lo[a] = eval.coarseLo(f0);
            hi[a] = eval.coarseHi(f1);
        }
        for (int K = lo.z; K <= hi.z; ++K)
            for (int J = lo.y; J <= hi.y; ++J)
                for (int I = lo.x; I <= hi.x; ++I)
                    mark[coarse.spec.linearIndex({I, J, K})] = 1;
    }
    std::vector<int> list;
    for (size_t i = 0; i < cells; ++i)
        if (mark[i])
            list.push_back(int(i));
    parallelFor(
        0, int64_t(list.size()),
        [&](int64_t b, int64_t e) {
            Scratch scratch;
            for (int64_t k = b; k < e; ++k) {
                const int ci = list[size_t(k)];
                eval.evaluate(ci % res, (ci / res) % res, ci / (res * res), coarse, scratch);
            }
        },
        64);
    coarse.homogeneous = isHomogeneous(coarse);
    if (recomputed)
        recomputed->insert(recomputed->end(), list.begin(), list.end());
    return list.size();
}

}  // namespace lucent
