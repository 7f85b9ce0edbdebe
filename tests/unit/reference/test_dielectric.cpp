// SPDX-License-Identifier: MIT
/// @file
/// @brief The reference path tracer at a smooth dielectric boundary, checked against an
/// independent forward light tracer (ForwardTracer.h: no shared transport code, analytic
/// geometry), a white furnace, reciprocity and closed forms. Tolerances are Z combined standard
/// errors measured from the samples, plus stated discretisation terms.

#include "ForwardTracer.h"
#include "TestScenes.h"

#include <lucent/core/Fresnel.h>
#include <lucent/core/Sampling.h>
#include <lucent/core/SphericalHarmonics.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/reference/Transport.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>

using namespace lucent;
using namespace lucent::reference;
using namespace lucent::test;
namespace fwd = lucent::test::forward;

namespace {

constexpr double Z = 5.0;  // tolerance in combined standard errors

/// Sample counts scale with LUCENT_VALIDATION_SCALE (default 1: the CI size; the benchmark-only
/// long run in docs/reference.md uses 16).
int scaled(int n) {
    const char* s = std::getenv("LUCENT_VALIDATION_SCALE");
    const double k = s ? std::max(0.01, std::atof(s)) : 1.0;
    return std::max(1, int(double(n) * k));
}

Vector3f fromPolar(double thetaDeg, double phiDeg) {
    const double t = thetaDeg * fwd::PI_D / 180.0, p = phiDeg * fwd::PI_D / 180.0;
    return Vector3f(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)),
                    float(std::cos(t)));
}

/// Uniform direction in the cone of half-angle acos(cosMax) around unit `axis` (pdf 1/Ω).
Vector3f inCone(const Vector3f& axis, double cosMax, Pcg32& rng) {
    const float cosT = 1.f - rng.uniform() * float(1.0 - cosMax);
    const float sinT = std::sqrt(std::max(0.f, 1.f - cosT * cosT));
    const float phi = 2.f * PI * rng.uniform();
    return glm::normalize(Frame(axis).toWorld({sinT * std::cos(phi), sinT * std::sin(phi), cosT}));
}

double coneSolidAngle(double cosMax) {
    return 2.0 * fwd::PI_D * (1.0 - cosMax);
}

// ---------------------------------------------------------------------------------------------
// Semi-infinite slab (medium at z < 0) under a directional light.
// ---------------------------------------------------------------------------------------------

struct SlabCase {
    double incidenceDeg, viewDeg, eta, albedo, g;
};

std::string describe(const SlabCase& c) {
    std::ostringstream s;
    s << "incidence " << c.incidenceDeg << "°, view " << c.viewDeg << "°, η " << c.eta
      << ", albedo " << c.albedo << ", g " << c.g;
    return s.str();
}

constexpr double SLAB_SIGMA_T = 1.0;    // mm⁻¹
constexpr double SLAB_E = 1.0;          // W/mm² on a surface facing the light
constexpr double VIEW_CONE_COS = 0.98;  // view cones of 11.5° half-angle

/// Forward estimate of Q = ∫_C L(ω)(ω·n) dω over the view cone (per unit area of surface):
/// E·cos θl × (fraction of photons leaving in C). Photon i enters at the origin (translation
/// invariance of the half-space).
MeanSe slabForward(const SlabCase& c, int photons, uint64_t seed) {
    fwd::Random rnd(seed);
    fwd::Medium m;
    m.sigma_t = SLAB_SIGMA_T;
    m.albedo = [&](const fwd::Vec&) { return c.albedo; };
    m.g = c.g;
    m.eta = c.eta;
    const fwd::Vec travel = -fwd::Vec(fromPolar(c.incidenceDeg, 0.0));
    const fwd::Vec view(fromPolar(c.viewDeg, 180.0));  // toward the viewer, on the far side
    const double scale = SLAB_E * -travel.z;
    MeanSe q;
    for (int i = 0; i < photons; ++i) {
        fwd::Vec d = travel;
        double tally = 0.0;
        if (fwd::enter(d, {0, 0, 1}, c.eta, rnd))
            fwd::walk(fwd::HalfSpace{}, m, fwd::Vec(0.0, 0.0, -1e-12), d, rnd,
                      [&](const fwd::Vec&, const fwd::Vec& out) {
                          if (glm::dot(out, view) >= VIEW_CONE_COS)
                              tally = scale;
                      });
        q.add(tally);
    }
    return q;
}

