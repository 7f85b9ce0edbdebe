// SPDX-License-Identifier: MIT
/// @file
/// @brief Main window: menus, docks, file operations, autosave.

#include "MainWindow.h"

#include "Document.h"
#include "Panels.h"
#include "SliceView.h"
#include "Viewport.h"

#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/scene/SceneEdit.h>
#include <lucent/scene/SceneFile.h>
#include <lucent/io/MitsubaIO.h>
#include <lucent/io/VdbIO.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/planner/LiveCalibration.h>
#include <lucent/planner/LiveCosts.h>
#include "ReferencePanel.h"

#include <QAction>
#include <QApplication>
#include <QCloseEvent>
#include <QCheckBox>
#include <QDialog>
#include <QDialogButtonBox>
#include <QDir>
#include <QDockWidget>
#include <QElapsedTimer>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QInputDialog>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QListWidget>
#include <QLabel>
#include <QLineEdit>
#include <QMenuBar>
#include <QMessageBox>
#include <QMimeData>
#include <QPointer>
#include <QProgressDialog>
#include <QRadioButton>
#include <QScreen>
#include <QScrollArea>
#include <QScrollBar>
#include <QSettings>
#include <QStandardPaths>
#include <QStatusBar>
#include <QTextBrowser>
#include <QSurfaceFormat>
#include <QThread>
#include <QUndoStack>
#include <QUrl>

#include <algorithm>
#include <iterator>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

/// The docs resource lives in the static library lucent_gui: registered explicitly, since the
/// linker may drop its otherwise unreferenced initialiser. Q_INIT_RESOURCE must be called
/// outside a namespace.
static void initDocsResource() {
    Q_INIT_RESOURCE(lucent_docs);
}

namespace lucent::app {

namespace {
constexpr int MAX_RECENT = 8;
/// Version of the Render settings defaults saved with the preferences (2: Dipole by default;
/// 3: the method saved by registry name; 4: Auto by default).
constexpr int RENDER_DEFAULTS_VERSION = 4;
/// Registry names of the selector's entries before version 3 of the preferences, by index: what
/// a saved index meant then (a migration table, not a list of methods to offer).
constexpr const char* PRE_REGISTRY_METHOD_ORDER[] = {
    "direct", "single-scattering", "sslpv", "dipole", "better-dipole", "dirpole", "combined"};
constexpr int AUTOSAVE_INTERVAL_MS = 120 * 1000;
/// Factor of one [ / ] step on the brush radius (eight steps ≈ ×6).
constexpr double BRUSH_STEP = 1.25;
const QStringList MESH_SUFFIXES = {"obj", "ply", "off", "stl", "vtp", "vtk"};
}  // namespace

namespace {
/// Adds OK and Cancel under `form` and runs `dialog`. @return true when accepted.
bool execWithOkCancel(QDialog& dialog, QFormLayout* form) {
    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel);
    form->addRow(buttons);
    QObject::connect(buttons, &QDialogButtonBox::accepted, &dialog, &QDialog::accept);
    QObject::connect(buttons, &QDialogButtonBox::rejected, &dialog, &QDialog::reject);
    return dialog.exec() == QDialog::Accepted;
}
}  // namespace

void MainWindow::useGlSurfaceFormat() {
    QSurfaceFormat fmt;
    fmt.setVersion(4, 5);
    fmt.setProfile(QSurfaceFormat::CoreProfile);
    fmt.setDepthBufferSize(24);
    QSurfaceFormat::setDefaultFormat(fmt);
}

bool MainWindow::applyMeshEdit(MeshEditKind kind) {
    return applyMeshEdit(kind, MeshEditParams{});
}

bool MainWindow::applyMeshEdit(MeshEditKind kind, const MeshEditParams& params) {
    try {
        if (!m_doc->hasObject())
            LUCENT_THROW(ValueError, "the scene has no mesh to edit");
        Scene scene = m_doc->scene();
        editObjectMesh(scene.objects[0], kind, params);      // the engine's edit + re-voxelise
        scene.camera.position = m_viewport->camera().eye();  // keep the current view
        scene.camera.target = m_viewport->camera().target;
        m_doc->setScene(std::move(scene), m_doc->filePath());
        m_doc->noteSceneEdited();
        statusBar()->showMessage(
            tr("Mesh edited: %1 triangles").arg(m_doc->mesh()->triangleCount()), 5000);
        return true;
    } catch (const std::exception& ex) {
        reportError(tr("Mesh edit"), ex);
        return false;
    }
}

QString MainWindow::autosavePath() {
    return QStandardPaths::writableLocation(QStandardPaths::AppLocalDataLocation) +
           QStringLiteral("/autosave/autosave.json");
}

MainWindow::MainWindow(bool restoreSettings, QWidget* parent)
    : QMainWindow(parent), m_doc(new Document(this)), m_useSettings(restoreSettings) {
    initDocsResource();
    setObjectName(QStringLiteral("LucentMainWindow"));
    setAcceptDrops(true);
    m_doc->newDefault();
    m_viewport = new Viewport(m_doc, this);
    setCentralWidget(m_viewport);
    createDocks();
    createActions();
    m_hoverLabel = new QLabel;
    statusBar()->addPermanentWidget(m_hoverLabel);
    connect(m_viewport, &Viewport::hoverVoxel, m_hoverLabel, &QLabel::setText);
    // Auto: why the planner chose the method it runs (until another message replaces it).
    connect(m_viewport, &Viewport::autoPlanChanged, this, [this](const QString& reason) {
        statusBar()->showMessage(tr("Auto: %1").arg(reason));
        m_render->setAutoPlan(reason);
    });
    connect(m_viewport, &Viewport::paintError, this, [this](const QString& m) {
        statusBar()->showMessage(tr("Cannot paint: %1").arg(m), 10000);
    });
    // A preview method that fails falls back to Direct in the viewport; the dock follows and
    // the user is told why (queued: the viewport emits it from inside its frame).
    connect(
        m_viewport, &Viewport::renderFailed, this,
        [this](const QString& message, const QString& method) {
            const QString fallback = QString::fromLatin1(Viewport::FALLBACK_METHOD);
            m_render->setMethod(fallback);
            const QString text = tr("The %1 preview failed and the viewport switched to %2: %3")
                                     .arg(RenderPanel::methodTitle(method),
                                          RenderPanel::methodTitle(fallback), message);
            m_lastError = text;
            statusBar()->showMessage(text, 15000);
            if (!m_useSettings)
                std::fprintf(stderr, "lucent: %s\n", qPrintable(text));
        },
        Qt::QueuedConnection);
    connect(m_doc, &Document::modifiedChanged, this, [this] { updateTitle(); });
    connect(m_doc, &Document::sceneReplaced, this, [this] {
        updateTitle();
        loadBookmarks();
    });
    connect(m_render, &RenderPanel::bookmarksChanged, this, &MainWindow::storeBookmarks);
    updateTitle();
    // 1400×900, or what the screen has room for (a 1366×768 laptop).
    QSize size(1400, 900);
    if (const QScreen* sc = screen())
        size = size.boundedTo(sc->availableGeometry().size());
    resize(size);
    if (m_useSettings) {
        QSettings s;
        restoreGeometry(s.value("window/geometry").toByteArray());
        m_layoutRestored = restoreState(s.value("window/state").toByteArray());
        m_recent = s.value("recentFiles").toStringList();
        m_vdbChoice.rendererGrids = s.value("export/rendererGrids", true).toBool();
        m_vdbChoice.mitsubaVol = s.value("export/mitsubaVol", false).toBool();
        // Preferences: the brush, the render settings and the light handles as last left.
        restorePanelSettings(m_brush, s, QStringLiteral("brush"));
        // Before version 2 of the defaults every closed session saved the then-default method
        // (SSLPV, which hid paint), chosen or not: that saved choice is not kept.
        const int defaultsVersion = s.value(QStringLiteral("render/defaultsVersion"), 1).toInt();
        if (defaultsVersion < 2) {
            s.remove(QStringLiteral("render/renderMethod"));
        } else if (defaultsVersion < 3) {
            // Before version 3 the method was saved as its index in the selector, whose order
            // was the app's own method enum; it is saved by registry name since.
            bool isIndex = false;
            const int index = s.value(QStringLiteral("render/renderMethod")).toInt(&isIndex);
            if (isIndex && index >= 0 && index < int(std::size(PRE_REGISTRY_METHOD_ORDER)))
                s.setValue(QStringLiteral("render/renderMethod"),
                           QString::fromLatin1(PRE_REGISTRY_METHOD_ORDER[index]));
        }
        // Before version 4 every closed session saved the then-default Dipole, chosen or not:
        // that is not taken as a choice over the new default, Auto. Other methods were chosen.
        if (defaultsVersion >= 2 && defaultsVersion < 4 &&
            s.value(QStringLiteral("render/renderMethod")).toString() == QLatin1String("dipole"))
            s.remove(QStringLiteral("render/renderMethod"));
        restorePanelSettings(m_render, s, QStringLiteral("render"));
        if (auto* gizmos = findChild<QAction*>(QStringLiteral("actionLightGizmos")))
            gizmos->setChecked(s.value("view/lightGizmos", true).toBool());
        m_autosave.setInterval(AUTOSAVE_INTERVAL_MS);
        connect(&m_autosave, &QTimer::timeout, this, &MainWindow::autosaveNow);
        m_autosave.start();
        QTimer::singleShot(0, this, &MainWindow::offerRecovery);
    }
    rebuildRecentMenu();
    statusBar()->showMessage(
        tr("Default scene. LMB paints, Alt+LMB / MMB orbits, Shift+MMB / RMB "
           "pans, wheel zooms, F frames the object."));
    // This machine's live-cost calibration, if any (after the greeting: a warning about a bad
    // calibration file must stay visible).
    if (m_useSettings)
        loadLiveCosts();
}

