// SPDX-License-Identifier: MIT
/// @file
/// @brief Dock panels of the main window.

#include "Panels.h"

#include "Document.h"
#include "Viewport.h"

#include <lucent/core/Error.h>
#include <lucent/material/Presets.h>

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
#include <QStandardItemModel>
#include <QVBoxLayout>

#include <initializer_list>

namespace lucent::app {

namespace {

QDoubleSpinBox* spin(double lo, double hi, double value, int decimals, const QString& suffix,
                     double step = 0.1) {
    auto* s = new QDoubleSpinBox;
    s->setRange(lo, hi);
    s->setDecimals(decimals);
    s->setSingleStep(step);
    s->setValue(value);
    s->setSuffix(suffix);
    s->setKeyboardTracking(false);
    // Narrow by default so three RGB fields fit a slim dock; they grow with the dock.
    s->setMinimumWidth(56);
    s->setSizePolicy(QSizePolicy::Ignored, QSizePolicy::Fixed);
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
    m_eyedropTool = new QRadioButton(tr("Eyedropper"));
    m_paintTool->setChecked(true);
    form->addRow(tr("Tool"), row({m_paintTool, m_eyedropTool}));
    const BrushSettings defaults;
    m_radius = spin(0.05, 500.0, 3.0, 2, tr(" mm"), 0.5);
    m_depth = spin(0.0, 500.0, 0.0, 2, tr(" mm"), 0.5);
    m_falloff = new QComboBox;
    m_falloff->addItems({tr("Constant"), tr("Linear"), tr("Smooth"), tr("Gaussian")});
    m_falloff->setCurrentIndex(int(defaults.falloff));
    m_strength = spin(0.0, 1.0, 0.5, 2, QString(), 0.05);
    m_spacing = spin(BrushSettings::MIN_SPACING, BrushSettings::MAX_SPACING, defaults.spacing, 2,
                     tr(" × radius"), 0.05);
    m_mode = new QComboBox;
    m_mode->addItems(
        {tr("Set"), tr("Add"), tr("Subtract"), tr("Multiply"), tr("Smooth"), tr("Reset to base")});
    form->addRow(tr("Radius"), m_radius);
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
        m_sigmaT[size_t(c)] = spin(0.0, 1000.0, 1.0, 3, QString(), 0.1);
        m_sigmaS[size_t(c)] = spin(0.0, 1000.0, 0.8, 3, QString(), 0.1);
    }
    form->addRow(tr("σt R G B (mm⁻¹)"), row({m_sigmaT[0], m_sigmaT[1], m_sigmaT[2]}));
    form->addRow(tr("σs′ R G B (mm⁻¹)"), row({m_sigmaS[0], m_sigmaS[1], m_sigmaS[2]}));
    m_g = spin(-double(G_MAX), double(G_MAX), 0.0, 2, QString(), 0.05);
    form->addRow(tr("g"), m_g);
    m_swatch = new QPushButton(tr("Albedo colour…"));
    m_swatch->setToolTip(
        tr("Pick the single-scattering albedo σs′/σt as a colour; σt is kept "
           "and σs′ = albedo × σt per channel."));
    form->addRow(tr("Albedo"), m_swatch);

    auto* fills = new QGroupBox(tr("Fills (undoable)"));
    auto* fl = new QFormLayout(fills);
    auto* fillButton = new QPushButton(tr("Fill interior with brush value"));
    fl->addRow(fillButton);
    m_pattern = new QComboBox;
    m_pattern->addItems({tr("Turbulence"), tr("Marble")});
    m_patternScale = spin(0.1, 1e4, 10.0, 1, tr(" mm"), 1.0);
    auto* procButton = new QPushButton(tr("Procedural fill (base → brush)"));
    fl->addRow(tr("Pattern"), m_pattern);
    fl->addRow(tr("Scale"), m_patternScale);
    fl->addRow(procButton);
    outer->addWidget(fills);
    outer->addStretch(1);

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
            ProceduralFill f;
            f.pattern = m_pattern->currentIndex() == 0 ? ProceduralPattern::Turbulence
                                                       : ProceduralPattern::Marble;
            f.materialA = m_doc->material() ? m_doc->material()->base() : MaterialSample{};
            f.materialB = m_viewport->brush().engine.value;
            f.scale = float(m_patternScale->value());
            f.channels = m_viewport->brush().engine.channels;
            m_doc->fillProcedural(f);
        } catch (const std::exception& ex) {
            reportError(this, tr("Procedural fill"), ex);
        }
    });
    apply();
}

