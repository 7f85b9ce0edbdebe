// SPDX-License-Identifier: MIT
/// @file
/// @brief CPU combined mode: windowed image-space dipole + SSLPV, split by SSLPV's own local
/// kernel or by skipped propagation steps (docs/methods/combined.md).

#include <lucent/combined/Combined.h>

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Sampling.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Medium.h>
#include <lucent/material/Resample.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/sslpv/GridDiffusion.h>
#include <lucent/sslpv/Transfer.h>
#include <shared/CombinedShared.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

namespace lucent::combined {

namespace {
constexpr double PI_D = 3.14159265358979323846;
}  // namespace

float SplitPlan::dipoleMaxRadius() const {
    // dipole::GatherSettings::maxRadius: 0 means unlimited, so r_s = +∞ maps to 0; r_s = 0
    // never reaches the gather (dipoleOn is false).
    return std::isinf(splitRadius) ? 0.f : splitRadius;
}

SplitPlan planSplit(float splitRadius, float cellSize, int baseSkip, int maxSteps, SplitMode mode) {
    LUCENT_CHECK(!std::isnan(splitRadius), "combined: split radius is NaN");
    LUCENT_CHECK(std::isfinite(cellSize) && cellSize > 0.f,
                 "combined: SSLPV cell size must be finite and > 0 mm (got ", cellSize, ")");
    LUCENT_CHECK(baseSkip >= 0 && maxSteps >= 0,
                 "combined: skipAccumulateSteps and maxSteps must be >= 0");
    SplitPlan p;
    p.mode = mode;
    p.cellSize = cellSize;
    p.splitRadius = splitRadius < 0.f ? DEFAULT_SPLIT_CELLS * cellSize : splitRadius;
    if (mode == SplitMode::Kernel) {
        // SSLPV runs unchanged; its local part within r_s is replaced by the dipole's.
        p.splitRadius = std::min(p.splitRadius, MAX_KERNEL_SPLIT_CELLS * cellSize);
        p.skipSteps = baseSkip;
        p.dipoleOn = p.splitRadius > 0.f;
        p.sslpvOn = true;
        return p;
    }
    // k = max(k₀, round(r_s/Δx)): after n six-neighbour steps light has moved at most n cells
    // (Manhattan), hence at most n·Δx (Euclidean); steps n ≤ k therefore carry only light from
    // sources within k·Δx ≈ r_s (docs/methods/combined.md, "Steps split").
    const double cells = std::isinf(p.splitRadius) ? double(maxSteps) + 1.0
                                                   : std::round(double(p.splitRadius / cellSize));
    p.skipSteps = int(std::clamp(cells, double(baseSkip), double(maxSteps) + 1.0));
    p.skipSteps = std::max(p.skipSteps, baseSkip);
    p.dipoleOn = p.splitRadius > 0.f;
    p.sslpvOn = p.skipSteps < maxSteps;
    return p;
}

// ---------------------------------------------------------------------------------------------
// The automatic SSLPV skip

namespace {
/// Calls f(material) for every inside voxel of `volume`, in x-fastest order.
template <typename F>
void forEachInsideVoxel(const MaterialVolume& volume, F&& f) {
    const int n = volume.resolution();
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Coord c(x, y, z);
                if (volume.isInside(c))
                    f(volume.at(c));
            }
}

/// dipoleFarShare with the boundary terms computed once by the caller: they cost 2×64 Fresnel
/// evaluations, far more than the closed forms (volumeFarShare runs this per distinct voxel).
double farShareWith(dipole::Model model, const MaterialSample& material,
                    const dipole::Boundary& boundary, float eta, float splitRadius, float extent) {
    // Light leaves at most D from where it entered: the window [0, r_s] and the object's
    // [0, D] overlap in everything when r_s ≥ D.
    const double r0 = double(splitRadius), r1 = std::max(r0, double(extent));
    double share = 0.0;
    for (int c = 0; c < 3; ++c) {
        const dipole::ScalarMedium med =
            dipole::fromReduced(material.sigma_t[c], material.sigma_s[c], eta);
        const dipole::DipoleProfile p =
            dipole::DipoleProfile::make(model, med.sigma_a, med.sigma_s, boundary);
        // Relative to what the object can hold, ∫_0^{max(r_s, D)} R_d dA, not the infinite
        // plane's total: an optically thin object (D ≪ 1/σt′) holds a flat, tiny part of the
        // profile, most of it beyond r_s.
        const double within = p.totalReflectance() - p.reflectanceBeyond(r1);
        if (!(within > 0.0))
            continue;  // a black channel sends nothing anywhere
        const double far = p.reflectanceBeyond(r0) - p.reflectanceBeyond(r1);
        share = std::max(share, std::clamp(far / within, 0.0, 1.0));
    }
    return share;
}

void checkFarShareArguments(float splitRadius, float extent) {
    LUCENT_CHECK(
        !std::isnan(splitRadius) && splitRadius >= 0.f && !std::isnan(extent) && extent >= 0.f,
        "combined: far share needs a split radius and an object extent >= 0 mm");
}
}  // namespace

