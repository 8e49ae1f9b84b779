"""Frames crafted with scapy that a real master would never send: the slave survives each one and
answers the next good frame (ETG.1000.4 frame structure)."""
import socket
import struct
import time
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

    def test_runt_frame_is_answered_padded(self):
        # A veth does not pad: the slave's link pads the runt to 60 bytes, as the master's NIC would have on a
        # wire, and the reply comes back at that length (docs/decisions/esc.md, "Frame tolerance").
        frame = harness.ecat_frame([(BRD, 0x11, 0, 0, b"\x00")], pad=False)  # 29 bytes, no padding
        reply = harness.exchange(self.sock, frame)
        self.assertIsNotNone(reply)
        self.assertEqual(len(reply), 60)
        self.assertEqual(reply[29:], b"\x00" * 31)
        self.assertEqual(harness.parse_datagrams(reply)[0][5], 1)

    def test_header_length_not_evaluated(self):
        # libethercat writes the length of the whole frame into the EtherCAT header; an ESC ignores the field
        # and walks the datagrams by their own headers.
        for hdr_len in (60, 0x7FF, 0):
            frame = bytearray(harness.ecat_frame([(APRD, 0x12, 0, 0x0000, b"\x00\x00")]))
            struct.pack_into("<H", frame, 14, hdr_len | 0x1000)
            reply = harness.exchange(self.sock, bytes(frame))
            self.assertIsNotNone(reply, f"no answer with header length {hdr_len}")
            self.assertEqual(struct.unpack_from("<H", reply, 14)[0] & 0x7FF, hdr_len)
            cmd, idx, adp, lf = struct.unpack_from("<BBH2xH", reply, 16)
            wkc = struct.unpack_from("<H", reply, 16 + 12)[0]
            self.assertEqual((cmd, idx, adp, wkc), (APRD, 0x12, 1, 1), f"header length {hdr_len}")

    def test_padding(self):
        # Up to 64 bytes after the last datagram are padding; more is a frame length error: the frame is lost
        # (ESC datasheet section I, Table 57).
        body = harness.ecat_frame([(APRD, 0x13, 0, 0x0000, b"\x00\x00")], pad=False)
        reply = harness.exchange(self.sock, body + b"\x00" * 64)
        self.assertIsNotNone(reply)
        self.assertEqual(len(reply), len(body) + 64)
        frame = harness.ecat_frame([(APRD, 0x14, 0, 0x0000, b"\x00\x00")], pad=False) + b"\x00" * 65
        reply = harness.exchange(self.sock, frame, timeout=0.3)
        self.assertTrue(reply is None or harness.parse_datagrams(reply)[0][1] != 0x14, "answered a length error")
        self.assert_still_answers(0x15)

    def test_udp(self):
        # EtherCAT in IPv4/UDP to port 0x88A4 (ESC datasheet section I, UDP/IP): processed, UDP checksum cleared.
        ecat = harness.ecat_frame([(APRD, 0x16, 0, 0x0000, b"\x00\x00")], pad=False)[14:]
        udp = struct.pack(">HHHH", 0x88A4, 0x88A4, 8 + len(ecat), 0xBEEF) + ecat
        ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), 1, 0, 64, 17, 0, bytes([10, 0, 0, 1]),
                         bytes([10, 0, 0, 255]))
        frame = b"\xff" * 6 + b"\x01" * 6 + b"\x08\x00" + ip + udp
        s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(0x0800))
        try:
            s.bind((self.bus.iface, 0))
            reply = None
            s.send(frame)
            deadline = time.monotonic() + 1.0
            while reply is None and time.monotonic() < deadline:
                s.settimeout(max(0.01, deadline - time.monotonic()))
                try:
                    data, addr = s.recvfrom(2048)
                except socket.timeout:
                    break
                if addr[2] != harness.PACKET_OUTGOING and data[6] & 0x02:
                    reply = data
        finally:
            s.close()
        self.assertIsNotNone(reply, "no answer to EtherCAT in UDP")
        self.assertEqual(reply[12:14], b"\x08\x00")
        self.assertEqual(struct.unpack_from(">H", reply, 40)[0], 0, "UDP checksum not cleared")
        cmd, idx, adp = struct.unpack_from("<BBH", reply, 44)
        wkc = struct.unpack_from("<H", reply, 44 + 12)[0]
        self.assertEqual((cmd, idx, adp, wkc), (APRD, 0x16, 1, 1))

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
