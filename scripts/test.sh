#!/usr/bin/env bash
# README command (2): installs what is missing, builds, and runs the whole test suite: unit tests of every module
# and the integration tests that run the real ecat-slave on a veth pair inside a network namespace (root needed
# for those; without root they are reported as skipped).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/build.sh"
build="${BUILD_DIR:-$root/build}"
ctest --test-dir "$build" --output-on-failure -j"$(nproc)" --timeout 600
