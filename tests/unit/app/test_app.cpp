// SPDX-License-Identifier: MIT
/// @file
/// @brief GUI tests of the `lucent` app under Xvfb: start-up and rendering without GL errors,
/// a non-blank viewport with every preview method (direct, single scattering, SSLPV, dipoles),
/// a stroke changing the SSLPV preview near it through an incremental (dirty-brick) update,
/// simulated mouse strokes changing the expected voxels, undo/redo
/// through the UI actions, eyedropper, slice view, and the save/open/export round trips.

#include "Document.h"
#include "MainWindow.h"
#include "Panels.h"
#if LUCENT_APP_HAS_REFERENCE
#include "ReferencePanel.h"
#endif
#include "SliceView.h"
#include "Viewport.h"

#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#if LUCENT_APP_HAS_IO
#include <lucent/io/VdbIO.h>
#endif

#include <QAction>
#include <QApplication>
#include <QDir>
#include <QDropEvent>
#include <QMimeData>
#include <QUrl>
#include <QSurfaceFormat>
#include <QTest>

#include <gtest/gtest.h>

#include <memory>
#include <cstdio>
#include <set>

namespace lucent::app {
namespace {

/// Every component of every voxel, for bit-exact comparisons.
std::vector<float> snapshot(const MaterialVolume& v) {
    std::vector<float> all;
    for (int c = 0; c < MaterialVolume::COMPONENTS; ++c) {
        const std::vector<float> d = v.denseComponent(c);
        all.insert(all.end(), d.begin(), d.end());
    }
    return all;
}

QString outputPath(const char* name) {
    QDir().mkpath(QStringLiteral(LUCENT_TEST_OUTPUT_DIR));
    return QStringLiteral(LUCENT_TEST_OUTPUT_DIR "/") + QString::fromLatin1(name);
}

/// A window shown at a fixed viewport size with at least `frames` frames rendered.
std::unique_ptr<MainWindow> shownWindow(int frames = 2) {
    auto w = std::make_unique<MainWindow>(/*restoreSettings=*/false);
    w->viewport()->setFixedSize(640, 360);
    w->show();
    EXPECT_TRUE(QTest::qWaitForWindowExposed(w.get()));
    Viewport* vp = w->viewport();
    for (int i = 0; vp->stats().frames < frames && i < frames + 5; ++i) {
        const long long f = vp->stats().frames;
        vp->update();
        EXPECT_TRUE(QTest::qWaitFor([&] { return vp->stats().frames > f; }, 10000));
    }
    return w;
}

/// A brush whose effect is exact: Set mode, constant falloff, full strength.
void setExactBrush(Viewport* vp, const MaterialSample& value, float radius) {
    AppBrush& b = vp->brush();
    b.engine = BrushSettings{};
    b.engine.radius = radius;
    b.engine.falloff = Falloff::Constant;
    b.engine.strength = 1.f;
    b.engine.mode = BrushMode::Set;
    b.engine.channels = ALL_CHANNELS;
    b.engine.value = value;
    b.engine.spacing = 0.25f;
    b.depthMm = 0.f;
    vp->setTool(Viewport::Tool::Paint);
}

const MaterialSample PAINT{Rgb(7.5f, 6.25f, 5.f), Rgb(5.f, 4.f, 3.f), Rgb(0.25f)};

/// Distance from p to the segment [a, b].
float distanceToSegment(const Point3f& p, const Point3f& a, const Point3f& b) {
    const Vector3f ab = b - a;
    const float len2 = glm::dot(ab, ab);
    const float t = len2 > 0.f ? std::clamp(glm::dot(p - a, ab) / len2, 0.f, 1.f) : 0.f;
    return glm::length(p - (a + t * ab));
}

/// Simulated LMB drag from a to b in `steps` moves.
void drag(QWidget* w, QPoint a, QPoint b, int steps = 12) {
    QTest::mousePress(w, Qt::LeftButton, Qt::NoModifier, a);
    for (int i = 1; i <= steps; ++i)
        QTest::mouseMove(w, a + (b - a) * i / steps);
    QTest::mouseRelease(w, Qt::LeftButton, Qt::NoModifier, b);
}

/// Renders one more frame of the viewport (update → paintGL).
void renderOneFrame(Viewport* vp) {
    const long long f = vp->stats().frames;
    vp->update();
    EXPECT_TRUE(QTest::qWaitFor([&] { return vp->stats().frames > f; }, 20000));
}

/// Pixels that differ from the clear colour (0.16, 0.17, 0.19 → 41, 43, 48) belong to the
/// object: fraction of the image they cover and the number of distinct grey levels among them.
std::pair<double, size_t> objectCoverage(const QImage& img) {
    const QRgb clear = qRgb(41, 43, 48);
    long long object = 0;
    std::set<int> levels;
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x) {
            const QRgb p = img.pixel(x, y);
            if (std::abs(qRed(p) - qRed(clear)) + std::abs(qGreen(p) - qGreen(clear)) +
                    std::abs(qBlue(p) - qBlue(clear)) >
                6) {
                ++object;
                levels.insert(qGray(p));
            }
        }
    return {double(object) / double(img.width() * img.height()), levels.size()};
}

/// Mean |Δ| over the RGB channels of two equally sized images within `rect`, 8-bit levels.
double meanAbsDiff(const QImage& a, const QImage& b, const QRect& rect) {
    double sum = 0.0;
    long long n = 0;
    const QRect r = rect.intersected(a.rect());
    for (int y = r.top(); y <= r.bottom(); ++y)
        for (int x = r.left(); x <= r.right(); ++x) {
            const QRgb p = a.pixel(x, y), q = b.pixel(x, y);
            sum += std::abs(qRed(p) - qRed(q)) + std::abs(qGreen(p) - qGreen(q)) +
                   std::abs(qBlue(p) - qBlue(q));
            n += 3;
        }
    return n > 0 ? sum / double(n) : 0.0;
}

QAction* findAction(MainWindow& w, const char* name) {
    return w.findChild<QAction*>(QString::fromLatin1(name));
}

}  // namespace

