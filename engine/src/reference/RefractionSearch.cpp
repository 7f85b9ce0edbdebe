// SPDX-License-Identifier: MIT
/// @file
/// @brief RefractionSearch: a normal-cone BVH over the faces and the exact per-face solve of
/// Snell's law (see RefractionSearch.h and docs/reference.md).

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/reference/RefractionSearch.h>
#include <lucent/reference/Transport.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <optional>
#include <unordered_map>

namespace lucent::reference {

namespace {

using Vec3d = glm::dvec3;

constexpr int LEAF_FACES = 4;
/// Faces the local search may test before it stops growing (RefractionSearch::sample).
constexpr int MAX_LOCAL_FACES = 64;
/// Steps of the walk towards the face that holds the refraction point.
constexpr int MAX_WALK_STEPS = 8;
/// Probability that sample() also runs the complete search to add what the local search
/// missed (weighted by its inverse): the cost of completeness, amortised.
constexpr float COMPLETION_PROBABILITY = 1.f / 64.f;
/// The local search also grows around faces whose plane solution lies outside them by less
/// than this fraction of their longest edge.
constexpr double NEAR_MISS = 0.0;

/// A short list of face indices (solutions of one query: a handful).
struct FaceList {
    std::array<uint32_t, MAX_LOCAL_FACES> faces;
    int count = 0;
    void add(uint32_t f) {
        if (count < MAX_LOCAL_FACES)
            faces[count++] = f;
    }
};

/// A small set of face indices: a list plus an open-addressing hash table (4 × the capacity,
/// linear probing) for constant-time membership.
class LocalFaces {
public:
    std::array<uint32_t, MAX_LOCAL_FACES> faces;
    int count = 0;

