"""Shared harness of the integration tests: the real `ecat-slave` on one end of a veth pair inside a
private network namespace, the real `ecatctl` (or raw frames from scapy) on the other end.

Every Bus gets unique names (pid + counter), so tests may run in parallel, and removes its namespace,
links and processes when it ends, even when the test fails. Paths of the binaries come from the
environment (ECAT_SLAVE, ECATCTL), set by tests/integration/CMakeLists.txt.
"""
import itertools
import re
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
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


def socket_dir():
    """A short private folder for UNIX sockets (a control socket and its clients): the kernel limits their paths
    to 107 bytes (sockaddr_un), so they never go under ECAT_TEST_OUT, which is as long as the path of the clone
    the tests run in. The caller removes it (shutil.rmtree)."""
    return tempfile.mkdtemp(prefix="ecat-sock-", dir="/tmp")


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
        self.sock_dir = socket_dir()  # for control sockets: self.dir may be too long for one
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
        self.wait_answering(self.proc)

    def wait_answering(self, *procs):
        """Waits (10 s at most) until the bus answers a register read; raises if one of procs exits."""
        deadline = time.monotonic() + 10
        while True:
            for p in procs:
                if p.poll() is not None:
                    raise RuntimeError(f"ecat-slave exited with {p.returncode}: {self.slave_output()}")
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
        shutil.rmtree(self.sock_dir, ignore_errors=True)

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


def bus_in_preop(test, *slave_args):
    """A Bus for the unittest.TestCase `test` (closed at its cleanup), its slave taken to PREOP; the test is
    skipped when the slave runs without firmware."""
    bus = Bus(slave_args=slave_args).__enter__()
    test.addCleanup(bus.close)
    r = bus.ecatctl("--timeout", "50", "state", "0", "PREOP", check=False)
    if r.returncode != 0 and "not reached in time" in r.stderr:
        test.skipTest("ecat-slave runs without firmware (AL status never follows AL control)")
    return bus


def datagram_keys(frame):
    """(command, index, address offset, length) of each datagram of an EtherCAT frame, as far as it parses (a
    malformed frame gives the datagrams before the point where it breaks off). A slave changes the address
    position of auto-increment commands, the data and the working counter, never these: they identify the
    request a reply answers."""
    keys = []
    if len(frame) < 16 or frame[12:14] != b"\x88\xa4":
        return keys
    end = min(len(frame), 16 + (struct.unpack_from("<H", frame, 14)[0] & 0x7FF))
    pos = 16
    while pos + 10 <= end:
        cmd, idx, _adp, ado, lf = struct.unpack_from("<BBHHH", frame, pos)
        keys.append((cmd, idx, ado, lf & 0x7FF))
        pos += 12 + (lf & 0x7FF)
        if not lf & 0x8000:
            break
    return keys


def is_reply_to(request, reply):
    """True if reply is the request come back through the slaves: an EtherCAT frame whose source address has
    bit 1 of its first byte set by an ESC (when the request's had not) and whose datagrams carry the request's
    commands, indices, offsets and lengths (ETG.1000.4: the master matches a reply to its request by the
    index). A reply to an earlier request, or to another master's frame, is not."""
    if len(reply) < 16 or reply[12:14] != b"\x88\xa4":
        return False
    if not request[6] & 0x02 and not reply[6] & 0x02:
        return False
    return datagram_keys(reply) == datagram_keys(request)


def drain(sock):
    """Drops every frame queued on the socket (late replies, another master's traffic)."""
    sock.setblocking(False)
    try:
        while True:
            sock.recv(4096)
    except (BlockingIOError, socket.timeout):
        pass
    finally:
        sock.setblocking(True)


def during_control_flood(path, data, work):
    """Runs work() while a thread keeps the control socket at path busy with the datagram data (sent from a socket
    without an address: no answers, only work); returns (work's result, datagrams sent)."""
    stop = threading.Event()
    sent = [0]

    def flooder():
        s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        s.settimeout(0.5)
        try:
            while not stop.is_set():
                try:
                    s.sendto(data, path)
                    sent[0] += 1
                except (socket.timeout, BlockingIOError):
                    pass
        finally:
            s.close()

    t = threading.Thread(target=flooder)
    t.start()
    try:
        result = work()
    finally:
        stop.set()
        t.join()
    return result, sent[0]


def exchange(sock, frame, timeout=0.5, match=None):
    """Sends a frame and returns the reply to it (is_reply_to, or match(frame, reply) when given), or None when
    none came within timeout. Frames queued before are dropped and replies to other requests skipped, so a late
    reply to an earlier request is never taken for this one's."""
    match = match or is_reply_to
    drain(sock)
    sock.send(frame)
    deadline = time.monotonic() + timeout
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return None
        sock.settimeout(left)
        try:
            data, addr = sock.recvfrom(4096)
        except socket.timeout:
            return None
        if addr[2] == PACKET_OUTGOING or not match(frame, data):
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


