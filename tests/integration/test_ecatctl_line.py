"""The ecatctl verbs over a whole line (IgH `ethercat` crc, states, alias, graph) against a line of three soft
slaves on veth: counters a malformed frame really raised, cleared by --clear; every slave's state read and
changed at once; an alias written into the SII with its checksum and taken at the next start; the line as
Graphviz dot, parsed back."""
import os
import re
import unittest

import harness

STATE_DIR_ARG = "--state-dir"


class EcatctlLine(unittest.TestCase):
    def test_crc_states_alias_graph(self):
        state = harness.tempfile.mkdtemp(prefix="ecat-line-", dir=os.environ.get("ECAT_TEST_OUT"))
        with harness.Bus(slave_args=["--slaves", "3", STATE_DIR_ARG, state]) as bus:
            self.check_crc(bus)
            self.check_states(bus)
            self.check_graph(bus)
            self.check_alias_written(bus)
        # The written alias is in the state directory's EEPROM words: a new start (power-on) takes it.
        with harness.Bus(slave_args=["--slaves", "3", STATE_DIR_ARG, state]) as bus:
            out = bus.ecatctl("alias").stdout
            self.assertRegex(out, r"(?m)^1\s+alias 77 \(0x004d\)$", out)
            self.assertRegex(out, r"(?m)^0\s+alias 0 \(0x0000\)$", out)
            self.assertIn("77:1", bus.ecatctl("slaves").stdout)

    def test_mailbox_verbs_set_up_a_cleared_mailbox_again(self):
        """A slave in PREOP whose mailbox SyncManagers someone cleared: every verb that talks to the mailbox
        sets them up again through INIT (as IgH's master does) and says so, instead of failing."""
        state = harness.tempfile.mkdtemp(prefix="ecat-mbx-", dir=os.environ.get("ECAT_TEST_OUT"))
        with harness.Bus(slave_args=[STATE_DIR_ARG, state]) as bus:
            self.assertEqual(bus.ecatctl("state", "0", "preop").stdout.strip(), "PREOP")
            for verb in (["upload", "0", "0x1008", "0"], ["sdos", "0"], ["diag", "0"], ["pdos", "0"]):
                for sm in ("0x0806", "0x080E"):  # SM0 and SM1 activate: off
                    bus.ecatctl("reg", "write", "0", sm, "00")
                r = bus.ecatctl(*verb, check=False)
                self.assertEqual(r.returncode, 0, f"{verb}: {r.stderr}")
                self.assertIn("set up again through INIT", r.stderr, verb)
                self.assertEqual(bus.ecatctl("state", "0").stdout.split()[0], "PREOP", verb)
            self.assertIn("MAXPOS", bus.ecatctl("upload", "0", "0x1008", "0").stdout)

    def crc_rows(self, out):
        """{(slave, port): (invalid, rx, fwd, lost)} and {slave: (processing unit, pdi)}."""
        ports, units = {}, {}
        slave = None
        for line in out.splitlines()[1:]:
            f = line.split()
            if len(f) == 8:
                slave = int(f[0])
                ports[(slave, int(f[1]))] = tuple(int(x) for x in f[2:6])
                units[slave] = (int(f[6]), int(f[7]))
            elif len(f) == 5 and slave is not None:
                ports[(slave, int(f[0]))] = tuple(int(x) for x in f[1:5])
        return ports, units

    def check_crc(self, bus):
        ports, units = self.crc_rows(bus.ecatctl("crc").stdout)
        self.assertEqual(sorted(units), [0, 1, 2])
        self.assertEqual(sorted(ports), [(s, p) for s in range(3) for p in (0, 1)])
        self.assertEqual(units[0][0], 0)
        # A datagram whose length runs past the end of the frame: a length error in the first ESC's
        # processing unit (0x030C), the frame is lost.
        frame = bytearray(harness.ecat_frame([(0x04, 0x11, 0x1001, 0x0130, b"\x00\x00")]))
        frame[14 + 2 + 6] = 0xFF
        with bus.raw_socket() as s:
            s.send(bytes(frame))
        # The frame may take a moment through the slave's runtime: the counter is read until it shows.
        for _ in range(50):
            ports, units = self.crc_rows(bus.ecatctl("crc").stdout)
            if units[0][0]:
                break
        self.assertEqual(units[0][0], 1, units)
        self.assertEqual(units[1][0], 0, units)
        out = bus.ecatctl("crc", "--clear").stdout
        self.assertTrue(out.rstrip().endswith("cleared"), out)
        ports, units = self.crc_rows(bus.ecatctl("crc").stdout)
        self.assertEqual(units[0], (0, 0))

    def check_states(self, bus):
        out = bus.ecatctl("states").stdout
        self.assertEqual(re.findall(r"(?m)^(\d)\s+(\S+)", out), [("0", "INIT"), ("1", "INIT"), ("2", "INIT")])
        out = bus.ecatctl("states", "preop").stdout
        self.assertEqual(re.findall(r"(?m)^(\d)\s+(\S+)", out), [("0", "PREOP"), ("1", "PREOP"), ("2", "PREOP")])
        r = bus.ecatctl("states", "bogus", check=False)
        self.assertEqual(r.returncode, 2)
        self.assertIn("unknown state 'bogus'", r.stderr)
        out = bus.ecatctl("states", "init").stdout
        self.assertEqual(re.findall(r"(?m)^(\d)\s+(\S+)", out), [("0", "INIT"), ("1", "INIT"), ("2", "INIT")])

    def check_graph(self, bus):
        out = bus.ecatctl("graph").stdout
        self.assertTrue(out.startswith("digraph ethercat {"), out)
        self.assertTrue(out.rstrip().endswith("}"), out)
        edges = re.findall(r"(?m)^\s+(\w+) -> (\w+)", out)
        self.assertEqual(edges, [("master", "s0"), ("s0", "s1"), ("s1", "s2")])
        self.assertEqual(len(re.findall(r'(?m)^\s+s\d \[label="\d: MAXPOS', out)), 3)

    def check_alias_written(self, bus):
        out = bus.ecatctl("alias", "1", "77").stdout
        self.assertIn("alias 77 written to SII word 4", out)
        out = bus.ecatctl("alias", "1").stdout
        # The register keeps the power-on value; SII word 4 has the new one.
        self.assertRegex(out, r"^1\s+alias 0 \(0x0000\), SII word 4: 77 \(0x004d\)")
        self.assertIn("checksum ok", bus.ecatctl("slaves", "-v", "1").stdout)
        r = bus.ecatctl("alias", "1", "70000", check=False)
        self.assertEqual(r.returncode, 2)


if __name__ == "__main__":
    unittest.main()
