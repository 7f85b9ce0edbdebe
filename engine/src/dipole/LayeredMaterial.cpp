// SPDX-License-Identifier: MIT
/// @file
/// @brief The layered read-out of a painted volume (LayeredMaterial.h).

#include <lucent/dipole/LayeredMaterial.h>

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Quadrature.h>
#include <lucent/dipole/HalfSpace.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>

namespace lucent::dipole {

namespace {

/// Kubelka–Munk coefficients of a medium with diffusion's decay constant (file comment of the
/// header): K = 2σa, S = (3σs′ − σa)/4, so that √(K² + 2KS) = σ_tr. Below α′ = 1/4 diffusion
/// has no positive S; S is then held at a tiny positive value (the medium returns almost
/// nothing either way).
struct KubelkaMunk {
    double k = 0.0, s = 0.0;
    double sigmaTr = 0.0;  ///< √(K² + 2KS), mm⁻¹
};

KubelkaMunk kubelkaMunk(const TwoFluxLayer& l) {
    const double sigmaT = l.sigmaA + l.sigmaSp;
    const double sigmaA = std::max(l.sigmaA, 1e-9 * sigmaT);
    KubelkaMunk km;
    km.k = 2.0 * sigmaA;
    km.s = std::max(0.25 * (3.0 * l.sigmaSp - sigmaA), 1e-12 * sigmaT);
    km.sigmaTr = std::sqrt(km.k * km.k + 2.0 * km.k * km.s);
    return km;
}

/// R∞ = a − √(a² − 1) with a = 1 + K/S, written as 1/(a + b) to keep it accurate when a is large.
double reflectanceOfHalfSpace(const KubelkaMunk& km) {
    const double a = 1.0 + km.k / km.s;
    return 1.0 / (a + std::sqrt(a * a - 1.0));
}

/// Kubelka's layer of thickness d over a background of reflectance rg:
///     R = (t (1 − rg a) + rg b) / (t (a − rg) + b),  t = tanh(b S d) = tanh(σ_tr d),
/// which is rg for d → 0 and R∞ for d → ∞.
double layerOver(const KubelkaMunk& km, double thicknessMm, double rg) {
    const double a = 1.0 + km.k / km.s;
    const double b = std::sqrt(a * a - 1.0);
    const double t = std::tanh(km.sigmaTr * thicknessMm);
    return (t * (1.0 - rg * a) + rg * b) / (t * (a - rg) + b);
}

/// The two-flux reflectance of `count` layers, top first, the last semi-infinite: stacked from
/// the bottom up (arguments unchecked).
double stackedReflectance(const TwoFluxLayer* layers, size_t count) {
    double r = reflectanceOfHalfSpace(kubelkaMunk(layers[count - 1]));
    for (size_t i = count - 1; i-- > 0;)
        r = layerOver(kubelkaMunk(layers[i]), layers[i].thicknessMm, r);
    return r;
}

void checkLayer(const TwoFluxLayer& l, bool last) {
    LUCENT_CHECK(std::isfinite(l.sigmaA) && l.sigmaA >= 0.0 && std::isfinite(l.sigmaSp) &&
                     l.sigmaSp >= 0.0 && l.sigmaA + l.sigmaSp > 0.0,
                 "two-flux layer: sigma_a and sigma_s' must be finite, >= 0 and not both 0 (got ",
                 l.sigmaA, ", ", l.sigmaSp, ")");
    LUCENT_CHECK(last || (std::isfinite(l.thicknessMm) && l.thicknessMm >= 0.0),
                 "two-flux layer: thickness must be finite and >= 0 mm (got ", l.thicknessMm, ")");
}

/// The exact half-space total R(α′) at one η, tabulated at nodes uniform in s = √(1 − α′)
/// (R is close to linear in s near α′ = 1, where it matters most), inverted by bisection on
/// the monotone table. Built once per η per process (≈ 60 ms).
class ExactTotalTable {
public:
    static constexpr int NODES = 257;

    explicit ExactTotalTable(double eta) {
        m_total.resize(NODES);
        for (int i = 0; i < NODES; ++i) {
            const double s = double(i) / (NODES - 1);
            m_total[size_t(i)] = halfSpaceReflectance(1.0 - s * s, eta);
        }
        // r_i = 2 ∫₀¹ F(μ) μ dμ, the Fresnel reflectance from inside averaged over a diffuse
        // (cosine-weighted) hemisphere; total internal reflection below the critical cosine.
        const QuadratureRule g = gaussLegendre(256).mappedTo(0.0, 1.0);
        for (size_t k = 0; k < g.x.size(); ++k)
            m_internalReflectance += 2.0 * g.w[k] * g.x[k] * fresnelDielectric(g.x[k], 1.0 / eta);
    }

