"""Soak (issue 14): a DC-synchronous cyclic session of 100 000 cycles of 1 ms with the real ecat-slave, 2% of the
frames dropped by the kernel (1% of what the master sends, 1% of what the slave sends back), 1% of the cycle
frames replaced by bad frames, and CoE mailbox traffic (SDO downloads and uploads, a refused write) running
beside it in the same master process (tests/integration/soak_master.cpp, ecat-soak). Afterwards: the slave is
still in OP without an error and consistent (every value written reads back, the outputs it took are ones the
master sent, no cycle came back with a wrong working counter), every SDO ended done or aborted with a code,
and the slave's statistics (--stats-file) count every bad frame, by reason.

The loss: an XDP program (generic XDP on the receiving side of both veth ends) drops a frame when
bpf_get_prandom_u32() falls under 1% of its range (netem is not in every kernel). Not tc: the master's and the
slave's raw sockets bypass the egress qdisc, and a packet socket bound to ETH_P_ALL (the links take VLAN-tagged
and UDP frames too) sees a frame before tc ingress can drop it; generic XDP runs before both. Frames from the
bad frames' own source address pass, so every bad frame reaches the slave and the slave's count must match
exactly. The loss shows as lost cycles on the master's side (XDP keeps no count of its own here).

ECAT_SOAK_CYCLES=N runs a shorter soak (default 100000: about 2 minutes); ctest label `soak`."""
import ctypes
import os
import re
import shutil
import struct
import subprocess
import tempfile
import unittest

import harness

BAD_SOURCE_WORD = 0x02BAD0BA  # first 4 bytes of the bad frames' source address (soak_master.cpp kBadSource)


def bpf_insn(code, dst=0, src=0, off=0, imm=0):
    return struct.pack("<BBhi", code, (src << 4) | dst, off, imm)


def loss_program(fraction):
    """eBPF for XDP: XDP_DROP for `fraction` of the frames (random), never for a frame from the bad frames'
    source address (bytes 6..9 of the frame, read little-endian)."""
    threshold = int(fraction * 2**32)
    bad_le = struct.unpack("<i", struct.pack(">I", BAD_SOURCE_WORD))[0]
    return b"".join([
        bpf_insn(0x61, 2, 1, 0),                  # r2 = ctx->data
        bpf_insn(0x61, 3, 1, 4),                  # r3 = ctx->data_end
        bpf_insn(0xBF, 4, 2),                     # r4 = r2
        bpf_insn(0x07, 4, 0, 0, 10),              # r4 += 10
        bpf_insn(0x2D, 4, 3, 4),                  # r4 > data_end: pass
        bpf_insn(0x61, 0, 2, 6),                  # r0 = source address bytes 0..3
        bpf_insn(0x16, 0, 0, 2, bad_le),          # (32-bit) a bad frame: pass
        bpf_insn(0x85, imm=7),                    # r0 = bpf_get_prandom_u32()
        bpf_insn(0xA5, 0, 0, 2, threshold),       # r0 < threshold: drop
        bpf_insn(0xB7, 0, 0, 0, 2),               # XDP_PASS
        bpf_insn(0x95),
        bpf_insn(0xB7, 0, 0, 0, 1),               # XDP_DROP
        bpf_insn(0x95),
    ])


def load_and_pin(program, path):
    """BPF_PROG_LOAD (type XDP) and BPF_OBJ_PIN at path (a bpffs), through the bpf() system call."""
    libc = ctypes.CDLL(None, use_errno=True)
    sys_bpf = 321  # x86_64
    code = ctypes.create_string_buffer(program, len(program))
    lic = ctypes.create_string_buffer(b"GPL")
    log = ctypes.create_string_buffer(16384)
    attr = struct.pack("<IIQQIIQI", 6, len(program) // 8, ctypes.addressof(code), ctypes.addressof(lic), 1,
                       len(log), ctypes.addressof(log), 0)
    attr = ctypes.create_string_buffer(attr.ljust(128, b"\0"), 128)
    fd = libc.syscall(sys_bpf, 5, attr, 128)
    if fd < 0:
        raise OSError(ctypes.get_errno(), f"BPF_PROG_LOAD: {log.value.decode(errors='replace')}")
    try:
        name = ctypes.create_string_buffer(path.encode())
        attr = ctypes.create_string_buffer(struct.pack("<QII", ctypes.addressof(name), fd, 0).ljust(128, b"\0"), 128)
        if libc.syscall(sys_bpf, 6, attr, 128) != 0:
            raise OSError(ctypes.get_errno(), "BPF_OBJ_PIN")
    finally:
        os.close(fd)


