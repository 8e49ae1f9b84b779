"""The real ecat-slave starting over a state directory with crafted or left-over files (issue 14): a bad file
is reported and the defaults run (finding 3: a 40-byte parameters.bin with valid CRCs and a record count of
0xFFFFFFFF threw std::bad_alloc at every start); temporaries an interrupted save left behind are removed at
the start (finding 7)."""
import os
import shutil
import struct
import tempfile
import unittest
import zlib

import harness


def out_dir():
    return os.environ.get("ECAT_TEST_OUT") or None


def u32(bus, index, sub):
    return int(bus.ecatctl("upload", "0", hex(index), str(sub), "--type", "u32").stdout.split()[0], 16)


def parameters_file(vendor, product, revision, count, payload=b""):
    """od/include/od/store.hpp layout: 36 header bytes, then the CRC-32 of them; valid CRCs throughout."""
    head = b"SECATPRM" + struct.pack("<HHIIIIII", 1, 40, vendor, product, revision, count, len(payload),
                                     zlib.crc32(payload) & 0xFFFFFFFF)
    return head + struct.pack("<I", zlib.crc32(head) & 0xFFFFFFFF) + payload


class StateDirectory(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(dir=out_dir())
        self.addCleanup(shutil.rmtree, self.dir, True)
        self.state = os.path.join(self.dir, "state")

    def defaults(self):
        """Identity and the default following error window (0x6065) of a slave over an empty directory."""
        with harness.Bus(slave_args=["--state-dir", os.path.join(self.dir, "clean")]) as bus:
            return (u32(bus, 0x1018, 1), u32(bus, 0x1018, 2), u32(bus, 0x1018, 3)), u32(bus, 0x6065, 0)

    def test_parameters_with_an_impossible_record_count_start_with_the_defaults(self):
        identity, default_window = self.defaults()
        os.makedirs(self.state)
        path = os.path.join(self.state, "parameters.bin")
        with open(path, "wb") as f:
            f.write(parameters_file(*identity, 0xFFFFFFFF))
        self.assertEqual(os.path.getsize(path), 40)
        with harness.Bus(slave_args=["--state-dir", self.state]) as bus:
            # It starts (the harness waited for it to answer), it says why the file is not used ...
            self.assertIn("not used", bus.slave_output())
            self.assertIn("records", bus.slave_output())
            # ... it runs the defaults, and it runs: OP with process data.
            self.assertEqual(u32(bus, 0x6065, 0), default_window)
            r = bus.ecatctl("pd", "0", "-n", "100")
            self.assertIn("state: OP\n", r.stdout)
            # Storing again replaces the bad file with a good one.
            bus.ecatctl("download", "0", "0x6065", "0", "0x4321", "--type", "u32")
            bus.ecatctl("download", "0", "0x1010", "1", "save", "--type", "string")
            self.assertTrue(bus.slave_alive())
        with harness.Bus(slave_args=["--state-dir", self.state]) as bus:
            self.assertEqual(u32(bus, 0x6065, 0), 0x4321)
            self.assertNotIn("not used", bus.slave_output())

    def test_temporaries_of_interrupted_saves_are_removed_at_the_start(self):
        stale = [os.path.join(self.state, n) for n in ("parameters.bin.tmp", "sii-writes.bin.tmp")]
        stale += [os.path.join(self.state, "firmware", n) for n in ("slot0.bin.tmp", "slot1.bin.tmp", "active.tmp")]
        os.makedirs(os.path.join(self.state, "firmware"))
        for p in stale:
            with open(p, "wb") as f:
                f.write(b"SECATPRM half written")
        with harness.Bus(slave_args=["--state-dir", self.state]) as bus:
            self.assertEqual([p for p in stale if os.path.exists(p)], [])
            self.assertIn("left by an interrupted save", bus.slave_output())
            # The slave runs and a save now works as usual.
            bus.ecatctl("download", "0", "0x1010", "1", "save", "--type", "string")
            self.assertTrue(os.path.exists(os.path.join(self.state, "parameters.bin")))
            self.assertEqual([p for p in stale if os.path.exists(p)], [])


if __name__ == "__main__":
    harness.main()
