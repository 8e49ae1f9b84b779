"""Every command shown in README.md and tools/ecatctl/README.md, run as written against the real ecat-slave.

The commands are read from the READMEs themselves, so a command added there is tested without touching this
file: every line of a ```sh block (README.md) or of an indented block (tools/ecatctl/README.md), and every
inline `code` span that is a command of this project's programs with arguments (e.g. `fwimage info
image.bin`). Lines of other programs (apt, ip, ethtool, a foreign master's tools) are listed, not run; lines
with <placeholders> or [options] are synopses, not commands.

Each README runs in its own network namespace, so `ecat-slave` creates its veth pair ecat0/ecat1 as the
README says, and `ecatctl` finds ecat1 as its default interface, without touching the host's interfaces.
The only change made to a command: `ecat-slave` gets `--state-dir` in the test's directory (not the system's
/var/lib/softecat); a later `ecat-slave` start stops the one before. Commands run in a temporary working
directory (with the repository's folders linked into it), in README order, except that fwimage and drive-sim
run first (the image `foe write image.bin` sends is the one `fwimage build ... -o image.bin` makes); a file
named FILE is there for `--payload FILE`.
"""
import os
import re
import shlex
import shutil
import subprocess
import tempfile
import time
import unittest

import harness

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
READMES = ["README.md", os.path.join("tools", "ecatctl", "README.md")]

# Commands not run, each with the reason.
SKIP = {
    "bash scripts/demo.sh": "the demo script itself (builds, and uses ecat0/ecat1 of the host)",
    "bash scripts/test.sh": "the whole test suite, of which this test is a part",
    "build/tools/ecat-slave/ecat-slave --iface enp3s0": "needs a real NIC",
    "ecat-slave --iface enp3s0": "needs a real NIC",
}

# The project's programs: the names a README uses -> the environment variable with the built binary.
PROGRAMS = {
    "build/tools/ecat-slave/ecat-slave": "ECAT_SLAVE",
    "ecat-slave": "ECAT_SLAVE",
    "build/tools/ecatctl/ecatctl": "ECATCTL",
    "ecatctl": "ECATCTL",
    "build/tools/fwimage/fwimage": "FWIMAGE",
    "fwimage": "FWIMAGE",
    "build/tools/drive-sim/drive-sim": "DRIVE_SIM",
    "drive-sim": "DRIVE_SIM",
    "build/tools/ecat-conform/ecat-conform": "ECAT_CONFORM",
    "ecat-conform": "ECAT_CONFORM",
}


def strip_comment(line):
    """A shell line without its trailing # comment (a # starting a word)."""
    out, quote = [], None
    for i, c in enumerate(line):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "#" and (i == 0 or line[i - 1] in " \t"):
            break
        out.append(c)
    return "".join(out).strip()


def readme_commands(text):
    """(line number, command text) of every command line of a README, in order."""
    found = []
    lines = text.splitlines()
    fence = None
    prev_blank = True
    in_indented = False
    for n, raw in enumerate(lines, 1):
        if raw.lstrip().startswith("```"):
            fence = None if fence is not None else raw.strip()[3:].strip()
            continue
        if fence is not None:
            if fence in ("sh", "bash", "shell", "console"):
                found.append((n, strip_comment(raw)))
            continue
        if raw.startswith("    ") and (prev_blank or in_indented) and raw.strip():
            in_indented = True
            found.append((n, strip_comment(raw)))
        else:
            in_indented = bool(raw.startswith("    ") and in_indented)
            # Inline code spans that are one of our programs with arguments.
            for span in re.findall(r"`([^`]+)`", raw):
                words = span.split()
                if len(words) >= 2 and words[0] in PROGRAMS and not words[1].startswith("|"):
                    found.append((n, span.strip()))
        prev_blank = not raw.strip()
    return [(n, c) for n, c in found if c]


def is_synopsis(cmd):
    return bool(re.search(r"<[^>]+>|\[[^\]]+\]", cmd))


