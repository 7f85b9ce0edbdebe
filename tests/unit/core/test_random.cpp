// SPDX-License-Identifier: MIT
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Sampling.h>

#include <gtest/gtest.h>

#include <atomic>

using namespace lucent;

TEST(Random, Pcg32IsDeterministicAndUniform) {
    Pcg32 a(42), b(42);
    double sum = 0;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
        const float u = a.uniform();
        ASSERT_EQ(u, b.uniform());
        ASSERT_GE(u, 0.f);
        ASSERT_LT(u, 1.f);
        sum += u;
    }
    // Mean of n uniforms: σ = 1/√(12n) ≈ 9.1e-4; 5σ bound.
    EXPECT_NEAR(sum / n, 0.5, 5 * 9.2e-4);
}

TEST(Random, SequencesStayInUnitSquare) {
    for (uint32_t i = 0; i < 1000; ++i) {
        const Point2f p = r2Sequence(i), h = hammersley(i, 1000);
        EXPECT_TRUE(p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1);
        EXPECT_TRUE(h.x >= 0 && h.x < 1 && h.y >= 0 && h.y < 1);
    }
    EXPECT_FLOAT_EQ(radicalInverse2(1), 0.5f);
    EXPECT_FLOAT_EQ(halton(1, 3), 1.f / 3.f);
}

TEST(Sampling, HenyeyGreensteinMeanCosineIsG) {
    Pcg32 rng(3);
    const Vector3f wo(0, 0, 1);
    for (float g : {-0.7f, 0.f, 0.4f, 0.95f}) {
        double mean = 0;
        const int n = 200000;
        for (int i = 0; i < n; ++i)
            mean += glm::dot(sampleHenyeyGreenstein(wo, g, {rng.uniform(), rng.uniform()}), wo);
        // σ(cos) ≤ 1, so the mean's σ ≤ 1/√n ≈ 2.2e-3; 5σ.
        EXPECT_NEAR(mean / n, g, 0.011) << g;
    }
}

TEST(Parallel, CoversRangeExactlyOnce) {
    std::vector<std::atomic<int>> hits(10000);
    parallelFor(
        0, 10000,
        [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i)
                hits[i]++;
        },
        64);
    for (auto& h : hits)
        EXPECT_EQ(h.load(), 1);
    ThreadLimit one(1);
    EXPECT_EQ(maxThreads(), 1);
}
