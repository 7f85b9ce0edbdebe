// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Geometric and colour types. World units are millimetres; σ coefficients are mm⁻¹.
/// Names state meaning even where the storage is the same GLM vector (pbrt-v4 vecmath.h style):
/// Point3f for positions, Vector3f for directions/offsets, Normal3f for unit normals, Rgb for
/// linear RGB triples (radiance, σ per channel...). Voxel index space uses Coord.

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace lucent {

using Point3f = glm::vec3;
using Vector3f = glm::vec3;
using Normal3f = glm::vec3;
using Point2f = glm::vec2;
using Vector2f = glm::vec2;
/// Linear RGB triple, one float per channel (r, g, b). Used for physical per-channel values.
using Rgb = glm::vec3;
/// Integer voxel coordinate (i, j, k).
using Coord = glm::ivec3;
using Mat4f = glm::mat4;
using Mat3f = glm::mat3;

inline constexpr float PI = 3.14159265358979323846f;
inline constexpr float INV_PI = 0.31830988618379067154f;
inline constexpr float INV_4PI = 0.07957747154594766788f;
inline constexpr float INF = std::numeric_limits<float>::infinity();

/// Axis-aligned box, inclusive of both corners, in millimetres.
struct Bounds3f {
    Point3f lo{INF};
    Point3f hi{-INF};

    [[nodiscard]] bool isEmpty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    [[nodiscard]] Vector3f extent() const { return isEmpty() ? Vector3f(0.f) : hi - lo; }
    [[nodiscard]] Point3f center() const { return 0.5f * (lo + hi); }
    void expand(const Point3f& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void expand(const Bounds3f& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
    [[nodiscard]] bool contains(const Point3f& p) const {
        return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y &&
               p.z <= hi.z;
    }
};

/// Voxel index box with inclusive bounds (OpenVDB CoordBBox convention).
struct CoordBox {
    Coord lo{0};
    Coord hi{-1};
    [[nodiscard]] bool isEmpty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
};

/// True when every component is finite (not NaN, not ±Inf).
inline bool isFinite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Rec. 709 luminance of a linear RGB value.
inline float luminance(const Rgb& c) {
    return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
}

}  // namespace lucent
