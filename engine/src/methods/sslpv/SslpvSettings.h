// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief SSLPV settings the sslpv method and combined's SSLPV part share (private to the
/// methods module): the propagation's stop parameters and the diffusion mode's settings.

#include <lucent/core/Error.h>
#include <lucent/methods/Params.h>
#include <lucent/sslpv/SslpvProvider.h>

#include <algorithm>
#include <string>
#include <vector>

namespace lucent::methods::detail {

/// The stop rules and live refinement of an SSLPV propagation (the sslpv method, combined's
/// SSLPV part), with the same defaults: offline to the global stop; live no global stop (it is
/// not local: paint in one place would end the propagation everywhere) but the per-brick one,
/// and idle frames carry a change's propagation on. `subject` starts each description (e.g.
/// "the SSLPV part: "); `propagationModes` names the modes the per-brick rules apply to.
inline std::vector<ParamDescriptor> propagationStopParams(const std::string& subject,
                                                          const std::string& propagationModes) {
    return {{"stop",
             ParamType::Float,
             subject + "stop propagating once the flux still in flight is below this fraction "
                       "of the injected flux (0: always run all steps; live preview default 0)",
             0,
             1,
             {},
             "0.01",
             "",
             "0"},
            {"brick-stop",
             ParamType::Float,
             subject + propagationModes +
                 "a brick of cells whose light is below this fraction of the injected light per "
                 "cell stops propagating, and the solve ends once every brick is dark (0: off; "
                 "live preview default 0.0001)",
             0,
             1,
             {},
             "0",
             "",
             "0.0001"},
            {"refine-steps",
             ParamType::Int,
             subject + "live preview" +
                 (propagationModes.empty() ? std::string(": ") : ", " + propagationModes) +
                 "while light is still in flight after a change's frame, idle frames carry the "
                 "propagation on (steps per frame) until the stop rules end it or this many steps "
                 "in all (0: a change's frame is the last)",
             0,
             4096,
             {},
             "0",
             "",
             "1024",
             ParamScope::Live}};
}

/// Provider options for SSLPV's mode diffusion (docs/methods/sslpv.md, "Diffusion mode"), from
/// the parameters `steps` and `stop`. Not propagation: conjugate-gradient iterations of the
/// diffusion solve, warm-started from the last solution (a stroke re-solves from the picture
/// before it). The propagation's live defaults (32 fixed steps, no stop) would leave the first
/// frame unconverged, so unless given, both live and offline run to an unbalanced power of 10⁻³
/// of the source, at most 1024 iterations; one solve per change (no refinement, no per-brick
/// stop: `brick-stop` is the propagation's). The source is
/// integrated over each beam's chord per cell, so a few texels per cell face carry it: 4 texels
/// of RSM per grid cell across (≈ 5 per lit cell face) instead of the propagation's 256², which
/// re-walked 25 beams per face on every stroke (docs/benchmarks.md, "Diffusion mode").
/// @param gl whether the propagation was asked to run on the GL backend. @throw ValueError then
/// (the diffusion solve runs on the CPU); `subject` starts the message, e.g. "sslpv: mode
/// diffusion".
inline void useDiffusionMode(sslpv::SslpvProviderOptions& o, const Params& p,
                             const std::string& subject, bool gl) {
    LUCENT_CHECK(!gl, subject, " solves on the CPU (propagation=cpu)");
    o.render.solver.mode = sslpv::SslpvMode::Diffusion;
    o.render.injectionResolution = std::clamp(4 * o.render.gridResolution, 64, 256);
    o.render.solver.maxSteps = p.isGiven("steps") ? p.getInt("steps") : 1024;
    o.render.solver.stopEpsilon = p.isGiven("stop") ? float(p.getFloat("stop")) : 1e-3f;
    o.render.solver.brickStopEpsilon = 0.f;  // a propagation rule: the solve has no bricks
    o.refineSteps = 0;
}

}  // namespace lucent::methods::detail
