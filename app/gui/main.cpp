// SPDX-License-Identifier: MIT
/// @file
/// @brief Entry point of the `lucent` app.
///
///     lucent [PROJECT|MESH|VDB] [--screenshot PATH] [--frames N] [--benchmark]
///            [--benchmark-json PATH] [--live-costs PATH] [--viewport WxH] [--window WxH]
///            [--method auto|NAME]   (NAME: a registry name with a GL pass, `lucent-cli methods`)
///            [--param KEY=VALUE ...] (a live parameter of that method, as its field takes it)
///            [--paint-demo] [--reference SPP] [--reference-view reference|preview|error]
///            [--raise DOCKS] [--no-settings]
///            [--swap-interval N] [--crash-test-script]
/// --screenshot grabs the whole window after N rendered frames (default 3) and exits;
/// --benchmark measures start-up to first frame, idle frame time and stroke-to-frame latency
/// (what Qt adds around paintGL is measured by tests/bench/bench_app_compose.cpp); with
/// --live-costs it measures the live costs Auto plans with instead (planner/LiveCosts.h).
/// --crash-test-script (test-only) paints, autosaves and saves the opened project until killed
/// (tests/unit/app/test_crash.cpp).

#include "Document.h"
#include "MainWindow.h"
#include "Viewport.h"
#include "ReferencePanel.h"

#include <lucent/core/FileIO.h>
#include <lucent/core/Timer.h>
#include <lucent/methods/Method.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/LiveCosts.h>

#include <QApplication>
#include <QEventLoop>
#include <QCommandLineParser>
#include <QDateTime>
#include <QDockWidget>
#include <QFile>
#include <QSurfaceFormat>
#include <QTimer>

#include <algorithm>
#include <memory>
#include <utility>
#include <cstdio>
#include <thread>
#include <vector>

