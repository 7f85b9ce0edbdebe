// SPDX-License-Identifier: MIT
/// @file
/// @brief Viewport: GL resources, camera, picking and painting interaction.

#include "Viewport.h"

#include "Document.h"
#include "GuiShaders.h"

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
    m_volumeFull = true;
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

namespace {

unsigned compileStage(QOpenGLFunctions_4_5_Core* gl, GLenum type, const char* src,
                      const char* name) {
    const GLuint s = gl->glCreateShader(type);
    gl->glShaderSource(s, 1, &src, nullptr);
    gl->glCompileShader(s);
    GLint ok = 0;
    gl->glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        gl->glGetShaderInfoLog(s, sizeof log, nullptr, log);
        gl->glDeleteShader(s);
        LUCENT_THROW(GpuError, "shader ", name, " failed to compile: ", log);
    }
    return s;
}

}  // namespace

unsigned Viewport::compileProgram() {
    const GLuint vs = compileStage(this, GL_VERTEX_SHADER, shaders::SURFACE_VERT, "surface.vert");
    const GLuint fs = compileStage(this, GL_FRAGMENT_SHADER, shaders::SURFACE_FRAG, "surface.frag");
    const GLuint p = glCreateProgram();
    glAttachShader(p, vs);
    glAttachShader(p, fs);
    glLinkProgram(p);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetProgramInfoLog(p, sizeof log, nullptr, log);
        glDeleteProgram(p);
        LUCENT_THROW(GpuError, "surface program failed to link: ", log);
    }
    return p;
}

void Viewport::initializeGL() {
    try {
        if (!initializeOpenGLFunctions())
            LUCENT_THROW(GpuError, "OpenGL 4.5 core functions are not available (got ",
                         context()->format().majorVersion(), ".",
                         context()->format().minorVersion(), ")");
        m_stats.glRenderer =
            QStringLiteral("%1 — %2").arg(reinterpret_cast<const char*>(glGetString(GL_RENDERER)),
                                          reinterpret_cast<const char*>(glGetString(GL_VERSION)));
        m_program = compileProgram();
        glGenVertexArrays(1, &m_vao);
        glGenBuffers(1, &m_vbo);
        glGenBuffers(1, &m_ebo);
        glGenTextures(1, &m_texSigmaT);
        glGenTextures(1, &m_texSigmaS);
        m_glReady = true;
        m_meshDirty = m_volumeFull = true;
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
    glDeleteProgram(m_program);
    glDeleteVertexArrays(1, &m_vao);
    glDeleteBuffers(1, &m_vbo);
    glDeleteBuffers(1, &m_ebo);
    glDeleteTextures(1, &m_texSigmaT);
    glDeleteTextures(1, &m_texSigmaS);
    glDeleteFramebuffers(1, &m_lowFbo);
    glDeleteRenderbuffers(2, m_lowRb);
    m_lowFbo = m_lowRb[0] = m_lowRb[1] = 0;
    m_lowSize = QSize();
    m_program = m_vao = m_vbo = m_ebo = m_texSigmaT = m_texSigmaS = 0;
    m_texResolution = 0;
    m_glReady = false;
}

void Viewport::resizeGL(int, int) {}

void Viewport::uploadMesh() {
    const TriangleMesh* mesh = m_doc->mesh();
    std::vector<float> interleaved;  // posed position, posed normal, rest position
    std::vector<uint32_t> indices;
    if (mesh) {
        const TriangleMesh* shown = mesh;
#if LUCENT_APP_HAS_DEFORM
        TriangleMesh posed;
        if (m_render.deform && !mesh->isEmpty()) {
            // A twist about the vertical axis through the object's centre: ±0.6 rad over its
            // height, oscillating at 0.5 Hz (Deform.h: amount·sin(2π·rate·t)).
            const Bounds3f b = mesh->bounds();
            Deformer twist;
            twist.type = DeformerType::Twist;
            twist.center = b.center();
            twist.axis = Vector3f(0.f, 1.f, 0.f);
            twist.amount = 0.6f / std::max(b.extent().y, 1e-3f);
            twist.rateHz = 0.5f;
            posed = deform(*mesh, {twist}, float(m_clock.elapsed()) * 1e-3f);
            shown = &posed;
        }
#endif
        interleaved.reserve(mesh->positions.size() * 9);
        for (size_t i = 0; i < mesh->positions.size(); ++i) {
            const Point3f& p = shown->positions[i];
            const Point3f& r = mesh->positions[i];
            const Normal3f n =
                i < shown->normals.size() ? shown->normals[i] : Normal3f(0.f, 1.f, 0.f);
            interleaved.insert(interleaved.end(), {p.x, p.y, p.z, n.x, n.y, n.z, r.x, r.y, r.z});
        }
        for (const auto& t : mesh->triangles)
            indices.insert(indices.end(), {t[0], t[1], t[2]});
    }
    glBindVertexArray(m_vao);
    glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(interleaved.size() * sizeof(float)),
                 interleaved.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m_ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(uint32_t)),
                 indices.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 9 * sizeof(float), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 9 * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, 9 * sizeof(float),
                          reinterpret_cast<const void*>(6 * sizeof(float)));
    glBindVertexArray(0);
    m_indexCount = int(indices.size());
    m_meshDirty = false;
}

