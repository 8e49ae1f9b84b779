"""ecat-slave --esi FILE [--device SPEC] for every device of every example ESI in esi/examples (a new example, or a
new device in one, is covered without editing this file): ecatctl finds it with the identity and name the ESI
gives, it reaches OP with the process data of its default assignment and the exact working counter, its control
socket shows the process data, and ecat-conform --esi FILE against it reports no failure. Bad files and specs
are usage errors (exit 2) that name the file."""
import json
import os
import re
import struct
import subprocess
import tempfile
import time
import unittest
import xml.etree.ElementTree as ET

import harness

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLES = os.path.normpath(os.path.join(HERE, "..", "..", "esi", "examples"))
ROW = re.compile(r"^(\d+)\s+0x([0-9a-f]{4})\s+(\S+)\s+0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8}) 0x([0-9a-f]{8}) ?(.*)$",
                 re.M)
LAYOUT = re.compile(r"outputs: SM(\d+) 0x([0-9a-f]+), (\d+) bytes; inputs: SM(\d+) 0x([0-9a-f]+), (\d+) bytes")


def number(text):
    """An ESI number: #x hex or decimal."""
    t = text.strip()
    return int(t[2:], 16) if t.lower().startswith("#x") else int(t, 0)


def port_descriptor(physics):
    """ESC register 0x0007 as the ESI's Physics declares the ports (ETG.2000: one character per port, Y MII, K E-Bus,
    H MII with fast hot connect, a blank none; ESC datasheet: 2 bits a port, 11 MII, 10 EBUS, 00 not implemented);
    without Physics two MII ports."""
    code = {"Y": 3, "H": 3, "K": 2}
    return sum(code.get(c, 0) << (2 * p) for p, c in enumerate((physics or "YY")[:4]))


def pdo_bits(pdos, sm_of):
    """Bits of the PDOs assigned by default (those with an Sm attribute) to the SMs of each direction (a device
    may have several: SM2 and SM4 for outputs, ...)."""
    bits = {"out": 0, "in": 0}
    for kind, pdo in pdos:
        if pdo.get("Sm") is None:
            continue
        side = "out" if kind == "RxPdo" else "in"
        if sm_of.get(side) is not None and int(pdo.get("Sm")) not in sm_of["all_" + side]:
            continue
        for e in pdo.findall("Entry"):
            bits[side] += number(e.findtext("BitLen"))
    return bits


def example_devices():
    """(file, root, modules by ModuleIdent, device element, SM of each direction) for each device of each example."""
    for name in sorted(os.listdir(EXAMPLES)):
        if not name.endswith(".xml"):
            continue
        path = os.path.join(EXAMPLES, name)
        root = ET.parse(path).getroot()
        modules = {}
        for m in root.iter("Module"):
            t = m.find("Type")
            if t is not None and t.get("ModuleIdent"):
                modules[number(t.get("ModuleIdent"))] = m
        for dev in root.findall("Descriptions/Devices/Device"):
            sms = [sm_kind(s) for s in dev.findall("Sm")]
            sm_of = {"out": sms.index("Outputs") if "Outputs" in sms else None,
                     "in": sms.index("Inputs") if "Inputs" in sms else None,
                     "all_out": [n for n, kind in enumerate(sms) if kind == "Outputs"],
                     "all_in": [n for n, kind in enumerate(sms) if kind == "Inputs"]}
            yield path, root, modules, dev, sm_of


def sm_kind(sm):
    """An Sm's kind: its text, or, without one (a master's export: exported.xml), what its ControlByte makes it
    in the ESC (bits 0-1 10 mailbox, bits 2-3 01 the master writes)."""
    text = (sm.text or "").strip()
    if text or sm.get("ControlByte") is None:
        return text
    c = number(sm.get("ControlByte"))
    write = (c >> 2) & 3 == 1
    if c & 3 == 2:
        return "MBoxOut" if write else "MBoxIn"
    return "Outputs" if write else "Inputs"


