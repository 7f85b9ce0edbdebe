// SPDX-License-Identifier: MIT
/// @file
/// @brief libFuzzer target of VDB material files: the input is written as a .vdb file and read
/// as `lucent-cli info --validate` does: summarizeVdb (the integrity walk, then OpenVDB),
/// formatVdbSummary, then importVdb (the app's material import and a project's sidecar).
/// Every input must be read or refused with a lucent::Error; anything else is a finding.

#include "FuzzSupport.h"

#include <lucent/core/Error.h>
#include <lucent/io/VdbIO.h>

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    lucent::fuzz::setFuzzImportLimits();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = lucent::fuzz::writeInput("input.vdb", data, size);
    try {
        const lucent::io::VdbFileSummary summary = lucent::io::summarizeVdb(path);
        (void)lucent::io::formatVdbSummary(summary);
    } catch (const lucent::Error&) {
    }
    try {
        const lucent::io::ImportedMaterial material = lucent::io::importVdb(path);
        (void)material;
    } catch (const lucent::Error&) {
    }
    return 0;
}