def values(text):
    return {k: int(v) for k, v in (line.split()[:2] for line in text.splitlines() if len(line.split()) >= 2)
            if re.fullmatch(r"-?\d+", v)}


class Soak(unittest.TestCase):
    def test_dc_session_with_loss_bad_frames_and_mailbox_traffic(self):
        soak = harness.env_path("ECAT_SOAK")
        if shutil.which("tc") is None:
            self.skipTest("tc (iproute2) not installed")
        cycles = int(os.environ.get("ECAT_SOAK_CYCLES", "100000"))
        d = tempfile.mkdtemp(dir=os.environ.get("ECAT_TEST_OUT") or None)
        self.addCleanup(shutil.rmtree, d, True)
        stats_file = os.path.join(d, "stats.txt")
        bus = harness.Bus(slave_args=["--stats-file", stats_file]).__enter__()
        self.addCleanup(bus.close)

        # 1% loss on each direction: the program on the receiving side of the master's end (frames coming
        # back) and of the slave's end in its namespace (frames going out).
        fs = os.path.join(d, "bpffs")
        os.makedirs(fs)
        if subprocess.run(["mount", "-t", "bpf", "bpf", fs]).returncode != 0:
            self.skipTest("cannot mount a bpf filesystem")
        self.addCleanup(subprocess.run, ["umount", fs])
        pinned = os.path.join(fs, "loss")
        try:
            load_and_pin(loss_program(0.01), pinned)
        except OSError as e:
            self.skipTest(f"cannot load the loss program: {e}")
        ns = ["ip", "netns", "exec", bus.ns]
        for prefix, dev in (([], bus.iface), (ns, bus.slave_iface)):
            r = subprocess.run(prefix + ["ip", "link", "set", "dev", dev, "xdpgeneric", "pinned", pinned],
                               capture_output=True, text=True)
            if r.returncode != 0:
                self.skipTest(f"cannot attach the loss program (generic XDP): {r.stderr.strip()}")

        r = subprocess.run([soak, "--iface", bus.iface, "--cycles", str(cycles), "--cycle-us", "1000",
                            "--bad-percent", "1", "--sdo-every", "20"],
                           capture_output=True, text=True, timeout=1800)
        self.assertEqual(r.returncode, 0, f"{r.stdout}\n{r.stderr}\nslave: {bus.slave_output()}")
        master = values(r.stdout)
        self.assertEqual(bus.stop_slave(), 0, bus.slave_output())
        with open(stats_file) as f:
            slave = values(f.read())
        print(f"\nsoak (master side):\n{r.stdout}slave statistics: {slave}", flush=True)

        # The session ran its cycles; the loss was real.
        self.assertEqual(master["cycles_ok"] + master["cycles_lost"] + master["wkc_errors"] +
                         master["other_errors"] + master["bad_frames"], cycles)
        if cycles >= 10000:
            self.assertGreater(master["cycles_lost"], 0)
            self.assertGreater(master["bad_frames"], 0)
        # No state corruption: OP without an error, every cycle that came back had the expected working
        # counter, values written read back, the slave's outputs are ones the master sent.
        self.assertEqual((master["final_state"], master["final_error"]), (8, 0), r.stdout)
        self.assertEqual((master["wkc_errors"], master["other_errors"]), (0, 0), r.stdout)
        self.assertEqual(master["sdo_mismatches"], 0, r.stdout)
        self.assertEqual(master["target_recent"], 1, r.stdout)
        # Every SDO done or aborted with a code (and the refused write with the right one).
        self.assertGreater(master["sdo_ops"], 0)
        self.assertEqual(master["sdo_no_answer"], 0, r.stderr)
        self.assertEqual(master["sdo_done"] + master["sdo_aborted"], master["sdo_ops"])
        self.assertEqual(master["sdo_wrong_abort"], 0, r.stdout)
        # The slave counted every bad frame, by reason; and nothing else was malformed.
        self.assertEqual(master["bad_refused"], 0)
        self.assertEqual(slave["esc.frames_malformed"], master["bad_frames"], slave)
        for reason in ("length", "datagram"):
            self.assertEqual(slave[f"esc.malformed_{reason}"], master[f"bad_{reason}"], (reason, slave))


if __name__ == "__main__":
    harness.main()
