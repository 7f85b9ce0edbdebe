// SPDX-License-Identifier: MIT
// Integer hashes for decorrelating per-pixel / per-texel sample sequences on the GPU.
#pragma once

// PCG hash (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering", pcg).
uint pcgHash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform float in [0, 1) from the top 24 bits of a hash (never 1).
float toUnit(uint v) { return float(v >> 8) * (1.0 / 16777216.0); }
