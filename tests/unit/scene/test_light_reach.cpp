// SPDX-License-Identifier: MIT
/// @file
/// @brief Light reach bounds and the light skip (lucent/scene/LightReach.h): the bounds hold
/// at every point of the sphere (checked by sampling it), the cone test skips only spots that
/// miss, and the ε rule compares channels separately.

#include <lucent/core/Error.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/scene/LightReach.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace lucent {
namespace {

/// Unshadowed irradiance of `l` on a surface at `p` facing it (the quantity lightReach bounds).
Rgb facingIrradiance(const Light& l, const Point3f& p) {
    if (l.type == Light::Type::Directional)
        return l.intensity;
    const Vector3f d = p - l.position;
    const float d2 = glm::dot(d, d);
    if (l.type == Light::Type::Sphere) {
        const float rho2 = l.radius * l.radius;
        return d2 > rho2 ? PI * l.intensity * (rho2 / d2) : PI * l.intensity;
    }
    return l.intensityToward(d / std::sqrt(d2)) / d2;
}

Light spot(const Point3f& position, const Vector3f& direction, float outerDeg, float innerDeg) {
    Light l;
    l.type = Light::Type::Spot;
    l.position = position;
    l.direction = glm::normalize(direction);
    l.spotOuterDeg = outerDeg;
    l.spotInnerDeg = innerDeg;
    l.intensity = Rgb(100.f);
    return l;
}

Bounds3f unitSphereBox() {  // bounding sphere: centre 0, radius √3
    Bounds3f b;
    b.expand(Point3f(-1.f));
    b.expand(Point3f(1.f));
    return b;
}

TEST(LightReach, BoundsHoldAtEveryPointOfTheSphere) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    const Point3f centre(0.5f, -1.f, 2.f);
    const float radius = 3.f;
    const auto randomDirection = [&] {
        Vector3f v;
        do
            v = Vector3f(u(rng), u(rng), u(rng));
        while (glm::dot(v, v) > 1.f || glm::dot(v, v) < 1e-4f);
        return glm::normalize(v);
    };
    int misses = 0, spotsWithLeast = 0;
    for (int trial = 0; trial < 400; ++trial) {
        Light l;
        l.type = Light::Type(trial % 4);
        l.position = centre + randomDirection() * (radius * (1.1f + 4.f * std::abs(u(rng))));
        l.direction = trial % 3 == 0 ? glm::normalize(centre - l.position) : randomDirection();
        l.intensity = Rgb(1.f + std::abs(u(rng)), 2.f, 0.5f);
        l.spotOuterDeg = 5.f + 60.f * std::abs(u(rng));
        l.spotInnerDeg = l.spotOuterDeg * std::abs(u(rng));
        l.radius = 0.2f + std::abs(u(rng));
        const LightReach r = lightReach(l, centre, radius);
        misses += r.misses;
        spotsWithLeast += l.type == Light::Type::Spot && r.least.r > 0.f;
        // Points inside the ball and on its surface (surfaces of the object lie inside it).
        for (int k = 0; k < 2000; ++k) {
            const float s = k % 2 ? 1.f : std::cbrt(std::abs(u(rng)));
            const Point3f p = centre + randomDirection() * (radius * s);
            const Rgb e = facingIrradiance(l, p);
            for (int c = 0; c < 3; ++c) {
                if (r.misses) {
                    ASSERT_EQ(e[c], 0.f) << "trial " << trial << ": a missed light reaches " << c;
                    continue;
                }
                // 1e-4 relative: float rounding of the distance and the cone angles.
                ASSERT_LE(e[c], r.most[c] * (1.f + 1e-4f)) << "trial " << trial;
                ASSERT_GE(e[c], r.least[c] * (1.f - 1e-4f)) << "trial " << trial;
            }
        }
    }
    // Both sides of the cone test were exercised (seed 7: about a third of the spots miss).
    EXPECT_GT(misses, 10);
    EXPECT_GT(spotsWithLeast, 5);
}

