// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief OpenVDB export and import of a painted MaterialVolume, and a summary of any VDB file
/// (docs/file-formats.md, "Material volumes (OpenVDB)"). OpenVDB itself stays in VdbIO.cpp.
///
///     exportVdb(volume, "marble.vdb", {.materialName = "marble"});
///     ImportedMaterial m = importVdb("marble.vdb");     // bit-exact round trip
///     std::cout << formatVdbSummary(summarizeVdb("any.vdb"));
///
/// Grids written (all sparse: active exactly on the inside voxels, background 0):
///   - `sigma_t` (vec3s, mm⁻¹) reduced extinction σt′ = σa + σs′ per RGB channel;
///   - `sigma_s` (vec3s, mm⁻¹) REDUCED scattering σs′ = σs(1 − g) per channel;
///   - `g`       (vec3s)       Henyey–Greenstein asymmetry per channel;
/// and renderer-ready grids (derived, ignored by importVdb), optional:
///   - `density` (float, mm⁻¹) grey extinction of the similarity-reduced (isotropic-phase)
///     medium: Rec. 709 luminance-weighted σt′;
///   - `albedo`  (vec3s) per-channel reduced single-scattering albedo σs′/σt′;
///   - `color`   (vec3s) the same values as `albedo`, under Blender's conventional name.
/// Index (i,j,k) of every grid is Lucent voxel (i,j,k); the transform puts its centre at
/// origin + (i+½, j+½, k+½)·h mm (a half-voxel translation, since OpenVDB voxel centres sit
/// at integer index coordinates).

#include <lucent/core/Types.h>
#include <lucent/material/MaterialVolume.h>

#include <cstdint>
#include <string>
#include <vector>

namespace lucent::io {

/// Version of the Lucent layout inside the VDB file (metadata `lucent_format_version`).
inline constexpr int VDB_FORMAT_VERSION = 1;

/// Voxel sizes importVdb accepts, mm (0.1 µm .. 10 m: beyond them no one paints a material);
/// exportVdb refuses to write a file outside them.
inline constexpr float VDB_MIN_VOXEL_SIZE_MM = 1e-4f;
inline constexpr float VDB_MAX_VOXEL_SIZE_MM = 1e4f;

/// Options of exportVdb.
struct VdbExportOptions {
    bool rendererGrids = true;  ///< also write `density`, `albedo` and `color`
    std::string materialName;   ///< stored as metadata `lucent_material_name` (may be empty)
};

/// Material-level metadata stored in (and reconstructed from) a Lucent VDB file.
struct VdbMaterialMetadata {
    GridSpec spec;             ///< resolution, origin (mm) and voxel size (mm), bit-exact
    float eta = 1.3f;          ///< relative index of refraction
    MaterialSample base;       ///< the volume's base (fill) material
    std::string materialName;  ///< free text, may be empty
    std::string generator;     ///< "Lucent"
    std::string generatorVersion;
    int formatVersion = VDB_FORMAT_VERSION;
};

/// Result of importVdb.
struct ImportedMaterial {
    MaterialVolume volume;
    VdbMaterialMetadata metadata;
};

/// Writes `volume` as an OpenVDB file. Atomic and checked (lucent/core/FileIO.h): an existing
/// file at `path` is replaced only when the whole new file has been written and synced.
/// @param volume a non-empty material volume.
/// @param path destination file (usually *.vdb).
/// @throw ValueError if the volume is empty or its voxel size is outside
/// [VDB_MIN_VOXEL_SIZE_MM, VDB_MAX_VOXEL_SIZE_MM] (a file importVdb would reject; typically a
/// mesh imported at the wrong scale); IoError naming `path` if writing fails.
void exportVdb(const MaterialVolume& volume, const std::string& path,
               const VdbExportOptions& options = {});

/// The bytes exportVdb writes, for callers that write them together with other files
/// (saveProject).
/// @throw ValueError if the volume is empty; IoError if OpenVDB fails.
std::string encodeVdb(const MaterialVolume& volume, const VdbExportOptions& options = {});

/// Reads a file written by exportVdb back, float32 bit-exact.
/// @throw IoError naming `path` and the problem if the file is missing, truncated, not a VDB,
/// not a Lucent material file, lacks a grid, has a grid of the wrong type or topology, holds
/// NaN/Inf or out-of-domain values, or has an absurd resolution/transform.
ImportedMaterial importVdb(const std::string& path);

/// Summary of one grid of any VDB file.
struct VdbGridSummary {
    std::string name;
    std::string valueType;  ///< OpenVDB type name: "float", "vec3s", ...
    std::string gridClass;  ///< "fog volume", "level set", "unknown", ...
    CoordBox activeBox;     ///< index-space bounding box of the active values (inclusive)
    Point3f worldMin{0.f};  ///< world-space bounds of the active voxels (voxel faces)
    Point3f worldMax{0.f};
    glm::dvec3 voxelSize{0.0};  ///< world units per voxel
    uint64_t activeVoxelCount = 0;
    uint64_t leafCount = 0;
    int components = 0;            ///< 1 scalar, 3 vector, 0 values not summarised
    std::vector<double> minValue;  ///< per component, over the active values
    std::vector<double> maxValue;
    uint64_t nonFiniteCount = 0;  ///< active NaN/Inf values (voxels or tiles)
    std::vector<std::pair<std::string, std::string>> metadata;  ///< name → value as text
    std::string note;  ///< why the grid was not read (a type Lucent does not check), or empty
};

/// Summary of a VDB file.
struct VdbFileSummary {
    std::string path;
    uint64_t fileBytes = 0;
    std::string formatVersion;  ///< "<library major>.<minor>/<file format>"
    std::vector<std::pair<std::string, std::string>> metadata;  ///< file-level metadata
    std::vector<VdbGridSummary> grids;
};

/// Summarises any readable VDB file (foreign files included). The whole file is checked first
/// (every size OpenVDB would trust, docs/file-formats.md "Integrity check"); grids of types
/// the check does not know (point data, point index) are listed without being read.
/// @throw IoError naming `path` if the file is missing, not a readable VDB, corrupt or over
/// the import limits (lucent/core/FileIO.h).
VdbFileSummary summarizeVdb(const std::string& path);

/// Human-readable multi-line text of a summary (what `lucent-cli info` prints).
std::string formatVdbSummary(const VdbFileSummary& summary);

}  // namespace lucent::io
