// SPDX-License-Identifier: MIT
// Per-frame uniform block (std140, binding LUCENT_BINDING_FRAME); see shared/LightingShared.h.
#pragma once
#include "shared/LightingShared.h"

layout(std140, binding = LUCENT_BINDING_FRAME) uniform FrameBlock {
    FrameUniforms frame;
};