/// The path tracer's estimate of the same Q: radiance along rays of the cone, Q = Ω_C·E[L (ω·n)]
/// with ω uniform in C. The half-space is a box 2000 mm wide and 600 mm deep (a path reaching a
/// side face travels ≥ 1000 mean free paths: e^{-1000}).
VolumeScene slabScene(const SlabCase& c) {
    GridSpec spec;
    spec.origin = Point3f(-1000.f, -1000.f, -600.f);
    spec.voxelSize = 2000.f / 16.f;
    spec.resolution = 16;
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = -fromPolar(c.incidenceDeg, 0.0);
    sun.intensity = Rgb(float(SLAB_E));
    const float sigmaT = float(SLAB_SIGMA_T);
    return VolumeScene(
        boxMesh({-1000.f, -1000.f, -600.f}, {1000.f, 1000.f, 0.f}),
        GridMedium::uniform(spec, grey(sigmaT, float(c.albedo) * sigmaT, float(c.g)), {}), {sun});
}

MeanSe slabPathTracer(const SlabCase& c, int paths, uint64_t seed) {
    const VolumeScene scene = slabScene(c);
    TransportOptions to;
    to.boundary = BoundaryModel::Dielectric;
    to.eta = float(c.eta);
    to.subsurfaceOnly = true;
    const Vector3f view = fromPolar(c.viewDeg, 180.0);
    const double omega = coneSolidAngle(VIEW_CONE_COS);
    Pcg32 rng(seed);
    MeanSe q;
    for (int i = 0; i < paths; ++i) {
        const Vector3f w = inCone(view, VIEW_CONE_COS, rng);
        const Point3f at(20.f * rng.uniform() - 10.f, 20.f * rng.uniform() - 10.f, 0.f);
        const float l = estimateRadiance(scene, at + 5.f * w, -w, 0, rng, to);
        q.add(omega * double(l) * double(w.z));
    }
    return q;
}

void expectSlabAgrees(const SlabCase& c, int photons, int paths, uint64_t seed) {
    const MeanSe f = slabForward(c, photons, seed);
    const MeanSe p = slabPathTracer(c, paths, seed + 1);
    ASSERT_GT(f.mean(), 0.0) << describe(c);
    EXPECT_NEAR(p.mean(), f.mean(), Z * std::hypot(f.se(), p.se())) << describe(c);
    std::printf("  %-58s forward %.5f ± %.5f  path tracer %.5f ± %.5f  ratio %.4f\n",
                describe(c).c_str(), f.mean(), f.se(), p.mean(), p.se(), p.mean() / f.mean());
}

}  // namespace

TEST(DielectricSlab, AgreesWithForwardTracerAtEveryIncidenceAndView) {
    // η = 1.3, albedo 0.9, isotropic: incidence 0°, 60°, 80° (60° and 80° are past the 50.3°
    // critical angle of the straight connection, which saw nothing there), views 0°, 45°, 70°.
    uint64_t seed = 100;
    for (double incidence : {0.0, 60.0, 80.0})
        for (double view : {0.0, 45.0, 70.0})
            expectSlabAgrees({incidence, view, 1.3, 0.9, 0.0}, scaled(400000), scaled(16000),
                             seed += 2);
}

TEST(DielectricSlab, AgreesWithForwardTracerAcrossEtaAlbedoAndAnisotropy) {
    uint64_t seed = 200;
    for (const SlabCase& c :
         {SlabCase{60.0, 45.0, 1.8, 0.9, 0.0}, SlabCase{80.0, 0.0, 1.0, 0.9, 0.0},
          SlabCase{60.0, 70.0, 1.3, 0.5, 0.0}, SlabCase{80.0, 45.0, 1.3, 0.99, 0.0},
          SlabCase{60.0, 0.0, 1.3, 0.95, 0.8}, SlabCase{0.0, 70.0, 1.8, 0.95, 0.8}})
        expectSlabAgrees(c, scaled(400000), scaled(16000), seed += 2);
}

// The grazing-view cases that came out 1.5–4 % low (2–3 standard errors) in the scale-16 run of
// the two tests above, with eight times the samples and fresh seeds: a bias would stay, noise
// would shrink. Benchmark-only (minutes at scale 1): run with --gtest_also_run_disabled_tests.
TEST(DielectricSlab, DISABLED_GrazingViewsAtHighStatistics) {
    uint64_t seed = 900;
    for (const SlabCase& c :
         {SlabCase{60.0, 70.0, 1.3, 0.9, 0.0}, SlabCase{60.0, 70.0, 1.3, 0.5, 0.0},
          SlabCase{0.0, 70.0, 1.8, 0.95, 0.8}})
        expectSlabAgrees(c, scaled(8 * 400000), scaled(8 * 16000), seed += 2);
}

