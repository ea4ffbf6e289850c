#!/usr/bin/python3
"""taxopt's LinuxCNC programs on LinuxCNC's own motion controller (issue 36; ctest label
`controller`, run serially: one LinuxCNC per machine).

A generated sine part (5 passes of 20 mm), `--method paper --feed-schedule`, posted for the
LinuxCNC preset (data/machines/linuxcnc-xyzac-trt.toml: TCP with M428/M429) and the same
machine in machine mode, runs on the controller with a copy of LinuxCNC's sample xyzac-trt
configuration and a 50 mm tool (scripts/linuxcnc_controller.py). Asserted: the program runs to
its last line with no error (soft limits, joint following, interpreter); the commanded path
passes every programmed point within the blend tolerance the program sets (G64 P0.01) plus a
servo period's travel at 20 mm/s (0.02 mm). Measured and printed, not asserted (issue 36 items
3 and 6 stay open: the first runs showed joint Y at 23 mm/s and 330 mm/s^2 against 20 and 300
in TCP mode, Y and Z up to 20.2 mm/s and 360 mm/s^2 in machine mode, and the controller's time
10 to 30 % above the report's cycle): every joint's peak velocity and acceleration, with the
lines where they occur, and the controller's time against the report's.

    test_controller.py TAXOPT_EXE SOURCE_DIR
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile


def main():
    exe, src = sys.argv[1], sys.argv[2]
    work = tempfile.mkdtemp(prefix="taxopt-controller-test-")
    cls, stl = os.path.join(work, "g.cls"), os.path.join(work, "g.stl")
    subprocess.run([exe, "generate", "--width", "3", "--length", "20", "--out-cls", cls,
                    "--out-mesh", stl], check=True, capture_output=True)
    preset = os.path.join(src, "data/machines/linuxcnc-xyzac-trt.toml")
    machine_mode = os.path.join(work, "machine-mode.toml")
    with open(preset) as f, open(machine_mode, "w") as g:
        g.write(f.read().replace('mode = "tcp"', 'mode = "machine"'))
    failures = []
    for name, machine in (("tcp", preset), ("machine", machine_mode)):
        ngc, report = os.path.join(work, name + ".ngc"), os.path.join(work, name + ".json")
        r = subprocess.run([exe, "--in", cls, "--part", stl, "--machine", machine,
                            "--method", "paper", "--feed-schedule", "-q", "--gcode", ngc,
                            "--report", report], capture_output=True, text=True)
        if r.returncode != 0:
            failures.append("%s: taxopt exit %d: %s" % (name, r.returncode, r.stderr))
            continue
        out = os.path.join(work, name + "-controller.json")
        c = subprocess.run(["/usr/bin/python3", os.path.join(src, "scripts/linuxcnc_controller.py"),
                            "--ngc", ngc, "--points", "--json", out, "--timeout", "600"],
                           capture_output=True, text=True)
        if not os.path.exists(out):
            failures.append("%s: the controller run gave no summary: %s" % (name, c.stderr[-2000:]))
            continue
        s = json.load(open(out))
        after = json.load(open(report))["operations"][0]["after"]
        print("== %s mode" % name)
        print("controller: ran to end %s, %.2f s moving, points passed within %.4f mm / %.3f deg"
              % (s["ran_to_end"], s.get("move_s", 0), s.get("point_miss_mm", -1),
                 s.get("point_miss_deg", -1)))
        print("report: cycle %.2f s (feed %.2f, rapid %.2f) + table turns %.2f s"
              % (after["cycle_time_s"], after["feed_time_s"], after["rapid_time_s"],
                 after["table_turn_s"]))
        for j, p in sorted(s.get("joints", {}).items()):
            print("joint %s: velocity %.3f of %s (line %s), acceleration %.1f of %s (line %s); %s"
                  % (j, p["max_velocity"], p["limit_velocity"], p["velocity_line"],
                     p["max_accel"], p["limit_accel"], p["accel_line"], s["filter"]))
        if not s["ran_to_end"] or s["errors"]:
            failures.append("%s: did not run to its end: %s" % (name, s["errors"]))
        if s.get("last_line", 0) < s.get("program_lines", 1) - 2:
            failures.append("%s: stopped at line %s of %s" % (name, s.get("last_line"),
                                                               s.get("program_lines")))
        if not s.get("points") or s.get("point_miss_mm", 1e9) > 0.01 + 0.02:
            failures.append("%s: a point missed by %s mm" % (name, s.get("point_miss_mm")))
    for f in failures:
        print("FAILED: " + f)
    shutil.rmtree(work, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
