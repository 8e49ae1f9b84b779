"""A line from an ENI (issue 21 part 4): `ecat-slave --eni esi/eni/examples/mixed-line.xml` serves the line that ENI
describes, and a master configured with that ENI finds what it expects. The master here is EniMaster: it knows
nothing but the ENI. It checks the slaves' identities and order (ecatctl scan), then runs the ENI as a master runs
it: per state transition the register init commands of every slave (station addresses by position, SyncManagers,
FMMUs, DC, AL control) with the working counters the ENI gives (Cnt), the CoE init commands (SDO downloads), and in
SAFEOP/OP the ENI's cyclic frame, every command with the working counter its Cnt says. A tree: the drive sits on
port C of the coupler, behind the terminals of port B. Bad ENIs are refused with FILE:LINE and exit 2."""
import os
import struct
import subprocess
import tempfile
import time
import unittest
import xml.etree.ElementTree as ET

import harness

SOURCE = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
EXAMPLE = os.path.join(SOURCE, "esi", "eni", "examples", "mixed-line.xml")
STATE_CODES = {"I": 1, "P": 2, "B": 3, "S": 4, "O": 8}
STATE_NAMES = {1: "INIT", 2: "PREOP", 4: "SAFEOP", 8: "OP"}


def num(text):
    text = (text or "").strip()
    return int(text[2:], 16) if text[:2].lower() in ("#x", "0x") else int(text)


