#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Fuzz targets of every importer (docs/benchmarks.md, "Fuzzing"); clang 14 with libFuzzer,
# ASan and UBSan, in their own build folder (build/fuzz).
#   .ci/fuzz.sh smoke            build, then a few seconds per target (ctest label `fuzz`;
#                                the seeds include every regression input of tests/data)
#   .ci/fuzz.sh long TARGET N    benchmark-only: N executions of fuzz_TARGET (e.g. mesh_off
#                                1000000), niced, in one process; the corpus grows in
#                                build/fuzz/fuzz/corpus/TARGET, findings go to .../artifacts
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-}
case "$mode" in
    smoke | long) ;;
    *) echo "usage: .ci/fuzz.sh smoke | long TARGET RUNS" >&2; exit 2 ;;
esac
dpkg-query -W -f='${Status}' libclang-rt-14-dev 2>/dev/null | grep -q "install ok installed" || {
    echo "lucent: the fuzz build needs clang-14 and libclang-rt-14-dev (libFuzzer)" >&2; exit 1; }

CCACHE_BASEDIR=$PWD cmake --preset fuzz >/dev/null
CCACHE_BASEDIR=$PWD nice cmake --build --preset fuzz

if [ "$mode" = smoke ]; then
    exec ctest --preset fuzz
fi

target=${2:?target, e.g. mesh_off}
runs=${3:?number of executions}
exec nice -n 10 sh "build/fuzz/fuzz/run_$target.sh" -runs="$runs"
