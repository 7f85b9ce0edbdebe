// SPDX-License-Identifier: MIT
/// @file
/// @brief Qt Tests (under Xvfb) of the app's docks and menus beyond test_app.cpp: light types
/// (change, add, fields shown per type, colour) as undo steps that reach the renderer; VDB
/// export options (native / renderer-ready / Mitsuba); preferences remembered in QSettings;
/// drag-and-drop filtering; conventional shortcuts; brush radius on screen and its keys; the
/// live-cost calibration (Edit ▸ Preferences): a calibration file in the config location is
/// planned with, a bad one falls back to the shipped costs with a warning, calibrating writes
/// one and Cancel stops it, "Use Shipped Live Costs" deletes it.

#include "Document.h"
#include "MainWindow.h"
#include "Panels.h"
#include "SliceView.h"
#include "Viewport.h"
#include "GuiTestWaits.h"
#include "GuiTestMain.h"
#include "LightIrradiance.h"

#include <lucent/core/Error.h>
#include <lucent/material/Procedural.h>
#include <lucent/io/VdbIO.h>
#include <lucent/planner/LiveCalibration.h>
#include <lucent/planner/LiveCosts.h>

#include <QAction>
#include <QApplication>
#include <QComboBox>
#include <QDir>
#include <QDragEnterEvent>
#include <QFile>
#include <QFileInfo>
#include <QLabel>
#include <QMenu>
#include <QMimeData>
#include <QSettings>
#include <QSignalSpy>
#include <QSpinBox>
#include <QStandardPaths>
#include <QStatusBar>
#include <QUrl>
#include <QDoubleSpinBox>
#include <QProgressDialog>
#include <QPushButton>
#include <QTest>
#include <QTextBrowser>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>

