// SPDX-License-Identifier: MIT
/// @file
/// @brief GUI tests of the `lucent` app under Xvfb: start-up and rendering without GL errors,
/// a non-blank viewport with every preview method (direct, single scattering, SSLPV, dipoles),
/// a stroke changing the SSLPV preview near it through an incremental (dirty-brick) update,
/// simulated mouse strokes changing the expected voxels, undo/redo
/// through the UI actions, eyedropper, slice view, and the save/open/export round trips; input,
/// drops and screenshots through the viewport's real GL window (a QOpenGLWindow in a window
/// container).

#include "Document.h"
#include "ImageView.h"
#include "MainWindow.h"
#include "Panels.h"
#include "ReferencePanel.h"
#include "SliceView.h"
#include "Viewport.h"
#include "GuiTestWaits.h"
#include "KeepLibrariesLoaded.h"

#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/scene/SceneFile.h>
#include <lucent/gpu/Shader.h>
#include <lucent/io/VdbIO.h>
#include <lucent/planner/LiveCosts.h>

#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QLabel>
#include <QMessageBox>
#include <QPointingDevice>
#include <QPushButton>
#include <QScreen>
#include <QSignalSpy>
#include <QSpinBox>
#include <QStatusBar>
#include <QStandardItemModel>
#include <QStandardPaths>
#include <QTabletEvent>
#include <QDir>
#include <QDockWidget>
#include <QDropEvent>
#include <QLineEdit>
#include <QJsonArray>
#include <QJsonDocument>
#include <QJsonObject>
#include <QMimeData>
#include <QUrl>
#include <QSurfaceFormat>
#include <QTest>
#include <QWheelEvent>
#include <QWindow>

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
    EXPECT_TRUE(QTest::qWaitForWindowExposed(w.get(), test::kWindowWaitMs));
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

/// Rightmost pixel column of row `y` whose centre hits the object, −1 for none.
int rightEndOnRow(const Viewport* vp, int y) {
    for (int x = vp->width() - 1; x >= 0; --x)
        if (vp->pickAt(QPointF(x + 0.5, y + 0.5)))
            return x;
    return -1;
}

/// The shared test mesh of the drop tests: under $LUCENT_SHARED_DIR when set (a worktree
/// outside the main checkout), else the build's shared folder.
QString suzannePath() {
    const QString dir = qEnvironmentVariableIsSet("LUCENT_SHARED_DIR")
                            ? qEnvironmentVariable("LUCENT_SHARED_DIR")
                            : QStringLiteral(LUCENT_SHARED_DIR);
    return dir + QStringLiteral("/meshes/suzanne.obj");
}

/// Why the drop tests cannot run; empty when they can.
std::string meshDropSkipReason() {
    if (!QFile::exists(suzannePath()))
        return "test mesh absent: " + suzannePath().toStdString();
    return {};
}

/// Drag data of the test mesh as a file manager sends it.
std::unique_ptr<QMimeData> suzanneDragData() {
    auto data = std::make_unique<QMimeData>();
    data->setUrls({QUrl::fromLocalFile(suzannePath())});
    return data;
}

/// The document holds Suzanne (~1k triangles; the default mesh has 20 480).
void expectSuzanneOpened(MainWindow& w) {
    ASSERT_TRUE(w.lastError().isEmpty()) << w.lastError().toStdString();
    const TriangleMesh* m = w.document()->mesh();
    ASSERT_NE(m, nullptr);
    EXPECT_LT(m->triangleCount(), 2000u);
    EXPECT_GT(m->triangleCount(), 900u);
}

QAction* findAction(MainWindow& w, const char* name) {
    return w.findChild<QAction*>(QString::fromLatin1(name));
}

}  // namespace

TEST(AppStart, RendersDefaultSceneWithoutGlErrors) {
    auto w = shownWindow(3);
    const ViewportStats& s = w->viewport()->stats();
    ASSERT_TRUE(s.initError.isEmpty()) << s.initError.toStdString();
    EXPECT_TRUE(s.renderError.isEmpty()) << s.renderError.toStdString();
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

namespace {
/// Mean |Δ| (8-bit levels, RGB) that a dark, absorbing stroke across the middle of the default
/// view makes within 12 px of it, with the method selected, after `frames` frames (progressive
/// methods refine meanwhile).
double darkStrokeContrast(const std::string& method, int frames) {
    auto w = std::make_unique<MainWindow>(/*restoreSettings=*/false);
    EXPECT_TRUE(w->setRenderMethod(QString::fromStdString(method))) << method;
    Viewport* vp = w->viewport();
    vp->setFixedSize(640, 360);
    w->show();
    EXPECT_TRUE(QTest::qWaitForWindowExposed(w.get(), test::kWindowWaitMs));
    // Auto plans with the live-cost table's own unit, so that its choice is the one it makes
    // on the measuring machine whatever the load of this one (under load a slower Direct frame
    // rightly makes fewer methods fit 50 ms).
    vp->previewRenderer().pinAutoDirectMs(planner::defaultLiveCosts().directMs);
    EXPECT_TRUE(QTest::qWaitFor(
        [&] {
            renderOneFrame(vp);
            return !vp->previewRenderer().isPlanning();
        },
        120000));
    for (int i = 0; i < frames; ++i)
        renderOneFrame(vp);
    const QImage before = vp->grabRender().convertToFormat(QImage::Format_RGB32);
    // Charcoal: strongly absorbing, little scattering (albedo 0.05).
    setExactBrush(vp, MaterialSample{Rgb(6.f), Rgb(0.3f), Rgb(0.f)}, 3.f);
    const QPoint a(vp->width() / 2 - 60, vp->height() / 2),
        b(vp->width() / 2 + 60, vp->height() / 2);
    EXPECT_EQ(vp->strokeBetween(a, b), 1);
    for (int i = 0; i < frames; ++i)
        renderOneFrame(vp);
    const QImage after = vp->grabRender().convertToFormat(QImage::Format_RGB32);
    return meanAbsDiff(before, after, QRect(a - QPoint(0, 12), b + QPoint(0, 12)));
}
}  // namespace

// Issue 17, item 3: the default preview (SSLPV Paper 32³) showed a black, blocky body on which
// a dark stroke was invisible. The default method must show such a stroke.
TEST(AppStart, DefaultMethodShowsADarkStroke) {
    const std::string def = RenderSettings{}.method;
    // 8 frames: what an artist sees about a second after the stroke on llvmpipe.
    const double contrast = darkStrokeContrast(def, 8);
    // 3 levels over the band around the stroke (half of it is off the 3 mm brush): the old
    // default (SSLPV Paper 32³) measured 0.2 here; every other subsurface method 32–36.
    EXPECT_GT(contrast, 3.0) << "default method " << def;
    if (qEnvironmentVariableIsSet("LUCENT_MEASURE_METHODS"))
        for (const methods::MethodInfo* info : PreviewRenderer::previewMethods())
            std::printf("dark stroke contrast, %s: %.2f levels\n", info->title.c_str(),
                        darkStrokeContrast(info->name, 8));
}

TEST(AppStart, EveryPreviewMethodRendersWithoutGlErrors) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    const std::string methods[] = {"direct", "single-scattering", "sslpv", "dipole",
                                   "better-dipole"};
    std::vector<QImage> images;
    for (const std::string& method : methods) {
        SCOPED_TRACE(method);
        ASSERT_TRUE(w->setRenderMethod(QString::fromStdString(method)));
        ASSERT_EQ(vp->renderSettings().method, method);
        renderOneFrame(vp);
        renderOneFrame(vp);
        const ViewportStats& s = vp->stats();
        ASSERT_TRUE(s.renderError.isEmpty()) << s.renderError.toStdString();
        EXPECT_EQ(s.glErrors, 0);
        const QImage img = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
        ASSERT_FALSE(img.isNull());
        img.save(outputPath(("app_method_" + method + ".png").c_str()));
        const auto [coverage, levels] = objectCoverage(img);
        EXPECT_GT(coverage, 0.02) << "object covers " << coverage << " of the viewport";
        EXPECT_GT(levels, 8u) << "object is not shaded";
        // Every pass the renderer runs is timed for the Statistics dock.
        EXPECT_FALSE(s.preview.passes.empty());
        // The method's own numbers (Method::stats) reach the Statistics dock.
        EXPECT_EQ(s.preview.method, method);
        if (method == "sslpv" || method == "dipole") {
            EXPECT_FALSE(s.preview.methodStats.empty());
        }
        if (method == "dipole") {
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
            << methods[i] << " looks like direct";
    // The other SSLPV settings of the dock: GL propagation, SH order 2, calibrated, 16³.
    RenderSettings rs = vp->renderSettings();
    rs.method = "sslpv";
    rs.params = methods::ParamSet::fromAssignments(
        {"propagation=gl", "sh=2", "mode=calibrated", "grid=16"});
    vp->setRenderSettings(rs);
    renderOneFrame(vp);
    EXPECT_TRUE(vp->stats().renderError.isEmpty()) << vp->stats().renderError.toStdString();
    EXPECT_EQ(vp->stats().glErrors, 0);
    const auto [coverage, levels] =
        objectCoverage(vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32));
    EXPECT_GT(coverage, 0.02);
    EXPECT_GT(levels, 8u);
}

TEST(AppPaint, StrokeChangesSslpvPixelsNearTheStroke) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("sslpv")));
    renderOneFrame(vp);
    renderOneFrame(vp);
    const QImage before = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    // SSLPV's Method::stats() keys (engine/src/methods/sslpv/SslpvMethod.cpp).
    const auto stat = [vp](const char* key) {
        return std::stoi(vp->stats().preview.methodStat(key));
    };
    const int fullBefore = stat("full resamples");
    const int incBefore = stat("incremental updates");
    // The default scene is back-lit: SSLPV light glows through the thin ears at both ends.
    // Find the right end of the object on the middle row and paint a vertical stroke of a
    // strong absorber (σt 5 mm⁻¹, σs′ 0: albedo 0, no light comes back) over the right ear.
    const int cy = before.height() / 2;
    const int xr = rightEndOnRow(vp, cy);
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
    EXPECT_EQ(stat("full resamples"), fullBefore);
    EXPECT_EQ(stat("incremental updates"), incBefore + 1);
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

