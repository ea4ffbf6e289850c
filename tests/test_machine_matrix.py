#!/usr/bin/env python3
"""Every machine of data/machines against the demo and every real CL file, both methods
(issue 61's done-when): a run that exits 0 keeps every joint of its blocks within the machine's
velocity limits (gcode.tcp_joint_peaks, LinuxCNC with TCP on) and its axes within their ranges;
a run that refuses exits 1 with an error line and writes no program; nothing else.

    python3 tests/test_machine_matrix.py build/release/taxopt .

144 runs, about 25 s on 2 cores (ctest label slow: the sanitizer presets leave it out).
"""
import concurrent.futures
import json
import os
import subprocess
import sys
import tempfile

# The options the tests give each real file (tests/support.cpp real_flags).
PEENING_SKIPS = ["SATUTEST", "RECIPE", "AIR", "GLASS", "FEEDOVER", "SAVERE", "STANDOFF",
                 "SUBPROG", "SURFACE", "INITIAL", "REWIND"]


def real_flags(name):
    flags = []
    if name in ("amorim-interface-glue.apt", "amorim-wall-holes.apt"):
        flags += ["--skip-record", "CUTCOM"]
    if name.startswith("peening-"):
        for word in PEENING_SKIPS:
            flags += ["--skip-record", word]
        flags += ["--tool-number", "1", "--spindle-rpm", "1000"]
    if name.startswith("mech491-"):
        flags += ["--spindle-rpm", "1000", "--tool-number", "1"]
    return flags


def inputs(source, work):
    """The demo with its part, and every real file (the peening file's SPINDLE records made
    comments, as tests/support.cpp real_text does)."""
    out = {"demo": ["--in", f"{source}/data/demo/sine.cls", "--part", f"{source}/data/demo/sine.stl"]}
    real = f"{source}/tests/data/real"
    for name in sorted(os.listdir(real)):
        if not name.endswith((".apt", ".cls", ".ncl", ".aptsource")):
            continue
        path = f"{real}/{name}"
        if name.startswith("peening-"):
            with open(path, errors="replace") as f:
                lines = f.read().splitlines(True)
            path = f"{work}/{name}"
            with open(path, "w") as f:
                f.write("".join("$$ " + l if l.startswith("SPINDLE/") else l for l in lines))
        out[name] = ["--in", path] + real_flags(name)
    return out


def limit_of(limits, joint):
    axis = limits.get(joint, {})
    return axis.get("max_velocity_mm_s", axis.get("max_velocity_deg_s"))


def judge(run):
    """What is wrong with one run, or an empty list."""
    wrong = []
    if run["code"] not in (0, 1):
        return [f"exit {run['code']}: {run['err'][-300:]}"]
    if run["code"] == 1:
        if "error:" not in run["err"]:
            wrong.append("exit 1 without an error line")
        if os.path.exists(run["ngc"]):
            wrong.append("exit 1 left a program behind")
        return wrong
    with open(run["report"]) as f:
        report = json.load(f)
    peaks = (report.get("gcode") or {}).get("tcp_joint_peaks") or {}
    for joint, peak in peaks.items():
        limit = limit_of(report.get("axis_limits", {}), joint)
        if limit and peak["velocity_per_s"] > 1.001 * limit:
            wrong.append(f"joint {joint} at {peak['velocity_per_s']:.1f}/s against {limit} "
                         f"(G-code line {peak['velocity_line']})")
    for op in report.get("operations", []):
        if not (op.get("verification") or {}).get("within_axis_limits", True):
            wrong.append(f"operation {op['name']}: an axis outside its range")
    if report.get("problems"):
        wrong.append(f"exit 0 with problems: {report['problems'][:1]}")
    return wrong


def run_one(binary, source, work, machine, name, args, method):
    tag = f"{machine}.{name}.{method}"
    report, ngc = f"{work}/{tag}.json", f"{work}/{tag}.ngc"
    cmd = [binary] + args + ["--machine", f"{source}/data/machines/{machine}.toml",
                             "--method", method, "--feed-schedule", "-q",
                             "--report", report, "--gcode", ngc]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    return {"tag": tag, "machine": machine, "code": p.returncode, "err": p.stderr,
            "report": report, "ngc": ngc}


def main():
    binary, source = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    machines = sorted(m[:-5] for m in os.listdir(f"{source}/data/machines") if m.endswith(".toml"))
    failures, posted = [], {m: 0 for m in machines}
    with tempfile.TemporaryDirectory() as work:
        cases = inputs(source, work)
        jobs = [(m, n, a, meth) for m in machines for n, a in cases.items()
                for meth in ("paper", "global")]
        with concurrent.futures.ThreadPoolExecutor(2) as pool:
            runs = pool.map(lambda j: run_one(binary, source, work, *j), jobs)
            for run in runs:
                wrong = judge(run)
                posted[run["machine"]] += run["code"] == 0
                print(f"{run['tag']:70s} exit {run['code']}  {'; '.join(wrong) or 'ok'}")
                failures += [f"{run['tag']}: {w}" for w in wrong]
    for machine, count in posted.items():
        if count == 0:
            failures.append(f"{machine}: no input posts (the matrix checks nothing there)")
    print(f"{len(jobs)} runs, {sum(posted.values())} posted, {len(failures)} failures")
    for f in failures:
        print("FAIL", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
