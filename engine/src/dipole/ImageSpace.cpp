// SPDX-License-Identifier: MIT
/// @file
/// @brief CPU image-space dipole integration (Mertens et al. 2005 §5–7).

#include <lucent/core/Fresnel.h>
#include <lucent/dipole/ImageSpace.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Sampling.h>
#include <lucent/dipole/Sampling.h>

#include <array>
#include <cmath>
#include <limits>

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
    /// The light views' samplers: conditioned on the disc A′ (r′ ≤ discRadius, Mertens et al. 2005
    /// §5; docs/methods/dipole.md §3d "Light views sample the disc A′").
    std::array<DipoleSampler, 3> lightSampler;
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
            // Local-radius window: the sampler conditioned on r ≤ maxRadius (renormalised pdf).
            sampler[c] = DipoleSampler(profile[c]).truncated(double(gs.maxRadius));
            if (!sampler[c].isValid())
                continue;
            channels[channelCount++] = c;
            // R′: quantile of the virtual source, which bounds the mixture's quantile from above.
            discRadius = std::max(discRadius, sampleSourceRadius(profile[c].sigmaTr(),
                                                                 profile[c].zv(), gs.discQuantile));
        }
        if (gs.maxRadius > 0.f)
            discRadius = std::min(discRadius, double(gs.maxRadius));
        for (int c = 0; c < 3; ++c)
            lightSampler[c] = DipoleSampler(profile[c]).truncated(discRadius);
    }
};

/// The surface point an irradiance image shows "behind" a point p′: the pixel containing p′'s
/// projection, with the image's ray through p′ intersected with that pixel's tangent plane
/// (exact on planar regions; "location p_i on the surface from the depth texture", Mertens et al.
/// 2005 §6.2).
struct ImageHit {
    size_t pixel = 0;
    Point3f p{0.f};
    Normal3f n{0.f, 0.f, 1.f};
};

bool lookUp(const SurfaceBuffers& buf, const Point3f& pPlane, ImageHit& hit) {
    Point2f px;
    if (!buf.project(pPlane, px))
        return false;
    hit.pixel = buf.index(int(px.x), int(px.y));
    if (!buf.covered[hit.pixel])
        return false;
    hit.p = buf.position[hit.pixel];
    hit.n = glm::normalize(buf.normal[hit.pixel]);
    const Point3f origin = buf.orthographic ? pPlane : buf.eye;
    const Vector3f dir =
        buf.orthographic ? glm::normalize(buf.viewDirection) : glm::normalize(pPlane - buf.eye);
    const float denom = glm::dot(dir, hit.n);
    if (std::abs(denom) > 0.1f)
        hit.p = origin + dir * (glm::dot(hit.p - origin, hit.n) / denom);
    return true;
}

/// Eq. 8–9 Jacobian |dA_p/dA_p′| = (cos α′/cos α)(d²/d′²) of an image, from equal solid angles
/// δA_p cos α/d² = δA_p′ cos α′/d′² (α at p, α′ at p′, d = |e − p|), clamped to maxJacobian.
double areaJacobian(const SurfaceBuffers& buf, const Point3f& p, const Normal3f& np,
                    const Point3f& pPlane, const Normal3f& no, const GatherSettings& gs) {
    if (!gs.jacobian)
        return 1.0;
    const double cosA = std::abs(glm::dot(np, buf.towardEye(p)));
    const double cosAp = std::abs(glm::dot(no, buf.towardEye(pPlane)));
    double ratio = 1.0;
    if (!buf.orthographic) {
        const double d = glm::length(buf.eye - p), dp = glm::length(buf.eye - pPlane);
        ratio = dp > 0.0 ? (d * d) / (dp * dp) : 1.0;
    }
    return cosA > 1e-6 ? std::min(double(gs.maxJacobian), cosAp / cosA * ratio)
                       : double(gs.maxJacobian);
}

/// World size (mm) of one pixel of `buf` at point x. The linear part of clipFromWorld's row 1
/// is the projection's P₁₁ times a unit row of the view rotation, so its length is P₁₁
/// (perspective: 1/tan(fov/2); orthographic: 2/view height) and one pixel spans
/// 2·w/(P₁₁·height) at clip w (the view depth; 1 for orthographic). 0 behind the view.
double pixelFootprint(const SurfaceBuffers& buf, const Point3f& x) {
    const Mat4f& m = buf.clipFromWorld;
    const double p11 = glm::length(glm::dvec3(m[0][1], m[1][1], m[2][1]));
    const double w = buf.orthographic ? 1.0 : double((m * glm::vec4(x, 1.f)).w);
    return w > 0.0 && p11 > 0.0 ? 2.0 * w / (p11 * double(buf.height)) : 0.0;
}

