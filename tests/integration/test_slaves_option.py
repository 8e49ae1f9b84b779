"""ecat-slave --slaves N: N drives in a line behind one interface, as a master counts and addresses them; faults
through the control socket end up in the statistics; a bad topology file names its file and line."""
import os
import re
import shutil
import socket
import subprocess
import tempfile
import unittest

import harness

ROW = re.compile(r"^(\d+)\s+0x([0-9a-f]{4})\s+(\S+)\s+0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8}) ?(.*)$",
                 re.M)


class SlavesOption(unittest.TestCase):
    def control(self, bus, path, line):
        me = os.path.join(bus.sock_dir, f"me{os.getpid()}.sock")
        s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.addCleanup(s.close)
        if os.path.exists(me):
            os.unlink(me)
        s.bind(me)
        s.settimeout(5)
        s.sendto(line.encode() + b"\n", path)
        reply = s.recv(65536).decode()
        s.close()
        os.unlink(me)
        return reply

    def test_three_drives_counted_addressed_and_taken_to_preop(self):
        with harness.Bus(slave_args=("--slaves", "3")) as bus:
            r = bus.ecatctl("scan")
            self.assertIn("3 slaves\n", r.stdout)
            rows = ROW.findall(r.stdout)
            self.assertEqual(len(rows), 3, r.stdout)
            for k, row in enumerate(rows):
                pos, station, state, vendor, _product, _revision, serial, _name = row
                self.assertEqual(int(pos), k)
                self.assertEqual(int(station, 16), 0x1001 + k)
                self.assertEqual(int(serial, 16), k + 1, "serial numbers 1..N")
                self.assertEqual(int(vendor, 16), 0x000000FB)
                self.assertTrue(state.startswith("INIT"), state)
            # Each answers at its own station address.
            for k in range(3):
                r = bus.ecatctl("reg", "read", "--station", hex(0x1001 + k), "0x10", "--type", "u16")
                self.assertEqual(r.stdout.split()[0], hex(0x1001 + k))
            # Each can be taken to PREOP on its own (position addressing); the others stay in INIT.
            for k in range(3):
                bus.ecatctl("state", str(k), "PREOP")
                states = [row[2] for row in ROW.findall(bus.ecatctl("scan").stdout)]
                self.assertEqual(states, ["PREOP"] * (k + 1) + ["INIT"] * (2 - k))
            # Each drive has its own state directory.
            for k in range(1, 4):
                self.assertTrue(os.path.isdir(os.path.join(bus.dir, "state", f"drive{k}")), k)
            self.assertTrue(bus.slave_alive())

    def test_faults_through_the_control_socket_are_counted(self):
        bus = harness.Bus()  # its folder exists from here on; the slave starts with `with`
        ctl = os.path.join(bus.sock_dir, "ctl.sock")
        stats = os.path.join(bus.dir, "stats.txt")
        bus.slave_args = ["--slaves", "3", "--control", ctl, "--stats-file", stats]
        with bus:
            self.assertIn("3 slaves\n", bus.ecatctl("scan").stdout)
            reply = self.control(bus, ctl, "link 1 1 down")
            self.assertEqual(reply, "ok link drive2 1 down\n")
            self.assertIn("2 slaves\n", bus.ecatctl("scan").stdout, "the line ends at drive2")
            self.assertEqual(self.control(bus, ctl, "link drive2 1 up"), "ok link drive2 1 up\n")
            self.assertIn("3 slaves\n", bus.ecatctl("scan").stdout)
            self.assertEqual(self.control(bus, ctl, "power drive3 cycle"), "ok power drive3 cycle\n")
            seg = self.control(bus, ctl, "segment")
            self.assertTrue(seg.startswith("ok segment 3 devices\n"), seg)
            self.assertIn("device 2 drive3 power on state INIT", seg)
            self.assertTrue(self.control(bus, ctl, "slave 5 status").startswith("error: no device '5'"))
            self.assertTrue(self.control(bus, ctl, "slave drive2 status").startswith("ok state INIT"))
            self.assertEqual(bus.stop_slave(), 0)
            with open(stats) as f:
                lines = dict(line.split() for line in f if line.strip())
            self.assertEqual(lines["segment.device2.power_cycles"], "1")
            self.assertEqual(lines["segment.link_changes"], "2")
            self.assertIn("segment.hop1.frames", lines)
            log = bus.slave_output()
            self.assertIn("cable at port 1 of drive2 pulled", log)
            self.assertIn("drive3 (device 2) switched on", log)

    def test_a_bad_topology_file_names_file_and_line(self):
        d = tempfile.mkdtemp(prefix="ecat-it-topo-", dir=os.environ.get("ECAT_TEST_OUT"))
        self.addCleanup(shutil.rmtree, d, True)
        topo = os.path.join(d, "bad.topo")

        def run_with(text):
            with open(topo, "w") as f:
                f.write(text)
            return subprocess.run([harness.env_path("ECAT_SLAVE"), "--topology", topo, "--iface", "lo",
                                   "--state-dir", os.path.join(d, "state")],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)

        r = run_with("# a line\ndevice a\ndevice b at=nowhere:1\n")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(f"{topo}:3: at=nowhere:1: unknown device 'nowhere'", r.stderr)
        r = run_with("device a\ndevice b config=missing.conf\n")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(f"{topo}:2: device b: ", r.stderr)


if __name__ == "__main__":
    harness.main()
