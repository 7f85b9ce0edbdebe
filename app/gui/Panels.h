// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Dock panels: Tools (brush), Presets, Lights, Render settings, Statistics.
/// Each edits the Document / Viewport directly; values are in physical units (mm, mm⁻¹, W/sr).

#include <lucent/material/Medium.h>
#include <lucent/material/Procedural.h>
#include <lucent/methods/Method.h>
#include <lucent/scene/Scene.h>

#include <QStringList>
#include <QWidget>

#include <array>
#include <map>
#include <string>
#include <vector>

class QCheckBox;
class QColor;
class QComboBox;
class QDoubleSpinBox;
class QFormLayout;
class QLabel;
class QListWidget;
class QPushButton;
class QRadioButton;
class QSettings;
class QSpinBox;
class QStackedWidget;

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
    /// Rescales the radius to 1/25 of the object's bounding-box diagonal when it is outside
    /// [1/200, 1/4] of it (called for every new scene). @return the radius, mm.
    double fitRadiusToObject();
    /// Multiplies the radius (mm) by `factor` (the [ and ] shortcuts), within its range.
    void scaleRadius(double factor);
    /// Selects the eyedropper (true) or the paint tool (false).
    void setEyedropper(bool on);
    /// The procedural fill the Fills fields describe (pattern, scale, octaves, seed, vein
    /// turbulence or layer thickness and jitter) from the base material to the brush value,
    /// on the brush's channels; what the Procedural fill button applies.
    [[nodiscard]] ProceduralFill proceduralFill() const;
    /// Screen pixels per mm at the depth of the camera's target (0 before the viewport has a
    /// size): the radius field in px is the radius in mm times this.
    [[nodiscard]] double pixelsPerMm() const;

private:
    void updateSwatch();
    void updateRadiusPx();
    /// σs′ fields limited to σt while the brush sets both in Set mode.
    void updateScatteringLimits();
    Document* m_doc;
    Viewport* m_viewport;
    QRadioButton* m_paintTool;
    QRadioButton* m_eyedropTool;
    QDoubleSpinBox* m_radius;
    QSpinBox* m_radiusPx;
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
    QSpinBox* m_octaves;
    QSpinBox* m_seed;
    QDoubleSpinBox* m_marbleAmplitude;
    QDoubleSpinBox* m_layerThickness;
    QDoubleSpinBox* m_layerJitter;
    QComboBox* m_pressure;
    QLabel* m_problem;  ///< why the brush cannot paint (brushProblem), hidden when it can
};

/// Preferences: saves the value of every named field of `panel` (spin boxes, combo boxes,
/// check boxes; widgets with an objectName) under `group` of `settings`. A combo box whose
/// entries carry names as item data (the method selector, choice parameters) is saved by that
/// name, so that a reordered list still maps.
void savePanelSettings(QWidget* panel, QSettings& settings, const QString& group);
/// Restores what savePanelSettings wrote, through the widgets (so their signals apply the
/// values); values out of a field's range are clamped by it, unknown entries are ignored.
void restorePanelSettings(QWidget* panel, QSettings& settings, const QString& group);

/// Material presets (Jensen et al. 2001 measured, plus artist presets).
class PresetPanel : public QWidget {
    Q_OBJECT
public:
    PresetPanel(Document* doc, BrushPanel* brush, QWidget* parent = nullptr);

private:
    Document* m_doc;
    QListWidget* m_list;
};

