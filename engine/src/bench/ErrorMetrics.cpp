// SPDX-License-Identifier: MIT
/// @file
/// @brief Error metrics with Monte Carlo noise floors (ErrorMetrics.h has the definitions).

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lucent::bench {

namespace {
constexpr double LUMA[3] = {0.2126, 0.7152, 0.0722};       // Rec. 709, as luminance() in Types.h
constexpr double SQRT_2_OVER_PI = 0.79788456080286535588;  // E|X|/σ for a zero-mean normal

void checkSize(const ImageRgb& img, const ImageRgb& ref, const char* what) {
    LUCENT_CHECK(img.width() == ref.width() && img.height() == ref.height(), "compare: ", what,
                 " is ", img.width(), "×", img.height(), " but the reference is ", ref.width(), "×",
                 ref.height());
}
}  // namespace

ErrorReport compareImages(const ImageRgb& test, const ImageRgb& reference,
                          const ImageRgb* referenceVariance, const ImageRgb* testVariance,
                          const std::vector<uint8_t>* mask) {
    LUCENT_CHECK(!reference.isEmpty(), "compare: the reference image is empty");
    checkSize(test, reference, "the test image");
    if (referenceVariance)
        checkSize(*referenceVariance, reference, "the reference variance");
    if (testVariance)
        checkSize(*testVariance, reference, "the test variance");
    const size_t n = reference.pixels().size();
    if (mask)
        LUCENT_CHECK(mask->size() == n, "compare: the mask has ", mask->size(),
                     " pixels, the images ", n);

    // Per pixel: a, b, v for R, G, B and luminance.
    struct Px {
        double a[4], b[4], v[4];
    };
    std::vector<Px> px;
    std::vector<size_t> blockOf;  // block index of each compared pixel
    px.reserve(n);
    blockOf.reserve(n);
    const size_t width = size_t(reference.width());
    const size_t blocksPerRow = (width + ErrorReport::BLOCK_SIZE - 1) / ErrorReport::BLOCK_SIZE;
    for (size_t i = 0; i < n; ++i) {
        if (mask && !(*mask)[i])
            continue;
        blockOf.push_back((i / width) / ErrorReport::BLOCK_SIZE * blocksPerRow +
                          (i % width) / ErrorReport::BLOCK_SIZE);
        const Rgb& a = test.pixels()[i];
        const Rgb& b = reference.pixels()[i];
        LUCENT_CHECK(isFinite(a) && isFinite(b), "compare: non-finite value at pixel (",
                     i % size_t(reference.width()), ", ", i / size_t(reference.width()), ")");
        Px p{};
        for (int c = 0; c < 3; ++c) {
            p.a[c] = a[c];
            p.b[c] = b[c];
            double v = 0.0;
            if (referenceVariance)
                v += std::max(0.f, referenceVariance->pixels()[i][c]);
            if (testVariance)
                v += std::max(0.f, testVariance->pixels()[i][c]);
            p.v[c] = v;
            p.a[3] += LUMA[c] * a[c];
            p.b[3] += LUMA[c] * b[c];
            p.v[3] += LUMA[c] * LUMA[c] * v;
        }
        px.push_back(p);
    }
    LUCENT_CHECK(!px.empty(), "compare: the mask selects no pixel");

    ErrorReport r;
    r.pixelCount = px.size();
    r.hasNoiseFloor = referenceVariance || testVariance;
    const double count = double(px.size());
    for (int c = 0; c < 4; ++c) {
        ChannelError& e = r.channels[size_t(c)];
        double sumB = 0;
        for (const Px& p : px)
            sumB += p.b[c];
        e.meanReference = sumB / count;
        const double eps = 1e-3 * std::abs(e.meanReference);
        double se = 0, rel = 0, sv = 0, relFloor = 0;
        for (const Px& p : px) {
            const double diff = p.a[c] - p.b[c];
            const double denom = std::max(std::abs(p.b[c]), eps);
            se += diff * diff;
            sv += p.v[c];
            if (denom > 0) {
                rel += std::abs(diff) / denom;
                relFloor += SQRT_2_OVER_PI * std::sqrt(p.v[c]) / denom;
            }
        }
        e.rmse = std::sqrt(se / count);
        e.meanRelError = rel / count;
        e.rmseFloor = std::sqrt(sv / count);
        e.meanRelFloor = relFloor / count;
        if (e.meanReference > 0) {
            e.relRmse = e.rmse / e.meanReference;
            e.relRmseFloor = e.rmseFloor / e.meanReference;
        }
        double sumA = 0;
        for (const Px& p : px)
            sumA += p.a[c];
        e.meanRatio = sumB > 0 ? sumA / sumB : 0.0;
    }

    // Blocks: sums of a, b, v and the pixel count per block, then the block metrics.
    const size_t blockRows =
        (size_t(reference.height()) + ErrorReport::BLOCK_SIZE - 1) / ErrorReport::BLOCK_SIZE;
    struct Block {
        double a[4] = {}, b[4] = {}, v[4] = {};
        size_t n = 0;
    };
    std::vector<Block> blocks(blocksPerRow * blockRows);
    for (size_t k = 0; k < px.size(); ++k) {
        Block& blk = blocks[blockOf[k]];
        for (int c = 0; c < 4; ++c) {
            blk.a[c] += px[k].a[c];
            blk.b[c] += px[k].b[c];
            blk.v[c] += px[k].v[c];
        }
        ++blk.n;
    }
    std::erase_if(blocks, [](const Block& blk) { return blk.n == 0; });
    r.blockCount = blocks.size();
    std::vector<double> relErrors(blocks.size());
    for (int c = 0; c < 4; ++c) {
        const double meanB = r.channels[size_t(c)].meanReference;
        double l1 = 0, l1Floor = 0, se = 0, sv = 0;
        for (size_t k = 0; k < blocks.size(); ++k) {
            const Block& blk = blocks[k];
            const double nk = double(blk.n);
            const double diff = (blk.a[c] - blk.b[c]) / nk;  // ā_k − b̄_k
            const double varMean = blk.v[c] / (nk * nk);     // σ_k²
            l1 += nk * std::abs(diff);
            l1Floor += nk * SQRT_2_OVER_PI * std::sqrt(varMean);
            se += nk * diff * diff;
            sv += nk * varMean;
            relErrors[k] = std::abs(diff) / std::max(blk.b[c] / nk, 0.1 * meanB);
        }
        BlockError& e = r.blocks[size_t(c)];
        if (meanB > 0) {
            const double sumB = meanB * count;  // Σ n_k b̄_k = Σ b
            e.relL1 = l1 / sumB;
            e.relL1Floor = l1Floor / sumB;
            e.relRmse = std::sqrt(se / count) / meanB;
            e.relRmseFloor = std::sqrt(sv / count) / meanB;
            // Nearest-rank 95th percentile.
            const size_t rank = size_t(std::ceil(0.95 * double(relErrors.size()))) - 1;
            std::nth_element(relErrors.begin(), relErrors.begin() + std::ptrdiff_t(rank),
                             relErrors.end());
            e.p95 = relErrors[rank];
        }
        const auto net = [](double error, double floor) {
            return std::sqrt(std::max(0.0, error * error - floor * floor));
        };
        e.relL1Net = net(e.relL1, e.relL1Floor);
        e.relRmseNet = net(e.relRmse, e.relRmseFloor);
    }
    return r;
}

std::vector<uint8_t> maskFromImage(const ImageRgb& coverage) {
    std::vector<uint8_t> mask(coverage.pixels().size());
    for (size_t i = 0; i < mask.size(); ++i) {
        const Rgb& c = coverage.pixels()[i];
        mask[i] = (c.r > 0.5f || c.g > 0.5f || c.b > 0.5f) ? 1 : 0;
    }
    return mask;
}

std::vector<uint8_t> maskOfNonBlack(const ImageRgb& a, const ImageRgb& b) {
    LUCENT_CHECK(a.width() == b.width() && a.height() == b.height(), "maskOfNonBlack: ", a.width(),
                 "x", a.height(), " against ", b.width(), "x", b.height());
    std::vector<uint8_t> mask(a.pixels().size());
    for (size_t i = 0; i < mask.size(); ++i)
        mask[i] = (luminance(a.pixels()[i]) != 0.f || luminance(b.pixels()[i]) != 0.f) ? 1 : 0;
    return mask;
}

std::string formatReport(const ErrorReport& report) {
    std::string s;
    char line[256];
    std::snprintf(line, sizeof line, "pixels compared: %zu%s\n", report.pixelCount,
                  report.hasNoiseFloor ? "" : "   (no variance layer: noise floors n/a)");
    s += line;
    std::snprintf(line, sizeof line, "%-9s %12s %12s %12s %12s %12s %12s %12s\n", "channel",
                  "mean ref", "RMSE", "(floor)", "rel RMSE", "(floor)", "mean rel", "(floor)");
    s += line;
    const char* names[4] = {"R", "G", "B", "luminance"};
    for (int c = 0; c < 4; ++c) {
        const ChannelError& e = report.channels[size_t(c)];
        if (report.hasNoiseFloor)
            std::snprintf(line, sizeof line,
                          "%-9s %12.5g %12.5g %12.5g %12.5g %12.5g %12.5g %12.5g\n", names[c],
                          e.meanReference, e.rmse, e.rmseFloor, e.relRmse, e.relRmseFloor,
                          e.meanRelError, e.meanRelFloor);
        else
            std::snprintf(line, sizeof line, "%-9s %12.5g %12.5g %12s %12.5g %12s %12.5g %12s\n",
                          names[c], e.meanReference, e.rmse, "n/a", e.relRmse, "n/a",
                          e.meanRelError, "n/a");
        s += line;
    }
    std::snprintf(line, sizeof line, "%d×%d blocks: %zu\n", ErrorReport::BLOCK_SIZE,
                  ErrorReport::BLOCK_SIZE, report.blockCount);
    s += line;
    std::snprintf(line, sizeof line, "%-9s %12s %12s %12s %12s %12s %12s %12s %12s\n", "channel",
                  "rel L1", "(floor)", "net", "rel RMSE", "(floor)", "net", "p95 error",
                  "mean ratio");
    s += line;
    for (int c = 0; c < 4; ++c) {
        const BlockError& e = report.blocks[size_t(c)];
        const double ratio = report.channels[size_t(c)].meanRatio;
        if (report.hasNoiseFloor)
            std::snprintf(line, sizeof line,
                          "%-9s %12.5g %12.5g %12.5g %12.5g %12.5g %12.5g %12.5g %12.5g\n",
                          names[c], e.relL1, e.relL1Floor, e.relL1Net, e.relRmse, e.relRmseFloor,
                          e.relRmseNet, e.p95, ratio);
        else
            std::snprintf(line, sizeof line,
                          "%-9s %12.5g %12s %12s %12.5g %12s %12s %12.5g %12.5g\n", names[c],
                          e.relL1, "n/a", "n/a", e.relRmse, "n/a", "n/a", e.p95, ratio);
        s += line;
    }
    return s;
}

}  // namespace lucent::bench