TEST(AppStart, RendersDefaultSceneWithoutGlErrors) {
    auto w = shownWindow(3);
    const ViewportStats& s = w->viewport()->stats();
    ASSERT_TRUE(s.initError.isEmpty()) << s.initError.toStdString();
    EXPECT_GE(s.frames, 3);
    EXPECT_EQ(s.glErrors, 0);
    EXPECT_TRUE(w->document()->hasObject());
    EXPECT_GT(w->document()->mesh()->triangleCount(), 0u);
}

TEST(AppStart, ViewportIsNotBlank) {
    auto w = shownWindow(2);
    const QImage img = w->viewport()->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    ASSERT_FALSE(img.isNull());
    img.save(outputPath("app_viewport.png"));
    // Pixels that differ from the clear colour (0.16, 0.17, 0.19 → 41, 43, 48) belong to the
    // object; the default camera frames it, so it must cover a visible part of the view, and
    // it must be shaded (several distinct grey levels), not a flat silhouette.
    const QRgb clear = qRgb(41, 43, 48);
    long long object = 0;
    std::set<int> levels;
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x) {
            const QRgb p = img.pixel(x, y);
            if (std::abs(qRed(p) - qRed(clear)) + std::abs(qGreen(p) - qGreen(clear)) +
                    std::abs(qBlue(p) - qBlue(clear)) >
                6) {
                ++object;
                levels.insert(qGray(p));
            }
        }
    const double coverage = double(object) / double(img.width() * img.height());
    EXPECT_GT(coverage, 0.02) << "object covers " << coverage << " of the viewport";
    EXPECT_GT(levels.size(), 8u) << "object is not shaded";
}

