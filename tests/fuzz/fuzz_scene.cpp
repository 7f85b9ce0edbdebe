// SPDX-License-Identifier: MIT
/// @file
/// @brief libFuzzer targets of scene and project files, read by loadScene as the app's Open
/// and `lucent-cli render/reference/evaluate` do: JSON parsing, field checks, then building
/// the object (mesh file or procedural mesh, voxelisation, material volume or VDB material).
///   - fuzz_scene: the input is `scene.json`, in a folder holding the small files its seeds
///     refer to (sphere_closed.off, tetra_open.obj, material_sphere16.vdb from tests/data).
///   - fuzz_project (LUCENT_FUZZ_PROJECT): the input is a project, i.e. the scene JSON and its
///     sidecar VDB, joined by SIDECAR_SEPARATOR (make_seeds.py writes the seeds); both parts
///     are mutated, so the VDB material meets the mesh checks (resolution, fit to the mesh).
/// Every input must load or be refused with a lucent::Error; anything else is a finding.

#include "FuzzSupport.h"

#include <lucent/core/Error.h>
#include <lucent/scene/SceneFile.h>

#include <cstdio>
#include <string_view>

#ifndef LUCENT_FUZZ_DATA_DIR
#error "define LUCENT_FUZZ_DATA_DIR (tests/data)"
#endif

namespace {

[[maybe_unused]] constexpr std::string_view SIDECAR_SEPARATOR = "\n=== project.vdb ===\n";

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    lucent::fuzz::setFuzzImportLimits();
    for (const char* name : {"sphere_closed.off", "tetra_open.obj", "material_sphere16.vdb"})
        lucent::fuzz::copyIntoSandbox(std::string(LUCENT_FUZZ_DATA_DIR) + "/robust/" + name);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string_view input(reinterpret_cast<const char*>(data), size);
#if LUCENT_FUZZ_PROJECT
    const size_t cut = input.find(SIDECAR_SEPARATOR);
    const std::string sidecar = lucent::fuzz::sandbox() + "/project.vdb";
    if (cut == std::string_view::npos) {
        std::remove(sidecar.c_str());  // a project without its sidecar
    } else {
        const std::string_view vdb = input.substr(cut + SIDECAR_SEPARATOR.size());
        lucent::fuzz::writeInput("project.vdb", reinterpret_cast<const uint8_t*>(vdb.data()),
                                 vdb.size());
        input = input.substr(0, cut);
    }
    const char* name = "project.json";
#else
    const char* name = "scene.json";
#endif
    const std::string path = lucent::fuzz::writeInput(
        name, reinterpret_cast<const uint8_t*>(input.data()), input.size());
    try {
        const lucent::Scene scene = lucent::loadScene(path);
        (void)scene;
    } catch (const lucent::Error&) {
    }
    return 0;
}