// The image-space dipole in the app after a stroke (docs/methods/dipole.md §3c, "Material-only
// restarts"): once the preview has refined, a stroke restarts only the pixels whose material it
// changed, so the stroke's frame changes the image near the stroke and keeps the rest of the
// refined image (it only goes on refining). Before, every stroke dropped the whole image back
// to a noisy 4-sample preview: the far region then moved by whole 8-bit levels.
TEST(AppPaint, DipoleStrokeKeepsTheRefinedImageAwayFromIt) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("dipole")));
    // The dipole's Method::stats() keys (engine/src/methods/dipole/DipoleMethod.cpp).
    const auto stat = [vp](const char* key) { return vp->stats().preview.methodStat(key); };
    ASSERT_TRUE(QTest::qWaitFor([&] { return std::atoi(stat("frames").c_str()) >= 8; }, 60000))
        << "the dipole preview did not refine to 8 frames while idle";
    const QImage before = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    const int cy = before.height() / 2;
    const int xr = rightEndOnRow(vp, cy);
    ASSERT_GT(xr, before.width() / 2) << "object not found on the middle row";
    const int xs = xr - 30;
    setExactBrush(vp, {Rgb(5.f), Rgb(0.f), Rgb(0.f)}, 4.f);
    ASSERT_EQ(vp->strokeBetween(QPointF(xs, cy - 30), QPointF(xs, cy + 30)), 1);
    renderOneFrame(vp);
    const QImage after = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    before.save(outputPath("app_dipole_before.png"));
    after.save(outputPath("app_dipole_after.png"));
    EXPECT_EQ(vp->stats().glErrors, 0);
    EXPECT_GT(std::atoi(stat("pixels restarted by the last stroke").c_str()), 0);
    const QRect nearStroke(xs - 20, cy - 45, 40, 90);
    const int xl = before.width() - 1 - xr;  // the object is symmetric about the view centre
    const QRect farAway(xl - 6, cy - 45, 40, 90);
    const double dNear = meanAbsDiff(before, after, nearStroke);
    const double dFar = meanAbsDiff(before, after, farAway);
    std::printf("dipole stroke: mean |delta| near %.2f, far %.4f (8-bit levels)\n", dNear, dFar);
    EXPECT_GT(dNear, 2.0) << "dipole pixels near the stroke did not change";
    // Away from it only the idle refinement moves pixels (a frame more of 8+): well under a
    // level on average.
    EXPECT_LT(dFar, 0.25) << "the refined image away from the stroke was not kept";
    EXPECT_GT(dNear, 8.0 * dFar) << "near " << dNear << ", far " << dFar;
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

namespace {
/// Leftmost pixel column of row `y` whose centre hits the object, −1 for none.
int leftEndOnRow(const Viewport* vp, int y) {
    for (int x = 0; x < vp->width(); ++x)
        if (vp->pickAt(QPointF(x + 0.5, y + 0.5)))
            return x;
    return -1;
}
}  // namespace

// Issue 17, item 6: a stroke that started beside the object was dropped silently. It now paints
// from where the drag reaches the surface, and a drag that never reaches it says so.
TEST(AppPaint, StrokeStartingOffTheObjectPaintsFromWhereItReachesIt) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    setExactBrush(vp, PAINT, 3.f * vol->spec().voxelSize);
    const int y = vp->height() / 2;
    const int left = leftEndOnRow(vp, y), right = rightEndOnRow(vp, y);
    ASSERT_GT(left, 10) << "the default view must leave room beside the object";
    ASSERT_GT(right, left + 20);
    QSignalSpy refused(vp, &Viewport::paintError);
    const std::vector<float> before = snapshot(*vol);
    drag(vp, QPoint(left - 10, y), QPoint((left + right) / 2, y), 24);
    EXPECT_NE(snapshot(*vol), before) << "the stroke was dropped";
    EXPECT_EQ(w->document()->undoStack()->count(), 1);
    EXPECT_EQ(refused.count(), 0);
    // The first stamp is where the drag met the surface: the voxel under the object's edge on
    // that row is painted.
    const auto edge = vp->pickAt(QPointF(left + 1.5, y + 0.5));
    ASSERT_TRUE(edge);
    const Coord c =
        vol->spec().cellOf(edge->position - edge->normal * (0.5f * vol->spec().voxelSize));
    EXPECT_EQ(vol->at(c).sigma_t, sanitize(PAINT).sigma_t);
    // Entirely beside the object: nothing painted, and the user is told why.
    const std::vector<float> painted = snapshot(*vol);
    drag(vp, QPoint(2, 2), QPoint(std::max(3, left - 5), 2), 8);
    EXPECT_EQ(snapshot(*vol), painted);
    ASSERT_EQ(refused.count(), 1);
    EXPECT_TRUE(refused[0][0].toString().contains(QStringLiteral("never reached")))
        << refused[0][0].toString().toStdString();
}

// Issue 17, item 9: the status bar's voxel readout stayed on the last voxel once the cursor
// left the object.
TEST(AppPaint, VoxelReadoutClearsOffTheObject) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    QSignalSpy readout(vp, &Viewport::hoverVoxel);
    const QPoint centre(vp->width() / 2, vp->height() / 2);
    ASSERT_TRUE(vp->pickAt(centre));
    QTest::mouseMove(vp, centre);
    ASSERT_TRUE(QTest::qWaitFor([&] { return readout.count() >= 1; }, 2000));
    EXPECT_TRUE(readout.last()[0].toString().startsWith(QStringLiteral("voxel (")));
    ASSERT_FALSE(vp->pickAt(QPoint(2, 2)));
    QTest::mouseMove(vp, QPoint(2, 2));
    ASSERT_TRUE(QTest::qWaitFor([&] { return readout.count() >= 2; }, 2000));
    EXPECT_TRUE(readout.last()[0].toString().isEmpty()) << "stale readout off the object";
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

    // The preview's accuracy against it: compared when the reference is done, shown as a
    // block error heat-map on request, refused (with the reason) once the view has moved.
    EXPECT_GT(ref->blockRelL1(), 0.0);
    EXPECT_TRUE(std::isfinite(ref->blockRelL1()));
    EXPECT_GT(ref->meanRatio(), 0.0);
    auto* accuracy = ref->findChild<QLabel*>(QStringLiteral("referenceAccuracy"));
    ASSERT_TRUE(accuracy);
    EXPECT_TRUE(accuracy->text().contains(QStringLiteral("block error")))
        << accuracy->text().toStdString();
    EXPECT_TRUE(accuracy->text().contains(QStringLiteral("noise")))
        << accuracy->text().toStdString();
    ref->setView(ReferencePanel::View::ErrorMap);
    auto* picture = ref->findChild<ImageView*>(QStringLiteral("referencePicture"));
    ASSERT_TRUE(picture);
    EXPECT_FALSE(picture->image().isNull());
    EXPECT_EQ(picture->image().width(), 48) << "one heat-map pixel per reference pixel";
    w->viewport()->camera().yawDeg += 20.f;
    EXPECT_FALSE(ref->compareWithPreview());
    EXPECT_TRUE(accuracy->text().contains(QStringLiteral("view changed")))
        << accuracy->text().toStdString();
}

// ---- Light gizmos ---------------------------------------------------------------------------

/// Unit view direction of the viewport's camera.
Vector3f viewForward(Viewport* vp) {
    return glm::normalize(vp->camera().target - vp->camera().eye());
}

TEST(AppLights, DragMovesPointLightOnTheViewPlaneAndUndoRestoresIt) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    Document* doc = w->document();
    ASSERT_GE(doc->scene().lights.size(), 1u);
    // Light 0 of the default scene: the back light, behind the object but on screen.
    const Light original = doc->scene().lights[0];
    const auto handle = vp->lightHandle(0);
    ASSERT_TRUE(handle);
    ASSERT_TRUE(vp->rect().contains(handle->toPoint())) << "back light handle off screen";
    const QPoint press = handle->toPoint();  // within a pixel of the handle
    ASSERT_EQ(vp->lightAt(press), 0);
    const QPoint delta(40, -25);
    drag(vp, press, press + delta, 8);
    // One undo step, and no paint: the press picked the handle, not the surface below it.
    EXPECT_EQ(doc->undoStack()->count(), 1);
    EXPECT_EQ(doc->history().undoCount(), 0u);
    EXPECT_EQ(vp->selectedLight(), 0);
    const Light& moved = doc->scene().lights[0];
    // On the view-aligned plane through the light: depth unchanged, handle follows the cursor.
    const Vector3f fwd = viewForward(vp);
    const Point3f eye = vp->camera().eye();
    const float depth = glm::dot(original.position - eye, fwd);
    EXPECT_NEAR(glm::dot(moved.position - eye, fwd), depth, 1e-3f * depth);
    const auto movedHandle = vp->lightHandle(0);
    ASSERT_TRUE(movedHandle);
    // Float rounding of the ray/plane maths at ~200 mm: far below 0.01 px.
    EXPECT_NEAR(movedHandle->x(), handle->x() + delta.x(), 0.01);
    EXPECT_NEAR(movedHandle->y(), handle->y() + delta.y(), 0.01);
    // The pinhole maps a plane at depth d with 2·d·tan(fov/2)/H mm per pixel.
    const double mmPerPixel = 2.0 * double(depth) *
                              std::tan(0.5 * double(glm::radians(vp->camera().fovYDeg))) /
                              double(vp->height());
    const double expected = std::hypot(delta.x(), delta.y()) * mmPerPixel;
    EXPECT_NEAR(double(glm::length(moved.position - original.position)), expected, 1e-4 * expected);
    // The Lights dock shows the dragged light and its new position.
    EXPECT_EQ(w->lightPanel()->currentLight(), 0);
    auto* posX = w->lightPanel()->findChild<QDoubleSpinBox*>(QStringLiteral("lightPos0"));
    ASSERT_NE(posX, nullptr);
    EXPECT_NEAR(posX->value(), double(moved.position.x), 0.005);  // 2 decimals shown
    const Point3f movedPosition = moved.position;
    // Undo restores the light bit-exactly; redo moves it back.
    QAction* undo = findAction(*w, "actionUndo");
    QAction* redo = findAction(*w, "actionRedo");
    undo->trigger();
    EXPECT_EQ(doc->scene().lights[0].position, original.position);
    EXPECT_NEAR(posX->value(), double(original.position.x), 0.005);
    EXPECT_FALSE(doc->isModified());
    redo->trigger();
    EXPECT_EQ(doc->scene().lights[0].position, movedPosition);
    renderOneFrame(vp);
    EXPECT_EQ(vp->stats().glErrors, 0);
    // The gizmo is drawn in the light's colour over the frame, hidden in the exported render.
    const QImage shown = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    const QImage bare = vp->grabRender().convertToFormat(QImage::Format_RGB32);
    const QPoint h = vp->lightHandle(0)->toPoint();
    EXPECT_GT(meanAbsDiff(shown, bare, QRect(h - QPoint(3, 3), QSize(7, 7))), 20.0)
        << "no gizmo drawn at the light's handle";
}