void Viewport::uploadVolume(bool full) {
    MaterialVolume* vol = m_doc->material();
    if (!vol)
        return;
    Timer timer;
    const int res = vol->resolution();
    constexpr int B = MaterialVolume::BRICK, BV = MaterialVolume::BRICK_VOXELS;
    std::vector<int> bricks = vol->takeDirtyBricks();
    if (full || res != m_texResolution) {
        // (Re)allocate both textures at the grid resolution; texels are voxels (GL_NEAREST:
        // the piecewise-constant lookup rule of MaterialVolume).
        for (GLuint tex : {m_texSigmaT, m_texSigmaS}) {
            glDeleteTextures(1, &tex);
        }
        glGenTextures(1, &m_texSigmaT);
        glGenTextures(1, &m_texSigmaS);
        for (GLuint tex : {m_texSigmaT, m_texSigmaS}) {
            glBindTexture(GL_TEXTURE_3D, tex);
            glTexStorage3D(GL_TEXTURE_3D, 1, GL_RGBA32F, res, res, res);
            glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
            glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
            for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
                glTexParameteri(GL_TEXTURE_3D, w, GL_CLAMP_TO_BORDER);
            const float zero[4] = {0.f, 0.f, 0.f, 0.f};
            glTexParameterfv(GL_TEXTURE_3D, GL_TEXTURE_BORDER_COLOR, zero);
        }
        m_texResolution = res;
        bricks.clear();
        for (int b = 0; b < vol->brickCount(); ++b)
            bricks.push_back(b);
    }
    std::vector<float> st(size_t(BV) * 4), ss(size_t(BV) * 4);
    for (int b : bricks) {
        const float* d = vol->brickData(b);
        for (int v = 0; v < BV; ++v)
            for (int c = 0; c < 3; ++c) {
                st[size_t(v) * 4 + c] =
                    d[size_t(MaterialVolume::component(Channel::SigmaT, c)) * BV + v];
                ss[size_t(v) * 4 + c] =
                    d[size_t(MaterialVolume::component(Channel::SigmaS, c)) * BV + v];
            }
        const Coord o = vol->brickOrigin(b);
        const Coord size = glm::min(Coord(B), Coord(res) - o);
        if (size != Coord(B)) {  // partial brick at the grid's far edge: compact the rows
            std::vector<float> cst, css;
            for (int z = 0; z < size.z; ++z)
                for (int y = 0; y < size.y; ++y)
                    for (int x = 0; x < size.x; ++x) {
                        const size_t v = size_t(MaterialVolume::voxelInBrick(x, y, z)) * 4;
                        cst.insert(cst.end(), st.begin() + long(v), st.begin() + long(v) + 4);
                        css.insert(css.end(), ss.begin() + long(v), ss.begin() + long(v) + 4);
                    }
            glTextureSubImage3D(m_texSigmaT, 0, o.x, o.y, o.z, size.x, size.y, size.z, GL_RGBA,
                                GL_FLOAT, cst.data());
            glTextureSubImage3D(m_texSigmaS, 0, o.x, o.y, o.z, size.x, size.y, size.z, GL_RGBA,
                                GL_FLOAT, css.data());
        } else {
            glTextureSubImage3D(m_texSigmaT, 0, o.x, o.y, o.z, B, B, B, GL_RGBA, GL_FLOAT,
                                st.data());
            glTextureSubImage3D(m_texSigmaS, 0, o.x, o.y, o.z, B, B, B, GL_RGBA, GL_FLOAT,
                                ss.data());
        }
    }
    m_volumeFull = false;
    if (!bricks.empty()) {
        m_stats.uploadMs = timer.elapsedMs();
        m_stats.bricksUploaded = int(bricks.size());
    }
}

