// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief IEEE 754 binary16 conversions for GL half-float textures and buffers (round to nearest,
/// ties to even; overflow to ±Inf; NaN stays NaN; subnormal halves both ways).

#include <cstdint>

namespace lucent {

/// The binary16 nearest `value` (ties to even); ±Inf beyond 65504.
uint16_t floatToHalf(float value);
/// The float that binary16 `bits` holds (exact).
float halfToFloat(uint16_t bits);

}  // namespace lucent
