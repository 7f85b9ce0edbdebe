// SPDX-License-Identifier: MIT
/// @file
/// @brief Document: scene ownership, file operations, undoable edits, modification tracking.

#include "Document.h"

#include <lucent/core/Error.h>
#include <lucent/scene/SceneFile.h>

#include <algorithm>
#include <cmath>

namespace lucent::app {

Document::Document(QObject* parent) : QObject(parent) {
    connect(&m_undo, &QUndoStack::cleanChanged, this,
            [this](bool) { Q_EMIT modifiedChanged(isModified()); });
    connect(&m_undo, &QUndoStack::indexChanged, this,
            [this](int) { Q_EMIT undoAvailabilityChanged(canUndo()); });
}

Document::~Document() {
    disconnect(&m_undo, nullptr, this, nullptr);
}

void Document::setScene(Scene scene, const QString& path) {
    if (m_history.isStrokeOpen() && material())
        m_history.cancelStroke(*material());
    m_scene = std::move(scene);
    m_path = path;
    m_history.clear();
    m_undo.clear();
    m_undo.setClean();
    m_undoFloor = 0;
    m_extraChanges = false;
    Q_EMIT sceneReplaced();
    Q_EMIT modifiedChanged(false);
    Q_EMIT undoAvailabilityChanged(canUndo());
}

void Document::newDefault() {
    setScene(makeDefaultScene(), QString());
}

void Document::open(const QString& path) {
    Scene s = loadScene(path.toStdString());  // throws, leaving the current scene intact
    if (s.objects.empty() || !s.objects[0].material)
        LUCENT_THROW(IoError, path.toStdString(), ": the scene has no object with a material");
    setScene(std::move(s), path);
}

void Document::save(const QString& path) {
    saveProject(m_scene, path.toStdString());
    m_path = path;
    m_extraChanges = false;
    // Mid-stroke (a shortcut while the pen is down) the file holds part of a stroke: neither
    // the step before it nor the one it will push equals the file, so no step is clean.
    if (m_history.isStrokeOpen())
        m_undo.resetClean();
    else
        m_undo.setClean();
    Q_EMIT modifiedChanged(isModified());
}

void Document::saveCopy(const QString& path) const {
    saveProject(m_scene, path.toStdString());
}

void Document::noteSceneEdited() {
    m_extraChanges = true;
    Q_EMIT sceneEdited();
    Q_EMIT modifiedChanged(true);
}

namespace {
bool sameLights(const std::vector<Light>& a, const std::vector<Light>& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const Light& x, const Light& y) {
        return x.type == y.type && x.position == y.position && x.direction == y.direction &&
               x.intensity == y.intensity && x.spotOuterDeg == y.spotOuterDeg &&
               x.spotInnerDeg == y.spotInnerDeg && x.radius == y.radius;
    });
}
}  // namespace

void Document::setLightLive(int index, const Light& light) {
    LUCENT_CHECK(index >= 0 && size_t(index) < m_scene.lights.size(), "light ", index,
                 " does not exist (the scene has ", m_scene.lights.size(), " lights)");
    m_scene.lights[size_t(index)] = light;
    Q_EMIT sceneEdited();
}

void Document::commitLights(const std::vector<Light>& before, const QString& label) {
    if (sameLights(before, m_scene.lights))
        return;
    // Both states are kept by value: a light step costs a few hundred bytes.
    const std::vector<Light> after = m_scene.lights;
    m_undo.push(new HistoryCommand(
        label,
        [this, before] {
            m_scene.lights = before;
            Q_EMIT sceneEdited();
        },
        [this, after] {
            m_scene.lights = after;
            Q_EMIT sceneEdited();
        }));
}

void Document::setLights(std::vector<Light> lights, const QString& label) {
    const std::vector<Light> before = m_scene.lights;
    m_scene.lights = std::move(lights);
    commitLights(before, label);
    Q_EMIT sceneEdited();
}

QString brushProblem(const BrushSettings& brush) {
    if ((brush.channels & ALL_CHANNELS) == 0)
        return Document::tr("Choose at least one channel (σt, σs′ or g) for the brush to paint.");
    const bool setsBoth = brush.mode == BrushMode::Set &&
                          (brush.channels & uint8_t(Channel::SigmaT)) &&
                          (brush.channels & uint8_t(Channel::SigmaS));
    if (setsBoth) {
        const char* const colour[] = {QT_TR_NOOP("red"), QT_TR_NOOP("green"), QT_TR_NOOP("blue")};
        for (int c = 0; c < 3; ++c)
            if (brush.value.sigma_s[c] > brush.value.sigma_t[c])
                return Document::tr(
                           "The scattering σs′ (%1) of %2 mm⁻¹ is larger than the extinction σt "
                           "of %3 mm⁻¹: a material cannot scatter more light than it takes out. "
                           "Lower σs′ or raise σt.")
                    .arg(Document::tr(colour[c]))
                    .arg(double(brush.value.sigma_s[c]), 0, 'g', 4)
                    .arg(double(brush.value.sigma_t[c]), 0, 'g', 4);
    }
    try {
        validateBrush(brush);
    } catch (const std::exception& ex) {
        return Document::tr("The brush settings cannot paint: %1")
            .arg(QString::fromUtf8(ex.what()));
    }
    return {};
}