namespace lucent::app {
namespace {

QAction* findAction(MainWindow& w, const char* name) {
    return w.findChild<QAction*>(QString::fromLatin1(name));
}

template <class T>
T* child(QWidget* parent, const char* name) {
    T* c = parent->findChild<T*>(QString::fromLatin1(name));
    EXPECT_NE(c, nullptr) << "no widget named " << name;
    return c;
}

/// A window shown with the viewport at 320×180 and at least one frame rendered.
std::unique_ptr<MainWindow> shownWindow() {
    auto w = std::make_unique<MainWindow>(/*restoreSettings=*/false);
    w->viewport()->setFixedSize(320, 180);
    w->show();
    EXPECT_TRUE(QTest::qWaitForWindowExposed(w.get(), test::kWindowWaitMs));
    return w;
}

/// Renders one more frame of the viewport and returns it without overlays.
QImage frame(Viewport* vp) {
    return vp->grabRender().convertToFormat(QImage::Format_RGB32);
}

/// Mean |Δ| over the RGB channels of two equally sized images, 8-bit levels.
double meanAbsDiff(const QImage& a, const QImage& b) {
    double sum = 0.0;
    for (int y = 0; y < a.height(); ++y)
        for (int x = 0; x < a.width(); ++x) {
            const QRgb p = a.pixel(x, y), q = b.pixel(x, y);
            sum += std::abs(qRed(p) - qRed(q)) + std::abs(qGreen(p) - qGreen(q)) +
                   std::abs(qBlue(p) - qBlue(q));
        }
    return sum / (3.0 * a.width() * a.height());
}

}  // namespace

// ---- Lights dock: types --------------------------------------------------------------------

TEST(LightsDock, TypeChangeIsOneUndoStepAndShowsItsFields) {
    MainWindow w(/*restoreSettings=*/false);
    Document* doc = w.document();
    LightPanel* panel = w.lightPanel();
    ASSERT_FALSE(doc->scene().lights.empty());
    panel->setCurrentLight(0);
    ASSERT_EQ(doc->scene().lights[0].type, Light::Type::Point) << "default scene's back light";
    const std::vector<Light> before = doc->scene().lights;
    auto* type = child<QComboBox>(panel, "lightType");
    auto* inner = child<QDoubleSpinBox>(panel, "lightSpotInner");
    auto* outer = child<QDoubleSpinBox>(panel, "lightSpotOuter");
    auto* radius = child<QDoubleSpinBox>(panel, "lightRadius");
    auto* dir = child<QDoubleSpinBox>(panel, "lightDir0");
    auto* pos = child<QDoubleSpinBox>(panel, "lightPos0");
    ASSERT_TRUE(type && inner && outer && radius && dir && pos);
    // A point light: position, no direction, no cone, no radius.
    EXPECT_EQ(type->currentIndex(), int(Light::Type::Point));
    EXPECT_TRUE(panel->isFieldShown(pos));
    EXPECT_FALSE(panel->isFieldShown(dir));
    EXPECT_FALSE(panel->isFieldShown(inner));
    EXPECT_FALSE(panel->isFieldShown(radius));

    const int steps = doc->undoStack()->count();
    type->setCurrentIndex(int(Light::Type::Spot));
    ASSERT_EQ(doc->scene().lights[0].type, Light::Type::Spot);
    EXPECT_EQ(doc->undoStack()->count(), steps + 1);
    EXPECT_TRUE(panel->isFieldShown(dir));
    EXPECT_TRUE(panel->isFieldShown(inner));
    EXPECT_TRUE(panel->isFieldShown(outer));
    EXPECT_FALSE(panel->isFieldShown(radius));
    EXPECT_FLOAT_EQ(float(outer->value()), std::round(doc->scene().lights[0].spotOuterDeg * 10.f) /
                                               10.f);  // the field shows the light, 1 decimal
    // The cone fields edit the light; an outer angle below the inner one pulls it down.
    outer->setValue(4.0);
    EXPECT_FLOAT_EQ(doc->scene().lights[0].spotOuterDeg, 4.f);
    EXPECT_FLOAT_EQ(doc->scene().lights[0].spotInnerDeg, 4.f);
    EXPECT_DOUBLE_EQ(inner->value(), 4.0);

    type->setCurrentIndex(int(Light::Type::Sphere));
    ASSERT_EQ(doc->scene().lights[0].type, Light::Type::Sphere);
    EXPECT_TRUE(panel->isFieldShown(radius));
    EXPECT_FALSE(panel->isFieldShown(inner));
    EXPECT_FALSE(panel->isFieldShown(dir));
    radius->setValue(0.5);
    EXPECT_FLOAT_EQ(doc->scene().lights[0].radius, 0.5f);

    type->setCurrentIndex(int(Light::Type::Directional));
    EXPECT_FALSE(panel->isFieldShown(pos));
    EXPECT_TRUE(panel->isFieldShown(dir));

    // Undo through the Edit menu walks back every step, to the original lights exactly.
    QAction* undo = findAction(w, "actionUndo");
    QAction* redo = findAction(w, "actionRedo");
    ASSERT_TRUE(undo && redo);
    undo->trigger();
    EXPECT_EQ(doc->scene().lights[0].type, Light::Type::Sphere);
    EXPECT_EQ(type->currentIndex(), int(Light::Type::Sphere)) << "the dock follows undo";
    while (doc->undoStack()->count() > steps && doc->undoStack()->canUndo() &&
           doc->undoStack()->index() > steps)
        undo->trigger();
    const Light& l = doc->scene().lights[0];
    EXPECT_EQ(l.type, before[0].type);
    EXPECT_EQ(l.position, before[0].position);
    EXPECT_EQ(l.intensity, before[0].intensity);
    redo->trigger();
    EXPECT_EQ(doc->scene().lights[0].type, Light::Type::Spot);
}

TEST(LightsDock, AddsEveryTypeAndRemoves) {
    MainWindow w(/*restoreSettings=*/false);
    Document* doc = w.document();
    LightPanel* panel = w.lightPanel();
    Point3f center;
    float objectRadius = 0.f;
    doc->lightTarget(center, objectRadius);
    const std::vector<Light> original = doc->scene().lights;
    const std::pair<const char*, Light::Type> buttons[] = {
        {"lightAddPoint", Light::Type::Point},
        {"lightAddSpot", Light::Type::Spot},
        {"lightAddDirectional", Light::Type::Directional},
        {"lightAddSphere", Light::Type::Sphere}};
    size_t expected = original.size();
    for (const auto& [name, t] : buttons) {
        auto* b = child<QPushButton>(panel, name);
        ASSERT_NE(b, nullptr);
        b->click();
        ASSERT_EQ(doc->scene().lights.size(), ++expected) << name;
        const Light& l = doc->scene().lights.back();
        EXPECT_EQ(l.type, t) << name;
        EXPECT_EQ(panel->currentLight(), int(expected) - 1) << name;
        if (t != Light::Type::Directional) {
            // About 1 W/mm² on the object: I = 2·size² W/sr at d = √2·size (size = 2·radius),
            // the spot's cone holds it; float32 arithmetic, a few ulps.
            EXPECT_LT(lucent::test::relDiff(lucent::test::irradianceAt(l, center), Rgb(1.f)), 1e-4f)
                << name;
        }
        if (t == Light::Type::Spot) {  // the cone covers the object's bounding sphere
            EXPECT_GE(
                l.spotInnerDeg,
                glm::degrees(std::asin(objectRadius / glm::length(center - l.position))) - 1e-3f);
        }
    }
    // Remove deletes the selected light (the sphere just added), as one undo step.
    auto* remove = child<QPushButton>(panel, "lightRemove");
    ASSERT_NE(remove, nullptr);
    remove->click();
    ASSERT_EQ(doc->scene().lights.size(), expected - 1);
    EXPECT_EQ(doc->scene().lights.back().type, Light::Type::Directional);
    doc->undoStack()->undo();
    EXPECT_EQ(doc->scene().lights.back().type, Light::Type::Sphere);
    // Five steps back: the original lights.
    for (int i = 0; i < 4; ++i)
        doc->undoStack()->undo();
    EXPECT_EQ(doc->scene().lights.size(), original.size());
}

TEST(LightsDock, ColourKeepsTheBrightestChannel) {
    MainWindow w(/*restoreSettings=*/false);
    Document* doc = w.document();
    LightPanel* panel = w.lightPanel();
    panel->setCurrentLight(0);
    const Rgb before = doc->scene().lights[0].intensity;
    const float peak = std::max({before.r, before.g, before.b});
    panel->setCurrentLightColour(QColor::fromRgbF(1.f, 0.5f, 0.25f));
    const Rgb after = doc->scene().lights[0].intensity;
    // QColor keeps 16 bits per channel: ratios within 1/65535 of the peak.
    const float tol = peak / 65535.f;
    EXPECT_FLOAT_EQ(after.r, peak);
    EXPECT_NEAR(after.g, 0.5f * peak, tol);
    EXPECT_NEAR(after.b, 0.25f * peak, tol);
    // The intensity fields follow (3 decimals).
    EXPECT_NEAR(child<QDoubleSpinBox>(panel, "lightIntensity1")->value(), double(after.g), 5e-4);
    doc->undoStack()->undo();
    EXPECT_EQ(doc->scene().lights[0].intensity, before);
}

TEST(LightsDock, EtaIsAnUndoStepReachingTheMaterial) {
    MainWindow w(/*restoreSettings=*/false);
    Document* doc = w.document();
    const float before = doc->scene().eta;
    auto* eta = child<QDoubleSpinBox>(w.lightPanel(), "lightEta");
    ASSERT_NE(eta, nullptr);
    eta->setValue(1.5);
    EXPECT_FLOAT_EQ(doc->scene().eta, 1.5f);
    EXPECT_FLOAT_EQ(doc->material()->eta(), 1.5f) << "the material (saved in the VDB) too";
    EXPECT_TRUE(doc->isModified());
    findAction(w, "actionUndo")->trigger();
    EXPECT_FLOAT_EQ(doc->scene().eta, before);
    EXPECT_FLOAT_EQ(doc->material()->eta(), before);
    EXPECT_NEAR(eta->value(), double(before), 5e-4);  // the field follows, 3 decimals
    EXPECT_FALSE(doc->isModified());
    findAction(w, "actionRedo")->trigger();
    EXPECT_FLOAT_EQ(doc->material()->eta(), 1.5f);
    EXPECT_THROW(doc->setEta(0.5f), Error);
}

// ---- Renderer ------------------------------------------------------------------------------

TEST(LightsDock, TypeAndConeEditsReachTheRenderer) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    Document* doc = w->document();
    LightPanel* panel = w->lightPanel();
    ASSERT_TRUE(w->setRenderMethod(QStringLiteral("direct")));
    // Only the default scene's front light (L1; L0 lights the hidden back) stays, so its
    // edits show in full on the opaque surface of the Direct method.
    ASSERT_GE(doc->scene().lights.size(), 2u);
    doc->setLights({doc->scene().lights[1]}, QStringLiteral("One light"));
    panel->setCurrentLight(0);
    const QImage point = frame(vp);
    // As a spot aimed at the object with a cone holding it, the image barely changes ...
    child<QComboBox>(panel, "lightType")->setCurrentIndex(int(Light::Type::Spot));
    const QImage spot = frame(vp);
    // ... turned away from the object, its light is gone.
    auto* dirY = child<QDoubleSpinBox>(panel, "lightDir1");
    const Vector3f away = -doc->scene().lights[0].direction;
    child<QDoubleSpinBox>(panel, "lightDir0")->setValue(double(away.x));
    dirY->setValue(double(away.y));
    child<QDoubleSpinBox>(panel, "lightDir2")->setValue(double(away.z));
    const QImage awayImage = frame(vp);
    EXPECT_EQ(vp->stats().glErrors, 0);
    QDir().mkpath(QStringLiteral(LUCENT_TEST_OUTPUT_DIR));
    awayImage.save(QStringLiteral(LUCENT_TEST_OUTPUT_DIR "/panels_spot_away.png"));
    const double dSpot = meanAbsDiff(point, spot), dAway = meanAbsDiff(point, awayImage);
    EXPECT_GT(dAway, 1.0) << "turning the spot away must darken the view";
    EXPECT_GT(dAway, 4.0 * dSpot) << "a spot holding the object lights it like the point did";
}

