#!/usr/bin/env bash
# Long fuzzing campaign (docs/robustness.md): builds the libFuzzer targets with clang (build-fuzz/) and runs
# each harness for HOURS (default 1) on its seed corpus, one after the other, niced; prints executions and
# executions per second per harness. Findings land in build-fuzz/fuzz-artifacts/<harness>/; turn each into
# a regression input (tests/fuzz/regressions/<harness>/) once fixed.
#   scripts/fuzz-long.sh [HOURS] [HARNESS...]
set -euo pipefail
cd "$(dirname "$0")/.."
hours=${1:-1}; shift || true
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DSOFTECAT_FUZZ=ON >/dev/null
cmake --build build-fuzz --target fuzzers
seconds=$(awk -v h="$hours" 'BEGIN { printf "%d", h * 3600 }')
exec nice tests/fuzz/run_fuzzers.sh build-fuzz "$seconds" "$@"