// ---------------------------------------------------------------------------------------------
// Sphere (radius 10 mm) under a directional or a point light, seen by an orthographic "camera":
// rings of equal area in the plane through the centre perpendicular to the view direction v.
// ---------------------------------------------------------------------------------------------

namespace {

constexpr double BALL_R = 10.0;  // mm
constexpr int RINGS = 4;
constexpr double BALL_VIEW_CONE_COS = 0.95;  // 18.2° half-angle: the sphere's bins are smaller
constexpr int SPHERE_SUBDIVISIONS = 6;       // 81 920 faces: normals within 0.6° of the sphere's

struct SphereCase {
    bool pointLight;  ///< point light at 30 mm along the light axis, else directional
    double lightDeg;  ///< light axis: polar angle from +z (azimuth 0)
    double viewDeg;   ///< view direction v: polar angle from +z (azimuth 180)
    double eta, albedoLeft, albedoRight, g;  ///< albedo for x < 0 and x > 0
};

std::string describe(const SphereCase& c) {
    std::ostringstream s;
    s << (c.pointLight ? "point" : "directional") << " light at " << c.lightDeg << "°, view "
      << c.viewDeg << "°, η " << c.eta << ", albedo " << c.albedoLeft << "/" << c.albedoRight
      << ", g " << c.g;
    return s.str();
}

constexpr double LIGHT_DISTANCE = 30.0;  // mm, point light
constexpr double POINT_I = 400.0;        // W/sr
constexpr double SUN_E = 1.0;            // W/mm²

/// Image-plane basis for view v: e1 in the xz-plane (so e1 = +x for v = +z), e2 = v × e1.
void imageBasis(const Vector3f& v, Vector3f& e1, Vector3f& e2) {
    e1 = glm::normalize(Vector3f(v.z, 0.f, -v.x));
    e2 = glm::cross(v, e1);
}

/// Ring bin of image radius ρ (rings of equal area), -1 outside the disc; `side` 0 for e1 < 0.
int ringOf(double rho) {
    if (rho >= BALL_R)
        return -1;
    return std::min(RINGS - 1, int(RINGS * (rho * rho) / (BALL_R * BALL_R)));
}

/// Forward tallies Q[side][ring] (flux, W) of rays leaving within the view cone.
std::array<std::array<MeanSe, RINGS>, 2> sphereForward(const SphereCase& c, int photons,
                                                       uint64_t seed) {
    fwd::Random rnd(seed);
    fwd::Medium m;
    m.sigma_t = 1.0;
    m.albedo = [&](const fwd::Vec& p) { return p.x < 0.0 ? c.albedoLeft : c.albedoRight; };
    m.g = c.g;
    m.eta = c.eta;
    const fwd::Ball ball{fwd::Vec(0.0), BALL_R};
    const fwd::Vec axis(fromPolar(c.lightDeg, 0.0));  // from the centre toward the light
    const fwd::Vec view(fromPolar(c.viewDeg, 180.0));
    Vector3f e1f, e2f;
    imageBasis(Vector3f(view), e1f, e2f);
    const fwd::Vec e1(e1f), e2(e2f);
    // Frame around the light axis for emission.
    const fwd::Vec a = std::abs(axis.x) < 0.9 ? fwd::Vec(1, 0, 0) : fwd::Vec(0, 1, 0);
    const fwd::Vec t1 = glm::normalize(glm::cross(a, axis)), t2 = glm::cross(axis, t1);
    const double cosMax = std::sqrt(1.0 - BALL_R * BALL_R / (LIGHT_DISTANCE * LIGHT_DISTANCE));
    const double photonFlux = c.pointLight ? POINT_I * 2.0 * fwd::PI_D * (1.0 - cosMax)
                                           : SUN_E * fwd::PI_D * BALL_R * BALL_R;
    std::array<std::array<MeanSe, RINGS>, 2> q{};
    for (int i = 0; i < photons; ++i) {
        fwd::Vec origin, d;
        if (c.pointLight) {
            origin = LIGHT_DISTANCE * axis;
            const double ct = 1.0 - rnd() * (1.0 - cosMax), st = std::sqrt(1.0 - ct * ct);
            const double phi = 2.0 * fwd::PI_D * rnd();
            d = glm::normalize(-ct * axis + st * (std::cos(phi) * t1 + std::sin(phi) * t2));
        } else {
            const double r = BALL_R * std::sqrt(rnd()), phi = 2.0 * fwd::PI_D * rnd();
            origin = 3.0 * BALL_R * axis + r * (std::cos(phi) * t1 + std::sin(phi) * t2);
            d = -axis;
        }
        // Entry point on the sphere (the near intersection).
        const double b = glm::dot(origin, d), cc = glm::dot(origin, origin) - BALL_R * BALL_R;
        const double disc = b * b - cc;
        int hitSide = -1, hitRing = -1;
        if (disc > 0.0) {
            const fwd::Vec p = origin + (-b - std::sqrt(disc)) * d;
            if (fwd::enter(d, glm::normalize(p), c.eta, rnd))
                fwd::walk(ball, m, p - 1e-12 * glm::normalize(p), d, rnd,
                          [&](const fwd::Vec& out, const fwd::Vec& w) {
                              const double wv = glm::dot(w, view);
                              if (wv < BALL_VIEW_CONE_COS)
                                  return;
                              const fwd::Vec onPlane = out - (glm::dot(out, view) / wv) * w;
                              const double x = glm::dot(onPlane, e1), y = glm::dot(onPlane, e2);
                              hitRing = ringOf(std::hypot(x, y));
                              hitSide = x < 0.0 ? 0 : 1;
                          });
        }
        for (int s = 0; s < 2; ++s)
            for (int k = 0; k < RINGS; ++k)
                q[s][k].add(s == hitSide && k == hitRing ? photonFlux : 0.0);
    }
    return q;
}

/// The path tracer's Q[side][ring] = A·Ω_C·E[L (ω·v)] over rays of the bin (q uniform in the
/// half ring, ω uniform in the view cone), on an icosphere inscribed in the ball.
std::array<std::array<MeanSe, RINGS>, 2> spherePathTracer(const SphereCase& c, int paths,
                                                          uint64_t seed) {
    GridSpec spec;
    spec.origin = Point3f(-12.f);
    spec.voxelSize = 1.5f;  // a voxel face at x = 0 splits the halves exactly
    spec.resolution = 16;
    const float sigmaT = 1.f;
    const GridMedium medium = gridFrom(spec.origin, spec.voxelSize, spec.resolution,
                                       [&](int i, int, int) {
                                           const double albedo =
                                               i < 8 ? c.albedoLeft : c.albedoRight;
                                           return grey(sigmaT, float(albedo) * sigmaT, float(c.g));
                                       },
                                       {});
    Light light;
    const Vector3f axis = fromPolar(c.lightDeg, 0.0);
    if (c.pointLight) {
        light.type = Light::Type::Point;
        light.position = float(LIGHT_DISTANCE) * axis;
        light.intensity = Rgb(float(POINT_I));
    } else {
        light.type = Light::Type::Directional;
        light.direction = -axis;
        light.intensity = Rgb(float(SUN_E));
    }
    const VolumeScene scene(makeSphere(float(BALL_R), SPHERE_SUBDIVISIONS), medium, {light});
    TransportOptions to;
    to.boundary = BoundaryModel::Dielectric;
    to.eta = float(c.eta);
    to.subsurfaceOnly = true;
    const Vector3f view = fromPolar(c.viewDeg, 180.0);
    Vector3f e1, e2;
    imageBasis(view, e1, e2);
    const double omega = coneSolidAngle(BALL_VIEW_CONE_COS);
    const double halfRingArea = 0.5 * fwd::PI_D * BALL_R * BALL_R / RINGS;
    Pcg32 rng(seed);
    std::array<std::array<MeanSe, RINGS>, 2> q{};
    for (int s = 0; s < 2; ++s)
        for (int k = 0; k < RINGS; ++k)
            for (int i = 0; i < paths; ++i) {
                const double r2 = BALL_R * BALL_R * (double(k) + rng.uniform()) / RINGS;
                const double phi = fwd::PI_D * (rng.uniform() + 0.5) + (s ? fwd::PI_D : 0.0);
                const Point3f onPlane =
                    float(std::sqrt(r2)) * (float(std::cos(phi)) * e1 + float(std::sin(phi)) * e2);
                const Vector3f w = inCone(view, BALL_VIEW_CONE_COS, rng);
                const float l =
                    estimateRadiance(scene, onPlane + float(3.0 * BALL_R) * w, -w, 0, rng, to);
                q[s][k].add(halfRingArea * omega * double(l) * double(glm::dot(w, view)));
            }
    return q;
}

void expectSphereAgrees(const SphereCase& c, int photons, int paths, uint64_t seed) {
    const auto f = sphereForward(c, photons, seed);
    const auto p = spherePathTracer(c, paths, seed + 1);
    std::printf("  %s\n", describe(c).c_str());
    for (int s = 0; s < 2; ++s)
        for (int k = 0; k < RINGS; ++k) {
            const MeanSe& a = f[s][k];
            const MeanSe& b = p[s][k];
            EXPECT_NEAR(b.mean(), a.mean(), Z * std::hypot(a.se(), b.se()))
                << describe(c) << ", half " << s << ", ring " << k;
            std::printf(
                "    half %d ring %d  forward %.5f ± %.5f  path tracer %.5f ± %.5f  "
                "ratio %.4f\n",
                s, k, a.mean(), a.se(), b.mean(), b.se(), b.mean() / a.mean());
        }
}

}  // namespace