// ---- Files: Export VDB options ------------------------------------------------------------

TEST(ExportVdb, NativeOrRendererReadyGridsAndMitsubaFiles) {
    MainWindow w(/*restoreSettings=*/false);
    QDir().mkpath(QStringLiteral(LUCENT_TEST_OUTPUT_DIR));
    const QString dir = QStringLiteral(LUCENT_TEST_OUTPUT_DIR);
    const auto gridNames = [](const QString& path) {
        std::set<std::string> names;
        for (const io::VdbGridSummary& g : io::summarizeVdb(path.toStdString()).grids)
            names.insert(g.name);
        return names;
    };
    MainWindow::VdbExportChoice native;
    native.rendererGrids = false;
    native.materialName = QStringLiteral("native test");
    const QString nativePath = dir + QStringLiteral("/panels_native.vdb");
    ASSERT_TRUE(w.exportVdbTo(nativePath, native, /*wait=*/true)) << w.lastError().toStdString();
    EXPECT_EQ(gridNames(nativePath), (std::set<std::string>{"sigma_t", "sigma_s", "g"}));
    EXPECT_EQ(w.lastExportSteps(), 1);
    EXPECT_EQ(io::importVdb(nativePath.toStdString()).metadata.materialName, "native test");

    MainWindow::VdbExportChoice ready;
    ready.rendererGrids = true;
    ready.mitsubaVol = true;
    const QString readyPath = dir + QStringLiteral("/panels_ready.vdb");
    for (const char* f :
         {"/panels_ready_sigma_t.vol", "/panels_ready_albedo.vol", "/panels_ready_medium.xml"})
        QFile::remove(dir + QString::fromLatin1(f));
    ASSERT_TRUE(w.exportVdbTo(readyPath, ready, /*wait=*/true)) << w.lastError().toStdString();
    EXPECT_EQ(gridNames(readyPath),
              (std::set<std::string>{"sigma_t", "sigma_s", "g", "density", "albedo", "color"}));
    EXPECT_EQ(w.lastExportSteps(), 4);
    for (const char* f :
         {"/panels_ready_sigma_t.vol", "/panels_ready_albedo.vol", "/panels_ready_medium.xml"})
        EXPECT_TRUE(QFile::exists(dir + QString::fromLatin1(f))) << f;
    // Both files hold the painted volume bit-exactly.
    EXPECT_EQ(io::importVdb(readyPath.toStdString()).volume.denseComponent(0),
              w.document()->material()->denseComponent(0));
}

TEST(ExportVdb, FailureIsReportedNamingTheFile) {
    MainWindow w(/*restoreSettings=*/false);
    const QString bad = QStringLiteral("/nonexistent-dir/x.vdb");
    EXPECT_FALSE(w.exportVdbTo(bad, /*wait=*/true));
    EXPECT_TRUE(w.lastError().contains(QStringLiteral("nonexistent-dir")))
        << w.lastError().toStdString();
}

// ---- Tools dock: procedural fills ---------------------------------------------------------

TEST(BrushPanelTest, SurfaceLayerFillPutsTheBrushValueDownToItsThickness) {
    MainWindow w(/*restoreSettings=*/false);
    Document* doc = w.document();
    BrushPanel* brush = w.brushPanel();
    MaterialVolume* vol = doc->material();
    const MaterialSample paint{Rgb(7.5f, 6.25f, 5.f), Rgb(5.f, 4.f, 3.f), Rgb(0.25f)};
    brush->setBrushValue(paint);
    child<QComboBox>(brush, "brushPattern")->setCurrentIndex(int(ProceduralPattern::Layered));
    // Not a multiple of half a voxel, so no voxel centre lies on the layer's boundary.
    const float thickness = 2.3f * vol->spec().voxelSize;
    child<QDoubleSpinBox>(brush, "brushLayerThickness")->setValue(double(thickness));
    EXPECT_FLOAT_EQ(brush->proceduralFill().layers.at(0).thickness,
                    float(child<QDoubleSpinBox>(brush, "brushLayerThickness")->value()));
    const float t = brush->proceduralFill().layers[0].thickness;  // as the field rounded it
    const int steps = doc->undoStack()->count();
    child<QPushButton>(brush, "brushProceduralFill")->click();
    ASSERT_EQ(doc->undoStack()->count(), steps + 1) << "one undo step";
    const std::vector<float> depth = distanceToSurface(*vol);
    const MaterialSample top = sanitize(brush->proceduralFill().materialB);
    const MaterialSample below = sanitize(vol->base());
    const int n = vol->resolution();
    long long inLayer = 0, under = 0;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Coord c(x, y, z);
                if (!vol->isInside(c))
                    continue;
                const bool layer = depth[vol->spec().linearIndex(c)] < t;
                (layer ? inLayer : under) += 1;
                ASSERT_EQ(vol->at(c).sigma_t, (layer ? top : below).sigma_t)
                    << x << " " << y << " " << z;
            }
    EXPECT_GT(inLayer, 0);
    EXPECT_GT(under, 0) << "the default shape is thicker than 2 × 2.3 voxels somewhere";
    doc->undoStack()->undo();
}

TEST(BrushPanelTest, ProceduralSeedAndOctavesReachTheFill) {
    MainWindow w(/*restoreSettings=*/false);
    BrushPanel* brush = w.brushPanel();
    Document* doc = w.document();
    child<QComboBox>(brush, "brushPattern")->setCurrentIndex(int(ProceduralPattern::Turbulence));
    child<QSpinBox>(brush, "brushPatternOctaves")->setValue(3);
    EXPECT_EQ(brush->proceduralFill().octaves, 3);
    const auto fillWithSeed = [&](int seed) {
        child<QSpinBox>(brush, "brushPatternSeed")->setValue(seed);
        child<QPushButton>(brush, "brushProceduralFill")->click();
        std::vector<float> v = doc->material()->denseComponent(0);
        doc->undoStack()->undo();
        return v;
    };
    const std::vector<float> a = fillWithSeed(1), b = fillWithSeed(2), a2 = fillWithSeed(1);
    EXPECT_EQ(a, a2) << "the same seed gives the same pattern";
    EXPECT_NE(a, b) << "another seed another pattern";
}