double dipoleFarShare(dipole::Model model, const MaterialSample& material, float eta,
                      float splitRadius, float extent) {
    checkFarShareArguments(splitRadius, extent);
    return farShareWith(model, material, dipole::Boundary::of(eta), eta, splitRadius, extent);
}

double volumeFarShare(dipole::Model model, const MaterialVolume& volume, float eta,
                      float splitRadius, float extent) {
    checkFarShareArguments(splitRadius, extent);
    const dipole::Boundary boundary = dipole::Boundary::of(eta);
    double share = 0.0;
    bool any = false;
    MaterialSample last;
    // Painted volumes hold long runs of one material: a run costs one profile evaluation.
    forEachInsideVoxel(volume, [&](const MaterialSample& v) {
        if (any && v.sigma_t == last.sigma_t && v.sigma_s == last.sigma_s)
            return;
        share = std::max(share, farShareWith(model, v, boundary, eta, splitRadius, extent));
        last = v;
        any = true;
    });
    LUCENT_CHECK(any, "combined: the material volume has no inside voxel");
    return share;
}

float objectExtent(const TriangleMesh& mesh) {
    return glm::length(mesh.bounds().extent());
}

void applyFarSkip(SplitPlan& plan, double farShare, float tolerance) {
    LUCENT_CHECK(std::isfinite(tolerance) && tolerance >= 0.f,
                 "CombinedSettings.farTolerance must be finite and >= 0 (got ", tolerance, ")");
    plan.farShare = farShare;
    // Without the dipole (r_s = 0) SSLPV carries all of the light: never skipped.
    if (plan.dipoleOn && plan.sslpvOn && farShare <= double(tolerance)) {
        plan.sslpvOn = false;
        plan.sslpvSkipped = true;
    }
}

// ---------------------------------------------------------------------------------------------
// SSLPV's own surface kernel

Rgb SslpvSurfaceKernel::evaluate(float r) const {
    const auto it = std::lower_bound(ringOuter.begin(), ringOuter.end(), r);
    return it == ringOuter.end() ? Rgb(0.f) : ringValue[size_t(it - ringOuter.begin())];
}

Rgb SslpvSurfaceKernel::integral(float R) const {
    glm::dvec3 sum(0.0);
    double inner = 0.0;
    for (size_t b = 0; b < ringOuter.size() && inner < double(R); ++b) {
        const double outer = std::min(double(ringOuter[b]), double(R));
        const double area = PI_D * (outer * outer - inner * inner);
        sum += glm::dvec3(ringValue[b].r, ringValue[b].g, ringValue[b].b) * area;
        inner = double(ringOuter[b]);
    }
    return Rgb(float(sum.x), float(sum.y), float(sum.z));
}

