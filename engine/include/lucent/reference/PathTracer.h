// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Progressive reference rendering of a Scene: per-pixel mean and variance,
/// deterministic per-pixel seeds, stop at a sample count or a target relative standard error,
/// cancellable, with a progress callback.
///
///     ReferenceOptions opt;
///     opt.spp = 256;                    // or opt.targetRse = 0.01f with opt.spp as the cap
///     ReferenceImage img = renderReference(scene, opt);
///     writeReferenceExr(img, "ref.exr");  // RGB mean + "variance" + "coverage" layers

#include <lucent/core/Image.h>
#include <lucent/reference/Transport.h>
#include <lucent/scene/Scene.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

namespace lucent::reference {

/// Version of the reference estimator: part of every cached reference's key, so a cache made
/// by an older estimator is never reused. 3: the medium fills the mesh up to its surface (the
/// masked-out voxels the mesh partly fills read their inside neighbours' material,
/// BoundarySkin.h; 2 read vacuum there). 2: exact refracted next-event estimation at the
/// dielectric boundary (1: straight shadow connections).
constexpr int REFERENCE_ESTIMATOR_VERSION = 3;

/// Progress of a running render (called from the rendering thread between passes).
struct ReferenceProgress {
    int spp = 0;      ///< samples per pixel done
    int maxSpp = 0;   ///< cap
    float rse = INF;  ///< current relative standard error (see renderReference)
    float targetRse = 0.f;
    double elapsedMs = 0.0;
};

struct ReferenceOptions {
    int spp = 64;           ///< samples per pixel (the cap when targetRse > 0); ≥ 3
    float targetRse = 0.f;  ///< stop when the image RSE ≤ this (0: run to spp)
    uint64_t seed = 1;      ///< image = f(scene, seed, spp), independent of threads
    int threads = 0;        ///< worker threads, 0 = all
    BoundaryModel boundary = BoundaryModel::Dielectric;
    bool subsurfaceOnly = false;
    MajorantMode majorant = MajorantMode::Auto;
    /// true: every sample traces one path for all three channels with hero-channel spectral
    /// MIS (hero = sample index mod 3); false: sample s traces channel s mod 3 only.
    bool spectralMis = true;
    int maxScatter = 1 << 20;
    /// Called after every pass; may be empty.
    std::function<void(const ReferenceProgress&)> progress;
    /// Called after every pass with the current mean image (progressive display); may be
    /// empty (then no preview image is assembled).
    std::function<void(const ImageRgb& mean)> preview;
    /// Polled between tiles; when it becomes true the render stops with the passes done.
    const std::atomic<bool>* cancel = nullptr;
};

struct ReferenceImage {
    ImageRgb mean;       ///< per-pixel radiance estimate, W/(mm²·sr), linear
    ImageRgb variance;   ///< per-pixel variance of `mean` (sample variance / sample count)
    ImageRgb coverage;   ///< 1 where the pixel-centre ray hits the object, else 0
    int spp = 0;         ///< samples per pixel actually taken
    float rse = INF;     ///< final relative standard error
    double seconds = 0;  ///< wall time
    uint64_t paths = 0;  ///< camera paths traced
    uint64_t tentativeCollisions = 0;  ///< σt lookups of delta and ratio tracking (work measure)
    bool cancelled = false;
};

/// Renders scene.objects[0] with scene.lights through scene.camera.
///
/// Colour: with spectralMis (default) sample s traces one path with hero channel s mod 3 and
/// MIS weights for all three channels (estimateRadianceRgb); otherwise sample s traces channel
/// s mod 3 only (each channel's mean uses its own samples). Both are unbiased per channel.
/// RSE = √(mean over covered pixels of Var[mean luminance]) / (mean covered luminance).
/// @throw ValueError for a scene without objects/material, spp < 3, targetRse < 0, threads < 0.
ReferenceImage renderReference(const Scene& scene, const ReferenceOptions& options);

/// Writes mean (R,G,B) with the layers "variance" and "coverage". Atomic.
/// @throw IoError naming the path.
void writeReferenceExr(const ReferenceImage& image, const std::string& path);

}  // namespace lucent::reference
