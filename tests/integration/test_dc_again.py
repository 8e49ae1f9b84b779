"""DC sessions in a row on the same drives: the real ecat-slave, the real `ecatctl pd --dc` (one drive) and
`ecatctl pd --all --dc` (a line of three). A session ends in PREOP with SYNC0 still running; the next one clears
0x0981, programs a new start time and activates again (ETG.1020, DC start-up). Each session must reach OP and
cycle without lost frames or working-counter errors; before the fix the second ended in SAFEOP+ERR 0x002C
(the drive took a SYNC0 event of the first activation for the start of the second)."""
import re
import unittest

import harness

STATS = re.compile(r"cycles (\d+), lost (\d+), wkc errors (\d+) \(expected wkc (\d+)\)")
ALL_ROW = re.compile(r"^(\d+)\s+0x[0-9a-f]+\s+(\S+(?: \+ERR(?: 0x[0-9a-f]+)?)?)\s+\d+", re.M)


class DcAgain(unittest.TestCase):
    def start(self, *slave_args):
        return harness.bus_in_preop(self, *slave_args)

    def session(self, bus, *args, expected_wkc=None):
        r = bus.ecatctl("pd", *args, check=False)
        m = STATS.search(r.stdout)
        self.assertIsNotNone(m, f"rc {r.returncode}\n{r.stdout}\n{r.stderr}\n{bus.slave_output()}")
        cycles, lost, wkc_errors, wkc = (int(x) for x in m.groups())
        self.assertEqual(r.returncode, 0, f"{r.stdout}\n{r.stderr}\n{bus.slave_output()}")
        self.assertEqual((lost, wkc_errors), (0, 0), r.stdout)
        self.assertGreater(cycles, 0)
        if expected_wkc is not None:
            self.assertEqual(wkc, expected_wkc)
        return r

    def assert_all_op(self, r, n):
        rows = ALL_ROW.findall(r.stdout)
        self.assertEqual([int(p) for p, _ in rows], list(range(n)), r.stdout)
        self.assertEqual([s for _, s in rows], ["OP"] * n, r.stdout)

    def test_one_drive_three_dc_sessions(self):
        bus = self.start()
        for count in ("1000", "300", "300"):
            r = self.session(bus, "0", "--dc", "-n", count, expected_wkc=3)
            self.assertIn("state: OP\n", r.stdout)
            self.assertEqual(bus.ecatctl("state", "0").stdout.strip(), "PREOP")
        self.assertNotIn("0x002C", bus.slave_output())

    def test_line_of_three_dc_sessions_with_all(self):
        bus = self.start("--slaves", "3")
        # One drive first (as in the issue), then the whole line twice, then one drive again.
        r = self.session(bus, "0", "--dc", "-n", "500", expected_wkc=3)
        self.assertIn("state: OP\n", r.stdout)
        for _ in range(2):
            r = self.session(bus, "--all", "--dc", "-n", "500", expected_wkc=9)
            self.assert_all_op(r, 3)
        r = self.session(bus, "2", "--dc", "-n", "300", expected_wkc=3)
        self.assertIn("state: OP\n", r.stdout)
        for k in range(3):
            self.assertEqual(bus.ecatctl("state", str(k)).stdout.strip(), "PREOP")
        self.assertNotIn("0x002C", bus.slave_output())

    def test_dc_after_sm_synchronous_and_back(self):
        # DC, SM-synchronous (the master stops SYNC0), DC again: every switch reaches OP.
        bus = self.start("--slaves", "3")
        self.assert_all_op(self.session(bus, "--all", "--dc", "-n", "300", expected_wkc=9), 3)
        self.assert_all_op(self.session(bus, "--all", "-n", "300", expected_wkc=9), 3)
        self.assert_all_op(self.session(bus, "--all", "--dc", "-n", "300", expected_wkc=9), 3)


if __name__ == "__main__":
    harness.main()
