"""FoE through ecatctl against the real ecat-slave: a firmware image written through BOOT, read back,
a bad image refused (needs the slave's firmware with its FoE server)."""
import os
import re
import struct
import unittest
import zlib

import harness


def firmware_image(vendor, product, version=0x01300000, size=5000):
    """The slave's image format (foe/image/include/foe/image.hpp): 32-byte header with CRC-32, payload."""
    payload = bytes((i * 7) & 0xFF for i in range(size))
    head = struct.pack("<IHHIIIII", 0x57464553, 1, 32, vendor, product, version, len(payload), 0)
    return head + struct.pack("<I", zlib.crc32(head + payload) & 0xFFFFFFFF) + payload


class Foe(unittest.TestCase):
    def setUp(self):
        self.bus = harness.bus_in_preop(self)
        scan = self.bus.ecatctl("scan").stdout
        m = re.search(r"^0\s+0x1001\s+\S+\s+0x([0-9a-f]{8}) 0x([0-9a-f]{8})", scan, re.M)
        self.assertIsNotNone(m, scan)
        self.vendor, self.product = int(m.group(1), 16), int(m.group(2), 16)
        name = self.bus.ecatctl("upload", "0", "0x1008", "0", "--type", "string").stdout.strip()
        self.device = name or "MAXPOS"

    def write_local(self, name, data):
        path = os.path.join(self.bus.dir, name)
        with open(path, "wb") as f:
            f.write(data)
        return path

    def test_firmware_round_trip_through_bootstrap(self):
        image = firmware_image(self.vendor, self.product, size=3333)
        path = self.write_local("fw.bin", image)
        r = self.bus.ecatctl("foe", "write", path, "--name", self.device, check=False)
        if r.returncode == 6 and "mailbox error 0x0002" in r.stderr:
            self.skipTest("ecat-slave serves no FoE")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(self.bus.ecatctl("state", "0").stdout.strip(), "INIT")  # back from BOOT
        out = os.path.join(self.bus.dir, "back.bin")
        self.bus.ecatctl("foe", "read", self.device, "-o", out)
        with open(out, "rb") as f:
            self.assertEqual(f.read(), image)

    def test_bad_image_and_missing_file_are_foe_errors(self):
        path = self.write_local("junk.bin", b"not a firmware image" * 10)
        r = self.bus.ecatctl("foe", "write", path, "--name", self.device, check=False)
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertRegex(r.stderr, r"FoE error 0x80[0-9a-f]{2}")
        r = self.bus.ecatctl("foe", "read", "no-such-file.bin", check=False)
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("FoE error 0x8001", r.stderr)

    def test_image_for_another_product_is_refused(self):
        path = self.write_local("other.bin", firmware_image(self.vendor, self.product ^ 0x00010000))
        r = self.bus.ecatctl("foe", "write", path, "--name", self.device, check=False)
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("FoE error 0x80", r.stderr)


if __name__ == "__main__":
    harness.main()
