"""`ecat-slave --fault NAME` over a real veth pair: a fault of each layer (ESC, state machine, CoE, the device
composition) given on the command line breaks its one behaviour as seen by ecatctl, while the clean slave
answers correctly and the faulty one keeps answering everything else. Per-fault detail is in the unit tests
(tests/*/faults_test.cpp); decisions in docs/decisions/faults.md."""
import os
import re
import subprocess
import unittest

import harness


def abort_of(r):
    """The abort code ecatctl reports on stderr (exit code 6), or None."""
    m = re.search(r"SDO abort 0x([0-9a-f]{8})", r.stderr)
    return int(m.group(1), 16) if m and r.returncode == 6 else None


def boot(bus):
    """ecatctl's FoE write (INIT, bootstrap mailbox from the SII, BOOT) of a file the slave does not know: a
    slave that enters BOOT refuses the file over FoE (0x8001), one that refuses BOOT says so."""
    path = os.path.join(bus.dir, "not-an-image.bin")
    with open(path, "wb") as f:
        f.write(b"\x00" * 64)
    return bus.ecatctl("foe", "write", path, "--name", "not-an-image.bin", check=False)


def product_code(bus):
    return int(bus.ecatctl("upload", "0", "0x1018", "2").stdout.split()[0], 16)


class FaultList(unittest.TestCase):
    def test_list_and_unknown_name(self):
        slave = harness.env_path("ECAT_SLAVE")
        r = subprocess.run([slave, "--fault", "list"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, timeout=30)
        self.assertEqual(r.returncode, 0, r.stderr)
        names = [line.split()[0] for line in r.stdout.splitlines() if line.strip()]
        self.assertGreaterEqual(len(names), 22)
        for required in ("wkc-aprd", "ca-no-padding", "info-error-short", "abort-missing-object",
                         "abort-command-download", "bootstrap-refused", "identity-mismatch",
                         "mbx-counter-ignored", "mbx-repeat-ignored", "watchdog-never", "pdo-map-in-safeop",
                         "quickstop-ignored"):
            self.assertIn(required, names)
        r = subprocess.run([slave, "--fault", "no-such-fault"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True, timeout=30)
        self.assertEqual(r.returncode, 2)
        self.assertIn("no-such-fault", r.stderr)


class FaultsOverVeth(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        with harness.Bus() as bus:
            bus.ecatctl("scan")
            cls.clean_product = product_code(bus)
            cls.clean_missing = abort_of(bus.ecatctl("upload", "0", "0x5fff", "0", check=False))
            cls.clean_other_station = bus.ecatctl("reg", "read", "0x1234", "0x0000", "2", "--station",
                                                  check=False)
            cls.clean_boot = boot(bus)

    def test_clean_slave(self):
        self.assertEqual(self.clean_missing, 0x06020000)
        self.assertNotEqual(self.clean_other_station.returncode, 0, self.clean_other_station.stdout)
        self.assertNotIn("0x0013", self.clean_boot.stderr)
        self.assertIn("FoE error 0x8001", self.clean_boot.stderr)  # in BOOT, the FoE server refused the name

    def test_fprd_any_address(self):
        with harness.Bus(slave_args=("--fault", "fprd-any-address")) as bus:
            bus.ecatctl("scan")
            r = bus.ecatctl("reg", "read", "0x1234", "0x0000", "2", "--station", check=False)  # not its address
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertEqual(product_code(bus), self.clean_product)

    def test_bootstrap_refused(self):
        with harness.Bus(slave_args=("--fault", "bootstrap-refused")) as bus:
            bus.ecatctl("scan")
            r = boot(bus)
            self.assertNotEqual(r.returncode, 0, r.stdout)
            self.assertIn("AL status code 0x0013", r.stderr)
            self.assertIn("BOOT", r.stderr)
            bus.ecatctl("state", "0", "init", check=False)
            self.assertEqual(product_code(bus), self.clean_product)  # Pre-Op and CoE as usual

    def test_abort_missing_object(self):
        with harness.Bus(slave_args=("--fault", "abort-missing-object")) as bus:
            bus.ecatctl("scan")
            self.assertEqual(abort_of(bus.ecatctl("upload", "0", "0x5fff", "0", check=False)), 0x06090011)
            self.assertEqual(product_code(bus), self.clean_product)

    def test_identity_mismatch_and_a_combination(self):
        with harness.Bus(slave_args=("--fault", "identity-mismatch,abort-missing-object")) as bus:
            bus.ecatctl("scan")
            self.assertEqual(product_code(bus), self.clean_product + 1)
            self.assertEqual(abort_of(bus.ecatctl("upload", "0", "0x5fff", "0", check=False)), 0x06090011)
            self.assertIn("identity-mismatch", bus.slave_output())


if __name__ == "__main__":
    harness.main()
