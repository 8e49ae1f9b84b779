"""ecat-conform against the soft slave over a veth pair: the clean slave passes every test, and each
`ecat-slave --fault NAME` makes the test(s) named in faults.txt fail and no test of an unrelated group.

usage: test_conform.py clean | noslave | dies | stalls | fault NAME [NAME ...] | mutant NAME [NAME ...]
       | variation NAME [NAME ...] | table [NAME ...]
mutant/variation: a proxy between ecat-conform and the clean slave rewrites the slave's answers
(mutants.py); a mutant must make at least one test fail, a variation must raise no failure and no warning
that the unmutated run through the proxy does not raise. table: every mutant and variation (or those
named), with the tests that killed each, as a markdown table (ECAT_TEST_OUT/mutation-table.md).
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
import mutants  # noqa: E402

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


class ProxyLink:
    """A veth pair (cm<uid> for ecat-conform, cp<uid> for the proxy) and the proxy between cp<uid> and the
    bus's master end."""
    _n = 0

    def __init__(self, bus_iface, mutation):
        ProxyLink._n += 1
        uid = f"{os.getpid() % 100000}p{ProxyLink._n}"
        self.iface, self.peer = f"cm{uid}", f"cp{uid}"
        self.bus_iface, self.mutation = bus_iface, mutation
        self.proxy = None

    def __enter__(self):
        subprocess.run(["ip", "link", "add", self.iface, "type", "veth", "peer", "name", self.peer], check=True)
        for i in (self.iface, self.peer):
            subprocess.run(["sysctl", "-qw", f"net.ipv6.conf.{i}.disable_ipv6=1"], check=False)
            subprocess.run(["ip", "link", "set", i, "up"], check=True)
        try:
            self.proxy = mutants.Proxy(self.peer, self.bus_iface, self.mutation).__enter__()
        except BaseException:
            subprocess.run(["ip", "link", "del", self.iface], check=False)
            raise
        return self

    def __exit__(self, *exc):
        try:
            self.proxy.__exit__(*exc)
        finally:
            subprocess.run(["ip", "link", "del", self.iface], check=False)
        return False


def table_markdown(rows):
    lines = ["| kind | name | clause | result | killed by (tests of its group, first 4) | s |", "|---|---|---|---|---|---|"]
    for kind, name, clause, failed, warned, ok, elapsed, _ in rows:
        res = ("killed" if ok else "SURVIVED" + (" (known, see TABLE_SURVIVORS)" if name in mutants.TABLE_SURVIVORS else "")) \
            if kind == "mutant" else ("clean" if ok else "FALSE ALARM")
        by = failed if kind == "mutant" else failed + warned
        more = f" +{len(by) - 4}" if len(by) > 4 else ""
        lines.append(f"| {kind} | `{name}` | {clause} | {res} | {', '.join(by[:4])}{more} | {elapsed:.1f} |")
    m = [r for r in rows if r[0] == "mutant"]
    v = [r for r in rows if r[0] == "variation"]
    lines.append("")
    lines.append(f"mutants killed {sum(r[5] for r in m)}/{len(m)}; variations clean {sum(r[5] for r in v)}/{len(v)}")
    return "\n".join(lines) + "\n"


