"""Interoperability: SDO downloads exactly as KickCAT's master library sends them, over the veth pair into the
real ecat-slave, then read back with ecatctl.

KickCAT (lib/src/CoE/mailbox/request.cc, SDOMessage) builds a download of more than 4 bytes that fits one
mailbox as a normal initiate with the size indicator CLEAR: mailbox header (length 10 + n, address 0,
channel/priority 0, type CoE, counter 1..7), CoE header 0x2000 (SDO request), command 0x20 (0x30 with complete
access), index, subindex, Complete Size n (u32), the n data bytes; the rest of the SM0 buffer is zero. It takes
the 0x60/0x70 initiate response as success and sends no segment. The slave must store the value then
(docs/decisions/coe.md, "Normal download with the size indicator clear")."""
import struct
import unittest

import harness
from test_coe_errors import MBX_COE, COE_SDO_REQ, COE_SDO_RESP, RawMailbox, Slave


def kickcat_download(index, sub, data, complete_access=False):
    """The CoE part of KickCAT's SDOMessage for a download of 5..(mailbox - 16) bytes."""
    assert len(data) > 4
    cmd = (1 << 5) | (0x10 if complete_access else 0)  # command 1 (download), s = 0, e = 0, size bits 0
    return struct.pack("<HBHBI", COE_SDO_REQ << 12, cmd, index, sub, len(data)) + data


class KickCatDownloads(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.bus, cls.mbx = RawMailbox.on_started_slave()
        cls.counter = 0

    @classmethod
    def tearDownClass(cls):
        cls.mbx.close()
        cls.bus.close()

    def kickcat(self, payload):
        KickCatDownloads.counter = KickCatDownloads.counter % 7 + 1  # KickCAT's nextCounter(): 1..7
        self.mbx.drain()
        self.mbx.send(MBX_COE, payload, counter=self.counter)
        reply = self.mbx.receive()
        self.assertIsNotNone(reply, "no mailbox answer")
        mtype, p = reply
        self.assertEqual(mtype, MBX_COE, p.hex())
        return p

    def assert_download_response(self, p, cmd, index, sub):
        self.assertEqual(p[1] >> 4, COE_SDO_RESP, p.hex())
        self.assertEqual(p[2], cmd, p.hex())
        self.assertEqual(struct.unpack_from("<HB", p, 3), (index, sub), p.hex())

    def test_pdo_assignment_by_complete_access_is_changed(self):
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1C12", "1").stdout.split()[0], "0x1600")
        # 0x1C12 := {0x1601}: SI0 = 1 (16 bits with complete access), entry 1, and entry 2 (past the count,
        # so "don't care") - 6 bytes, more than an expedited transfer carries.
        image = struct.pack("<BBHH", 1, 0, 0x1601, 0x1601)
        p = self.kickcat(kickcat_download(0x1C12, 0, image, complete_access=True))
        self.assert_download_response(p, 0x70, 0x1C12, 0)
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1C12", "0").stdout.split()[0], "0x01")
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1C12", "1").stdout.split()[0], "0x1601")
        # Back to 0x1600 the same way.
        image = struct.pack("<BBHH", 1, 0, 0x1600, 0x1601)
        self.assert_download_response(self.kickcat(kickcat_download(0x1C12, 0, image, True)), 0x70, 0x1C12, 0)
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1C12", "1").stdout.split()[0], "0x1600")

    def test_record_by_complete_access_is_stored(self):
        # 0x607D software position limits: SI0 (16 bits, read-only, skipped) + two INT32 = 10 bytes.
        image = struct.pack("<BBii", 2, 0, -100000, 250000)
        self.assert_download_response(self.kickcat(kickcat_download(0x607D, 0, image, True)), 0x70, 0x607D, 0)
        self.assertIn("(-100000)", self.bus.ecatctl("upload", "0", "0x607D", "1", "--type", "i32").stdout)
        self.assertIn("(250000)", self.bus.ecatctl("upload", "0", "0x607D", "2", "--type", "i32").stdout)

    def test_announced_size_above_the_entry_is_refused_not_acknowledged(self):
        # 0x1C12 holds at most SI0 + its entries; 112 bytes (the largest KickCAT sends in a 128-byte mailbox)
        # cannot be stored: abort 0x06070012, and the assignment is unchanged.
        before = self.bus.ecatctl("upload", "0", "0x1C12", "0", "--complete").stdout
        image = struct.pack("<BBH", 1, 0, 0x1601) + bytes(108)
        p = self.kickcat(kickcat_download(0x1C12, 0, image, complete_access=True))
        self.assertEqual(p[2], 0x80, p.hex())
        self.assertEqual(struct.unpack_from("<I", p, 6)[0], 0x06070012, p.hex())
        self.assertEqual(self.bus.ecatctl("upload", "0", "0x1C12", "0", "--complete").stdout, before)


if __name__ == "__main__":
    harness.main()