/// Is surface point x (found through another image, where one pixel spans `footprintOther` mm)
/// visible in `buf`? The same rule as the gather's own look-up (the pixel containing x is
/// covered and its tangent-plane point along the ray through x is x), with a tolerance of one
/// pixel footprint of each image for the two tangent-plane reconstructions of the surface.
bool visibleIn(const SurfaceBuffers& buf, const Point3f& x, double footprintOther) {
    ImageHit h;
    if (!lookUp(buf, x, h))
        return false;
    const double tol = pixelFootprint(buf, x) + footprintOther;
    return glm::length(glm::dvec3(h.p - x)) <= tol;
}

/// Where image `buf`'s ray through surface point x meets the tangent plane of x_o.
bool tangentPlanePoint(const SurfaceBuffers& buf, const Point3f& x, const Point3f& xo,
                       const Normal3f& no, Point3f& pPlane) {
    const Vector3f dir = -buf.towardEye(x);
    const float cosine = glm::dot(dir, no);
    if (std::abs(cosine) < 1e-4f)
        return false;
    pPlane = x + dir * (glm::dot(xo - x, no) / cosine);
    Point2f px;
    return buf.project(pPlane, px);
}

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
    // Interleaved sampling (Keller & Heidrich 2001, Mertens et al. 2005 §6.1): a k×k table of
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
    LUCENT_CHECK(std::isfinite(gs.maxRadius) && gs.maxRadius >= 0.f,
                 "GatherSettings.maxRadius must be finite and >= 0 mm (0 = unlimited; got ",
                 gs.maxRadius, ")");
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
            const float ft = float(1.0 - fresnelDielectric(cosO, eta));
            out.radiance.at(x, y) = out.exitance.at(x, y) * (ft * INV_PI);
        }
}

ViewSamples viewSamples(int importance, int uniform, int views, int view) {
    LUCENT_CHECK(views >= 1 && view >= 0 && view < views && importance >= 0 && uniform >= 0,
                 "viewSamples: need 0 <= view < views and counts >= 0 (got view ", view, " of ",
                 views, ")");
    // Samples g = 0 … N−1 (importance first, then uniform) go to view g mod V: the number of
    // g < n with g ≡ view (mod V).
    const auto below = [&](int n) { return n > view ? (n - view - 1) / views + 1 : 0; };
    ViewSamples a;
    a.importance = below(importance);
    a.uniform = below(importance + uniform) - a.importance;
    if (a.importance + a.uniform == 0)
        a.importance = 1;  // fewer samples than views: every view keeps its support
    return a;
}

GatherResult gatherImageSpace(const SurfaceBuffers& buf, const GatherSettings& gs) {
    return gatherImageSpace(buf, {}, gs);
}

double backlitFluxFraction(const SurfaceBuffers& cam, const SurfaceBuffers& light,
                           const GatherSettings& gs) {
    const Boundary boundary = validateGather(cam, gs);
    light.validate();
    std::vector<double> rowTotal(size_t(light.height), 0.0), rowBack(size_t(light.height), 0.0);
    parallelFor(0, light.height, [&](int64_t y0, int64_t y1) {
        PixelMaterial pm;
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < light.width; ++x) {
                const size_t i = light.index(x, y);
                const Rgb& E = light.irradiance[i];
                if (!light.covered[i] || E == Rgb(0.f))
                    continue;
                const Point3f p = light.position[i];
                const Normal3f n = glm::normalize(light.normal[i]);
                // Flux through the texel: E·dA, dA = footprint²/cos α (α: normal vs the ray).
                const double fp = pixelFootprint(light, p);
                const double cosA =
                    std::max(0.05, double(std::abs(glm::dot(n, light.towardEye(p)))));
                const double flux = double(luminance(E)) * fp * fp / cosA;
                rowTotal[size_t(y)] += flux;
                ImageHit front;
                if (!lookUp(cam, p, front))
                    continue;  // outside the camera's image: not in front of any gathered pixel
                const double dist = glm::length(glm::dvec3(front.p - p));
                if (dist <= pixelFootprint(cam, p) + fp)
                    continue;  // the camera sees this point: the camera image holds its E
                const MaterialSample& m = cam.material[front.pixel];
                if (!pm.valid || !(pm.key == m))
                    pm.build(m, gs, boundary);
                if (dist <= pm.discRadius)
                    rowBack[size_t(y)] += flux;
            }
    });
    double total = 0.0, back = 0.0;
    for (int y = 0; y < light.height; ++y) {
        total += rowTotal[size_t(y)];
        back += rowBack[size_t(y)];
    }
    return total > 0.0 ? back / total : 0.0;
}

