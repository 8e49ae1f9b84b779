#!/usr/bin/env bash
# Installs every Debian package the project needs to build, run and test.
# Used by both README commands and by .ci/run. Idempotent; quiet when all is present.
set -euo pipefail
PKGS=(build-essential cmake ninja-build pkg-config
      libpcap-dev zlib1g-dev libeigen3-dev libgtest-dev libgmock-dev libcli11-dev libxml2-dev libxml2-utils
      iproute2 tshark python3 python3-scapy python3-yaml gnuplot-nox clang-format help2man dpkg-dev file
      clang libclang-rt-14-dev)  # clang + libFuzzer/sanitizer runtimes: the fuzz build (tests/fuzz) and the clang -Werror build
missing=()
for p in "${PKGS[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
    SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    export DEBIAN_FRONTEND=noninteractive
    echo "install-deps: installing ${missing[*]}"
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
