// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The open project: the engine Scene, its file path, the engine's paint History and
/// the QUndoStack mirroring it. Views listen to its signals; every voxel edit goes through it.

#include "BrushTool.h"

#include <lucent/material/History.h>
#include <lucent/material/Procedural.h>
#include <lucent/scene/Scene.h>
#include <lucent/scene/SceneEdit.h>

#include <QObject>
#include <QString>
#include <QUndoStack>

namespace lucent::app {

/// Why `brush` cannot paint, in words for an artist (what to change), or an empty string when
/// it can. The engine's checks (validateBrush) name its fields; this names what the Tools dock
/// shows.
QString brushProblem(const BrushSettings& brush);

class Document : public QObject {
    Q_OBJECT
public:
    explicit Document(QObject* parent = nullptr);
    /// Disconnects the undo stack first: ~QUndoStack clears the stack and emits cleanChanged,
    /// which must not reach this half-destroyed document (or its listeners).
    ~Document() override;

    /// Replaces the scene by the built-in default scene (makeDefaultScene; no files needed).
    void newDefault();
    /// Loads a project / scene JSON. @throw lucent::Error naming the file; the current scene
    /// is kept on failure.
    void open(const QString& path);
    /// Saves a project (scene JSON + sidecar VDB, both atomic). The undo stack is kept; its
    /// current step becomes the clean one (undoing past it marks the project modified, coming
    /// back marks it saved). Saved in the middle of a stroke, the file holds the stroke so far,
    /// which no undo step reaches: the project stays modified. @throw lucent::Error.
    void save(const QString& path);
    /// Saves a copy (autosave) without changing the path or the modified state.
    void saveCopy(const QString& path) const;
    /// Replaces the scene (e.g. autosave recovery); clears the undo stack.
    void setScene(Scene scene, const QString& path);

    [[nodiscard]] const QString& filePath() const { return m_path; }
    [[nodiscard]] bool isModified() const { return !m_undo.isClean() || m_extraChanges; }
    [[nodiscard]] Scene& scene() { return m_scene; }
    [[nodiscard]] const Scene& scene() const { return m_scene; }
    [[nodiscard]] bool hasObject() const {
        return !m_scene.objects.empty() && m_scene.objects[0].material != nullptr;
    }
    /// The painted volume of the (single) object, nullptr if none.
    [[nodiscard]] MaterialVolume* material() {
        return hasObject() ? m_scene.objects[0].material.get() : nullptr;
    }
    [[nodiscard]] const MaterialVolume* material() const {
        return hasObject() ? m_scene.objects[0].material.get() : nullptr;
    }
    [[nodiscard]] const TriangleMesh* mesh() const {
        return m_scene.objects.empty() ? nullptr : &m_scene.objects[0].mesh;
    }
    QUndoStack* undoStack() { return &m_undo; }
    [[nodiscard]] const History& history() const { return m_history; }
    /// Whether Edit ▸ Undo can go one step back. Not QUndoStack::canUndo: when the History's
    /// memory budget dropped its oldest strokes, the steps at and below the newest dropped one
    /// are out of reach (undoing them would change nothing, and a clean step among them would
    /// claim the volume is as saved when it is not).
    [[nodiscard]] bool canUndo() const { return m_undo.index() > m_undoFloor; }
    /// Undoes one step when canUndo(). What Edit ▸ Undo calls.
    void undo();
    /// Sets the History's memory cap (History::setBudgetBytes); strokes over it are dropped,
    /// oldest first, and so are the undo steps before them. @throw ValueError.
    void setHistoryBudget(size_t bytes);

    //! @{ \name Undoable material edits (engine Brush.h / Procedural.h operations)
    /// Opens a stroke. @throw ValueError for invalid brush settings.
    void beginStroke(const BrushSettings& brush);
    /// One stamp of the open stroke at `center` (mm). @return voxels touched.
    /// @param radiusScale, strengthScale factors in (0, 1] on the stroke's radius and strength
    ///        for this stamp (tablet pressure; 1 for the mouse).
    size_t strokeStamp(const Point3f& center, float radiusScale = 1.f, float strengthScale = 1.f);
    /// Closes the stroke; pushes one undo step if anything changed.
    void endStroke(const QString& label);
    [[nodiscard]] bool isStrokeOpen() const { return m_history.isStrokeOpen(); }
    void fill(const MaterialSample& value, ChannelMask channels);
    void fillProcedural(const ProceduralFill& fill);
    //! @}

    //! @{ \name Lights: undoable edits (gizmo drags, Lights dock)
    /// Replaces light `index` without an undo step, for live feedback while a gizmo is dragged;
    /// commitLights() records the whole drag afterwards. Emits sceneEdited.
    /// @throw ValueError when `index` is not a light of the scene.
    void setLightLive(int index, const Light& light);
    /// Records the change from `before` to the current lights as one undo step (the change is
    /// already applied). Nothing is recorded when the lights did not change.
    void commitLights(const std::vector<Light>& before, const QString& label);
    /// Replaces every light (edit, add, remove) as one undo step. Emits sceneEdited.
    void setLights(std::vector<Light> lights, const QString& label);
    /// Changes the type of light `index` (convertLight towards lightTarget()) as one undo step.
    /// @throw ValueError when `index` is not a light of the scene.
    void setLightType(int index, Light::Type type);
    /// Where new and converted lights aim: the object's bounding-box centre (mm) and its
    /// bounding-sphere radius (mm); the origin and 20 mm without a mesh.
    void lightTarget(Point3f& center, float& radius) const;
    //! @}

    /// Sets the relative index of refraction η of the scene and its material as one undo step.
    /// Emits sceneEdited. @throw ValueError unless 1 ≤ η ≤ 3 (the Lights dock's range).
    void setEta(float eta);

    /// Call after changing the camera (not undoable): marks the document modified.
    void noteSceneEdited();

Q_SIGNALS:
    void sceneReplaced();   ///< a new scene: meshes, volumes, lights all changed
    void materialEdited();  ///< voxels changed; the volume's dirty bricks say which
    void sceneEdited();     ///< lights / η / camera changed
    void modifiedChanged(bool modified);
    /// canUndo() may have changed.
    void undoAvailabilityChanged(bool canUndo);

private:
    void pushHistoryStep(const QString& label);
    /// Raises m_undoFloor above the paint steps whose strokes the History dropped.
    void followHistoryBudget();

    Scene m_scene;
    QString m_path;
    History m_history;
    BrushSettings m_strokeBrush;
    QUndoStack m_undo;
    /// QUndoStack index below which nothing can be undone (steps of dropped strokes).
    int m_undoFloor = 0;
    bool m_extraChanges = false;
};

}  // namespace lucent::app
