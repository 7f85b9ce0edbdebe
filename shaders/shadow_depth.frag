#version 450 core
// SPDX-License-Identifier: MIT
// Shadow pass: depth only (no colour attachment).

void main() {}