// ---- Mesh menu ------------------------------------------------------------------------------

TEST(MeshMenu, EditsTakeTheirParameterAndRefuseBadOnes) {
    MainWindow w(/*restoreSettings=*/false);
    Document* doc = w.document();
    const size_t before = doc->mesh()->triangleCount();
    MainWindow::MeshEditParams p;
    p.decimateFraction = 0.25;
    ASSERT_TRUE(w.applyMeshEdit(MainWindow::MeshEditKind::Decimate, p))
        << w.lastError().toStdString();
    // Quadric decimation stops at about the target (MeshEdit.h): a quarter, give or take the
    // last collapses; far below what "Decimate to half" gave.
    const size_t after = doc->mesh()->triangleCount();
    EXPECT_LE(after, before * 3 / 10) << before << " → " << after;
    EXPECT_GE(after, before / 5) << before << " → " << after;
    // Out-of-range parameters are reported, naming the edit, and leave the mesh unchanged.
    p.subdivideIterations = 9;
    EXPECT_FALSE(w.applyMeshEdit(MainWindow::MeshEditKind::Subdivide, p));
    EXPECT_EQ(doc->mesh()->triangleCount(), after);
    p.decimateFraction = 1.5;
    EXPECT_FALSE(w.applyMeshEdit(MainWindow::MeshEditKind::Decimate, p));
    EXPECT_TRUE(w.lastError().contains(QStringLiteral("decimate"))) << w.lastError().toStdString();
    EXPECT_EQ(doc->mesh()->triangleCount(), after);
}

// ---- Main window: preferences, drops, shortcuts --------------------------------------------

TEST(MainWindowPrefs, BrushRenderAndViewPreferencesAreRemembered) {
    // Settings go to the Qt test locations (~/.qttest), not the user's.
    QStandardPaths::setTestModeEnabled(true);
    QSettings().clear();
    qputenv(MainWindow::RECOVERY_ENV, "discard");
    {
        MainWindow w(/*restoreSettings=*/true);
        child<QDoubleSpinBox>(w.brushPanel(), "brushRadius")->setValue(7.25);
        child<QComboBox>(w.brushPanel(), "brushFalloff")->setCurrentIndex(3);
        child<QDoubleSpinBox>(w.brushPanel(), "brushSigmaT1")->setValue(4.5);
        auto* method = child<QComboBox>(w.renderPanel(), "renderMethod");
        method->setCurrentIndex(method->findData(QStringLiteral("single-scattering")));
        child<QDoubleSpinBox>(w.renderPanel(), "renderExposure")->setValue(-1.5);
        child<QSpinBox>(w.renderPanel(), "param.sslpv.grid")->setValue(64);
        child<QSpinBox>(w.renderPanel(), "param.single-scattering.steps")->setValue(12);
        auto* mode = child<QComboBox>(w.renderPanel(), "param.sslpv.mode");
        mode->setCurrentIndex(mode->findData(QStringLiteral("calibrated")));
        findAction(w, "actionLightGizmos")->setChecked(false);
        ASSERT_TRUE(w.close());
    }
    {
        MainWindow w(/*restoreSettings=*/true);
        EXPECT_DOUBLE_EQ(child<QDoubleSpinBox>(w.brushPanel(), "brushRadius")->value(), 7.25);
        EXPECT_EQ(child<QComboBox>(w.brushPanel(), "brushFalloff")->currentIndex(), 3);
        EXPECT_DOUBLE_EQ(child<QDoubleSpinBox>(w.brushPanel(), "brushSigmaT1")->value(), 4.5);
        // ... and they reach the engine-side settings, not only the fields.
        EXPECT_FLOAT_EQ(w.viewport()->brush().engine.radius, 7.25f);
        EXPECT_EQ(w.viewport()->brush().engine.falloff, Falloff(3));
        EXPECT_EQ(w.viewport()->renderSettings().method, "single-scattering");
        EXPECT_EQ(w.viewport()->renderSettings().params.toString(), "steps=12");
        EXPECT_FLOAT_EQ(w.viewport()->renderSettings().exposureStops, -1.5f);
        EXPECT_EQ(child<QSpinBox>(w.renderPanel(), "param.sslpv.grid")->value(), 64);
        EXPECT_EQ(child<QComboBox>(w.renderPanel(), "param.sslpv.mode")->currentData(),
                  QStringLiteral("calibrated"));
        EXPECT_FALSE(w.viewport()->lightGizmosVisible());
        ASSERT_TRUE(w.close());
    }
    {
        // Without settings (tests, scripted runs) the defaults hold.
        MainWindow w(/*restoreSettings=*/false);
        EXPECT_EQ(w.viewport()->renderSettings().method, RenderSettings{}.method);
        EXPECT_TRUE(w.viewport()->lightGizmosVisible());
    }
    {
        // Preferences of a build before issue 17 saved SSLPV, the old default, at every exit:
        // not taken as a choice (the new default shows paint); the other fields are.
        QSettings s;
        s.remove(QStringLiteral("render/defaultsVersion"));
        s.setValue(QStringLiteral("render/renderMethod"), 2);  // SSLPV's index then
        s.sync();
        MainWindow w(/*restoreSettings=*/true);
        EXPECT_EQ(w.viewport()->renderSettings().method, RenderSettings{}.method);
        EXPECT_FLOAT_EQ(w.viewport()->renderSettings().exposureStops, -1.5f);
        ASSERT_TRUE(w.close());
    }
    {
        // Preferences of a build before the method registry (defaults version 2) saved the
        // selector's index in the order of the app's old method enum: it still maps.
        QSettings s;
        s.setValue(QStringLiteral("render/defaultsVersion"), 2);
        s.setValue(QStringLiteral("render/renderMethod"), 5);  // the directional dipole then
        s.sync();
        MainWindow w(/*restoreSettings=*/true);
        EXPECT_EQ(w.viewport()->renderSettings().method, "dirpole");
        ASSERT_TRUE(w.close());
    }
    {
        // Until Auto became the default (version 4) every session saved Dipole, the default
        // then, at exit: not taken as a choice.
        QSettings s;
        s.setValue(QStringLiteral("render/defaultsVersion"), 3);
        s.setValue(QStringLiteral("render/renderMethod"), QStringLiteral("dipole"));
        s.sync();
        MainWindow w(/*restoreSettings=*/true);
        EXPECT_EQ(w.viewport()->renderSettings().method, AUTO_METHOD);
    }
    {
        // Since then the method is saved by name (as the window two blocks up saved it).
        QSettings s;
        s.setValue(QStringLiteral("render/defaultsVersion"), 4);
        s.setValue(QStringLiteral("render/renderMethod"), QStringLiteral("dirpole"));
        s.sync();
    }
    {
        MainWindow w(/*restoreSettings=*/true);
        EXPECT_EQ(w.viewport()->renderSettings().method, "dirpole");
        EXPECT_EQ(QSettings().value(QStringLiteral("render/renderMethod")).toString(),
                  QStringLiteral("dirpole"));
    }
    QSettings().clear();
    qunsetenv(MainWindow::RECOVERY_ENV);
    QStandardPaths::setTestModeEnabled(false);
}

