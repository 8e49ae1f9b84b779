#!/usr/bin/env bash
# README command (1): builds, starts the soft slave on a veth pair it creates itself, scans it from the master
# side with ecatctl, shows the result, and cleans up. Needs root (raw sockets, veth creation).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/build.sh"
build="${BUILD_DIR:-$root/build}"
exec bash "$root/scripts/demo-run.sh" "$build"
