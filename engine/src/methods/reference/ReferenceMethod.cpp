// SPDX-License-Identifier: MIT
/// @file
/// @brief `reference`: the Monte Carlo volumetric path tracer (lucent/reference/PathTracer.h),
/// the ground truth every other method is measured against (docs/reference.md). CPU only.

#include <lucent/core/Error.h>
#include <lucent/methods/Registry.h>
#include <lucent/reference/PathTracer.h>

#include "../MethodUtil.h"

#include <algorithm>

namespace lucent::methods {

namespace {

using detail::num;

class ReferenceMethod final : public Method {
public:
    using Method::Method;

    ImageRgb renderCpu(const Scene& scene, const CpuRequest& request) override {
        reference::ReferenceOptions opt;
        opt.spp = params().getInt("spp");
        opt.seed = uint64_t(params().getInt("seed"));
        opt.threads = params().getInt("threads");
        opt.boundary = reference::parseBoundaryModel(params().getChoice("boundary"));
        opt.subsurfaceOnly = request.subsurfaceOnly;
        if (request.progress) {
            const auto progress = request.progress;
            opt.progress = [progress](const reference::ReferenceProgress& p) {
                double frac = double(p.spp) / double(std::max(1, p.maxSpp));
                progress(frac, std::to_string(p.spp) + " spp  RSE " + num(p.rse, "%.4f") + "  " +
                                   num(p.elapsedMs * 1e-3, "%.1f") + " s");
            };
        }
        const reference::ReferenceImage img = reference::renderReference(scene, opt);
        m_stats = {{"spp", std::to_string(img.spp)},
                   {"RSE", num(img.rse, "%.4f")},
                   {"seconds", num(img.seconds, "%.2f")},
                   {"paths", std::to_string(img.paths)}};
        return img.mean;
    }

    [[nodiscard]] Stats stats() const override { return m_stats; }

private:
    void applyParams(const Params&) override {}  // read by renderCpu

    Stats m_stats;
};

}  // namespace

MethodEntry referenceMethod() {
    MethodEntry e;
    MethodInfo& i = e.info;
    i.name = "reference";
    i.title = "Reference (path tracer)";
    i.summary = "CPU Monte Carlo volumetric path tracer (ground truth)";
    i.docs = "docs/reference.md";
    i.caps.cpu = true;
    i.caps.preferred = Backend::Cpu;
    i.caps.groundTruth = true;
    i.params = {
        {"spp", ParamType::Int, "samples per pixel", 3, 1 << 24, {}, "64"},
        {"seed",
         ParamType::Int,
         "random seed: same seed and spp give the same image",
         0,
         1 << 30,
         {},
         "1"},
        {"threads", ParamType::Int, "worker threads (0: all)", 0, 1024, {}, "0"},
        {"boundary",
         ParamType::Choice,
         "dielectric: exact Fresnel and refraction; matched: eta = 1; straight: fast "
         "approximation (not ground truth)",
         0,
         0,
         {"dielectric", "matched", "straight"},
         "dielectric"},
    };
    for (int spp : {4, 16, 64})
        i.quality.push_back({std::to_string(spp) + " spp",
                             ParamSet::fromAssignments({"spp=" + std::to_string(spp)}),
                             Backend::Auto});
    e.create = detail::make<ReferenceMethod>;
    return e;
}

}  // namespace lucent::methods