TEST(MainWindowMenus, RecentFilesShowMissingOnesAndClear) {
    MainWindow w(/*restoreSettings=*/false);
    QDir().mkpath(QStringLiteral(LUCENT_TEST_OUTPUT_DIR));
    const QString a = QStringLiteral(LUCENT_TEST_OUTPUT_DIR "/panels_recent_a.json");
    const QString b = QStringLiteral(LUCENT_TEST_OUTPUT_DIR "/panels_recent_b.json");
    ASSERT_TRUE(w.saveTo(a)) << w.lastError().toStdString();
    ASSERT_TRUE(w.saveTo(b)) << w.lastError().toStdString();
    auto* menu = w.findChild<QMenu*>(QStringLiteral("menuRecent"));
    ASSERT_NE(menu, nullptr);
    const auto entries = [menu] {
        QList<QAction*> files;
        for (QAction* x : menu->actions())
            if (!x->isSeparator() && x->objectName() != QLatin1String("actionClearRecent"))
                files.push_back(x);
        return files;
    };
    ASSERT_EQ(entries().size(), 2);
    EXPECT_EQ(entries()[0]->toolTip(), QFileInfo(b).absoluteFilePath()) << "newest first";
    EXPECT_TRUE(entries()[1]->isEnabled());
    QFile::remove(a);
    Q_EMIT menu->aboutToShow();
    ASSERT_EQ(entries().size(), 2);
    EXPECT_FALSE(entries()[1]->isEnabled()) << "a deleted file cannot be opened";
    EXPECT_TRUE(entries()[1]->text().contains(QStringLiteral("missing")));
    QAction* clear = w.findChild<QAction*>(QStringLiteral("actionClearRecent"));
    ASSERT_NE(clear, nullptr);
    clear->trigger();
    QCoreApplication::processEvents();
    EXPECT_TRUE(entries().isEmpty());
    EXPECT_FALSE(menu->isEnabled());
}

TEST(RenderPanelTest, CameraBookmarksAreKeptWithTheProject) {
    QStandardPaths::setTestModeEnabled(true);
    QSettings().clear();
    qputenv(MainWindow::RECOVERY_ENV, "discard");
    QDir().mkpath(QStringLiteral(LUCENT_TEST_OUTPUT_DIR));
    const QString project = QStringLiteral(LUCENT_TEST_OUTPUT_DIR "/panels_bookmarks.json");
    OrbitCamera first, second;
    {
        MainWindow w(/*restoreSettings=*/true);
        ASSERT_TRUE(w.saveTo(project)) << w.lastError().toStdString();
        OrbitCamera& c = w.viewport()->camera();
        c.yawDeg = 33.f;
        c.distance = 71.5f;
        first = c;
        child<QPushButton>(w.renderPanel(), "renderBookmarkSave")->click();
        c.yawDeg = -120.f;
        c.pitchDeg = 20.f;
        c.target = Point3f(1.f, 2.f, 3.f);
        second = c;
        child<QPushButton>(w.renderPanel(), "renderBookmarkSave")->click();
        child<QPushButton>(w.renderPanel(), "renderBookmarkSave")->click();
        child<QPushButton>(w.renderPanel(), "renderBookmarkDelete")->click();  // the third
        ASSERT_EQ(w.renderPanel()->bookmarks().size(), 2);
        ASSERT_TRUE(w.close());
    }
    {
        MainWindow w(/*restoreSettings=*/true);
        EXPECT_TRUE(w.renderPanel()->bookmarks().isEmpty()) << "the default scene has none";
        ASSERT_TRUE(w.openFile(project)) << w.lastError().toStdString();
        auto* list = child<QComboBox>(w.renderPanel(), "renderBookmarks");
        ASSERT_EQ(list->count(), 2);
        EXPECT_EQ(list->itemText(1), QStringLiteral("View 2"));
        for (int i = 0; i < 2; ++i) {
            list->setCurrentIndex(i);
            child<QPushButton>(w.renderPanel(), "renderBookmarkGo")->click();
            const OrbitCamera& want = i == 0 ? first : second;
            const OrbitCamera& c = w.viewport()->camera();
            // Written with 9 significant digits: float32 values come back exactly.
            EXPECT_EQ(c.target, want.target);
            EXPECT_EQ(c.distance, want.distance);
            EXPECT_EQ(c.yawDeg, want.yawDeg);
            EXPECT_EQ(c.pitchDeg, want.pitchDeg);
        }
        ASSERT_TRUE(w.close());
    }
    QSettings().clear();
    qunsetenv(MainWindow::RECOVERY_ENV);
    QStandardPaths::setTestModeEnabled(false);
}

TEST(MainWindowDrop, OnlyOpenableFilesAreAccepted) {
    MainWindow w(/*restoreSettings=*/false);
    const auto accepted = [&w](const QString& file) {
        QMimeData mime;
        mime.setUrls({QUrl::fromLocalFile(file)});
        QDragEnterEvent e(QPoint(10, 10), Qt::CopyAction, &mime, Qt::LeftButton, Qt::NoModifier);
        QApplication::sendEvent(&w, &e);
        return e.isAccepted();
    };
    EXPECT_TRUE(accepted(QStringLiteral("/tmp/project.json")));
    EXPECT_TRUE(accepted(QStringLiteral("/tmp/bunny.PLY")));
    EXPECT_TRUE(accepted(QStringLiteral("/tmp/m.vdb")));
    EXPECT_FALSE(accepted(QStringLiteral("/tmp/notes.txt")));
    EXPECT_FALSE(accepted(QStringLiteral("/tmp/picture.png")));
}

