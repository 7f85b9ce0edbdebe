// SPDX-License-Identifier: MIT
#include <lucent/core/Half.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace lucent;

TEST(Half, RoundTripAndRounding) {
    for (float v : {0.f, 1.f, -2.5f, 65504.f, 6.1035156e-5f, 5.9604645e-8f, 0.1f, 3.14159f}) {
        const float r = halfToFloat(floatToHalf(v));
        // binary16 keeps 11 significant bits: relative error ≤ 2⁻¹¹ for normal values.
        EXPECT_NEAR(r, v, std::abs(v) * 0x1p-11f + 1e-12f) << v;
    }
    EXPECT_TRUE(std::isinf(halfToFloat(floatToHalf(1e6f))));
    EXPECT_EQ(floatToHalf(1.f), 0x3c00);
    EXPECT_EQ(halfToFloat(0x3555), 0.333251953125f);
    // Ties to even: 1 + 2⁻¹¹ lies halfway between 1 (even mantissa) and 1 + 2⁻¹⁰.
    EXPECT_EQ(floatToHalf(1.f + 0x1p-11f), 0x3c00);
    EXPECT_EQ(floatToHalf(1.f + 3.f * 0x1p-11f), 0x3c02);
    // Subnormals: the smallest half is 2⁻²⁴; below half of it, zero (sign kept).
    EXPECT_EQ(floatToHalf(0x1p-24f), 0x0001);
    EXPECT_EQ(halfToFloat(0x0001), 0x1p-24f);
    EXPECT_EQ(floatToHalf(-0x1p-26f), 0x8000);
    EXPECT_TRUE(std::isnan(halfToFloat(floatToHalf(std::nanf("")))));
}
