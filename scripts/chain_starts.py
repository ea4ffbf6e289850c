#!/usr/bin/python3
"""How hard LinuxCNC started each chain of feed blocks of a tcp program: measured against the
planner model at the full and at half the block's acceleration (measured on LinuxCNC's motion controller, tests/controller).

    chain_starts.py PROGRAM.ngc SAMPLES.txt [--accel 300,300,300,300,300]
                    [--velocity 20,20,20,30,30]

SAMPLES is what scripts/linuxcnc_controller.py --samples FILE recorded for PROGRAM (the
commanded axes X Y Z A C and the program line every 1 ms servo period). For every feed block
that starts a chain from rest (after a rapid, a dwell or a stop) and goes on into another
feed block, and whose motion lasts at least 60 ms, it takes the axis that sets the block's
acceleration and compares the peak of its acceleration over the block's first 30 ms
(central second differences over 10 periods, as linuxcnc_controller.py filters) with the same
filter applied to a ramp from rest at the full path acceleration (every axis within --accel,
units per s^2) and at half of it. It prints one line per block and, per kind (the block
turns A or C, the next one does), the range of measured / model. LinuxCNC (tp.c) blends two
feed blocks of which one turns a rotary axis parabolically and runs a block so blended at
half its acceleration; taxopt's report models that (GcodeProgram::tcp_joint_peaks).
"""
import argparse
import collections
import re
import sys

PERIOD_S, WINDOW = 0.001, 10


def blocks_of(path):
    """(line, kind, from, to, F) of every block that moves or stops the chain."""
    pos, motion, feed, out = [0.0] * 5, None, 0.0, []
    for n, text in enumerate(open(path).read().split("\n"), 1):
        s = text.split("(")[0].strip().upper()
        if not s:
            continue
        if re.match(r"(G4\b|M0\b|M1\b|M428|M429|G43|G49|G53)", s):
            out.append((n, "stop", None, None, 0.0))
            if s.startswith("G53"):
                continue
        m = re.match(r"G([01])\b", s)
        if m:
            motion = int(m.group(1))
        f = re.search(r"F([0-9.]+)", s)
        if f:
            feed = float(f.group(1))
        words = dict((k, float(v)) for k, v in re.findall(r"([XYZAC])(-?[0-9.]+)", s))
        if not words or motion is None:
            continue
        new = [words.get(k, pos[i]) for i, k in enumerate("XYZAC")]
        out.append((n, "G%d" % motion, pos, new, feed))
        pos = new
    return out


def ramp_peak(u_acc, u_vel, distance):
    """The filtered peak acceleration of an axis moving `distance` over a block that starts
    from rest at path acceleration u_acc (1/s^2) up to u_vel (1/s), over its first 30 ms."""
    t_up = u_vel / u_acc

    def u(t):
        if t <= 0.0:
            return 0.0
        if t < t_up:
            return 0.5 * u_acc * t * t
        return 0.5 * u_acc * t_up * t_up + u_vel * (t - t_up)
    w = WINDOW * PERIOD_S
    return max(abs(u(k * PERIOD_S + w) - 2 * u(k * PERIOD_S) + u(k * PERIOD_S - w)) / w ** 2
               for k in range(31)) * distance


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("program")
    ap.add_argument("samples")
    ap.add_argument("--accel", default="300,300,300,300,300")
    ap.add_argument("--velocity", default="20,20,20,30,30")
    args = ap.parse_args()
    lim_a = [float(x) for x in args.accel.split(",")]
    lim_v = [float(x) for x in args.velocity.split(",")]
    rows = []
    for text in open(args.samples):
        w = text.split()
        if len(w) == 12:
            rows.append([float(x) for x in w[1:11]] + [int(w[11])])
    first_of = {}
    for i, r in enumerate(rows):
        first_of.setdefault(r[10], i)
    blocks = blocks_of(args.program)
    kinds = collections.defaultdict(list)
    for k, (n, kind, a, b, feed) in enumerate(blocks):
        if kind != "G1" or k == 0 or blocks[k - 1][1] == "G1":
            continue
        if k + 1 >= len(blocks) or blocks[k + 1][1] != "G1" or n not in first_of:
            continue
        d = [abs(b[j] - a[j]) for j in range(5)]
        if max(d) < 1e-9:
            continue
        tip = (d[0] ** 2 + d[1] ** 2 + d[2] ** 2) ** 0.5
        u_acc = min(lim_a[j] / d[j] for j in range(5) if d[j] > 1e-9)
        u_vel = min(lim_v[j] / d[j] for j in range(5) if d[j] > 1e-9)
        if feed > 0.0:
            u_vel = min(u_vel, feed / 60.0 / (tip if tip > 1e-9 else (d[3] ** 2 + d[4] ** 2) ** 0.5))
        if 1.0 / u_vel < 0.06:
            continue  # too short to judge its start apart from its end
        axis = max(range(5), key=lambda j: d[j] / lim_a[j])
        nxt = blocks[k + 1]
        turns = d[3] > 1e-9 or d[4] > 1e-9
        next_turns = abs(nxt[3][3] - nxt[2][3]) > 1e-9 or abs(nxt[3][4] - nxt[2][4]) > 1e-9
        i0, c, w = first_of[n], 5 + axis, WINDOW
        if i0 < w or i0 + 30 + w >= len(rows):
            continue
        measured = max(abs(rows[i + w][c] - 2 * rows[i][c] + rows[i - w][c]) / (w * PERIOD_S) ** 2
                       for i in range(i0, i0 + 31))
        full = ramp_peak(u_acc, u_vel, d[axis])
        half = ramp_peak(0.5 * u_acc, u_vel, d[axis])
        kinds[(turns, next_turns)].append((measured / full, measured / half))
        print("line %d (turns A/C %s, the next %s), axis %s: measured %.2f, model at full %.2f, "
              "at half %.2f" % (n, turns, next_turns, "XYZAC"[axis], measured, full, half))
    for (turns, next_turns), r in sorted(kinds.items()):
        print("turns A/C %s, the next %s: %d blocks, measured / full %.3f .. %.3f, "
              "measured / half %.3f .. %.3f"
              % (turns, next_turns, len(r), min(x[0] for x in r), max(x[0] for x in r),
                 min(x[1] for x in r), max(x[1] for x in r)))
    return 0 if kinds else 1


if __name__ == "__main__":
    sys.exit(main())
