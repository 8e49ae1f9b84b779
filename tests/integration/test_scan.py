"""ecatctl scan against the real ecat-slave: one slave, the identity its SII carries, its AL state."""
import re
import unittest

import harness

ROW = re.compile(r"^(\d+)\s+0x([0-9a-f]{4})\s+(\S+)\s+0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8})"
                 r"(?: +(?:-|-?\d+))? *(.*)$",  # then the DC delay in ns (- without DC) and the name
                 re.M)


def scan(bus):
    r = bus.ecatctl("scan")
    rows = ROW.findall(r.stdout)
    return r, rows


class Scan(unittest.TestCase):
    def test_finds_one_slave_with_the_identity_of_its_sii(self):
        image, _ = harness.build_sii(vendor=0x000000FB, product=0x30010000, revision=0x01200000, serial=0xA1B2C3D4)
        with harness.Bus(eeprom=image) as bus:
            r, rows = scan(bus)
            self.assertIn("1 slave\n", r.stdout)
            self.assertEqual(len(rows), 1, r.stdout)
            pos, station, _state, vendor, product, revision, serial, name = rows[0]
            self.assertEqual(name, "Soft slave")  # from the SII General/STRINGS categories
            self.assertEqual(pos, "0")
            self.assertEqual(station, "1001")
            self.assertEqual(int(vendor, 16), 0x000000FB)
            self.assertEqual(int(product, 16), 0x30010000)
            self.assertEqual(int(revision, 16), 0x01200000)
            self.assertEqual(int(serial, 16), 0xA1B2C3D4)
            # The address the scan assigned is the one the slave now answers to.
            r = bus.ecatctl("reg", "read", "--station", "0x1001", "0x10", "--type", "u16")
            self.assertEqual(r.stdout.strip(), "0x1001 (4097)")
            self.assertTrue(bus.slave_alive())

    def test_default_image_is_the_maxpos_identity(self):
        with harness.Bus() as bus:
            if "no EEPROM image" in bus.slave_output():
                self.skipTest("ecat-slave serves no SII image without --eeprom")
            _, rows = scan(bus)
            self.assertEqual(len(rows), 1)
            _, _, state, vendor, product, _revision, _serial, name = rows[0]
            self.assertTrue(name, "no device name from the SII")
            self.assertEqual(int(vendor, 16), 0x000000FB)  # maxon motor ag
            self.assertEqual(int(product, 16), 0x30010000)  # MAXPOS 50/5 (MAXPOS firmware specification §7.2.4.3)
            self.assertRegex(state, r"^(INIT|PREOP|SAFEOP|OP|BOOT)")

    def test_both_link_backends_on_the_master_side(self):
        image, _ = harness.build_sii(serial=0x77)
        with harness.Bus(eeprom=image) as bus:
            for backend in ("pcap", "packet"):
                r = bus.ecatctl("--backend", backend, "scan")
                rows = ROW.findall(r.stdout)
                self.assertEqual(len(rows), 1, f"{backend}: {r.stdout}")
                self.assertEqual(int(rows[0][6], 16), 0x77)
                r = bus.ecatctl("--backend", backend, "sii", "read", "-o", bus.dir + f"/{backend}.bin")
            with open(bus.dir + "/pcap.bin", "rb") as a, open(bus.dir + "/packet.bin", "rb") as b:
                self.assertEqual(a.read(), b.read())

    def test_scan_twice_gives_the_same_answer(self):
        image, _ = harness.build_sii(serial=7)
        with harness.Bus(eeprom=image) as bus:
            first = scan(bus)[1]
            second = scan(bus)[1]
            self.assertEqual(first, second)


if __name__ == "__main__":
    harness.main()