    LocalFaces() { m_table.fill(EMPTY); }
    [[nodiscard]] bool isFull() const { return count >= MAX_LOCAL_FACES; }
    [[nodiscard]] bool contains(uint32_t f) const {
        for (uint32_t i = hash(f);; i = (i + 1) & MASK) {
            if (m_table[i] == f)
                return true;
            if (m_table[i] == EMPTY)
                return false;
        }
    }
    /// Adds f unless present or full; true if added.
    bool add(uint32_t f) {
        if (isFull())
            return false;
        uint32_t i = hash(f);
        for (; m_table[i] != EMPTY; i = (i + 1) & MASK)
            if (m_table[i] == f)
                return false;
        m_table[i] = f;
        faces[count++] = f;
        return true;
    }

private:
    static constexpr uint32_t EMPTY = ~0u;
    static constexpr uint32_t MASK = 4 * MAX_LOCAL_FACES - 1;
    static uint32_t hash(uint32_t f) { return (f * 2654435761u) >> 8 & MASK; }
    std::array<uint32_t, 4 * MAX_LOCAL_FACES> m_table;
};
constexpr int MAX_DEPTH = 60;
/// Slack (radians) added to every pruning test: the bounds are computed in float, the
/// per-face solve in double; a node is skipped only when it misses by more than this.
constexpr float PRUNE_SLACK = 2e-3f;

struct Node {
    Point3f centre{0.f};  ///< bounding-sphere centre (mm)
    float radius = 0.f;   ///< bounding-sphere radius (mm)
    Vector3f coneAxis{0.f, 0.f, 1.f};
    /// cos and sin of the cone's half-angle plus PRUNE_SLACK: every face normal lies within
    /// the half-angle of coneAxis (a full cone: cos = −1, sin = 0).
    float coneCos = -1.f, coneSin = 0.f;
    uint32_t first = 0;  ///< leaf: first face in m_order; interior: right child
    uint32_t count = 0;  ///< faces in a leaf, 0 for an interior node (left child = next)
};

struct Face {
    std::array<Vec3d, 3> v;       ///< vertices (mm), counter-clockwise seen from outside
    Vec3d n;                      ///< unit outward normal
    std::array<Vec3d, 3> inward;  ///< n × (v[k+1] − v[k]): points into the triangle
};

thread_local uint64_t t_facesTested = 0;
thread_local uint64_t t_completeSearches = 0;

double angleBetween(const Vector3f& a, const Vector3f& b) {
    return std::acos(std::clamp(double(glm::dot(a, b)), -1.0, 1.0));
}

/// Chord 2 sin(α/2) = √(2 − 2 cos α) of the cone of directions from a point at distance d to
/// a sphere of radius r < d (sin α = r/d): the largest |u − u₀| within the cone.
float chordToSphere(float r, float d) {
    const float s = r / d;
    return std::sqrt(std::max(0.f, 2.f - 2.f * std::sqrt(std::max(0.f, 1.f - s * s))));
}

/// True for one of the two directions of every edge (the first non-zero component of b − a is
/// positive). Neighbouring faces traverse a shared edge in opposite directions (consistent
/// winding), so exactly one of them owns the points on it.
bool ownsEdge(const Vec3d& e) {
    return e.x != 0.0 ? e.x > 0.0 : (e.y != 0.0 ? e.y > 0.0 : e.z > 0.0);
}

/// p lies in the triangle. A point on an edge (within rounding) belongs to exactly one of the two
/// faces that share it (a tie rule like a rasteriser's top-left rule), so a refraction point on
/// an edge, e.g. on the diagonal of a flat quad, is counted once, not twice.
bool insideTriangle(const Face& f, const Vec3d& p) {
    for (int k = 0; k < 3; ++k) {
        const Vec3d& a = f.v[k];
        const Vec3d e = f.v[(k + 1) % 3] - a;
        const Vec3d ap = p - a;
        const double side = glm::dot(glm::cross(e, ap), f.n);
        const double tolerance = 1e-10 * glm::length(e) * (glm::length(e) + glm::length(ap));
        if (side > tolerance)
            continue;
        if (side < -tolerance || !ownsEdge(e))
            return false;
    }
    return true;
}

/// Snell's law along the line between the feet of the source and of x on the plane: the
/// refraction point at distance u from the source's foot solves
///   f(u) = u/√(u² + a²) − η·(D − u)/√((D − u)² + b²) = 0,
/// (sin θi = η sin θt), a strictly increasing function with f(0) ≤ 0 ≤ f(D): one root.
/// Safeguarded Newton in double precision within a bracket [lo, hi] that holds the root.
double solveRefractionOffset(double a, double b, double D, double eta, double lo, double hi) {
    const auto f = [&](double u, double& df) {
        const double ra = std::sqrt(u * u + a * a), rb = std::sqrt((D - u) * (D - u) + b * b);
        df = a * a / (ra * ra * ra) + eta * b * b / (rb * rb * rb);
        return u / ra - eta * (D - u) / rb;
    };
    // Start where the straight line crosses the plane, inside the bracket [lo, hi] ⊆ [0, D].
    double u = std::clamp(D * a / (a + b), lo, hi);
    for (int it = 0; it < 100; ++it) {
        double df = 0.0;
        const double v = f(u, df);
        if (v < 0.0)
            lo = u;
        else
            hi = u;
        double next = df > 0.0 ? u - v / df : 0.5 * (lo + hi);
        if (!(next > lo && next < hi))
            next = 0.5 * (lo + hi);
        if (std::abs(next - u) <= 1e-11 * (D + a + b))
            return next;
        u = next;
    }
    return u;
}

}  // namespace

namespace {

/// A query: light from `source` (a point, or a unit travel direction) to x inside, index η.
struct Query {
    Vector3f source;
    bool isDirection;
    Vec3d x;
    double eta;
};

/// Where light of query q would refract on the plane of face f to reach x, before the
/// triangle test: nothing when x is not below the plane, the source not above it, or the
/// refraction impossible (η < 1 past the critical angle). With `onlyInside`, also nothing when
/// the point cannot lie in the triangle: for a point source it lies between the feet of the
/// source and of x, so both feet outside the same edge rule the face out before the solve.
std::optional<Vec3d> planeSolution(const Face& f, const Query& q, Vec3d& incident,
                                   double& distOutside, bool onlyInside = false) {
    const double b = -glm::dot(f.n, q.x - f.v[0]);  // depth of x below the plane
    if (!(b > 0.0))
        return std::nullopt;
    if (q.isDirection) {
        incident = glm::normalize(Vec3d(q.source));
        const double cosI = -glm::dot(incident, f.n);
        if (!(cosI > 0.0))
            return std::nullopt;
        // Snell, vector form (pbrt-v3 Eq. 8.8); back along the transmitted ray to the plane.
        const double sin2T = (1.0 - cosI * cosI) / (q.eta * q.eta);
        if (sin2T >= 1.0)
            return std::nullopt;
        const Vec3d t = incident / q.eta + (cosI / q.eta - std::sqrt(1.0 - sin2T)) * f.n;
        distOutside = INF;
        return q.x - (b / -glm::dot(t, f.n)) * t;
    }
    const Vec3d src(q.source);
    const double a = glm::dot(f.n, src - f.v[0]);  // height of the source
    if (!(a > 0.0))
        return std::nullopt;
    const Vec3d footSrc = src - a * f.n, footX = q.x + b * f.n;
    const Vec3d along = footX - footSrc;
    const double D = glm::length(along);
    if (!(D > 0.0)) {
        if (onlyInside && !insideTriangle(f, footSrc))
            return std::nullopt;
        distOutside = a;
        incident = -f.n;
        return footSrc;
    }
    const Vec3d e = along / D;
    double lo = 0.0, hi = D;
    if (onlyInside) {
        // The point lies at u ∈ [0, D] on the line footSrc + u·e, where the increasing
        // f(u) = sin θi − η sin θt vanishes. Clip the line to the triangle ([lo, hi], widened
        // by a rounding margin: the exact triangle test after the solve decides): no sign change
        // of f there, no refraction point in the face, without solving.
        const double margin = 1e-9 * (D + a + b);
        for (int k = 0; k < 3 && lo <= hi; ++k) {
            const double s0 = glm::dot(f.inward[k], footSrc - f.v[k]);
            const double ds = glm::dot(f.inward[k], e);
            const double len = glm::length(f.inward[k]);
            if (std::abs(ds) < 1e-300) {
                if (s0 < -margin * len)
                    return std::nullopt;
            } else if (ds > 0.0) {
                lo = std::max(lo, (-s0 - margin * len) / ds);
            } else {
                hi = std::min(hi, (-s0 + margin * len) / ds);
            }
        }
        if (!(lo <= hi))
            return std::nullopt;
        const auto sign = [&](double u) {
            return u / std::sqrt(u * u + a * a) -
                   q.eta * (D - u) / std::sqrt((D - u) * (D - u) + b * b);
        };
        if (sign(lo) > 0.0 || sign(hi) < 0.0)
            return std::nullopt;
    }
    const Vec3d p = footSrc + e * solveRefractionOffset(a, b, D, q.eta, lo, hi);
    distOutside = glm::length(p - src);
    incident = (p - src) / distOutside;
    return p;
}

/// The refraction of query q through face f, if its plane solution lies in the triangle.
std::optional<Refraction> solveFace(const Face& f, uint32_t index, const Query& q) {
    ++t_facesTested;
    Vec3d incident;
    double distOutside = INF;
    const std::optional<Vec3d> p = planeSolution(f, q, incident, distOutside, true);
    if (!p || !insideTriangle(f, *p))
        return std::nullopt;
    const Vec3d toX = q.x - *p;
    const double distInside = glm::length(toX);
    if (!(distInside > 0.0))
        return std::nullopt;
    const Vec3d transmitted = toX / distInside;
    const double cosI = -glm::dot(incident, f.n), cosT = -glm::dot(transmitted, f.n);
    if (!(cosI > 0.0) || !(cosT > 0.0))
        return std::nullopt;
    Refraction r;
    r.p = Point3f(*p);
    r.normal = Normal3f(f.n);
    r.face = index;
    r.incident = Vector3f(incident);
    r.transmitted = Vector3f(transmitted);
    r.cosI = float(cosI);
    r.cosT = float(cosT);
    r.distOutside = float(distOutside);
    r.distInside = float(distInside);
    r.fresnelTransmittance = 1.f - fresnelDielectric(r.cosI, float(q.eta));
    if (q.isDirection) {
        r.irradianceGain = float(cosI / cosT);
    } else {
        // Widths of the refracted pencil per unit solid angle at the source: sagittal
        // d₁ + s/η, tangential d₁·cosθt/cosθi + s·cosθi/(η cosθt) (docs/reference.md).
        const double d1 = distOutside, s = distInside;
        r.irradianceGain =
            float(1.0 / ((d1 + s / q.eta) * (d1 * cosT / cosI + s * cosI / (q.eta * cosT))));
    }
    return r;
}

bool validQuery(const Vector3f& source, const Point3f& x, float eta) {
    return eta > 0.f && eta != 1.f && isFinite(source) && isFinite(x);
}

}  // namespace

struct RefractionSearch::Impl {
    std::vector<Face> faces;
    std::vector<uint32_t> order;  ///< faces in leaf order
    std::vector<Node> nodes;
    /// Mesh connectivity on vertices welded by position (files often split vertices at
    /// seams): the three edge neighbours of each face (NO_FACE on an open edge), and the faces
    /// around each welded vertex (CSR).
    std::vector<std::array<uint32_t, 3>> welded;  ///< welded vertex ids per face
    std::vector<std::array<uint32_t, 3>> edgeNeighbour;
    std::vector<uint32_t> vertexFaceStart, vertexFaces;

