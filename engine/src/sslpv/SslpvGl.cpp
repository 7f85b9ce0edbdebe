// SPDX-License-Identifier: MIT
/// @file
/// @brief GL 4.5 compute propagation of SSLPV (shaders/sslpv_propagate.comp).

#include <lucent/sslpv/SslpvGl.h>

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/core/Half.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/GpuTimer.h>
#include <lucent/gpu/Shader.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace lucent::sslpv {

struct SslpvGlPropagator::Impl {
    SslpvGlStorage storage;
    gpu::GlProgram program;    ///< generic term-list gather (order 2)
    gpu::GlProgram programL1;  ///< order 1, sparsity-specialised gather
    gpu::GlProgram unpack;     ///< accumulation SSBO → four RGBA32F 3-D textures
    gpu::GpuProfiler profiler;

    // Persistent GPU grids for one (resolution, order): created once, reused by every
    // propagate(); the shadows hold what each input buffer currently contains.
    int res = 0, order = 0;
    size_t cells = 0, gpuPlane = 0;
    gpu::GlObject source;        ///< step-0 sources (injection × folded factors)
    gpu::GlObject prop[2];       ///< ping-pong
    gpu::GlObject acc, exit;     ///< accumulation and exitant grids
    gpu::GlObject factor;        ///< 9 fp32 planes [ch·3 + band]
    gpu::GlObject mask;          ///< sink mask plane (fp32)
    gpu::GlObject readoutAlpha;  ///< SslpvSolver::readoutAlpha plane (fp32), for writeTextures()
    gpu::GlObject terms;         ///< term list (ivec4)
    std::vector<uint8_t> shadowSource, shadowFactor, shadowMask, shadowReadoutAlpha;
    bool hasResult = false;

    // Read-back cache (filled on demand).
    SslpvGrid acc_, exit_;
    bool accStale = true, exitStale = true;
    SslpvGlTimings timings;

    void destroyGrids() {
        for (gpu::GlObject* b :
             {&source, &prop[0], &prop[1], &acc, &exit, &factor, &mask, &readoutAlpha, &terms})
            b->destroy();
        shadowSource.clear();
        shadowFactor.clear();
        shadowMask.clear();
        shadowReadoutAlpha.clear();
        res = order = 0;
        hasResult = false;
    }

    /// Uploads the chunks of `data` that differ from `shadow` (merged into contiguous ranges)
    /// and updates the shadow. Returns the bytes uploaded.
    static size_t uploadChanged(const gpu::GlObject& buf, std::vector<uint8_t>& shadow,
                                const void* data, size_t bytes, size_t chunk) {
        const auto* d = static_cast<const uint8_t*>(data);
        if (shadow.size() != bytes) {
            glNamedBufferSubData(buf.id(), 0, GLsizeiptr(bytes), d);
            shadow.assign(d, d + bytes);
            return bytes;
        }
        size_t uploaded = 0;
        for (size_t off = 0; off < bytes;) {
            size_t len = std::min(chunk, bytes - off);
            if (std::memcmp(d + off, &shadow[off], len) == 0) {
                off += len;
                continue;
            }
            size_t end = off + len;  // extend over the following changed chunks
            while (end < bytes) {
                const size_t l = std::min(chunk, bytes - end);
                if (std::memcmp(d + end, &shadow[end], l) == 0)
                    break;
                end += l;
            }
            glNamedBufferSubData(buf.id(), GLintptr(off), GLsizeiptr(end - off), d + off);
            std::memcpy(&shadow[off], d + off, end - off);
            uploaded += end - off;
            off = end;
        }
        return uploaded;
    }

    /// `grid`, read back from `b` first when `stale` (a read-back cache per grid).
    const SslpvGrid& readBack(const gpu::GlObject& b, SslpvGrid& grid, bool& stale,
                              const char* what) {
        LUCENT_CHECK(hasResult, "SslpvGlPropagator::", what, "(): nothing propagated yet");
        if (stale) {
            fetch(b, grid);
            stale = false;
        }
        return grid;
    }

    /// Reads one grid buffer back into `grid` (fp16 decoded).
    void fetch(const gpu::GlObject& b, SslpvGrid& grid) {
        const Timer t;
        const bool fp16 = storage == SslpvGlStorage::Float16;
        const int count = shCount(order);
        const size_t cellBytes = fp16 ? 2 : 4;
        std::vector<uint8_t> raw(size_t(3) * count * gpuPlane * cellBytes);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glGetNamedBufferSubData(b.id(), 0, GLsizeiptr(raw.size()), raw.data());
        if (grid.resolution() != res || grid.order() != order)
            grid = SslpvGrid(res, order);
        for (int ch = 0; ch < 3; ++ch)
            for (int i = 0; i < count; ++i) {
                float* out = grid.plane(ch, i);
                const size_t off = (size_t(ch) * count + i) * gpuPlane;
                for (size_t k = 0; k < cells; ++k) {
                    if (fp16) {
                        uint16_t h;
                        std::memcpy(&h, &raw[(off + k) * 2], 2);
                        out[k] = halfToFloat(h);
                    } else {
                        std::memcpy(&out[k], &raw[(off + k) * 4], 4);
                    }
                }
            }
        gpu::checkGlError("SslpvGlPropagator read-back");
        timings.readbackCpuMs = t.elapsedMs();
        ++timings.readbacks;
    }
};

