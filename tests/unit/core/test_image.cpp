// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Image.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace lucent;

TEST(Image, ExrRoundTripIsExact) {
    ImageRgb img(7, 5), var(7, 5);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x) {
            img.at(x, y) = Rgb(x * 0.1f, y * 1e3f, 1e-7f * (x + y));
            var.at(x, y) = Rgb(float(x * y));
        }
    const std::string path = std::string(LUCENT_TEST_OUTPUT_DIR) + "/roundtrip.exr";
    writeExrLayers(img, {{"variance", &var}}, path);
    const ImageRgb back = readExr(path), backVar = readExr(path, "variance");
    for (size_t i = 0; i < img.pixels().size(); ++i) {
        EXPECT_EQ(back.pixels()[i], img.pixels()[i]);
        EXPECT_EQ(backVar.pixels()[i], var.pixels()[i]);
    }
}

TEST(Image, PngRoundTripWithin8BitQuantisation) {
    ImageRgb img(4, 4);
    for (int i = 0; i < 16; ++i)
        img.pixels()[i] = Rgb(i / 15.f, 0.5f, 0.f);
    const std::string path = std::string(LUCENT_TEST_OUTPUT_DIR) + "/roundtrip.png";
    writePng(img, path);
    const ImageRgb back = readPng(path);
    // 8-bit sRGB steps are at most 1/255 in display space; in linear space the step is at most
    // (d/dv EOTF ≤ 2.4·1.055^-2.4... ≈ 3) × 1/510 ≈ 6e-3 at the top end.
    for (int i = 0; i < 16; ++i)
        EXPECT_NEAR(back.pixels()[i].r, img.pixels()[i].r, 6e-3f);
}

TEST(Image, MalformedExrIsAClearError) {
    const std::string path = std::string(LUCENT_TEST_OUTPUT_DIR) + "/garbage.exr";
    std::ofstream(path) << "not an exr";
    EXPECT_THROW(readExr(path), IoError);
    EXPECT_THROW(readExr(path + ".missing"), IoError);
}

TEST(Image, FailedWriteLeavesTargetUntouched) {
    const std::string path = std::string(LUCENT_TEST_OUTPUT_DIR) + "/keep.txt";
    std::ofstream(path) << "precious";
    EXPECT_THROW(writeFileAtomically(path,
                                     [](const std::string& tmp) {
                                         std::ofstream(tmp) << "partial";
                                         LUCENT_THROW(IoError, "disk full");
                                     }),
                 IoError);
    std::ifstream in(path);
    std::string s;
    in >> s;
    EXPECT_EQ(s, "precious");
}
