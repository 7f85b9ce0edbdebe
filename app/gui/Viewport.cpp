// SPDX-License-Identifier: MIT
/// @file
/// @brief Viewport: GL resources, camera, picking and painting interaction; the QOpenGLWindow
/// that draws, hosted in a window container.

#include "Viewport.h"

#include "Document.h"

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/mesh/Deform.h>

#include <QCoreApplication>
#include <QDropEvent>
#include <QKeyEvent>
#include <QMouseEvent>
#include <QOpenGLContext>
#include <QOpenGLFramebufferObject>
#include <QOpenGLFunctions>
#include <QOpenGLPaintDevice>
#include <QOpenGLWindow>
#include <QPainter>
#include <QTabletEvent>
#include <QVBoxLayout>
#include <QWheelEvent>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <cstdio>
#include <vector>

namespace lucent::app {

// ---- OrbitCamera ----------------------------------------------------------------------------

Point3f OrbitCamera::eye() const {
    const float yaw = glm::radians(yawDeg), pitch = glm::radians(pitchDeg);
    const Vector3f back(std::sin(yaw) * std::cos(pitch), std::sin(pitch),
                        std::cos(yaw) * std::cos(pitch));
    return target + distance * back;
}

Mat4f OrbitCamera::viewFromWorld() const {
    return glm::lookAt(eye(), target, Vector3f(0.f, 1.f, 0.f));
}

Mat4f OrbitCamera::clipFromView(float aspect) const {
    const float nearPlane = std::max(1e-3f, distance * 0.01f);
    return glm::perspective(glm::radians(fovYDeg), std::max(aspect, 1e-3f), nearPlane,
                            distance * 100.f + 1.f);
}

void OrbitCamera::lookAt(const Point3f& eyePos, const Point3f& targetPos) {
    target = targetPos;
    const Vector3f d = eyePos - targetPos;
    distance = std::max(glm::length(d), 1e-3f);
    pitchDeg = glm::degrees(std::asin(std::clamp(d.y / distance, -1.f, 1.f)));
    pitchDeg = std::clamp(pitchDeg, -89.f, 89.f);
    yawDeg = glm::degrees(std::atan2(d.x, d.z));
}

// ---- ViewportWindow -------------------------------------------------------------------------

/// The native GL window of a Viewport. It owns the context and the swap; everything else (the
/// frame, the GL resources, the interaction) lives in the facade, to which it hands its GL
/// callbacks and input events. Its geometry equals the facade's (the container fills it), so
/// event positions need no mapping.
class ViewportWindow final : public QOpenGLWindow {
public:
    explicit ViewportWindow(Viewport* owner)
        : QOpenGLWindow(QOpenGLWindow::NoPartialUpdate), m_owner(owner) {}

    /// Schedules a frame at the next pass of the event loop; calls before it coalesce.
    /// QPaintDeviceWindow::update() marks the window dirty and asks the platform for an
    /// update request, which Qt's default platform window delivers from a 5 ms timer
    /// (QPlatformWindow::requestUpdate, "idle time to gather system events"): 5 ms or more of
    /// latency per frame. The request posted here paints at once. Update requests that arrive
    /// with no frame due (the timer's, after the posted one painted) are dropped: Qt 6.4
    /// would paint a second, identical frame for them (measured: every other frame twice).
    void scheduleFrame() {
        m_frameDue = true;
        QOpenGLWindow::update();
        if (!m_framePosted) {
            m_framePosted = true;
            QCoreApplication::postEvent(this, new QEvent(QEvent::UpdateRequest));
        }
    }

protected:
    // Exposure and size changes need a frame, whichever event Qt paints it from.
    void exposeEvent(QExposeEvent* e) override {
        m_frameDue = true;
        QOpenGLWindow::exposeEvent(e);
    }
    void resizeEvent(QResizeEvent* e) override {
        m_frameDue = true;
        QOpenGLWindow::resizeEvent(e);
    }
    void initializeGL() override { m_owner->initializeGL(); }
    void paintGL() override {
        m_frameDue = false;  // whatever asked for it (update request, expose, resize)
        m_owner->paintGL();
    }
    void mousePressEvent(QMouseEvent* e) override {
        m_owner->setFocus(Qt::MouseFocusReason);  // keys then reach the viewport
        m_owner->mousePressEvent(e);
    }
    void mouseMoveEvent(QMouseEvent* e) override { m_owner->mouseMoveEvent(e); }
    void mouseReleaseEvent(QMouseEvent* e) override { m_owner->mouseReleaseEvent(e); }
    void wheelEvent(QWheelEvent* e) override { m_owner->wheelEvent(e); }
    void keyPressEvent(QKeyEvent* e) override { m_owner->keyPressEvent(e); }
    // Ignored (hover, modifiers, the eyedropper): Qt then synthesises mouse events for this
    // window from it, as it does for widgets.
    void tabletEvent(QTabletEvent* e) override { m_owner->tabletEvent(e); }

