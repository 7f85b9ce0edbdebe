// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The central 3-D viewport: hosts the OpenGL 4.5 core context in which PreviewRenderer
/// (gpu::SceneRenderer + the selected subsurface provider) draws the painted object; orbit/pan/
/// zoom camera, ray-picked brush painting and eyedropper.
///
/// After a stroke only the volume's dirty 8³ bricks are handed to the renderer (SSLPV
/// re-resamples and re-propagates only them, the texture-based passes re-upload only them).
///
/// Light gizmos: every light has a handle drawn over the frame (QPainter, in the light's
/// colour). Clicking a handle selects the light and dragging moves it, one undo step per drag:
/// point, spot and sphere lights move on the view-aligned plane through their position;
/// directional lights move on a sphere around the object and shine towards its centre.
/// Tablet pens paint with pressure (AppBrush::pressureMode); the mouse is pressure 1.
///
/// Hosting: Viewport is a plain QWidget facade; the GL drawing happens in a QOpenGLWindow
/// (ViewportWindow, Viewport.cpp) embedded with QWidget::createWindowContainer and filling the
/// facade. A QOpenGLWidget would make Qt compose the whole top-level window on every frame
/// (18–79 ms a frame on llvmpipe/Xvfb, docs/benchmarks.md "App latency"); the native GL window
/// swaps on its own (3–4 ms). Input reaching the GL window (mouse, wheel, keys, tablet, hover,
/// leave, drag-and-drop, context menu) is handed to the facade's handlers, so events sent to
/// either behave the same.
///
///     auto* vp = new Viewport(doc, parent);   // a widget: lay it out, size it, connect it
///     vp->update();                           // schedules a GL frame
///     QImage frame = vp->grabFramebuffer();   // renders a frame offscreen and reads it back

#include "AutoLevelCheck.h"
#include "AutoMeasure.h"
#include "BrushTool.h"
#include "PreviewRenderer.h"

#include <lucent/mesh/MeshPicker.h>

#include <QElapsedTimer>
#include <QPixmap>
#include <QTimer>
#include <QWidget>

#include <memory>
#include <optional>

class QWindow;

namespace lucent::app {

class Document;
class ViewportWindow;

/// Orbit camera around a target point; +y is up.
struct OrbitCamera {
    Point3f target{0.f};
    float distance = 60.f;  ///< mm
    float yawDeg = 0.f;     ///< about +y, 0 looks along −z
    float pitchDeg = 0.f;   ///< elevation, clamped to ±89°
    float fovYDeg = 40.f;

    [[nodiscard]] Point3f eye() const;
    [[nodiscard]] Mat4f viewFromWorld() const;
    [[nodiscard]] Mat4f clipFromView(float aspect) const;
    /// Places the camera at `eye` looking at `target`.
    void lookAt(const Point3f& eye, const Point3f& target);
};

/// Per-frame timings shown in the Statistics dock.
struct ViewportStats {
    double frameMs = 0.0;  ///< last paintGL, GPU work included (glFinish)
    /// The app's own time per frame outside paintGL (Qt's event loop, the composition and the
    /// buffer swap): the median gap between one frame's end and the next frame's start over
    /// the last frames drawn back to back (a progressive method refining); 0 until measured.
    /// Auto adds it to the predictions of live costs measured headless (docs/planner.md).
    double hostMs = 0.0;
    double uploadMs = 0.0;   ///< last material update (brick upload / incremental resample)
    int bricksUploaded = 0;  ///< bricks in the last material update
    PreviewStats preview;    ///< per-pass timings and method details of the last frame
    long long frames = 0;    ///< frames rendered since start
    int glErrors = 0;        ///< glGetError() != GL_NO_ERROR count since start
    QString glRenderer;      ///< GL_RENDERER / GL_VERSION
    QString initError;       ///< non-empty when GL set-up failed
    /// Message of the last frame that failed to render (empty if none did); the viewport then
    /// switched to the Direct method (Viewport::renderFailed).
    QString renderError;
    int renderErrors = 0;  ///< frames that failed to render since start
};

class Viewport : public QWidget {
    Q_OBJECT
public:
    enum class Tool { Paint, Eyedropper };
    /// Radius within which a click picks a light handle, logical pixels.
    static constexpr double HANDLE_PICK_PX = 9.0;
    /// The method a failing preview method falls back to: it needs no subsurface pass.
    static constexpr const char* FALLBACK_METHOD = "direct";

    explicit Viewport(Document* doc, QWidget* parent = nullptr);
    ~Viewport() override;

