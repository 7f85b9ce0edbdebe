#!/bin/bash
# SPDX-License-Identifier: MIT
# Renders every case of manifest.txt with the given lucent-cli into this folder (64x48 EXR).
# Usage (from the repository root): tests/data/parity/capture.sh path/to/lucent-cli
set -euo pipefail
cli=$1
here=$(dirname "$0")
grep -v '^#' "$here/manifest.txt" | while IFS='|' read -r scene name opts; do
    scene=$(echo $scene); name=$(echo $name)
    # shellcheck disable=SC2086
    "$cli" render "resources/scenes/$scene.json" $opts --width 64 --height 48 \
        -o "$here/${name}__${scene}.exr" > /dev/null 2>&1
    echo "$scene $name"
done