    bool event(QEvent* e) override {
        switch (e->type()) {
            case QEvent::UpdateRequest:
                // Hidden or minimised: the frame stays due and the next expose draws it.
                m_framePosted = false;
                return m_frameDue && isExposed() ? QOpenGLWindow::event(e) : true;
            case QEvent::Leave:
                m_owner->leaveEvent(e);
                return true;
            case QEvent::DragEnter:
            case QEvent::DragMove:
            case QEvent::DragLeave:
            case QEvent::Drop:
                forwardDrag(e);
                return true;
            case QEvent::ContextMenu:
                // The widget path: the facade, then (ignored) its parents.
                QCoreApplication::sendEvent(m_owner, e);
                return true;
            default:
                return QOpenGLWindow::event(e);
        }
    }

private:
    /// Drag-and-drop over the GL window goes to the nearest ancestor widget that accepts drops
    /// (the main window: meshes, VDBs, projects), as it would over a plain child widget; the
    /// answer (accepted, drop action) comes back to the window system through `e`.
    void forwardDrag(QEvent* e) {
        QWidget* target = m_owner;
        while (target && !target->acceptDrops())
            target = target->parentWidget();
        if (!target) {
            e->ignore();
            return;
        }
        if (e->type() == QEvent::DragLeave) {
            QDragLeaveEvent leave;
            QCoreApplication::sendEvent(target, &leave);
            return;
        }
        auto* d = static_cast<QDropEvent*>(e);
        const QPoint pos = m_owner->mapTo(target, d->position().toPoint());
        const auto forward = [&](QDropEvent&& f) {
            f.setDropAction(d->dropAction());
            f.setAccepted(d->isAccepted());
            QCoreApplication::sendEvent(target, &f);
            d->setDropAction(f.dropAction());
            d->setAccepted(f.isAccepted());
        };
        if (e->type() == QEvent::DragEnter)
            forward(QDragEnterEvent(pos, d->possibleActions(), d->mimeData(), d->buttons(),
                                    d->modifiers()));
        else if (e->type() == QEvent::DragMove)
            forward(QDragMoveEvent(pos, d->possibleActions(), d->mimeData(), d->buttons(),
                                   d->modifiers()));
        else
            forward(QDropEvent(QPointF(pos), d->possibleActions(), d->mimeData(), d->buttons(),
                               d->modifiers()));
    }

