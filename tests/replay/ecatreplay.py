"""Replay of recorded master start-ups against the current ecat-slave (issue 22, docs/decisions/replay.md).

A recording is a pcap of the master end of a veth pair: the master's frames and the slave's replies, in the
order they crossed the link, beside a JSON sidecar that says how the slave was started. The replay sends the
recorded master frames in order, paced by their recorded times, and compares each reply with the recorded one
by the invariants a master relies on (project()), not by timing-dependent bytes. The rules, in short (the
decision record has them in full):

* Every datagram's working counter is compared; so are the data a read returns, except the registers and
  bytes whose value is a time or follows from timing (TIMING_REGISTERS, SM status of the process-data SMs)
  and the data of logical datagrams (process data: inputs come from the drive's motion).
* Polls: a frame that only reads (or only exchanges process data / distributes the clock) may be answered
  ahead of the recording (the observed answer equals the recorded answer of a later identical request within
  SETTLE_S of recording time: the slave was faster; the identical requests up to that one are then not sent,
  they were polls for what is already there) or behind it (the frame is sent again, every millisecond, until
  the recorded answer comes, for at most SETTLE_S: the slave was slower). A read that emptied a mailbox is not
  sent again.
* DC times the master writes (system time 0x0910, start time 0x0990) were computed from the recorded slave's
  clock: they are shifted by the difference between the replayed and the recorded local time (learnt from
  reads of 0x0910/0x0918).
* A request the recording has no reply for (lost on the link) is sent and its reply not checked.
The first mismatch ends the replay with the frame number, the datagram, and the recorded and observed values.
"""
import bisect
import gzip
import json
import os
import socket
import struct
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "integration"))
import harness  # noqa: E402

ETH_P_ECAT = 0x88A4

# EtherCAT commands (ETG.1000.4 table "EtherCAT command types").
NOP, APRD, APWR, APRW, FPRD, FPWR, FPRW, BRD, BWR, BRW, LRD, LWR, LRW, ARMW, FRMW = range(15)
NAMES = ["NOP", "APRD", "APWR", "APRW", "FPRD", "FPWR", "FPRW", "BRD", "BWR", "BRW", "LRD", "LWR", "LRW",
         "ARMW", "FRMW"]
READS = {APRD, FPRD, BRD}
LOGICAL = {LRD, LWR, LRW}
PHYS_WRITES = {APWR, APRW, FPWR, FPRW, BWR, BRW}
CLOCK = {ARMW, FRMW}

# Registers whose value is a time or follows from when frames came (ESC datasheet section II register
# descriptions): [start, end) byte ranges, masked in every read.
TIMING_REGISTERS = [
    (0x0220, 0x0224, "AL event request (set by SM accesses, cleared by the PDI when it gets to them)"),
    (0x0440, 0x0444, "watchdog status and counters"),
    (0x0900, 0x0920, "DC receive times, system time, local receive time"),
    (0x092C, 0x0930, "DC system time difference"),
    (0x0932, 0x0936, "DC speed counter difference"),
    (0x098E, 0x0990, "SYNC0/SYNC1 status"),
    (0x0990, 0x09A0, "DC start time / next SYNC1 pulse (the ESC moves it on)"),
    (0x09AE, 0x0A00, "latch status and latch times"),
]
# Bits of otherwise compared registers that follow from timing: [address] = mask of the bits not compared.
TIMING_BITS = {
    0x0110: 0x02,  # DL status bit 1: PDI watchdog reloaded in time (the slave's own task, under load)
}
SETTLE_S = 2.0  # how far (in recording time) an answer may come ahead of or behind the recording
CYCLE_GAP_S = 0.05  # a recorded process-data frame this soon after a poll: the master's cycle was running
# The replay's own pause between two process-data frames beyond the recording's, from which a slave's watchdog
# (100 ms by default) or its DC synchronisation check may rightly react: the host stalled the replay.
STALL_LIMIT_S = 0.05
SM_STATUS_MASKED_FROM = 2  # SM status (byte 5) of SM2 and up: buffer states of process data, timing


