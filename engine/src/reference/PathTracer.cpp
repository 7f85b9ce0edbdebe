// SPDX-License-Identifier: MIT
/// @file
/// @brief Progressive, tiled, deterministic reference rendering (PathTracer.h).

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Timer.h>
#include <lucent/reference/PathTracer.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace lucent::reference {

namespace {

/// Puts the calling thread in flush-to-zero / denormals-are-zero mode for its lifetime and
/// restores the previous mode. Every tile runs under it, whichever thread runs the tile, so
/// the image is bit-identical for any thread count: without it a worker thread and the main
/// thread could round denormal intermediates differently (observed: a 1e-42 difference
/// between 1 and 16 threads).
class ScopedFlushDenormals {
public:
#if defined(__SSE2__)
    ScopedFlushDenormals() : m_saved(_mm_getcsr()) {
        _mm_setcsr(m_saved | 0x8040u);
    }
    ~ScopedFlushDenormals() {
        _mm_setcsr(m_saved);
    }

private:
    unsigned m_saved;
#endif
};

constexpr int TILE = 16;             ///< tile edge, pixels (one parallel task)
constexpr int MIN_SPP_FOR_RSE = 12;  ///< 4 samples per channel before trusting a variance
constexpr int MAX_PASS_SPP = 96;     ///< passes double up to this many samples per pixel
constexpr float LUMA[3] = {0.2126f, 0.7152f, 0.0722f};  // Rec. 709 (Types.h luminance)

/// Running per-pixel, per-channel sums (double: exact enough for 10⁶ samples).
struct Accumulator {
    std::vector<std::array<double, 3>> sum, sumSq;
    std::vector<std::array<uint32_t, 3>> count;
    std::vector<double> lumSum,
        lumSumSq;  // per-sample luminance (spectral MIS: correlated channels)
    explicit Accumulator(size_t n)
        : sum(n, {0, 0, 0}),
          sumSq(n, {0, 0, 0}),
          count(n, {0, 0, 0}),
          lumSum(n, 0),
          lumSumSq(n, 0) {}

    [[nodiscard]] float mean(size_t i, int c) const {
        return count[i][c] ? float(sum[i][c] / count[i][c]) : 0.f;
    }
    /// Variance of the channel mean: unbiased sample variance / n.
    [[nodiscard]] float varianceOfMean(size_t i, int c) const {
        const double n = count[i][c];
        if (n < 2)
            return 0.f;
        const double m = sum[i][c] / n;
        const double s2 = std::max(0.0, (sumSq[i][c] - n * m * m) / (n - 1.0));
        return float(s2 / n);
    }
};

/// Image RSE: √(mean over covered pixels of Var[luminance mean]) / mean covered luminance.
float imageRse(const Accumulator& acc, const std::vector<uint8_t>& covered, bool spectralMis) {
    double var = 0, lum = 0;
    size_t n = 0;
    for (size_t i = 0; i < covered.size(); ++i) {
        if (!covered[i])
            continue;
        for (int c = 0; c < 3; ++c) {
            if (acc.count[i][c] < 2)
                return INF;  // no variance estimate yet
            lum += LUMA[c] * acc.mean(i, c);
            // Per-channel sampling: disjoint samples, Var[Σ wc·mc] = Σ wc²·Var[mc].
            if (!spectralMis)
                var += LUMA[c] * LUMA[c] * acc.varianceOfMean(i, c);
        }
        if (spectralMis) {  // one path for all channels: variance of the per-sample luminance
            const double n = acc.count[i][0];
            const double m = acc.lumSum[i] / n;
            var += std::max(0.0, (acc.lumSumSq[i] - n * m * m) / (n - 1.0)) / n;
        }
        ++n;
    }
    if (n == 0 || !(lum > 0))
        return INF;
    return float(std::sqrt(var / double(n)) / (lum / double(n)));
}

}  // namespace