def examples():
    """(file, spec, expected) for each device of each example: identity, name, process-data bytes."""
    out = []
    for path, root, modules, dev, sm_of in example_devices():
        vendor = number(root.findtext("Vendor/Id"))
        t = dev.find("Type")
        product, revision = number(t.get("ProductCode")), number(t.get("RevisionNo"))
        pdos = [(p.tag, p) for p in dev if p.tag in ("RxPdo", "TxPdo")]
        # A modular device: the default module of each slot brings its PDOs.
        for slot in dev.findall("Slots/Slot"):
            for ident in slot.findall("ModuleIdent"):
                if ident.get("Default") in ("1", "true") and number(ident.text) in modules:
                    m = modules[number(ident.text)]
                    pdos += [(p.tag, p) for p in m if p.tag in ("RxPdo", "TxPdo")]
        bits = pdo_bits(pdos, sm_of)
        sm_out = dev.findall("Sm")[sm_of["out"]] if sm_of["out"] is not None else None
        first_out = next((e for kind, p in pdos if kind == "RxPdo" and p.get("Sm") is not None
                          for e in p.findall("Entry") if number(e.findtext("Index")) != 0), None)
        out.append({"file": path, "spec": f"0x{product:08x}:0x{revision:08x}", "vendor": vendor,
                    "product": product, "revision": revision, "type": (t.text or "").strip(),
                    "out_bytes": (bits["out"] + 7) // 8, "in_bytes": (bits["in"] + 7) // 8,
                    "mailbox": dev.find("Mailbox") is not None, "physics": dev.get("Physics"),
                    "eeprom_data": dev.find("Eeprom/Data") is not None,
                    "out_sm_start": number(sm_out.get("StartAddress")) if sm_out is not None else None,
                    "out_sm_control": number(sm_out.get("ControlByte")) if sm_out is not None else None,
                    "first_output": None if first_out is None else
                    f"0x{number(first_out.findtext('Index')):04x}:{number(first_out.findtext('SubIndex'))}"})
    return out


# ecat-conform failures that remain, each with its reason (reported, issue 21): defects of the device served that
# belong to another part of the work. A failure not listed fails the test; a listed one that no longer fails fails
# it too, so the list cannot go stale. A key is an example file, or "file@SPEC" for one device of it; the value maps
# the check's name to its reason. Empty: every example passes ecat-conform.
KNOWN = {}


def known_failures(d):
    """The KNOWN entries of the example file of d and of its device."""
    name = os.path.basename(d["file"])
    return dict(KNOWN.get(name, {}), **KNOWN.get(f"{name}@{d['spec']}", {}))