TEST(AppStart, EveryPreviewMethodRendersWithoutGlErrors) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    using M = RenderSettings::Method;
    const std::pair<M, const char*> methods[] = {{M::Direct, "direct"},
                                                 {M::SingleScattering, "single"},
                                                 {M::Sslpv, "sslpv"},
                                                 {M::Dipole, "dipole"},
                                                 {M::BetterDipole, "better_dipole"}};
    std::vector<QImage> images;
    for (const auto& [method, name] : methods) {
        SCOPED_TRACE(name);
        w->setRenderMethod(int(method));
        ASSERT_EQ(vp->renderSettings().method, method);
        renderOneFrame(vp);
        renderOneFrame(vp);
        const ViewportStats& s = vp->stats();
        ASSERT_TRUE(s.initError.isEmpty()) << s.initError.toStdString();
        EXPECT_EQ(s.glErrors, 0);
        const QImage img = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
        ASSERT_FALSE(img.isNull());
        img.save(outputPath((std::string("app_method_") + name + ".png").c_str()));
        const auto [coverage, levels] = objectCoverage(img);
        EXPECT_GT(coverage, 0.02) << "object covers " << coverage << " of the viewport";
        EXPECT_GT(levels, 8u) << "object is not shaded";
        // Every pass the renderer runs is timed for the Statistics dock.
        EXPECT_FALSE(s.preview.passes.empty());
        if (method == M::Sslpv || method == M::Dipole) {
            EXPECT_FALSE(s.preview.methodDetail.empty());
        }
        if (method == M::Dipole) {
            // Progressive refinement while idle: frames keep coming with no update() call.
            const long long f = s.frames;
            EXPECT_TRUE(QTest::qWaitFor([&] { return vp->stats().frames >= f + 2; }, 20000))
                << "the dipole preview does not refine while idle";
        }
        images.push_back(img);
    }
    // Each subsurface method adds its own term: its image differs from the direct one
    // (opaque grey surface) by more than 8-bit rounding over the whole viewport.
    for (size_t i = 1; i < images.size(); ++i)
        EXPECT_GT(meanAbsDiff(images[0], images[i], images[0].rect()), 1.0)
            << methods[i].second << " looks like direct";
    // The other SSLPV settings of the dock: GL propagation, SH order 2, calibrated, 16³.
    RenderSettings rs = vp->renderSettings();
    rs.method = M::Sslpv;
    rs.sslpvGlSolve = true;
    rs.sslpvOrder = 2;
    rs.sslpvCalibrated = true;
    rs.sslpvGrid = 16;
    vp->setRenderSettings(rs);
    renderOneFrame(vp);
    EXPECT_TRUE(vp->stats().initError.isEmpty()) << vp->stats().initError.toStdString();
    EXPECT_EQ(vp->stats().glErrors, 0);
    const auto [coverage, levels] =
        objectCoverage(vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32));
    EXPECT_GT(coverage, 0.02);
    EXPECT_GT(levels, 8u);
}