TEST(DielectricSphere, DirectionalLightAgreesWithForwardTracer) {
    expectSphereAgrees({false, 0.0, 0.0, 1.3, 0.95, 0.95, 0.0}, scaled(600000), scaled(2000), 300);
    expectSphereAgrees({false, 0.0, 60.0, 1.3, 0.95, 0.95, 0.8}, scaled(600000), scaled(2000), 310);
}

TEST(DielectricSphere, PointLightAgreesWithForwardTracer) {
    expectSphereAgrees({true, 30.0, 0.0, 1.8, 0.9, 0.9, 0.0}, scaled(600000), scaled(2000), 400);
}

TEST(DielectricSphere, HeterogeneousHalvesAgreeWithForwardTracer) {
    expectSphereAgrees({false, 20.0, 0.0, 1.3, 0.7, 0.98, 0.0}, scaled(600000), scaled(2000), 500);
}

// ---------------------------------------------------------------------------------------------
// Closed forms and invariants.
// ---------------------------------------------------------------------------------------------

TEST(DielectricClosedForm, ObliqueSingleScatteringThroughTheSurface) {
    // Optically thick slab (σt·d = 16) under a directional light at incidence θl, seen at θv,
    // one scattering event (maxScatter = 1). Inside, the light travels at θl' (Snell) with the
    // irradiance E·(1 − F(θl))·cos θl / cos θl' across its beam, the camera ray at θv', and
    //   L1 = (1 − F(θv))/η² · σs·p_HG(cos Θ)·E⊥ / (σt·(1 + μv'/μl'))·(1 − e^{−σt d (1/μv' +
    //   1/μl')})
    // with μ' = cos θ' and Θ the angle between the two inside directions (the single-scattering
    // solution of Chandrasekhar 1960 §1.4 with the refracted geometry; the 1/η² is the radiance
    // scaling of the camera ray leaving the denser medium). At 60° and 80° incidence the old
    // straight shadow connection met total internal reflection and returned exactly 0.
    const float sigmaT = 0.8f, sigmaS = 0.6f, d = 20.f, g = 0.4f, eta = 1.3f;
    GridSpec spec;
    spec.origin = Point3f(-100.f, -100.f, -100.f);
    spec.voxelSize = 12.5f;
    spec.resolution = 16;
    uint64_t seed = 700;
    for (double incidence : {0.0, 60.0, 80.0}) {
        for (double view : {0.0, 50.0, 70.0}) {
            Light sun;
            sun.type = Light::Type::Directional;
            const Vector3f towardLight = fromPolar(incidence, 0.0);
            sun.direction = -towardLight;
            sun.intensity = Rgb(2.f);
            const VolumeScene scene(
                boxMesh({-100, -100, -d}, {100, 100, 0}),
                GridMedium::uniform(spec, grey(sigmaT, sigmaS, g), {MajorantMode::Bricks, false}),
                {sun});
            TransportOptions to;
            to.boundary = BoundaryModel::Dielectric;
            to.eta = eta;
            to.maxScatter = 1;
            to.subsurfaceOnly = true;
            const Vector3f towardCamera = fromPolar(view, 150.0);
            // Inside directions (travel): light, and the camera ray reversed.
            const auto refractIn = [&](const Vector3f& travel) {
                const double c = -travel.z, r = 1.0 / eta;
                const double ct = std::sqrt(1.0 - r * r * (1.0 - c * c));
                return glm::dvec3(travel) * r + (r * c - ct) * glm::dvec3(0, 0, 1);
            };
            const glm::dvec3 lightIn = refractIn(-towardLight);
            const glm::dvec3 cameraIn = refractIn(-towardCamera);  // camera ray travelling in
            const double muL = -lightIn.z, muV = -cameraIn.z;
            const double fl = fresnelDielectric(float(towardLight.z), float(eta));
            const double fv = fresnelDielectric(float(towardCamera.z), float(eta));
            const double eBeam = 2.0 * (1.0 - fl) * towardLight.z / muL;
            // Θ: light travel direction against the direction back toward the camera.
            const double cosTheta = glm::dot(lightIn, -cameraIn);
            const double expected = (1.0 - fv) / (double(eta) * eta) * sigmaS *
                                    hgPhase(g, float(cosTheta)) * eBeam /
                                    (sigmaT * (1.0 + muV / muL)) *
                                    (1.0 - std::exp(-sigmaT * d * (1.0 / muV + 1.0 / muL)));
            Pcg32 rng(seed++);
            MeanSe l;
            for (int i = 0; i < scaled(20000); ++i)
                l.add(estimateRadiance(scene, 10.f * towardCamera, -towardCamera, 0, rng, to));
            EXPECT_NEAR(l.mean(), expected, Z * l.se())
                << "incidence " << incidence << "°, view " << view << "°";
        }
    }
}