class EsiDevices(unittest.TestCase):
    def serve(self, d, *extra):
        bus = harness.Bus()
        ctl = os.path.join(bus.sock_dir, f"ctl{os.getpid()}.sock")
        bus.slave_args = ["--esi", d["file"], "--device", d["spec"], "--control", ctl] + list(extra)
        return bus, ctl

    def check_found(self, bus, d):
        r = bus.ecatctl("scan")
        rows = ROW.findall(r.stdout)
        self.assertEqual(len(rows), 1, r.stdout)
        _pos, _station, _state, vendor, product, revision, _serial, name = rows[0]
        self.assertEqual(int(vendor, 16), d["vendor"], r.stdout)
        self.assertEqual(int(product, 16), d["product"], r.stdout)
        self.assertEqual(int(revision, 16), d["revision"], r.stdout)
        self.assertIn(d["type"], name + r.stdout, "the name from the ESI")
        # The ESC has the ports the ESI's Physics declares (0x0007).
        reg = bus.ecatctl("reg", "read", "0", "0x0007", "1").stdout.split()
        self.assertEqual(int(reg[1], 16), port_descriptor(d["physics"]), f"0x0007 for Physics {d['physics']!r}")

    def check_op(self, bus, d, ctl):
        if d["out_bytes"] + d["in_bytes"] == 0 and d["mailbox"]:
            # A mailbox and no process data (a gateway configured by CoE): ecatctl sets up the mailbox SMs from
            # the SII and steps to OP without any process data.
            r = bus.ecatctl("state", "0", "OP", check=False)
            self.assertEqual(r.returncode, 0, r.stdout + r.stderr + bus.slave_output())
            status = harness.control(ctl, "status")
            self.assertTrue(status.startswith("ok state OP"), status)
            return
        if d["out_bytes"] + d["in_bytes"] == 0:
            # No process data and no mailbox (a coupler): OP through the AL control alone, no LRW to count.
            bus.ecatctl("scan")  # station address 0x1001
            mm = harness.MiniMaster(bus)
            try:
                for state in (2, 4, 8):
                    mm.fpwr(0x1001, 0x0120, struct.pack("<H", state))
                    deadline = time.monotonic() + 5
                    while True:
                        al = struct.unpack("<H", mm.fprd(0x1001, 0x0130, 2))[0]
                        if al == state or al & 0x10 or time.monotonic() > deadline:
                            break
                        time.sleep(0.01)
                    self.assertEqual(al, state, f"AL status 0x{al:x}, code 0x{mm.al_code(0x1001):04x}")
            finally:
                mm.close()
            status = harness.control(ctl, "status")
            self.assertTrue(status.startswith("ok state OP"), status)
            return
        r = bus.ecatctl("pd", "0", "-n", "200", "--keep", check=False)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr + bus.slave_output())
        m = LAYOUT.search(r.stdout)
        self.assertIsNotNone(m, r.stdout)
        self.assertEqual(int(m.group(3)), d["out_bytes"], "output bytes of the default assignment\n" + r.stdout)
        self.assertEqual(int(m.group(6)), d["in_bytes"], "input bytes of the default assignment\n" + r.stdout)
        self.assertRegex(r.stdout, r"state: OP\b")
        status = harness.control(ctl, "status")
        self.assertTrue(status.startswith("ok state OP"), status)

    def test_every_example_device_is_found_reaches_op_and_conforms(self):
        devices = examples()
        self.assertGreater(len(devices), 0, EXAMPLES)
        conform = os.environ.get("ECAT_CONFORM")
        for d in devices:
            with self.subTest(file=os.path.basename(d["file"]), device=d["spec"]):
                bus, ctl = self.serve(d)
                with bus:
                    self.check_found(bus, d)
                    self.check_op(bus, d, ctl)
                    if conform and os.path.exists(conform):
                        out = os.path.join(bus.dir, "conform.json")
                        bus.ecatctl("state", "0", "INIT", check=False)
                        r = subprocess.run([conform, "--iface", bus.iface, "--esi", d["file"], "--json", out],
                                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=600)
                        with open(out) as f:
                            report = json.load(f)
                        failed = {t["id"]: t.get("message", "") for t in report["results"] if t["status"] == "FAIL"}
                        known = known_failures(d)
                        unexpected = {k: v for k, v in failed.items() if k not in known}
                        self.assertEqual(unexpected, {}, r.stdout[-4000:])
                        fixed = sorted(k for k in known if k not in failed)
                        self.assertEqual(fixed, [], "known failures that pass now: drop them from KNOWN")
                    self.assertTrue(bus.slave_alive(), bus.slave_output())

    def test_ecatctl_takes_a_line_of_every_example_device_through_the_states(self):
        """Every way ecatctl brings slaves up works for every kind of device on one line: with and without
        mailbox (a coupler, digital IO terminals), with an EEPROM image of its own, modular; a mailbox verb on
        a slave without mailbox says so."""
        # A device without port 1 (Physics "Y": an end device) can only end the line.
        devices = sorted(examples(), key=lambda d: not port_descriptor(d["physics"]) & 0x0C)
        self.assertTrue(all(port_descriptor(d["physics"]) & 0x0C for d in devices[:-1]), "one end device at most")
        with tempfile.TemporaryDirectory() as tmp:
            topo = os.path.join(tmp, "line.topo")
            with open(topo, "w") as f:
                for k, d in enumerate(devices):
                    f.write(f"device d{k} esi={d['file']} device={d['spec']}\n")
            with harness.Bus(slave_args=["--topology", topo]) as bus:
                def states():
                    rows = [ln.split() for ln in bus.ecatctl("states").stdout.splitlines() if ln.strip()]
                    return [r[1] for r in rows]

                for target in ("PREOP", "SAFEOP", "INIT", "SAFEOP", "PREOP", "INIT"):
                    r = bus.ecatctl("states", target, check=False)
                    self.assertEqual(r.returncode, 0, f"states {target}\n{r.stdout}{r.stderr}")
                    self.assertEqual(states(), [target] * len(devices), target)
                r = bus.ecatctl("states", "OP", check=False)  # without cyclic frames the SM watchdogs end it
                self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
                for k, d in enumerate(devices):
                    with self.subTest(device=k, file=os.path.basename(d["file"]), spec=d["spec"]):
                        bus.ecatctl("state", str(k), "INIT")
                        for target in ("PREOP", "SAFEOP"):
                            r = bus.ecatctl("state", str(k), target, check=False)
                            self.assertEqual(r.returncode, 0, f"state {k} {target}\n{r.stdout}{r.stderr}")
                        if not d["mailbox"]:
                            r = bus.ecatctl("upload", str(k), "0x1018", "1", check=False)
                            self.assertEqual(r.returncode, 6, r.stdout + r.stderr)
                            self.assertIn("has no mailbox", r.stderr)
                self.assertTrue(bus.slave_alive(), bus.slave_output())

    def test_outputs_on_the_register_space_follow_the_sm_and_the_watchdog(self):
        """A device whose output SM lies on the register space (a digital-output terminal: 0x0F00, device
        emulation, no controller): the outputs an LRW writes reach the device's outputs; when the master stops,
        the process-data watchdog that the SM's writes triggered expires (0x0440 bit 0 clears, ESC datasheet
        section II), the state stays OP and the outputs go to 0; the next writes bring them back."""
        devices = [d for d in examples() if d["out_sm_start"] is not None and d["out_sm_start"] < 0x1000]
        self.assertGreater(len(devices), 0, "an example with its outputs on 0x0F00")
        for d in devices:
            with self.subTest(file=os.path.basename(d["file"]), device=d["spec"]):
                bus, ctl = self.serve(d)
                with bus:
                    bus.ecatctl("scan")  # station address 0x1001
                    m = LAYOUT.search(bus.ecatctl("pd", "0", "-n", "1", "--state", "SAFEOP").stdout)
                    self.assertIsNotNone(m)
                    sm, start, size = int(m.group(1)), int(m.group(2), 16), int(m.group(3))
                    self.assertEqual(start, d["out_sm_start"])
                    mm = harness.MiniMaster(bus)
                    try:
                        # The outputs SM as the ESI declares it, one write FMMU onto it; only the outputs.
                        mm.fpwr(0x1001, 0x0800 + 8 * sm, struct.pack("<HHBBBB", start, size, d["out_sm_control"], 0,
                                                                      1, 0))
                        mm.fpwr(0x1001, 0x0600, struct.pack("<IHBBHBBBxxx", 0x10000, size, 0, 7, start, 0, 2, 1))
                        image = bytearray(size)
                        image[0] = 0xFF  # the first output entry sits at bit 0 of the image

                        def write(n):
                            for _ in range(n):
                                r = mm.txrx([(harness.LRW, 0x0000, 0x0001, bytes(image))])
                                if r is not None:
                                    self.assertEqual(r[0][1], 2)
                                time.sleep(0.001)

                        for state in (2, 4, 8):
                            mm.fpwr(0x1001, 0x0120, struct.pack("<H", state))
                            write(20)
                            self.assertEqual(struct.unpack("<H", mm.fprd(0x1001, 0x0130, 2))[0], state)

                        def output():
                            r = harness.control(ctl, f"get {d['first_output']}")
                            self.assertTrue(r.startswith("ok "), r)
                            return r.rsplit("=", 1)[1].strip()

                        write(50)
                        self.assertNotEqual(output(), "0")
                        self.assertEqual(struct.unpack("<H", mm.fprd(0x1001, 0x0440, 2))[0] & 1, 1)
                        div = struct.unpack("<H", mm.fprd(0x1001, 0x0400, 2))[0]
                        wd = struct.unpack("<H", mm.fprd(0x1001, 0x0420, 2))[0]
                        self.assertNotEqual(wd, 0)
                        time.sleep((div + 2) * 40e-9 * wd * 3 + 0.2)  # the master is gone
                        self.assertEqual(struct.unpack("<H", mm.fprd(0x1001, 0x0440, 2))[0] & 1, 0)
                        self.assertEqual(struct.unpack("<H", mm.fprd(0x1001, 0x0130, 2))[0], 8)
                        deadline = time.monotonic() + 5
                        while output() != "0" and time.monotonic() < deadline:
                            time.sleep(0.01)
                        self.assertEqual(output(), "0")
                        write(50)
                        self.assertNotEqual(output(), "0")
                    finally:
                        mm.close()
                    self.assertTrue(bus.slave_alive(), bus.slave_output())

    def test_every_sm_of_a_direction_carries_its_own_pdos(self):
        """A terminal with two output and two input SyncManagers (tests/esi/fixtures/several-sms.xml: RxPdo 0x1600
        on SM0, RxPdo 0x1800 on SM1, TxPdo 0x1A00 on SM2, TxPdo 0x1C00 on SM3): a master that configures all
        four as the SII says gets the outputs of both output SMs into the device and the inputs (which mirror
        them: same names and types) back through both input SMs; one that sets the second output SM up with
        another length is refused SAFEOP (0x001D); one that leaves the second SMs off (a master of one SM per
        direction) exchanges the first ones' PDOs only."""
        d = {"file": os.path.join(HERE, "..", "esi", "fixtures", "several-sms.xml"), "spec": "EXD2262"}
        bus, ctl = self.serve(d)
        with bus:
            bus.ecatctl("scan")  # station address 0x1001
            mm = harness.MiniMaster(bus)
            try:
                sms = [(0x1000, 2, 0x64), (0x1200, 2, 0x64), (0x1400, 2, 0x20), (0x1600, 2, 0x20)]

                def configure(count, sm1_length=2):
                    """The SMs and FMMUs as the SII gives them: all four, or (count 1) the first of each direction."""
                    fm = b""
                    for n, (start, length, control) in enumerate(sms):
                        used = count == 2 or n in (0, 2)
                        mm.fpwr(0x1001, 0x0800 + 8 * n, bytes(8))
                        if used:
                            length = sm1_length if n == 1 else length
                            mm.fpwr(0x1001, 0x0800 + 8 * n, struct.pack("<HHBBBB", start, length, control, 0, 1, 0))
                        fm += struct.pack("<IHBBHBBBxxx", 0x10000 + 2 * n, length, 0, 7, start, 0,
                                          2 if control == 0x64 else 1, 1 if used else 0)
                    mm.fpwr(0x1001, 0x0600, fm)

                def state(want):
                    mm.fpwr(0x1001, 0x0120, struct.pack("<H", want))
                    deadline = time.monotonic() + 5
                    while True:
                        al = struct.unpack("<H", mm.fprd(0x1001, 0x0130, 2))[0]
                        if (al & 0x0F) == want or al & 0x10 or time.monotonic() > deadline:
                            return al
                        time.sleep(0.01)

                def cycle(out, n):
                    r = None
                    for _ in range(n):
                        r = mm.txrx([(harness.LRW, 0x0000, 0x0001, out + bytes(4))]) or r
                        time.sleep(0.001)
                    return r

                def to_op(out):
                    for want in (4, 8):
                        mm.fpwr(0x1001, 0x0120, struct.pack("<H", want))
                        cycle(out, 20)
                        self.assertEqual(state(want), want, f"AL code 0x{mm.al_code(0x1001):04x}")
                    r = cycle(out, 20)
                    self.assertIsNotNone(r)
                    self.assertEqual(r[0][1], 3)  # read + write
                    return r[0][0][4:]

                self.assertEqual(state(2), 2)
                configure(2, sm1_length=1)
                self.assertEqual(state(4), 0x12)
                self.assertEqual(mm.al_code(0x1001), 0x001D)
                mm.fpwr(0x1001, 0x0120, struct.pack("<H", 0x12))  # acknowledge, back to PREOP
                self.assertEqual(state(2), 2)
                configure(2)
                out = bytes([0x34, 0x12, 0x56, 0x78])
                self.assertEqual(to_op(out), out, "the inputs of SM2 and SM3 mirror the outputs of SM0 and SM1")
                status = harness.control(ctl, "status")
                self.assertIn('0x7010:01 "Channel 2"=86', status)
                self.assertIn('0x7010:02 "Channel 2 extra"=120', status)
                self.assertEqual(state(2), 2)
                configure(1)
                self.assertEqual(to_op(bytes([0x78, 0x56, 0, 0]))[:2], bytes([0x78, 0x56]))
            finally:
                mm.close()
            self.assertTrue(bus.slave_alive(), bus.slave_output())

    def test_ecatctl_pd_maps_every_sm_of_a_direction(self):
        """The same terminal through the master library's process-data session (ecatctl pd, no mailbox: the layout
        from the SII alone): every SM with PDOs set up with an FMMU of its own, OP with the working counter 3
        (the ESC counts an LRW once per direction, not per FMMU), the outputs of both output SMs in the device
        and back through both input SMs."""
        d = {"file": os.path.join(HERE, "..", "esi", "fixtures", "several-sms.xml"), "spec": "EXD2262"}
        bus, ctl = self.serve(d)
        with bus:
            r = bus.ecatctl("pd", "0", "-n", "50", "--outputs", "0x34", "0x12", "0x56", "0x78", "--keep", check=False)
            self.assertEqual(r.returncode, 0, r.stdout + r.stderr + bus.slave_output())
            m = LAYOUT.search(r.stdout)
            self.assertIsNotNone(m, r.stdout)
            self.assertEqual((int(m.group(3)), int(m.group(6))), (4, 4), r.stdout)
            self.assertIn("SM0 0x1000 2 bytes outputs; SM1 0x1200 2 bytes outputs; SM2 0x1400 2 bytes inputs; "
                          "SM3 0x1600 2 bytes inputs;", r.stdout)
            self.assertRegex(r.stdout, r"wkc errors 0 \(expected wkc 3\)")
            self.assertIn("0x0000: 34 12 56 78", r.stdout, "the inputs of SM2 and SM3 mirror the outputs of SM0 and SM1")
            status = harness.control(ctl, "status")
            self.assertIn('0x7010:01 "Channel 2"=86', status)
            self.assertIn('0x7010:02 "Channel 2 extra"=120', status)
            self.assertTrue(bus.slave_alive(), bus.slave_output())

    def test_modular_devices_serve_the_modules_their_spec_chooses(self):
        """A modular device (Slots/Modules) with another module configuration than the default, chosen in the
        device spec (SPEC@MODULE,MODULE,...): slot n takes the module after its default in the list it offers. The
        master finds the process image of those modules and reaches OP with the exact working counter."""
        chosen = []
        for path, root, modules, dev, sm_of in example_devices():
            slots = dev.findall("Slots/Slot")
            if not slots:
                continue
            t = dev.find("Type")
            product, revision = number(t.get("ProductCode")), number(t.get("RevisionNo"))
            idents, defaults = [], []
            vendor = number(root.findtext("Vendor/Id"))
            for n, slot in enumerate(slots):
                offered = [number(i.text) for i in slot.findall("ModuleIdent")]
                # Or by class (Slot/ModuleClass, ETG.2000): the file's modules of a class the slot names, of the
                # file's vendor when the class gives one; no Default.
                classes = [(c.findtext("Class"), c.findtext("VendorId")) for c in slot.findall("ModuleClass")]
                offered += [i for i, m in modules.items()
                            if any(m.find("Type").get("ModuleClass") == c and (v is None or number(v) == vendor)
                                   for c, v in classes)]
                default = next((k for k, i in enumerate(slot.findall("ModuleIdent"))
                                if i.get("Default") in ("1", "true")), -1)
                idents.append(offered[(default + 1 + n) % len(offered)] if offered else None)
                defaults.append(offered[default] if default >= 0 else None)
            pdos = [(p.tag, p) for p in dev if p.tag in ("RxPdo", "TxPdo")]
            for i in idents:
                if i in modules:
                    pdos += [(p.tag, p) for p in modules[i] if p.tag in ("RxPdo", "TxPdo")]
            bits = pdo_bits(pdos, sm_of)
            spec = f"0x{product:08x}:0x{revision:08x}@" + ",".join("-" if i is None else f"0x{i:x}" for i in idents)
            chosen.append({"file": path, "spec": spec, "out_bytes": (bits["out"] + 7) // 8,
                           "in_bytes": (bits["in"] + 7) // 8, "modules": spec.split("@", 1)[1],
                           "defaults": ",".join("-" if i is None else f"0x{i:x}" for i in defaults),
                           "coe": dev.find("Mailbox/CoE") is not None})
        self.assertGreater(len(chosen), 0, "a modular example")
        conform = os.environ.get("ECAT_CONFORM")
        for d in chosen:
            with self.subTest(file=os.path.basename(d["file"]), device=d["spec"]):
                bus, ctl = self.serve(d)
                with bus:
                    self.check_op(bus, d, ctl)
                    if conform and os.path.exists(conform):
                        # ecat-conform judges the slave against its ESI with the modules the slave says it has
                        # (0xF050, Detected Module Ident List, ETG.5001.1), or those --modules names: no
                        # failure the file does not list either way. --modules overrides what the slave says:
                        # named as each slot's default, the default modules' PDO layout is not the slave's and
                        # the process-data tests fail (the judgement follows the modules; the test can fail).
                        # Without CoE the slave has no 0xF050 to say its modules: judged only as --modules says.
                        runs = [(d["modules"], None)] + ([(None, None)] if d["coe"] else []) + [(d["defaults"], "pd")]
                        for modules, group in runs:
                            out = os.path.join(bus.dir, "conform.json")
                            bus.ecatctl("state", "0", "INIT", check=False)
                            cmd = [conform, "--iface", bus.iface, "--esi", d["file"], "--json", out]
                            if group is not None:
                                cmd += ["--group", group]
                            if modules is not None:
                                cmd += ["--modules", modules]
                            r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                               timeout=600)
                            with open(out) as f:
                                report = json.load(f)
                            failed = {t["id"]: t.get("message", "") for t in report["results"]
                                      if t["status"] == "FAIL"}
                            if group is not None:
                                self.assertNotEqual(failed, {}, "judged against the default modules")
                                continue
                            self.assertNotIn("could not be read from 0xF050", r.stdout, "the slave says its modules")
                            known = known_failures(dict(d, spec=d["spec"].split("@")[0]))
                            unexpected = {k: v for k, v in failed.items() if k not in known}
                            self.assertEqual(unexpected, {}, (modules, r.stdout[-4000:]))
                            # The modules plugged in are the device's state (0xF050, ETG.5001.1), not an ESI
                            # default: no warning either.
                            warned = {t["id"]: t.get("message", "") for t in report["results"]
                                      if t["status"] == "WARN"}
                            self.assertEqual(warned, {}, (modules, r.stdout[-4000:]))
                    self.assertTrue(bus.slave_alive(), bus.slave_output())

    def test_several_units_of_an_example_have_serial_numbers_one_to_n(self):
        d = next(x for x in examples() if not x["mailbox"])
        bus, _ctl = self.serve(d, "--slaves", "3")
        with bus:
            rows = ROW.findall(bus.ecatctl("scan").stdout)
            self.assertEqual([int(r[6], 16) for r in rows], [1, 2, 3])
            self.assertTrue(all(int(r[4], 16) == d["product"] for r in rows))