bool MainWindow::setRenderMethod(const QString& method) {
    return m_render->setMethod(method);
}

bool MainWindow::setRenderParam(const QString& param, const QString& value) {
    return m_render->setParam(param, value);
}

MainWindow::~MainWindow() {
    // The document outlives this destructor's body (QObject deletes it with the other
    // children): nothing it emits from now on may reach the half-destroyed window.
    disconnect(m_doc, nullptr, this, nullptr);
    // A calibration still measuring: stop it and wait (its thread must not outlive the window;
    // its finished handler, connected to this window, will not run any more).
    if (m_calibrationThread) {
        m_calibrationCancel->store(true);
        m_calibrationThread->wait();
        delete m_calibrationThread;
    }
}

QString MainWindow::readableMessage(const std::string& text) {
    // Error messages may quote a file's bytes (a binary file read as text): invalid UTF-8 and
    // control characters become "<binary data>" once per run, and very long messages are cut.
    constexpr int MAX_CHARS = 600;
    const QString raw = QString::fromUtf8(text.data(), qsizetype(text.size()));
    QString out;
    bool inBinary = false;
    for (const QChar ch : raw) {
        const bool binary = ch == QChar::ReplacementCharacter ||
                            (ch.category() == QChar::Other_Control && ch != QLatin1Char('\n') &&
                             ch != QLatin1Char('\t')) ||
                            ch.category() == QChar::Other_PrivateUse || ch.isNull();
        if (binary && !inBinary)
            out += tr("<binary data>");
        inBinary = binary;
        if (!binary)
            out += ch;
        if (out.size() > MAX_CHARS) {
            out.truncate(MAX_CHARS);
            out += QStringLiteral("…");
            break;
        }
    }
    return out;
}

void MainWindow::reportError(const QString& what, const std::exception& ex) {
    const QString message = readableMessage(ex.what());
    m_lastError = QStringLiteral("%1: %2").arg(what, message);
    statusBar()->showMessage(tr("%1 failed").arg(what), 5000);
    if (m_useSettings)
        QMessageBox::warning(this, what, message);
    else  // scripted / test runs never block on a dialog
        std::fprintf(stderr, "lucent: %s\n", qPrintable(m_lastError));
}

void MainWindow::createDocks() {
    // Every dock scrolls its panel instead of imposing the panel's full height on the window:
    // the window then fits a 1366×768 screen (the docks' minimum sizes add up; the Tools and
    // Render settings forms alone are taller than such a screen).
    auto addDock = [this](const QString& title, const char* name, QWidget* w,
                          Qt::DockWidgetArea area) {
        auto* scroll = new QScrollArea;
        scroll->setObjectName(QString::fromLatin1(name) + QStringLiteral("Scroll"));
        scroll->setWidget(w);
        scroll->setWidgetResizable(true);
        scroll->setFrameShape(QFrame::NoFrame);
        scroll->setHorizontalScrollBarPolicy(Qt::ScrollBarAsNeeded);
        auto* dock = new QDockWidget(title, this);
        dock->setObjectName(QString::fromLatin1(name));
        dock->setWidget(scroll);
        addDockWidget(area, dock);
        return dock;
    };
    m_brush = new BrushPanel(m_doc, m_viewport);
    auto* tools = addDock(tr("Tools"), "dockTools", m_brush, Qt::LeftDockWidgetArea);
    auto* presets = addDock(tr("Presets"), "dockPresets", new PresetPanel(m_doc, m_brush),
                            Qt::LeftDockWidgetArea);
    m_slice = new SliceView(m_doc);
    auto* channels =
        addDock(tr("Material channels"), "dockChannels", m_slice, Qt::RightDockWidgetArea);
    m_render = new RenderPanel(m_doc, m_viewport);
    auto* render = addDock(tr("Render settings"), "dockRender", m_render, Qt::RightDockWidgetArea);
    m_lights = new LightPanel(m_doc);
    auto* lights = addDock(tr("Lights"), "dockLights", m_lights, Qt::RightDockWidgetArea);
    // The dock's list and the viewport's gizmo selection are one selection.
    connect(m_lights, &LightPanel::currentLightChanged, m_viewport, &Viewport::setSelectedLight);
    connect(m_viewport, &Viewport::lightSelected, this, [this, lights](int i) {
        m_lights->setCurrentLight(i);
        lights->raise();
    });
    m_viewport->setSelectedLight(m_lights->currentLight());
    m_stats = new StatsPanel(m_doc, m_viewport);
    auto* stats = addDock(tr("Statistics"), "dockStats", m_stats, Qt::RightDockWidgetArea);
    tabifyDockWidget(tools, presets);
    tools->raise();
    // One tab group under the slice: Render settings, Lights, Statistics, Reference.
    tabifyDockWidget(render, lights);
    tabifyDockWidget(lights, stats);
    m_reference = new ReferencePanel(m_doc, m_viewport);
    auto* reference =
        addDock(tr("Reference"), "dockReference", m_reference, Qt::RightDockWidgetArea);
    tabifyDockWidget(stats, reference);
    render->raise();
    // Default proportions (a saved layout, restored later, overrides them); applied once the
    // window is laid out, since QMainWindow ignores resizeDocks before that.
    QTimer::singleShot(0, this, [this, tools, presets, channels, render, lights, stats] {
        if (!m_layoutRestored) {
            // Wide enough for each panel's fields (no horizontal scrolling), within 30 % of
            // the window per side so the viewport keeps the middle.
            const auto fit = [this](std::initializer_list<QDockWidget*> docks, int least) {
                int w = least;
                for (QDockWidget* d : docks)
                    if (auto* area = qobject_cast<QScrollArea*>(d->widget()))
                        w = std::max(w, area->widget()->minimumSizeHint().width() +
                                            area->verticalScrollBar()->sizeHint().width() +
                                            2 * area->frameWidth() + 4);
                return std::min(w, width() * 3 / 10);
            };
            resizeDocks({tools, channels},
                        {fit({tools, presets}, 300), fit({channels, render, lights, stats}, 340)},
                        Qt::Horizontal);
            // The slice gets 40 % of the height, the tab group the rest.
            resizeDocks({channels, render}, {height() * 2 / 5, height() * 3 / 5}, Qt::Vertical);
        }
    });
}

