// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The SSLPV propagation as GL 4.5 compute (shaders/sslpv_propagate.comp): same maths,
/// data layout and folded factors as the CPU solver, grids in SSBOs stored as fp32 or fp16.
///
///     SslpvSolver cpu(opt);  cpu.setMaterial(m, eta);  cpu.setInjectionSamples(s);  cpu.solve();
///     SslpvGlPropagator gl(SslpvGlStorage::Float16);   // a GL 4.5 context is current
///     gl.propagate(cpu);           // re-runs cpu's propagation on the GPU (cpu's stepsUsed)
///     gl.writeTextures(tex);       // GPU → four RGBA32F 3-D textures, no read-back
///     gl.accumulation();           // read back into an SslpvGrid (only when a CPU user asks)
///     gl.destroy();                // context current
///
/// The CPU solver still does injection and folds the per-cell factors; the GPU runs the
/// steps. The GPU runs as many steps as the CPU solve used (SslpvStats::stepsUsed: maxSteps,
/// or fewer where SslpvOptions::stopEpsilon stopped it), so both paths converge alike without a
/// reduction per step on the GPU.
/// The GL buffers persist: they are created when the grid size, SH order or storage first
/// appears and reused afterwards; each propagate() uploads only the z-slices of the factor,
/// mask, inside and step-0 source planes whose contents changed since the last upload (a paint
/// stroke uploads the slices it touched), and nothing is read back until accumulation() or
/// exitant() is called.

#include <lucent/sslpv/SslpvSolver.h>

#include <cstdint>
#include <memory>

namespace lucent::sslpv {

/// Storage precision of the GPU grids (factors and masks are always fp32).
enum class SslpvGlStorage { Float32, Float16 };

/// CPU and GPU times of the last propagate(), milliseconds.
struct SslpvGlTimings {
    double uploadCpuMs = 0.0;     ///< building the inputs, comparing and uploading changes
    double propagateCpuMs = 0.0;  ///< issuing the dispatches (and waiting for the timer)
    double propagateGpuMs = 0.0;  ///< GL timestamp queries around the steps
    double readbackCpuMs = 0.0;   ///< the last read-back (accumulation() or exitant())
    size_t uploadedBytes = 0;     ///< bytes uploaded by the last propagate()
    size_t readbacks = 0;         ///< grids read back so far (cumulative)
};

class SslpvGlPropagator {
public:
    /// Compiles the program. Precondition: a GL 4.5 context is current.
    /// @throw GpuError on compile/link errors.
    explicit SslpvGlPropagator(SslpvGlStorage storage = SslpvGlStorage::Float32);
    ~SslpvGlPropagator();
    SslpvGlPropagator(const SslpvGlPropagator&) = delete;
    SslpvGlPropagator& operator=(const SslpvGlPropagator&) = delete;

    /// Runs `solver`'s propagation (its injection grid, folded factors, sink mask, order,
    /// stepsUsed of its last solve, skipAccumulateSteps); nothing is read back until
    /// accumulation() or exitant() is called.
    /// @throw ValueError if the solver has not been solved; GpuError on GL errors.
    void propagate(const SslpvSolver& solver);
    /// The accumulation grid of the last propagate(), read back from the GPU on the first call
    /// after it (context current). @throw ValueError before the first propagate().
    [[nodiscard]] const SslpvGrid& accumulation() const;
    /// The exitant grid, read back likewise.
    [[nodiscard]] const SslpvGrid& exitant() const;
    /// Writes the accumulation grid into four RGBA32F N³ 3-D textures on the GPU: texture i
    /// holds SH coefficient i (i < 4) of the three channels in rgb; texture 0's alpha is the
    /// read-out's (SslpvSolver::readoutAlpha); the other alphas are 0. This
    /// is the layout SslpvSubsurfaceProvider samples. Context current.
    /// @throw ValueError before the first propagate().
    void writeTextures(const unsigned textures[4]) const;
    [[nodiscard]] const SslpvGlTimings& timings() const;
    [[nodiscard]] SslpvGlStorage storage() const;
    /// Frees GL objects (context current). Idempotent.
    void destroy();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace lucent::sslpv
