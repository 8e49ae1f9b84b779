#!/usr/bin/env bash
# README command (1): builds what the demo runs (ecat-slave and ecatctl, not the tests and benchmarks), starts the
# soft slave on a veth pair it creates itself, drives it from the master side with ecatctl, shows the result, and
# cleans up. Needs root (raw sockets, veth creation).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"
targets=(ecat-slave ecatctl)
if [ "$(id -u)" -ne 0 ]; then echo "demo: needs root (raw sockets and a veth pair); run it with sudo" >&2; exit 2; fi
bash "$root/scripts/install-deps.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" >/dev/null

# How much there is to build, and roughly how long it takes: at most about 5 CPU-seconds a step (a translation unit
# or a link, Release; the whole tree with its tests, cold, is 261 steps and 11 CPU-minutes, 2.6 s a step, but the
# programs' steps are the heavy ones), shared by the cores.
cores=$(nproc)
steps=0
for t in "${targets[@]}"; do
    [ -x "$build/tools/$t/$t" ] || steps=$(ninja -C "$build" -t commands "${targets[@]}" | wc -l)
done
if [ "$steps" -gt 0 ]; then
    minutes=$(((steps * 5 + cores * 60 - 1) / (cores * 60)))
    echo "== building ${targets[*]} (not the tests): $steps steps, roughly $minutes min on $cores core(s);" \
         "a second run builds nothing"
fi
log="$(mktemp /tmp/ecat-demo-build.XXXXXX)"
# Progress on one line (a line per tenth when not on a terminal); the compiler's output only on failure.
set +e
cmake --build "$build" -j"$cores" --target "${targets[@]}" 2>&1 | tee "$log" | awk -v tty="$([ -t 1 ] && echo 1)" '
    match($0, /^\[[0-9]+\/[0-9]+\]/) {
        split(substr($0, 2, RLENGTH - 2), n, "/")
        if (n[2] != total) { total = n[2]; next_pct = 0 }  # ninja counts again after regenerating
        pct = int(100 * n[1] / n[2])
        if (tty) { printf "\r   %d/%d (%d%%)", n[1], n[2], pct; fflush(); shown = 1 }
        else if (pct >= next_pct) { printf "   %d/%d (%d%%)\n", n[1], n[2], pct; fflush(); next_pct = pct + 10 }
    }
    END { if (shown) printf "\n" }'
status=${PIPESTATUS[0]}
set -e
if [ "$status" -ne 0 ]; then
    echo "demo: the build failed; its output:" >&2
    grep -v '^\[[0-9]*/[0-9]*\]' "$log" | tail -n 60 >&2
fi
rm -f "$log"
[ "$status" -eq 0 ] || exit "$status"
exec bash "$root/scripts/demo-run.sh" "$build"
