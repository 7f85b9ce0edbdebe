// SPDX-License-Identifier: MIT
// Checks the set-up the app's ThreadSanitizer entries stand on (docs/benchmarks.md,
// "ThreadSanitizer"): the app's workers (QThread::create) hand their results to the UI thread
// through queued signals, as MainWindow's export, ReferencePanel, PlanChart and AutoMeasure do.
//
//   tsan_qt_handoff handoff   the worker writes its result, then finishes; the UI thread reads
//                             it in the `finished` handler. Ordered by QtCore's event queue:
//                             TSan must stay silent, which it does only when QtCore itself is
//                             built with TSan (Debian's library reports this as a race).
//   tsan_qt_handoff race      the worker posts the same read first and writes afterwards: a
//                             real race, which TSan must report (so the set-up still sees
//                             Lucent's own accesses across the handoff).
//
// Exit status 0 and no report in `handoff`; the CTest entry of `race` passes on TSan's report.
#include <QCoreApplication>
#include <QMetaObject>
#include <QThread>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>

namespace {
int g_result = 0;  // a plain int on purpose: only the handoff can order its accesses
// Relaxed, so that they order nothing for TSan. In `race` the two threads wait on them so that
// the accesses come in this order with no Qt call of either thread in between: the UI thread
// reads, then the worker writes, then the UI thread quits. (Unpaced, the race was missed in
// about 2 of 5 runs: a wake-up of the event loop that the worker's post made after the UI thread
// had quit acquired what the quit released, ordering the read before the write.)
std::atomic<bool> g_read{false};
std::atomic<bool> g_written{false};

void waitFor(const std::atomic<bool>& flag) {
    while (!flag.load(std::memory_order_relaxed))
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
}
}  // namespace

int main(int argc, char** argv) {
    QCoreApplication app(argc, argv);
    const bool racy = argc > 1 && std::strcmp(argv[1], "race") == 0;
    int seen = -1;
    auto readAndQuit = [&seen, &app, racy] {
        seen = g_result;
        if (racy) {
            g_read.store(true, std::memory_order_relaxed);
            waitFor(g_written);
        }
        app.quit();
    };
    QThread* worker = QThread::create([racy, &app, readAndQuit] {
        if (racy) {
            QMetaObject::invokeMethod(&app, readAndQuit, Qt::QueuedConnection);
            waitFor(g_read);
            g_result = 42;  // after the handoff: unordered with the UI thread's read
            g_written.store(true, std::memory_order_relaxed);
        } else {
            g_result = 42;
        }
    });
    if (!racy)
        QObject::connect(worker, &QThread::finished, &app, readAndQuit, Qt::QueuedConnection);
    worker->start();
    app.exec();
    worker->wait();
    delete worker;
    std::printf("%s: the UI thread read %d\n", racy ? "race" : "handoff", seen);
    return 0;
}
