"""The replay's poll rules (docs/decisions/replay.md, "Polls and timing") against a simulated slave: a recorded
mailbox exchange (request written, SM1 polled until the answer comes, then polled empty) must replay against a
slave that writes its answer at any legal moment (before the master's first poll, or after any number of them),
and must not replay against one that answers twice or never. No root, no link: ecatreplay.replay() is given
the simulated slave in place of the socket.

The class these tests hold: every order in which the slave's firmware and the master may legally interleave.
A recording holds one of them (here: the answer there at the first poll); a slower firmware answers the first
polls empty, and an empty poll before the answer must never be taken for the empty poll after it (which would
skip the read that empties the mailbox and find the answer still there one frame later)."""
import os
import struct
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "integration"))
import ecatreplay as er  # noqa: E402

SM0, SM1, N = 0x1000, 0x1080, 16
ANSWER = bytes([0x04, 0x00, 0x00, 0x00, 0x00, 0x20, 0x01, 0x00, 0x02, 0x00]) + bytes(N - 10)  # mailbox error
EMPTY = bytes(N)
REQUEST = bytes([0x08, 0x00, 0x00, 0x00, 0x00, 0x06]) + bytes(N - 6)  # reserved type 6


def frame(cmd, ado, data, wkc=0, reply=False):
    """An Ethernet frame with one datagram addressed to station 0x1001."""
    dg = struct.pack("<BBHHHH", cmd, 0, 0x1001, ado, len(data), 0) + data + struct.pack("<H", wkc)
    src = b"\x03" + bytes(5) if reply else b"\x01" + bytes(5)
    return b"\xff" * 6 + src + struct.pack(">H", er.ETH_P_ECAT) + struct.pack("<H", len(dg) | 0x1000) + dg


def recording(answered_at, polls_after):
    """[(t, request, reply)]: the request written, `answered_at` empty polls, the answer, `polls_after` empty
    polls, then the next request written (so the polls end at a write, as ecat-conform's do)."""
    pairs, t = [], 0.0

    def add(cmd, ado, data, rdata, wkc):
        nonlocal t
        pairs.append((t, frame(cmd, ado, data), frame(cmd, ado, rdata, wkc, reply=True)))
        t += 0.0002

    add(er.FPWR, SM0, REQUEST, REQUEST, 1)
    for _ in range(answered_at):
        add(er.FPRD, SM1, EMPTY, EMPTY, 0)
    add(er.FPRD, SM1, EMPTY, ANSWER, 1)
    for _ in range(polls_after):
        add(er.FPRD, SM1, EMPTY, EMPTY, 0)
    add(er.FPWR, SM0, REQUEST, REQUEST, 1)
    return pairs


class Slave:
    """A mailbox slave: a written request is answered once, after its firmware let `delay` reads of SM1 go by
    empty (its poll comes after theirs); `copies` > 1 is a faulty slave that writes the answer again."""

    def __init__(self, delay, copies=1):
        self.delay, self.copies = delay, copies
        self.waiting, self.left = 0, 0

    def __call__(self, request, _timeout):
        cmd, _idx, _adp, ado, data, _wkc = er.datagrams(request)[0]
        if cmd == er.FPWR and ado == SM0:
            self.waiting, self.left = self.delay, self.copies
            return frame(cmd, ado, data, 1, reply=True)
        if cmd == er.FPRD and ado == SM1:
            if self.left and self.waiting == 0:
                self.left -= 1
                return frame(cmd, ado, ANSWER, 1, reply=True)
            self.waiting = max(0, self.waiting - 1)
            return frame(cmd, ado, EMPTY, 0, reply=True)
        return None


AL_CONTROL, AL_STATUS = 0x0120, 0x0130
SAFEOP, OP, INIT = 0x04, 0x08, 0x01


def al(state):
    return struct.pack("<H", state)