    uint32_t build(std::vector<uint32_t>& items, size_t begin, size_t end,
                   const std::vector<Point3f>& centroids, const std::vector<Bounds3f>& boxes,
                   int depth) {
        const uint32_t index = uint32_t(nodes.size());
        nodes.emplace_back();
        Bounds3f box, cbox;
        Vec3d normalSum(0.0);
        for (size_t i = begin; i < end; ++i) {
            box.expand(boxes[items[i]]);
            cbox.expand(centroids[items[i]]);
            normalSum += faces[items[i]].n;
        }
        Node node;
        node.centre = box.center();
        node.radius = 0.5f * glm::length(box.extent()) * (1.f + 1e-5f) + 1e-6f;
        const double len = glm::length(normalSum);
        if (len > 1e-9) {
            node.coneAxis = Vector3f(normalSum / len);
            double half = 0.0;
            for (size_t i = begin; i < end; ++i)
                half = std::max(half, angleBetween(node.coneAxis, Vector3f(faces[items[i]].n)));
            half += double(PRUNE_SLACK);
            if (half < double(PI)) {
                node.coneCos = float(std::cos(half));
                node.coneSin = float(std::sin(half));
            }
        }
        if (end - begin <= size_t(LEAF_FACES) || depth >= MAX_DEPTH) {
            node.first = uint32_t(order.size());
            node.count = uint32_t(end - begin);
            for (size_t i = begin; i < end; ++i)
                order.push_back(items[i]);
            nodes[index] = node;
            return index;
        }
        // Median split on the widest axis of the centroids: a balanced tree whose nodes stay
        // spatially compact, so their normal cones stay narrow on smooth surfaces.
        const Vector3f ext = cbox.extent();
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const size_t mid = begin + (end - begin) / 2;
        std::nth_element(
            items.begin() + long(begin), items.begin() + long(mid), items.begin() + long(end),
            [&](uint32_t l, uint32_t r) { return centroids[l][axis] < centroids[r][axis]; });
        build(items, begin, mid, centroids, boxes, depth + 1);
        node.first = build(items, mid, end, centroids, boxes, depth + 1);
        node.count = 0;
        nodes[index] = node;
        return index;
    }

