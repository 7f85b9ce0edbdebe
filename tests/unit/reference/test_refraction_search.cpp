// SPDX-License-Identifier: MIT
/// @file
/// @brief RefractionSearch: completeness against a brute-force solve written independently here
/// (2-D Newton on Fermat's optical path over each face's plane), Snell's law and the pencil's
/// irradiance gain of every solution, and the unbiasedness of the local search with stochastic
/// completion.

#include "TestScenes.h"

#include <lucent/core/Random.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/reference/MeshBoundary.h>
#include <lucent/reference/RefractionSearch.h>

#include <gtest/gtest.h>

#include <map>
#include <optional>

using namespace lucent;
using namespace lucent::reference;
using namespace lucent::test;

namespace {

using Vec = glm::dvec3;

/// Light source of a query: a point, or light travelling along a unit direction.
struct Source {
    bool isDirection = false;
    Vec value{0.0};
};

/// Independent solve on the plane of triangle (a, b, c): the refraction point minimises the
/// optical path |p − L| + η|x − p| (point) or ωl·p + η|x − p| (direction: the plane-wave
/// phase), a strictly convex function on the plane (Fermat). 2-D Newton in plane coordinates.
/// Returns the point and its signed distance inside the triangle (> 0 inside, mm).
std::optional<std::pair<Vec, double>> bruteForce(const Vec& a, const Vec& b, const Vec& c,
                                                 const Source& s, const Vec& x, double eta) {
    const Vec n = glm::normalize(glm::cross(b - a, c - a));
    if (glm::dot(x - a, n) >= 0.0)
        return std::nullopt;  // x must be inside (below the plane)
    if (s.isDirection ? glm::dot(s.value, n) >= 0.0 : glm::dot(s.value - a, n) <= 0.0)
        return std::nullopt;  // the source must light the outside of the plane
    const Vec u = glm::normalize(b - a), v = glm::cross(n, u);
    Vec p = a + glm::dot(x - a, u) * u + glm::dot(x - a, v) * v;  // x's foot
    double gradient = INFINITY;
    for (int it = 0; it < 200; ++it) {
        // Gradient and Hessian (in the plane) of η|x − p| + the source term.
        glm::dmat3 H(0.0);
        Vec g(0.0);
        const auto addDistance = [&](const Vec& q, double w) {  // w·|p − q|
            const Vec d = p - q;
            const double r = glm::length(d);
            const Vec e = d / r;
            g += w * e;
            H += (w / r) * (glm::dmat3(1.0) - glm::outerProduct(e, e));
        };
        addDistance(x, eta);
        if (s.isDirection)
            g += s.value;  // the phase ωl·p of the plane wave
        else
            addDistance(s.value, 1.0);
        const double gu = glm::dot(g, u), gv = glm::dot(g, v);
        gradient = std::hypot(gu, gv);
        const double huu = glm::dot(u, H * u), huv = glm::dot(u, H * v), hvv = glm::dot(v, H * v);
        const double det = huu * hvv - huv * huv;
        const double du = -(hvv * gu - huv * gv) / det, dv = -(-huv * gu + huu * gv) / det;
        p += du * u + dv * v;
        if (std::hypot(du, dv) < 1e-13)
            break;
    }
    // A stationary point is Snell's law; without one (η < 1 past the critical angle the
    // functional is unbounded below) there is no refraction.
    if (!(gradient < 1e-9))
        return std::nullopt;
    // Signed distance to the triangle's edges (minimum over the three inward distances).
    double inside = INFINITY;
    const Vec vs[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
        const Vec e = vs[(k + 1) % 3] - vs[k];
        inside = std::min(inside, glm::dot(glm::cross(e, p - vs[k]), n) / glm::length(e));
    }
    return std::make_pair(p, inside);
}

Point3f insidePoint(const MeshBoundary& boundary, const Bounds3f& box, Pcg32& rng) {
    for (;;) {
        const Point3f x =
            box.lo + Vector3f(rng.uniform(), rng.uniform(), rng.uniform()) * box.extent();
        // Inside: an odd number of crossings along +z.
        int crossings = 0;
        Point3f o = x;
        while (const std::optional<SurfaceHit> h = boundary.intersect(o, {0, 0, 1}, 0.f, INF)) {
            ++crossings;
            o += Vector3f(0, 0, 1) * (h->t + 1e-4f);
        }
        if (crossings % 2 == 1)
            return x;
    }
}

struct Solved {
    Refraction r;
    float weight = 1.f;
};

std::map<uint32_t, Refraction> complete(const RefractionSearch& search, const Source& s,
                                        const Point3f& x, float eta) {
    std::map<uint32_t, Refraction> found;
    const auto visit = [&](const Refraction& r) { EXPECT_TRUE(found.emplace(r.face, r).second); };
    if (s.isDirection)
        search.forEachFromDirection(Vector3f(s.value), x, eta, visit);
    else
        search.forEachFromPoint(Point3f(s.value), x, eta, visit);
    return found;
}

}  // namespace

