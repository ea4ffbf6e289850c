#!/usr/bin/python3
"""Runs a G-code program on LinuxCNC's own motion controller, headless, and measures it.

The controller is LinuxCNC 2.9 (Debian package linuxcnc-uspace) with a copy of its sample
configuration `xyzac-trt` (or `xyzbc-trt`) made here: kinematics, limits and the M428/M429
remaps as shipped; the display is linuxcncrsh (its remote shell, port 5007), no vismach, pyvcp
or Tk tool-change dialog, and a tool table with tools 1-99 of one length. A HAL sampler on the
servo thread records every joint's and axis's commanded position and the program line each
servo period; halsampler writes them to a file.

    linuxcnc_controller.py --ngc PROGRAM [--kins xyzac|xyzbc|bridgemill] [--tool-length MM]
                           [--axis-accel-scale S] [--work-offset X,Y,Z] [--samples FILE]
                           [--json FILE]

`--work-offset X,Y,Z` (mm) sets G54 before the run (MDI `G10 L2 P1`), as a shop sets the
workpiece zero at the machine: the program's zero sits there in machine coordinates with the
rotary axes at home (taxopt's `--work-offset`). The points are measured with it.

`--axis-accel-scale S` multiplies every [AXIS_*] MAX_ACCELERATION of the copy by S (the
[JOINT_*] ones stay): the remedy taxopt's `tcp_joint_limit` warning gives.

prints (and writes with --json) a summary: whether the program ran to its end without an
error, the controller's errors, its time from the first move to the end, every joint's peak
velocity and acceleration (from the commanded positions, central differences over
`--window` servo periods: see `filter` in the summary) against the INI's MAX_VELOCITY and
MAX_ACCELERATION, and how far the axis path passed from every programmed point of the file
(`--points` FILE: one "x y z a c" per line, program units).

Facts this relies on (measured here): as root, rtapi_app needs RTAPI_UID naming a
fallback uid (65534); RTAPI_FIFO_PATH is the master's socket path (a file in a folder of our
own); HOME must be writable; one LinuxCNC runs per machine (/tmp/linuxcnc.lock).
"""
import argparse
import json
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

SAMPLE_ROOT = "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis"
SAMPLES = {
    "xyzac": (SAMPLE_ROOT + "/table-rotary-tilting", "xyzac-trt.ini", "ac"),
    "xyzbc": (SAMPLE_ROOT + "/table-rotary-tilting", "xyzbc-trt.ini", "bc"),
    # The head-head bridge mill (5axiskins, XYZBCWY, seven joints: W and a second Y beside
    # X Y Z B C); its pivot length is its GUI's 250 mm plus the tool length offset.
    "bridgemill": (SAMPLE_ROOT + "/bridgemill", "5axis.ini", "bc"),
}
# The bridge mill's pivot length without its GUI: as its 5axisgui.hal computes it (the GUI's
# pivot_len, 250 by default, plus motion.tooloffset.z) into 5axiskins.pivot-length.
BRIDGEMILL_PIVOT_HAL = """loadrt sum2 names=pivotsum
addf pivotsum servo-thread
setp pivotsum.in0 250
net :tool-len motion.tooloffset.z => pivotsum.in1
net :pivot-len pivotsum.out => 5axiskins.pivot-length
"""


def scaled_ini_lines(lines, axis_accel_scale):
    """The INI's lines with every [AXIS_*] MAX_ACCELERATION multiplied by axis_accel_scale."""
    out, section = [], ""
    for line in lines:
        s = line.strip()
        if s.startswith("["):
            section = s
        key = s.split("=")[0].strip() if "=" in s else ""
        if axis_accel_scale != 1.0 and section.startswith("[AXIS_") and key == "MAX_ACCELERATION":
            line = "MAX_ACCELERATION = %.10g" % (float(s.split("=", 1)[1]) * axis_accel_scale)
        out.append(line)
    return out


