// SPDX-License-Identifier: MIT
/// @file
/// @brief CPU image-space dipole integration (seed 004 §5–7).

#include <lucent/dipole/ImageSpace.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Sampling.h>
#include <lucent/dipole/Sampling.h>

#include <array>
#include <cmath>

namespace lucent::dipole {
namespace {

constexpr double PI_D = 3.14159265358979323846;
constexpr float SIGMA_LIMIT = 1e6f;

float fract(float v) {
    return v - std::floor(v);
}

/// Per-pixel material state: three channel profiles, their samplers and the disc radius R′.
struct PixelMaterial {
    MaterialSample key;
    bool valid = false;
    std::array<DipoleProfile, 3> profile;
    std::array<DipoleSampler, 3> sampler;
    std::array<int, 3> channels{};  // channels whose sampler is valid
    int channelCount = 0;
    double discRadius = 0.0;

    void build(const MaterialSample& m, const GatherSettings& gs, const Boundary& b) {
        key = m;
        valid = true;
        channelCount = 0;
        discRadius = 0.0;
        for (int c = 0; c < 3; ++c) {
            const ScalarMedium med = fromReduced(m.sigma_t[c], m.sigma_s[c], gs.eta);
            profile[c] = DipoleProfile::make(gs.model, med.sigma_a, med.sigma_s, b);
            sampler[c] = DipoleSampler(profile[c]);
            if (!sampler[c].isValid())
                continue;
            channels[channelCount++] = c;
            // R′: quantile of the virtual source, which bounds the mixture's quantile from above.
            discRadius = std::max(discRadius, sampleSourceRadius(profile[c].sigmaTr(),
                                                                 profile[c].zv(), gs.discQuantile));
        }
    }
};

}  // namespace

void SurfaceBuffers::resize(int w, int h) {
    LUCENT_CHECK(w >= 1 && h >= 1 && w <= 16384 && h <= 16384,
                 "SurfaceBuffers: size must be in [1, 16384]² (got ", w, "x", h, ")");
    width = w;
    height = h;
    const size_t n = size_t(w) * size_t(h);
    position.assign(n, Point3f(0.f));
    normal.assign(n, Normal3f(0.f, 0.f, 1.f));
    irradiance.assign(n, Rgb(0.f));
    material.assign(n, MaterialSample{});
    covered.assign(n, 0);
}

bool SurfaceBuffers::project(const Point3f& p, Point2f& pixel) const {
    const glm::vec4 clip = clipFromWorld * glm::vec4(p, 1.f);
    if (!(clip.w > 0.f))
        return false;
    const float nx = clip.x / clip.w, ny = clip.y / clip.w;
    pixel = {(nx * 0.5f + 0.5f) * float(width), (0.5f - ny * 0.5f) * float(height)};
    return pixel.x >= 0.f && pixel.y >= 0.f && pixel.x < float(width) && pixel.y < float(height);
}

Vector3f SurfaceBuffers::towardEye(const Point3f& p) const {
    if (orthographic)
        return -glm::normalize(viewDirection);
    const Vector3f d = eye - p;
    const float l = glm::length(d);
    return l > 0.f ? d / l : Vector3f(0.f, 0.f, 1.f);
}

void SurfaceBuffers::validate() const {
    const size_t n = size_t(width) * size_t(height);
    LUCENT_CHECK(width >= 1 && height >= 1, "SurfaceBuffers: empty (", width, "x", height, ")");
    LUCENT_CHECK(position.size() == n, "SurfaceBuffers.position: ", position.size(),
                 " entries, expected ", n);
    LUCENT_CHECK(normal.size() == n, "SurfaceBuffers.normal: ", normal.size(),
                 " entries, expected ", n);
    LUCENT_CHECK(irradiance.size() == n, "SurfaceBuffers.irradiance: ", irradiance.size(),
                 " entries, expected ", n);
    LUCENT_CHECK(material.size() == n, "SurfaceBuffers.material: ", material.size(),
                 " entries, expected ", n);
    LUCENT_CHECK(covered.size() == n, "SurfaceBuffers.covered: ", covered.size(),
                 " entries, expected ", n);
    LUCENT_CHECK(
        orthographic ? glm::length(viewDirection) > 0.f : isFinite(eye),
        "SurfaceBuffers: orthographic needs a nonzero viewDirection, perspective a finite eye");
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t i = index(x, y);
            if (!covered[i])
                continue;
            LUCENT_CHECK(isFinite(position[i]), "SurfaceBuffers.position at pixel (", x, ",", y,
                         ") is not finite");
            LUCENT_CHECK(isFinite(normal[i]) && glm::length(normal[i]) > 0.5f,
                         "SurfaceBuffers.normal at pixel (", x, ",", y, ") is not a unit vector");
            const Rgb& e = irradiance[i];
            LUCENT_CHECK(isFinite(e) && e.r >= 0.f && e.g >= 0.f && e.b >= 0.f,
                         "SurfaceBuffers.irradiance at pixel (", x, ",", y,
                         ") must be finite and >= 0");
            const MaterialSample& m = material[i];
            for (int c = 0; c < 3; ++c)
                LUCENT_CHECK(std::isfinite(m.sigma_t[c]) && std::isfinite(m.sigma_s[c]) &&
                                 m.sigma_s[c] >= 0.f && m.sigma_s[c] <= m.sigma_t[c] &&
                                 m.sigma_t[c] <= SIGMA_LIMIT,
                             "SurfaceBuffers.material at pixel (", x, ",", y,
                             "): need 0 <= sigma_s' <= sigma_t <= 1e6 mm^-1, finite");
        }
}

