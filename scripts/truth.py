#!/usr/bin/env python3
"""The truth harness: what the report claims against what the machine does with the program.

For each generated surface and mesh step, posts the same CL file and part with --method none,
paper and global, reads every program back through LinuxCNC's own interpreter (rs274, the
canonical moves), times each feed block as the controller takes it from the written words
(tip path / F under G94, the rotary distance over F where only A and C turn) and computes the
peak rotary acceleration of each program from those times; prints it beside what the report
says (the operation's before and after max_accel_deg_s2).

    python3 scripts/truth.py build/release/taxopt [--steps 0.25,0.5,1,2]
        [--surfaces sine,plane,bump,saddle]

Exit 1 when a method's timed peak is worse than its input's (a reported gain that is a loss on
the machine) or when the report's percentage differs from the timed one by more than
--tolerance percentage points (default 5).
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile


def canon_moves(rs274, ngc):
    """(kind, xyz, a, c, feed mm/min) of every STRAIGHT_* move rs274 reads in `ngc`."""
    with tempfile.NamedTemporaryFile("w", suffix=".tbl", delete=False) as tbl:
        tbl.write("T1 P1 D6 Z50 ;\n")
    clean = ngc + ".rs274.ngc"
    with open(ngc) as src, open(clean, "w") as dst:
        for line in src:
            if line.strip() not in ("M428", "M429"):  # the sample's TCP switch: not in rs274's set
                dst.write(line)
    # rs274 keeps its parameter file in the working directory and maps $HOME/.tool.mmap with
    # O_TRUNC: two concurrent runs (ctest -j, the other truth test, tests/support.cpp) truncate
    # each other's mapping and one fails. Each run gets its own folder and HOME.
    with tempfile.TemporaryDirectory() as home:
        out = subprocess.run([rs274, "-t", tbl.name, "-v", os.path.join(home, "rs274ngc.var"),
                              "-g", clean], capture_output=True, text=True, timeout=120,
                             cwd=home, env={**os.environ, "HOME": home})
    os.unlink(tbl.name)
    os.unlink(clean)
    if out.returncode != 0:
        raise RuntimeError(f"rs274 refused {ngc}: {out.stderr.strip()[:200]}")
    moves, rate = [], 0.0
    for line in out.stdout.splitlines():
        m = re.search(r"SET_FEED_RATE\(([-\d.eE]+)\)", line)
        if m:
            rate = float(m.group(1))
            continue
        if "DWELL(" in line:
            # The controller stops there (G4 P0 before and after LinuxCNC's joint-safe rapids):
            # the blocks on either side are no chain.
            moves.append(None)
            continue
        m = re.search(r"(STRAIGHT_FEED|STRAIGHT_TRAVERSE)\(([^)]*)\)", line)
        if not m:
            continue
        v = [float(t) for t in m.group(2).split(",")]
        moves.append((m.group(1) == "STRAIGHT_FEED", (v[0], v[1], v[2]), v[3], v[5], rate))
    return moves


def timed_peak_accel(moves):
    """Peak synthetic rotary acceleration (deg/s^2) of the feed chains, block times from the
    words: a_i = (w_i - w_{i-1}) / ((t_{i-1} + t_i) / 2), each chain from its first block; a
    rapid or a dwell (the controller at rest) ends a chain."""
    peak, prev, last = 0.0, None, None
    for move in moves:
        if move is None:
            prev = None
            continue
        feed, xyz, a, c, rate = move
        if feed and last is not None and rate > 0:
            lin = math.dist(xyz, last[0])
            rot = math.hypot(a - last[1], c - last[2])
            dt = (lin if lin > 1e-9 else rot) / (rate / 60.0)
            if dt > 0:
                om = ((a - last[1]) / dt, (c - last[2]) / dt)
                if prev is not None:
                    acc = [(om[k] - prev[0][k]) / (0.5 * (dt + prev[1])) for k in range(2)]
                    peak = max(peak, math.hypot(*acc))
                prev = (om, dt)
        else:
            prev = None
        last = (xyz, a, c)
    return peak


def run(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    return out.returncode, out.stderr


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("taxopt")
    ap.add_argument("--steps", default="0.25,0.5,1,2")
    ap.add_argument("--surfaces", default="sine")
    ap.add_argument("--methods", default="paper,global")
    ap.add_argument("--tolerance", type=float, default=5.0,
                    help="percentage points the report may differ from the timed program")
    ap.add_argument("--rs274", default="rs274")
    args = ap.parse_args()
    bad = 0
    print("| surface | mesh step mm | method | report before | report after | report % |"
          " timed before | timed after | timed % |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        for surface in args.surfaces.split(","):
            for step in args.steps.split(","):
                cls, stl = f"{d}/{surface}.cls", f"{d}/{surface}-{step}.stl"
                rc, err = run([args.taxopt, "generate", "--surface", surface, "--out-cls", cls,
                               "--out-mesh", stl, "--mesh-step", step])
                if rc != 0:
                    print(f"generate {surface} {step}: exit {rc}: {err.strip()[:200]}")
                    bad += 1
                    continue
                timed = {}
                for method in ["none"] + args.methods.split(","):
                    ngc, rep = f"{d}/{method}.ngc", f"{d}/{method}.json"
                    rc, err = run([args.taxopt, "--in", cls, "--part", stl, "--method", method,
                                   "--gcode", ngc, "--report", rep, "-q"]
                                  + (["--force"] if method == "none" else []))
                    if rc != 0 and not (method == "none" and rc == 1):
                        print(f"| {surface} | {step} | {method} | exit {rc}: "
                              f"{err.strip().splitlines()[-1][:120] if err.strip() else ''} |")
                        bad += 1
                        continue
                    timed[method] = timed_peak_accel(canon_moves(args.rs274, ngc))
                    if method == "none":
                        continue
                    op = json.load(open(rep))["operations"][0]
                    b, a = op["before"]["max_accel_deg_s2"], op["after"]["max_accel_deg_s2"]
                    rp = 100.0 * (a / b - 1.0) if b > 0 else 0.0
                    tb, ta = timed.get("none", float("nan")), timed[method]
                    tp = 100.0 * (ta / tb - 1.0) if tb > 0 else 0.0
                    print(f"| {surface} | {step} | {method} | {b:.1f} | {a:.1f} | {rp:+.1f} |"
                          f" {tb:.1f} | {ta:.1f} | {tp:+.1f} |")
                    if ta > tb * 1.001 or abs(rp - tp) > args.tolerance:
                        bad += 1
    print(f"{'ok' if bad == 0 else str(bad) + ' disagreements'}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