std::vector<Rgb> sslpvHalfSpaceResponse(const MaterialSample& material, float eta,
                                        const sslpv::SslpvOptions& options, float cellSize, int n,
                                        int half, float incidenceCos) {
    LUCENT_CHECK(std::isfinite(cellSize) && cellSize > 0.f,
                 "combined kernel: cell size must be finite and > 0 mm");
    LUCENT_CHECK(n >= 8 && n <= 128 && half >= 0 && half <= (n - 3) / 2,
                 "combined kernel: need 8 <= n <= 128 and 0 <= half <= (n - 3)/2 (got n ", n,
                 ", half ", half, ")");
    LUCENT_CHECK(incidenceCos > 0.f && incidenceCos <= 1.f,
                 "combined kernel: the incidence cosine must lie in (0, 1] (got ", incidenceCos,
                 ")");
    for (int c = 0; c < 3; ++c)
        LUCENT_CHECK(std::isfinite(material.sigma_t[c]) && material.sigma_s[c] >= 0.f &&
                         material.sigma_s[c] <= material.sigma_t[c],
                     "combined kernel: material needs 0 <= sigma_s' <= sigma_t (mm^-1), finite");
    CoarseMaterial m;
    m.spec.resolution = n;
    m.spec.voxelSize = cellSize;
    m.spec.origin = Point3f(0.f);
    const size_t count = m.spec.voxelCount();
    m.insideFraction.assign(count, 0.f);
    for (int c = 0; c < 3; ++c) {
        m.sigma_t[c].assign(count, material.sigma_t[c]);
        m.sigma_s[c].assign(count, material.sigma_s[c]);
        m.g[c].assign(count, material.g[c]);
    }
    for (int z = 1; z < n - 1; ++z)
        for (int y = 1; y < n - 1; ++y)
            for (int x = 1; x < n - 1; ++x)
                m.insideFraction[m.spec.linearIndex({x, y, z})] = 1.f;
    m.homogeneous = true;
    const int c0 = n / 2;
    const float zTop = float(n - 1) * cellSize;
    // 2×2 texels of ¼ W each into the top cell (c0, c0), as the RSM would, arriving at the
    // given incidence (the walk refracts them and finds where they scatter first).
    const Vector3f arriving(std::sqrt(std::max(0.f, 1.f - incidenceCos * incidenceCos)), 0.f,
                            -incidenceCos);
    std::vector<sslpv::SslpvInjectionSample> texels;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i)
            texels.push_back({Point3f((float(c0) + 0.25f + 0.5f * float(i)) * cellSize,
                                      (float(c0) + 0.25f + 0.5f * float(j)) * cellSize, zTop),
                              Normal3f(0.f, 0.f, 1.f), arriving, Rgb(0.25f)});
    sslpv::SslpvSolver solver(options);
    solver.setMaterial(m, eta);
    solver.setInjectionSamples(std::move(texels));
    solver.solve();
    const int side = 2 * half + 1;
    const float scale = solver.exitScale() * cellSize * cellSize;
    std::vector<Rgb> g(size_t(side) * size_t(side));
    for (int j = -half; j <= half; ++j)
        for (int i = -half; i <= half; ++i)
            g[size_t(j + half) * size_t(side) + size_t(i + half)] =
                scale * solver.radiance(Point3f((float(c0 + i) + 0.5f) * cellSize,
                                                (float(c0 + j) + 0.5f) * cellSize, zTop),
                                        Normal3f(0.f, 0.f, 1.f));
    return g;
}

SslpvSurfaceKernel computeSslpvSurfaceKernel(const MaterialSample& material, float eta,
                                             const sslpv::SslpvOptions& options, float cellSize,
                                             float radius, float incidenceCos) {
    LUCENT_CHECK(std::isfinite(cellSize) && cellSize > 0.f,
                 "combined kernel: cell size must be finite and > 0 mm");
    LUCENT_CHECK(std::isfinite(radius) && radius >= 0.f,
                 "combined kernel: radius must be finite and >= 0 mm");
    // Half-space: the kernel is wanted out to `radius`; sinks lie 6 cells beyond it laterally
    // and the slab is as deep as it is wide.
    const int reach = int(std::ceil(radius / cellSize)) + 6;
    const int n = std::clamp(2 * reach + 3, 16, 2 * int(MAX_KERNEL_SPLIT_CELLS) + 15);
    const int half = std::min(reach, (n - 3) / 2);
    const std::vector<Rgb> g =
        sslpvHalfSpaceResponse(material, eta, options, cellSize, n, half, incidenceCos);
    // Rings by distance from the source cell, in cells: ring 0 = {0}, ring b = [b − ½, b + ½).
    const int rings = half + 1, side = 2 * half + 1;
    std::vector<glm::dvec3> ringSum(size_t(rings), glm::dvec3(0.0));
    std::vector<int> ringCells(size_t(rings), 0);
    for (int j = -half; j <= half; ++j)
        for (int i = -half; i <= half; ++i) {
            const int b = int(std::floor(std::hypot(double(i), double(j)) + 0.5));
            if (b >= rings)
                continue;
            ringSum[size_t(b)] += glm::dvec3(g[size_t(j + half) * size_t(side) + size_t(i + half)]);
            ++ringCells[size_t(b)];
        }
    // Per unit *transmitted* irradiance (the dipole's E): divide by T(θ_i); R-units: × π.
    const double t0 = 1.0 - double(fresnelDielectric(incidenceCos, eta));
    SslpvSurfaceKernel k;
    k.cellSize = cellSize;
    double inner = 0.0;
    int cells = 0;
    for (int b = 0; b < rings; ++b) {
        cells += ringCells[size_t(b)];
        const double outer = double(cellSize) * std::sqrt(double(cells) / PI_D);
        const double area = PI_D * (outer * outer - inner * inner);
        const glm::dvec3 v = ringSum[size_t(b)] * (PI_D / (t0 * area));
        k.ringOuter.push_back(float(outer));
        k.ringValue.push_back(Rgb(float(v.x), float(v.y), float(v.z)));
        inner = outer;
    }
    return k;
}

