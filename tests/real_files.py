"""The real CL files of tests/data/real with the options the suite runs them with (as
tests/support.cpp's real_flags and real_text give them to the Catch tests), for the Python
tests: the machine matrix and LinuxCNC's controller."""
import os

# CATIA's peening file: its own records, which move nothing, skipped.
PEENING_SKIPS = ["SATUTEST", "RECIPE", "AIR", "GLASS", "FEEDOVER", "SAVERE",
                 "STANDOFF", "SUBPROG", "SURFACE", "INITIAL", "REWIND"]


def real_flags(name):
    """SOLIDWORKS CAM's compensation records skipped; the NX files name no spindle speed or
    tool (the production NX post for the Haas wrote T0 M06 and S1000 M03); CATIA's peening
    file its skips, a tool and a speed."""
    flags = []
    if name in ("amorim-interface-glue.apt", "amorim-wall-holes.apt"):
        flags += ["--skip-record", "CUTCOM"]
    if name.startswith("peening-"):
        flags += [w for k in PEENING_SKIPS for w in ("--skip-record", k)]
        flags += ["--tool-number", "1", "--spindle-rpm", "1000"]
    if name.startswith("mech491-"):
        flags += ["--spindle-rpm", "1000", "--tool-number", "1"]
    return flags


def real_path(real_dir, name, work):
    """The file to read: the project's copy, or for the peening file a copy in `work` with its
    SPINDLE records made comments (line numbers kept)."""
    path = os.path.join(real_dir, name)
    if not name.startswith("peening-"):
        return path
    with open(path) as f:
        text = f.read().split("\n")
    path = os.path.join(work, name)
    with open(path, "w") as f:
        f.write("\n".join("$$ " + l if l.startswith("SPINDLE/") else l for l in text))
    return path
