"""ecatctl's error paths: missing interface, nobody on the wire, no privileges."""
import os
import shutil
import subprocess
import unittest

import harness


def run(*args):
    return subprocess.run([harness.env_path("ECATCTL"), *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, timeout=60)


class CliErrors(unittest.TestCase):
    def test_missing_interface(self):
        r = run("--iface", "nosuchif0", "scan")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("nosuchif0", r.stderr)

    def test_no_slave_answers(self):
        a, b = f"enx{os.getpid() % 100000}a", f"enx{os.getpid() % 100000}b"
        subprocess.run(["ip", "link", "add", a, "type", "veth", "peer", "name", b], check=True)
        try:
            subprocess.run(["ip", "link", "set", a, "up"], check=True)
            subprocess.run(["ip", "link", "set", b, "up"], check=True)
            r = run("--iface", a, "--timeout", "20", "--retries", "1", "scan")
            self.assertEqual(r.returncode, 5, r.stderr)
            self.assertIn("no slave answered", r.stderr)
        finally:
            subprocess.run(["ip", "link", "del", a])

    def test_interface_down(self):
        a, b = f"edn{os.getpid() % 100000}a", f"edn{os.getpid() % 100000}b"
        subprocess.run(["ip", "link", "add", a, "type", "veth", "peer", "name", b], check=True)
        try:
            r = run("--iface", a, "scan")  # never set up
            self.assertEqual(r.returncode, 3, r.stderr)
            self.assertIn(a, r.stderr)
        finally:
            subprocess.run(["ip", "link", "del", a])

    def test_no_privileges(self):
        setpriv = shutil.which("setpriv")
        if not setpriv:
            self.skipTest("setpriv not installed")
        r = subprocess.run([setpriv, "--reuid=65534", "--regid=65534", "--clear-groups", "--inh-caps=-all",
                            harness.env_path("ECATCTL"), "--iface", "lo", "scan"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)
        self.assertEqual(r.returncode, 4, r.stderr)

    def test_usage(self):
        self.assertEqual(run().returncode, 2)
        self.assertEqual(run("frobnicate").returncode, 2)
        self.assertEqual(run("--help").returncode, 0)


if __name__ == "__main__":
    harness.main()
