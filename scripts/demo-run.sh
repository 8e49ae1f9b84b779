#!/usr/bin/env bash
# Runs the demo on an already built tree: ecat-slave on a veth pair it creates, then ecatctl against it.
set -euo pipefail
build="${1:?usage: demo-run.sh BUILD_DIR}"
slave="$build/tools/ecat-slave/ecat-slave"
ctl="$build/tools/ecatctl/ecatctl"
if [ "$(id -u)" -ne 0 ]; then echo "demo: needs root (raw sockets and a veth pair); run it with sudo" >&2; exit 2; fi
log=$(mktemp /tmp/ecat-slave.XXXXXX.log)
"$slave" --capture /tmp/ecat-demo.pcap >"$log" 2>&1 &
pid=$!
cleanup() { kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; }
trap cleanup EXIT
for _ in $(seq 50); do ip link show ecat1 >/dev/null 2>&1 && break; sleep 0.1; done
sleep 0.3
echo "== ecat-slave is running (pid $pid) on ecat0; the master side is ecat1"
run() { echo; echo "\$ ecatctl $*"; "$ctl" --iface ecat1 "$@"; }
run scan
run states
run state op
run sdo upload 1 0x1018 1 --type u32 || true
run sdo upload 1 0x1008 0 --type string || true
run sii decode || true
cleanup; trap - EXIT
echo; echo "== slave log"; cat "$log"; rm -f "$log"
echo "== frames captured in /tmp/ecat-demo.pcap (open it in Wireshark)"
