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
    pairs = ecatreplay.pair(ecatreplay.read_pcap(pcap))
    with harness.Bus(slave_args=list(side["slave_args"]) + list(extra_args)) as bus:
        stats = ecatreplay.replay(pairs, bus.iface)
        if not extra_args and not side.get("malformed_requests"):
            bus.stop_slave()
            problems = harness.tshark_problems(bus.capture)
            if problems:
                raise AssertionError(f"{name}: the slave's capture of the replay does not decode cleanly:\n"
                                     + "\n".join(problems[:10]))
    return stats


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
        them in those requests and in the replies that carry their data back, nowhere else."""
        if not shutil.which("tshark"):
            self.skipTest("tshark not installed")
        for name, pcap, side in ecatreplay.corpus():
            with self.subTest(recording=name):
                frames = ecatreplay.read_pcap(pcap)
                with tempfile.NamedTemporaryFile(suffix=".pcap") as f:
                    ecatreplay.write_pcap(f.name, frames)
                    r = subprocess.run(["tshark", "-r", f.name, "-Y", "_ws.malformed || _ws.expert.severity == error",
                                        "-T", "fields", "-e", "frame.number"], stdout=subprocess.PIPE,
                                       stderr=subprocess.PIPE, text=True, timeout=300)
                self.assertEqual(r.returncode, 0, r.stderr)
                bad = {int(x) - 1 for x in r.stdout.split()}
                if side.get("malformed_requests"):
                    requests = {i for i, (_t, fr) in enumerate(frames) if not fr[6] & 0x02}
                    bad_keys = {ecatreplay.keys(frames[i][1]) for i in bad & requests}
                    bad = {i for i in bad if i not in requests and ecatreplay.keys(frames[i][1]) not in bad_keys}
                self.assertEqual(sorted(bad)[:20], [], f"{name}: frames (from 0) tshark reports as malformed")

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
