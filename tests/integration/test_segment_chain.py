"""Soft slaves chained across interfaces (issue 13): two ecat-slave processes joined by a veth pair
(`--out-iface` of the first leads to `--iface` of the second) are one line for a master on the first one's
input: two (or 1 + 2) drives in line order with increasing DC delays, to Op with the exact working counter; when
the second one's interface loses its carrier the first closes its port (loop back) and the line is shorter, and
it grows again with the carrier. The master is harness.MiniMaster (python) with ecatctl."""
import os
import subprocess
import time
import unittest

import harness
from test_segment_line import require_segment, scan_rows


class Chain(harness.Bus):
    """ecat-slave A on the namespace end of the master's veth pair with --out-iface OUT, and ecat-slave B on the
    peer of OUT, both in the same private namespace."""

    def __init__(self, args_a=(), args_b=()):
        super().__init__(slave_args=args_a)
        uid = self.ns[len("ecit"):]
        self.out_iface = f"eo{uid}"
        self.in_b = f"ei{uid}"
        self.args_b = list(args_b)
        self.proc_b = None
        self.log_b = os.path.join(self.dir, "slave-b.log")
        self._log_b = None

    def _start(self):
        self._run("ip", "netns", "add", self.ns)
        for cmd in (("ip", "link", "add", self.iface, "type", "veth", "peer", "name", self.slave_iface),
                    ("ip", "link", "set", self.slave_iface, "netns", self.ns),
                    ("ip", "link", "set", self.iface, "up")):
            self._run(*cmd)
        self._run("sysctl", "-qw", f"net.ipv6.conf.{self.iface}.disable_ipv6=1", check=False)
        ns = ("ip", "netns", "exec", self.ns)
        self._run(*ns, "ip", "link", "add", self.out_iface, "type", "veth", "peer", "name", self.in_b)
        for i in (self.slave_iface, self.out_iface, self.in_b):
            self._run(*ns, "sysctl", "-qw", f"net.ipv6.conf.{i}.disable_ipv6=1", check=False)
            self._run(*ns, "ip", "link", "set", i, "up")
        self._log_b = open(self.log_b, "w")
        self.proc_b = subprocess.Popen([*ns, self.slave_bin, "--iface", self.in_b, "--state-dir",
                                        os.path.join(self.dir, "state-b"), *self.args_b],
                                       stdout=self._log_b, stderr=subprocess.STDOUT, start_new_session=True)
        # A on the master's veth pair with port 1 on OUT; ready when the line answers a register read.
        self._log = open(self.slave_log, "w")
        self.proc = subprocess.Popen([*ns, self.slave_bin, "--iface", self.slave_iface, "--out-iface",
                                      self.out_iface, "--capture", self.capture, "--state-dir",
                                      os.path.join(self.dir, "state"), *self.slave_args],
                                     stdout=self._log, stderr=subprocess.STDOUT, start_new_session=True)
        self.wait_answering(self.proc, self.proc_b)

    def ns_ip(self, *args):
        return self._run("ip", "netns", "exec", self.ns, "ip", *args)

    def close(self):
        if self.proc_b is not None and self.proc_b.poll() is None:
            self.proc_b.terminate()
            try:
                self.proc_b.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc_b.kill()
                self.proc_b.wait(timeout=5)
        if self._log_b:
            self._log_b.close()
            self._log_b = None
        super().close()

    def slave_output(self):
        try:
            with open(self.log_b) as f:
                b = f.read()
        except OSError:
            b = ""
        return super().slave_output() + "\n--- slave B ---\n" + b


class ChainedProcesses(unittest.TestCase):
    def setUp(self):
        require_segment(self)
        r = subprocess.run([harness.env_path("ECAT_SLAVE"), "--help"], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=30)
        if "--out-iface" not in r.stdout:
            self.skipTest("ecat-slave has no --out-iface")

    def wait_count(self, m, n, seconds=5):
        # Until A notices that its out link lost or regained its carrier (polled every 100 ms, as a PHY takes a
        # while to see a pulled cable), frames that go out of its port 1 are lost: a BRD without a reply is
        # asked again, up to the deadline.
        deadline = time.monotonic() + seconds
        count = None
        while True:
            r = m.txrx([(harness.BRD, 0, 0, b"\x00")])
            if r is not None:
                count = r[0][1]
                if count == n:
                    return count
            if time.monotonic() >= deadline:
                return count
            time.sleep(0.05)

    def line_to_op(self, bus, n, serials):
        m = harness.MiniMaster(bus)
        self.addCleanup(m.close)
        self.assertEqual(self.wait_count(m, n), n, bus.slave_output())
        out = m.scan()
        rows = scan_rows(out)
        self.assertEqual([r[1] for r in rows], [0x1001 + k for k in range(n)], out)
        # B's drives come after A's, in B's order (A's single drive has the program's default serial number).
        self.assertEqual([r[6] for r in rows][len(rows) - len(serials):], serials, out)
        m.discover()
        m.configure(dc=True)
        delays = [d[0] for d in m.delays]
        self.assertEqual(delays[0], 0)
        self.assertTrue(all(a < b for a, b in zip(delays, delays[1:])), m.delays)
        m.go(4)
        m.go(8)
        s = m.run(2000)
        self.assertEqual(m.expected_wkc, 3 * n)
        self.assertEqual((s["wkc_errors"], s["wkc_min"], s["wkc_max"]), (0, 3 * n, 3 * n), s)
        self.assertLessEqual(s["lost"], 20, s)
        self.assertEqual(m.states, [8] * n)
        return m

    def test_two_processes_one_line(self):
        with Chain() as bus:
            m = self.line_to_op(bus, 2, [])
            # B's interface loses its carrier: A closes port 1 and answers alone, as a hardware ESC does.
            bus.ns_ip("link", "set", bus.in_b, "down")
            self.assertEqual(self.wait_count(m, 1), 1, bus.slave_output())
            bus.ns_ip("link", "set", bus.in_b, "up")
            self.assertEqual(self.wait_count(m, 2), 2, bus.slave_output())

    def test_one_plus_two(self):
        with Chain(args_b=["--slaves", "2"]) as bus:
            self.line_to_op(bus, 3, [1, 2])


if __name__ == "__main__":
    harness.main()