def make_config(work, kins, tool_length, axis_accel_scale=1.0):
    src, ini_name, _ = SAMPLES[kins]
    cfg = os.path.join(work, "cfg")
    os.makedirs(cfg)
    if os.path.isdir(os.path.join(src, "remap_subs")):
        shutil.copytree(os.path.join(src, "remap_subs"), os.path.join(cfg, "remap_subs"))
    out = []
    section = ""
    with open(os.path.join(src, ini_name)) as f:
        for line in scaled_ini_lines(f.read().split("\n"), axis_accel_scale):
            s = line.strip()
            if s.startswith("["):
                section = s
            key = s.split("=")[0].strip() if "=" in s else ""
            if section == "[DISPLAY]" and key == "DISPLAY":
                line = "DISPLAY = linuxcncrsh"
            elif section == "[DISPLAY]" and key in ("PYVCP", "OPEN_FILE", "TKPKG", "NGCGUI_FONT",
                                                    "NGCGUI_SUBFILE"):
                continue
            elif section == "[HAL]" and key in ("POSTGUI_HALFILE", "HALUI"):
                continue
            elif section == "[HALUI]":
                continue
            elif section == "[HAL]" and key == "HALFILE" and "basic_sim" in s:
                # The simulated machine (its servo thread), then our sampler on that thread.
                out.append("HALFILE = LIB:basic_sim.tcl -no_use_hal_manualtoolchange")
                line = "HALFILE = sampler.hal"
            elif section == "[HAL]" and key == "HALFILE" and "5axisgui" in s:
                line = "HALFILE = pivot.hal"  # the GUI's pins go, its pivot sum stays
            elif section == "[HAL]" and key == "HALCMD" and "-gui" in s:
                # The vismach window's pins go; the kinematics' nets stay.
                if "loadusr" in s:
                    continue
                words = [w for w in s.split("=", 1)[1].split() if "-gui." not in w]
                if len(words) < 3:
                    continue
                line = "HALCMD = " + " ".join(words)
            elif section == "[EMCIO]" and key == "TOOL_TABLE":
                line = "TOOL_TABLE = tool.tbl"
            elif section == "[RS274NGC]" and key == "PARAMETER_FILE":
                line = "PARAMETER_FILE = params.var"
            out.append(line)
    with open(os.path.join(cfg, "m.ini"), "w") as f:
        f.write("\n".join(out) + "\n")
    with open(os.path.join(cfg, "pivot.hal"), "w") as f:
        f.write(BRIDGEMILL_PIVOT_HAL)
    with open(os.path.join(cfg, "tool.tbl"), "w") as f:
        for t in range(1, 100):
            f.write("T%d P%d Z%g D6 ;\n" % (t, t, tool_length))
    joints = ["joint.%d.pos-cmd" % j for j in range(5)]
    letters = "xyzac" if kins == "xyzac" else "xyzbc"
    # The bridge mill's joints: 0-4 are X Y Z B C as in the others (5 W, 6 the second Y).
    axes = ["axis.%s.pos-cmd" % a for a in letters]
    with open(os.path.join(cfg, "sampler.hal"), "w") as f:
        f.write("loadrt sampler depth=16384 cfg=ffffffffffs\n")
        f.write("addf sampler.0 servo-thread\n")
        for i, pin in enumerate(joints + axes):
            f.write("net smp%d %s => sampler.0.pin.%d\n" % (i, pin, i))
        f.write("net smpline motion.program-line => sampler.0.pin.10\n")
    return cfg


class Shell:
    """linuxcncrsh's remote shell."""

    def __init__(self, proc):
        deadline = time.time() + 60
        while True:
            try:
                self.sock = socket.create_connection(("127.0.0.1", 5007), timeout=30)
                break
            except OSError:
                if proc.poll() is not None:
                    raise RuntimeError("LinuxCNC ended before its shell opened")
                if time.time() > deadline:
                    raise RuntimeError("linuxcncrsh did not open port 5007 within 60 s")
                time.sleep(0.5)
        self.f = self.sock.makefile("rw", newline="\n")

    def cmd(self, c):
        self.f.write(c + "\r\n")
        self.f.flush()
        return self.f.readline().strip()


