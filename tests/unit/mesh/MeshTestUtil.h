// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Helpers shared by the mesh tests: exact polyhedron volume and topology counts.

#include <lucent/mesh/TriangleMesh.h>

#include <map>
#include <utility>

namespace lucent::test {

/// Signed volume of a closed triangle mesh (divergence theorem: Σ a·(b×c)/6); positive for
/// outward counter-clockwise faces.
inline double signedVolume(const TriangleMesh& m) {
    double v = 0.0;
    for (const auto& t : m.triangles) {
        const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        v += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    return v;
}

/// Counts directed edges: a closed, consistently oriented 2-manifold uses every directed edge
/// exactly once and its reverse exactly once.
inline bool isClosedOriented(const TriangleMesh& m) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (const auto& t : m.triangles)
        for (int e = 0; e < 3; ++e)
            ++directed[{t[size_t(e)], t[size_t((e + 1) % 3)]}];
    for (const auto& [edge, count] : directed) {
        if (count != 1)
            return false;
        auto it = directed.find({edge.second, edge.first});
        if (it == directed.end() || it->second != 1)
            return false;
    }
    return true;
}

}  // namespace lucent::test
