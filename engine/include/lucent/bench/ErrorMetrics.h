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

#include <lucent/core/Image.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace lucent {

/// One channel's (or luminance's) errors and noise floors.
struct ChannelError {
    double rmse = 0.0;
    double relRmse = 0.0;
    double meanRelError = 0.0;
    double meanReference = 0.0;  ///< b̄
    double rmseFloor = 0.0;      ///< 0 when no variance was given
    double relRmseFloor = 0.0;
    double meanRelFloor = 0.0;
};

struct ErrorReport {
    static constexpr int LUMINANCE = 3;
    std::array<ChannelError, 4> channels;  ///< R, G, B, luminance (Rec. 709)
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

/// A plain-text table of the report (one row per channel, floors beside the errors).
std::string formatReport(const ErrorReport& report);

}  // namespace lucent
