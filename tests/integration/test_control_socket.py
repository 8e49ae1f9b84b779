"""The control socket and the files ecat-slave reads, as issue 24's campaign found them (findings 1-3, 5-8),
against the real binary: an oversized datagram refused whole, a control flood that leaves the frames and the
cycles alone, the socket's mode and who may replace or remove what, and the usage errors (exit 2) for bad
topology files, device counts, configuration files and state directories, all before the network is touched."""
import os
import socket
import stat
import subprocess
import tempfile
import threading
import shutil
import unittest

import harness
from test_segment_line import require_segment


def slave(*args, timeout=30):
    """ecat-slave with args on an interface that does not exist: a usage error must come before it matters."""
    return subprocess.run([harness.env_path("ECAT_SLAVE"), "--iface", "nosuchif0", *args], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=timeout)


def send(path, data, reply=True, timeout=5.0):
    """One datagram to the control socket; the answer (from a socket with an address) or None."""
    s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    me = f"{path}.{os.getpid()}.{threading.get_ident()}.me"
    try:
        if reply:
            s.bind(me)
            s.settimeout(timeout)
        s.sendto(data, path)
        return s.recv(65536).decode() if reply else None
    finally:
        s.close()
        if reply and os.path.exists(me):
            os.unlink(me)


class ControlSocket(unittest.TestCase):
    def setUp(self):
        require_segment(self)
        self.tmp = harness.socket_dir()  # short: a UNIX socket path is at most 107 bytes, the clone's may be longer
        self.addCleanup(shutil.rmtree, self.tmp, True)
        self.ctl = os.path.join(self.tmp, "ctl.sock")

    def bus(self, *args):
        b = harness.Bus(slave_args=["--control", self.ctl, *args])
        b.__enter__()
        self.addCleanup(b.close)
        return b

    def test_a_datagram_longer_than_the_buffer_is_refused_whole(self):
        """Finding 1: 4096 bytes of padding and 'delay 0 999999' answered 'ok delay hop 0 99'."""
        self.bus("--slaves", "2")
        answer = send(self.ctl, b" " * 4096 + b"delay 0 999999\n")
        self.assertTrue(answer.startswith("error: datagram longer than 4096 bytes: refused whole"), answer)
        seg = send(self.ctl, b"segment\n")
        self.assertIn("hop 0 drop 0 corrupt 0 delay 0 ", seg)
        # The same command in a datagram that fits is carried out.
        self.assertEqual(send(self.ctl, b" " * 100 + b"delay 0 999\n"), "ok delay hop 0 999\n")

    def test_a_control_flood_loses_no_frame_and_no_cycle(self):
        """Finding 2: 20 datagrams of 290 lines to a 16-drive segment left the line without one answer for 3 s;
        a status/segment flood let 7 of 31 BRDs through in 5 s. Frames come first: with the socket's queue kept
        full for the whole run, the drives stay in Op with the full working counter in every answered cycle."""
        b = self.bus("--slaves", "16")
        m = harness.MiniMaster(b)
        self.addCleanup(m.close)
        m.to_op(dc=True)
        calm = m.run(300)
        self.assertEqual((calm["wkc_errors"], calm["wkc_min"]), (0, m.expected_wkc), calm)
        flood = ("status\nsegment\n" * 145).encode()  # 290 lines, under 4096 bytes
        self.assertLess(len(flood), 4096)
        s, sent = harness.during_control_flood(self.ctl, flood, lambda: m.run(2000))
        self.assertGreater(sent, 20, "the flood did not run")
        # Every answered cycle had the full working counter; the drives never left Op (a starved drive's
        # SyncManager watchdog would have taken it to Safe-Op with an error after 100 ms).
        self.assertEqual((s["wkc_errors"], s["wkc_min"], s["wkc_max"]), (0, m.expected_wkc, m.expected_wkc), s)
        self.assertEqual(m.states, [8] * 16, s)
        # A lost cycle is one without an answer in 50 ms: the old loop lost most of them.
        self.assertLessEqual(s["lost"] * 20, s["cycles"], s)
        self.assertTrue(send(self.ctl, b"status\n").startswith("ok state "))  # the socket still answers

    def test_the_socket_is_the_owners_and_only_its_own_path_is_removed(self):
        """Finding 3: the mode followed the umask (0777 at umask 000), --control unlinked whatever was at the
        path, a live socket of another program included, and deleted the path at exit."""
        old = os.umask(0)
        try:
            b = self.bus()
        finally:
            os.umask(old)
        self.assertEqual(stat.S_IMODE(os.lstat(self.ctl).st_mode), 0o600)
        # A second slave on the same path: the live socket is not taken over.
        with self.assertRaises(RuntimeError) as e:
            self.bus()
        self.assertIn("socket in use", str(e.exception))
        self.assertTrue(send(self.ctl, b"status\n").startswith("ok state"))  # still the first one's
        # Someone else's file at the path by the time the slave stops: left alone.
        os.unlink(self.ctl)
        with open(self.ctl, "w") as f:
            f.write("not yours")
        self.assertEqual(b.stop_slave(), 0, b.slave_output()[-2000:])
        with open(self.ctl) as f:
            self.assertEqual(f.read(), "not yours")
        # A regular file at the path is never replaced.
        with self.assertRaises(RuntimeError) as e:
            self.bus()
        self.assertIn("not a socket", str(e.exception))
        with open(self.ctl) as f:
            self.assertEqual(f.read(), "not yours")


