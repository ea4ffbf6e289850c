#!/usr/bin/env python3
"""Checks a shared libtaxopt's export table against the public headers, both ways.

    python3 scripts/check_exports.py build/shared/libtaxopt.so include/taxopt

- every function and class that include/taxopt declares with TAXOPT_API is exported (a
  consumer linking it finds it);
- nothing of taxopt's that no public header declares is: the internals (the pipeline's
  stages, the reader, the writer, the controller models) stay inside the library.
Exit 1 naming what is wrong on either side.
"""
import pathlib
import re
import subprocess
import sys


def public_names(include_dir):
    """Names of the TAXOPT_API functions and classes of every public header."""
    functions, classes = set(), set()
    for header in pathlib.Path(include_dir).rglob("*.hpp"):
        for line in header.read_text().splitlines():
            m = re.match(r"^(?:class|struct) TAXOPT_API (\w+)", line)
            if m:
                classes.add(m.group(1))
                continue
            m = re.match(r"^TAXOPT_API .*?[\s*&](~?\w+)\(", line)
            if m:
                functions.add(m.group(1))
    return functions, classes


def defined_out_of_line(name, source_dir):
    """True when some source file defines a member of class `name`."""
    pattern = re.compile(r"\b" + re.escape(name) + r"::~?\w+\(")
    return any(pattern.search(f.read_text()) for f in pathlib.Path(source_dir).rglob("*.cpp"))


def exported(library):
    out = subprocess.run(["nm", "-D", "-C", "--defined-only", library], check=True,
                         capture_output=True, text=True).stdout
    symbols = []
    for line in out.splitlines():
        parts = line.split(" ", 2)
        if len(parts) == 3 and parts[1] in "TtWVBDRuw" and parts[2].startswith("taxopt::"):
            symbols.append(parts[2])
    return symbols


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    library, include_dir = sys.argv[1], sys.argv[2]
    source_dir = pathlib.Path(include_dir).parent.parent / "src"
    functions, classes = public_names(include_dir)
    symbols = exported(library)
    problems = []
    # Every public declaration exported.
    for name in sorted(functions):
        if not any(re.match(r"taxopt::" + re.escape(name) + r"(\[abi:\w+\])?\(", s) for s in symbols):
            problems.append(f"declared TAXOPT_API, not exported: taxopt::{name}")
    for name in sorted(classes):
        if not defined_out_of_line(name, source_dir):
            continue  # all inline (an exception type, an interface): nothing to export
        if not any(s.startswith(f"taxopt::{name}::") or s.endswith(f" for taxopt::{name}")
                   for s in symbols):
            problems.append(f"class declared TAXOPT_API, nothing of it exported: taxopt::{name}")
    # Nothing exported that no public header declares.
    for s in symbols:
        head = re.sub(r"\[abi:\w+\]", "", s.split("(", 1)[0])
        owner = head.split("::")
        if len(owner) >= 3 and owner[1] in classes:
            continue
        if len(owner) == 2 and owner[1] in functions:
            continue
        if s.startswith(("typeinfo", "vtable")):
            continue
        problems.append(f"exported though no public header declares it: {s}")
    for p in problems:
        print(p, file=sys.stderr)
    print(f"{len(symbols)} taxopt symbols exported; {len(functions)} functions and "
          f"{len(classes)} classes declared TAXOPT_API; {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