std::vector<std::array<float, 5>> interleaveShifts(const GatherSettings& gs) {
    // Interleaved sampling (Keller & Heidrich 2001, seed 004 §6.1): a k×k table of
    // Cranley–Patterson shifts; pixel (x, y) uses shift (x mod k, y mod k) on one shared set.
    std::vector<std::array<float, 5>> shifts(size_t(gs.interleave) * size_t(gs.interleave));
    Pcg32 rng(gs.seed, 0x5eed);
    for (auto& s : shifts)
        for (float& v : s)
            v = rng.uniform();
    return shifts;
}

Boundary validateGather(const SurfaceBuffers& buf, const GatherSettings& gs) {
    LUCENT_CHECK(gs.model != Model::Directional,
                 "gatherImageSpace: model 'dirpole' needs incident directions; use the light-view "
                 "directional pipeline (supported here: dipole, better-dipole)");
    LUCENT_CHECK(
        gs.importanceSamples >= 0 && gs.importanceSamples <= 65536 && gs.uniformSamples >= 0 &&
            gs.uniformSamples <= 65536 && gs.importanceSamples + gs.uniformSamples >= 1,
        "GatherSettings: importanceSamples/uniformSamples must be in [0, 65536], sum >= 1");
    LUCENT_CHECK(gs.discQuantile > 0.f && gs.discQuantile < 1.f,
                 "GatherSettings.discQuantile must be in (0, 1) (got ", gs.discQuantile, ")");
    LUCENT_CHECK(gs.maxJacobian >= 1.f && std::isfinite(gs.maxJacobian),
                 "GatherSettings.maxJacobian must be finite and >= 1");
    LUCENT_CHECK(gs.interleave >= 1 && gs.interleave <= 64,
                 "GatherSettings.interleave must be in [1, 64]");
    const Boundary boundary = Boundary::of(gs.eta);
    buf.validate();
    return boundary;
}

void exitanceToRadiance(const SurfaceBuffers& buf, float eta, GatherResult& out) {
    out.radiance = ImageRgb(buf.width, buf.height);
    for (int y = 0; y < buf.height; ++y)
        for (int x = 0; x < buf.width; ++x) {
            const size_t idx = buf.index(x, y);
            if (!buf.covered[idx])
                continue;
            const Normal3f no = glm::normalize(buf.normal[idx]);
            // Eq. 3: L = F_t(η, ω_o) B/π, F_t = 1 − F_r for the exit direction.
            const double cosO =
                std::max(0.0, double(glm::dot(no, buf.towardEye(buf.position[idx]))));
            const float ft = float(1.0 - fresnelReflectance(cosO, eta));
            out.radiance.at(x, y) = out.exitance.at(x, y) * (ft * INV_PI);
        }
}

