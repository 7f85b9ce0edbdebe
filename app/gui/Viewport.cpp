// SPDX-License-Identifier: MIT
/// @file
/// @brief Viewport: GL resources, camera, picking and painting interaction.

#include "Viewport.h"

#include "Document.h"

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#if LUCENT_APP_HAS_DEFORM
#include <lucent/mesh/Deform.h>
#endif

#include <QKeyEvent>
#include <QMouseEvent>
#include <QOpenGLContext>
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

// ---- Viewport -------------------------------------------------------------------------------

Viewport::Viewport(Document* doc, QWidget* parent) : QOpenGLWidget(parent), m_doc(doc) {
    setMouseTracking(true);
    setFocusPolicy(Qt::StrongFocus);
    setMinimumSize(320, 180);
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
    onSceneReplaced();
}

bool Viewport::hasDeformation() {
    return LUCENT_APP_HAS_DEFORM != 0;
}

Viewport::~Viewport() {
    if (m_glReady && context()) {
        makeCurrent();
        cleanupGL();
        doneCurrent();
    }
}

void Viewport::setRenderSettings(const RenderSettings& s) {
    m_render = s;
    m_render.steps = std::clamp(m_render.steps, 1, 512);
    m_render.lightSteps = std::clamp(m_render.lightSteps, 1, 128);
    m_render.sslpvGrid = m_render.sslpvGrid <= 16 ? 16 : m_render.sslpvGrid <= 32 ? 32 : 64;
    m_render.sslpvSteps = std::clamp(m_render.sslpvSteps, 1, 512);
    m_render.sslpvOrder = m_render.sslpvOrder == 2 ? 2 : 1;
    m_render.dipoleSpp = std::clamp(m_render.dipoleSpp, 1, 4096);
    if (s.turntable && !m_turntable.isActive())
        m_turntable.start();
    if (!s.turntable)
        m_turntable.stop();
    m_render.deform = s.deform && hasDeformation();
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
    m_meshDirty = true;
    m_sceneReplaced = true;
    m_stroking = false;
    m_drag = Drag::None;
    update();
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
    try {
        m_doc->beginStroke(m_brush.engine);
    } catch (const std::exception& ex) {
        Q_EMIT paintError(QString::fromUtf8(ex.what()));
        return;
    }
    m_stroking = true;
    m_lastStamp = stampCenter(hit);
    m_doc->strokeStamp(m_lastStamp);
}

void Viewport::continueStroke(const PickHit& hit) {
    if (!m_stroking)
        return;
    // Stamps every spacing·radius mm along the straight path from the last stamp towards the
    // current hit (Brush.h spacing convention), never closer than half a voxel.
    const MaterialVolume* vol = m_doc->material();
    const float spacing = std::max(m_brush.engine.spacing * m_brush.engine.radius,
                                   vol ? 0.5f * vol->spec().voxelSize : 0.f);
    const Point3f target = stampCenter(hit);
    for (Vector3f seg = target - m_lastStamp; glm::length(seg) >= spacing && spacing > 0.f;
         seg = target - m_lastStamp) {
        m_lastStamp += glm::normalize(seg) * spacing;
        m_doc->strokeStamp(m_lastStamp);
    }
}

void Viewport::endStroke() {
    if (!m_stroking)
        return;
    m_stroking = false;
    m_doc->endStroke(tr("Paint stroke"));
}

int Viewport::strokeBetween(const QPointF& a, const QPointF& b) {
    const int samples = 16;
    const size_t before = m_doc->history().undoCount();
    for (int i = 0; i <= samples; ++i) {
        const QPointF p = a + (b - a) * (double(i) / samples);
        const auto hit = pickAt(p);
        if (!hit)
            continue;
        if (!m_stroking)
            beginStroke(*hit);
        else
            continueStroke(*hit);
    }
    endStroke();
    return int(m_doc->history().undoCount() - before);
}