# ---------------------------------------------------------------------------------------------- pcap files
def read_pcap(path):
    """[(time_s, frame_bytes)] of a classic pcap (optionally gzip-compressed)."""
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rb") as f:
        data = f.read()
    magic = struct.unpack_from("<I", data, 0)[0]
    if magic in (0xA1B2C3D4, 0xA1B23C4D):
        end, nano = "<", magic == 0xA1B23C4D
    elif magic in (0xD4C3B2A1, 0x4D3CB2A1):
        end, nano = ">", magic == 0x4D3CB2A1
    else:
        raise ValueError(f"{path}: not a classic pcap file (magic 0x{magic:08x})")
    linktype = struct.unpack_from(end + "I", data, 20)[0]
    if linktype != 1:
        raise ValueError(f"{path}: link type {linktype}, expected Ethernet (1)")
    pos, out = 24, []
    while pos + 16 <= len(data):
        sec, frac, incl, _orig = struct.unpack_from(end + "IIII", data, pos)
        pos += 16
        out.append((sec + frac / (1e9 if nano else 1e6), data[pos:pos + incl]))
        pos += incl
    return out


def write_pcap(path, frames):
    """frames: [(time_s, bytes)] -> classic microsecond pcap, gzip-compressed when path ends in .gz."""
    parts = [struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)]
    for t, fr in frames:
        sec = int(t)
        parts.append(struct.pack("<IIII", sec, int(round((t - sec) * 1e6)) % 1000000, len(fr), len(fr)) + fr)
    body = b"".join(parts)
    if path.endswith(".gz"):
        with gzip.GzipFile(path, "wb", mtime=0) as f:
            f.write(body)
    else:
        with open(path, "wb") as f:
            f.write(body)


# ---------------------------------------------------------------------------------------------- frames
def ecat_offset(frame):
    """Offset of the EtherCAT header in an Ethernet frame (after an optional VLAN tag), or None."""
    if len(frame) < 16:
        return None
    et = struct.unpack_from(">H", frame, 12)[0]
    if et == 0x8100 and len(frame) >= 20 and struct.unpack_from(">H", frame, 16)[0] == ETH_P_ECAT:
        return 18
    return 14 if et == ETH_P_ECAT else None


def datagrams(frame):
    """[(cmd, idx, adp, ado, data, wkc)] walked by the datagram headers (length and More bit) up to the end of
    the frame, as an ESC walks them (the EtherCAT header's length is not relied on)."""
    off = ecat_offset(frame)
    if off is None:
        return []
    pos, out = off + 2, []
    while pos + 12 <= len(frame):
        cmd, idx, adp, ado, lf, _irq = struct.unpack_from("<BBHHHH", frame, pos)
        n = lf & 0x7FF
        if pos + 12 + n > len(frame):
            break
        out.append((cmd, idx, adp, ado, frame[pos + 10:pos + 10 + n],
                    struct.unpack_from("<H", frame, pos + 10 + n)[0]))
        pos += 12 + n
        if not lf & 0x8000:
            break
    return out


def keys(frame):
    """What a reply keeps of its request: command, index, offset and length of each datagram."""
    return tuple((d[0], d[1], d[3], len(d[4])) for d in datagrams(frame))


def request_identity(frame):
    """Two requests are 'the same request' (a poll repeated) when their datagrams have the same command, address
    and length and, for those that write physical memory, the same data (the index may differ)."""
    return tuple((d[0], d[2], d[3], len(d[4]), bytes(d[4]) if d[0] in PHYS_WRITES and not _clock_write(d) else b"")
                 for d in datagrams(frame))


def _clock_write(d):
    """A write of the master's time to a reference clock's system time (0x0910, IgH's
    ecrt_master_sync_reference_clock every cycle): the cycle's clock distribution, like FRMW."""
    return d[0] in (APWR, FPWR, BWR) and d[3] == 0x0910 and len(d[4]) in (4, 8)


def pair(frames):
    """Recorded frames -> [(time, request, reply or None)]: a frame is a reply when its source address has bit 1
    of the first byte set (an ESC sets it) and a request with its keys is waiting; it answers the oldest such
    request (a master may have several frames with the same index in flight: libethercat does). Anything else
    with EtherCAT datagrams is a request."""
    out, pending = [], {}
    for t, fr in frames:
        k = keys(fr)
        if not k:
            continue
        if fr[6] & 0x02 and pending.get(k):
            out[pending[k].pop(0)][2] = fr
            continue
        pending.setdefault(k, []).append(len(out))
        out.append([t, fr, None])
    return [tuple(x) for x in out]


