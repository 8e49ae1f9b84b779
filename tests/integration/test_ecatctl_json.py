"""ecatctl --json against a line of two soft drives, checked against the schema documented in
docs/ecatctl-json.md: the tables there are parsed, and every document must hold exactly the keys of its table,
each with the type given (optional keys may be missing). So the documentation and the program cannot drift
apart, and a key renamed in the code fails here."""
import json
import os
import re
import unittest

import harness

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DOC = os.path.join(REPO, "docs", "ecatctl-json.md")

TYPES = {
    "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
    "string": lambda v: isinstance(v, str),
    "boolean": lambda v: isinstance(v, bool),
    "array": lambda v: isinstance(v, list),
    "object": lambda v: isinstance(v, dict),
    "any": lambda v: v is not None,
    "null": lambda v: v is None,
}


def schemas():
    """{section title: {key path: (type alternatives, optional)}} from the doc's tables."""
    out, section = {}, None
    with open(DOC, encoding="utf-8") as f:
        for line in f:
            m = re.match(r"^## (.+)$", line)
            if m:
                section = m.group(1).strip()
                out[section] = {}
                continue
            m = re.match(r"^\| ([a-z_\[\].]+) \| ([a-z\\|]+) \| (.*) \|$", line.rstrip("\n"))
            if m and section and m.group(1) != "key":
                kinds = m.group(2).replace("\\|", "|").split("|")
                out[section][m.group(1)] = (kinds, "*optional*" in m.group(3))
    return out


class EcatctlJson(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.schemas = schemas()
        cls.state = harness.tempfile.mkdtemp(prefix="ecat-json-", dir=os.environ.get("ECAT_TEST_OUT"))
        cls.bus = harness.Bus(slave_args=["--slaves", "2", "--state-dir", cls.state]).__enter__()

    @classmethod
    def tearDownClass(cls):
        cls.bus.close()

    def check(self, section, doc, path=""):
        """Every key of doc under path is documented with its type; every required key is there."""
        table = self.schemas[section]
        self.assertIsInstance(doc, dict, path)
        prefix = path + "." if path else ""
        for key, value in doc.items():
            full = prefix + key
            self.assertIn(full, table, f"{section}: key {full} is not documented in docs/ecatctl-json.md")
            kinds, _ = table[full]
            self.assertTrue(any(TYPES[k](value) for k in kinds), f"{section}: {full} = {value!r} is not {kinds}")
            if isinstance(value, list):
                for item in value:
                    if isinstance(item, dict):
                        self.check(section, item, full + "[]")
            elif isinstance(value, dict):
                self.check(section, value, full)
        for key, (_, optional) in table.items():
            if optional or not key.startswith(prefix) or "." in key[len(prefix):]:
                continue
            self.assertIn(key[len(prefix):], doc, f"{section}: required key {key} missing")

    def run_json(self, *args):
        r = self.bus.ecatctl(*args, "--json")
        return json.loads(r.stdout)

    def test_every_documented_verb(self):
        self.assertEqual(set(self.schemas), {"scan", "slaves", "upload", "sdos", "diag", "pd", "pd --all"})
        scan = self.run_json("scan")
        self.check("scan", scan)
        self.assertEqual([s["position"] for s in scan["slaves"]], [0, 1])
        self.assertEqual([s["serial"] for s in scan["slaves"]], [1, 2])
        self.assertEqual(scan["slaves"][0]["name"], "MAXPOS")

        slaves = self.run_json("slaves")
        self.check("slaves", slaves)
        self.assertEqual(len(slaves["slaves"]), 2)
        one = self.run_json("slaves", "1")
        self.check("slaves", one)
        self.assertEqual([s["position"] for s in one["slaves"]], [1])

        up = self.run_json("upload", "0", "0x1018", "0", "-c")
        self.check("upload", up)
        self.assertEqual(up["index"], 0x1018)
        by_sub = {e["subindex"]: e["value"] for e in up["entries"]}
        self.assertEqual(by_sub[1], scan["slaves"][0]["vendor_id"])
        self.assertEqual(by_sub[2], scan["slaves"][0]["product_code"])
        name = self.run_json("upload", "0", "0x1008", "0")
        self.check("upload", name)
        self.assertEqual(name["entries"][0]["value"], "MAXPOS")
        typed = self.run_json("upload", "0", "0x1018", "1", "--type", "u32")
        self.check("upload", typed)
        self.assertEqual(typed["values"], [scan["slaves"][0]["vendor_id"]])

        sdos = self.run_json("sdos", "0")
        self.check("sdos", sdos)
        indices = [o["index"] for o in sdos["objects"]]
        self.assertEqual(indices, sorted(indices))
        self.assertIn(0x6041, indices)
        quiet = self.run_json("sdos", "0", "-q")
        self.check("sdos", quiet)
        self.assertNotIn("entries", quiet["objects"][0])

        diag = self.run_json("diag", "0")
        self.check("diag", diag)
        self.assertGreaterEqual(len(diag["messages"]), 1)

        pd = self.run_json("pd", "0", "-n", "100")
        self.check("pd", pd)
        self.assertEqual((pd["state"], pd["lost"], pd["wkc_errors"]), ("OP", 0, 0))
        self.assertIn(0x6041, [e["index"] for e in pd["inputs"]])
        self.assertIn(0x6040, [e["index"] for e in pd["outputs"]])

        line = self.run_json("pd", "--all", "-n", "100", "--dc")
        self.check("pd --all", line)
        self.assertEqual([s["state"] for s in line["slaves"]], ["OP", "OP"])
        self.assertEqual(line["expected_wkc"], sum(s["expected_wkc"] for s in line["slaves"]))


if __name__ == "__main__":
    unittest.main()
