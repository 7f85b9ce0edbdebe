// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Random.h>
#include <lucent/material/History.h>

#include "TestUtil.h"

#include <gtest/gtest.h>

#include <map>

using namespace lucent;
using lucent::test::ballMask;
using lucent::test::bitEqual;
using lucent::test::rawBricks;
using lucent::test::unitGrid;

namespace {

const MaterialSample BASE{Rgb(1.f, 2.f, 3.f), Rgb(0.5f, 1.f, 1.5f), Rgb(0.f, 0.1f, 0.2f)};

BrushSettings randomBrush(Pcg32& rng) {
    BrushSettings b;
    b.mode = BrushMode(rng.uniformBelow(6));
    b.falloff = Falloff(rng.uniformBelow(4));
    b.channels = ChannelMask(1 + rng.uniformBelow(7));
    b.radius = 1.f + 5.f * rng.uniform();
    b.strength = 0.2f + 0.8f * rng.uniform();
    b.spacing = 0.3f + rng.uniform();
    for (int c = 0; c < 3; ++c) {
        b.value.sigma_t[c] = 5.f * rng.uniform();
        b.value.sigma_s[c] = b.value.sigma_t[c] * rng.uniform();
        b.value.g[c] = 0.9f * rng.uniform();
    }
    return b;
}

}  // namespace

TEST(History, UndoRedoIsBitExactAfter1000RandomStrokes) {
    MaterialVolume v(unitGrid(32), BASE);
    v.setInsideMask(ballMask(32, 15.f));
    History h;
    PaintSession session(v, h);
    Pcg32 rng(2026);
    // Snapshots every 100 strokes (a full copy is 1.2 MB; 1000 copies would not be small).
    std::map<int, std::vector<float>> snapshots;
    snapshots[0] = rawBricks(v);
    int stored = 0;
    for (int s = 1; s <= 1000; ++s) {
        const BrushSettings b = randomBrush(rng);
        // Start inside the ball (radius 10 of 15): a stamp of radius ≥ 1 mm always covers a
        // voxel centre (the farthest point from every centre is √3/2 mm away), so every stroke
        // is stored.
        Point3f p;
        do {
            p = Point3f(6.f + 20.f * rng.uniform(), 6.f + 20.f * rng.uniform(),
                        6.f + 20.f * rng.uniform());
        } while (glm::length(p - Point3f(16.f)) > 10.f);
        if (s % 97 == 0) {
            session.fill({Rgb(rng.uniform() + 0.5f), Rgb(0.25f), Rgb(0.f)}, ALL_CHANNELS);
        } else if (s % 2 == 0) {
            session.beginStroke(b);
            for (int k = 0; k < 3; ++k)
                session.strokeTo(p + Vector3f(float(k) * 2.f * rng.uniform(), float(k), 0.f));
            session.endStroke();
        } else {
            session.stroke(b, {p, p + Vector3f(3.f * rng.uniform(), -2.f, 1.f)});
        }
        stored = int(h.undoCount());
        if (s % 100 == 0)
            snapshots[s] = rawBricks(v);
    }
    ASSERT_EQ(stored, 1000);  // every stroke touched the ball (centres are well inside)
    const std::vector<float> final = rawBricks(v);
    for (int s = 1000; s >= 1; --s) {
        ASSERT_TRUE(session.undo());
        if (snapshots.count(s - 1)) {
            ASSERT_TRUE(bitEqual(rawBricks(v), snapshots[s - 1])) << s - 1;
        }
    }
    EXPECT_FALSE(session.undo());
    EXPECT_TRUE(bitEqual(rawBricks(v), snapshots[0]));
    for (int s = 1; s <= 1000; ++s) {
        ASSERT_TRUE(session.redo());
        if (snapshots.count(s)) {
            ASSERT_TRUE(bitEqual(rawBricks(v), snapshots[s])) << s;
        }
    }
    EXPECT_FALSE(session.redo());
    EXPECT_TRUE(bitEqual(rawBricks(v), final));
}

TEST(History, NewStrokeClearsRedoAndUndoMarksDirty) {
    MaterialVolume v(unitGrid(16), BASE);
    History h;
    PaintSession session(v, h);
    BrushSettings b;
    b.radius = 2.f;
    b.value = {Rgb(4.f), Rgb(1.f), Rgb(0.f)};
    session.stamp(b, Point3f(4.f));
    session.stamp(b, Point3f(12.f));
    EXPECT_EQ(h.undoCount(), 2u);
    EXPECT_EQ(h.undoLabel(), "stamp");
    v.takeDirtyBricks();
    EXPECT_TRUE(session.undo());
    const std::vector<int> dirty = v.takeDirtyBricks();
    EXPECT_FALSE(dirty.empty());
    for (int brick : dirty) {
        const Coord o = v.brickOrigin(brick);
        EXPECT_GE(o.x, 8);  // only the bricks around (12, 12, 12) were restored
    }
    EXPECT_EQ(h.redoCount(), 1u);
    session.stamp(b, Point3f(8.f));
    EXPECT_EQ(h.redoCount(), 0u);
    EXPECT_FALSE(session.redo());
    // An empty stroke (outside the grid) is not stored.
    session.stamp(b, Point3f(-50.f));
    EXPECT_EQ(h.undoCount(), 2u);
}