# ---------------------------------------------------------------------------------------------- invariants
def _masked_bytes(cmd, ado, n):
    """Indices of the data bytes of a physical read at ado..ado+n that are timing-dependent."""
    masked = set()
    for lo, hi, _why in TIMING_REGISTERS:
        for a in range(max(lo, ado), min(hi, ado + n)):
            masked.add(a - ado)
    for sm in range(SM_STATUS_MASKED_FROM, 16):
        a = 0x0800 + 8 * sm + 5
        if ado <= a < ado + n:
            masked.add(a - ado)
    return masked


def project(request, reply):
    """The invariants of a reply: per datagram (working counter, data with timing-dependent bytes as None)."""
    out = []
    for (cmd, _i, _adp, ado, _rq, _w), (_c, _i2, _a2, _o2, data, wkc) in zip(datagrams(request), datagrams(reply)):
        if cmd in LOGICAL or cmd == NOP:
            out.append((wkc, None))
            continue
        masked = _masked_bytes(cmd, ado, len(data))
        out.append((wkc, tuple(None if i in masked else b & ~TIMING_BITS.get(ado + i, 0) & 0xFF
                               for i, b in enumerate(data))))
    return out


def describe(request, index):
    d = datagrams(request)[index]
    name = NAMES[d[0]] if d[0] < len(NAMES) else f"cmd {d[0]}"
    return f"datagram {index} {name} adp 0x{d[2]:04x} ado 0x{d[3]:04x} len {len(d[4])}"


def _fmt(v):
    wkc, data = v
    if data is None:
        return f"wkc {wkc}"
    return f"wkc {wkc} data " + "".join("??" if b is None else f"{b:02x}" for b in data[:64]) + (
        "..." if len(data) > 64 else "")


def difference(request, recorded, observed):
    """Text naming the first datagram whose invariants differ, or None."""
    rec, obs = project(request, recorded), project(request, observed)
    if len(rec) != len(obs):
        return f"{len(obs)} datagrams in the reply, recorded {len(rec)}"
    for i, (a, b) in enumerate(zip(rec, obs)):
        if a != b:
            where = ""
            if a[0] == b[0] and a[1] is not None and b[1] is not None:
                first = next(k for k, (x, y) in enumerate(zip(a[1], b[1])) if x != y)
                where = f" (first difference at data byte {first})"
            return f"{describe(request, i)}{where}: recorded {_fmt(a)}, observed {_fmt(b)}"
    return None


def read_only(request):
    """A frame that changes nothing a repetition would change again: reads, process data, clock distribution
    (FRMW/ARMW and the master's time written to 0x0910)."""
    return all(d[0] in READS or d[0] in LOGICAL or d[0] in CLOCK or d[0] == NOP or _clock_write(d)
               for d in datagrams(request))


def consumed(request, reply):
    """True if the reply shows a read that emptied a mailbox (memory at 0x1000 and up read with wkc > 0)."""
    return any(d[0] in READS and d[3] >= 0x1000 and r[5] > 0
               for d, r in zip(datagrams(request), datagrams(reply)))


# ---------------------------------------------------------------------------------------------- DC times
class ClockShift:
    """The replayed slave's clock is not the recorded one's: DC times the master computed from a read of it are
    moved by the difference the last read of the system time (0x0910) or local time (0x0918) showed, plus how much
    further the replay lags behind the recording since that read (a start time 'now + 100 ms' written late must
    still be 100 ms ahead of the slave's clock)."""

    def __init__(self):
        self.delta = 0
        self.lag = 0.0

    def learn(self, request, recorded, observed, lag):
        for d, r, o in zip(datagrams(request), datagrams(recorded), datagrams(observed)):
            if d[0] not in READS | CLOCK or not r[5] or not o[5]:
                continue
            for reg in (0x0910, 0x0918):
                k = reg - d[3]
                if 0 <= k and k + 8 <= len(r[4]) and k + 8 <= len(o[4]):
                    rec = struct.unpack_from("<Q", r[4], k)[0]
                    obs = struct.unpack_from("<Q", o[4], k)[0]
                    self.delta, self.lag = (obs - rec) & 0xFFFFFFFFFFFFFFFF, lag
                    break

    def rewrite(self, request, lag):
        """The request with times written to 0x0910 and 0x0990 moved by the learnt difference."""
        if not self.delta:
            return request
        delta = (self.delta + int((lag - self.lag) * 1e9)) & 0xFFFFFFFFFFFFFFFF
        fr = bytearray(request)
        off = ecat_offset(request)
        pos = off + 2
        for d in datagrams(request):
            cmd, ado, n = d[0], d[3], len(d[4])
            if cmd in PHYS_WRITES and ado in (0x0910, 0x0990) and n in (4, 8):
                fmt = "<Q" if n == 8 else "<I"
                mask = (1 << (8 * n)) - 1
                v = struct.unpack_from(fmt, fr, pos + 10)[0]
                struct.pack_into(fmt, fr, pos + 10, (v + delta) & mask)
            pos += 12 + n
        return bytes(fr)


