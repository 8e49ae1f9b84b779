#!/usr/bin/env bash
# Creates or removes a veth pair for running ecat-slave by hand against a master on the same machine.
#   scripts/veth.sh up [SLAVE_END [MASTER_END]]    (default ecat0 ecat1)
#   scripts/veth.sh down [SLAVE_END]
# ecat-slave without --iface does the same by itself (and removes the pair at exit); this script is for
# setups where the pair must outlive the slave (e.g. a master that keeps its interface open).
set -euo pipefail
cmd=${1:-}
a=${2:-ecat0}
b=${3:-ecat1}
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
case "$cmd" in
up)
    $SUDO ip link del "$a" 2>/dev/null || true
    $SUDO ip link add "$a" type veth peer name "$b"
    for i in "$a" "$b"; do
        if [ -e "/proc/sys/net/ipv6/conf/$i/disable_ipv6" ]; then
            echo 1 | $SUDO tee "/proc/sys/net/ipv6/conf/$i/disable_ipv6" >/dev/null
        fi
        $SUDO ip link set "$i" up
    done
    echo "slave end: $a   master end: $b"
    ;;
down)
    $SUDO ip link del "$a" 2>/dev/null || true
    ;;
*)
    echo "usage: $0 up [SLAVE_END [MASTER_END]] | down [SLAVE_END]" >&2
    exit 2
    ;;
esac