# -- a segment of soft slaves (issue 13) -------------------------------------------------------------------------
# A small cyclic master in python for the tests of a line of drives (tests/integration/test_segment*.py): the
# registers it uses are those of the ESC datasheet section I (SM §8, FMMU §7, DC §9) and ETG.1000.4/.6; the
# process-data layout and the CoE writes come from ecatctl. Station addresses 0x1001.. as `ecatctl scan` assigns.
APRD, APWR, FPRD, FPWR, BRD, BWR, LRW, FRMW = 1, 2, 4, 5, 7, 8, 12, 14
AL_NAMES = {1: "INIT", 2: "PREOP", 3: "BOOT", 4: "SAFEOP", 8: "OP"}
# ecatctl pd's layout line: the SyncManager, start and length of the outputs and of the inputs (SM2/SM3 with a
# mailbox, SM0/SM1 or others without one).
LAYOUT = re.compile(r"outputs: SM(\d+) 0x([0-9a-f]+), (\d+) bytes; inputs: SM(\d+) 0x([0-9a-f]+), (\d+) bytes")
DC_EPOCH_NS = 946684800 * 10**9  # EtherCAT system time counts from 2000-01-01


def control(path, line, timeout=5.0):
    """One command on ecat-slave's control socket (a UNIX datagram socket); returns the reply text."""
    me = f"{path}.{os.getpid()}.{next(_counter)}.me"
    s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    try:
        s.bind(me)
        s.settimeout(timeout)
        s.sendto(line.encode() + b"\n", path)
        return s.recv(65536).decode()
    finally:
        s.close()
        try:
            os.unlink(me)
        except OSError:
            pass


def read_stats(path):
    """key value lines of a --stats-file."""
    out = {}
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) >= 2:
                out[parts[0]] = parts[1]
    return out