    Viewport* m_owner;
    bool m_framePosted = false;  ///< an UpdateRequest of scheduleFrame() is in the queue
    bool m_frameDue = false;     ///< scheduleFrame() was called since the last paintGL
};

// ---- Viewport -------------------------------------------------------------------------------

Viewport::Viewport(Document* doc, QWidget* parent) : QWidget(parent), m_doc(doc) {
    setMouseTracking(true);
    setFocusPolicy(Qt::StrongFocus);
    setMinimumSize(320, 180);
    // The GL window in a container filling the facade; focus given to the facade goes to the
    // container, which activates the window (its key events then reach keyPressEvent).
    m_window = new ViewportWindow(this);
    m_container = QWidget::createWindowContainer(m_window, this);
    m_container->setFocusPolicy(Qt::StrongFocus);
    m_container->setMouseTracking(true);
    setFocusProxy(m_container);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->addWidget(m_container);
    connect(m_doc, &Document::sceneReplaced, this, &Viewport::onSceneReplaced);
    connect(m_doc, &Document::materialEdited, this, [this] { update(); });
    connect(m_doc, &Document::sceneEdited, this, [this] { update(); });
    m_turntable.setInterval(33);
    connect(&m_turntable, &QTimer::timeout, this, [this] {
        m_camera.yawDeg += 30.f * 0.033f;  // 30°/s
        update();
    });
    m_animation.setInterval(33);
    connect(&m_animation, &QTimer::timeout, this, [this] {
        m_meshDirty = true;  // re-pose the mesh for the new time
        update();
    });
    m_clock.start();
    m_levelChecker = new AutoLevelChecker(this, m_doc);
    m_autoMeasurer = new AutoMeasurer(this, m_doc);
    // The two run one at a time: each finished one lets a waiting other start.
    connect(m_levelChecker, &AutoLevelChecker::checked, m_autoMeasurer,
            [this] { m_autoMeasurer->afterFrame(); });
    connect(m_autoMeasurer, &AutoMeasurer::measured, m_levelChecker,
            [this] { m_levelChecker->afterFrame(); });
    onSceneReplaced();
}

void Viewport::applyViewTo(Camera& camera, int width) const {
    camera.position = m_camera.eye();
    camera.target = m_camera.target;
    camera.up = Vector3f(0.f, 1.f, 0.f);
    camera.orthographic = false;
    camera.fovYDeg = m_camera.fovYDeg;
    camera.width = width;
    const double aspect = double(height()) / double(std::max(this->width(), 1));
    camera.height = std::max(16, int(std::lround(width * aspect)));
}

void Viewport::setRefinementPaused(bool paused) {
    m_refinementPaused = paused;
    if (paused)
        m_autoMeasurer->stopForNow();
    else
        update();
}

Scene Viewport::frozenSceneOfView(int width) const {
    Scene scene = m_doc->scene();
    scene.objects[0].material = std::make_shared<MaterialVolume>(*m_doc->material());
    applyViewTo(scene.camera, width);
    return scene;
}

Viewport::~Viewport() {
    if (m_glReady && m_window->context()) {
        m_window->makeCurrent();
        cleanupGL();
        m_window->doneCurrent();
    }
    // The container deletes the GL window and its context; the renderer is released already.
    if (m_window->context())
        m_window->context()->disconnect(this);
    delete m_container;
}

void Viewport::update() {
    m_window->scheduleFrame();
}

void Viewport::paintEvent(QPaintEvent*) {
    // The facade is covered by the GL window; a repaint of it asks for a GL frame.
    m_window->scheduleFrame();
}

QWindow* Viewport::glWindow() const {
    return m_window;
}

void Viewport::setViewCursor(Qt::CursorShape shape) {
    setCursor(shape);
    m_window->setCursor(shape);  // the native window shows its own cursor
}

void Viewport::setRenderSettings(const RenderSettings& s) {
    m_render = s;  // the method's parameters are checked when its frame makes it
    m_render.overlayChannel = std::clamp(m_render.overlayChannel, 0, 2);
    m_render.overlayOpacity = std::isfinite(m_render.overlayOpacity)
                                  ? std::clamp(m_render.overlayOpacity, 0.f, 1.f)
                                  : 0.5f;
    if (s.turntable && !m_turntable.isActive())
        m_turntable.start();
    if (!s.turntable)
        m_turntable.stop();
    m_render.deform = s.deform;
    if (m_render.deform && !m_animation.isActive())
        m_animation.start();
    if (!m_render.deform && m_animation.isActive()) {
        m_animation.stop();
        m_meshDirty = true;  // back to the rest pose
    }
    update();
}

void Viewport::onSceneReplaced() {
    const Scene& scene = m_doc->scene();
    m_camera.lookAt(scene.camera.position, scene.camera.target);
    m_camera.fovYDeg = scene.camera.fovYDeg;
    // A project saved before the camera was kept, or a camera that looks past the object:
    // show the object rather than an empty view.
    if (!cameraShowsObject())
        frameObject();
    m_meshDirty = true;
    m_sceneReplaced = true;
    m_stroking = m_strokeReached = m_strokeRefused = false;
    m_tabletStroke = false;
    m_drag = Drag::None;
    m_lightsBeforeDrag.clear();
    if (m_selectedLight >= int(scene.lights.size()))
        m_selectedLight = -1;
    update();
}

bool Viewport::cameraShowsObject() const {
    const TriangleMesh* mesh = m_doc->mesh();
    if (!mesh || mesh->isEmpty())
        return true;
    const Bounds3f b = mesh->bounds();
    const float radius = std::max(0.5f * glm::length(b.extent()), 1e-4f);
    const Point3f eye = m_camera.eye();
    const Vector3f toCentre = b.center() - eye;
    const float d = glm::length(toCentre);
    if (d <= radius)
        return false;  // inside the object's bounding sphere
    const Vector3f forward = glm::normalize(m_camera.target - eye);
    const float halfFov = glm::radians(0.5f * m_camera.fovYDeg);
    const float offAxis = std::acos(std::clamp(glm::dot(toCentre, forward) / d, -1.f, 1.f));
    const float sphere = std::asin(std::min(1.f, radius / d));  // angular radius
    // Some of the sphere inside the (vertical) field of view, and not a speck: its angular
    // size at least 2 % of the view's.
    return offAxis - sphere < halfFov && sphere > 0.02f * halfFov;
}

void Viewport::frameObject() {
    const TriangleMesh* mesh = m_doc->mesh();
    if (!mesh || mesh->isEmpty())
        return;
    const Bounds3f b = mesh->bounds();
    const float radius = 0.5f * glm::length(b.extent());
    m_camera.target = b.center();
    // Distance at which a sphere of that radius fits the vertical field of view.
    m_camera.distance = radius / std::sin(glm::radians(0.5f * m_camera.fovYDeg)) * 1.05f;
    update();
}

void Viewport::cameraRay(const QPointF& pos, Point3f& origin, Vector3f& direction) const {
    const float w = float(std::max(width(), 1)), h = float(std::max(height(), 1));
    const Mat4f clipFromWorld = m_camera.clipFromView(w / h) * m_camera.viewFromWorld();
    const Mat4f worldFromClip = glm::inverse(clipFromWorld);
    const float x = 2.f * float(pos.x()) / w - 1.f, y = 1.f - 2.f * float(pos.y()) / h;
    glm::vec4 nearP = worldFromClip * glm::vec4(x, y, -1.f, 1.f);
    glm::vec4 farP = worldFromClip * glm::vec4(x, y, 1.f, 1.f);
    origin = Point3f(nearP) / nearP.w;
    direction = glm::normalize(Point3f(farP) / farP.w - origin);
}

std::optional<PickHit> Viewport::pickAt(const QPointF& pos) const {
    const TriangleMesh* mesh = m_doc->mesh();
    if (!mesh)
        return std::nullopt;
    Point3f o;
    Vector3f d;
    cameraRay(pos, o, d);
    return pickMesh(*mesh, o, d);
}

// ---- Painting -------------------------------------------------------------------------------

Point3f Viewport::stampCenter(const PickHit& hit) const {
    return hit.position - hit.normal * m_brush.depthMm;
}

void Viewport::beginStroke(const PickHit& hit) {
    m_strokeReached = true;
    if (const QString problem = brushProblem(m_brush.engine); !problem.isEmpty()) {
        m_strokeRefused = true;  // said once per stroke, not at every mouse move
        Q_EMIT paintError(problem);
        return;
    }
    try {
        m_doc->beginStroke(m_brush.engine);
    } catch (const std::exception& ex) {
        m_strokeRefused = true;
        Q_EMIT paintError(QString::fromUtf8(ex.what()));
        return;
    }
    m_stroking = true;
    m_lastStamp = stampCenter(hit);
    m_doc->strokeStamp(m_lastStamp, m_brush.radiusScale(m_pressure),
                       m_brush.strengthScale(m_pressure));
}

void Viewport::continueStroke(const PickHit& hit) {
    if (!m_stroking)
        return;
    // Stamps every spacing·radius mm along the straight path from the last stamp towards the
    // current hit (Brush.h spacing convention), never closer than half a voxel.
    // The radius is the pressure-scaled one of this stamp.
    const MaterialVolume* vol = m_doc->material();
    const float radiusScale = m_brush.radiusScale(m_pressure);
    const float strengthScale = m_brush.strengthScale(m_pressure);
    const float spacing = std::max(m_brush.engine.spacing * m_brush.engine.radius * radiusScale,
                                   vol ? 0.5f * vol->spec().voxelSize : 0.f);
    const Point3f target = stampCenter(hit);
    for (Vector3f seg = target - m_lastStamp; glm::length(seg) >= spacing && spacing > 0.f;
         seg = target - m_lastStamp) {
        m_lastStamp += glm::normalize(seg) * spacing;
        m_doc->strokeStamp(m_lastStamp, radiusScale, strengthScale);
    }
}

void Viewport::endStroke() {
    if (!m_stroking)
        return;
    m_stroking = false;
    m_doc->endStroke(tr("Paint stroke"));
}

void Viewport::finishDragStroke() {
    const bool missed = !m_stroking && !m_strokeReached;
    endStroke();
    m_strokeReached = m_strokeRefused = false;
    if (missed)
        Q_EMIT paintError(
            tr("The stroke never reached the object: drag across its surface "
               "to paint."));
}

int Viewport::strokeBetween(const QPointF& a, const QPointF& b) {
    const int samples = 16;
    // Counted on the undo stack: the History's count stays put once its budget drops a stroke
    // for each new one.
    const int before = m_doc->undoStack()->index();
    for (int i = 0; i <= samples; ++i) {
        const QPointF p = a + (b - a) * (double(i) / samples);
        const auto hit = pickAt(p);
        if (!hit)
            continue;
        if (m_stroking)
            continueStroke(*hit);
        else if (!m_strokeRefused)
            beginStroke(*hit);
    }
    finishDragStroke();
    return m_doc->undoStack()->index() - before;
}

void Viewport::updateHover(const QPointF& pos) {
    const auto hit = pickAt(pos);
    // Off the object (or outside the grid) the readout is cleared rather than left showing the
    // last voxel.
    QString readout;
    if (hit) {
        m_cursor = hit->position;
        if (const MaterialVolume* vol = m_doc->material()) {
            const Coord c =
                vol->spec().cellOf(hit->position - hit->normal * (0.5f * vol->spec().voxelSize));
            if (vol->spec().contains(c)) {
                const MaterialSample s = vol->at(c);
                readout =
                    QStringLiteral("voxel (%1, %2, %3)  σt = %4 %5 %6 mm⁻¹  σs′ = %7 %8 %9 mm⁻¹")
                        .arg(c.x)
                        .arg(c.y)
                        .arg(c.z)
                        .arg(double(s.sigma_t.r), 0, 'g', 3)
                        .arg(double(s.sigma_t.g), 0, 'g', 3)
                        .arg(double(s.sigma_t.b), 0, 'g', 3)
                        .arg(double(s.sigma_s.r), 0, 'g', 3)
                        .arg(double(s.sigma_s.g), 0, 'g', 3)
                        .arg(double(s.sigma_s.b), 0, 'g', 3);
            }
        }
    } else {
        m_cursor.reset();
    }
    setHoverText(readout);
    update();
}

void Viewport::setHoverText(const QString& text) {
    if (text == m_hoverText)
        return;
    m_hoverText = text;
    Q_EMIT hoverVoxel(text);
}

// ---- Light gizmos ---------------------------------------------------------------------------

void Viewport::setSelectedLight(int index) {
    const int n = int(m_doc->scene().lights.size());
    m_selectedLight = index >= 0 && index < n ? index : -1;
    update();
}

void Viewport::setLightGizmosVisible(bool visible) {
    m_gizmosVisible = visible;
    update();
}

void Viewport::gizmoSphere(Point3f& center, float& radius) const {
    const TriangleMesh* mesh = m_doc->mesh();
    if (mesh && !mesh->isEmpty()) {
        const Bounds3f b = mesh->bounds();
        center = b.center();
        radius = 1.5f * 0.5f * std::max(glm::length(b.extent()), 1e-3f);
    } else {
        center = m_camera.target;
        radius = 0.5f * m_camera.distance;
    }
}

std::optional<Point3f> Viewport::lightHandleWorld(int index) const {
    const auto& lights = m_doc->scene().lights;
    if (index < 0 || size_t(index) >= lights.size())
        return std::nullopt;
    const Light& l = lights[size_t(index)];
    if (l.type != Light::Type::Directional)
        return l.position;
    Point3f c;
    float r = 0.f;
    gizmoSphere(c, r);
    const float len = glm::length(l.direction);
    const Vector3f d = len > 0.f ? l.direction / len : Vector3f(0.f, -1.f, 0.f);
    return c - r * d;  // the light travels along d, from the handle through the centre
}

std::optional<QPointF> Viewport::project(const Point3f& p) const {
    const float w = float(std::max(width(), 1)), h = float(std::max(height(), 1));
    const glm::vec4 clip =
        m_camera.clipFromView(w / h) * m_camera.viewFromWorld() * glm::vec4(p, 1.f);
    if (clip.w <= 1e-6f)
        return std::nullopt;
    // Inverse of cameraRay's mapping: NDC x, y ∈ [−1, 1] → widget pixels, y down.
    const float x = clip.x / clip.w, y = clip.y / clip.w;
    return QPointF(double(0.5f * (x + 1.f) * w), double(0.5f * (1.f - y) * h));
}

std::optional<QPointF> Viewport::lightHandle(int index) const {
    const auto world = lightHandleWorld(index);
    return world ? project(*world) : std::nullopt;
}

int Viewport::lightAt(const QPointF& pos) const {
    if (!m_gizmosVisible)
        return -1;
    int best = -1;
    double bestDist = HANDLE_PICK_PX;
    // The selected light wins ties: it is drawn on top.
    for (int i = 0; i < int(m_doc->scene().lights.size()); ++i) {
        const auto h = lightHandle(i);
        if (!h)
            continue;
        const double d = std::hypot(h->x() - pos.x(), h->y() - pos.y());
        if (d < bestDist || (d <= bestDist && i == m_selectedLight)) {
            bestDist = d;
            best = i;
        }
    }
    return best;
}

void Viewport::beginLightDrag(int index, const QPointF& pos) {
    setViewCursor(Qt::ClosedHandCursor);
    m_selectedLight = index;
    Q_EMIT lightSelected(index);
    m_lightsBeforeDrag = m_doc->scene().lights;
    m_drag = Drag::Light;
    const Light& l = m_lightsBeforeDrag[size_t(index)];
    Point3f o;
    Vector3f d;
    cameraRay(pos, o, d);
    // Point / spot / sphere: the plane through the light facing the camera; the offset keeps
    // the light from jumping to the cursor when the press was a few pixels off its centre.
    m_dragPlanePoint = l.position;
    m_dragPlaneNormal = glm::normalize(m_camera.target - m_camera.eye());
    const float denom = glm::dot(d, m_dragPlaneNormal);
    m_dragOffset = Vector3f(0.f);
    if (std::abs(denom) > 1e-6f) {
        const float t = glm::dot(m_dragPlanePoint - o, m_dragPlaneNormal) / denom;
        m_dragOffset = l.position - (o + t * d);
    }
    update();
}

void Viewport::continueLightDrag(const QPointF& pos) {
    const int i = m_selectedLight;
    if (i < 0 || size_t(i) >= m_doc->scene().lights.size() ||
        size_t(i) >= m_lightsBeforeDrag.size())
        return;
    Light l = m_doc->scene().lights[size_t(i)];
    Point3f o;
    Vector3f d;
    cameraRay(pos, o, d);
    if (l.type == Light::Type::Directional) {
        // Ray–sphere intersection (nearest hit); off the sphere, the closest point of the ray
        // to the centre pushed out onto the sphere. The light then shines from there.
        Point3f c;
        float r = 0.f;
        gizmoSphere(c, r);
        const Vector3f oc = o - c;
        const float b = glm::dot(oc, d), disc = b * b - (glm::dot(oc, oc) - r * r);
        Point3f p;
        if (disc >= 0.f && -b - std::sqrt(disc) > 0.f) {
            p = o + (-b - std::sqrt(disc)) * d;
        } else {
            const Point3f closest = o + std::max(-b, 0.f) * d;
            const Vector3f out = closest - c;
            p = c + r * (glm::length(out) > 0.f ? glm::normalize(out) : -d);
        }
        l.direction = glm::normalize(c - p);
    } else {
        const float denom = glm::dot(d, m_dragPlaneNormal);
        if (std::abs(denom) < 1e-6f)
            return;  // ray parallel to the plane: keep the last position
        const float t = glm::dot(m_dragPlanePoint - o, m_dragPlaneNormal) / denom;
        if (t <= 0.f)
            return;
        l.position = o + t * d + m_dragOffset;
    }
    m_doc->setLightLive(i, l);
}

void Viewport::endLightDrag() {
    setViewCursor(Qt::OpenHandCursor);
    m_drag = Drag::None;
    m_doc->commitLights(m_lightsBeforeDrag, tr("Move light %1").arg(m_selectedLight));
    m_lightsBeforeDrag.clear();
}

void Viewport::drawOverlay(unsigned framebuffer, int w, int h) {
    if (!m_gizmosVisible || m_hideOverlays)
        return;
    const auto& lights = m_doc->scene().lights;
    if (lights.empty())
        return;
    // QPainter through a GL paint device on the frame's framebuffer (the window's or a grab's),
    // so the overlay is part of every frame and of every grab; coordinates in logical pixels.
    QOpenGLContext::currentContext()->functions()->glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    QOpenGLPaintDevice device(w, h);
    device.setDevicePixelRatio(m_window->devicePixelRatio());
    QPainter painter(&device);
    painter.setRenderHint(QPainter::Antialiasing);
    QFont font = painter.font();
    font.setPointSizeF(8.0);
    painter.setFont(font);
    const auto colourOf = [](const Light& l) {
        // The light's colour: its RGB intensity normalised by the largest channel.
        const float m = std::max({l.intensity.r, l.intensity.g, l.intensity.b});
        if (!(m > 0.f))
            return QColor(128, 128, 128);
        return QColor::fromRgbF(l.intensity.r / m, l.intensity.g / m, l.intensity.b / m);
    };
    Point3f center;
    float radius = 0.f;
    gizmoSphere(center, radius);
    // The selected light last, so it is drawn on top of the others.
    std::vector<int> order;
    for (int i = 0; i < int(lights.size()); ++i)
        if (i != m_selectedLight)
            order.push_back(i);
    if (m_selectedLight >= 0 && m_selectedLight < int(lights.size()))
        order.push_back(m_selectedLight);
    for (int i : order) {
        const Light& l = lights[size_t(i)];
        const auto h = lightHandle(i);
        if (!h)
            continue;
        const bool selected = i == m_selectedLight;
        const QColor colour = colourOf(l);
        painter.setPen(QPen(colour, selected ? 2.0 : 1.2));
        painter.setBrush(Qt::NoBrush);
        if (l.type == Light::Type::Directional) {
            // Arrow from the handle towards the object's centre.
            if (const auto c = project(center)) {
                const QPointF dir = *c - *h;
                const double len = std::hypot(dir.x(), dir.y());
                if (len > 1.0) {
                    const QPointF u = dir / len, tip = *h + u * std::min(len, 40.0);
                    const QPointF n(-u.y(), u.x());
                    painter.drawLine(*h, tip);
                    painter.drawLine(tip, tip - 7.0 * u + 4.0 * n);
                    painter.drawLine(tip, tip - 7.0 * u - 4.0 * n);
                }
                if (selected) {  // outline of the sphere the handle moves on
                    const Mat4f v = m_camera.viewFromWorld();
                    const Vector3f right(v[0][0], v[1][0], v[2][0]);
                    if (const auto rim = project(center + radius * right)) {
                        const double rr = std::hypot(rim->x() - c->x(), rim->y() - c->y());
                        painter.setPen(QPen(colour, 1.0, Qt::DashLine));
                        painter.drawEllipse(*c, rr, rr);
                        painter.setPen(QPen(colour, 2.0));
                    }
                }
            }
        } else if (l.type == Light::Type::Spot) {
            if (const auto tip = project(l.position + 0.15f * radius * glm::normalize(l.direction)))
                painter.drawLine(*h, *tip);
        }
        const double r = selected ? 7.0 : 5.0;
        painter.setBrush(colour);
        painter.setPen(
            QPen(selected ? QColor(255, 255, 255) : QColor(20, 20, 20), selected ? 2.0 : 1.0));
        painter.drawEllipse(*h, r, r);
        painter.setPen(QColor(230, 230, 230));
        painter.drawText(*h + QPointF(r + 3.0, -r), QStringLiteral("L%1").arg(i));
    }
    painter.end();
}

// ---- Mouse and keys -------------------------------------------------------------------------

void Viewport::mousePressEvent(QMouseEvent* e) {
    m_lastMouse = e->position();
    const bool alt = e->modifiers() & Qt::AltModifier;
    if (e->button() == Qt::MiddleButton || (e->button() == Qt::LeftButton && alt)) {
        m_drag = (e->modifiers() & Qt::ShiftModifier) ? Drag::Pan : Drag::Orbit;
    } else if (e->button() == Qt::RightButton) {
        m_drag = Drag::Pan;
    } else if (e->button() == Qt::LeftButton) {
        if (const int light = lightAt(e->position()); light >= 0) {
            beginLightDrag(light, e->position());
            return;
        }
        m_pressure = 1.f;  // the mouse paints at full pressure
        const auto hit = pickAt(e->position());
        if (!hit && m_tool == Tool::Paint && !m_render.deform) {
            // A stroke may start beside the object: it paints from where it reaches the
            // surface (mouseMoveEvent), as in 2-D painting tools.
            m_drag = Drag::Paint;
            return;
        }
        if (!hit)
            return;
        if (m_tool == Tool::Eyedropper) {
            if (const MaterialVolume* vol = m_doc->material()) {
                const Coord c = vol->spec().cellOf(hit->position -
                                                   hit->normal * (0.5f * vol->spec().voxelSize));
                if (vol->spec().contains(c))
                    Q_EMIT eyedropped(vol->at(c));
            }
            return;
        }
        if (m_render.deform) {
            Q_EMIT paintError(
                tr("Painting is paused while the deformation animation runs (Render settings)."));
            return;
        }
        m_drag = Drag::Paint;
        beginStroke(*hit);
    }
}

void Viewport::mouseMoveEvent(QMouseEvent* e) {
    const QPointF d = e->position() - m_lastMouse;
    m_lastMouse = e->position();
    switch (m_drag) {
        case Drag::Orbit:
            m_camera.yawDeg -= 0.4f * float(d.x());
            m_camera.pitchDeg = std::clamp(m_camera.pitchDeg + 0.4f * float(d.y()), -89.f, 89.f);
            update();
            break;
        case Drag::Pan: {
            // Moves the target in the view plane so the point under the cursor follows it.
            const float mmPerPixel = 2.f * m_camera.distance *
                                     std::tan(glm::radians(0.5f * m_camera.fovYDeg)) /
                                     float(std::max(height(), 1));
            const Mat4f v = m_camera.viewFromWorld();
            const Vector3f right(v[0][0], v[1][0], v[2][0]), up(v[0][1], v[1][1], v[2][1]);
            m_camera.target += (-float(d.x()) * right + float(d.y()) * up) * mmPerPixel;
            update();
            break;
        }
        case Drag::Paint:
            if (const auto hit = pickAt(e->position())) {
                if (m_stroking)
                    continueStroke(*hit);
                else if (!m_strokeRefused)
                    beginStroke(*hit);  // the first time the drag reaches the surface
            }
            updateHover(e->position());
            break;
        case Drag::Light:
            continueLightDrag(e->position());
            break;
        case Drag::None:
            // A light handle under the cursor can be grabbed.
            setViewCursor(lightAt(e->position()) >= 0 ? Qt::OpenHandCursor : Qt::ArrowCursor);
            updateHover(e->position());
            break;
    }
}

void Viewport::mouseReleaseEvent(QMouseEvent*) {
    if (m_drag == Drag::Paint)
        finishDragStroke();
    if (m_drag == Drag::Light)
        endLightDrag();
    m_drag = Drag::None;
}

void Viewport::tabletEvent(QTabletEvent* e) {
    // The pen paints with its pressure. Anything else (eyedropper, gizmo handles, navigation
    // with modifiers or barrel buttons, hovering) is ignored here and reaches the mouse
    // handlers as the mouse events Qt synthesises from an ignored tablet event.
    const float pressure = float(std::clamp(e->pressure(), 0.0, 1.0));
    bool handled = false;
    if (e->type() == QEvent::TabletPress) {
        const bool paints = e->button() == Qt::LeftButton && m_tool == Tool::Paint &&
                            e->modifiers() == Qt::NoModifier && !m_render.deform &&
                            lightAt(e->position()) < 0;
        if (paints) {
            // As with the mouse, a pen stroke may start beside the object.
            m_pressure = pressure;
            m_drag = Drag::Paint;
            m_tabletStroke = handled = true;
            if (const auto hit = pickAt(e->position()))
                beginStroke(*hit);
        }
    } else if (m_tabletStroke && e->type() == QEvent::TabletMove) {
        m_pressure = pressure;
        if (const auto hit = pickAt(e->position())) {
            if (m_stroking)
                continueStroke(*hit);
            else if (!m_strokeRefused)
                beginStroke(*hit);
        }
        updateHover(e->position());
        handled = true;
    } else if (m_tabletStroke && e->type() == QEvent::TabletRelease) {
        finishDragStroke();
        m_drag = Drag::None;
        m_tabletStroke = false;
        m_pressure = 1.f;
        handled = true;
    }
    if (handled)
        m_lastMouse = e->position();
    e->setAccepted(handled);
}

void Viewport::wheelEvent(QWheelEvent* e) {
    // 120 units per notch; each notch scales the distance by 0.9 (zoom in) or 1/0.9.
    const float notches = float(e->angleDelta().y()) / 120.f;
    m_camera.distance = std::clamp(m_camera.distance * std::pow(0.9f, notches), 1e-2f, 1e5f);
    update();
}

void Viewport::keyPressEvent(QKeyEvent* e) {
    if (e->key() == Qt::Key_F) {
        frameObject();
        return;
    }
    QWidget::keyPressEvent(e);
}

void Viewport::leaveEvent(QEvent*) {
    m_cursor.reset();
    setHoverText(QString());
    update();
}

ImageRgb Viewport::linearImage() {
    if (!m_glReady || m_stats.frames == 0)
        LUCENT_THROW(GpuError, "the viewport has not rendered a frame yet");
    m_window->makeCurrent();
    ImageRgb img = m_preview.linearImage();
    m_window->doneCurrent();
    if (img.isEmpty())
        LUCENT_THROW(GpuError, "the preview renderer has no linear image");
    return img;
}

QImage Viewport::grabFramebuffer() {
    if (!m_window->context())
        return {};  // never shown: no context yet
    m_window->makeCurrent();
    const qreal dpr = m_window->devicePixelRatio();
    const int w = std::max(1, int(width() * dpr)), h = std::max(1, int(height() * dpr));
    QImage img;
    {
        // RGBA8 like the window's back buffer, with depth/stencil like its default format.
        QOpenGLFramebufferObject fbo(w, h, QOpenGLFramebufferObject::CombinedDepthStencil);
        renderFrame(fbo.handle(), w, h);
        img = QImage(w, h, QImage::Format_RGBA8888);
        QOpenGLFunctions* gl = m_window->context()->functions();
        gl->glBindFramebuffer(GL_FRAMEBUFFER, fbo.handle());
        gl->glPixelStorei(GL_PACK_ALIGNMENT, 4);  // 4 bytes a pixel: rows are always aligned
        gl->glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, img.bits());
        countGlErrors();
    }
    m_window->doneCurrent();
    // GL rows run bottom-up; the frame is opaque (what the window shows), whatever the alpha
    // the passes left.
    img = img.mirrored(false, true);
    for (int y = 0; y < h; ++y) {
        uchar* row = img.scanLine(y);
        for (int x = 0; x < w; ++x)
            row[4 * x + 3] = 255;
    }
    img = img.convertToFormat(QImage::Format_RGB32);
    img.setDevicePixelRatio(dpr);
    return img;
}

