// SPDX-License-Identifier: MIT
/// @file
/// @brief What Qt adds around paintGL (docs/benchmarks.md, "Where the rest goes: Qt's
/// composition"): the same PreviewRenderer frame (default scene, direct lighting, 640×360)
/// drawn by three GL hosts, a QOpenGLWidget inside a large main window (the app's old
/// arrangement), the same widget as a 640×360 top-level window, and a QOpenGLWindow embedded
/// with QWidget::createWindowContainer in the large window, then by the app's own viewport
/// (MainWindow with its docks). Run under Xvfb with QT_QPA_PLATFORM=xcb:
///
///     bench_app_compose [--swap-interval N]
///
/// Moved out of the app's main.cpp (it was `lucent --compose-experiment`): an experiment on Qt,
/// not something the app does. lucent-cli evaluate does not cover it (it renders headless,
/// without Qt).

#include "MainWindow.h"
#include "Viewport.h"

#include <lucent/core/Timer.h>
#include <lucent/scene/SceneFile.h>

#include <QApplication>
#include <QEventLoop>
#include <QLabel>
#include <QMainWindow>
#include <QOpenGLContext>
#include <QOpenGLFunctions>
#include <QOpenGLWidget>
#include <QOpenGLWindow>
#include <QSurfaceFormat>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace {

using lucent::Timer;
using lucent::app::MainWindow;

/// Requests a frame and runs the event loop until the viewport has rendered it.
void renderFrame(lucent::app::Viewport* vp) {
    const long long before = vp->stats().frames;
    vp->update();
    while (vp->stats().frames == before)
        QCoreApplication::processEvents(QEventLoop::AllEvents | QEventLoop::WaitForMoreEvents, 5);
}

/// Renderer state of one host (one GL context each).
struct ComposeHostGl {
    lucent::Scene* scene = nullptr;
    lucent::app::PreviewRenderer preview;
    bool first = true;
    double paintMs = 0.0;
    long long swaps = 0;

    void paint(unsigned fbo, int w, int h) {
        Timer t;
        lucent::app::PreviewFrame f;
        f.scene = scene;
        f.volume = scene->objects[0].material.get();
        f.shownMesh = &scene->objects[0].mesh;
        f.sceneReplaced = first;
        first = false;
        f.camera = scene->camera;
        f.camera.width = w;
        f.camera.height = h;
        f.settings.method = "direct";
        f.settings.resolutionScale = 1.f;
        f.framebuffer = fbo;
        f.framebufferWidth = w;
        f.framebufferHeight = h;
        preview.render(f);
        QOpenGLContext::currentContext()->functions()->glFinish();  // as Viewport::paintGL
        paintMs = t.elapsedMs();
    }
};

/// A GL host (QOpenGLWidget or QOpenGLWindow) drawing ComposeHostGl's frame.
template <class Base>
class ComposeHost : public Base {
public:
    explicit ComposeHost(ComposeHostGl* gl) : m_gl(gl) {
        QObject::connect(this, &Base::frameSwapped, this, [this] { ++m_gl->swaps; });
    }
    ~ComposeHost() override {
        this->makeCurrent();
        m_gl->preview.destroy();
        this->doneCurrent();
    }

protected:
    void initializeGL() override { m_gl->preview.create(); }
    void paintGL() override {
        const qreal dpr = this->devicePixelRatioF();
        m_gl->paint(this->defaultFramebufferObject(), int(this->width() * dpr),
                    int(this->height() * dpr));
    }

private:
    ComposeHostGl* m_gl;
};
using ComposeWidget = ComposeHost<QOpenGLWidget>;
using ComposeWindow = ComposeHost<QOpenGLWindow>;

/// update() → frameSwapped, `frames` times; @return medians (total, paintGL) in ms.
std::pair<double, double> timeHost(ComposeHostGl& gl, const std::function<void()>& update,
                                   int frames) {
    std::vector<double> total, paint;
    for (int i = 0; i < frames + 3; ++i) {  // 3 warm-up frames (first upload, shader variants)
        const long long before = gl.swaps;
        Timer t;
        update();
        while (gl.swaps == before)
            QCoreApplication::processEvents(QEventLoop::AllEvents | QEventLoop::WaitForMoreEvents,
                                            5);
        if (i >= 3) {
            total.push_back(t.elapsedMs());
            paint.push_back(gl.paintMs);
        }
    }
    return {lucent::medianMs(total), lucent::medianMs(paint)};
}

