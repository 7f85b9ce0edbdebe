// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Per-pass GPU timings (GL_TIMESTAMP queries, so scopes may nest) next to CPU timings
/// (wall clock of the code that issues the pass), in milliseconds.
///
/// Usage:
/// @code
///   GpuProfiler prof;                 // no GL yet
///   prof.beginFrame();
///   { auto s = prof.scope("shadow"); ...draw... }
///   { auto s = prof.scope("shade"); ...draw... }
///   prof.endFrame();                  // results arrive a frame or two later, without stalling
///   for (auto& t : prof.latest()) printf("%s %.2f ms GPU, %.2f ms CPU\n", ...);
///   {                                 // a frame whose code may throw:
///       GpuProfiler::FrameScope frame(prof);   // beginFrame()
///       { auto s = prof.scope("pass"); ...may throw... }
///       frame.end();                  // endFrame(); an exception before it cancels the frame
///   }
///   prof.destroy();                   // context current
/// @endcode

#include <lucent/gpu/GlResources.h>

#include <chrono>
#include <deque>
#include <string>
#include <vector>

namespace lucent::gpu {

/// One pass of one frame.
struct PassTiming {
    std::string name;
    double gpuMs = 0.0;  ///< GPU time between the pass's begin and end timestamps
    double cpuMs = 0.0;  ///< CPU wall time spent issuing the pass
    int depth = 0;       ///< nesting level (0 = top)
};

/// Records named, nestable GPU/CPU pass timings per frame.
class GpuProfiler {
public:
    class Scope {
    public:
        explicit Scope(GpuProfiler& p, const char* name) : m_profiler(&p) { p.begin(name); }
        Scope(const Scope&) = delete;
        Scope& operator=(const Scope&) = delete;
        ~Scope() { m_profiler->end(); }

    private:
        GpuProfiler* m_profiler;
    };

    /// Begins a frame; ends it with end(), or cancels it (cancelFrame) when left without end(),
    /// e.g. by an exception thrown by a pass: the profiler is then ready for the next frame
    /// instead of refusing every later beginFrame().
    class FrameScope {
    public:
        explicit FrameScope(GpuProfiler& p) : m_profiler(&p) { p.beginFrame(); }
        FrameScope(const FrameScope&) = delete;
        FrameScope& operator=(const FrameScope&) = delete;
        ~FrameScope() {
            if (m_open)
                m_profiler->cancelFrame();
        }
        /// endFrame(wait).
        void end(bool wait = false) {
            m_profiler->endFrame(wait);
            m_open = false;
        }

    private:
        GpuProfiler* m_profiler;
        bool m_open = true;
    };

    GpuProfiler() = default;
    GpuProfiler(const GpuProfiler&) = delete;
    GpuProfiler& operator=(const GpuProfiler&) = delete;

    /// Starts a frame (context current). Frames whose queries are all available are resolved.
    void beginFrame();
    /// Ends the frame; with `wait`, blocks until its queries are available and resolves it.
    void endFrame(bool wait = false);
    /// Drops the open frame (its passes, open or closed, are never resolved) so that the next
    /// beginFrame() starts cleanly. No-op outside a frame.
    void cancelFrame();
    [[nodiscard]] bool isInFrame() const { return m_inFrame; }
    /// Opens a pass (nestable). Must be closed by end() in the same frame.
    void begin(const char* name);
    void end();
    [[nodiscard]] Scope scope(const char* name) { return Scope(*this, name); }

    /// Resolves ended frames whose queries are available (all of them with `wait`).
    void collect(bool wait);

    /// Timings of the most recently resolved frame (empty until one is resolved).
    [[nodiscard]] const std::vector<PassTiming>& latest() const { return m_latest; }
    /// Timing of `name` in latest(), or nullptr.
    [[nodiscard]] const PassTiming* find(const std::string& name) const;
    /// Whether the context supports timer queries (GL 3.3+: always on 4.5).
    [[nodiscard]] bool isEnabled() const { return m_enabled; }
    /// Frees the queries (context current). Idempotent.
    void destroy();

private:
    struct Pass {
        std::string name;
        int depth = 0;
        GlObject begin;
        GlObject end;
        std::chrono::steady_clock::time_point cpuBegin;
        double cpuMs = 0.0;
    };
    struct Frame {
        std::vector<Pass> passes;
    };
    GlObject takeQuery();
    bool tryResolve(Frame& frame, bool wait);
    void recycle(Frame& frame);

    std::deque<Frame> m_pending;
    Frame m_current;
    std::vector<size_t> m_open;  ///< indices of open passes in m_current
    std::vector<GlObject> m_freeQueries;
    std::vector<PassTiming> m_latest;
    bool m_inFrame = false;
    bool m_enabled = true;
};

}  // namespace lucent::gpu