void MainWindow::createActions() {
    QMenu* file = menuBar()->addMenu(tr("&File"));
    QAction* a = file->addAction(tr("&New"), this, [this] {
        if (maybeSave())
            m_doc->newDefault();
    });
    a->setShortcut(QKeySequence::New);
    a->setObjectName(QStringLiteral("actionNew"));
    a = file->addAction(tr("&Open…"), this, [this] {
        if (!maybeSave())
            return;
        const QString p = QFileDialog::getOpenFileName(
            this, tr("Open project"), QString(),
            tr("Everything Lucent opens (*.json *.obj *.ply *.off *.stl *.vtp *.vtk *.vdb);;"
               "Lucent projects (*.json);;Meshes (*.obj *.ply *.off *.stl *.vtp *.vtk);;"
               "OpenVDB materials (*.vdb);;All files (*)"));
        if (!p.isEmpty())
            openFile(p);
    });
    a->setShortcut(QKeySequence::Open);
    a->setObjectName(QStringLiteral("actionOpen"));
    m_recentMenu = file->addMenu(tr("Open &Recent"));
    m_recentMenu->setObjectName(QStringLiteral("menuRecent"));
    // Rebuilt when shown, so files deleted meanwhile show as missing.
    connect(m_recentMenu, &QMenu::aboutToShow, this, &MainWindow::rebuildRecentMenu);
    a = file->addAction(tr("&Save"), this, [this] {
        if (m_doc->filePath().isEmpty()) {
            const QString p = QFileDialog::getSaveFileName(this, tr("Save project"),
                                                           QStringLiteral("untitled.json"),
                                                           tr("Lucent projects (*.json)"));
            if (!p.isEmpty())
                saveTo(p);
        } else {
            saveTo(m_doc->filePath());
        }
    });
    a->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_S));
    a->setObjectName(QStringLiteral("actionSave"));
    a = file->addAction(tr("Save &As…"), this, [this] {
        const QString p = QFileDialog::getSaveFileName(
            this, tr("Save project as"), m_doc->filePath(), tr("Lucent projects (*.json)"));
        if (!p.isEmpty())
            saveTo(p);
    });
    a->setShortcut(QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_S));
    a->setObjectName(QStringLiteral("actionSaveAs"));
    file->addSeparator();
    a = file->addAction(tr("&Import Mesh…"), this, [this] {
        const QString p = QFileDialog::getOpenFileName(
            this, tr("Import mesh"), QString(), tr("Meshes (*.obj *.ply *.off *.stl *.vtp *.vtk)"));
        if (!p.isEmpty() && maybeSave())
            importMesh(p, /*mmPerUnit=*/0.0);
    });
    a->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_I));
    a->setObjectName(QStringLiteral("actionImportMesh"));
    file->addAction(tr("Import &VDB Material…"), this, [this] {
        const QString p =
            QFileDialog::getOpenFileName(this, tr("Import VDB"), QString(), tr("OpenVDB (*.vdb)"));
        if (!p.isEmpty())
            importVdb(p);
    });
    a = file->addAction(tr("&Export VDB…"), this, [this] {
        const QString p = QFileDialog::getSaveFileName(
            this, tr("Export VDB"), QStringLiteral("material.vdb"), tr("OpenVDB (*.vdb)"));
        if (!p.isEmpty() && askVdbExportChoice())
            exportVdbTo(p);
    });
    a->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_E));
    a->setObjectName(QStringLiteral("actionExportVdb"));
    a = file->addAction(tr("Export &Render…"), this, [this] {
        const QString p =
            QFileDialog::getSaveFileName(this, tr("Export render"), QStringLiteral("render.png"),
                                         tr("PNG (*.png);;OpenEXR (*.exr)"));
        if (!p.isEmpty())
            exportRenderTo(p);
    });
    a->setShortcut(QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_E));
    a->setObjectName(QStringLiteral("actionExportRender"));
    file->addSeparator();
    a = file->addAction(tr("&Quit"), this, &QWidget::close);
    a->setShortcut(QKeySequence::Quit);
    a->setObjectName(QStringLiteral("actionQuit"));

    QMenu* meshMenu = menuBar()->addMenu(tr("&Mesh"));
    // Each edit asks for its parameter, starting from the value used last.
    meshMenu->addAction(tr("&Decimate…"), this, [this] {
        bool ok = false;
        const double percent =
            QInputDialog::getDouble(this, tr("Decimate"), tr("Triangles to keep (%):"),
                                    100.0 * m_meshEdit.decimateFraction, 1.0, 99.0, 0, &ok);
        if (!ok)
            return;
        m_meshEdit.decimateFraction = percent / 100.0;
        applyMeshEdit(MeshEditKind::Decimate, m_meshEdit);
    });
    // An iteration count, then the edit.
    const auto iterationsEdit = [this](const QString& title, const QString& label, int& value,
                                       int max, MeshEditKind kind) {
        bool ok = false;
        const int n = QInputDialog::getInt(this, title, label, value, 1, max, 1, &ok);
        if (!ok)
            return;
        value = n;
        applyMeshEdit(kind, m_meshEdit);
    };
    meshMenu->addAction(tr("&Subdivide (Loop)…"), this, [this, iterationsEdit] {
        iterationsEdit(tr("Subdivide"), tr("Iterations (×4 triangles each):"),
                       m_meshEdit.subdivideIterations, 5, MeshEditKind::Subdivide);
    });
    meshMenu->addAction(tr("S&mooth (Laplacian)…"), this, [this, iterationsEdit] {
        iterationsEdit(tr("Smooth"), tr("Iterations:"), m_meshEdit.smoothIterations, 1000,
                       MeshEditKind::Smooth);
    });
    meshMenu->addAction(tr("&Fill Holes…"), this, [this] {
        const TriangleMesh* mesh = m_doc->mesh();
        const double suggested = m_meshEdit.maxHoleMm > 0.0 ? m_meshEdit.maxHoleMm
                                 : mesh && !mesh->isEmpty()
                                     ? 0.1 * double(glm::length(mesh->bounds().extent()))
                                     : 1.0;
        bool ok = false;
        const double mm = QInputDialog::getDouble(this, tr("Fill holes"),
                                                  tr("Largest hole radius to close (mm):"),
                                                  suggested, 0.001, 1e6, 3, &ok);
        if (!ok)
            return;
        m_meshEdit.maxHoleMm = mm;
        applyMeshEdit(MeshEditKind::FillHoles, m_meshEdit);
    });
    QMenu* edit = menuBar()->addMenu(tr("&Edit"));
    // Not QUndoStack::createUndoAction: undo stops where the History's budget dropped strokes
    // (Document::canUndo).
    QAction* undo = edit->addAction(tr("&Undo"), m_doc, &Document::undo);
    const auto updateUndo = [this, undo] {
        undo->setEnabled(m_doc->canUndo());
        const QString step = m_doc->undoStack()->undoText();
        undo->setText(m_doc->canUndo() && !step.isEmpty() ? tr("&Undo %1").arg(step) : tr("&Undo"));
    };
    connect(m_doc, &Document::undoAvailabilityChanged, undo, updateUndo);
    updateUndo();
    undo->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_Z));
    undo->setObjectName(QStringLiteral("actionUndo"));
    QAction* redo = m_doc->undoStack()->createRedoAction(this, tr("&Redo"));
    redo->setShortcuts(
        {QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_Z), QKeySequence(Qt::CTRL | Qt::Key_Y)});
    redo->setObjectName(QStringLiteral("actionRedo"));
    edit->addAction(redo);
    edit->addSeparator();
    // Preferences of this machine rather than of a project.
    QMenu* preferences = edit->addMenu(tr("&Preferences"));
    preferences->setObjectName(QStringLiteral("menuPreferences"));
    a = preferences->addAction(tr("&Calibrate Live Costs…"), this,
                               [this] { calibrateLiveCosts(); });
    a->setObjectName(QStringLiteral("actionCalibrateLiveCosts"));
    a->setToolTip(
        tr("Measure what each preview method costs after a paint stroke on this "
           "machine (about a minute), so that Auto plans with it."));
    a = preferences->addAction(tr("Use &Shipped Live Costs"), this,
                               [this] { useShippedLiveCosts(); });
    a->setObjectName(QStringLiteral("actionUseShippedLiveCosts"));
    a->setToolTip(
        tr("Forget this machine's calibration: Auto plans with the costs shipped "
           "with Lucent."));
    a = preferences->addAction(tr("Auto: Check &Quality Levels"));
    a->setObjectName(QStringLiteral("actionAutoLevelCheck"));
    a->setCheckable(true);
    a->setChecked(!m_useSettings ||
                  QSettings().value(QStringLiteral("auto/levelCheck"), true).toBool());
    a->setToolTip(
        tr("In the background, render Auto's choice against its method's cheaper levels and "
           "take the cheapest that shows the same picture (docs/planner.md)."));
    m_viewport->levelChecker().setEnabled(a->isChecked());
    connect(a, &QAction::toggled, this, [this](bool on) {
        m_viewport->levelChecker().setEnabled(on);
        if (m_useSettings)
            QSettings().setValue(QStringLiteral("auto/levelCheck"), on);
    });
    a = preferences->addAction(tr("Auto: &Measure the Scene"));
    a->setObjectName(QStringLiteral("actionAutoMeasure"));
    a->setCheckable(true);
    // Off without settings: scripted runs (benchmarks, screenshots) and tests time and show
    // the models' plan without a path tracer running beside them.
    a->setChecked(m_useSettings &&
                  QSettings().value(QStringLiteral("auto/measure"), true).toBool());
    a->setToolTip(
        tr("Once you pause, render the exact image of the view at 64 pixels across in the "
           "background and each method that fits the frame budget against it, and let Auto "
           "choose by the measured errors instead of the predicted ones (docs/planner.md)."));
    m_viewport->autoMeasurer().setEnabled(a->isChecked());
    connect(a, &QAction::toggled, this, [this](bool on) {
        m_viewport->autoMeasurer().setEnabled(on);
        if (m_useSettings)
            QSettings().setValue(QStringLiteral("auto/measure"), on);
    });

    // Brush shortcuts as in painting tools: [ and ] resize, B paints, I picks.
    QMenu* brush = menuBar()->addMenu(tr("&Brush"));
    a = brush->addAction(tr("&Paint"), this, [this] { m_brush->setEyedropper(false); });
    a->setObjectName(QStringLiteral("actionBrushPaint"));
    a->setShortcut(QKeySequence(Qt::Key_B));
    a = brush->addAction(tr("&Eyedropper"), this, [this] { m_brush->setEyedropper(true); });
    a->setObjectName(QStringLiteral("actionEyedropper"));
    a->setShortcut(QKeySequence(Qt::Key_I));
    brush->addSeparator();
    a = brush->addAction(tr("&Larger"), this, [this] { m_brush->scaleRadius(BRUSH_STEP); });
    a->setObjectName(QStringLiteral("actionBrushLarger"));
    a->setShortcut(QKeySequence(Qt::Key_BracketRight));
    a = brush->addAction(tr("&Smaller"), this, [this] { m_brush->scaleRadius(1.0 / BRUSH_STEP); });
    a->setObjectName(QStringLiteral("actionBrushSmaller"));
    a->setShortcut(QKeySequence(Qt::Key_BracketLeft));

    m_viewMenu = menuBar()->addMenu(tr("&View"));
    a = m_viewMenu->addAction(tr("&Frame Object"), m_viewport, &Viewport::frameObject);
    a->setShortcut(QKeySequence(Qt::Key_F));
    a = m_viewMenu->addAction(tr("&Light Gizmos"));
    a->setObjectName(QStringLiteral("actionLightGizmos"));
    a->setCheckable(true);
    a->setChecked(m_viewport->lightGizmosVisible());
    a->setShortcut(QKeySequence(Qt::Key_G));
    connect(a, &QAction::toggled, m_viewport, &Viewport::setLightGizmosVisible);
    m_viewMenu->addSeparator();
    for (QDockWidget* d : findChildren<QDockWidget*>())
        m_viewMenu->addAction(d->toggleViewAction());

    QMenu* help = menuBar()->addMenu(tr("&Help"));
    a = help->addAction(tr("&User Guide"), this, &MainWindow::showUserGuide);
    a->setObjectName(QStringLiteral("actionUserGuide"));
    a->setShortcut(QKeySequence::HelpContents);
    a = help->addAction(tr("&Keyboard and Mouse"), this, &MainWindow::showShortcuts);
    a->setObjectName(QStringLiteral("actionShortcuts"));
    help->addSeparator();
    help->addAction(tr("&About Lucent"), this, [this] {
        QMessageBox::about(this, tr("About Lucent"),
                           tr("<b>Lucent</b> — paint heterogeneous subsurface-scattering material "
                              "into a mesh's volume and preview its translucency.<br>See "
                              "docs/user-guide.md."));
    });
}

