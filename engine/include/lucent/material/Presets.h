// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Measured and artist material presets, loaded from resources/presets/*.json
/// (Jensen et al. 2001, Table 1 / Figure 5 measured σs′ and σa in mm⁻¹, η = 1.3; plus
/// artist presets). The data are compiled into the binary as well, so no files are needed.

#include <lucent/material/Medium.h>

#include <string>
#include <vector>

namespace lucent {

struct MaterialPreset {
    std::string name;     ///< e.g. "marble", "skin1"
    Rgb sigma_s_reduced;  ///< σs′, mm⁻¹
    Rgb sigma_a;          ///< σa, mm⁻¹
    Rgb g{0.f};
    float eta = 1.3f;
    std::string source;  ///< citation

    /// σt = σa + σs′, σs′, g as a painted sample.
    [[nodiscard]] MaterialSample sample() const {
        return {sigma_a + sigma_s_reduced, sigma_s_reduced, g};
    }
};

/// Every preset, measured ones first.
const std::vector<MaterialPreset>& allPresets();
/// Looks a preset up by name (case-insensitive). @throw ValueError listing the valid names.
const MaterialPreset& findPreset(const std::string& name);
/// Parses a preset file ({"source": ..., "presets": [{"name", "sigma_s_reduced": [r,g,b],
/// "sigma_a": [r,g,b], optional "g": [r,g,b], "eta", optional "source"}]}), σ in mm⁻¹.
/// @param origin file name used in error messages.
/// @throw IoError naming the file and field when the JSON is malformed or a value is invalid.
std::vector<MaterialPreset> parsePresetJson(const std::string& text, const std::string& origin);

}  // namespace lucent
