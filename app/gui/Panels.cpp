// SPDX-License-Identifier: MIT
/// @file
/// @brief Dock panels of the main window.

#include "Panels.h"

#include "Document.h"
#include "Viewport.h"

#include <lucent/core/Error.h>
#include <lucent/material/Presets.h>
#include <lucent/methods/Registry.h>

#include <QCheckBox>
#include <QColorDialog>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QListWidget>
#include <QMessageBox>
#include <QPushButton>
#include <QRadioButton>
#include <QSpinBox>
#include <QStackedWidget>
#include <QStandardItemModel>
#include <QStyle>
#include <QStyleOptionSpinBox>
#include <QVBoxLayout>

#include <QSettings>

#include <cmath>
#include <initializer_list>

namespace lucent::app {

namespace {

/// Smallest width of a spin box that shows `text` whole (what QAbstractSpinBox::
/// minimumSizeHint computes for its range's extremes, here for the shown text).
int spinWidthFor(const QAbstractSpinBox* s, const QString& text) {
    QStyleOptionSpinBox opt;
    opt.initFrom(s);
    opt.buttonSymbols = s->buttonSymbols();
    opt.frame = s->hasFrame();
    opt.subControls = QStyle::SC_SpinBoxFrame | QStyle::SC_SpinBoxEditField | QStyle::SC_SpinBoxUp |
                      QStyle::SC_SpinBoxDown;
    // + a space and 2 px for the cursor, as Qt's own hint.
    const QSize content(s->fontMetrics().horizontalAdvance(text + QLatin1Char(' ')) + 2,
                        s->sizeHint().height());
    return s->style()->sizeFromContents(QStyle::CT_SpinBox, &opt, content, s).width();
}

/// Keeps a spin box at least as wide as the value it shows (56 px at least), so that a value
/// like "100.00 mm" is never cut ("100.00 mn"). Narrow values keep fields narrow, so three RGB
/// fields still fit a slim dock; they grow with the dock.
void fitWidthToValue(QDoubleSpinBox* s) {
    s->setMinimumWidth(std::max(56, spinWidthFor(s, s->text())));
}

QDoubleSpinBox* spin(double lo, double hi, double value, int decimals, const QString& suffix,
                     double step = 0.1) {
    auto* s = new QDoubleSpinBox;
    s->setRange(lo, hi);
    s->setDecimals(decimals);
    s->setSingleStep(step);
    s->setValue(value);
    s->setSuffix(suffix);
    s->setKeyboardTracking(false);
    s->setSizePolicy(QSizePolicy::Ignored, QSizePolicy::Fixed);
    fitWidthToValue(s);
    QObject::connect(s, &QDoubleSpinBox::textChanged, s, [s] { fitWidthToValue(s); });
    return s;
}

QWidget* row(std::initializer_list<QWidget*> widgets) {
    auto* w = new QWidget;
    auto* l = new QHBoxLayout(w);
    l->setContentsMargins(0, 0, 0, 0);
    for (QWidget* x : widgets)
        l->addWidget(x);
    return w;
}

/// Dynamic property marking a named field that is not a preference (derived or a mode).
constexpr const char* TRANSIENT = "lucentTransient";
/// Property of a combo box whose preference is the current entry's item data (a name), not its
/// index (savePanelSettings).
constexpr const char* SAVED_BY_NAME = "lucentSavedByName";

void reportError(QWidget* parent, const QString& what, const std::exception& ex) {
    QMessageBox::warning(parent, what, QString::fromUtf8(ex.what()));
}

}  // namespace

// ---- BrushPanel -----------------------------------------------------------------------------

BrushPanel::BrushPanel(Document* doc, Viewport* viewport, QWidget* parent)
    : QWidget(parent), m_doc(doc), m_viewport(viewport) {
    auto* outer = new QVBoxLayout(this);
    auto* form = new QFormLayout;
    outer->addLayout(form);
    m_paintTool = new QRadioButton(tr("Paint"));
    m_paintTool->setObjectName(QStringLiteral("brushToolPaint"));
    m_eyedropTool = new QRadioButton(tr("Eyedropper"));
    m_eyedropTool->setObjectName(QStringLiteral("brushToolEyedropper"));
    m_paintTool->setChecked(true);
    form->addRow(tr("Tool"), row({m_paintTool, m_eyedropTool}));
    const BrushSettings defaults = startingBrush();
    m_radius = spin(0.01, 500.0, double(defaults.radius), 2, tr(" mm"), 0.5);
    m_depth = spin(0.0, 500.0, 0.0, 2, tr(" mm"), 0.5);
    m_falloff = new QComboBox;
    m_falloff->addItems({tr("Constant"), tr("Linear"), tr("Smooth"), tr("Gaussian")});
    m_falloff->setCurrentIndex(int(defaults.falloff));
    m_strength = spin(0.0, 1.0, double(defaults.strength), 2, QString(), 0.05);
    m_spacing = spin(BrushSettings::MIN_SPACING, BrushSettings::MAX_SPACING, defaults.spacing, 2,
                     tr(" × radius"), 0.05);
    m_mode = new QComboBox;
    m_mode->addItems(
        {tr("Set"), tr("Add"), tr("Subtract"), tr("Multiply"), tr("Smooth"), tr("Reset to base")});
    // The same radius on screen, at the depth of the camera's target (the orbit centre).
    m_radiusPx = new QSpinBox;
    m_radiusPx->setObjectName(QStringLiteral("brushRadiusPx"));
    m_radiusPx->setRange(1, 5000);
    m_radiusPx->setSuffix(tr(" px"));
    m_radiusPx->setKeyboardTracking(false);
    m_radiusPx->setProperty(TRANSIENT, true);  // derived from the radius in mm
    m_radiusPx->setToolTip(
        tr("Brush radius in screen pixels at the depth of the orbit centre; follows zooming."));
    form->addRow(tr("Radius"), row({m_radius, m_radiusPx}));
    form->addRow(tr("Depth below surface"), m_depth);
    form->addRow(tr("Falloff"), m_falloff);
    form->addRow(tr("Strength"), m_strength);
    form->addRow(tr("Spacing"), m_spacing);
    form->addRow(tr("Mode"), m_mode);
    m_pressure = new QComboBox;
    m_pressure->setObjectName(QStringLiteral("brushPressure"));
    // Order = PressureMode.
    m_pressure->addItems({tr("Off"), tr("Radius"), tr("Strength"), tr("Radius and strength")});
    m_pressure->setCurrentIndex(int(AppBrush{}.pressureMode));
    m_pressure->setToolTip(
        tr("What the pen pressure of a graphics tablet scales; the mouse paints at full "
           "pressure."));
    form->addRow(tr("Pen pressure →"), m_pressure);
    m_chSigmaT = new QCheckBox(QStringLiteral("σt"));
    m_chSigmaS = new QCheckBox(QStringLiteral("σs′"));
    m_chG = new QCheckBox(QStringLiteral("g"));
    for (QCheckBox* c : {m_chSigmaT, m_chSigmaS, m_chG})
        c->setChecked(true);
    form->addRow(tr("Channels"), row({m_chSigmaT, m_chSigmaS, m_chG}));
    for (int c = 0; c < 3; ++c) {
        m_sigmaT[size_t(c)] =
            spin(0.0, 1000.0, double(defaults.value.sigma_t[c]), 3, QString(), 0.1);
        m_sigmaS[size_t(c)] =
            spin(0.0, 1000.0, double(defaults.value.sigma_s[c]), 3, QString(), 0.1);
    }
    form->addRow(tr("σt R G B (mm⁻¹)"), row({m_sigmaT[0], m_sigmaT[1], m_sigmaT[2]}));
    form->addRow(tr("σs′ R G B (mm⁻¹)"), row({m_sigmaS[0], m_sigmaS[1], m_sigmaS[2]}));
    for (int c = 0; c < 3; ++c) {
        m_sigmaT[size_t(c)]->setToolTip(
            tr("Extinction σt: how much light the material takes out per mm (absorbed or "
               "scattered)."));
        m_sigmaS[size_t(c)]->setToolTip(
            tr("Scattering σs′: the part of σt that is scattered rather than absorbed; it cannot "
               "exceed σt when the brush sets both."));
    }
    m_g = spin(-double(G_MAX), double(G_MAX), double(defaults.value.g[0]), 2, QString(), 0.05);
    form->addRow(tr("g"), m_g);
    m_swatch = new QPushButton(tr("Albedo colour…"));
    m_swatch->setToolTip(
        tr("Pick the single-scattering albedo σs′/σt as a colour; σt is kept "
           "and σs′ = albedo × σt per channel."));
    form->addRow(tr("Albedo"), m_swatch);
    // Why the brush cannot paint, in words, where the fields are (empty and hidden when it can).
    m_problem = new QLabel;
    m_problem->setObjectName(QStringLiteral("brushProblem"));
    m_problem->setWordWrap(true);
    m_problem->setStyleSheet(QStringLiteral("color: #e06c5a"));
    m_problem->hide();
    form->addRow(m_problem);

    auto* fills = new QGroupBox(tr("Fills (undoable)"));
    auto* fl = new QFormLayout(fills);
    auto* fillButton = new QPushButton(tr("Fill interior with brush value"));
    fl->addRow(fillButton);
    m_pattern = new QComboBox;
    m_pattern->setObjectName(QStringLiteral("brushPattern"));
    // Order = ProceduralPattern.
    m_pattern->addItems({tr("Turbulence"), tr("Marble"), tr("Surface layer")});
    m_pattern->setToolTip(
        tr("Turbulence and Marble blend from the base material to the brush value; Surface "
           "layer puts the brush value in a layer of the given thickness under the surface, "
           "over the base."));
    const ProceduralFill fillDefaults;
    m_patternScale = spin(0.1, 1e4, double(fillDefaults.scale), 1, tr(" mm"), 1.0);
    m_patternScale->setToolTip(tr("Noise period"));
    m_octaves = new QSpinBox;
    m_octaves->setObjectName(QStringLiteral("brushPatternOctaves"));
    m_octaves->setRange(1, 12);
    m_octaves->setValue(fillDefaults.octaves);
    m_seed = new QSpinBox;
    m_seed->setObjectName(QStringLiteral("brushPatternSeed"));
    m_seed->setRange(1, 1000000);
    m_seed->setValue(int(fillDefaults.seed));
    m_marbleAmplitude = spin(0.0, 100.0, double(fillDefaults.amplitude), 2, tr(" rad"), 0.5);
    m_marbleAmplitude->setObjectName(QStringLiteral("brushMarbleAmplitude"));
    m_marbleAmplitude->setToolTip(tr("Marble: how far turbulence bends the veins"));
    m_layerThickness = spin(0.01, 1e4, 1.0, 2, tr(" mm"), 0.25);
    m_layerThickness->setObjectName(QStringLiteral("brushLayerThickness"));
    m_layerJitter = spin(0.0, 1e4, 0.0, 2, tr(" mm"), 0.1);
    m_layerJitter->setObjectName(QStringLiteral("brushLayerJitter"));
    m_layerJitter->setToolTip(tr("Surface layer: noise on the depth (± mm), at the noise scale"));
    auto* procButton = new QPushButton(tr("Procedural fill"));
    fl->addRow(tr("Pattern"), m_pattern);
    fl->addRow(tr("Scale"), m_patternScale);
    fl->addRow(tr("Octaves"), m_octaves);
    fl->addRow(tr("Seed"), m_seed);
    fl->addRow(tr("Vein turbulence"), m_marbleAmplitude);
    fl->addRow(tr("Layer thickness"), m_layerThickness);
    fl->addRow(tr("Depth jitter"), m_layerJitter);
    fl->addRow(procButton);
    // Only the fields of the chosen pattern.
    const auto showPatternFields = [this, fl] {
        const auto p = ProceduralPattern(m_pattern->currentIndex());
        const bool layered = p == ProceduralPattern::Layered;
        fl->setRowVisible(m_octaves, !layered);
        fl->setRowVisible(m_marbleAmplitude, p == ProceduralPattern::Marble);
        fl->setRowVisible(m_layerThickness, layered);
        fl->setRowVisible(m_layerJitter, layered);
    };
    connect(m_pattern, &QComboBox::currentIndexChanged, this, showPatternFields);
    showPatternFields();
    outer->addWidget(fills);
    outer->addStretch(1);

    m_patternScale->setObjectName(QStringLiteral("brushPatternScale"));
    fillButton->setObjectName(QStringLiteral("brushFill"));
    procButton->setObjectName(QStringLiteral("brushProceduralFill"));
    // Names for tests and the saved preferences (savePanelSettings).
    m_radius->setObjectName(QStringLiteral("brushRadius"));
    m_depth->setObjectName(QStringLiteral("brushDepth"));
    m_falloff->setObjectName(QStringLiteral("brushFalloff"));
    m_strength->setObjectName(QStringLiteral("brushStrength"));
    m_spacing->setObjectName(QStringLiteral("brushSpacing"));
    m_mode->setObjectName(QStringLiteral("brushMode"));
    m_chSigmaT->setObjectName(QStringLiteral("brushChannelSigmaT"));
    m_chSigmaS->setObjectName(QStringLiteral("brushChannelSigmaS"));
    m_chG->setObjectName(QStringLiteral("brushChannelG"));
    for (int c = 0; c < 3; ++c) {
        m_sigmaT[size_t(c)]->setObjectName(QStringLiteral("brushSigmaT%1").arg(c));
        m_sigmaS[size_t(c)]->setObjectName(QStringLiteral("brushSigmaS%1").arg(c));
    }
    m_g->setObjectName(QStringLiteral("brushG"));
    connect(m_radius, &QDoubleSpinBox::valueChanged, this, [this] { updateRadiusPx(); });
    connect(m_radiusPx, &QSpinBox::valueChanged, this, [this](int px) {
        const double perMm = pixelsPerMm();
        if (perMm > 0.0)
            m_radius->setValue(double(px) / perMm);
    });
    // Zooming changes the on-screen size of the same radius in mm.
    connect(m_viewport, &Viewport::frameRendered, this, [this] { updateRadiusPx(); });
    const auto applyLater = [this] { apply(); };
    for (QDoubleSpinBox* s : {m_radius, m_depth, m_strength, m_spacing, m_g})
        connect(s, &QDoubleSpinBox::valueChanged, this, applyLater);
    for (int c = 0; c < 3; ++c) {
        connect(m_sigmaT[size_t(c)], &QDoubleSpinBox::valueChanged, this, applyLater);
        connect(m_sigmaS[size_t(c)], &QDoubleSpinBox::valueChanged, this, applyLater);
    }
    for (QComboBox* c : {m_falloff, m_mode, m_pressure})
        connect(c, &QComboBox::currentIndexChanged, this, applyLater);
    for (QCheckBox* c : {m_chSigmaT, m_chSigmaS, m_chG})
        connect(c, &QCheckBox::toggled, this, applyLater);
    connect(m_paintTool, &QRadioButton::toggled, this, applyLater);
    connect(m_swatch, &QPushButton::clicked, this, [this] {
        const MaterialSample s = m_viewport->brush().engine.value;
        const Rgb a = reducedAlbedo(s);
        const QColor initial = QColor::fromRgbF(float(a.r), float(a.g), float(a.b));
        const QColor c = QColorDialog::getColor(initial, this, tr("Brush albedo σs′/σt"));
        if (!c.isValid())
            return;
        const float rgb[3] = {float(c.redF()), float(c.greenF()), float(c.blueF())};
        for (int i = 0; i < 3; ++i)
            m_sigmaS[size_t(i)]->setValue(double(rgb[i]) * m_sigmaT[size_t(i)]->value());
        apply();
    });
    // A new object (import, open, new): a brush out of proportion with it is rescaled.
    connect(m_doc, &Document::sceneReplaced, this, [this] { fitRadiusToObject(); });
    connect(m_viewport, &Viewport::eyedropped, this, [this](const MaterialSample& s) {
        setBrushValue(s);
        m_paintTool->setChecked(true);
    });
    connect(fillButton, &QPushButton::clicked, this, [this] {
        try {
            apply();
            m_doc->fill(m_viewport->brush().engine.value, m_viewport->brush().engine.channels);
        } catch (const std::exception& ex) {
            reportError(this, tr("Fill"), ex);
        }
    });
    connect(procButton, &QPushButton::clicked, this, [this] {
        try {
            apply();
            m_doc->fillProcedural(proceduralFill());
        } catch (const std::exception& ex) {
            reportError(this, tr("Procedural fill"), ex);
        }
    });
    apply();
}

ProceduralFill BrushPanel::proceduralFill() const {
    const AppBrush& b = m_viewport->brush();
    ProceduralFill f;
    f.pattern = ProceduralPattern(m_pattern->currentIndex());
    f.materialA = m_doc->material() ? m_doc->material()->base() : MaterialSample{};
    f.materialB = b.engine.value;
    f.scale = float(m_patternScale->value());
    f.octaves = m_octaves->value();
    f.seed = uint64_t(m_seed->value());
    f.channels = b.engine.channels;
    if (f.pattern == ProceduralPattern::Layered) {
        // The brush value from the surface down to the thickness, the base below (the last
        // layer extends inwards without end).
        f.layers = {MaterialLayer{float(m_layerThickness->value()), f.materialB},
                    MaterialLayer{1.f, f.materialA}};
        f.amplitude = float(m_layerJitter->value());
    } else if (f.pattern == ProceduralPattern::Marble) {
        f.amplitude = float(m_marbleAmplitude->value());
    }
    return f;
}

double BrushPanel::pixelsPerMm() const {
    // Perspective: a length r at distance D across the view spans r·H / (2·D·tan(fovY/2))
    // pixels of a view H pixels high.
    const OrbitCamera& c = m_viewport->camera();
    const double viewMm = 2.0 * double(c.distance) * std::tan(glm::radians(double(c.fovYDeg)) / 2);
    return viewMm > 0.0 ? double(m_viewport->height()) / viewMm : 0.0;
}

void BrushPanel::updateRadiusPx() {
    const QSignalBlocker block(m_radiusPx);
    m_radiusPx->setValue(int(std::lround(m_radius->value() * pixelsPerMm())));
}

double BrushPanel::fitRadiusToObject() {
    const TriangleMesh* mesh = m_doc->mesh();
    if (!mesh || mesh->isEmpty())
        return m_radius->value();
    const double diagonal = double(glm::length(mesh->bounds().extent()));
    const double radius = m_radius->value();
    // Kept between 1/200 and 1/4 of the object's diagonal (a radius the user may have chosen
    // for this object); otherwise 1/25 of it, two significant digits: 3 mm on a 75 mm object,
    // 0.16 mm on a 4 mm one (a 6 mm brush covered all of a Suzanne imported in mm).
    if (radius < diagonal / 200.0 || radius > diagonal / 4.0) {
        const double fitted = diagonal / 25.0;
        const double unit = std::pow(10.0, std::floor(std::log10(fitted)) - 1.0);
        m_radius->setValue(std::max(m_radius->minimum(), std::round(fitted / unit) * unit));
    }
    return m_radius->value();
}

void BrushPanel::scaleRadius(double factor) {
    m_radius->setValue(m_radius->value() * factor);
}

void BrushPanel::setEyedropper(bool on) {
    (on ? m_eyedropTool : m_paintTool)->setChecked(true);
}

void BrushPanel::setBrushValue(const MaterialSample& s) {
    for (int c = 0; c < 3; ++c) {
        const QSignalBlocker b1(m_sigmaT[size_t(c)]);
        m_sigmaT[size_t(c)]->setValue(double(s.sigma_t[c]));
    }
    updateScatteringLimits();  // before σs′: its limit follows the new σt
    for (int c = 0; c < 3; ++c) {
        const QSignalBlocker b2(m_sigmaS[size_t(c)]);
        m_sigmaS[size_t(c)]->setValue(double(s.sigma_s[c]));
    }
    QSignalBlocker b3(m_g);
    m_g->setValue(double((s.g.r + s.g.g + s.g.b) / 3.f));
    apply();
}

void BrushPanel::updateScatteringLimits() {
    // Set mode writing σt and σs′ needs σs′ ≤ σt per channel (the engine refuses the stroke
    // otherwise): the σs′ fields cannot go above σt, so the limit holds while typing (a larger
    // value is not accepted; lowering σt lowers σs′ with it). Other modes take amounts or
    // factors, which have no such bound.
    const bool setsBoth = BrushMode(m_mode->currentIndex()) == BrushMode::Set &&
                          m_chSigmaT->isChecked() && m_chSigmaS->isChecked();
    for (int c = 0; c < 3; ++c)
        m_sigmaS[size_t(c)]->setMaximum(setsBoth ? m_sigmaT[size_t(c)]->value() : 1000.0);
}

void BrushPanel::apply() {
    updateScatteringLimits();
    AppBrush& b = m_viewport->brush();
    b.engine.radius = float(m_radius->value());
    b.depthMm = float(m_depth->value());
    b.engine.falloff = Falloff(m_falloff->currentIndex());
    b.engine.strength = float(m_strength->value());
    b.engine.spacing = float(m_spacing->value());
    b.engine.mode = BrushMode(m_mode->currentIndex());
    b.pressureMode = PressureMode(m_pressure->currentIndex());
    b.engine.channels = ChannelMask((m_chSigmaT->isChecked() ? int(Channel::SigmaT) : 0) |
                                    (m_chSigmaS->isChecked() ? int(Channel::SigmaS) : 0) |
                                    (m_chG->isChecked() ? int(Channel::G) : 0));
    for (int c = 0; c < 3; ++c) {
        b.engine.value.sigma_t[c] = float(m_sigmaT[size_t(c)]->value());
        b.engine.value.sigma_s[c] = float(m_sigmaS[size_t(c)]->value());
    }
    b.engine.value.g = Rgb(float(m_g->value()));
    m_viewport->setTool(m_paintTool->isChecked() ? Viewport::Tool::Paint
                                                 : Viewport::Tool::Eyedropper);
    updateSwatch();
    const QString problem = brushProblem(b.engine);
    m_problem->setText(problem);
    m_problem->setVisible(!problem.isEmpty());
}

void BrushPanel::updateSwatch() {
    const Rgb a = reducedAlbedo(m_viewport->brush().engine.value);
    const QColor c = QColor::fromRgbF(std::clamp(a.r, 0.f, 1.f), std::clamp(a.g, 0.f, 1.f),
                                      std::clamp(a.b, 0.f, 1.f));
    m_swatch->setStyleSheet(QStringLiteral("background-color: %1; color: %2")
                                .arg(c.name(), c.lightnessF() > 0.5 ? "black" : "white"));
}

// ---- Preferences ----------------------------------------------------------------------------

namespace {
/// The named fields of `panel` that hold preferences.
template <class Fn>
void forEachPreference(QWidget* panel, Fn&& fn) {
    for (QWidget* w : panel->findChildren<QWidget*>()) {
        if (w->objectName().isEmpty() || w->property(TRANSIENT).toBool())
            continue;
        fn(w, w->objectName());
    }
}
}  // namespace

void savePanelSettings(QWidget* panel, QSettings& settings, const QString& group) {
    settings.beginGroup(group);
    forEachPreference(panel, [&settings](QWidget* w, const QString& key) {
        if (auto* d = qobject_cast<QDoubleSpinBox*>(w))
            settings.setValue(key, d->value());
        else if (auto* i = qobject_cast<QSpinBox*>(w))
            settings.setValue(key, i->value());
        else if (auto* c = qobject_cast<QComboBox*>(w))
            settings.setValue(key, c->property(SAVED_BY_NAME).toBool()
                                       ? QVariant(c->currentData().toString())
                                       : QVariant(c->currentIndex()));
        else if (auto* b = qobject_cast<QCheckBox*>(w))
            settings.setValue(key, b->isChecked());
    });
    settings.endGroup();
}

void restorePanelSettings(QWidget* panel, QSettings& settings, const QString& group) {
    settings.beginGroup(group);
    forEachPreference(panel, [&settings](QWidget* w, const QString& key) {
        const QVariant v = settings.value(key);
        bool ok = false;
        if (!v.isValid())
            return;
        if (auto* d = qobject_cast<QDoubleSpinBox*>(w)) {
            const double x = v.toDouble(&ok);
            if (ok && std::isfinite(x))
                d->setValue(x);
        } else if (auto* i = qobject_cast<QSpinBox*>(w)) {
            const int x = v.toInt(&ok);
            if (ok)
                i->setValue(x);
        } else if (auto* c = qobject_cast<QComboBox*>(w)) {
            const int x =
                c->property(SAVED_BY_NAME).toBool() ? c->findData(v.toString()) : v.toInt(&ok);
            ok = ok || x >= 0;
            // Only enabled entries (a method this build lacks stays unselectable).
            const auto* model = qobject_cast<const QStandardItemModel*>(c->model());
            if (ok && x >= 0 && x < c->count() &&
                (!model || !model->item(x) || model->item(x)->isEnabled()))
                c->setCurrentIndex(x);
        } else if (auto* b = qobject_cast<QCheckBox*>(w)) {
            b->setChecked(v.toBool());
        }
    });
    settings.endGroup();
}

// ---- PresetPanel ----------------------------------------------------------------------------

PresetPanel::PresetPanel(Document* doc, BrushPanel* brush, QWidget* parent)
    : QWidget(parent), m_doc(doc) {
    auto* layout = new QVBoxLayout(this);
    m_list = new QListWidget;
    for (const MaterialPreset& p : allPresets()) {
        auto* item = new QListWidgetItem(QString::fromStdString(p.name));
        item->setToolTip(QStringLiteral("σs′ = %1 %2 %3 mm⁻¹, σa = %4 %5 %6 mm⁻¹, η = %7\n%8")
                             .arg(double(p.sigma_s_reduced.r))
                             .arg(double(p.sigma_s_reduced.g))
                             .arg(double(p.sigma_s_reduced.b))
                             .arg(double(p.sigma_a.r))
                             .arg(double(p.sigma_a.g))
                             .arg(double(p.sigma_a.b))
                             .arg(double(p.eta))
                             .arg(QString::fromStdString(p.source)));
        m_list->addItem(item);
    }
    layout->addWidget(m_list);
    auto* toBrush = new QPushButton(tr("Use as brush value"));
    auto* toObject = new QPushButton(tr("Fill object with preset"));
    layout->addWidget(row({toBrush, toObject}));
    auto current = [this]() -> const MaterialPreset* {
        const int i = m_list->currentRow();
        return i >= 0 && i < int(allPresets().size()) ? &allPresets()[size_t(i)] : nullptr;
    };
    connect(toBrush, &QPushButton::clicked, this, [brush, current] {
        if (const MaterialPreset* p = current())
            brush->setBrushValue(p->sample());
    });
    connect(m_list, &QListWidget::itemDoubleClicked, this, [brush, current] {
        if (const MaterialPreset* p = current())
            brush->setBrushValue(p->sample());
    });
    connect(toObject, &QPushButton::clicked, this, [this, current] {
        const MaterialPreset* p = current();
        if (!p)
            return;
        try {
            m_doc->fill(p->sample(), ALL_CHANNELS);
        } catch (const std::exception& ex) {
            reportError(this, tr("Preset"), ex);
        }
    });
}

// ---- LightPanel -----------------------------------------------------------------------------

LightPanel::LightPanel(Document* doc, QWidget* parent) : QWidget(parent), m_doc(doc) {
    m_form = new QFormLayout(this);
    m_light = new QComboBox;
    m_light->setObjectName(QStringLiteral("lightList"));
    m_light->setToolTip(tr("Select a light here or click its handle in the viewport."));
    m_type = new QComboBox;
    m_type->setObjectName(QStringLiteral("lightType"));
    // Order = Light::Type.
    m_type->addItems({tr("Point"), tr("Spot"), tr("Directional"), tr("Sphere")});
    m_type->setToolTip(
        tr("Changing the type keeps the light's place and the irradiance it gives at the "
           "object's centre."));
    m_form->addRow(tr("Light"), m_light);
    m_form->addRow(tr("Type"), m_type);
    for (int c = 0; c < 3; ++c) {
        m_pos[size_t(c)] = spin(-1e5, 1e5, 0.0, 2, QString(), 1.0);
        m_pos[size_t(c)]->setObjectName(QStringLiteral("lightPos%1").arg(c));
        m_dir[size_t(c)] = spin(-1.0, 1.0, 0.0, 3, QString(), 0.05);
        m_dir[size_t(c)]->setObjectName(QStringLiteral("lightDir%1").arg(c));
        m_intensity[size_t(c)] = spin(0.0, 1e9, 0.0, 3, QString(), 10.0);
        m_intensity[size_t(c)]->setObjectName(QStringLiteral("lightIntensity%1").arg(c));
    }
    m_posRow = row({m_pos[0], m_pos[1], m_pos[2]});
    m_dirRow = row({m_dir[0], m_dir[1], m_dir[2]});
    m_intensityRow = row({m_intensity[0], m_intensity[1], m_intensity[2]});
    m_form->addRow(tr("Position x y z (mm)"), m_posRow);
    m_form->addRow(tr("Direction x y z"), m_dirRow);
    // Cone half-angles: intensity is full inside the inner one and falls to 0 at the outer one.
    m_spotInner = spin(0.0, 90.0, 25.0, 1, tr("°"), 1.0);
    m_spotInner->setObjectName(QStringLiteral("lightSpotInner"));
    m_spotOuter = spin(0.1, 90.0, 30.0, 1, tr("°"), 1.0);
    m_spotOuter->setObjectName(QStringLiteral("lightSpotOuter"));
    m_form->addRow(tr("Cone inner / outer"), row({m_spotInner, m_spotOuter}));
    m_radius = spin(0.001, 1e5, 1.0, 3, tr(" mm"), 0.5);
    m_radius->setObjectName(QStringLiteral("lightRadius"));
    m_form->addRow(tr("Radius"), m_radius);
    m_form->addRow(tr("Intensity R G B"), m_intensityRow);
    m_colour = new QPushButton(tr("Colour…"));
    m_colour->setObjectName(QStringLiteral("lightColour"));
    m_colour->setToolTip(tr("Pick the light's colour; the brightest channel keeps its intensity."));
    m_form->addRow(tr("Colour"), m_colour);
    auto* addPoint = new QPushButton(tr("Add point"));
    addPoint->setObjectName(QStringLiteral("lightAddPoint"));
    auto* addDirectional = new QPushButton(tr("Add directional"));
    addDirectional->setObjectName(QStringLiteral("lightAddDirectional"));
    auto* addSpot = new QPushButton(tr("Add spot"));
    addSpot->setObjectName(QStringLiteral("lightAddSpot"));
    auto* addSphere = new QPushButton(tr("Add sphere"));
    addSphere->setObjectName(QStringLiteral("lightAddSphere"));
    m_remove = new QPushButton(tr("Remove"));
    m_remove->setObjectName(QStringLiteral("lightRemove"));
    m_form->addRow(row({addPoint, addSpot}));
    m_form->addRow(row({addDirectional, addSphere}));
    m_form->addRow(m_remove);
    m_eta = spin(1.0, 3.0, 1.3, 3, QString(), 0.01);
    m_eta->setObjectName(QStringLiteral("lightEta"));
    m_form->addRow(tr("η (relative IOR)"), m_eta);
    connect(m_light, &QComboBox::currentIndexChanged, this, [this](int i) {
        load();
        if (!m_loading)
            Q_EMIT currentLightChanged(i);
    });
    connect(m_type, &QComboBox::currentIndexChanged, this, [this](int t) {
        const int i = m_light->currentIndex();
        if (m_loading || i < 0 || t < 0)
            return;
        m_doc->setLightType(i, Light::Type(t));
    });
    for (int c = 0; c < 3; ++c) {
        connect(m_pos[size_t(c)], &QDoubleSpinBox::valueChanged, this,
                [this, c] { store(Field::Position, c); });
        connect(m_dir[size_t(c)], &QDoubleSpinBox::valueChanged, this,
                [this, c] { store(Field::Direction, c); });
        connect(m_intensity[size_t(c)], &QDoubleSpinBox::valueChanged, this,
                [this, c] { store(Field::Intensity, c); });
    }
    connect(m_spotInner, &QDoubleSpinBox::valueChanged, this,
            [this] { store(Field::SpotInner, 0); });
    connect(m_spotOuter, &QDoubleSpinBox::valueChanged, this,
            [this] { store(Field::SpotOuter, 0); });
    connect(m_radius, &QDoubleSpinBox::valueChanged, this, [this] { store(Field::Radius, 0); });
    connect(m_colour, &QPushButton::clicked, this, [this] {
        const int i = m_light->currentIndex();
        const auto& lights = m_doc->scene().lights;
        if (i < 0 || i >= int(lights.size()))
            return;
        const Rgb v = lights[size_t(i)].intensity;
        const float peak = std::max({v.r, v.g, v.b});
        const QColor initial =
            peak > 0.f ? QColor::fromRgbF(v.r / peak, v.g / peak, v.b / peak) : QColor(Qt::white);
        const QColor c = QColorDialog::getColor(initial, this, tr("Light colour"));
        if (c.isValid())
            setCurrentLightColour(c);
    });
    connect(m_eta, &QDoubleSpinBox::valueChanged, this, [this] {
        if (m_loading)
            return;
        m_doc->setEta(float(m_eta->value()));
    });
    connect(addPoint, &QPushButton::clicked, this, [this] { addLight(Light::Type::Point); });
    connect(addSpot, &QPushButton::clicked, this, [this] { addLight(Light::Type::Spot); });
    connect(addDirectional, &QPushButton::clicked, this,
            [this] { addLight(Light::Type::Directional); });
    connect(addSphere, &QPushButton::clicked, this, [this] { addLight(Light::Type::Sphere); });
    connect(m_remove, &QPushButton::clicked, this, [this] {
        const int i = m_light->currentIndex();
        std::vector<Light> lights = m_doc->scene().lights;
        if (i < 0 || i >= int(lights.size()))
            return;
        lights.erase(lights.begin() + i);
        m_doc->setLights(std::move(lights), tr("Remove light %1").arg(i));
    });
    // Gizmo drags, undo/redo and other panels change the lights: follow them.
    connect(m_doc, &Document::sceneEdited, this, [this] {
        syncList();
        load();
    });
    connect(m_doc, &Document::sceneReplaced, this, [this] {
        syncList();
        load();
    });
    syncList();
    load();
}

int LightPanel::currentLight() const {
    return m_light->currentIndex();
}

void LightPanel::setCurrentLight(int index) {
    if (index >= 0 && index < m_light->count() && index != m_light->currentIndex())
        m_light->setCurrentIndex(index);
}

bool LightPanel::isFieldShown(QWidget* field) const {
    // The field itself or the row widget holding it (position, direction, cone angles).
    for (QWidget* w = field; w && w != this; w = w->parentWidget()) {
        int rowIndex = -1;
        QFormLayout::ItemRole role{};
        m_form->getWidgetPosition(w, &rowIndex, &role);
        if (rowIndex >= 0)
            return m_form->isRowVisible(rowIndex);
    }
    return false;
}

void LightPanel::setCurrentLightColour(const QColor& colour) {
    const int i = m_light->currentIndex();
    std::vector<Light> lights = m_doc->scene().lights;
    if (i < 0 || i >= int(lights.size()) || !colour.isValid())
        return;
    const Rgb c(float(colour.redF()), float(colour.greenF()), float(colour.blueF()));
    const float colourPeak = std::max({c.r, c.g, c.b});
    Light& l = lights[size_t(i)];
    const float peak = std::max({l.intensity.r, l.intensity.g, l.intensity.b});
    if (colourPeak <= 0.f)
        return;  // black would switch the light off: use the intensity fields for that
    // A light at 0 keeps 0: the colour alone does not make it shine.
    l.intensity = c * (peak / colourPeak);
    m_doc->setLights(std::move(lights), tr("Colour of light %1").arg(i));
}

void LightPanel::syncList() {
    const auto& lights = m_doc->scene().lights;
    const int n = int(lights.size());
    const bool countChanged = m_light->count() != n;
    const int previous = m_light->currentIndex();
    m_loading = true;
    if (countChanged) {
        m_light->clear();
        for (int i = 0; i < n; ++i)
            m_light->addItem(QString());
        m_light->setCurrentIndex(n == 0 ? -1 : std::clamp(previous, 0, n - 1));
    }
    // Names follow type changes, which keep the count.
    for (int i = 0; i < n; ++i)
        m_light->setItemText(i,
                             tr("L%1 (%2)").arg(i).arg(tr(lightTypeName(lights[size_t(i)].type))));
    m_loading = false;
    if (countChanged)
        Q_EMIT currentLightChanged(m_light->currentIndex());
}

void LightPanel::load() {
    const bool wasLoading = m_loading;
    m_loading = true;
    const auto& lights = m_doc->scene().lights;
    const int i = m_light->currentIndex();
    const bool valid = i >= 0 && i < int(lights.size());
    const Light::Type type = valid ? lights[size_t(i)].type : Light::Type::Point;
    const bool directed = valid && (type == Light::Type::Directional || type == Light::Type::Spot);
    const bool positioned = valid && type != Light::Type::Directional;
    m_form->setRowVisible(m_posRow, !valid || positioned);
    m_form->setRowVisible(m_dirRow, !valid || directed);
    m_form->setRowVisible(m_spotInner->parentWidget(), valid && type == Light::Type::Spot);
    m_form->setRowVisible(m_radius, valid && type == Light::Type::Sphere);
    for (int c = 0; c < 3; ++c) {
        m_pos[size_t(c)]->setEnabled(positioned);
        m_dir[size_t(c)]->setEnabled(directed);
        m_intensity[size_t(c)]->setEnabled(valid);
    }
    m_type->setEnabled(valid);
    m_colour->setEnabled(valid);
    m_remove->setEnabled(valid);
    // The intensity's unit depends on the type (Scene.h, Light::intensity).
    static const char* const units[] = {"W/sr", "W/sr", "W/mm²", "W/(mm²·sr)"};
    if (auto* label = qobject_cast<QLabel*>(m_form->labelForField(m_intensityRow)))
        label->setText(tr("Intensity R G B (%1)").arg(QString::fromUtf8(units[int(type)])));
    if (valid) {
        const Light& l = lights[size_t(i)];
        m_type->setCurrentIndex(int(l.type));
        for (int c = 0; c < 3; ++c) {
            m_pos[size_t(c)]->setValue(double(l.position[c]));
            m_dir[size_t(c)]->setValue(double(l.direction[c]));
            m_intensity[size_t(c)]->setValue(double(l.intensity[c]));
        }
        m_spotInner->setValue(double(l.spotInnerDeg));
        m_spotOuter->setValue(double(l.spotOuterDeg));
        m_radius->setValue(double(l.radius));
    } else {
        m_type->setCurrentIndex(-1);
    }
    m_eta->setValue(double(m_doc->scene().eta));
    m_loading = wasLoading;
}

void LightPanel::store(Field field, int c) {
    if (m_loading)
        return;
    std::vector<Light> lights = m_doc->scene().lights;
    const int i = m_light->currentIndex();
    if (i < 0 || i >= int(lights.size()))
        return;
    // Only the edited component changes: the others keep their full precision (the fields
    // show rounded values).
    Light& l = lights[size_t(i)];
    switch (field) {
        case Field::Position:
            l.position[c] = float(m_pos[size_t(c)]->value());
            break;
        case Field::Direction: {
            Vector3f dir = l.direction;
            dir[c] = float(m_dir[size_t(c)]->value());
            if (glm::length(dir) < 1e-6f)
                return;  // a zero direction is not a direction: keep the light as it was
            l.direction = glm::normalize(dir);
            break;
        }
        case Field::Intensity:
            l.intensity[c] = float(m_intensity[size_t(c)]->value());
            break;
        // The scene format needs 0 ≤ inner ≤ outer ≤ 90° (SceneFile, "spot"): the other angle
        // follows an edit that would cross it.
        case Field::SpotInner:
            l.spotInnerDeg = float(m_spotInner->value());
            l.spotOuterDeg = std::max(l.spotOuterDeg, l.spotInnerDeg);
            break;
        case Field::SpotOuter:
            l.spotOuterDeg = float(m_spotOuter->value());
            l.spotInnerDeg = std::min(l.spotInnerDeg, l.spotOuterDeg);
            break;
        case Field::Radius:
            l.radius = float(m_radius->value());
            break;
    }
    m_doc->setLights(std::move(lights), tr("Edit light %1").arg(i));
}

void LightPanel::addLight(Light::Type type) {
    std::vector<Light> lights = m_doc->scene().lights;
    Point3f center;
    float radius = 0.f;
    m_doc->lightTarget(center, radius);
    const float size = 2.f * radius;  // the object's diagonal (mm)
    Light l;
    if (type == Light::Type::Directional) {
        l.type = type;
        l.direction = glm::normalize(Vector3f(-0.3f, -1.f, -0.4f));  // from above, front right
        l.intensity = Rgb(1.f);                                      // W/mm²
    } else {
        l.type = Light::Type::Point;
        l.position = center + Vector3f(0.f, size, size);  // above and in front of the object
        // W/sr giving ≈ 1 W/mm² at the object: I / d², d = √2·size mm.
        l.intensity = Rgb(2.f * size * size);
        // Spot and sphere: the same place and irradiance at the object (aimed at it).
        l = convertLight(l, type, center, radius);
    }
    lights.push_back(l);
    const int index = int(lights.size()) - 1;
    m_doc->setLights(std::move(lights), tr("Add light"));
    setCurrentLight(index);
}

// ---- RenderPanel ----------------------------------------------------------------------------

RenderPanel::RenderPanel(Document* doc, Viewport* viewport, QWidget* parent)
    : QWidget(parent), m_viewport(viewport) {
    auto* form = new QFormLayout(this);
    const RenderSettings d;
    // The selector: every registered method with a GL pass, by registry name (item data), and
    // under it the selected method's parameter fields (one page per method).
    m_method = new QComboBox;
    m_method->setObjectName(QStringLiteral("renderMethod"));
    m_method->setProperty(SAVED_BY_NAME, true);
    m_paramPages = new QStackedWidget;
    m_paramPages->setSizePolicy(QSizePolicy::Preferred, QSizePolicy::Maximum);
    // Auto first: the planner picks a registry method for the scene (no fields of its own).
    m_method->addItem(tr("Auto"), QString::fromLatin1(AUTO_METHOD));
    m_method->setItemData(0,
                          tr("The planner chooses the method and its setting for the scene; the "
                             "status bar says why (docs/planner.md)."),
                          Qt::ToolTipRole);
    m_autoPlan = new QLabel(tr("The planner chooses the method for the scene."));
    m_autoPlan->setObjectName(QStringLiteral("renderAutoPlan"));
    m_autoPlan->setWordWrap(true);
    m_autoPlan->setAlignment(Qt::AlignTop | Qt::AlignLeft);
    m_autoPlan->setTextInteractionFlags(Qt::TextSelectableByMouse);
    m_paramPages->addWidget(m_autoPlan);
    for (const methods::MethodInfo* info : PreviewRenderer::previewMethods()) {
        m_method->addItem(QString::fromStdString(info->title), QString::fromStdString(info->name));
        m_method->setItemData(m_method->count() - 1,
                              QString::fromStdString(info->summary + " (" + info->docs + ")"),
                              Qt::ToolTipRole);
        m_paramPages->addWidget(makeParamPage(*info));
    }
    // The stack takes the height of the shown page only (a QStackedWidget's own hint is its
    // largest page's: the SSLPV fields left a tall gap under Auto's one line).
    connect(m_paramPages, &QStackedWidget::currentChanged, this, [this](int shown) {
        for (int i = 0; i < m_paramPages->count(); ++i)
            m_paramPages->widget(i)->setSizePolicy(
                QSizePolicy::Preferred, i == shown ? QSizePolicy::Preferred : QSizePolicy::Ignored);
        m_paramPages->adjustSize();
    });
    m_method->setCurrentIndex(std::max(0, m_method->findData(QString::fromStdString(d.method))));
    m_paramPages->setCurrentIndex(m_method->currentIndex());
    Q_EMIT m_paramPages->currentChanged(m_paramPages->currentIndex());
    m_method->setToolTip(
        tr("Subsurface method added to the direct lighting of gpu::SceneRenderer."));
    m_subsurfaceOnly = new QCheckBox(tr("Subsurface term only (debug)"));
    m_subsurfaceOnly->setObjectName(QStringLiteral("renderSubsurfaceOnly"));
    m_exposure = spin(-20.0, 20.0, double(d.exposureStops), 1, tr(" stops"), 0.5);
    m_turntable = new QCheckBox(tr("Turntable (30°/s)"));
    m_turntable->setObjectName(QStringLiteral("renderTurntable"));
    m_turntable->setProperty(TRANSIENT, true);  // an animation, not a preference
    m_exposure->setObjectName(QStringLiteral("renderExposure"));
    form->addRow(tr("Method"), m_method);
    form->addRow(m_paramPages);
    m_scale = new QComboBox;
    m_scale->setObjectName(QStringLiteral("renderScale"));
    m_scale->addItems({tr("Full"), tr("Half"), tr("Quarter")});
    m_scale->setCurrentIndex(d.resolutionScale >= 1.f ? 0 : d.resolutionScale >= 0.5f ? 1 : 2);
    m_scale->setToolTip(tr("Preview resolution; lower is faster on software OpenGL."));
    form->addRow(tr("Resolution"), m_scale);
    connect(m_scale, &QComboBox::currentIndexChanged, this, [this] { apply(); });
    connect(m_subsurfaceOnly, &QCheckBox::toggled, this, [this] { apply(); });
    // Volume overlay: the painted channel ray-marched over the viewport (seeing inside).
    m_overlay = new QCheckBox(tr("Volume overlay"));
    m_overlay->setObjectName(QStringLiteral("renderOverlay"));
    m_overlay->setToolTip(
        tr("Show a painted channel through the surface, colour-mapped as in "
           "the Material channels dock."));
    m_overlayChannel = new QComboBox;
    m_overlayChannel->setObjectName(QStringLiteral("renderOverlayChannel"));
    m_overlayChannel->addItems({QStringLiteral("σt"), QStringLiteral("σs′"), QStringLiteral("g")});
    m_overlayChannel->setCurrentIndex(d.overlayChannel);
    m_overlayOpacity = spin(0.0, 1.0, double(d.overlayOpacity), 2, QString(), 0.05);
    m_overlayOpacity->setObjectName(QStringLiteral("renderOverlayOpacity"));
    m_overlay->setChecked(d.volumeOverlay);
    m_overlayChannel->setToolTip(tr("Overlay channel"));
    m_overlayOpacity->setToolTip(tr("Overlay opacity"));
    form->addRow(row({m_overlay, m_overlayChannel, m_overlayOpacity}));
    connect(m_overlay, &QCheckBox::toggled, this, [this] { apply(); });
    connect(m_overlayChannel, &QComboBox::currentIndexChanged, this, [this] { apply(); });
    connect(m_overlayOpacity, &QDoubleSpinBox::valueChanged, this, [this] { apply(); });
    form->addRow(tr("Exposure"), m_exposure);
    form->addRow(m_turntable);
    form->addRow(m_subsurfaceOnly);
    m_deform = new QCheckBox(tr("Deformation animation (twist; pauses painting)"));
    m_deform->setObjectName(QStringLiteral("renderDeform"));
    m_deform->setProperty(TRANSIENT, true);  // an animation, not a preference
    form->addRow(m_deform);
    connect(m_deform, &QCheckBox::toggled, this, [this] { apply(); });
    m_bookmarks = new QComboBox;
    m_bookmarks->setObjectName(QStringLiteral("renderBookmarks"));
    m_bookmarks->setProperty(TRANSIENT, true);  // saved per project (MainWindow)
    auto* save = new QPushButton(tr("Save view"));
    save->setObjectName(QStringLiteral("renderBookmarkSave"));
    auto* go = new QPushButton(tr("Go"));
    go->setObjectName(QStringLiteral("renderBookmarkGo"));
    auto* remove = new QPushButton(tr("Delete"));
    remove->setObjectName(QStringLiteral("renderBookmarkDelete"));
    form->addRow(tr("Camera bookmarks"), m_bookmarks);
    form->addRow(row({save, go, remove}));
    connect(m_method, &QComboBox::currentIndexChanged, this, [this] { apply(); });
    connect(m_exposure, &QDoubleSpinBox::valueChanged, this, [this] { apply(); });
    connect(m_turntable, &QCheckBox::toggled, this, [this] { apply(); });
    connect(save, &QPushButton::clicked, this, [this] {
        const OrbitCamera& c = m_viewport->camera();
        // Names stay unique after deletions: one past the highest number in use.
        int next = 1;
        for (int i = 0; i < m_bookmarks->count(); ++i)
            next =
                std::max(next, m_bookmarks->itemText(i).section(QLatin1Char(' '), -1).toInt() + 1);
        m_bookmarks->addItem(
            tr("View %1").arg(next),
            QVariantList{double(c.target.x), double(c.target.y), double(c.target.z),
                         double(c.distance), double(c.yawDeg), double(c.pitchDeg)});
        m_bookmarks->setCurrentIndex(m_bookmarks->count() - 1);
        Q_EMIT bookmarksChanged();
    });
    connect(go, &QPushButton::clicked, this, [this] {
        const QVariantList v = m_bookmarks->currentData().toList();
        if (v.size() != 6)
            return;
        OrbitCamera& c = m_viewport->camera();
        c.target = Point3f(v[0].toFloat(), v[1].toFloat(), v[2].toFloat());
        c.distance = v[3].toFloat();
        c.yawDeg = v[4].toFloat();
        c.pitchDeg = v[5].toFloat();
        m_viewport->update();
    });
    connect(remove, &QPushButton::clicked, this, [this] {
        if (m_bookmarks->currentIndex() < 0)
            return;
        m_bookmarks->removeItem(m_bookmarks->currentIndex());
        Q_EMIT bookmarksChanged();
    });
    connect(doc, &Document::sceneReplaced, m_bookmarks, &QComboBox::clear);
    apply();
}

QWidget* RenderPanel::makeParamPage(const methods::MethodInfo& info) {
    auto* page = new QWidget;
    auto* form = new QFormLayout(page);
    form->setContentsMargins(0, 0, 0, 0);
    std::vector<ParamField>& fields = m_paramFields[info.name];
    const QString method = QString::fromStdString(info.name);
    for (const methods::ParamDescriptor& p : info.params) {
        if (p.scope == methods::ParamScope::Offline)
            continue;  // offline renders only (a progressive method's total sample count)
        const std::string& value = p.defaultFor(methods::Backend::Gl, /*live=*/true);
        QWidget* field = nullptr;
        switch (p.type) {
            case methods::ParamType::Bool: {
                auto* c = new QCheckBox;
                c->setChecked(value == "on");
                connect(c, &QCheckBox::toggled, this, [this] { apply(); });
                field = c;
                break;
            }
            case methods::ParamType::Int: {
                auto* i = new QSpinBox;
                constexpr double INT_LIMIT = 2147483647.0;
                i->setRange(int(std::max(p.min, -INT_LIMIT)), int(std::min(p.max, INT_LIMIT)));
                i->setValue(std::stoi(value));
                i->setKeyboardTracking(false);
                connect(i, &QSpinBox::valueChanged, this, [this] { apply(); });
                field = i;
                break;
            }
            case methods::ParamType::Float: {
                // 4 decimals: a hundredth of a micrometre for radii in mm, 1e-4 W/mm² for
                // irradiance; the descriptor's range is the field's.
                auto* f = spin(p.min, p.max, std::stod(value), 4, QString(), 0.1);
                connect(f, &QDoubleSpinBox::valueChanged, this, [this] { apply(); });
                field = f;
                break;
            }
            case methods::ParamType::Choice: {
                auto* c = new QComboBox;
                for (const std::string& choice : p.choices)
                    c->addItem(QString::fromStdString(choice), QString::fromStdString(choice));
                c->setCurrentIndex(std::max(0, c->findData(QString::fromStdString(value))));
                c->setProperty(SAVED_BY_NAME, true);
                connect(c, &QComboBox::currentIndexChanged, this, [this] { apply(); });
                field = c;
                break;
            }
        }
        field->setObjectName(paramFieldName(method, QString::fromStdString(p.name)));
        field->setToolTip(QString::fromStdString(p.help + " " + p.rangeText()));
        form->addRow(QString::fromStdString(p.name), field);
        fields.push_back({p.name, value, field});
    }
    if (fields.empty())
        form->addRow(new QLabel(tr("No parameters.")));
    return page;
}

methods::ParamSet RenderPanel::paramsOf(const std::string& method) const {
    methods::ParamSet given;
    const auto it = m_paramFields.find(method);
    if (it == m_paramFields.end())
        return given;
    for (const ParamField& f : it->second) {
        // Only what differs from the live default is given: a method may refuse a value that
        // does not apply (SSLPV's attenuation in calibrated mode) only when it was given.
        if (auto* d = qobject_cast<QDoubleSpinBox*>(f.widget)) {
            if (d->value() != std::stod(f.defaultValue))  // as numbers: "0" is "0.0000"
                given.set(f.name, d->value());
            continue;
        }
        std::string value;
        if (auto* c = qobject_cast<QCheckBox*>(f.widget))
            value = c->isChecked() ? "on" : "off";
        else if (auto* i = qobject_cast<QSpinBox*>(f.widget))
            value = std::to_string(i->value());
        else if (auto* c = qobject_cast<QComboBox*>(f.widget))
            value = c->currentData().toString().toStdString();
        if (value != f.defaultValue)
            given.set(f.name, value);
    }
    return given;
}

QString RenderPanel::methodTitle(const QString& name) {
    if (name == QLatin1String(AUTO_METHOD))
        return tr("Auto");
    const std::string n = name.toStdString();
    return methods::exists(n) ? QString::fromStdString(methods::find(n).title) : name;
}

QString RenderPanel::paramFieldName(const QString& method, const QString& param) {
    return QStringLiteral("param.%1.%2").arg(method, param);
}

void RenderPanel::setAutoPlan(const QString& reason) {
    m_autoPlan->setText(reason.isEmpty() ? tr("The planner chooses the method for the scene.")
                                         : tr("Running: %1").arg(reason));
}

QString RenderPanel::method() const {
    return m_method->currentData().toString();
}

void RenderPanel::apply() {
    RenderSettings s;
    m_paramPages->setCurrentIndex(m_method->currentIndex());
    s.method = method().toStdString();
    s.params = paramsOf(s.method);
    s.exposureStops = float(m_exposure->value());
    s.turntable = m_turntable->isChecked();
    s.deform = m_deform->isChecked();
    s.resolutionScale = m_scale->currentIndex() == 0   ? 1.f
                        : m_scale->currentIndex() == 1 ? 0.5f
                                                       : 0.25f;
    s.subsurfaceOnly = m_subsurfaceOnly->isChecked();
    s.volumeOverlay = m_overlay->isChecked();
    s.overlayChannel = m_overlayChannel->currentIndex();
    s.overlayOpacity = float(m_overlayOpacity->value());
    m_overlayChannel->setEnabled(s.volumeOverlay);
    m_overlayOpacity->setEnabled(s.volumeOverlay);
    // Direct draws no subsurface term: an opaque surface (its MethodInfo has no GL subsurface
    // pass to isolate).
    m_subsurfaceOnly->setEnabled(s.method != Viewport::FALLBACK_METHOD);
    m_viewport->setRenderSettings(s);
}

QStringList RenderPanel::bookmarks() const {
    QStringList out;
    for (int i = 0; i < m_bookmarks->count(); ++i) {
        QStringList fields{m_bookmarks->itemText(i)};
        for (const QVariant& v : m_bookmarks->itemData(i).toList())
            fields.push_back(QString::number(v.toDouble(), 'g', 9));  // float32 round trip
        out.push_back(fields.join(QLatin1Char(';')));
    }
    return out;
}

void RenderPanel::setBookmarks(const QStringList& bookmarks) {
    m_bookmarks->clear();
    for (const QString& b : bookmarks) {
        const QStringList fields = b.split(QLatin1Char(';'));
        if (fields.size() != 7)
            continue;  // not written by bookmarks(): ignored
        QVariantList values;
        bool ok = true;
        for (int i = 1; i < 7 && ok; ++i) {
            const double x = fields[i].toDouble(&ok);
            ok = ok && std::isfinite(x);
            values.push_back(x);
        }
        if (ok && values[3].toDouble() > 0.0)  // a positive orbit distance
            m_bookmarks->addItem(fields[0], values);
    }
}

bool RenderPanel::setMethod(const QString& name) {
    const int index = m_method->findData(name);
    if (index < 0)
        return false;
    m_method->setCurrentIndex(index);
    return true;
}

bool RenderPanel::setParam(const QString& param, const QString& value) {
    const auto it = m_paramFields.find(method().toStdString());
    if (it == m_paramFields.end())
        return false;
    for (const ParamField& f : it->second) {
        if (f.name != param.toStdString())
            continue;
        bool ok = true;
        if (auto* c = qobject_cast<QComboBox*>(f.widget)) {
            const int index = c->findData(value);
            if (index < 0)
                return false;
            c->setCurrentIndex(index);
        } else if (auto* b = qobject_cast<QCheckBox*>(f.widget)) {
            if (value != QStringLiteral("on") && value != QStringLiteral("off"))
                return false;
            b->setChecked(value == QStringLiteral("on"));
        } else if (auto* i = qobject_cast<QSpinBox*>(f.widget)) {
            const int v = value.toInt(&ok);
            if (!ok || v < i->minimum() || v > i->maximum())
                return false;
            i->setValue(v);
        } else if (auto* d = qobject_cast<QDoubleSpinBox*>(f.widget)) {
            const double v = value.toDouble(&ok);
            if (!ok || v < d->minimum() || v > d->maximum())
                return false;
            d->setValue(v);
        } else {
            return false;
        }
        return true;
    }
    return false;
}

// ---- StatsPanel -----------------------------------------------------------------------------

StatsPanel::StatsPanel(Document* doc, Viewport* viewport, QWidget* parent)
    : QWidget(parent), m_doc(doc), m_viewport(viewport) {
    auto* layout = new QVBoxLayout(this);
    m_text = new QLabel;
    m_text->setTextInteractionFlags(Qt::TextSelectableByMouse);
    m_text->setWordWrap(true);
    layout->addWidget(m_text);
    layout->addStretch(1);
    connect(viewport, &Viewport::frameRendered, this, &StatsPanel::refresh);
    refresh();
}

void StatsPanel::refresh() {
    if (!isVisible())
        return;
    const ViewportStats& s = m_viewport->stats();
    QString t;
    t += tr("<b>GL</b>: %1<br>").arg(s.initError.isEmpty() ? s.glRenderer : s.initError);
    t += tr("frame: %1 ms (%2 fps)<br>")
             .arg(s.frameMs, 0, 'f', 1)
             .arg(s.frameMs > 0 ? 1000.0 / s.frameMs : 0.0, 0, 'f', 1);
    if (s.hostMs > 0)
        t += tr("app per frame (event loop, swap): %1 ms<br>").arg(s.hostMs, 0, 'f', 1);
    t += tr("last upload: %1 bricks in %2 ms<br>").arg(s.bricksUploaded).arg(s.uploadMs, 0, 'f', 2);
    t += tr("frames: %1, GL errors: %2<br>").arg(s.frames).arg(s.glErrors);
    if (!s.renderError.isEmpty())
        t += tr("<b>last render error</b> (%1 frames failed): %2<br>")
                 .arg(s.renderErrors)
                 .arg(s.renderError.toHtmlEscaped());
    for (const PreviewStats::Pass& p : s.preview.passes)
        t += tr("&nbsp;&nbsp;%1: %2 ms GPU, %3 ms CPU<br>")
                 .arg(QString::fromStdString(p.name))
                 .arg(p.gpuMs, 0, 'f', 2)
                 .arg(p.cpuMs, 0, 'f', 2);
    for (const std::string& skipped : s.preview.skippedLights)
        t += tr("skipped %1<br>").arg(QString::fromStdString(skipped).toHtmlEscaped());
    if (!s.preview.autoReason.empty())
        t += tr("<b>Auto</b>: %1<br>live costs: %2<br>")
                 .arg(QString::fromStdString(s.preview.autoReason).toHtmlEscaped(),
                      QString::fromStdString(s.preview.liveCosts).toHtmlEscaped());
    if (!s.preview.method.empty()) {
        t += tr("<b>%1</b><br>")
                 .arg(RenderPanel::methodTitle(QString::fromStdString(s.preview.method)));
        for (const methods::Stat& stat : s.preview.methodStats)
            t += QStringLiteral("&nbsp;&nbsp;%1: %2<br>")
                     .arg(QString::fromStdString(stat.key).toHtmlEscaped(),
                          QString::fromStdString(stat.value).toHtmlEscaped());
    }
    if (const MaterialVolume* v = m_doc->material())
        t += tr("volume: %1^3 voxels of %2 mm<br>")
                 .arg(v->resolution())
                 .arg(double(v->spec().voxelSize), 0, 'g', 3);
    if (const TriangleMesh* m = m_doc->mesh())
        t += tr("mesh: %1 triangles<br>").arg(m->triangleCount());
    t += tr("undo: %1 steps, %2 MiB")
             .arg(m_doc->history().undoCount())
             .arg(double(m_doc->history().bytesUsed()) / (1024.0 * 1024.0), 0, 'f', 1);
    m_text->setText(t);
}

}  // namespace lucent::app
