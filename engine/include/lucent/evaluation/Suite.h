// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The evaluation suite: the scenes every translucency method is scored on against the
/// exact reference (issue 14), built through the engine API (procedural meshes, presets,
/// brushes and procedural fills, deformers), plus cases made from scene files.
///
///     SuiteOptions o;                       // 64×64 pixels, material grid 48³
///     for (const EvalCase& c : buildSuite("default", o))
///         std::cout << c.name << ": " << c.description << "\n";
///
/// Units: mm, mm⁻¹ (docs/conventions.md). docs/evaluation.md lists the cases and why each is
/// there.

#include <lucent/material/Presets.h>
#include <lucent/scene/Scene.h>

#include <functional>
#include <string>
#include <vector>

namespace lucent::evaluation {

/// One scene to score the methods on.
struct EvalCase {
    std::string name;         ///< unique, file-name safe: "sphere-marble-eta1.3"
    std::string group;        ///< "homogeneous", "heterogeneous", "shape", "lights", "deforming"
    std::string description;  ///< one line: what the case exercises
    Scene scene;              ///< camera size already set
};

struct SuiteOptions {
    int width = 64;   ///< image width, pixels (cases with another aspect scale the height)
    int height = 64;  ///< image height, pixels
    int materialResolution = 48;  ///< voxels per axis of the painted grids built here
    /// Folder holding scenes/ (the back-lit scene file). Empty: the LUCENT_RESOURCES_DIR
    /// environment variable, else the source tree's resources/.
    std::string resourcesDir;
    /// The project's shared test meshes (the painted bunny is decimated from
    /// bunny_closed_75k.ply there; they are not part of the repository). Empty: the
    /// LUCENT_SHARED_MESHES environment variable, else ../shared/meshes beside the source tree.
    std::string sharedMeshesDir;
    /// Notes for the user: a case left out because its input is absent. May be empty.
    std::function<void(const std::string&)> log;
};

/// "default", "smoke".
std::vector<std::string> suiteNames();

/// The cases of suite `name`: "default" (every case of issue 14) or "smoke" (two small cases
/// for a test: one homogeneous, one painted; at most 32×32 pixels).
/// @throw ValueError for an unknown name (listing the known ones); IoError when a resource
/// file (mesh, scene) cannot be read.
std::vector<EvalCase> buildSuite(const std::string& name, const SuiteOptions& options = {});

/// Keeps the cases whose name contains one of `filters` (all when `filters` is empty).
/// @throw ValueError when a filter matches no case (listing the names).
std::vector<EvalCase> filterCases(std::vector<EvalCase> cases,
                                  const std::vector<std::string>& filters);

/// Cases from scene files: every file × preset × η (an empty list keeps the file's value),
/// named "<file stem>[-<preset>][-eta<η>]". A preset replaces every object's material by the
/// uniform preset on the grid the file gave, inside the mesh only (makeObject).
/// @param width, height image size (0: the file's).
/// @throw IoError / ValueError from loading; ValueError for two files with the same stem.
std::vector<EvalCase> casesFromSceneFiles(const std::vector<std::string>& paths,
                                          const std::vector<const MaterialPreset*>& presets,
                                          const std::vector<float>& etas, int width, int height);

/// The resources folder `options` points to (see SuiteOptions::resourcesDir).
std::string resourcesDir(const SuiteOptions& options);
/// The shared test meshes folder `options` points to (see SuiteOptions::sharedMeshesDir).
std::string sharedMeshesDir(const SuiteOptions& options);

}  // namespace lucent::evaluation