TEST(MainWindowMenus, ConventionalShortcuts) {
    MainWindow w(/*restoreSettings=*/false);
    const std::pair<const char*, QKeySequence> expected[] = {
        {"actionNew", QKeySequence::New},
        {"actionOpen", QKeySequence::Open},
        {"actionSave", QKeySequence(Qt::CTRL | Qt::Key_S)},
        {"actionSaveAs", QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_S)},
        {"actionUndo", QKeySequence(Qt::CTRL | Qt::Key_Z)},
        {"actionRedo", QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_Z)},
        {"actionExportRender", QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_E)},
        {"actionQuit", QKeySequence::Quit},
        {"actionBrushLarger", QKeySequence(Qt::Key_BracketRight)},
        {"actionBrushSmaller", QKeySequence(Qt::Key_BracketLeft)},
        {"actionEyedropper", QKeySequence(Qt::Key_I)},
        {"actionBrushPaint", QKeySequence(Qt::Key_B)}};
    for (const auto& [name, keys] : expected) {
        QAction* a = findAction(w, name);
        ASSERT_NE(a, nullptr) << name;
        EXPECT_EQ(a->shortcut(), keys) << name;
    }
}

TEST(BrushPanelTest, ShortcutsResizeAndSwitchTools) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    auto* radius = child<QDoubleSpinBox>(w->brushPanel(), "brushRadius");
    radius->setValue(4.0);
    // The keys themselves, pressed in the active window, go through the Brush menu.
    w->activateWindow();
    ASSERT_TRUE(QTest::qWaitForWindowActive(w.get(), test::kWindowWaitMs));
    vp->setFocus();
    QTest::keyClick(vp, Qt::Key_BracketRight);
    EXPECT_NEAR(vp->brush().engine.radius, 5.f, 1e-6f);
    QTest::keyClick(vp, Qt::Key_BracketLeft);
    QTest::keyClick(vp, Qt::Key_BracketLeft);
    EXPECT_NEAR(vp->brush().engine.radius, 3.2f, 1e-2f);  // 4/1.25, shown with 2 decimals
    QTest::keyClick(vp, Qt::Key_I);
    EXPECT_EQ(vp->tool(), Viewport::Tool::Eyedropper);
    QTest::keyClick(vp, Qt::Key_B);
    EXPECT_EQ(vp->tool(), Viewport::Tool::Paint);
}

TEST(BrushPanelTest, RadiusOnScreenFollowsTheCamera) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    BrushPanel* brush = w->brushPanel();
    auto* mm = child<QDoubleSpinBox>(brush, "brushRadius");
    auto* px = child<QSpinBox>(brush, "brushRadiusPx");
    const OrbitCamera& c = vp->camera();
    // Perspective: pixels per mm = H / (2·D·tan(fovY/2)) at the orbit distance D.
    const double perMm = vp->height() / (2.0 * c.distance * std::tan(glm::radians(c.fovYDeg) / 2));
    ASSERT_NEAR(brush->pixelsPerMm(), perMm, 1e-6 * perMm);  // float camera fields
    mm->setValue(3.0);
    EXPECT_EQ(px->value(), int(std::lround(3.0 * perMm)));
    // Typing a size on screen sets the radius in mm (rounded to the field's 0.01 mm).
    px->setValue(40);
    EXPECT_NEAR(mm->value(), 40.0 / perMm, 0.005);
    EXPECT_NEAR(vp->brush().engine.radius, 40.0 / perMm, 0.005);
    // Zooming in (half the distance) doubles the on-screen size of the same radius.
    const double radiusMm = mm->value();
    vp->camera().distance *= 0.5f;
    vp->update();
    EXPECT_TRUE(QTest::qWaitFor(
        [&] { return std::abs(px->value() - radiusMm * 2.0 * perMm) <= 1.0; }, 10000))
        << px->value();
    EXPECT_DOUBLE_EQ(mm->value(), radiusMm) << "zooming keeps the radius in mm";
}

// Issue 17, item 9: the slice's colour map stretched a 0.9999 … 1 range over the whole map,
// showing rounding noise as strong structure. Below 1 % of the magnitude it is one colour;
// real paint still spans the map.
TEST(SliceViewTest, NearlyUniformSliceIsOneColour) {
    const GridSpec spec = GridSpec::around(Bounds3f{Point3f(0.f), Point3f(16.f)}, 16);
    MaterialVolume v(spec, {Rgb(1.f), Rgb(0.5f), Rgb(0.f)});
    v.setInsideMask(std::vector<uint8_t>(spec.voxelCount(), 1));
    v.set({3, 4, 8}, {Rgb(0.9999f), Rgb(0.5f), Rgb(0.f)});
    SliceImage s = renderSlice(v, 2, /*component=*/0, 8);
    EXPECT_FLOAT_EQ(s.minValue, 0.9999f);
    EXPECT_FLOAT_EQ(s.maxValue, 1.f);
    EXPECT_TRUE(s.nearlyUniform);
    EXPECT_GE(s.mapMax - s.mapMin, 0.01f * 0.999f);
    // A z slice: voxel x to the right, y up (row 0 at the top).
    const auto pixel = [&](int x, int y) { return QColor(s.image.pixel(x, 15 - y)); };
    const QColor painted = pixel(3, 4), other = pixel(5, 5);
    const int diff = std::abs(painted.red() - other.red()) +
                     std::abs(painted.green() - other.green()) +
                     std::abs(painted.blue() - other.blue());
    EXPECT_LE(diff, 6) << "rounding noise shown as colour";  // ~1 % of the map: ≤ 2 levels each
    // A real difference keeps the full map: the ends are viridis' ends.
    v.set({3, 4, 8}, {Rgb(2.f), Rgb(0.5f), Rgb(0.f)});
    s = renderSlice(v, 2, 0, 8);
    EXPECT_FALSE(s.nearlyUniform);
    EXPECT_EQ(pixel(3, 4), QColor(viridis(1.f)));
    EXPECT_EQ(pixel(5, 5), QColor(viridis(0.f)));
}

// Issue 17, item 9: Help had only About. It now opens the user guide and a list of every
// shortcut (built from the menus, so it cannot drift from them).
TEST(MainWindowMenus, HelpShowsTheUserGuideAndTheShortcuts) {
    MainWindow w(/*restoreSettings=*/false);
    QAction* guide = findAction(w, "actionUserGuide");
    QAction* keys = findAction(w, "actionShortcuts");
    ASSERT_TRUE(guide && keys);
    EXPECT_EQ(guide->shortcut(), QKeySequence(QKeySequence::HelpContents));
    guide->trigger();
    auto* guideWindow = w.findChild<QTextBrowser*>(QStringLiteral("userGuide"));
    ASSERT_NE(guideWindow, nullptr);
    EXPECT_TRUE(guideWindow->isVisible());
    const QString text = guideWindow->toPlainText();
    EXPECT_TRUE(text.contains(QStringLiteral("User guide"))) << text.left(200).toStdString();
    EXPECT_TRUE(text.contains(QStringLiteral("Undo and redo")));
    keys->trigger();
    auto* keysWindow = w.findChild<QTextBrowser*>(QStringLiteral("shortcuts"));
    ASSERT_NE(keysWindow, nullptr);
    const QString list = keysWindow->toPlainText();
    // Every menu action with a shortcut is listed with its keys.
    for (QAction* a : w.findChildren<QAction*>()) {
        if (a->shortcut().isEmpty() || a->text().isEmpty())
            continue;
        EXPECT_TRUE(list.contains(a->shortcut().toString(QKeySequence::NativeText)))
            << a->text().toStdString();
    }
    EXPECT_TRUE(list.contains(QStringLiteral("Orbit")));
    guideWindow->close();
    keysWindow->close();
}