    void buildConnectivity(const TriangleMesh& mesh);

    /// Every refraction of q: traversal of the normal-cone BVH with conservative pruning, then
    /// the exact per-face solve in the leaves.
    template <typename F>
    void searchAll(const Query& q, F&& visit) const;

    /// The deterministic local search of sample(): rays from x through `boundary`, first
    /// towards the source, then towards the point solved on the plane of the face last hit,
    /// until that point lies in the face hit (a fixed point); then the one-ring of every
    /// solution face found (overlapping refracted beams of neighbouring facets), growing while
    /// new solutions or near misses appear. Writes the faces tested and the solution faces;
    /// false when no solution was found.
    bool searchNear(const Query& q, const MeshBoundary& boundary, uint32_t straightHit,
                    LocalFaces& tested, FaceList& solutions) const;
};

void RefractionSearch::Impl::buildConnectivity(const TriangleMesh& mesh) {
    // Weld vertices with bit-identical positions.
    std::vector<uint32_t> weldOf(mesh.positions.size());
    const auto bits = [](float v) {
        uint32_t u;
        std::memcpy(&u, &v, sizeof u);
        return uint64_t(u);
    };
    std::unordered_map<uint64_t, std::vector<uint32_t>> buckets;  // collisions: exact compare
    uint32_t next = 0;
    std::vector<Point3f> weldedPos;
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const Point3f& p = mesh.positions[v];
        const uint64_t h =
            (bits(p.x) * 73856093ull) ^ (bits(p.y) * 19349663ull) ^ (bits(p.z) * 83492791ull);
        std::vector<uint32_t>& bucket = buckets[h];
        uint32_t id = NO_FACE;
        for (const uint32_t c : bucket)
            if (weldedPos[c] == p)
                id = c;
        if (id == NO_FACE) {
            id = next++;
            weldedPos.push_back(p);
            bucket.push_back(id);
        }
        weldOf[v] = id;
    }
    welded.resize(mesh.triangles.size());
    std::vector<uint32_t> counts(next + 1, 0);
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            welded[t][k] = weldOf[mesh.triangles[t][k]];
            ++counts[welded[t][k] + 1];
        }
    vertexFaceStart.assign(counts.begin(), counts.end());
    std::partial_sum(vertexFaceStart.begin(), vertexFaceStart.end(), vertexFaceStart.begin());
    vertexFaces.resize(vertexFaceStart.back());
    std::vector<uint32_t> fill(vertexFaceStart.begin(), vertexFaceStart.end() - 1);
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k)
            vertexFaces[fill[welded[t][k]]++] = uint32_t(t);
    // Edge neighbours: the other face around both welded ends of the edge (on a 2-manifold
    // mesh there is exactly one; for a non-manifold edge, any one of them).
    edgeNeighbour.assign(mesh.triangles.size(), {NO_FACE, NO_FACE, NO_FACE});
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = welded[t][k], b = welded[t][(k + 1) % 3];
            for (uint32_t i = vertexFaceStart[a]; i < vertexFaceStart[a + 1]; ++i) {
                const uint32_t o = vertexFaces[i];
                if (o == t)
                    continue;
                const auto& w = welded[o];
                if ((w[0] == b || w[1] == b || w[2] == b)) {
                    edgeNeighbour[t][k] = o;
                    break;
                }
            }
        }
}