/// Shows `view` (640×360) in `win` resized to 1400×1100, about the app's main window, next to
/// a label standing in for the docks.
void showInLargeWindow(QMainWindow& win, QWidget* view) {
    auto* central = new QWidget;
    view->setParent(central);
    view->setFixedSize(640, 360);
    view->move(10, 10);
    auto* label = new QLabel(QStringLiteral("docks stand-in"), central);
    label->setGeometry(660, 10, 200, 30);
    win.setCentralWidget(central);
    win.resize(1400, 1100);
    win.show();
}

/// The app's own viewport (MainWindow at 1400×1100, viewport 640×360, Direct): update() → frame
/// done, `frames` times after 3 warm-up frames. @return medians (total, paintGL) in ms.
std::pair<double, double> timeAppViewport(int frames) {
    MainWindow win(/*restoreSettings=*/false);
    lucent::app::Viewport* vp = win.viewport();
    vp->setFixedSize(640, 360);
    lucent::app::RenderSettings rs = vp->renderSettings();
    rs.method = "direct";
    rs.params = {};
    rs.resolutionScale = 1.f;
    vp->setRenderSettings(rs);
    win.resize(1400, 1100);
    win.show();
    for (int i = 0; i < 20; ++i)
        QCoreApplication::processEvents(QEventLoop::AllEvents, 10);
    std::vector<double> total, paint;
    for (int i = 0; i < frames + 3; ++i) {
        Timer t;
        renderFrame(vp);  // returns after paintGL and the window's swap (same paint event)
        if (i >= 3) {
            total.push_back(t.elapsedMs());
            paint.push_back(vp->stats().frameMs);
        }
    }
    return {lucent::medianMs(total), lucent::medianMs(paint)};
}

/// Runs the hosts one after the other and prints frame, paintGL and Qt's share.
int runComposeExperiment() {
    lucent::Scene scene = lucent::makeDefaultScene();
    const int frames = 20;
    struct Result {
        const char* name;
        double totalMs, paintMs;
    };
    std::vector<Result> results;
    const auto settle = [] {
        for (int i = 0; i < 20; ++i)
            QCoreApplication::processEvents(QEventLoop::AllEvents, 10);
    };
    {  // 1. QOpenGLWidget in a 1400×1100 main window (about the app's size)
        ComposeHostGl gl;
        gl.scene = &scene;
        QMainWindow win;
        auto* w = new ComposeWidget(&gl);
        showInLargeWindow(win, w);
        settle();
        const auto [t, p] = timeHost(
            gl, [w] { w->update(); }, frames);
        results.push_back({"QOpenGLWidget in 1400x1100 window", t, p});
    }
    {  // 2. the widget alone as a 640×360 top-level
        ComposeHostGl gl;
        gl.scene = &scene;
        ComposeWidget w(&gl);
        w.resize(640, 360);
        w.show();
        settle();
        const auto [t, p] = timeHost(
            gl, [&w] { w.update(); }, frames);
        results.push_back({"QOpenGLWidget as 640x360 top-level", t, p});
    }
    {  // 3. QOpenGLWindow in a container in the 1400×1100 window
        ComposeHostGl gl;
        gl.scene = &scene;
        QMainWindow win;
        auto* glWindow = new ComposeWindow(&gl);
        showInLargeWindow(win, QWidget::createWindowContainer(glWindow));
        settle();
        const auto [t, p] = timeHost(
            gl, [glWindow] { glWindow->update(); }, frames);
        results.push_back({"QOpenGLWindow in container, 1400x1100", t, p});
    }
    {  // 4. the app: MainWindow with its docks, the Viewport (QOpenGLWindow in a container)
        const auto [t, p] = timeAppViewport(frames);
        results.push_back({"app Viewport in MainWindow, 1400x1100", t, p});
    }
    const QSurfaceFormat f = QSurfaceFormat::defaultFormat();
    std::printf(
        "compose experiment: PreviewRenderer direct, 640x360, medians of %d frames; "
        "swap interval %d, swap behaviour %d\n",
        frames, f.swapInterval(), int(f.swapBehavior()));
    std::printf("%-40s %10s %10s %12s\n", "host", "frame", "paintGL", "Qt's share");
    for (const Result& r : results)
        std::printf("%-40s %7.1f ms %7.1f ms %9.1f ms\n", r.name, r.totalMs, r.paintMs,
                    r.totalMs - r.paintMs);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    MainWindow::useGlSurfaceFormat();
    for (int i = 1; i + 1 < argc; ++i)
        if (std::strcmp(argv[i], "--swap-interval") == 0) {
            // Before any window exists, so that every context gets it.
            QSurfaceFormat f = QSurfaceFormat::defaultFormat();
            f.setSwapInterval(std::stoi(argv[i + 1]));
            QSurfaceFormat::setDefaultFormat(f);
        }
    QApplication app(argc, argv);
    return runComposeExperiment();
}