def run(args):
    work = tempfile.mkdtemp(prefix="taxopt-lcnc-")
    os.chmod(work, 0o755)
    fifo = os.path.join(work, "fifo")
    home = os.path.join(work, "home")
    os.makedirs(fifo)
    os.makedirs(home)
    os.chmod(fifo, 0o777)
    os.chmod(home, 0o777)
    cfg = make_config(work, args.kins, args.tool_length, args.axis_accel_scale)
    ngc = os.path.join(cfg, "program.ngc")
    shutil.copy(args.ngc, ngc)
    env = dict(os.environ, RTAPI_FIFO_PATH=os.path.join(fifo, "rtapi"), HOME=home)
    if os.geteuid() == 0:
        env["RTAPI_UID"] = "65534"
    log_path = os.path.join(work, "linuxcnc.log")
    log = open(log_path, "w")
    proc = subprocess.Popen(["linuxcnc", "-r", "m.ini"], cwd=cfg, env=env, stdout=log,
                            stderr=subprocess.STDOUT, start_new_session=True)
    samples_path = args.samples or os.path.join(work, "samples.txt")
    sampler = None
    summary = {"ran_to_end": False, "errors": []}
    try:
        sh = Shell(proc)
        sampler = subprocess.Popen(["halsampler", "-t", samples_path], env=env,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for c in ("hello EMC taxopt 1.0", "set enable EMCTOO", "set echo off",
                  "set verbose on", "set estop off", "set machine on", "set mode manual",
                  "set home -1"):
            sh.cmd(c)
        time.sleep(1.0)
        if any(args.offset):
            sh.cmd("set mode mdi")
            sh.cmd("set mdi G10 L2 P1 X%.6f Y%.6f Z%.6f" % tuple(args.offset))
            time.sleep(0.5)
        sh.cmd("set mode auto")
        reply = sh.cmd("set open " + ngc)
        if "ACK" not in reply:
            summary["errors"].append("open: " + reply)
        lines = sum(1 for _ in open(ngc))
        t0 = time.time()
        sh.cmd("set run")
        last_line = 0
        while True:
            time.sleep(0.25)
            # The operator's messages (linuxcncrsh: "ERROR OK" when there is none): an error
            # the controller shows its operator, whatever the log says.
            err = sh.cmd("get error")
            if err and err.upper() not in ("ERROR OK", "ERROR") and "OK" not in err.split()[-1:]:
                summary["errors"].append("controller: " + err[:300])
            status = sh.cmd("get program_status")
            if "PAUSED" in status.upper():
                # A program stop (M0, M1): the operator presses cycle start.
                summary["resumed"] = summary.get("resumed", 0) + 1
                sh.cmd("set resume")
                continue
            line = sh.cmd("get program_line").split()
            if len(line) >= 2 and line[-1].lstrip("-").isdigit():
                last_line = max(last_line, int(line[-1]))
            if "IDLE" in status.upper() and time.time() - t0 > 1.0:
                break
            if time.time() - t0 > args.timeout:
                summary["errors"].append("timeout after %g s" % args.timeout)
                sh.cmd("set abort")
                break
        summary["wall_s"] = time.time() - t0
        summary["last_line"] = last_line
        summary["program_lines"] = lines
        time.sleep(0.5)
        for c in ("set machine off", "set estop on"):
            sh.cmd(c)
        try:
            sh.cmd("shutdown")
        except OSError:
            pass
    finally:
        if sampler:
            time.sleep(0.5)
            sampler.terminate()
            try:
                sampler.wait(timeout=10)
            except subprocess.TimeoutExpired:
                sampler.kill()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGTERM)
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
        log.close()
    with open(log_path) as f:
        text = f.read()
    for l in text.split("\n"):
        low = l.lower()
        if ("error" in low and "emctask" in low) or "exceeded" in low or "soft limit" in low or \
           "joint" in low and "following error" in low:
            summary["errors"].append(l.strip()[:300])
    summary["log"] = log_path
    analyse(samples_path, args, summary)
    summary["ran_to_end"] = not summary["errors"] and summary.get("end_line", 0) > 0
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    return summary