def state_recording(reached_at, polls, rewrite_every):
    """[(t, request, reply)]: the slave in SAFEOP, the master requests OP and polls AL status `polls` times,
    writing the OP request again before every `rewrite_every`-th poll (0: never; libethercat: every one), the
    recorded slave in OP from poll `reached_at` on; then the master requests INIT and sees it."""
    pairs, t = [], 0.0

    def add(cmd, ado, data, rdata, wkc=1):
        nonlocal t
        pairs.append((t, frame(cmd, ado, data), frame(cmd, ado, rdata, wkc, reply=True)))
        t += 0.0002

    add(er.FPWR, AL_CONTROL, al(OP), al(OP))
    for n in range(polls):
        if rewrite_every and n and n % rewrite_every == 0:
            add(er.FPWR, AL_CONTROL, al(OP), al(OP))
        add(er.FPRD, AL_STATUS, al(0), al(OP if n >= reached_at else SAFEOP))
    add(er.FPWR, AL_CONTROL, al(INIT), al(INIT))
    add(er.FPRD, AL_STATUS, al(0), al(INIT))
    return pairs


class StateSlave:
    """A slave in SAFEOP whose firmware completes a requested OP after `delay` reads of AL status (its poll comes
    after theirs; a request repeated while it is pending changes nothing), and goes to INIT at once. Faults:
    `early` goes to OP when SAFEOP is requested (a state nobody asked for); `falls_back` leaves OP again for
    SAFEOP with the error flag after two reads in OP."""

    def __init__(self, delay, early=False, falls_back=False):
        self.delay, self.early, self.falls_back = delay, early, falls_back
        self.state, self.pending, self.reads_in_op = SAFEOP, None, 0

    def __call__(self, request, _timeout):
        cmd, _idx, _adp, ado, data, _wkc = er.datagrams(request)[0]
        if cmd == er.FPWR and ado == AL_CONTROL:
            want = struct.unpack("<H", bytes(data))[0]
            if want == OP or (want == SAFEOP and self.early):
                if self.state != OP and self.pending is None:
                    self.pending = self.delay
            elif want == INIT:
                self.state, self.pending = INIT, None
            return frame(cmd, ado, data, 1, reply=True)
        if cmd == er.FPRD and ado == AL_STATUS:
            if self.pending is not None:
                if self.pending == 0:
                    self.state, self.pending = OP, None
                else:
                    self.pending -= 1
            if self.state == OP:
                self.reads_in_op += 1
                if self.falls_back and self.reads_in_op > 2:
                    self.state = SAFEOP | 0x10
            return frame(cmd, ado, al(self.state), 1, reply=True)
        return None


class PollRules(unittest.TestCase):
    def test_every_timing_of_a_state_change_replays(self):
        """The recorded slave reached OP at the first, second or fifth poll; the master wrote its OP request once,
        again before every poll (libethercat) or before every third; the replayed slave's firmware completes the
        transition before the first poll or after up to ten: all pass. (With the old rule, a repeated request
        ended the list of later polls, and a slave in OP sooner than recorded failed: libethercat-example_with_dc
        at frame 4993 under load, AL status recorded SAFEOP, observed OP.)"""
        for rewrite_every in (0, 1, 3):
            for reached_at in (0, 1, 4):
                for delay in range(0, 11):
                    with self.subTest(rewrite_every=rewrite_every, recorded_at=reached_at, slave_delay=delay):
                        stats = er.replay(state_recording(reached_at, 12, rewrite_every), None, settle_s=0.5,
                                          exchange=StateSlave(delay))
                        self.assertEqual(stats["checked"], stats["frames"])

    def test_state_never_reached_fails(self):
        for rewrite_every in (0, 1):
            with self.subTest(rewrite_every=rewrite_every), self.assertRaises(er.Mismatch):
                er.replay(state_recording(1, 12, rewrite_every), None, settle_s=0.2, exchange=StateSlave(10**6))

    def test_state_left_again_fails(self):
        """OP reached, then SAFEOP with the error flag: no recorded answer says that."""
        for rewrite_every in (0, 1):
            with self.subTest(rewrite_every=rewrite_every), self.assertRaises(er.Mismatch):
                er.replay(state_recording(0, 12, rewrite_every), None, settle_s=0.2,
                          exchange=StateSlave(0, falls_back=True))

    def test_state_not_requested_yet_fails(self):
        """A different request ends the list: a slave in OP while the master has only asked for SAFEOP (and polls
        for it) fails, although OP is recorded after the master's OP request."""
        pairs, t = [], 0.0
        for cmd, ado, data, rdata in ([(er.FPWR, AL_CONTROL, al(SAFEOP), al(SAFEOP))] +
                                      [(er.FPRD, AL_STATUS, al(0), al(SAFEOP))] * 3 +
                                      [(er.FPWR, AL_CONTROL, al(OP), al(OP))] +
                                      [(er.FPRD, AL_STATUS, al(0), al(OP))] * 3):
            pairs.append((t, frame(cmd, ado, data), frame(cmd, ado, rdata, 1, reply=True)))
            t += 0.0002
        with self.assertRaises(er.Mismatch):
            er.replay(pairs, None, settle_s=0.2, exchange=StateSlave(0, early=True))

    def test_every_legal_timing_replays(self):
        """The answer recorded at the first, second or fifth poll; the replayed slave's firmware answers before
        the first poll or after up to ten: all pass."""
        for answered_at in (0, 1, 4):
            for delay in range(0, 11):
                with self.subTest(recorded_at=answered_at, slave_delay=delay):
                    stats = er.replay(recording(answered_at, 6), None, settle_s=0.5, exchange=Slave(delay))
                    self.assertEqual(stats["checked"], stats["frames"])

    def test_answer_twice_fails(self):
        """A slave that puts its answer in SM1 a second time fails, whatever its timing."""
        for delay in (0, 1, 3):
            with self.subTest(slave_delay=delay):
                with self.assertRaises(er.Mismatch):
                    er.replay(recording(1, 6), None, settle_s=0.5, exchange=Slave(delay, copies=2))

    def test_never_answering_fails(self):
        with self.assertRaises(er.Mismatch):
            er.replay(recording(1, 6), None, settle_s=0.2, exchange=Slave(10**6))


