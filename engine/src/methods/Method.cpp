// SPDX-License-Identifier: MIT
#include <lucent/methods/Method.h>

#include <lucent/core/Error.h>

#include <algorithm>

namespace lucent::methods {

Method::Method(const MethodInfo& info, const MethodContext& context)
    : m_info(info), m_context(context) {
    LUCENT_CHECK(context.backend == Backend::Gl || context.backend == Backend::Cpu, info.name,
                 ": a method instance needs a resolved backend (gl or cpu)");
}

Method::~Method() = default;

void Method::setParams(const ParamSet& given) {
    Params p(m_info.name, m_info.params, given, m_context.backend, m_context.live);
    applyParams(p);
    m_params = std::move(p);
}

void Method::note(const std::string& message) const {
    if (m_context.log)
        m_context.log(message);
}

void Method::createGl(const gpu::ShaderLibrary&) {}

void Method::destroyGl() {}

void Method::setScene(const SceneInputs&) {}

void Method::materialChanged(const std::vector<int>&) {}

void Method::cameraChanged(const Camera&) {}

void Method::geometryChanged() {}

gpu::SubsurfaceProvider* Method::subsurfacePass() {
    return nullptr;
}

gpu::SurfaceMaterial Method::surface() const {
    return translucentSurface();
}

ImageRgb Method::renderCpu(const Scene&, const CpuRequest&) {
    LUCENT_THROW(ValueError, m_info.name, " has no CPU renderer");
}

bool Method::converged() const {
    return true;
}

Stats Method::stats() const {
    return {};
}

gpu::SurfaceMaterial translucentSurface() {
    // The reflection at a smooth boundary is a delta whatever η (see the header).
    gpu::SurfaceMaterial surface;
    surface.diffuseAlbedo = Rgb(0.f);
    surface.specularAlbedo = Rgb(0.f);
    return surface;
}

}  // namespace lucent::methods
