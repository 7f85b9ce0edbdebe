// SPDX-License-Identifier: MIT
/// @file
/// @brief GL 4.5 compute propagation of SSLPV (shaders/sslpv_propagate.comp).

#include <lucent/sslpv/SslpvGl.h>

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/GpuTimer.h>
#include <lucent/gpu/Shader.h>

#include <epoxy/gl.h>

#include <cstring>
#include <string>
#include <vector>

namespace lucent {

uint16_t floatToHalf(float value) {
    uint32_t x;
    std::memcpy(&x, &value, sizeof(x));
    const uint32_t sign = (x >> 16) & 0x8000u;
    uint32_t mant = x & 0x7fffffu;
    const int exp = int((x >> 23) & 0xffu);
    if (exp == 255)
        return uint16_t(sign | 0x7c00u | (mant ? 0x200u : 0u));  // Inf / NaN
    const int e = exp - 127 + 15;
    if (e >= 31)
        return uint16_t(sign | 0x7c00u);  // overflow → Inf
    if (e <= 0) {                         // subnormal half (or zero)
        if (e < -10)
            return uint16_t(sign);
        mant |= 0x800000u;
        const int shift = 14 - e;
        uint32_t h = mant >> shift;
        const uint32_t rem = mant & ((1u << shift) - 1u), halfway = 1u << (shift - 1);
        if (rem > halfway || (rem == halfway && (h & 1u)))
            ++h;
        return uint16_t(sign | h);
    }
    uint32_t h = (uint32_t(e) << 10) | (mant >> 13);
    const uint32_t rem = mant & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u)))
        ++h;  // carry may round up to Inf: correct
    return uint16_t(sign | h);
}

float halfToFloat(uint16_t bits) {
    const uint32_t sign = uint32_t(bits & 0x8000u) << 16;
    const uint32_t exp = (bits >> 10) & 0x1fu;
    const uint32_t mant = bits & 0x3ffu;
    float out;
    if (exp == 0) {
        out = std::ldexp(float(mant), -24);  // zero or subnormal
        return sign ? -out : out;
    }
    const uint32_t f = exp == 31 ? (sign | 0x7f800000u | (mant << 13))
                                 : (sign | ((exp - 15 + 127) << 23) | (mant << 13));
    std::memcpy(&out, &f, sizeof(out));
    return out;
}

struct SslpvGlPropagator::Impl {
    SslpvGlStorage storage;
    gpu::GlProgram program;    ///< generic term-list gather (order 2)
    gpu::GlProgram programL1;  ///< order 1, sparsity-specialised gather
    gpu::GpuProfiler profiler;
    SslpvGrid acc, exit;
    SslpvGlTimings timings;
};

SslpvGlPropagator::SslpvGlPropagator(SslpvGlStorage storage) : m_impl(std::make_unique<Impl>()) {
    m_impl->storage = storage;
    const gpu::ShaderLibrary lib;
    std::vector<std::string> defines;
    if (storage == SslpvGlStorage::Float16)
        defines.push_back("SSLPV_FP16");
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
    m_impl->profiler.destroy();
}

const SslpvGrid& SslpvGlPropagator::accumulation() const {
    return m_impl->acc;
}
const SslpvGrid& SslpvGlPropagator::exitant() const {
    return m_impl->exit;
}
const SslpvGlTimings& SslpvGlPropagator::timings() const {
    return m_impl->timings;
}
SslpvGlStorage SslpvGlPropagator::storage() const {
    return m_impl->storage;
}

