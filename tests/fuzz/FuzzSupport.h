// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Shared pieces of the libFuzzer targets (docs/benchmarks.md, "Fuzzing"). The engine's
/// importers take a path, as the app and the CLI call them, so each input is written to a
/// private folder of the fuzzing process (on /dev/shm when it exists) and read through the
/// same entry point.

#include <cstddef>
#include <cstdint>
#include <string>

namespace lucent::fuzz {

/// The fuzzing process's private folder, created on first use and removed at exit.
const std::string& sandbox();

/// Writes `size` bytes to sandbox()/name (replacing it). @return the path.
std::string writeInput(const std::string& name, const uint8_t* data, size_t size);

/// Copies `sourceFile` into the sandbox under its file name (for files a scene refers to).
void copyIntoSandbox(const std::string& sourceFile);

/// Lowers the import limits (lucent/core/FileIO.h) so that every input the engine accepts
/// decodes to less than libFuzzer's memory limit (-rss_limit_mb=2048 with ASan's overhead):
/// an input that still grows past it is a claim the engine does not check, i.e. a finding.
void setFuzzImportLimits();

}  // namespace lucent::fuzz
