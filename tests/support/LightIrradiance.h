// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Test helpers for light edits (tests/unit/scene and the app's Lights dock tests): the
/// irradiance a light gives at a point, written independently of lucent::convertLight.

#include <lucent/core/Types.h>
#include <lucent/scene/Scene.h>

#include <algorithm>
#include <cmath>

namespace lucent::test {

/// Irradiance (W/mm², normal incidence) that `l` gives at point `x`, written independently of
/// convertLight: point/spot I(ω)/d² (Light::intensityToward), sphere πL·sin²α with
/// sin α = R/d, directional its own value.
inline Rgb irradianceAt(const Light& l, const Point3f& x) {
    if (l.type == Light::Type::Directional)
        return l.intensity;
    const Vector3f toX = x - l.position;
    const float d = glm::length(toX);
    if (l.type == Light::Type::Sphere) {
        const float sinAlpha = l.radius / d;
        return l.intensity * (PI * sinAlpha * sinAlpha);
    }
    return l.intensityToward(toX / d) / (d * d);
}

/// Relative difference of the largest channel.
inline float relDiff(const Rgb& a, const Rgb& b) {
    const Rgb d = glm::abs(a - b);
    return std::max({d.r, d.g, d.b}) / std::max({std::abs(b.r), std::abs(b.g), std::abs(b.b)});
}

}  // namespace lucent::test
