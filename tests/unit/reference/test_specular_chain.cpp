// SPDX-License-Identifier: MIT
/// @file
/// @brief SpecularChainTracer: chains connect exactly, the irradiance gain of a single refraction
/// equals RefractionSearch's closed form, and the chains a box holds are found.

#include "TestScenes.h"

#include <lucent/mesh/Procedural.h>
#include <lucent/reference/RefractionSearch.h>
#include <lucent/reference/SpecularChain.h>

#include <gtest/gtest.h>

using namespace lucent;
using namespace lucent::reference;
using namespace lucent::test;

TEST(SpecularChain, SingleRefractionGainMatchesTheClosedForm) {
    const TriangleMesh mesh = makeSphere(10.f, 4);
    const MeshBoundary boundary(mesh);
    const RefractionSearch search(mesh);
    const float eta = 1.4f;
    const SpecularChainTracer tracer(boundary, eta);
    Pcg32 rng(3);
    int checked = 0;
    for (int q = 0; q < 100; ++q) {
        const Point3f x(rng.uniform() * 8.f - 4.f, rng.uniform() * 8.f - 4.f,
                        rng.uniform() * 8.f - 4.f);
        for (const ChainSource& source :
             {ChainSource{Vector3f(5.f, 30.f, -8.f), false},
              ChainSource{glm::normalize(Vector3f(0.3f, -1.f, 0.2f)), true}}) {
            const auto check = [&](const Refraction& r) {
                SpecularChain kinds;
                kinds.events = 1;
                kinds.reflects[0] = false;
                const std::optional<SpecularChain> c =
                    tracer.trace(x, -r.transmitted, kinds, source);
                if (!c)
                    return;  // occluded: the search does not test visibility
                EXPECT_EQ(c->faces[0], r.face);
                EXPECT_NEAR(c->irradianceGain, r.irradianceGain, 2e-3 * r.irradianceGain);
                EXPECT_NEAR(c->fresnel, r.fresnelTransmittance, 1e-5);
                ++checked;
            };
            if (source.isDirection)
                search.forEachFromDirection(source.value, x, eta, check);
            else
                search.forEachFromPoint(source.value, x, eta, check);
        }
    }
    EXPECT_GT(checked, 150);
}

TEST(SpecularChain, SeedsConnectToChainsWithReflections) {
    // In a box, light entering the top refracts toward the side faces and is totally
    // reflected there: from a point inside, random seeds must find reflect-then-refract chains,
    // and every chain connect() returns must end exactly on the light.
    const TriangleMesh mesh = boxMesh({-5, -5, -5}, {5, 5, 5});
    const MeshBoundary boundary(mesh);
    const SpecularChainTracer tracer(boundary, 1.3f);
    const ChainSource sun{glm::normalize(Vector3f(-0.4f, -0.2f, -1.f)), true};
    Pcg32 rng(5);
    int seeds = 0, connected = 0, withReflection = 0;
    for (int i = 0; i < 4000; ++i) {
        const Point3f x(rng.uniform() * 8.f - 4.f, rng.uniform() * 8.f - 4.f,
                        rng.uniform() * 8.f - 4.f);
        const std::optional<SpecularChain> seed = tracer.sampleSeed(x, rng);
        if (!seed || seed->isSingleRefraction())
            continue;
        ++seeds;
        const std::optional<SpecularChain> c = tracer.connect(x, *seed, sun);
        if (!c)
            continue;
        ++connected;
        withReflection += c->reflects[0];
        EXPECT_GT(glm::dot(c->finalDirection, -sun.value), 1.f - 1e-5f);
        EXPECT_GT(c->irradianceGain, 0.0);
    }
    std::printf("  %d non-trivial seeds, %d connected, %d starting with a reflection\n", seeds,
                connected, withReflection);
    EXPECT_GT(connected, 20);
}
