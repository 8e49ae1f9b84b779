"""Every command shown in README.md, docs/*.md and tools/*/README.md, run as written against the real ecat-slave.

The commands are read from the pages themselves, so a command added there is tested without touching this
file: every line of a ```sh block or of an indented block, and in README.md and tools/ecatctl/README.md also
every inline `code` span that is a command of this project's programs with arguments (e.g. `fwimage info
image.bin`; in docs/ an inline span names an option in a sentence, and is listed only). `ip` lines run too
(inside the test's network namespace, which is all they touch). Lines of other programs (apt, cmake,
ethtool, a foreign master's tools) are listed, not run; lines with <placeholders>, [options] or an upper-case
placeholder word (N, NAME, PATH) are synopses, not commands. The project's programs are on PATH as they are
once installed (`ecatctl scan`), from the build directory.

Each page runs in its own network namespace, so `ecat-slave` creates its veth pair ecat0/ecat1 as the
page says, and `ecatctl` finds ecat1 as its default interface, without touching the host's interfaces.
The only change made to a command: `ecat-slave` gets `--state-dir` in the test's directory (not the system's
/var/lib/softecat; a --state-dir the page gives is moved there); a later `ecat-slave` start stops the ones
before, except that slaves started in the background (`&`) in one block run together (a chain of processes). Commands run in a temporary working
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
READMES = ["README.md", os.path.join("tools", "ecatctl", "README.md")]  # inline spans are commands too
DOCS = sorted([os.path.join("docs", f) for f in os.listdir(os.path.join(ROOT, "docs")) if f.endswith(".md")] +
              [os.path.join("tools", d, "README.md") for d in os.listdir(os.path.join(ROOT, "tools"))
               if os.path.isfile(os.path.join(ROOT, "tools", d, "README.md"))])
PAGES = READMES + [d for d in DOCS if d not in READMES]

# Commands not run, each with the reason.
SKIP = {
    "bash scripts/demo.sh": "the demo script itself (builds, and uses ecat0/ecat1 of the host)",
    "bash scripts/test.sh": "the whole test suite, of which this test is a part",
    "build/tools/ecat-slave/ecat-slave --iface enp3s0": "needs a real NIC",
    "ecat-slave --iface enp3s0": "needs a real NIC",
    "ip addr flush dev enp3s0": "needs a real NIC",
    "ip link set enp3s0 up": "needs a real NIC",
    "ecat-slave --iface eth1 --slaves 16": "needs a real NIC",
    "ecat-slave --iface in0 --out-iface out0": "needs interfaces in0 and out0 (docs/segment.md's two-process "
                                               "example creates and runs its own)",
}
# Other programs whose lines run: they only touch the test's network namespace.
RUN_OTHERS = {"ip"}

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
    "ecat-ci": "ECAT_CI",
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


def readme_commands(text, inline=True):
    """(line number, command text) of every command line of a README, in order (inline: with the inline code
    spans that are commands of the project's programs)."""
    return [(n, c) for n, c, _ in readme_blocks(text, inline)]


def readme_blocks(text, inline=True):
    """(line number, command text, block number) of every command line; the lines of one code block share
    their block number, each inline span has its own."""
    found = []
    block = 0
    lines = text.splitlines()
    fence = None
    prev_blank = True
    in_indented = False
    for n, raw in enumerate(lines, 1):
        if raw.lstrip().startswith("```"):
            fence = None if fence is not None else raw.strip()[3:].strip()
            block += 1
            continue
        if fence is not None:
            if fence in ("sh", "bash", "shell", "console"):
                found.append((n, strip_comment(raw), block))
            continue
        if raw.startswith("    ") and (prev_blank or in_indented) and raw.strip():
            if not in_indented:
                block += 1
            in_indented = True
            found.append((n, strip_comment(raw), block))
        else:
            in_indented = bool(raw.startswith("    ") and in_indented)
            # Inline code spans that are one of our programs with arguments.
            for span in re.findall(r"`([^`]+)`", raw) if inline else []:
                words = span.split()
                if len(words) >= 2 and words[0] in PROGRAMS and not words[1].startswith("|"):
                    block += 1
                    found.append((n, span.strip(), block))
        prev_blank = not raw.strip()
    return [(n, c, b) for n, c, b in found if c]


def is_synopsis(cmd):
    if re.search(r"<[^>]+>|\[[^\]]+\]", cmd):
        return True
    # An upper-case word is a placeholder (N, NAME, PATH), except FILE, which the test provides.
    return any(re.fullmatch(r"[A-Z][A-Z_]*", w) and w != "FILE" for w in cmd.split())


class Readme(unittest.TestCase):
    def setUp(self):
        self.bins = {v: harness.env_path(v) for v in sorted(set(PROGRAMS.values()))}
        self.dir = tempfile.mkdtemp(prefix="ecat-readme-", dir=os.environ.get("ECAT_TEST_OUT"))
        self.addCleanup(shutil.rmtree, self.dir, True)
        # The programs on PATH by their names, as after an install (a page says `ecatctl scan`).
        self.bin_dir = os.path.join(self.dir, "bin")
        os.makedirs(self.bin_dir)
        for name, var in PROGRAMS.items():
            if "/" not in name:
                os.symlink(self.bins[var], os.path.join(self.bin_dir, name))
        self.env = dict(os.environ, PATH=self.bin_dir + os.pathsep + os.environ.get("PATH", ""))

    def parse(self, readme):
        """Commands of one page: (line, text, argv, background?, block); skipped ones apart."""
        with open(os.path.join(ROOT, readme)) as f:
            text = f.read()
        runs, others = [], []
        raw_lines = text.splitlines()
        for line, cmd, block in readme_blocks(text, inline=readme in READMES):
            try:
                words = shlex.split(cmd)
            except ValueError:  # not shell: output shown in an indented block
                others.append((line, cmd))
                continue
            if words and words[0] == "sudo":
                words = words[1:]
            plain = " ".join(words)
            if plain in SKIP or (words and plain.rstrip(" &") in SKIP):
                continue
            if not words or (words[0] not in PROGRAMS and words[0] not in RUN_OTHERS) or is_synopsis(cmd):
                others.append((line, cmd))
                continue
            background = words[-1] == "&"
            if background:
                words = words[:-1]
            if "|" in words or ">" in words or ";" in words:
                self.fail(f"{readme}:{line}: `{cmd}`: pipes and redirections are not run by this test")
            argv = ([self.bins[PROGRAMS[words[0]]]] if words[0] in PROGRAMS else [shutil.which(words[0])]) + words[1:]
            # A comment that says how many slaves the command shows (`ecatctl scan   # 2 slaves`) is checked.
            said = re.search(r"#\s*(\d+) slaves?\b", raw_lines[line - 1]) if cmd in raw_lines[line - 1] else None
            runs.append((line, cmd, argv, background, block, int(said.group(1)) if said else None))
        return runs, others

    def test_readme_commands_are_found(self):
        # The parser must see the commands the README shows (a broken parser would pass everything).
        runs, _ = self.parse("README.md")
        texts = [r[1] for r in runs]
        for expected in ("ecatctl state 0 op", "ecatctl foe write image.bin", "fwimage info image.bin"):
            self.assertTrue(any(expected in t for t in texts), f"{expected!r} not among {texts}")
        runs, _ = self.parse(READMES[1])
        self.assertTrue(any(r[3] for r in runs), "tools/ecatctl/README.md starts the slave in the background")
        runs, _ = self.parse(os.path.join("docs", "segment.md"))
        chain = [r for r in runs if r[3] and "--iface" in r[2]]
        self.assertEqual(len(chain), 2, "docs/segment.md chains two processes")
        self.assertEqual(chain[0][4], chain[1][4], "in one block")
        self.assertTrue(any(r[2][0].endswith("/ip") for r in runs), "its ip lines are run")
        self.assertEqual([r[5] for r in runs if r[5] is not None], [2, 2], "its '# 2 slaves' comments are checked")
        self.assertIn(os.path.join("docs", "ci.md"), DOCS)
        self.assertTrue(is_synopsis("ecat-slave --slaves N") and not is_synopsis("fwimage build --payload FILE"))

    def test_topology_example_is_the_file(self):
        """docs/segment.md shows tools/ecat-slave/examples/tree.topo as it is (its command runs that file)."""
        with open(os.path.join(ROOT, "docs", "segment.md")) as f:
            page = f.read()
        with open(os.path.join(ROOT, "tools", "ecat-slave", "examples", "tree.topo")) as f:
            self.assertIn("```text\n" + f.read() + "```", page)

    def run_readme(self, readme):
        runs, others = self.parse(readme)
        for line, cmd in others:
            print(f"{readme}:{line}: not run (not one of the project's programs, or a synopsis): {cmd}")
        if not runs:
            print(f"{readme}: no commands of the project's programs")
            return
        k = PAGES.index(readme)
        ns = f"rdme{os.getpid() % 100000}x{k}"
        subprocess.run(["ip", "netns", "add", ns], check=True)
        self.addCleanup(subprocess.run, ["ip", "netns", "del", ns])
        work = os.path.join(self.dir, f"work{k}")
        os.makedirs(work)
        # The README's paths are relative to the repository (od/examples/...): its folders are linked into
        # the working directory, whose files (image.bin, ...) stay the test's own.
        for entry in os.listdir(ROOT):
            if not entry.startswith(".") and entry != "build" and not os.path.exists(os.path.join(work, entry)):
                os.symlink(os.path.join(ROOT, entry), os.path.join(work, entry))
        with open(os.path.join(work, "FILE"), "wb") as f:  # `fwimage build --payload FILE ...`
            f.write(bytes((i * 13 + 7) & 0xFF for i in range(40000)))
        state = os.path.join(self.dir, f"state{k}")
        slaves = []  # (process, block, background)

        def in_ns(argv):
            return ["ip", "netns", "exec", ns] + argv

        def stop_slaves():
            for p, *_ in slaves:
                if p.poll() is None:
                    p.terminate()
                    try:
                        p.wait(timeout=10)
                    except subprocess.TimeoutExpired:
                        p.kill()
                        p.wait()

        self.addCleanup(stop_slaves)
        # fwimage and drive-sim first (they make the files later commands use); every other command, ecat-slave
        # --write-esi included (its ESI is of the device as the state directory holds it then), in README order.
        offline = [r for r in runs if os.path.basename(r[2][0]) in ("fwimage", "drive-sim")]
        online = [r for r in runs if r not in offline]
        for line, cmd, argv, background, block, slaves_said in offline + online:
            where = f"{readme}:{line}: `{cmd}`"
            if os.path.basename(argv[0]) == "ecat-slave":
                argv = self.own_state_dir(argv, os.path.join(state, f"line{line}"))
            if os.path.basename(argv[0]) == "ecat-slave" and self.starts_slave(argv):
                # A start replaces the slaves before, unless they and it are started in the background in one
                # block (processes chained with --out-iface).
                if not (background and slaves and all(bg and b == block for _, b, bg in slaves)):
                    stop_slaves()
                    slaves.clear()
                log = open(os.path.join(self.dir, f"slave{k}-{line}.log"), "w")
                self.addCleanup(log.close)
                p = subprocess.Popen(in_ns(argv), cwd=work, stdout=log, stderr=subprocess.STDOUT, env=self.env)
                slaves.append((p, block, background))
                self.wait_for_slave(in_ns, p, argv, where)
                continue
            self.assertFalse(background, f"{where}: only ecat-slave is started in the background")
            r = subprocess.run(in_ns(argv), cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               errors="replace", timeout=240, env=self.env)
            failed = "\n".join(ln for ln in r.stdout.splitlines() if "FAIL" in ln)  # a report's failures
            self.assertEqual(r.returncode, 0,
                             f"{where} exited {r.returncode}:\n{failed}\n{r.stdout[-1500:]}\n{r.stderr[-1500:]}")
            if slaves_said is not None:
                self.assertRegex(r.stdout, rf"(?m)^{slaves_said} slaves?$", f"{where}: the page says so")
            print(f"{where}: ok")
        stop_slaves()
        for p, *_ in slaves:
            self.assertEqual(p.returncode, 0, f"an ecat-slave of {readme} exited {p.returncode}")

    @staticmethod
    def own_state_dir(argv, state):
        """argv with the state directory in the test's directory: a --state-dir the page gives is replaced."""
        out, skip = [], False
        for i, a in enumerate(argv):
            if skip:
                skip = False
                continue
            if a == "--state-dir":
                skip = True
                continue
            if a.startswith("--state-dir="):
                continue
            out.append(a)
        return out + ["--state-dir", state]

    @staticmethod
    def starts_slave(argv):
        if any(a == "--fault" and b == "list" for a, b in zip(argv[1:], argv[2:])):
            return False  # prints the faults and exits
        return not any(a in ("--help", "-h", "--version", "--send") or a.startswith(("--write-", "--send="))
                       for a in argv[1:])

    def wait_for_slave(self, in_ns, proc, argv, where):
        """Until the slave serves its interface: a packet socket of its own is open (ecat-slave opens it once
        the interface is ready) and, for the veth pair it creates, a frame on the master end comes back."""
        deadline = time.monotonic() + 20
        own_iface = "--iface" in argv
        while True:
            self.assertIsNone(proc.poll(), f"{where}: ecat-slave exited {proc.returncode}")
            if own_iface:
                ready = self.has_packet_socket(proc)
            else:
                r = subprocess.run(in_ns([self.bins["ECATCTL"], "--timeout", "20", "--retries", "0", "reg", "read",
                                          "0", "0", "1"]), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                ready = r.returncode == 0
            if ready:
                return
            self.assertLess(time.monotonic(), deadline, f"{where}: the slave does not answer")
            time.sleep(0.1)

    @staticmethod
    def has_packet_socket(proc):
        """True if a process of proc's tree (ip netns exec runs ecat-slave as itself) holds an AF_PACKET socket."""
        try:
            with open(f"/proc/{proc.pid}/net/packet") as f:
                inodes = {line.split()[-1] for line in f.read().splitlines()[1:] if line.split()}
            for fd in os.listdir(f"/proc/{proc.pid}/fd"):
                link = os.readlink(f"/proc/{proc.pid}/fd/{fd}")
                if link.startswith("socket:[") and link[8:-1] in inodes:
                    return True
        except OSError:
            pass
        return False

    def test_readme(self):
        self.run_readme(READMES[0])

    def test_demo(self):
        """README command (1) past its build (scripts/demo.sh builds ecat-slave and ecatctl, then runs this): in a
        network namespace of its own, with the build of this test run."""
        build = os.environ.get("SOFTECAT_BUILD_DIR")
        if not build:
            self.skipTest("SOFTECAT_BUILD_DIR not set")
        ns = f"rdme{os.getpid() % 100000}demo"
        subprocess.run(["ip", "netns", "add", ns], check=True)
        self.addCleanup(subprocess.run, ["ip", "netns", "del", ns])
        capture = os.path.join(self.dir, "demo.pcap")
        r = subprocess.run(["ip", "netns", "exec", ns, "bash", os.path.join(ROOT, "scripts", "demo-run.sh"), build],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=240,
                           env=dict(os.environ, ECAT_DEMO_CAPTURE=capture))
        self.assertEqual(r.returncode, 0, r.stdout[-3000:])
        self.assertRegex(r.stdout, r"(?m)^1 slave$")
        self.assertRegex(r.stdout, r"(?m)^ok state ", "the control socket answered the demo's 'status'")
        self.assertIn(f"frames captured in {capture}", r.stdout)
        self.assertGreater(os.path.getsize(capture), 24, "frames were captured")

    def test_ecatctl_readme(self):
        self.run_readme(READMES[1])

    def test_docs(self):
        for page in DOCS:
            if page in READMES:
                continue
            with self.subTest(page=page):
                self.run_readme(page)


if __name__ == "__main__":
    harness.main()
