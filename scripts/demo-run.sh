#!/usr/bin/env bash
# Runs the demo on an already built tree: ecat-slave (the soft MAXPOS drive) on a veth pair it creates, then
# ecatctl against it: scan, identity over SDO, the SII, OP with process data (SM-synchronous and DC), and the
# drive moving under process data. Cleans up everything it created, also when interrupted.
set -euo pipefail
build="${1:?usage: demo-run.sh BUILD_DIR}"
slave="$build/tools/ecat-slave/ecat-slave"
ctl="$build/tools/ecatctl/ecatctl"
if [ "$(id -u)" -ne 0 ]; then echo "demo: needs root (raw sockets and a veth pair); run it with sudo" >&2; exit 2; fi
for b in "$slave" "$ctl"; do [ -x "$b" ] || { echo "demo: $b is not built" >&2; exit 2; }; done

work=$(mktemp -d /tmp/ecat-demo.XXXXXX)
log="$work/slave.log"
pid=""
cleanup() {
  if [ -n "$pid" ]; then kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; pid=""; fi
  ip link del ecat1 2>/dev/null || true  # normally removed by ecat-slave itself on SIGTERM
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# The slave keeps its stored parameters and firmware images in a state directory (default /var/lib/softecat);
# the demo uses a throw-away one.
capture="${ECAT_DEMO_CAPTURE:-/tmp/ecat-demo.pcap}"
"$slave" --state-dir "$work/state" --control "$work/control.sock" --capture "$capture" >"$log" 2>&1 &
pid=$!
for _ in $(seq 50); do ip link show ecat1 >/dev/null 2>&1 && break; sleep 0.1; done
sleep 0.3
if ! kill -0 "$pid" 2>/dev/null; then echo "demo: ecat-slave did not start:" >&2; cat "$log" >&2; exit 1; fi
echo "== ecat-slave is running (pid $pid) on ecat0; the master side is ecat1"
run() { echo; echo "\$ ecatctl $*"; "$ctl" --iface ecat1 "$@"; }

run scan
echo; echo "== identity and device name over CoE SDO (the slave goes INIT -> PREOP for its mailbox)"
run upload 0 0x1018 1
run upload 0 0x1018 2
run upload 0 0x1018 3
run upload 0 0x1008 0 --type string
run upload 0 0x100A 0 --type string
echo; echo "== the SII EEPROM, generated from the same object model (first lines)"
echo "\$ ecatctl sii decode | head -n 24"
"$ctl" --iface ecat1 sii decode | head -n 24 || true
run state 0

echo; echo "== cyclic process data with the default PDO mapping: PREOP -> SAFEOP -> OP"
run pd 0 -n 500 --cycle-us 1000
run pd 0 -n 500 --cycle-us 1000 --dc

if "$ctl" pd --help 2>/dev/null | grep -q -- "--step"; then
  echo; echo "== the drive moves: profile position mode over process data"
  echo "   outputs: controlword, target position, ..., modes of operation (byte 16) = 1 (profile position)"
  run download 0 0x6081 0 3000 --type u32   # profile velocity, rpm
  run upload 0 0x6064 0 --type i32          # actual position before
  # 40000 inc = 0x00009C40; fault reset, shutdown (6), switch on (7), enable (15), then new set-point (0x1F).
  t="40,9c,00,00"
  z="00,00,00,00,00,00,00,00,00,00"
  run pd 0 --cycle-us 1000 --step "20:80,00,$t,$z,01" --step "20:06,00,$t,$z,01" --step "20:07,00,$t,$z,01" \
      --step "20:0f,00,$t,$z,01" -n 1500 --outputs 0x1f 0 0x40 0x9c 0 0 0 0 0 0 0 0 0 0 0 0 1
  run upload 0 0x6064 0 --type i32          # actual position after: the target
  echo; echo "   leaving OP while enabled: the 0x6007 reaction (quick stop, then Fault 0x8180) as on a real drive"
  run upload 0 0x603F 0
fi

if [ -S "$work/control.sock" ]; then
  echo; echo "== the simulated machine, through the control socket (--control): 'status'"
  echo "\$ ecat-slave --control $work/control.sock --send status"
  "$slave" --control "$work/control.sock" --send status || true
fi

kill "$pid" 2>/dev/null || true
wait "$pid" 2>/dev/null || true
pid=""
echo; echo "== slave log"; cat "$log"
echo "== frames captured in $capture (open it in Wireshark)"