TEST(AppPaint, StrokeChangesSslpvPixelsNearTheStroke) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    w->setRenderMethod(int(RenderSettings::Method::Sslpv));
    renderOneFrame(vp);
    renderOneFrame(vp);
    const QImage before = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    const int fullBefore = vp->stats().preview.sslpvFullResamples;
    const int incBefore = vp->stats().preview.sslpvIncrementalUpdates;
    // The default scene is back-lit: SSLPV light glows through the thin ears at both ends.
    // Find the right end of the object on the middle row and paint a vertical stroke of a
    // strong absorber (σt 5 mm⁻¹, σs′ 0: albedo 0, no light comes back) over the right ear.
    const int cy = before.height() / 2;
    int xr = -1;
    for (int x = before.width() - 1; x >= 0 && xr < 0; --x)
        if (vp->pickAt(QPointF(x + 0.5, cy + 0.5)))
            xr = x;
    ASSERT_GT(xr, before.width() / 2) << "object not found on the middle row";
    const int xs = xr - 30;
    setExactBrush(vp, {Rgb(5.f), Rgb(0.f), Rgb(0.f)}, 4.f);
    ASSERT_EQ(vp->strokeBetween(QPointF(xs, cy - 30), QPointF(xs, cy + 30)), 1);
    renderOneFrame(vp);
    const QImage after = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    before.save(outputPath("app_sslpv_before.png"));
    after.save(outputPath("app_sslpv_after.png"));
    const ViewportStats& s = vp->stats();
    EXPECT_EQ(s.glErrors, 0);
    // Only the dirty bricks went to the provider: one incremental update, no full resample.
    EXPECT_EQ(s.preview.sslpvFullResamples, fullBefore);
    EXPECT_EQ(s.preview.sslpvIncrementalUpdates, incBefore + 1);
    // Near the stroke (its 60 px plus the 4 mm ≈ 16 px brush) the ear darkens; the left end of
    // the object, more than 40 mm away (over 8 mean free paths of the skin base), barely moves.
    const QRect nearStroke(xs - 20, cy - 45, 40, 90);
    const int xl = before.width() - 1 - xr;  // the object is symmetric about the view centre
    const QRect farAway(xl - 6, cy - 45, 40, 90);
    const double dNear = meanAbsDiff(before, after, nearStroke);
    const double dFar = meanAbsDiff(before, after, farAway);
    std::printf("SSLPV stroke: mean |delta| near %.2f, far %.2f (8-bit levels)\n", dNear, dFar);
    EXPECT_GT(dNear, 2.0) << "SSLPV pixels near the stroke did not change";
    EXPECT_GT(dNear, 4.0 * dFar) << "near " << dNear << ", far " << dFar;
}

TEST(AppPaint, MouseStrokeChangesExpectedVoxels) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    ASSERT_NE(vol, nullptr);
    const float radius = 4.f * vol->spec().voxelSize;
    setExactBrush(vp, PAINT, radius);
    const QPoint a(vp->width() / 2 - 30, vp->height() / 2),
        b(vp->width() / 2 + 30, vp->height() / 2);
    const auto hitA = vp->pickAt(a), hitB = vp->pickAt(b);
    ASSERT_TRUE(hitA && hitB) << "the default camera must show the object at the viewport centre";
    const std::vector<float> before = snapshot(*vol);
    drag(vp, a, b);
    EXPECT_EQ(w->document()->undoStack()->count(), 1);

    // Every changed voxel lies within the radius of the stroke path (the stamps are on the
    // straight path between successive cursor hits; the surface between a and b bends, so
    // allow the chord-to-surface gap: the path is bounded by the hits' segment plus the
    // largest hit-to-chord deviation, at most |a−b|/2 for a convex-ish patch).
    const GridSpec& spec = vol->spec();
    const float slack = 0.5f * glm::length(hitB->position - hitA->position) + spec.voxelSize;
    const size_t n = spec.voxelCount();
    const std::vector<float> after = snapshot(*vol);
    size_t changed = 0;
    for (size_t i = 0; i < n; ++i) {
        bool diff = false;
        for (int c = 0; c < MaterialVolume::COMPONENTS; ++c)
            diff |= before[c * n + i] != after[c * n + i];
        if (!diff)
            continue;
        ++changed;
        const int x = int(i % spec.resolution), y = int((i / spec.resolution) % spec.resolution),
                  z = int(i / (size_t(spec.resolution) * spec.resolution));
        const Point3f p = spec.cellCenter({x, y, z});
        ASSERT_LE(distanceToSegment(p, hitA->position, hitB->position), radius + slack)
            << "voxel " << x << "," << y << "," << z << " changed far from the stroke";
    }
    EXPECT_GT(changed, 0u);
    // The inside voxels within the radius of the first stamp (the press point) hold exactly the
    // brush value: Set mode, constant falloff, strength 1 gives v = u (Brush.h).
    const MaterialSample expected = sanitize(PAINT);
    int checked = 0;
    const Coord c0 = spec.cellOf(hitA->position);
    for (int dz = -4; dz <= 4; ++dz)
        for (int dy = -4; dy <= 4; ++dy)
            for (int dx = -4; dx <= 4; ++dx) {
                const Coord c = c0 + Coord(dx, dy, dz);
                if (!spec.contains(c) || !vol->isInside(c))
                    continue;
                if (glm::length(spec.cellCenter(c) - hitA->position) >= radius)
                    continue;
                const MaterialSample s = vol->at(c);
                EXPECT_EQ(s.sigma_t, expected.sigma_t);
                EXPECT_EQ(s.sigma_s, expected.sigma_s);
                EXPECT_EQ(s.g, expected.g);
                ++checked;
            }
    EXPECT_GT(checked, 10);
    EXPECT_EQ(vp->stats().glErrors, 0);
}