def ini_limits(kins):
    src, ini_name, _ = SAMPLES[kins]
    limits = {}
    section = ""
    with open(os.path.join(src, ini_name)) as f:
        for line in f:
            s = line.strip()
            if s.startswith("["):
                section = s[1:-1]
            elif section.startswith("JOINT_") and "=" in s:
                k, v = [x.strip() for x in s.split("=", 1)]
                j = int(section[6:])
                if k in ("MAX_VELOCITY", "MAX_ACCELERATION"):
                    limits.setdefault(j, {})[k] = float(v)
    return limits


def analyse(path, args, summary):
    rows = []
    with open(path) as f:
        for line in f:
            w = line.split()
            if len(w) != 12:
                continue
            rows.append([float(x) for x in w[1:11]] + [int(w[11]), int(w[0])])
    summary["samples"] = len(rows)
    # halsampler -t tags each row with its sample number: where its reader fell behind (the
    # machine busy with other work) the FIFO overran and numbers are missing. A window across
    # such a gap would difference positions a jump apart (a joint "at 417 mm/s" at line 0):
    # no velocity or acceleration is taken across one, and the times count the periods lost.
    tags = [r[11] for r in rows]
    summary["lost_samples"] = sum(max(0, tags[i] - tags[i - 1] - 1) for i in range(1, len(tags)))
    if not rows:
        summary["errors"].append("no samples recorded")
        return
    period = 0.001  # SERVO_PERIOD of the sample configurations: 1 ms
    moving = [i for i in range(1, len(rows)) if any(abs(rows[i][j] - rows[i - 1][j]) > 1e-9
                                                    for j in range(5))]
    if not moving:
        summary["errors"].append("nothing moved")
        return
    first, last = moving[0] - 1, moving[-1]
    summary["move_s"] = (tags[last] - tags[first]) * period
    # The controller's time per program line: the servo periods in which the commanded
    # joints moved, s (a program stop, a dwell or a tool change waits without moving and is
    # not the motion's time).
    line_s = {}
    for i in range(first + 1, last + 1):
        if any(abs(rows[i][j] - rows[i - 1][j]) > 1e-9 for j in range(5)):
            line_s[rows[i][10]] = line_s.get(rows[i][10], 0.0) + period * (tags[i] - tags[i - 1])
    summary["line_s"] = {str(k): v for k, v in sorted(line_s.items())}
    summary["end_line"] = max(r[10] for r in rows)
    # Velocities and accelerations of the commanded joints: differences over a window of
    # `w` servo periods (the controller's own trajectory is piecewise quadratic at 1 ms; a
    # window smooths the quantisation of the positions' printed digits).
    w = args.window
    limits = ini_limits(args.kins)
    peaks = {}
    for j in range(5):
        vmax = amax = 0.0
        vmax_at = amax_at = 0
        for i in range(first + w, last - w + 1):
            if tags[i + w] - tags[i - w] != 2 * w:
                continue  # a window across lost samples
            # Only the program's motion: line 0 is the controller before the program runs or
            # after it ends (its homing, which `set home -1` starts a second before the run;
            # under a loaded CI a joint "at 424/s" there, with no sample lost).
            if rows[i - w][10] <= 0 or rows[i + w][10] <= 0:
                continue
            v = (rows[i + w][j] - rows[i - w][j]) / (2 * w * period)
            a = (rows[i + w][j] - 2 * rows[i][j] + rows[i - w][j]) / ((w * period) ** 2)
            if abs(v) > vmax:
                vmax, vmax_at = abs(v), rows[i][10]
            if abs(a) > amax:
                amax, amax_at = abs(a), rows[i][10]
        lim = limits.get(j, {})
        peaks[str(j)] = {"max_velocity": vmax, "velocity_line": vmax_at,
                         "max_accel": amax, "accel_line": amax_at,
                         "limit_velocity": lim.get("MAX_VELOCITY"),
                         "limit_accel": lim.get("MAX_ACCELERATION")}
    summary["joints"] = peaks
    summary["filter"] = "central differences over %d servo periods (%g ms)" % (w, w * period * 1e3)
    if args.points:
        pts = points_of(args.ngc)
        # Each point against the whole axis path (x y z, the tool length offset taken off Z):
        # the nearest commanded position, and the rotaries there; the distance to the path
        # between that sample and its neighbours (a rapid at 200 mm/s moves 0.2 mm a servo
        # period, so a sample can lie 0.1 mm from a point the path passes through).
        import numpy as np
        path = np.array([[r[5], r[6], r[7] - args.tool_length, r[8], r[9]]
                         for r in rows[first:last + 1]])
        worst_mm = worst_deg = 0.0
        for p in pts:
            q = np.array(p[0:3]) + np.array(args.offset)
            d = np.linalg.norm(path[:, 0:3] - q, axis=1)
            i = int(np.argmin(d))
            near = float(d[i])
            for j in (i - 1, i + 1):
                if 0 <= j < len(path):
                    a, b = path[i, 0:3], path[j, 0:3]
                    ab = b - a
                    t = float(np.clip(np.dot(q - a, ab) / max(float(np.dot(ab, ab)), 1e-30),
                                      0.0, 1.0))
                    near = min(near, float(np.linalg.norm(a + t * ab - q)))
            worst_mm = max(worst_mm, near)
            # The rotaries where the path passes the point: of the samples as near (within
            # 0.05 mm), the one turned likest it (a table that turns by 90 deg with the tip
            # held passes the same place twice).
            close = d <= d[i] + 0.05
            turn = np.maximum(np.abs(path[close, 3] - p[3]), np.abs(path[close, 4] - p[4]))
            worst_deg = max(worst_deg, float(turn.min()))
        summary["points"] = len(pts)
        summary["point_miss_mm"] = worst_mm
        summary["point_miss_deg"] = worst_deg