    /// The diffuse reflectance of the boundary seen from inside.
    [[nodiscard]] double internalReflectance() const { return m_internalReflectance; }

    static std::shared_ptr<const ExactTotalTable> shared(double eta) {
        static std::mutex mutex;
        static std::map<double, std::shared_ptr<const ExactTotalTable>> tables;
        const std::lock_guard<std::mutex> lock(mutex);
        std::shared_ptr<const ExactTotalTable>& t = tables[eta];
        if (!t)
            t = std::make_shared<const ExactTotalTable>(eta);
        return t;
    }

    [[nodiscard]] double total(double albedo) const {
        const double s = std::sqrt(std::clamp(1.0 - albedo, 0.0, 1.0)) * (NODES - 1);
        const int i = std::min(int(s), NODES - 2);
        const double f = s - double(i);
        return (1.0 - f) * m_total[size_t(i)] + f * m_total[size_t(i) + 1];
    }

    /// The albedo whose total is `r` (clamped to the table's range).
    [[nodiscard]] double albedo(double r) const {
        if (r >= m_total.front())
            return 1.0;
        if (r <= m_total.back())
            return 0.0;
        // m_total falls with i: find i with m_total[i] >= r > m_total[i + 1].
        int lo = 0, hi = NODES - 1;
        while (hi - lo > 1) {
            const int mid = (lo + hi) / 2;
            (m_total[size_t(mid)] >= r ? lo : hi) = mid;
        }
        const double f = (m_total[size_t(lo)] - r) / (m_total[size_t(lo)] - m_total[size_t(hi)]);
        const double s = (double(lo) + f) / (NODES - 1);
        return 1.0 - s * s;
    }

private:
    std::vector<double> m_total;
    double m_internalReflectance = 0.0;
};

}  // namespace

double twoFluxReflectance(const std::vector<TwoFluxLayer>& layers) {
    LUCENT_CHECK(!layers.empty(), "twoFluxReflectance: no layers");
    for (size_t i = 0; i < layers.size(); ++i)
        checkLayer(layers[i], i + 1 == layers.size());
    return stackedReflectance(layers.data(), layers.size());
}

namespace {

/// layeredEquivalentAlbedo without the argument checks, on a table already fetched.
double equivalentAlbedo(const TwoFluxLayer* column, size_t count, const ExactTotalTable& exact) {
    const TwoFluxLayer& top = column[0];
    const double albedoTop = top.sigmaSp / (top.sigmaA + top.sigmaSp);
    bool homogeneous = true;
    for (size_t i = 1; i < count && homogeneous; ++i)
        homogeneous = column[i].sigmaA == top.sigmaA && column[i].sigmaSp == top.sigmaSp;
    if (homogeneous)
        return albedoTop;
    const double r = stackedReflectance(column, count);
    const double rTop = reflectanceOfHalfSpace(kubelkaMunk(top));
    if (!(rTop > 0.0))
        return albedoTop;
    // Behind the boundary: of the light that comes up, r_i goes back down for another pass
    // through the column, so what leaves per unit entering is R (1 − r_i) / (1 − r_i R). At
    // η 1.3 (r_i ≈ 0.44) this weighs the core more than the bare two-flux model does.
    const double ri = exact.internalReflectance();
    const auto behindBoundary = [ri](double rr) { return rr * (1.0 - ri) / (1.0 - ri * rr); };
    // The column's two-flux excess over the top medium alone is added to the top medium's
    // exact total. (A ratio instead diverges where the top medium's albedo is below 1/4, where
    // its two-flux R is ~0 but its exact total is not: a dark coat over a bright core read
    // as albedo 1, bright dots along the edges of dark strokes.)
    return exact.albedo(exact.total(albedoTop) + behindBoundary(r) - behindBoundary(rTop));
}

}  // namespace

double layeredEquivalentAlbedo(const std::vector<TwoFluxLayer>& column, double eta) {
    LUCENT_CHECK(!column.empty(), "layeredEquivalentAlbedo: no layers");
    for (size_t i = 0; i < column.size(); ++i)
        checkLayer(column[i], i + 1 == column.size());
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "layeredEquivalentAlbedo: eta must be in [1, 3] (got ", eta, ")");
    return equivalentAlbedo(column.data(), column.size(), *ExactTotalTable::shared(eta));
}