TEST(AppPaint, UndoRedoThroughTheUi) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    setExactBrush(vp, PAINT, 3.f * vol->spec().voxelSize);
    const std::vector<float> before = snapshot(*vol);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    drag(vp, c - QPoint(20, 10), c + QPoint(20, 10));
    const std::vector<float> painted = snapshot(*vol);
    ASSERT_NE(before, painted);
    QAction* undo = findAction(*w, "actionUndo");
    QAction* redo = findAction(*w, "actionRedo");
    ASSERT_TRUE(undo && redo);
    EXPECT_TRUE(undo->isEnabled());
    EXPECT_EQ(undo->shortcut(), QKeySequence(Qt::CTRL | Qt::Key_Z));
    undo->trigger();
    EXPECT_EQ(snapshot(*vol), before) << "undo must restore the volume bit-exactly";
    EXPECT_FALSE(w->document()->isModified());
    EXPECT_TRUE(redo->isEnabled());
    redo->trigger();
    EXPECT_EQ(snapshot(*vol), painted);
    EXPECT_TRUE(w->document()->isModified());
    // The viewport re-renders the restored state without GL errors.
    const long long f = vp->stats().frames;
    undo->trigger();
    EXPECT_TRUE(QTest::qWaitFor([&] { return vp->stats().frames > f; }, 10000));
    EXPECT_EQ(vp->stats().glErrors, 0);
    EXPECT_GT(vp->stats().bricksUploaded, 0);
}

TEST(AppPaint, EyedropperPicksPaintedValue) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    setExactBrush(vp, PAINT, 4.f * vol->spec().voxelSize);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    drag(vp, c, c + QPoint(2, 0), 1);
    // Reset the brush value, then pick it back with the eyedropper.
    vp->brush().engine.value = MaterialSample{Rgb(0.1f), Rgb(0.05f), Rgb(0.f)};
    vp->setTool(Viewport::Tool::Eyedropper);
    QTest::mouseClick(vp, Qt::LeftButton, Qt::NoModifier, c);
    const MaterialSample expected = sanitize(PAINT);
    EXPECT_EQ(vp->brush().engine.value.sigma_t, expected.sigma_t);
    EXPECT_EQ(vp->brush().engine.value.sigma_s, expected.sigma_s);
    EXPECT_NEAR(vp->brush().engine.value.g.r, expected.g.r, 1e-6f);  // spin box mean of RGB
    EXPECT_EQ(vp->tool(), Viewport::Tool::Paint);
}

TEST(AppPaint, SliceViewShowsPaint) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    setExactBrush(vp, PAINT, 4.f * vol->spec().voxelSize);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    const auto hit = vp->pickAt(c);
    ASSERT_TRUE(hit);
    const Coord cell = vol->spec().cellOf(hit->position - hit->normal * vol->spec().voxelSize);
    w->sliceView()->setSlice(2, 0, cell.z);
    const QImage before = w->sliceView()->image();
    drag(vp, c, c + QPoint(2, 0), 1);
    const QImage after = w->sliceView()->image();
    ASSERT_EQ(before.size(), after.size());
    EXPECT_NE(before, after);
    // The painted σt (7.5 mm⁻¹) is the slice maximum when it exceeds the default material:
    // then its voxel maps to the top of the colour map.
    const SliceImage s = renderSlice(*vol, 2, 0, cell.z);
    if (s.maxValue == PAINT.sigma_t.r) {
        const int res = vol->resolution();
        EXPECT_EQ(s.image.pixel(cell.x, res - 1 - cell.y), viridis(1.f));
    }
}

