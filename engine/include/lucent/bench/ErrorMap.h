// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Where a preview is wrong: the signed relative error of luminance per
/// ErrorReport::BLOCK_SIZE² block (ErrorMetrics.h), for a heat-map beside the metrics, and the
/// area resampling that brings a preview to its reference's size.
///
///     ImageRgb preview = resampleArea(viewportImage, ref.mean.width(), ref.mean.height());
///     BlockErrorMap map = blockErrorMap(preview, ref.mean, &mask);
///     // map.at(bx, by) > 0: the preview is too bright there; NaN: no compared pixel

#include <lucent/core/Image.h>

#include <cstdint>
#include <vector>

namespace lucent::bench {

/// Per block k: (ā_k − b̄_k) / max(b̄_k, b̄/10), luminance (Rec. 709), over the masked pixels;
/// b̄ the mean over all of them. The denominator is the 95th-percentile block error's
/// (ErrorMetrics.h), so the map shows what that metric ranks: relative to the block, but not
/// blown up in near-black blocks.
struct BlockErrorMap {
    int width = 0, height = 0;  ///< blocks per row and per column
    int blockSize = 0;          ///< pixels per block edge
    std::vector<float> values;  ///< row-major, top row first; NaN where no pixel was compared
    [[nodiscard]] float at(int bx, int by) const { return values[size_t(by * width + bx)]; }
};

/// @param mask width·height bytes, nonzero where compared (null: every pixel).
/// @throw ValueError if the sizes differ, the mask selects no pixel, a value is not finite or
///        the reference's mean luminance is not > 0.
BlockErrorMap blockErrorMap(const ImageRgb& test, const ImageRgb& reference,
                            const std::vector<uint8_t>* mask);

/// Area-weighted average onto width × height pixels (each output pixel the mean of the input
/// area it covers, partial pixels weighted by their overlap): a resampling that keeps the mean
/// radiance, so a mean ratio taken after it is the one before.
/// @throw ValueError if the image is empty or width, height < 1.
ImageRgb resampleArea(const ImageRgb& image, int width, int height);

}  // namespace lucent::bench
