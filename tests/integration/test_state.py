"""`ecatctl state` takes a slave to any state with the set-up that state needs (as IgH's `ethercat states`):
the mailbox SMs from the SII for PREOP, the bootstrap mailbox for BOOT, the process data SMs and FMMUs for
SAFEOP and OP, stepping through the states between. Also how slaves are named (a position that is not on
the line, a station address), and `foe write` without --name (the device's name from its SII)."""
import os
import re
import struct
import unittest
import zlib

import harness


def al_state(bus):
    return bus.ecatctl("state", "0").stdout.strip()


class StateVerb(unittest.TestCase):
    def setUp(self):
        self.bus = harness.Bus().__enter__()
        self.addCleanup(self.bus.close)
        self.assertEqual(al_state(self.bus), "INIT")  # the slave starts in INIT with SM0/SM1 off

    def go(self, target, expect):
        r = self.bus.ecatctl("state", "0", target, check=False)
        self.assertEqual(r.returncode, 0, f"state 0 {target}: {r.stderr}")
        self.assertEqual(r.stdout.strip(), expect)
        return r

    def sm(self, n):
        """SM n: start, length, control, activate (registers 0x0800 + 8n)."""
        out = self.bus.ecatctl("reg", "read", "0", f"0x{0x800 + 8 * n:04x}", "8").stdout
        b = bytes(int(x, 16) for x in re.findall(r"\b[0-9a-f]{2}\b", out.split(":", 1)[1])[:8])
        start, length, control, _, activate = struct.unpack("<HHBBB", b[:7])
        return start, length, control, activate & 1

    def test_init_to_preop_sets_up_the_standard_mailbox(self):
        self.go("preop", "PREOP")
        self.assertEqual(self.sm(0)[:2], (0x1000, 128))  # SII words 0x18/0x19
        self.assertEqual(self.sm(1)[:2], (0x1080, 128))
        self.assertEqual(self.sm(0)[3], 1)

    def test_init_to_op_steps_through_preop_and_safeop(self):
        r = self.go("op", "OP")
        self.assertIn("ecatctl pd", r.stderr)  # says that nothing keeps it in OP afterwards
        self.assertEqual(self.sm(2)[3], 1)  # process-data SMs set up as `pd` does
        self.assertEqual(self.sm(3)[3], 1)
        self.go("init", "INIT")

    def test_init_to_safeop_and_back_down(self):
        self.go("SAFEOP", "SAFEOP")
        self.go("PREOP", "PREOP")
        self.go("SAFEOP", "SAFEOP")
        self.go("INIT", "INIT")

    def test_boot_uses_the_bootstrap_mailbox_and_preop_comes_back_through_init(self):
        self.go("PREOP", "PREOP")
        self.go("BOOT", "BOOT")  # PREOP -> INIT -> bootstrap SMs -> BOOT
        self.assertEqual(self.sm(0)[:2], (0x1000, 1024))  # SII words 0x14/0x15
        self.assertEqual(self.sm(1)[:2], (0x1400, 1024))
        self.go("PREOP", "PREOP")  # BOOT -> INIT -> standard SMs -> PREOP
        self.assertEqual(self.sm(0)[:2], (0x1000, 128))

    def test_an_error_is_acknowledged_on_the_way(self):
        self.go("PREOP", "PREOP")
        self.bus.ecatctl("reg", "write", "0", "0x0120", "0x08", "0x00")  # PREOP -> OP: refused (0x0011)
        for _ in range(500):
            if "+ERR" in al_state(self.bus):
                break
        self.assertTrue(al_state(self.bus).startswith("PREOP +ERR 0x0011"))
        self.go("OP", "OP")

    def test_no_such_slave(self):
        r = self.bus.ecatctl("state", "5", check=False)
        self.assertEqual(r.returncode, 5, r.stderr)
        self.assertIn("there is no slave 5", r.stderr)
        self.assertIn("1 slave on the line", r.stderr)
        self.assertNotIn("working counter", r.stderr)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)  # one message
        r = self.bus.ecatctl("state", "5", "PREOP", check=False)
        self.assertEqual(r.returncode, 5, r.stderr)

    def test_station_address(self):
        self.bus.ecatctl("scan")  # assigns 0x1001
        r = self.bus.ecatctl("state", "--station", "0x1001", "PREOP", check=False)
        self.assertEqual((r.returncode, r.stdout.strip()), (0, "PREOP"), r.stderr)
        r = self.bus.ecatctl("state", "--station", "0x1005", check=False)
        self.assertEqual(r.returncode, 5, r.stderr)
        self.assertIn("station address 0x1005", r.stderr)

    def test_every_verb_takes_the_slave_as_dash_p_or_station(self):
        # IgH style -p N also for the verbs that take the slave as their first argument.
        self.assertEqual(self.bus.ecatctl("state", "-p", "0", "PREOP").stdout.strip(), "PREOP")
        self.assertEqual(self.bus.ecatctl("upload", "-p", "0", "0x1018", "1").stdout.split()[0], "0x000000fb")
        self.assertEqual(self.bus.ecatctl("upload", "--position=0", "0x1018", "1").stdout.split()[0], "0x000000fb")
        self.assertIn("0x0130", self.bus.ecatctl("reg", "read", "0x0130", "2", "-p", "0").stdout)
        self.bus.ecatctl("scan")
        for verb in (["upload", "0x1018", "1"], ["sdos", "-q"], ["diag"], ["pd", "-n", "5"]):
            r = self.bus.ecatctl(verb[0], "--station", "0x1001", *verb[1:], check=False)
            self.assertEqual(r.returncode, 0, f"{verb}: {r.stderr}")
            r = self.bus.ecatctl(verb[0], "-p", "3", *verb[1:], check=False)
            self.assertEqual(r.returncode, 5 if verb[0] in ("pd",) else r.returncode, f"{verb}: {r.stderr}")
            self.assertNotEqual(r.returncode, 0, f"{verb}: {r.stderr}")
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, f"{verb}: {r.stderr}")
        r = self.bus.ecatctl("pd", "-s", "0x1005", "-n", "5", check=False)
        self.assertEqual(r.returncode, 5, r.stderr)

    def test_foe_write_defaults_to_the_device_name(self):
        scan = self.bus.ecatctl("scan").stdout
        # identity, then the DC delay column (ns, or -), then the name
        m = re.search(r"^0\s+0x1001\s+\S+\s+0x([0-9a-f]{8}) 0x([0-9a-f]{8}) \S+ \S+ +(?:-|-?\d+) +(\S+)", scan, re.M)
        self.assertIsNotNone(m, scan)
        vendor, product, name = int(m.group(1), 16), int(m.group(2), 16), m.group(3)
        payload = bytes(i & 0xFF for i in range(3000))
        head = struct.pack("<IHHIIIII", 0x57464553, 1, 32, vendor, product, 0x01300000, len(payload), 0)
        path = os.path.join(self.bus.dir, "image.bin")  # a local name the device does not take
        with open(path, "wb") as f:
            f.write(head + struct.pack("<I", zlib.crc32(head + payload) & 0xFFFFFFFF) + payload)
        r = self.bus.ecatctl("foe", "write", path, check=False)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn(f"written to '{name}'", r.stderr)
        r = self.bus.ecatctl("foe", "write", path, "--name", "image.bin", check=False)
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("FoE error 0x8001", r.stderr)
        self.assertIn("device name", r.stderr)  # which names it takes
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)


ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