QPixmap Viewport::grabWithFrame(QWidget* widget) {
    QPixmap shot = widget->grab();
    if (!isVisible() || !(widget == this || widget->isAncestorOf(this)))
        return shot;
    const QImage frame = grabFramebuffer();
    if (frame.isNull())
        return shot;
    QPainter painter(&shot);  // logical coordinates: the pixmap and the frame carry the DPR
    painter.drawImage(QRectF(QPointF(mapTo(widget, QPoint(0, 0))), QSizeF(size())), frame);
    painter.end();
    return shot;
}

QImage Viewport::grabRender() {
    m_hideOverlays = true;
    QImage img = grabFramebuffer();
    m_hideOverlays = false;
    update();  // the next on-screen frame shows the overlays again
    return img;
}

// ---- GL -------------------------------------------------------------------------------------

void Viewport::initializeGL() {
    try {
        // The renderer calls GL through epoxy; the viewport needs only a few ES 2 level calls,
        // through the context's own QOpenGLFunctions. (QOpenGLFunctions_4_5_Core builds one
        // backend per GL version that Qt 6.4 never frees: 19 leaks per context under LSan.)
        const QSurfaceFormat fmt = m_window->context()->format();
        if (fmt.version() < qMakePair(4, 5))
            LUCENT_THROW(GpuError, "OpenGL 4.5 core functions are not available (got ",
                         fmt.majorVersion(), ".", fmt.minorVersion(), ")");
        QOpenGLFunctions* gl = m_window->context()->functions();
        m_stats.glRenderer = QStringLiteral("%1 — %2").arg(
            reinterpret_cast<const char*>(gl->glGetString(GL_RENDERER)),
            reinterpret_cast<const char*>(gl->glGetString(GL_VERSION)));
        m_preview.create();  // programs from the engine's shader library (shaders/)
        m_glReady = true;
        m_meshDirty = m_sceneReplaced = true;
        // The window's context dies with the window (its destructor makes it current first):
        // release the renderer's GL objects while it is still current. Never reached from
        // ~Viewport, which cleans up before it deletes the window.
        QOpenGLContext* ctx = m_window->context();
        connect(ctx, &QOpenGLContext::aboutToBeDestroyed, this, [this, ctx] {
            if (QOpenGLContext::currentContext() == ctx)
                cleanupGL();
            m_glReady = false;
        });
    } catch (const std::exception& ex) {
        m_stats.initError = QString::fromUtf8(ex.what());
    }
    countGlErrors();
}