class EsiErrors(unittest.TestCase):
    def run_slave(self, *args):
        return subprocess.run([os.environ["ECAT_SLAVE"], *args, "--write-esi", "-"], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, timeout=60)

    def test_a_file_with_several_devices_needs_a_spec_and_lists_them(self):
        multi = next(f for f in {d["file"] for d in examples()}
                     if sum(1 for x in examples() if x["file"] == f) > 1)
        r = self.run_slave("--esi", multi)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(os.path.basename(multi), r.stderr)
        for d in examples():
            if d["file"] == multi:
                self.assertIn(f"{d['product']:08x}".lower(), r.stderr.lower())

    def test_a_bad_spec_and_a_bad_file_are_usage_errors_naming_the_file(self):
        d = examples()[0]
        r = self.run_slave("--esi", d["file"], "--device", "0x12345678:0x1")
        self.assertEqual(r.returncode, 2, r.stderr)
        with tempfile.TemporaryDirectory() as tmp:
            bad = os.path.join(tmp, "bad.xml")
            with open(bad, "w") as f:
                f.write("<EtherCATInfo>\n  <Vendor>\n</EtherCATInfo>\n")
            r = self.run_slave("--esi", bad)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertIn("bad.xml", r.stderr)
            r = self.run_slave("--esi", os.path.join(tmp, "missing.xml"))
            self.assertEqual(r.returncode, 2, r.stderr)

    def test_a_line_of_a_device_without_port_1_is_a_usage_error(self):
        """--slaves N of a device whose Physics has no port 1 ("Y": an end device): no line to build (exit 2)."""
        end = next(d for d in examples() if not port_descriptor(d["physics"]) & 0x0C)
        with tempfile.TemporaryDirectory() as tmp:
            r = subprocess.run([os.environ["ECAT_SLAVE"], "--esi", end["file"], "--device", end["spec"], "--slaves",
                                "2", "--iface", "softecat-none0", "--state-dir", tmp], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, timeout=60)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("no port 1", r.stderr)
        self.assertIn(os.path.basename(end["file"]), r.stderr)

    def test_write_esi_and_write_sii_round_trip(self):
        with tempfile.TemporaryDirectory() as tmp:
            for d in examples():
                with self.subTest(file=os.path.basename(d["file"]), device=d["spec"]):
                    esi, esi2, sii, sii2 = (os.path.join(tmp, n) for n in ("back.xml", "back2.xml", "a.bin",
                                                                                 "b.bin"))
                    slave = os.environ["ECAT_SLAVE"]
                    subprocess.run([slave, "--esi", d["file"], "--device", d["spec"], "--write-esi", esi,
                                    "--write-sii", sii], check=True, timeout=60, stderr=subprocess.PIPE)
                    # The ESI written back describes the same device: its SII is the same, byte for byte (a
                    # device served from its own Eeprom/Data image gets that image written back), and it
                    # writes back the same ESI.
                    r = subprocess.run([slave, "--esi", esi, "--write-sii", sii2, "--write-esi", esi2],
                                       timeout=60, stderr=subprocess.PIPE, text=True)
                    self.assertEqual(r.returncode, 0, r.stderr)
                    with open(sii, "rb") as a, open(sii2, "rb") as b:
                        self.assertEqual(a.read(), b.read())
                    with open(esi, "rb") as a, open(esi2, "rb") as b:
                        self.assertEqual(a.read(), b.read())
                    if d["eeprom_data"]:
                        with open(esi, encoding="utf-8") as f:
                            self.assertIn("<Data>", f.read())


if __name__ == "__main__":
    harness.main()