// Issue 17, item 7: σs′ > σt was accepted by the fields, then every stroke was refused with
// only a status-bar message in the engine's names (brush.value.sigma_s[0]). The σs′ fields now
// stop at σt while typing, and a brush that still cannot paint says why in plain words.
TEST(BrushPanelTest, ScatteringCannotExceedExtinctionAndProblemsAreInWords) {
    auto w = shownWindow();
    Viewport* vp = w->viewport();
    BrushPanel* brush = w->brushPanel();
    auto* sigmaT = child<QDoubleSpinBox>(brush, "brushSigmaT0");
    auto* sigmaS = child<QDoubleSpinBox>(brush, "brushSigmaS0");
    auto* mode = child<QComboBox>(brush, "brushMode");
    auto* problem = child<QLabel>(brush, "brushProblem");
    ASSERT_EQ(mode->currentIndex(), int(BrushMode::Set));
    sigmaT->setValue(2.0);
    // Typing 5 into σs′ (red): the field does not take more than σt.
    sigmaS->selectAll();
    QTest::keyClicks(sigmaS, QStringLiteral("5"));
    QTest::keyClick(sigmaS, Qt::Key_Return);
    EXPECT_LE(sigmaS->value(), 2.0);
    EXPECT_LE(vp->brush().engine.value.sigma_s.r, vp->brush().engine.value.sigma_t.r);
    // Lowering σt lowers σs′ with it.
    sigmaS->setValue(1.5);
    sigmaT->setValue(1.0);
    EXPECT_DOUBLE_EQ(sigmaS->value(), 1.0);
    EXPECT_TRUE(problem->isHidden());
    EXPECT_TRUE(brushProblem(vp->brush().engine).isEmpty());
    // In Add mode σs′ is an amount: larger than σt is fine.
    mode->setCurrentIndex(int(BrushMode::Add));
    sigmaS->setValue(3.0);
    EXPECT_DOUBLE_EQ(sigmaS->value(), 3.0);
    EXPECT_TRUE(problem->isHidden()) << problem->text().toStdString();
    // Back in Set mode the fields hold the limit again.
    mode->setCurrentIndex(int(BrushMode::Set));
    EXPECT_LE(sigmaS->value(), sigmaT->value());
    // A brush set past the fields (a script) is refused with a sentence an artist can act on.
    AppBrush& b = vp->brush();
    b.engine.mode = BrushMode::Set;
    b.engine.channels = ALL_CHANNELS;
    b.engine.value.sigma_t = Rgb(1.f);
    b.engine.value.sigma_s = Rgb(1.f, 2.f, 0.5f);
    QSignalSpy refused(vp, &Viewport::paintError);
    const QPointF c(vp->width() / 2.0, vp->height() / 2.0);
    EXPECT_EQ(vp->strokeBetween(c - QPointF(20, 0), c + QPointF(20, 0)), 0);
    ASSERT_GE(refused.count(), 1);
    const QString message = refused[0][0].toString();
    EXPECT_TRUE(message.contains(QStringLiteral("scattering σs′ (green)")))
        << message.toStdString();
    EXPECT_TRUE(message.contains(QStringLiteral("Lower σs′ or raise σt"))) << message.toStdString();
    EXPECT_FALSE(message.contains(QStringLiteral("brush.value"))) << message.toStdString();
    EXPECT_TRUE(QTest::qWaitFor(
        [&] { return w->statusBar()->currentMessage().contains(QStringLiteral("scattering σs′")); },
        2000))
        << w->statusBar()->currentMessage().toStdString();
    // No channel: said in words too.
    b.engine.channels = 0;
    EXPECT_TRUE(brushProblem(b.engine).contains(QStringLiteral("at least one channel")));
}

// ---- Live costs: Edit ▸ Preferences ▸ Calibrate Live Costs -----------------------------------

namespace {

/// A fresh config folder as XDG_CONFIG_HOME (LUCENT_LIVE_COSTS unset) and Qt's test locations for
/// the window's own settings; on leaving, the environment and the shipped live costs again.
class AppLiveCosts : public ::testing::Test {
protected:
    void SetUp() override {
        m_config = std::filesystem::temp_directory_path() / "lucent_app_live_costs_config";
        std::filesystem::remove_all(m_config);
        std::filesystem::create_directories(m_config);
        m_hadXdg = qEnvironmentVariableIsSet("XDG_CONFIG_HOME");
        m_oldXdg = qgetenv("XDG_CONFIG_HOME");
        m_hadGiven = qEnvironmentVariableIsSet(planner::LIVE_COSTS_ENV);
        m_oldGiven = qgetenv(planner::LIVE_COSTS_ENV);
        qputenv("XDG_CONFIG_HOME", QByteArray::fromStdString(m_config.string()));
        qunsetenv(planner::LIVE_COSTS_ENV);
        QStandardPaths::setTestModeEnabled(true);  // the window's QSettings go to ~/.qttest
        qputenv(MainWindow::RECOVERY_ENV, "discard");
    }
    void TearDown() override {
        if (m_hadXdg)
            qputenv("XDG_CONFIG_HOME", m_oldXdg);
        else
            qunsetenv("XDG_CONFIG_HOME");
        if (m_hadGiven)
            qputenv(planner::LIVE_COSTS_ENV, m_oldGiven);
        QStandardPaths::setTestModeEnabled(false);
        PreviewRenderer::useLiveCosts(planner::loadLiveCosts(""));  // the shipped table
        std::filesystem::remove_all(m_config);
    }
    /// The user's calibration file under the test's config folder.
    [[nodiscard]] std::string calibrationPath() const {
        return (m_config / "lucent" / "live_costs.json").string();
    }
    /// The shipped table with every ratio tripled, "measured" on a GPU on 2026-12-03.
    static planner::LiveCosts tripledShipped() {
        planner::LiveCosts c = planner::defaultLiveCosts();
        c.source = "test";
        c.date = "2026-12-03";
        c.renderer = "Test GPU (fake)";
        for (planner::LiveCost& e : c.entries)
            e.strokeRatio *= 3.0;
        return c;
    }

private:
    std::filesystem::path m_config;
    QByteArray m_oldXdg, m_oldGiven;
    bool m_hadXdg = false, m_hadGiven = false;
};

/// Renders frames (at least one, at most 10) until Auto's plan says it used the live costs
/// `expected`, with its Direct frame pinned so that it plans at once; returns what the last
/// frame's plan said.
std::string plannedLiveCosts(MainWindow& w, const std::string& expected) {
    Viewport* vp = w.viewport();
    vp->previewRenderer().pinAutoDirectMs(PreviewRenderer::liveCostTable().inUse.costs.directMs);
    for (int i = 0; i < 10; ++i) {
        const long long f = vp->stats().frames;
        vp->update();
        if (!QTest::qWaitFor([&] { return vp->stats().frames > f; }, test::kWindowWaitMs))
            break;
        if (vp->stats().preview.liveCosts == expected)
            break;
    }
    return vp->stats().preview.liveCosts;
}

}  // namespace