# ---------------------------------------------------------------------------------------------- the replay
def _settled(request, recorded, observed, later):
    """Whether the observed answer to a read-only request is one the recording allows: every datagram answered as
    recorded, or as the same datagram of one of the later identical requests (later: their recorded replies, in
    order). The datagrams of one frame (the states of several slaves) may each be at a different point.
    Returns None (no), 0 (as recorded) or the number of later requests the answer is ahead of (1..)."""
    rec, obs = project(request, recorded), project(request, observed)
    if len(rec) != len(obs):
        return None
    lat = [project(request, r) for r in later]
    furthest = 0
    for k, o in enumerate(obs):
        if o == rec[k]:
            continue
        n = next((m + 1 for m, p in enumerate(lat) if len(p) == len(obs) and p[k] == o), None)
        if n is None:
            return None
        furthest = max(furthest, n)
    return furthest


def _same_poll_later(pairs, ids, i, end, settle_s):
    """The later requests whose recorded answers frame i may be answered with (ahead): the identical requests
    within settle_s, before the master's next write (end), and not past a recorded read that emptied a mailbox.
    That read changes the slave's state as a write does: the mailbox is empty before the answer came and again
    after it was read, and an empty answer to a poll that recorded the answer is the slave being behind (its
    firmware has not written the answer yet), never ahead. A read recorded as emptying the mailbox ends the list
    (it is the last one in it); when frame i is that read, nothing later is ahead of it."""
    t = pairs[i][0]
    if pairs[i][2] is not None and consumed(pairs[i][1], pairs[i][2]):
        return []
    out = []
    for j in range(i + 1, end):
        if pairs[j][0] - t > settle_s:
            break
        if ids[j] != ids[i] or pairs[j][2] is None:
            continue
        out.append(j)
        if consumed(pairs[j][1], pairs[j][2]):
            break
    return out


AL_CONTROL = 0x0120


def _repeats_state_request(request, previous_write):
    """True if request writes nothing but AL control (0x0120; its other datagrams read-only: reads, process data,
    the clock) and is identical to the master's previous frame that was not read-only. A master that requests a
    state again while it polls for it (libethercat every 5 ms until the slave is there) asks the same question:
    when the slave's firmware completes the transition, earlier or later than in the recording, is timing."""
    if previous_write is None:
        return False
    writes = [d for d in datagrams(request)
              if not (d[0] in READS or d[0] in LOGICAL or d[0] in CLOCK or d[0] == NOP or _clock_write(d))]
    return (bool(writes) and all(d[0] in PHYS_WRITES and d[3] == AL_CONTROL and len(d[4]) == 2 for d in writes)
            and request_identity(request) == request_identity(previous_write))


def _next_writes(pairs):
    """For each frame, the index of the master's next frame that ends its polls' 'same poll later' list: the next
    frame that is not read-only, except one that repeats the master's last state request (_repeats_state_request):
    the polls before and after it ask whether the slave reached that state."""
    ends = [len(pairs)] * len(pairs)
    previous, ending = None, []
    for k, (_t, rq, _rp) in enumerate(pairs):
        if read_only(rq):
            continue
        if not _repeats_state_request(rq, previous):
            ending.append(k)
        previous = rq
    nxt, e = len(pairs), len(ending) - 1
    for k in range(len(pairs) - 1, -1, -1):
        while e >= 0 and ending[e] > k:
            nxt = ending[e]
            e -= 1
        ends[k] = nxt
    return ends


