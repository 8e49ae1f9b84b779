"""Frames crafted with scapy that a real master would never send: the slave survives each one and
answers the next good frame (ETG.1000.4 frame structure)."""
import struct
import unittest

import harness

APRD, BRD = 1, 7


def good(idx):
    return harness.ecat_frame([(APRD, idx, 0, 0x0000, b"\x00\x00")])


class Malformed(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        image, _ = harness.build_sii()
        cls.bus = harness.Bus(eeprom=image).__enter__()
        cls.sock = cls.bus.raw_socket()

    @classmethod
    def tearDownClass(cls):
        cls.sock.close()
        cls.bus.close()

    def assert_still_answers(self, idx):
        self.assertTrue(self.bus.slave_alive(), self.bus.slave_output())
        # Drain anything the bad frame produced, then a good one must come back processed.
        for _ in range(5):
            reply = harness.exchange(self.sock, good(idx))
            self.assertIsNotNone(reply, "no answer to a good frame after a bad one")
            d = harness.parse_datagrams(reply)
            if d and d[0][1] == idx:
                break
        else:
            self.fail("the reply to the good frame never came")
        self.assertEqual(len(d), 1)
        cmd, _, adp, ado, _data, wkc = d[0]
        self.assertEqual((cmd, adp, ado, wkc), (APRD, 1, 0, 1))
        self.assertTrue(reply[6] & 0x02, "source MAC bit 1 not set by the slave")

    def test_good_frame_baseline(self):
        self.assert_still_answers(0x10)

    def test_runt_frame_is_answered_at_its_length(self):
        frame = harness.ecat_frame([(BRD, 0x11, 0, 0, b"\x00")], pad=False)  # 29 bytes, no padding
        reply = harness.exchange(self.sock, frame)
        self.assertIsNotNone(reply)
        self.assertEqual(len(reply), len(frame))
        self.assertEqual(harness.parse_datagrams(reply)[0][5], 1)

    def test_truncated_datagram(self):
        # Header claims 14 bytes of datagrams, the frame ends inside the first one.
        payload = struct.pack("<H", 14 | 0x1000) + struct.pack("<BBHH", APRD, 0x21, 0, 0x0000)
        harness.exchange(self.sock, harness.ether(payload, pad=False), timeout=0.2)
        self.assert_still_answers(0x22)
        # Same, padded to 60 bytes with zeros that do not belong to the datagram.
        payload = struct.pack("<H", 40 | 0x1000) + struct.pack("<BBHHHH", APRD, 0x23, 0, 0, 30, 0)
        harness.exchange(self.sock, harness.ether(payload, pad=False), timeout=0.2)
        self.assert_still_answers(0x24)

    def test_wrong_lengths(self):
        # Datagram length larger than the EtherCAT header length.
        body = struct.pack("<BBHHHH", APRD, 0x31, 0, 0, 200, 0) + b"\x00" * 4
        harness.exchange(self.sock, harness.ether(struct.pack("<H", len(body) | 0x1000) + body), timeout=0.2)
        self.assert_still_answers(0x32)
        # EtherCAT header length larger than the frame.
        body = struct.pack("<BBHHHH", APRD, 0x33, 0, 0, 2, 0) + b"\x00" * 4
        harness.exchange(self.sock, harness.ether(struct.pack("<H", 0x7FF | 0x1000) + body), timeout=0.2)
        self.assert_still_answers(0x34)
        # More bit set on the last datagram.
        body = struct.pack("<BBHHHH", APRD, 0x35, 0, 0, 2 | 0x8000, 0) + b"\x00" * 4
        harness.exchange(self.sock, harness.ether(struct.pack("<H", len(body) | 0x1000) + body), timeout=0.2)
        self.assert_still_answers(0x36)
        # Length 0 header, and a frame that stops right after the EtherType.
        harness.exchange(self.sock, harness.ether(struct.pack("<H", 0x1000)), timeout=0.2)
        harness.exchange(self.sock, harness.ether(b"", pad=False), timeout=0.2)
        self.assert_still_answers(0x37)
        # Not a DLPDU (type 4) and a reserved bit set.
        body = struct.pack("<BBHHHH", APRD, 0x38, 0, 0, 2, 0) + b"\x00" * 4
        harness.exchange(self.sock, harness.ether(struct.pack("<H", len(body) | 0x4000) + body), timeout=0.2)
        self.assert_still_answers(0x39)

    def test_unknown_command(self):
        for cmd in (15, 0x20, 0xFF):
            frame = harness.ecat_frame([(cmd, 0x40, 0, 0x0000, b"\x11\x22")])
            reply = harness.exchange(self.sock, frame, timeout=0.3)
            if reply is not None:
                d = harness.parse_datagrams(reply)
                if d and d[0][1] == 0x40:
                    self.assertEqual(d[0][5], 0, f"command {cmd} counted")
                    self.assertEqual(d[0][4], b"\x11\x22", f"command {cmd} changed the data")
            self.assert_still_answers(0x41)

    def test_many_datagrams_and_largest_frame(self):
        dgs = [(APRD, i, 0, 0x0000, b"\x00") for i in range(100)]
        reply = harness.exchange(self.sock, harness.ecat_frame(dgs))
        self.assertIsNotNone(reply)
        d = harness.parse_datagrams(reply)
        self.assertEqual(len(d), 100)
        self.assertTrue(all(x[5] == 1 for x in d))
        big = harness.ecat_frame([(BRD, 0x50, 0, 0x1000, b"\x00" * 1486)])
        self.assertEqual(len(big), 1514)
        reply = harness.exchange(self.sock, big)
        self.assertIsNotNone(reply)
        self.assertEqual(len(reply), 1514)
        self.assert_still_answers(0x51)


if __name__ == "__main__":
    harness.main()