void Viewport::countGlErrors() {
    QOpenGLContext* ctx = QOpenGLContext::currentContext();
    if (!m_glReady || !ctx)
        return;
    QOpenGLFunctions* gl = ctx->functions();
    while (gl->glGetError() != GL_NO_ERROR)
        ++m_stats.glErrors;
}

void Viewport::cleanupGL() {
    if (!m_glReady)
        return;
    m_preview.destroy();
    m_glReady = false;
}

const TriangleMesh* Viewport::shownMesh() {
    const TriangleMesh* mesh = m_doc->mesh();
    if (mesh && m_render.deform && !mesh->isEmpty()) {
        // A twist about the vertical axis through the object's centre: ±0.6 rad over its
        // height, oscillating at 0.5 Hz (Deform.h: amount·sin(2π·rate·t)).
        const Bounds3f b = mesh->bounds();
        Deformer twist;
        twist.type = DeformerType::Twist;
        twist.center = b.center();
        twist.axis = Vector3f(0.f, 1.f, 0.f);
        twist.amount = 0.6f / std::max(b.extent().y, 1e-3f);
        twist.rateHz = 0.5f;
        m_posed = deform(*mesh, {twist}, float(m_clock.elapsed()) * 1e-3f);
        return &m_posed;
    }
    return mesh;
}