TEST(LightReach, ClosedFormsOfEachType) {
    const Point3f centre(0.f);
    Light point;
    point.position = Point3f(0.f, 0.f, 10.f);
    point.intensity = Rgb(36.f);
    LightReach r = lightReach(point, centre, 4.f);
    EXPECT_FLOAT_EQ(r.most.r, 36.f / 36.f);    // I/(D − R)², D − R = 6
    EXPECT_FLOAT_EQ(r.least.r, 36.f / 196.f);  // I/(D + R)², D + R = 14
    EXPECT_FALSE(r.misses);
    r = lightReach(point, centre, 12.f);  // the light inside the sphere: no upper bound
    EXPECT_TRUE(std::isinf(r.most.g));

    Light sun;
    sun.type = Light::Type::Directional;
    sun.intensity = Rgb(0.3f, 0.2f, 0.1f);
    r = lightReach(sun, centre, 100.f);
    EXPECT_EQ(r.most, sun.intensity);
    EXPECT_EQ(r.least, sun.intensity);

    Light bulb;
    bulb.type = Light::Type::Sphere;
    bulb.position = Point3f(10.f, 0.f, 0.f);
    bulb.radius = 2.f;
    bulb.intensity = Rgb(1.f);
    r = lightReach(bulb, centre, 4.f);
    EXPECT_FLOAT_EQ(r.most.r, PI * 4.f / 36.f);    // πL ρ²/(D − R)²
    EXPECT_FLOAT_EQ(r.least.r, PI * 4.f / 196.f);  // πL ρ²/(D + R)²
    r = lightReach(bulb, centre, 9.f);             // the sphere touches the emitter: πL
    EXPECT_FLOAT_EQ(r.most.r, PI);

    Light black = point;
    black.intensity = Rgb(0.f);
    EXPECT_TRUE(lightReach(black, centre, 1.f).misses);
}

TEST(LightReach, SpotConeAgainstTheSphere) {
    const Point3f centre(0.f);
    const float radius = 1.f;
    // 10 mm away on +z: the sphere subtends asin(0.1) = 5.74°.
    const Point3f at(0.f, 0.f, 10.f);
    // Straight at it, inner cone 20° holds the whole sphere: least = I/(D + R)².
    LightReach r = lightReach(spot(at, {0.f, 0.f, -1.f}, 30.f, 20.f), centre, radius);
    EXPECT_FALSE(r.misses);
    EXPECT_FLOAT_EQ(r.least.r, 100.f / 121.f);
    // Inner cone 3° is narrower than the sphere: the falloff reaches part of it, least = 0.
    r = lightReach(spot(at, {0.f, 0.f, -1.f}, 30.f, 3.f), centre, radius);
    EXPECT_FALSE(r.misses);
    EXPECT_EQ(r.least.r, 0.f);
    // Aimed 20° off with a 10° cone: 20° − 5.74° > 10°, a miss.
    const float off = glm::radians(20.f);
    r = lightReach(spot(at, {std::sin(off), 0.f, -std::cos(off)}, 10.f, 5.f), centre, radius);
    EXPECT_TRUE(r.misses);
    // 15° off with a 10° cone: 15° − 5.74° < 10°, the rim reaches the sphere.
    const float grazing = glm::radians(15.f);
    r = lightReach(spot(at, {std::sin(grazing), 0.f, -std::cos(grazing)}, 10.f, 5.f), centre,
                   radius);
    EXPECT_FALSE(r.misses);
    // Aimed away: a miss; the apex inside the sphere: never.
    EXPECT_TRUE(lightReach(spot(at, {0.f, 0.f, 1.f}, 60.f, 50.f), centre, radius).misses);
    EXPECT_FALSE(
        lightReach(spot(Point3f(0.f, 0.f, 0.5f), {0.f, 0.f, 1.f}, 10.f, 5.f), centre, radius)
            .misses);
}

