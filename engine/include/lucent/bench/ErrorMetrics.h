// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Image error metrics against a reference, per channel and for luminance, each
/// reported next to the noise floor the Monte Carlo variance of the images alone would give.
///
///     ErrorReport r = compareImages(test, reference, &referenceVariance, nullptr, &mask);
///     std::cout << formatReport(r);
///
/// Over the N pixels selected by the mask (object-covered pixels), for a channel with test
/// values a, reference values b and per-pixel variances v (of b, plus of a when given):
///   RMSE            = √(Σ (a − b)² / N)
///   relative RMSE   = RMSE / b̄,                b̄ = Σ b / N (mean reference value)
///   mean rel. error = Σ |a − b| / max(|b|, ε) / N,   ε = 10⁻³·b̄ (guards near-black pixels)
/// Noise floors (the expected metric if a and b differed by their Monte Carlo noise only):
///   RMSE floor      = √(Σ v / N)
///   rel. RMSE floor = RMSE floor / b̄
///   mean rel. floor = Σ √(2/π)·√v / max(|b|, ε) / N      (E|X| = σ√(2/π) for X ~ N(0, σ²))
///   mean ratio      = Σ a / Σ b   (1: the right brightness on average; separates a scale error
///                                  from a shape error)
///
/// Block metrics (BlockError): the image is cut into BLOCK_SIZE × BLOCK_SIZE tiles from the top
/// left; block k holds its n_k masked pixels, with means ā_k, b̄_k and the variance of its mean
/// σ_k² = Σ v / n_k². Per-pixel Monte Carlo noise averages out over a block, so block errors
/// measure what an eye compares (the shape of the light at a few pixels' scale) and need far
/// fewer reference samples to resolve. Blocks are weighted by n_k (Σ n_k = N):
///   block rel. L1          = Σ n_k |ā_k − b̄_k| / Σ n_k b̄_k
///   block rel. L1 floor    = Σ n_k √(2/π) σ_k / Σ n_k b̄_k
///   block rel. RMSE        = √(Σ n_k (ā_k − b̄_k)² / N) / b̄
///   block rel. RMSE floor  = √(Σ n_k σ_k² / N) / b̄
///   net (noise removed)    = √max(0, error² − floor²)  (independent noise adds in quadrature)
///   95th-percentile error  = 95th percentile over blocks of |ā_k − b̄_k| / max(b̄_k, b̄/10)
///                            (relative to the block, but not to near-black blocks)

#include <lucent/core/Image.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace lucent::bench {

/// One channel's (or luminance's) errors and noise floors.
struct ChannelError {
    double rmse = 0.0;
    double relRmse = 0.0;
    double meanRelError = 0.0;
    double meanReference = 0.0;  ///< b̄
    double rmseFloor = 0.0;      ///< 0 when no variance was given
    double relRmseFloor = 0.0;
    double meanRelFloor = 0.0;
    double meanRatio = 0.0;  ///< Σ a / Σ b (0 when Σ b = 0)
};

/// One channel's (or luminance's) errors over BLOCK_SIZE² pixel blocks (see the file comment).
struct BlockError {
    double relL1 = 0.0;
    double relL1Floor = 0.0;
    double relL1Net = 0.0;  ///< relL1 with its noise floor subtracted in quadrature
    double relRmse = 0.0;
    double relRmseFloor = 0.0;
    double relRmseNet = 0.0;
    double p95 = 0.0;  ///< 95th-percentile block relative error
};

struct ErrorReport {
    static constexpr int LUMINANCE = 3;
    static constexpr int BLOCK_SIZE = 4;   ///< block edge, pixels
    std::array<ChannelError, 4> channels;  ///< R, G, B, luminance (Rec. 709)
    std::array<BlockError, 4> blocks;      ///< the same channels over blocks
    size_t blockCount = 0;                 ///< blocks holding at least one compared pixel
    size_t pixelCount = 0;                 ///< pixels compared
    bool hasNoiseFloor = false;            ///< a variance image was given
};

/// Compares `test` with `reference` over the pixels where `mask` is nonzero (all pixels when
/// `mask` is null). `referenceVariance` / `testVariance` are per-pixel variances of the two
/// estimates (may be null); the luminance variance is Σ wc²·vc (independent channels).
/// @param mask width·height bytes, row-major, top row first.
/// @throw ValueError if sizes differ, the mask selects no pixel, or a value is non-finite.
ErrorReport compareImages(const ImageRgb& test, const ImageRgb& reference,
                          const ImageRgb* referenceVariance, const ImageRgb* testVariance,
                          const std::vector<uint8_t>* mask);

/// Mask of pixels where `coverage` (e.g. a reference's "coverage" layer or a mask image) has
/// any channel > 0.5.
std::vector<uint8_t> maskFromImage(const ImageRgb& coverage);

/// Mask of pixels that are not black (luminance ≠ 0) in `a` or in `b`: two renders of one frame
/// compared where either shows something, the background left out. Sizes must agree.
/// @throw ValueError if they do not.
std::vector<uint8_t> maskOfNonBlack(const ImageRgb& a, const ImageRgb& b);

/// A plain-text table of the report: per pixel, then per block (one row per channel, floors
/// beside the errors).
std::string formatReport(const ErrorReport& report);

}  // namespace lucent::bench