TEST(DielectricFurnace, NonAbsorbingObjectInUniformLightHasItsRadiance) {
    // White furnace: albedo 1 everywhere, a uniform environment of radiance L. In equilibrium
    // the radiance is L outside and η²·L inside (L/n² is invariant), so every camera ray that
    // meets the object, reflected or transmitted, carries exactly L: this checks the Fresnel
    // split, the 1/η² scaling and the refracted next-event estimation of the environment
    // together. Heterogeneous σt and g (0.6 / −0.3), η = 1.3; the surface reflection is kept.
    const auto white = [](int i, int j, int k) {
        const float s = 0.4f + 0.3f * float((i * 7 + j * 3 + k * 5) % 4);
        return grey(s, s, (i + j + k) % 2 == 0 ? 0.6f : -0.3f);
    };
    const GridMedium m = gridFrom({-6, -6, -6}, 0.75f, 16, white, {MajorantMode::Bricks, true});
    const Rgb sky(0.7f, 1.f, 1.3f);
    const VolumeScene scene(makeSphere(5.f, 4), m, {}, sky);
    TransportOptions to;
    to.boundary = BoundaryModel::Dielectric;
    to.eta = 1.3f;
    Pcg32 rng(801);
    MeanSe l[3];
    for (int i = 0; i < scaled(6000); ++i) {
        // Rays from a point on a 12 mm sphere toward a random point of the object's disc.
        const Vector3f from = glm::normalize(
            Vector3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f));
        const Point3f o = 12.f * from;
        const Vector3f target =
            Vector3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) * 6.f;
        const Rgb v = estimateRadianceRgb(scene, o, glm::normalize(target - o), i % 3, rng, to);
        for (int c = 0; c < 3; ++c)
            l[c].add(v[c]);
    }
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(l[c].mean(), sky[c], Z * l[c].se()) << "channel " << c;
}

