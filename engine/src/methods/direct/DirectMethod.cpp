// SPDX-License-Identifier: MIT
/// @file
/// @brief `direct`: the object as an opaque surface under direct lighting (gpu::SceneRenderer:
/// Lambert + normalised Blinn-Phong with shadow maps), no subsurface term. The baseline every
/// translucency method is compared with (docs/gpu.md).

#include <lucent/methods/Registry.h>

namespace lucent::methods {

namespace {

class DirectMethod final : public Method {
public:
    using Method::Method;

    /// Opaque grey: gpu::SurfaceMaterial's defaults (ρ_d 0.8, ρ_s 0.04, exponent 64).
    [[nodiscard]] gpu::SurfaceMaterial surface() const override { return {}; }

private:
    void applyParams(const Params&) override {}
};

}  // namespace

MethodEntry directMethod() {
    MethodEntry e;
    MethodInfo& i = e.info;
    i.name = "direct";
    i.title = "Direct";
    i.summary = "opaque surface, direct lighting (Lambert + Blinn-Phong) with shadow maps";
    i.docs = "docs/gpu.md";
    i.caps.gl = true;
    i.quality = {{"-", {}, Backend::Auto}};
    i.evaluate = {""};
    e.create = [](const MethodInfo& info, const MethodContext& context) {
        return std::unique_ptr<Method>(new DirectMethod(info, context));
    };
    return e;
}

}  // namespace lucent::methods
