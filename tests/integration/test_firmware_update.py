"""`ecatctl firmware-update` against the real ecat-slave over the veth pair: the seed's update procedure
(BOOT, FoE write, INIT, restart, revision check) changing the revision everywhere, and every way it can go
wrong on the wire: wrong password, an image for another product, a corrupted image, a transfer cut off
half-way, the slave killed while it stores the image, path-like file names, a write outside Bootstrap.
After each failure the old firmware must still run (SII revision, 0x1018:03, 0x100A)."""
import os
import re
import shutil
import signal
import struct
import subprocess
import tempfile
import time
import unittest
import zlib

import harness

ROW = re.compile(r"^0\s+0x1001\s+(\S+)\s+0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8})", re.M)
NEW_VERSION = 0x01300000


def firmware_image(vendor, product, version, size=6000):
    """foe/image/include/foe/image.hpp: 32-byte header (magic, versions, identity, length, flags, CRC-32)."""
    payload = bytes((i * 7 + (i >> 8)) & 0xFF for i in range(size))
    head = struct.pack("<IHHIIIII", 0x57464553, 1, 32, vendor, product, version, len(payload), 0)
    return head + struct.pack("<I", zlib.crc32(head + payload) & 0xFFFFFFFF) + payload


def version_text(version):
    return f"{version >> 16:04X}h"


