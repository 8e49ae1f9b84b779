"""Shared harness of the integration tests: the real `ecat-slave` on one end of a veth pair inside a
private network namespace, the real `ecatctl` (or raw frames from scapy) on the other end.

Every Bus gets unique names (pid + counter), so tests may run in parallel, and removes its namespace,
links and processes when it ends, even when the test fails. Paths of the binaries come from the
environment (ECAT_SLAVE, ECATCTL), set by tests/integration/CMakeLists.txt.
"""
import itertools
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import unittest

SKIP = 77  # SKIP_RETURN_CODE in CMake
ETH_P_ECAT = 0x88A4
_counter = itertools.count()


def env_path(name):
    p = os.environ.get(name)
    if not p or not os.path.exists(p):
        raise unittest.SkipTest(f"{name} not set or missing ({p!r})")
    return p


def sii_crc(data14):
    crc = 0xFF
    for b in data14:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


def build_sii(vendor=0x000000FB, product=0x30010000, revision=0x01200000, serial=0x00001234,
              name="Soft slave", size=2048, mailbox=(0x1000, 128, 0x1080, 128), alias=0):
    """An SII image (ETG.2010 SII layout): header with CRC, STRINGS, GENERAL, SyncM, end; padded
    with 0xFF to `size` bytes as an erased EEPROM."""
    w = [0] * 0x40
    w[0] = 0x0C05  # PDI SPI, DC sync/latch units on
    w[2] = 1000
    w[4] = alias
    w[8], w[9] = vendor & 0xFFFF, vendor >> 16
    w[10], w[11] = product & 0xFFFF, product >> 16
    w[12], w[13] = revision & 0xFFFF, revision >> 16
    w[14], w[15] = serial & 0xFFFF, serial >> 16
    w[0x18], w[0x19], w[0x1A], w[0x1B] = mailbox
    w[0x1C] = 0x0004  # CoE
    w[0x3E] = size * 8 // 1024 - 1
    w[0x3F] = 1
    hdr = struct.pack("<7H", *w[:7])
    w[7] = sii_crc(hdr)
    body = b"".join(struct.pack("<H", x) for x in w)

    def category(kind, data):
        if len(data) % 2:
            data += b"\x00"
        return struct.pack("<HH", kind, len(data) // 2) + data

    strings = [b"Drives", name.encode()]
    sdata = bytes([len(strings)]) + b"".join(bytes([len(s)]) + s for s in strings)
    general = bytearray(32)
    general[0] = 1  # group "Drives"
    general[3] = 2  # name
    general[5] = 0x01  # CoE SDO
    general[16] = 0x01  # port 0 MII
    syncm = struct.pack("<HHBBBB", mailbox[0], mailbox[1], 0x26, 0, 1, 1)
    syncm += struct.pack("<HHBBBB", mailbox[2], mailbox[3], 0x22, 0, 1, 2)
    body += category(10, sdata) + category(30, bytes(general)) + category(41, syncm)
    body += struct.pack("<H", 0xFFFF)
    end = len(body)  # bytes up to and including the end word
    body += b"\xff" * (size - len(body))
    return body, end


class Bus:
    """ecat-slave in a namespace on one veth end; the other end (`iface`) in this namespace."""

    def __init__(self, eeprom=None, slave_args=(), out_dir=None):
        self.slave_bin = env_path("ECAT_SLAVE")
        self.ecatctl_bin = env_path("ECATCTL")
        uid = f"{os.getpid() % 100000}x{next(_counter)}"
        self.ns = f"ecit{uid}"
        self.iface = f"em{uid}"        # master end, here
        self.slave_iface = f"es{uid}"  # slave end, in the namespace
        self.dir = tempfile.mkdtemp(prefix=f"ecat-it-{uid}-", dir=out_dir or os.environ.get("ECAT_TEST_OUT"))
        self.capture = os.path.join(self.dir, "capture.pcap")
        self.eeprom_path = None
        if eeprom is not None:
            self.eeprom_path = os.path.join(self.dir, "eeprom.bin")
            with open(self.eeprom_path, "wb") as f:
                f.write(eeprom)
        self.slave_args = list(slave_args)
        self.proc = None
        self.slave_log = os.path.join(self.dir, "slave.log")
        self._log = None

    # -- set-up and tear-down ------------------------------------------------------------------
    def __enter__(self):
        try:
            self._start()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def _run(self, *cmd, check=True):
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
        if check and r.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed: {r.stderr.strip()}")
        return r

    def _start(self):
        self._run("ip", "netns", "add", self.ns)
        self._run("ip", "link", "add", self.iface, "type", "veth", "peer", "name", self.slave_iface)
        self._run("ip", "link", "set", self.slave_iface, "netns", self.ns)
        for cmd in (("sysctl", "-qw", f"net.ipv6.conf.{self.iface}.disable_ipv6=1"),):
            self._run(*cmd, check=False)
        self._run("ip", "netns", "exec", self.ns, "sysctl", "-qw",
                  f"net.ipv6.conf.{self.slave_iface}.disable_ipv6=1", check=False)
        self._run("ip", "link", "set", self.iface, "up")
        self._run("ip", "netns", "exec", self.ns, "ip", "link", "set", self.slave_iface, "up")
        cmd = ["ip", "netns", "exec", self.ns, self.slave_bin, "--iface", self.slave_iface,
               "--capture", self.capture]
        if self.eeprom_path:
            cmd += ["--eeprom", self.eeprom_path]
        cmd += self.slave_args
        if not any(a == "--state-dir" or a.startswith("--state-dir=") for a in self.slave_args):
            # Stored parameters and firmware images of this bus only (not the system's /var/lib/softecat).
            cmd += ["--state-dir", os.path.join(self.dir, "state")]
        self._log = open(self.slave_log, "w")
        self.proc = subprocess.Popen(cmd, stdout=self._log, stderr=subprocess.STDOUT, start_new_session=True)
        # Ready when it answers a register read.
        deadline = time.monotonic() + 10
        while True:
            if self.proc.poll() is not None:
                raise RuntimeError(f"ecat-slave exited with {self.proc.returncode}: {self.slave_output()}")
            r = self.ecatctl("--timeout", "20", "--retries", "0", "reg", "read", "0", "0", "1", check=False)
            if r.returncode == 0:
                return
            if time.monotonic() > deadline:
                raise RuntimeError(f"ecat-slave did not answer: {r.stderr} / {self.slave_output()}")
            time.sleep(0.05)

    def slave_supports(self, option):
        r = subprocess.run([self.slave_bin, "--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           timeout=30)
        return option in r.stdout

    def stop_slave(self):
        """Stops ecat-slave with SIGTERM (so it flushes its capture); returns its exit code."""
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(timeout=5)
        rc = self.proc.returncode
        if self._log:
            self._log.close()
            self._log = None
        return rc

    def close(self):
        try:
            self.stop_slave()
        finally:
            self._run("ip", "netns", "del", self.ns, check=False)  # takes the slave end (and its peer) along
            if os.path.exists(f"/sys/class/net/{self.iface}"):
                self._run("ip", "link", "del", self.iface, check=False)
            if not os.environ.get("ECAT_TEST_KEEP"):
                self.cleanup_files()  # capture, logs, state; ECAT_TEST_KEEP=1 keeps them for a post-mortem

    def cleanup_files(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def slave_alive(self):
        return self.proc is not None and self.proc.poll() is None

    def slave_output(self):
        try:
            with open(self.slave_log) as f:
                return f.read()
        except OSError:
            return ""

    # -- the master side -----------------------------------------------------------------------
    def ecatctl(self, *args, check=True, binary=False):
        cmd = [self.ecatctl_bin, "--iface", self.iface, *args]
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=60, text=not binary)
        if check and r.returncode != 0:
            raise AssertionError(f"{' '.join(cmd)} -> {r.returncode}\nstdout: {r.stdout}\nstderr: {r.stderr}\n"
                                 f"slave: {self.slave_output()}")
        return r

    def raw_socket(self):
        s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ECAT))
        s.bind((self.iface, 0))
        return s


PACKET_OUTGOING = 4


def exchange(sock, frame, timeout=0.5):
    """Sends a frame and returns the first EtherCAT frame that comes back in (not our own), or None."""
    sock.send(frame)
    deadline = time.monotonic() + timeout
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return None
        sock.settimeout(left)
        try:
            data, addr = sock.recvfrom(2048)
        except socket.timeout:
            return None
        if addr[2] == PACKET_OUTGOING:
            continue
        return data


def ecat_frame(datagrams, src=b"\x01\x01\x01\x01\x01\x01", pad=True):
    """datagrams: list of (cmd, idx, adp, ado, data). Returns Ethernet bytes (via scapy when present)."""
    body = b""
    for i, (cmd, idx, adp, ado, data) in enumerate(datagrams):
        more = 0x8000 if i + 1 < len(datagrams) else 0
        body += struct.pack("<BBHHHH", cmd, idx, adp, ado, len(data) | more, 0) + data + b"\x00\x00"
    payload = struct.pack("<H", len(body) | 0x1000) + body
    return ether(payload, src=src, pad=pad)


def ether(payload, src=b"\x01\x01\x01\x01\x01\x01", pad=True):
    from scapy.layers.l2 import Ether  # Debian's python3-scapy
    from scapy.packet import Raw
    srcs = ":".join(f"{b:02x}" for b in src)
    frame = bytes(Ether(dst="ff:ff:ff:ff:ff:ff", src=srcs, type=ETH_P_ECAT) / Raw(load=payload))
    if pad and len(frame) < 60:
        frame += b"\x00" * (60 - len(frame))
    return frame


def parse_datagrams(frame):
    """[(cmd, idx, adp, ado, data, wkc)] of a well-formed reply."""
    hdr = struct.unpack_from("<H", frame, 14)[0]
    end = 16 + (hdr & 0x7FF)
    pos, out = 16, []
    while pos + 12 <= end:
        cmd, idx, adp, ado, lf, _irq = struct.unpack_from("<BBHHHH", frame, pos)
        n = lf & 0x7FF
        data = frame[pos + 10:pos + 10 + n]
        wkc = struct.unpack_from("<H", frame, pos + 10 + n)[0]
        out.append((cmd, idx, adp, ado, data, wkc))
        pos += 12 + n
        if not lf & 0x8000:
            break
    return out


def tshark_problems(capture):
    """Lines of `tshark -V` that report malformed packets or expert errors; None if tshark is missing."""
    tshark = shutil.which("tshark")
    if not tshark:
        return None
    r = subprocess.run([tshark, "-r", capture, "-V"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                       timeout=300)
    if r.returncode != 0:
        return [f"tshark failed: {r.stderr.strip()}"]
    return [line for line in r.stdout.splitlines() if "Malformed" in line or "Expert Info (Error" in line]


def main():
    """Entry point of every test script: skip (exit 77) unless root with network namespaces."""
    if os.geteuid() != 0:
        print("SKIP: integration tests need root (network namespaces, veth, raw sockets)")
        sys.exit(SKIP)
    if shutil.which("ip") is None:
        print("SKIP: iproute2 'ip' not found")
        sys.exit(SKIP)
    probe = f"ecitprobe{os.getpid() % 100000}"
    r = subprocess.run(["ip", "netns", "add", probe], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    if r.returncode != 0:
        print(f"SKIP: cannot create a network namespace: {r.stderr.decode().strip()}")
        sys.exit(SKIP)
    subprocess.run(["ip", "netns", "del", probe])
    for name in ("ECAT_SLAVE", "ECATCTL"):
        if not os.path.exists(os.environ.get(name, "")):
            print(f"SKIP: {name} not set")
            sys.exit(SKIP)
    prog = unittest.main(exit=False, verbosity=2)
    res = prog.result
    if not res.wasSuccessful():
        sys.exit(1)
    if res.testsRun > 0 and len(res.skipped) == res.testsRun:
        sys.exit(SKIP)
    sys.exit(0)