template <typename F>
void RefractionSearch::Impl::searchAll(const Query& q, F&& visit) const {
    ++t_completeSearches;
    // The outward normal is parallel to h = ωi − η·ωt with the sign of η − 1 (Snell's law:
    // the tangential parts cancel, the normal part is η cos θt − cos θi).
    const float eta = float(q.eta);
    const float hSign = eta > 1.f ? 1.f : -1.f;
    const Point3f x(q.x);
    std::array<uint32_t, 2 * MAX_DEPTH + 2> stack{};
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const uint32_t index = stack[--top];
        const Node& node = nodes[index];
        // Conservative pruning: incident directions from the source to the node's bounding
        // sphere lie in a cone (chord δi), transmitted directions from it to x in another
        // (chord δt), so |h − h₀| ≤ δi + η·δt = δ and h lies within the angle s = asin(δ/|h₀|)
        // of h₀. The node is skipped when angle(h₀, axis) > s + half-angle (+ slack), tested
        // with cosines: cos angle < cos(s + half) while s + half < π.
        if (node.coneCos > -1.f) {
            Vector3f i0 = q.source;
            float deltaI = 0.f;
            bool prunable = true;
            if (!q.isDirection) {
                const Vector3f v = node.centre - q.source;
                const float d = glm::length(v);
                prunable = d > node.radius;
                if (prunable) {
                    i0 = v / d;
                    deltaI = chordToSphere(node.radius, d);
                }
            }
            if (prunable) {
                const Vector3f w = x - node.centre;
                const float d = glm::length(w);
                if (d > node.radius) {
                    const Vector3f h0 = hSign * (i0 - eta * (w / d));
                    const float m = glm::length(h0);
                    const float sinS = (deltaI + eta * chordToSphere(node.radius, d)) / m;
                    if (sinS < 1.f) {
                        const float cosS = std::sqrt(1.f - sinS * sinS);
                        const float sinSum = sinS * node.coneCos + cosS * node.coneSin;
                        const float cosSum = cosS * node.coneCos - sinS * node.coneSin;
                        if (sinSum > 0.f && glm::dot(h0, node.coneAxis) < cosSum * m)
                            continue;
                    }
                }
            }
        }
        if (node.count == 0) {
            stack[top++] = node.first;  // right child
            stack[top++] = index + 1;   // left child
            continue;
        }
        for (uint32_t k = 0; k < node.count; ++k) {
            const uint32_t f = order[node.first + k];
            if (const std::optional<Refraction> r = solveFace(faces[f], f, q))
                visit(*r);
        }
    }
}