namespace {
/// A non-modal help window (kept open while working), reused when asked for again.
QTextBrowser* helpWindow(QWidget* parent, const QString& name, const QString& title) {
    if (auto* existing = parent->findChild<QTextBrowser*>(name)) {
        existing->show();
        existing->raise();
        existing->activateWindow();
        return existing;
    }
    auto* browser = new QTextBrowser(parent);
    browser->setObjectName(name);
    browser->setWindowFlag(Qt::Window);
    browser->setWindowTitle(title);
    browser->setOpenExternalLinks(true);
    browser->resize(760, 620);
    return browser;
}
}  // namespace

void MainWindow::showUserGuide() {
    QTextBrowser* browser =
        helpWindow(this, QStringLiteral("userGuide"), tr("Lucent — User guide"));
    if (browser->document()->isEmpty()) {
        QFile guide(QStringLiteral(":/docs/user-guide.md"));
        QString text = tr("The user guide is not in this build.");
        if (guide.open(QIODevice::ReadOnly | QIODevice::Text))
            text = QString::fromUtf8(guide.readAll());
        // Pictures (images/…) from the source tree when it is there; otherwise their captions.
        browser->setSearchPaths({QStringLiteral(LUCENT_DOCS_DIR)});
        browser->setMarkdown(text);
    }
    browser->show();
}

QString MainWindow::shortcutsText() const {
    // Every menu action with a shortcut, as the menus define them (so the list cannot drift),
    // then the viewport's mouse bindings.
    QString rows;
    for (QAction* menuAction : menuBar()->actions()) {
        const QMenu* menu = menuAction->menu();
        if (!menu)
            continue;
        for (QAction* a : menu->actions()) {
            if (a->shortcuts().isEmpty())
                continue;
            QStringList keys;
            for (const QKeySequence& k : a->shortcuts())
                keys.push_back(k.toString(QKeySequence::NativeText).toHtmlEscaped());
            rows += QStringLiteral("<tr><td>%1 ▸ %2</td><td><b>%3</b></td></tr>")
                        .arg(menuAction->text().remove(QLatin1Char('&')),
                             a->text().remove(QLatin1Char('&')).remove(QStringLiteral("…")),
                             keys.join(QStringLiteral(", ")));
        }
    }
    const QString mouse =
        tr("<tr><td>Paint</td><td><b>left drag</b> over the object (a drag may start beside "
           "it)</td></tr>"
           "<tr><td>Orbit</td><td><b>Alt + left drag</b> or <b>middle drag</b></td></tr>"
           "<tr><td>Pan</td><td><b>Shift + middle drag</b> or <b>right drag</b></td></tr>"
           "<tr><td>Zoom</td><td><b>wheel</b></td></tr>"
           "<tr><td>Move a light</td><td><b>drag its handle</b> (L0, L1, …)</td></tr>");
    return tr("<h3>Keys</h3><table cellpadding=\"3\">%1</table>"
              "<h3>Mouse in the viewport</h3><table cellpadding=\"3\">%2</table>")
        .arg(rows, mouse);
}