TEST(AppLights, DragMovesDirectionalLightOnTheGizmoSphere) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    Document* doc = w->document();
    // A directional light travelling away from the viewer: its handle is in front of the object.
    std::vector<Light> lights = doc->scene().lights;
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = glm::normalize(Vector3f(-0.3f, -0.2f, -1.f));
    sun.intensity = Rgb(1.f, 0.8f, 0.5f);
    lights.push_back(sun);
    doc->setLights(lights, QStringLiteral("Add sun"));
    const int index = int(lights.size()) - 1;
    EXPECT_EQ(doc->undoStack()->count(), 1);
    const auto handle = vp->lightHandle(index);
    ASSERT_TRUE(handle);
    const QPoint press = handle->toPoint();
    ASSERT_EQ(vp->lightAt(press), index);
    Point3f center;
    float radius = 0.f;
    vp->gizmoSphere(center, radius);
    const auto c = vp->project(center);
    ASSERT_TRUE(c);
    // Release on the far side of the sphere's centre, well inside its outline.
    const QPoint release = (c->toPoint() * 2 + (c->toPoint() - press)) / 3;
    drag(vp, press, release, 10);
    ASSERT_EQ(doc->undoStack()->count(), 2);
    const Light& moved = doc->scene().lights[size_t(index)];
    EXPECT_NEAR(glm::length(moved.direction), 1.f, 1e-6f);
    // The handle sits where the cursor was released, on the sphere, and the light shines
    // from it through the centre. Float rounding of a ray–sphere hit: below 0.01 px.
    const auto movedHandle = vp->lightHandle(index);
    ASSERT_TRUE(movedHandle);
    EXPECT_NEAR(movedHandle->x(), double(release.x()), 0.01);
    EXPECT_NEAR(movedHandle->y(), double(release.y()), 0.01);
    const Point3f h = *vp->lightHandleWorld(index);
    EXPECT_NEAR(glm::length(h - center), radius, 1e-4f * radius);
    EXPECT_LT(glm::length(glm::normalize(center - h) - moved.direction), 1e-5f);
    // The dock followed the selection and shows the new direction (3 decimals).
    EXPECT_EQ(w->lightPanel()->currentLight(), index);
    for (int k = 0; k < 3; ++k) {
        auto* f = w->lightPanel()->findChild<QDoubleSpinBox*>(QStringLiteral("lightDir%1").arg(k));
        ASSERT_NE(f, nullptr);
        EXPECT_NEAR(f->value(), double(moved.direction[k]), 5e-4);
    }
    renderOneFrame(vp);
    EXPECT_EQ(vp->stats().glErrors, 0);
    vp->grabWithFrame(w.get()).save(outputPath("app_light_gizmo_window.png"));
    // Undo: the drag, then the added light.
    QAction* undo = findAction(*w, "actionUndo");
    undo->trigger();
    EXPECT_EQ(doc->scene().lights[size_t(index)].direction, sun.direction);
    undo->trigger();
    EXPECT_EQ(doc->scene().lights.size(), size_t(index));
    EXPECT_EQ(w->lightPanel()->currentLight(), index - 1);
}

// ---- Tablet pressure ------------------------------------------------------------------------

/// The simulated pen of the tablet tests (one device for every test).
const QPointingDevice& testPen() {
    static const QPointingDevice pen(
        QStringLiteral("test pen"), 4242, QInputDevice::DeviceType::Stylus,
        QPointingDevice::PointerType::Pen,
        QInputDevice::Capability::Position | QInputDevice::Capability::Pressure, 1, 3);
    return pen;
}

/// Sends a tablet event of a pen at `pos` with `pressure` to a widget or a window. @return
/// whether it was accepted.
template <class Target>
bool sendTablet(Target* w, QEvent::Type type, QPointF pos, double pressure) {
    const QPointingDevice& pen = testPen();
    const Qt::MouseButton button = type == QEvent::TabletMove ? Qt::NoButton : Qt::LeftButton;
    const Qt::MouseButtons buttons =
        type == QEvent::TabletRelease ? Qt::NoButton : Qt::MouseButtons(Qt::LeftButton);
    QTabletEvent e(type, &pen, pos, w->mapToGlobal(pos), pressure, 0.f, 0.f, 0.f, 0.0, 0.f,
                   Qt::NoModifier, button, buttons);
    QApplication::sendEvent(w, &e);
    return e.isAccepted();
}

// ---- The GL window: real input, drops and screenshots ---------------------------------------
// The viewport draws in a QOpenGLWindow hosted by QWidget::createWindowContainer; the tests
// above send events to the facade widget, these send them to the GL window itself, where the
// window system delivers them.

/// Simulated LMB drag on a window from a to b in `steps` moves.
void dragOnWindow(QWindow* win, QPoint a, QPoint b, int steps = 12) {
    QTest::mousePress(win, Qt::LeftButton, Qt::NoModifier, a);
    for (int i = 1; i <= steps; ++i)
        QTest::mouseMove(win, a + (b - a) * i / steps);
    QTest::mouseRelease(win, Qt::LeftButton, Qt::NoModifier, b);
}

TEST(AppWindow, StrokeOnTheGlWindowChangesVoxelsAndThePreview) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    QWindow* gl = vp->glWindow();
    ASSERT_NE(gl, nullptr);
    // The GL window is a child of the main window: Xvfb may expose it after its parent.
    ASSERT_TRUE(QTest::qWaitForWindowExposed(gl, test::kWindowWaitMs));
    // The container fills the facade: window and widget positions are the same.
    EXPECT_EQ(gl->size(), vp->size());
    EXPECT_EQ(gl->mapToGlobal(QPoint(0, 0)), vp->mapToGlobal(QPoint(0, 0)));
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("sslpv")));
    renderOneFrame(vp);
    const QImage before = vp->grabRender().convertToFormat(QImage::Format_RGB32);
    // As AppPaint.StrokeChangesSslpvPixelsNearTheStroke: a strong absorber (albedo 0) over the
    // back-lit right ear darkens the SSLPV glow there.
    const int cy = before.height() / 2;
    const int xr = rightEndOnRow(vp, cy);
    ASSERT_GT(xr, before.width() / 2) << "object not found on the middle row";
    const int xs = xr - 30;
    setExactBrush(vp, {Rgb(5.f), Rgb(0.f), Rgb(0.f)}, 4.f);
    MaterialVolume* vol = w->document()->material();
    const std::vector<float> voxelsBefore = snapshot(*vol);
    dragOnWindow(gl, QPoint(xs, cy - 30), QPoint(xs, cy + 30));
    EXPECT_EQ(w->document()->undoStack()->count(), 1) << "one stroke, one undo step";
    EXPECT_NE(snapshot(*vol), voxelsBefore) << "the stroke on the GL window painted nothing";
    renderOneFrame(vp);
    const QImage after = vp->grabRender().convertToFormat(QImage::Format_RGB32);
    EXPECT_EQ(vp->stats().glErrors, 0);
    const double dNear = meanAbsDiff(before, after, QRect(xs - 20, cy - 45, 40, 90));
    EXPECT_GT(dNear, 2.0) << "the preview did not change near the stroke";
    // Undo through the UI restores the voxels.
    findAction(*w, "actionUndo")->trigger();
    EXPECT_EQ(snapshot(*vol), voxelsBefore);
}

namespace {
/// The docks of `w` that are on screen (not closed, not a hidden tab), in window coordinates.
std::vector<std::pair<QString, QRect>> shownDocks(MainWindow& w) {
    std::vector<std::pair<QString, QRect>> out;
    for (QDockWidget* d : w.findChildren<QDockWidget*>())
        if (d->isVisible() && !d->visibleRegion().isEmpty())
            out.push_back({d->objectName(), QRect(d->mapTo(&w, QPoint(0, 0)), d->size())});
    return out;
}

/// At the window's current size: the status bar and every shown dock inside the window, no two
/// docks overlapping, the viewport not squeezed away.
void expectLaidOut(MainWindow& w) {
    const QRect inside = w.rect();
    const QRect status(w.statusBar()->mapTo(&w, QPoint(0, 0)), w.statusBar()->size());
    EXPECT_TRUE(w.statusBar()->isVisible());
    EXPECT_TRUE(inside.contains(status)) << "status bar off the window";
    const auto docks = shownDocks(w);
    EXPECT_GE(docks.size(), 2u);
    for (size_t i = 0; i < docks.size(); ++i) {
        EXPECT_TRUE(inside.contains(docks[i].second))
            << docks[i].first.toStdString() << " off the window";
        for (size_t j = i + 1; j < docks.size(); ++j)
            EXPECT_FALSE(docks[i].second.intersects(docks[j].second))
                << docks[i].first.toStdString() << " overlaps " << docks[j].first.toStdString();
    }
    EXPECT_GE(w.viewport()->width(), 320);
    EXPECT_GE(w.viewport()->height(), 180);
}
}  // namespace

// Issue 17, item 2: the window's minimum height was 1276 px, so on 1000- and 1080-px screens the
// status bar and the Reference dock were off-screen, and docks overlapped once resized.
TEST(AppWindow, FitsA1366x768ScreenWithEveryDockReachable) {
    MainWindow w(/*restoreSettings=*/false);
    // 1366×768 less a title bar and a panel (about 60 px), as a maximised window there.
    const QSize laptop(1366, 768 - 60);
    EXPECT_LE(w.minimumSizeHint().height(), laptop.height());
    EXPECT_LE(w.minimumSizeHint().width(), laptop.width());
    w.resize(laptop);
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w, test::kWindowWaitMs));
    QTest::qWait(50);  // the default dock proportions are applied after the first layout
    EXPECT_EQ(w.size(), laptop) << "the window grew past the screen";
    expectLaidOut(w);
    // The Reference dock is a tab of the right-hand group, not a dock of its own.
    auto* reference = w.findChild<QDockWidget*>(QStringLiteral("dockReference"));
    if (reference) {
        auto* stats = w.findChild<QDockWidget*>(QStringLiteral("dockStats"));
        EXPECT_TRUE(w.tabifiedDockWidgets(reference).contains(stats));
    }
    // Every dock scrolls rather than pushing the window: raising each one keeps the layout.
    for (QDockWidget* d : w.findChildren<QDockWidget*>()) {
        SCOPED_TRACE(d->objectName().toStdString());
        d->raise();
        QTest::qWait(10);
        expectLaidOut(w);
    }
    // Smaller still, then a large screen: still laid out.
    for (const QSize size : {QSize(1024, 600), QSize(1920, 1080 - 60)}) {
        SCOPED_TRACE(size.width());
        w.resize(size);
        QTest::qWait(50);
        EXPECT_EQ(w.size(), size);
        expectLaidOut(w);
    }
}

// Issue 17, item 2: the reference picture was scaled once when rendered and, as a QLabel
// pixmap, could lock the dock's width. It now follows the dock.
TEST(AppWindow, ReferencePictureFollowsTheDock) {
    MainWindow w(/*restoreSettings=*/false);
    w.resize(1366, 708);
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w, test::kWindowWaitMs));
    auto* dock = w.findChild<QDockWidget*>(QStringLiteral("dockReference"));
    ASSERT_NE(dock, nullptr);
    dock->raise();
    ReferencePanel* panel = w.referencePanel();
    auto* picture = panel->findChild<ImageView*>(QStringLiteral("referencePicture"));
    ASSERT_NE(picture, nullptr);
    const int narrow = panel->minimumSizeHint().width();
    // A large render must not widen the dock's minimum.
    QImage big(1920, 1080, QImage::Format_RGB32);
    big.fill(Qt::white);
    picture->setImage(big);
    EXPECT_EQ(panel->minimumSizeHint().width(), narrow);
    // The picture is drawn at the widget's size, aspect kept, whatever that size becomes.
    for (const QSize size : {QSize(200, 150), QSize(400, 300)}) {
        picture->resize(size);
        const QRect r = picture->imageRect();
        EXPECT_EQ(r.width(), size.width());
        EXPECT_NEAR(double(r.height()), size.width() * 1080.0 / 1920.0, 1.0);
        const QImage shot = picture->grab().toImage();
        EXPECT_EQ(QColor(shot.pixel(r.center())), QColor(Qt::white));
    }
}