void Viewport::paintGL() {
    // The window's own framebuffer (0 with NoPartialUpdate), at the window's device size.
    const qreal dpr = m_window->devicePixelRatio();
    renderFrame(m_window->defaultFramebufferObject(),
                std::max(1, int(std::lround(m_window->width() * dpr))),
                std::max(1, int(std::lround(m_window->height() * dpr))));
}

void Viewport::renderFrame(unsigned framebuffer, int fullW, int fullH) {
    Timer timer;
    // The host time: the gap since the previous frame ended, when that frame asked for this
    // one at once (otherwise the gap is the artist's idle time). A gap over a second is a
    // stall (a dialog, a blocked event loop), not a frame's cost.
    constexpr size_t HOST_SAMPLES = 15;
    if (m_nextFrameChained && m_sinceFrameEnd.isValid()) {
        const double gap = double(m_sinceFrameEnd.nsecsElapsed()) * 1e-6;
        if (gap < 1000.0) {
            if (m_hostSamples.size() < HOST_SAMPLES)
                m_hostSamples.push_back(gap);
            else
                m_hostSamples[m_hostNext] = gap;
            m_hostNext = (m_hostNext + 1) % HOST_SAMPLES;
            m_stats.hostMs = medianMs(m_hostSamples);
        }
    }
    m_nextFrameChained = false;
    // A clear only where no frame is drawn: the tone map writes every pixel of a frame.
    const auto clear = [&] {
        QOpenGLContext* ctx = QOpenGLContext::currentContext();
        if (!ctx)
            return;                               // no context could be made (initError says why)
        QOpenGLFunctions* gl = ctx->functions();  // even when the 4.5 functions are missing
        gl->glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
        gl->glViewport(0, 0, fullW, fullH);
        gl->glClearColor(0.16f, 0.17f, 0.19f, 1.f);
        gl->glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    };
    if (!m_glReady || !m_doc->hasObject()) {
        clear();
        if (!m_glReady)
            Q_EMIT frameRendered();  // no frame, but the Statistics dock shows initError
        return;
    }

    PreviewFrame f;
    f.scene = &m_doc->scene();
    f.volume = m_doc->material();
    f.shownMesh = shownMesh();
    f.meshChanged = m_meshDirty;
    f.sceneReplaced = m_sceneReplaced;
    f.dirtyBricks = f.volume->takeDirtyBricks();
    // Reduced-resolution preview: the renderer works at scale × the widget's pixels and its
    // tone-map pass upscales (bilinear) into the widget's framebuffer.
    const float scale = std::clamp(m_render.resolutionScale, 0.125f, 1.f);
    Camera& cam = f.camera;
    cam.position = m_camera.eye();
    cam.target = m_camera.target;
    cam.up = Vector3f(0.f, 1.f, 0.f);
    cam.fovYDeg = m_camera.fovYDeg;
    cam.width = std::max(1, int(std::ceil(float(fullW) * scale)));
    cam.height = std::max(1, int(std::ceil(float(fullH) * scale)));
    cam.nearPlane = std::max(1e-3f, m_camera.distance * 0.01f);  // as OrbitCamera::clipFromView
    cam.farPlane = m_camera.distance * 100.f + 1.f;
    f.settings = m_render;
    f.settings.volumeOverlay = m_render.volumeOverlay && !m_hideOverlays;
    if (m_cursor && m_tool == Tool::Paint && !m_hideOverlays)
        f.cursor = m_cursor;
    f.brushRadius = m_brush.engine.radius * m_brush.radiusScale(m_pressure);
    f.framebuffer = framebuffer;
    f.framebufferWidth = fullW;
    f.framebufferHeight = fullH;
    f.hostMs = m_stats.hostMs;
    try {
        m_preview.render(f);
        m_meshDirty = m_sceneReplaced = false;
    } catch (const std::exception& ex) {
        // A method that fails must not leave the viewport blank: report the error, switch to
        // Direct (which needs no subsurface provider) and draw this frame with it. The
        // renderer dropped the failed method's provider, so choosing it again starts afresh.
        // The dirty bricks taken above went to the failed provider: the retry re-synchronises
        // everything as for a new scene.
        const QString message = QString::fromUtf8(ex.what());
        const std::string failed = f.settings.method;
        m_stats.renderError = message;
        ++m_stats.renderErrors;
        bool drawn = false;
        if (failed != FALLBACK_METHOD) {
            m_render.method = FALLBACK_METHOD;
            m_render.params = {};
            f.settings.method = FALLBACK_METHOD;
            f.settings.params = {};
            f.sceneReplaced = f.meshChanged = true;
            try {
                m_preview.render(f);
                drawn = true;
            } catch (const std::exception& again) {
                m_stats.renderError = QString::fromUtf8(again.what());
                ++m_stats.renderErrors;
            }
        }
        m_meshDirty = false;
        m_sceneReplaced = !drawn;
        if (!drawn)
            clear();
        Q_EMIT renderFailed(message, QString::fromStdString(failed));
    }
    const std::string lastReason = m_stats.preview.autoReason;
    m_stats.preview = m_preview.stats();
    if (m_stats.preview.autoReason != lastReason && !m_stats.preview.autoReason.empty())
        Q_EMIT autoPlanChanged(QString::fromStdString(m_stats.preview.autoReason));
    m_stats.uploadMs = m_stats.preview.uploadMs;
    m_stats.bricksUploaded = m_stats.preview.bricksUploaded;
    // Finished here, so the frame time includes the (software) rasterisation.
    QOpenGLContext::currentContext()->functions()->glFinish();
    countGlErrors();
    drawOverlay(framebuffer, fullW, fullH);  // QPainter over the frame
    countGlErrors();
    m_stats.frameMs = timer.elapsedMs();
    ++m_stats.frames;
    // Progressive methods (dipoles) refine while the user is idle, and Auto times a few Direct
    // frames before its first plan.
    if (m_preview.wantsAnotherFrame() && !m_refinementPaused) {
        QTimer::singleShot(0, this, [this] { update(); });
        m_nextFrameChained = true;
    }
    m_sinceFrameEnd.start();
    m_levelChecker->afterFrame();
    m_autoMeasurer->afterFrame();
    Q_EMIT frameRendered();
}

}  // namespace lucent::app
