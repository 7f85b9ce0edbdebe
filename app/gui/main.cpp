// SPDX-License-Identifier: MIT
/// @file
/// @brief Entry point of the `lucent` app.
///
///     lucent [PROJECT|MESH|VDB] [--screenshot PATH] [--frames N] [--benchmark]
///            [--benchmark-json PATH] [--viewport WxH]
///            [--method direct|single|sslpv|dipole|better-dipole]
///            [--paint-demo] [--reference SPP] [--raise DOCKS] [--no-settings]
/// --screenshot grabs the whole window after N rendered frames (default 3) and exits;
/// --benchmark measures start-up to first frame, idle frame time and stroke-to-frame latency.

#include "Document.h"
#include "MainWindow.h"
#include "Viewport.h"
#if LUCENT_APP_HAS_REFERENCE
#include "ReferencePanel.h"
#endif

#include <lucent/core/Timer.h>

#include <QApplication>
#include <QEventLoop>
#include <QCommandLineParser>
#include <QDockWidget>
#include <QFile>
#include <QSurfaceFormat>
#include <QTimer>

#include <algorithm>
#include <utility>
#include <cstdio>
#include <vector>

namespace {

using lucent::Timer;
using lucent::app::MainWindow;

/// Preview method from its command-line name. @return false for an unknown name.
bool parseMethod(const QString& name, lucent::app::RenderSettings::Method& out) {
    using M = lucent::app::RenderSettings::Method;
    const std::pair<const char*, M> names[] = {{"direct", M::Direct},
                                               {"single", M::SingleScattering},
                                               {"sslpv", M::Sslpv},
                                               {"dipole", M::Dipole},
                                               {"better-dipole", M::BetterDipole}};
    for (const auto& [n, m] : names)
        if (name == QLatin1String(n)) {
            out = m;
            return true;
        }
    return false;
}

/// Median of a sample (robust to the odd slow frame on a shared machine).
double median(std::vector<double> v) {
    if (v.empty())
        return 0.0;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Idle frame and stroke-to-frame latency of the current preview method (medians, ms).
struct MethodTiming {
    double idleMs = 0.0, strokeMs = 0.0, strokePaintGlMs = 0.0;
};

/// Requests a frame and runs the event loop until the viewport has rendered it (the path a
/// real repaint takes: update() → paint event → paintGL → composition).
void renderFrame(lucent::app::Viewport* vp) {
    const long long before = vp->stats().frames;
    vp->update();
    while (vp->stats().frames == before)
        QCoreApplication::processEvents(QEventLoop::AllEvents | QEventLoop::WaitForMoreEvents, 5);
}

MethodTiming timeMethod(lucent::app::Viewport* vp) {
    renderFrame(vp);  // settle: the first frame after a change of method compiles nothing new
    const int idleFrames = 15, strokes = 8;
    std::vector<double> idle, latency, frameOnly;
    for (int i = 0; i < idleFrames; ++i) {
        Timer t;
        renderFrame(vp);
        idle.push_back(t.elapsedMs());
    }
    const double cx = vp->width() / 2.0, cy = vp->height() / 2.0;
    for (int i = 0; i < strokes; ++i) {
        const double dy = (i - strokes / 2) * 4.0;
        Timer t;  // stroke (picking + engine stamps + history) → dirty-brick upload → frame
        vp->strokeBetween(QPointF(cx - 40, cy + dy), QPointF(cx + 40, cy + dy));
        renderFrame(vp);
        latency.push_back(t.elapsedMs());
        frameOnly.push_back(vp->stats().frameMs);
    }
    return {median(idle), median(latency), median(frameOnly)};
}

/// Runs the latency harness on a shown window whose first frame has been rendered.
void runBenchmark(MainWindow& w, double startupMs, const QString& jsonPath,
                  const QString& methodFilter) {
    using Method = lucent::app::RenderSettings::Method;
    lucent::app::Viewport* vp = w.viewport();
    lucent::app::RenderSettings rs = vp->renderSettings();
    struct Row {
        const char* name;
        Method method;
        float scale;
        MethodTiming t;
    };
    // Stroke latency of the live methods at the viewport's full resolution (SSLPV at 32³, CPU
    // solve; dipoles at their default samples per frame), plus the direct baseline.
    std::vector<Row> rows = {{"direct, full res (baseline)", Method::Direct, 1.f, {}},
                             {"single-scatter, full res", Method::SingleScattering, 1.f, {}},
                             {"sslpv 32^3, full res", Method::Sslpv, 1.f, {}},
                             {"dipole, full res", Method::Dipole, 1.f, {}},
                             {"better dipole, full res", Method::BetterDipole, 1.f, {}},
                             {"sslpv 32^3, half res", Method::Sslpv, 0.5f, {}}};
    Method only = Method::Direct;
    if (!methodFilter.isEmpty() && parseMethod(methodFilter, only))  // baseline + that method
        std::erase_if(rows,
                      [&](const Row& r) { return r.method != Method::Direct && r.method != only; });
    rs.sslpvGrid = 32;
    rs.sslpvGlSolve = false;
    for (Row& r : rows) {
        rs.method = r.method;
        rs.resolutionScale = r.scale;
        vp->setRenderSettings(rs);
        r.t = timeMethod(vp);
    }
    std::printf("viewport %dx%d, renderer %s\n", vp->width(), vp->height(),
                qPrintable(vp->stats().glRenderer));
    std::printf("startup to first frame: %.1f ms\n", startupMs);
    std::printf("%-36s %11s %14s %10s %12s %14s\n", "method", "idle frame", "stroke->frame",
                "(paintGL)", "stroke/idle", "idle/baseline");
    const double base = rows[0].t.idleMs;  // baseline: direct shading at full resolution
    for (const Row& r : rows)
        std::printf("%-36s %8.1f ms %11.1f ms %7.1f ms %12.2f %14.2f\n", r.name, r.t.idleMs,
                    r.t.strokeMs, r.t.strokePaintGlMs,
                    r.t.idleMs > 0 ? r.t.strokeMs / r.t.idleMs : 0.0,
                    base > 0 ? r.t.idleMs / base : 0.0);
    std::printf(
        "(single-scatter: %d view steps, %d shadow steps; sslpv: %d steps, order %d; "
        "dipole: %d spp/frame)\n",
        rs.steps, rs.lightSteps, rs.sslpvSteps, rs.sslpvOrder, rs.dipoleSpp);
    if (!jsonPath.isEmpty()) {
        QFile f(jsonPath);
        if (f.open(QIODevice::WriteOnly)) {
            QString json = QStringLiteral("{\"viewport\":[%1,%2],\"startup_ms\":%3,\"methods\":[")
                               .arg(vp->width())
                               .arg(vp->height())
                               .arg(startupMs);
            for (size_t i = 0; i < rows.size(); ++i)
                json += QStringLiteral("%1{\"name\":\"%2\",\"idle_ms\":%3,\"stroke_ms\":%4}")
                            .arg(i ? QStringLiteral(",") : QString())
                            .arg(QLatin1String(rows[i].name))
                            .arg(rows[i].t.idleMs)
                            .arg(rows[i].t.strokeMs);
            f.write((json + QStringLiteral("]}\n")).toUtf8());
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    Timer startup;
    QSurfaceFormat fmt;
    fmt.setVersion(4, 5);
    fmt.setProfile(QSurfaceFormat::CoreProfile);
    fmt.setDepthBufferSize(24);
    QSurfaceFormat::setDefaultFormat(fmt);
    QApplication app(argc, argv);
    QApplication::setOrganizationName(QStringLiteral("Lucent"));
    QApplication::setApplicationName(QStringLiteral("lucent"));
    QApplication::setApplicationVersion(QStringLiteral("0.1.0"));

    QCommandLineParser parser;
    parser.setApplicationDescription(
        QStringLiteral("Paint translucent materials and watch them live."));
    parser.addHelpOption();
    parser.addVersionOption();
    parser.addPositionalArgument(QStringLiteral("file"),
                                 QStringLiteral("project, mesh or VDB to open"));
    QCommandLineOption shot(QStringLiteral("screenshot"),
                            QStringLiteral("Grab the window to PATH and exit."),
                            QStringLiteral("PATH"));
    QCommandLineOption frames(QStringLiteral("frames"),
                              QStringLiteral("Frames before the screenshot (3)."),
                              QStringLiteral("N"), QStringLiteral("3"));
    QCommandLineOption bench(
        QStringLiteral("benchmark"),
        QStringLiteral("Measure start-up, idle frame and stroke latency, then exit."));
    QCommandLineOption benchJson(QStringLiteral("benchmark-json"),
                                 QStringLiteral("Also write the results to PATH."),
                                 QStringLiteral("PATH"));
    QCommandLineOption viewportSize(QStringLiteral("viewport"),
                                    QStringLiteral("Viewport size WxH (e.g. 640x360)."),
                                    QStringLiteral("WxH"));
    QCommandLineOption noSettings(
        QStringLiteral("no-settings"),
        QStringLiteral("Ignore saved layout, recent files and autosave."));
    QCommandLineOption paintDemo(QStringLiteral("paint-demo"),
                                 QStringLiteral("Before the screenshot, paint two strokes of a "
                                                "red-tinted material across the view."));
    QCommandLineOption raiseDock(
        QStringLiteral("raise"),
        QStringLiteral("Bring dock tabs to the front (e.g. dockStats,dockPresets)."),
        QStringLiteral("NAMES"));
    QCommandLineOption reference(QStringLiteral("reference"),
                                 QStringLiteral("Before the screenshot, run a reference render "
                                                "of SPP samples per pixel in the Reference dock."),
                                 QStringLiteral("SPP"));
    QCommandLineOption method(
        QStringLiteral("method"),
        QStringLiteral("Preview method: direct, single, sslpv, dipole or better-dipole."),
        QStringLiteral("M"));
    parser.addOptions({shot, frames, bench, benchJson, viewportSize, noSettings, paintDemo,
                       raiseDock, method, reference});
    parser.process(app);

    const bool scripted = parser.isSet(shot) || parser.isSet(bench);
    MainWindow window(!scripted && !parser.isSet(noSettings));
    if (parser.isSet(viewportSize)) {
        const QStringList wh = parser.value(viewportSize).split(QLatin1Char('x'));
        if (wh.size() != 2 || wh[0].toInt() <= 0 || wh[1].toInt() <= 0) {
            std::fprintf(stderr, "lucent: --viewport expects WxH, e.g. 640x360\n");
            return 2;
        }
        window.viewport()->setFixedSize(wh[0].toInt(), wh[1].toInt());
    }
    if (!parser.positionalArguments().isEmpty() &&
        !window.openFile(parser.positionalArguments().first()))
        return scripted ? 1 : 0;
    if (parser.isSet(method)) {
        lucent::app::RenderSettings rs = window.viewport()->renderSettings();
        if (!parseMethod(parser.value(method), rs.method)) {
            std::fprintf(stderr,
                         "lucent: --method expects direct, single, sslpv, dipole or "
                         "better-dipole (got '%s')\n",
                         qPrintable(parser.value(method)));
            return 2;
        }
        window.setRenderMethod(int(rs.method));
    }
    window.show();
    for (const QString& name : parser.value(raiseDock).split(QLatin1Char(','), Qt::SkipEmptyParts))
        if (auto* dock = window.findChild<QDockWidget*>(name))
            dock->raise();
    bool demoPainted = !parser.isSet(paintDemo);
    bool referenceStarted = !parser.isSet(reference);
    const auto referenceRunning = [&window] {
#if LUCENT_APP_HAS_REFERENCE
        return window.referencePanel() && window.referencePanel()->isRunning();
#else
        (void)window;
        return false;
#endif
    };

    const int wantFrames = std::max(1, parser.value(frames).toInt());
    bool done = false;
    QObject::connect(window.viewport(), &lucent::app::Viewport::frameRendered, &window, [&] {
        if (done)
            return;
        const auto& st = window.viewport()->stats();
        if (parser.isSet(bench) && st.frames >= 1) {
            done = true;
            const double startupMs = startup.elapsedMs();
            QTimer::singleShot(0, &window, [&, startupMs] {
                runBenchmark(window, startupMs, parser.value(benchJson),
                             parser.isSet(method) ? parser.value(method) : QString());
                QApplication::exit(window.viewport()->stats().glErrors == 0 ? 0 : 3);
            });
        } else if (!demoPainted) {
            demoPainted = true;
            QTimer::singleShot(0, &window, [&] {
                lucent::app::Viewport* vp = window.viewport();
                lucent::app::AppBrush& b = vp->brush();
                b.engine.radius = 5.f;
                b.engine.falloff = lucent::Falloff::Smooth;
                b.engine.strength = 1.f;
                b.engine.mode = lucent::BrushMode::Set;
                // Weakly scattering red: blue and green are absorbed within a fraction of a mm.
                b.engine.value = {lucent::Rgb(0.6f, 3.f, 4.f), lucent::Rgb(0.55f, 0.3f, 0.3f),
                                  lucent::Rgb(0.f)};
                const double cx = vp->width() / 2.0, cy = vp->height() / 2.0;
                vp->strokeBetween(QPointF(cx - 0.3 * cx, cy - 0.15 * cy),
                                  QPointF(cx + 0.3 * cx, cy + 0.1 * cy));
                vp->strokeBetween(QPointF(cx - 0.1 * cx, cy + 0.3 * cy),
                                  QPointF(cx + 0.1 * cx, cy - 0.35 * cy));
                vp->update();
            });
        } else if (!referenceStarted) {
            referenceStarted = true;
#if LUCENT_APP_HAS_REFERENCE
            if (auto* ref = window.referencePanel()) {
                ref->setParameters(200, std::max(3, parser.value(reference).toInt()));
                QObject::connect(ref, &lucent::app::ReferencePanel::finished, window.viewport(),
                                 qOverload<>(&QWidget::update));
                ref->start();
            }
#endif
        } else if (parser.isSet(shot) && st.frames >= wantFrames && !referenceRunning()) {
            done = true;
            QTimer::singleShot(100, &window, [&] {
                const QString path = parser.value(shot);
                const bool ok = window.grab().save(path);
                std::fprintf(stderr, "lucent: screenshot %s %s (%lld frames, %d GL errors)\n",
                             qPrintable(path), ok ? "written" : "FAILED",
                             window.viewport()->stats().frames,
                             window.viewport()->stats().glErrors);
                QApplication::exit(ok ? 0 : 1);
            });
        } else if (parser.isSet(shot)) {
            QTimer::singleShot(referenceRunning() ? 250 : 0, window.viewport(),
                               qOverload<>(&QWidget::update));
        }
    });
    if (!window.viewport()->stats().initError.isEmpty())
        std::fprintf(stderr, "lucent: %s\n", qPrintable(window.viewport()->stats().initError));
    return QApplication::exec();
}