// Issue 17, item 9: spin boxes cut their text ("100.00 mn" for a 100 mm brush). Every number
// field of every dock, at the widest value it accepts, shows its whole text.
TEST(AppWindow, SpinBoxesShowTheirWholeValue) {
    MainWindow w(/*restoreSettings=*/false);
    w.resize(1366, 708);
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w, test::kWindowWaitMs));
    int checked = 0;
    for (QDockWidget* d : w.findChildren<QDockWidget*>()) {
        d->raise();
        for (QDoubleSpinBox* s : d->findChildren<QDoubleSpinBox*>()) {
            if (!s->isVisibleTo(d))
                continue;  // a field hidden for the current light type, for instance
            // The longest text of the range (e.g. "-100000.00" beats "100000.00").
            const double wide =
                std::abs(s->minimum()) > std::abs(s->maximum()) ? s->minimum() : s->maximum();
            s->setValue(wide);
        }
        QTest::qWait(20);  // layouts settle
        for (QAbstractSpinBox* s : d->findChildren<QAbstractSpinBox*>()) {
            if (!s->isVisible())
                continue;
            auto* edit = s->findChild<QLineEdit*>();
            ASSERT_NE(edit, nullptr);
            const int needed = edit->fontMetrics().horizontalAdvance(edit->text());
            EXPECT_GE(edit->width(), needed)
                << d->objectName().toStdString() << " / " << s->objectName().toStdString() << ": '"
                << edit->text().toStdString() << "' cut";
            ++checked;
        }
    }
    EXPECT_GT(checked, 20);
}

TEST(AppWindow, ScreenshotsShowTheFrameNotABlankWindow) {
    auto w = shownWindow(2);
    Viewport* vp = w->viewport();
    QWindow* gl = vp->glWindow();
    // A method whose frames repeat exactly (Auto may switch methods when its Direct frame is
    // measured, and a progressive method refines between the grabs compared below).
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("direct")));
    renderOneFrame(vp);
    renderOneFrame(vp);
    // What the X server shows in the GL window (the swapped frame itself).
    const QImage onScreen =
        gl->screen()->grabWindow(gl->winId()).toImage().convertToFormat(QImage::Format_RGB32);
    onScreen.save(outputPath("app_glwindow_screen.png"));
    ASSERT_FALSE(onScreen.isNull());
    const auto [screenCoverage, screenLevels] = objectCoverage(onScreen);
    EXPECT_GT(screenCoverage, 0.02) << "the GL window shows no object";
    EXPECT_GT(screenLevels, 8u) << "the GL window shows no shading";
    // The whole window as --screenshot writes it: the frame painted where the viewport sits.
    const QImage shot = vp->grabWithFrame(w.get()).toImage().convertToFormat(QImage::Format_RGB32);
    shot.save(outputPath("app_window_screenshot.png"));
    const qreal dpr = shot.devicePixelRatio();
    const QRect vpRect(vp->mapTo(w.get(), QPoint(0, 0)) * dpr, vp->size() * dpr);
    ASSERT_TRUE(shot.rect().contains(vpRect));
    const QImage inShot = shot.copy(vpRect);
    const auto [coverage, levels] = objectCoverage(inShot);
    EXPECT_GT(coverage, 0.02) << "object covers " << coverage << " of the viewport's area";
    EXPECT_GT(levels, 8u);
    // It is the viewport's frame: the same deterministic frame as a grab of the viewport
    // (SSLPV/direct frames repeat exactly; the last bits may differ in the window grab's
    // blending, so compare within 8-bit rounding).
    const QImage direct = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    ASSERT_EQ(direct.size(), inShot.size());
    EXPECT_LT(meanAbsDiff(direct, inShot, direct.rect()), 1.0);
    // and the on-screen frame matches it too.
    if (onScreen.size() == direct.size()) {
        EXPECT_LT(meanAbsDiff(direct, onScreen, direct.rect()), 1.0);
    }
    EXPECT_EQ(vp->stats().glErrors, 0);
}

TEST(AppWindow, InputOnTheGlWindowReachesTheViewport) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    QWindow* gl = vp->glWindow();
    const QPoint c(vp->width() / 2, vp->height() / 2);
    // Wheel: one notch (120 units) towards the object scales the distance by 0.9.
    const float d0 = vp->camera().distance;
    QWheelEvent wheel(QPointF(c), gl->mapToGlobal(QPointF(c)), QPoint(), QPoint(0, 120),
                      Qt::NoButton, Qt::NoModifier, Qt::NoScrollPhase, false);
    QCoreApplication::sendEvent(gl, &wheel);
    EXPECT_NEAR(vp->camera().distance, 0.9f * d0, 1e-5f * d0);  // float rounding
    // F frames the object (key events of the GL window reach the viewport).
    vp->camera().distance = 10.f * d0;
    QTest::keyClick(gl, Qt::Key_F);
    EXPECT_LT(vp->camera().distance, 2.f * d0) << "F did not frame the object";
    vp->frameObject();
    renderOneFrame(vp);
    // Hover over the object reports the voxel under the cursor.
    QSignalSpy hover(vp, &Viewport::hoverVoxel);
    QTest::mouseMove(gl, c);
    EXPECT_GE(hover.count(), 1) << "no hover report from the GL window";
    // The cursor shape is the GL window's: an open hand over a light handle, else an arrow.
    const auto h = vp->lightHandle(0);
    ASSERT_TRUE(h);
    QTest::mouseMove(gl, h->toPoint());
    EXPECT_EQ(gl->cursor().shape(), Qt::OpenHandCursor);
    QTest::mouseMove(gl, c);
    EXPECT_EQ(gl->cursor().shape(), Qt::ArrowCursor);
    // A click on the GL window gives the viewport the keyboard focus.
    w->brushPanel()->setFocus();
    vp->setTool(Viewport::Tool::Eyedropper);  // the click picks, it does not paint
    ASSERT_NE(w->focusWidget(), vp->focusProxy());
    QTest::mouseClick(gl, Qt::LeftButton, Qt::NoModifier, c);
    // The facade's focus proxy is the window container (which activates the GL window).
    EXPECT_EQ(w->focusWidget(), vp->focusProxy());
    // A pen dab on the GL window paints one undo step (pressure path of the window).
    setExactBrush(vp, PAINT, 4.f * w->document()->material()->spec().voxelSize);
    EXPECT_TRUE(sendTablet(gl, QEvent::TabletPress, QPointF(c), 0.8));
    EXPECT_TRUE(sendTablet(gl, QEvent::TabletRelease, QPointF(c), 0.8));
    EXPECT_EQ(w->document()->undoStack()->count(), 1);
    // A pen hovering (no press) is left to the mouse path.
    EXPECT_FALSE(sendTablet(gl, QEvent::TabletMove, QPointF(c), 0.0));
    // Resizing the viewport resizes the GL window, which draws a frame at the new size with
    // no update() call.
    const long long f = vp->stats().frames;
    vp->setFixedSize(480, 270);
    EXPECT_TRUE(QTest::qWaitFor([&] { return vp->stats().frames > f; }, 10000))
        << "no frame after a resize";
    EXPECT_EQ(gl->size(), QSize(480, 270));
    EXPECT_EQ(vp->grabFramebuffer().size(), QSize(480, 270) * gl->devicePixelRatio());
    EXPECT_EQ(vp->stats().glErrors, 0);
}

TEST(AppPaint, TabletPressureScalesTheStamp) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    Document* doc = w->document();
    MaterialVolume* vol = doc->material();
    const QPointF c(vp->width() / 2.0, vp->height() / 2.0);
    const auto hit = vp->pickAt(c);
    ASSERT_TRUE(hit);
    // Voxels changed by one pen dab (press and release at c) at `pressure`, counted in the
    // box of the largest stamp (radius 4 voxels) around the hit; the caller undoes it.
    const GridSpec& spec = vol->spec();
    const Coord hitCell = spec.cellOf(hit->position);
    const auto local = [&] {
        std::vector<MaterialSample> v;
        for (int dz = -6; dz <= 6; ++dz)
            for (int dy = -6; dy <= 6; ++dy)
                for (int dx = -6; dx <= 6; ++dx)
                    if (const Coord q = hitCell + Coord(dx, dy, dz); spec.contains(q))
                        v.push_back(vol->at(q));
        return v;
    };
    const auto dab = [&](double pressure) {
        const std::vector<MaterialSample> before = local();
        EXPECT_TRUE(sendTablet(vp, QEvent::TabletPress, c, pressure));
        EXPECT_TRUE(sendTablet(vp, QEvent::TabletRelease, c, pressure));
        const std::vector<MaterialSample> after = local();
        size_t changed = 0;
        for (size_t i = 0; i < before.size(); ++i)
            changed += before[i] != after[i];
        return changed;
    };
    // Radius mode through the Tools dock: the stamp's radius is radius × pressure.
    auto* pressureBox = w->brushPanel()->findChild<QComboBox*>(QStringLiteral("brushPressure"));
    ASSERT_NE(pressureBox, nullptr);
    pressureBox->setCurrentIndex(int(PressureMode::Radius));
    ASSERT_EQ(vp->brush().pressureMode, PressureMode::Radius);
    setExactBrush(vp, PAINT, 4.f * vol->spec().voxelSize);  // keeps the pressure mode
    const std::vector<MaterialSample> pristine = local();
    const size_t full = dab(1.0);
    EXPECT_EQ(doc->undoStack()->count(), 1) << "a pen dab is one undo step";
    doc->undoStack()->undo();
    ASSERT_TRUE(local() == pristine);
    const size_t light = dab(0.4);
    doc->undoStack()->undo();
    // A ball (half inside the surface) of 4 voxels holds ~130 inside voxels; at 0.4 × the
    // radius 0.4³ ≈ 6 % of that, with voxelisation noise: well under a third.
    EXPECT_GT(full, 50u);
    EXPECT_GT(light, 0u);
    EXPECT_LT(double(light), 0.3 * double(full)) << "full " << full << ", light " << light;

    // Strength mode: Set with constant falloff moves a voxel by pressure × (u − v).
    vp->brush().pressureMode = PressureMode::Strength;
    const Coord cell =
        vol->spec().cellOf(hit->position - hit->normal * (0.5f * vol->spec().voxelSize));
    ASSERT_TRUE(vol->isInside(cell));
    const MaterialSample v0 = vol->at(cell);
    dab(0.5);
    const MaterialSample v1 = vol->at(cell);
    const MaterialSample u = sanitize(PAINT);
    for (int k = 0; k < 3; ++k) {
        const float expected = v0.sigma_t[k] + 0.5f * (u.sigma_t[k] - v0.sigma_t[k]);
        EXPECT_NEAR(v1.sigma_t[k], expected, 1e-5f * expected);  // float rounding
    }
    doc->undoStack()->undo();
    // Off: the pen paints like the mouse, whatever its pressure.
    vp->brush().pressureMode = PressureMode::Off;
    dab(0.2);
    EXPECT_EQ(vol->at(cell).sigma_t, u.sigma_t);
    doc->undoStack()->undo();
    // A pen move with no press (hovering) paints nothing and is left to the mouse path.
    EXPECT_FALSE(sendTablet(vp, QEvent::TabletMove, c, 0.0));
    EXPECT_TRUE(local() == pristine);
}

// ---- Render dock: methods and volume overlay ----------------------------------------------