TEST(AppPaint, MeshEditKeepsPaint) {
    if (!MainWindow::hasMeshEdit())
        GTEST_SKIP() << "mesh edits not built";
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    setExactBrush(vp, PAINT, 4.f * vol->spec().voxelSize);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    const auto hit = vp->pickAt(c);
    ASSERT_TRUE(hit);
    drag(vp, c, c + QPoint(2, 0), 1);
    // A voxel two voxels under the surface: inside before and after a subdivision, which moves
    // the surface by much less than a voxel on this smooth mesh.
    const Coord deep =
        vol->spec().cellOf(hit->position - hit->normal * (2.f * vol->spec().voxelSize));
    ASSERT_EQ(vol->at(deep).sigma_t, sanitize(PAINT).sigma_t);
    const size_t before = w->document()->mesh()->triangleCount();
    ASSERT_TRUE(w->applyMeshEdit(MainWindow::MeshEditKind::Subdivide))
        << w->lastError().toStdString();
    EXPECT_EQ(w->document()->mesh()->triangleCount(), 4 * before);  // Loop: ×4 per iteration
    EXPECT_EQ(w->document()->material()->at(deep).sigma_t, sanitize(PAINT).sigma_t);
    EXPECT_TRUE(w->document()->isModified());
    const long long f = vp->stats().frames;
    vp->update();
    EXPECT_TRUE(QTest::qWaitFor([&] { return vp->stats().frames > f; }, 10000));
    EXPECT_EQ(vp->stats().glErrors, 0);
}

TEST(AppPaint, DeformationAnimationRendersAndPausesPainting) {
    if (!Viewport::hasDeformation())
        GTEST_SKIP() << "deformers not built";
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    const QImage rest = vp->grabFramebuffer();
    RenderSettings rs = vp->renderSettings();
    rs.deform = true;
    vp->setRenderSettings(rs);
    // The twist oscillates at 0.5 Hz: 0.4 s later the pose differs visibly from the rest pose.
    QTest::qWait(400);
    const long long f = vp->stats().frames;
    EXPECT_TRUE(QTest::qWaitFor([&] { return vp->stats().frames > f; }, 10000));
    const QImage posed = vp->grabFramebuffer();
    EXPECT_NE(rest, posed);
    EXPECT_EQ(vp->stats().glErrors, 0);
    // Painting is paused: a drag adds no undo step.
    setExactBrush(vp, PAINT, 1.f);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    drag(vp, c, c + QPoint(10, 0), 2);
    EXPECT_EQ(w->document()->undoStack()->count(), 0);
    rs.deform = false;
    vp->setRenderSettings(rs);
}

TEST(AppReference, ProgressiveRenderOffTheUiThread) {
#if LUCENT_APP_HAS_REFERENCE
    auto w = shownWindow();
    ReferencePanel* ref = w->referencePanel();
    ASSERT_NE(ref, nullptr);
    ref->setParameters(/*width=*/48, /*spp=*/3);
    ref->start();
    EXPECT_TRUE(ref->isRunning());
    // The UI thread keeps rendering frames while the path tracer runs.
    const long long f = w->viewport()->stats().frames;
    w->viewport()->update();
    EXPECT_TRUE(QTest::qWaitFor([&] { return w->viewport()->stats().frames > f; }, 10000));
    ASSERT_TRUE(QTest::qWaitFor([&] { return !ref->isRunning(); }, 120000));
    const QImage img = ref->image();
    ASSERT_FALSE(img.isNull());
    EXPECT_EQ(img.width(), 48);
    // The object covers the centre of the view; the lit path-traced image is not all black.
    int lit = 0;
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x)
            lit += qGray(img.pixel(x, y)) > 8;
    EXPECT_GT(lit, 20);
