"""The recorded start-ups of foreign masters (tests/replay/corpus), replayed against the current ecat-slave
(docs/decisions/replay.md): each reply must keep the invariants the master relied on. A slave broken on purpose
(--fault) must fail the replay, so the test can fail."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "integration"))
import harness  # noqa: E402
import ecatreplay  # noqa: E402

ONLY = os.environ.get("ECAT_REPLAY_ONLY")  # a name, to replay one recording


def replay(name, pcap, side, extra_args=()):
    """Starts the slave as the recording's was started (sidecar slave_args), on a fresh veth pair, and replays.
    A mismatch after the host stalled the replay (ecatreplay.HostStall) is not the slave's: the replay starts
    again with a fresh slave, up to three times in all."""
    pairs = ecatreplay.pair(ecatreplay.read_pcap(pcap))
    for attempt in range(1, 4):
        with harness.Bus(slave_args=list(side["slave_args"]) + list(extra_args)) as bus:
            try:
                return ecatreplay.replay(pairs, bus.iface)
            except ecatreplay.HostStall as e:
                if attempt == 3:
                    raise ecatreplay.Mismatch(f"{name}: {e}\nslave: {bus.slave_output()[-1500:]}") from None
                print(f"{name}: replayed again (attempt {attempt + 1}): {e}", file=sys.stderr)
            except ecatreplay.Mismatch as e:
                raise ecatreplay.Mismatch(f"{name}: {e}\nslave: {bus.slave_output()[-1500:]}") from None


class Replay(unittest.TestCase):
    def test_corpus(self):
        entries = [e for e in ecatreplay.corpus() if not ONLY or e[0] == ONLY]
        self.assertTrue(entries, "no recordings in tests/replay/corpus")
        for name, pcap, side in entries:
            with self.subTest(recording=name):
                stats = replay(name, pcap, side)
                print(f"{name}: {stats}")
                self.assertGreater(stats["checked"], 0)

    def test_recordings_decode_cleanly(self):
        """The corpus decodes in tshark without malformed packets or expert errors; a recording whose master sends
        malformed requests on purpose (sidecar malformed_requests: ecat-conform's robustness tests) may have
        them in those requests and in the replies that carry their data back, nowhere else. One tshark run over
        all recordings one after the other."""
        if not shutil.which("tshark"):
            self.skipTest("tshark not installed")
        entries = ecatreplay.corpus()
        frames, owner = [], []
        for name, pcap, side in entries:
            f = ecatreplay.read_pcap(pcap)
            owner += [(name, side, len(frames))] * len(f)
            frames += f
        with tempfile.NamedTemporaryFile(suffix=".pcap") as f:
            ecatreplay.write_pcap(f.name, frames)
            r = subprocess.run(["tshark", "-r", f.name, "-Y", "_ws.malformed || _ws.expert.severity == error",
                                "-T", "fields", "-e", "frame.number"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, timeout=300)
        self.assertEqual(r.returncode, 0, r.stderr)
        bad = {int(x) - 1 for x in r.stdout.split()}
        allowed = set()
        for i in bad:  # a deliberately malformed request, and the replies with its datagrams' keys
            name, side, base = owner[i]
            if side.get("malformed_requests") and not frames[i][1][6] & 0x02:
                k = ecatreplay.keys(frames[i][1])
                allowed |= {j for j in bad if owner[j][0] == name and ecatreplay.keys(frames[j][1]) == k}
        rest = sorted(bad - allowed)
        self.assertEqual([f"{owner[i][0]} frame {i - owner[i][2] + 1}" for i in rest[:20]], [],
                         "frames tshark reports as malformed")

    def test_faulty_slave_fails(self):
        """A slave that answers an expedited SDO upload with the wrong size (a mailbox answer) or never starts
        SYNC0 (so Op is refused: AL status and code), or refuses Bootstrap (so no firmware update), does not pass
        the replay of a master that relies on it."""
        by_name = {e[0]: e for e in ecatreplay.corpus()}
        cases = [("soem-slaveinfo", "expedited-size-wrong"), ("libethercat-example_with_dc", "sync0-never"),
                 ("soem-firm_update", "bootstrap-refused"), ("libethercat-foe_tool", "bootstrap-refused")]
        for rec, fault in cases:
            self.assertIn(rec, by_name)
            with self.subTest(recording=rec, fault=fault):
                name, pcap, side = by_name[rec]
                with self.assertRaises(ecatreplay.Mismatch) as cm:
                    replay(name, pcap, side, ["--fault", fault])
                print(f"{rec} with --fault {fault}: {cm.exception}")

    def test_tampered_recording_fails(self):
        """The poll rules accept no answer the recording does not hold: a recording with one SII word or one
        mailbox answer changed fails at that frame against the correct slave."""
        by_name = {e[0]: e for e in ecatreplay.corpus()}

        def first(pairs, want):
            return next(i for i, (_t, rq, rp) in enumerate(pairs) if rp is not None and want(pairs, i))

        def sii_vendor_word(pairs, i):  # the read of SII word 8 (vendor id), after the address that asked for it
            d = ecatreplay.datagrams(pairs[i][1])[0]
            if d[0] != ecatreplay.FPRD or d[3] != 0x0508:
                return False
            for k in range(i - 1, max(i - 5, -1), -1):
                p = ecatreplay.datagrams(pairs[k][1])[0]
                if p[0] == ecatreplay.FPWR and p[3] == 0x0504:
                    return p[4][:2] == b"\x08\x00"
            return False

        def mailbox_answer(pairs, i):
            d, r = ecatreplay.datagrams(pairs[i][1])[0], ecatreplay.datagrams(pairs[i][2])[0]
            return d[0] == ecatreplay.FPRD and d[3] >= 0x1000 and r[5] == 1

        for rec, want, byte in (("libethercat-eepromtool", sii_vendor_word, 0), ("soem-slaveinfo", mailbox_answer, 8)):
            with self.subTest(recording=rec):
                name, pcap, side = by_name[rec]
                pairs = ecatreplay.pair(ecatreplay.read_pcap(pcap))
                i = first(pairs, want)
                t, rq, rp = pairs[i]
                reply = bytearray(rp)
                reply[ecatreplay.ecat_offset(rp) + 2 + 10 + byte] ^= 0x01
                pairs[i] = (t, rq, bytes(reply))
                with harness.Bus(slave_args=side["slave_args"]) as bus:
                    with self.assertRaises(ecatreplay.Mismatch) as cm:
                        ecatreplay.replay(pairs, bus.iface)
                self.assertIn(f"frame {i + 1} of", str(cm.exception))
                print(f"{rec} with frame {i + 1} changed: {cm.exception}")


if __name__ == "__main__":
    harness.main()
