"""The real ecat-slave as the composed soft drive (softdrive) against the real ecatctl: the MAXPOS identity
from the model's SII, OP with the default mapping, SDO uploads, --write-sii / --write-esi, the configuration
file (identity and program options in one file), the control socket, parameters stored across a restart."""
import os
import re
import shutil
import socket
import subprocess
import tempfile
import time
import struct
import unittest
import zlib

import harness

ROW = re.compile(r"^(\d+)\s+0x([0-9a-f]{4})\s+(\S+)\s+0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8})"
                 r"(?: +(?:-|-?\d+))?(?: +(\S.*))?$",  # then the DC delay in ns (- without DC) and the name
                 re.M)
HERE = os.path.dirname(os.path.abspath(__file__))
SCHEMA = os.path.normpath(os.path.join(HERE, "..", "..", "esi", "schema", "EtherCATInfo.xsd"))


def out_dir():
    return os.environ.get("ECAT_TEST_OUT") or None


class DeviceOnTheWire(unittest.TestCase):
    def test_scan_shows_the_maxpos_identity(self):
        with harness.Bus() as bus:
            r = bus.ecatctl("scan")
            rows = ROW.findall(r.stdout)
            self.assertEqual(len(rows), 1, r.stdout)
            _pos, _station, state, vendor, product, revision, _serial, name = rows[0]
            self.assertEqual(state, "INIT")
            self.assertEqual(int(vendor, 16), 0x000000FB)
            self.assertEqual(int(product, 16), 0x30010000)
            self.assertEqual(int(revision, 16), 0x01200000)
            self.assertIn(name, ("", "MAXPOS"))  # newer ecatctl prints the SII device name
            self.assertNotIn("no EEPROM image", bus.slave_output())

    def test_sdo_uploads_of_the_identity(self):
        with harness.Bus() as bus:
            self.assertEqual(bus.ecatctl("upload", "0", "0x1018", "1").stdout.strip(), "0x000000fb (251)")
            self.assertEqual(bus.ecatctl("upload", "0", "0x1018", "2").stdout.strip(), "0x30010000 (805371904)")
            self.assertEqual(bus.ecatctl("upload", "0", "0x1008", "0", "--type", "string").stdout.strip(), "MAXPOS")
            self.assertEqual(bus.ecatctl("upload", "0", "0x100a", "0", "--type", "string").stdout.strip(), "0120h")

    def test_state_op_with_the_default_mapping(self):
        with harness.Bus() as bus:
            r = bus.ecatctl("pd", "0", "-n", "300", "--cycle-us", "1000")
            self.assertIn("state: OP\n", r.stdout)
            self.assertIn("outputs: SM2 0x1100, 23 bytes; inputs: SM3 0x1300, 27 bytes", r.stdout)
            self.assertRegex(r.stdout, r"cycles 300, lost 0, wkc errors 0 \(expected wkc 3\)")
            # Statusword (first input word) of a drive that is powered but not enabled: switch on disabled.
            m = re.search(r"0x0000: ([0-9a-f]{2}) ([0-9a-f]{2})", r.stdout)
            self.assertIsNotNone(m, r.stdout)
            sw = int(m.group(1), 16) | int(m.group(2), 16) << 8
            self.assertEqual(sw & 0x4F, 0x40, r.stdout)
            self.assertEqual(bus.ecatctl("state", "0").stdout.strip(), "PREOP")

    def test_sii_on_the_wire_is_the_one_write_sii_writes(self):
        d = tempfile.mkdtemp(dir=out_dir())
        self.addCleanup(shutil.rmtree, d, True)
        path = os.path.join(d, "sii.bin")
        with harness.Bus() as bus:
            r = subprocess.run([bus.slave_bin, "--write-sii", path, "--state-dir", os.path.join(bus.dir, "state")],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=30)
            self.assertEqual(r.returncode, 0, r.stdout)
            r = bus.ecatctl("sii", "read", "-o", os.path.join(d, "read.bin"))
            with open(path, "rb") as f:
                written = f.read()
            with open(os.path.join(d, "read.bin"), "rb") as f:
                read = f.read()
            self.assertGreater(len(read), 64 * 2)
            self.assertEqual(written[:len(read)], read)


