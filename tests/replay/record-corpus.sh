#!/bin/sh
# Records the replay corpus (tests/replay/README.md): every master this host can run, against one drive and
# against a line of three. Run as root from the repository root after building ecat-slave, ecatctl and
# ecat-conform in build/; the foreign masters are looked for under EXT (default /work/ext), built as
# README.md's section on foreign masters says, outside this repository. A master that is not there is skipped.
# Each recording replaces the one of the same name; review `git diff --stat tests/replay/corpus` after.
#   sudo tests/replay/record-corpus.sh [NAME-GLOB]      e.g. 'soem-*'
set -eu
EXT=${EXT:-/work/ext}
B=${BUILD:-build}
export ECAT_SLAVE=${ECAT_SLAVE:-$B/tools/ecat-slave/ecat-slave} ECATCTL=${ECATCTL:-$B/tools/ecatctl/ecatctl}
ONLY=${1:-*}
REC="python3 tests/replay/record.py"
# Recording on a loaded host: the slave at real-time priority (not replayed; timing only).
RT=${RT:---rt-priority 40}

want() { case "$1" in $ONLY) return 0 ;; *) return 1 ;; esac; }
rev() { git -C "$1" rev-parse --short HEAD 2>/dev/null || echo unknown; }

# A firmware image for the FoE updates (8 KiB payload of 'S', version 1.32), under the name the drive takes.
FW=$(mktemp -d); trap 'rm -rf "$FW"' EXIT
head -c 8192 /dev/zero | tr '\0' 'S' >"$FW/payload.bin"
IMG=MAXPOS_0132h_3001h_0000h_0000h.bin
"$B/tools/fwimage/fwimage" build --payload "$FW/payload.bin" --version 0x01320000 -o "$FW/$IMG" >/dev/null

S=$EXT/soem/build/samples
if [ -x "$S/slaveinfo/slaveinfo" ]; then
  V="SOEM $(rev "$EXT/soem")"
  for n in 1 3; do
    sfx=$([ $n = 3 ] && echo -line3 || true)
    want "soem-slaveinfo$sfx" && $REC "soem-slaveinfo$sfx" --slaves $n $RT --master-version "$V" \
      --description "SOEM slaveinfo -map" -- "$S/slaveinfo/slaveinfo" {iface} -map
    want "soem-simple_ng$sfx" && $REC "soem-simple_ng$sfx" --slaves $n $RT --seconds 2.2 --master-version "$V" \
      --description "SOEM simple_ng: to OP, process data" -- "$S/simple_ng/simple_ng" {iface}
  done
  want soem-ec_sample && $REC soem-ec_sample $RT --seconds 2.2 --master-version "$V" \
    --description "SOEM ec_sample: to OP with DC, process data" -- "$S/ec_sample/ec_sample" {iface} 1000
  # firm_update sends its file argument as the FoE file name: run it in the image's directory.
  want soem-firm_update && $REC soem-firm_update $RT --master-version "$V" \
    --description "SOEM firm_update: PREOP -> INIT -> BOOT, FoE write of a firmware image, INIT" -- \
    sh -c "cd $FW && exec $S/firm_update/firm_update {iface} 1 $IMG"
fi

L=$EXT/libethercat/build
if [ -x "$L/ethercatdiag" ]; then
  V="libethercat $(rev "$EXT/libethercat") (+ the README's two CMake fixes), libosal $(rev "$EXT/libosal")"
  want libethercat-ethercatdiag && $REC libethercat-ethercatdiag $RT --master-version "$V" \
    --description "libethercat ethercatdiag -v: scan" -- "$L/ethercatdiag" -i sock-raw:{iface} -v
  want libethercat-eepromtool && $REC libethercat-eepromtool $RT --master-version "$V" \
    --description "libethercat eepromtool: SII read over EtherCAT" -- \
    "$L/eepromtool" -i sock-raw:{iface} -s 0 -r -f /dev/null
  for n in 1 3; do
    sfx=$([ $n = 3 ] && echo -line3 || true)
    want "libethercat-example_with_dc$sfx" && $REC "libethercat-example_with_dc$sfx" --slaves $n $RT \
      --seconds 2.8 --master-version "$V" --description "libethercat example_with_dc: to OP with DC (SYNC0 1 ms)" \
      -- "$L/example_with_dc" -i sock-raw:{iface} -a 0x1 -p 0
  done
  want libethercat-foe_tool && $REC libethercat-foe_tool $RT --master-version "$V" \
    --description "libethercat foe_tool: INIT -> BOOT, FoE write of a firmware image, INIT" -- \
    "$L/foe_tool" -i sock-raw:{iface} -w -s 0 "$FW/$IMG" MAXPOS
fi

K=$EXT/kickcat/build/tools/scan_topology
if [ -x "$K" ]; then
  # KickCAT's tools give up on a reply after 500 us: record on a quiet host, without the capture's extra load
  # from other work, and again if it timed out (the sidecar keeps the master's exit status).
  V="KickCAT source snapshot in $EXT/kickcat (argparse.hpp added outside this repository)"
  want kickcat-scan_topology-line3 && $REC kickcat-scan_topology-line3 --slaves 3 --master-version "$V" \
    --description "KickCAT scan_topology: scan and topology of a line" -- "$K" -i {iface}
fi

# The project's own master and conformance tool, through the pcap backend: the packet backend sends past the
# kernel's packet taps (PACKET_QDISC_BYPASS), so a capture on the master end would not see its frames.
V="softecat $(git rev-parse --short HEAD)"
C="$ECATCTL -b pcap -i {iface}"
want ecatctl-scan-upload-pd && $REC ecatctl-scan-upload-pd $RT --master-version "$V" \
  --description "ecatctl scan, upload 0x1018:01, pdos, pd with DC for 1000 cycles" -- \
  sh -c "$C scan && $C upload 0 0x1018 1 && $C pdos 0 && $C pd 0 -n 1000 --dc"
want ecatctl-pd-all-line3 && $REC ecatctl-pd-all-line3 --slaves 3 $RT --master-version "$V" \
  --description "ecatctl scan and pd --all --dc for 1000 cycles" -- sh -c "$C scan && $C pd --all --dc -n 1000"
CONFORM=${ECAT_CONFORM:-$B/tools/ecat-conform/ecat-conform}
for g in esc,sii esm,mbx; do
  n=ecat-conform-$(echo $g | tr , -)
  want "$n" && $REC "$n" $RT --master-version "$V" --malformed-requests --description "ecat-conform --group $g" \
    -- "$CONFORM" --backend pcap -i {iface} --group $g
done

V="tests/replay/igh_master.py, from the IgH master (github.com/ribalda/ethercat 97e7ee64)"
for n in 1 3; do
  sfx=$([ $n = 3 ] && echo -line3 || true)
  want "igh-sequence$sfx" && $REC "igh-sequence$sfx" --slaves $n $RT --master-version "$V" \
    --description "IgH master's scan, configuration (CoE PDO mapping, DC) and OP" -- \
    python3 tests/replay/igh_master.py {iface}
done
true
