// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli info`: grids, types, bounds, active voxels, value ranges and metadata of
/// any OpenVDB file; `--validate` also checks it as a Lucent material file.

#include "CliCommon.h"

#include <lucent/core/Error.h>
#include <lucent/io/VdbIO.h>

#include <cstdio>
#include <memory>
#include <string>

namespace lucent::cli {

namespace {

struct InfoOptions {
    std::string file;
    bool validate = false;
};

void runInfo(const InfoOptions& args) {
    const std::string& path = args.file;
    const io::VdbFileSummary summary = io::summarizeVdb(path);
    std::fputs(io::formatVdbSummary(summary).c_str(), stdout);
    if (args.validate) {
        const io::ImportedMaterial m = io::importVdb(path);
        size_t inside = 0;
        for (uint8_t v : m.volume.insideMask())
            inside += v != 0;
        std::printf(
            "lucent material: valid (format %d, %d^3 voxels of %.6g mm, %zu inside, eta "
            "%.4g%s%s)\n",
            m.metadata.formatVersion, m.metadata.spec.resolution, double(m.metadata.spec.voxelSize),
            inside, double(m.metadata.eta), m.metadata.materialName.empty() ? "" : ", ",
            m.metadata.materialName.c_str());
    }
}

}  // namespace

void addInfoCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* sub = addCommand(
        cli, "info", "describe an OpenVDB file (grids, bounds, value ranges, metadata)",
        "usage: lucent-cli info [--validate] FILE.vdb\n",
        "Prints the file's metadata and, per grid: value type and class, active voxel count,\n"
        "index and world bounding boxes, voxel size, the range of the active values (per\n"
        "component) and the grid metadata. Works on any VDB file.\n");
    auto args = std::make_shared<InfoOptions>();
    sub->add_option("FILE.vdb", args->file, "the OpenVDB file")->required()->check(existingFile());
    sub->add_flag("--validate", args->validate,
                  "also read the file as a Lucent material volume and fail (exit 1) with the "
                  "reason if it is not a valid one");
    sub->callback([args] { runInfo(*args); });
}

}  // namespace lucent::cli
