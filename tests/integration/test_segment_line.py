"""A segment of soft slaves (issue 13) seen by a master over a real veth pair: `ecat-slave --slaves 3` is a line
of three drives (serial numbers 1..3) that a master takes to Op with distributed clocks, one LRW for all of them
with the exact working counter and propagation delays that increase along the line; a topology file with a
four-port junction is found in the ESC processing order (0 -> 3 -> 1 -> 2); topology files with mistakes are
refused with "FILE:LINE: message" and exit code 2. The master is harness.MiniMaster (python) with ecatctl."""
import os
import re
import shutil
import subprocess
import tempfile
import unittest

import harness


def require_segment(test):
    slave = harness.env_path("ECAT_SLAVE")
    r = subprocess.run([slave, "--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=30)
    if "--slaves" not in r.stdout or "--topology" not in r.stdout:
        test.skipTest("ecat-slave has no --slaves/--topology")


def scan_rows(out):
    """[(pos, station, state, vendor, product, revision, serial)] of `ecatctl scan`."""
    rows = []
    for line in out.splitlines():
        m = re.match(r"(\d+)\s+0x([0-9a-f]{4})\s+(\S+)\s+0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8})",
                     line)
        if m:
            rows.append((int(m.group(1)), int(m.group(2), 16), m.group(3)) + tuple(int(m.group(i), 16)
                                                                                   for i in range(4, 8)))
    return rows


def scan_delays(out):
    """The DC delay column of `ecatctl scan`, if it has one ([ns] per position), else None."""
    lines = out.splitlines()
    head = next((line for line in lines if line.startswith("pos")), "")
    cols = head.split()
    col = next((i for i, c in enumerate(cols) if c.lower().startswith("delay") or c.lower() == "dc"), None)
    if col is None:
        return None
    out = []
    for line in lines:
        parts = line.split()
        if parts and parts[0].isdigit() and len(parts) > col:
            m = re.match(r"(-?\d+)", parts[col])
            out.append(int(m.group(1)) if m else None)
    return out


class Line(unittest.TestCase):
    def test_three_drives_to_op_with_dc(self):
        require_segment(self)
        with harness.Bus(slave_args=["--slaves", "3"]) as bus:
            m = harness.MiniMaster(bus)
            self.addCleanup(m.close)
            self.assertEqual(m.count_slaves(), 3)
            out = m.scan()
            rows = scan_rows(out)
            self.assertEqual([r[0] for r in rows], [0, 1, 2], out)
            self.assertEqual([r[1] for r in rows], [0x1001, 0x1002, 0x1003], out)
            self.assertEqual([r[6] for r in rows], [1, 2, 3], out)  # serial numbers 1..N in line order
            self.assertEqual(len({(r[3], r[4], r[5]) for r in rows}), 1, out)  # one identity
            # 0x1018:04 (serial over CoE) agrees with the SII.
            for pos in range(3):
                v = bus.ecatctl("upload", str(pos), "0x1018", "4", "--type", "u32").stdout.split()[0]
                self.assertEqual(int(v, 16), pos + 1)
            m.discover()
            m.configure(dc=True)
            delays = [d[0] for d in m.delays]
            self.assertEqual(delays[0], 0)
            self.assertTrue(delays[0] < delays[1] < delays[2], m.delays)
            # DL status (0x0110): port 0 and 1 communicating in the first two, only port 0 in the last one.
            dl = [d[2] for d in m.delays]
            for k in (0, 1):
                self.assertEqual(dl[k] & 0x0A00, 0x0A00, hex(dl[k]))
            self.assertEqual(dl[2] & 0x0A00, 0x0200, hex(dl[2]))
            m.go(4)
            m.go(8)
            self.assertEqual(m.expected_wkc, 9)
            s = m.run(2000)
            self.assertEqual(s["wkc_errors"], 0, s)
            self.assertEqual((s["wkc_min"], s["wkc_max"]), (9, 9), s)
            self.assertLessEqual(s["lost"], 20, s)  # a python master on a shared machine may miss a reply
            self.assertEqual(m.states, [8, 8, 8])
            # SYNC0 runs in each drive (activation and cycle as written) and the reference clock ticks.
            for st in m.stations():
                self.assertEqual(m.fprd(st, 0x0981, 1), b"\x03")
            delays_read = [int.from_bytes(m.fprd(st, 0x0928, 4), "little") for st in m.stations()]
            self.assertEqual(delays_read, [d & 0xFFFFFFFF for d in delays])
            # ecatctl's own scan lists the DC delays of the master library's measurement: the same order.
            scan = bus.ecatctl("scan").stdout
            self.assertEqual([r[2] for r in scan_rows(scan)], ["OP"] * 3, scan)
            d = scan_delays(scan)
            self.assertIsNotNone(d, scan)
            self.assertTrue(d[0] < d[1] < d[2], scan)
            # State directories per drive: <state-dir>/drive<k>.
            bus.ecatctl("download", "1", "0x1010", "1", "save", "--type", "string")
            self.assertTrue(os.path.exists(os.path.join(bus.dir, "state", "drive2", "parameters.bin")),
                            os.listdir(os.path.join(bus.dir, "state")))


    def test_ecatctl_pd_all_with_dc(self):
        """The project's own master (ecatctl pd --all) on the same line: one session over all drives."""
        require_segment(self)
        with harness.Bus(slave_args=["--slaves", "3"]) as bus:
            if "--all" not in bus.ecatctl("pd", "--help").stdout:
                self.skipTest("ecatctl pd has no --all")
            r = bus.ecatctl("pd", "--all", "--dc", "-n", "2000", "--cycle-us", "1000", check=False)
            m = re.search(r"cycles (\d+), lost (\d+), wkc errors (\d+) \(expected wkc (\d+)", r.stdout)
            self.assertIsNotNone(m, r.stdout + r.stderr)
            cycles, lost, wkc_errors, expected = (int(x) for x in m.groups())
            self.assertEqual((cycles, wkc_errors, expected), (2000, 0, 9), r.stdout)
            self.assertLessEqual(lost, 20, r.stdout)
            rows = re.findall(r"^(\d+)\s+0x([0-9a-f]{4})\s+(\S+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(-?\d+)$", r.stdout, re.M)
            self.assertEqual([row[2] for row in rows], ["OP"] * 3, r.stdout)
            delays = [int(row[6]) for row in rows]
            self.assertTrue(delays[0] < delays[1] < delays[2], r.stdout)
            scan = bus.ecatctl("scan").stdout
            d = scan_delays(scan)
            self.assertIsNotNone(d, scan)
            self.assertTrue(d[0] < d[1] < d[2], scan)


TREE = """# a junction (four ports) with a drive on each of ports 1, 2 and 3
timing processing-ns=320 forwarding-ns=280 cable-ns=10
device j ports=4 serial=10
device a at=j:3 serial=13   # port 3 comes right after port 0 in the processing order
device b at=j:1 serial=11
device c at=j:2 serial=12 drift-ppm=20 offset-ns=5000 cable-ns=50
"""


class Tree(unittest.TestCase):
    def test_junction_in_processing_order_and_to_op(self):
        require_segment(self)
        d = tempfile.mkdtemp(dir=os.environ.get("ECAT_TEST_OUT"))
        self.addCleanup(shutil.rmtree, d, True)
        topo = os.path.join(d, "tree.topo")
        with open(topo, "w") as f:
            f.write(TREE)
        with harness.Bus(slave_args=["--topology", topo]) as bus:
            m = harness.MiniMaster(bus)
            self.addCleanup(m.close)
            self.assertEqual(m.count_slaves(), 4)
            out = m.scan()
            self.assertEqual([r[6] for r in scan_rows(out)], [10, 13, 11, 12], out)
            # The junction: ports 0..3 all with communication (DL status bits 9, 11, 13, 15), the leaves port 0.
            dl = [int.from_bytes(m.fprd(st, 0x0110, 2), "little") for st in m.stations()]
            self.assertEqual(dl[0] & 0xAA00, 0xAA00, [hex(x) for x in dl])
            for x in dl[1:]:
                self.assertEqual(x & 0xAA00, 0x0200, [hex(x) for x in dl])
            # Port descriptor (0x0007): four ports on the junction, two on the drives.
            self.assertEqual(m.fprd(0x1001, 0x0007, 1), b"\xff")
            self.assertEqual(m.fprd(0x1002, 0x0007, 1), b"\x0f")
            # Receive times of the junction latched in processing order: port 0, then 3, 1, 2 (one local clock).
            m.one(harness.BWR, 0, 0x0900, bytes(4))
            t = [int.from_bytes(m.fprd(0x1001, 0x0900 + 4 * p, 4), "little") for p in range(4)]
            self.assertTrue(t[0] < t[3] < t[1] < t[2], t)
            m.discover()
            m.configure(dc=False)
            m.go(4)
            m.go(8)
            s = m.run(1000)
            self.assertEqual(m.expected_wkc, 12)
            self.assertEqual((s["wkc_errors"], s["wkc_min"], s["wkc_max"]), (0, 12, 12), s)
            self.assertEqual(m.states, [8] * 4)


class BadTopology(unittest.TestCase):
    CASES = [
        # (text, line of the mistake, a word the message names)
        ("device a\ndevice b colour=red\n", 2, "colour"),
        ("device a\ndevice b at=nosuch:1\n", 2, "nosuch"),
        ("device a\ndevice b at=a:1\ndevice c at=a:1\n", 3, None),  # port 1 of a used twice
        ("device a serial=12x\n", 1, "12x"),
        ("timing processing-ns=fast\n", 1, "fast"),
        ("device a config=missing.conf\n", 1, "missing.conf"),
        ("device a\ndevice b at=a:3\n", 2, None),  # a two-port ESC has no port 3
        ("device a ports=4\ndevice b at=a:1\ndevice c at=b:1\ndevice b at=c:1\n", 4, None),  # b again (a loop)
        ("# comment\n\nfrobnicate now\n", 3, "frobnicate"),
    ]

    def test_file_line_message_and_exit_2(self):
        require_segment(self)
        slave = harness.env_path("ECAT_SLAVE")
        d = tempfile.mkdtemp(dir=os.environ.get("ECAT_TEST_OUT"))
        self.addCleanup(shutil.rmtree, d, True)
        for i, (text, line, word) in enumerate(self.CASES):
            with self.subTest(text=text):
                path = os.path.join(d, f"bad{i}.topo")
                with open(path, "w") as f:
                    f.write(text)
                try:
                    r = subprocess.run([slave, "--topology", path, "--iface", "lo", "--state-dir",
                                        os.path.join(d, "state")], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                       text=True, timeout=10)
                except subprocess.TimeoutExpired:
                    self.fail(f"ecat-slave ran with {text!r}")
                self.assertEqual(r.returncode, 2, r.stderr)
                self.assertIn(f"{path}:{line}: ", r.stderr)
                if word:
                    self.assertIn(word, r.stderr)
        r = subprocess.run([slave, "--topology", os.path.join(d, "none.topo"), "--iface", "lo"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=10)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("none.topo", r.stderr)

    def test_slave_count_out_of_range(self):
        require_segment(self)
        slave = harness.env_path("ECAT_SLAVE")
        for n in ("0", "1001", "x"):
            r = subprocess.run([slave, "--slaves", n, "--iface", "lo"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, timeout=10)
            self.assertEqual(r.returncode, 2, (n, r.stderr))
            self.assertIn("--slaves", r.stderr)


if __name__ == "__main__":
    harness.main()
