// SPDX-License-Identifier: MIT
/// @file
/// @brief Shared pieces of the libFuzzer targets (see FuzzSupport.h).

#include "FuzzSupport.h"

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#ifndef LUCENT_FUZZ_SOURCE_DIR
#error "define LUCENT_FUZZ_SOURCE_DIR (tests/fuzz)"
#endif

/// UBSan's options, read at start-up: every report stops the run (so that libFuzzer keeps the
/// input), with a stack, except the upstream reports listed and justified in ubsan.supp.
extern "C" const char* __ubsan_default_options() {
    return "halt_on_error=1:print_stacktrace=1:suppressions=" LUCENT_FUZZ_SOURCE_DIR "/ubsan.supp";
}

namespace lucent::fuzz {

namespace fs = std::filesystem;

namespace {

struct Sandbox {
    Sandbox() {
        const fs::path base =
            fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
        path = (base / ("lucent-fuzz-" + std::to_string(::getpid()))).string();
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~Sandbox() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
    std::string path;
};

}  // namespace

const std::string& sandbox() {
    static const Sandbox box;
    return box.path;
}

std::string writeInput(const std::string& name, const uint8_t* data, size_t size) {
    const std::string path = sandbox() + "/" + name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    out.close();
    if (!out)
        LUCENT_THROW(IoError, "fuzz: cannot write '", path, "'");
    return path;
}

void copyIntoSandbox(const std::string& sourceFile) {
    fs::copy_file(sourceFile, fs::path(sandbox()) / fs::path(sourceFile).filename(),
                  fs::copy_options::overwrite_existing);
}

void setFuzzImportLimits() {
    ImportLimits limits;
    limits.maxFileBytes = uint64_t(16) << 20;  // libFuzzer's inputs are far smaller
    // 2^19 elements: a 4 KiB zlib input can claim 4 M point ids of a triangle strip, and each
    // triangle costs about 5 µs in the instrumented build; at 2^19 the largest input loads in
    // about 2.5 s, an eighth of -timeout (tests/data/fuzz/vtp_strip_million_ids_*.vtp).
    limits.maxElements = uint64_t(1) << 19;
    limits.maxDecodedBytes = uint64_t(256) << 20;  // 256 MiB, an eighth of -rss_limit_mb
    limits.maxReaderCpuSeconds = 10;               // unused in-process; -timeout bounds it
    setImportLimits(limits);
}

}  // namespace lucent::fuzz
