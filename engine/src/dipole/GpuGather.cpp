// SPDX-License-Identifier: MIT
/// @file
/// @brief GL compute image-space dipole gather: uploads the camera buffers as std430 vec4
/// arrays, dispatches shaders/dipole_gather.comp, reads back B(x_o).

#include <lucent/dipole/GpuGather.h>

#include <lucent/core/Error.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/Shader.h>

#include <epoxy/gl.h>

#include <vector>

namespace lucent::dipole {

struct GpuGather::Impl {
    gpu::GlProgram program;
};

GpuGather::GpuGather(const gpu::ShaderLibrary& library) : m_impl(std::make_unique<Impl>()) {
    m_impl->program = gpu::GlProgram::compute(library, "dipole_gather.comp");
}

GpuGather::~GpuGather() = default;

void GpuGather::destroy() {
    if (m_impl)
        m_impl->program.destroy();
}

GatherResult GpuGather::run(const SurfaceBuffers& buf, const GatherSettings& gs) {
    LUCENT_CHECK(m_impl && m_impl->program.isValid(), "GpuGather::run: the program was destroyed");
    const Boundary boundary = validateGather(buf, gs);
    const size_t n = size_t(buf.width) * size_t(buf.height);
    // std430 arrays of vec4 (16-byte stride): no padding questions.
    std::vector<glm::vec4> position(n), normal(n), irradiance(n), material(2 * n);
    for (size_t i = 0; i < n; ++i) {
        position[i] = glm::vec4(buf.position[i], buf.covered[i] ? 1.f : 0.f);
        normal[i] = glm::vec4(buf.normal[i], 0.f);
        irradiance[i] = glm::vec4(buf.irradiance[i], 0.f);
        material[2 * i] = glm::vec4(buf.material[i].sigma_t, 0.f);
        material[2 * i + 1] = glm::vec4(buf.material[i].sigma_s, 0.f);
    }
    const auto shifts = interleaveShifts(gs);
    std::vector<glm::vec4> shiftData(2 * shifts.size());
    for (size_t c = 0; c < shifts.size(); ++c) {
        shiftData[2 * c] = {shifts[c][0], shifts[c][1], shifts[c][2], shifts[c][3]};
        shiftData[2 * c + 1] = {shifts[c][4], 0.f, 0.f, 0.f};
    }
    static_assert(sizeof(glm::vec4) == 16, "std430 vec4 stride");
    std::vector<gpu::GlObject> buffers;
    buffers.push_back(gpu::createBuffer(n * 16, position.data(), 0));
    buffers.push_back(gpu::createBuffer(n * 16, normal.data(), 0));
    buffers.push_back(gpu::createBuffer(n * 16, irradiance.data(), 0));
    buffers.push_back(gpu::createBuffer(2 * n * 16, material.data(), 0));
    buffers.push_back(gpu::createBuffer(shiftData.size() * 16, shiftData.data(), 0));
    buffers.push_back(gpu::createBuffer(n * 16, nullptr, GL_DYNAMIC_STORAGE_BIT));
    for (unsigned b = 0; b < buffers.size(); ++b)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, buffers[b].id());

    const gpu::GlProgram& prog = m_impl->program;
    glUseProgram(prog.id());
    const auto set1i = [&](const char* name, int v) { glUniform1i(prog.uniformLocation(name), v); };
    const auto set1f = [&](const char* name, float v) {
        glUniform1f(prog.uniformLocation(name), v);
    };
    glUniformMatrix4fv(prog.uniformLocation("u_clipFromWorld"), 1, GL_FALSE,
                       &buf.clipFromWorld[0][0]);
    glUniform3f(prog.uniformLocation("u_eye"), buf.eye.x, buf.eye.y, buf.eye.z);
    glUniform3f(prog.uniformLocation("u_viewDir"), buf.viewDirection.x, buf.viewDirection.y,
                buf.viewDirection.z);
    set1i("u_ortho", buf.orthographic ? 1 : 0);
    glUniform2i(prog.uniformLocation("u_size"), buf.width, buf.height);
    set1i("u_model", gs.model == Model::Dipole ? 0 : 1);
    glUniform3f(prog.uniformLocation("u_boundary"), float(boundary.fdr), float(boundary.c1),
                float(boundary.c2));
    set1i("u_nImp", gs.importanceSamples);
    set1i("u_nUni", gs.uniformSamples);
    set1f("u_discQuantile", gs.discQuantile);
    set1f("u_maxRadius", gs.maxRadius);
    set1i("u_jacobian", gs.jacobian ? 1 : 0);
    set1f("u_maxJacobian", gs.maxJacobian);
    set1i("u_interleave", gs.interleave);
    glDispatchCompute(unsigned(buf.width + 7) / 8, unsigned(buf.height + 7) / 8, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    std::vector<glm::vec4> exitance(n);
    glGetNamedBufferSubData(buffers.back().id(), 0, GLsizeiptr(n * 16), exitance.data());
    glUseProgram(0);
    for (auto& b : buffers)
        b.destroy();
    gpu::checkGlError("GpuGather::run");

    GatherResult out;
    out.exitance = ImageRgb(buf.width, buf.height);
    for (int y = 0; y < buf.height; ++y)
        for (int x = 0; x < buf.width; ++x)
            out.exitance.at(x, y) = Rgb(exitance[buf.index(x, y)]);
    exitanceToRadiance(buf, gs.eta, out);
    return out;
}

}  // namespace lucent::dipole
