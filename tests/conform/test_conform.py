"""ecat-conform against the soft slave over a veth pair: the clean slave passes every test, and each
`ecat-slave --fault NAME` makes the test(s) named in faults.txt fail and no test of an unrelated group.

usage: test_conform.py clean | noslave | dies | fault NAME [NAME ...]
The slave serves an SII with station alias 0x1234 (and the ESI says the same), so the alias tests run too.
"""
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "integration"))
import harness  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ALIAS = 0x1234


def matrix():
    rows = {}
    with open(os.path.join(HERE, "faults.txt")) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            name, tests, groups = (x.strip() for x in line.split("|"))
            rows[name] = (tests.split(","), set(groups.split(",")))
    return rows


def alias_images(work):
    """The slave's SII with word 4 (station alias) set and the checksum redone; its ESI with ConfigData
    to match."""
    slave = os.environ["ECAT_SLAVE"]
    sii, esi = os.path.join(work, "alias.bin"), os.path.join(work, "alias.xml")
    subprocess.run([slave, "--write-sii", sii, "--state-dir", work], check=True, timeout=60,
                   stdout=subprocess.DEVNULL)
    subprocess.run([slave, "--write-esi", esi, "--state-dir", work], check=True, timeout=60,
                   stdout=subprocess.DEVNULL)
    b = bytearray(pathlib.Path(sii).read_bytes())
    b[8], b[9] = ALIAS & 0xFF, ALIAS >> 8
    b[14] = harness.sii_crc(bytes(b[:14]))
    pathlib.Path(sii).write_bytes(bytes(b))
    text = pathlib.Path(esi).read_text()
    start = text.index("<ConfigData>") + len("<ConfigData>")
    cd = text[start:text.index("</ConfigData>")]
    cd = cd[:16] + f"{ALIAS & 0xFF:02x}{ALIAS >> 8:02x}" + cd[20:]
    pathlib.Path(esi).write_text(text[:start] + cd + text[text.index("</ConfigData>"):])
    return sii, esi


class ConformBus(harness.Bus):
    """A Bus whose readiness probe is ecat-conform itself (BRD): ecatctl cannot talk to a slave whose APRD
    counts wrong or whose replies keep our source MAC, and those are faults under test."""

    def ecatctl(self, *args, check=True, binary=False):
        if "reg" in args and "read" in args and not check:
            return subprocess.run([os.environ["ECAT_CONFORM"], "--iface", self.iface, "--filter", "esc.brd.wkc"],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)
        return super().ecatctl(*args, check=check, binary=binary)


