"""A slave process stopped (SIGSTOP) while the master keeps cycling looks to the master like an ESC whose firmware
paused: the ESC took every frame when it arrived (the kernel's receive time stamp), so the process-data watchdog
(ESC datasheet 0x0400/0x0420, 100 ms), refreshed in time by every LRW, does not expire (its counter 0x0442 stays)
and the slave stays in OP. It expired when the runtime ticked the ESC to "now" before it took the frames queued
during the stop (the counter counted it; AL status SAFEOP + 0x001B when the firmware saw it). A slave that spins
to its deadlines (--spin-us) is stopped while it waits awake for one, the case that ticked before taking the
frames; a slave that sleeps to them is stopped in its wait."""
import os
import signal
import threading
import time
import unittest

import harness

OP = 8


class PausedSlave(unittest.TestCase):
    def stop_three_times(self, *slave_args):
        bus = harness.bus_in_preop(self, *slave_args)
        mm = harness.MiniMaster(bus)
        self.addCleanup(mm.close)
        mm.to_op(dc=True)
        self.assertEqual(mm.states, [OP])
        expiries = mm.fprd(0x1001, 0x0442, 1)[0]  # process-data watchdog counter
        for stop in range(3):
            # Cycles go on (a frame at least every 50 ms, the reply timeout) while the slave is stopped for 150 ms.
            result = {}
            master = threading.Thread(target=lambda: result.update(mm.run(500)))
            master.start()
            try:
                time.sleep(0.1)
                os.kill(bus.proc.pid, signal.SIGSTOP)
                try:
                    time.sleep(0.15)
                finally:
                    os.kill(bus.proc.pid, signal.SIGCONT)
            finally:
                master.join()
            self.assertGreater(result.get("lost", 0), 0, "the stop was not seen by the master")
            mm.run(20)
            code = mm.al_code(0x1001)
            self.assertEqual((mm.states, hex(code)), ([OP], "0x0"),
                             f"stop {stop}: left OP (AL status code {hex(code)})\n{bus.slave_output()[-2000:]}")
            self.assertEqual(mm.fprd(0x1001, 0x0442, 1)[0], expiries, f"stop {stop}: process-data watchdog expired")

    def test_a_slave_stopped_while_it_spins_to_a_deadline_stays_in_op(self):
        self.stop_three_times("--spin-us", "2000")

    def test_a_slave_stopped_while_it_sleeps_stays_in_op(self):
        self.stop_three_times()


if __name__ == "__main__":
    harness.main()