void BrushPanel::setBrushValue(const MaterialSample& s) {
    for (int c = 0; c < 3; ++c) {
        QSignalBlocker b1(m_sigmaT[size_t(c)]), b2(m_sigmaS[size_t(c)]);
        m_sigmaT[size_t(c)]->setValue(double(s.sigma_t[c]));
        m_sigmaS[size_t(c)]->setValue(double(s.sigma_s[c]));
    }
    QSignalBlocker b3(m_g);
    m_g->setValue(double((s.g.r + s.g.g + s.g.b) / 3.f));
    apply();
}

void BrushPanel::apply() {
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
        // In Set mode σs′ ≤ σt is what the material allows; show the clamp in the fields.
        b.engine.value.sigma_s[c] = float(m_sigmaS[size_t(c)]->value());
    }
    b.engine.value.g = Rgb(float(m_g->value()));
    m_viewport->setTool(m_paintTool->isChecked() ? Viewport::Tool::Paint
                                                 : Viewport::Tool::Eyedropper);
    updateSwatch();
}

void BrushPanel::updateSwatch() {
    const Rgb a = reducedAlbedo(m_viewport->brush().engine.value);
    const QColor c = QColor::fromRgbF(std::clamp(a.r, 0.f, 1.f), std::clamp(a.g, 0.f, 1.f),
                                      std::clamp(a.b, 0.f, 1.f));
    m_swatch->setStyleSheet(QStringLiteral("background-color: %1; color: %2")
                                .arg(c.name(), c.lightnessF() > 0.5 ? "black" : "white"));
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
    auto* form = new QFormLayout(this);
    m_light = new QComboBox;
    m_light->setToolTip(tr("Select a light here or click its handle in the viewport."));
    m_type = new QLabel;
    form->addRow(tr("Light"), m_light);
    form->addRow(tr("Type"), m_type);
    for (int c = 0; c < 3; ++c) {
        m_pos[size_t(c)] = spin(-1e5, 1e5, 0.0, 2, QString(), 1.0);
        m_pos[size_t(c)]->setObjectName(QStringLiteral("lightPos%1").arg(c));
        m_dir[size_t(c)] = spin(-1.0, 1.0, 0.0, 3, QString(), 0.05);
        m_dir[size_t(c)]->setObjectName(QStringLiteral("lightDir%1").arg(c));
        m_intensity[size_t(c)] = spin(0.0, 1e9, 0.0, 3, QString(), 10.0);
    }
    form->addRow(tr("Position x y z (mm)"), row({m_pos[0], m_pos[1], m_pos[2]}));
    form->addRow(tr("Direction x y z"), row({m_dir[0], m_dir[1], m_dir[2]}));
    form->addRow(tr("Intensity R G B"), row({m_intensity[0], m_intensity[1], m_intensity[2]}));
    form->addRow(new QLabel(tr("Units: point/spot W/sr, directional W/mm², sphere W/(mm²·sr)")));
    auto* addPoint = new QPushButton(tr("Add point"));
    auto* addDirectional = new QPushButton(tr("Add directional"));
    addDirectional->setObjectName(QStringLiteral("lightAddDirectional"));
    m_remove = new QPushButton(tr("Remove"));
    form->addRow(row({addPoint, addDirectional, m_remove}));
    m_eta = spin(1.0, 3.0, 1.3, 3, QString(), 0.01);
    form->addRow(tr("η (relative IOR)"), m_eta);
    connect(m_light, &QComboBox::currentIndexChanged, this, [this](int i) {
        load();
        if (!m_loading)
            Q_EMIT currentLightChanged(i);
    });
    for (int c = 0; c < 3; ++c) {
        connect(m_pos[size_t(c)], &QDoubleSpinBox::valueChanged, this,
                [this, c] { store(Field::Position, c); });
        connect(m_dir[size_t(c)], &QDoubleSpinBox::valueChanged, this,
                [this, c] { store(Field::Direction, c); });
        connect(m_intensity[size_t(c)], &QDoubleSpinBox::valueChanged, this,
                [this, c] { store(Field::Intensity, c); });
    }
    connect(m_eta, &QDoubleSpinBox::valueChanged, this, [this] {
        if (m_loading)
            return;
        m_doc->scene().eta = float(m_eta->value());
        if (MaterialVolume* v = m_doc->material())
            v->setEta(float(m_eta->value()));
        m_doc->noteSceneEdited();
    });
    connect(addPoint, &QPushButton::clicked, this, [this] { addLight(Light::Type::Point); });
    connect(addDirectional, &QPushButton::clicked, this,
            [this] { addLight(Light::Type::Directional); });
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

void LightPanel::syncList() {
    const int n = int(m_doc->scene().lights.size());
    if (m_light->count() == n)
        return;
    const int previous = m_light->currentIndex();
    m_loading = true;
    m_light->clear();
    for (int i = 0; i < n; ++i)
        m_light->addItem(tr("Light %1").arg(i));
    m_light->setCurrentIndex(n == 0 ? -1 : std::clamp(previous, 0, n - 1));
    m_loading = false;
    Q_EMIT currentLightChanged(m_light->currentIndex());
}

void LightPanel::load() {
    const bool wasLoading = m_loading;
    m_loading = true;
    const auto& lights = m_doc->scene().lights;
    const int i = m_light->currentIndex();
    const bool valid = i >= 0 && i < int(lights.size());
    const bool directed = valid && (lights[size_t(i)].type == Light::Type::Directional ||
                                    lights[size_t(i)].type == Light::Type::Spot);
    const bool positioned = valid && lights[size_t(i)].type != Light::Type::Directional;
    for (int c = 0; c < 3; ++c) {
        m_pos[size_t(c)]->setEnabled(positioned);
        m_dir[size_t(c)]->setEnabled(directed);
        m_intensity[size_t(c)]->setEnabled(valid);
    }
    m_remove->setEnabled(valid);
    if (valid) {
        const Light& l = lights[size_t(i)];
        static const char* names[] = {"point", "spot", "directional", "sphere"};
        m_type->setText(QString::fromLatin1(names[int(l.type)]));
        for (int c = 0; c < 3; ++c) {
            m_pos[size_t(c)]->setValue(double(l.position[c]));
            m_dir[size_t(c)]->setValue(double(l.direction[c]));
            m_intensity[size_t(c)]->setValue(double(l.intensity[c]));
        }
    } else {
        m_type->setText(tr("(no lights)"));
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
    }
    m_doc->setLights(std::move(lights), tr("Edit light %1").arg(i));
}

void LightPanel::addLight(Light::Type type) {
    std::vector<Light> lights = m_doc->scene().lights;
    Light l;
    l.type = type;
    const TriangleMesh* mesh = m_doc->mesh();
    const Bounds3f b = mesh && !mesh->isEmpty() ? mesh->bounds() : Bounds3f{};
    const Point3f c = mesh && !mesh->isEmpty() ? b.center() : Point3f(0.f);
    const float size = mesh && !mesh->isEmpty() ? glm::length(b.extent()) : 40.f;
    if (type == Light::Type::Directional) {
        l.direction = glm::normalize(Vector3f(-0.3f, -1.f, -0.4f));  // from above, front right
        l.intensity = Rgb(1.f);                                      // W/mm²
    } else {
        l.position = c + Vector3f(0.f, size, size);  // above and in front of the object
        // W/sr giving ≈ 1 W/mm² at the object: I / d², d = √2·size mm.
        l.intensity = Rgb(2.f * size * size);
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
    m_method = new QComboBox;
    // Order = RenderSettings::Method.
    m_method->setObjectName(QStringLiteral("renderMethod"));
    m_method->addItems({tr("Direct (opaque surface)"), tr("Single scattering (ray-marched)"),
                        tr("SSLPV (live translucency)"), tr("Dipole (progressive)"),
                        tr("Better dipole (progressive)"), tr("Directional dipole (progressive)"),
                        tr("Combined (dipole + SSLPV)")});
    // Methods this build lacks stay listed (indices = RenderSettings::Method) but disabled.
    if (auto* model = qobject_cast<QStandardItemModel*>(m_method->model()))
        for (int i = 0; i < m_method->count(); ++i)
            if (!PreviewRenderer::hasMethod(RenderSettings::Method(i))) {
                model->item(i)->setEnabled(false);
                model->item(i)->setToolTip(tr("Not available in this build"));
            }
    m_method->setCurrentIndex(int(d.method));
    m_method->setToolTip(
        tr("Subsurface method added to the direct lighting of gpu::SceneRenderer."));
    m_sslpvMode = new QComboBox;
    m_sslpvMode->addItems({tr("Paper"), tr("Calibrated")});
    m_sslpvMode->setCurrentIndex(d.sslpvCalibrated ? 1 : 0);
    m_sslpvGrid = new QComboBox;
    m_sslpvGrid->addItems({QStringLiteral("16³"), QStringLiteral("32³"), QStringLiteral("64³")});
    m_sslpvGrid->setCurrentIndex(d.sslpvGrid <= 16 ? 0 : d.sslpvGrid <= 32 ? 1 : 2);
    m_sslpvSteps = new QSpinBox;
    m_sslpvSteps->setRange(1, 512);
    m_sslpvSteps->setValue(d.sslpvSteps);
    m_sslpvOrder = new QComboBox;
    m_sslpvOrder->addItems({tr("1 (4 coefficients)"), tr("2 (9 coefficients)")});
    m_sslpvOrder->setCurrentIndex(d.sslpvOrder == 2 ? 1 : 0);
    m_sslpvSolve = new QComboBox;
    m_sslpvSolve->addItems({tr("CPU"), tr("GPU (GL compute)")});
    m_sslpvSolve->setCurrentIndex(d.sslpvGlSolve ? 1 : 0);
    m_dipoleSpp = new QSpinBox;
    m_dipoleSpp->setRange(1, 4096);
    m_dipoleSpp->setValue(d.dipoleSpp);
    m_dipoleSpp->setToolTip(
        tr("Samples per pixel added each frame; refinement goes on while idle."));
    m_dirpoleSpp = new QSpinBox;
    m_dirpoleSpp->setObjectName(QStringLiteral("renderDirpoleSpp"));
    m_dirpoleSpp->setRange(1, 4096);
    m_dirpoleSpp->setValue(d.dirpoleSpp);
    m_dirpoleSpp->setToolTip(
        tr("Directional dipole: disc samples per texel added each frame; "
           "refinement goes on while idle."));
    m_splitRadius = spin(-1.0, 500.0, double(d.combinedSplitRadius), 2, tr(" mm"), 0.5);
    m_splitRadius->setObjectName(QStringLiteral("renderSplitRadius"));
    m_splitRadius->setSpecialValueText(tr("Auto (4 SSLPV cells)"));  // shown at −1
    m_splitRadius->setToolTip(
        tr("Combined: the dipole gathers light that entered within this "
           "radius; SSLPV carries what travels further."));
    m_subsurfaceOnly = new QCheckBox(tr("Subsurface term only (debug)"));
    m_steps = new QSpinBox;
    m_steps->setRange(1, 512);
    m_steps->setValue(d.steps);
    m_lightSteps = new QSpinBox;
    m_lightSteps->setRange(1, 128);
    m_lightSteps->setValue(d.lightSteps);
    m_exposure = spin(-20.0, 20.0, double(d.exposureStops), 1, tr(" stops"), 0.5);
    m_ambient = spin(0.0, 1e6, double(d.ambient), 4, tr(" W/mm²"), 0.001);
    m_turntable = new QCheckBox(tr("Turntable (30°/s)"));
    m_smooth = new QCheckBox(tr("Smooth voxels (trilinear, display only)"));
    form->addRow(tr("Method"), m_method);
    m_scale = new QComboBox;
    m_scale->addItems({tr("Full"), tr("Half"), tr("Quarter")});
    m_scale->setCurrentIndex(d.resolutionScale >= 1.f ? 0 : d.resolutionScale >= 0.5f ? 1 : 2);
    m_scale->setToolTip(tr("Preview resolution; lower is faster on software OpenGL."));
    form->addRow(tr("Resolution"), m_scale);
    connect(m_scale, &QComboBox::currentIndexChanged, this, [this] { apply(); });
    form->addRow(tr("SSLPV mode"), m_sslpvMode);
    form->addRow(tr("SSLPV grid"), m_sslpvGrid);
    form->addRow(tr("SSLPV steps"), m_sslpvSteps);
    form->addRow(tr("SSLPV SH order"), m_sslpvOrder);
    form->addRow(tr("SSLPV solve"), m_sslpvSolve);
    form->addRow(tr("Dipole spp/frame"), m_dipoleSpp);
    form->addRow(tr("Dirpole spp/frame"), m_dirpoleSpp);
    form->addRow(tr("Split radius"), m_splitRadius);
    for (QComboBox* c : {m_sslpvMode, m_sslpvGrid, m_sslpvOrder, m_sslpvSolve})
        connect(c, &QComboBox::currentIndexChanged, this, [this] { apply(); });
    connect(m_sslpvSteps, &QSpinBox::valueChanged, this, [this] { apply(); });
    connect(m_dipoleSpp, &QSpinBox::valueChanged, this, [this] { apply(); });
    connect(m_dirpoleSpp, &QSpinBox::valueChanged, this, [this] { apply(); });
    connect(m_splitRadius, &QDoubleSpinBox::valueChanged, this, [this] { apply(); });
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
    form->addRow(tr("View steps"), m_steps);
    form->addRow(tr("Shadow steps"), m_lightSteps);
    form->addRow(tr("Exposure"), m_exposure);
    form->addRow(tr("Ambient"), m_ambient);
    form->addRow(m_turntable);
    form->addRow(m_smooth);
    form->addRow(m_subsurfaceOnly);
    if (Viewport::hasDeformation()) {
        m_deform = new QCheckBox(tr("Deformation animation (twist; pauses painting)"));
        form->addRow(m_deform);
        connect(m_deform, &QCheckBox::toggled, this, [this] { apply(); });
    }
    m_bookmarks = new QComboBox;
    auto* save = new QPushButton(tr("Save view"));
    auto* go = new QPushButton(tr("Go"));
    form->addRow(tr("Camera bookmarks"), row({m_bookmarks, save, go}));
    connect(m_method, &QComboBox::currentIndexChanged, this, [this] { apply(); });
    connect(m_steps, &QSpinBox::valueChanged, this, [this] { apply(); });
    connect(m_lightSteps, &QSpinBox::valueChanged, this, [this] { apply(); });
    connect(m_exposure, &QDoubleSpinBox::valueChanged, this, [this] { apply(); });
    connect(m_ambient, &QDoubleSpinBox::valueChanged, this, [this] { apply(); });
    connect(m_turntable, &QCheckBox::toggled, this, [this] { apply(); });
    connect(m_smooth, &QCheckBox::toggled, this, [this] { apply(); });
    connect(save, &QPushButton::clicked, this, [this] {
        const OrbitCamera& c = m_viewport->camera();
        m_bookmarks->addItem(
            tr("View %1").arg(m_bookmarks->count() + 1),
            QVariantList{double(c.target.x), double(c.target.y), double(c.target.z),
                         double(c.distance), double(c.yawDeg), double(c.pitchDeg)});
        m_bookmarks->setCurrentIndex(m_bookmarks->count() - 1);
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
    connect(doc, &Document::sceneReplaced, m_bookmarks, &QComboBox::clear);
    apply();
}

void RenderPanel::apply() {
    RenderSettings s;
    s.method = RenderSettings::Method(m_method->currentIndex());
    s.steps = m_steps->value();
    s.lightSteps = m_lightSteps->value();
    s.exposureStops = float(m_exposure->value());
    s.ambient = float(m_ambient->value());
    s.turntable = m_turntable->isChecked();
    s.smoothVoxels = m_smooth->isChecked();
    s.deform = m_deform && m_deform->isChecked();
    s.resolutionScale = m_scale->currentIndex() == 0   ? 1.f
                        : m_scale->currentIndex() == 1 ? 0.5f
                                                       : 0.25f;
    s.sslpvCalibrated = m_sslpvMode->currentIndex() == 1;
    s.sslpvGrid = 16 << m_sslpvGrid->currentIndex();
    s.sslpvSteps = m_sslpvSteps->value();
    s.sslpvOrder = m_sslpvOrder->currentIndex() + 1;
    s.sslpvGlSolve = m_sslpvSolve->currentIndex() == 1;
    s.dipoleSpp = m_dipoleSpp->value();
    s.dirpoleSpp = m_dirpoleSpp->value();
    // Below 0 the special value "Auto": the combined module's default split.
    s.combinedSplitRadius = m_splitRadius->value() < 0.0 ? -1.f : float(m_splitRadius->value());
    s.subsurfaceOnly = m_subsurfaceOnly->isChecked();
    s.volumeOverlay = m_overlay->isChecked();
    s.overlayChannel = m_overlayChannel->currentIndex();
    s.overlayOpacity = float(m_overlayOpacity->value());
    m_overlayChannel->setEnabled(s.volumeOverlay);
    m_overlayOpacity->setEnabled(s.volumeOverlay);
    using M = RenderSettings::Method;
    const bool single = s.method == M::SingleScattering;
    const bool combined = s.method == M::Combined;
    const bool sslpv = s.method == M::Sslpv || combined;  // Combined: SSLPV beyond the split
    m_steps->setEnabled(single);
    m_lightSteps->setEnabled(single);
    m_ambient->setEnabled(single);
    m_smooth->setEnabled(single);
    for (QWidget* w : std::initializer_list<QWidget*>{m_sslpvMode, m_sslpvGrid, m_sslpvSteps,
                                                      m_sslpvOrder, m_sslpvSolve})
        w->setEnabled(sslpv);
    m_dipoleSpp->setEnabled(s.method == M::Dipole || s.method == M::BetterDipole || combined);
    m_dirpoleSpp->setEnabled(s.method == M::DirectionalDipole);
    m_splitRadius->setEnabled(combined);
    m_subsurfaceOnly->setEnabled(s.method != M::Direct);
    m_viewport->setRenderSettings(s);
}

void RenderPanel::setMethod(int method) {
    m_method->setCurrentIndex(method);
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
    t += tr("last upload: %1 bricks in %2 ms<br>").arg(s.bricksUploaded).arg(s.uploadMs, 0, 'f', 2);
    t += tr("frames: %1, GL errors: %2<br>").arg(s.frames).arg(s.glErrors);
    for (const PreviewStats::Pass& p : s.preview.passes)
        t += tr("&nbsp;&nbsp;%1: %2 ms GPU, %3 ms CPU<br>")
                 .arg(QString::fromStdString(p.name))
                 .arg(p.gpuMs, 0, 'f', 2)
                 .arg(p.cpuMs, 0, 'f', 2);
    if (!s.preview.methodDetail.empty())
        t +=
            QString::fromStdString(s.preview.methodDetail).toHtmlEscaped() + QStringLiteral("<br>");
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
