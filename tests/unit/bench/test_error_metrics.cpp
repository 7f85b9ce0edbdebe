// SPDX-License-Identifier: MIT
/// @file
/// @brief Error metrics on hand-computed images, and their noise floors on synthetic noise.

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/core/Random.h>

#include <gtest/gtest.h>

using namespace lucent;

TEST(ErrorMetrics, HandComputedValues) {
    // Reference R = 1, 3 on two pixels; test R = 2, 3: RMSE = √(1/2), mean ref 2,
    // rel RMSE = √(1/2)/2, mean rel = (1/1 + 0)/2 = 0.5.
    ImageRgb ref(2, 1), test(2, 1);
    ref.at(0, 0) = Rgb(1, 2, 0);
    ref.at(1, 0) = Rgb(3, 2, 0);
    test.at(0, 0) = Rgb(2, 2, 0);
    test.at(1, 0) = Rgb(3, 2, 0);
    const ErrorReport r = compareImages(test, ref, nullptr, nullptr, nullptr);
    EXPECT_EQ(r.pixelCount, 2u);
    EXPECT_FALSE(r.hasNoiseFloor);
    EXPECT_NEAR(r.channels[0].rmse, std::sqrt(0.5), 1e-12);
    EXPECT_NEAR(r.channels[0].meanReference, 2.0, 1e-12);
    EXPECT_NEAR(r.channels[0].relRmse, std::sqrt(0.5) / 2, 1e-12);
    EXPECT_NEAR(r.channels[0].meanRelError, 0.5, 1e-12);
    EXPECT_EQ(r.channels[1].rmse, 0.0);
    // Black channel: relative metrics stay finite (0) rather than dividing by zero.
    EXPECT_EQ(r.channels[2].relRmse, 0.0);
    EXPECT_EQ(r.channels[2].meanRelError, 0.0);
    // Luminance: only R differs, by 1 on one pixel: RMSE = 0.2126·√(1/2).
    EXPECT_NEAR(r.channels[ErrorReport::LUMINANCE].rmse, 0.2126 * std::sqrt(0.5), 1e-6);
}

TEST(ErrorMetrics, MaskSelectsPixels) {
    ImageRgb ref(2, 1, Rgb(1.f)), test(2, 1, Rgb(1.f)), cov(2, 1);
    test.at(1, 0) = Rgb(100.f);  // outside the mask: ignored
    cov.at(0, 0) = Rgb(1.f);
    const std::vector<uint8_t> mask = maskFromImage(cov);
    const ErrorReport r = compareImages(test, ref, nullptr, nullptr, &mask);
    EXPECT_EQ(r.pixelCount, 1u);
    EXPECT_EQ(r.channels[0].rmse, 0.0);
    const std::vector<uint8_t> none(2, 0);
    EXPECT_THROW(compareImages(test, ref, nullptr, nullptr, &none), ValueError);
}

TEST(ErrorMetrics, RejectsMismatchedAndNonFinite) {
    ImageRgb a(2, 2), b(3, 2);
    EXPECT_THROW(compareImages(a, b, nullptr, nullptr, nullptr), ValueError);
    ImageRgb c(2, 2);
    c.at(1, 1) = Rgb(std::nanf(""));
    EXPECT_THROW(compareImages(c, a, nullptr, nullptr, nullptr), ValueError);
}

TEST(ErrorMetrics, NoiseFloorMatchesGaussianNoise) {
    // Test = reference + N(0, σ²) noise with the variance layer saying σ²: the RMSE and the mean
    // relative error must equal their floors. For P = 40 000 pixels the RMSE² estimate has
    // relative standard deviation √(2/P) ≈ 0.7 %, the mean |X| one √((π/2 − 1)/P) ≈ 0.38 %;
    // accept 5σ: 3.5 % and 1.9 %.
    const int w = 200, h = 200;
    ImageRgb ref(w, h), test(w, h), var(w, h);
    Pcg32 rng(8);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float v = 1.f + float(x) / w;  // reference value
            const float sigma = 0.05f * v;
            // Box–Muller normal.
            const float u1 = std::max(rng.uniform(), 1e-12f), u2 = rng.uniform();
            const float n = std::sqrt(-2.f * std::log(u1)) * std::cos(2.f * PI * u2);
            ref.at(x, y) = Rgb(v);
            test.at(x, y) = Rgb(v + sigma * n);
            var.at(x, y) = Rgb(sigma * sigma);
        }
    const ErrorReport r = compareImages(test, ref, &var, nullptr, nullptr);
    ASSERT_TRUE(r.hasNoiseFloor);
    const ChannelError& e = r.channels[0];
    EXPECT_NEAR(e.rmse / e.rmseFloor, 1.0, 0.035);
    EXPECT_NEAR(e.relRmse / e.relRmseFloor, 1.0, 0.035);
    EXPECT_NEAR(e.meanRelError / e.meanRelFloor, 1.0, 0.019);
    EXPECT_NE(formatReport(r).find("luminance"), std::string::npos);
}