bool RefractionSearch::Impl::searchNear(const Query& q, const MeshBoundary& boundary,
                                        uint32_t straightHit, LocalFaces& tested,
                                        FaceList& solutions) const {
    const Point3f x(q.x);
    const auto firstFace = [&](const Vector3f& toward) {
        const std::optional<SurfaceHit> hit = boundary.intersect(x, toward, 0.f, INF);
        return hit && hit->triangle < faces.size() ? hit->triangle : NO_FACE;
    };
    uint32_t face = straightHit < faces.size()
                        ? straightHit
                        : firstFace(q.isDirection ? -q.source : glm::normalize(q.source - x));
    uint32_t previous = NO_FACE;
    bool reached = false;
    for (int step = 0; step < MAX_WALK_STEPS && face != NO_FACE; ++step) {
        Vec3d incident;
        double distOutside;
        const std::optional<Vec3d> p = planeSolution(faces[face], q, incident, distOutside);
        if (!p)
            break;
        if (insideTriangle(faces[face], *p)) {
            reached = true;
            break;
        }
        const uint32_t next = firstFace(Vector3f(glm::normalize(*p - q.x)));
        if (next == previous || next == face)
            break;  // a two-cycle: the refraction point (if any) lies near their common edge
        previous = face;
        face = next;
    }
    if (face == NO_FACE)
        return false;
    // Flood: the one-ring of the face reached (or of the last two faces of an oscillating
    // walk), then the one-ring of every face whose plane solution lies inside it or less than
    // one edge length outside it (overlapping refracted beams of neighbouring facets lie
    // there), until no such face is left.
    FaceList expand;
    const auto tryAdd = [&](uint32_t g) {
        if (!tested.add(g))
            return;
        ++t_facesTested;
        const Face& f = faces[g];
        Vec3d incident;
        double distOutside;
        const std::optional<Vec3d> p =
            planeSolution(f, q, incident, distOutside, /*onlyInside=*/NEAR_MISS == 0.0);
        if (!p)
            return;
        double outside = 0.0, longest = 0.0;
        for (int k = 0; k < 3; ++k) {
            const Vec3d e = f.v[(k + 1) % 3] - f.v[k];
            const double len = glm::length(e);
            longest = std::max(longest, len);
            outside = std::max(outside, -glm::dot(glm::cross(e, *p - f.v[k]), f.n) / len);
        }
        if (insideTriangle(f, *p))
            solutions.add(g);
        if (outside < NEAR_MISS * longest)
            expand.add(g);
    };
    const auto addRing = [&](uint32_t g) {
        for (const uint32_t v : welded[g])
            for (uint32_t i = vertexFaceStart[v]; i < vertexFaceStart[v + 1]; ++i)
                tryAdd(vertexFaces[i]);
    };
    addRing(face);
    if (!reached && previous != NO_FACE)
        addRing(previous);
    for (int head = 0; head < expand.count; ++head)
        addRing(expand.faces[head]);
    return solutions.count > 0;
}

