// SPDX-License-Identifier: MIT
/// @file
/// @brief The engine used from several threads at once, as the app uses it (issue 16, item 3).
/// The app's worker threads (app/gui: ReferencePanel, MainWindow's VDB export, PlanChart,
/// AutoLevelCheck, AutoMeasure) each
/// take a frozen copy of the scene or the material and run one engine call on it while the UI
/// thread goes on painting the original and rendering the preview. This test does the same
/// with std::threads and checks that every result equals the same call made alone:
/// - the reference path tracer on a frozen copy (its image depends only on scene, seed and
///   spp, docs/reference.md), itself parallel, while
/// - a VDB export of another copy runs (checked by reading the file back), and
/// - Auto's level check renders SSLPV's diffusion levels of a third copy, and
/// - Auto's own measurement renders the exact reference of a fourth copy and two candidates
///   against it (GL, as the app runs it; left out without a headless context), while
/// - the "UI" thread paints strokes into the original and renders SSLPV (CPU) after each.
/// On its own the test checks that the copies are deep (a shared volume would change the
/// reference image and the export). Its real purpose is the ThreadSanitizer job (the `tsan`
/// preset, docs/benchmarks.md "ThreadSanitizer"): lazily built tables, caches, registries and
/// everything else the three calls share are then checked for races.

