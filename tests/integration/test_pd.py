"""Cyclic process data through `ecatctl pd` against the real ecat-slave: PREOP -> SAFEOP -> OP with the
layout the slave declares, LRW with working counter 3, SM-synchronous and DC SYNC0, the process-data
watchdog when the master stops (needs the slave's firmware)."""
import re
import time
import unittest

import harness

STATS = re.compile(r"cycles (\d+), lost (\d+), wkc errors (\d+) \(expected wkc (\d+)\), rtt min ([\d.]+) us, "
                   r"avg ([\d.]+) us, max ([\d.]+) us")


class ProcessData(unittest.TestCase):
    def setUp(self):
        self.bus = harness.bus_in_preop(self)

    def run_pd(self, *args):
        r = self.bus.ecatctl("pd", "0", *args)
        m = STATS.search(r.stdout)
        self.assertIsNotNone(m, r.stdout)
        cycles, lost, wkc_errors, expected = (int(x) for x in m.groups()[:4])
        return r, cycles, lost, wkc_errors, expected, float(m.group(5))

    def test_sm_synchronous_op(self):
        r, cycles, lost, wkc_errors, expected, _ = self.run_pd("-n", "500", "--cycle-us", "1000")
        self.assertIn("state: OP\n", r.stdout)
        self.assertEqual((cycles, lost, wkc_errors, expected), (500, 0, 0, 3))
        # Back to PREOP at the end (no --keep).
        self.assertEqual(self.bus.ecatctl("state", "0").stdout.strip(), "PREOP")

    def test_dc_sync0_op(self):
        r, cycles, lost, wkc_errors, _, _ = self.run_pd("-n", "500", "--cycle-us", "1000", "--dc")
        self.assertIn("state: OP\n", r.stdout)
        self.assertEqual((cycles, lost, wkc_errors), (500, 0, 0))
        self.assertRegex(r.stdout, r"reference system time [1-9]\d+ ns")
        # SYNC0 really runs: activation register and cycle time as the master wrote them.
        self.assertEqual(self.bus.ecatctl("reg", "read", "0", "0x0981", "--type", "u8").stdout.strip(), "0x03 (3)")
        self.assertEqual(self.bus.ecatctl("reg", "read", "0", "0x09a0", "--type", "u32").stdout.strip(),
                         "0x000f4240 (1000000)")

    def test_watchdog_when_the_master_stops(self):
        self.run_pd("-n", "200", "--keep")
        time.sleep(0.5)  # default SM watchdog 100 ms
        st = self.bus.ecatctl("state", "0").stdout.strip()
        self.assertTrue(st.startswith("SAFEOP +ERR 0x001b"), st)
        # The next session acknowledges the error and runs again.
        r, _, lost, wkc_errors, _, _ = self.run_pd("-n", "200")
        self.assertEqual((lost, wkc_errors), (0, 0))

    def mapping(self, pdo):
        """[(index, sub, bits)] of a PDO mapping object, read over CoE."""
        count = int(self.bus.ecatctl("upload", "0", hex(pdo), "0", "--type", "u8").stdout.split()[0], 16)
        out = []
        for sub in range(1, count + 1):
            v = int(self.bus.ecatctl("upload", "0", hex(pdo), str(sub), "--type", "u32").stdout.split()[0], 16)
            out.append((v >> 16, (v >> 8) & 0xFF, v & 0xFF))
        return out

    def test_cia402_drive_reaches_operation_enabled(self):
        rx = self.mapping(0x1600)
        tx = self.mapping(0x1A00)
        self.assertEqual(rx[0][:2], (0x6040, 0))  # controlword first
        self.assertEqual(tx[0][:2], (0x6041, 0))  # statusword first
        size = sum(bits for _, _, bits in rx) // 8
        # Modes of operation (0x6060) = 8 (cyclic synchronous position), if it is mapped.
        mode = [0] * size
        offset = 0
        for index, _sub, bits in rx:
            if index == 0x6060:
                mode[offset // 8] = 8
            offset += bits

        def step(cycles, controlword):
            data = [controlword & 0xFF, controlword >> 8] + mode[2:]
            return ["--step", f"{cycles}:" + ",".join(f"{b:02x}" for b in data)]

        # Fault reset, shutdown, switch on, enable operation (CiA 402 state machine).
        args = step(50, 0x80) + step(50, 0x06) + step(50, 0x07) + step(100, 0x0F)
        r, _, lost, wkc_errors, _, _ = self.run_pd("-n", "100", *args)
        self.assertEqual((lost, wkc_errors), (0, 0))
        first = r.stdout.split("inputs:\n")[1].split()[1:3]
        statusword = int(first[0], 16) | int(first[1], 16) << 8
        self.assertEqual(statusword & 0x6F, 0x27, f"statusword 0x{statusword:04x}: not 'operation enabled'")

    def test_capture_of_a_cyclic_session_decodes_cleanly(self):
        self.run_pd("-n", "300", "--dc")
        self.assertEqual(self.bus.stop_slave(), 0, self.bus.slave_output())
        problems = harness.tshark_problems(self.bus.capture)
        if problems is None:
            self.skipTest("tshark not installed")
        self.assertEqual(problems, [], "\n".join(problems[:20]))


class ProcessDataWithABusySlave(unittest.TestCase):
    """The slave's other ways of waiting (`--spin-us`, `--busy-poll`) run the same cyclic sessions: OP in DC
    and in SM-synchronous mode, every cycle answered with the expected working counter, and the slave's
    statistics at exit show that it really spun to its deadlines / polled."""

    def session(self, bus, *args):
        r = bus.ecatctl("pd", "0", "-n", "500", "--cycle-us", "1000", *args)
        m = STATS.search(r.stdout)
        self.assertIsNotNone(m, r.stdout)
        self.assertIn("state: OP\n", r.stdout)
        self.assertEqual(tuple(int(x) for x in m.groups()[:3]), (500, 0, 0), r.stdout)

    def run_bus(self, waiting):
        bus = harness.Bus(slave_args=waiting + ["--verbose"]).__enter__()
        self.addCleanup(bus.close)
        if not bus.slave_supports(waiting[0]):
            self.skipTest(f"ecat-slave has no {waiting[0]}")
        self.session(bus, "--dc")
        self.session(bus)
        self.assertEqual(bus.stop_slave(), 0, bus.slave_output())
        return bus.slave_output()

    def test_spin_us(self):
        out = self.run_bus(["--spin-us", "200"])
        m = re.search(r"spin waits (\d+), mean (\d+) ns", out)
        self.assertIsNotNone(m, out)
        self.assertGreater(int(m.group(1)), 0, "SYNC0 deadlines were spun to")
        self.assertRegex(out, r"busy loop kept from running: \d+ times over 50 us")

    def test_busy_poll(self):
        out = self.run_bus(["--busy-poll"])
        self.assertRegex(out, r"busy loop kept from running: \d+ times over 50 us")
        self.assertNotRegex(out, r"spin waits", "busy polling never arms a spin")
        m = re.search(r"timer arms (\d+)", out)
        self.assertIsNotNone(m, out)
        self.assertEqual(int(m.group(1)), 0, "busy polling never arms the timer")


if __name__ == "__main__":
    harness.main()