namespace {

/// The inside mask box-blurred over (2r + 1)³ voxels (separable running sums), dense, x fastest.
std::vector<float> smoothedInside(const MaterialVolume& volume, int r) {
    const int n = volume.resolution();
    const std::vector<uint8_t>& inside = volume.insideMask();
    std::vector<float> a(inside.begin(), inside.end()), b(a.size());
    const float norm = 1.f / float(2 * r + 1);
    const size_t strides[3] = {1, size_t(n), size_t(n) * size_t(n)};
    for (int axis = 0; axis < 3; ++axis) {
        const size_t stride = strides[axis];
        parallelFor(
            0, int64_t(n) * n,
            [&](int64_t begin, int64_t end) {
                for (int64_t line = begin; line < end; ++line) {
                    // The line's first voxel: the two other coordinates from `line`.
                    const size_t u = size_t(line % n), v = size_t(line / n);
                    size_t start = 0;
                    if (axis == 0)
                        start = u * strides[1] + v * strides[2];
                    else if (axis == 1)
                        start = u + v * strides[2];
                    else
                        start = u + v * strides[1];
                    float sum = 0.f;
                    for (int i = -r; i <= r; ++i)
                        if (i >= 0 && i < n)
                            sum += a[start + size_t(i) * stride];
                    for (int i = 0; i < n; ++i) {
                        b[start + size_t(i) * stride] = sum * norm;
                        const int out = i - r, in = i + r + 1;
                        if (out >= 0)
                            sum -= a[start + size_t(out) * stride];
                        if (in < n)
                            sum += a[start + size_t(in) * stride];
                    }
                }
            },
            64);
        std::swap(a, b);
    }
    return a;
}

/// Rewrites σs′ of the surface-band voxels of `seen` inside the bricks flagged in `bricks`
/// (all when empty) from the columns of `volume`. With `changed` (per brick: its values in
/// `volume` changed since `seen` was last brought up to date), a voxel outside a changed brick
/// whose column passes through no changed brick keeps its value: what it reads is the same.
void rewriteBand(const MaterialVolume& volume, MaterialVolume& seen, double eta,
                 const LayeredReadoutSettings& settings, const std::vector<float>& smooth,
                 const std::vector<uint8_t>& bricks,
                 const std::vector<uint8_t>* changed = nullptr) {
    const GridSpec& spec = volume.spec();
    const int n = spec.resolution;
    const ExactTotalTable& exact = *ExactTotalTable::shared(eta);
    const float step = 0.5f;  // voxels per layer
    const int maxSteps = int(float(std::max(1, settings.maxDepthVoxels)) / step);
    const double stopOpticalDepth = -std::log(std::clamp(settings.stopWeight, 1e-12, 1.0));
    const double stepMm = double(step) * double(spec.voxelSize);
    const auto at = [&](int x, int y, int z) {
        x = std::clamp(x, 0, n - 1);
        y = std::clamp(y, 0, n - 1);
        z = std::clamp(z, 0, n - 1);
        return smooth[spec.linearIndex(Coord(x, y, z))];
    };
    // σt′ and σs′ of the voxel holding p (nearest voxel, as MaterialVolume::sample, reading
    // only the two quantities); false outside the grid, the mask or the material.
    const int per = volume.bricksPerAxis();
    constexpr int B = MaterialVolume::BRICK;
    const auto brickOf = [&](const Coord& c) {
        return ((c.z / B) * per + c.y / B) * per + c.x / B;
    };
    const auto sigmaAt = [&](const Point3f& p, MaterialSample& m) {
        const Coord c = spec.cellOf(p);
        if (!spec.contains(c) || !volume.isInside(c))
            return false;
        const float* d = volume.brickData(brickOf(c));
        const int v = MaterialVolume::voxelInBrick(c.x % B, c.y % B, c.z % B);
        for (int ch = 0; ch < 3; ++ch) {
            m.sigma_t[ch] =
                d[MaterialVolume::component(Channel::SigmaT, ch) * MaterialVolume::BRICK_VOXELS +
                  v];
            m.sigma_s[ch] =
                d[MaterialVolume::component(Channel::SigmaS, ch) * MaterialVolume::BRICK_VOXELS +
                  v];
        }
        return m.sigma_t != Rgb(0.f);
    };
    // Whether the column from p0 along `inward` samples a voxel of a changed brick (the samples
    // of the march below, to its longest; past the object's surface too: a superset).
    const auto readsChanged = [&](const Point3f& p0, const Vector3f& inward) {
        for (int k = 1; k < maxSteps; ++k) {
            const Coord c = spec.cellOf(p0 + inward * (float(k) * step * spec.voxelSize));
            if (spec.contains(c) && (*changed)[size_t(brickOf(c))])
                return true;
        }
        return false;
    };
    std::vector<int> todo;
    for (int b = 0; b < seen.brickCount(); ++b)
        if ((bricks.empty() || bricks[size_t(b)]) && volume.brickHasInside(b))
            todo.push_back(b);
    parallelFor(
        0, int64_t(todo.size()),
        [&](int64_t begin, int64_t end) {
            std::array<std::vector<TwoFluxLayer>, 3> column;
            for (int64_t t = begin; t < end; ++t) {
                const int brick = todo[size_t(t)];
                const Coord o = seen.brickOrigin(brick);
                for (int z = o.z; z < std::min(o.z + MaterialVolume::BRICK, n); ++z)
                    for (int y = o.y; y < std::min(o.y + MaterialVolume::BRICK, n); ++y)
                        for (int x = o.x; x < std::min(o.x + MaterialVolume::BRICK, n); ++x) {
                            const Coord c(x, y, z);
                            // The band: inside voxels with an outside voxel in their box.
                            if (!volume.isInside(c) || smooth[spec.linearIndex(c)] >= 1.f)
                                continue;
                            const Vector3f grad(at(x + 1, y, z) - at(x - 1, y, z),
                                                at(x, y + 1, z) - at(x, y - 1, z),
                                                at(x, y, z + 1) - at(x, y, z - 1));
                            const float len = glm::length(grad);
                            if (!(len > 1e-4f))
                                continue;  // no defined inward direction (a thin sliver)
                            const Vector3f inward = grad / len;  // the mask rises inwards
                            const Point3f p0 = spec.cellCenter(c);
                            if (changed && !(*changed)[size_t(brick)] && !readsChanged(p0, inward))
                                continue;  // reads nothing that changed: its value stands
                            const MaterialSample here = volume.at(c);
                            for (auto& col : column)
                                col.clear();
                            double depth[3] = {0.0, 0.0, 0.0};
                            bool open[3] = {true, true, true};
                            for (int k = 0; k < maxSteps; ++k) {
                                MaterialSample m = here;
                                if (k > 0 &&
                                    !sigmaAt(p0 + inward * (float(k) * step * spec.voxelSize), m))
                                    break;  // left the object: the medium is taken to continue
                                bool any = false;
                                for (int ch = 0; ch < 3; ++ch) {
                                    if (!open[ch])
                                        continue;
                                    TwoFluxLayer l;
                                    l.sigmaSp = double(m.sigma_s[ch]);
                                    l.sigmaA = std::max(0.0, double(m.sigma_t[ch]) - l.sigmaSp);
                                    l.thicknessMm = stepMm;
                                    if (!(l.sigmaA + l.sigmaSp > 0.0)) {
                                        open[ch] = false;
                                        continue;
                                    }
                                    // Runs of one medium are one layer (the stack's cost
                                    // is then the number of media met, not of steps).
                                    std::vector<TwoFluxLayer>& col = column[size_t(ch)];
                                    if (!col.empty() && col.back().sigmaA == l.sigmaA &&
                                        col.back().sigmaSp == l.sigmaSp)
                                        col.back().thicknessMm += stepMm;
                                    else
                                        col.push_back(l);
                                    // Stop once what lies deeper weighs under stopWeight.
                                    const double sigmaTr = std::sqrt(
                                        3.0 * std::max(l.sigmaA, 1e-9) * (l.sigmaA + l.sigmaSp));
                                    depth[ch] += 2.0 * sigmaTr * stepMm;
                                    open[ch] = depth[ch] < stopOpticalDepth;
                                    any = any || open[ch];
                                }
                                if (!any)
                                    break;
                            }
                            // Raw writes: each brick belongs to one task (set() would bump
                            // the shared revision counter from several threads).
                            float* data = seen.brickData(brick);
                            const int v = MaterialVolume::voxelInBrick(x - o.x, y - o.y, z - o.z);
                            for (int ch = 0; ch < 3; ++ch) {
                                const std::vector<TwoFluxLayer>& col = column[size_t(ch)];
                                float& out = data[MaterialVolume::component(Channel::SigmaS, ch) *
                                                      MaterialVolume::BRICK_VOXELS +
                                                  v];
                                // Written either way: an update may find a column that was
                                // layered homogeneous now.
                                if (col.size() < 2 || !(here.sigma_t[ch] > 0.f)) {
                                    out = here.sigma_s[ch];
                                    continue;
                                }
                                const double albedo =
                                    equivalentAlbedo(col.data(), col.size(), exact);
                                out = std::min(float(albedo), 1.f) * here.sigma_t[ch];
                            }
                        }
            }
        },
        1);
}

void checkEta(double eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "layered read-out: eta must be in [1, 3] (got ", eta, ")");
}

}  // namespace

