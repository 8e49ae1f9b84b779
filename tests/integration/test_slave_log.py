"""The slave tells what it does: one line on stderr per state change, refused AL request (with its AL status
code and name), 0x1010 save; --quiet and --log-level; SII drift warnings at start (an --eeprom with a bad
checksum or another identity than 0x1018, master-written SII words kept in the state directory) and
--reset-sii to go back to the generated SII."""
import os
import struct
import subprocess
import time
import unittest
import zlib

import harness


def wait_for(bus, text, timeout=5.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if text in bus.slave_output():
            return True
        time.sleep(0.05)
    return False


def refuse_op_from_init(bus):
    # AL control = Op written straight into the register, so the request is the same whatever `ecatctl state`
    # does first: Init -> Op is no valid transition (0x0011).
    bus.ecatctl("reg", "write", "0", "0x0120", "0x08", "0x00")
    for _ in range(100):
        r = bus.ecatctl("reg", "read", "0", "0x0130", "2")
        if "0x11" in r.stdout.lower() or "11 00" in r.stdout.lower():
            break
        time.sleep(0.02)


def sii_writes_file(path, words):
    body = b"SECATSII" + struct.pack("<I", len(words))
    for address, value in sorted(words.items()):
        body += struct.pack("<HH", address, value)
    with open(path, "wb") as f:
        f.write(body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF))


class SlaveLog(unittest.TestCase):
    def test_state_change_refused_request_and_parameter_save_are_logged(self):
        with harness.Bus() as bus:
            refuse_op_from_init(bus)
            self.assertTrue(wait_for(bus, "refused AL state request INIT -> OP: AL status code 0x0011"),
                            bus.slave_output())
            bus.ecatctl("reg", "write", "0", "0x0120", "0x11", "0x00")  # acknowledge, stay in Init
            bus.ecatctl("pd", "0", "-n", "20", "--cycle-us", "1000")  # up to Op and back to Pre-Op
            self.assertTrue(wait_for(bus, "AL state INIT -> PREOP"), bus.slave_output())
            self.assertTrue(wait_for(bus, "AL state SAFEOP -> OP"), bus.slave_output())
            bus.ecatctl("download", "0", "0x1010", "1", "0x65766173", "--type", "u32")
            self.assertTrue(wait_for(bus, "stored parameters saved (0x1010:1"), bus.slave_output())
            # The drive's diagnosis texts travel as text ids: ecatctl shows the whole text, once per message.
            diag = bus.ecatctl("diag", "0").stdout
            self.assertIn("Switch On Disabled", diag)
            self.assertNotIn("text id", diag)
            for l in diag.splitlines():
                self.assertLessEqual(l.count("Switch On Disabled"), 1, l)
            out = bus.slave_output()
            self.assertNotIn("watchdog expired in PREOP", out)  # the watchdog after leaving Op is no news
            line = [l for l in out.splitlines() if "refused AL state request" in l][0]
            # Journal-friendly: program name, level, no colour codes when not on a terminal.
            self.assertTrue(line.startswith("ecat-slave: warning: "), line)
            self.assertNotIn("\033[", out)
            self.assertIn("(Invalid requested state change)", line)

    def test_quiet_logs_errors_only(self):
        with harness.Bus(slave_args=["--quiet"]) as bus:
            refuse_op_from_init(bus)
            bus.ecatctl("reg", "write", "0", "0x0120", "0x11", "0x00")
            bus.ecatctl("pd", "0", "-n", "10", "--cycle-us", "1000")
            self.assertEqual(bus.stop_slave(), 0)
            out = bus.slave_output()
            self.assertNotIn("refused AL state request", out)
            self.assertNotIn("AL state INIT -> PREOP", out)

    def test_log_level_debug_adds_the_drive_states(self):
        with harness.Bus(slave_args=["--log-level", "debug"]) as bus:
            self.assertTrue(wait_for(bus, "debug: drive: Switch On Disabled"), bus.slave_output())


class SiiDrift(unittest.TestCase):
    def test_eeprom_with_another_identity_and_a_bad_checksum_is_warned_about(self):
        image = bytearray(harness.build_sii(vendor=0x00000002, product=0x12345678)[0])
        image[14] ^= 0xFF  # checksum of words 0-6 broken
        with harness.Bus(eeprom=bytes(image)) as bus:
            out = bus.slave_output()
            self.assertIn("SII checksum (word 7)", out)
            self.assertIn("SII vendor id 0x00000002 differs from 0x1018:01 0x000000FB", out)
            self.assertIn("SII product code 0x12345678 differs from 0x1018:02", out)

    def test_matching_eeprom_gets_no_warning(self):
        with harness.Bus(eeprom=harness.build_sii(serial=0)[0]) as bus:
            self.assertNotIn("differs from 0x1018", bus.slave_output())
            self.assertNotIn("SII checksum", bus.slave_output())

    def test_master_written_sii_words_are_announced_and_reset_sii_goes_back(self):
        with harness.Bus() as first:
            state = os.path.join(first.dir, "kept-state")
            os.makedirs(state)
            path = os.path.join(state, "sii-writes.bin")
            sii_writes_file(path, {0x0004: 0x0042, 0x0008: 0x0002})  # station alias and the vendor id
            with harness.Bus(slave_args=["--state-dir", state]) as bus:
                out = bus.slave_output()
                self.assertIn("word(s) a master wrote into the EEPROM, kept in " + path, out)
                self.assertIn("--reset-sii", out)
                self.assertIn("SII vendor id 0x00000002 differs from 0x1018:01", out)
            with harness.Bus(slave_args=["--state-dir", state, "--reset-sii"]) as bus:
                out = bus.slave_output()
                self.assertIn("removed " + path, out)
                self.assertNotIn("a master wrote", out)
                self.assertFalse(os.path.exists(path))


class PdoExclude(unittest.TestCase):
    """The ESI's Exclude, enforced: two RxPDOs that each map the controlword cannot be assigned together."""

    def test_two_rx_pdos_are_refused_with_0x06040043_and_the_esi_says_why(self):
        with harness.Bus() as bus:
            bus.ecatctl("upload", "0", "0x1000", "0")  # Init -> Pre-Op (mailbox from the SII)
            self.assertEqual(bus.ecatctl("upload", "0", "0x1c12", "2").stdout.split()[0], "0x1601")
            r = bus.ecatctl("download", "0", "0x1c12", "0", "2", "--type", "u8", check=False)
            self.assertEqual(r.returncode, 6, r.stdout + r.stderr)
            self.assertIn("0x06040043", r.stdout + r.stderr)
            self.assertEqual(bus.ecatctl("upload", "0", "0x1c12", "0").stdout.split()[0], "0x01")
            esi = os.path.join(bus.dir, "drive.xml")
            w = subprocess.run([bus.slave_bin, "--write-esi", esi, "--state-dir", os.path.join(bus.dir, "state")],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
            self.assertEqual(w.returncode, 0, w.stdout)
            with open(esi) as f:
                text = f.read()
            self.assertRegex(text, r"<RxPdo Sm=\"2\">\s*<Index>#x1600</Index>\s*<Name[^>]*>[^<]*</Name>\s*"
                                   r"<Exclude>#x1601</Exclude>\s*<Exclude>#x1602</Exclude>\s*<Exclude>#x1603</Exclude>")


if __name__ == "__main__":
    harness.main()
