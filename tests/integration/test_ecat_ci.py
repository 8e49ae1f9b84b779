"""ecat-ci, the command a master project's CI runs: a line of soft slaves on a fresh veth pair in fresh
namespaces, the master's command on the master end, everything torn down, the command's exit status. Run as root
and as an unprivileged user (a fresh user namespace, where the kernel allows it), and the ecat-ci lines of the
GitHub Actions workflow in docs/ci.md as they are written."""
import os
import re
import shutil
import subprocess
import tempfile
import unittest

import harness

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "ecat-ci", "ecat-ci")


def processes_using(path):
    """Command lines of the processes whose arguments mention path (the slave's state directory is under it)."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if path in cmd:
            found.append(cmd)
    return found


class EcatCi(unittest.TestCase):
    def setUp(self):
        self.env = dict(os.environ, ECAT_SLAVE=harness.env_path("ECAT_SLAVE"), ECATCTL=harness.env_path("ECATCTL"))
        self.dir = tempfile.mkdtemp(prefix="ecat-ci-test-")
        os.chmod(self.dir, 0o777)
        self.addCleanup(shutil.rmtree, self.dir, True)

    def tearDown(self):
        # Torn down: no ecat-slave (its state directory is in self.dir) is left, so the namespaces it held, and the
        # veth pair in them, are gone. (The host's own links are not compared: other tests create theirs.)
        self.assertEqual(processes_using(self.dir), [], "ecat-ci left processes behind")
        self.assertEqual(os.listdir(self.dir), [], "ecat-ci left files behind")

    def run_ci(self, *args, user=None):
        cmd = [SCRIPT, *args]
        if user:
            cmd = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "--inh-caps=-all"] + cmd
        return subprocess.run(cmd, env=dict(self.env, TMPDIR=self.dir), cwd=self.dir, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, timeout=120)

    def test_master_command_sees_the_line_and_its_status_is_returned(self):
        r = self.run_ci("--slaves", "3", "--", self.env["ECATCTL"], "--iface", "{iface}", "scan")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("3 slaves", r.stdout)
        self.assertEqual(len(re.findall(r"^\d+\s+0x100\d", r.stdout, re.M)), 3, r.stdout)
        r = self.run_ci("--", "sh", "-c", 'test "$ECAT_IFACE" = ecat1 && exit 42')
        self.assertEqual(r.returncode, 42, r.stderr)
        r = self.run_ci("--", "sh", "-c", "exit 0")
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_options_reach_the_slave(self):
        # A deliberately faulty slave: ecatctl reads APRD's working counter 2 where 1 is right.
        r = self.run_ci("--slave-arg=--fault=wkc-aprd", "--", self.env["ECATCTL"], "--iface", "{iface}", "reg",
                        "read", "0", "0x0130", "2")
        self.assertEqual(r.returncode, 6, r.stderr)  # ecatctl: unexpected answer
        self.assertIn("working counter", r.stderr)

    def test_slave_that_cannot_start_is_reported(self):
        r = self.run_ci("--slave-arg=--config=/nonexistent.conf", "--", "true")
        self.assertEqual(r.returncode, 125, r.stderr)
        self.assertIn("nonexistent.conf", r.stderr)
        self.assertEqual(self.run_ci("--slaves", "0", "--", "true").returncode, 2)
        self.assertEqual(self.run_ci().returncode, 2)

    def test_without_root(self):
        probe = subprocess.run(["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "unshare", "-rn",
                                "true"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if probe.returncode != 0:
            self.skipTest(f"unprivileged user namespaces not allowed here: {probe.stderr.strip()}")
        for path in (self.env["ECAT_SLAVE"], self.env["ECATCTL"], SCRIPT):
            if not os.access(path, os.X_OK, effective_ids=False) or subprocess.run(
                    ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "test", "-x", path]).returncode:
                self.skipTest(f"{path} is not executable by an unprivileged user")
        r = self.run_ci("--slaves", "2", "--", "sh", "-c", '"$ECATCTL" --iface "$ECAT_IFACE" scan; exit 3',
                        user=True)
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("2 slaves", r.stdout)

    def test_workflow_example(self):
        import yaml  # Debian's python3-yaml
        with open(os.path.join(ROOT, "docs", "ci.md")) as f:
            text = f.read()
        blocks = re.findall(r"```yaml\n(.*?)```", text, re.S)
        self.assertEqual(len(blocks), 1, "docs/ci.md has one workflow")
        flow = yaml.safe_load(blocks[0])
        steps = [s for job in flow["jobs"].values() for s in job["steps"]]
        self.assertTrue(any("apt-get install -y ./softecat_" in s.get("run", "") for s in steps),
                        "the workflow installs the .deb")
        runs = [line.strip() for s in steps for line in s.get("run", "").splitlines()
                if line.strip().startswith("ecat-ci ")]
        self.assertGreaterEqual(len(runs), 2, runs)
        for line in runs:
            words = line.split()
            sep = words.index("--")
            master = words[sep + 1:]
            if master[0] != "ecatctl":  # the master project's own program: ecatctl stands in for it
                master = ["ecatctl", "--iface", "{iface}", "scan"]
            r = self.run_ci(*words[1:sep], "--", self.env["ECATCTL"], *master[1:])
            self.assertEqual(r.returncode, 0, f"{line}: {r.stderr}")
        # The command shown at the top of the page.
        first = re.search(r"```sh\n(ecat-ci .*)\n```", text).group(1).split()
        r = self.run_ci(*first[1:first.index("--") + 1], self.env["ECATCTL"], *first[first.index("--") + 2:])
        self.assertEqual(r.returncode, 0, r.stderr)


if __name__ == "__main__":
    harness.main()
