#!/usr/bin/env python3
"""The whole process and each stage of a run at growing sizes (issue 65's table).

The generated sine of the issue (`taxopt generate --surface sine --length 590 --mesh-step 0.75`)
at widths 50, 100, 200 and 400 mm (about 36k, 72k, 144k and 288k points), each run as a user
runs it (`taxopt --in big.cls --part big.stl --gcode out.nc -v`): wall time and peak memory of
the process (GNU time), the report's stage times, and the ratio of each to the size before it
(linear: 2.0). Prints a markdown table and the command that made it.

Run from the source folder after a release build:
    python3 bench/stage_table.py [--taxopt build/release/taxopt] [--widths 50,100,200,400]
        [--methods paper,global] [--runs 1]
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

STAGES = ["contacts", "optimise", "post", "verify"]


def run_once(taxopt, folder, method):
    report = os.path.join(folder, "report.json")
    cmd = ["/usr/bin/time", "-f", "TIME %e %M", taxopt, "--in", os.path.join(folder, "big.cls"),
           "--part", os.path.join(folder, "big.stl"), "--gcode", os.path.join(folder, "out.nc"),
           "--report", report, "--method", method]
    p = subprocess.run(cmd, capture_output=True, text=True)
    m = re.search(r"TIME ([0-9.]+) ([0-9]+)", p.stderr)
    if p.returncode not in (0, 1) or not m:
        sys.exit("run failed (exit %d): %s\n%s" % (p.returncode, " ".join(cmd), p.stderr[-2000:]))
    with open(report) as f:
        r = json.load(f)
    points = sum(op["points"] for op in r["operations"])
    out = {"whole": float(m.group(1)), "memory_mb": int(m.group(2)) / 1024.0, "points": points}
    out.update({s: sum(float(op["timings_s"][s]) for op in r["operations"]) for s in STAGES})
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--taxopt", default="build/release/taxopt")
    ap.add_argument("--widths", default="50,100,200,400")
    ap.add_argument("--methods", default="paper,global")
    ap.add_argument("--runs", type=int, default=1, help="runs per row (the median is shown)")
    a = ap.parse_args()
    taxopt = os.path.abspath(a.taxopt)
    print("Command: python3 bench/stage_table.py --widths %s --methods %s --runs %d" %
          (a.widths, a.methods, a.runs))
    print()
    print("| points | triangles | method | whole s | x | contacts s | optimise s | post s |"
          " verify s | peak MB |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    previous = {}
    with tempfile.TemporaryDirectory() as tmp:
        for width in [float(w) for w in a.widths.split(",")]:
            gen = [taxopt, "generate", "--surface", "sine", "--width", str(width), "--length",
                   "590", "--mesh-step", "0.75", "--out-cls", os.path.join(tmp, "big.cls"),
                   "--out-mesh", os.path.join(tmp, "big.stl")]
            subprocess.run(gen, check=True, capture_output=True)
            triangles = (os.path.getsize(os.path.join(tmp, "big.stl")) - 84) // 50
            for method in a.methods.split(","):
                runs = [run_once(taxopt, tmp, method) for _ in range(a.runs)]
                row = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
                ratio = ""
                if method in previous:
                    ratio = "%.2f" % (row["whole"] / previous[method]["whole"])
                previous[method] = row
                cells = ["%.2f" % row[s] for s in STAGES]
                print("| %d | %d | %s | %.2f | %s | %s | %.0f |" %
                      (row["points"], triangles, method, row["whole"], ratio, " | ".join(cells),
                       row["memory_mb"]))
                sys.stdout.flush()


if __name__ == "__main__":
    main()
