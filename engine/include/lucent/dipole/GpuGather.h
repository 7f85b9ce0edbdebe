// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief OpenGL 4.5 compute version of the image-space dipole gather (shaders/dipole_gather.comp):
/// same samples, weights and interleave table as gatherImageSpace(), in float on the GPU,
/// including GatherSettings::maxRadius (camera image only: light views are gathered by the CPU
/// gather and by DipoleSubsurfaceProvider).
///
///     auto ctx = gpu::GlContext::createHeadless();      // or the app's current context
///     dipole::GpuGather gather(gpu::ShaderLibrary{});    // compiles; context current
///     GatherResult g = gather.run(buffers, settings);    // context current
///     gather.destroy();                                  // explicit, context current

#include <lucent/dipole/ImageSpace.h>

#include <memory>

namespace lucent::gpu {
class ShaderLibrary;
}

namespace lucent::dipole {

class GpuGather {
public:
    /// Compiles dipole_gather.comp. Precondition: a GL 4.5 context is current.
    /// @throw GpuError with the shader file and line on compile/link errors.
    explicit GpuGather(const gpu::ShaderLibrary& library);
    ~GpuGather();
    GpuGather(const GpuGather&) = delete;
    GpuGather& operator=(const GpuGather&) = delete;

    /// Uploads the buffers, dispatches one invocation per pixel, reads back B and forms
    /// L = F_t B/π on the CPU. @throw ValueError as gatherImageSpace(); GpuError on GL errors.
    GatherResult run(const SurfaceBuffers& buffers, const GatherSettings& settings);
    /// Frees the program (context current). Idempotent.
    void destroy();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace lucent::dipole