TEST(DielectricSlab, StraightApproximationLosesTheLightPastTheCriticalAngle) {
    // The issue this estimator fixes, kept as a check that the comparison has teeth: at 60°
    // incidence the straight shadow connection leaves the slab past the 50.3° critical angle
    // and sees nothing, while light does refract in (the exact estimator above agrees with the
    // forward tracer there).
    const VolumeScene scene = slabScene({60.0, 0.0, 1.3, 0.9, 0.0});
    TransportOptions to;
    to.boundary = BoundaryModel::Straight;
    to.eta = 1.3f;
    to.subsurfaceOnly = true;
    Pcg32 rng(950);
    for (int i = 0; i < 2000; ++i)
        ASSERT_EQ(estimateRadiance(scene, {0.f, 0.f, 5.f}, {0.f, 0.f, -1.f}, 0, rng, to), 0.f);
    to.boundary = BoundaryModel::Dielectric;
    MeanSe exact;
    for (int i = 0; i < 2000; ++i)
        exact.add(estimateRadiance(scene, {0.f, 0.f, 5.f}, {0.f, 0.f, -1.f}, 0, rng, to));
    EXPECT_GT(exact.mean(), 10.0 * exact.se());
}

// ---------------------------------------------------------------------------------------------
// A 10 mm box of optically thin medium: light that enters a face near an edge meets the side
// faces past the critical angle and is totally reflected, so here light reaches a scattering
// point through internal reflections before and after it scatters. Image-plane bins: a 2×2
// grid over [−8, 8]² mm in the plane through the centre perpendicular to v.
// ---------------------------------------------------------------------------------------------