class Conform(unittest.TestCase):
    mode = "clean"
    faults = []

    def run_conform(self, fault=None, mutation=None, proxy=False, device=None, groups=None):
        """device: (example ESI, ecat-slave --device, ecat-conform --device) to serve another device than the
        drive (mutants.DEVICE); groups: only these groups of the catalogue (ecat-conform --group)."""
        work = tempfile.mkdtemp(prefix="ecat-conform-", dir=os.environ.get("ECAT_TEST_OUT"))
        if device:
            esi = os.path.join(HERE, "..", "..", "esi", "examples", device[0])
            args = ["--esi", esi, "--device", device[1]]
            device_args = ["--device", str(device[2])]
        else:
            sii, esi = alias_images(work)
            args = ["--eeprom", sii]
            device_args = []
        if fault:
            args += ["--fault", fault]
        with ConformBus(slave_args=args) as bus:
            out = os.path.join(work, "result.json")
            junit = os.path.join(work, "result.xml")

            extra = ["--group", ",".join(sorted(groups))] if groups else []

            def run(iface):
                t0 = time.monotonic()
                cmd = [os.environ["ECAT_CONFORM"], "--iface", iface, "--esi", esi, "--foe-file", "MAXPOS", "--json",
                       out, "--junit", junit, "--allow-fault"] + device_args + extra
                try:
                    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120)
                except subprocess.TimeoutExpired as e:
                    # Killed: the reports hold every test up to the one that ran (marked interrupted).
                    r = subprocess.CompletedProcess(cmd, -9, e.stdout or "", e.stderr or "")
                return r, time.monotonic() - t0

            if proxy or mutation:
                # The proxy is a Python program on a shared host: its latency varies, so the waits are longer.
                extra.extend(["--timeout-scale", "3"])
                with ProxyLink(bus.iface, mutation) as p:
                    r, elapsed = run(p.iface)
                self.last_fired = p.proxy.fired
                self.assertEqual(p.proxy.errors, [], "the mutation raised")
            else:
                r, elapsed = run(bus.iface)
            self.assertTrue(os.path.exists(out), f"no JSON written: {r.stderr}")
            res = json.loads(pathlib.Path(out).read_text())
            import xml.dom.minidom
            xml.dom.minidom.parse(junit)  # well-formed
            return r, res, elapsed

    def mutation_runs(self, names):
        """Runs the proxy without mutation, then each named mutant/variation; returns rows of the table."""
        base_warn = set()
        if any(n in mutants.VARIATIONS for n in names):
            # Variations are judged against the warnings of the same run without a mutation.
            _, base, _ = self.run_conform(proxy=True)
            if any(x["status"] == "FAIL" for x in base["results"]):
                # Once more, as a variation is (below): the proxy on a loaded host can miss a watchdog.
                _, base, _ = self.run_conform(proxy=True)
            base_fail = sorted(x["id"] for x in base["results"] if x["status"] == "FAIL")
            self.assertEqual(base_fail, [], "the unmutated run through the proxy fails")
            base_warn = {x["id"] for x in base["results"] if x["status"] == "WARN"}
        rows = []
        for name in names:
            kind = "mutant" if name in mutants.MUTANTS else "variation"
            clause, fn = (mutants.MUTANTS if kind == "mutant" else mutants.VARIATIONS)[name]
            device = mutants.DEVICE.get(name)
            # A mutant counts as killed only by a failure in the groups where it must be caught, so the CI
            # subset (mode "mutant") runs just those groups: the same verdict, a fraction of the catalogue. The
            # table (mode "table") runs everything, for its "caught anywhere" figure.
            groups = mutants.expected_groups(name) if kind == "mutant" and self.mode == "mutant" else None
            if groups and "*" in groups:
                groups = None
            _, res, elapsed = self.run_conform(mutation=fn, device=device, groups=groups)
            if kind == "variation" and any(x["status"] == "FAIL" for x in res["results"]):
                # Once more: process data through a Python proxy on a loaded host can miss a watchdog. A
                # variation that fails twice is a false alarm of the tool.
                _, res, elapsed = self.run_conform(mutation=fn, device=device)
            failed = sorted(x["id"] for x in res["results"] if x["status"] == "FAIL")
            anywhere = len(failed)
            if kind == "mutant":
                # Only failures in the group where the defect must be caught count as its kill.
                groups = mutants.expected_groups(name)
                failed = [i for i in failed if "*" in groups or i.split(".")[0] in groups]
            warned = sorted(x["id"] for x in res["results"] if x["status"] == "WARN" and x["id"] not in base_warn)
            detail = {x["id"]: x["message"] + " / " + x["observed"] for x in res["results"]
                      if x["status"] in ("FAIL", "WARN") and x["id"] not in base_warn}
            ok = bool(failed) if kind == "mutant" else not failed and not warned
            rows.append((kind, name, clause, failed, warned, ok, elapsed, detail))
            print(f"{kind} {name}: {'ok' if ok else 'NOT OK'} in {elapsed:.1f} s, changed {self.last_fired} "
                  f"replies, {anywhere} failures in all: {' '.join(failed[:6])}"
                  f"{' warned ' + ' '.join(warned) if warned else ''}", file=sys.stderr, flush=True)
        return rows

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
        if self.mode == "stalls":
            # The host stalls the slave (SIGSTOP for 300 ms, every second: a busy machine that deschedules it)
            # during the sdo and mbx groups: no test fails for it, the stalls are noted; a slave that stops for
            # good is still reported within a second (mode dies). The first stall (600 ms) is already on when
            # the tool starts: its set-up (slave count, addresses, SII) waits for the slave as well.
            import signal
            import threading
            work = tempfile.mkdtemp(prefix="ecat-conform-", dir=os.environ.get("ECAT_TEST_OUT"))
            sii, esi = alias_images(work)
            with ConformBus(slave_args=["--eeprom", sii]) as bus:
                out = os.path.join(work, "r.json")
                bus.proc.send_signal(signal.SIGSTOP)
                p = subprocess.Popen([os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--esi", esi, "--json", out,
                                      "--group", "sdo,mbx"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                stalls = []

                def stall():
                    time.sleep(0.6)
                    bus.proc.send_signal(signal.SIGCONT)
                    stalls.append(time.monotonic())
                    time.sleep(1.0)
                    while p.poll() is None:
                        bus.proc.send_signal(signal.SIGSTOP)
                        time.sleep(0.3)
                        bus.proc.send_signal(signal.SIGCONT)
                        stalls.append(time.monotonic())
                        time.sleep(1.0)

                th = threading.Thread(target=stall)
                th.start()
                try:
                    stdout, _ = p.communicate(timeout=120)
                finally:
                    th.join()
            res = json.loads(pathlib.Path(out).read_text())
            failed = [x["id"] + ": " + x["message"] for x in res["results"] if x["status"] == "FAIL"]
            self.assertTrue(stalls)
            self.assertEqual(failed, [], stdout[-3000:])
            self.assertEqual(p.returncode, 0)
            print(f"{len(stalls)} stalls; notes: {res.get('notes')}", file=sys.stderr)
            return
        if self.mode == "tool_stalls":
            # The host stalls the tool instead: SIGSTOP of ecat-conform for 250 ms just after it reported every
            # second test of the drive's state machine (cia402.dc.*, each runs the drive with process data), so
            # the stall lands in the next one while it cycles. The slave's watchdog (100 ms) trips and the drive leaves its state, rightly. The
            # tool sees its own process data paused, runs a test that failed once more (a test before the
            # next stall) and notes it: no failure for the host's doing.
            import re
            import signal
            work = tempfile.mkdtemp(prefix="ecat-conform-", dir=os.environ.get("ECAT_TEST_OUT"))
            sii, esi = alias_images(work)
            with ConformBus(slave_args=["--eeprom", sii]) as bus:
                out = os.path.join(work, "r.json")
                p = subprocess.Popen([os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--esi", esi, "--json", out,
                                      "--group", "pd,cia402"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     text=True, bufsize=1)
                stalls, seen, lines = 0, 0, []
                try:
                    for line in p.stdout:
                        lines.append(line)
                        if not re.search(r"\bcia402\.dc\.", line):
                            continue
                        seen += 1
                        if seen % 2 == 1:
                            time.sleep((0.03, 0.07, 0.12)[stalls % 3])  # early, middle, late in the next test
                            p.send_signal(signal.SIGSTOP)
                            time.sleep(0.25)
                            p.send_signal(signal.SIGCONT)
                            stalls += 1
                    p.wait(timeout=240)
                finally:
                    if p.poll() is None:
                        p.kill()
            res = json.loads(pathlib.Path(out).read_text())
            failed = [x["id"] + ": " + x["message"] for x in res["results"] if x["status"] == "FAIL"]
            self.assertGreaterEqual(stalls, 4, "".join(lines[-40:]))
            self.assertEqual(failed, [], f"notes: {res.get('notes')}\n" + "".join(lines[-60:]))
            self.assertEqual(p.returncode, 0)
            print(f"{stalls} stalls of the tool; notes: {res.get('notes')}", file=sys.stderr)
            return
        if self.mode == "stopped":
            # Stopped half-way (--deadline, then SIGTERM): valid JUnit and JSON of the tests done, the running
            # one marked as interrupted, exit code 3, the text report ends saying where it stopped.
            import signal
            import xml.dom.minidom
            work = tempfile.mkdtemp(prefix="ecat-conform-", dir=os.environ.get("ECAT_TEST_OUT"))
            sii, esi = alias_images(work)
            with ConformBus(slave_args=["--eeprom", sii]) as bus:
                for how in ("deadline", "sigterm"):
                    out, junit = os.path.join(work, how + ".json"), os.path.join(work, how + ".xml")
                    cmd = [os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--esi", esi, "--json", out,
                           "--junit", junit]
                    if how == "deadline":
                        cmd += ["--deadline", "2"]
                    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                    if how == "sigterm":
                        time.sleep(2.0)
                        p.send_signal(signal.SIGTERM)
                    stdout, _ = p.communicate(timeout=60)
                    self.assertEqual(p.returncode, 3, stdout[-2000:])
                    self.assertIn("stopped", stdout.splitlines()[-2] + stdout.splitlines()[-1])
                    res = json.loads(pathlib.Path(out).read_text())
                    statuses = [x["status"] for x in res["results"]]
                    self.assertGreater(len(statuses), 5, how)
                    self.assertLess(len(statuses), 264, how)
                    self.assertIn("PASS", statuses)
                    self.assertIn("interrupted", res["results"][-1]["message"])
                    doc = xml.dom.minidom.parse(junit)
                    self.assertEqual(len(doc.getElementsByTagName("testcase")), len(statuses))
                    # Every result in the JSON was printed, as it happened, in the text report.
                    for x in res["results"][:-1]:
                        self.assertIn(x["id"], stdout)
            return
        if self.mode == "line":
            # --slave all on a line of three soft drives, each against the ESI of --esi-dir that matches its
            # SII: one report, every slave's results tagged with its position, no failure.
            work = tempfile.mkdtemp(prefix="ecat-conform-", dir=os.environ.get("ECAT_TEST_OUT"))
            esi_dir = os.path.join(work, "esi")
            os.makedirs(esi_dir)
            subprocess.run([os.environ["ECAT_SLAVE"], "--write-esi", os.path.join(esi_dir, "drive.xml"),
                            "--state-dir", work], check=True, timeout=60, stdout=subprocess.DEVNULL)
            pathlib.Path(esi_dir, "not-an-esi.xml").write_text("<nothing/>")
            with ConformBus(slave_args=["--slaves", "3"]) as bus:
                out, junit = os.path.join(work, "r.json"), os.path.join(work, "r.xml")
                r = subprocess.run([os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--slave", "all", "--esi-dir",
                                    esi_dir, "--json", out, "--junit", junit], stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True, timeout=300)
            res = json.loads(pathlib.Path(out).read_text())
            failed = [f"slave {x['slave']} {x['id']}: {x['message']} / {x['observed']}" for x in res["results"]
                      if x["status"] == "FAIL"]
            self.assertEqual(failed, [], r.stdout[-3000:])
            self.assertEqual(r.returncode, 0)
            per = {k: [x for x in res["results"] if x["slave"] == k] for k in (0, 1, 2)}
            self.assertEqual(len(per[0]), len(per[1]))
            self.assertEqual(len(per[0]) * 3, len(res["results"]))
            self.assertNotIn("needs the ESI", r.stdout)
            for k in (0, 1, 2):
                self.assertIn(f"=== slave {k}: slave {k} of 3", r.stdout)
            import xml.dom.minidom
            names = {s.getAttribute("name") for s in xml.dom.minidom.parse(junit).getElementsByTagName("testsuite")}
            self.assertIn("slave2.sdo", names)
            return
        if self.mode == "foe_write":
            # The whole FoE write (--allow-foe-write): an image built with the device's own identity goes
            # through packet by packet, the slave restarts into it from Bootstrap, and 0x100A then names it.
            work = tempfile.mkdtemp(prefix="ecat-conform-", dir=os.environ.get("ECAT_TEST_OUT"))
            sii, esi = alias_images(work)
            payload = os.path.join(work, "payload.bin")
            pathlib.Path(payload).write_bytes(bytes((i * 13 + (i >> 7)) & 0xFF for i in range(3000)))
            image = os.path.join(work, "image.bin")
            subprocess.run([os.environ["FWIMAGE"], "build", "--payload", payload, "--version", "0x01310000",
                            "--esi", esi, "-o", image], check=True, timeout=60, stdout=subprocess.DEVNULL)
            with ConformBus(slave_args=["--eeprom", sii]) as bus:
                out = os.path.join(work, "r.json")
                r = subprocess.run([os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--esi", esi, "--group", "foe",
                                    "--foe-file", "MAXPOS", "--allow-foe-write", "--foe-image", image, "--json", out],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=300)
                res = {x["id"]: x for x in json.loads(pathlib.Path(out).read_text())["results"]}
                self.assertEqual(res["foe.write_complete"]["status"], "PASS", r.stdout[-3000:])
                self.assertEqual(r.returncode, 0, r.stdout[-3000:])
                # The image now stored is read back over FoE (foe.read_file): DATA packets numbered from 1.
                r = subprocess.run([os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--esi", esi, "--filter",
                                    "foe.read_file", "--foe-file", "MAXPOS", "--json", out],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120)
                x = json.loads(pathlib.Path(out).read_text())["results"][0]
                self.assertEqual(x["status"], "PASS", r.stdout[-3000:])
                self.assertTrue(x["observed"].startswith("1 2 "), x)  # packet numbers seen, not a refusal
                # The unseen defects of the read path are caught there: DATA numbered from 0, a reserved byte,
                # a wrong ACK refused with another code than 0x8005.
                for name in ("foe-data-packet-no", "foe-reserved", "foe-packet-number-as-illegal"):
                    with ProxyLink(bus.iface, mutants.MUTANTS[name][1]) as p:
                        r = subprocess.run([os.environ["ECAT_CONFORM"], "--iface", p.iface, "--esi", esi,
                                            "--filter", "foe.read_file", "--foe-file", "MAXPOS", "--json", out,
                                            "--timeout-scale", "3"],
                                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120)
                    x = json.loads(pathlib.Path(out).read_text())["results"][0]
                    self.assertEqual(x["status"], "FAIL", f"{name}: {x}")
                self.assertIn("3032 bytes", res["foe.write_complete"]["observed"])
                sw = bus.ecatctl("upload", "0", "0x100A", "0").stdout
                self.assertIn("0131h", sw)
            # Without --allow-foe-write the test says why it did not run.
            with ConformBus(slave_args=["--eeprom", sii]) as bus:
                r = subprocess.run([os.environ["ECAT_CONFORM"], "--iface", bus.iface, "--esi", esi, "--filter",
                                    "foe.write_complete", "--foe-file", "MAXPOS", "--json", out],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120)
                x = json.loads(pathlib.Path(out).read_text())["results"][0]
                self.assertEqual(x["status"], "SKIP")
                self.assertIn("--allow-foe-write", x["message"])
            return
        if self.mode == "contained":
            # One defect must not spoil the rest of the run. A slave that keeps a write to its AL status (stuck
            # in that state until its ESC is reset) fails the test that found it, is reset, and the other
            # groups run as against a clean slave. A slave that shows the error indication after every
            # successful state change fails the esm tests, which judge the indication, and no test that only
            # needs the state (its bring-up acknowledges the indication and carries on, with a note).
            for name, where, most, said in (("al-status-write-kept", {"esc"}, 3, "ESC reset"),
                                            ("esm-success-error-flag", {"esm"}, 12, "error indication set")):
                with self.subTest(mutant=name):
                    _, res, _ = self.run_conform(mutation=mutants.MUTANTS[name][1])
                    failed = {x["id"]: x for x in res["results"] if x["status"] == "FAIL"}
                    self.assertTrue(failed, "nothing failed")
                    self.assertLessEqual(len(failed), most, sorted(failed))
                    self.assertEqual(sorted(i for i, x in failed.items() if x["group"] not in where), [])
                    passed = [x for x in res["results"] if x["status"] == "PASS"]
                    self.assertGreater(len(passed), 200)
                    told = [x["message"] for x in failed.values()] + res.get("notes", [])
                    self.assertTrue(any(said in t for t in told), told)
            return
        if self.mode == "liar":
            # A slave whose every working counter is one too high (besides BRD, so it is found): the run ends
            # in under a minute and fails.
            t0 = time.monotonic()
            r, res, elapsed = self.run_conform(mutation=mutants.MUTANTS["liar-wkc"][1])
            self.assertEqual(r.returncode, 1)
            self.assertLess(time.monotonic() - t0, 60, f"run took {elapsed:.0f} s")
            print(f"lying slave: {len(res['results'])} tests in {elapsed:.1f} s", file=sys.stderr)
            return
        if self.mode in ("mutant", "variation", "table"):
            names = self.faults or (list(mutants.MUTANTS) + list(mutants.VARIATIONS))
            for n in mutants.MUTANTS:
                mutants.expected_groups(n)  # every mutant says where it must be caught
            for n in names:
                self.assertIn(n, {**mutants.MUTANTS, **mutants.VARIATIONS}, "unknown mutant or variation")
            rows = self.mutation_runs(names)
            text = table_markdown(rows)
            if self.mode == "table":
                path = os.path.join(os.environ.get("ECAT_TEST_OUT", "."), "mutation-table.md")
                pathlib.Path(path).write_text(text)
                print(text)
                print(f"written to {path}", file=sys.stderr)
            bad = [f"{r[1]}: " + ("no test failed" if r[0] == "mutant" else "; ".join(
                f"{k}: {v}" for k, v in r[7].items())) for r in rows if not r[5] and r[1] not in mutants.TABLE_SURVIVORS]
            self.assertEqual(bad, [], text)
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
    if len(sys.argv) >= 2 and sys.argv[1] in ("clean", "fault", "noslave", "dies", "stalls", "tool_stalls", "stopped", "liar", "line", "mutant", "variation", "contained", "foe_write",
                                              "table"):
        Conform.mode = sys.argv[1]
        Conform.faults = sys.argv[2:]
        del sys.argv[1:]
    # SIGTERM (a ctest time-out, a kill) unwinds like an exception: namespaces, links and the slave go.
    import signal
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))
    if not os.path.exists(os.environ.get("ECAT_CONFORM", "")):
        print("SKIP: ECAT_CONFORM not set")
        sys.exit(harness.SKIP)
    harness.main()