#include <lucent/core/Image.h>
#include <lucent/io/VdbIO.h>
#include <lucent/material/Brush.h>
#include <lucent/methods/RenderImage.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/planner/LevelCheck.h>
#include <lucent/planner/MeasureScene.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/SceneFile.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace lucent {
namespace {

Scene smallSkinSphere() {
    Scene scene = loadScene(std::string(LUCENT_SOURCE_DIR) + "/resources/scenes/skin_sphere.json");
    scene.camera.width = 32;
    scene.camera.height = 24;
    return scene;
}

/// What ReferencePanel::frozenScene does: the scene with its own copy of the material.
Scene frozenCopy(const Scene& scene) {
    Scene copy = scene;
    copy.objects[0].material = std::make_shared<MaterialVolume>(*scene.objects[0].material);
    return copy;
}

reference::ReferenceImage renderSmallReference(const Scene& scene) {
    reference::ReferenceOptions o;
    o.spp = 6;
    o.seed = 7;
    o.threads = 2;
    return reference::renderReference(scene, o);
}

ImageRgb renderSslpvCpu(const Scene& scene) {
    methods::ParamSet p;
    p.set("grid", 16);
    methods::RenderOptions o;
    o.backend = methods::Backend::Cpu;
    return methods::renderImage(scene, "sslpv", p, o).radiance;
}

/// A dark stroke across the sphere, one of `n`, each at another height.
void paintDarkStroke(MaterialVolume& volume, int i, int n) {
    BrushSettings brush;
    brush.radius = 1.5f;
    brush.channels = uint8_t(Channel::SigmaT) | uint8_t(Channel::SigmaS);
    brush.value.sigma_t = Rgb(4.f);
    brush.value.sigma_s = Rgb(0.5f);
    const float y = -3.f + 6.f * float(i) / float(n);
    paintStroke(volume, brush, {Point3f(-4.f, y, 0.f), Point3f(4.f, y, 0.f)});
}

/// What the viewport's AutoLevelChecker runs (on the CPU here, as the other calls).
planner::LevelCheck checkDiffusionLevels(const Scene& scene) {
    planner::AutoChoice choice;
    choice.method = "sslpv";
    choice.variant = "diffusion";
    choice.setting = "grid 64";
    choice.params = planner::resolveCandidate("sslpv:diffusion", "grid 64").params;
    choice.plan.chosen.error = 0.05;
    planner::LevelCheckOptions o;
    o.tolerance = {10.0, 0.0};  // every step within: both differences are measured
    o.width = 32;
    o.render.backend = methods::Backend::Cpu;
    return planner::checkLevels(scene, planner::defaultModels(), choice, o);
}

/// What the viewport's AutoMeasurer runs: the exact reference of a small frame (one thread),
/// then SSLPV diffusion at grids 16 and 32 against it, on the preview's backend.
planner::OwnReferenceMeasurement measureOnItsOwn(const Scene& scene) {
    const planner::Models& models = planner::defaultModels();
    planner::OwnReferenceOptions o;
    for (size_t i = 0; i < models.candidates.size(); ++i)
        if (models.candidates[i].method == "sslpv:diffusion" &&
            models.candidates[i].setting != "grid 64")
            o.which.push_back(i);
    o.width = 16;
    o.referenceSpp = 6;
    o.referenceThreads = 1;
    o.render.backend = methods::Backend::Gl;
    return planner::measureWithOwnReference(scene, models, o);
}

bool sameImage(const ImageRgb& a, const ImageRgb& b) {
    return a.width() == b.width() && a.height() == b.height() && a.pixels() == b.pixels();
}

TEST(ConcurrentUse, AppWorkerPatternsGiveWhatEachCallGivesAlone) {
    constexpr int STROKES = 3;
    const Scene scene = smallSkinSphere();
    const std::string vdbPath = std::string(LUCENT_TEST_OUTPUT_DIR) + "/concurrent_use_export.vdb";

    // Alone, one after the other.
    const reference::ReferenceImage referenceAlone = renderSmallReference(frozenCopy(scene));
    const planner::LevelCheck levelsAlone = checkDiffusionLevels(frozenCopy(scene));
    const bool gl = gpu::GlContext::isHeadlessAvailable();
    planner::OwnReferenceMeasurement measuredAlone;
    if (gl)
        measuredAlone = measureOnItsOwn(frozenCopy(scene));
    Scene painted = frozenCopy(scene);
    for (int i = 0; i < STROKES; ++i)
        paintDarkStroke(*painted.objects[0].material, i, STROKES);
    const ImageRgb previewAlone = renderSslpvCpu(painted);

    // Together: the workers get frozen copies of the unpainted scene, the "UI" thread paints
    // the original (its own copy here, so that the test's `scene` stays as it was).
    Scene live = frozenCopy(scene);
    const Scene forReference = frozenCopy(live);
    const MaterialVolume forExport(*live.objects[0].material);
    const Scene forLevelCheck = frozenCopy(live);
    const Scene forMeasurement = frozenCopy(live);
    reference::ReferenceImage referenceTogether;
    planner::LevelCheck levelsTogether;
    planner::OwnReferenceMeasurement measuredTogether;
    std::exception_ptr referenceError, exportError, levelError, measureError;
    std::thread referenceWorker([&] {
        try {
            referenceTogether = renderSmallReference(forReference);
        } catch (...) {
            referenceError = std::current_exception();
        }
    });
    std::thread exportWorker([&] {
        try {
            io::exportVdb(forExport, vdbPath, {});
        } catch (...) {
            exportError = std::current_exception();
        }
    });
    std::thread levelWorker([&] {
        try {
            levelsTogether = checkDiffusionLevels(forLevelCheck);
        } catch (...) {
            levelError = std::current_exception();
        }
    });
    std::thread measureWorker([&] {
        try {
            if (gl)
                measuredTogether = measureOnItsOwn(forMeasurement);
        } catch (...) {
            measureError = std::current_exception();
        }
    });
    ImageRgb previewTogether;
    for (int i = 0; i < STROKES; ++i) {
        paintDarkStroke(*live.objects[0].material, i, STROKES);
        previewTogether = renderSslpvCpu(live);
    }
    referenceWorker.join();
    exportWorker.join();
    levelWorker.join();
    measureWorker.join();
    if (measureError)
        std::rethrow_exception(measureError);
    if (referenceError)
        std::rethrow_exception(referenceError);
    if (exportError)
        std::rethrow_exception(exportError);
    if (levelError)
        std::rethrow_exception(levelError);

    EXPECT_TRUE(sameImage(referenceTogether.mean, referenceAlone.mean))
        << "the reference of a frozen copy changed while the original was painted";
    EXPECT_EQ(referenceTogether.spp, referenceAlone.spp);
    EXPECT_TRUE(sameImage(previewTogether, previewAlone))
        << "the preview of the painted scene differs from the same render made alone";
    const io::ImportedMaterial exported = io::importVdb(vdbPath);
    EXPECT_EQ(exported.volume.contentHash(), forExport.contentHash())
        << "the exported copy is not the volume it was copied from";
    EXPECT_NE(exported.volume.contentHash(), live.objects[0].material->contentHash())
        << "the strokes should have changed the original";
    std::remove(vdbPath.c_str());
    ASSERT_EQ(levelsAlone.steps.size(), 2u);
    ASSERT_EQ(levelsTogether.steps.size(), levelsAlone.steps.size());
    for (size_t i = 0; i < levelsAlone.steps.size(); ++i)
        EXPECT_DOUBLE_EQ(levelsTogether.steps[i].difference, levelsAlone.steps[i].difference)
            << "the level check of a frozen copy changed while the original was painted";
    EXPECT_EQ(levelsTogether.setting, levelsAlone.setting);
    if (gl) {
        const auto& alone = measuredAlone.measurement.candidates;
        const auto& together = measuredTogether.measurement.candidates;
        ASSERT_EQ(alone.size(), 2u);
        ASSERT_EQ(together.size(), alone.size());
        EXPECT_DOUBLE_EQ(measuredTogether.referenceNoise, measuredAlone.referenceNoise);
        for (size_t i = 0; i < alone.size(); ++i) {
            ASSERT_TRUE(alone[i].ok() && together[i].ok()) << alone[i].failed << together[i].failed;
            EXPECT_DOUBLE_EQ(together[i].blockRelL1, alone[i].blockRelL1)
                << "Auto's measurement of a frozen copy changed while the original was painted";
        }
    }
}

}  // namespace
}  // namespace lucent