    OrbitCamera& camera() { return m_camera; }
    [[nodiscard]] const RenderSettings& renderSettings() const { return m_render; }
    void setRenderSettings(const RenderSettings& s);
    AppBrush& brush() { return m_brush; }
    void setTool(Tool t) { m_tool = t; }
    [[nodiscard]] Tool tool() const { return m_tool; }
    [[nodiscard]] const ViewportStats& stats() const { return m_stats; }
    /// The renderer behind the GL window (its shader library, for tests and live editing).
    PreviewRenderer& previewRenderer() { return m_preview; }
    /// Auto's level check, run on a worker after frames (AutoLevelCheck.h).
    AutoLevelChecker& levelChecker() { return *m_levelChecker; }
    /// Auto measuring the scene on its own, on a worker once the artist pauses (AutoMeasure.h).
    AutoMeasurer& autoMeasurer() { return *m_autoMeasurer; }
    /// While paused, a progressive method does not refine in idle frames (a frame is drawn only
    /// when something asks for one), Auto's level check starts no render and a measurement of
    /// Auto's in progress stops (to run again after): the live-cost calibration then has the
    /// machine to itself. Resuming asks for a frame.
    void setRefinementPaused(bool paused);
    [[nodiscard]] bool refinementPaused() const { return m_refinementPaused; }

    /// `camera` set to this view: the orbit camera's eye, target and field of view (perspective,
    /// y up), `width` pixels wide with the viewport's aspect (at least 16 pixels high).
    void applyViewTo(Camera& camera, int width) const;
    /// The document's scene with its own copy of the painted material, seen through this view
    /// (applyViewTo) `width` pixels wide: what a worker thread may render while painting goes
    /// on (Auto's level check and measurement, the Reference dock). Requires an object.
    [[nodiscard]] Scene frozenSceneOfView(int width) const;
    /// Frames the object (F key): target at its centre, distance to fit its bounds.
    void frameObject();
    /// Whether the camera sees part of the object's bounding sphere at a visible size (more
    /// than 2 % of the field of view). A new scene whose camera does not is framed.
    [[nodiscard]] bool cameraShowsObject() const;
    /// Camera ray through widget position `pos` (logical pixels, origin top-left).
    void cameraRay(const QPointF& pos, Point3f& origin, Vector3f& direction) const;
    /// Mesh hit under widget position `pos`.
    [[nodiscard]] std::optional<PickHit> pickAt(const QPointF& pos) const;
    /// Paints a straight stroke from a to b (widget positions) as one undoable command, the
    /// way a mouse drag does; used by scripted tests and benchmarks. @return undo steps added
    /// (1 when the stroke changed voxels, else 0).
    int strokeBetween(const QPointF& a, const QPointF& b);

    //! @{ \name Light gizmos
    /// Selected light (index into Scene::lights), −1 for none. Selecting emits nothing.
    [[nodiscard]] int selectedLight() const { return m_selectedLight; }
    void setSelectedLight(int index);
    void setLightGizmosVisible(bool visible);
    [[nodiscard]] bool lightGizmosVisible() const { return m_gizmosVisible; }
    /// World position of light `index`'s handle (mm): the light's position, or for a
    /// directional light the point of the gizmo sphere it shines from (centre − R·direction).
    [[nodiscard]] std::optional<Point3f> lightHandleWorld(int index) const;
    /// Handle of light `index` in widget coordinates; empty when it is behind the camera.
    [[nodiscard]] std::optional<QPointF> lightHandle(int index) const;
    /// Light whose handle is nearest to `pos` within HANDLE_PICK_PX, −1 for none.
    [[nodiscard]] int lightAt(const QPointF& pos) const;
    /// Sphere on which directional-light handles move: the object's bounding sphere × 1.5.
    void gizmoSphere(Point3f& center, float& radius) const;
    /// Widget position of world point `p`; empty when it is behind the camera.
    [[nodiscard]] std::optional<QPointF> project(const Point3f& p) const;
    //! @}

    //! @{ \name GL window
    /// Schedules a frame of the GL window; calls before it is drawn coalesce into one. Hides
    /// QWidget::update() (the facade itself draws nothing; a QWidget::update() through a base
    /// pointer reaches paintEvent, which schedules a frame too).
    void update();
    /// Renders a frame, overlays included, into an offscreen framebuffer of the viewport's
    /// size in device pixels and returns it (display sRGB, opaque). Null before the GL window
    /// has been shown once (no context yet).
    [[nodiscard]] QImage grabFramebuffer();
    /// `widget->grab()` with the viewport's frame (grabFramebuffer) painted where the viewport
    /// sits: QWidget::grab() cannot read the native GL window. `widget`: the viewport or one of
    /// its ancestors (e.g. the main window); for another widget it is a plain grab().
    [[nodiscard]] QPixmap grabWithFrame(QWidget* widget);
    /// The QOpenGLWindow that draws and receives the real input events.
    [[nodiscard]] QWindow* glWindow() const;
    //! @}

