// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief What each light can deliver to an object, bounded from the object's bounding sphere,
/// and the lights a preview may skip (issue 15, "lights that miss the object or contribute
/// less than ε"):
///
///     LightCulling c = cullLights(scene.lights, objectBounds(scene));
///     renderer.setLights(c.kept);            // c.skipped: why each other light was left out
///
/// A light is skipped when it delivers nothing to the object (a spot whose outer cone misses
/// the bounding sphere, a black light), or when in every RGB channel its largest irradiance
/// anywhere on the object is at most ε times the least irradiance the strongest light gives to
/// a surface facing it anywhere on the object (the conservative pair of bounds below). The
/// preview is linear in the lights, so what is dropped is that light's own image: at most ε of
/// what the strongest light alone shows on a surface of the same orientation and shadowing.
/// The reference path tracer never skips a light (it is the measuring stick).
///
/// Units: irradiance W/mm² on a surface facing the light, per RGB channel (Light's units).

#include <lucent/core/Types.h>
#include <lucent/scene/Scene.h>

#include <string>
#include <vector>

namespace lucent {

/// The skip threshold ε: 2⁻¹⁰, a quarter of the step between 8-bit display levels at full
/// scale (1/255): a skipped light moves a pixel's linear radiance by at most ε of the brightest
/// radiance the strongest light gives the object (tests/unit/methods/test_light_skip.cpp).
inline constexpr float LIGHT_SKIP_EPSILON = 1.f / 1024.f;

/// Bounds on one light's unshadowed irradiance on a surface facing it, over every point of a
/// sphere (the object's bounding sphere), per RGB channel.
struct LightReach {
    /// No point of the sphere receives light: a spot whose outer cone misses it, or a black
    /// light. Then `most` and `least` are 0.
    bool misses = false;
    /// Upper bound over the sphere (+∞ when the light sits inside it: no bound).
    Rgb most{0.f};
    /// Lower bound over the sphere (0 where none is known, e.g. a spot whose full-intensity
    /// inner cone does not hold the whole sphere).
    Rgb least{0.f};
};

/// Bounds of light `light` over the sphere of `centre` and `radius` (mm; radius ≥ 0). A point
/// light of intensity I at distance d gives I/d², a sphere light of radiance L and radius r
/// gives πL·min(1, r²/d²) (the disc it subtends, seen head-on), a directional light its
/// irradiance everywhere; distances range over [max(D − R, 0), D + R] for a centre distance D.
/// The spot cone is the one the GL renderer draws (outer half-angle at least 0.1°).
[[nodiscard]] LightReach lightReach(const Light& light, const Point3f& centre, float radius);

/// The lights a preview renders and those it skips.
struct LightCulling {
    std::vector<Light> kept;  ///< in their original order
    /// One line per skipped light: "light 2 (spot): its cone misses the object".
    std::vector<std::string> skipped;
};

/// Splits `lights` by the rule of the file comment, against the sphere bounding `bounds`.
/// Keeps every light when `bounds` is empty, when `epsilon` < 0 (the skip off) or when the
/// rule would skip them all (the scene is black either way, and a method that needs a light of
/// some type then reports that light as it would without the skip).
/// @throw ValueError for a non-finite epsilon.
[[nodiscard]] LightCulling cullLights(const std::vector<Light>& lights, const Bounds3f& bounds,
                                      float epsilon = LIGHT_SKIP_EPSILON);

/// The world-space bounds of every object's mesh (empty for a scene without objects).
[[nodiscard]] Bounds3f objectBounds(const Scene& scene);

}  // namespace lucent
