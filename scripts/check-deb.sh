#!/usr/bin/env bash
# Checks a softecat .deb (cpack -G DEB): its contents (programs, man pages, completion, systemd unit, schema,
# examples) and dependencies; then installs it with apt, runs the installed programs (ecat-ci with ecatctl
# against a soft slave), and removes it, checking that nothing of it is left. Needs root. Used by .ci/run.
set -euo pipefail
deb="$(realpath "${1:?usage: check-deb.sh softecat_VERSION_ARCH.deb}")"
programs=(ecat-slave ecatctl ecat-conform fwimage drive-sim ecat-ci)
fail() { echo "check-deb: $*" >&2; exit 1; }
if dpkg-query -W -f='${Status}' softecat 2>/dev/null | grep -q "install ok installed"; then
    fail "softecat is installed already; remove it first (apt remove softecat)"
fi
contents="$(dpkg-deb -c "$deb" | awk '{print $6}' | sed 's#^\./#/#')"
for p in "${programs[@]}"; do
    for f in "/usr/bin/$p" "/usr/share/man/man1/$p.1.gz" "/usr/share/bash-completion/completions/$p"; do
        grep -qx "$f" <<<"$contents" || fail "$f is not in the package"
    done
done
for f in /usr/lib/systemd/system/ecat-slave@.service /usr/share/softecat/schema/EtherCATInfo.xsd \
         /usr/share/doc/softecat/examples/device.conf; do
    grep -qx "$f" <<<"$contents" || fail "$f is not in the package"
done
depends="$(dpkg-deb -f "$deb" Depends)"
echo "Depends: $depends"
for d in libc6 libpcap0.8 libxml2 zlib1g iproute2 util-linux; do
    grep -q "\\b$d\\b" <<<"$depends" || fail "the package does not depend on $d"
done

export DEBIAN_FRONTEND=noninteractive
apt-get install -y -qq --no-install-recommends "$deb" >/dev/null  # recommends (bash-completion) would change the machine
trap 'apt-get remove -y -qq softecat >/dev/null 2>&1 || true' EXIT
for p in "${programs[@]}"; do
    [ "$(command -v "$p")" = "/usr/bin/$p" ] || fail "$p is not on PATH after apt install"
    "$p" --version >/dev/null || fail "$p --version failed"
    if command -v man >/dev/null; then man -w "$p" >/dev/null 2>&1 || fail "no man page for $p"; fi
done
(cd / && env -u ECAT_SLAVE -u ECATCTL ecat-ci --slaves 2 -- ecatctl --iface '{iface}' scan) | grep -q "2 slaves" \
    || fail "the installed ecat-ci and ecatctl do not see two soft slaves"
apt-get remove -y -qq softecat >/dev/null
trap - EXIT
for p in "${programs[@]}"; do
    [ ! -e "/usr/bin/$p" ] || fail "/usr/bin/$p is left after apt remove"
done
[ ! -e /usr/lib/systemd/system/ecat-slave@.service ] || fail "the systemd unit is left after apt remove"
! dpkg-query -W -f='${Status}' softecat 2>/dev/null | grep -q "install ok installed" || fail "still installed"
echo "check-deb: $(basename "$deb"): contents, dependencies, install, use and removal ok"