GatherResult gatherImageSpace(const SurfaceBuffers& buf, const GatherSettings& gs) {
    const Boundary boundary = validateGather(buf, gs);
    const int k = gs.interleave;
    const std::vector<std::array<float, 5>> shifts = interleaveShifts(gs);

    GatherResult out;
    out.exitance = ImageRgb(buf.width, buf.height);
    const int nImp = gs.importanceSamples, nUni = gs.uniformSamples;

    parallelFor(
        0, buf.height,
        [&](int64_t y0, int64_t y1) {
            PixelMaterial pm;
            for (int y = int(y0); y < int(y1); ++y)
                for (int x = 0; x < buf.width; ++x) {
                    const size_t idx = buf.index(x, y);
                    if (!buf.covered[idx])
                        continue;
                    const MaterialSample& mat = buf.material[idx];
                    if (!pm.valid || !(pm.key == mat))
                        pm.build(mat, gs, boundary);
                    if (pm.channelCount == 0)
                        continue;
                    const Point3f xo = buf.position[idx];
                    const Normal3f no = glm::normalize(buf.normal[idx]);
                    const Frame frame(no);
                    const auto& shift = shifts[size_t(y % k) * k + size_t(x % k)];
                    const double R = pm.discRadius;
                    const double pUniform = nUni > 0 && R > 0.0 ? 1.0 / (PI_D * R * R) : 0.0;
                    // Number of importance samples per channel technique (round robin).
                    std::array<int, 3> nChan{0, 0, 0};
                    for (int i = 0; i < nImp; ++i)
                        ++nChan[size_t(pm.channels[size_t(i % pm.channelCount)])];

                    glm::dvec3 B(0.0);
                    const auto addSample = [&](double rPlane, float phi) {
                        const Point3f pPlane = xo + float(rPlane) * (std::cos(phi) * frame.s +
                                                                     std::sin(phi) * frame.t);
                        Point2f px;
                        if (!buf.project(pPlane, px))
                            return;
                        const size_t j = buf.index(int(px.x), int(px.y));
                        if (!buf.covered[j])
                            return;
                        const Rgb& E = buf.irradiance[j];
                        if (E == Rgb(0.f))
                            return;  // unlit (shadowed) sample: contributes exactly 0
                        // Reconstruct the surface point: the eye ray through p′ meets the fetched
                        // pixel's tangent plane (exact on planar regions; "location p_i on the
                        // surface from the depth texture", §6.2).
                        Point3f p = buf.position[j];
                        const Normal3f np = glm::normalize(buf.normal[j]);
                        const Point3f origin = buf.orthographic ? pPlane : buf.eye;
                        const Vector3f dir = buf.orthographic ? glm::normalize(buf.viewDirection)
                                                              : glm::normalize(pPlane - buf.eye);
                        const float denom = glm::dot(dir, np);
                        if (std::abs(denom) > 0.1f)
                            p = origin + dir * (glm::dot(p - origin, np) / denom);
                        const double r = glm::length(glm::dvec3(p - xo));
                        // Eq. 8–9 Jacobian |dA_p/dA_p′| = (cos α′/cos α)(d²/d′²) from equal solid
                        // angles δA_p cos α/d² = δA_p′ cos α′/d′² (α at p, α′ at p′, d = |e − p|).
                        double J = 1.0;
                        if (gs.jacobian) {
                            const double cosA = std::abs(glm::dot(np, buf.towardEye(p)));
                            const double cosAp = std::abs(glm::dot(no, buf.towardEye(pPlane)));
                            double ratio = 1.0;
                            if (!buf.orthographic) {
                                const double d = glm::length(buf.eye - p),
                                             dp = glm::length(buf.eye - pPlane);
                                ratio = dp > 0.0 ? (d * d) / (dp * dp) : 1.0;
                            }
                            J = cosA > 1e-6 ? std::min(double(gs.maxJacobian), cosAp / cosA * ratio)
                                            : double(gs.maxJacobian);
                        }
                        // Multi-sample balance heuristic over the channel techniques and the disc
                        // (Veach 1997; seed 004 §6.1): weight/pdf = 1/Σ_t n_t p_t(x).
                        double denomPdf = rPlane <= R ? nUni * pUniform : 0.0;
                        for (int c = 0; c < 3; ++c)
                            if (nChan[size_t(c)] > 0)
                                denomPdf +=
                                    nChan[size_t(c)] * pm.sampler[size_t(c)].pdfArea(rPlane);
                        if (!(denomPdf > 0.0))
                            return;
                        const double w = J / denomPdf;
                        for (int c = 0; c < 3; ++c)
                            B[c] += pm.profile[size_t(c)].Rd(r) * double(E[c]) * w;
                    };
                    for (int i = 0; i < nImp; ++i) {
                        const Point2f h = hammersley(uint32_t(i), uint32_t(nImp));
                        const float uSrc = fract(halton(uint32_t(i), 3) + shift[0]);
                        const float uR = fract(h.x + shift[1]), uPhi = fract(h.y + shift[2]);
                        const int c = pm.channels[size_t(i % pm.channelCount)];
                        addSample(pm.sampler[size_t(c)].sample(uSrc, uR), 2.f * PI * uPhi);
                    }
                    for (int i = 0; i < nUni && R > 0.0; ++i) {
                        const Point2f h = hammersley(uint32_t(i), uint32_t(nUni));
                        const float uR = fract(h.x + shift[3]), uPhi = fract(h.y + shift[4]);
                        addSample(R * std::sqrt(double(uR)), 2.f * PI * uPhi);
                    }
                    out.exitance.at(x, y) = Rgb(float(B.x), float(B.y), float(B.z));
                }
        },
        /*grain=*/1);
    exitanceToRadiance(buf, gs.eta, out);
    return out;
}

}  // namespace lucent::dipole