TEST(LightCulling, SkipsMissedAndDimLightsOnly) {
    Light key;
    key.type = Light::Type::Directional;
    key.direction = Vector3f(0.f, 0.f, -1.f);
    key.intensity = Rgb(1.f);
    // A point light whose bound is half of ε × the key (skipped) and one at twice (kept).
    const float eps = LIGHT_SKIP_EPSILON;
    const float near = 20.f - std::sqrt(3.f);  // distance to the bounding sphere
    Light dim;
    dim.position = Point3f(20.f, 0.f, 0.f);
    dim.intensity = Rgb(0.5f * eps * near * near);
    Light fill = dim;
    fill.intensity = Rgb(2.f * eps * near * near);
    const Light away = spot(Point3f(0.f, 0.f, 10.f), {0.f, 0.f, 1.f}, 30.f, 20.f);
    const LightCulling c = cullLights({key, dim, away, fill}, unitSphereBox());
    ASSERT_EQ(c.kept.size(), 2u);
    EXPECT_EQ(c.kept[0].type, Light::Type::Directional);
    EXPECT_EQ(c.kept[1].intensity, fill.intensity);  // the original order
    ASSERT_EQ(c.skipped.size(), 2u);
    EXPECT_NE(c.skipped[0].find("light 1 (point)"), std::string::npos) << c.skipped[0];
    EXPECT_NE(c.skipped[1].find("light 2 (spot): its cone misses the object"), std::string::npos)
        << c.skipped[1];

    // Channels separately: a dim blue light is the only blue light beside a red key.
    Light red = key;
    red.intensity = Rgb(1.f, 0.f, 0.f);
    Light blue = dim;
    blue.intensity = Rgb(0.f, 0.f, 1e-6f);
    EXPECT_EQ(cullLights({red, blue}, unitSphereBox()).kept.size(), 2u);
}

TEST(LightCulling, KeepsEverythingWhenOffEmptyOrAllDark) {
    Light key;
    key.type = Light::Type::Directional;
    key.intensity = Rgb(1.f);
    const Light away = spot(Point3f(0.f, 0.f, 10.f), {0.f, 0.f, 1.f}, 30.f, 20.f);
    EXPECT_EQ(cullLights({key, away}, unitSphereBox(), -1.f).kept.size(), 2u);  // the skip off
    EXPECT_EQ(cullLights({key, away}, Bounds3f{}).kept.size(), 2u);  // no object to bound
    // Every light dark: the scene stays as given (a method that needs a light says so).
    Light black = key;
    black.intensity = Rgb(0.f);
    const LightCulling all = cullLights({black, away}, unitSphereBox());
    EXPECT_EQ(all.kept.size(), 2u);
    EXPECT_TRUE(all.skipped.empty());
    EXPECT_THROW((void)cullLights({key}, unitSphereBox(), NAN), ValueError);
    // A non-finite light is kept, for the renderer to refuse with its own message.
    Light broken = key;
    broken.intensity = Rgb(NAN);
    EXPECT_EQ(cullLights({key, broken}, unitSphereBox()).kept.size(), 2u);
}

TEST(LightCulling, ObjectBoundsCoverEveryObject) {
    Scene scene;
    EXPECT_TRUE(objectBounds(scene).isEmpty());
    scene.objects.push_back(makeObject(makeSphere(2.f, 2), 16, {}));
    TriangleMesh small = makeSphere(1.f, 2);
    for (Point3f& p : small.positions)
        p.x += 10.f;
    scene.objects.push_back(makeObject(std::move(small), 16, {}));
    const Bounds3f b = objectBounds(scene);
    EXPECT_NEAR(b.lo.x, -2.f, 1e-5f);
    EXPECT_NEAR(b.hi.x, 11.f, 1e-5f);
}

}  // namespace
}  // namespace lucent
