// SPDX-License-Identifier: MIT
/// @file
/// @brief Block error maps and area resampling (ErrorMap.h).

#include <lucent/bench/ErrorMap.h>
#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lucent::bench {

BlockErrorMap blockErrorMap(const ImageRgb& test, const ImageRgb& reference,
                            const std::vector<uint8_t>* mask) {
    LUCENT_CHECK(!reference.isEmpty(), "error map: the reference image is empty");
    LUCENT_CHECK(test.width() == reference.width() && test.height() == reference.height(),
                 "error map: the image is ", test.width(), "×", test.height(),
                 " but the reference is ", reference.width(), "×", reference.height());
    const size_t n = reference.pixels().size();
    LUCENT_CHECK(!mask || mask->size() == n, "error map: the mask has ", mask->size(),
                 " pixels, the images ", n);
    constexpr int B = ErrorReport::BLOCK_SIZE;
    BlockErrorMap map;
    map.blockSize = B;
    map.width = (reference.width() + B - 1) / B;
    map.height = (reference.height() + B - 1) / B;
    std::vector<double> sumA(size_t(map.width) * size_t(map.height), 0.0);
    std::vector<double> sumB(sumA.size(), 0.0);
    std::vector<int> count(sumA.size(), 0);
    double totalB = 0.0;
    size_t compared = 0;
    for (int y = 0; y < reference.height(); ++y)
        for (int x = 0; x < reference.width(); ++x) {
            const size_t i = size_t(y) * size_t(reference.width()) + size_t(x);
            if (mask && !(*mask)[i])
                continue;
            const Rgb& a = test.pixels()[i];
            const Rgb& b = reference.pixels()[i];
            LUCENT_CHECK(isFinite(a) && isFinite(b), "error map: non-finite value at pixel (", x,
                         ", ", y, ")");
            const size_t k = size_t(y / B) * size_t(map.width) + size_t(x / B);
            sumA[k] += luminance(a);
            sumB[k] += luminance(b);
            ++count[k];
            totalB += luminance(b);
            ++compared;
        }
    LUCENT_CHECK(compared > 0, "error map: the mask selects no pixel");
    const double meanB = totalB / double(compared);
    LUCENT_CHECK(meanB > 0, "error map: the reference is black over the compared pixels");
    map.values.assign(sumA.size(), std::numeric_limits<float>::quiet_NaN());
    for (size_t k = 0; k < sumA.size(); ++k) {
        if (count[k] == 0)
            continue;
        const double a = sumA[k] / count[k], b = sumB[k] / count[k];
        map.values[k] = float((a - b) / std::max(b, 0.1 * meanB));
    }
    return map;
}

ImageRgb resampleArea(const ImageRgb& image, int width, int height) {
    LUCENT_CHECK(!image.isEmpty(), "resample: the image is empty");
    LUCENT_CHECK(width >= 1 && height >= 1, "resample: the size must be at least 1×1, got ", width,
                 "×", height);
    // Separable: the weights of an output pixel over input columns (rows) are its overlap with
    // each input pixel, in input pixels, divided by the output pixel's width (height).
    const auto weights = [](int in, int out) {
        std::vector<std::vector<std::pair<int, float>>> w(static_cast<size_t>(out));
        const double scale = double(in) / double(out);
        for (int o = 0; o < out; ++o) {
            const double lo = o * scale, hi = (o + 1) * scale;
            for (int i = int(std::floor(lo)); i < std::min(in, int(std::ceil(hi))); ++i) {
                const double overlap = std::min(hi, double(i + 1)) - std::max(lo, double(i));
                if (overlap > 0)
                    w[size_t(o)].push_back({i, float(overlap / scale)});
            }
        }
        return w;
    };
    const auto wx = weights(image.width(), width);
    const auto wy = weights(image.height(), height);
    ImageRgb rows(width, image.height());
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < width; ++x) {
            Rgb s(0.f);
            for (const auto& [i, w] : wx[size_t(x)])
                s += image.at(i, y) * w;
            rows.at(x, y) = s;
        }
    ImageRgb out(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            Rgb s(0.f);
            for (const auto& [i, w] : wy[size_t(y)])
                s += rows.at(x, i) * w;
            out.at(x, y) = s;
        }
    return out;
}

}  // namespace lucent::bench
