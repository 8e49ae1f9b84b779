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
    """Starts the slave as the recording's was started (sidecar slave_args), on a fresh veth pair, and replays."""
    pairs = ecatreplay.pair(ecatreplay.read_pcap(pcap))
    with harness.Bus(slave_args=list(side["slave_args"]) + list(extra_args)) as bus:
        try:
            return ecatreplay.replay(pairs, bus.iface)
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
        SYNC0 (so Op is refused: AL status and code) does not pass the replay of a master that relies on it."""
        by_name = {e[0]: e for e in ecatreplay.corpus()}
        cases = [("soem-slaveinfo", "expedited-size-wrong"), ("libethercat-example_with_dc", "sync0-never")]
        for rec, fault in cases:
            self.assertIn(rec, by_name)
            with self.subTest(recording=rec, fault=fault):
                name, pcap, side = by_name[rec]
                with self.assertRaises(ecatreplay.Mismatch) as cm:
                    replay(name, pcap, side, ["--fault", fault])
                print(f"{rec} with --fault {fault}: {cm.exception}")


if __name__ == "__main__":
    harness.main()