class OfflineOutputs(unittest.TestCase):
    """--write-sii / --write-esi need no network and no root."""

    def setUp(self):
        self.slave = harness.env_path("ECAT_SLAVE")
        self.ecatctl = harness.env_path("ECATCTL")
        self.dir = tempfile.mkdtemp(dir=out_dir())
        self.addCleanup(shutil.rmtree, self.dir, True)

    def run_slave(self, *args):
        return subprocess.run([self.slave, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              timeout=60)

    def test_write_esi_validates_against_the_schema(self):
        if not shutil.which("xmllint"):
            self.skipTest("xmllint missing")
        esi = os.path.join(self.dir, "device.xml")
        r = self.run_slave("--write-esi", esi, "--state-dir", os.path.join(self.dir, "state"))
        self.assertEqual(r.returncode, 0, r.stderr)
        v = subprocess.run(["xmllint", "--noout", "--schema", SCHEMA, esi], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=120)
        self.assertEqual(v.returncode, 0, v.stdout[-2000:])
        with open(esi) as f:
            text = f.read()
        self.assertIn('ProductCode="#x30010000" RevisionNo="#x01200000"', text)

    def test_write_sii_decodes(self):
        sii = os.path.join(self.dir, "device.sii")
        r = self.run_slave("--write-sii", sii, "--state-dir", os.path.join(self.dir, "state"))
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(os.path.getsize(sii), 2048)
        d = subprocess.run([self.ecatctl, "sii", "decode", sii], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, timeout=30)
        self.assertEqual(d.returncode, 0, d.stderr)
        self.assertIn("vendor 0x000000FB, product 0x30010000, revision 0x01200000", d.stdout)
        self.assertIn("checksum 0x", d.stdout)
        self.assertIn(": ok", d.stdout)
        self.assertIn("mailbox protocols 0x000C (CoE FoE)", d.stdout)
        self.assertNotIn("problem", d.stdout.lower())

    def test_configuration_file_carries_identity_and_program_options(self):
        conf = os.path.join(self.dir, "drive.conf")
        state = os.path.join(self.dir, "from-config")
        with open(conf, "w") as f:
            f.write(f"state-dir = {state}\nwrite-sii = {self.dir}/c.sii\n\n"
                    "[identity]\nserial_number = 0x00C0FFEE\ndevice_name = \"MAXPOS-X\"\n")
        r = self.run_slave("--config", conf)
        self.assertEqual(r.returncode, 0, r.stderr)
        d = subprocess.run([self.ecatctl, "sii", "decode", os.path.join(self.dir, "c.sii")], stdout=subprocess.PIPE,
                           text=True, timeout=30)
        self.assertIn("serial 0x00C0FFEE", d.stdout)
        self.assertIn('"MAXPOS-X"', d.stdout)

    def test_the_example_configuration_loads(self):
        example = os.path.join(HERE, "..", "..", "tools", "ecat-slave", "drive.conf")
        sii = os.path.join(self.dir, "example.sii")
        r = self.run_slave("--config", example, "--state-dir", os.path.join(self.dir, "state"), "--write-sii", sii)
        self.assertEqual(r.returncode, 0, r.stderr)
        d = subprocess.run([self.ecatctl, "sii", "decode", sii], stdout=subprocess.PIPE, text=True, timeout=30)
        self.assertIn("serial 0x00000001", d.stdout)

    def test_configuration_errors_are_usage_errors(self):
        conf = os.path.join(self.dir, "bad.conf")
        with open(conf, "w") as f:
            f.write("[identity]\nvendor_idd = 1\n")
        r = self.run_slave("--config", conf, "--write-sii", os.path.join(self.dir, "x.sii"))
        self.assertEqual(r.returncode, 2)
        self.assertIn("bad.conf:2", r.stderr)
        with open(conf, "w") as f:
            f.write("no-such-option = 1\n")
        r = self.run_slave("--config", conf, "--write-sii", os.path.join(self.dir, "x.sii"))
        self.assertEqual(r.returncode, 2)
        self.assertIn("no-such-option", r.stderr)
        r = self.run_slave("--control", "/nonexistent-dir/ctl.sock", "--iface", "lo")
        self.assertEqual(r.returncode, 2)
        self.assertIn("--control", r.stderr)


class RunTime(unittest.TestCase):
    def test_control_socket_toggles_a_digital_input(self):
        d = harness.socket_dir()
        self.addCleanup(shutil.rmtree, d, True)
        path = os.path.join(d, "ctl.sock")
        me = os.path.join(d, "me.sock")
        with harness.Bus(slave_args=["--control", path]) as bus:
            before = int(bus.ecatctl("upload", "0", "0x3141", "1", "--type", "u16").stdout.split()[0], 16)
            self.assertEqual(before & 0x08, 0)
            s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
            self.addCleanup(s.close)
            s.bind(me)
            s.settimeout(5)
            # The socket lives in the slave's mount namespace = ours (ip netns exec keeps /tmp).
            s.sendto(b"input 4 on\n", path)
            self.assertEqual(s.recv(256), b"ok input 4 on\n")
            time.sleep(0.1)  # the drive runs every 10 ms outside Op
            after = int(bus.ecatctl("upload", "0", "0x3141", "1", "--type", "u16").stdout.split()[0], 16)
            self.assertEqual(after & 0x08, 0x08)
            s.sendto(b"status\n", path)
            self.assertTrue(s.recv(256).startswith(b"ok state PREOP statusword 0x"))
            s.sendto(b"input 9 on\n", path)
            self.assertTrue(s.recv(256).startswith(b"error: "))
            self.assertTrue(bus.slave_alive())

    def test_drive_moves_and_reacts_to_the_watchdog(self):
        with harness.Bus() as bus:
            if "--step" not in bus.ecatctl("pd", "--help").stdout:
                self.skipTest("ecatctl pd has no --step")
            bus.ecatctl("download", "0", "0x6081", "0", "3000", "--type", "u32")  # profile velocity
            # Profile position (mode 1 at output byte 16) to 30000 inc: shutdown, switch on, enable, new set-point.
            t = "30,75,00,00"
            z = ",".join(["00"] * 10)
            steps = []
            for cw in ("06", "07", "0f"):
                steps += ["--step", f"20:{cw},00,{t},{z},01"]
            out = "0x1f 0 0x30 0x75 0 0 0 0 0 0 0 0 0 0 0 0 1".split()
            r = bus.ecatctl("pd", "0", "--cycle-us", "1000", *steps, "-n", "1200", "--keep", "--outputs", *out)
            self.assertIn("state: OP\n", r.stdout)
            m = re.search(r"0x0000: ([0-9a-f]{2}) ([0-9a-f]{2}) ([0-9a-f]{2}) ([0-9a-f]{2}) ([0-9a-f]{2}) ([0-9a-f]{2})",
                          r.stdout)
            sw = int(m.group(1), 16) | int(m.group(2), 16) << 8
            pos = int.from_bytes(bytes(int(m.group(i), 16) for i in range(3, 7)), "little", signed=True)
            self.assertEqual(sw & 0x6F, 0x27, r.stdout)  # operation enabled
            self.assertLessEqual(abs(pos - 30000), 5, r.stdout)  # at the target (position window)
            # The master is gone (--keep): SM watchdog -> SAFEOP + error 0x001B, and the drive's 0x6007 reaction
            # (3: quick-stop ramp, then Fault 0x8180) completes although nobody cycles any more.
            time.sleep(0.5)
            self.assertTrue(bus.ecatctl("state", "0").stdout.strip().startswith("SAFEOP +ERR 0x001b"))
            self.assertEqual(bus.ecatctl("upload", "0", "0x603f", "0").stdout.strip(), "0x8180 (33152)")
            sw = int(bus.ecatctl("upload", "0", "0x6041", "0", "--type", "u16").stdout.split()[0], 16)
            self.assertEqual(sw & 0x4F, 0x08, hex(sw))  # Fault

    def test_statistics_at_exit(self):
        d = tempfile.mkdtemp(dir=out_dir())
        self.addCleanup(shutil.rmtree, d, True)
        stats = os.path.join(d, "stats.txt")
        with harness.Bus(slave_args=["--stats-file", stats]) as bus:
            bus.ecatctl("pd", "0", "-n", "100")
            self.assertEqual(bus.stop_slave(), 0)
        with open(stats) as f:
            values = dict(line.split() for line in f if line.strip())
        self.assertEqual(values["device.builds"], "1")
        self.assertGreaterEqual(int(values["device.drive_cycles"]), 100)
        self.assertGreaterEqual(int(values["stack.transitions"]), 4)  # I->P->S->O->P at least

    def test_stored_parameters_survive_a_restart_of_the_program(self):
        d = tempfile.mkdtemp(dir=out_dir())
        self.addCleanup(shutil.rmtree, d, True)
        state = os.path.join(d, "state")
        with harness.Bus(slave_args=["--state-dir", state]) as bus:
            bus.ecatctl("download", "0", "0x6065", "0", "0x4321", "--type", "u32")
            bus.ecatctl("download", "0", "0x1010", "1", "save", "--type", "string")
        self.assertTrue(os.path.exists(os.path.join(state, "parameters.bin")))
        with harness.Bus(slave_args=["--state-dir", state]) as bus:
            r = bus.ecatctl("upload", "0", "0x6065", "0", "--type", "u32")
            self.assertEqual(r.stdout.strip(), "0x00004321 (17185)")
        # A damaged file: reported, defaults used, the slave still runs.
        with open(os.path.join(state, "parameters.bin"), "r+b") as f:
            f.seek(50)
            f.write(b"\xde\xad")
        with harness.Bus(slave_args=["--state-dir", state]) as bus:
            r = bus.ecatctl("upload", "0", "0x6065", "0", "--type", "u32")
            self.assertNotEqual(r.stdout.strip(), "0x00004321 (17185)")
            self.assertIn("not used", bus.slave_output())


def firmware_image(vendor, product, version, size=4000):
    """foe/image/include/foe/image.hpp: 32-byte header with CRC-32 over header bytes 0..27 and the payload."""
    payload = bytes((i * 13) & 0xFF for i in range(size))
    head = struct.pack("<IHHIIIII", 0x57464553, 1, 32, vendor, product, version, len(payload), 0)
    return head + struct.pack("<I", zlib.crc32(head + payload) & 0xFFFFFFFF) + payload


class FirmwareUpdate(unittest.TestCase):
    def test_new_image_through_bootstrap_changes_the_identity_everywhere(self):
        d = tempfile.mkdtemp(dir=out_dir())
        self.addCleanup(shutil.rmtree, d, True)
        state = os.path.join(d, "state")
        image = os.path.join(d, "fw.bin")
        with open(image, "wb") as f:
            f.write(firmware_image(0xFB, 0x30010000, 0x01300000))
        with harness.Bus(slave_args=["--state-dir", state]) as bus:
            r = bus.ecatctl("foe", "write", image, "--name", "MAXPOS", check=False)
            if r.returncode != 0 and "foe" in r.stderr and "not" in r.stderr and "command" in r.stderr:
                self.skipTest("ecatctl has no foe verb")
            self.assertEqual(r.returncode, 0, r.stderr + bus.slave_output())
            # Bootstrap -> Init restarted the device from the new image: SII, 0x1018:03 and 0x100A agree.
            rows = ROW.findall(bus.ecatctl("scan").stdout)
            self.assertEqual(int(rows[0][5], 16), 0x01300000, rows)
            self.assertEqual(bus.ecatctl("upload", "0", "0x1018", "3").stdout.strip(), "0x01300000 (19922944)")
            self.assertEqual(bus.ecatctl("upload", "0", "0x100a", "0", "--type", "string").stdout.strip(), "0130h")
            r = bus.ecatctl("pd", "0", "-n", "100")
            self.assertIn("state: OP\n", r.stdout)
        # The next start boots the stored image; --write-sii of the same state directory says so too.
        with harness.Bus(slave_args=["--state-dir", state]) as bus:
            rows = ROW.findall(bus.ecatctl("scan").stdout)
            self.assertEqual(int(rows[0][5], 16), 0x01300000, rows)
            sii = os.path.join(d, "sii.bin")
            subprocess.run([bus.slave_bin, "--state-dir", state, "--write-sii", sii], check=True, timeout=30)
            with open(sii, "rb") as f:
                self.assertEqual(struct.unpack_from("<I", f.read(), 0x0C * 2)[0], 0x01300000)
        # --write-esi names the firmware it describes: that state directory's when it is named, otherwise the
        # built-in one, whatever the default state directory holds (a fresh slave's own ESI check passes).
        named = subprocess.run([harness.env_path("ECAT_SLAVE"), "--state-dir", state, "--write-esi", "-"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
        self.assertEqual(named.returncode, 0, named.stderr)
        self.assertIn('RevisionNo="#x01300000"', named.stdout)
        self.assertIn(f"the firmware active in {state}, software version 0130h, revision 0x01300000", named.stderr)
        built_in = subprocess.run([harness.env_path("ECAT_SLAVE"), "--write-esi", "-"], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True, timeout=30)
        self.assertEqual(built_in.returncode, 0, built_in.stderr)
        self.assertIn('RevisionNo="#x01200000"', built_in.stdout)
        self.assertIn("the built-in firmware, software version 0120h, revision 0x01200000", built_in.stderr)
        fresh = subprocess.run([harness.env_path("ECAT_SLAVE"), "--state-dir", os.path.join(d, "fresh"),
                                "--write-esi", "-"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               timeout=30)
        self.assertEqual(fresh.stdout, built_in.stdout)


if __name__ == "__main__":
    if os.geteuid() != 0:
        print("integration tests need root (network namespaces, veth pairs)")
        raise SystemExit(harness.SKIP)
    unittest.main()
