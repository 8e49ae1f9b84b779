"""AL state requests and CoE SDO transfers through ecatctl against the real ecat-slave (needs the slave
to run its firmware: the state machine and the CoE server)."""
import time
import unittest

import harness


class CoeAndState(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.bus = harness.Bus().__enter__()
        r = cls.bus.ecatctl("--timeout", "50", "state", "0", "PREOP", check=False)
        cls.no_firmware = None
        if r.returncode != 0:
            st = cls.bus.ecatctl("state", "0", check=False).stdout.strip()
            if st == "INIT" and "not reached in time" in r.stderr:
                cls.no_firmware = "ecat-slave runs without firmware (AL status never follows AL control)"
            elif "no EEPROM" in cls.bus.slave_output():
                cls.no_firmware = "ecat-slave serves no SII image, so no mailbox layout"

    @classmethod
    def tearDownClass(cls):
        cls.bus.close()

    def setUp(self):
        if self.no_firmware:
            self.skipTest(self.no_firmware)

    def test_preop_is_reached(self):
        self.assertEqual(self.bus.ecatctl("state", "0").stdout.split()[0], "PREOP")

    def test_identity_object_matches_the_sii(self):
        vendor = self.bus.ecatctl("upload", "0", "0x1018", "1").stdout.strip()
        product = self.bus.ecatctl("upload", "0", "0x1018", "2").stdout.strip()
        scan = self.bus.ecatctl("scan").stdout
        self.assertEqual(vendor, "0x000000fb (251)")
        self.assertIn(product.split()[0], scan)

    def test_device_name(self):
        r = self.bus.ecatctl("upload", "0", "0x1008", "0", "--type", "string")
        self.assertTrue(r.stdout.strip(), r.stdout)

    def test_download_then_upload(self):
        # A mapping entry is written while subindex 0 is 0 (ETG.1000.6); the slave refuses it before.
        r = self.bus.ecatctl("download", "0", "0x1600", "1", "0x607A0020", "--type", "u32", check=False)
        self.assertIn("0x06010003", r.stderr)
        self.bus.ecatctl("download", "0", "0x1600", "0", "0", "--type", "u8")
        self.bus.ecatctl("download", "0", "0x1600", "1", "0x607A0020", "--type", "u32")
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1600", "1").stdout.strip(), "0x607a0020 (1618608160)")
        # Complete access is decoded per subindex with the names and types from SDO information.
        r = self.bus.ecatctl("upload", "0", "0x1600", "0", "--complete")
        self.assertTrue(r.stdout.startswith("0x1600:00 "), r.stdout)
        self.assertRegex(r.stdout, r"(?m)^0x1600:01 .* = 0x607a0020 \(1618608160\)$")

    def test_download_takes_the_type_from_sdo_information(self):
        # Without --type a value wider than a byte is encoded as the entry's type (here INTEGER32), as upload
        # decodes it; a value that does not fit the type is a usage error before anything is written.
        before = self.bus.ecatctl("upload", "0", "0x607a", "0").stdout.strip()
        self.bus.ecatctl("download", "0", "0x607a", "0", "3000")
        self.assertTrue(self.bus.ecatctl("upload", "0", "0x607a", "0").stdout.strip().endswith("(3000)"))
        r = self.bus.ecatctl("download", "0", "0x6060", "0", "3000", check=False)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("does not fit", r.stderr)
        self.bus.ecatctl("download", "0", "0x607a", "0", before.split()[-1].strip("()"))

    def test_abort_codes_are_reported(self):
        r = self.bus.ecatctl("upload", "0", "0x5fff", "0", check=False)
        self.assertEqual(r.returncode, 6)
        self.assertIn("0x06020000", r.stderr)
        r = self.bus.ecatctl("download", "0", "0x1018", "1", "1", "2", "3", "4", check=False)
        self.assertEqual(r.returncode, 6)
        self.assertIn("0x06010002", r.stderr)

    def test_invalid_transition_is_refused_with_its_code(self):
        # PREOP -> OP written straight into AL control (`ecatctl state 0 OP` steps through SAFEOP instead).
        self.bus.ecatctl("reg", "write", "0", "0x0120", "0x08", "0x00")
        deadline = time.monotonic() + 5
        while True:
            st = self.bus.ecatctl("state", "0").stdout.strip()
            if "+ERR" in st or time.monotonic() > deadline:
                break
            time.sleep(0.01)
        self.assertTrue(st.startswith("PREOP +ERR 0x0011"), st)
        # `state` acknowledges the error: no error flag left, still in PREOP.
        self.assertEqual(self.bus.ecatctl("state", "0", "PREOP").returncode, 0)
        self.assertEqual(self.bus.ecatctl("state", "0").stdout.strip(), "PREOP")

    def test_object_dictionary_listing(self):
        r = self.bus.ecatctl("sdos", "0")
        self.assertIn('SDO 0x1018, "', r.stdout)
        self.assertIn("  0x1018:01, r-r-r-, uint32, 32 bit, ", r.stdout)
        self.assertRegex(r.stdout, r"  0x6040:00, rwrwrw, uint16, 16 bit, ")
        quiet = self.bus.ecatctl("sdos", "0", "-q").stdout.splitlines()
        self.assertTrue(all(line.startswith("SDO 0x") for line in quiet))
        self.assertEqual(len(quiet), r.stdout.count("SDO 0x"))

    def test_z_capture_of_mailbox_traffic_decodes_cleanly(self):
        # Runs last (name order): stops the slave to flush its capture.
        self.bus.ecatctl("upload", "0", "0x1008", "0", "--type", "string")
        self.bus.ecatctl("upload", "0", "0x5fff", "0", check=False)
        self.bus.ecatctl("sdos", "0", "-q")
        self.assertEqual(self.bus.stop_slave(), 0, self.bus.slave_output())
        problems = harness.tshark_problems(self.bus.capture)
        if problems is None:
            self.skipTest("tshark not installed")
        self.assertEqual(problems, [], "\n".join(problems[:20]))


if __name__ == "__main__":
    harness.main()