namespace {

constexpr int BOX_BINS = 2;
constexpr double BOX_HALF = 5.0, BOX_GRID_HALF = 8.0;

struct BoxCase {
    double lightPolarDeg, lightAzimuthDeg, viewPolarDeg, viewAzimuthDeg;
    double sigmaT, albedo, eta;
};

std::string describe(const BoxCase& c) {
    std::ostringstream s;
    s << "light (" << c.lightPolarDeg << "°, " << c.lightAzimuthDeg << "°), view ("
      << c.viewPolarDeg << "°, " << c.viewAzimuthDeg << "°), σt " << c.sigmaT << ", albedo "
      << c.albedo << ", η " << c.eta;
    return s.str();
}

int boxBin(double u, double v) {
    const auto cell = [](double w) {
        return int(std::floor((w + BOX_GRID_HALF) / (2.0 * BOX_GRID_HALF) * BOX_BINS));
    };
    const int i = cell(u), j = cell(v);
    return i < 0 || j < 0 || i >= BOX_BINS || j >= BOX_BINS ? -1 : j * BOX_BINS + i;
}

std::array<MeanSe, BOX_BINS * BOX_BINS> boxForward(const BoxCase& c, int photons, uint64_t seed) {
    fwd::Random rnd(seed);
    fwd::Medium m;
    m.sigma_t = c.sigmaT;
    m.albedo = [&](const fwd::Vec&) { return c.albedo; };
    m.eta = c.eta;
    const fwd::Box box{fwd::Vec(-BOX_HALF), fwd::Vec(BOX_HALF)};
    const fwd::Vec axis(fromPolar(c.lightPolarDeg, c.lightAzimuthDeg));
    const fwd::Vec view(fromPolar(c.viewPolarDeg, c.viewAzimuthDeg));
    Vector3f e1f, e2f;
    imageBasis(Vector3f(view), e1f, e2f);
    const fwd::Vec e1(e1f), e2(e2f);
    const fwd::Vec a = std::abs(axis.x) < 0.9 ? fwd::Vec(1, 0, 0) : fwd::Vec(0, 1, 0);
    const fwd::Vec t1 = glm::normalize(glm::cross(a, axis)), t2 = glm::cross(axis, t1);
    const double discR = BOX_HALF * std::sqrt(3.0) * 1.001;
    const double photonFlux = SUN_E * fwd::PI_D * discR * discR;
    std::array<MeanSe, BOX_BINS * BOX_BINS> q{};
    for (int i = 0; i < photons; ++i) {
        const double r = discR * std::sqrt(rnd()), phi = 2.0 * fwd::PI_D * rnd();
        const fwd::Vec origin = 30.0 * axis + r * (std::cos(phi) * t1 + std::sin(phi) * t2);
        fwd::Vec d = -axis;
        int hit = -1;
        const double t = box.entryDistance(origin, d);
        if (t >= 0.0) {
            const fwd::Vec p = origin + t * d;
            const fwd::Vec n = box.normal(p);
            if (fwd::enter(d, n, c.eta, rnd))
                fwd::walk(box, m, p - 1e-12 * n, d, rnd,
                          [&](const fwd::Vec& out, const fwd::Vec& w) {
                              const double wv = glm::dot(w, view);
                              if (wv < BALL_VIEW_CONE_COS)
                                  return;
                              const fwd::Vec onPlane = out - (glm::dot(out, view) / wv) * w;
                              hit = boxBin(glm::dot(onPlane, e1), glm::dot(onPlane, e2));
                          });
        }
        for (int b = 0; b < BOX_BINS * BOX_BINS; ++b)
            q[size_t(b)].add(b == hit ? photonFlux : 0.0);
    }
    return q;
}

std::array<MeanSe, BOX_BINS * BOX_BINS> boxPathTracer(const BoxCase& c, int paths, uint64_t seed) {
    GridSpec spec;
    spec.origin = Point3f(-6.f);
    spec.voxelSize = 0.75f;
    spec.resolution = 16;
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = -fromPolar(c.lightPolarDeg, c.lightAzimuthDeg);
    sun.intensity = Rgb(float(SUN_E));
    const float sigmaT = float(c.sigmaT);
    const VolumeScene scene(boxMesh(Point3f(float(-BOX_HALF)), Point3f(float(BOX_HALF))),
                            GridMedium::uniform(spec, grey(sigmaT, float(c.albedo) * sigmaT), {}),
                            {sun});
    TransportOptions to;
    to.boundary = BoundaryModel::Dielectric;
    to.eta = float(c.eta);
    to.subsurfaceOnly = true;
    const Vector3f view = fromPolar(c.viewPolarDeg, c.viewAzimuthDeg);
    Vector3f e1, e2;
    imageBasis(view, e1, e2);
    const double omega = coneSolidAngle(BALL_VIEW_CONE_COS);
    const double cell = 2.0 * BOX_GRID_HALF / BOX_BINS;
    Pcg32 rng(seed);
    std::array<MeanSe, BOX_BINS * BOX_BINS> q{};
    for (int b = 0; b < BOX_BINS * BOX_BINS; ++b)
        for (int i = 0; i < paths; ++i) {
            const double u = -BOX_GRID_HALF + cell * (b % BOX_BINS + rng.uniform());
            const double v = -BOX_GRID_HALF + cell * (b / BOX_BINS + rng.uniform());
            const Point3f onPlane = float(u) * e1 + float(v) * e2;
            const Vector3f w = inCone(view, BALL_VIEW_CONE_COS, rng);
            const float l = estimateRadiance(scene, onPlane + 30.f * w, -w, 0, rng, to);
            q[size_t(b)].add(cell * cell * omega * double(l) * double(glm::dot(w, view)));
        }
    return q;
}

void expectBoxAgrees(const BoxCase& c, int photons, int paths, uint64_t seed) {
    const auto f = boxForward(c, photons, seed);
    const auto p = boxPathTracer(c, paths, seed + 1);
    std::printf("  %s\n", describe(c).c_str());
    double sumF = 0.0, sumP = 0.0, varF = 0.0, varP = 0.0;
    for (int b = 0; b < BOX_BINS * BOX_BINS; ++b) {
        const MeanSe& a = f[size_t(b)];
        const MeanSe& t = p[size_t(b)];
        sumF += a.mean();
        sumP += t.mean();
        varF += a.se() * a.se();
        varP += t.se() * t.se();
        if (a.mean() == 0.0 && t.mean() == 0.0)
            continue;
        EXPECT_NEAR(t.mean(), a.mean(), Z * std::hypot(a.se(), t.se()))
            << describe(c) << ", bin " << b;
        std::printf("    bin %2d  forward %.5f ± %.5f  path tracer %.5f ± %.5f  ratio %.4f\n", b,
                    a.mean(), a.se(), t.mean(), t.se(), t.mean() / a.mean());
    }
    // The total over the image, where the statistics are best.
    EXPECT_NEAR(sumP, sumF, Z * std::sqrt(varF + varP)) << describe(c) << ", all bins";
    std::printf("    all      forward %.5f ± %.5f  path tracer %.5f ± %.5f  ratio %.4f\n", sumF,
                std::sqrt(varF), sumP, std::sqrt(varP), sumP / sumF);
}

}  // namespace

TEST(DielectricBox, TotalInternalReflectionAgreesWithForwardTracer) {
    // η = 1 checks the box itself; at η = 1.3 and 1.8, without the specular chains the path
    // tracer was 5 % and 16 % too dark (the light reaching a scattering point through internal
    // reflections).
    expectBoxAgrees({50.0, 45.0, 40.0, 200.0, 0.3, 0.6, 1.0}, scaled(2000000), scaled(16000), 990);
    expectBoxAgrees({30.0, 20.0, 0.0, 0.0, 0.5, 0.9, 1.3}, scaled(2000000), scaled(16000), 1000);
    expectBoxAgrees({50.0, 45.0, 40.0, 200.0, 0.3, 0.6, 1.8}, scaled(2000000), scaled(16000), 1010);
}