TEST(RefractionSearch, CompleteSearchFindsEveryBruteForceSolution) {
    // Every face whose plane solution lies clearly inside it (1e-6 mm) must be found, none whose
    // solution lies clearly outside; random inside points, point and directional sources, η
    // above and below 1, convex and non-convex meshes.
    const std::vector<std::pair<const char*, TriangleMesh>> meshes = {
        {"sphere", makeSphere(10.f, 3)},
        {"torus", makeTorus(12.f, 5.f, 24, 12)},
        {"thin-thick", makeThinThick(30.f)}};
    Pcg32 rng(7);
    int solutions = 0;
    for (const auto& [name, mesh] : meshes) {
        const RefractionSearch search(mesh);
        const MeshBoundary boundary(mesh);
        const Bounds3f box = mesh.bounds();
        const float size = glm::length(box.extent());
        for (int q = 0; q < 60; ++q) {
            const Point3f x = insidePoint(boundary, box, rng);
            Source s;
            s.isDirection = q % 2 == 0;
            const Vec dir =
                glm::normalize(Vec(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
            s.value = s.isDirection ? dir : Vec(box.center()) + double(size) * dir;
            const float eta = q % 3 == 0 ? 0.8f : (q % 3 == 1 ? 1.3f : 1.8f);
            const std::map<uint32_t, Refraction> found = complete(search, s, x, eta);
            for (size_t f = 0; f < mesh.triangles.size(); ++f) {
                const auto& t = mesh.triangles[f];
                const auto bf = bruteForce(Vec(mesh.positions[t[0]]), Vec(mesh.positions[t[1]]),
                                           Vec(mesh.positions[t[2]]), s, Vec(x), eta);
                if (!bf || std::abs(bf->second) < 1e-6)
                    continue;  // no solution, or on an edge within rounding
                const bool expected = bf->second > 0.0;
                ASSERT_EQ(found.count(uint32_t(f)) == 1, expected)
                    << name << " face " << f << " query " << q << " η " << eta;
                if (expected) {
                    ++solutions;
                    EXPECT_LT(glm::length(Vec(found.at(uint32_t(f)).p) - bf->first),
                              1e-4 * double(size));
                }
            }
        }
    }
    EXPECT_GT(solutions, 100);  // the test really exercised the search
}

TEST(RefractionSearch, SolutionsObeySnellAndThePencilGain) {
    // Snell (sin θi = η sin θt, incident, transmitted and normal coplanar) and the irradiance
    // gain against a finite-difference pencil: rays from the source at angular offsets ±ε
    // refracted at the plane and intersected with the plane through x perpendicular to the
    // transmitted direction span an area A for a solid angle Ω; gain = Ω/A (to O(ε²)).
    const TriangleMesh mesh = makeSphere(10.f, 4);
    const RefractionSearch search(mesh);
    const MeshBoundary boundary(mesh);
    Pcg32 rng(11);
    int checked = 0;
    for (int q = 0; q < 200; ++q) {
        const Point3f x = insidePoint(boundary, mesh.bounds(), rng);
        const Vec light(20.0 * (rng.uniform() - 0.5), 25.0, 20.0 * (rng.uniform() - 0.5));
        const double eta = 1.45;
        search.forEachFromPoint(Point3f(light), x, float(eta), [&](const Refraction& r) {
            const Vec n(r.normal), i(r.incident), t(r.transmitted);
            const double sinI = glm::length(glm::cross(i, n)), sinT = glm::length(glm::cross(t, n));
            EXPECT_NEAR(sinI, eta * sinT, 2e-5);
            EXPECT_NEAR(glm::dot(glm::cross(i, n), t), 0.0, 2e-5);
            // Finite-difference pencil.
            const double eps = 1e-4;
            const Vec a =
                glm::normalize(glm::cross(i, std::abs(i.x) < 0.9 ? Vec(1, 0, 0) : Vec(0, 1, 0)));
            const Vec b = glm::cross(i, a);
            const Vec pOnPlane(r.p);
            const auto landing = [&](const Vec& dir) {
                const double s = glm::dot(pOnPlane - light, n) / glm::dot(dir, n);
                const Vec hit = light + s * dir;
                const double c = -glm::dot(dir, n);
                const double k = 1.0 - (1.0 - c * c) / (eta * eta);
                const Vec tr = dir / eta + (c / eta - std::sqrt(k)) * n;
                // Intersection with the plane through x perpendicular to t.
                const double u = glm::dot(Vec(x) - hit, t) / glm::dot(tr, t);
                return hit + u * tr;
            };
            const Vec pa =
                landing(glm::normalize(i + eps * a)) - landing(glm::normalize(i - eps * a));
            const Vec pb =
                landing(glm::normalize(i + eps * b)) - landing(glm::normalize(i - eps * b));
            const double area = glm::length(glm::cross(pa, pb));
            const double omega = 4.0 * eps * eps;
            EXPECT_NEAR(double(r.irradianceGain), omega / area, 1e-3 * omega / area);
            ++checked;
        });
    }
    EXPECT_GT(checked, 100);
}

TEST(RefractionSearch, LocalSearchWithCompletionIsUnbiased) {
    // The weights of sample() average exactly to the complete set when u is stratified over
    // [0, 1) in a multiple of 64 strata: Σ_k (1/N)·Σ weight·c = Σ_all c for any c; here c = 1
    // and c = the gain. The local search alone (u = 1) finds almost every solution: reported.
    const TriangleMesh mesh = makeSphere(10.f, 5);
    const RefractionSearch search(mesh);
    const MeshBoundary boundary(mesh);
    Pcg32 rng(13);
    int missed = 0, queries = 0;
    uint64_t localFaces = 0;
    double missedAttenuated = 0.0, totalAttenuated = 0.0;  // weighted by e^{-1 mm⁻¹·s}
    for (int q = 0; q < 400; ++q, ++queries) {
        const Point3f x = insidePoint(boundary, mesh.bounds(), rng);
        const Vector3f travel = glm::normalize(Vector3f(0.2f, -1.f, 0.1f));
        const std::optional<SurfaceHit> seed = boundary.intersect(x, -travel, 0.f, INF);
        ASSERT_TRUE(seed);
        double all = 0.0, allCount = 0.0, allAttenuated = 0.0;
        search.forEachFromDirection(travel, x, 1.3f, [&](const Refraction& r) {
            all += r.irradianceGain;
            allCount += 1.0;
            allAttenuated += r.irradianceGain * std::exp(-r.distInside);
        });
        double mean = 0.0, meanCount = 0.0, local = 0.0;
        const int strata = 128;  // a multiple of 1/P = 64
        for (int k = 0; k < strata; ++k) {
            const float u = (float(k) + 0.5f) / float(strata);
            search.sampleFromDirection(travel, x, 1.3f, boundary, u,
                                       [&](const Refraction& r, float w) {
                                           mean += w * r.irradianceGain / strata;
                                           meanCount += w / strata;
                                       });
        }
        const uint64_t before = RefractionSearch::facesTested();
        double localAttenuated = 0.0;
        search.sampleFromDirection(travel, x, 1.3f, boundary, 1.f, [&](const Refraction& r, float) {
            local += r.irradianceGain;
            localAttenuated += r.irradianceGain * std::exp(-r.distInside);
        });
        missedAttenuated += allAttenuated - localAttenuated;
        totalAttenuated += allAttenuated;
        localFaces += RefractionSearch::facesTested() - before;
        EXPECT_NEAR(mean, all, 1e-5 * all);
        EXPECT_NEAR(meanCount, allCount, 1e-5);
        missed += std::abs(local - all) > 1e-6 * all;
    }
    std::printf(
        "  local search: %.1f faces per query, missed a solution in %d of %d queries "
        "(%.2f%% of the gain attenuated by σt = 1 mm⁻¹)\n",
        double(localFaces) / queries, missed, queries, 100.0 * missedAttenuated / totalAttenuated);
}