TEST_F(AppLiveCosts, ACalibrationInTheConfigFolderIsPlannedWithAndABadOneIsNot) {
    ASSERT_EQ(planner::userLiveCostsPath(), calibrationPath());
    planner::saveLiveCosts(tripledShipped(), calibrationPath());
    {
        MainWindow w(/*restoreSettings=*/true);
        w.show();
        ASSERT_TRUE(QTest::qWaitForWindowExposed(&w, test::kWindowWaitMs));
        EXPECT_TRUE(w.liveCostsWarning().isEmpty()) << w.liveCostsWarning().toStdString();
        const LiveCostTable& t = PreviewRenderer::liveCostTable();
        EXPECT_TRUE(t.inUse.calibrated);
        EXPECT_EQ(t.label, "calibrated on this machine 2026-12-03 (Test GPU)");
        ASSERT_FALSE(t.models.candidates.empty());
        EXPECT_NEAR(std::exp(t.models.candidates[0].cost[0]),
                    3.0 * planner::defaultLiveCosts().entries[0].strokeRatio, 1e-3);
        // The plan says which costs it used (the Statistics dock shows it).
        EXPECT_EQ(plannedLiveCosts(w, t.label), t.label);
        ASSERT_TRUE(w.close());
    }
    {
        // Cut short: the shipped costs, and the user is told why, naming the file.
        std::ofstream(calibrationPath(), std::ios::trunc) << "{\"format\": \"lucent-planner-li";
        MainWindow w(/*restoreSettings=*/true);
        w.show();
        ASSERT_TRUE(QTest::qWaitForWindowExposed(&w, test::kWindowWaitMs));
        const QString warning = w.liveCostsWarning();
        EXPECT_TRUE(warning.contains(QString::fromStdString(calibrationPath())))
            << warning.toStdString();
        EXPECT_TRUE(warning.contains(QStringLiteral("shipped"))) << warning.toStdString();
        EXPECT_TRUE(w.statusBar()->currentMessage().contains(warning))
            << w.statusBar()->currentMessage().toStdString();
        EXPECT_FALSE(PreviewRenderer::liveCostTable().inUse.calibrated);
        EXPECT_EQ(plannedLiveCosts(w, PreviewRenderer::liveCostTable().label),
                  PreviewRenderer::liveCostTable().label);
        EXPECT_EQ(PreviewRenderer::liveCostTable().label.rfind("shipped", 0), 0u);
        ASSERT_TRUE(w.close());
    }
}

TEST_F(AppLiveCosts, CalibratingWritesTheFileCancelStopsAndShippedDeletesIt) {
    MainWindow w(/*restoreSettings=*/false);
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w, test::kWindowWaitMs));
    ASSERT_NE(findAction(w, "actionCalibrateLiveCosts"), nullptr);
    ASSERT_NE(findAction(w, "actionUseShippedLiveCosts"), nullptr);
    // Every shipped candidate (a file must cover them to be used), on a small viewport.
    planner::LiveCalibrationOptions o;
    o.viewportWidth = 96;
    o.viewportHeight = 64;
    o.strokes = 1;
    o.warmupStrokes = 0;
    o.idleFrames = 0;
    o.rounds = 1;

    // Cancelled from its progress dialog: no file, the costs in use unchanged.
    ASSERT_TRUE(w.calibrateLiveCosts(o, /*wait=*/false));
    EXPECT_TRUE(w.isCalibrating());
    EXPECT_FALSE(w.calibrateLiveCosts(o, false));  // one at a time
    auto* dialog = w.findChild<QProgressDialog*>(QStringLiteral("calibrationProgress"));
    ASSERT_NE(dialog, nullptr);
    auto* cancelButton = dialog->findChild<QPushButton*>();  // its only button
    ASSERT_NE(cancelButton, nullptr);
    cancelButton->click();
    ASSERT_TRUE(QTest::qWaitFor([&] { return !w.isCalibrating(); }, 60000));
    EXPECT_FALSE(std::filesystem::exists(calibrationPath()));
    EXPECT_FALSE(PreviewRenderer::liveCostTable().inUse.calibrated);
    EXPECT_TRUE(w.statusBar()->currentMessage().contains(QStringLiteral("cancelled")))
        << w.statusBar()->currentMessage().toStdString();

    // To the end: the file is written, parses, and Auto plans with it.
    ASSERT_TRUE(w.calibrateLiveCosts(o, /*wait=*/true)) << w.lastError().toStdString();
    ASSERT_TRUE(std::filesystem::exists(calibrationPath()));
    const planner::LiveCostsInUse onDisk = planner::loadLiveCosts(calibrationPath());
    EXPECT_TRUE(onDisk.calibrated) << onDisk.warning;
    const LiveCostTable& t = PreviewRenderer::liveCostTable();
    EXPECT_TRUE(t.inUse.calibrated);
    EXPECT_EQ(t.inUse.costs.source, onDisk.costs.source);
    EXPECT_NE(t.inUse.costs.source.find("96x64"), std::string::npos) << t.inUse.costs.source;
    EXPECT_EQ(t.label.rfind("calibrated on this machine", 0), 0u) << t.label;
    EXPECT_EQ(plannedLiveCosts(w, t.label), t.label);

    // Use Shipped Live Costs: the file goes, the shipped table comes back.
    findAction(w, "actionUseShippedLiveCosts")->trigger();
    EXPECT_FALSE(std::filesystem::exists(calibrationPath()));
    EXPECT_FALSE(PreviewRenderer::liveCostTable().inUse.calibrated);
    EXPECT_EQ(PreviewRenderer::liveCostTable().label.rfind("shipped", 0), 0u);
    ASSERT_TRUE(w.close());
}

}  // namespace lucent::app

int main(int argc, char** argv) {
    return lucent::app::test::runGuiTests(argc, argv);
}