void MainWindow::showShortcuts() {
    QTextBrowser* browser =
        helpWindow(this, QStringLiteral("shortcuts"), tr("Lucent — Keyboard and mouse"));
    browser->setHtml(shortcutsText());
    browser->resize(520, 560);
    browser->show();
}

void MainWindow::updateTitle() {
    const QString name =
        m_doc->filePath().isEmpty() ? tr("Default scene") : QFileInfo(m_doc->filePath()).fileName();
    setWindowTitle(QStringLiteral("%1%2 — Lucent")
                       .arg(name, m_doc->isModified() ? QStringLiteral("*") : QString()));
}

bool MainWindow::maybeSave() {
    if (!m_doc->isModified() || !m_useSettings)
        return true;
    const auto r =
        QMessageBox::question(this, tr("Unsaved changes"), tr("Save the changes to the project?"),
                              QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel);
    if (r == QMessageBox::Cancel)
        return false;
    if (r == QMessageBox::Discard)
        return true;
    QString p = m_doc->filePath();
    if (p.isEmpty())
        p = QFileDialog::getSaveFileName(this, tr("Save project"), QStringLiteral("untitled.json"));
    return !p.isEmpty() && saveTo(p);
}

bool MainWindow::openFile(const QString& path) {
    const QString suffix = QFileInfo(path).suffix().toLower();
    if (suffix == QLatin1String("vdb"))
        return importVdb(path);
    if (MESH_SUFFIXES.contains(suffix))
        return importMesh(path, /*mmPerUnit=*/0.0);
    try {
        m_doc->open(path);
        addRecent(path);
        statusBar()->showMessage(tr("Opened %1").arg(path), 5000);
        return true;
    } catch (const std::exception& ex) {
        reportError(tr("Open"), ex);
        return false;
    }
}

namespace {
/// QSettings key of the camera bookmarks of the project at `path`.
QString bookmarksKey(const QString& path) {
    return QStringLiteral("cameraBookmarks/") +
           QString::fromLatin1(QUrl::toPercentEncoding(QFileInfo(path).absoluteFilePath()));
}
}  // namespace

void MainWindow::storeBookmarks() {
    if (!m_useSettings || m_doc->filePath().isEmpty())
        return;  // an unsaved project keeps them until it is saved
    QSettings s;
    const QStringList b = m_render->bookmarks();
    if (b.isEmpty())
        s.remove(bookmarksKey(m_doc->filePath()));
    else
        s.setValue(bookmarksKey(m_doc->filePath()), b);
}

void MainWindow::loadBookmarks() {
    if (m_useSettings && !m_doc->filePath().isEmpty())
        m_render->setBookmarks(QSettings().value(bookmarksKey(m_doc->filePath())).toStringList());
}

void MainWindow::storeViewInScene() {
    // The viewport's orbit camera is what the user sees: the project keeps it (a reopened
    // project shows the same view, and the CLI renders it).
    Camera& c = m_doc->scene().camera;
    const OrbitCamera& view = m_viewport->camera();
    c.position = view.eye();
    c.target = view.target;
    c.up = Vector3f(0.f, 1.f, 0.f);
    c.orthographic = false;
    c.fovYDeg = view.fovYDeg;
    // Planes as the viewport's (OrbitCamera::clipFromView), so a far camera is not clipped.
    c.nearPlane = std::max(1e-3f, view.distance * 0.01f);
    c.farPlane = view.distance * 100.f + 1.f;
}

namespace {
bool sameContents(const QString& a, const QString& b) {
    QFile fa(a), fb(b);
    if (fa.size() != fb.size() || !fa.open(QIODevice::ReadOnly) || !fb.open(QIODevice::ReadOnly))
        return false;
    while (!fa.atEnd())
        if (fa.read(1 << 20) != fb.read(1 << 20))
            return false;
    return true;
}
}  // namespace

bool MainWindow::keepMeshWithProject(const QString& projectPath) {
    if (!m_doc->hasObject())
        return true;
    MeshSource& source = m_doc->scene().objects[0].meshSource;
    if (source.file.empty())
        return true;  // procedural: nothing to keep
    const QFileInfo mesh(QString::fromStdString(source.file));
    const QDir folder = QFileInfo(projectPath).absoluteDir();
    const QString relative = folder.relativeFilePath(mesh.absoluteFilePath());
    if (!relative.startsWith(QLatin1String("../")) && !QDir::isAbsolutePath(relative))
        return true;  // already inside the project folder
    if (!mesh.exists())
        return true;  // nothing to copy: the project keeps the (relative) reference
    if (m_useSettings) {
        const auto answer = QMessageBox::question(
            this, tr("Save project"),
            tr("The mesh %1 is outside the project's folder. Copy it into the folder, so that the "
               "project can be moved or shared as one folder?")
                .arg(mesh.fileName()),
            QMessageBox::Yes | QMessageBox::No | QMessageBox::Cancel, QMessageBox::Yes);
        if (answer == QMessageBox::Cancel)
            return false;
        if (answer == QMessageBox::No)
            return true;
    }
    // Beside the project under its own name; another file of that name gets a suffix.
    QString target = folder.filePath(mesh.fileName());
    for (int i = 2; QFileInfo::exists(target) && !sameContents(target, mesh.absoluteFilePath());
         ++i)
        target = folder.filePath(
            QStringLiteral("%1_%2.%3").arg(mesh.completeBaseName()).arg(i).arg(mesh.suffix()));
    if (!QFileInfo::exists(target) && !QFile::copy(mesh.absoluteFilePath(), target))
        LUCENT_THROW(IoError, "cannot copy the mesh '", mesh.absoluteFilePath().toStdString(),
                     "' to '", target.toStdString(), "'");
    source.file = target.toStdString();
    return true;
}

bool MainWindow::saveTo(const QString& path) {
    try {
        storeViewInScene();
        if (!keepMeshWithProject(path))
            return false;
        m_doc->save(path);
        storeBookmarks();  // under the new path
        addRecent(path);
        if (m_useSettings)
            removeAutosave();  // the saved project holds everything the autosave did
        statusBar()->showMessage(tr("Saved %1").arg(path), 5000);
        return true;
    } catch (const std::exception& ex) {
        reportError(tr("Save"), ex);
        return false;
    }
}

double MainWindow::guessMillimetresPerUnit(double largestExtent) {
    // The unit that makes the object closest to 100 mm (on a log scale): what is painted with
    // subsurface scattering is held in the hand (a face, a fruit, a figurine). Blender's
    // Suzanne, 2.7 units wide, comes out in cm (27 mm); the Stanford bunny, 0.16 units, in
    // metres (160 mm).
    if (!(largestExtent > 0.0) || !std::isfinite(largestExtent))
        return 1.0;
    // Only the metric units are guessed: inches are offered in the dialog, but with a factor
    // of 2.54 between them and cm they would win by coincidence as often as not.
    double best = 1.0, bestDistance = INFINITY;
    for (const MeshUnit& u : meshUnits()) {
        if (u.mm != 1.0 && u.mm != 10.0 && u.mm != 1000.0)
            continue;
        const double distance = std::abs(std::log10(largestExtent * u.mm / 100.0));
        if (distance < bestDistance) {
            bestDistance = distance;
            best = u.mm;
        }
    }
    return best;
}