RefractionSearch::RefractionSearch(const TriangleMesh& mesh) : m_impl(std::make_unique<Impl>()) {
    LUCENT_CHECK(!mesh.isEmpty(), "RefractionSearch: the mesh has no triangles");
    const size_t nv = mesh.positions.size();
    std::vector<Point3f> centroids;
    std::vector<Bounds3f> boxes;
    std::vector<uint32_t> items;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        LUCENT_CHECK(tri[0] < nv && tri[1] < nv && tri[2] < nv, "RefractionSearch: triangle ", t,
                     " has a vertex index out of range");
        const Point3f a = mesh.positions[tri[0]], b = mesh.positions[tri[1]],
                      c = mesh.positions[tri[2]];
        LUCENT_CHECK(isFinite(a) && isFinite(b) && isFinite(c), "RefractionSearch: triangle ", t,
                     " has a non-finite vertex");
        Face f;
        f.v = {Vec3d(a), Vec3d(b), Vec3d(c)};
        const Vec3d n = glm::cross(f.v[1] - f.v[0], f.v[2] - f.v[0]);
        const double len = glm::length(n);
        f.n = len > 0.0 ? n / len : Vec3d(0.0);
        for (int k = 0; k < 3; ++k)
            f.inward[k] = glm::cross(f.n, f.v[(k + 1) % 3] - f.v[k]);
        m_impl->faces.push_back(f);
        if (len > 0.0) {  // a degenerate face refracts nothing
            Bounds3f box;
            box.expand(a);
            box.expand(b);
            box.expand(c);
            boxes.push_back(box);
            centroids.push_back((a + b + c) / 3.f);
            items.push_back(uint32_t(t));
        } else {
            boxes.emplace_back();
            centroids.emplace_back(0.f);
        }
    }
    LUCENT_CHECK(!items.empty(), "RefractionSearch: every triangle is degenerate");
    m_impl->buildConnectivity(mesh);
    m_impl->nodes.reserve(2 * items.size() / LEAF_FACES + 1);
    m_impl->build(items, 0, items.size(), centroids, boxes, 0);
}

RefractionSearch::~RefractionSearch() = default;
RefractionSearch::RefractionSearch(RefractionSearch&&) noexcept = default;
RefractionSearch& RefractionSearch::operator=(RefractionSearch&&) noexcept = default;

uint64_t RefractionSearch::facesTested() {
    return t_facesTested;
}

uint64_t RefractionSearch::completeSearches() {
    return t_completeSearches;
}

void RefractionSearch::search(const Vector3f& source, bool isDirection, const Point3f& x, float eta,
                              Callback callback, void* user) const {
    if (!validQuery(source, x, eta))
        return;
    m_impl->searchAll({source, isDirection, Vec3d(x), double(eta)},
                      [&](const Refraction& r) { callback(user, r, 1.f); });
}

void RefractionSearch::sample(const Vector3f& source, bool isDirection, const Point3f& x, float eta,
                              const MeshBoundary& boundary, uint32_t straightHit, float u,
                              Callback callback, void* user) const {
    if (!validQuery(source, x, eta))
        return;
    const Impl& impl = *m_impl;
    const Query q{source, isDirection, Vec3d(x), double(eta)};
    LocalFaces tested;
    FaceList solutions;
    impl.searchNear(q, boundary, straightHit, tested, solutions);
    // Unbiased completion (docs/reference.md): Σ_all = Σ_local + Σ_(all∖local). The local
    // faces are a deterministic function of the query; the rest is estimated by running the
    // complete search with probability P and weighting what it adds by 1/P. (Where no
    // refracted ray reaches x at all, e.g. behind the terminator, the local search finds
    // nothing and only the rare completion looks further.)
    for (int k = 0; k < solutions.count; ++k) {
        const uint32_t f = solutions.faces[k];
        if (const std::optional<Refraction> r = solveFace(impl.faces[f], f, q))
            callback(user, *r, 1.f);
    }
    if (u < COMPLETION_PROBABILITY)
        impl.searchAll(q, [&](const Refraction& r) {
            if (!tested.contains(r.face))
                callback(user, r, 1.f / COMPLETION_PROBABILITY);
        });
}

}  // namespace lucent::reference