namespace {

using lucent::Timer;
using lucent::app::MainWindow;

/// What --method takes, comma-separated (for messages): auto and the preview methods'
/// registry names.
QString previewMethodNames() {
    QStringList names{QString::fromLatin1(lucent::app::AUTO_METHOD)};
    for (const lucent::methods::MethodInfo* info : lucent::app::PreviewRenderer::previewMethods())
        names.push_back(QString::fromStdString(info->name));
    return names.join(QStringLiteral(", "));
}

/// Idle frame and stroke-to-frame latency of the current preview method (medians, ms), with
/// where the stroke frame's time goes.
struct MethodTiming {
    double idleMs = 0.0, strokeMs = 0.0, strokePaintGlMs = 0.0;
    double idlePaintGlMs = 0.0;  ///< paintGL of the idle frames (idle − this = Qt's share)
    double uploadMs = 0.0;       ///< material update inside the stroke frame (CPU)
    double strokeCpuMs = 0.0;    ///< the stroke itself: picking, engine stamps, history
    /// GPU ms per renderer pass of the stroke frames (shadows, gbuffer, subsurface, shade,
    /// tonemap), medians.
    std::vector<std::pair<std::string, double>> strokePassGpuMs;
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
    std::vector<double> idle, idlePaint, latency, frameOnly, upload, strokeCpu;
    std::vector<std::pair<std::string, std::vector<double>>> passes;
    for (int i = 0; i < idleFrames; ++i) {
        Timer t;
        renderFrame(vp);
        idle.push_back(t.elapsedMs());
        idlePaint.push_back(vp->stats().frameMs);
    }
    const double cx = vp->width() / 2.0, cy = vp->height() / 2.0;
    for (int i = 0; i < strokes; ++i) {
        const double dy = (i - strokes / 2) * 4.0;
        Timer t;  // stroke (picking + engine stamps + history) → dirty-brick upload → frame
        vp->strokeBetween(QPointF(cx - 40, cy + dy), QPointF(cx + 40, cy + dy));
        strokeCpu.push_back(t.elapsedMs());
        renderFrame(vp);
        latency.push_back(t.elapsedMs());
        frameOnly.push_back(vp->stats().frameMs);
        upload.push_back(vp->stats().uploadMs);
        for (const auto& pass : vp->stats().preview.passes) {  // this frame's (collected)
            auto it = std::find_if(passes.begin(), passes.end(),
                                   [&](const auto& p) { return p.first == pass.name; });
            if (it == passes.end())
                it = passes.insert(passes.end(), {pass.name, {}});
            it->second.push_back(pass.gpuMs);
        }
    }
    MethodTiming m{lucent::medianMs(idle),
                   lucent::medianMs(latency),
                   lucent::medianMs(frameOnly),
                   lucent::medianMs(idlePaint),
                   lucent::medianMs(upload),
                   lucent::medianMs(strokeCpu),
                   {}};
    for (const auto& [name, v] : passes)
        m.strokePassGpuMs.push_back({name, lucent::medianMs(v)});
    return m;
}

/// Waits until Auto's level check of the first frames (a worker rendering the pick's levels,
/// AutoLevelCheck.h) has finished: it would share the cores with the first timings.
void waitForLevelCheck(lucent::app::Viewport* vp) {
    while (vp->levelChecker().running())
        QCoreApplication::processEvents(QEventLoop::AllEvents | QEventLoop::WaitForMoreEvents, 5);
}

/// Runs the latency harness on a shown window whose first frame has been rendered.
void runBenchmark(MainWindow& w, double startupMs, const QString& jsonPath,
                  const QString& methodFilter) {
    lucent::app::Viewport* vp = w.viewport();
    waitForLevelCheck(vp);
    lucent::app::RenderSettings rs = vp->renderSettings();
    struct Row {
        const char* name;
        std::string method;  ///< registry name
        float scale;
        bool reuse = true;     ///< RenderSettings::reusePasses (false: every pass every frame)
        bool overlay = false;  ///< RenderSettings::volumeOverlay (σt, opacity 0.5)
        MethodTiming t;
    };
    // Stroke latency of the live methods at the viewport's full resolution and at the app's
    // default half resolution (every method at its live defaults: SSLPV 32³ with the CPU
    // solve, dipoles at 16 samples per frame), plus the direct baseline; the "no reuse" rows
    // re-run the G-buffer and the direct lighting every frame (as before pass reuse; shadow
    // maps were already kept) for a same-run before/after.
    std::vector<Row> rows = {
        {"direct, full res (baseline)", "direct", 1.f, true, false, {}},
        {"direct, full res, no reuse", "direct", 1.f, false, false, {}},
        {"single-scatter, full res", "single-scattering", 1.f, true, false, {}},
        {"sslpv 32^3, full res, no reuse", "sslpv", 1.f, false, false, {}},
        {"sslpv 32^3, full res", "sslpv", 1.f, true, false, {}},
        {"dipole, full res, no reuse", "dipole", 1.f, false, false, {}},
        {"dipole, full res", "dipole", 1.f, true, false, {}},
        {"better dipole, full res", "better-dipole", 1.f, true, false, {}},
        {"sslpv 32^3, half res", "sslpv", 0.5f, true, false, {}},
        {"sslpv 32^3, half res + overlay", "sslpv", 0.5f, true, true, {}},
        {"dipole, half res", "dipole", 0.5f, true, false, {}},
        {"directional dipole, full res", "dirpole", 1.f, true, false, {}},
        {"directional dipole, half res", "dirpole", 0.5f, true, false, {}},
        {"combined, full res", "combined", 1.f, true, false, {}},
        {"combined, half res", "combined", 0.5f, true, false, {}}};
    if (!methodFilter.isEmpty()) {  // the baseline + that method
        const std::string only = methodFilter.toStdString();
        std::erase_if(rows, [&](const Row& r) { return r.method != "direct" && r.method != only; });
    }
    for (Row& r : rows) {
        rs.method = r.method;
        rs.params = {};  // the method's live defaults
        rs.resolutionScale = r.scale;
        rs.reusePasses = r.reuse;
        rs.volumeOverlay = r.overlay;
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
    std::printf("(every method at its live defaults: lucent-cli methods lists them)\n");
    // Where a stroke frame goes: renderer passes (GPU ms), the material update (CPU), and what
    // is outside paintGL (picking + stamping before, Qt's composition after).
    std::printf("\nstroke frame breakdown (medians, ms)\n%-36s", "method");
    for (const char* pass : {"shadows", "gbuffer", "subsurface", "shade", "tonemap"})
        std::printf(" %10s", pass);
    std::printf(" %10s %10s %12s %12s\n", "upload", "stroke CPU", "Qt (idle)", "outside GL");
    for (const Row& r : rows) {
        std::printf("%-36s", r.name);
        for (const char* pass : {"shadows", "gbuffer", "subsurface", "shade", "tonemap"}) {
            double ms = 0.0;
            for (const auto& [name, v] : r.t.strokePassGpuMs)
                if (name == pass)
                    ms = v;
            std::printf(" %10.2f", ms);
        }
        // The direct method updates no material: its upload column would be a stale value.
        std::printf(" %10.2f %10.1f %12.1f %12.1f\n", r.method == "direct" ? 0.0 : r.t.uploadMs,
                    r.t.strokeCpuMs, r.t.idleMs - r.t.idlePaintGlMs,
                    r.t.strokeMs - r.t.strokePaintGlMs);
    }
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

/// Measures the live costs Auto plans with (planner/LiveCosts.h): for every candidate of the
/// shipped table, at the app's default render settings, the stroke → frame median over the
/// render time of a Direct stroke frame (its paintGL, median). Each candidate's ratio is taken
/// against a Direct timing made just before it, and the median of five rounds is kept: on a
/// shared machine the load drifts within a run, and a pair measured together sees the same
/// load (three rounds left entries within ±10 % of the 50 ms budget on either side of it from
/// one run to the next). Prints them and writes them to `path` in the table's format.
/// @throw lucent::Error when the file cannot be written.
void measureLiveCosts(MainWindow& w, const QString& path) {
    constexpr int ROUNDS = 5;
    lucent::app::Viewport* vp = w.viewport();
    waitForLevelCheck(vp);
    const lucent::app::RenderSettings defaults;  // half resolution, passes reused
    const auto timed = [&](const std::string& method, const lucent::methods::ParamSet& params) {
        lucent::app::RenderSettings rs = defaults;
        rs.method = method;
        rs.params = params;
        vp->setRenderSettings(rs);
        return timeMethod(vp);
    };
    const std::vector<lucent::planner::LiveCost>& entries =
        lucent::planner::defaultLiveCosts().entries;
    std::vector<std::vector<double>> ratios(entries.size()), strokeMs(entries.size());
    std::vector<double> unitMs;
    for (int round = 0; round < ROUNDS; ++round)
        for (size_t i = 0; i < entries.size(); ++i) {
            const double unit = timed("direct", {}).strokePaintGlMs;
            const lucent::planner::CandidateRun run =
                lucent::planner::resolveCandidate(entries[i].method, entries[i].setting);
            const MethodTiming t = timed(run.method, run.params);
            unitMs.push_back(unit);
            ratios[i].push_back(t.strokeMs / unit);
            strokeMs[i].push_back(t.strokeMs);
        }
    std::printf("viewport %dx%d, renderer %s; Direct frame render %.1f ms (median of %zu)\n",
                vp->width(), vp->height(), qPrintable(vp->stats().glRenderer),
                lucent::medianMs(unitMs), unitMs.size());
    std::printf("%-28s %-10s %14s %13s %20s\n", "candidate", "setting", "stroke->frame",
                "stroke_ratio", "ratios (rounds)");
    lucent::planner::LiveCosts measured;
    measured.directMs = lucent::medianMs(unitMs);
    measured.date =
        QDateTime::currentDateTimeUtc().toString(QStringLiteral("yyyy-MM-dd")).toStdString();
    // GL_RENDERER of the viewport's "GL_RENDERER — GL_VERSION" line.
    measured.renderer =
        vp->stats().glRenderer.section(QStringLiteral(" — "), 0, 0).trimmed().toStdString();
    measured.cpuThreads = int(std::thread::hardware_concurrency());
    measured.hostIncluded = true;  // the window's stroke -> frame: Qt's share is in it
    for (size_t i = 0; i < entries.size(); ++i) {
        lucent::planner::LiveCost m = entries[i];
        m.strokeRatio = lucent::medianMs(ratios[i]);
        measured.entries.push_back(m);
        std::printf("%-28s %-10s %11.1f ms %13.2f      ", m.method.c_str(), m.setting.c_str(),
                    lucent::medianMs(strokeMs[i]), m.strokeRatio);
        for (double r : ratios[i])
            std::printf(" %.2f", r);
        std::printf("\n");
    }
    measured.source = "lucent --benchmark --live-costs (app default render settings, viewport " +
                      std::to_string(vp->width()) + "x" + std::to_string(vp->height()) + ", " +
                      vp->stats().glRenderer.toStdString() + ", median of " +
                      std::to_string(ROUNDS) + " rounds, " +
                      QDateTime::currentDateTimeUtc()
                          .toString(QStringLiteral("yyyy-MM-dd hh:mm 'UTC'"))
                          .toStdString() +
                      ")";
    lucent::writeFileAtomically(path.toStdString(), lucent::planner::formatLiveCosts(measured));
    std::printf("written %s\n", qPrintable(path));
}

/// --crash-test-script, for tests/unit/app/test_crash.cpp: paints scripted strokes into the
/// opened project until the process is killed. A stroke is STAMPS stamps along +x, one per
/// 10 ms timer tick, so the event loop renders the live preview in between as during a drag;
/// after every second stroke the app autosaves, after every third it saves onto the project.
/// Each step goes to stdout at once, with the content hash (MaterialVolume::contentHash) of
/// the volume written, so that a test killing the app with SIGKILL knows what each file must
/// hold: "opened H", "autosave-path P", "stroke N open|closed", "autosave end N H",
/// "save begin N H", "save end N".
void startCrashTestScript(MainWindow& window) {
    using namespace lucent;
    app::Document* doc = window.document();
    const MaterialVolume* vol = doc->material();
    const auto say = [](const QString& line) {
        std::printf("%s\n", qPrintable(line));
        std::fflush(stdout);
    };
    const auto hashText = [](const MaterialVolume& v) {
        return QString::number(qulonglong(v.contentHash()), 16);
    };
    say(QStringLiteral("autosave-path %1").arg(MainWindow::autosavePath()));
    say(QStringLiteral("opened %1").arg(hashText(*vol)));
    // Where strokes start: every 97th inside voxel (a deterministic spread over the object).
    auto starts = std::make_shared<std::vector<Coord>>();
    const GridSpec spec = vol->spec();
    size_t inside = 0;
    for (int z = 0; z < spec.resolution; ++z)
        for (int y = 0; y < spec.resolution; ++y)
            for (int x = 0; x < spec.resolution; ++x)
                if (vol->isInside({x, y, z}) && inside++ % 97 == 0)
                    starts->push_back({x, y, z});
    if (starts->empty()) {
        say(QStringLiteral("error the object has no inside voxels"));
        QApplication::exit(1);
        return;
    }
    constexpr int STAMPS = 12;
    // Strokes differ from one launch to the next (a relaunch on the saved project paints new
    // values over it): the first stroke's number comes from the opened material.
    auto stroke = std::make_shared<int>(int(vol->contentHash() % 1000u));
    auto stamp = std::make_shared<int>(0);
    auto* timer = new QTimer(&window);
    timer->setInterval(10);
    QObject::connect(timer, &QTimer::timeout, &window, [=, &window] {
        const int n = *stroke;
        if (*stamp == 0) {
            BrushSettings b;
            b.radius = 3.f * spec.voxelSize;
            b.falloff = Falloff::Constant;
            b.strength = 1.f;
            b.mode = BrushMode::Set;
            b.channels = ALL_CHANNELS;
            b.value = {Rgb(1.f + float(n % 7)), Rgb(0.5f), Rgb(0.1f * float(n % 3))};
            doc->beginStroke(b);
            say(QStringLiteral("stroke %1 open").arg(n));
        }
        const Coord start = (*starts)[size_t(n) * 7919u % starts->size()];
        doc->strokeStamp(spec.cellCenter(start) + Vector3f(float(*stamp) * spec.voxelSize, 0, 0));
        if (++*stamp < STAMPS)
            return;
        *stamp = 0;
        doc->endStroke(QStringLiteral("scripted stroke"));
        say(QStringLiteral("stroke %1 closed").arg(n));
        if (n % 2 == 1 && doc->isModified()) {  // autosave writes only unsaved changes
            window.autosaveNow();
            say(QStringLiteral("autosave end %1 %2").arg(n).arg(hashText(*doc->material())));
        }
        if (n % 3 == 2) {
            say(QStringLiteral("save begin %1 %2").arg(n).arg(hashText(*doc->material())));
            if (!window.saveTo(doc->filePath()))
                say(QStringLiteral("error %1").arg(window.lastError()));
            say(QStringLiteral("save end %1").arg(n));
        }
        ++*stroke;
    });
    timer->start();
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
    QCommandLineOption liveCosts(
        QStringLiteral("live-costs"),
        QStringLiteral("With --benchmark: measure the live costs Auto plans with instead, and "
                       "write them to PATH (resources/planner/live_costs.json)."),
        QStringLiteral("PATH"));
    QCommandLineOption viewportSize(QStringLiteral("viewport"),
                                    QStringLiteral("Viewport size WxH (e.g. 640x360)."),
                                    QStringLiteral("WxH"));
    QCommandLineOption windowSize(QStringLiteral("window"),
                                  QStringLiteral("Main window size WxH (e.g. 1366x768)."),
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
    QCommandLineOption referenceView(
        QStringLiteral("reference-view"),
        QStringLiteral("What the Reference dock shows: reference (default), preview or error."),
        QStringLiteral("VIEW"));
    QCommandLineOption swapInterval(
        QStringLiteral("swap-interval"),
        QStringLiteral("QSurfaceFormat swap interval (default: Qt's, 1); 0 disables vsync."),
        QStringLiteral("N"));
    QCommandLineOption method(
        QStringLiteral("method"),
        QStringLiteral("Preview method: %1 (default auto).").arg(previewMethodNames()),
        QStringLiteral("M"));
    QCommandLineOption param(
        QStringLiteral("param"),
        QStringLiteral("A live parameter of the --method, as KEY=VALUE (e.g. mode=diffusion for "
                       "sslpv); repeatable."),
        QStringLiteral("KEY=VALUE"));
    QCommandLineOption crashTest(
        QStringLiteral("crash-test-script"),
        QStringLiteral("Test-only: paint, autosave and save the opened project until killed, "
                       "printing each step (tests/unit/app/test_crash.cpp)."));
    parser.addOptions({shot, frames, bench, benchJson, liveCosts, viewportSize, windowSize,
                       noSettings, paintDemo, raiseDock, method, param, reference, referenceView,
                       swapInterval, crashTest});
    parser.process(app);
    if (parser.isSet(swapInterval)) {
        // Before any window exists, so that every context gets it.
        QSurfaceFormat f = QSurfaceFormat::defaultFormat();
        f.setSwapInterval(parser.value(swapInterval).toInt());
        QSurfaceFormat::setDefaultFormat(f);
    }

    const bool scripted = parser.isSet(shot) || parser.isSet(bench) || parser.isSet(crashTest);
    if (parser.isSet(crashTest) && parser.positionalArguments().isEmpty()) {
        std::fprintf(stderr, "lucent: --crash-test-script needs a project to open\n");
        return 2;
    }
    MainWindow window(!scripted && !parser.isSet(noSettings));
    // WxH of --viewport / --window; an empty size when malformed.
    const auto parseSize = [&parser](const QCommandLineOption& option) {
        const QStringList wh = parser.value(option).split(QLatin1Char('x'));
        return wh.size() == 2 && wh[0].toInt() > 0 && wh[1].toInt() > 0
                   ? QSize(wh[0].toInt(), wh[1].toInt())
                   : QSize();
    };
    if (parser.isSet(viewportSize)) {
        const QSize size = parseSize(viewportSize);
        if (size.isEmpty()) {
            std::fprintf(stderr, "lucent: --viewport expects WxH, e.g. 640x360\n");
            return 2;
        }
        window.viewport()->setFixedSize(size);
    }
    if (parser.isSet(windowSize)) {
        const QSize size = parseSize(windowSize);
        if (size.isEmpty()) {
            std::fprintf(stderr, "lucent: --window expects WxH, e.g. 1366x768\n");
            return 2;
        }
        window.resize(size);
    }
    if (!parser.positionalArguments().isEmpty() &&
        !window.openFile(parser.positionalArguments().first()))
        return scripted ? 1 : 0;
    if (parser.isSet(method) && !window.setRenderMethod(parser.value(method))) {
        std::fprintf(stderr, "lucent: --method expects one of %s (got '%s')\n",
                     qPrintable(previewMethodNames()), qPrintable(parser.value(method)));
        return 2;
    }
    for (const QString& kv : parser.values(param)) {
        const qsizetype eq = kv.indexOf(QLatin1Char('='));
        if (eq <= 0 || !window.setRenderParam(kv.left(eq), kv.mid(eq + 1))) {
            std::fprintf(stderr,
                         "lucent: --param '%s' is not KEY=VALUE of a live parameter of the preview "
                         "method (`lucent-cli methods` lists them)\n",
                         qPrintable(kv));
            return 2;
        }
    }
    window.show();
    for (const QString& name : parser.value(raiseDock).split(QLatin1Char(','), Qt::SkipEmptyParts))
        if (auto* dock = window.findChild<QDockWidget*>(name))
            dock->raise();
    bool demoPainted = !parser.isSet(paintDemo);
    bool crashTestStarted = !parser.isSet(crashTest);
    bool referenceStarted = !parser.isSet(reference);
    const auto referenceRunning = [&window] {
        return window.referencePanel() && window.referencePanel()->isRunning();
    };

    const int wantFrames = std::max(1, parser.value(frames).toInt());
    bool done = false;
    QObject::connect(window.viewport(), &lucent::app::Viewport::frameRendered, &window, [&] {
        if (done)
            return;
        const auto& st = window.viewport()->stats();
        if (st.frames == 0 && !st.initError.isEmpty()) {  // GL set-up failed: no frame comes
            done = true;
            std::fprintf(stderr, "lucent: %s\n", qPrintable(st.initError));
            if (scripted)
                QTimer::singleShot(0, &window, [] { QApplication::exit(4); });
            return;
        }
        if (!crashTestStarted) {
            crashTestStarted = true;
            done = true;  // runs until killed
            QTimer::singleShot(0, &window, [&window] { startCrashTestScript(window); });
        } else if (parser.isSet(bench) && st.frames >= 1) {
            done = true;
            const double startupMs = startup.elapsedMs();
            QTimer::singleShot(0, &window, [&, startupMs] {
                if (parser.isSet(liveCosts)) {
                    try {
                        measureLiveCosts(window, parser.value(liveCosts));
                    } catch (const std::exception& e) {
                        std::fprintf(stderr, "lucent: %s\n", e.what());
                        QApplication::exit(2);
                        return;
                    }
                } else {
                    runBenchmark(window, startupMs, parser.value(benchJson),
                                 parser.isSet(method) ? parser.value(method) : QString());
                }
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
        } else if (!referenceStarted && !window.viewport()->previewRenderer().isPlanning()) {
            // After Auto has timed its Direct frames, as when an artist starts a reference: the
            // path tracer takes both cores, and a unit timed beside it would be kept for the
            // scene (in a scripted run that made Auto take SSLPV 16³ on the default scene).
            referenceStarted = true;
            if (auto* ref = window.referencePanel()) {
                ref->setParameters(200, std::max(3, parser.value(reference).toInt()));
                const QString view = parser.value(referenceView);
                using View = lucent::app::ReferencePanel::View;
                ref->setView(view == QStringLiteral("error")     ? View::ErrorMap
                             : view == QStringLiteral("preview") ? View::Preview
                                                                 : View::Reference);
                QObject::connect(ref, &lucent::app::ReferencePanel::finished, window.viewport(),
                                 [&window] { window.viewport()->update(); });
                ref->start();
            }
        } else if (parser.isSet(shot) && st.frames >= wantFrames && !referenceRunning()) {
            done = true;
            QTimer::singleShot(100, &window, [&] {
                const QString path = parser.value(shot);
                // The window with the viewport's frame painted in (QWidget::grab cannot read
                // the native GL window).
                const bool ok = window.viewport()->grabWithFrame(&window).save(path);
                std::fprintf(stderr, "lucent: screenshot %s %s (%lld frames, %d GL errors)\n",
                             qPrintable(path), ok ? "written" : "FAILED",
                             window.viewport()->stats().frames,
                             window.viewport()->stats().glErrors);
                QApplication::exit(ok ? 0 : 1);
            });
        } else if (parser.isSet(shot)) {
            QTimer::singleShot(referenceRunning() ? 250 : 0, window.viewport(),
                               [&window] { window.viewport()->update(); });
        }
    });
    return QApplication::exec();
}