ReferenceImage renderReference(const Scene& scene, const ReferenceOptions& options) {
    LUCENT_CHECK(!scene.objects.empty(), "reference: the scene has no object");
    const SceneObject& object = scene.objects.front();
    LUCENT_CHECK(object.material != nullptr, "reference: objects[0] has no material volume");
    LUCENT_CHECK(!object.mesh.isEmpty(), "reference: objects[0] has an empty mesh");
    LUCENT_CHECK(options.spp >= 3,
                 "reference: spp must be ≥ 3 (one sample per colour channel), got ", options.spp);
    LUCENT_CHECK(std::isfinite(options.targetRse) && options.targetRse >= 0.f,
                 "reference: target RSE must be ≥ 0, got ", options.targetRse);
    LUCENT_CHECK(options.threads >= 0, "reference: threads must be ≥ 0, got ", options.threads);
    LUCENT_CHECK(options.maxScatter >= 1, "reference: maxScatter must be ≥ 1");
    const Camera& camera = scene.camera;
    LUCENT_CHECK(
        camera.width >= 1 && camera.height >= 1 && camera.width <= 16384 && camera.height <= 16384,
        "reference: camera size ", camera.width, "×", camera.height, " out of range");
    const float eta = options.boundary == BoundaryModel::Matched ? 1.f : scene.eta;
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.f && eta <= 3.f,
                 "reference: eta must be in [1, 3], got ", eta);

    Timer timer;
    std::unique_ptr<ThreadLimit> limit;
    if (options.threads > 0)
        limit = std::make_unique<ThreadLimit>(options.threads);

    GridMedium::Options mediumOptions;
    mediumOptions.majorant = options.majorant;
    const VolumeScene volumeScene(object.mesh,
                                  GridMedium::fromMaterial(*object.material, mediumOptions),
                                  scene.lights, scene.environment);
    TransportOptions transport;
    transport.boundary = options.boundary;
    transport.eta = eta;
    transport.subsurfaceOnly = options.subsurfaceOnly;
    transport.maxScatter = options.maxScatter;

    const int w = camera.width, h = camera.height;
    const size_t pixels = size_t(w) * h;
    ReferenceImage out;
    out.coverage = ImageRgb(w, h);
    std::vector<uint8_t> covered(pixels, 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Point3f o;
            Vector3f d;
            camera.generateRay(float(x) + 0.5f, float(y) + 0.5f, o, d);
            if (volumeScene.boundary().intersect(o, glm::normalize(d), 0.f, INF)) {
                covered[size_t(y) * w + x] = 1;
                out.coverage.at(x, y) = Rgb(1.f);
            }
        }

    Accumulator acc(pixels);
    const int tilesX = (w + TILE - 1) / TILE, tilesY = (h + TILE - 1) / TILE;
    std::atomic<bool> stopped{false};
    std::atomic<uint64_t> paths{0}, lookups{0};
    int done = 0;
    float rse = INF;
    while (done < options.spp) {
        // Passes double (3, 3, 6, 12, ...) up to MAX_PASS_SPP, in whole colour triples.
        int passSpp = std::clamp(done, 3, MAX_PASS_SPP);
        passSpp -= passSpp % 3;
        const int s0 = done, s1 = std::min(options.spp, done + passSpp);
        parallelFor(
            0, int64_t(tilesX) * tilesY,
            [&](int64_t begin, int64_t end) {
                const ScopedFlushDenormals flushDenormals;
                for (int64_t tile = begin; tile < end; ++tile) {
                    if (options.cancel && options.cancel->load(std::memory_order_relaxed)) {
                        stopped = true;
                        return;
                    }
                    const int tx = int(tile % tilesX) * TILE, ty = int(tile / tilesX) * TILE;
                    uint64_t n = 0;
                    TrackingStats stats;
                    for (int y = ty; y < std::min(h, ty + TILE); ++y)
                        for (int x = tx; x < std::min(w, tx + TILE); ++x) {
                            const size_t i = size_t(y) * w + x;
                            for (int s = s0; s < s1; ++s) {
                                // The sample's stream depends only on (pixel, index, seed).
                                Pcg32 rng(
                                    pixelSeed(uint32_t(x), uint32_t(y), uint32_t(s), options.seed));
                                const int ch = s % 3;  // traced (or hero) channel
                                Point3f o;
                                Vector3f d;
                                camera.generateRay(float(x) + rng.uniform(),
                                                   float(y) + rng.uniform(), o, d);
                                if (options.spectralMis) {
                                    const Rgb v =
                                        estimateRadianceRgb(volumeScene, o, glm::normalize(d), ch,
                                                            rng, transport, &stats);
                                    double lum = 0;
                                    for (int c = 0; c < 3; ++c) {
                                        acc.sum[i][c] += v[c];
                                        acc.sumSq[i][c] += double(v[c]) * v[c];
                                        ++acc.count[i][c];
                                        lum += LUMA[c] * v[c];
                                    }
                                    acc.lumSum[i] += lum;
                                    acc.lumSumSq[i] += lum * lum;
                                } else {
                                    const float v =
                                        estimateRadiance(volumeScene, o, glm::normalize(d), ch, rng,
                                                         transport, &stats);
                                    acc.sum[i][ch] += v;
                                    acc.sumSq[i][ch] += double(v) * v;
                                    ++acc.count[i][ch];
                                }
                                ++n;
                            }
                        }
                    paths += n;
                    lookups += stats.tentativeCollisions;
                }
            },
            /*grain=*/1);
        if (stopped)
            break;
        done = s1;
        rse = imageRse(acc, covered, options.spectralMis);
        if (options.progress) {
            ReferenceProgress p;
            p.spp = done;
            p.maxSpp = options.spp;
            p.rse = rse;
            p.targetRse = options.targetRse;
            p.elapsedMs = timer.elapsedMs();
            options.progress(p);
        }
        if (options.preview) {
            ImageRgb preview(w, h);
            for (size_t i = 0; i < pixels; ++i)
                preview.pixels()[i] = Rgb(acc.mean(i, 0), acc.mean(i, 1), acc.mean(i, 2));
            options.preview(preview);
        }
        if (options.targetRse > 0.f && done >= MIN_SPP_FOR_RSE && rse <= options.targetRse)
            break;
    }

    out.mean = ImageRgb(w, h);
    out.variance = ImageRgb(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            for (int c = 0; c < 3; ++c) {
                out.mean.at(x, y)[c] = acc.mean(i, c);
                out.variance.at(x, y)[c] = acc.varianceOfMean(i, c);
            }
        }
    out.spp = done;
    out.rse = imageRse(acc, covered, options.spectralMis);
    out.seconds = timer.elapsedMs() * 1e-3;
    out.paths = paths.load();
    out.tentativeCollisions = lookups.load();
    out.cancelled = stopped.load();
    return out;
}

void writeReferenceExr(const ReferenceImage& image, const std::string& path) {
    writeExrLayers(image.mean, {{"variance", &image.variance}, {"coverage", &image.coverage}},
                   path);
}

}  // namespace lucent::reference