// The selector and the parameter fields come from the registry: one entry per method with a
// GL pass, and each method's fields reach the renderer as that method's parameters.
TEST(AppRender, MethodSelectorAndFieldsComeFromTheRegistry) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    auto* method = w->findChild<QComboBox*>(QStringLiteral("renderMethod"));
    ASSERT_NE(method, nullptr);
    const std::vector<const methods::MethodInfo*> previews = PreviewRenderer::previewMethods();
    // Auto first, then the registry's methods with a GL pass in the registry's order.
    ASSERT_EQ(method->count(), int(previews.size()) + 1);
    EXPECT_EQ(method->itemData(0).toString(), QString::fromLatin1(AUTO_METHOD));
    for (size_t i = 0; i < previews.size(); ++i)
        EXPECT_EQ(method->itemData(int(i) + 1).toString().toStdString(), previews[i]->name);
    EXPECT_EQ(method->findData(QStringLiteral("reference")), -1) << "reference has no GL pass";
    EXPECT_FALSE(w->setRenderMethod(QStringLiteral("reference")));
    EXPECT_FALSE(w->setRenderMethod(QStringLiteral("no-such-method")));
    const QImage direct = [&] {
        EXPECT_TRUE(w->setRenderMethod(QStringLiteral("direct")));
        renderOneFrame(vp);
        return vp->grabRender().convertToFormat(QImage::Format_RGB32);
    }();
    const auto field = [&](const char* m, const char* p) {
        return w->findChild<QWidget*>(RenderPanel::paramFieldName(m, p));
    };
    auto* dirpoleSpp = qobject_cast<QSpinBox*>(field("dirpole", "spp-frame"));
    auto* split = qobject_cast<QDoubleSpinBox*>(field("combined", "split-radius"));
    ASSERT_NE(dirpoleSpp, nullptr);
    ASSERT_NE(split, nullptr);
    EXPECT_EQ(field("dipole", "spp"), nullptr) << "offline-only parameters get no field";
    for (const char* m : {"dirpole", "combined"}) {
        SCOPED_TRACE(m);
        method->setCurrentIndex(method->findData(QString::fromLatin1(m)));
        ASSERT_EQ(vp->renderSettings().method, m);
        // Only the selected method's page is shown.
        EXPECT_EQ(dirpoleSpp->isVisibleTo(w.get()), std::string(m) == "dirpole");
        EXPECT_EQ(split->isVisibleTo(w.get()), std::string(m) == "combined");
        EXPECT_TRUE(vp->renderSettings().params.empty()) << "live defaults are not given";
        if (std::string(m) == "dirpole") {
            dirpoleSpp->setValue(4);
            EXPECT_EQ(vp->renderSettings().params.toString(), "spp-frame=4");
        } else {
            split->setValue(3.0);
            EXPECT_EQ(vp->renderSettings().params.toString(), "split-radius=3");
        }
        renderOneFrame(vp);
        renderOneFrame(vp);
        EXPECT_EQ(vp->stats().glErrors, 0);
        EXPECT_TRUE(vp->stats().renderError.isEmpty()) << vp->stats().renderError.toStdString();
        const QImage img = vp->grabRender().convertToFormat(QImage::Format_RGB32);
        // The subsurface term changes the picture against the opaque direct shading.
        EXPECT_GT(meanAbsDiff(direct, img, img.rect()), 1.0);
    }
}

// Auto, the default: the viewport runs the planner's choice and the status bar says why.
TEST(AppRender, AutoRunsAMethodAndTheStatusBarSaysWhy) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    ASSERT_EQ(vp->renderSettings().method, AUTO_METHOD);
    // Direct while the planner times a Direct frame of this size (ten frames), then its choice.
    EXPECT_TRUE(QTest::qWaitFor(
        [&] {
            renderOneFrame(vp);
            return !vp->previewRenderer().isPlanning();
        },
        120000));
    renderOneFrame(vp);
    const ViewportStats& s = vp->stats();
    EXPECT_TRUE(s.renderError.isEmpty()) << s.renderError.toStdString();
    EXPECT_TRUE(PreviewRenderer::isPreviewMethod(s.preview.method)) << s.preview.method;
    EXPECT_FALSE(s.preview.autoReason.empty());
    // The Direct frames Auto timed asked for each other back to back: the gap between them is
    // the app's own time per frame (event loop, composition, swap), which Auto adds to live
    // costs measured headless.
    EXPECT_GT(s.hostMs, 0.0);
    EXPECT_LT(s.hostMs, 1000.0);
    // The status bar follows (queued: the viewport emits from inside its frame).
    EXPECT_TRUE(QTest::qWaitFor(
        [&] { return w->statusBar()->currentMessage().startsWith(QStringLiteral("Auto: ")); },
        5000))
        << w->statusBar()->currentMessage().toStdString();
    EXPECT_TRUE(
        w->statusBar()->currentMessage().contains(QString::fromStdString(s.preview.autoReason)));
    // So does Auto's page of the Render dock, which takes only its own height (the stack of
    // method pages used to keep the tallest page's).
    auto* page = w->findChild<QLabel*>(QStringLiteral("renderAutoPlan"));
    ASSERT_TRUE(page);
    EXPECT_TRUE(page->text().contains(QString::fromStdString(s.preview.autoReason)));
    EXPECT_LT(page->parentWidget()->height(), 3 * page->sizeHint().height())
        << "the method pages' stack is " << page->parentWidget()->height() << " px high";
}

TEST(AppRender, VolumeOverlayControlsReachTheRenderer) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    auto* overlay = w->findChild<QCheckBox*>(QStringLiteral("renderOverlay"));
    auto* channel = w->findChild<QComboBox*>(QStringLiteral("renderOverlayChannel"));
    auto* opacity = w->findChild<QDoubleSpinBox*>(QStringLiteral("renderOverlayOpacity"));
    ASSERT_TRUE(overlay && channel && opacity);
    EXPECT_FALSE(vp->renderSettings().volumeOverlay);
    renderOneFrame(vp);
    const QImage off = vp->grabRender().convertToFormat(QImage::Format_RGB32);
    overlay->setChecked(true);
    channel->setCurrentIndex(1);
    opacity->setValue(0.8);
    EXPECT_TRUE(vp->renderSettings().volumeOverlay);
    EXPECT_EQ(vp->renderSettings().overlayChannel, 1);
    EXPECT_FLOAT_EQ(vp->renderSettings().overlayOpacity, 0.8f);
    renderOneFrame(vp);
    EXPECT_EQ(vp->stats().glErrors, 0);
    EXPECT_TRUE(vp->stats().renderError.isEmpty()) << vp->stats().renderError.toStdString();
    const QImage on = vp->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    on.save(outputPath("app_volume_overlay.png"));
    vp->grabWithFrame(w.get()).save(outputPath("app_volume_overlay_window.png"));
    // The overlay covers the object: the picture changes by more than 8-bit rounding.
    EXPECT_GT(meanAbsDiff(off, on, off.rect()), 1.0);
    overlay->setChecked(false);
    EXPECT_FALSE(vp->renderSettings().volumeOverlay);
}

namespace {
/// Sets a named spin box, combo box or check box of the window to `value`; returns its old value.
QVariant setField(MainWindow& w, const char* name, const QVariant& value) {
    QWidget* field = w.findChild<QWidget*>(QString::fromLatin1(name));
    EXPECT_NE(field, nullptr) << name;
    if (auto* d = qobject_cast<QDoubleSpinBox*>(field)) {
        const QVariant old = d->value();
        d->setValue(value.toDouble());
        return old;
    }
    if (auto* i = qobject_cast<QSpinBox*>(field)) {
        const QVariant old = i->value();
        i->setValue(value.toInt());
        return old;
    }
    if (auto* c = qobject_cast<QComboBox*>(field)) {
        const QVariant old = c->currentIndex();
        c->setCurrentIndex(value.toInt());
        return old;
    }
    if (auto* b = qobject_cast<QCheckBox*>(field)) {
        const QVariant old = b->isChecked();
        b->setChecked(value.toBool());
        return old;
    }
    ADD_FAILURE() << name << " is not a spin box, combo box or check box";
    return {};
}

/// The viewport shows the object with `method`, and no frame failed.
void expectRendersWith(MainWindow& w, const std::string& method, const std::string& what) {
    Viewport* vp = w.viewport();
    SCOPED_TRACE(what);
    EXPECT_EQ(vp->renderSettings().method, method) << "the method fell back";
    EXPECT_EQ(vp->stats().renderErrors, 0) << vp->stats().renderError.toStdString();
    EXPECT_EQ(vp->stats().glErrors, 0);
    const auto [coverage, levels] =
        objectCoverage(vp->grabRender().convertToFormat(QImage::Format_RGB32));
    EXPECT_GT(coverage, 0.02) << "the viewport is blank";
}

/// A value other than the live default for each parameter field of `info` (cheap ones: a
/// smaller count, the next choice, the other state, a small positive number).
std::vector<std::pair<QString, QVariant>> parameterChanges(const methods::MethodInfo& info) {
    std::vector<std::pair<QString, QVariant>> out;
    for (const methods::ParamDescriptor& p : info.params) {
        if (p.scope == methods::ParamScope::Offline)
            continue;
        const std::string& d = p.defaultFor(methods::Backend::Gl, /*live=*/true);
        QVariant value;
        switch (p.type) {
            case methods::ParamType::Bool:
                value = d != "on";
                break;
            case methods::ParamType::Int: {
                const int x = std::stoi(d);
                value = x / 2 >= int(p.min) && x / 2 != x ? x / 2 : x + 1;
                break;
            }
            case methods::ParamType::Float:
                value = std::stod(d) > 0.0 ? std::stod(d) / 2.0 : std::stod(d) + 2.5;
                break;
            case methods::ParamType::Choice: {
                const auto it = std::find(p.choices.begin(), p.choices.end(), d);
                value = int((it - p.choices.begin() + 1) % std::ssize(p.choices));
                break;
            }
        }
        out.push_back({RenderPanel::paramFieldName(QString::fromStdString(info.name),
                                                   QString::fromStdString(p.name)),
                       value});
    }
    return out;
}
}  // namespace

// Issue: changing the SSLPV grid at run time (32³ → 64³) dropped the provider's material; the
// exception then left the renderer's profiler mid-frame and every later frame of every method
// failed, even after File ▸ New. Every field of the Render settings dock (the registry's
// parameter fields of the method shown, and the dock's own) is changed here while each method
// is shown, through the dock's widgets, and each frame must render that method.
TEST(AppRender, EverySettingChangesAtRunTimeForEveryMethod) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    vp->setFixedSize(320, 180);  // ~200 frames: keep each one cheap on llvmpipe
    const std::pair<QString, QVariant> dockChanges[] = {
        {QStringLiteral("renderSubsurfaceOnly"), true},
        {QStringLiteral("renderOverlay"), true},
        {QStringLiteral("renderOverlayChannel"), 2},
        {QStringLiteral("renderOverlayOpacity"), 0.3},
        {QStringLiteral("renderExposure"), 0.5},
        {QStringLiteral("renderScale"), 2},
        {QStringLiteral("renderTurntable"), true},
    };
    for (const methods::MethodInfo* info : PreviewRenderer::previewMethods()) {
        SCOPED_TRACE(info->name);
        ASSERT_TRUE(w->setRenderMethod(QString::fromStdString(info->name)));
        renderOneFrame(vp);
        expectRendersWith(*w, info->name, "selected");
        std::vector<std::pair<QString, QVariant>> changes = parameterChanges(*info);
        // Grids first away from and back to the default 32³, as the issue's session did.
        if (info->name == "sslpv")
            changes.insert(changes.begin(), {RenderPanel::paramFieldName("sslpv", "grid"), 64});
        changes.insert(changes.end(), std::begin(dockChanges), std::end(dockChanges));
        for (const auto& [name, value] : changes) {
            const std::string what = name.toStdString();
            const QVariant old = setField(*w, what.c_str(), value);
            renderOneFrame(vp);
            expectRendersWith(*w, info->name, what);
            setField(*w, what.c_str(), old);
            renderOneFrame(vp);
            expectRendersWith(*w, info->name, what + " restored");
        }
        if (HasFailure())
            return;  // one method's failures are enough to read
    }
    // File ▸ New after a grid change: the new scene renders with the new grid.
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("sslpv")));
    setField(*w, RenderPanel::paramFieldName("sslpv", "grid").toUtf8().constData(), 64);
    findAction(*w, "actionNew")->trigger();
    renderOneFrame(vp);
    expectRendersWith(*w, "sslpv", "File > New at 64³");
}