void Document::lightTarget(Point3f& center, float& radius) const {
    const TriangleMesh* m = mesh();
    if (m && !m->isEmpty()) {
        const Bounds3f b = m->bounds();
        center = b.center();
        radius = std::max(0.5f * glm::length(b.extent()), 1e-3f);
    } else {
        center = Point3f(0.f);
        radius = 20.f;
    }
}

void Document::setLightType(int index, Light::Type type) {
    LUCENT_CHECK(index >= 0 && size_t(index) < m_scene.lights.size(), "light ", index,
                 " does not exist (the scene has ", m_scene.lights.size(), " lights)");
    Point3f center;
    float radius = 0.f;
    lightTarget(center, radius);
    std::vector<Light> lights = m_scene.lights;
    lights[size_t(index)] = convertLight(lights[size_t(index)], type, center, radius);
    setLights(std::move(lights), tr("Change the type of light %1").arg(index));
}

void Document::setEta(float eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.f && eta <= 3.f, "η = ", eta, " is outside [1, 3]");
    const float before = m_scene.eta;
    if (eta == before)
        return;
    const auto apply = [this](float value) {
        m_scene.eta = value;
        if (MaterialVolume* v = material())
            v->setEta(value);
        Q_EMIT sceneEdited();
    };
    apply(eta);
    m_undo.push(new HistoryCommand(
        tr("Set η to %1").arg(double(eta)), [apply, before] { apply(before); },
        [apply, eta] { apply(eta); }));
}

void Document::pushHistoryStep(const QString& label) {
    m_undo.push(new HistoryCommand(
        label,
        [this] {
            if (MaterialVolume* v = material())
                m_history.undo(*v);
            Q_EMIT materialEdited();
        },
        [this] {
            if (MaterialVolume* v = material())
                m_history.redo(*v);
            Q_EMIT materialEdited();
        },
        /*isPaint=*/true));
    followHistoryBudget();
}

void Document::followHistoryBudget() {
    // The History keeps the newest undoCount() strokes; below the stack's index, the paint
    // steps beyond that count lost theirs. Undo stops above the newest of them (and the light
    // steps older than it go out of reach too, as the oldest states of a limited history do).
    size_t kept = m_history.undoCount();
    int floor = 0;
    for (int i = m_undo.index() - 1; i >= 0; --i) {
        const auto* step = dynamic_cast<const HistoryCommand*>(m_undo.command(i));
        if (!step || !step->isPaint())
            continue;
        if (kept == 0) {
            floor = i + 1;
            break;
        }
        --kept;
    }
    if (floor > m_undoFloor) {
        m_undoFloor = floor;
        Q_EMIT undoAvailabilityChanged(canUndo());
    }
}

void Document::undo() {
    if (canUndo())
        m_undo.undo();
}

void Document::setHistoryBudget(size_t bytes) {
    m_history.setBudgetBytes(bytes);
    followHistoryBudget();
}

void Document::beginStroke(const BrushSettings& brush) {
    MaterialVolume* v = material();
    LUCENT_CHECK(v != nullptr, "paint: the scene has no material volume");
    validateBrush(brush);
    if (m_history.isStrokeOpen())
        m_history.endStroke(*v);
    m_strokeBrush = brush;
    m_history.beginStroke(*v);
}

size_t Document::strokeStamp(const Point3f& center, float radiusScale, float strengthScale) {
    MaterialVolume* v = material();
    if (!v || !m_history.isStrokeOpen())
        return 0;
    BrushSettings b = m_strokeBrush;
    b.radius *= std::clamp(radiusScale, AppBrush::MIN_PRESSURE, 1.f);
    b.strength *= std::clamp(strengthScale, 0.f, 1.f);
    const size_t n = stamp(*v, b, center, &m_history);
    if (n > 0)
        Q_EMIT materialEdited();
    return n;
}

void Document::endStroke(const QString& label) {
    MaterialVolume* v = material();
    if (!v || !m_history.isStrokeOpen())
        return;
    if (m_history.endStroke(*v))
        pushHistoryStep(label);
}

void Document::fill(const MaterialSample& value, ChannelMask channels) {
    MaterialVolume* v = material();
    LUCENT_CHECK(v != nullptr, "fill: the scene has no material volume");
    m_history.beginStroke(*v);
    try {
        fillInterior(*v, value, channels, &m_history);
    } catch (...) {
        m_history.cancelStroke(*v);
        throw;
    }
    if (m_history.endStroke(*v))
        pushHistoryStep(tr("Fill"));
    Q_EMIT materialEdited();
}

void Document::fillProcedural(const ProceduralFill& fill) {
    MaterialVolume* v = material();
    LUCENT_CHECK(v != nullptr, "procedural fill: the scene has no material volume");
    m_history.beginStroke(*v);
    try {
        lucent::fillProcedural(*v, fill, &m_history);
    } catch (...) {
        m_history.cancelStroke(*v);
        throw;
    }
    if (m_history.endStroke(*v))
        pushHistoryStep(tr("Procedural fill"));
    Q_EMIT materialEdited();
}

}  // namespace lucent::app
