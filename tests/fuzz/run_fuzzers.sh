#!/usr/bin/env bash
# Runs the libFuzzer targets of a -DSOFTECAT_FUZZ=ON build on their seed corpora (docs/robustness.md).
#   tests/fuzz/run_fuzzers.sh BUILD_DIR SECONDS [HARNESS...]
# Each harness runs SECONDS on a scratch copy of tests/fuzz/corpus/<harness> (the corpus in the tree is
# not grown) with ASan + UBSan halting on the first error. Prints per harness the executions, executions
# per second, corpus size and the result; crashing inputs go to BUILD_DIR/fuzz-artifacts/<harness>/.
# Exit status 1 if any harness found something (or could not run), or was interrupted: a run stopped by
# SIGINT (libFuzzer exit 72, "run interrupted" in its log, no input written) is reported as "interrupted", not
# as a finding, and still fails, so that a cut run never passes for a whole one. FUZZ_JOBS harnesses run at
# once (default: the number of CPUs); the table is printed in the order given when all are done.
set -uo pipefail
build=${1:?build dir}; seconds=${2:?seconds per harness}; shift 2
here=$(cd "$(dirname "$0")" && pwd)
harnesses=("$@")
if ((${#harnesses[@]} == 0)); then
    harnesses=(esc_frame slave coe_mailbox foe_server sii device_config loaders master_reply control topology esi_reader eni_reader
               esi_line)
fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
parallel=${FUZZ_JOBS:-$(nproc)}  # harnesses at once: each libFuzzer run is one process on one core
mkdir -p "$build/fuzz-artifacts"
# One harness: its run, then one result line (and the first lines of a finding) in BUILD_DIR/fuzz-artifacts/H.result.
run_one() {
    local h=$1 bin="$build/tests/fuzz/${1}_fuzzer" out="$build/fuzz-artifacts/$1.result"
    if [ ! -x "$bin" ]; then echo "$h: $bin missing" >"$out"; return 1; fi
    local work art log rc execs rate units result
    work=$(mktemp -d "${TMPDIR:-/tmp}/softecat-fuzz-$h-XXXXXX")
    art="$build/fuzz-artifacts/$h"; mkdir -p "$art"
    log="$build/fuzz-artifacts/$h.log"
    "$bin" "$work" "$here/corpus/$h" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
        -max_len=16384 -print_final_stats=1 -artifact_prefix="$art/" ${FUZZ_EXTRA_ARGS:-} >"$log" 2>&1
    rc=$?
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    units=$(find "$work" -type f | wc -l)
    local finding=1
    if [ "$rc" -eq 0 ]; then
        result=ok; finding=0
    elif [ "$rc" -eq 72 ] && grep -q "run interrupted" "$log" && ! grep -q "Test unit written" "$log"; then
        # Stopped from outside (SIGINT): nothing found in the part that ran, but the run is not whole.
        result="interrupted (exit 72, see $log)"; finding=0
    else
        result="FINDING (exit $rc, see $log)"
    fi
    {
        printf '%-14s %14s %10s %8s  %s\n' "$h" "${execs:-?}" "${rate:-?}" "$units" "$result"
        if [ "$finding" -ne 0 ]; then grep -E "ERROR|runtime error|fuzz check|Test unit written" "$log" | head -5; fi
    } >"$out"
    rm -rf "$work"
    return "$rc"
}
printf '%-14s %14s %10s %8s  %s\n' harness executions exec/s units result
pids=()
for h in "${harnesses[@]}"; do
    while (($(jobs -rp | wc -l) >= parallel)); do wait -n || true; done
    run_one "$h" &
    pids+=($!)
done
failed=0
for i in "${!harnesses[@]}"; do
    wait "${pids[$i]}" || failed=1
    cat "$build/fuzz-artifacts/${harnesses[$i]}.result"
done
exit "$failed"
