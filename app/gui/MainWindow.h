// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The main window: viewport, docks, menus and shortcuts, file operations (projects,
/// VDB export, render export), recent files, drag and drop, autosave and crash recovery.

#include <lucent/scene/SceneEdit.h>

#include <QMainWindow>
#include <QStringList>
#include <QTimer>

#include <atomic>
#include <memory>
#include <string>
#include <vector>

class QAction;
class QLabel;
class QMenu;
class QThread;

namespace lucent::planner {
struct LiveCalibrationOptions;
}  // namespace lucent::planner

namespace lucent::app {

class BrushPanel;
class LightPanel;
class ReferencePanel;
class RenderPanel;
class Document;
class SliceView;
class StatsPanel;
class Viewport;

class MainWindow : public QMainWindow {
    Q_OBJECT
public:
    /// @param restoreSettings false for tests and scripted runs: ignore saved layout and recent
    ///        files, no autosave, no recovery prompt, errors to stderr instead of dialogs.
    explicit MainWindow(bool restoreSettings = true, QWidget* parent = nullptr);
    ~MainWindow() override;

    Document* document() { return m_doc; }
    Viewport* viewport() { return m_viewport; }
    SliceView* sliceView() { return m_slice; }
    BrushPanel* brushPanel() { return m_brush; }
    LightPanel* lightPanel() { return m_lights; }
    RenderPanel* renderPanel() { return m_render; }
    ReferencePanel* referencePanel() { return m_reference; }
    /// Selects the preview method `method` (registry name) through the Render settings dock.
    /// @return false (nothing changes) when it is not a preview method.
    bool setRenderMethod(const QString& method);
    /// Sets a live parameter of the selected preview method (RenderPanel::setParam).
    bool setRenderParam(const QString& param, const QString& value);

    //! @{ \name File operations; each reports errors in a message box and returns false
    bool openFile(const QString& path);
    /// Imports a mesh file as the object (voxelised at 128³, filled with the base material).
    /// @param mmPerUnit millimetres per unit of the file; ≤ 0: guessMillimetresPerUnit, which
    ///        an interactive run shows in a dialog (unit, size, warnings) before importing.
    bool importMesh(const QString& path, double mmPerUnit);
    /// A length unit a mesh file may be in.
    struct MeshUnit {
        QString name;
        double mm;  ///< millimetres per unit
    };
    /// mm, cm, m, inch.
    static const std::vector<MeshUnit>& meshUnits();
    /// The metric unit (mm, cm or m) that makes a mesh `largestExtent` file units across
    /// closest to 100 mm (log scale). @return millimetres per unit; 1 for a degenerate extent.
    static double guessMillimetresPerUnit(double largestExtent);
    /// Why an object `largestExtentMm` across is probably in the wrong unit (< 5 mm or > 2 m),
    /// empty when its size is plausible.
    static QString meshSizeWarning(double largestExtentMm);
    /// What the last mesh import repaired (MeshReport::warnings, readable).
    [[nodiscard]] const QStringList& lastImportWarnings() const { return m_importWarnings; }
    /// The status-bar line of the last import: size, unit, repairs and size warning.
    [[nodiscard]] const QString& lastImportMessage() const { return m_lastImportMessage; }
    /// `text` fit for a message box: invalid UTF-8 and control characters (bytes of a binary
    /// file quoted by a reader) shown as "<binary data>", at most 600 characters.
    static QString readableMessage(const std::string& text);
    bool saveTo(const QString& path);
    /// What File ▸ Export VDB writes (its options dialog; remembered in QSettings).
    struct VdbExportChoice {
        /// Also the renderer-ready grids `density`, `albedo`, `color` (Blender's and Mitsuba's
        /// names; lucent/io/VdbIO.h). false: only the native grids σt, σs′, g.
        bool rendererGrids = true;
        /// Also Mitsuba 3 `.vol` grids and a medium XML next to the VDB
        /// (`<dir>/<stem>_sigma_t.vol`, `_albedo.vol`, `_medium.xml`; lucent/io/MitsubaIO.h).
        bool mitsubaVol = false;
        QString materialName;  ///< metadata `lucent_material_name` / the XML comment
    };
    /// Exports the painted volume as OpenVDB (and optionally Mitsuba 3) on a worker thread,
    /// with a progress dialog counting the files written.
    /// @param wait block (running the event loop) until the export finished.
    bool exportVdbTo(const QString& path, bool wait = false);
    bool exportVdbTo(const QString& path, const VdbExportChoice& choice, bool wait = false);
    /// Files the last export wrote (or was writing) and how many of them are done; the
    /// progress dialog shows the same count (for tests).
    [[nodiscard]] int lastExportSteps() const { return m_exportSteps; }
    /// Writes the current render without gizmos or brush cursor. PNG: the tone-mapped display
    /// image at the viewport's size. EXR: the linear radiance W/(mm²·sr) at render resolution
    /// (Viewport::linearImage), independent of the exposure.
    bool exportRenderTo(const QString& path);
    //! @}

