// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The versioned JSON scene format and projects (scene JSON + sidecar VDB); see
/// docs/file-formats.md. Loading builds every object: mesh (file or procedural, in mm),
/// its solid voxelisation and its material volume.

#include <lucent/scene/Scene.h>

#include <string>
#include <vector>

namespace lucent {

inline constexpr int SCENE_FORMAT_VERSION = 1;

/// Parses scene JSON text. Relative file paths resolve against `baseDir`.
/// @throw IoError/ValueError naming the offending field (e.g. "lights[0].intensity: expected
///        3 numbers") for unknown, missing or invalid fields.
Scene parseScene(const std::string& jsonText, const std::string& baseDir = ".");

/// Reads and parses a scene file. @throw IoError naming the file.
Scene loadScene(const std::string& path);

/// Serialises a scene to JSON text (the material is referenced, not embedded).
std::string sceneToJson(const Scene& scene);

/// Saves a project: `path` (scene JSON) and the painted material as a sidecar VDB next to it,
/// `<stem>.vdb` or `<stem>.1.vdb`: each save writes the one the project on disk does not refer
/// to, then replaces the JSON (the single commit point), then removes the other. So a save
/// that fails or is killed at any moment leaves the previous project or the new one intact,
/// never a mix. @throw IoError on failure (nothing of the previous project is changed).
void saveProject(const Scene& scene, const std::string& path);

/// The files of the project at `path` that exist: the JSON and its sidecars.
std::vector<std::string> projectFiles(const std::string& path);

/// Removes the project at `path` (its JSON and sidecars), ignoring files that do not exist.
void removeProject(const std::string& path);

/// The built-in default scene: a back-lit shape with thin and thick parts, pre-painted with a
/// heterogeneous material. Needs no files.
Scene makeDefaultScene();

}  // namespace lucent
