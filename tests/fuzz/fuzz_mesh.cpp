// SPDX-License-Identifier: MIT
/// @file
/// @brief libFuzzer target of one mesh format (LUCENT_FUZZ_MESH_EXTENSION, e.g. ".off"):
/// the input is written as a file of that extension and read by loadMesh, as `lucent-cli
/// export --mesh` and the app's mesh import do: the validation walk (MeshValidate.cpp), the
/// upstream reader (OpenMesh, or VTK, which the fuzz build runs in-process instead of in a
/// child process so that the sanitizers see it), then repair and validation. Every input must
/// either load or be refused with a lucent::Error; anything else (a crash, a sanitizer report,
/// another exception, a timeout or running out of memory) is a finding.

#include "FuzzSupport.h"

#include <lucent/core/Error.h>
#include <lucent/mesh/MeshIO.h>

#ifndef LUCENT_FUZZ_MESH_EXTENSION
#error "define LUCENT_FUZZ_MESH_EXTENSION, e.g. \".obj\""
#endif

#if LUCENT_FUZZ_MALLOC_MAY_FAIL
/// VTK targets: in the app, VTK's readers run in a child process whose address space is
/// limited, so an allocation sized by a corrupt value (e.g. the last entry of a cell offsets
/// array, which VTK 9.1 trusts) fails and VTK reports an error, which becomes an IoError.
/// Letting malloc return null for sizes beyond ASan's maximum reproduces that here; an
/// allocation above -malloc_limit_mb (2 GiB) still stops the run as a finding. VTK's leaks on
/// its error paths are freed by the child's exit in the app (tests/fuzz/CMakeLists.txt).
extern "C" const char* __asan_default_options() {
    return "allocator_may_return_null=1:detect_leaks=0";
}
#endif

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    lucent::fuzz::setFuzzImportLimits();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path =
        lucent::fuzz::writeInput(std::string("input") + LUCENT_FUZZ_MESH_EXTENSION, data, size);
    try {
        lucent::MeshReport report;
        const lucent::TriangleMesh mesh = lucent::loadMesh(path, 1.f, &report);
        (void)mesh;
    } catch (const lucent::Error&) {
        // A clear refusal is the expected outcome for most inputs.
    }
    return 0;
}