void SslpvGlPropagator::propagate(const SslpvSolver& solver) {
    LUCENT_CHECK(m_impl->program.isValid() && m_impl->programL1.isValid(),
                 "SslpvGlPropagator: the program was destroyed");
    const SslpvGrid& inj = solver.injection();
    LUCENT_CHECK(inj.resolution() > 0 && !solver.isDirty(),
                 "SslpvGlPropagator: solve the CPU solver first (injection and factors)");
    const SslpvOptions& opt = solver.options();
    const int n = inj.resolution(), count = inj.coeffCount();
    const bool fp16 = m_impl->storage == SslpvGlStorage::Float16;
    const size_t cells = inj.planeSize();
    const size_t gpuPlane = cells + (cells & 1u);  // even: fp16 pairs never straddle planes
    const size_t planes = size_t(3) * count;

    // Upload: step-0 sources (injection × folded factors, as on the CPU), zero grids,
    // factors, sink mask, and the matrices as a term list.
    const Timer upload;
    std::vector<float> factor(9 * gpuPlane, 0.f);
    for (int ch = 0; ch < 3; ++ch)
        for (int band = 0; band < 3; ++band) {
            const std::vector<float> f = solver.foldedFactorPlane(ch, band);
            std::copy(f.begin(), f.end(), factor.begin() + long((ch * 3 + band) * gpuPlane));
        }
    std::vector<float> mask(gpuPlane, 0.f);
    {
        const std::vector<float> m = solver.sinkMaskPlane();
        std::copy(m.begin(), m.end(), mask.begin());
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
    const size_t cellBytes = fp16 ? 2 : 4;
    const size_t gridBytes = planes * gpuPlane * cellBytes;
    std::vector<uint16_t> half;
    const void* prop0Data = prop0.data();
    if (fp16) {
        half.resize(prop0.size());
        for (size_t k = 0; k < prop0.size(); ++k)
            half[k] = floatToHalf(prop0[k]);
        prop0Data = half.data();
    }
    const std::vector<uint8_t> zeros(gridBytes, 0);  // +0.0 in both encodings
    const auto& mats = propagationMatrices(opt.order);
    const int p = n + 2;
    const int offs[6] = {1, -1, p, -p, p * p, -p * p};
    std::vector<int> terms;  // ivec4 per term
    int termStart[10] = {};
    for (int i = 0; i < count; ++i) {
        termStart[i] = int(terms.size() / 4);
        for (int o = 0; o < 6; ++o)
            for (int j = 0; j < count; ++j) {
                const float w = mats[o].at(i, j);
                if (std::abs(w) <= 1e-7f)
                    continue;  // zero by symmetry (quadrature ~1e−17)
                int wb;
                std::memcpy(&wb, &w, sizeof(wb));
                terms.insert(terms.end(), {j, offs[o], wb, 0});
            }
    }
    termStart[count] = int(terms.size() / 4);
    for (int i = count + 1; i < 10; ++i)
        termStart[i] = termStart[count];

    std::vector<gpu::GlObject> buf;
    buf.push_back(gpu::createBuffer(gridBytes, prop0Data, 0));                          // 0: prop A
    buf.push_back(gpu::createBuffer(gridBytes, zeros.data(), 0));                       // 1: prop B
    buf.push_back(gpu::createBuffer(gridBytes, zeros.data(), GL_DYNAMIC_STORAGE_BIT));  // 2: acc
    buf.push_back(gpu::createBuffer(gridBytes, zeros.data(), GL_DYNAMIC_STORAGE_BIT));  // 3: exit
    buf.push_back(gpu::createBuffer(factor.size() * 4, factor.data(), 0));              // 4
    buf.push_back(gpu::createBuffer(mask.size() * 4, mask.data(), 0));                  // 5
    buf.push_back(gpu::createBuffer(terms.size() * 4, terms.data(), 0));                // 6
    m_impl->timings.uploadCpuMs = upload.elapsedMs();

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
    const gpu::GlProgram& prog = l1 ? m_impl->programL1 : m_impl->program;
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
    for (unsigned b = 2; b < 7; ++b)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, buf[b].id());
    const unsigned groups = unsigned((gpuPlane / 2 + 63) / 64);
    m_impl->profiler.beginFrame();
    {
        auto scope = m_impl->profiler.scope("sslpv.propagate");
        bool accWritten = false, exitWritten = false;
        int cur = 0;
        for (int step = 1; step <= opt.maxSteps; ++step) {
            const bool accumulate = step > opt.skipAccumulateSteps;
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf[size_t(cur)].id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buf[size_t(1 - cur)].id());
            glUniform1i(prog.uniformLocation("u_accumulate"), accumulate ? 1 : 0);
            glUniform1i(prog.uniformLocation("u_assignAcc"), accumulate && !accWritten ? 1 : 0);
            glUniform1i(prog.uniformLocation("u_assignExit"), exitWritten ? 0 : 1);
            glDispatchCompute(groups, 3, 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            accWritten = accWritten || accumulate;
            exitWritten = exitWritten || opt.removeExitant;
            cur = 1 - cur;
        }
    }
    m_impl->profiler.endFrame(/*wait=*/true);
    m_impl->timings.propagateCpuMs = issue.elapsedMs();
    const gpu::PassTiming* t = m_impl->profiler.find("sslpv.propagate");
    m_impl->timings.propagateGpuMs = t ? t->gpuMs : 0.0;

    // Read back into CPU grids.
    const Timer readback;
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<uint8_t> raw(gridBytes);
    auto fetch = [&](const gpu::GlObject& b, SslpvGrid& grid) {
        glGetNamedBufferSubData(b.id(), 0, GLsizeiptr(gridBytes), raw.data());
        grid = SslpvGrid(n, opt.order);
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
    };
    fetch(buf[2], m_impl->acc);
    fetch(buf[3], m_impl->exit);
    for (auto& b : buf)
        b.destroy();
    glUseProgram(0);
    gpu::checkGlError("SslpvGlPropagator::propagate");
    m_impl->timings.readbackCpuMs = readback.elapsedMs();
}

}  // namespace lucent