class MiniMaster:
    """Process data for every slave of the line in one LRW per cycle (plus FRMW of the reference clock's system
    time with DC, and an FPRD of each slave's AL status), DC set up from the port receive times of a line."""

    def __init__(self, bus, timeout=0.02):
        self.bus = bus
        self.sock = bus.raw_socket()
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        self.timeout = timeout
        self.idx = 0
        self.count = 0
        self.layouts = []
        self.sms = []
        self.dc = False
        self.delays = []
        self.states = []
        self.expected_wkc = 0

    def close(self):
        self.sock.close()

    # -- frames ------------------------------------------------------------------------------------------------
    def txrx(self, datagrams, timeout=None):
        """datagrams: [(cmd, adp, ado, data)]; returns [(data, wkc)] or None when no reply came."""
        self.idx = (self.idx + 1) & 0xFF
        idx = self.idx
        body = b""
        for i, (cmd, adp, ado, data) in enumerate(datagrams):
            more = 0x8000 if i + 1 < len(datagrams) else 0
            body += struct.pack("<BBHHHH", cmd, idx, adp, ado, len(data) | more, 0) + data + b"\x00\x00"
        frame = b"\xff" * 6 + b"\x01" * 6 + b"\x88\xa4" + struct.pack("<H", len(body) | 0x1000) + body
        if len(frame) < 60:
            frame += b"\x00" * (60 - len(frame))
        self.drain()
        self.sock.send(frame)
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self.sock.settimeout(left)
            try:
                data, addr = self.sock.recvfrom(4096)
            except socket.timeout:
                return None
            if addr[2] == PACKET_OUTGOING or not is_reply_to(frame, data):
                continue  # our own frame, a late reply, or a reply to another master's frame (ecatctl)
            return [(d[4], d[5]) for d in parse_datagrams(data)]

    def drain(self):
        """Drops what is queued (replies to ecatctl's frames, late replies)."""
        drain(self.sock)

    def one(self, cmd, adp, ado, data, tries=5):
        for _ in range(tries):
            r = self.txrx([(cmd, adp, ado, data)])
            if r is not None:
                return r[0]
        raise AssertionError(f"no reply to command {cmd} 0x{adp:04x}:0x{ado:04x} ({self.bus.slave_output()[-2000:]})")

    def fprd(self, station, ado, n):
        data, wkc = self.one(FPRD, station, ado, bytes(n))
        if wkc != 1:
            raise AssertionError(f"FPRD 0x{station:04x}:0x{ado:04x} wkc {wkc}")
        return data

    def fpwr(self, station, ado, data):
        _, wkc = self.one(FPWR, station, ado, data)
        if wkc != 1:
            raise AssertionError(f"FPWR 0x{station:04x}:0x{ado:04x} wkc {wkc}")

    def count_slaves(self):
        return self.one(BRD, 0, 0, b"\x00")[1]

    def stations(self):
        return [0x1001 + i for i in range(self.count)]

    # -- set-up ------------------------------------------------------------------------------------------------
    def scan(self):
        """ecatctl scan (station addresses 0x1001..); returns its rows as {pos: line} and sets the count."""
        out = self.bus.ecatctl("scan").stdout
        self.count = int(out.split()[0])
        return out

    def discover(self):
        """The process-data layout of each slave from `ecatctl pd <pos> -n 1 --state SAFEOP` (back to PREOP)."""
        self.layouts = []
        self.sms = []  # (output SM, input SM) of each slave
        for pos in range(self.count):
            # Only the layout line counts here (what the cycles see is run()'s to judge): a device without process
            # data (a coupler) has it printed and SAFEOP refused (nothing to cycle), and in a line of devices
            # without mailbox the one-cycle check may count a neighbour's FMMU left from its own discovery.
            r = self.bus.ecatctl("pd", str(pos), "-n", "1", "--state", "SAFEOP", check=False)
            m = LAYOUT.search(r.stdout)
            if m is None:
                raise AssertionError(r.stdout + r.stderr)
            self.layouts.append((int(m.group(2), 16), int(m.group(3)), int(m.group(5), 16), int(m.group(6))))
            self.sms.append((int(m.group(1)), int(m.group(4))))

    def dc_measure(self):
        """Latches the receive times at every port (BWR 0x0900) and computes the propagation delay of each slave
        of a line from the round trips behind port 1 (ESC datasheet section I §9.1.3); returns
        [(delay_ns, port_times, dl_status, local_time)]."""
        self.one(BWR, 0, 0x0900, bytes(4))
        rows = []
        for st in self.stations():
            times = struct.unpack("<4I", self.fprd(st, 0x0900, 16))
            dl = struct.unpack("<H", self.fprd(st, 0x0110, 2))[0]
            local = struct.unpack("<Q", self.fprd(st, 0x0918, 8))[0]
            rows.append([times, dl, local])
        out = []
        prev_delay, prev_rt = 0, 0
        for k, (times, dl, local) in enumerate(rows):
            rt = (times[1] - times[0]) & 0xFFFFFFFF if dl & (1 << 11) else 0  # port 1 communicating
            delay = 0 if k == 0 else prev_delay + (prev_rt - rt) // 2
            out.append((delay, times, dl, local))
            prev_delay, prev_rt = delay, rt
        return out

    def configure(self, dc=True, cycle_ns=1_000_000):
        """Sync mode over CoE (ecatctl), SM2/SM3 and FMMUs of every slave (logically one after the other), and with
        dc the clock offsets and delays of a line and SYNC0 on the same grid in every slave."""
        self.dc = dc
        mode = "2" if dc else "1"
        for pos in range(self.count):
            # A device without mailbox (an ESI's IO terminal, a coupler) has no 0x1C32 to write: refused, and
            # the cycles in OP show whether the others took it.
            self.bus.ecatctl("download", str(pos), "0x1c32", "1", mode, "--type", "u16", check=False)
            self.bus.ecatctl("download", str(pos), "0x1c33", "1", mode if dc else "34", "--type", "u16",
                             check=False)
            if dc:
                self.bus.ecatctl("download", str(pos), "0x1c32", "2", str(cycle_ns), "--type", "u32")
        logical = 0x10000
        self.expected_wkc = 0
        self.image = 0
        for st, (o_start, o_len, i_start, i_len), (o_sm, i_sm) in zip(self.stations(), self.layouts, self.sms):
            for sm, start, length, control in ((o_sm, o_start, o_len, 0x64), (i_sm, i_start, i_len, 0x20)):
                if not length:
                    continue  # a device with inputs or outputs only may have no such SyncManager
                self.fpwr(st, 0x0800 + 8 * sm, bytes(8))
                self.fpwr(st, 0x0800 + 8 * sm, struct.pack("<HHBBBB", start, length, control, 0, 1 if length else 0, 0))
            fm = struct.pack("<IHBBHBBBxxx", logical, o_len, 0, 7, o_start, 0, 2, 1 if o_len else 0)
            fm += struct.pack("<IHBBHBBBxxx", logical + o_len, i_len, 0, 7, i_start, 0, 1, 1 if i_len else 0)
            self.fpwr(st, 0x0600, fm)
            logical += o_len + i_len
            self.expected_wkc += (2 if o_len else 0) + (1 if i_len else 0)
        self.image = logical - 0x10000
        if not dc:
            for st in self.stations():
                self.fpwr(st, 0x0980, bytes(2))
            return
        self.delays = self.dc_measure()
        now = time.time_ns() - DC_EPOCH_NS
        for st, (delay, _times, _dl, local) in zip(self.stations(), self.delays):
            self.fpwr(st, 0x0920, struct.pack("<Q", (now + delay - local) & 0xFFFFFFFFFFFFFFFF))
            self.fpwr(st, 0x0928, struct.pack("<I", delay & 0xFFFFFFFF))
        for _ in range(200):  # drift compensation: the reference clock's time to all others
            self.txrx([(FRMW, 0x1001, 0x0910, bytes(8))])
        for st in self.stations():
            self.fpwr(st, 0x0980, bytes(2))
            self.fpwr(st, 0x09A0, struct.pack("<I", cycle_ns))
        t = struct.unpack("<Q", self.fprd(0x1001, 0x0910, 8))[0]
        start = ((t + 100_000_000) // cycle_ns + 1) * cycle_ns
        for st in self.stations():
            self.fpwr(st, 0x0990, struct.pack("<Q", start))
            self.fpwr(st, 0x0980, struct.pack("<H", 0x0300))
        # Cycle until SYNC0 runs (it starts 100 ms from now) before any state request: a drive entering SAFEOP
        # starts its SYNC0 supervision, and in OP SYNC0 must arrive (else AL status 0x002C).
        self.run(150)

    # -- cycles ------------------------------------------------------------------------------------------------
    def request(self, state, stations=None):
        for st in stations or self.stations():
            self.fpwr(st, 0x0120, struct.pack("<H", state))

    def al_code(self, station):
        return struct.unpack("<H", self.fprd(station, 0x0134, 2))[0]

    def run(self, cycles, period_ns=1_000_000, until=None, timeout=0.05):
        """Cycles at period_ns: LRW of the whole image (+ FRMW with DC, + FPRD 0x0130 of each slave). Stops early
        when until(states) is true. A reply later than `timeout` counts as lost (a loaded machine delays replies by
        milliseconds now and then; tests that lose frames on purpose use a shorter one). Returns a dict of counters; self.states holds the last AL states read."""
        dgs = [(LRW, 0x0000, 0x0001, bytes(self.image))]  # logical address 0x00010000
        if self.dc:
            dgs.append((FRMW, 0x1001, 0x0910, bytes(8)))
        dgs += [(FPRD, st, 0x0130, bytes(2)) for st in self.stations()]
        stats = {"cycles": 0, "lost": 0, "wkc_errors": 0, "wkc_min": 1 << 30, "wkc_max": 0}
        nxt = time.monotonic_ns()
        for _ in range(cycles):
            nxt += period_ns
            r = self.txrx(dgs, timeout=timeout)
            stats["cycles"] += 1
            if r is None:
                stats["lost"] += 1
            else:
                wkc = r[0][1]
                stats["wkc_min"] = min(stats["wkc_min"], wkc)
                stats["wkc_max"] = max(stats["wkc_max"], wkc)
                if wkc != self.expected_wkc:
                    stats["wkc_errors"] += 1
                first = 2 if self.dc else 1
                self.states = [struct.unpack("<H", d)[0] if w == 1 else None for d, w in r[first:]]
                if until is not None and until(self.states):
                    break
            left = nxt - time.monotonic_ns()
            if left > 0:
                time.sleep(left / 1e9)
            elif left < -50 * period_ns:
                nxt = time.monotonic_ns()  # far behind (a loaded machine): no burst to catch up
        return stats

    def go(self, state, max_cycles=5000):
        """Requests `state` of every slave while cycling; raises with the AL status codes if not reached."""
        self.request(state)
        self.run(max_cycles, until=lambda s: all(x == state for x in s) and len(s) == self.count)
        if not (len(self.states) == self.count and all(x == state for x in self.states)):
            codes = [(hex(x) if x is not None else None,
                      hex(self.al_code(st)) if x is not None and x & 0x10 else "") for st, x in
                     zip(self.stations(), self.states)]
            raise AssertionError(f"{AL_NAMES.get(state)} not reached: {codes}\n{self.bus.slave_output()[-3000:]}")

    def to_op(self, dc=True):
        self.scan()
        self.discover()
        self.configure(dc=dc)
        self.go(4)
        self.go(8)

    def recover(self, max_cycles=5000):
        """What a master does after errors: acknowledges SAFEOP+ERR and requests OP again, while cycling."""
        self.run(5)
        for st, s in zip(self.stations(), self.states):
            if s is not None and s & 0x10:
                self.fpwr(st, 0x0120, struct.pack("<H", (s & 0x0F) | 0x10))
        self.go(8, max_cycles)