void Viewport::paintGL() {
    Timer timer;
    const qreal dpr = devicePixelRatioF();
    glViewport(0, 0, GLsizei(width() * dpr), GLsizei(height() * dpr));
    glClearColor(0.16f, 0.17f, 0.19f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (!m_glReady || !m_doc->hasObject())
        return;
    if (m_meshDirty)
        uploadMesh();
    uploadVolume(m_volumeFull);

    // Reduced-resolution preview: render into an offscreen target of scale × the widget's
    // pixels, then upscale (bilinear blit) into the widget's framebuffer.
    const int fullW = int(width() * dpr), fullH = int(height() * dpr);
    const float scale = std::clamp(m_render.resolutionScale, 0.125f, 1.f);
    const bool reduced = scale < 1.f;
    const int lowW = std::max(1, int(std::ceil(float(fullW) * scale)));
    const int lowH = std::max(1, int(std::ceil(float(fullH) * scale)));
    if (reduced) {
        if (lowW != m_lowSize.width() || lowH != m_lowSize.height()) {
            glDeleteFramebuffers(1, &m_lowFbo);
            glDeleteRenderbuffers(2, m_lowRb);
            glCreateFramebuffers(1, &m_lowFbo);
            glCreateRenderbuffers(2, m_lowRb);
            glNamedRenderbufferStorage(m_lowRb[0], GL_RGBA8, lowW, lowH);
            glNamedRenderbufferStorage(m_lowRb[1], GL_DEPTH_COMPONENT24, lowW, lowH);
            glNamedFramebufferRenderbuffer(m_lowFbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                           m_lowRb[0]);
            glNamedFramebufferRenderbuffer(m_lowFbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                                           m_lowRb[1]);
            m_lowSize = QSize(lowW, lowH);
        }
        glBindFramebuffer(GL_FRAMEBUFFER, m_lowFbo);
        glViewport(0, 0, lowW, lowH);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    }

    const Scene& scene = m_doc->scene();
    const MaterialVolume& vol = *scene.objects[0].material;
    const Mat4f clipFromWorld =
        m_camera.clipFromView(float(width()) / float(std::max(height(), 1))) *
        m_camera.viewFromWorld();

    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glUseProgram(m_program);
    auto loc = [this](const char* n) { return glGetUniformLocation(m_program, n); };
    glUniformMatrix4fv(loc("u_clipFromWorld"), 1, GL_FALSE, glm::value_ptr(clipFromWorld));
    const Point3f eye = m_camera.eye();
    glUniform3f(loc("u_eye"), eye.x, eye.y, eye.z);
    glUniform1i(loc("u_method"), int(m_render.method));
    glUniform1i(loc("u_steps"), m_render.steps);
    glUniform1i(loc("u_lightSteps"), m_render.lightSteps);
    glUniform1f(loc("u_exposure"), std::exp2(m_render.exposureStops));
    glUniform1f(loc("u_eta"), scene.eta);
    glUniform3f(loc("u_ambient"), m_render.ambient, m_render.ambient, m_render.ambient);
    const int lightCount = std::min<int>(int(scene.lights.size()), 4);
    glUniform1i(loc("u_lightCount"), lightCount);
    for (int i = 0; i < lightCount; ++i) {
        const Light& l = scene.lights[size_t(i)];
        char name[40];
        const auto uni = [&](const char* base) {
            std::snprintf(name, sizeof name, "%s[%d]", base, i);
            return loc(name);
        };
        Rgb intensity = l.intensity;
        // Sphere light of radiance L, radius R: intensity L·πR² W/sr seen from afar.
        if (l.type == Light::Type::Sphere)
            intensity *= PI * l.radius * l.radius;
        glUniform1i(uni("u_lightType"), int(l.type));
        glUniform3f(uni("u_lightPos"), l.position.x, l.position.y, l.position.z);
        glUniform3f(uni("u_lightDir"), l.direction.x, l.direction.y, l.direction.z);
        glUniform3f(uni("u_lightI"), intensity.r, intensity.g, intensity.b);
        glUniform2f(uni("u_spotCos"), std::cos(glm::radians(l.spotOuterDeg)),
                    std::cos(glm::radians(l.spotInnerDeg)));
    }
    const GridSpec& spec = vol.spec();
    glUniform3f(loc("u_gridOrigin"), spec.origin.x, spec.origin.y, spec.origin.z);
    glUniform1f(loc("u_gridSize"), spec.voxelSize * float(spec.resolution));
    glUniform1f(loc("u_voxelSize"), spec.voxelSize);
    if (m_cursor && m_tool == Tool::Paint)
        glUniform4f(loc("u_brush"), m_cursor->x, m_cursor->y, m_cursor->z, m_brush.engine.radius);
    else
        glUniform4f(loc("u_brush"), 0.f, 0.f, 0.f, -1.f);
    const GLint filter = m_render.smoothVoxels ? GL_LINEAR : GL_NEAREST;
    for (GLuint tex : {m_texSigmaT, m_texSigmaS}) {
        glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, filter);
        glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, filter);
    }
    glBindTextureUnit(0, m_texSigmaT);
    glBindTextureUnit(1, m_texSigmaS);
    glUniform1i(loc("u_sigmaT"), 0);
    glUniform1i(loc("u_sigmaS"), 1);
    glBindVertexArray(m_vao);
    glDrawElements(GL_TRIANGLES, m_indexCount, GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
    glUseProgram(0);
    if (reduced) {
        glBlitNamedFramebuffer(m_lowFbo, defaultFramebufferObject(), 0, 0, lowW, lowH, 0, 0, fullW,
                               fullH, GL_COLOR_BUFFER_BIT, GL_LINEAR);
        glBindFramebuffer(GL_FRAMEBUFFER, defaultFramebufferObject());
    }
    glFinish();  // so the frame time includes the (software) rasterisation
    while (glGetError() != GL_NO_ERROR)
        ++m_stats.glErrors;
    m_stats.frameMs = timer.elapsedMs();
    ++m_stats.frames;
    Q_EMIT frameRendered();
}

}  // namespace lucent::app