SslpvGlPropagator::SslpvGlPropagator(SslpvGlStorage storage) : m_impl(std::make_unique<Impl>()) {
    m_impl->storage = storage;
    const gpu::ShaderLibrary lib;
    std::vector<std::string> defines;
    if (storage == SslpvGlStorage::Float16)
        defines.push_back("SSLPV_FP16");
    m_impl->unpack = gpu::GlProgram::compute(lib, "sslpv_unpack.comp", defines);
    m_impl->program = gpu::GlProgram::compute(lib, "sslpv_propagate.comp", defines);
    defines.push_back("SSLPV_L1");
    m_impl->programL1 = gpu::GlProgram::compute(lib, "sslpv_propagate.comp", defines);
}

SslpvGlPropagator::~SslpvGlPropagator() = default;

void SslpvGlPropagator::destroy() {
    if (!m_impl)
        return;
    m_impl->program.destroy();
    m_impl->programL1.destroy();
    m_impl->unpack.destroy();
    m_impl->profiler.destroy();
    m_impl->destroyGrids();
}

const SslpvGrid& SslpvGlPropagator::accumulation() const {
    return m_impl->readBack(m_impl->acc, m_impl->acc_, m_impl->accStale, "accumulation");
}
const SslpvGrid& SslpvGlPropagator::exitant() const {
    return m_impl->readBack(m_impl->exit, m_impl->exit_, m_impl->exitStale, "exitant");
}
const SslpvGlTimings& SslpvGlPropagator::timings() const {
    return m_impl->timings;
}
SslpvGlStorage SslpvGlPropagator::storage() const {
    return m_impl->storage;
}

void SslpvGlPropagator::writeTextures(const unsigned textures[4]) const {
    const Impl& s = *m_impl;
    LUCENT_CHECK(s.hasResult, "SslpvGlPropagator::writeTextures(): nothing propagated yet");
    const GLuint p = s.unpack.id();
    glUseProgram(p);
    glProgramUniform1i(p, s.unpack.uniformLocation("u_res"), s.res);
    glProgramUniform1i(p, s.unpack.uniformLocation("u_padded"), s.res + 2);
    glProgramUniform1i(p, s.unpack.uniformLocation("u_planeSize"), int(s.gpuPlane));
    glProgramUniform1i(p, s.unpack.uniformLocation("u_coeffs"), shCount(s.order));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, s.acc.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, s.readoutAlpha.id());
    for (unsigned i = 0; i < 4; ++i)
        glBindImageTexture(i, textures[i], 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    const unsigned g = unsigned(s.res + 3) / 4;
    glDispatchCompute(g, g, g);
    // The textures are written with imageStore (incoherent): made visible to texture fetches and
    // image loads (the sample pass), and to glGetTexImage / glTexSubImage (a read-back, or the
    // CPU upload of SslpvSubsurfaceProvider after a backend switch, which must also wait for these
    // writes), GL 4.5 §7.13.2.
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                    GL_TEXTURE_UPDATE_BARRIER_BIT);
    glUseProgram(0);
    gpu::checkGlError("SslpvGlPropagator::writeTextures");
}

