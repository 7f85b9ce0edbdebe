// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The preset JSON files, embedded at build time (generated PresetData.cpp).

namespace lucent::detail {

extern const char* const PRESETS_JENSEN2001_JSON;  ///< resources/presets/jensen2001.json
extern const char* const PRESETS_ARTIST_JSON;      ///< resources/presets/artist.json

}  // namespace lucent::detail
