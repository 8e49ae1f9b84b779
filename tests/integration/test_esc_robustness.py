"""Regression tests of issue 14 (robustness campaign), replayed over the wire as they were found: the exact
frames sent with a raw socket (scapy builds them), ecatctl to check that the master still gets through."""
import struct
import time
import unittest

import harness

APRD, APWR, FPRD, FPWR = 1, 2, 4, 5


class EscRobustness(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.bus = harness.Bus().__enter__()
        cls.sock = cls.bus.raw_socket()
        cls.idx = 0

    @classmethod
    def tearDownClass(cls):
        cls.sock.close()
        cls.bus.close()

    # -- raw datagrams ------------------------------------------------------------------------------
    def send(self, cmd, adp, ado, data):
        """One datagram in one frame; returns (data, wkc) of the reply."""
        EscRobustness.idx = (EscRobustness.idx + 1) & 0xFF
        idx = EscRobustness.idx
        frame = harness.ecat_frame([(cmd, idx, adp, ado, data)])
        for _ in range(3):
            reply = harness.exchange(self.sock, frame)  # ecatctl's earlier traffic is skipped
            if reply is not None:
                d = harness.parse_datagrams(reply)
                return d[0][4], d[0][5]
        self.fail(f"no answer to cmd {cmd} 0x{ado:04x}: {self.bus.slave_output()}")

    def station(self):
        data, wkc = self.send(APRD, 0, 0x0010, b"\x00\x00")
        self.assertEqual(wkc, 1)
        st = struct.unpack("<H", data)[0]
        if st == 0:
            st = 0x1001
            self.assertEqual(self.send(APWR, 0, 0x0010, struct.pack("<H", st))[1], 1)
        return st

    def require_firmware(self):
        """Takes the slave to PREOP (upload configures the mailbox from the SII first) with one SDO."""
        r = self.bus.ecatctl("--timeout", "200", "upload", "0", "0x1018", "1", check=False)
        if r.returncode != 0 and "not reached in time" in r.stderr:
            self.skipTest("ecat-slave runs without firmware")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.strip(), "0x000000fb (251)")

    # -- finding 1 ----------------------------------------------------------------------------------
    def test_sm_over_the_registers_does_not_lock_the_master_out(self):
        self.require_firmware()
        st = self.station()
        # SM4: start 0x0100, length 0x8000, buffered, enabled.
        _, wkc = self.send(FPWR, st, 0x0820, bytes.fromhex("0001008020000100"))
        self.assertEqual(wkc, 1)
        data, wkc = self.send(FPRD, st, 0x0820, bytes(8))
        self.assertEqual((wkc, data), (1, bytes.fromhex("0001008020000100")[:5] + data[5:6] + b"\x01\x00"))
        data, wkc = self.send(FPRD, st, 0x0130, bytes(2))
        self.assertEqual(wkc, 1)
        # The master and the stack still reach every register: scan, state and SDOs work.
        self.assertIn("PREOP", self.bus.ecatctl("scan").stdout)
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1018", "1").stdout.strip(), "0x000000fb (251)")
        self.bus.ecatctl("state", "0", "INIT")
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1018", "1").stdout.strip(), "0x000000fb (251)")
        # ... and the master can disable the SM again.
        st = self.station()
        self.assertEqual(self.send(FPWR, st, 0x0826, b"\x00")[1], 1)
        self.assertEqual(self.send(FPRD, st, 0x0826, b"\x00"), (b"\x00", 1))
        self.assertTrue(self.bus.slave_alive(), self.bus.slave_output())


    # -- finding 2 ----------------------------------------------------------------------------------
    def system_time(self, st):
        data, wkc = self.send(FPRD, st, 0x0910, bytes(8))
        self.assertEqual(wkc, 1)
        return struct.unpack("<Q", data)[0]

    def test_dc_speed_counter_start_zero_does_not_stop_the_clock(self):
        st = self.station()
        self.assertEqual(self.send(FPWR, st, 0x0930, b"\x00\x00")[1], 1)
        try:
            now = self.system_time(st)
            for i in range(5):  # the local copy about 2^30 ns ahead of the "reference": slow down
                self.assertEqual(self.send(FPWR, st, 0x0910, struct.pack("<Q", now - (1 << 30) + i * 1000000))[1], 1)
                time.sleep(0.001)
            # The local clock keeps its rate within the bounded correction: neither frozen nor doubled.
            outer0 = time.monotonic()
            t1 = self.system_time(st)
            inner0 = time.monotonic()
            time.sleep(0.2)
            inner1 = time.monotonic()
            t2 = self.system_time(st)
            outer1 = time.monotonic()
            self.assertGreaterEqual(t2 - t1, 0.5 * (inner1 - inner0) * 1e9, "the DC clock stopped")
            self.assertLessEqual(t2 - t1, 1.5 * (outer1 - outer0) * 1e9, "the DC clock runs too fast")
            # SYNC0 still comes: 1 ms cycle from 20 ms ahead; the next pulse time (0x0990) moves on.
            self.assertEqual(self.send(FPWR, st, 0x09A0, struct.pack("<II", 1000000, 0))[1], 1)
            start = self.system_time(st) + 20000000
            self.assertEqual(self.send(FPWR, st, 0x0990, struct.pack("<Q", start))[1], 1)
            self.assertEqual(self.send(FPWR, st, 0x0981, b"\x03")[1], 1)
            time.sleep(0.2)
            data, _ = self.send(FPRD, st, 0x0990, bytes(8))
            self.assertGreater(struct.unpack("<Q", data)[0], start, "SYNC0 never fired")
            self.assertTrue(self.bus.slave_alive(), self.bus.slave_output())
        finally:
            self.send(FPWR, st, 0x0981, b"\x00")
            self.send(FPWR, st, 0x0930, b"\x00\x10")


    # -- finding 4 ----------------------------------------------------------------------------------
    def test_esc_reset_restarts_the_firmware(self):
        self.require_firmware()  # one SDO: the firmware's mailbox has seen this master's first counter
        st = self.station()
        for c in b"RES":
            self.assertEqual(self.send(FPWR, st, 0x0040, bytes([c]))[1], 1)
        self.assertEqual(self.send(FPRD, st, 0x0130, bytes(2))[1], 0)  # the station address is reset too
        data, wkc = self.send(APRD, 0, 0x0130, bytes(2))
        self.assertEqual((wkc, data[0] & 0x0F), (1, 0x01))  # the ESC is in Init
        # The master starts over (mailbox, PREOP) and its next request (counter 1 again) is served, not
        # dropped as a repeat.
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1018", "1").stdout.strip(), "0x000000fb (251)")
        self.assertIn("PREOP", self.bus.ecatctl("state", "0").stdout)
        self.assertTrue(self.bus.slave_alive(), self.bus.slave_output())

    # -- finding 5 ----------------------------------------------------------------------------------
    def sii_command(self, st, command, word):
        self.assertEqual(self.send(FPWR, st, 0x0500, b"\x02")[1], 1)  # the EEPROM to the ECAT side
        self.assertEqual(self.send(FPWR, st, 0x0500, b"\x00")[1], 1)
        self.assertEqual(self.send(FPWR, st, 0x0502, struct.pack("<HI", command, word))[1], 1)
        for _ in range(100):
            data, wkc = self.send(FPRD, st, 0x0502, bytes(14))
            self.assertEqual(wkc, 1)
            status = struct.unpack_from("<H", data)[0]
            if not status & 0x8000:
                return status, data[6:14]
            time.sleep(0.001)
        self.fail("EEPROM interface stays busy")

    def test_eeprom_read_at_the_top_word_address_does_not_wrap(self):
        st = self.station()
        status, word0 = self.sii_command(st, 0x0100, 0)
        self.assertEqual(status & 0x6000, 0)
        self.assertNotEqual(word0[:4], b"\xff\xff\xff\xff")
        status, data = self.sii_command(st, 0x0100, 0xFFFFFFFE)
        self.assertEqual(status & 0x2000, 0x2000, f"no acknowledge error: 0x{status:04x}")
        self.assertEqual(data, b"\xff" * 8)
        # The next command clears the error bits.
        status, data = self.sii_command(st, 0x0100, 0)
        self.assertEqual(status & 0x6000, 0)
        self.assertEqual(data, word0)


if __name__ == "__main__":
    harness.main()
