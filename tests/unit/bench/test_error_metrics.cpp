// SPDX-License-Identifier: MIT
/// @file
/// @brief Error metrics on hand-computed images, and their noise floors on synthetic noise.

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/core/Random.h>

#include <gtest/gtest.h>

using namespace lucent;
using namespace lucent::bench;

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

TEST(ErrorMetrics, NonBlackMaskIsEitherImagesNonBlackPixels) {
    ImageRgb a(4, 1), b(4, 1);  // black
    a.at(1, 0) = Rgb(0.f, 0.01f, 0.f);
    b.at(2, 0) = Rgb(3.f);
    a.at(3, 0) = b.at(3, 0) = Rgb(1.f);
    EXPECT_EQ(maskOfNonBlack(a, b), (std::vector<uint8_t>{0, 1, 1, 1}));
    EXPECT_THROW(maskOfNonBlack(a, ImageRgb(2, 2)), ValueError);
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

TEST(ErrorMetrics, BlockValuesByHand) {
    // 8×4 pixels = two 4×4 blocks. Block 0: reference 1, test 1.5 (block error 0.5). Block 1:
    // reference 3, test 3 except one pixel 4.6 (block mean error 1.6/16 = 0.1).
    ImageRgb ref(8, 4), test(8, 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            ref.at(x, y) = Rgb(x < 4 ? 1.f : 3.f);
            test.at(x, y) = Rgb(x < 4 ? 1.5f : 3.f);
        }
    test.at(6, 2) = Rgb(4.6f);
    const ErrorReport r = compareImages(test, ref, nullptr, nullptr, nullptr);
    EXPECT_EQ(r.blockCount, 2u);
    const BlockError& e = r.blocks[0];
    EXPECT_NEAR(e.relL1, (16 * 0.5 + 16 * 0.1) / (16 * 1.0 + 16 * 3.0), 1e-6);
    EXPECT_NEAR(e.relRmse, std::sqrt((16 * 0.25 + 16 * 0.01) / 32.0) / 2.0, 1e-6);
    // Block relative errors 0.5/1 and 0.1/3; the nearest-rank 95th percentile of two is the larger.
    EXPECT_NEAR(e.p95, 0.5, 1e-6);
    EXPECT_NEAR(r.channels[0].meanRatio, (16 * 1.5 + 16 * 3.0 + 1.6) / 64.0, 1e-6);
    // Without a variance there is no floor: net = error.
    EXPECT_EQ(e.relL1Floor, 0.0);
    EXPECT_NEAR(e.relL1Net, e.relL1, 1e-12);
    EXPECT_NE(formatReport(r).find("4×4 blocks: 2"), std::string::npos);
}

TEST(ErrorMetrics, PartialBlocksAtTheEdgeAndUnderTheMask) {
    // 5×5 pixels: blocks of 4×4, 1×4, 4×1, 1×1. Masking out column 4 leaves two blocks.
    ImageRgb ref(5, 5, Rgb(2.f)), test(5, 5, Rgb(2.f)), cov(5, 5, Rgb(1.f));
    for (int y = 0; y < 5; ++y) {
        cov.at(4, y) = Rgb(0.f);
        test.at(4, y) = Rgb(50.f);  // masked: ignored
    }
    test.at(0, 4) = Rgb(3.f);  // the 4×1 block of the bottom row: mean error 1/4
    const std::vector<uint8_t> mask = maskFromImage(cov);
    const ErrorReport r = compareImages(test, ref, nullptr, nullptr, &mask);
    EXPECT_EQ(r.pixelCount, 20u);
    EXPECT_EQ(r.blockCount, 2u);
    EXPECT_NEAR(r.blocks[0].relL1, (4 * 0.25) / (20 * 2.0), 1e-6);
}

TEST(ErrorMetrics, BlockNoiseFloorIsRemovedInQuadrature) {
    // Test = 1.02 × reference + N(0, σ²), σ = 0.05·v, with the variance layer saying σ². Over
    // 4×4 blocks the noise of a block mean is σ/4; the net (floor-removed) block relative RMSE
    // must recover the 2 % scale error alone: 0.02·√E[v²]/E[v] = 0.02·√(7/3)/1.5 = 0.020367
    // for v uniform in [1, 2]. K = 2500 blocks: the squared error's standard deviation is
    // about √(2/K)·f² + 2·s·f/√K with s = 0.0204 and f = 0.0127 the scale and noise parts,
    // i.e. 2.7 % of s², 1.4 % of s: accept 5σ, 7 %. Pure noise (no scale error): block L1 and
    // its floor agree within 5·√((π/2 − 1)/K) = 7.6 %.
    const int w = 200, h = 200;
    ImageRgb ref(w, h), scaled(w, h), noisy(w, h), var(w, h);
    Pcg32 rng(9);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float v = 1.f + float(x) / w;
            const float sigma = 0.05f * v;
            const float u1 = std::max(rng.uniform(), 1e-12f), u2 = rng.uniform();
            const float n = std::sqrt(-2.f * std::log(u1)) * std::cos(2.f * PI * u2);
            ref.at(x, y) = Rgb(v);
            noisy.at(x, y) = Rgb(v + sigma * n);
            scaled.at(x, y) = Rgb(1.02f * v + sigma * n);
            var.at(x, y) = Rgb(sigma * sigma);
        }
    const ErrorReport s = compareImages(scaled, ref, &var, nullptr, nullptr);
    EXPECT_NEAR(s.blocks[0].relRmseNet / 0.020367, 1.0, 0.07);
    EXPECT_NEAR(s.channels[0].meanRatio, 1.02, 0.002);
    // Per pixel the same scale error is hidden under noise four times larger than a block's.
    EXPECT_GT(s.channels[0].relRmse, 1.5 * s.blocks[0].relRmse);
    const ErrorReport p = compareImages(noisy, ref, &var, nullptr, nullptr);
    EXPECT_NEAR(p.blocks[0].relL1 / p.blocks[0].relL1Floor, 1.0, 0.076);
    // Its squared block RMSE is the squared floor within 5·√(2/K) = 14 %: net ≤ √0.14 floor.
    EXPECT_LT(p.blocks[0].relRmseNet, 0.38 * p.blocks[0].relRmseFloor);
}