void SslpvGlPropagator::propagate(const SslpvSolver& solver) {
    Impl& s = *m_impl;
    LUCENT_CHECK(s.program.isValid() && s.programL1.isValid(),
                 "SslpvGlPropagator: the program was destroyed");
    const SslpvGrid& inj = solver.injection();
    LUCENT_CHECK(inj.resolution() > 0 && !solver.isDirty(),
                 "SslpvGlPropagator: solve the CPU solver first (injection and factors)");
    const SslpvOptions& opt = solver.options();
    const int n = inj.resolution(), count = inj.coeffCount();
    const bool fp16 = s.storage == SslpvGlStorage::Float16;
    const size_t cells = inj.planeSize();
    const size_t gpuPlane = cells + (cells & 1u);  // even: fp16 pairs never straddle planes
    const size_t planes = size_t(3) * count;
    const size_t cellBytes = fp16 ? 2 : 4;
    const size_t gridBytes = planes * gpuPlane * cellBytes;
    const int p = n + 2;
    const int offs[6] = {1, -1, p, -p, p * p, -p * p};
    const auto& mats = propagationMatrices(opt.order);

    const Timer upload;
    // Buffers for this grid size and order: created once (the only GL objects made here).
    if (s.res != n || s.order != opt.order) {
        s.destroyGrids();
        s.res = n;
        s.order = opt.order;
        s.cells = cells;
        s.gpuPlane = gpuPlane;
        for (gpu::GlObject* b : {&s.source, &s.prop[0], &s.prop[1], &s.acc, &s.exit})
            *b = gpu::createBuffer(gridBytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
        s.factor = gpu::createBuffer(9 * gpuPlane * 4, nullptr, GL_DYNAMIC_STORAGE_BIT);
        s.mask = gpu::createBuffer(gpuPlane * 4, nullptr, GL_DYNAMIC_STORAGE_BIT);
        s.readoutAlpha = gpu::createBuffer(gpuPlane * 4, nullptr, GL_DYNAMIC_STORAGE_BIT);
        // The matrices as a term list (fixed for the order and grid size).
        std::vector<int> terms;  // ivec4 per term
        for (int i = 0; i < count; ++i)
            for (int o = 0; o < 6; ++o)
                for (int j = 0; j < count; ++j) {
                    const float w = mats[o].at(i, j);
                    if (std::abs(w) <= 1e-7f)
                        continue;  // zero by symmetry (quadrature ~1e−17)
                    int wb;
                    std::memcpy(&wb, &w, sizeof(wb));
                    terms.insert(terms.end(), {j, offs[o], wb, 0});
                }
        s.terms = gpu::createBuffer(terms.size() * 4, terms.data(), 0);
        // Padding of prop/source planes must read as zero: clear once.
        for (gpu::GlObject* b : {&s.source, &s.prop[0], &s.prop[1], &s.acc, &s.exit})
            glClearNamedBufferData(b->id(), GL_R8, GL_RED, GL_UNSIGNED_BYTE, nullptr);
    }
    int termStart[10] = {};
    {
        int t = 0;
        for (int i = 0; i < count; ++i) {
            termStart[i] = t;
            for (int o = 0; o < 6; ++o)
                for (int j = 0; j < count; ++j)
                    t += std::abs(mats[o].at(i, j)) > 1e-7f ? 1 : 0;
        }
        for (int i = count; i < 10; ++i)
            termStart[i] = t;
    }

    // Inputs: factors, sink mask, read-out alphas, step-0 sources (injection × folded factors, as
    // on the CPU); only their changed z-slices are uploaded (chunk = one padded slice).
    std::vector<float> factor(9 * gpuPlane, 0.f);
    for (int ch = 0; ch < 3; ++ch)
        for (int band = 0; band < 3; ++band) {
            const std::vector<float> f = solver.foldedFactorPlane(ch, band);
            std::copy(f.begin(), f.end(), factor.begin() + long((ch * 3 + band) * gpuPlane));
        }
    std::vector<float> mask(gpuPlane, 0.f), alpha(gpuPlane, 0.f);
    {
        const std::vector<float> m = solver.sinkMaskPlane();
        std::copy(m.begin(), m.end(), mask.begin());
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x)
                    alpha[inj.index({x, y, z})] = solver.readoutAlpha({x, y, z});
    }
    std::vector<float> prop0(planes * gpuPlane, 0.f);
    for (int ch = 0; ch < 3; ++ch)
        for (int i = 0; i < count; ++i) {
            const int band = i == 0 ? 0 : (i < 4 ? 1 : 2);
            const float* in = inj.plane(ch, i);
            const float* f = &factor[(ch * 3 + band) * gpuPlane];
            float* out = &prop0[(ch * count + i) * gpuPlane];
            for (size_t k = 0; k < cells; ++k)
                out[k] = in[k] * f[k];
        }
    std::vector<uint16_t> half;
    const void* prop0Data = prop0.data();
    if (fp16) {
        half.resize(prop0.size());
        for (size_t k = 0; k < prop0.size(); ++k)
            half[k] = floatToHalf(prop0[k]);
        prop0Data = half.data();
    }
    const size_t slice = size_t(p) * p;
    size_t uploaded = 0;
    uploaded +=
        Impl::uploadChanged(s.factor, s.shadowFactor, factor.data(), factor.size() * 4, slice * 4);
    uploaded += Impl::uploadChanged(s.mask, s.shadowMask, mask.data(), mask.size() * 4, slice * 4);
    uploaded += Impl::uploadChanged(s.readoutAlpha, s.shadowReadoutAlpha, alpha.data(),
                                    alpha.size() * 4, slice * 4);
    uploaded +=
        Impl::uploadChanged(s.source, s.shadowSource, prop0Data, gridBytes, slice * cellBytes);
    s.timings.uploadedBytes = uploaded;
    s.timings.uploadCpuMs = upload.elapsedMs();

    const Timer issue;
    // Order 1: the specialised program when the matrices have the sparsity of §4.
    bool l1 = opt.order == 1;
    float l1w[6][4] = {}, l1d[6][2] = {};
    if (l1) {
        for (int o = 0; o < 6; ++o) {
            const int k = o < 2 ? 3 : (o < 4 ? 1 : 2);
            const int a = k == 1 ? 2 : 1, b = k == 3 ? 2 : 3;
            const PropagationMatrix& m = mats[o];
            l1w[o][0] = m.at(0, 0);
            l1w[o][1] = m.at(0, k);
            l1w[o][2] = m.at(k, 0);
            l1w[o][3] = m.at(k, k);
            l1d[o][0] = m.at(a, a);
            l1d[o][1] = m.at(b, b);
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j) {
                    const bool used = i == j || (i == 0 && j == k) || (i == k && j == 0);
                    if (!used && std::abs(m.at(i, j)) > 1e-7f)
                        l1 = false;
                }
        }
    }
    const gpu::GlProgram& prog = l1 ? s.programL1 : s.program;
    glUseProgram(prog.id());
    if (l1) {
        glUniform4fv(prog.uniformLocation("u_l1"), 6, &l1w[0][0]);
        glUniform2fv(prog.uniformLocation("u_l1d"), 6, &l1d[0][0]);
        glUniform1iv(prog.uniformLocation("u_offset"), 6, offs);
    }
    glUniform1i(prog.uniformLocation("u_planeSize"), int(gpuPlane));
    glUniform1i(prog.uniformLocation("u_cells"), int(cells));
    glUniform1i(prog.uniformLocation("u_padded"), p);
    glUniform1i(prog.uniformLocation("u_coeffs"), count);
    glUniform1iv(prog.uniformLocation("u_termStart"), 10, termStart);
    glUniform1i(prog.uniformLocation("u_sinks"), opt.removeExitant ? 1 : 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, s.acc.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, s.exit.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, s.factor.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, s.mask.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, s.terms.id());
    const unsigned groups = unsigned((gpuPlane / 2 + 63) / 64);
    bool accWritten = false, exitWritten = false;
    gpu::GpuProfiler::FrameScope frame(s.profiler);  // cancelled if a pass throws
    {
        auto scope = s.profiler.scope("sslpv.propagate");
        // Step 1 reads the step-0 sources, then the ping-pong pair alternates (the sources
        // stay untouched, so an unchanged injection is never re-uploaded).
        // As many steps as the CPU solve ran: with SslpvOptions::stopEpsilon it stopped once
        // converged, so both paths propagate to the same point without a GPU reduction.
        const gpu::GlObject* src = &s.source;
        int next = 0;
        const int steps = solver.stats().stepsUsed;
        for (int step = 1; step <= steps; ++step) {
            const bool accumulate = step > opt.skipAccumulateSteps;
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, src->id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, s.prop[next].id());
            glUniform1i(prog.uniformLocation("u_accumulate"), accumulate ? 1 : 0);
            glUniform1i(prog.uniformLocation("u_assignAcc"), accumulate && !accWritten ? 1 : 0);
            glUniform1i(prog.uniformLocation("u_assignExit"), exitWritten ? 0 : 1);
            gpu::dispatchLine(groups, 3);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            accWritten = accWritten || accumulate;
            exitWritten = exitWritten || opt.removeExitant;
            src = &s.prop[next];
            next = 1 - next;
        }
    }
    // Grids no step assigned are zero (as the CPU solver's). The clear is a buffer update: it
    // must wait for the shader writes of an earlier propagate() to the same grid (§7.13.2).
    if (!accWritten || !exitWritten)
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    if (!accWritten)
        glClearNamedBufferData(s.acc.id(), GL_R8, GL_RED, GL_UNSIGNED_BYTE, nullptr);
    if (!exitWritten)
        glClearNamedBufferData(s.exit.id(), GL_R8, GL_RED, GL_UNSIGNED_BYTE, nullptr);
    frame.end(/*wait=*/true);
    s.timings.propagateCpuMs = issue.elapsedMs();
    const gpu::PassTiming* t = s.profiler.find("sslpv.propagate");
    s.timings.propagateGpuMs = t ? t->gpuMs : 0.0;
    glUseProgram(0);
    gpu::checkGlError("SslpvGlPropagator::propagate");
    s.hasResult = true;
    s.accStale = s.exitStale = true;
}

}  // namespace lucent::sslpv
