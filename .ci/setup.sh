#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Lucent set-up on Debian 12: install what is missing, build, then launch the app or run the tests.
#   .ci/setup.sh run    install, build (Release), launch `lucent` on the default scene
#   .ci/setup.sh test   what CI runs (through .ci/run): install, then three stages, each a
#                       build and its tests with ctest: the ci preset (release, asserts, warnings
#                       as errors; the whole suite), the asan-ubsan-ci preset (the engine, the
#                       CLI and all their tests under AddressSanitizer, LeakSanitizer and UBSan,
#                       halting on the first error; no Qt app, to fit CI's time budget), then the
#                       libFuzzer smoke run (.ci/fuzz.sh smoke: the importers' fuzz targets, clang
#                       14, every seed and regression input, then 5 s of fuzzing per target)
#   .ci/setup.sh asan   install, then the asan-ubsan-full preset: the whole suite, GUI tests
#                       included, under the same sanitizers (docs/benchmarks.md, "Sanitizer
#                       stage")
# Idempotent: apt-get runs only when a package is missing; works as root or through sudo.
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-}
case "$mode" in
    run | test | asan) ;;
    *) echo "usage: .ci/setup.sh run|test|asan" >&2; exit 2 ;;
esac

packages=(build-essential cmake ninja-build pkg-config ccache
    qt6-base-dev qt6-base-dev-tools libqt6opengl6-dev qt6-charts-dev
    libvtk9-dev libopenvdb-dev libopenvdb-tools libboost-iostreams-dev libopenmesh-dev libglm-dev
    libtbb-dev libepoxy-dev libegl-dev libembree-dev libopenexr-dev libpng-dev zlib1g-dev nlohmann-json3-dev libeigen3-dev
    libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev glslang-tools xvfb xauth clang-format
    clang-14 libclang-rt-14-dev)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
    echo "lucent: installing ${#missing[@]} missing package(s): ${missing[*]}"
    sudo=()
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null || { echo "lucent: need root or sudo to install packages" >&2; exit 1; }
        sudo=(sudo)
    fi
    "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q
    "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# Configure, build and (unless it is the release preset) test one preset; each has its own
# build folder (build/<preset>).
stage() {
    cmake --preset "$1"
    cmake --build --preset "$1"
    [ "$1" = release ] || ctest --preset "$1"
}

case "$mode" in
    # ci first: its failures are the quick ones to read. The sanitizer stage leaves out the Qt
    # app and its GUI tests: with them the stages would not fit "a cold build plus the suite
    # well under 40 minutes on 2 cores" (docs/benchmarks.md, "Sanitizer stage"); the fuzz smoke
    # run adds about 3 minutes cold (docs/benchmarks.md, "Fuzzing").
    test) stage ci; stage asan-ubsan-ci; .ci/fuzz.sh smoke; exit 0 ;;
    asan) stage asan-ubsan-full; exit 0 ;;
esac

stage release
app=build/release/app/gui/lucent
if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
    echo "lucent: no display found, launching under xvfb-run"
    exec xvfb-run -a -s "-screen 0 1600x1000x24" env QT_QPA_PLATFORM=xcb "$app" "${@:2}"
fi
exec "$app" "${@:2}"
