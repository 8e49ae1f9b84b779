"""No message is built in a fixed char array: a %s (a path, a name, an abort text) printed with snprintf into
one is cut when it is longer than the array (ecatctl once said `ecatctl: /tmp/.../bad.bin: chec`). Messages
use util::strprintf (util/strfmt.hpp), which makes a std::string of the length the text needs. Numbers of a
bounded width (snprintf "0x%08X" into char[16]) are not messages and are left alone.

Usage: message_buffers.py SOURCE_DIR; exits 1 and names file and line of each such snprintf."""
import os
import re
import sys

# snprintf(NAME, sizeof NAME, "format", ...) or snprintf(NAME, sizeof(NAME), ...) with a string conversion.
CALL = re.compile(r"\bsnprintf\(\s*(\w+)\s*,\s*sizeof\s*\(?\s*\1\s*\)?\s*,\s*((?:\"(?:[^\"\\]|\\.)*\"\s*)+)", re.S)
STRING_CONVERSION = re.compile(r"%[-+ #0]*(\d+|\*)?(\.(\d+|\*))?s")
SKIP_DIRS = {".git", "build"}


def problems(root):
    found = []
    for top, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.startswith("build")]
        for name in files:
            if not name.endswith((".cpp", ".hpp", ".h", ".cc")):
                continue
            path = os.path.join(top, name)
            with open(path, errors="replace") as f:
                text = f.read()
            for m in CALL.finditer(text):
                if STRING_CONVERSION.search(m.group(2)):
                    line = text.count("\n", 0, m.start()) + 1
                    found.append(f"{os.path.relpath(path, root)}:{line}: snprintf of a string into the fixed "
                                 f"array '{m.group(1)}': build the message with util::strprintf")
    return found


def main():
    root = sys.argv[1]
    # The check must see what it looks for (a broken pattern would pass everything).
    sample = 'char b[96];\nstd::snprintf(b, sizeof b, "%s: checksum", path.c_str());\n'
    assert CALL.search(sample) and STRING_CONVERSION.search(CALL.search(sample).group(2)), "pattern broken"
    assert not STRING_CONVERSION.search('"0x%08X"'), "pattern broken"
    found = problems(root)
    for p in found:
        print(p)
    print(f"{len(found)} message(s) built in fixed char arrays")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
