// SPDX-License-Identifier: MIT
/// @file
/// @brief GpuProfiler: GL_TIMESTAMP query pairs per pass, resolved without stalling.

#include <lucent/core/Error.h>
#include <lucent/gpu/GpuTimer.h>

#include <epoxy/gl.h>

namespace lucent::gpu {

GlObject GpuProfiler::takeQuery() {
    if (!m_freeQueries.empty()) {
        GlObject q = std::move(m_freeQueries.back());
        m_freeQueries.pop_back();
        return q;
    }
    return GlObject::create(GlObjectKind::Query, GL_TIMESTAMP);
}

void GpuProfiler::beginFrame() {
    LUCENT_CHECK(!m_inFrame, "GpuProfiler::beginFrame called twice without endFrame");
    collect(false);
    // Bound the queue: a caller that never lets queries complete must not grow it forever.
    while (m_pending.size() > 4) {
        tryResolve(m_pending.front(), true);
        m_pending.pop_front();
    }
    m_current = Frame{};
    m_open.clear();
    m_inFrame = true;
}

void GpuProfiler::begin(const char* name) {
    LUCENT_CHECK(m_inFrame, "GpuProfiler::begin('", name, "') outside beginFrame/endFrame");
    Pass pass;
    pass.name = name;
    pass.depth = int(m_open.size());
    pass.begin = takeQuery();
    pass.end = takeQuery();
    glQueryCounter(pass.begin.id(), GL_TIMESTAMP);
    pass.cpuBegin = std::chrono::steady_clock::now();
    m_open.push_back(m_current.passes.size());
    m_current.passes.push_back(std::move(pass));
}

void GpuProfiler::end() {
    LUCENT_CHECK(!m_open.empty(), "GpuProfiler::end without begin");
    Pass& pass = m_current.passes[m_open.back()];
    m_open.pop_back();
    glQueryCounter(pass.end.id(), GL_TIMESTAMP);
    pass.cpuMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - pass.cpuBegin)
            .count();
}

void GpuProfiler::endFrame(bool wait) {
    LUCENT_CHECK(m_inFrame, "GpuProfiler::endFrame without beginFrame");
    LUCENT_CHECK(m_open.empty(), "GpuProfiler::endFrame with ", m_open.size(),
                 " pass(es) still open");
    m_inFrame = false;
    m_pending.push_back(std::move(m_current));
    m_current = Frame{};
    if (wait)
        collect(true);
}

void GpuProfiler::cancelFrame() {
    if (!m_inFrame)
        return;
    recycle(m_current);  // the queries issued so far are reused; their results never read
    m_current = Frame{};
    m_open.clear();
    m_inFrame = false;
}

void GpuProfiler::collect(bool wait) {
    while (!m_pending.empty() && tryResolve(m_pending.front(), wait))
        m_pending.pop_front();
}

bool GpuProfiler::tryResolve(Frame& frame, bool wait) {
    if (!wait) {
        for (const Pass& p : frame.passes) {
            GLint available = 0;
            glGetQueryObjectiv(p.end.id(), GL_QUERY_RESULT_AVAILABLE, &available);
            if (!available)
                return false;
        }
    }
    std::vector<PassTiming> out;
    out.reserve(frame.passes.size());
    for (const Pass& p : frame.passes) {
        GLuint64 t0 = 0;
        GLuint64 t1 = 0;
        glGetQueryObjectui64v(p.begin.id(), GL_QUERY_RESULT, &t0);
        glGetQueryObjectui64v(p.end.id(), GL_QUERY_RESULT, &t1);
        out.push_back({p.name, t1 >= t0 ? double(t1 - t0) * 1e-6 : 0.0, p.cpuMs, p.depth});
    }
    m_latest = std::move(out);
    recycle(frame);
    return true;
}

void GpuProfiler::recycle(Frame& frame) {
    for (Pass& p : frame.passes) {
        m_freeQueries.push_back(std::move(p.begin));
        m_freeQueries.push_back(std::move(p.end));
    }
    frame.passes.clear();
}

const PassTiming* GpuProfiler::find(const std::string& name) const {
    for (const PassTiming& t : m_latest)
        if (t.name == name)
            return &t;
    return nullptr;
}

void GpuProfiler::destroy() {
    for (Frame& f : m_pending)
        recycle(f);
    m_pending.clear();
    recycle(m_current);
    m_open.clear();
    m_inFrame = false;
    for (GlObject& q : m_freeQueries)
        q.destroy();
    m_freeQueries.clear();
}

}  // namespace lucent::gpu
