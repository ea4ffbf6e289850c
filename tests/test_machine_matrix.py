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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from real_files import real_flags, real_path  # noqa: E402


def inputs(source, work):
    """The demo with its part, and every real file with the suite's options (real_files.py)."""
    out = {"demo": ["--in", f"{source}/data/demo/sine.cls", "--part", f"{source}/data/demo/sine.stl"]}
    real = f"{source}/tests/data/real"
    for name in sorted(os.listdir(real)):
        if name.endswith((".apt", ".cls", ".ncl", ".aptsource")):
            out[name] = ["--in", real_path(real, name, work)] + real_flags(name)
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
