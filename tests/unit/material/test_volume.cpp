// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Medium.h>

#include "TestUtil.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace lucent;
using lucent::test::unitGrid;

TEST(Sanitize, ClampsIntoTheValidDomain) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    MaterialSample s{Rgb(-1.f, nan, 2e6f), Rgb(5.f, 1.f, nan), Rgb(1.5f, -2.f, nan)};
    s.sigma_t.r = -1.f;
    const MaterialSample o = sanitize(s);
    EXPECT_EQ(o.sigma_t, Rgb(0.f, 0.f, SIGMA_MAX));
    EXPECT_EQ(o.sigma_s, Rgb(0.f, 0.f, 0.f));  // σs′ ≤ σt; NaN → 0
    EXPECT_EQ(o.g, Rgb(G_MAX, -G_MAX, 0.f));
    const MaterialSample ok{Rgb(1.f, 2.f, 3.f), Rgb(0.5f, 2.f, 0.f), Rgb(0.2f)};
    EXPECT_EQ(sanitize(ok), ok);  // valid samples are untouched
    const float inf = std::numeric_limits<float>::infinity();
    EXPECT_EQ(sanitize({Rgb(inf), Rgb(inf), Rgb(-inf)}).sigma_t, Rgb(SIGMA_MAX));
}

TEST(GridSpec, AroundPadsAndCentres) {
    Bounds3f b;
    b.expand(Point3f(-10.f, 0.f, 0.f));
    b.expand(Point3f(10.f, 5.f, 2.f));
    const GridSpec s = GridSpec::around(b, 64, 2.f);
    EXPECT_EQ(s.resolution, 64);
    EXPECT_FLOAT_EQ(s.voxelSize, 20.f / 60.f);  // longest extent over resolution − 2·pad
    const Point3f c = s.bounds().center();
    EXPECT_NEAR(c.x, 0.f, 1e-5f);
    EXPECT_NEAR(c.y, 2.5f, 1e-5f);
    EXPECT_NEAR(c.z, 1.f, 1e-5f);
    EXPECT_TRUE(s.bounds().contains(b.lo) && s.bounds().contains(b.hi));
    EXPECT_THROW(GridSpec::around(b, 8), ValueError);
    EXPECT_THROW(GridSpec::around(b, 512), ValueError);
    EXPECT_THROW(GridSpec::around(Bounds3f{}, 64), ValueError);
    Bounds3f bad = b;
    bad.hi.x = std::numeric_limits<float>::infinity();
    EXPECT_THROW(GridSpec::around(bad, 64), ValueError);
}

TEST(MaterialVolume, BricksAndAccess) {
    const MaterialSample base{Rgb(2.f), Rgb(1.f), Rgb(0.1f)};
    MaterialVolume v(unitGrid(20), base);  // 20 = 2.5 bricks: partial bricks at the top end
    EXPECT_EQ(v.bricksPerAxis(), 3);
    EXPECT_EQ(v.brickCount(), 27);
    EXPECT_EQ(v.at({19, 19, 19}), base);
    EXPECT_EQ(v.brickOrigin(v.brickIndexOf({17, 9, 3})), Coord(16, 8, 0));
    EXPECT_TRUE(v.isHomogeneous());
    v.takeDirtyBricks();
    const uint64_t rev = v.revision();
    const MaterialSample s{Rgb(3.f, 4.f, 5.f), Rgb(9.f, 1.f, 2.f), Rgb(0.f)};
    v.set({17, 9, 3}, s);
    EXPECT_GT(v.revision(), rev);
    const MaterialSample got = v.at({17, 9, 3});
    EXPECT_EQ(got.sigma_s, Rgb(3.f, 1.f, 2.f));  // sanitised: σs′ ≤ σt
    EXPECT_EQ(v.component({17, 9, 3}, MaterialVolume::component(Channel::SigmaT, 2)), 5.f);
    EXPECT_EQ(v.sample(Point3f(17.5f, 9.2f, 3.9f)), got);
    EXPECT_EQ(v.sample(Point3f(-0.1f, 1.f, 1.f)), MaterialSample{});
    EXPECT_FALSE(v.isHomogeneous());
    const std::vector<int> dirty = v.takeDirtyBricks();
    ASSERT_EQ(dirty.size(), 1u);
    EXPECT_EQ(dirty[0], v.brickIndexOf({17, 9, 3}));
    EXPECT_TRUE(v.takeDirtyBricks().empty());
    const std::vector<float> dense =
        v.denseComponent(MaterialVolume::component(Channel::SigmaT, 1));
    ASSERT_EQ(dense.size(), v.spec().voxelCount());
    EXPECT_EQ(dense[v.spec().linearIndex({17, 9, 3})], 4.f);
    EXPECT_EQ(dense[v.spec().linearIndex({0, 0, 0})], 2.f);
    EXPECT_THROW(v.denseComponent(9), ValueError);
    EXPECT_THROW(v.set({20, 0, 0}, s), ValueError);
    EXPECT_THROW(v.setEta(0.5f), ValueError);
    EXPECT_THROW(v.setEta(std::nanf("")), ValueError);
    v.setEta(1.5f);
    EXPECT_EQ(v.eta(), 1.5f);
}

