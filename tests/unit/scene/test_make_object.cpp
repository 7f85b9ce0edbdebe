// SPDX-License-Identifier: MIT
/// @file
/// @brief makeObject (issue 13): the one way a mesh becomes a scene object. Before it, one of
/// the five copies (lucent-cli evaluate --presets) filled the whole grid with material, outside
/// the mesh too; the inside mask must always be set.

#include <lucent/mesh/Procedural.h>
#include <lucent/scene/Scene.h>

#include <gtest/gtest.h>

namespace lucent {
namespace {

TEST(MakeObject, FillsTheMeshOnlyWithTheBaseMaterial) {
    MaterialSample base;
    base.sigma_t = Rgb(2.f, 3.f, 4.f);
    base.sigma_s = Rgb(1.f, 2.f, 3.f);
    const SceneObject obj = makeObject(makeSphere(/*radius=*/5.f, /*subdivisions=*/3), 32, base);
    ASSERT_TRUE(obj.material);
    const MaterialVolume& vol = *obj.material;
    EXPECT_EQ(vol.resolution(), 32);
    EXPECT_EQ(obj.materialSource.resolution, 32);
    EXPECT_TRUE(obj.materialSource.uniform);
    // The grid is GridSpec::around the sphere's bounds: its centre voxel is inside, its corner
    // voxel (outside the sphere, inside the box) is vacuum.
    const Coord centre(16, 16, 16), corner(0, 0, 0);
    EXPECT_TRUE(vol.isInside(centre));
    EXPECT_FALSE(vol.isInside(corner));
    EXPECT_EQ(vol.at(centre).sigma_t, base.sigma_t);
    EXPECT_EQ(vol.at(corner).sigma_t, Rgb(0.f));
    size_t inside = 0;
    for (uint8_t v : vol.insideMask())
        inside += v != 0;
    // A sphere fills π/6 ≈ 52 % of its bounding cube; the grid pads the box by a voxel or so on
    // each side, so well under that but far above zero.
    EXPECT_GT(inside, vol.insideMask().size() / 4);
    EXPECT_LT(inside, vol.insideMask().size() / 2);
}

}  // namespace
}  // namespace lucent
