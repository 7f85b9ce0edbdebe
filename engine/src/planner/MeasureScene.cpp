// SPDX-License-Identifier: MIT
/// @file
/// @brief Candidates measured on one scene (MeasureScene.h).

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/MeasureScene.h>
#include <lucent/reference/PathTracer.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace lucent::planner {

SceneMeasurement measureCandidates(const Scene& scene, const Models& models,
                                   const MeasureOptions& options) {
    const ImageRgb* ref = options.reference;
    if (ref && (ref->width() != scene.camera.width || ref->height() != scene.camera.height))
        LUCENT_THROW(ValueError, "measureCandidates: the reference is ", ref->width(), "x",
                     ref->height(), ", the camera ", scene.camera.width, "x", scene.camera.height);
    std::vector<size_t> which = options.which;
    if (which.empty()) {
        which.resize(models.candidates.size());
        std::iota(which.begin(), which.end(), size_t{0});
    }
    for (size_t i : which)
        if (i >= models.candidates.size())
            LUCENT_THROW(ValueError, "measureCandidates: candidate ", i, " of ",
                         models.candidates.size());
    const auto cancelled = [&] { return options.cancel && options.cancel->load(); };

    SceneMeasurement out;
    // The unit: a Direct render of the same frame through the same call (context creation
    // included), as the evaluation suite measures it for the models (measureDirectMs).
    out.directMs = measureDirectMs(scene, options.render);
    const size_t total = which.size();
    if (options.progress)
        options.progress(0, total, nullptr);
    for (size_t done = 0; done < total; ++done) {
        if (cancelled()) {
            out.cancelled = true;
            break;
        }
        const CandidateModel& model = models.candidates[which[done]];
        CandidateMeasurement m;
        m.method = model.method;
        m.setting = model.setting;
        try {
            const methods::RenderResult r =
                renderCandidate(scene, model.method, model.setting, options.render);
            m.ms = r.milliseconds;
            m.radiance = r.radiance;
            m.costRatio = r.milliseconds / std::max(out.directMs, 1e-9);
            if (ref) {
                const bench::ErrorReport e = bench::compareImages(
                    r.radiance, *ref, options.referenceVariance, nullptr, options.mask);
                // The dock's number (ReferencePanel::compareWithPreview): luminance blocks;
                // or the evaluation's, net of the reference's noise.
                const auto& blocks = e.blocks[bench::ErrorReport::LUMINANCE];
                m.blockRelL1 = options.netOfNoise ? blocks.relL1Net : blocks.relL1;
            }
        } catch (const Error& e) {
            m = CandidateMeasurement();
            m.method = model.method;
            m.setting = model.setting;
            m.failed = e.what();
        }
        out.candidates.push_back(m);
        if (options.progress)
            options.progress(done + 1, total, &out.candidates.back());
    }
    return out;
}

OwnReferenceMeasurement measureWithOwnReference(const Scene& scene, const Models& models,
                                                const OwnReferenceOptions& options) {
    LUCENT_CHECK(options.width >= 8, "measureWithOwnReference: width must be at least 8, got ",
                 options.width);
    LUCENT_CHECK(options.referenceSpp >= 3,
                 "measureWithOwnReference: the reference needs at least 3 samples per pixel, got ",
                 options.referenceSpp);
    Scene small = scene;
    const double aspect = double(scene.camera.height) / double(std::max(scene.camera.width, 1));
    small.camera.width = options.width;
    small.camera.height = std::max(1, int(std::lround(options.width * aspect)));
    OwnReferenceMeasurement out;
    out.width = small.camera.width;
    out.height = small.camera.height;
    reference::ReferenceOptions ro;
    ro.spp = options.referenceSpp;
    ro.threads = options.referenceThreads;
    ro.cancel = options.cancel;
    ro.subsurfaceOnly = options.render.subsurfaceOnly;  // the same term the candidates render
    const reference::ReferenceImage ref = reference::renderReference(small, ro);
    out.referenceSeconds = ref.seconds;
    out.referenceSpp = ref.spp;
    if (ref.cancelled) {
        out.measurement.cancelled = true;
        return out;
    }
    const std::vector<uint8_t> mask = bench::maskFromImage(ref.coverage);
    // What a perfect image reads against this reference: its own noise, per 4×4 block.
    out.referenceNoise = bench::compareImages(ref.mean, ref.mean, &ref.variance, nullptr, &mask)
                             .blocks[bench::ErrorReport::LUMINANCE]
                             .relL1Floor;
    MeasureOptions mo;
    mo.reference = &ref.mean;
    mo.referenceVariance = &ref.variance;
    mo.mask = &mask;
    mo.netOfNoise = true;  // as the evaluation scores, and the models predict
    mo.which = options.which;
    mo.render = options.render;
    mo.cancel = options.cancel;
    out.measurement = measureCandidates(small, models, mo);
    return out;
}

Models measuredModels(const Models& models, const SceneMeasurement& measurement,
                      MeasuredParts parts) {
    Models out = models;
    out.source =
        models.source + (parts == MeasuredParts::ErrorsOnly ? "; errors measured on the scene"
                                                            : "; measured on the scene");
    // The models' smallest positive error: log-linear, so an exact 0 has no log.
    constexpr double MIN_ERROR = 1e-6;
    for (const CandidateMeasurement& m : measurement.candidates) {
        if (!m.ok() || !(m.costRatio > 0) || !std::isfinite(m.costRatio))
            continue;
        for (CandidateModel& c : out.candidates) {
            if (c.method != m.method || c.setting != m.setting)
                continue;
            // Intercept only (term 0 is the constant 1): the measurement on every scene
            // features this scene has, as liveModels does with a measured stroke cost.
            if (parts == MeasuredParts::CostsAndErrors) {
                std::fill(c.cost.begin(), c.cost.end(), 0.0);
                c.cost[0] = std::log(m.costRatio);
                c.costLogRms = 0.0;
            }
            if (m.blockRelL1 >= 0 && std::isfinite(m.blockRelL1)) {
                std::fill(c.error.begin(), c.error.end(), 0.0);
                c.error[0] = std::log(std::max(m.blockRelL1, MIN_ERROR));
                c.errorLogRms = 0.0;
            }
        }
    }
    return out;
}

MeasuredChoice chooseByMeasuring(const Scene& scene, const Models& models,
                                 const AutoChoice& planned, const Budget& budget, bool glAvailable,
                                 const OwnReferenceOptions& options, const methods::Log& log) {
    MeasuredChoice out;
    out.choice = planned;
    OwnReferenceOptions o = options;
    o.which.clear();
    for (const Option& option : planned.plan.options)
        if (option.fits)
            o.which.push_back(option.index);
    if (o.which.empty())  // nothing fits: the plan takes the least late, so measure them all
        for (const Option& option : planned.plan.options)
            o.which.push_back(option.index);
    if (o.which.empty())
        return out;
    out.measurement = measureWithOwnReference(scene, models, o);
    if (out.measurement.measurement.cancelled)
        return out;
    Budget b = budget;
    b.directMs = planned.directMs;  // the frame planned for, not the small one measured
    b.errorMargin = out.measurement.referenceNoise;  // what the reference can tell apart
    out.choice = chooseOffline(
        scene, measuredModels(models, out.measurement.measurement, MeasuredParts::ErrorsOnly), b,
        glAvailable, log);
    out.choice.plan.reason = "errors measured on this scene: " + out.choice.plan.reason;
    return out;
}

}  // namespace lucent::planner