def require_eni(test):
    r = subprocess.run([harness.env_path("ECAT_SLAVE"), "--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True, timeout=30)
    if "--eni" not in r.stdout:
        test.skipTest("ecat-slave has no --eni")


class EniMaster:
    """A master that knows only the ENI: its init commands, CoE init commands and cyclic commands."""

    def __init__(self, bus, path):
        self.bus = bus
        self.mm = harness.MiniMaster(bus)
        self.root = ET.parse(path).getroot()
        self.slaves = self.root.findall("Config/Slave")
        self.state = 1
        self.wkc_errors = []
        self.cycles = 0
        self.checked = 0  # cycles whose working counters were compared with the ENI's

    def close(self):
        self.mm.close()

    def identities(self):
        return [tuple(num(s.findtext("Info/" + k)) & 0xFFFFFFFF for k in ("VendorId", "ProductCode", "RevisionNo"))
                for s in self.slaves]

    def stations(self):
        return [num(s.findtext("Info/PhysAddr")) for s in self.slaves]

    @staticmethod
    def datagram(cmd):
        code = num(cmd.findtext("Cmd"))
        if cmd.find("Addr") is not None:
            addr = num(cmd.findtext("Addr")) & 0xFFFFFFFF
            adp, ado = addr & 0xFFFF, addr >> 16
        else:
            adp, ado = num(cmd.findtext("Adp") or "0") & 0xFFFF, num(cmd.findtext("Ado"))
        if cmd.find("Data") is not None:
            data = bytes.fromhex(cmd.findtext("Data"))
        else:
            data = bytes(num(cmd.findtext("DataLength") or "0"))
        return code, adp, ado, data

    def init_cmd(self, slave, cmd):
        code, adp, ado, data = self.datagram(cmd)
        if ado == 0x0990 and code == 5:  # DC start time: the master computes it from the slave's system time
            now = struct.unpack("<Q", self.mm.fprd(adp, 0x0910, 8))[0]
            cycle = num(slave.findtext("DC/CycleTime0"))
            data = struct.pack("<Q", ((now + 100_000_000) // cycle + 1) * cycle)
        want = num(cmd.findtext("Cnt")) if cmd.find("Cnt") is not None else None
        tries = 1 + num(cmd.findtext("Retries") or "0")
        for _ in range(max(tries, 3)):
            r = self.mm.txrx([(code, adp, ado, data)])
            if r is not None and (want is None or r[0][1] == want):
                return
        raise AssertionError(f"{cmd.findtext('Comment')}: working counter {None if r is None else r[0][1]}, "
                             f"the ENI says {want}\n{self.bus.slave_output()[-2000:]}")

    def cyclic_frame(self):
        cmds = []
        for cmd in self.root.findall("Config/Cyclic/Frame/Cmd"):
            states = [s.text for s in cmd.findall("State")]
            cmds.append((self.datagram(cmd), num(cmd.findtext("Cnt")), states))
        return cmds

    def cycle(self, n, until=None):
        frame = self.cyclic_frame()
        per_slave = [(harness.FPRD, st, 0x0130, bytes(2)) for st in self.stations()]
        states = []
        for _ in range(n):
            r = self.mm.txrx([d for d, _, _ in frame] + per_slave, timeout=0.05)
            self.cycles += 1
            if r is not None:
                states = [struct.unpack("<H", d)[0] for d, _ in r[len(frame):]]
                # The ENI's Cnt holds once every slave is in the state the command is for (a master checks the
                # working counters of the state it has reached, not while the slaves are changing state).
                if all(x == self.state for x in states):
                    self.checked += 1
                    for (d, cnt, names), (_, wkc) in zip(frame, r):
                        if STATE_NAMES.get(self.state) in names and wkc != cnt:
                            self.wkc_errors.append((d[0], d[2], wkc, cnt, self.state))
                if until and until(states):
                    return states
            time.sleep(0.001)
        return states

    def transition(self, target):
        name = {1: "I", 2: "P", 4: "S", 8: "O"}
        t = name[self.state] + name[target]
        for cmd in self.root.findall("Config/Master/InitCmds/InitCmd"):
            if t in [x.text for x in cmd.findall("Transition")]:
                self.init_cmd(None, cmd)
        al = []
        for k, slave in enumerate(self.slaves):
            for cmd in slave.findall("InitCmds/InitCmd"):
                if t not in [x.text for x in cmd.findall("Transition")]:
                    continue
                if num(cmd.findtext("Ado") or "0") == 0x0120 and cmd.find("Addr") is None:
                    al.append((slave, cmd))
                elif num(cmd.findtext("Ado") or "0") == 0x0130:
                    continue  # reads of the AL status: the cycles below watch it
                else:
                    self.init_cmd(slave, cmd)
            for coe in slave.findall("Mailbox/CoE/InitCmds/InitCmd"):
                if t in [x.text for x in coe.findall("Transition")] and num(coe.findtext("Ccs")) == 1:
                    data = bytes.fromhex(coe.findtext("Data"))
                    where = ["--station", str(num(slave.findtext("Info/PhysAddr"))),
                             hex(num(coe.findtext("Index"))), str(num(coe.findtext("SubIndex")))]
                    if coe.get("CompleteAccess") in ("true", "1"):
                        # The whole object from the subindex, the ENI's bytes as they are.
                        self.bus.ecatctl("download", "--complete", *where, *[hex(b) for b in data])
                        continue
                    # The ENI's bytes as one value of their size (ecatctl takes single values by the entry's type).
                    kind = {1: "u8", 2: "u16", 4: "u32", 8: "u64"}[len(data)]
                    self.bus.ecatctl("download", *where, str(int.from_bytes(data, "little")), "--type", kind)
        if target >= 4:
            self.cycle(150)  # SYNC0 of the DC slaves starts 100 ms from their start time
        for slave, cmd in al:
            self.init_cmd(slave, cmd)
        self.state = target
        states = self.cycle(3000, until=lambda s: len(s) == len(self.slaves) and all(x == target for x in s))
        if not (len(states) == len(self.slaves) and all(x == target for x in states)):
            codes = [hex(struct.unpack("<H", self.mm.fprd(st, 0x0134, 2))[0]) for st in self.stations()]
            raise AssertionError(f"{STATE_NAMES[target]} not reached: {[hex(s) for s in states]} AL status codes "
                                 f"{codes}\n{self.bus.slave_output()[-3000:]}")


class EniLine(unittest.TestCase):
    def run_line(self, args, eni=EXAMPLE):
        require_eni(self)
        with harness.Bus(slave_args=args) as bus:
            m = EniMaster(bus, eni)
            self.addCleanup(m.close)
            # Found in the ENI's order, with the ENI's identities.
            self.assertEqual(m.mm.count_slaves(), len(m.slaves))
            out = bus.ecatctl("scan").stdout
            rows = []
            for line in out.splitlines():
                parts = line.split()
                if len(parts) >= 7 and parts[0].isdigit():
                    rows.append(tuple(int(p, 16) for p in parts[3:6]))
            self.assertEqual(rows, m.identities(), out)
            for target in (2, 4, 8):
                m.transition(target)
            m.cycle(500)
            self.assertEqual(m.wkc_errors, [], "cyclic working counters differ from the ENI's Cnt")
            self.assertGreater(m.checked, 500)
            # Back to Init as the ENI says (OI), all slaves follow.
            m.transition(1)
            return bus.slave_output()

    def test_eni_data_only_reaches_op(self):
        log = self.run_line(["--eni", EXAMPLE])
        # Where each slave's description came from, and what is not emulated, said at start.
        self.assertEqual(log.count("served from"), 5, log)
        self.assertIn("CiA 402", log)

    def test_with_esi_dir_reaches_op(self):
        log = self.run_line(["--eni", EXAMPLE, "--esi-dir", os.path.join(SOURCE, "esi", "examples")])
        # Every slave of the example has its ESI in esi/examples: each is served from it.
        self.assertEqual(log.count("(ENI data)"), 0, log)
        self.assertEqual(log.count("served from"), 5, log)
        for esi in ("coupler.xml", "digital-io.xml", "analog-in.xml", "drive402.xml"):
            self.assertIn(esi, log)

    def test_modular_device_gets_the_enis_modules(self):
        # A modular device whose ENI configures modules other than the ESI's defaults (esi/eni/examples/
        # modular-line.xml): served from its ESI with those modules, it takes the ENI's PDO assignment and SM
        # lengths and reaches Op with the ENI's working counters; with the defaults the master's assignment of
        # 0x1603 is aborted and the line stops in PREOP.
        eni = os.path.join(SOURCE, "esi", "eni", "examples", "modular-line.xml")
        log = self.run_line(["--eni", eni, "--esi-dir", os.path.join(SOURCE, "esi", "examples")], eni)
        self.assertIn("modular-io.xml", log)
        self.assertIn("modules EXM-AI2,EXM-AI2,-,EXM-DO8 (from its PDOs)", log)
        self.assertNotIn("the default modules are served", log)
        self.assertNotIn("not a PDO of the device", log)
        # From the ENI's data alone the same line reaches Op as well.
        log = self.run_line(["--eni", eni], eni)
        self.assertIn("(ENI data)", log)
        # A configuration tool writes a device's module list whole (complete access of 0xF030, ETG.5001.1) when
        # its ESI asks for it: from the ENI's data the slave holds the array the master writes, and the line
        # reaches Op; with the ESI the list chooses the modules.
        with tempfile.TemporaryDirectory() as d:
            f030 = os.path.join(d, "f030.xml")
            ca = ("<InitCmd Fixed=\"true\" CompleteAccess=\"true\"><Transition>PS</Transition>"
                  "<Comment><![CDATA[configured module ident list]]></Comment><Timeout>0</Timeout><Ccs>1</Ccs>"
                  "<Index>#xf030</Index><SubIndex>0</SubIndex><Data>040001300000013000000000000001200000</Data>"
                  "</InitCmd>")
            with open(eni) as src, open(f030, "w") as out:
                out.write(src.read().replace("<CoE>\n\t\t\t\t\t<InitCmds>\n", "<CoE>\n\t\t\t\t\t<InitCmds>\n" + ca, 1))
            log = self.run_line(["--eni", f030], f030)
            self.assertIn("served from", log)
            self.assertNotIn("by complete access", log, "the array is served, nothing said")

    def test_topology_with_esi_devices(self):
        # A mixed line written by hand: a coupler and a digital input terminal from their ESIs (one device of a
        # file with several, by its spec), then the built-in drive.
        require_eni(self)
        examples = os.path.join(SOURCE, "esi", "examples")
        with tempfile.TemporaryDirectory() as d:
            topo = os.path.join(d, "line.topo")
            with open(topo, "w") as f:
                f.write(f"device coupler esi={examples}/coupler.xml ports=4\n"
                        f"device di esi={examples}/digital-io.xml device=0x03f03052:0x00110000\n"
                        f"device drive at=coupler:2\n")
            with harness.Bus(slave_args=["--topology", topo]) as bus:
                out = bus.ecatctl("scan").stdout
                rows = [tuple(int(p, 16) for p in line.split()[3:6]) for line in out.splitlines()
                        if len(line.split()) >= 7 and line.split()[0].isdigit()]
                self.assertEqual(rows[:2], [(0xA5E, 0x00011100, 0x00010000), (0xA5E, 0x03F03052, 0x00110000)], out)
                self.assertEqual(len(rows), 3, out)
                self.assertEqual(rows[2][0], 0xFB, out)  # the built-in MAXPOS on port 2 of the coupler
                log = bus.slave_output()
                self.assertIn("served from " + examples + "/digital-io.xml", log)
            # Mistakes in the new keys: FILE:LINE and exit 2.
            slave = harness.env_path("ECAT_SLAVE")
            for text, line, says in (
                    ("device a\ndevice b device=0x1\n", 2, "without esi=FILE"),
                    (f"device a esi={examples}/digital-io.xml\n", 1, "0x03F03052"),  # several devices: listed
                    (f"device a esi={examples}/coupler.xml config=x.conf\n", 1, "esi= and config= together"),
                    ("device a esi=/nonexistent.xml\n", 1, "/nonexistent.xml")):
                with open(topo, "w") as f:
                    f.write(text)
                r = subprocess.run([slave, "--iface", "lo", "--topology", topo], stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True, timeout=30)
                self.assertEqual(r.returncode, 2, (text, r.stderr))
                self.assertIn(f"{topo}:{line}: ", r.stderr, text)
                self.assertIn(says, r.stderr, text)

    def test_bad_eni_is_file_line_exit_2(self):
        require_eni(self)
        slave = harness.env_path("ECAT_SLAVE")
        with open(EXAMPLE) as f:
            example = f.read()
        with tempfile.TemporaryDirectory() as d:
            cases = {
                "esi.xml": ("<?xml version=\"1.0\"?>\n<EtherCATInfo/>\n", ":2: "),
                "broken.xml": ("<EtherCATConfig>\n<Config>\n", ":3: "),
                "dangling.xml": (example.replace("<PhysAddr>1002</PhysAddr>\n\t\t\t</PreviousPort>",
                                                              "<PhysAddr>4242</PhysAddr>\n\t\t\t</PreviousPort>"), ":"),
                # The drive on port D: a frame passes it before the terminals of port B, not in the ENI's order.
                "order.xml": (example.replace("<Port>C</Port>", "<Port>D</Port>"), ":"),
            }
            for name, (text, where) in cases.items():
                path = os.path.join(d, name)
                with open(path, "w") as f:
                    f.write(text)
                r = subprocess.run([slave, "--iface", "lo", "--eni", path], stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True, timeout=30)
                self.assertEqual(r.returncode, 2, (name, r.stderr))
                self.assertIn(path + where, r.stderr, name)
                self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)


if __name__ == "__main__":
    harness.main()