#else
    GTEST_SKIP() << "reference module not built";
#endif
}

TEST(AppFiles, SaveOpenRoundTripOfUniformFill) {
    // A uniform material (fill through the Tools dock's engine path), then save and reopen.
    auto w = shownWindow();
    w->document()->fill(sanitize(PAINT), ALL_CHANNELS);
    ASSERT_TRUE(w->document()->isModified());
    const QString path = outputPath("app_uniform.json");
    ASSERT_TRUE(w->saveTo(path)) << w->lastError().toStdString();
    EXPECT_TRUE(QFile::exists(outputPath("app_uniform.vdb"))) << "sidecar VDB next to the JSON";
    MainWindow other(/*restoreSettings=*/false);
    ASSERT_TRUE(other.openFile(path)) << other.lastError().toStdString();
    EXPECT_EQ(snapshot(*other.document()->material()), snapshot(*w->document()->material()));
}

TEST(AppFiles, SaveOpenRoundTrip) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    setExactBrush(vp, PAINT, 4.f * vol->spec().voxelSize);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    drag(vp, c - QPoint(25, 0), c + QPoint(25, 0));
    ASSERT_TRUE(w->document()->isModified());
    const QString path = outputPath("app_roundtrip.json");
    ASSERT_TRUE(w->saveTo(path));
    EXPECT_FALSE(w->document()->isModified());
    EXPECT_EQ(w->document()->filePath(), path);

    MainWindow other(/*restoreSettings=*/false);
    ASSERT_TRUE(other.openFile(path));
    const MaterialVolume* reopened = other.document()->material();
    ASSERT_NE(reopened, nullptr);
    EXPECT_EQ(reopened->spec(), vol->spec());
    EXPECT_EQ(snapshot(*reopened), snapshot(*vol)) << "project round trip must be bit-exact";
    EXPECT_EQ(other.document()->scene().lights.size(), w->document()->scene().lights.size());
    EXPECT_FALSE(other.document()->isModified());

    // A broken file is reported, and the open project stays.
    const QString bad = outputPath("app_broken.json");
    QFile f(bad);
    ASSERT_TRUE(f.open(QIODevice::WriteOnly));
    f.write("{ not json");
    f.close();
    QTimer::singleShot(200, [] {  // dismiss the error box
        for (QWidget* t : QApplication::topLevelWidgets())
            if (t->inherits("QMessageBox"))
                t->close();
    });
    EXPECT_FALSE(other.openFile(bad));
    EXPECT_EQ(snapshot(*other.document()->material()), snapshot(*vol));
}

TEST(AppFiles, ExportVdbRoundTrip) {
    if (!MainWindow::hasVdbSupport())
        GTEST_SKIP() << "io module not built";
#if LUCENT_APP_HAS_IO
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    setExactBrush(vp, PAINT, 4.f * vol->spec().voxelSize);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    drag(vp, c - QPoint(25, 5), c + QPoint(25, 5));
    const QString path = outputPath("app_export.vdb");
    QFile::remove(path);
    ASSERT_TRUE(w->exportVdbTo(path, /*wait=*/true));
    const ImportedMaterial m = importVdb(path.toStdString());
    EXPECT_EQ(m.volume.spec(), vol->spec());
    EXPECT_EQ(snapshot(m.volume), snapshot(*vol)) << "VDB export must be bit-exact";
    // Import through the UI path as well (drag-and-drop / File ▸ Import VDB).
    MainWindow other(false);
    ASSERT_TRUE(other.openFile(path));
    EXPECT_EQ(snapshot(*other.document()->material()), snapshot(*vol));
#endif
}