const std::vector<MainWindow::MeshUnit>& MainWindow::meshUnits() {
    static const std::vector<MeshUnit> units = {{QStringLiteral("mm"), 1.0},
                                                {QStringLiteral("cm"), 10.0},
                                                {QStringLiteral("m"), 1000.0},
                                                {QStringLiteral("inch"), 25.4}};
    return units;
}

QString MainWindow::meshSizeWarning(double largestExtentMm) {
    // Outside what the 128³ grid and the default brush serve well: voxels under 0.04 mm or a
    // mesh taller than a person.
    if (largestExtentMm < 5.0)
        return tr("At this scale the object is only %1 mm across: its voxels are %2 mm, and "
                  "light passes through it almost unchanged. Is the unit right?")
            .arg(largestExtentMm, 0, 'g', 3)
            .arg(largestExtentMm / GridSpec::DEFAULT_RESOLUTION, 0, 'g', 2);
    if (largestExtentMm > 2000.0)
        return tr("At this scale the object is %1 m across: subsurface light travels a few mm, "
                  "so it will look opaque. Is the unit right?")
            .arg(largestExtentMm / 1000.0, 0, 'g', 3);
    return {};
}

bool MainWindow::askMeshUnits(const QString& path, double largestExtent,
                              const QStringList& warnings, double& mmPerUnit) {
    QDialog dialog(this);
    dialog.setWindowTitle(tr("Import mesh"));
    auto* form = new QFormLayout(&dialog);
    form->addRow(new QLabel(tr("<b>%1</b> is %2 units across. One unit of the file is:")
                                .arg(QFileInfo(path).fileName())
                                .arg(largestExtent, 0, 'g', 4)));
    auto* unit = new QComboBox;
    for (const MeshUnit& u : meshUnits())
        unit->addItem(u.name, u.mm);
    unit->addItem(tr("custom"), 0.0);
    auto* scale = new QDoubleSpinBox;
    scale->setRange(1e-6, 1e6);
    scale->setDecimals(6);
    scale->setSuffix(tr(" mm"));
    scale->setValue(mmPerUnit);
    auto* size = new QLabel;
    auto* warning = new QLabel;
    warning->setWordWrap(true);
    warning->setStyleSheet(QStringLiteral("color: #e06c5a"));
    form->addRow(tr("Unit"), unit);
    form->addRow(tr("1 unit ="), scale);
    form->addRow(tr("Size"), size);
    form->addRow(warning);
    const auto refresh = [&] {
        const double mm = largestExtent * scale->value();
        size->setText(tr("%1 mm across").arg(mm, 0, 'g', 4));
        const QString w = meshSizeWarning(mm);
        warning->setText(w);
        warning->setVisible(!w.isEmpty());
    };
    connect(unit, &QComboBox::currentIndexChanged, &dialog, [&](int i) {
        if (const double mm = unit->itemData(i).toDouble(); mm > 0.0)
            scale->setValue(mm);
    });
    connect(scale, &QDoubleSpinBox::valueChanged, &dialog, [&](double v) {
        const int i = unit->findData(v);
        const QSignalBlocker block(unit);
        unit->setCurrentIndex(i >= 0 ? i : unit->count() - 1);
        refresh();
    });
    unit->setCurrentIndex(std::max(0, unit->findData(mmPerUnit)));
    refresh();
    if (!warnings.isEmpty()) {
        auto* list = new QListWidget;
        list->addItems(warnings);
        list->setMaximumHeight(120);
        form->addRow(new QLabel(
            tr("The file was repaired on import (%n warning(s)):", "", int(warnings.size()))));
        form->addRow(list);
    }
    if (!execWithOkCancel(dialog, form))
        return false;
    mmPerUnit = scale->value();
    return true;
}

bool MainWindow::importMesh(const QString& path, double mmPerUnit) {
    try {
        MeshReport report;
        SceneObject obj;
        // Loaded in the file's units first: the unit is chosen from its size, then applied
        // (a uniform scale keeps the normals).
        obj.mesh = loadMesh(path.toStdString(), 1.f, &report);
        const Vector3f e = obj.mesh.bounds().extent();
        const double extent = double(std::max({e.x, e.y, e.z}));
        m_importWarnings.clear();
        for (const std::string& w : report.warnings)
            m_importWarnings.push_back(readableMessage(w));
        if (!(mmPerUnit > 0.0)) {
            mmPerUnit = guessMillimetresPerUnit(extent);
            if (m_useSettings && !askMeshUnits(path, extent, m_importWarnings, mmPerUnit))
                return false;
        }
        for (Point3f& p : obj.mesh.positions)
            p *= float(mmPerUnit);
        obj.meshSource.file = path.toStdString();
        obj.meshSource.scale = float(mmPerUnit);
        const MaterialSample base =
            m_doc->material() ? m_doc->material()->base() : MaterialSample{};
        SceneObject filled = makeObject(std::move(obj.mesh), GridSpec::DEFAULT_RESOLUTION, base);
        obj.mesh = std::move(filled.mesh);
        obj.material = std::move(filled.material);
        obj.material->setEta(m_doc->scene().eta);
        obj.materialSource.uniform = true;
        obj.materialSource.value = base;
        Scene scene = m_doc->scene();
        scene.objects = {std::move(obj)};
        m_doc->setScene(std::move(scene), QString());
        m_doc->noteSceneEdited();
        m_viewport->frameObject();
        const double sizeMm = extent * mmPerUnit;
        QString message = tr("Imported %1: %2 triangles, %3 mm across (1 unit = %4 mm)")
                              .arg(QFileInfo(path).fileName())
                              .arg(m_doc->mesh()->triangleCount())
                              .arg(sizeMm, 0, 'g', 4)
                              .arg(mmPerUnit, 0, 'g', 6);
        if (!m_importWarnings.isEmpty())
            message += tr("; repaired: %1").arg(m_importWarnings.join(QStringLiteral("; ")));
        if (const QString w = meshSizeWarning(sizeMm); !w.isEmpty())
            message += QStringLiteral(" — ") + w;
        m_lastImportMessage = message;
        statusBar()->showMessage(message, 20000);
        if (!m_useSettings && !m_importWarnings.isEmpty())
            std::fprintf(stderr, "lucent: %s\n", qPrintable(message));
        return true;
    } catch (const std::exception& ex) {
        reportError(tr("Import mesh"), ex);
        return false;
    }
}

bool MainWindow::importVdb(const QString& path) {
    try {
        io::ImportedMaterial imported = lucent::io::importVdb(path.toStdString());
        Scene scene = m_doc->scene();
        if (scene.objects.empty())
            LUCENT_THROW(ValueError, "no object to receive the material");
        scene.objects[0].material = std::make_shared<MaterialVolume>(std::move(imported.volume));
        scene.objects[0].materialSource = MaterialSource{};
        scene.objects[0].materialSource.vdbFile = path.toStdString();
        scene.eta = imported.metadata.eta;
        m_doc->setScene(std::move(scene), QString());
        m_doc->noteSceneEdited();
        statusBar()->showMessage(tr("Imported material %1").arg(path), 5000);
        return true;
    } catch (const std::exception& ex) {
        reportError(tr("Import VDB"), ex);
        return false;
    }
}

bool MainWindow::exportVdbTo(const QString& path, bool wait) {
    return exportVdbTo(path, m_vdbChoice, wait);
}

