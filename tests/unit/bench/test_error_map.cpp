// SPDX-License-Identifier: MIT
/// @file
/// @brief The block error map (signed, relative, NaN where nothing was compared) agrees with
/// its definition and with compareImages, and area resampling keeps the mean.

#include <lucent/bench/ErrorMap.h>
#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace lucent;
using namespace lucent::bench;

TEST(ErrorMap, SignedRelativeErrorPerBlock) {
    // 8×4 pixels: two 4×4 blocks. Reference 1 everywhere; the test is 1.2× in the left block
    // and 0.5× in the right one.
    ImageRgb ref(8, 4), test(8, 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            ref.at(x, y) = Rgb(1.f);
            test.at(x, y) = Rgb(x < 4 ? 1.2f : 0.5f);
        }
    const BlockErrorMap m = blockErrorMap(test, ref, nullptr);
    ASSERT_EQ(m.width, 2);
    ASSERT_EQ(m.height, 1);
    EXPECT_NEAR(m.at(0, 0), 0.2f, 1e-6f);
    EXPECT_NEAR(m.at(1, 0), -0.5f, 1e-6f);
    // A block without compared pixels is NaN, not 0 (0 would read "exact").
    std::vector<uint8_t> mask(32, 1);
    for (int y = 0; y < 4; ++y)
        for (int x = 4; x < 8; ++x)
            mask[size_t(y * 8 + x)] = 0;
    const BlockErrorMap masked = blockErrorMap(test, ref, &mask);
    EXPECT_NEAR(masked.at(0, 0), 0.2f, 1e-6f);
    EXPECT_TRUE(std::isnan(masked.at(1, 0)));
    // A near-black reference block is measured against a tenth of the mean, not itself.
    ref.at(4, 0) = ref.at(5, 0) = Rgb(0.f);
    for (int y = 0; y < 4; ++y)
        for (int x = 4; x < 8; ++x)
            ref.at(x, y) = Rgb(1e-6f), test.at(x, y) = Rgb(0.f);
    const BlockErrorMap dark = blockErrorMap(test, ref, nullptr);
    EXPECT_GT(dark.at(1, 0), -1e-4f);  // tiny, not −1
}

TEST(ErrorMap, MeanOfAbsoluteBlockErrorsMatchesTheReportWhereTheReferenceIsUniform) {
    // With a uniform reference every block's denominator is b̄, so the pixel-weighted mean of
    // |map| is the report's block relative L1.
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.5f, 1.5f);
    ImageRgb ref(16, 12), test(16, 12);
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 16; ++x) {
            ref.at(x, y) = Rgb(2.f);
            test.at(x, y) = Rgb(2.f * u(rng));
        }
    const BlockErrorMap m = blockErrorMap(test, ref, nullptr);
    double sum = 0.0;
    for (float v : m.values)
        sum += std::abs(v);
    const ErrorReport r = compareImages(test, ref, nullptr, nullptr, nullptr);
    EXPECT_NEAR(sum / double(m.values.size()), r.blocks[ErrorReport::LUMINANCE].relL1, 1e-5);
}

TEST(ErrorMap, RefusesWhatItCannotCompare) {
    EXPECT_THROW(blockErrorMap(ImageRgb(4, 4), ImageRgb(8, 4), nullptr), ValueError);
    EXPECT_THROW(blockErrorMap(ImageRgb(4, 4), ImageRgb(4, 4), nullptr), ValueError);  // black
    ImageRgb ref(4, 4);
    ref.at(0, 0) = Rgb(1.f);
    std::vector<uint8_t> none(16, 0);
    EXPECT_THROW(blockErrorMap(ref, ref, &none), ValueError);
    ImageRgb bad = ref;
    bad.at(1, 1) = Rgb(NAN);
    EXPECT_THROW(blockErrorMap(bad, ref, nullptr), ValueError);
}

TEST(ErrorMap, AreaResamplingKeepsTheMeanAndAverages) {
    ImageRgb img(7, 5);
    double sum = 0.0;
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x) {
            img.at(x, y) = Rgb(float(x + 10 * y), 1.f, float(x * y));
            sum += x + 10 * y;
        }
    for (auto [w, h] : {std::pair{3, 2}, {7, 5}, {14, 9}, {1, 1}}) {
        const ImageRgb r = resampleArea(img, w, h);
        ASSERT_EQ(r.width(), w);
        ASSERT_EQ(r.height(), h);
        double rs = 0.0;
        for (const Rgb& p : r.pixels()) {
            rs += p.r;
            EXPECT_NEAR(p.g, 1.f, 1e-5f);  // a constant stays that constant
        }
        EXPECT_NEAR(rs / (w * h), sum / 35.0, 1e-4) << w << "×" << h;
    }
    // Exact halving: each output pixel is the mean of its 2×2.
    ImageRgb even(4, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x)
            even.at(x, y) = Rgb(float(x + 4 * y));
    const ImageRgb half = resampleArea(even, 2, 1);
    EXPECT_NEAR(half.at(0, 0).r, (0 + 1 + 4 + 5) / 4.f, 1e-6f);
    EXPECT_NEAR(half.at(1, 0).r, (2 + 3 + 6 + 7) / 4.f, 1e-6f);
    EXPECT_THROW(resampleArea(ImageRgb(), 2, 2), ValueError);
    EXPECT_THROW(resampleArea(img, 0, 2), ValueError);
}