class Mismatch(AssertionError):
    pass


class HostStall(Mismatch):
    """A mismatch after the replay itself fell behind the recording's process-data cycle by more than
    STALL_LIMIT_S: the slave may have answered the gap the host made rather than the recording (a stalled
    host), so the verdict is not the slave's."""


def _is_reply(request, data):
    """The slave's answer to request: source address bit 1 set (an ESC sets it) and the request's datagram keys,
    walked as an ESC walks them (keys())."""
    return bool(data[6] & 0x02) and keys(data) == keys(request)


_index = [0]


def _exchange(sock, frame, timeout):
    """Sends frame, returns the reply to it or None (harness.exchange: queued frames dropped first). Every send
    carries a fresh datagram index (the slave does not look at it; ETG.1000.4 leaves it to the master), so a late
    reply to an earlier send of the same poll is never taken for this one's."""
    _index[0] = (_index[0] + 1) & 0xFF
    fr = bytearray(frame)
    off = ecat_offset(frame)
    pos = off + 2
    for d in datagrams(frame):
        fr[pos + 1] = _index[0]
        pos += 12 + len(d[4])
    return harness.exchange(sock, bytes(fr), timeout, match=_is_reply)


def replay(pairs, iface, settle_s=SETTLE_S, reply_timeout=0.5, log=None, exchange=None):
    """Sends the recorded requests on iface and checks the replies; raises Mismatch at the first difference.
    Returns counters {frames, checked, ahead, behind, resent, skipped}. exchange(frame, timeout) -> reply or None
    replaces the link (iface is then not used): the rules' own tests answer with a simulated slave."""
    sock = None
    if exchange is None:
        sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ECAT))
        sock.bind((iface, 0))
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)

        def exchange(frame, timeout):
            return _exchange(sock, frame, timeout)
    ids = [request_identity(rq) for _t, rq, _rp in pairs]
    stats = {"frames": 0, "checked": 0, "ahead": 0, "behind": 0, "resent": 0, "skipped": 0, "kept_cycling": 0}
    skip = set()
    last_cycle = None
    # Times of the recorded process-data frames: while the recording's cycle runs on past a poll (a master with a
    # cyclic task beside its state machine), the replay keeps it running while it waits; a master that stopped
    # cycling (to see the watchdog trip) is not helped along.
    cycle_times = [t for t, rq, _rp in pairs if read_only(rq) and any(d[0] in LOGICAL for d in datagrams(rq))]
    next_write = _next_writes(pairs)
    clock = ClockShift()
    t0_rec = pairs[0][0] if pairs else 0.0
    t0 = time.monotonic()
    # The longest pause of the replay's own process data beyond the recording's: (excess s, frame number).
    stall = [0.0, 0]
    last_pd = [None, None]  # monotonic time and recorded time of the last process-data frame sent

    def sent_pd(t_rec, i):
        now = time.monotonic()
        if last_pd[0] is not None:
            excess = (now - last_pd[0]) - (t_rec - last_pd[1])
            if excess > stall[0]:
                stall[:] = [excess, i + 1]
        last_pd[:] = [now, t_rec]

    def mismatch(text):
        if stall[0] > STALL_LIMIT_S:
            return HostStall(f"{text} (the replay itself had paused its process data {stall[0] * 1000:.0f} ms "
                             f"longer than the recording before frame {stall[1]}: a stalled host)")
        return Mismatch(text)
    try:
        for i, (t, request, recorded) in enumerate(pairs):
            if i in skip:
                stats["skipped"] += 1
                continue
            wait = t0 + (t - t0_rec) - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            lag = (time.monotonic() - t0) - (t - t0_rec)
            frame = clock.rewrite(request, lag)
            stats["frames"] += 1
            observed = exchange(frame, reply_timeout)
            if any(d[0] in LOGICAL for d in datagrams(request)):
                sent_pd(t, i)
            if read_only(request) and any(d[0] in LOGICAL for d in datagrams(request)):
                last_cycle = frame
            if log and observed is None:
                log(f"frame {i + 1}: no reply within {reply_timeout} s ({describe(request, 0)})")
            if recorded is None:
                continue  # lost in the recording: nothing to compare
            tries = 0
            while observed is None and read_only(request) and tries < 3:
                tries += 1
                observed = exchange(frame, reply_timeout)
            if observed is None:
                raise mismatch(f"frame {i + 1} ({describe(request, 0)}): no reply (recorded one)")
            stats["checked"] += 1
            diff = difference(request, recorded, observed)
            if diff is None:
                clock.learn(request, recorded, observed, lag)
                continue
            if read_only(request):
                # The same poll later: identical requests within settle_s, up to the master's next write (after
                # it the same read asks about something else, e.g. the next SII word).
                later = _same_poll_later(pairs, ids, i, next_write[i], settle_s)
                verdict = _settled(request, recorded, observed, [pairs[j][2] for j in later])
                if verdict is not None and verdict > 0:
                    # Ahead: each datagram answered as in the recording or as a later identical request was.
                    stats["ahead"] += 1
                    if log:
                        log(f"frame {i + 1}: ahead, answered as frame {later[verdict - 1] + 1} was ({diff})")
                    if not any(d[0] in LOGICAL for d in datagrams(request)):
                        skip.update(k for k in later[:verdict])
                    continue
                # Behind: send again until the recorded answer comes (or, datagram by datagram, a later one).
                if not consumed(request, observed):
                    k = bisect.bisect_right(cycle_times, t)
                    cycling = k < len(cycle_times) and cycle_times[k] - t <= CYCLE_GAP_S
                    deadline = time.monotonic() + settle_s
                    while verdict is None and time.monotonic() < deadline:
                        time.sleep(0.001)
                        if last_cycle is not None and last_cycle is not frame and cycling:
                            # The master's cycle runs on while it polls (its own task or thread): the last
                            # process-data frame again, so watchdogs and clocks see what they saw in the recording.
                            exchange(last_cycle, reply_timeout)
                            last_pd[0] = time.monotonic()
                            stats["kept_cycling"] += 1
                        stats["resent"] += 1
                        observed = exchange(frame, reply_timeout)
                        if observed is None:
                            continue
                        verdict = _settled(request, recorded, observed, [pairs[j][2] for j in later])
                        diff = difference(request, recorded, observed)
                        if verdict is None and consumed(request, observed):
                            break
                    if log:
                        log(f"frame {i + 1}: behind, sent again for {time.monotonic() - deadline + settle_s:.3f} s "
                            f"({describe(request, 0)})")
                    if verdict is not None:
                        stats["behind"] += 1
                        if verdict > 0 and not any(d[0] in LOGICAL for d in datagrams(request)):
                            skip.update(k for k in later[:verdict])
                        if diff is None:
                            clock.learn(request, recorded, observed, lag)
                        continue
            raise mismatch(f"frame {i + 1} of {len(pairs)} (recorded at {t - t0_rec:.6f} s): {diff}")
    finally:
        if sock is not None:
            sock.close()
    if log:
        log(f"replayed {stats}")
    return stats