    //! @{ \name Live costs: what Auto expects a preview frame to cost (planner/LiveCosts.h)
    /// Makes Auto plan with the user's calibration (planner::userLiveCostsPath) when it exists
    /// and can be used, else with the shipped table; a file that cannot be used is reported
    /// (status bar, and stderr in scripted runs) and ignored. Called at start-up of an
    /// interactive session (restoreSettings), so scripted runs and tests plan with the shipped
    /// table unless they call it.
    void loadLiveCosts();
    /// Why the last loadLiveCosts did not use the user's file ("" when it did or there is none).
    [[nodiscard]] const QString& liveCostsWarning() const { return m_liveCostsWarning; }
    /// Edit ▸ Preferences ▸ Calibrate Live Costs: planner::calibrateLiveCosts on a worker thread
    /// (the viewport's size and render scale, the preview's idle refinement paused) with a
    /// progress dialog and Cancel; then writes the user's calibration file and plans with it.
    /// @param wait run the event loop until it has finished.
    /// @return false when it cannot start (one is running, no config location); with `wait`,
    ///         also when it failed or was cancelled.
    bool calibrateLiveCosts(bool wait = false);
    /// The same with the calibration's options given (tests: a small viewport, few strokes).
    bool calibrateLiveCosts(const planner::LiveCalibrationOptions& options, bool wait);
    [[nodiscard]] bool isCalibrating() const { return m_calibrating; }
    /// Edit ▸ Preferences ▸ Use Shipped Live Costs: deletes the user's calibration file (an
    /// interactive session asks first) and plans with the shipped table. @return false when
    /// the file could not be deleted or the user declined.
    bool useShippedLiveCosts();
    //! @}

    /// Message of the last failed operation (also shown to the user).
    [[nodiscard]] const QString& lastError() const { return m_lastError; }

    /// Mesh edits of the Mesh menu (the engine's, lucent/scene/SceneEdit.h).
    using MeshEditKind = lucent::MeshEditKind;
    /// Parameters of the mesh edits (the Mesh menu asks for the one of its edit).
    using MeshEditParams = lucent::MeshEditParams;
    /// Replaces the object's mesh by the edited one and re-voxelises it into the same grid
    /// (lucent::editObjectMesh), so the paint inside is kept (voxels that become inside get the
    /// base material). Clears the undo history. Reports errors (a parameter out of range names it)
    /// like the file operations; the scene is unchanged then. @return false on failure.
    bool applyMeshEdit(MeshEditKind kind);
    bool applyMeshEdit(MeshEditKind kind, const MeshEditParams& params);

    /// Makes OpenGL 4.5 core with a 24-bit depth buffer (what the viewport renders with) the
    /// default surface format. Call before the QApplication is created.
    static void useGlSurfaceFormat();
    /// True when File ▸ Open (and a drop on the window) takes `path`: a project (.json), a
    /// mesh (MESH_SUFFIXES) or a .vdb material.
    static bool canOpen(const QString& path);
    /// Path of the autosave project (AppLocalDataLocation/autosave/autosave.json). Its presence
    /// at start-up means the last session did not exit cleanly (a clean exit removes it).
    static QString autosavePath();
    /// Writes the autosave copy now when the document has unsaved changes.
    void autosaveNow();
    /// Help ▸ User Guide: docs/user-guide.md in a window (non-modal, kept open while working).
    void showUserGuide();
    /// Help ▸ Keyboard and Mouse: every menu shortcut and the viewport's mouse bindings.
    void showShortcuts();
    /// What showShortcuts shows (HTML), built from the menus' actions.
    [[nodiscard]] QString shortcutsText() const;
    /// Environment variable answering the recovery question without a dialog (scripted runs,
    /// tests): "accept" recovers, "discard" deletes the autosave; unset asks the user.
    static constexpr const char* RECOVERY_ENV = "LUCENT_RECOVERY";

protected:
    void closeEvent(QCloseEvent* e) override;
    void dragEnterEvent(QDragEnterEvent* e) override;
    void dropEvent(QDropEvent* e) override;

private:
    void createActions();
    void createDocks();
    bool maybeSave();
    void addRecent(const QString& path);
    void rebuildRecentMenu();
    void updateTitle();
    bool importVdb(const QString& path);
    /// The unit dialog of importMesh; false when cancelled.
    bool askMeshUnits(const QString& path, double largestExtent, const QStringList& warnings,
                      double& mmPerUnit);
    /// Writes the viewport's camera into the scene (saved with the project).
    void storeViewInScene();
    /// Before saving to `projectPath`: a mesh file outside the project's folder is copied into
    /// it (an interactive run asks first) and the scene refers to the copy. false: cancelled.
    /// @throw IoError when the copy fails.
    bool keepMeshWithProject(const QString& projectPath);
    void offerRecovery();
    /// Camera bookmarks of the open project, kept in QSettings under its path.
    void storeBookmarks();
    void loadBookmarks();
    /// The Export VDB options dialog; false when cancelled.
    bool askVdbExportChoice();
    void removeAutosave();
    void reportError(const QString& what, const std::exception& ex);

    Document* m_doc;
    Viewport* m_viewport;
    SliceView* m_slice = nullptr;
    BrushPanel* m_brush = nullptr;
    StatsPanel* m_stats = nullptr;
    RenderPanel* m_render = nullptr;
    LightPanel* m_lights = nullptr;
    ReferencePanel* m_reference = nullptr;  // null when the reference module is absent
    QMenu* m_recentMenu = nullptr;
    QMenu* m_viewMenu = nullptr;
    QLabel* m_hoverLabel = nullptr;
    QStringList m_recent;
    QString m_lastError;
    QStringList m_importWarnings;
    QString m_lastImportMessage;
    QTimer m_autosave;
    bool m_useSettings;
    bool m_exporting = false;
    bool m_calibrating = false;
    QThread* m_calibrationThread = nullptr;  ///< the calibration's worker while it runs
    std::shared_ptr<std::atomic<bool>> m_calibrationCancel;
    QString m_liveCostsWarning;
    int m_exportSteps = 0;
    VdbExportChoice m_vdbChoice;
    MeshEditParams m_meshEdit;  ///< last values asked by the Mesh menu
    bool m_layoutRestored = false;
};

}  // namespace lucent::app
