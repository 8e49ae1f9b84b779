#!/usr/bin/env python3
"""Builds the seed corpora of the fuzz harnesses (tests/fuzz/corpus/<harness>/) from real traffic and real
files: the real ecat-slave on a veth pair in a private network namespace (tests/integration/harness.py),
driven by the real ecatctl through a session (scan, SII, state changes, SDO upload/download/info, FoE
through Bootstrap, process data), recorded with `ecat-slave --capture`; then the capture is cut into seeds:

  esc_frame, slave   the master's frames of each command (after the set-up frames of the session, for the
                     whole slave), as [time in 10 us][16-bit length][frame] records
  master_reply       the slave's replies to each command, as the master harness's link answers (mode 0:
                     working counter and each datagram's data), and whole reply frames for the frame reader
  coe_mailbox        the CoE mailbox payloads the master wrote to SM0, per command
  foe_server         the FoE mailbox payloads, per command
  sii                the SII image of `ecat-slave --write-sii` and the one ecatctl read over the wire
  device_config      the example configurations in the tree
  loaders            the files the slave wrote into its state directory (parameters.bin after 0x1010
                     "save", the firmware slot pointer and slot images, sii-writes.bin after `sii write`)
  esi_line           a second session against a line of every device of the example ESIs (esi/examples,
                     `ecat-slave --topology` with esi= lines): scan, states, SDO, process data of the line

Usage (as root): tests/fuzz/make_corpus.py --slave build/tools/ecat-slave/ecat-slave \
                    --ecatctl build/tools/ecatctl/ecatctl [--out tests/fuzz/corpus] [--only esi_line]
"""
import argparse
import hashlib
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "integration"))


def read_pcap(path):
    """[(time_ns, bytes)] of a classic pcap file (micro- or nanosecond timestamps)."""
    with open(path, "rb") as f:
        data = f.read()
    magic = struct.unpack_from("<I", data, 0)[0]
    nano = magic == 0xA1B23C4D
    at, out = 24, []
    while at + 16 <= len(data):
        sec, frac, incl, _ = struct.unpack_from("<IIII", data, at)
        at += 16
        out.append((sec * 1_000_000_000 + (frac if nano else frac * 1000), data[at:at + incl]))
        at += incl
    return out


def datagrams(frame):
    """[(cmd, adp, ado, data, wkc)] of an EtherCAT frame."""
    if len(frame) < 16 or frame[12:14] != b"\x88\xa4":
        return []
    at, out = 16, []
    while at + 12 <= len(frame):
        cmd, _idx, adp, ado, lf, _irq = struct.unpack_from("<BBHHHH", frame, at)
        n = lf & 0x7FF
        if at + 10 + n + 2 > len(frame):
            break
        out.append((cmd, adp, ado, frame[at + 10:at + 10 + n], struct.unpack_from("<H", frame, at + 10 + n)[0]))
        if not lf & 0x8000:
            break
        at += 12 + n
    return out