# ---------------------------------------------------------------------------------------------- the corpus
HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")


def corpus():
    """[(name, pcap path, sidecar dict)] of every recording in tests/replay/corpus."""
    out = []
    for f in sorted(os.listdir(CORPUS)):
        if f.endswith(".json"):
            name = f[:-5]
            with open(os.path.join(CORPUS, f)) as fh:
                side = json.load(fh)
            out.append((name, os.path.join(CORPUS, side["pcap"]), side))
    return out


def summary(pairs):
    """What a recording shows the master got: the slaves counted by broadcast reads (the largest working counter
    of a BRD), the last AL status read of each station (FPRD 0x0130) and the working counters of the logical
    datagrams of the last second."""
    slaves, states, lwkc = 0, {}, {}
    end = pairs[-1][0] if pairs else 0
    for t, rq, rp in pairs:
        if rp is None:
            continue
        for d, r in zip(datagrams(rq), datagrams(rp)):
            if d[0] == BRD:
                slaves = max(slaves, r[5])
            if d[0] == FPRD and d[3] == 0x0130 and len(r[4]) >= 1 and r[5] == 1:
                states[d[2]] = r[4][0] & 0x1F
            if d[0] in LOGICAL and t > end - 1.0:
                lwkc[r[5]] = lwkc.get(r[5], 0) + 1
    return {"slaves": slaves, "al_states": {f"0x{k:04x}": v for k, v in sorted(states.items())},
            "logical_wkc_last_second": lwkc}