LayeredReadout::LayeredReadout(const MaterialVolume& volume, double eta,
                               const LayeredReadoutSettings& settings)
    : m_seen(volume), m_eta(eta), m_settings(settings) {
    checkEta(eta);
    m_settings.surfaceBandVoxels = std::max(1, m_settings.surfaceBandVoxels);
    m_settings.maxDepthVoxels = std::max(1, m_settings.maxDepthVoxels);
    if (volume.resolution() == 0)
        return;
    // Also for a homogeneous volume (its read-out is the volume): the first stroke on it then
    // costs what any stroke does (the mask's blur is 85 ms of a 128³ volume's first stroke
    // otherwise, docs/benchmarks.md "Layered read-out").
    m_smoothInside = smoothedInside(volume, m_settings.surfaceBandVoxels);
    if (!volume.isHomogeneous())
        rewriteBand(volume, m_seen, m_eta, m_settings, m_smoothInside, {});
}

std::vector<int> LayeredReadout::update(const MaterialVolume& volume,
                                        const std::vector<int>& dirtyBricks) {
    LUCENT_CHECK(m_seen.spec() == volume.spec(),
                 "layered read-out: the volume's grid is not the one it was built on");
    for (int d : dirtyBricks)
        LUCENT_CHECK(d >= 0 && d < volume.brickCount(), "layered read-out: brick ", d,
                     " is out of range");
    if (dirtyBricks.empty())
        return {};
    if (dirtyBricks.size() == size_t(volume.brickCount())) {
        // A new inside mask (setInsideMask marks every brick): everything again.
        *this = LayeredReadout(volume, m_eta, m_settings);
        std::vector<int> all(size_t(volume.brickCount()));
        for (size_t b = 0; b < all.size(); ++b)
            all[b] = int(b);
        return all;
    }
    // A column starts within surfaceBandVoxels of the surface and reaches maxDepthVoxels:
    // bricks that far from a dirty brick may read it.
    const int per = volume.bricksPerAxis();
    const int reach =
        (m_settings.maxDepthVoxels + MaterialVolume::BRICK - 1) / MaterialVolume::BRICK;
    std::vector<uint8_t> flag(size_t(volume.brickCount()), 0);
    for (int d : dirtyBricks) {
        const Coord o = volume.brickOrigin(d) / MaterialVolume::BRICK;
        for (int z = std::max(0, o.z - reach); z <= std::min(per - 1, o.z + reach); ++z)
            for (int y = std::max(0, o.y - reach); y <= std::min(per - 1, o.y + reach); ++y)
                for (int x = std::max(0, o.x - reach); x <= std::min(per - 1, o.x + reach); ++x)
                    flag[size_t((z * per + y) * per + x)] = 1;
    }
    std::vector<uint8_t> dirty(size_t(volume.brickCount()), 0);
    for (int d : dirtyBricks) {
        dirty[size_t(d)] = 1;
        // The painted bricks start from the volume's values; the band is rewritten below.
        std::copy_n(volume.brickData(d), MaterialVolume::BRICK_VOXELS * MaterialVolume::COMPONENTS,
                    m_seen.brickData(d));
    }
    // In the other bricks within reach, only voxels whose column reads a painted brick change.
    rewriteBand(volume, m_seen, m_eta, m_settings, m_smoothInside, flag, &dirty);
    std::vector<int> changed;
    for (int b = 0; b < volume.brickCount(); ++b)
        if (flag[size_t(b)]) {
            m_seen.markBrickDirty(b);
            changed.push_back(b);
        }
    return changed;
}

MaterialVolume layeredEquivalent(const MaterialVolume& volume, double eta,
                                 const LayeredReadoutSettings& settings) {
    checkEta(eta);
    if (volume.resolution() == 0 || volume.isHomogeneous())
        return volume;  // read as it is; no updates will follow, so no mask to prepare
    return LayeredReadout(volume, eta, settings).volume();
}

}  // namespace lucent::dipole