def records(frames):
    """[dt][len16][frame] records; dt = time since the previous frame in 10 us (at most 255)."""
    out, prev = bytearray(), None
    for t, f in frames:
        dt = 0 if prev is None else min(255, max(0, (t - prev) // 10_000))
        prev = t
        out += bytes([dt]) + struct.pack("<H", len(f)) + f
    return bytes(out)


class Writer:
    def __init__(self, out, limit):
        self.out, self.limit, self.count = out, limit, {}

    def put(self, harness, name, data, limit=None):
        if not data:
            return
        data = data[: limit or self.limit]
        d = os.path.join(self.out, harness)
        os.makedirs(d, exist_ok=True)
        tag = hashlib.sha1(data).hexdigest()[:10]
        with open(os.path.join(d, f"{name}-{tag}"), "wb") as f:
            f.write(data)
        self.count[harness] = self.count.get(harness, 0) + 1


def firmware_image(vendor, product, version=0x01300000, size=700):
    payload = bytes((i * 7) & 0xFF for i in range(size))
    head = struct.pack("<IHHIIIII", 0x57464553, 1, 32, vendor, product, version, len(payload), 0)
    return head + struct.pack("<I", zlib.crc32(head + payload) & 0xFFFFFFFF) + payload


def esi_line_corpus(harness, a, w):
    """The esi_line seeds: a session of ecatctl against a line of every device of every example ESI, in the
    order the harness builds it (files sorted by name, devices in file order)."""
    shutil.rmtree(os.path.join(a.out, "esi_line"), ignore_errors=True)
    examples = os.path.join(ROOT, "esi", "examples")
    files = sorted(f for f in os.listdir(examples) if f.endswith(".xml"))
    marks = []
    lines, analog = [], None
    for f in files:
        path = os.path.join(examples, f)
        for t in ET.parse(path).getroot().findall("Descriptions/Devices/Device/Type"):
            spec = f"{t.get('ProductCode').replace('#x', '0x')}:{t.get('RevisionNo').replace('#x', '0x')}"
            if f == "analog-in.xml" and analog is None:
                analog = len(lines)
            lines.append(f"device d{len(lines)} esi={path} device={spec}")
    tmp = tempfile.mkdtemp(prefix="softecat-corpus-")
    topo = os.path.join(tmp, "line.topo")
    with open(topo, "w") as t:
        t.write("\n".join(lines) + "\n")
    with harness.Bus(slave_args=["--topology", topo]) as bus:
        def run(name, *args):
            t0 = time.time_ns()
            r = bus.ecatctl(*args, check=False)
            marks.append((name, t0, time.time_ns()))
            if r.returncode != 0:
                print(f"esi_line: ecatctl {' '.join(args)}: exit {r.returncode}: {r.stderr.strip()[-300:]}")

        run("scan", "scan")
        run("preop", "states", "PREOP")
        if analog is not None:
            run("upload", "upload", str(analog), "0x1018", "1")
            run("sdo_info", "sdos", str(analog))
        run("safeop", "states", "SAFEOP")
        run("pd", "pd", "--all", "-n", "40", "--cycle-us", "1000")
        run("init", "states", "INIT")
        time.sleep(0.3)
        bus.stop_slave()
        capture = read_pcap(bus.capture)
    shutil.rmtree(tmp, ignore_errors=True)
    requests = [(t, f) for t, f in capture if len(f) > 6 and not f[6] & 0x02]
    setup_end = next(e for n, _s, e in marks if n == "scan")
    setup = [(t, f) for t, f in requests if t <= setup_end]
    for name, s, e in marks:
        req = [(t, f) for t, f in requests if s <= t <= e]
        if req:
            w.put("esi_line", name, records(setup[-10:] + req if name != "scan" else req), 16384)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--slave", required=True)
    ap.add_argument("--ecatctl", required=True)
    ap.add_argument("--out", default=os.path.join(HERE, "corpus"))
    ap.add_argument("--max-seed", type=int, default=6144, help="bytes per seed file at most")
    ap.add_argument("--only", choices=["esi_line"], help="build this corpus alone")
    a = ap.parse_args()
    os.environ["ECAT_SLAVE"], os.environ["ECATCTL"] = os.path.abspath(a.slave), os.path.abspath(a.ecatctl)
    import harness  # noqa: E402 (needs the environment above)

    if a.only == "esi_line":
        w = Writer(a.out, a.max_seed)
        esi_line_corpus(harness, a, w)
        for k, v in sorted(w.count.items()):
            print(f"{k}: {v} seeds")
        return

    for h in ("esc_frame", "slave", "master_reply", "coe_mailbox", "foe_server", "sii", "loaders"):
        shutil.rmtree(os.path.join(a.out, h), ignore_errors=True)
    w = Writer(a.out, a.max_seed)

    marks = []  # (name, start_ns, end_ns) of each command
    with harness.Bus() as bus:
        def run(name, *args):
            t0 = time.time_ns()
            r = bus.ecatctl(*args, check=False)
            marks.append((name, t0, time.time_ns()))
            return r

        run("scan", "scan")
        sii_path = os.path.join(bus.dir, "sii.bin")
        run("sii_read", "sii", "read", "-o", sii_path)
        run("preop", "state", "0", "PREOP")
        run("upload_string", "upload", "0", "0x1008", "0", "--type", "string")
        run("upload_u32", "upload", "0", "0x1018", "1")
        run("upload_complete", "upload", "0", "0x1600", "0", "--complete")
        run("upload_abort", "upload", "0", "0x5fff", "0")
        run("download", "download", "0", "0x6060", "0", "1", "--type", "i8")
        run("download_bad", "download", "0", "0x1018", "1", "1", "2", "3", "4")
        run("sdo_info", "sdos", "0")
        run("diag", "diag", "0")
        run("save", "download", "0", "0x1010", "1", "0x65766173", "--type", "u32")
        scan = bus.ecatctl("scan").stdout
        vendor = product = None
        for line in scan.splitlines():
            parts = line.split()
            if len(parts) >= 5 and parts[1] == "0x1001":
                vendor, product = int(parts[3], 16), int(parts[4], 16)
        run("foe_read_missing", "foe", "read", "MAXPOS", "-o", os.path.join(bus.dir, "none.bin"))
        run("boot", "state", "0", "BOOT")
        if vendor is not None:
            img = os.path.join(bus.dir, "fw.bin")
            with open(img, "wb") as f:
                f.write(firmware_image(vendor, product))
            run("foe_write", "foe", "write", img, "--name", "MAXPOS")
            run("foe_write_bad", "foe", "write", sii_path, "--name", "MAXPOS")
            run("foe_read", "foe", "read", "MAXPOS", "-o", os.path.join(bus.dir, "back.bin"))
        run("init", "state", "0", "INIT")
        run("preop2", "state", "0", "PREOP")
        run("pd", "pd", "0", "-n", "40", "--cycle-us", "1000")
        run("init2", "state", "0", "INIT")
        if os.path.exists(sii_path):
            run("sii_write", "sii", "write", sii_path, "-p", "0")
        time.sleep(0.3)
        bus.stop_slave()
        capture = read_pcap(bus.capture)
        state = os.path.join(bus.dir, "state")
        for root, _dirs, files in os.walk(state):
            for fn in files:
                p = os.path.join(root, fn)
                with open(p, "rb") as f:
                    data = f.read()
                if fn == "parameters.bin":
                    w.put("loaders", "parameters", b"\x00" + data)
                    w.put("loaders", "parameters-repair", b"\x80" + data)
                elif fn == "sii-writes.bin":
                    w.put("loaders", "sii-writes", b"\x01" + data)
                    w.put("loaders", "sii-writes-repair", b"\x81" + data)
                elif fn in ("active", "slot0.bin", "slot1.bin"):
                    pass
            fw = os.path.join(state, "firmware")
            if root == fw:
                parts = []
                for fn in ("active", "slot0.bin", "slot1.bin"):
                    p = os.path.join(fw, fn)
                    data = open(p, "rb").read() if os.path.exists(p) else b""
                    parts.append(struct.pack("<H", len(data)) + data)
                w.put("loaders", "firmware", b"\x02" + b"".join(parts))
                w.put("loaders", "firmware-repair", b"\x82" + b"".join(parts))
        if os.path.exists(sii_path):
            w.put("sii", "sii-read", open(sii_path, "rb").read())

    # The SII as the program writes it.
    sii_file = os.path.join(a.out, "..", "sii.tmp")
    subprocess.run([a.slave, "--write-sii", sii_file], check=True, stdout=subprocess.DEVNULL)
    written_sii = open(sii_file, "rb").read()
    w.put("sii", "write-sii", written_sii)
    os.remove(sii_file)

    requests = [(t, f) for t, f in capture if len(f) > 6 and not f[6] & 0x02]
    replies = [(t, f) for t, f in capture if len(f) > 6 and f[6] & 0x02]
    setup_end = next(e for n, s, e in marks if n == "preop")
    setup = [(t, f) for t, f in requests if t <= setup_end]

    # Mailbox addresses from the SII header (words 0x14 boot out, 0x18 standard out).
    sii = open(sii_path, "rb").read() if os.path.exists(sii_path) else written_sii
    mbx_out = {struct.unpack_from("<H", sii, 0x30)[0], struct.unpack_from("<H", sii, 0x28)[0]} if len(sii) > 0x40 else set()
    mbx_size = struct.unpack_from("<H", sii, 0x32)[0] if len(sii) > 0x40 else 128

    ops = {"scan": 0, "sii_read": 1, "preop": 9, "upload_string": 3, "upload_u32": 3, "upload_complete": 3 | 0x80,
           "upload_abort": 3, "download": 4, "download_bad": 4 | 0x80, "sdo_info": 5, "diag": 3, "save": 4,
           "foe_read_missing": 8, "boot": 9, "foe_write": 9 | 0x80, "foe_write_bad": 9, "foe_read": 8,
           "init": 9, "preop2": 9, "pd": 9, "init2": 9, "sii_write": 1}
    for name, s, e in marks:
        req = [(t, f) for t, f in requests if s <= t <= e]
        rep = [(t, f) for t, f in replies if s <= t <= e]
        if not req:
            continue
        w.put("esc_frame", name, records(req[:200]), 3072)
        w.put("slave", name, records(setup[-40:] + req if name != "scan" else req), 6144)
        # The master harness: mode 0 answers (working counter, data of each datagram) in order.
        m = bytearray([ops.get(name, 0) & 0xFF])
        for _t, f in rep[:200]:
            dgs = datagrams(f)
            if not dgs:
                continue
            m.append(((min(dgs[0][4], 3)) << 2) | 0)
            for d in dgs:
                m += d[3]
        w.put("master_reply", name, bytes(m), 2048)
        if rep:
            w.put("master_reply", name + "-frame", bytes([11]) + rep[0][1])
        # Mailbox payloads written to SM0.
        for kind, harness_name, ctl in ((3, "coe_mailbox", 0), (4, "foe_server", 0)):
            seq = bytearray([max(0, min(255, (mbx_size - 10) // 4))])
            for _t, f in req:
                for cmd, _adp, ado, data, _wkc in datagrams(f):
                    if cmd in (2, 5) and ado in mbx_out and len(data) >= 6 and data[5] & 0x0F == kind:
                        n = min(struct.unpack_from("<H", data, 0)[0], len(data) - 6)
                        seq += bytes([ctl]) + struct.pack("<H", n) + data[6:6 + n]
            if len(seq) > 1:
                w.put(harness_name, name, bytes(seq))

    # The example device configurations of the tree (parsed as text, and loaded as a file).
    shutil.rmtree(os.path.join(a.out, "device_config"), ignore_errors=True)
    for conf in (os.path.join(ROOT, "od", "examples", "device.conf"), os.path.join(ROOT, "tools", "ecat-slave", "drive.conf")):
        text = open(conf, "rb").read()
        w.put("device_config", os.path.basename(conf), text)
        w.put("loaders", "config-" + os.path.basename(conf), b"\x03" + text)

    esi_line_corpus(harness, a, w)
    for k, v in sorted(w.count.items()):
        print(f"{k}: {v} seeds")


if __name__ == "__main__":
    main()