float meanIncidenceCosine(const TriangleMesh& mesh, const std::vector<Light>& lights, float eta) {
    double weighted = 0.0, weight = 0.0;
    for (const auto& tri : mesh.triangles) {
        const Point3f& a = mesh.positions[tri[0]];
        const Point3f& b = mesh.positions[tri[1]];
        const Point3f& c = mesh.positions[tri[2]];
        const Vector3f cross = glm::cross(b - a, c - a);
        const float twiceArea = glm::length(cross);
        if (!(twiceArea > 0.f))
            continue;                          // degenerate: no area, no normal
        const Normal3f n = cross / twiceArea;  // outward (computeVertexNormals' convention)
        const Point3f centroid = (a + b + c) / 3.f;
        for (const Light& light : lights) {
            const double e = double(luminance(dipole::lightIrradiance(light, centroid, n, eta)));
            if (!(e > 0.0))
                continue;
            const Vector3f toLight = light.type == Light::Type::Directional
                                         ? -glm::normalize(light.direction)
                                         : glm::normalize(light.position - centroid);
            weighted += double(twiceArea) * e * double(glm::dot(n, toLight));
            weight += double(twiceArea) * e;
        }
    }
    if (!(weight > 0.0))
        return 1.f;
    const double step = double(KERNEL_INCIDENCE_STEP);
    return float(std::clamp(std::round(weighted / weight / step) * step, step, 1.0));
}

namespace {
/// Running mean of reduced materials (σt′, σs′ clamped to σt′, g), in double precision.
struct MaterialMean {
    glm::dvec3 st{0.0}, ss{0.0}, g{0.0};
    size_t count = 0;
    void add(const MaterialSample& v) {
        st += glm::dvec3(v.sigma_t.r, v.sigma_t.g, v.sigma_t.b);
        ss += glm::dvec3(v.sigma_s.r, v.sigma_s.g, v.sigma_s.b);
        g += glm::dvec3(v.g.r, v.g.g, v.g.b);
        ++count;
    }
    MaterialSample mean() const {
        const double inv = 1.0 / double(count);
        MaterialSample m;
        m.sigma_t = Rgb(glm::vec3(st * inv));
        m.sigma_s = glm::min(Rgb(glm::vec3(ss * inv)), m.sigma_t);
        m.g = Rgb(glm::vec3(g * inv));
        return m;
    }
};
}  // namespace

MaterialSample meanInsideMaterial(const MaterialVolume& volume) {
    MaterialMean mean;
    forEachInsideVoxel(volume, [&](const MaterialSample& v) { mean.add(v); });
    LUCENT_CHECK(mean.count > 0, "combined: the material volume has no inside voxel");
    return mean.mean();
}

std::vector<Coord> surfaceShell(const MaterialVolume& volume, float depthMm) {
    LUCENT_CHECK(std::isfinite(depthMm), "combined: the surface shell's depth must be finite (got ",
                 depthMm, ")");
    const GridSpec& spec = volume.spec();
    const int n = spec.resolution;
    const int k = std::max(1, int(std::lround(double(depthMm) / double(spec.voxelSize))));
    // near[i]: an outside voxel, or the grid's exterior, lies within k voxels of i along the
    // axes done so far; after the three separable passes, within the (2k+1)³ box around i. A
    // box, not a Euclidean distance: "within about one cell" needs no more, and an exact
    // distance transform gave the suite's errors within 0.002.
    const std::vector<uint8_t>& inside = volume.insideMask();
    const size_t nn = size_t(n), plane = nn * nn;
    std::vector<uint8_t> near(inside.size()), next(inside.size());
    for (size_t i = 0; i < near.size(); ++i)
        near[i] = inside[i] ? 0 : 1;
    // Along x: each voxel ORs the k on either side of it in its row.
    for (size_t row = 0; row < near.size() / nn; ++row) {
        const uint8_t* src = &near[row * nn];
        uint8_t* dst = &next[row * nn];
        for (int x = 0; x < n; ++x) {
            uint8_t v = x - k < 0 || x + k >= n;
            for (int d = -k; d <= k && !v; ++d)
                v = src[x + d];
            dst[x] = v;
        }
    }
    near.swap(next);
    // Along y (stride n) and z (stride n²): whole lines of x, or planes, ORed together, so the
    // inner loops are contiguous and vectorise; (2k+1)·n³ byte operations per axis.
    const auto dilateLines = [&](size_t stride) {
        const size_t outer = near.size() / (nn * stride);
        for (size_t o = 0; o < outer; ++o)
            for (int c = 0; c < n; ++c) {
                uint8_t* dst = &next[(o * nn + size_t(c)) * stride];
                const bool edge = c - k < 0 || c + k >= n;  // the grid's exterior is outside
                std::fill(dst, dst + stride, uint8_t(edge));
                if (edge)
                    continue;
                for (int d = -k; d <= k; ++d) {
                    const uint8_t* src = &near[(o * nn + size_t(c + d)) * stride];
                    for (size_t i = 0; i < stride; ++i)
                        dst[i] |= src[i];
                }
            }
        near.swap(next);
    };
    dilateLines(nn);
    dilateLines(plane);
    std::vector<Coord> shell;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Coord c(x, y, z);
                const size_t i = spec.linearIndex(c);
                if (inside[i] && near[i])
                    shell.push_back(c);
            }
    LUCENT_CHECK(!shell.empty(), "combined: the material volume has no inside voxel");
    return shell;
}

