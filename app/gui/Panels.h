// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Dock panels: Tools (brush), Presets, Lights, Render settings, Statistics.
/// Each edits the Document / Viewport directly; values are in physical units (mm, mm⁻¹, W/sr).

#include <lucent/material/Medium.h>
#include <lucent/scene/Scene.h>

#include <QWidget>

#include <array>

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QListWidget;
class QPushButton;
class QRadioButton;
class QSpinBox;

namespace lucent::app {

class Document;
class Viewport;

/// Brush tool panel.
class BrushPanel : public QWidget {
    Q_OBJECT
public:
    BrushPanel(Document* doc, Viewport* viewport, QWidget* parent = nullptr);
    /// Shows `s` as the brush value (σt, σs′, g) and applies it to the viewport brush.
    void setBrushValue(const MaterialSample& s);
    /// Pushes every widget value into the viewport's brush.
    void apply();

private:
    void updateSwatch();
    Document* m_doc;
    Viewport* m_viewport;
    QRadioButton* m_paintTool;
    QRadioButton* m_eyedropTool;
    QDoubleSpinBox* m_radius;
    QDoubleSpinBox* m_depth;
    QComboBox* m_falloff;
    QDoubleSpinBox* m_strength;
    QDoubleSpinBox* m_spacing;
    QComboBox* m_mode;
    QCheckBox* m_chSigmaT;
    QCheckBox* m_chSigmaS;
    QCheckBox* m_chG;
    std::array<QDoubleSpinBox*, 3> m_sigmaT{};
    std::array<QDoubleSpinBox*, 3> m_sigmaS{};
    QDoubleSpinBox* m_g;
    QPushButton* m_swatch;
    QComboBox* m_pattern;
    QDoubleSpinBox* m_patternScale;
    QComboBox* m_pressure;
};

/// Material presets (Jensen et al. 2001 measured, plus artist presets).
class PresetPanel : public QWidget {
    Q_OBJECT
public:
    PresetPanel(Document* doc, BrushPanel* brush, QWidget* parent = nullptr);

private:
    Document* m_doc;
    QListWidget* m_list;
};

/// Lights and η of the scene. Light edits (fields, add, remove) are undo steps; the fields
/// follow gizmo drags and undo/redo (Document::sceneEdited).
class LightPanel : public QWidget {
    Q_OBJECT
public:
    explicit LightPanel(Document* doc, QWidget* parent = nullptr);
    /// Shows light `index` (−1: none) in the fields; emits currentLightChanged when it changes.
    void setCurrentLight(int index);
    [[nodiscard]] int currentLight() const;

Q_SIGNALS:
    void currentLightChanged(int index);

private:
    void syncList();
    enum class Field { Position, Direction, Intensity };
    void load();
    /// Writes component `c` of `field` of the current light (one undo step).
    void store(Field field, int c);
    void addLight(Light::Type type);
    Document* m_doc;
    QComboBox* m_light;
    QLabel* m_type;
    std::array<QDoubleSpinBox*, 3> m_pos{};
    std::array<QDoubleSpinBox*, 3> m_dir{};
    std::array<QDoubleSpinBox*, 3> m_intensity{};
    QPushButton* m_remove;
    QDoubleSpinBox* m_eta;
    bool m_loading = false;
};

/// Preview method and camera bookmarks.
class RenderPanel : public QWidget {
    Q_OBJECT
public:
    RenderPanel(Document* doc, Viewport* viewport, QWidget* parent = nullptr);
    /// Selects a preview method (index = RenderSettings::Method) as the combo box does.
    void setMethod(int method);

private:
    void apply();
    Viewport* m_viewport;
    QComboBox* m_method;
    QSpinBox* m_steps;
    QSpinBox* m_lightSteps;
    QDoubleSpinBox* m_exposure;
    QDoubleSpinBox* m_ambient;
    QCheckBox* m_turntable;
    QCheckBox* m_smooth;
    QComboBox* m_scale;
    QCheckBox* m_deform = nullptr;
    QComboBox* m_bookmarks;
    // SSLPV
    QComboBox* m_sslpvMode;
    QComboBox* m_sslpvGrid;
    QSpinBox* m_sslpvSteps;
    QComboBox* m_sslpvOrder;
    QComboBox* m_sslpvSolve;
    // Dipoles, directional dipole, combined
    QSpinBox* m_dipoleSpp;
    QSpinBox* m_dirpoleSpp;
    QDoubleSpinBox* m_splitRadius;
    QCheckBox* m_subsurfaceOnly;
    // Volume overlay
    QCheckBox* m_overlay;
    QComboBox* m_overlayChannel;
    QDoubleSpinBox* m_overlayOpacity;
};

/// Frame timings, upload sizes, GL state, volume and history sizes.
class StatsPanel : public QWidget {
    Q_OBJECT
public:
    StatsPanel(Document* doc, Viewport* viewport, QWidget* parent = nullptr);
    void refresh();

private:
    Document* m_doc;
    Viewport* m_viewport;
    QLabel* m_text;
};

}  // namespace lucent::app