bool MainWindow::exportVdbTo(const QString& path, const VdbExportChoice& choice, bool wait) {
    if (m_exporting || !m_doc->material())
        return false;
    m_exporting = true;
    // The export works on a copy so painting can go on while the worker writes.
    auto copy = std::make_shared<MaterialVolume>(*m_doc->material());
    auto error = std::make_shared<std::string>();
    auto done = std::make_shared<std::atomic<int>>(0);
    const std::string target = path.toStdString();
    const QFileInfo info(path);
    const std::string mitsubaPrefix =
        (info.path() + QStringLiteral("/") + info.completeBaseName()).toStdString();
    io::VdbExportOptions vdbOptions;
    vdbOptions.rendererGrids = choice.rendererGrids;
    vdbOptions.materialName = choice.materialName.toStdString();
    io::MitsubaExportOptions mitsubaOptions;
    mitsubaOptions.materialName = vdbOptions.materialName;
    const bool mitsuba = choice.mitsubaVol;
    // One step per file: the VDB, then the Mitsuba grids σt, albedo and the medium XML (one
    // engine call writes those three).
    const int steps = mitsuba ? 4 : 1;
    m_exportSteps = steps;
    QThread* worker = QThread::create(
        [copy, error, done, target, vdbOptions, mitsuba, mitsubaPrefix, mitsubaOptions] {
            try {
                io::exportVdb(*copy, target, vdbOptions);
                done->store(1);
                if (mitsuba) {
                    io::exportMitsubaVol(*copy, mitsubaPrefix, mitsubaOptions);
                    done->store(4);
                }
            } catch (const std::exception& ex) {
                *error = ex.what();
            }
        });
    auto* progress = new QProgressDialog(tr("Exporting %1…").arg(path), QString(), 0, steps, this);
    progress->setObjectName(QStringLiteral("exportProgress"));
    progress->setWindowModality(Qt::WindowModal);
    progress->setMinimumDuration(300);
    progress->setValue(0);
    auto* poll = new QTimer(progress);
    connect(poll, &QTimer::timeout, progress, [progress, done] { progress->setValue(*done); });
    poll->start(50);
    auto ok = std::make_shared<bool>(false);
    connect(worker, &QThread::finished, this, [this, worker, progress, error, path, ok, done] {
        progress->setValue(*done);
        progress->deleteLater();
        worker->deleteLater();
        m_exporting = false;
        if (error->empty()) {
            *ok = true;
            statusBar()->showMessage(tr("Exported %1").arg(path), 5000);
        } else {
            reportError(tr("Export VDB"), IoError(*error));
        }
    });
    worker->start();
    if (wait) {
        while (m_exporting)
            QApplication::processEvents(QEventLoop::AllEvents, 50);
        return *ok;
    }
    return true;
}

void MainWindow::loadLiveCosts() {
    const planner::LiveCostsInUse inUse = planner::loadLiveCosts(planner::userLiveCostsPath());
    PreviewRenderer::useLiveCosts(inUse);
    m_liveCostsWarning = QString::fromStdString(inUse.warning);
    if (!m_liveCostsWarning.isEmpty()) {
        statusBar()->showMessage(tr("Auto: %1").arg(m_liveCostsWarning), 30000);
        std::fprintf(stderr, "lucent: %s\n", qPrintable(m_liveCostsWarning));
    }
    m_viewport->update();  // Auto plans again with them
}

bool MainWindow::calibrateLiveCosts(bool wait) {
    planner::LiveCalibrationOptions options;
    // The viewport as it is rendered: its device pixels at the Render dock's scale.
    const qreal dpr = m_viewport->devicePixelRatioF();
    options.viewportWidth = std::max(16, int(std::lround(m_viewport->width() * dpr)));
    options.viewportHeight = std::max(16, int(std::lround(m_viewport->height() * dpr)));
    options.resolutionScale = std::clamp(m_viewport->renderSettings().resolutionScale, 0.125f, 1.f);
    return calibrateLiveCosts(options, wait);
}

bool MainWindow::calibrateLiveCosts(const planner::LiveCalibrationOptions& options, bool wait) {
    if (m_calibrating)
        return false;
    const std::string path = planner::userLiveCostsPath();
    if (path.empty()) {
        reportError(tr("Calibrate live costs"),
                    ValueError("neither XDG_CONFIG_HOME nor HOME is set: there is no folder "
                               "for the calibration"));
        return false;
    }
    m_calibrating = true;
    // Idle refinement of a progressive preview would take CPU from the measurement.
    m_viewport->setRefinementPaused(true);
    auto cancel = std::make_shared<std::atomic<bool>>(false);
    m_calibrationCancel = cancel;
    auto result = std::make_shared<planner::LiveCalibration>();
    auto error = std::make_shared<std::string>();
    auto* progress = new QProgressDialog(tr("Measuring the live preview on this machine…"),
                                         tr("Cancel"), 0, 1, this);
    progress->setObjectName(QStringLiteral("calibrationProgress"));
    progress->setWindowTitle(tr("Calibrate live costs"));
    progress->setWindowModality(Qt::WindowModal);
    progress->setMinimumDuration(0);
    progress->setAutoClose(false);
    progress->setAutoReset(false);
    progress->setValue(0);
    connect(progress, &QProgressDialog::canceled, this, [cancel] { cancel->store(true); });
    planner::LiveCalibrationOptions o = options;
    o.command = "lucent Calibrate Live Costs";
    o.cancel = cancel.get();  // the worker's lambda holds `cancel`
    const QPointer<QProgressDialog> dialog(progress);
    o.progress = [dialog](const planner::LiveCalibrationProgress& p) {
        QMetaObject::invokeMethod(QCoreApplication::instance(), [dialog, p] {
            if (!dialog || dialog->wasCanceled())
                return;
            dialog->setMaximum(p.total);
            dialog->setValue(p.done);
            if (!p.next.empty())
                dialog->setLabelText(tr("Measuring the live preview on this machine: %1 (%2 of "
                                        "%3)…")
                                         .arg(QString::fromStdString(p.next))
                                         .arg(p.done + 1)
                                         .arg(p.total));
        });
    };
    QThread* worker = QThread::create([o, cancel, result, error] {
        try {
            *result = planner::calibrateLiveCosts(o);
        } catch (const std::exception& ex) {
            *error = ex.what();
        }
    });
    m_calibrationThread = worker;
    auto ok = std::make_shared<bool>(false);
    connect(worker, &QThread::finished, this, [this, worker, progress, result, error, path, ok] {
        worker->deleteLater();
        progress->deleteLater();
        m_calibrationThread = nullptr;
        m_calibrating = false;
        m_viewport->setRefinementPaused(false);
        if (!error->empty()) {
            reportError(tr("Calibrate live costs"), GpuError(*error));
            return;
        }
        if (result->cancelled) {
            statusBar()->showMessage(
                tr("Calibration cancelled: Auto keeps planning with live costs %1.")
                    .arg(QString::fromStdString(PreviewRenderer::liveCostTable().label)),
                10000);
            return;
        }
        try {
            planner::saveLiveCosts(result->costs, path);
        } catch (const std::exception& ex) {
            reportError(tr("Calibrate live costs"), ex);
            return;
        }
        loadLiveCosts();  // the file just written, through the same checks as at start-up
        *ok = PreviewRenderer::liveCostTable().inUse.calibrated;
        if (*ok)
            statusBar()->showMessage(
                tr("Auto now plans with live costs %1 (%2).")
                    .arg(QString::fromStdString(PreviewRenderer::liveCostTable().label),
                         QString::fromStdString(path)),
                15000);
    });
    worker->start();
    if (wait) {
        while (m_calibrating)
            QApplication::processEvents(QEventLoop::AllEvents, 50);
        return *ok;
    }
    return true;
}