class SoemFirmUpdate(unittest.TestCase):
    """What SOEM's firm_update sample (and libethercat) sends: PREOP (standard mailbox), INIT, SM0/SM1 rewritten
    with the bootstrap mailbox from the SII WITHOUT disabling them first (FPWR of 8 bytes each, activate bit
    set), then BOOT. The slave stack deactivated SM0/SM1 through the PDI when it entered INIT (as Beckhoff's
    SSC and SOES do), so the ESC takes the new configuration and the slave reaches BOOT with the bootstrap
    mailbox (docs/decisions/esc.md, "SM configuration after a PDI deactivation")."""

    def firm_update_sequence(self, bus, boot_mailbox):
        self.assertEqual(bus.ecatctl("state", "0", "PREOP").stdout.strip(), "PREOP")
        self.assertEqual(bus.ecatctl("state", "0", "INIT").stdout.strip(), "INIT")
        (out_start, out_size), (in_start, in_size) = boot_mailbox
        for reg, start, size, control in ((0x800, out_start, out_size, 0x26), (0x808, in_start, in_size, 0x22)):
            b = struct.pack("<HHBBBB", start, size, control, 0, 1, 0)
            bus.ecatctl("reg", "write", "0", hex(reg), *(hex(x) for x in b))
        bus.ecatctl("reg", "write", "0", "0x0120", "0x03", "0x00")  # BOOT
        for _ in range(500):
            st = al_state(bus)
            if st.startswith("BOOT") or "+ERR" in st:
                return st
        return st

    def test_the_default_device_reaches_boot(self):
        with harness.Bus() as bus:
            st = self.firm_update_sequence(bus, ((0x1000, 1024), (0x1400, 1024)))
            self.assertEqual(st, "BOOT")
            self.assertEqual(self.sm(bus, 0), (0x1000, 1024))
            self.assertEqual(self.sm(bus, 1), (0x1400, 1024))

    def test_an_sm_still_active_on_the_pdi_side_keeps_its_configuration(self):
        # In PREOP the mailbox runs: writing SM0 while enabled changes nothing (ESC write protection), and the
        # slave keeps answering on the standard mailbox.
        with harness.Bus() as bus:
            self.assertEqual(bus.ecatctl("state", "0", "PREOP").stdout.strip(), "PREOP")
            b = struct.pack("<HHBBBB", 0x1000, 1024, 0x26, 0, 1, 0)
            bus.ecatctl("reg", "write", "0", "0x800", *(hex(x) for x in b))
            self.assertEqual(self.sm(bus, 0), (0x1000, 128))

    def sm(self, bus, n):
        """SM n: start, length (registers 0x0800 + 8n)."""
        out = bus.ecatctl("reg", "read", "0", f"0x{0x800 + 8 * n:04x}", "8").stdout
        b = bytes(int(x, 16) for x in re.findall(r"\b[0-9a-f]{2}\b", out.split(":", 1)[1])[:8])
        return struct.unpack("<HH", b[:4])

    def test_a_bootstrap_mailbox_equal_to_the_standard_one_lets_it_in(self):
        conf = os.path.join(ROOT, "od", "examples", "bootstrap-as-standard.conf")
        with harness.Bus(slave_args=["--config", conf]) as bus:
            st = self.firm_update_sequence(bus, ((0x1000, 128), (0x1080, 128)))
            self.assertEqual(st, "BOOT")


if __name__ == "__main__":
    harness.main()
