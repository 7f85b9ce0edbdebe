// SPDX-License-Identifier: MIT
/// @file
/// @brief Twist, bend and ripple deformers (Barr, "Global and Local Deformations of Solid
/// Primitives", SIGGRAPH 1984, sections "Twisting" and "Bending") and the displacement
/// brush.

#include <lucent/core/Error.h>
#include <lucent/mesh/Deform.h>

#include <cmath>

namespace lucent {
namespace {

void validate(const Deformer& d, size_t i) {
    const std::string f = "deformer[" + std::to_string(i) + "]";
    LUCENT_CHECK(isFinite(d.center), f, ".center must be finite");
    LUCENT_CHECK(isFinite(d.axis) && glm::length(d.axis) > 1e-12f, f, ".axis must be non-zero");
    LUCENT_CHECK(std::isfinite(d.amount), f, ".amount must be finite");
    LUCENT_CHECK(std::isfinite(d.rateHz) && d.rateHz >= 0.f, f, ".rateHz must be ≥ 0");
    if (d.type == DeformerType::Ripple)
        LUCENT_CHECK(std::isfinite(d.wavelength) && d.wavelength > 0.f, f,
                     ".wavelength must be > 0 mm");
    if (d.type == DeformerType::Bend) {
        const Vector3f a = glm::normalize(d.axis);
        const Vector3f b = d.bendToward - glm::dot(d.bendToward, a) * a;
        LUCENT_CHECK(isFinite(d.bendToward) && glm::length(b) > 1e-6f, f,
                     ".bendToward must not be parallel to the axis");
    }
}

Point3f apply(const Deformer& d, const Point3f& p, float t) {
    const Vector3f a = glm::normalize(d.axis);
    const Vector3f q = p - d.center;
    const float h = glm::dot(q, a);  // coordinate along the axis
    const float osc = d.rateHz > 0.f ? std::sin(2.f * PI * d.rateHz * t) : 1.f;
    switch (d.type) {
        case DeformerType::Twist: {
            // Barr 1984, "Twisting": rotation about the axis by θ = k·h (Rodrigues' formula).
            const float theta = d.amount * osc * h;
            const float c = std::cos(theta), s = std::sin(theta);
            const Vector3f qa = h * a, qp = q - qa;
            return d.center + qa + c * qp + s * glm::cross(a, qp);
        }
        case DeformerType::Bend: {
            // Barr 1984, "Bending" (without the clamped region): the axis bends onto a circle of
            // radius R = 1/κ in the plane (axis, bendToward); a point at axial h and offset x
            // toward the bend keeps its distance R − x from the circle's centre, at angle θ = κ·h.
            const float kappa = d.amount * osc;
            if (std::abs(kappa) < 1e-9f)
                return p;
            Vector3f b = d.bendToward - glm::dot(d.bendToward, a) * a;
            b = glm::normalize(b);
            const float x = glm::dot(q, b);
            const Vector3f rest = q - h * a - x * b;  // the component the bend leaves alone
            const float r = 1.f / kappa;
            const float theta = kappa * h;
            return d.center + rest + (r - (r - x) * std::cos(theta)) * b +
                   (r - x) * std::sin(theta) * a;
        }
        case DeformerType::Ripple: {
            // Radial travelling sine wave along the axis: A·sin(2π(ρ/λ − f·t)), ρ = distance
            // from the axis.
            const float rho = glm::length(q - h * a);
            return p + a * (d.amount * std::sin(2.f * PI * (rho / d.wavelength - d.rateHz * t)));
        }
    }
    return p;
}

}  // namespace

Point3f deformPoint(const Point3f& rest, const std::vector<Deformer>& stack, float timeSeconds) {
    LUCENT_CHECK(std::isfinite(timeSeconds), "deform: time must be finite");
    for (size_t i = 0; i < stack.size(); ++i)
        validate(stack[i], i);
    Point3f p = rest;
    for (const Deformer& d : stack)
        p = apply(d, p, timeSeconds);
    return p;
}

TriangleMesh deform(const TriangleMesh& rest, const std::vector<Deformer>& stack,
                    float timeSeconds) {
    LUCENT_CHECK(std::isfinite(timeSeconds), "deform: time must be finite");
    for (size_t i = 0; i < stack.size(); ++i)
        validate(stack[i], i);
    TriangleMesh out;
    out.triangles = rest.triangles;
    out.positions.resize(rest.positions.size());
    for (size_t v = 0; v < rest.positions.size(); ++v) {
        Point3f p = rest.positions[v];
        for (const Deformer& d : stack)
            p = apply(d, p, timeSeconds);
        out.positions[v] = p;
    }
    computeVertexNormals(out);
    return out;
}

size_t displaceBrush(TriangleMesh& mesh, const Point3f& center, float radius, float amount) {
    LUCENT_CHECK(isFinite(center), "displaceBrush: center must be finite");
    LUCENT_CHECK(std::isfinite(radius) && radius > 0.f, "displaceBrush: radius must be > 0 mm");
    LUCENT_CHECK(std::isfinite(amount), "displaceBrush: amount must be finite");
    if (mesh.normals.size() != mesh.positions.size())
        computeVertexNormals(mesh);
    size_t moved = 0;
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const float d = glm::length(mesh.positions[v] - center) / radius;
        if (d >= 1.f)
            continue;
        const float w = 1.f - d * d * (3.f - 2.f * d);  // 1 − smoothstep(0, 1, d)
        mesh.positions[v] += amount * w * mesh.normals[v];
        ++moved;
    }
    if (moved)
        computeVertexNormals(mesh);
    return moved;
}

}  // namespace lucent