/// Lights and η of the scene. Light edits (fields, type, colour, add, remove) are undo steps;
/// the fields follow gizmo drags and undo/redo (Document::sceneEdited). Only the fields of the
/// current light's type are shown: position (point, spot, sphere), direction (spot,
/// directional), cone angles (spot), radius (sphere).
class LightPanel : public QWidget {
    Q_OBJECT
public:
    explicit LightPanel(Document* doc, QWidget* parent = nullptr);
    /// Shows light `index` (−1: none) in the fields; emits currentLightChanged when it changes.
    void setCurrentLight(int index);
    [[nodiscard]] int currentLight() const;
    /// Gives the current light the chromaticity of `colour` (one undo step): the intensity's
    /// largest channel is kept, the others follow the colour's ratios. What the Colour… button
    /// does after its dialog.
    void setCurrentLightColour(const QColor& colour);
    /// Whether the form row holding `field` is shown (for tests).
    [[nodiscard]] bool isFieldShown(QWidget* field) const;

Q_SIGNALS:
    void currentLightChanged(int index);

private:
    void syncList();
    enum class Field { Position, Direction, Intensity, SpotInner, SpotOuter, Radius };
    void load();
    /// Writes component `c` of `field` of the current light (one undo step).
    void store(Field field, int c);
    void addLight(Light::Type type);
    Document* m_doc;
    QFormLayout* m_form;
    QComboBox* m_light;
    QComboBox* m_type;
    std::array<QDoubleSpinBox*, 3> m_pos{};
    std::array<QDoubleSpinBox*, 3> m_dir{};
    std::array<QDoubleSpinBox*, 3> m_intensity{};
    QWidget* m_posRow;
    QWidget* m_dirRow;
    QWidget* m_intensityRow;
    QDoubleSpinBox* m_spotInner;
    QDoubleSpinBox* m_spotOuter;
    QDoubleSpinBox* m_radius;
    QPushButton* m_colour;
    QPushButton* m_remove;
    QDoubleSpinBox* m_eta;
    bool m_loading = false;
};

/// Preview method, its parameters and camera bookmarks. The method selector (Auto, then every
/// registered method with a GL pass) and each method's parameter fields are built from the
/// engine's registry (methods::MethodInfo, ParamDescriptor): one page of fields per method,
/// shown for the selected one.
class RenderPanel : public QWidget {
    Q_OBJECT
public:
    RenderPanel(Document* doc, Viewport* viewport, QWidget* parent = nullptr);
    /// Selects the preview method `name` (AUTO_METHOD or a registry name) as the selector does.
    /// @return false (nothing changes) when `name` is not a preview method.
    bool setMethod(const QString& name);
    /// Sets the selected method's field of parameter `param` to `value` as if typed (a choice's
    /// value, on/off, a number), which applies it. @return false (nothing changes) when the
    /// method has no such live field or the value does not fit it.
    bool setParam(const QString& param, const QString& value);
    /// The selected method's registry name.
    [[nodiscard]] QString method() const;
    /// The selector's label of method `name` (its MethodInfo::title; `name` if unknown).
    [[nodiscard]] static QString methodTitle(const QString& name);
    /// objectName of the field of parameter `param` of method `method` ("param.sslpv.grid"):
    /// the key of its saved preference, and how tests find it.
    [[nodiscard]] static QString paramFieldName(const QString& method, const QString& param);
    /// Auto's page shows the planner's reason for its choice (PreviewStats::autoReason).
    void setAutoPlan(const QString& reason);
    /// Camera bookmarks as text, one per entry: "name;target x;y;z (mm);distance (mm);yaw°;
    /// pitch°" (how MainWindow keeps them per project in QSettings).
    [[nodiscard]] QStringList bookmarks() const;
    /// Replaces the bookmarks; malformed entries are skipped.
    void setBookmarks(const QStringList& bookmarks);

Q_SIGNALS:
    /// A bookmark was saved or deleted by the user.
    void bookmarksChanged();

private:
    /// One parameter field of a method's page.
    struct ParamField {
        std::string name;          ///< ParamDescriptor::name
        std::string defaultValue;  ///< the live default (what the method takes when not given)
        QWidget* widget;           ///< QCheckBox, QSpinBox, QDoubleSpinBox or QComboBox
    };
    void apply();
    /// A page of fields for `info`'s live parameters (ParamScope Both and Live).
    QWidget* makeParamPage(const methods::MethodInfo& info);
    /// The values of `method`'s fields that differ from its live defaults.
    [[nodiscard]] methods::ParamSet paramsOf(const std::string& method) const;
    Viewport* m_viewport;
    QComboBox* m_method;
    QStackedWidget* m_paramPages;  ///< page i: the fields of the selector's entry i
    QLabel* m_autoPlan;            ///< Auto's page: the plan's reason
    std::map<std::string, std::vector<ParamField>> m_paramFields;  ///< by method name
    QDoubleSpinBox* m_exposure;
    QCheckBox* m_turntable;
    QComboBox* m_scale;
    QCheckBox* m_deform = nullptr;
    QComboBox* m_bookmarks;
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