bool MainWindow::useShippedLiveCosts() {
    const std::string path = planner::userLiveCostsPath();
    std::error_code ec;
    if (!path.empty() && std::filesystem::exists(path, ec)) {
        if (m_useSettings &&
            QMessageBox::question(this, tr("Use shipped live costs"),
                                  tr("Delete this machine's live-cost calibration (%1)? Auto "
                                     "then plans with the costs shipped with Lucent.")
                                      .arg(QString::fromStdString(path))) != QMessageBox::Yes)
            return false;
        if (!std::filesystem::remove(path, ec) && ec) {
            reportError(tr("Use shipped live costs"),
                        IoError("cannot delete '" + path + "': " + ec.message()));
            return false;
        }
    }
    loadLiveCosts();
    statusBar()->showMessage(
        tr("Auto plans with live costs %1.")
            .arg(QString::fromStdString(PreviewRenderer::liveCostTable().label)),
        10000);
    return true;
}

bool MainWindow::askVdbExportChoice() {
    QDialog dialog(this);
    dialog.setWindowTitle(tr("Export VDB"));
    auto* form = new QFormLayout(&dialog);
    auto* native = new QRadioButton(tr("Native grids only (σt, σs′, g per RGB channel)"));
    auto* ready = new QRadioButton(
        tr("Native + renderer-ready grids for Blender / Mitsuba (density, albedo, color)"));
    (m_vdbChoice.rendererGrids ? ready : native)->setChecked(true);
    auto* mitsuba = new QCheckBox(tr("Also Mitsuba 3 .vol grids and medium XML"));
    mitsuba->setChecked(m_vdbChoice.mitsubaVol);
    auto* name = new QLineEdit(m_vdbChoice.materialName);
    form->addRow(native);
    form->addRow(ready);
    form->addRow(mitsuba);
    form->addRow(tr("Material name"), name);
    if (!execWithOkCancel(dialog, form))
        return false;
    m_vdbChoice.rendererGrids = ready->isChecked();
    m_vdbChoice.mitsubaVol = mitsuba->isChecked();
    m_vdbChoice.materialName = name->text();
    if (m_useSettings) {
        QSettings s;
        s.setValue("export/rendererGrids", m_vdbChoice.rendererGrids);
        s.setValue("export/mitsubaVol", m_vdbChoice.mitsubaVol);
    }
    return true;
}

bool MainWindow::exportRenderTo(const QString& path) {
    try {
        if (QFileInfo(path).suffix().toLower() == QLatin1String("exr")) {
            // The renderer's linear radiance before exposure and tone curve: what a compositor
            // or the CLI's `compare` expects.
            writeExr(m_viewport->linearImage(), path.toStdString());
        } else {
            const QImage img = m_viewport->grabRender().convertToFormat(QImage::Format_RGB32);
            if (img.isNull())
                LUCENT_THROW(GpuError, "the viewport has no image to export");
            // Written through QImage so the PNG holds exactly the displayed 8-bit values;
            // atomically, like every other file the app writes.
            writeFileAtomically(path.toStdString(), [&img, &path](const std::string& tmp) {
                if (!img.save(QString::fromStdString(tmp), "PNG"))
                    LUCENT_THROW(IoError, "cannot write PNG '", path.toStdString(), "'");
            });
        }
        statusBar()->showMessage(tr("Wrote %1").arg(path), 5000);
        return true;
    } catch (const std::exception& ex) {
        reportError(tr("Export render"), ex);
        return false;
    }
}

void MainWindow::addRecent(const QString& path) {
    const QString abs = QFileInfo(path).absoluteFilePath();
    m_recent.removeAll(abs);
    m_recent.prepend(abs);
    while (m_recent.size() > MAX_RECENT)
        m_recent.removeLast();
    if (m_useSettings)
        QSettings().setValue("recentFiles", m_recent);
    rebuildRecentMenu();
}

void MainWindow::rebuildRecentMenu() {
    m_recentMenu->clear();
    for (const QString& p : m_recent) {
        const bool exists = QFileInfo::exists(p);
        QAction* a = m_recentMenu->addAction(
            exists ? QFileInfo(p).fileName() : tr("%1 (missing)").arg(QFileInfo(p).fileName()),
            this, [this, p] {
                if (maybeSave())
                    openFile(p);
            });
        a->setToolTip(p);
        a->setEnabled(exists);
    }
    if (!m_recent.isEmpty()) {
        m_recentMenu->addSeparator();
        QAction* clear = m_recentMenu->addAction(tr("&Clear Menu"), this, [this] {
            m_recent.clear();
            if (m_useSettings)
                QSettings().setValue("recentFiles", m_recent);
            // Not from inside the handler of an action the rebuild deletes.
            QMetaObject::invokeMethod(this, &MainWindow::rebuildRecentMenu, Qt::QueuedConnection);
        });
        clear->setObjectName(QStringLiteral("actionClearRecent"));
    }
    m_recentMenu->setEnabled(!m_recent.isEmpty());
}

void MainWindow::autosaveNow() {
    if (!m_doc->isModified())
        return;
    try {
        QDir().mkpath(QFileInfo(autosavePath()).absolutePath());
        storeViewInScene();
        m_doc->saveCopy(autosavePath());
        statusBar()->showMessage(tr("Autosaved"), 2000);
    } catch (const std::exception& ex) {
        statusBar()->showMessage(tr("Autosave failed: %1").arg(QString::fromUtf8(ex.what())), 8000);
    }
}

void MainWindow::removeAutosave() {
    removeProject(autosavePath().toStdString());  // the JSON and its sidecar VDB
}

void MainWindow::offerRecovery() {
    if (!QFileInfo::exists(autosavePath()))
        return;
    const QByteArray answer = qgetenv(RECOVERY_ENV);
    bool recover = answer == "accept";
    if (answer != "accept" && answer != "discard")
        recover = QMessageBox::question(
                      this, tr("Recover"),
                      tr("Lucent did not exit cleanly last time. Recover the autosaved project?"),
                      QMessageBox::Yes | QMessageBox::No) == QMessageBox::Yes;
    if (!recover) {
        removeAutosave();
        return;
    }
    try {
        m_doc->open(autosavePath());
        m_doc->setScene(std::move(m_doc->scene()), QString());
        m_doc->noteSceneEdited();  // recovered work is unsaved
        statusBar()->showMessage(tr("Recovered the autosaved project"), 8000);
        // The autosave stays until the next autosave replaces it or a clean exit removes it,
        // so a second crash before then still finds it.
    } catch (const std::exception& ex) {
        reportError(tr("Recover"), ex);
    }
}

void MainWindow::closeEvent(QCloseEvent* e) {
    if (m_exporting || !maybeSave()) {
        e->ignore();
        return;
    }
    if (m_useSettings) {
        QSettings s;
        s.setValue("window/geometry", saveGeometry());
        s.setValue("window/state", saveState());
        savePanelSettings(m_brush, s, QStringLiteral("brush"));
        savePanelSettings(m_render, s, QStringLiteral("render"));
        s.setValue(QStringLiteral("render/defaultsVersion"), RENDER_DEFAULTS_VERSION);
        s.setValue("view/lightGizmos", m_viewport->lightGizmosVisible());
        removeAutosave();  // clean exit: nothing to recover
    }
    e->accept();
}

bool MainWindow::canOpen(const QString& path) {
    const QString suffix = QFileInfo(path).suffix().toLower();
    return suffix == QLatin1String("json") || suffix == QLatin1String("vdb") ||
           MESH_SUFFIXES.contains(suffix);
}

void MainWindow::dragEnterEvent(QDragEnterEvent* e) {
    // Only what File ▸ Open takes: the cursor shows at once that other files are refused.
    for (const QUrl& url : e->mimeData()->urls())
        if (url.isLocalFile() && canOpen(url.toLocalFile())) {
            e->acceptProposedAction();
            return;
        }
    e->ignore();
}

void MainWindow::dropEvent(QDropEvent* e) {
    for (const QUrl& url : e->mimeData()->urls()) {
        if (!url.isLocalFile() || !canOpen(url.toLocalFile()))
            continue;
        if (maybeSave())
            openFile(url.toLocalFile());
        break;  // one project at a time
    }
}

}  // namespace lucent::app
