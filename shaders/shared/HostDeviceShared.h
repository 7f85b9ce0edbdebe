// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Lets one header declare structs for both C++ and GLSL (Falcor HostDeviceShared.slangh
/// style). In C++ the GLSL type names map to GLM types inside namespace lucent::gpu::shared;
/// in GLSL the macros vanish. Only 16-byte-aligned members (vec4, ivec4, uvec4, mat4) are used in
/// shared structs so std140 and std430 layouts equal the C++ layout; each struct is checked with
/// LUCENT_SHARED_SIZE. GLSL sees this file through the engine's #include resolver, which drops
/// the __cplusplus branch.

#ifdef __cplusplus
#include <glm/glm.hpp>

#include <cstdint>

#define LUCENT_SHARED_BEGIN namespace lucent::gpu::shared {
#define LUCENT_SHARED_END }
/// Checks a struct's C++ size against its GLSL (std140/std430) size in bytes.
#define LUCENT_SHARED_SIZE(T, bytes) \
    static_assert(sizeof(T) == (bytes), #T ": C++ layout must match the GLSL layout")
namespace lucent::gpu::shared {
using vec4 = glm::vec4;
using ivec4 = glm::ivec4;
using uvec4 = glm::uvec4;
using mat4 = glm::mat4;
}  // namespace lucent::gpu::shared
#else
#define LUCENT_SHARED_BEGIN
#define LUCENT_SHARED_END
/// GLSL gets the size as a constant, e.g. `const int GpuLight_SIZE = 64`.
#define LUCENT_SHARED_SIZE(T, bytes) const int T##_SIZE = bytes
#endif
