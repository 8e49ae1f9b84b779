"""`cmake --install`: the programs, a man page and bash completion for each, the examples, the ESI schema copy
and the systemd template unit ecat-slave@.service, which gives the slave exactly the capabilities it needs: the
installed ecat-slave, run as an unprivileged user with those capabilities only (as systemd would run it), serves
an interface a master scans; without them it cannot start. (The .deb built from the same rules is installed and
removed by .ci/run.)"""
import configparser
import gzip
import os
import re
import shutil
import subprocess
import tempfile
import time
import unittest

import harness

PROGRAMS = ["ecat-slave", "ecatctl", "ecat-conform", "fwimage", "drive-sim", "ecat-ci"]


class Install(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        build = os.environ.get("SOFTECAT_BUILD_DIR")
        if not build or not os.path.isdir(build):
            raise unittest.SkipTest("SOFTECAT_BUILD_DIR not set")
        cls.prefix = tempfile.mkdtemp(prefix="ecat-install-")
        os.chmod(cls.prefix, 0o755)
        r = subprocess.run(["cmake", "--install", build, "--prefix", cls.prefix], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=300)
        if r.returncode != 0:
            shutil.rmtree(cls.prefix, True)
            raise AssertionError(f"cmake --install failed:\n{r.stdout[-3000:]}")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.prefix, True)

    def path(self, *parts):
        return os.path.join(self.prefix, *parts)

    def test_programs_with_version_man_page_and_completion(self):
        for p in PROGRAMS:
            exe = self.path("bin", p)
            self.assertTrue(os.access(exe, os.X_OK), exe)
            r = subprocess.run([exe, "--version"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               timeout=30)
            self.assertEqual(r.returncode, 0, f"{p} --version: {r.stderr}")
            self.assertRegex(r.stdout, rf"^{p} \d+\.\d+\.\d+", p)
            with gzip.open(self.path("share", "man", "man1", f"{p}.1.gz"), "rt") as f:
                page = f.read()
            self.assertIn(".SH NAME", page, p)
            self.assertIn("\\-\\-help", page, f"{p}.1 lists no options")
            self.assertTrue(os.path.isfile(self.path("share", "bash-completion", "completions", p)), p)
            if not shutil.which("man"):
                continue
            r = subprocess.run(["man", "-l", "-P", "cat", self.path("share", "man", "man1", f"{p}.1.gz")],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60,
                               env=dict(os.environ, MANWIDTH="80"))
            self.assertEqual(r.returncode, 0, r.stderr)

    def complete(self, line):
        """What bash completion offers for the last word of line, with the installed programs on PATH."""
        words = line.split(" ")
        script = (f"source {self.path('share', 'bash-completion', 'completions', words[0])}\n"
                  f"COMP_WORDS=({' '.join(repr(w) for w in words)}); COMP_CWORD={len(words) - 1}\n"
                  f"_softecat_complete; printf '%s\\n' \"${{COMPREPLY[@]}}\"\n")
        r = subprocess.run(["bash", "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           env=dict(os.environ, PATH=self.path("bin") + ":" + os.environ["PATH"]), timeout=30)
        self.assertEqual(r.returncode, 0, r.stderr)
        return r.stdout.split()

    def test_completion_offers_subcommands_and_options(self):
        self.assertIn("scan", self.complete("ecatctl sc"))
        self.assertIn("sdos", self.complete("ecatctl sd"))
        self.assertIn("--complete", self.complete("ecatctl upload --comp"))
        self.assertIn("--slaves", self.complete("ecat-slave --sla"))
        self.assertIn("build", self.complete("fwimage b"))
        self.assertIn("--payload", self.complete("fwimage build --pay"))

    def test_examples_and_schema(self):
        for f in ("device.conf", "bootstrap-as-standard.conf", "drive.conf", os.path.join("drive-sim", "homing.txt"),
                  os.path.join("segment", "tree.topo"), os.path.join("segment", "axis-b.conf")):
            self.assertTrue(os.path.isfile(self.path("share", "doc", "softecat", "examples", f)), f)
        schema = self.path("share", "softecat", "schema", "EtherCATInfo.xsd")
        self.assertTrue(os.path.isfile(schema))
        # The installed schema is the one the ESI validates against.
        esi = self.path("drive.xml")
        state = tempfile.mkdtemp(prefix="ecat-install-state-")
        self.addCleanup(shutil.rmtree, state, True)
        r = subprocess.run([self.path("bin", "ecat-slave"), "--write-esi", esi, "--state-dir", state],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)
        self.assertEqual(r.returncode, 0, r.stderr)
        if shutil.which("xmllint"):
            r = subprocess.run(["xmllint", "--noout", "--schema", schema, esi], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, timeout=60)
            self.assertEqual(r.returncode, 0, r.stderr)

    def unit(self):
        path = self.path("lib", "systemd", "system", "ecat-slave@.service")
        parser = configparser.ConfigParser(strict=False, interpolation=None)
        parser.optionxform = str
        with open(path) as f:
            parser.read_string(f.read())
        return path, parser

    def test_systemd_unit_is_valid(self):
        path, unit = self.unit()
        self.assertTrue(unit["Service"]["ExecStart"].startswith("/usr/bin/ecat-slave --iface %I "))
        self.assertEqual(unit["Service"]["AmbientCapabilities"], unit["Service"]["CapabilityBoundingSet"])
        if not shutil.which("systemd-analyze"):
            self.skipTest("systemd-analyze not installed")
        d = tempfile.mkdtemp(prefix="ecat-unit-")
        self.addCleanup(shutil.rmtree, d, True)
        with open(path) as f:
            text = f.read().replace("/usr/bin/ecat-slave", self.path("bin", "ecat-slave"))
        with open(os.path.join(d, "ecat-slave@.service"), "w") as f:
            f.write(text)
        r = subprocess.run(["systemd-analyze", "verify", "--man=no", os.path.join(d, "ecat-slave@eth0.service")],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
        self.assertEqual(r.returncode, 0, r.stdout)
        self.assertEqual(r.stdout.strip(), "", r.stdout)

    def test_systemd_unit_capabilities_are_needed_and_enough(self):
        if not shutil.which("setpriv"):
            self.skipTest("setpriv not installed")
        _, unit = self.unit()
        caps = unit["Service"]["AmbientCapabilities"].split()
        self.assertTrue(caps)
        names = ",".join("+" + c.lower().removeprefix("cap_") for c in caps)
        ns = f"ecinst{os.getpid() % 100000}"
        subprocess.run(["ip", "netns", "add", ns], check=True)
        self.addCleanup(subprocess.run, ["ip", "netns", "del", ns])
        subprocess.run(["ip", "-n", ns, "link", "add", "u0", "type", "veth", "peer", "name", "u1"], check=True)
        for i in ("u0", "u1"):  # the unit's ExecStartPre brings the interface up
            subprocess.run(["ip", "-n", ns, "link", "set", i, "up"], check=True)
        state = tempfile.mkdtemp(prefix="ecat-unit-state-")
        os.chmod(state, 0o777)
        self.addCleanup(shutil.rmtree, state, True)

        def slave(cap_args, sub):
            return ["ip", "netns", "exec", ns, "setpriv", "--reuid=65534", "--regid=65534", "--clear-groups",
                    *cap_args, self.path("bin", "ecat-slave"), "--iface", "u0", "--state-dir",
                    os.path.join(state, sub)]

        # Without capabilities the slave cannot start (so the unit's are not decoration).
        r = subprocess.run(slave(["--inh-caps=-all", "--bounding-set=-all"], "none"), stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True, timeout=30)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("CAP_NET_RAW", r.stderr)
        # With the unit's, and no others, it serves the interface.
        p = subprocess.Popen(slave([f"--inh-caps=-all,{names}", f"--ambient-caps=-all,{names}",
                                    f"--bounding-set=-all,{names}"], "unit"),
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

        def stop():
            if p.poll() is None:
                p.terminate()
                p.wait(timeout=10)
        self.addCleanup(p.stdout.close)
        self.addCleanup(stop)
        deadline = time.monotonic() + 20
        while True:
            r = subprocess.run(["ip", "netns", "exec", ns, harness.env_path("ECATCTL"), "--iface", "u1", "scan"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)
            if r.returncode == 0 or time.monotonic() > deadline or p.poll() is not None:
                break
            time.sleep(0.2)
        self.assertEqual(r.returncode, 0, f"{r.stderr}\nslave: {p.stdout.read() if p.poll() is not None else ''}")
        self.assertIn("1 slave", r.stdout)
        stop()
        self.assertEqual(p.returncode, 0, p.stdout.read())


if __name__ == "__main__":
    harness.main()