// `lucent --method sslpv --param mode=diffusion` (the user guide's screenshot): a live parameter
// set by name reaches the renderer, and names or values the method does not take are refused.
TEST(AppRender, ParametersSetByNameReachTheRenderer) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    vp->setFixedSize(320, 180);
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("sslpv")));
    ASSERT_TRUE(w->setRenderParam(QStringLiteral("mode"), QStringLiteral("diffusion")));
    ASSERT_TRUE(w->setRenderParam(QStringLiteral("grid"), QStringLiteral("16")));
    renderOneFrame(vp);
    expectRendersWith(*w, "sslpv", "mode diffusion");
    const methods::ParamSet& p = vp->renderSettings().params;
    ASSERT_NE(p.find("mode"), nullptr);
    EXPECT_EQ(*p.find("mode"), "diffusion");
    EXPECT_FALSE(w->setRenderParam(QStringLiteral("mode"), QStringLiteral("photons")));
    EXPECT_FALSE(w->setRenderParam(QStringLiteral("grid"), QStringLiteral("100000")));
    EXPECT_FALSE(w->setRenderParam(QStringLiteral("no-such-param"), QStringLiteral("1")));
    EXPECT_EQ(*vp->renderSettings().params.find("mode"), "diffusion");
}

// A method whose frame fails (here SSLPV with a shader that does not compile) must not leave
// the viewport blank: the frame is drawn with Direct, the dock shows Direct, the user is told
// why, and the method works again when chosen after the cause is gone.
TEST(AppRender, FailingMethodFallsBackToDirectAndRecovers) {
    // Direct from the first frame, so the SSLPV pass is built after the shader breaks.
    auto w = std::make_unique<MainWindow>(/*restoreSettings=*/false);
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("direct")));
    w->viewport()->setFixedSize(640, 360);
    w->show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(w.get(), test::kWindowWaitMs));
    Viewport* vp = w->viewport();
    renderOneFrame(vp);
    gpu::ShaderLibrary& shaders = vp->previewRenderer().shaderLibrary();
    const std::string good = shaders.read("sslpv_sample.comp");
    shaders.setFile("sslpv_sample.comp", "#version 450 core\nvoid main() { broken }\n");
    QSignalSpy failed(vp, &Viewport::renderFailed);
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("sslpv")));
    renderOneFrame(vp);
    ASSERT_EQ(failed.count(), 1);
    EXPECT_EQ(failed[0][1].toString(), QStringLiteral("sslpv"));
    EXPECT_EQ(vp->renderSettings().method, "direct");
    EXPECT_EQ(vp->stats().renderErrors, 1);
    const auto [coverage, levels] =
        objectCoverage(vp->grabRender().convertToFormat(QImage::Format_RGB32));
    EXPECT_GT(coverage, 0.02) << "the failed frame left the viewport blank";
    // The dock and the status bar follow (queued from inside the frame).
    auto* method = w->findChild<QComboBox*>(QStringLiteral("renderMethod"));
    EXPECT_TRUE(QTest::qWaitFor(
        [&] { return method->currentData().toString() == QStringLiteral("direct"); }, 5000));
    EXPECT_TRUE(w->lastError().contains(QStringLiteral("switched to Direct")))
        << w->lastError().toStdString();
    shaders.setFile("sslpv_sample.comp", good);
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("sslpv")));
    renderOneFrame(vp);
    EXPECT_EQ(vp->renderSettings().method, "sslpv");
    EXPECT_EQ(vp->stats().renderErrors, 1) << vp->stats().renderError.toStdString();
    EXPECT_EQ(failed.count(), 1);
}

// ---- Screenshots for docs/user-guide.md ------------------------------------------------------

/// Writes the user guide's screenshots of the light gizmo and the volume overlay into
/// $LUCENT_SCREENSHOT_DIR (a tool run by hand, see docs/user-guide.md; skipped without it).
TEST(AppDocs, Screenshots) {
    const QString dir = qEnvironmentVariable("LUCENT_SCREENSHOT_DIR");
    if (dir.isEmpty())
        GTEST_SKIP() << "set LUCENT_SCREENSHOT_DIR to write the user guide's screenshots";
    MainWindow w(/*restoreSettings=*/false);
    // The whole screen (the user guide's pictures are taken on 1366×768 and 1920×1080 screens).
    w.resize(w.screen()->availableGeometry().size());
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w, test::kWindowWaitMs));
    Viewport* vp = w.viewport();
    renderOneFrame(vp);
    const QString suffix = qEnvironmentVariable("LUCENT_SCREENSHOT_SUFFIX");
    const auto raise = [&w](const char* dock) {
        if (auto* d = w.findChild<QDockWidget*>(QString::fromLatin1(dock)))
            d->raise();
    };
    // A warm directional light added in the Lights dock, then dragged by its handle.
    auto* add = w.lightPanel()->findChild<QPushButton*>(QStringLiteral("lightAddDirectional"));
    ASSERT_NE(add, nullptr);
    add->click();
    const int sun = int(w.document()->scene().lights.size()) - 1;
    std::vector<Light> lights = w.document()->scene().lights;
    lights[size_t(sun)].direction = glm::normalize(Vector3f(-0.2f, -0.3f, -1.f));
    lights[size_t(sun)].intensity = Rgb(1.f, 0.75f, 0.45f);
    w.document()->setLights(lights, QStringLiteral("Sun"));
    const auto h = vp->lightHandle(sun);
    ASSERT_TRUE(h);
    drag(vp, h->toPoint(), h->toPoint() + QPoint(-90, 40), 10);
    raise("dockLights");
    for (int i = 0; i < 3; ++i)
        renderOneFrame(vp);
    ASSERT_TRUE(
        vp->grabWithFrame(&w).save(dir + QStringLiteral("/app-light-gizmo%1.png").arg(suffix)));
    // The volume overlay of σt through the Render settings dock.
    w.findChild<QCheckBox*>(QStringLiteral("renderOverlay"))->setChecked(true);
    w.findChild<QDoubleSpinBox*>(QStringLiteral("renderOverlayOpacity"))->setValue(0.7);
    vp->setLightGizmosVisible(false);
    raise("dockRender");
    for (int i = 0; i < 3; ++i)
        renderOneFrame(vp);
    ASSERT_TRUE(
        vp->grabWithFrame(&w).save(dir + QStringLiteral("/app-volume-overlay%1.png").arg(suffix)));
    EXPECT_EQ(vp->stats().glErrors, 0);
}

