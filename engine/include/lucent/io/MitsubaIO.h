// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Mitsuba 3 export of a painted MaterialVolume: dense `.vol` grids for the
/// `gridvolume` plugin plus a ready-to-use `heterogeneous` medium as scene XML
/// (docs/file-formats.md, "Mitsuba 3 (.vol)").
///
///     MitsubaExportResult r = exportMitsubaVol(volume, "out/marble");
///     // out/marble_sigma_t.vol, out/marble_albedo.vol, out/marble_medium.xml
///     // scene.xml:  <include filename="marble_medium.xml"/>
///     //             <shape ...> <ref name="interior" id="lucent_medium"/> </shape>
///
/// Mapping (ḡ = mean of g over the inside voxels and the three channels, phase HG(ḡ)):
///   σs,c = σs′_c / (1 − ḡ),  σa,c = σt′_c − σs′_c,  σt,c = σa,c + σs,c,  albedo_c = σs,c/σt,c,
/// so that the similarity-reduced medium σs,c(1 − ḡ) = σs′_c equals Lucent's painted medium in
/// every voxel. With `hgMeanG = false` (ḡ := 0, isotropic phase) the grids hold exactly the
/// OpenVDB `sigma_t` and `albedo` grids of exportVdb.

#include <lucent/material/MaterialVolume.h>

#include <string>

namespace lucent::io {

/// Version of the `.vol` format written (Mitsuba 3 reads only version 3).
inline constexpr int MITSUBA_VOL_VERSION = 3;
/// Encoding identifier of float32 data (the only one Mitsuba 3 reads).
inline constexpr int MITSUBA_VOL_ENCODING_FLOAT32 = 1;
/// Bytes before the voxel data: "VOL", version, encoding, 3 sizes, channels, 6 floats.
inline constexpr size_t MITSUBA_VOL_HEADER_BYTES = 48;

/// Options of exportMitsubaVol.
struct MitsubaExportOptions {
    /// true: `sigma_t` has 3 channels (RGB extinction; exact in Mitsuba's *_rgb variants,
    /// spectrally upsampled in *_spectral ones). false: 1 channel, the Rec. 709 luminance of
    /// σt (the same grey extinction as the OpenVDB `density` grid), for any variant.
    bool rgbSigmaT = true;
    /// true: unreduce with the volume's mean g and write phase HG(ḡ) (see the file comment).
    /// false: write the reduced medium (ḡ := 0) with an isotropic phase.
    bool hgMeanG = true;
    /// Nearest-neighbour lookups reproduce Lucent's piecewise-constant voxels exactly;
    /// false leaves Mitsuba's default trilinear interpolation.
    bool nearestFilter = true;
    std::string mediumId = "lucent_medium";  ///< XML id of the medium, [A-Za-z0-9_-]+
    std::string materialName;                ///< written into the XML comment (may be empty)
};

/// Paths written and the mean asymmetry used.
struct MitsubaExportResult {
    std::string sigmaTPath;  ///< `<prefix>_sigma_t.vol`
    std::string albedoPath;  ///< `<prefix>_albedo.vol`
    std::string xmlPath;     ///< `<prefix>_medium.xml`
    float meanG = 0.f;       ///< ḡ written as the HG parameter (0 when !hgMeanG)
    size_t insideVoxels = 0;
};

/// Writes `<prefix>_sigma_t.vol`, `<prefix>_albedo.vol` and `<prefix>_medium.xml` (each
/// atomically: an existing file is replaced only once its new content is complete). The grids
/// are dense, res³ voxels, x fastest; voxel (i,j,k) is Lucent voxel (i,j,k); outside voxels 0.
/// Extinction is in mm⁻¹ and the XML's `to_world` maps the unit cube onto the grid's box in mm.
/// @param prefix path prefix; its directory must exist.
/// @throw ValueError if the volume is empty, has no inside voxel, or mediumId is invalid;
/// IoError naming the file if writing fails.
MitsubaExportResult exportMitsubaVol(const MaterialVolume& volume, const std::string& prefix,
                                     const MitsubaExportOptions& options = {});

}  // namespace lucent::io