    /// The last frame's linear radiance at render resolution, W/(mm²·sr)
    /// (PreviewRenderer::linearImage). @throw GpuError when nothing has been rendered.
    [[nodiscard]] ImageRgb linearImage();
    /// Renders a frame without gizmos and brush cursor and returns it (display sRGB).
    [[nodiscard]] QImage grabRender();

Q_SIGNALS:
    /// A frame was drawn (stats() updated); also after a failed GL set-up (stats().initError
    /// non-empty, stats().frames unchanged), so the failure can be shown.
    void frameRendered();
    void eyedropped(const lucent::MaterialSample& sample);
    /// The voxel under the cursor and its coefficients; empty when the cursor is off the
    /// object or outside the viewport.
    void hoverVoxel(const QString& text);
    void paintError(const QString& message);
    /// A frame of preview method `method` (registry name) failed with `message`. The frame was
    /// drawn with FALLBACK_METHOD instead, and renderSettings().method is now that.
    void renderFailed(const QString& message, const QString& method);
    /// With the Auto method: the planner's choice or its reason changed (planner::Plan::reason,
    /// one line).
    void autoPlanChanged(const QString& reason);
    /// The user picked light `index` by clicking its handle.
    void lightSelected(int index);

protected:
    void paintEvent(QPaintEvent* e) override;
    void mousePressEvent(QMouseEvent* e) override;
    void mouseMoveEvent(QMouseEvent* e) override;
    void mouseReleaseEvent(QMouseEvent* e) override;
    void wheelEvent(QWheelEvent* e) override;
    void keyPressEvent(QKeyEvent* e) override;
    void leaveEvent(QEvent* e) override;
    void tabletEvent(QTabletEvent* e) override;

private:
    friend class ViewportWindow;  // hands its GL callbacks and input events to the facade

    void initializeGL();
    void paintGL();
    /// One frame into `framebuffer` (w × h device pixels): the preview, then the overlays.
    void renderFrame(unsigned framebuffer, int w, int h);
    /// Sets the cursor shape on the facade and on the GL window (which shows it).
    void setViewCursor(Qt::CursorShape shape);
    void onSceneReplaced();
    void cleanupGL();
    /// Adds the pending glGetError() codes of the current context to stats().glErrors.
    void countGlErrors();
    void beginStroke(const PickHit& hit);
    void continueStroke(const PickHit& hit);
    void endStroke();
    /// End of a mouse or pen drag of the paint tool: closes the stroke, or says that it never
    /// reached the surface.
    void finishDragStroke();
    [[nodiscard]] Point3f stampCenter(const PickHit& hit) const;
    void updateHover(const QPointF& pos);
    /// Emits hoverVoxel when the readout changes (empty: nothing under the cursor).
    void setHoverText(const QString& text);
    void beginLightDrag(int index, const QPointF& pos);
    void continueLightDrag(const QPointF& pos);
    void endLightDrag();
    void drawOverlay(unsigned framebuffer, int w, int h);
    /// The rest mesh, or the twisted one while the deformation animation runs (into m_posed).
    const TriangleMesh* shownMesh();

    Document* m_doc;
    OrbitCamera m_camera;
    RenderSettings m_render;
    AppBrush m_brush;
    Tool m_tool = Tool::Paint;
    ViewportStats m_stats;
    /// hostMs: when the last frame ended and whether it asked for the next at once, and the
    /// recent gaps (a ring of HOST_SAMPLES).
    QElapsedTimer m_sinceFrameEnd;
    bool m_nextFrameChained = false;
    std::vector<double> m_hostSamples;
    size_t m_hostNext = 0;

    // Interaction state.
    enum class Drag { None, Paint, Orbit, Pan, Light } m_drag = Drag::None;
    QPointF m_lastMouse;
    bool m_stroking = false;
    bool m_strokeReached = false;  ///< the current drag has reached the surface
    bool m_strokeRefused = false;  ///< the brush could not paint (paintError said why)
    Point3f m_lastStamp{0.f};
    float m_pressure = 1.f;  ///< pen pressure of the current stamp (mouse: 1)
    bool m_tabletStroke = false;
    // Light gizmos.
    int m_selectedLight = -1;
    bool m_gizmosVisible = true;
    bool m_hideOverlays = false;      ///< grabRender(): the bare render
    bool m_refinementPaused = false;  ///< setRefinementPaused
    std::vector<Light> m_lightsBeforeDrag;
    Point3f m_dragPlanePoint{0.f};  ///< point/spot: the view-aligned plane of the drag
    Vector3f m_dragPlaneNormal{0.f};
    Vector3f m_dragOffset{0.f};  ///< light position − plane hit at the press
    std::optional<Point3f> m_cursor;
    QString m_hoverText;  ///< the voxel readout last emitted (hoverVoxel)
    QTimer m_turntable;
    QTimer m_animation;
    QElapsedTimer m_clock;

    // Rendering (GL objects valid while the GL window's context lives).
    ViewportWindow* m_window = nullptr;  ///< owned by m_container
    QWidget* m_container = nullptr;      ///< child widget hosting m_window
    bool m_glReady = false;
    PreviewRenderer m_preview;
    AutoLevelChecker* m_levelChecker = nullptr;  ///< a child QObject
    AutoMeasurer* m_autoMeasurer = nullptr;      ///< a child QObject
    TriangleMesh m_posed;
    bool m_meshDirty = true, m_sceneReplaced = true;
};

}  // namespace lucent::app