class UsageErrors(unittest.TestCase):
    """Findings 5-8: each is exit 2 with the file (and line) named, before any network set-up (the interface
    given does not exist: an error about it would mean the check came too late)."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(dir=os.environ.get("ECAT_TEST_OUT"))
        self.addCleanup(shutil.rmtree, self.tmp, True)
        self.state = os.path.join(self.tmp, "state")

    def write(self, name, text):
        p = os.path.join(self.tmp, name)
        with open(p, "w") as f:
            f.write(text)
        return p

    def usage_error(self, *args):
        r = slave("--state-dir", self.state, *args)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertNotIn("nosuchif0", r.stderr)
        return r.stderr

    def test_files_that_are_not_regular_files_are_refused_unread(self):
        fifo = os.path.join(self.tmp, "fifo")
        os.mkfifo(fifo)
        self.assertIn("not a regular file (a FIFO)", self.usage_error("--config", fifo))  # no writer: no hang
        self.assertIn("not a regular file", self.usage_error("--config", "/dev/zero"))
        self.assertIn("not a regular file", self.usage_error("--topology", fifo))
        self.assertIn("not a regular file", self.usage_error("--eeprom", fifo))
        big = self.write("big.topo", "device a\n")
        os.truncate(big, (1 << 20) + 1)
        self.assertIn("larger than", self.usage_error("--topology", big))

    def test_device_names_cannot_leave_the_state_directory(self):
        for name in ("../escapeA", "/tmp/x", "./a"):
            topo = self.write("t.topo", f"device first\ndevice {name}\n")
            self.assertIn(f"{topo}:2: device name '{name}'", self.usage_error("--topology", topo))
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "escapeA")))
        topo = self.write("dup.topo", "device a state-dir=s\ndevice b state-dir=s\n")
        self.assertIn(f"{topo}:2: state-dir=s", self.usage_error("--topology", topo))
        topo = self.write("same.topo", f"device a\ndevice b state-dir={self.state}/a\n")
        self.assertIn("in use by another device or process", self.usage_error("--topology", topo))

    def test_one_device_limit(self):
        topo = self.write("many.topo", "".join(f"device d{k}\n" for k in range(1001)))
        self.assertIn(f"{topo}:1001: more than 1000 devices", self.usage_error("--topology", topo))
        self.usage_error("--slaves", "1001")

    def test_every_configuration_value_is_checked_before_the_network(self):
        # A name of '=' was taken for the dictionary's marker and threw after the network was set up.
        conf = self.write("eq.conf", "[identity]\ndevice_name = =\nhardware_version = =\nsoftware_version = =\n")
        r = slave("--config", conf, "--state-dir", self.state)
        # Every check passed: it got as far as the interface (without the fix: "od: row marked \"=\"...").
        self.assertIn("network interface 'nosuchif0' does not exist", r.stderr)
        conf = self.write("n.conf", "[identity]\nserial_number = 1e300\n")
        self.assertIn(f"{conf}:2: bad number '1e300' for serial_number", self.usage_error("--config", conf))
        # What only the SII build refuses (strings that do not fit a 128-byte EEPROM) is found before it too.
        conf = self.write("small.conf", "[identity]\norder_code = \"" + "x" * 200 + "\"\n[eeprom]\nbytes = 128\n")
        self.assertIn(conf, self.usage_error("--config", conf))

    def test_a_state_directory_has_one_user(self):
        b = harness.Bus(slave_args=["--state-dir", self.state])
        b.__enter__()
        self.addCleanup(b.close)
        self.assertIn("in use by another device or process", self.usage_error())


if __name__ == "__main__":
    harness.main()