class Readme(unittest.TestCase):
    def setUp(self):
        self.bins = {v: harness.env_path(v) for v in sorted(set(PROGRAMS.values()))}
        self.dir = tempfile.mkdtemp(prefix="ecat-readme-", dir=os.environ.get("ECAT_TEST_OUT"))
        self.addCleanup(shutil.rmtree, self.dir, True)

    def parse(self, readme):
        """Commands of one README: (line, text, argv with the binaries, background?); skipped ones apart."""
        with open(os.path.join(ROOT, readme)) as f:
            text = f.read()
        runs, others = [], []
        for line, cmd in readme_commands(text):
            words = shlex.split(cmd)
            if words and words[0] == "sudo":
                words = words[1:]
            plain = " ".join(words)
            if plain in SKIP or (words and plain.rstrip(" &") in SKIP):
                continue
            if not words or words[0] not in PROGRAMS or is_synopsis(cmd):
                others.append((line, cmd))
                continue
            background = words[-1] == "&"
            if background:
                words = words[:-1]
            if "|" in words or ">" in words or ";" in words:
                self.fail(f"{readme}:{line}: `{cmd}`: pipes and redirections are not run by this test")
            argv = [self.bins[PROGRAMS[words[0]]]] + words[1:]
            runs.append((line, cmd, argv, background))
        return runs, others

    def test_readme_commands_are_found(self):
        # The parser must see the commands the README shows (a broken parser would pass everything).
        runs, _ = self.parse("README.md")
        texts = [c for _, c, _, _ in runs]
        for expected in ("ecatctl state 0 op", "ecatctl foe write image.bin", "fwimage info image.bin"):
            self.assertTrue(any(expected in t for t in texts), f"{expected!r} not among {texts}")
        runs, _ = self.parse(READMES[1])
        self.assertTrue(any(bg for *_, bg in runs), "tools/ecatctl/README.md starts the slave in the background")

    def run_readme(self, readme):
        runs, others = self.parse(readme)
        self.assertTrue(runs, f"no commands found in {readme}")
        for line, cmd in others:
            print(f"{readme}:{line}: not run (not one of the project's programs, or a synopsis): {cmd}")
        ns = f"rdme{os.getpid() % 100000}x{READMES.index(readme)}"
        subprocess.run(["ip", "netns", "add", ns], check=True)
        self.addCleanup(subprocess.run, ["ip", "netns", "del", ns])
        work = os.path.join(self.dir, f"work{READMES.index(readme)}")
        os.makedirs(work)
        # The README's paths are relative to the repository (od/examples/...): its folders are linked into
        # the working directory, whose files (image.bin, ...) stay the test's own.
        for entry in os.listdir(ROOT):
            if not entry.startswith(".") and entry != "build" and not os.path.exists(os.path.join(work, entry)):
                os.symlink(os.path.join(ROOT, entry), os.path.join(work, entry))
        with open(os.path.join(work, "FILE"), "wb") as f:  # `fwimage build --payload FILE ...`
            f.write(bytes((i * 13 + 7) & 0xFF for i in range(40000)))
        state = os.path.join(self.dir, f"state{READMES.index(readme)}")
        slave = []

        def in_ns(argv):
            return ["ip", "netns", "exec", ns] + argv

        def stop_slave():
            for p in slave:
                if p.poll() is None:
                    p.terminate()
                    try:
                        p.wait(timeout=10)
                    except subprocess.TimeoutExpired:
                        p.kill()
                        p.wait()

        self.addCleanup(stop_slave)
        # fwimage and drive-sim first (they make the files later commands use); every other command, ecat-slave
        # --write-esi included (its ESI is of the device as the state directory holds it then), in README order.
        offline = [r for r in runs if os.path.basename(r[2][0]) in ("fwimage", "drive-sim")]
        online = [r for r in runs if r not in offline]
        for line, cmd, argv, background in offline + online:
            where = f"{readme}:{line}: `{cmd}`"
            if os.path.basename(argv[0]) == "ecat-slave":
                argv = argv + ["--state-dir", state]
            if os.path.basename(argv[0]) == "ecat-slave" and self.starts_slave(argv):
                stop_slave()  # a README that starts the slave again (another configuration) replaces it
                log = open(os.path.join(self.dir, f"slave{READMES.index(readme)}.log"), "w")
                self.addCleanup(log.close)
                p = subprocess.Popen(in_ns(argv), cwd=work, stdout=log, stderr=subprocess.STDOUT)
                slave.append(p)
                self.wait_for_slave(in_ns, p, where)
                continue
            self.assertFalse(background, f"{where}: only ecat-slave is started in the background")
            r = subprocess.run(in_ns(argv), cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               errors="replace", timeout=240)
            failed = "\n".join(ln for ln in r.stdout.splitlines() if "FAIL" in ln)  # a report's failures
            self.assertEqual(r.returncode, 0,
                             f"{where} exited {r.returncode}:\n{failed}\n{r.stdout[-1500:]}\n{r.stderr[-1500:]}")
            print(f"{where}: ok")
        stop_slave()
        for p in slave:
            self.assertEqual(p.returncode, 0, f"an ecat-slave of {readme} exited {p.returncode}")

    @staticmethod
    def starts_slave(argv):
        if any(a == "--fault" and b == "list" for a, b in zip(argv[1:], argv[2:])):
            return False  # prints the faults and exits
        return not any(a in ("--help", "-h", "--version") or a.startswith("--write-") for a in argv[1:])

    def needs_slave(self, argv):
        name = os.path.basename(argv[0])
        if name == "ecat-conform":
            return not any(a in ("--list", "--help", "-h") for a in argv[1:])
        return name == "ecatctl" or (name == "ecat-slave" and self.starts_slave(argv))

    def wait_for_slave(self, in_ns, proc, where):
        deadline = time.monotonic() + 20
        while True:
            self.assertIsNone(proc.poll(), f"{where}: ecat-slave exited {proc.returncode}")
            r = subprocess.run(in_ns([self.bins["ECATCTL"], "--timeout", "20", "--retries", "0", "reg", "read", "0",
                                      "0", "1"]), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            if r.returncode == 0:
                return
            self.assertLess(time.monotonic(), deadline, f"{where}: the slave does not answer: {r.stderr}")
            time.sleep(0.1)

    def test_readme(self):
        self.run_readme(READMES[0])

    def test_ecatctl_readme(self):
        self.run_readme(READMES[1])


if __name__ == "__main__":
    harness.main()