MaterialSample surfaceMaterial(const MaterialVolume& volume, const std::vector<Coord>& shell) {
    LUCENT_CHECK(!shell.empty(), "combined: the surface shell is empty");
    MaterialMean mean;
    for (const Coord& c : shell)
        mean.add(volume.at(c));
    return mean.mean();
}

float dipoleNearShare(float sigmaT, float albedo, float boundaryA, float radius) {
    if (!(sigmaT > 0.f))
        return 0.f;
    const float zr = 1.f / sigmaT;
    const float zv = zr + 4.f * boundaryA / (3.f * sigmaT);  // z_r + 4AD, D = 1/(3σt′)
    const float s = sigmaT * std::sqrt(3.f * std::max(0.f, 1.f - albedo));  // σ_tr = √(3σaσt′)
    const float dr = std::sqrt(radius * radius + zr * zr),
                dv = std::sqrt(radius * radius + zv * zv);
    // Twice the totals over α′ (Jensen et al. 2001: ∫_r^∞ R_d 2πr dr = α′/2 Σ z e^{−σ_tr d}/d).
    const float total = std::exp(-s * zr) + std::exp(-s * zv);
    const float beyond = zr * std::exp(-s * dr) / dr + zv * std::exp(-s * dv) / dv;
    return total > 0.f ? std::clamp(1.f - beyond / total, 0.f, 1.f) : 0.f;
}

KernelSurfaceTerms kernelSurfaceTerms(const MaterialSample& kernelMaterial, float eta,
                                      float splitRadius,
                                      const sslpv::ExactReflectanceRatio& table) {
    LUCENT_CHECK(eta >= 1.f && eta <= 3.f, "combined: eta must lie in [1, 3]");
    const double fdr = dipole::fresnelDiffuseReflectanceJensen(eta);
    KernelSurfaceTerms k;
    k.boundaryA = float((1.0 + fdr) / (1.0 - fdr));
    k.splitRadius = splitRadius;
    const Rgb albedo = reducedAlbedo(kernelMaterial);
    for (int c = 0; c < 3; ++c) {
        k.exactTotal[c] = table.exactTotal(albedo[c]);
        k.nearShare[c] =
            dipoleNearShare(kernelMaterial.sigma_t[c], albedo[c], k.boundaryA, splitRadius);
    }
    return k;
}

MaterialSample discMeanMaterial(const dipole::SurfaceBuffers& buffers, int x, int y, float radius) {
    LUCENT_ASSERT(x >= 0 && y >= 0 && x < buffers.width && y < buffers.height);
    MaterialSample mean;
    const size_t idx = buffers.index(x, y);
    if (!buffers.covered[idx])
        return mean;
    const Point3f xo = buffers.position[idx];
    const Frame frame(glm::normalize(buffers.normal[idx]));
    constexpr uint32_t samples = LUCENT_COMBINED_DISC_MEAN_SAMPLES;
    int count = 0;
    for (uint32_t i = 0; i < samples; ++i) {
        const Point2f h = hammersley(i, samples);
        const float r = radius * std::sqrt(h.x), phi = 2.f * PI * h.y;
        Point2f pixel;
        if (!buffers.project(xo + r * (std::cos(phi) * frame.s + std::sin(phi) * frame.t), pixel))
            continue;
        // A pixel without material (not covered, or outside the painted volume) is left out, as
        // on the GPU, whose per-pixel material is zero there.
        const MaterialSample& m = buffers.material[buffers.index(int(pixel.x), int(pixel.y))];
        if (m.sigma_t == Rgb(0.f))
            continue;
        mean.sigma_t += m.sigma_t;
        mean.sigma_s += m.sigma_s;
        ++count;
    }
    if (count > 0) {
        mean.sigma_t /= float(count);
        mean.sigma_s /= float(count);
    }
    return mean;
}