class CyclingSlave:
    """A slave in OP whose process-data watchdog expires when the process data pauses longer than 100 ms (the
    ESC's default): it then reports SAFEOP with error 0x001B. `stall_at`: the process-data frame (1-based) before
    which the host stalls the replay for `stall_s` (the exchange itself sleeps, as a descheduled master
    would); `defect`: reports SAFEOP + error without any pause."""

    def __init__(self, stall_at=None, stall_s=0.0, defect=False):
        import time
        self.time = time
        self.stall_at, self.stall_s, self.defect = stall_at, stall_s, defect
        self.frames, self.last, self.tripped = 0, None, False

    def __call__(self, request, _timeout):
        cmd, _idx, _adp, ado, data, _wkc = er.datagrams(request)[0]
        if cmd == er.LRW:
            self.frames += 1
            if self.frames == self.stall_at:
                self.time.sleep(self.stall_s)
            now = self.time.monotonic()
            if self.last is not None and now - self.last > 0.1:
                self.tripped = True
            self.last = now
            return frame(cmd, ado, data, 3, reply=True)
        if cmd == er.FPRD and ado == AL_STATUS:
            bad = self.tripped or self.defect
            return frame(cmd, ado, al(0x14 if bad else OP), 1, reply=True)
        return None


def cycling_recording(frames=40):
    """[(t, request, reply)]: process data every 2 ms, AL status read (OP) after every tenth frame."""
    pairs, t = [], 0.0
    for k in range(frames):
        pairs.append((t, frame(er.LRW, 0, bytes(4)), frame(er.LRW, 0, bytes(4), 3, reply=True)))
        t += 0.002
        if k % 10 == 9:
            pairs.append((t, frame(er.FPRD, AL_STATUS, bytes(2)), frame(er.FPRD, AL_STATUS, al(OP), 1, reply=True)))
            t += 0.0002
    return pairs


class HostStalls(unittest.TestCase):
    """The class: a verdict that depends on the host keeping the replay's pace. A slave that answers a pause
    the host made (its watchdog trips) is told apart from one that is wrong by itself: the first mismatch is
    a HostStall (test_replay.py replays it again), the second a Mismatch."""

    def test_a_pause_of_the_replay_makes_the_mismatch_a_host_stall(self):
        with self.assertRaises(er.HostStall) as cm:
            er.replay(cycling_recording(), None, settle_s=0.05, exchange=CyclingSlave(stall_at=15, stall_s=0.15))
        self.assertIn("paused its process data", str(cm.exception))

    def test_a_slave_wrong_by_itself_is_a_mismatch(self):
        with self.assertRaises(er.Mismatch) as cm:
            er.replay(cycling_recording(), None, settle_s=0.05, exchange=CyclingSlave(defect=True))
        self.assertNotIsInstance(cm.exception, er.HostStall)

    def test_the_same_slave_without_a_pause_replays(self):
        er.replay(cycling_recording(), None, settle_s=0.05, exchange=CyclingSlave())


if __name__ == "__main__":
    unittest.main()