TEST(AppFiles, SaveOpenRoundTripOfUniformFill) {
    // A uniform material (fill through the Tools dock's engine path), then save and reopen.
    auto w = shownWindow();
    w->document()->fill(sanitize(PAINT), ALL_CHANNELS);
    ASSERT_TRUE(w->document()->isModified());
    const QString path = outputPath("app_uniform.json");
    ASSERT_TRUE(w->saveTo(path)) << w->lastError().toStdString();
    // The JSON and one sidecar VDB next to it (<stem>.vdb or <stem>.1.vdb: saves alternate).
    EXPECT_EQ(projectFiles(path.toStdString()).size(), 2u);
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

/// A hidden window painting through the viewport's scripted strokes (picking needs the
/// viewport's size, not its GL frames).
std::unique_ptr<MainWindow> paintingWindow() {
    auto w = std::make_unique<MainWindow>(/*restoreSettings=*/false);
    w->viewport()->setFixedSize(640, 360);
    setExactBrush(w->viewport(), PAINT, 2.f * w->document()->material()->spec().voxelSize);
    return w;
}

/// One horizontal stroke through the middle of the viewport, `dy` pixels below its centre.
void paintRow(MainWindow& w, double dy) {
    Viewport* vp = w.viewport();
    const QPointF c(vp->width() / 2.0, vp->height() / 2.0 + dy);
    ASSERT_EQ(vp->strokeBetween(c - QPointF(20, 0), c + QPointF(20, 0)), 1);
}

TEST(AppFiles, SaveKeepsTheUndoHistoryAndMarksItsStepClean) {
    // As in Blender or Photoshop: saving (Save, Save As, autosave) neither clears nor moves the
    // undo history; undoing past the saved step marks the project modified, coming back to it
    // marks it saved. Open and New start a fresh history.
    QStandardPaths::setTestModeEnabled(true);  // the autosave goes to ~/.qttest
    auto w = paintingWindow();
    Document* doc = w->document();
    QAction* undo = findAction(*w, "actionUndo");
    QAction* redo = findAction(*w, "actionRedo");
    ASSERT_TRUE(undo && redo);
    EXPECT_FALSE(undo->isEnabled()) << "a new document has nothing to undo";
    paintRow(*w, -10);
    const std::vector<float> first = snapshot(*doc->material());
    paintRow(*w, 10);
    const std::vector<float> saved = snapshot(*doc->material());
    const QString path = outputPath("app_undo_save.json");
    ASSERT_TRUE(w->saveTo(path)) << w->lastError().toStdString();
    EXPECT_FALSE(doc->isModified());
    EXPECT_EQ(doc->undoStack()->count(), 2) << "saving must keep the undo steps";
    ASSERT_TRUE(undo->isEnabled());
    undo->trigger();
    EXPECT_EQ(snapshot(*doc->material()), first);
    EXPECT_TRUE(doc->isModified()) << "undoing past the saved step changes the project";
    EXPECT_TRUE(w->windowTitle().contains(QLatin1Char('*')));
    redo->trigger();
    EXPECT_EQ(snapshot(*doc->material()), saved);
    EXPECT_FALSE(doc->isModified()) << "back at the saved step, the project is as saved";

    // An autosave leaves the history and the modified state alone.
    paintRow(*w, 0);
    ASSERT_TRUE(doc->isModified());
    w->autosaveNow();
    EXPECT_TRUE(QFile::exists(MainWindow::autosavePath()));
    EXPECT_TRUE(doc->isModified()) << "an autosave is not a save";
    EXPECT_EQ(doc->undoStack()->count(), 3);
    undo->trigger();
    EXPECT_FALSE(doc->isModified()) << "the autosave must not move the clean step";
    EXPECT_EQ(snapshot(*doc->material()), saved);
    redo->trigger();

    // Save As: the new file's step is the clean one; the old steps stay undoable.
    const QString other = outputPath("app_undo_save_as.json");
    ASSERT_TRUE(w->saveTo(other)) << w->lastError().toStdString();
    EXPECT_FALSE(doc->isModified());
    EXPECT_EQ(doc->filePath(), other);
    EXPECT_EQ(doc->undoStack()->count(), 3);
    undo->trigger();
    undo->trigger();
    EXPECT_EQ(snapshot(*doc->material()), first);
    EXPECT_TRUE(doc->isModified());

    // Open and New: a fresh history, nothing to undo into the previous project.
    ASSERT_TRUE(w->openFile(path)) << w->lastError().toStdString();
    EXPECT_EQ(snapshot(*doc->material()), saved);
    EXPECT_EQ(doc->undoStack()->count(), 0);
    EXPECT_EQ(doc->history().undoCount(), 0u);
    EXPECT_FALSE(undo->isEnabled());
    EXPECT_FALSE(redo->isEnabled());
    EXPECT_FALSE(doc->isModified());
    paintRow(*w, 0);
    findAction(*w, "actionNew")->trigger();  // no question: scripted windows do not ask
    EXPECT_EQ(doc->undoStack()->count(), 0);
    EXPECT_EQ(doc->history().undoCount(), 0u);
    EXPECT_FALSE(undo->isEnabled());
    EXPECT_FALSE(doc->isModified());
    removeProject(MainWindow::autosavePath().toStdString());  // the JSON and its VDB
    QStandardPaths::setTestModeEnabled(false);
}

TEST(AppFiles, SaveInTheMiddleOfAStrokeLeavesTheProjectModified) {
    // A save while the pen is down (Ctrl+S mid-drag) writes part of a stroke: no undo step
    // equals that file, so undoing the stroke must not claim the project is as saved.
    auto w = paintingWindow();
    Document* doc = w->document();
    BrushSettings brush = w->viewport()->brush().engine;
    const Bounds3f box = doc->mesh()->bounds();
    doc->beginStroke(brush);
    // Voxels of the stroke: the object's surface where the default shape has volume.
    size_t touched = 0;
    for (int i = 0; i < 64 && touched == 0; ++i)
        touched = doc->strokeStamp(box.lo + (box.hi - box.lo) * (float(i) / 64.f));
    ASSERT_GT(touched, 0u) << "no stamp along the diagonal reached the object";
    ASSERT_TRUE(w->saveTo(outputPath("app_mid_stroke.json"))) << w->lastError().toStdString();
    EXPECT_TRUE(doc->isModified()) << "the stroke is still open: the project is not as saved";
    doc->endStroke(QStringLiteral("stroke"));
    ASSERT_EQ(doc->undoStack()->count(), 1);
    findAction(*w, "actionUndo")->trigger();
    EXPECT_TRUE(doc->isModified()) << "the volume before the stroke is not what was saved";
}

TEST(AppFiles, UndoStopsWhereTheHistoryBudgetDroppedStrokes) {
    // The History drops its oldest strokes past its memory budget. The undo stack must stop
    // above them: undoing a dropped step would change nothing, and reaching the saved step
    // that way would call the project saved while its volume differs from the file.
    auto w = paintingWindow();
    Document* doc = w->document();
    paintRow(*w, -20);
    ASSERT_TRUE(w->saveTo(outputPath("app_undo_budget.json"))) << w->lastError().toStdString();
    // The smallest budget: the History keeps only the newest stroke.
    doc->setHistoryBudget(size_t(MaterialVolume::BRICK_VOXELS) * MaterialVolume::COMPONENTS *
                          sizeof(float));
    paintRow(*w, -5);
    const std::vector<float> second = snapshot(*doc->material());
    paintRow(*w, 10);
    ASSERT_EQ(doc->history().undoCount(), 1u);
    ASSERT_EQ(doc->undoStack()->count(), 3);
    QAction* undo = findAction(*w, "actionUndo");
    int undone = 0;
    while (undo->isEnabled() && undone < 5) {
        undo->trigger();
        ++undone;
    }
    EXPECT_EQ(undone, 1) << "only the stroke the History still holds can be undone";
    EXPECT_EQ(snapshot(*doc->material()), second);
    EXPECT_TRUE(doc->isModified()) << "the saved step is out of reach: the volume differs";
    findAction(*w, "actionRedo")->trigger();
    EXPECT_EQ(doc->history().undoCount(), 1u);
}

TEST(AppFiles, ExportVdbRoundTrip) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    MaterialVolume* vol = w->document()->material();
    setExactBrush(vp, PAINT, 4.f * vol->spec().voxelSize);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    drag(vp, c - QPoint(25, 5), c + QPoint(25, 5));
    const QString path = outputPath("app_export.vdb");
    QFile::remove(path);
    ASSERT_TRUE(w->exportVdbTo(path, /*wait=*/true));
    const io::ImportedMaterial m = io::importVdb(path.toStdString());
    EXPECT_EQ(m.volume.spec(), vol->spec());
    EXPECT_EQ(snapshot(m.volume), snapshot(*vol)) << "VDB export must be bit-exact";
    // Import through the UI path as well (drag-and-drop / File ▸ Import VDB).
    MainWindow other(false);
    ASSERT_TRUE(other.openFile(path));
    EXPECT_EQ(snapshot(*other.document()->material()), snapshot(*vol));
}

TEST(AppFiles, ExportVdbOfUntouchedDefaultScene) {
    MainWindow w(/*restoreSettings=*/false);
    const QString path = outputPath("app_default.vdb");
    QFile::remove(path);
    ASSERT_TRUE(w.exportVdbTo(path, /*wait=*/true)) << w.lastError().toStdString();
    ASSERT_TRUE(QFile::exists(path));
    const io::ImportedMaterial m = io::importVdb(path.toStdString());
    EXPECT_EQ(snapshot(m.volume), snapshot(*w.document()->material()));
}

