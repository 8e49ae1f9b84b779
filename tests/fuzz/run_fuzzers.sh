#!/usr/bin/env bash
# Runs the libFuzzer targets of a -DSOFTECAT_FUZZ=ON build on their seed corpora (docs/robustness.md).
#   tests/fuzz/run_fuzzers.sh BUILD_DIR SECONDS [HARNESS...]
# Each harness runs SECONDS on a scratch copy of tests/fuzz/corpus/<harness> (the corpus in the tree is
# not grown) with ASan + UBSan halting on the first error. Prints per harness the executions, executions
# per second, corpus size and the result; crashing inputs go to BUILD_DIR/fuzz-artifacts/<harness>/.
# Exit status 1 if any harness found something (or could not run).
set -uo pipefail
build=${1:?build dir}; seconds=${2:?seconds per harness}; shift 2
here=$(cd "$(dirname "$0")" && pwd)
harnesses=("$@")
if ((${#harnesses[@]} == 0)); then
    harnesses=(esc_frame slave coe_mailbox foe_server sii device_config loaders master_reply control topology esi_reader eni_reader)
fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
failed=0
printf '%-14s %14s %10s %8s  %s\n' harness executions exec/s units result
for h in "${harnesses[@]}"; do
    bin="$build/tests/fuzz/${h}_fuzzer"
    if [ ! -x "$bin" ]; then echo "$h: $bin missing"; failed=1; continue; fi
    work=$(mktemp -d "${TMPDIR:-/tmp}/softecat-fuzz-$h-XXXXXX")
    art="$build/fuzz-artifacts/$h"; mkdir -p "$art"
    log="$build/fuzz-artifacts/$h.log"
    "$bin" "$work" "$here/corpus/$h" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
        -max_len=16384 -print_final_stats=1 -artifact_prefix="$art/" ${FUZZ_EXTRA_ARGS:-} >"$log" 2>&1
    rc=$?
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    units=$(find "$work" -type f | wc -l)
    if [ "$rc" -eq 0 ]; then result=ok; else result="FINDING (exit $rc, see $log)"; failed=1; fi
    printf '%-14s %14s %10s %8s  %s\n' "$h" "${execs:-?}" "${rate:-?}" "$units" "$result"
    if [ "$rc" -ne 0 ]; then grep -E "ERROR|runtime error|fuzz check|Test unit written" "$log" | head -5; fi
    rm -rf "$work"
done
exit "$failed"