TEST(History, CancelRestoresAndErrorsAreClear) {
    MaterialVolume v(unitGrid(16), BASE);
    History h;
    const std::vector<float> before = rawBricks(v);
    h.beginStroke(v, "test");
    BrushSettings b;
    b.value = {Rgb(4.f), Rgb(1.f), Rgb(0.f)};
    stamp(v, b, Point3f(8.f), &h);
    EXPECT_THROW(h.beginStroke(v), ValueError);
    EXPECT_THROW(h.undo(v), ValueError);
    h.cancelStroke(v);
    EXPECT_TRUE(bitEqual(rawBricks(v), before));
    EXPECT_EQ(h.undoCount(), 0u);
    EXPECT_THROW(h.endStroke(v), ValueError);
    // A history is bound to one grid.
    h.beginStroke(v);
    stamp(v, b, Point3f(8.f), &h);
    h.endStroke(v);
    MaterialVolume other(unitGrid(24), BASE);
    EXPECT_THROW(h.undo(other), ValueError);
    EXPECT_THROW(History(16), ValueError);  // less than one brick
    PaintSession session(v, h);
    EXPECT_THROW(session.strokeTo(Point3f(1.f)), ValueError);
    b.radius = -1.f;
    EXPECT_THROW(session.beginStroke(b), ValueError);
    EXPECT_FALSE(session.isStrokeOpen());
    EXPECT_FALSE(h.isStrokeOpen());
}

namespace {
/// Bytes of one brick's copy (what a one-brick stroke stores, plus bookkeeping).
constexpr size_t BRICK_BYTES =
    size_t(MaterialVolume::BRICK_VOXELS) * MaterialVolume::COMPONENTS * 4;

/// `count` strokes of one stamp each, all in the same single brick, into `h`.
void stampOneBrickStrokes(MaterialVolume& v, History& h, int count) {
    PaintSession session(v, h);
    BrushSettings b;
    b.radius = 1.f;
    b.value = {Rgb(4.f), Rgb(1.f), Rgb(0.f)};
    for (int i = 0; i < count; ++i)
        session.stamp(b, Point3f(4.f));
}
}  // namespace

TEST(History, BudgetDropsOldestStrokes) {
    MaterialVolume v(unitGrid(32), BASE);
    History h(10 * BRICK_BYTES);
    stampOneBrickStrokes(v, h, 30);
    EXPECT_LE(h.bytesUsed(), h.budgetBytes());
    EXPECT_GE(h.undoCount(), 8u);
    EXPECT_LT(h.undoCount(), 10u);
}

TEST(History, LoweringTheBudgetDropsOldestStrokesAtOnce) {
    MaterialVolume v(unitGrid(32), BASE);
    History h;
    stampOneBrickStrokes(v, h, 5);
    ASSERT_EQ(h.undoCount(), 5u);
    // The smallest budget keeps only the newest stroke, so the last edit stays undoable.
    h.setBudgetBytes(BRICK_BYTES);
    EXPECT_EQ(h.undoCount(), 1u);
    EXPECT_EQ(h.budgetBytes(), BRICK_BYTES);
    EXPECT_THROW(h.setBudgetBytes(16), ValueError);  // less than one brick
    EXPECT_EQ(h.budgetBytes(), BRICK_BYTES);
}

TEST(PaintSession, InteractiveStrokeMatchesPolylineStroke) {
    MaterialVolume a(unitGrid(32), BASE), c(unitGrid(32), BASE);
    History ha, hc;
    BrushSettings b;
    b.mode = BrushMode::Add;
    b.radius = 3.f;
    b.spacing = 0.3f;
    b.value = {Rgb(0.5f), Rgb(0.2f), Rgb(0.f)};
    const std::vector<Point3f> path{Point3f(5.f), Point3f(12.f, 5.f, 5.f),
                                    Point3f(12.f, 20.f, 9.f)};
    PaintSession sa(a, ha);
    sa.stroke(b, path);
    PaintSession sc(c, hc);
    sc.beginStroke(b);
    for (const Point3f& p : path)
        sc.strokeTo(p);
    sc.endStroke();
    EXPECT_EQ(ha.undoCount(), 1u);
    EXPECT_EQ(hc.undoCount(), 1u);
    // Same stamps up to float rounding of their positions (≤ 1e-5 mm) → values within 1e-4.
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x)
                for (int k = 0; k < MaterialVolume::COMPONENTS; ++k)
                    ASSERT_NEAR(a.component({x, y, z}, k), c.component({x, y, z}, k), 1e-4f);
}

TEST(PaintSession, ApplyPresetIsUndoable) {
    MaterialVolume v(unitGrid(16), BASE);
    History h;
    PaintSession s(v, h);
    const MaterialSample jade{Rgb(1.f), Rgb(0.9f), Rgb(0.f)};
    s.applyPreset(jade, 1.66f);
    EXPECT_EQ(v.at({3, 3, 3}), jade);
    EXPECT_EQ(v.base(), jade);
    EXPECT_FLOAT_EQ(v.eta(), 1.66f);
    EXPECT_TRUE(s.undo());
    EXPECT_EQ(v.at({3, 3, 3}), BASE);
    EXPECT_THROW(s.applyPreset(jade, 9.f), ValueError);
}