Rgb localScaleToSurfaceMaterial(const Rgb& readoutAlbedo, const MaterialSample& discMean,
                                const KernelSurfaceTerms& kernel,
                                const sslpv::ExactReflectanceRatio& table) {
    Rgb scale(1.f);
    for (int c = 0; c < 3; ++c) {
        if (!(readoutAlbedo[c] > 0.f && kernel.exactTotal[c] > 0.f))
            continue;
        scale[c] = table.exactTotal(readoutAlbedo[c]) / kernel.exactTotal[c];
        const float sigmaT = discMean.sigma_t[c];
        if (sigmaT > 0.f && kernel.nearShare[c] > 0.f)
            scale[c] *= dipoleNearShare(sigmaT, discMean.sigma_s[c] / sigmaT, kernel.boundaryA,
                                        kernel.splitRadius) /
                        kernel.nearShare[c];
    }
    return scale;
}

Point2f pixelShift(int x, int y, uint32_t seed) {
    // PCG hash (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering"), chained.
    const auto pcg = [](uint32_t v) {
        const uint32_t state = v * 747796405u + 2891336453u;
        const uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
        return (word >> 22u) ^ word;
    };
    const uint32_t h1 = pcg(uint32_t(x) + pcg(uint32_t(y) + pcg(seed)));
    const uint32_t h2 = pcg(h1);
    return {float(h1 >> 8u) * 0x1p-24f, float(h2 >> 8u) * 0x1p-24f};
}

namespace {

/// ∫_{r0 ≤ |x_i − x_o| ≤ r1} R_lpv(r) E(x_i) dA on the tangent plane of every covered pixel
/// (W/mm², before the exit factor F_t/π), by `samples` stratified uniform samples on the
/// annulus (r = √(r0² + u (r1² − r0²)), pdf 1/(π (r1² − r0²)); r0 = 0: r = r1 √u, the disc).
/// Calls out(x, y, xo, no, B) for every covered pixel.
template <typename Out>
void kernelIrradianceIntegral(const dipole::SurfaceBuffers& buf, const SslpvSurfaceKernel& kernel,
                              float r0, float r1, int samples, uint32_t seed, Out&& out) {
    const double area = PI_D * (double(r1) * double(r1) - double(r0) * double(r0));
    parallelFor(
        0, buf.height,
        [&](int64_t y0, int64_t y1) {
            for (int y = int(y0); y < int(y1); ++y)
                for (int x = 0; x < buf.width; ++x) {
                    const size_t idx = buf.index(x, y);
                    if (!buf.covered[idx])
                        continue;
                    const Point3f xo = buf.position[idx];
                    const Normal3f no = glm::normalize(buf.normal[idx]);
                    const Frame frame(no);
                    const Point2f shift = pixelShift(x, y, seed);
                    glm::dvec3 B(0.0);
                    for (int i = 0; i < samples && area > 0.0; ++i) {
                        const Point2f h = hammersley(uint32_t(i), uint32_t(samples));
                        const float u = h.x + shift.x - std::floor(h.x + shift.x);
                        const float v = h.y + shift.y - std::floor(h.y + shift.y);
                        const float r = r0 == 0.f ? r1 * std::sqrt(u)
                                                  : std::sqrt(r0 * r0 + u * (r1 * r1 - r0 * r0));
                        const float phi = 2.f * PI * v;
                        const Point3f p =
                            xo + r * (std::cos(phi) * frame.s + std::sin(phi) * frame.t);
                        Point2f px;
                        if (!buf.project(p, px))
                            continue;
                        const size_t j = buf.index(int(px.x), int(px.y));
                        if (!buf.covered[j])
                            continue;
                        const Rgb k = kernel.evaluate(r);
                        const Rgb& E = buf.irradiance[j];
                        B += glm::dvec3(k.r * E.r, k.g * E.g, k.b * E.b);
                    }
                    out(x, y, xo, no, B * (area / double(samples)));
                }
        },
        /*grain=*/1);
}

void checkLocalArgs(float splitRadius, int samples) {
    LUCENT_CHECK(std::isfinite(splitRadius) && splitRadius > 0.f,
                 "combined: the local estimate needs a finite split radius > 0 mm");
    LUCENT_CHECK(samples >= 1 && samples <= 4096,
                 "combined: localSamples must be in [1, 4096] (got ", samples, ")");
}

}  // namespace

