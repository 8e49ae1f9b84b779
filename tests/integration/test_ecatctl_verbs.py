"""The ecatctl verbs IgH `ethercat` and SOEM `slaveinfo` users expect, against the real ecat-slave on veth:
--version, slaves [-v], pdos, cstruct, xml, upload typed by SDO information (strings, REAL32/REAL64, complete
access per subindex) and pd decoded by PDO entry. Each checks real content: pdos and cstruct against a PDO
configuration written just before, cstruct compiled with a C compiler against a header declaring IgH's structs,
xml validated against the ETG schema kept in the repository."""
import os
import re
import shutil
import struct
import subprocess
import tempfile
import unittest

import harness

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCHEMA = os.path.join(REPO, "esi", "schema", "EtherCATInfo.xsd")

# IgH's application interface types as ecrt.h declares them (IgH EtherCAT Master 1.5/1.6, ecrt.h), written
# here so the test needs no IgH installation.
IGH_HEADER = r"""
#include <stddef.h>
#include <stdint.h>
typedef enum { EC_DIR_INVALID, EC_DIR_OUTPUT, EC_DIR_INPUT, EC_DIR_COUNT } ec_direction_t;
typedef enum { EC_WD_DEFAULT, EC_WD_ENABLE, EC_WD_DISABLE } ec_watchdog_mode_t;
typedef struct { uint16_t index; uint8_t subindex; uint8_t bit_length; } ec_pdo_entry_info_t;
typedef struct { uint16_t index; unsigned int n_entries; ec_pdo_entry_info_t const *entries; } ec_pdo_info_t;
typedef struct {
    uint8_t index;
    ec_direction_t dir;
    unsigned int n_pdos;
    ec_pdo_info_t const *pdos;
    ec_watchdog_mode_t watchdog_mode;
} ec_sync_info_t;
"""

# Walks slave_0_syncs as ecrt_slave_config_pdos() does and prints what it finds.
DUMP_MAIN = r"""
#include <stdio.h>
int main(void) {
    for (const ec_sync_info_t *s = slave_0_syncs; s->index != 0xff; ++s) {
        printf("sm %u %s %u %s\n", s->index, s->dir == EC_DIR_OUTPUT ? "out" : "in", s->n_pdos,
               s->watchdog_mode == EC_WD_ENABLE ? "wd" : "-");
        for (unsigned i = 0; i < s->n_pdos; ++i) {
            printf("pdo 0x%04x %u\n", s->pdos[i].index, s->pdos[i].n_entries);
            for (unsigned k = 0; k < s->pdos[i].n_entries; ++k)
                printf("entry 0x%04x:%02x %u\n", s->pdos[i].entries[k].index, s->pdos[i].entries[k].subindex,
                       s->pdos[i].entries[k].bit_length);
        }
    }
    return 0;
}
"""

# The configuration written before pdos/cstruct: SM2 = {0x1601} with two entries.
NEW_MAPPING = [(0x6040, 0, 16), (0x60FF, 0, 32)]


