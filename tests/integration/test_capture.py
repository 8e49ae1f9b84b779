"""The slave's --capture file decodes in tshark without malformed packets or expert errors."""
import shutil
import subprocess
import unittest

import harness


class Capture(unittest.TestCase):
    def test_capture_decodes_cleanly(self):
        tshark = shutil.which("tshark")
        if not tshark:
            self.skipTest("tshark not installed")
        image, _ = harness.build_sii()
        with harness.Bus(eeprom=image) as bus:
            bus.ecatctl("scan")
            bus.ecatctl("reg", "read", "0", "0x0000", "16")
            bus.ecatctl("reg", "write", "0", "0x0f80", "1", "2", "3")
            bus.ecatctl("sii", "read", "-o", bus.dir + "/dump.bin")
            bus.ecatctl("state", "0")
            self.assertEqual(bus.stop_slave(), 0, bus.slave_output())
            r = subprocess.run([tshark, "-r", bus.capture, "-V", "-o", "gui.column.format:\"No.\",\"%m\""],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            bad = [line for line in r.stdout.splitlines() if "Malformed" in line or "Expert Info (Error" in line]
            self.assertEqual(bad, [], "\n".join(bad[:20]))
            self.assertIn("EtherCAT datagram", r.stdout)
            frames = subprocess.run([tshark, "-r", bus.capture, "-T", "fields", "-e", "frame.number"],
                                    stdout=subprocess.PIPE, text=True, timeout=60).stdout.split()
            self.assertGreater(len(frames), 20)  # requests and replies both recorded


if __name__ == "__main__":
    harness.main()
