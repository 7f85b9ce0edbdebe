// SPDX-License-Identifier: MIT
/// @file
/// @brief boundarySkin: which masked-out voxels take material, and which mixture they take.

#include <lucent/material/BoundarySkin.h>
#include <lucent/material/MaterialVolume.h>

#include "TestUtil.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace lucent;
using lucent::test::makeSample;
using lucent::test::unitGrid;

namespace {

MaterialVolume maskedVolume(int n, const std::vector<Coord>& inside, const MaterialSample& base) {
    const GridSpec spec = unitGrid(n);
    MaterialVolume v(spec, base);
    std::vector<uint8_t> mask(spec.voxelCount(), 0);
    for (const Coord& c : inside)
        mask[spec.linearIndex(c)] = 1;
    v.setInsideMask(mask);
    return v;
}

const SkinVoxel* find(const std::vector<SkinVoxel>& skin, const GridSpec& spec, const Coord& c) {
    const size_t i = spec.linearIndex(c);
    const auto it =
        std::find_if(skin.begin(), skin.end(), [&](const SkinVoxel& s) { return s.index == i; });
    return it == skin.end() ? nullptr : &*it;
}

}  // namespace

TEST(BoundarySkin, NoSkinWhenEveryVoxelOrNoVoxelIsInside) {
    const MaterialSample jade = makeSample(Rgb(1.f), Rgb(0.9f), Rgb(0.f));
    MaterialVolume all(unitGrid(6), jade);  // the mask starts all-inside
    EXPECT_TRUE(boundarySkin(all).empty());
    EXPECT_TRUE(boundarySkin(maskedVolume(6, {}, jade)).empty());
}

TEST(BoundarySkin, TheVoxelsAroundOneInsideVoxelCarryItsMaterial) {
    // One inside voxel: its 26 neighbours (6 faces, 12 edges, 8 corners) are the skin, each
    // with the single neighbour's value; the voxels two away are not.
    const MaterialSample base = makeSample(Rgb(2.f, 3.f, 4.f), Rgb(1.f, 2.f, 3.f), Rgb(0.3f));
    const MaterialVolume v = maskedVolume(7, {Coord(3, 3, 3)}, base);
    const std::vector<SkinVoxel> skin = boundarySkin(v);
    ASSERT_EQ(skin.size(), 26u);
    EXPECT_TRUE(
        std::is_sorted(skin.begin(), skin.end(),
                       [](const SkinVoxel& a, const SkinVoxel& b) { return a.index < b.index; }));
    for (const SkinVoxel& s : skin) {
        EXPECT_FLOAT_EQ(s.value.sigma_t.g, 3.f);
        EXPECT_FLOAT_EQ(s.value.sigma_s.b, 3.f);
        EXPECT_FLOAT_EQ(s.value.g.r, 0.3f);
    }
    EXPECT_EQ(find(skin, v.spec(), Coord(1, 3, 3)), nullptr);
    EXPECT_EQ(find(skin, v.spec(), Coord(5, 5, 5)), nullptr);
    ASSERT_NE(find(skin, v.spec(), Coord(4, 4, 4)), nullptr);  // a corner
}

TEST(BoundarySkin, NearestNeighboursMixAsMediaInEqualVolumes) {
    // Inside voxels A (1,2,2), B (3,2,2) and D (2,3,3). (2,2,2) has A and B as face neighbours
    // and takes their mixture; (0,2,2) has only A; (2,1,2) has no inside face neighbour and mixes
    // its edge neighbours A and B; (1,3,2) has the face neighbour A and the edge neighbour D,
    // and the face outranks the edge.
    const GridSpec spec = unitGrid(5);
    MaterialVolume v = maskedVolume(5, {Coord(1, 2, 2), Coord(3, 2, 2), Coord(2, 3, 3)}, {});
    const MaterialSample a = makeSample(Rgb(2.f), Rgb(1.f), Rgb(0.5f));   // σs = 2, σs·g = 1
    const MaterialSample b = makeSample(Rgb(6.f), Rgb(3.f), Rgb(-0.5f));  // σs = 2, σs·g = −1
    v.set(Coord(1, 2, 2), a);
    v.set(Coord(3, 2, 2), b);
    v.set(Coord(2, 3, 3), makeSample(Rgb(9.f), Rgb(1.f), Rgb(0.f)));
    const std::vector<SkinVoxel> skin = boundarySkin(v);

    const SkinVoxel* between = find(skin, spec, Coord(2, 2, 2));
    ASSERT_NE(between, nullptr);
    EXPECT_FLOAT_EQ(between->value.sigma_t.r, 4.f);  // mean σt
    EXPECT_FLOAT_EQ(between->value.sigma_s.r, 2.f);  // mean σs′
    // g = Σσs·g / Σσs = (1 − 1) / 4 = 0.
    EXPECT_NEAR(between->value.g.r, 0.f, 1e-6f);

    const SkinVoxel* outer = find(skin, spec, Coord(0, 2, 2));
    ASSERT_NE(outer, nullptr);
    EXPECT_EQ(outer->value, v.at(Coord(1, 2, 2)));

    const SkinVoxel* below = find(skin, spec, Coord(2, 1, 2));
    ASSERT_NE(below, nullptr);
    EXPECT_FLOAT_EQ(below->value.sigma_t.r, 4.f);

    const SkinVoxel* overA = find(skin, spec, Coord(1, 3, 2));
    ASSERT_NE(overA, nullptr);
    EXPECT_EQ(overA->value, v.at(Coord(1, 2, 2)));
}

TEST(BoundarySkin, GIsWeightedByTheUnreducedScattering) {
    // A: σs′ 1, g 0.5 → σs 2; B: σs′ 1, g 0 → σs 1. Mixed: g = (2·0.5 + 1·0) / 3 = 1/3, and
    // σs′ = (2 + 1)/2 · (1 − 1/3) = 1 = the mean σs′.
    const GridSpec spec = unitGrid(5);
    MaterialVolume v = maskedVolume(5, {Coord(1, 2, 2), Coord(3, 2, 2)}, {});
    v.set(Coord(1, 2, 2), makeSample(Rgb(1.f), Rgb(1.f), Rgb(0.5f)));
    v.set(Coord(3, 2, 2), makeSample(Rgb(1.f), Rgb(1.f), Rgb(0.f)));
    const std::vector<SkinVoxel> skin = boundarySkin(v);
    const SkinVoxel* between = find(skin, spec, Coord(2, 2, 2));
    ASSERT_NE(between, nullptr);
    EXPECT_NEAR(between->value.g.g, 1.f / 3.f, 1e-6f);
    EXPECT_FLOAT_EQ(between->value.sigma_s.g, 1.f);
}