class FirmwareUpdate(unittest.TestCase):
    def start_bus(self, state_dir=None):
        args = ["--state-dir", state_dir] if state_dir else []
        bus = harness.Bus(slave_args=args).__enter__()
        self.addCleanup(bus.close)
        return bus

    def setUp(self):
        self.bus = self.start_bus()
        scan = self.bus.ecatctl("scan").stdout
        m = ROW.search(scan)
        self.assertIsNotNone(m, scan)
        self.vendor, self.product, self.revision = (int(m.group(i), 16) for i in (2, 3, 4))
        self.assertNotEqual(self.revision, NEW_VERSION)

    # -- helpers -----------------------------------------------------------------------------------
    def write_local(self, name, data, bus=None):
        path = os.path.join((bus or self.bus).dir, name)
        with open(path, "wb") as f:
            f.write(data)
        return path

    def good_image(self, version=NEW_VERSION, size=6000):
        return firmware_image(self.vendor, self.product, version, size)

    def update(self, *args, bus=None):
        return (bus or self.bus).ecatctl("firmware-update", *args, check=False)

    def assert_runs(self, version, bus=None):
        """The SII, 0x1018:03 and 0x100A all report `version`."""
        bus = bus or self.bus
        m = ROW.search(bus.ecatctl("scan").stdout)
        self.assertEqual(int(m.group(4), 16), version, "SII revision")
        self.assertEqual(bus.ecatctl("upload", "0", "0x1018", "3").stdout.split()[0], f"0x{version:08x}")
        self.assertEqual(bus.ecatctl("upload", "0", "0x100a", "0", "--type", "string").stdout.strip(),
                         version_text(version))

    def assert_old_firmware(self, bus=None):
        self.assert_runs(self.revision, bus)

    # -- the good path -----------------------------------------------------------------------------
    def test_full_update_changes_the_revision_everywhere(self):
        path = self.write_local("fw.bin", self.good_image(size=100_000))
        r = self.update(path)
        self.assertEqual(r.returncode, 0, r.stderr + self.bus.slave_output())
        self.assertEqual(r.stdout.strip(), f"0x{NEW_VERSION:08x}")
        self.assertIn("BOOT", r.stderr)
        self.assertIn("device restarted", r.stderr)
        self.assertIn(f"0x{self.revision:08x} -> 0x{NEW_VERSION:08x}", r.stderr)
        self.assert_runs(NEW_VERSION)
        # And once more to a third version, from the image the slave now runs.
        path = self.write_local("fw2.bin", self.good_image(0x01400000, size=3000))
        r = self.update(path)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assert_runs(0x01400000)

    def test_foe_write_shows_progress(self):
        path = self.write_local("fw.bin", self.good_image(size=50_000))
        r = self.bus.ecatctl("foe", "write", path, "--name", "MAXPOS", "--progress")
        lines = [x for x in r.stderr.splitlines() if "bytes" in x and "%" in x]
        self.assertGreaterEqual(len(lines), 2, r.stderr)
        self.assertRegex(lines[-1], r"50032/50032 bytes 100% [0-9.]+ [kM]B/s")
        # Without --progress and without a terminal: no progress lines.
        r = self.bus.ecatctl("foe", "write", path, "--name", "MAXPOS")
        self.assertNotIn("%", r.stderr)

    # -- refused by the slave ----------------------------------------------------------------------
    def test_wrong_password(self):
        path = self.write_local("fw.bin", self.good_image())
        r = self.update(path, "--password", "0x1234")
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("FoE error 0x800a", r.stderr)
        self.assertIn("No rights", r.stderr)
        self.assert_old_firmware()

    def test_image_for_another_product(self):
        path = self.write_local("other.bin", firmware_image(self.vendor, self.product ^ 0x00010000, NEW_VERSION))
        # Refused before anything is sent: a bad input file (exit 2).
        r = self.update(path)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertRegex(r.stderr, f"is for vendor 0x[0-9a-f]{{8}} product 0x{self.product ^ 0x00010000:08x}, "
                                   "this device is")
        self.assertEqual(self.bus.ecatctl("state", "0").stdout.split()[0], "PREOP")  # never went to BOOT
        # Sent anyway: the slave refuses it with 0x800D at its first DATA packet.
        r = self.update(path, "--force")
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("FoE error 0x800d", r.stderr)
        self.assertIn("another product", r.stderr)
        self.assert_old_firmware()

    def test_corrupted_image(self):
        image = bytearray(self.good_image(size=20_000))
        image[5000] ^= 0x40  # one payload bit: the CRC no longer matches
        path = self.write_local("bad.bin", bytes(image))
        r = self.update(path)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("not a valid firmware image", r.stderr)
        r = self.update(path, "--force")
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("FoE error 0x800c", r.stderr)
        self.assertIn("device back in INIT", r.stderr)
        self.assert_old_firmware()

    def test_bad_image_file_is_a_usage_error_before_the_link_is_opened(self):
        path = self.write_local("junk.bin", b"not an image")
        r = subprocess.run([self.bus.ecatctl_bin, "--iface", "nosuchif0", "firmware-update", path],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("not a firmware image", r.stderr)

    def test_path_like_file_names(self):
        path = self.write_local("fw.bin", self.good_image())
        for name in ("../x", "a/b", "..", "/MAXPOS", "MAXPOS\\x"):
            with self.subTest(name=name):
                r = self.update(path, "--name", name)
                self.assertEqual(r.returncode, 6, r.stderr)
                self.assertIn("FoE error 0x8002", r.stderr)
                self.assertIn("Access denied", r.stderr)
        # A name that is well-formed but not a firmware file of this device: not found.
        r = self.update(path, "--name", "other.bin")
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("FoE error 0x8001", r.stderr)
        self.assert_old_firmware()
        # The seed's firmware file name pattern is accepted as well as the device name.
        r = self.update(path, "--name", "MAXPOS_0130h_3001h_0000h_0000h.bin")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assert_runs(NEW_VERSION)

    def test_write_outside_bootstrap_is_refused(self):
        self.bus.ecatctl("upload", "0", "0x1000", "0")  # INIT -> PREOP with the mailbox from the SII
        self.assertEqual(self.bus.ecatctl("state", "0").stdout.split()[0], "PREOP")
        path = self.write_local("fw.bin", self.good_image())
        r = self.update(path, "--no-boot")
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("FoE error 0x8008", r.stderr)  # Bootstrap only (docs/decisions/foe.md)
        self.assertEqual(self.bus.ecatctl("state", "0").stdout.split()[0], "PREOP")
        self.assert_old_firmware()

    def test_device_refusing_boot_is_named_with_its_al_status_code(self):
        # The SII announces a bootstrap mailbox the slave does not have (SM0 512 bytes instead of its
        # 1024): the master sets up what the SII says and the slave refuses INIT -> BOOT with 0x0015.
        sii = os.path.join(self.bus.dir, "sii.bin")
        subprocess.run([self.bus.slave_bin, "--state-dir", os.path.join(self.bus.dir, "none"), "--write-sii", sii],
                       check=True, timeout=30, stdout=subprocess.DEVNULL)
        with open(sii, "rb") as f:
            image = bytearray(f.read())
        self.assertEqual(struct.unpack_from("<H", image, 0x15 * 2)[0], 1024)
        struct.pack_into("<H", image, 0x15 * 2, 512)
        bus = harness.Bus(eeprom=bytes(image)).__enter__()
        self.addCleanup(bus.close)
        r = self.update(self.write_local("fw.bin", self.good_image(), bus), bus=bus)
        self.assertEqual(r.returncode, 6, r.stderr)
        self.assertIn("device refused BOOT: stays in INIT, AL status code 0x0015", r.stderr)
        self.assert_old_firmware(bus)

    # -- interrupted -------------------------------------------------------------------------------
    def start_update(self, path, bus=None):
        bus = bus or self.bus
        return subprocess.Popen([bus.ecatctl_bin, "--iface", bus.iface, "firmware-update", path, "--progress"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    @staticmethod
    def stop(proc):
        proc.kill()
        proc.communicate()

    def wait_for_line(self, proc, pattern, timeout=60):
        """Reads the child's stderr until a line matches; returns everything read."""
        seen = []
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            line = proc.stderr.readline()
            if not line:
                break
            seen.append(line)
            if re.search(pattern, line):
                return "".join(seen)
        self.stop(proc)
        self.fail(f"no line matching {pattern!r}: {''.join(seen)}")

    def test_transfer_cut_off_half_way_then_a_new_update_works(self):
        path = self.write_local("big.bin", self.good_image(size=2 << 20))
        proc = self.start_update(path)
        self.wait_for_line(proc, r"bytes (4|5|6)\d% ")
        self.stop(proc)  # the master vanishes mid-transfer: no ERR, no INIT
        self.assertEqual(self.bus.ecatctl("state", "0").stdout.split()[0], "BOOT")
        self.bus.ecatctl("state", "0", "INIT")  # BOOT -> INIT: the device restarts, the half image is dropped
        self.assert_old_firmware()
        # A new update from BOOT works too (firmware-update resets a device it finds in BOOT first).
        proc = self.start_update(path)
        self.wait_for_line(proc, r"bytes [1-3]\d% ")
        self.stop(proc)
        r = self.update(self.write_local("fw.bin", self.good_image()))
        self.assertEqual(r.returncode, 0, r.stderr + self.bus.slave_output())
        self.assertIn("device is in BOOT", r.stderr)
        self.assert_runs(NEW_VERSION)

    def test_slave_killed_while_storing_keeps_the_old_firmware(self):
        state = tempfile.mkdtemp(dir=os.environ.get("ECAT_TEST_OUT") or None)
        self.addCleanup(shutil.rmtree, state, True)
        bus = self.start_bus(state)
        path = self.write_local("big.bin", self.good_image(size=8 << 20), bus)
        proc = self.start_update(path, bus)
        self.wait_for_line(proc, r"the slave is storing the image")
        os.killpg(bus.proc.pid, signal.SIGKILL)  # power cut while the image is being committed
        bus.proc.wait()
        self.stop(proc)
        bus.close()
        # Same state directory: the firmware that was active before boots.
        bus = self.start_bus(state)
        self.assert_old_firmware(bus)
        self.assertEqual([f for f in os.listdir(os.path.join(state, "firmware")) if f.endswith(".tmp")], [])
        # And the store still takes a new image.
        r = self.update(self.write_local("fw.bin", self.good_image(), bus), bus=bus)
        self.assertEqual(r.returncode, 0, r.stderr + bus.slave_output())
        self.assert_runs(NEW_VERSION, bus)


if __name__ == "__main__":
    harness.main()