GatherResult gatherImageSpace(const SurfaceBuffers& buf, const std::vector<SurfaceBuffers>& lights,
                              const GatherSettings& gs) {
    const Boundary boundary = validateGather(buf, gs);
    for (size_t l = 0; l < lights.size(); ++l) {
        try {
            lights[l].validate();
        } catch (const ValueError& e) {
            LUCENT_THROW(ValueError, "gatherImageSpace: light view ", l, ": ", e.what());
        }
    }
    const int k = gs.interleave;
    const std::vector<std::array<float, 5>> shifts = interleaveShifts(gs);
    // Image 0 is the camera's, images 1.. the light views.
    std::vector<const SurfaceBuffers*> views{&buf};
    for (const SurfaceBuffers& l : lights)
        views.push_back(&l);
    const int viewCount = int(views.size());

    GatherResult out;
    out.exitance = ImageRgb(buf.width, buf.height);
    out.stats.epsilon = 1.0 - double(gs.discQuantile);
    out.stats.lightViews = int(lights.size());
    const int nImp = gs.importanceSamples, nUni = gs.uniformSamples;
    const double window =
        gs.maxRadius > 0.f ? double(gs.maxRadius) : std::numeric_limits<double>::infinity();
    std::vector<double> rowMin(size_t(buf.height), std::numeric_limits<double>::infinity()),
        rowMax(size_t(buf.height), 0.0);
    std::vector<int> rowCount(size_t(buf.height), 0);

    parallelFor(
        0, buf.height,
        [&](int64_t y0, int64_t y1) {
            PixelMaterial pm;
            std::vector<ViewSamples> alloc(static_cast<size_t>(viewCount));
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
                    rowMin[size_t(y)] = std::min(rowMin[size_t(y)], R);
                    rowMax[size_t(y)] = std::max(rowMax[size_t(y)], R);
                    ++rowCount[size_t(y)];
                    const double pUniform = R > 0.0 ? 1.0 / (PI_D * R * R) : 0.0;
                    // The pixel's budget split over the views (viewSamples, §3d) and, per view,
                    // the importance samples per channel technique (round robin).
                    for (int v = 0; v < viewCount; ++v) {
                        ViewSamples& a = alloc[size_t(v)];
                        a = viewSamples(nImp, R > 0.0 ? nUni : 0, viewCount, v);
                        a.perChannel = {0, 0, 0};
                        for (int i = 0; i < a.importance; ++i)
                            ++a.perChannel[size_t(pm.channels[size_t(i % pm.channelCount)])];
                    }
                    // Multi-sample balance heuristic over view v's techniques (the channel
                    // samplers and the disc; Veach 1997 Eq. 9.13, Mertens et al. 2005 §6.1): Σ_t
                    // n_t p_t at tangent-plane radius r′, with view v's sample counts n_t.
                    const auto techniquePdf = [&](int v, double rPlane) {
                        const ViewSamples& a = alloc[size_t(v)];
                        double sum = rPlane <= R ? a.uniform * pUniform : 0.0;
                        const auto& samplers = v == 0 ? pm.sampler : pm.lightSampler;
                        for (int c = 0; c < 3; ++c)
                            if (a.perChannel[size_t(c)] > 0)
                                sum +=
                                    a.perChannel[size_t(c)] * samplers[size_t(c)].pdfArea(rPlane);
                        return sum;
                    };

                    glm::dvec3 B(0.0);
                    const auto addSample = [&](int view, double rPlane, float phi) {
                        const SurfaceBuffers& img = *views[size_t(view)];
                        const Point3f pPlane = xo + float(rPlane) * (std::cos(phi) * frame.s +
                                                                     std::sin(phi) * frame.t);
                        ImageHit hit;
                        if (!lookUp(img, pPlane, hit))
                            return;
                        if (view == 0 && hit.pixel == idx) {
                            // x_o's own pixel: its tangent plane is x_o's, which holds p′, so
                            // the eye ray through p′ meets it at p′ itself (r = r′) at any
                            // angle. lookUp's fallback for grazing rays (|cos| ≤ 0.1: the
                            // pixel's point) gave r = 0, R_d(0) over the whole grazing
                            // footprint: the issue-6 edge outlier (docs/methods/dipole.md §3).
                            hit.p = pPlane;
                            hit.n = no;
                        }
                        const Rgb& E = img.irradiance[hit.pixel];
                        if (E == Rgb(0.f))
                            return;  // unlit (shadowed) sample: contributes exactly 0
                        const double r = glm::length(glm::dvec3(hit.p - xo));
                        if (r > window)
                            return;  // outside the local-radius window (GatherSettings)
                        const double J = areaJacobian(img, hit.p, hit.n, pPlane, no, gs);
                        const double own = techniquePdf(view, rPlane);
                        if (!(own > 0.0) || !(J > 0.0))
                            return;
                        // Balance heuristic across the views' techniques in surface-area measure
                        // (Mertens et al. 2005 §7.1; Veach 1997 Eq. 9.13 with sample counts): view
                        // j reaches hit.p with density q_j = Σ_t n_jt p_t(r′_j)/J_j, r′_j where its
                        // ray through hit.p meets the tangent plane, if hit.p is visible in view j;
                        // the sample counts f/Σ_j q_j. One view: J/Σ_t n_t p_t (§3).
                        double w = J / own;
                        if (viewCount > 1) {
                            double sum = own / J;
                            const double footprint = pixelFootprint(img, hit.p);
                            for (int j = 0; j < viewCount; ++j) {
                                if (j == view)
                                    continue;
                                const SurfaceBuffers& other = *views[size_t(j)];
                                Point3f pj;
                                if (!visibleIn(other, hit.p, footprint) ||
                                    !tangentPlanePoint(other, hit.p, xo, no, pj))
                                    continue;
                                const double Jj = areaJacobian(other, hit.p, hit.n, pj, no, gs);
                                if (Jj > 0.0)
                                    sum += techniquePdf(j, glm::length(glm::dvec3(pj - xo))) / Jj;
                            }
                            w = 1.0 / sum;
                        }
                        for (int c = 0; c < 3; ++c)
                            B[c] += pm.profile[size_t(c)].Rd(r) * double(E[c]) * w;
                    };
                    for (int v = 0; v < viewCount; ++v) {
                        // View v's share of the sample set: its own Hammersley points,
                        // Cranley–Patterson-rotated by v times the golden ratio (view 0 without
                        // light views = the camera gather of §3 unchanged).
                        const float rot = float(v) * 0.61803398875f;
                        const int vImp = alloc[size_t(v)].importance;
                        const int vUni = alloc[size_t(v)].uniform;
                        for (int i = 0; i < vImp; ++i) {
                            const Point2f h = hammersley(uint32_t(i), uint32_t(vImp));
                            const float uSrc = fract(halton(uint32_t(i), 3) + shift[0] + rot);
                            const float uR = fract(h.x + shift[1] + rot),
                                        uPhi = fract(h.y + shift[2] + rot);
                            const int c = pm.channels[size_t(i % pm.channelCount)];
                            const DipoleSampler& smp =
                                v == 0 ? pm.sampler[size_t(c)] : pm.lightSampler[size_t(c)];
                            addSample(v, smp.sample(uSrc, uR), 2.f * PI * uPhi);
                        }
                        for (int i = 0; i < vUni; ++i) {
                            const Point2f h = hammersley(uint32_t(i), uint32_t(vUni));
                            const float uR = fract(h.x + shift[3] + rot),
                                        uPhi = fract(h.y + shift[4] + rot);
                            addSample(v, R * std::sqrt(double(uR)), 2.f * PI * uPhi);
                        }
                    }
                    out.exitance.at(x, y) = Rgb(float(B.x), float(B.y), float(B.z));
                }
        },
        /*grain=*/1);
    for (int y = 0; y < buf.height; ++y) {
        if (rowCount[size_t(y)] == 0)
            continue;
        out.stats.minRadius = out.stats.pixels == 0
                                  ? rowMin[size_t(y)]
                                  : std::min(out.stats.minRadius, rowMin[size_t(y)]);
        out.stats.maxRadius = std::max(out.stats.maxRadius, rowMax[size_t(y)]);
        out.stats.pixels += rowCount[size_t(y)];
    }
    exitanceToRadiance(buf, gs.eta, out);
    return out;
}

}  // namespace lucent::dipole
