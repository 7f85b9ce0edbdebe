// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli compare`: RMSE, relative RMSE and mean relative error of an image against
/// a reference, per channel and luminance, next to the Monte Carlo noise floor.

#include "CliCommon.h"

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/core/Image.h>

#include <cstdio>
#include <memory>
#include <optional>

namespace lucent::cli {

namespace {

/// A layer of an EXR, or nothing when the file lacks it.
std::optional<ImageRgb> tryLayer(const std::string& path, const std::string& layer) {
    try {
        return readExr(path, layer);
    } catch (const IoError&) {
        return std::nullopt;
    }
}

ImageRgb readAny(const std::string& path) {
    const bool png = path.size() >= 4 && path.compare(path.size() - 4, 4, ".png") == 0;
    return png ? readPng(path) : readExr(path);
}

struct CompareOptions {
    std::string test, reference, mask;
};

void runCompare(const CompareOptions& args) {
    const std::string& testPath = args.test;
    const std::string& refPath = args.reference;
    const ImageRgb test = readExr(testPath);
    const ImageRgb ref = readExr(refPath);
    const std::optional<ImageRgb> refVar = tryLayer(refPath, "variance");
    const std::optional<ImageRgb> testVar = tryLayer(testPath, "variance");

    std::vector<uint8_t> mask;
    std::string maskFrom;
    if (const std::optional<std::string> m =
            args.mask.empty() ? std::nullopt : std::optional(args.mask)) {
        const ImageRgb img = readAny(*m);
        if (img.width() != ref.width() || img.height() != ref.height())
            LUCENT_THROW(ValueError, "--mask ", *m, ": ", img.width(), "×", img.height(),
                         " but the reference is ", ref.width(), "×", ref.height());
        mask = bench::maskFromImage(img);
        maskFrom = *m;
    } else if (auto cov = tryLayer(refPath, "coverage");
               cov && cov->width() == ref.width() && cov->height() == ref.height()) {
        mask = bench::maskFromImage(*cov);
        maskFrom = refPath + " (coverage layer)";
    } else {
        // No coverage information: pixels where either image is not black (a size mismatch is
        // compareImages' error below).
        mask = test.width() == ref.width() && test.height() == ref.height()
                   ? bench::maskOfNonBlack(ref, test)
                   : std::vector<uint8_t>(ref.pixels().size());
        maskFrom = "non-black pixels";
    }
    const bench::ErrorReport r = bench::compareImages(test, ref, refVar ? &*refVar : nullptr,
                                                      testVar ? &*testVar : nullptr, &mask);
    std::printf("test: %s\nreference: %s\nmask: %s\nnoise floor from: %s\n", testPath.c_str(),
                refPath.c_str(), maskFrom.c_str(),
                refVar && testVar ? "variance layers of both images"
                : refVar          ? "the reference's variance layer"
                : testVar         ? "the test image's variance layer"
                                  : "none (no variance layer)");
    std::fputs(bench::formatReport(r).c_str(), stdout);
}

}  // namespace

void addCompareCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* sub = addCommand(
        cli, "compare", "error metrics of an image against a reference, with its noise floor",
        "usage: lucent-cli compare TEST.exr REFERENCE.exr [--mask MASK]\n",
        "Prints per channel (R, G, B) and for luminance, over the object-covered pixels:\n"
        "RMSE, relative RMSE (RMSE / mean reference) and mean relative error (|a−b| / b per\n"
        "pixel), each beside its noise floor: the value expected from the Monte Carlo variance\n"
        "alone (the 'variance' layers of REFERENCE and, if present, TEST). Definitions:\n"
        "docs/reference.md.\n");
    auto args = std::make_shared<CompareOptions>();
    sub->add_option("TEST.exr", args->test, "the image to judge")
        ->required()
        ->check(existingFile());
    sub->add_option("REFERENCE.exr", args->reference, "the reference (lucent-cli reference)")
        ->required()
        ->check(existingFile());
    sub->add_option("--mask", args->mask,
                    "EXR or PNG, same size; pixels with any channel > 0.5 are compared. Default: "
                    "REFERENCE's 'coverage' layer, else pixels not black in either")
        ->type_name("MASK")
        ->check(existingFile());
    sub->callback([args] { runCompare(*args); });
}

}  // namespace lucent::cli