class EcatctlVerbs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.bus = harness.Bus().__enter__()
        try:
            cls.bus.ecatctl("upload", "0", "0x1000", "0")  # INIT -> mailbox from the SII -> PREOP
        except BaseException:
            cls.bus.close()
            raise

    @classmethod
    def tearDownClass(cls):
        cls.bus.close()

    def ctl(self, *args):
        return self.bus.ecatctl(*args).stdout

    def write_config(self):
        """SM2 := {0x1601}, 0x1601 := controlword, target velocity (written entry by entry, as IgH does)."""
        self.ctl("download", "0", "0x1C12", "0", "0", "--type", "u8")
        self.ctl("download", "0", "0x1601", "0", "0", "--type", "u8")
        for i, (idx, sub, bits) in enumerate(NEW_MAPPING, start=1):
            self.ctl("download", "0", "0x1601", str(i), hex(idx << 16 | sub << 8 | bits), "--type", "u32")
        self.ctl("download", "0", "0x1601", "0", str(len(NEW_MAPPING)), "--type", "u8")
        self.ctl("download", "0", "0x1C12", "1", "0x1601", "--type", "u16")
        self.ctl("download", "0", "0x1C12", "0", "1", "--type", "u8")

    def restore_config(self):
        self.ctl("download", "0", "0x1C12", "0", "0", "--type", "u8")
        self.ctl("download", "0", "0x1C12", "1", "0x1600", "--type", "u16")
        self.ctl("download", "0", "0x1C12", "0", "1", "--type", "u8")

    # -- version -------------------------------------------------------------------------------------
    def test_version(self):
        r = subprocess.run([self.bus.ecatctl_bin, "--version"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, timeout=30)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout.strip(), r"^ecatctl \d+\.\d+\.\d+")

    # -- slaves --------------------------------------------------------------------------------------
    def test_slaves_lists_the_slave_with_its_state_and_name(self):
        out = self.ctl("slaves")
        self.assertEqual(len(out.splitlines()), 1, out)
        self.assertRegex(out, r"^0\s+0x[0-9a-f]{4}\s+\d+:0\s+PREOP\s+\S")

    def test_slaves_selects_by_position_or_station_address(self):
        self.ctl("scan")  # station addresses 0x1001..
        self.assertRegex(self.ctl("slaves", "0"), r"^0\s+0x1001\s")
        self.assertRegex(self.ctl("slaves", "-s", "0x1001"), r"^0\s+0x1001\s")
        for args in (("slaves", "5"), ("slaves", "-s", "0x1234")):
            r = self.bus.ecatctl(*args, check=False)
            self.assertEqual(r.returncode, 5, args)
            self.assertIn("no slave", r.stderr)

    def test_slaves_verbose_shows_what_slaveinfo_shows(self):
        out = self.ctl("slaves", "-v")
        vendor = int(self.ctl("upload", "0", "0x1018", "1").split()[0], 16)
        product = int(self.ctl("upload", "0", "0x1018", "2").split()[0], 16)
        self.assertIn(f"Vendor 0x{vendor:08x}, product 0x{product:08x}", out)
        # Sizes of the default PDOs: the same as the SM2/SM3 sizes pdos shows from the SII.
        pdos = self.ctl("pdos", "-q")
        sm2 = int(re.search(r"SM2: PhysAddr 0x[0-9a-f]+, DefaultSize +(\d+)", pdos).group(1))
        sm3 = int(re.search(r"SM3: PhysAddr 0x[0-9a-f]+, DefaultSize +(\d+)", pdos).group(1))
        m = re.search(r"Output size: (\d+) bits \((\d+) bytes\), input size: (\d+) bits \((\d+) bytes\)", out)
        self.assertIsNotNone(m, out)
        self.assertEqual((int(m.group(2)), int(m.group(4))), (sm2, sm3))
        self.assertRegex(out, r"Ports: 0:\S*\+link\+comm")
        self.assertRegex(out, r"DC: (yes, (32|64)-bit system time; system time delay \d+ ns|no)")
        # The mailbox SMs as the slave's registers hold them in PREOP, and the same in the SII.
        sm0 = self.bus.ecatctl("reg", "read", "0", "0x0800", "8").stdout.split()[1:]
        start = int(sm0[1] + sm0[0], 16)
        length = int(sm0[3] + sm0[2], 16)
        self.assertRegex(out, rf"SM0 A:{start:04x} L: *{length} F:[0-9a-f]{{8}} Type:1")
        self.assertRegex(out, r"SM3 A:[0-9a-f]{4} L: *\d+ F:[0-9a-f]{8} Type:4")
        self.assertRegex(out, r"FMMU0 Ls:[0-9a-f]{8} Ll: *\d+ ")
        self.assertIn(f"Mailbox: out 0x{start:04x} {length} bytes", out)
        self.assertRegex(out, r"Mailbox protocols: .*CoE")
        self.assertRegex(out, r"CoE details: SDO, SDO information, .*\(0x[0-9a-f]{2}\)")

    # -- pdos and cstruct ----------------------------------------------------------------------------
    def test_pdos_shows_the_mapping_written_just_before(self):
        self.write_config()
        try:
            out = self.ctl("pdos")
        finally:
            self.restore_config()
        sm2 = out.split("SM2:")[1].split("SM3:")[0]
        self.assertEqual(re.findall(r"RxPDO 0x([0-9a-f]{4})", sm2), ["1601"], out)
        entries = re.findall(r"PDO entry 0x([0-9a-f]{4}):([0-9a-f]{2}), +(\d+) bit, \"([^\"]*)\"", sm2)
        self.assertEqual([(int(i, 16), int(s, 16), int(b)) for i, s, b, _ in entries], NEW_MAPPING)
        self.assertEqual(entries[0][3], "Controlword")
        self.assertTrue(entries[1][3], "entry without a name")
        # After the restore: 0x1600 again.
        self.assertEqual(re.findall(r"RxPDO 0x([0-9a-f]{4})", self.ctl("pdos").split("SM2:")[1].split("SM3:")[0]),
                         ["1600"])

    def test_cstruct_compiles_against_igh_structs_and_matches_the_mapping(self):
        cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
        if cc is None:
            self.skipTest("no C compiler")
        self.write_config()
        try:
            code = self.ctl("cstruct")
        finally:
            self.restore_config()
        d = tempfile.mkdtemp(prefix="ecatctl-cstruct-")
        try:
            with open(os.path.join(d, "ecrt_types.h"), "w") as f:
                f.write(IGH_HEADER)
            with open(os.path.join(d, "slave.c"), "w") as f:
                f.write('#include "ecrt_types.h"\n' + code + DUMP_MAIN)
            exe = os.path.join(d, "slave")
            r = subprocess.run([cc, "-std=c99", "-Wall", "-Werror", "-o", exe, os.path.join(d, "slave.c")],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stdout + "\n" + code)
            dump = subprocess.run([exe], stdout=subprocess.PIPE, text=True, timeout=30).stdout
        finally:
            shutil.rmtree(d, ignore_errors=True)
        sm2 = dump.split("sm 2 ")[1].split("sm 3 ")[0]
        self.assertTrue(sm2.startswith("out 1 "), dump)
        self.assertIn("pdo 0x1601 2\n", sm2)
        got = [(int(i, 16), int(s, 16), int(b)) for i, s, b in re.findall(r"entry 0x(\w+):(\w+) (\d+)", sm2)]
        self.assertEqual(got, NEW_MAPPING)
        self.assertRegex(dump, r"sm 0 out 0 ")
        self.assertRegex(dump, r"sm 1 in 0 ")
        self.assertRegex(dump, r"sm 3 in 1 ")
        self.assertIn("/* Master 0, Slave 0, ", code)

    # -- xml -----------------------------------------------------------------------------------------
    def test_xml_validates_and_describes_the_slave(self):
        d = tempfile.mkdtemp(prefix="ecatctl-xml-")
        try:
            path = os.path.join(d, "slave.xml")
            self.ctl("xml", "-o", path)
            with open(path) as f:
                xml = f.read()
            product = int(self.ctl("upload", "0", "0x1018", "2").split()[0], 16)
            self.assertIn(f'ProductCode="#x{product:08x}"', xml)
            self.assertRegex(xml, r'<RxPdo Sm="2">\s*<Index>#x1600</Index>')
            self.assertRegex(xml, r'<TxPdo Sm="3">\s*<Index>#x1a00</Index>')
            self.assertRegex(xml, r"<Object>\s*<Index>#x6040</Index>\s*<Name>Controlword</Name>")
            self.assertIn('<CoE SdoInfo="true"', xml)
            if shutil.which("xmllint") is None:
                self.skipTest("xmllint not installed (libxml2-utils)")
            if not os.path.exists(SCHEMA):
                self.skipTest(f"the ETG schema is not in the repository ({SCHEMA})")
            r = subprocess.run(["xmllint", "--noout", "--schema", SCHEMA, path], stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stdout[:3000])
        finally:
            shutil.rmtree(d, ignore_errors=True)

    # -- upload / download typed ---------------------------------------------------------------------
    def test_upload_takes_the_type_from_sdo_information(self):
        name = self.ctl("upload", "0", "0x1008", "0").strip()  # VISIBLE_STRING: text, no --type needed
        self.assertEqual(name, self.ctl("upload", "0", "0x1008", "0", "--type", "string").strip())
        self.assertRegex(name, r"^[ -~]+$")
        out = self.ctl("upload", "0", "0x1C12", "0", "--complete")
        self.assertEqual(out.splitlines()[0].split(" = ")[1], "0x01 (1)", out)
        self.assertRegex(out, r"(?m)^0x1c12:01 \S.* = 0x1600 \(5632\)$")
        # INTEGER32 is printed signed from its type.
        self.ctl("download", "0", "0x607A", "0", "-5", "--type", "i32")
        self.assertEqual(self.ctl("upload", "0", "0x607A", "0").strip(), "0xfffffffb (-5)")

    def test_real32_and_real64_both_ways(self):
        self.ctl("download", "0", "0x607A", "0", "1.5", "--type", "real32")
        self.assertEqual(self.ctl("upload", "0", "0x607A", "0", "--type", "u32").split()[0], "0x3fc00000")
        self.assertEqual(self.ctl("upload", "0", "0x607A", "0", "--type", "real32").strip(), "1.5")
        r = self.bus.ecatctl("download", "0", "0x607A", "0", "-2.25", "--type", "real64", check=False)
        self.assertEqual(r.returncode, 6, r.stderr)  # 8 bytes into a 4-byte entry: the slave refuses
        self.assertIn("0x0607001", r.stderr)
        self.ctl("download", "0", "0x607A", "0", "0", "--type", "i32")

    # -- pd ------------------------------------------------------------------------------------------
    def test_pd_prints_the_images_by_pdo_entry(self):
        out = self.ctl("pd", "0", "-n", "20", "--outputs", "0x06", "0x00")
        self.assertIn("outputs by entry:", out)
        self.assertRegex(out, r"(?m)^  0x6040:00 Controlword = 0x0006 \(6\)$")
        m = re.search(r"(?m)^  0x6041:00 \S.* = 0x([0-9a-f]{4}) \(\d+\)$", out)
        self.assertIsNotNone(m, out)
        first = re.search(r"inputs:\n0x0000: ([0-9a-f]{2}) ([0-9a-f]{2})", out)
        self.assertEqual(m.group(1), first.group(2) + first.group(1))  # statusword = input bytes 0-1
        self.assertRegex(out, r"(?m)^  0x6064:00 \S.* = 0x[0-9a-f]{8} \(-?\d+\)$")


if __name__ == "__main__":
    harness.main()