class Conform(unittest.TestCase):
    mode = "clean"
    faults = []

    def run_conform(self, fault=None):
        work = tempfile.mkdtemp(prefix="ecat-conform-", dir=os.environ.get("ECAT_TEST_OUT"))
        sii, esi = alias_images(work)
        args = ["--eeprom", sii]
        if fault:
            args += ["--fault", fault]
        with ConformBus(slave_args=args) as bus:
            out = os.path.join(work, "result.json")
            junit = os.path.join(work, "result.xml")
            t0 = time.monotonic()
            r = subprocess.run([os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--esi", esi, "--foe-file", "MAXPOS",
                                "--json", out, "--junit", junit], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, timeout=120)
            elapsed = time.monotonic() - t0
            self.assertTrue(os.path.exists(out), f"no JSON written: {r.stderr}")
            res = json.loads(pathlib.Path(out).read_text())
            import xml.dom.minidom
            xml.dom.minidom.parse(junit)  # well-formed
            return r, res, elapsed

    def test_matrix(self):
        rows = matrix()
        if self.mode == "clean":
            # Every fault the slave knows has its row in the matrix.
            listed = subprocess.run([os.environ["ECAT_SLAVE"], "--fault", "list"], stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, text=True, timeout=30).stdout
            names = {line.split()[0] for line in listed.splitlines() if line.strip() and not line.startswith(" ")}
            names = {n for n in names if "-" in n and n.islower()}
            self.assertTrue(names, listed)
            self.assertEqual(sorted(names - set(rows)), [], "faults without a row in tests/conform/faults.txt")
            r, res, elapsed = self.run_conform()
            failed = [x["id"] + ": " + x["message"] + " / " + x["observed"] for x in res["results"] if x["status"] == "FAIL"]
            self.assertEqual(failed, [], r.stdout[-3000:])
            warned = [x["id"] + ": " + x["message"] + " / " + x["observed"] for x in res["results"] if x["status"] == "WARN"]
            self.assertEqual(warned, [], "the clean slave gets no warning against its own ESI")
            self.assertEqual(r.returncode, 0)
            self.assertTrue(r.stdout.rstrip().endswith(f"{res['passed']} passed, 0 failed, {res['skipped']} skipped"))
            self.assertGreaterEqual(len(res["results"]), 150)
            print(f"clean run: {len(res['results'])} tests in {elapsed:.1f} s", file=sys.stderr)
            return
        if self.mode == "noslave":
            # Nothing on the other end of the pair: every test fails with the reason, quickly, exit code 1.
            uid = f"{os.getpid() % 100000}"
            a, b = f"cfa{uid}", f"cfb{uid}"
            subprocess.run(["ip", "link", "add", a, "type", "veth", "peer", "name", b], check=True)
            try:
                subprocess.run(["ip", "link", "set", a, "up"], check=True)
                subprocess.run(["ip", "link", "set", b, "up"], check=True)
                out = os.path.join(tempfile.mkdtemp(dir=os.environ.get("ECAT_TEST_OUT")), "r.json")
                t0 = time.monotonic()
                r = subprocess.run([os.environ["ECAT_CONFORM"], "--iface", a, "--json", out], stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True, timeout=120)
                self.assertLess(time.monotonic() - t0, 60)
            finally:
                subprocess.run(["ip", "link", "del", a])
            self.assertEqual(r.returncode, 1, r.stderr)
            res = json.loads(pathlib.Path(out).read_text())
            self.assertGreaterEqual(len(res["results"]), 150)
            for x in res["results"]:
                self.assertEqual(x["status"], "FAIL")
                self.assertIn("no slave answered", x["message"])
            self.assertTrue(r.stdout.rstrip().endswith(f"0 passed, {len(res['results'])} failed, 0 skipped"))
            return
        if self.mode == "dies":
            # The slave stops in the middle of the run: the run ends in time, the tests after it fail saying so.
            work = tempfile.mkdtemp(prefix="ecat-conform-", dir=os.environ.get("ECAT_TEST_OUT"))
            sii, esi = alias_images(work)
            with ConformBus(slave_args=["--eeprom", sii]) as bus:
                out = os.path.join(work, "r.json")
                p = subprocess.Popen([os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--esi", esi, "--json", out],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                time.sleep(1.0)
                bus.stop_slave()
                stdout, _ = p.communicate(timeout=120)
            self.assertEqual(p.returncode, 1)
            res = json.loads(pathlib.Path(out).read_text())
            statuses = [x["status"] for x in res["results"]]
            self.assertIn("PASS", statuses)
            self.assertEqual(statuses[-1], "FAIL")
            self.assertTrue(any("no longer answers" in x["message"] for x in res["results"]), stdout[-2000:])
            return
        for fault in self.faults:
            with self.subTest(fault=fault):
                self.assertIn(fault, rows, "no row in faults.txt")
                must, groups = rows[fault]
                r, res, _ = self.run_conform(fault)
                failed = {x["id"]: x for x in res["results"] if x["status"] == "FAIL"}
                self.assertEqual(r.returncode, 1, f"--fault {fault}: the run passed")
                self.assertTrue(set(must) & set(failed), f"--fault {fault}: none of {must} failed; failed: {sorted(failed)}")
                unrelated = sorted(i for i, x in failed.items() if x["group"] not in groups)
                self.assertEqual(unrelated, [], f"--fault {fault}: unrelated groups failed: " + "; ".join(
                    f"{i}: {failed[i]['message']} / observed {failed[i]['observed']}" for i in unrelated))
                for i in set(must) & set(failed):
                    self.assertTrue(failed[i]["clause"] and failed[i]["observed"] + failed[i]["message"],
                                    "a failure names its clause and what was observed")


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] in ("clean", "fault", "noslave", "dies"):
        Conform.mode = sys.argv[1]
        Conform.faults = sys.argv[2:]
        del sys.argv[1:]
    if not os.path.exists(os.environ.get("ECAT_CONFORM", "")):
        print("SKIP: ECAT_CONFORM not set")
        sys.exit(harness.SKIP)
    harness.main()
