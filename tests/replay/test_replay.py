"""The recorded start-ups of foreign masters (tests/replay/corpus), replayed against the current ecat-slave
(docs/decisions/replay.md): each reply must keep the invariants the master relied on. A slave broken on purpose
(--fault) must fail the replay, so the test can fail."""
import os
import sys
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
        if not extra_args:
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
        """The corpus itself decodes in tshark without malformed packets or expert errors."""
        for name, pcap, _side in ecatreplay.corpus():
            with self.subTest(recording=name):
                import tempfile
                with tempfile.NamedTemporaryFile(suffix=".pcap") as f:
                    ecatreplay.write_pcap(f.name, ecatreplay.read_pcap(pcap))
                    problems = harness.tshark_problems(f.name)
                if problems is None:
                    self.skipTest("tshark not installed")
                self.assertEqual(problems, [], name)

    def test_faulty_slave_fails(self):
        """A slave with a wrong identity object or with wrong working counters does not pass the replay of a
        master that reads them."""
        by_name = {e[0]: e for e in ecatreplay.corpus()}
        cases = [("soem-slaveinfo", "wkc-aprd"), ("soem-slaveinfo", "identity-mismatch")]
        for rec, fault in cases:
            if rec not in by_name:
                continue
            with self.subTest(recording=rec, fault=fault):
                name, pcap, side = by_name[rec]
                with self.assertRaises(ecatreplay.Mismatch) as cm:
                    replay(name, pcap, side, ["--fault", fault])
                print(f"{rec} with --fault {fault}: {cm.exception}")


if __name__ == "__main__":
    harness.main()