TEST(AppFiles, ExportVdbOfUntouchedDefaultScene) {
    if (!MainWindow::hasVdbSupport())
        GTEST_SKIP() << "io module not built";
#if LUCENT_APP_HAS_IO
    MainWindow w(/*restoreSettings=*/false);
    const QString path = outputPath("app_default.vdb");
    QFile::remove(path);
    ASSERT_TRUE(w.exportVdbTo(path, /*wait=*/true)) << w.lastError().toStdString();
    ASSERT_TRUE(QFile::exists(path));
    const ImportedMaterial m = importVdb(path.toStdString());
    EXPECT_EQ(snapshot(m.volume), snapshot(*w.document()->material()));
#endif
}

TEST(AppFiles, ImportMeshByDragAndDrop) {
    if (!MainWindow::hasMeshImport())
        GTEST_SKIP() << "mesh import not built";
    const QString mesh = QStringLiteral(LUCENT_SHARED_DIR "/meshes/suzanne.obj");
    if (!QFile::exists(mesh))
        GTEST_SKIP() << "test mesh absent: " << mesh.toStdString();
    auto w = shownWindow();
    QMimeData data;
    data.setUrls({QUrl::fromLocalFile(mesh)});
    QDropEvent drop(QPointF(10, 10), Qt::CopyAction, &data, Qt::LeftButton, Qt::NoModifier);
    // Delivered straight to the window's event handler (QApplication's drop routing wants a
    // live QDrag session, which a synthetic event does not have).
    static_cast<QObject*>(w.get())->event(&drop);
    ASSERT_TRUE(w->lastError().isEmpty()) << w->lastError().toStdString();
    const TriangleMesh* m = w->document()->mesh();
    ASSERT_NE(m, nullptr);
    EXPECT_LT(m->triangleCount(), 2000u);  // Suzanne: ~1k triangles (the default mesh: 20 480)
    EXPECT_GT(m->triangleCount(), 900u);
    const MaterialVolume* v = w->document()->material();
    ASSERT_NE(v, nullptr);
    size_t inside = 0;
    for (uint8_t f : v->insideMask())
        inside += f;
    EXPECT_GT(inside, 1000u) << "the imported mesh must be voxelised";
    EXPECT_TRUE(w->document()->isModified());
    // It renders and can be painted.
    const long long f = w->viewport()->stats().frames;
    w->viewport()->update();
    EXPECT_TRUE(QTest::qWaitFor([&] { return w->viewport()->stats().frames > f; }, 10000));
    EXPECT_EQ(w->viewport()->stats().glErrors, 0);
}

TEST(AppFiles, BrokenMeshIsReported) {
    const QString bad = outputPath("app_broken.obj");
    QFile file(bad);
    ASSERT_TRUE(file.open(QIODevice::WriteOnly));
    file.write("v 0 0 0\nv nan 1 0\nf 1 2 3\n");
    file.close();
    MainWindow w(/*restoreSettings=*/false);
    const std::vector<float> before = snapshot(*w.document()->material());
    EXPECT_FALSE(w.openFile(bad));
    EXPECT_FALSE(w.lastError().isEmpty());
    EXPECT_EQ(snapshot(*w.document()->material()), before) << "the open scene must be kept";
}

TEST(AppFiles, ExportRenderPngAndExr) {
    auto w = shownWindow();
    const QString png = outputPath("app_render.png"), exr = outputPath("app_render.exr");
    QFile::remove(png);
    QFile::remove(exr);
    ASSERT_TRUE(w->exportRenderTo(png));
    ASSERT_TRUE(w->exportRenderTo(exr));
    const QImage img(png);
    EXPECT_EQ(img.size(), w->viewport()->size() * w->viewport()->devicePixelRatio());
    const ImageRgb lin = readExr(exr.toStdString());
    EXPECT_EQ(lin.width(), img.width());
}

}  // namespace lucent::app

int main(int argc, char** argv) {
    QSurfaceFormat fmt;
    fmt.setVersion(4, 5);
    fmt.setProfile(QSurfaceFormat::CoreProfile);
    fmt.setDepthBufferSize(24);
    QSurfaceFormat::setDefaultFormat(fmt);
    QApplication app(argc, argv);
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
