// SPDX-License-Identifier: MIT
/// @file
/// @brief GridMedium: validation, homogeneity detection and the per-brick majorant grid.

#include <lucent/core/Error.h>
#include <lucent/reference/GridMedium.h>

namespace lucent {

GridMedium::GridMedium(const GridSpec& spec, const std::vector<MediumCoefficients>& voxels,
                       const Options& options)
    : m_spec(spec), m_options(options) {
    LUCENT_CHECK(spec.resolution >= 1 && spec.voxelSize > 0.f && std::isfinite(spec.voxelSize) &&
                     isFinite(spec.origin),
                 "GridMedium: invalid grid spec (resolution ", spec.resolution, ", voxelSize ",
                 spec.voxelSize, " mm)");
    LUCENT_CHECK(voxels.size() == spec.voxelCount(), "GridMedium: expected ", spec.voxelCount(),
                 " voxels, got ", voxels.size());
    m_invVoxelSize = 1.f / spec.voxelSize;
    for (int c = 0; c < 3; ++c) {
        m_sigmaT[c].resize(voxels.size());
        m_sigmaS[c].resize(voxels.size());
        m_g[c].resize(voxels.size());
    }
    bool same = true;
    for (size_t i = 0; i < voxels.size(); ++i) {
        const MediumCoefficients& v = voxels[i];
        for (int c = 0; c < 3; ++c) {
            const float st = v.sigma_t[c], ss = v.sigma_s[c], g = v.g[c];
            // σs may exceed σt by float rounding of σa + σs; anything more is an error.
            LUCENT_CHECK(std::isfinite(st) && std::isfinite(ss) && std::isfinite(g) && st >= 0.f &&
                             ss >= 0.f && ss <= st * (1.f + 1e-5f) + 1e-30f && std::abs(g) < 1.f,
                         "GridMedium: voxel ", i, " channel ", c, " has invalid coefficients (σt ",
                         st, ", σs ", ss, " mm⁻¹, g ", g, ")");
            m_sigmaT[c][i] = st;
            m_sigmaS[c][i] = std::min(ss, st);
            m_g[c][i] = g;
            if (i > 0 && (st != m_sigmaT[c][0] || m_sigmaS[c][i] != m_sigmaS[c][0] ||
                          g != m_g[c][0]))
                same = false;
        }
    }
    m_homogeneous = same && options.homogeneousFastPath;
    buildMajorants();
}

GridMedium GridMedium::uniform(const GridSpec& spec, const MediumCoefficients& value,
                               const Options& options) {
    return GridMedium(spec, std::vector<MediumCoefficients>(spec.voxelCount(), value), options);
}

void GridMedium::buildMajorants() {
    const int r = m_spec.resolution;
    if (m_options.majorant == MajorantMode::Global) {
        m_cells = 1;
        m_cellSize = m_spec.voxelSize * float(r);
    } else {
        m_cells = (r + BRICK - 1) / BRICK;
        m_cellSize = m_spec.voxelSize * float(BRICK);
    }
    const int per = m_options.majorant == MajorantMode::Global ? r : BRICK;
    m_majorant.assign(size_t(m_cells) * m_cells * m_cells * 4, 0.f);
    m_globalMajorant = {0.f, 0.f, 0.f, 0.f};
    for (int z = 0; z < r; ++z)
        for (int y = 0; y < r; ++y)
            for (int x = 0; x < r; ++x) {
                const size_t v = (size_t(z) * r + y) * r + x;
                const size_t cell =
                    (size_t(z / per) * m_cells + size_t(y / per)) * m_cells + size_t(x / per);
                for (int c = 0; c < 3; ++c) {
                    const float st = m_sigmaT[c][v];
                    float& m = m_majorant[cell * 4 + size_t(c)];
                    m = std::max(m, st);
                    float& any = m_majorant[cell * 4 + size_t(ANY_CHANNEL)];
                    any = std::max(any, st);
                    for (size_t k : {size_t(c), size_t(ANY_CHANNEL)})
                        m_globalMajorant[k] = std::max(m_globalMajorant[k], st);
                }
            }
}

}  // namespace lucent