def points_of(ngc):
    """The programmed points of a taxopt program, mm and deg: every G0/G1 block with all of X
    Y Z and the two rotary words (the retracts, table turns and positioning blocks give
    fewer)."""
    pts = []
    scale = 1.0  # mm per program unit: G20 programs are in inches, the controller's axes in mm
    with open(ngc) as f:
        for line in f:
            code = line.split("(")[0].split(";")[0].upper().split()
            if "G20" in code:
                scale = 25.4
            elif "G21" in code:
                scale = 1.0
            words = {w[0]: w[1:] for w in code if w and w[0] in "XYZABC"}
            if "G53" in code or not any(w in ("G0", "G1") for w in code):
                continue
            rot = [k for k in "ABC" if k in words]
            if all(k in words for k in "XYZ") and len(rot) == 2 and "C" in rot:
                pts.append([scale * float(words["X"]), scale * float(words["Y"]),
                            scale * float(words["Z"]), float(words[rot[0]]), float(words["C"])])
    return pts


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ngc", required=True)
    ap.add_argument("--kins", default="xyzac", choices=sorted(SAMPLES))
    ap.add_argument("--tool-length", type=float, default=50.0)
    ap.add_argument("--axis-accel-scale", type=float, default=1.0,
                    help="every [AXIS_*] MAX_ACCELERATION of the copy times this")
    ap.add_argument("--work-offset", default="0,0,0",
                    help="G54 in machine coordinates, mm: X,Y,Z")
    ap.add_argument("--samples")
    ap.add_argument("--points", action="store_true",
                    help="measure how far the axis path passes from the program's points")
    ap.add_argument("--json")
    ap.add_argument("--window", type=int, default=10)
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--keep", action="store_true")
    args = ap.parse_args()
    try:
        args.offset = [float(v) for v in args.work_offset.split(",")]
        if len(args.offset) != 3 or not all(math.isfinite(v) for v in args.offset):
            raise ValueError
    except ValueError:
        print("linuxcnc_controller: --work-offset takes X,Y,Z in mm", file=sys.stderr)
        return 2
    if not 0.0 < args.axis_accel_scale <= 1.0:
        print("linuxcnc_controller: --axis-accel-scale must be in (0, 1]", file=sys.stderr)
        return 2
    if os.path.exists("/tmp/linuxcnc.lock"):
        print("linuxcnc_controller: /tmp/linuxcnc.lock exists: another LinuxCNC runs",
              file=sys.stderr)
        return 2
    summary = run(args)
    text = json.dumps(summary, indent=1)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text)
    print(text)
    return 0 if summary["ran_to_end"] else 1


if __name__ == "__main__":
    sys.exit(main())