TEST(MaterialVolume, ContentHashFollowsValuesAndMask) {
    const MaterialSample base{Rgb(2.f), Rgb(1.f), Rgb(0.1f)};
    MaterialVolume a(unitGrid(16), base), b(unitGrid(16), base);
    EXPECT_EQ(a.contentHash(), b.contentHash());
    const uint64_t before = a.contentHash();
    a.set({3, 4, 5}, {Rgb(2.f), Rgb(1.f), Rgb(0.2f)});  // one component of one voxel
    EXPECT_NE(a.contentHash(), before);
    a.set({3, 4, 5}, base);
    EXPECT_EQ(a.contentHash(), before);
    std::vector<uint8_t> mask = b.insideMask();
    mask[0] = 0;
    b.setInsideMask(mask);
    EXPECT_NE(b.contentHash(), before);
}

TEST(MaterialVolume, InsideMask) {
    const MaterialSample base{Rgb(2.f), Rgb(1.f), Rgb(0.f)};
    MaterialVolume v(unitGrid(16), base);
    std::vector<uint8_t> mask(v.spec().voxelCount(), 0);
    mask[v.spec().linearIndex({3, 3, 3})] = 1;
    v.takeDirtyBricks();
    v.setInsideMask(mask);
    EXPECT_EQ(v.takeDirtyBricks().size(), size_t(v.brickCount()));
    EXPECT_EQ(v.at({4, 4, 4}), MaterialSample{});
    EXPECT_EQ(v.component({4, 4, 4}, 0), 0.f);  // outside voxels are stored as zero
    EXPECT_EQ(v.at({3, 3, 3}), base);
    EXPECT_TRUE(v.brickHasInside(0));
    EXPECT_FALSE(v.brickHasInside(1));
    v.set({4, 4, 4}, {Rgb(9.f), Rgb(1.f), Rgb(0.f)});  // ignored: masked out
    EXPECT_EQ(v.at({4, 4, 4}), MaterialSample{});
    EXPECT_TRUE(v.isHomogeneous());
    v.setBase({Rgb(7.f), Rgb(1.f), Rgb(0.f)});
    mask[v.spec().linearIndex({4, 4, 4})] = 1;
    v.setInsideMask(mask);
    EXPECT_EQ(v.at({4, 4, 4}).sigma_t, Rgb(7.f));  // newly inside voxels get the base
    EXPECT_EQ(v.at({3, 3, 3}).sigma_t, Rgb(2.f));  // kept
    EXPECT_THROW(v.setInsideMask(std::vector<uint8_t>(10, 1)), ValueError);
}

TEST(MaterialVolume, RejectsBadSpec) {
    GridSpec s = unitGrid(16);
    s.voxelSize = -1.f;
    EXPECT_THROW(MaterialVolume(s, {}), ValueError);
    s = unitGrid(0);
    EXPECT_THROW(MaterialVolume(s, {}), ValueError);
    s = unitGrid(16);
    s.origin.x = std::nanf("");
    EXPECT_THROW(MaterialVolume(s, {}), ValueError);
}