TEST(AppFiles, ImportMeshByDragAndDrop) {
    if (const std::string why = meshDropSkipReason(); !why.empty())
        GTEST_SKIP() << why;
    auto w = shownWindow();
    const auto data = suzanneDragData();
    QDropEvent drop(QPointF(10, 10), Qt::CopyAction, data.get(), Qt::LeftButton, Qt::NoModifier);
    // Delivered straight to the window's event handler (QApplication's drop routing wants a
    // live QDrag session, which a synthetic event does not have).
    static_cast<QObject*>(w.get())->event(&drop);
    expectSuzanneOpened(*w);
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

TEST(AppFiles, ImportMeshByDropOnTheGlWindow) {
    if (const std::string why = meshDropSkipReason(); !why.empty())
        GTEST_SKIP() << why;
    auto w = shownWindow();
    QWindow* gl = w->viewport()->glWindow();
    const auto data = suzanneDragData();
    // The window system sends drags over the viewport to the GL window; it hands them to the
    // main window, which accepts files.
    const QPoint pos(w->viewport()->width() / 2, w->viewport()->height() / 2);
    QDragEnterEvent enter(pos, Qt::CopyAction, data.get(), Qt::LeftButton, Qt::NoModifier);
    QCoreApplication::sendEvent(gl, &enter);
    EXPECT_TRUE(enter.isAccepted()) << "the drag over the GL window was refused";
    EXPECT_EQ(enter.dropAction(), Qt::CopyAction);
    QDropEvent drop(QPointF(pos), Qt::CopyAction, data.get(), Qt::LeftButton, Qt::NoModifier);
    QCoreApplication::sendEvent(gl, &drop);
    expectSuzanneOpened(*w);
    renderOneFrame(w->viewport());
    EXPECT_EQ(w->viewport()->stats().glErrors, 0);
}

// Issue 17, item 4: a reopened project lost the camera (the viewport's view was never written
// into the scene) and referred to its mesh by a path climbing out of the project folder. The
// view is saved, the mesh is copied beside the project, and a project whose camera does not
// show the object opens framed.
TEST(AppFiles, ProjectKeepsTheCameraAndItsMesh) {
    const std::string skip = meshDropSkipReason();
    if (!skip.empty())
        GTEST_SKIP() << skip;
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    ASSERT_TRUE(w->importMesh(suzannePath(), /*mmPerUnit=*/10.0)) << w->lastError().toStdString();
    OrbitCamera& cam = vp->camera();
    cam.yawDeg += 35.f;
    cam.pitchDeg = 20.f;
    cam.distance *= 0.8f;
    cam.target += Vector3f(1.f, -0.5f, 0.f);
    const OrbitCamera seen = cam;
    QDir dir(outputPath("app_project_camera"));
    dir.removeRecursively();
    ASSERT_TRUE(QDir().mkpath(dir.path()));
    const QString project = dir.filePath(QStringLiteral("head.json"));
    ASSERT_TRUE(w->saveTo(project)) << w->lastError().toStdString();
    // The mesh now lies beside the project and the JSON names it without climbing out.
    EXPECT_TRUE(QFile::exists(dir.filePath(QStringLiteral("suzanne.obj"))));
    QFile json(project);
    ASSERT_TRUE(json.open(QIODevice::ReadOnly));
    const QString text = QString::fromUtf8(json.readAll());
    EXPECT_TRUE(text.contains(QStringLiteral("\"suzanne.obj\""))) << text.toStdString();
    EXPECT_FALSE(text.contains(QStringLiteral(".."))) << text.toStdString();
    // Reopened in another window: the same view (float round trip through eye/target).
    MainWindow other(/*restoreSettings=*/false);
    ASSERT_TRUE(other.openFile(project)) << other.lastError().toStdString();
    const OrbitCamera& back = other.viewport()->camera();
    const float tol = 1e-4f * seen.distance;  // float32 eye/target written with 9 digits
    EXPECT_NEAR(glm::length(back.eye() - seen.eye()), 0.f, tol);
    EXPECT_NEAR(glm::length(back.target - seen.target), 0.f, tol);
    EXPECT_NEAR(back.distance, seen.distance, tol);
    EXPECT_FLOAT_EQ(back.fovYDeg, seen.fovYDeg);
    EXPECT_EQ(other.document()->mesh()->triangleCount(), w->document()->mesh()->triangleCount());
    // Saving again does not copy the mesh a second time.
    ASSERT_TRUE(other.saveTo(project)) << other.lastError().toStdString();
    EXPECT_EQ(dir.entryList({QStringLiteral("*.obj")}, QDir::Files).size(), 1);
    // A camera looking away from the object (a project saved by an older build): framed.
    json.close();
    const QString awayPath = dir.filePath(QStringLiteral("away.json"));
    {
        // Camera 10 m away on the far side, looking further away: the object is behind it.
        QJsonObject root = QJsonDocument::fromJson(text.toUtf8()).object();
        QJsonObject camera = root[QStringLiteral("camera")].toObject();
        camera[QStringLiteral("position")] = QJsonArray{0, 0, 10000};
        camera[QStringLiteral("target")] = QJsonArray{0, 0, 20000};
        root[QStringLiteral("camera")] = camera;
        root[QStringLiteral("material")] =
            QJsonObject{{QStringLiteral("vdb"), QStringLiteral("away.vdb")}};
        QFile f(awayPath);
        ASSERT_TRUE(f.open(QIODevice::WriteOnly));
        f.write(QJsonDocument(root).toJson());
    }
    // The sidecar head.json refers to now (saves alternate <stem>.vdb and <stem>.1.vdb).
    const std::vector<std::string> headFiles = projectFiles(project.toStdString());
    ASSERT_EQ(headFiles.size(), 2u);
    QFile::copy(QString::fromStdString(headFiles[1]), dir.filePath(QStringLiteral("away.vdb")));
    ASSERT_TRUE(other.openFile(awayPath)) << other.lastError().toStdString();
    EXPECT_TRUE(other.viewport()->cameraShowsObject());
    const Bounds3f b = other.document()->mesh()->bounds();
    EXPECT_LT(glm::length(other.viewport()->camera().target - b.center()), 1e-3f);
}

// Issue 17, item 5: Suzanne (2.7 units wide) was taken as millimetres, so the 6 mm brush
// covered the whole head, and the import said only "5 warnings".
TEST(AppFiles, MeshImportGuessesTheUnitAndScalesTheBrush) {
    // The guess: the unit that makes the object closest to 100 mm.
    EXPECT_DOUBLE_EQ(MainWindow::guessMillimetresPerUnit(2.7), 10.0);      // Suzanne: cm
    EXPECT_DOUBLE_EQ(MainWindow::guessMillimetresPerUnit(0.155), 1000.0);  // bunny: m
    EXPECT_DOUBLE_EQ(MainWindow::guessMillimetresPerUnit(60.0), 1.0);      // already mm
    EXPECT_DOUBLE_EQ(MainWindow::guessMillimetresPerUnit(0.0), 1.0);
    EXPECT_FALSE(MainWindow::meshSizeWarning(2.7).isEmpty());
    EXPECT_FALSE(MainWindow::meshSizeWarning(2700.0 * 10.0).isEmpty());
    EXPECT_TRUE(MainWindow::meshSizeWarning(27.0).isEmpty());
    const std::string skip = meshDropSkipReason();
    if (!skip.empty())
        GTEST_SKIP() << skip;
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    // Scripted import (no dialog): the guessed unit.
    ASSERT_TRUE(w->importMesh(suzannePath(), /*mmPerUnit=*/0.0)) << w->lastError().toStdString();
    const Vector3f e = w->document()->mesh()->bounds().extent();
    const float across = std::max({e.x, e.y, e.z});
    EXPECT_NEAR(across, 27.f, 2.f) << "Suzanne is 2.7 units wide, in cm";
    EXPECT_FLOAT_EQ(w->document()->scene().objects[0].meshSource.scale, 10.f);
    const float diagonal = glm::length(e);
    float radius = vp->brush().engine.radius;
    EXPECT_GE(radius, diagonal / 200.f);
    EXPECT_LE(radius, diagonal / 4.f) << "the brush covers the whole object";
    // Every repair the reader made is spelled out, not just counted.
    for (const QString& warning : w->lastImportWarnings())
        EXPECT_TRUE(w->lastImportMessage().contains(warning)) << warning.toStdString();
    // Forced to millimetres: the size is flagged and the brush shrinks with the object.
    ASSERT_TRUE(w->importMesh(suzannePath(), /*mmPerUnit=*/1.0));
    EXPECT_TRUE(w->lastImportMessage().contains(QStringLiteral("only 2.7")))
        << w->lastImportMessage().toStdString();
    const float smallDiagonal = glm::length(w->document()->mesh()->bounds().extent());
    radius = vp->brush().engine.radius;
    EXPECT_LE(radius, smallDiagonal / 4.f);
    EXPECT_GE(radius, smallDiagonal / 200.f);
    // And a stroke across it paints part of it, not all of it.
    renderOneFrame(vp);
    const QPoint c(vp->width() / 2, vp->height() / 2);
    ASSERT_TRUE(vp->pickAt(c));
    EXPECT_EQ(vp->strokeBetween(c - QPoint(3, 0), c + QPoint(3, 0)), 1);
}

// Issue 17, item 9: a garbage .ply printed raw binary into the error dialog.
TEST(AppFiles, BinaryGarbageIsNotQuotedRaw) {
    const QString bad = outputPath("app_garbage.ply");
    QFile file(bad);
    ASSERT_TRUE(file.open(QIODevice::WriteOnly));
    QByteArray bytes("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n");
    for (int i = 0; i < 400; ++i)
        bytes.append(char((i * 97 + 13) % 256));  // binary body, NULs and control bytes
    file.write(bytes);
    file.close();
    MainWindow w(/*restoreSettings=*/false);
    EXPECT_FALSE(w.openFile(bad));
    const QString message = w.lastError();
    ASSERT_FALSE(message.isEmpty());
    EXPECT_LE(message.size(), 700);
    for (const QChar ch : message) {
        EXPECT_NE(ch, QChar::ReplacementCharacter) << message.toStdString();
        EXPECT_TRUE(ch == QLatin1Char('\n') || ch.category() != QChar::Other_Control)
            << "control character " << int(ch.unicode()) << " in: " << message.toStdString();
    }
    // The cleaning itself: invalid UTF-8 and control bytes become one marker per run.
    const QString cleaned =
        MainWindow::readableMessage(std::string("bad '") + "\x01\x02\xff\xfe" + "' here");
    EXPECT_EQ(cleaned, QStringLiteral("bad '<binary data>' here"));
    EXPECT_LE(MainWindow::readableMessage(std::string(5000, 'x')).size(), 601);
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

TEST(AppFiles, ExportRenderPngIsToneMappedAndExrIsLinear) {
    auto w = shownWindow(1);
    Viewport* vp = w->viewport();
    RenderSettings rs = vp->renderSettings();
    rs.method = "direct";      // deterministic frame after frame
    rs.resolutionScale = 1.f;  // render pixels = widget pixels: no upscale
    rs.exposureStops = 1.f;
    vp->setRenderSettings(rs);
    renderOneFrame(vp);
    const QString png = outputPath("app_render.png"), exr = outputPath("app_render.exr"),
                  exr2 = outputPath("app_render_exposure3.exr");
    for (const QString& p : {png, exr, exr2})
        QFile::remove(p);
    ASSERT_TRUE(w->exportRenderTo(png)) << w->lastError().toStdString();
    ASSERT_TRUE(w->exportRenderTo(exr)) << w->lastError().toStdString();
    const QImage img = QImage(png).convertToFormat(QImage::Format_RGB32);
    ASSERT_EQ(img.size(), vp->size() * vp->devicePixelRatio());
    const ImageRgb lin = readExr(exr.toStdString());
    ASSERT_EQ(lin.width(), img.width());
    ASSERT_EQ(lin.height(), img.height());
    // The PNG is the EXR through the viewport's tone map (exposure 2^1, Reinhard, sRGB): every
    // 8-bit value within one level (rounding of the GPU's float maths and 8-bit target).
    const ToneMap tm{std::exp2(1.f), ToneMap::Curve::Reinhard};
    int worst = 0;
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x) {
            const Rgb& l = lin.at(x, y);
            ASSERT_TRUE(std::isfinite(l.r) && std::isfinite(l.g) && std::isfinite(l.b))
                << "pixel " << x << "," << y;
            ASSERT_TRUE(l.r >= 0.f && l.g >= 0.f && l.b >= 0.f) << "pixel " << x << "," << y;
            const Rgb d = toneMapToDisplay(l, tm);
            const QRgb p = img.pixel(x, y);
            worst = std::max({worst, std::abs(qRed(p) - int(std::lround(255.f * d.r))),
                              std::abs(qGreen(p) - int(std::lround(255.f * d.g))),
                              std::abs(qBlue(p) - int(std::lround(255.f * d.b)))});
        }
    EXPECT_LE(worst, 1) << "the PNG is not the EXR tone-mapped";
    // Linear radiance does not depend on the exposure: at +3 stops the object's pixels are the
    // same (the background is chosen per exposure so it shows the clear colour: skip it).
    rs.exposureStops = 3.f;
    vp->setRenderSettings(rs);
    renderOneFrame(vp);
    ASSERT_TRUE(w->exportRenderTo(exr2));
    const ImageRgb lin2 = readExr(exr2.toStdString());
    ASSERT_EQ(lin2.width(), lin.width());
    const Rgb background = lin.at(0, 0);  // the corner shows no object in the default view
    long long object = 0;
    double worstRel = 0.0;
    for (int y = 0; y < lin.height(); ++y)
        for (int x = 0; x < lin.width(); ++x) {
            if (lin.at(x, y) == background)
                continue;
            ++object;
            for (int c = 0; c < 3; ++c) {
                const double a = lin.at(x, y)[c], b = lin2.at(x, y)[c];
                worstRel = std::max(worstRel, std::abs(a - b) / std::max(std::abs(a), 1e-12));
            }
        }
    EXPECT_GT(double(object), 0.02 * double(lin.width()) * lin.height());
    // The same deterministic frame, only the tone map changed: equal to float precision.
    EXPECT_LT(worstRel, 1e-5);
}

TEST(AppFiles, AutosaveIsRecoveredAfterACrashAndRemovedOnCleanExit) {
    // Settings and the autosave go to the Qt test locations (~/.qttest), not the user's.
    QStandardPaths::setTestModeEnabled(true);
    const QString autosave = MainWindow::autosavePath();
    const QString autosaveVdb = QFileInfo(autosave).path() + QStringLiteral("/autosave.vdb");
    QFile::remove(autosave);
    QFile::remove(autosaveVdb);
    qunsetenv(MainWindow::RECOVERY_ENV);
    std::vector<float> painted;
    {
        // Painting needs the viewport's size (picking), not its GL frames: the window stays
        // hidden, which keeps the test fast.
        auto w = std::make_unique<MainWindow>(/*restoreSettings=*/true);
        w->viewport()->setFixedSize(640, 360);
        Viewport* vp = w->viewport();
        setExactBrush(vp, PAINT, 4.f * w->document()->material()->spec().voxelSize);
        const QPointF c(vp->width() / 2.0, vp->height() / 2.0);
        ASSERT_EQ(vp->strokeBetween(c - QPointF(30, 5), c + QPointF(30, 5)), 1);
        painted = snapshot(*w->document()->material());
        w->autosaveNow();  // what the 2-minute timer does
        ASSERT_TRUE(QFile::exists(autosave));
        EXPECT_TRUE(QFile::exists(autosaveVdb));
        // The crash: the window goes away without a close event, so nothing is cleaned up.
    }
    ASSERT_TRUE(QFile::exists(autosave));
    // Restart: recovery is offered, and accepted here through the environment.
    qputenv(MainWindow::RECOVERY_ENV, "accept");
    auto w = std::make_unique<MainWindow>(/*restoreSettings=*/true);
    EXPECT_TRUE(QTest::qWaitFor([&] { return w->document()->isModified(); }, 10000))
        << "recovery was not offered";
    qunsetenv(MainWindow::RECOVERY_ENV);
    EXPECT_EQ(snapshot(*w->document()->material()), painted)
        << "the recovered material must equal the painted one bit-exactly";
    EXPECT_TRUE(w->document()->filePath().isEmpty()) << "recovered work is an unsaved project";
    EXPECT_TRUE(QFile::exists(autosave)) << "kept until the next autosave or a clean exit";
    // Clean exit: the unsaved-changes question is answered "Discard"; the autosave goes.
    bool asked = false;
    QTimer::singleShot(100, [&asked] {
        for (QWidget* t : QApplication::topLevelWidgets())
            if (auto* box = qobject_cast<QMessageBox*>(t); box && box->isVisible())
                if (QAbstractButton* discard = box->button(QMessageBox::Discard)) {
                    asked = true;
                    discard->click();
                }
    });
    EXPECT_TRUE(w->close());
    EXPECT_TRUE(asked) << "closing with unsaved changes must ask";
    EXPECT_FALSE(QFile::exists(autosave));
    EXPECT_FALSE(QFile::exists(autosaveVdb));
    QStandardPaths::setTestModeEnabled(false);
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
    const int result = RUN_ALL_TESTS();
    lucent::app::test::keepLibrariesLoaded();  // LSan names the GL driver's leaks at exit
    return result;
}
