// SPDX-License-Identifier: MIT
/// @file
/// @brief CPU directional-dipole pipeline (the dirpole thesis §4, Frisvad et al. 2014 BSSRDF).

#include <lucent/core/Fresnel.h>
#include <lucent/dipole/DirectionalPipeline.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Sampling.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/dipole/Sampling.h>
#include <lucent/reference/MeshBoundary.h>

#include <array>
#include <cmath>
#include <vector>

namespace lucent::dipole {

namespace {

/// The G-buffer shrink ε_g (Frisvad et al. 2014, §4.3.1) at a point, kept within one mean free
/// path 1/σt′ of the surface: the shrink only keeps the disc centre off the discretised
/// surface, and pushing it deeper than the dipole's own real source (depth 1/σt′) makes S_d
/// vanish in optically dense media (σt′ = 10⁴ mm⁻¹ went black with the fixed 0.05 mm). The
/// GL gather (shaders/dirpole_gather.comp) applies the same bound.
float shrinkWithin(float shrink, const Rgb& sigmaT) {
    const float densest = std::max(sigmaT.r, std::max(sigmaT.g, sigmaT.b));
    return densest > 0.f ? std::min(shrink, 1.f / densest) : shrink;
}

}  // namespace

struct DirectionalDipoleRenderer::Impl {
    Scene scene;
    DirectionalSettings settings;
    SurfaceBuffers buffers;
    std::unique_ptr<reference::MeshBoundary> boundary;
    std::vector<glm::dvec3> sum;  // per pixel, Σ over passes
    int passes = 0;
    float sceneRadius = 1.f;
    Point3f sceneCenter{0.f};
    DirpoleEnergyTable energy;  ///< for scene.eta when settings.energyNormalised
    /// With the exact target: the exit-angle and incidence corrections (empty, 1, otherwise).
    DirpoleExitTable exit;
    DirpoleIncidenceTable incidence;
};

DirectionalDipoleRenderer::DirectionalDipoleRenderer(const Scene& scene,
                                                     const DirectionalSettings& s)
    : m_impl(std::make_unique<Impl>()) {
    LUCENT_CHECK(s.samplesPerPass >= 1 && s.samplesPerPass <= 65536,
                 "DirectionalSettings.samplesPerPass must be in [1, 65536]");
    LUCENT_CHECK(s.shrink >= 0.f && std::isfinite(s.shrink),
                 "DirectionalSettings.shrink must be >= 0 mm");
    for (const Light& l : scene.lights)
        LUCENT_CHECK(
            l.type == Light::Type::Directional,
            "DirectionalDipoleRenderer: only directional lights are supported (light type ",
            int(l.type), ")");
    LUCENT_CHECK(scene.eta >= 1.f && scene.eta <= 3.f,
                 "DirectionalDipoleRenderer: scene eta must be in [1, 3]");
    m_impl->scene = scene;
    m_impl->settings = s;
    m_impl->buffers = buildSurfaceBuffers(scene);
    m_impl->boundary = std::make_unique<reference::MeshBoundary>(scene.objects[0].mesh);
    m_impl->sum.assign(m_impl->buffers.position.size(), glm::dvec3(0.0));
    const Bounds3f b = m_impl->boundary->bounds();
    m_impl->sceneCenter = b.center();
    m_impl->sceneRadius = 0.5f * glm::length(b.extent()) + 1.f;
    if (s.energyNormalised)
        m_impl->energy = *DirpoleEnergyTable::shared(double(scene.eta), s.energyTarget);
    if (s.energyNormalised && s.energyTarget == EnergyTarget::ExactHalfSpace) {
        m_impl->exit = *DirpoleExitTable::shared(double(scene.eta));
        m_impl->incidence = *DirpoleIncidenceTable::shared(double(scene.eta));
    }
}

DirectionalDipoleRenderer::~DirectionalDipoleRenderer() = default;

int DirectionalDipoleRenderer::passes() const {
    return m_impl->passes;
}
const SurfaceBuffers& DirectionalDipoleRenderer::buffers() const {
    return m_impl->buffers;
}

void DirectionalDipoleRenderer::addPass() {
    Impl& m = *m_impl;
    const SurfaceBuffers& buf = m.buffers;
    const float eta = m.scene.eta;
    const Boundary bd = Boundary::of(eta);
    const int k = m.settings.samplesPerPass;
    const uint32_t pass = uint32_t(m.passes);
    parallelFor(0, buf.height, [&](int64_t y0, int64_t y1) {
        MaterialSample lastMat;
        bool haveMat = false;
        std::array<DirectionalDipole, 3> dd;
        std::array<DipoleSampler, 3> samplers;
        std::array<int, 3> channels{};
        std::array<double, 3> alphaPrime{};
        int channelCount = 0;
        float shrink = m.settings.shrink;
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < buf.width; ++x) {
                const size_t idx = buf.index(x, y);
                if (!buf.covered[idx])
                    continue;
                const MaterialSample& mat = buf.material[idx];
                if (!haveMat || !(mat == lastMat)) {
                    channelCount = 0;
                    shrink = shrinkWithin(m.settings.shrink, mat.sigma_t);
                    for (int c = 0; c < 3; ++c) {
                        const ScalarMedium med = fromReduced(mat.sigma_t[c], mat.sigma_s[c], eta);
                        // Energy-normalised S_d (DirectionalSettings::energyNormalised): the
                        // table is empty (scale 1) when normalisation is off.
                        const double alphaP =
                            med.sigma_s > 0.0 ? med.sigma_s / (med.sigma_a + med.sigma_s) : 0.0;
                        alphaPrime[size_t(c)] = alphaP;
                        dd[size_t(c)] = DirectionalDipole(med.sigma_a, med.sigma_s, med.eta,
                                                          m.energy.scale(alphaP));
                        // Importance function: the better dipole's exact sampler (same D and
                        // σ_tr as the directional dipole), Mertens et al. 2005 §4.
                        samplers[size_t(c)] = DipoleSampler(
                            DipoleProfile::make(Model::BetterDipole, med.sigma_a, med.sigma_s, bd));
                        if (samplers[size_t(c)].isValid() && !dd[size_t(c)].isZero())
                            channels[size_t(channelCount++)] = c;
                    }
                    lastMat = mat;
                    haveMat = true;
                }
                if (channelCount == 0)
                    continue;
                std::array<int, 3> nChan{0, 0, 0};
                for (int i = 0; i < k; ++i)
                    ++nChan[size_t(channels[size_t(i % channelCount)])];
                const Point3f xo = buf.position[idx];
                const Normal3f no = glm::normalize(buf.normal[idx]);
                const Vector3f toEye = buf.towardEye(xo);
                const double cosO = std::max(0.0, double(glm::dot(no, toEye)));
                const double t21 = 1.0 - fresnelDielectric(cosO, eta);  // T₂₁(ω_o)
                // Per-pixel Cranley–Patterson offset of the R2 sequence (deterministic per seed)
                // and a per-pixel, per-pass stream for the source choice.
                Pcg32 rng(pixelSeed(uint32_t(x), uint32_t(y), 0, m.settings.seed));
                const Point2f offset(rng.uniform(), rng.uniform());
                Pcg32 sourceRng(pixelSeed(uint32_t(x), uint32_t(y), pass + 1, m.settings.seed));
                glm::dvec3 L(0.0);
                for (const Light& light : m.scene.lights) {
                    const Vector3f wl = glm::normalize(light.direction);  // direction light travels
                    // Seed 001 §4.3.1: shrink x_o towards the inside, across the light direction.
                    const Point3f xs = xo - shrink * (no - (-wl) * glm::dot(-wl, no));
                    const Frame lf(wl);
                    for (int i = 0; i < k; ++i) {
                        const Point2f u = r2Sequence(pass * uint32_t(k) + uint32_t(i), offset);
                        const int ch = channels[size_t(i % channelCount)];
                        const double r = samplers[size_t(ch)].sample(sourceRng.uniform(), u.x);
                        const float phi = 2.f * PI * u.y;
                        // Multi-sample balance heuristic over the channels' samplers:
                        // weight/pdf = 1/Σ_c n_c p_c(r), p_c per unit light-plane area.
                        double denom = 0.0;
                        for (int c = 0; c < 3; ++c)
                            if (nChan[size_t(c)] > 0)
                                denom += nChan[size_t(c)] * samplers[size_t(c)].pdfArea(r);
                        if (!(denom > 0.0))
                            continue;
                        // Ray along the light direction through the sample (light-view G-buffer).
                        const Point3f onPlane =
                            xs + float(r) * (std::cos(phi) * lf.s + std::sin(phi) * lf.t);
                        const Point3f origin =
                            onPlane -
                            wl * (2.f * m.sceneRadius + glm::length(onPlane - m.sceneCenter));
                        const auto hit = m.boundary->intersect(origin, wl, 0.f, INF);
                        if (!hit)
                            continue;
                        const Point3f xi = origin + hit->t * wl;
                        const Normal3f ni = hit->normal;
                        const float cosI = -glm::dot(ni, wl);
                        if (cosI <= 0.f)
                            continue;
                        // Refracted direction ω₁₂ (Snell, relative index 1/η from outside).
                        const float sin2T = (1.f - cosI * cosI) / (eta * eta);
                        const float cosT = std::sqrt(std::max(0.f, 1.f - sin2T));
                        const Vector3f w12 = glm::normalize(wl / eta + (cosI / eta - cosT) * ni);
                        const double t12 =
                            1.0 - fresnelDielectric(double(cosI), double(eta));  // T₁₂(ω_i)
                        for (int c = 0; c < 3; ++c) {
                            // The exact target's incidence correction (1 without it).
                            const double sd =
                                dd[size_t(c)].Sd(glm::dvec3(xi), glm::dvec3(ni), glm::dvec3(w12),
                                                 glm::dvec3(xo), glm::dvec3(no)) *
                                m.incidence.correction(alphaPrime[size_t(c)], double(cosT));
                            // L = ∫ E⊥ T₁₂ S_d dA⊥ (dA⊥ = cos θ_i dA: light-plane area).
                            L[c] += double(light.intensity[c]) * t12 * sd / denom;
                        }
                    }
                }
                // The exact target's exit-angle correction (1 without it): the light leaves
                // x_o with the half-space's angular distribution, not a diffuse one.
                for (int c = 0; c < 3; ++c)
                    L[c] *= m.exit.correction(alphaPrime[size_t(c)], cosO);
                m.sum[idx] += L * t21;
            }
    });
    ++m.passes;
}

ImageRgb DirectionalDipoleRenderer::radiance() const {
    const Impl& m = *m_impl;
    ImageRgb out(m.buffers.width, m.buffers.height);
    if (m.passes == 0)
        return out;
    for (size_t i = 0; i < m.sum.size(); ++i)
        out.pixels()[i] = Rgb(m.sum[i] / double(m.passes));
    return out;
}

}  // namespace lucent::dipole
