// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/material/Presets.h>

#include <gtest/gtest.h>

#include <string>

using namespace lucent;

namespace {
// Independent copy of Jensen, Marschner, Levoy, Hanrahan, "A Practical Model for Subsurface
// Light Transport", SIGGRAPH 2001, Figure 5: σs′ and σa in mm⁻¹ (R, G, B); η = 1.3.
struct Row {
    const char* name;
    float ss[3];
    float sa[3];
};
const Row JENSEN_2001[] = {
    {"apple", {2.29f, 2.39f, 1.97f}, {0.0030f, 0.0034f, 0.046f}},
    {"chicken1", {0.15f, 0.21f, 0.38f}, {0.015f, 0.077f, 0.19f}},
    {"chicken2", {0.19f, 0.25f, 0.32f}, {0.018f, 0.088f, 0.20f}},
    {"cream", {7.38f, 5.47f, 3.15f}, {0.0002f, 0.0028f, 0.0163f}},
    {"ketchup", {0.18f, 0.07f, 0.03f}, {0.061f, 0.97f, 1.45f}},
    {"marble", {2.19f, 2.62f, 3.00f}, {0.0021f, 0.0041f, 0.0071f}},
    {"potato", {0.68f, 0.70f, 0.55f}, {0.0024f, 0.0090f, 0.12f}},
    {"skimmilk", {0.70f, 1.22f, 1.90f}, {0.0014f, 0.0025f, 0.0142f}},
    {"skin1", {0.74f, 0.88f, 1.01f}, {0.032f, 0.17f, 0.48f}},
    {"skin2", {1.09f, 1.59f, 1.79f}, {0.013f, 0.070f, 0.145f}},
    {"wholemilk", {2.55f, 3.21f, 3.77f}, {0.0011f, 0.0024f, 0.014f}},
};
}  // namespace

TEST(Presets, MeasuredValuesEqualJensen2001Figure5) {
    const auto& all = allPresets();
    ASSERT_GE(all.size(), std::size(JENSEN_2001));
    for (size_t i = 0; i < std::size(JENSEN_2001); ++i) {
        const Row& r = JENSEN_2001[i];
        SCOPED_TRACE(r.name);
        EXPECT_EQ(all[i].name, r.name);  // measured presets come first, in table order
        const MaterialPreset& p = findPreset(r.name);
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(p.sigma_s_reduced[c], r.ss[c]);  // both parsed from the same decimal text
            EXPECT_EQ(p.sigma_a[c], r.sa[c]);
        }
        EXPECT_EQ(p.eta, 1.3f);
        EXPECT_EQ(p.g, Rgb(0.f));
        EXPECT_NE(p.source.find("Jensen"), std::string::npos);
        const MaterialSample s = p.sample();
        EXPECT_EQ(s.sigma_t, p.sigma_a + p.sigma_s_reduced);
        EXPECT_EQ(s.sigma_s, p.sigma_s_reduced);
    }
}

TEST(Presets, ArtistPresetsCiteTheirSource) {
    for (const char* name : {"jade", "wax", "soap"}) {
        const MaterialPreset& p = findPreset(name);
        EXPECT_FALSE(p.source.empty()) << name;
        EXPECT_NE(p.source.find("not measured"), std::string::npos) << name;
        EXPECT_EQ(sanitize(p.sample()), p.sample()) << name;  // valid material
        EXPECT_GE(p.eta, 1.f);
    }
    EXPECT_EQ(allPresets().size(), std::size(JENSEN_2001) + 3);
}

TEST(Presets, LookupIsCaseInsensitiveAndListsNames) {
    EXPECT_EQ(&findPreset("MARBLE"), &findPreset("marble"));
    EXPECT_EQ(findPreset("Skin1").name, "skin1");
    try {
        findPreset("granite");
        FAIL() << "expected ValueError";
    } catch (const ValueError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("granite"), std::string::npos);
        EXPECT_NE(msg.find("wholemilk"), std::string::npos);
        EXPECT_NE(msg.find("jade"), std::string::npos);
    }
}

TEST(Presets, MalformedJsonIsRejectedWithFieldNames) {
    auto message = [](const std::string& json) {
        try {
            parsePresetJson(json, "x.json");
        } catch (const IoError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message("{").find("x.json"), std::string::npos);
    EXPECT_NE(message(R"({"presets": 3})").find("presets"), std::string::npos);
    EXPECT_NE(
        message(
            R"({"source":"s","presets":[{"name":"a","sigma_s_reduced":[1,2],"sigma_a":[0,0,0],"eta":1.3}]})")
            .find("sigma_s_reduced"),
        std::string::npos);
    EXPECT_NE(
        message(
            R"({"source":"s","presets":[{"name":"a","sigma_s_reduced":[1,2,3],"sigma_a":[0,-1,0],"eta":1.3}]})")
            .find("sigma_a[1]"),
        std::string::npos);
    EXPECT_NE(
        message(
            R"({"source":"s","presets":[{"name":"a","sigma_s_reduced":[1,2,3],"sigma_a":[0,0,0],"eta":7}]})")
            .find("eta"),
        std::string::npos);
    EXPECT_NE(
        message(
            R"({"presets":[{"name":"a","sigma_s_reduced":[1,2,3],"sigma_a":[0,0,0],"eta":1.3}]})")
            .find("source"),
        std::string::npos);
    const auto ok = parsePresetJson(
        R"({"source":"s","presets":[{"name":"a","sigma_s_reduced":[1,2,3],"sigma_a":[0,0,0],"g":[0.5,0,0],"eta":1.5}]})",
        "ok.json");
    ASSERT_EQ(ok.size(), 1u);
    EXPECT_EQ(ok[0].g.r, 0.5f);
    EXPECT_EQ(ok[0].source, "s");
}
