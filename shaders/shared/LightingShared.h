// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Buffers of the direct-lighting passes, shared by C++ (gpu/SceneRenderer.cpp) and GLSL
/// (mesh_gbuffer.*, direct_shade.frag, post_tonemap.frag). Units: mm, W/sr, W/mm², W/(mm²·sr).

#include "HostDeviceShared.h"

/// Binding points (UBO binding for FrameUniforms, SSBO bindings for the arrays).
#define LUCENT_BINDING_FRAME 0
#define LUCENT_BINDING_LIGHTS 1
#define LUCENT_BINDING_SHADOW_LAYERS 2
#define LUCENT_BINDING_SURFACES 3

#define LUCENT_MAX_LIGHTS 8
#define LUCENT_LIGHT_POINT 0
#define LUCENT_LIGHT_SPOT 1
#define LUCENT_LIGHT_DIRECTIONAL 2

#define LUCENT_TONEMAP_CLAMP 0
#define LUCENT_TONEMAP_REINHARD 1
#define LUCENT_TONEMAP_ACES 2

LUCENT_SHARED_BEGIN

/// One light; std430 array element (SSBO binding LUCENT_BINDING_LIGHTS), 64 bytes.
struct GpuLight {
    vec4 positionType;       ///< xyz position (mm); w type (LUCENT_LIGHT_*)
    vec4 directionCosOuter;  ///< xyz unit direction light travels; w cos(spot outer half-angle)
    vec4 intensityCosInner;  ///< rgb W/sr (point/spot) or W/mm² (directional); w cos(inner)
    ivec4 shadow;  ///< x first shadow layer (−1: none); y layer count (1, or 6 for point)
};
LUCENT_SHARED_SIZE(GpuLight, 64);

/// One shadow-map layer; std430 array element (SSBO binding LUCENT_BINDING_SHADOW_LAYERS).
struct GpuShadowLayer {
    mat4 clipFromWorld;  ///< light clip space of this layer (OpenGL depth in [−1, 1])
    vec4 params;         ///< x: 1 orthographic / 0 perspective; y: world size of one texel at
                         ///< 1 mm from the light (perspective) or of one texel (orthographic)
};
LUCENT_SHARED_SIZE(GpuShadowLayer, 80);

/// Opaque surface of one mesh; std430 array element (SSBO binding LUCENT_BINDING_SURFACES).
struct GpuSurface {
    vec4 diffuse;            ///< rgb Lambert albedo
    vec4 specularShininess;  ///< rgb Blinn-Phong albedo; w exponent
};
LUCENT_SHARED_SIZE(GpuSurface, 32);

/// Per-frame uniforms; std140 UBO (binding LUCENT_BINDING_FRAME), 208 bytes.
struct FrameUniforms {
    mat4 clipFromWorld;
    mat4 viewFromWorld;
    vec4 cameraPosition;  ///< xyz mm; w 1 orthographic camera, 0 perspective
    vec4 cameraForward;   ///< xyz unit view direction (orthographic cameras)
    vec4 background;      ///< rgb radiance of uncovered pixels
    ivec4 flags;          ///< x light count; y shadows on; z specular on; w subsurface only
    vec4 toneMap;         ///< x exposure; y curve (LUCENT_TONEMAP_*)
};
LUCENT_SHARED_SIZE(FrameUniforms, 208);

LUCENT_SHARED_END
