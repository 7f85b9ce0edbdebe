// SPDX-License-Identifier: MIT
/// @file
/// @brief Transmittance-preserving resampling to a coarse grid (Resample.h, docs/material.md).
#include <lucent/material/Resample.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lucent {

namespace {

struct Overlap {
    int fine;       ///< fine voxel index along the axis
    double length;  ///< overlap with the coarse cell, in fine voxels (0, 1]
};

/// ln((Σ w_i e^{−τ_i}) / Σ w_i), evaluated with the smallest τ factored out so that optically
/// thick cells do not underflow to ln 0.
double logMeanTransmittance(const std::vector<double>& tau, const std::vector<double>& w) {
    double tmin = std::numeric_limits<double>::infinity();
    for (double t : tau)
        tmin = std::min(tmin, t);
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < tau.size(); ++i) {
        num += w[i] * std::exp(-(tau[i] - tmin));
        den += w[i];
    }
    return -tmin + std::log(num / den);
}

}  // namespace

CoarseMaterial resampleForPropagation(const MaterialVolume& volume, int resolution) {
    LUCENT_CHECK(volume.brickCount() > 0, "resampleForPropagation: the material volume is empty");
    const int n = volume.resolution();
    LUCENT_CHECK(resolution >= 1 && resolution <= n,
                 "resampleForPropagation: resolution = ", resolution, " is outside [1, ", n, "]");
    const GridSpec& fineSpec = volume.spec();
    CoarseMaterial out;
    out.spec.origin = fineSpec.origin;
    out.spec.resolution = resolution;
    out.spec.voxelSize = fineSpec.voxelSize * float(n) / float(resolution);
    const size_t cells = out.spec.voxelCount();
    for (int c = 0; c < 3; ++c) {
        out.sigma_t[c].assign(cells, 0.f);
        out.sigma_s[c].assign(cells, 0.f);
        out.g[c].assign(cells, 0.f);
    }
    out.insideFraction.assign(cells, 0.f);

    // 1-D overlaps of fine voxels [i, i+1) with coarse cells [I·r, (I+1)·r), r = n/resolution.
    const double ratio = double(n) / double(resolution);
    std::vector<std::vector<Overlap>> lists(static_cast<size_t>(resolution));
    for (int I = 0; I < resolution; ++I) {
        const double a = I * ratio, b = (I + 1) * ratio;
        for (int i = int(std::floor(a)); i < n && double(i) < b; ++i) {
            const double len = std::min(double(i + 1), b) - std::max(double(i), a);
            if (len > 1e-12)
                lists[size_t(I)].push_back({i, len});
        }
    }

    // Fine σt, σs′, g per channel (dense, zero outside the mask).
    const std::vector<uint8_t>& inside = volume.insideMask();
    std::vector<float> st[3], ss[3], gg[3];
    for (int c = 0; c < 3; ++c) {
        st[c] = volume.denseComponent(MaterialVolume::component(Channel::SigmaT, c));
        ss[c] = volume.denseComponent(MaterialVolume::component(Channel::SigmaS, c));
        gg[c] = volume.denseComponent(MaterialVolume::component(Channel::G, c));
        for (size_t i = 0; i < inside.size(); ++i)
            if (!inside[i])
                st[c][i] = ss[c][i] = gg[c][i] = 0.f;
    }
    const double h = fineSpec.voxelSize;
    const double H = ratio * h;  // coarse cell edge, mm
    const double cellVolume = ratio * ratio * ratio;

    parallelFor(0, int64_t(resolution), [&](int64_t kb, int64_t ke) {
        std::vector<double> tau, w;
        for (int K = int(kb); K < int(ke); ++K)
            for (int J = 0; J < resolution; ++J)
                for (int I = 0; I < resolution; ++I) {
                    const auto& LX = lists[size_t(I)];
                    const auto& LY = lists[size_t(J)];
                    const auto& LZ = lists[size_t(K)];
                    const size_t ci = out.spec.linearIndex({I, J, K});
                    // Volume-weighted sums for inside fraction, albedo and g.
                    double insideVol = 0.0, sumSt[3] = {}, sumSs[3] = {}, sumSsG[3] = {};
                    for (const Overlap& z : LZ)
                        for (const Overlap& y : LY)
                            for (const Overlap& x : LX) {
                                const size_t fi = fineSpec.linearIndex({x.fine, y.fine, z.fine});
                                if (!inside[fi])
                                    continue;
                                const double wv = x.length * y.length * z.length;
                                insideVol += wv;
                                for (int c = 0; c < 3; ++c) {
                                    sumSt[c] += wv * st[c][fi];
                                    sumSs[c] += wv * ss[c][fi];
                                    sumSsG[c] += wv * ss[c][fi] * gg[c][fi];
                                }
                            }
                    out.insideFraction[ci] = float(insideVol / cellVolume);
                    for (int c = 0; c < 3; ++c) {
                        // Mean transmittance across the cell along each axis: every fine column
                        // parallel to the axis contributes exp(−τ), τ = Σ σt·(overlap length)·h
                        // (Beer–Lambert), weighted by its cross-section overlap.
                        double logT[3];
                        for (int axis = 0; axis < 3; ++axis) {
                            const auto& LA = axis == 0 ? LX : axis == 1 ? LY : LZ;  // along
                            const auto& LU = axis == 0 ? LY : LX;                   // across 1
                            const auto& LV = axis == 2 ? LY : LZ;                   // across 2
                            tau.clear();
                            w.clear();
                            for (const Overlap& v : LV)
                                for (const Overlap& u : LU) {
                                    double t = 0.0;
                                    for (const Overlap& a : LA) {
                                        Coord q;
                                        q[axis] = a.fine;
                                        q[axis == 0 ? 1 : 0] = u.fine;
                                        q[axis == 2 ? 1 : 2] = v.fine;
                                        t += double(st[c][fineSpec.linearIndex(q)]) * a.length;
                                    }
                                    tau.push_back(t * h);
                                    w.push_back(u.length * v.length);
                                }
                            logT[axis] = logMeanTransmittance(tau, w);
                        }
                        // Mean of the three axes' transmittances, again in log space.
                        const std::vector<double> negLog = {-logT[0], -logT[1], -logT[2]};
                        const double logMean = logMeanTransmittance(negLog, {1.0, 1.0, 1.0});
                        // exp(−σt,eff·H) = T̄  ⇒  σt,eff = −ln T̄ / H.
                        const double sigmaT = std::max(0.0, -logMean / H);
                        const double albedo = sumSt[c] > 0.0 ? sumSs[c] / sumSt[c] : 0.0;
                        out.sigma_t[c][ci] = float(std::min(sigmaT, double(SIGMA_MAX)));
                        out.sigma_s[c][ci] = std::min(float(albedo * sigmaT), out.sigma_t[c][ci]);
                        out.g[c][ci] = sumSs[c] > 0.0 ? float(sumSsG[c] / sumSs[c]) : 0.f;
                    }
                }
    });

    // Homogeneous when every cell holding material is identical.
    out.homogeneous = true;
    bool haveRef = false;
    size_t ref = 0;
    for (size_t i = 0; i < cells && out.homogeneous; ++i) {
        if (out.insideFraction[i] <= 0.f)
            continue;
        if (!haveRef) {
            ref = i;
            haveRef = true;
            continue;
        }
        if (out.insideFraction[i] != out.insideFraction[ref])
            out.homogeneous = false;
        for (int c = 0; c < 3; ++c)
            if (out.sigma_t[c][i] != out.sigma_t[c][ref] ||
                out.sigma_s[c][i] != out.sigma_s[c][ref] || out.g[c][i] != out.g[c][ref])
                out.homogeneous = false;
    }
    return out;
}

}  // namespace lucent