void Viewport::updateHover(const QPointF& pos) {
    const auto hit = pickAt(pos);
    if (hit) {
        m_cursor = hit->position;
        if (const MaterialVolume* vol = m_doc->material()) {
            const Coord c =
                vol->spec().cellOf(hit->position - hit->normal * (0.5f * vol->spec().voxelSize));
            if (vol->spec().contains(c)) {
                const MaterialSample s = vol->at(c);
                Q_EMIT hoverVoxel(
                    QStringLiteral("voxel (%1, %2, %3)  σt = %4 %5 %6 mm⁻¹  σs′ = %7 %8 %9 mm⁻¹")
                        .arg(c.x)
                        .arg(c.y)
                        .arg(c.z)
                        .arg(double(s.sigma_t.r), 0, 'g', 3)
                        .arg(double(s.sigma_t.g), 0, 'g', 3)
                        .arg(double(s.sigma_t.b), 0, 'g', 3)
                        .arg(double(s.sigma_s.r), 0, 'g', 3)
                        .arg(double(s.sigma_s.g), 0, 'g', 3)
                        .arg(double(s.sigma_s.b), 0, 'g', 3));
            }
        }
    } else {
        m_cursor.reset();
    }
    update();
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
        const auto hit = pickAt(e->position());
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
            Q_EMIT paintError(tr("painting is paused while the deformation animation runs"));
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
            if (const auto hit = pickAt(e->position()))
                continueStroke(*hit);
            updateHover(e->position());
            break;
        case Drag::None:
            updateHover(e->position());
            break;
    }
}

void Viewport::mouseReleaseEvent(QMouseEvent* e) {
    if (m_drag == Drag::Paint)
        endStroke();
    m_drag = Drag::None;
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
    QOpenGLWidget::keyPressEvent(e);
}

void Viewport::leaveEvent(QEvent*) {
    m_cursor.reset();
    update();
}

// ---- GL -------------------------------------------------------------------------------------

void Viewport::initializeGL() {
    try {
        if (!initializeOpenGLFunctions())
            LUCENT_THROW(GpuError, "OpenGL 4.5 core functions are not available (got ",
                         context()->format().majorVersion(), ".",
                         context()->format().minorVersion(), ")");
        m_stats.glRenderer =
            QStringLiteral("%1 — %2").arg(reinterpret_cast<const char*>(glGetString(GL_RENDERER)),
                                          reinterpret_cast<const char*>(glGetString(GL_VERSION)));
        m_preview.create();  // programs from the engine's shader library (shaders/)
        m_glReady = true;
        m_meshDirty = m_sceneReplaced = true;
        connect(context(), &QOpenGLContext::aboutToBeDestroyed, this, [this] {
            makeCurrent();
            cleanupGL();
            doneCurrent();
        });
    } catch (const std::exception& ex) {
        m_stats.initError = QString::fromUtf8(ex.what());
    }
    while (m_glReady && glGetError() != GL_NO_ERROR)
        ++m_stats.glErrors;
}

void Viewport::cleanupGL() {
    if (!m_glReady)
        return;
    m_preview.destroy();
    m_glReady = false;
}

void Viewport::resizeGL(int, int) {}

const TriangleMesh* Viewport::shownMesh() {
    const TriangleMesh* mesh = m_doc->mesh();
#if LUCENT_APP_HAS_DEFORM
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
#endif
    return mesh;
}

void Viewport::paintGL() {
    Timer timer;
    const qreal dpr = devicePixelRatioF();
    const int fullW = std::max(1, int(width() * dpr)), fullH = std::max(1, int(height() * dpr));
    glBindFramebuffer(GL_FRAMEBUFFER, defaultFramebufferObject());
    glViewport(0, 0, fullW, fullH);
    glClearColor(0.16f, 0.17f, 0.19f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (!m_glReady || !m_doc->hasObject())
        return;

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
    if (m_cursor && m_tool == Tool::Paint)
        f.cursor = m_cursor;
    f.brushRadius = m_brush.engine.radius;
    f.framebuffer = defaultFramebufferObject();
    f.framebufferWidth = fullW;
    f.framebufferHeight = fullH;
    try {
        m_preview.render(f);
        m_meshDirty = m_sceneReplaced = false;
    } catch (const std::exception& ex) {
        // Shown in the Statistics dock; the frame stays cleared. The dirty bricks taken above
        // may be lost: the next frame re-synchronises everything.
        m_stats.initError = QString::fromUtf8(ex.what());
        ++m_stats.glErrors;
        m_sceneReplaced = true;
    }
    m_stats.preview = m_preview.stats();
    m_stats.uploadMs = m_stats.preview.uploadMs;
    m_stats.bricksUploaded = m_stats.preview.bricksUploaded;
    glFinish();  // so the frame time includes the (software) rasterisation
    while (glGetError() != GL_NO_ERROR)
        ++m_stats.glErrors;
    m_stats.frameMs = timer.elapsedMs();
    ++m_stats.frames;
    // Progressive methods (dipoles) refine while the user is idle.
    if (m_preview.wantsAnotherFrame())
        QTimer::singleShot(0, this, qOverload<>(&QWidget::update));
    Q_EMIT frameRendered();
}

}  // namespace lucent::app