ImageRgb localSslpvEstimate(const dipole::SurfaceBuffers& buf, const SslpvSurfaceKernel& kernel,
                            float splitRadius, float eta, int samples, uint32_t seed) {
    checkLocalArgs(splitRadius, samples);
    buf.validate();
    ImageRgb out(buf.width, buf.height);
    kernelIrradianceIntegral(
        buf, kernel, 0.f, splitRadius, samples, seed,
        [&](int x, int y, const Point3f& xo, const Normal3f& no, const glm::dvec3& B) {
            // Seed 004 Eq. 3: L = F_t(η, ω_o) B/π, the dipole's exit.
            const double cosO = std::max(0.0, double(glm::dot(no, buf.towardEye(xo))));
            const double ft = 1.0 - fresnelDielectric(cosO, eta);
            out.at(x, y) = Rgb(glm::vec3(B * (ft / PI_D)));
        });
    return out;
}

ImageRgb localSslpvFraction(const dipole::SurfaceBuffers& buf, const SslpvSurfaceKernel& kernel,
                            float splitRadius, int samples, uint32_t seed) {
    checkLocalArgs(splitRadius, samples);
    buf.validate();
    const float outer = kernel.ringOuter.empty() ? 0.f : kernel.ringOuter.back();
    ImageRgb nearPart(buf.width, buf.height), out(buf.width, buf.height);
    kernelIrradianceIntegral(buf, kernel, 0.f, splitRadius, samples, seed,
                             [&](int x, int y, const Point3f&, const Normal3f&,
                                 const glm::dvec3& B) { nearPart.at(x, y) = Rgb(glm::vec3(B)); });
    // The far annulus (r_s, ρ_last] with the same per-pixel shifts; empty when r_s ≥ ρ_last.
    const float r1 = std::max(outer, splitRadius);
    kernelIrradianceIntegral(
        buf, kernel, splitRadius, r1, samples, seed,
        [&](int x, int y, const Point3f&, const Normal3f&, const glm::dvec3& B) {
            const Rgb n = nearPart.at(x, y), all = n + Rgb(glm::vec3(B));
            Rgb f(0.f);
            for (int c = 0; c < 3; ++c)
                f[c] = all[c] > 0.f ? std::clamp(n[c] / all[c], 0.f, 1.f) : 0.f;
            out.at(x, y) = f;
        });
    return out;
}

// ---------------------------------------------------------------------------------------------
// The CPU renderer

float sslpvCellSize(const MaterialVolume& volume, int gridResolution) {
    const GridSpec& s = volume.spec();
    LUCENT_CHECK(gridResolution >= 1 && gridResolution <= s.resolution,
                 "combined: SSLPV grid resolution must be in [1, ", s.resolution, "] (got ",
                 gridResolution, ")");
    // The same cell edge resampleForPropagation gives the coarse grid (material/Resample.cpp).
    return s.voxelSize * float(s.resolution) / float(gridResolution);
}

sslpv::SslpvRenderOptions CombinedSettings::defaultSslpvOptions() {
    sslpv::SslpvRenderOptions o;
    o.solver.mode = sslpv::SslpvMode::Calibrated;
    o.direct = false;
    o.subsurface = true;
    return o;
}

