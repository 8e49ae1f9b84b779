"""ecatctl sii read / sii write against the real ecat-slave's SII EEPROM."""
import os
import struct
import subprocess
import unittest

import harness


class Sii(unittest.TestCase):
    def test_dump_equals_the_served_image(self):
        image, end = harness.build_sii(serial=0x55AA, name="A longer device name to make the strings odd")
        with harness.Bus(eeprom=image) as bus:
            out = os.path.join(bus.dir, "dump.bin")
            bus.ecatctl("sii", "read", "-o", out)
            with open(out, "rb") as f:
                dump = f.read()
            self.assertEqual(dump, image[:end])
            bus.ecatctl("sii", "read", "--all", "-o", out)
            with open(out, "rb") as f:
                self.assertEqual(f.read(), image)
            # Hex dump form, first line.
            r = bus.ecatctl("sii", "read")
            first = " ".join(f"{b:02x}" for b in image[:16])
            self.assertEqual(r.stdout.split("\n")[0], "0x0000: " + first)

    def test_dump_equals_the_default_image(self):
        with harness.Bus() as bus:
            if not bus.slave_supports("--write-sii"):
                self.skipTest("ecat-slave cannot write out its SII image")
            served = os.path.join(bus.dir, "served.bin")
            subprocess.run([bus.slave_bin, "--write-sii", served, "--state-dir", os.path.join(bus.dir, "state")],
                           check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=30)
            with open(served, "rb") as f:
                image = f.read()
            out = os.path.join(bus.dir, "dump.bin")
            bus.ecatctl("sii", "read", "--all", "-o", out)
            with open(out, "rb") as f:
                self.assertEqual(f.read(), image)
            bus.ecatctl("sii", "read", "-o", out)
            with open(out, "rb") as f:
                chain = f.read()
            self.assertEqual(chain, image[:len(chain)])
            self.assertEqual(chain[-2:], b"\xff\xff")  # ends with the end category

    def test_write_changes_the_slave_and_its_file(self):
        image, end = harness.build_sii(serial=1)
        changed, _ = harness.build_sii(serial=0x12345678)
        with harness.Bus(eeprom=image) as bus:
            src = os.path.join(bus.dir, "new.bin")
            with open(src, "wb") as f:
                f.write(changed[:end])
            bus.ecatctl("sii", "write", src)
            r = bus.ecatctl("scan")
            self.assertIn("0x12345678", r.stdout)
            out = os.path.join(bus.dir, "dump.bin")
            bus.ecatctl("sii", "read", "-o", out)
            with open(out, "rb") as f:
                self.assertEqual(f.read(), changed[:end])
            bus.stop_slave()
            with open(bus.eeprom_path, "rb") as f:
                persisted = f.read()
            self.assertEqual(persisted[:end], changed[:end])

    def test_write_refuses_a_bad_checksum(self):
        image, end = harness.build_sii()
        bad = bytearray(image[:end])
        bad[14] ^= 0xFF
        with harness.Bus(eeprom=image) as bus:
            src = os.path.join(bus.dir, "bad.bin")
            with open(src, "wb") as f:
                f.write(bad)
            r = bus.ecatctl("sii", "write", src, check=False)
            self.assertEqual(r.returncode, 2)
            self.assertIn("checksum", r.stderr)
            odd = os.path.join(bus.dir, "odd.bin")
            with open(odd, "wb") as f:
                f.write(image[:end] + b"\x00")
            self.assertEqual(bus.ecatctl("sii", "write", odd, check=False).returncode, 2)
            # Nothing was written.
            out = os.path.join(bus.dir, "dump.bin")
            bus.ecatctl("sii", "read", "-o", out)
            with open(out, "rb") as f:
                self.assertEqual(f.read(), image[:end])

    def test_identity_words(self):
        image, _ = harness.build_sii(vendor=0xFB, product=0x11223344)
        with harness.Bus(eeprom=image) as bus:
            out = os.path.join(bus.dir, "dump.bin")
            bus.ecatctl("sii", "read", "-o", out)
            with open(out, "rb") as f:
                dump = f.read()
            self.assertEqual(struct.unpack_from("<II", dump, 0x10), (0xFB, 0x11223344))

    def test_decode_from_the_slave_and_from_a_file(self):
        image, end = harness.build_sii(product=0x0BADCAFE, name="DecodeMe")
        with harness.Bus(eeprom=image) as bus:
            r = bus.ecatctl("sii", "decode", check=False)
            if r.returncode == 2 and "decode" in r.stderr:
                self.skipTest("ecatctl built without the esi library")
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("product 0x0BADCAFE", r.stdout)
            self.assertIn('"DecodeMe"', r.stdout)
            self.assertIn("end of categories", r.stdout)
            path = os.path.join(bus.dir, "img.bin")
            with open(path, "wb") as f:
                f.write(image[:end])
            self.assertEqual(bus.ecatctl("sii", "decode", path).stdout, r.stdout)


if __name__ == "__main__":
    harness.main()
