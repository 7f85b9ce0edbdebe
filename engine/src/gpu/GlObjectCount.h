// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Private: live/leaked GL object accounting shared by GlObject and GlProgram.

namespace lucent::gpu::detail {
void countCreated();
void countDestroyed();
/// An owner went away (destructor or overwrite) without destroy().
void countLeaked();
}  // namespace lucent::gpu::detail