CombinedResult renderCombined(const Scene& scene, const CombinedSettings& settings) {
    LUCENT_CHECK(!scene.objects.empty() && scene.objects[0].material != nullptr,
                 "combined: the scene needs an object with a material volume");
    LUCENT_CHECK(settings.localSamples >= 1 && settings.localSamples <= 4096,
                 "CombinedSettings.localSamples must be in [1, 4096] (got ", settings.localSamples,
                 ")");
    LUCENT_CHECK(std::isfinite(settings.farTolerance) && settings.farTolerance >= 0.f,
                 "CombinedSettings.farTolerance must be finite and >= 0 (got ",
                 settings.farTolerance, ")");
    const MaterialVolume& volume = *scene.objects[0].material;
    CombinedResult out;
    out.plan = planSplit(settings.splitRadius, sslpvCellSize(volume, settings.sslpv.gridResolution),
                         settings.sslpv.solver.skipAccumulateSteps, settings.sslpv.solver.maxSteps,
                         settings.mode);
    if (settings.autoSkipSslpv && out.plan.dipoleOn && out.plan.sslpvOn)
        applyFarSkip(out.plan,
                     volumeFarShare(settings.dipole.model, volume, scene.eta, out.plan.splitRadius,
                                    objectExtent(scene.objects[0].mesh)),
                     settings.farTolerance);
    const int w = scene.camera.width, h = scene.camera.height;
    out.dipole = ImageRgb(w, h);
    out.sslpv = ImageRgb(w, h);
    out.local = ImageRgb(w, h);
    if (out.plan.dipoleOn) {
        dipole::GatherSettings gs = settings.dipole;
        gs.maxRadius = out.plan.dipoleMaxRadius();
        dipole::LightViewSettings lv;
        lv.enabled = settings.dipoleLightViews;
        out.dipole = dipole::renderImageSpaceDipole(scene, gs, lv).radiance;
    }
    std::optional<sslpv::SslpvRenderer> sslpvPart;
    if (out.plan.sslpvOn) {
        sslpv::SslpvRenderOptions so = settings.sslpv;
        so.subsurface = true;
        so.direct = false;
        so.solver.skipAccumulateSteps = out.plan.skipSteps;
        // As renderSslpv, keeping the renderer: the Kernel split reads its albedo below.
        const SceneObject& object = scene.objects.front();
        sslpvPart.emplace(so);
        sslpvPart->setMesh(object.mesh);
        sslpvPart->setLights(scene.lights);
        sslpvPart->setMaterial(volume, scene.eta);
        out.sslpv = sslpvPart->render(scene.camera);
    }
    if (out.plan.mode == SplitMode::Kernel && out.plan.dipoleOn && out.plan.sslpvOn) {
        const MaterialSample kernelMaterial =
            surfaceMaterial(volume, surfaceShell(volume, out.plan.cellSize));
        const SslpvSurfaceKernel kernel = computeSslpvSurfaceKernel(
            kernelMaterial, scene.eta, settings.sslpv.solver, out.plan.cellSize,
            out.plan.splitRadius,
            meanIncidenceCosine(scene.objects[0].mesh, scene.lights, scene.eta));
        // SSLPV's local part: the kernel's estimate L̂, at most the kernel's near share f of
        // SSLPV's own radiance (docs/methods/combined.md, "The split's fix").
        const dipole::SurfaceBuffers buf = dipole::buildSurfaceBuffers(scene);
        const ImageRgb lhat = localSslpvEstimate(buf, kernel, out.plan.splitRadius, scene.eta,
                                                 settings.localSamples, settings.dipole.seed);
        const ImageRgb f = localSslpvFraction(buf, kernel, out.plan.splitRadius,
                                              settings.localSamples, settings.dipole.seed);
        // L̂ carried to the material at x_o: the albedo the SSLPV part's read-out sees there
        // (mode diffusion; the propagation modes read none and keep the kernel's) and the
        // surface's material within r_s. A homogeneous volume reads the kernel's own material
        // everywhere: the factor is 1 and is skipped, as on the GPU.
        const std::shared_ptr<const sslpv::ExactReflectanceRatio> table =
            sslpv::exactReflectanceRatio(scene.eta);
        const KernelSurfaceTerms kernelTerms =
            kernelSurfaceTerms(kernelMaterial, scene.eta, out.plan.splitRadius, *table);
        const sslpv::SslpvSolver& solver = sslpvPart->solver();
        const bool painted = !volume.isHomogeneous();
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = buf.index(x, y);
                Rgb lh = lhat.at(x, y);
                if (painted && buf.covered[i])
                    lh *= localScaleToSurfaceMaterial(
                        solver.readoutAlbedo(buf.position[i], glm::normalize(buf.normal[i])),
                        discMeanMaterial(buf, x, y, out.plan.splitRadius), kernelTerms, *table);
                out.local.at(x, y) = glm::min(lh, f.at(x, y) * out.sslpv.at(x, y));
            }
    }
    LUCENT_ASSERT(out.dipole.width() == w && out.sslpv.width() == w && out.local.width() == w);
    out.radiance = ImageRgb(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            out.radiance.at(x, y) =
                glm::max(out.dipole.at(x, y) + out.sslpv.at(x, y) - out.local.at(x, y), Rgb(0.f));
    return out;
}

}  // namespace lucent::combined
