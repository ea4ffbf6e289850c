#!/usr/bin/python3
"""taxopt's LinuxCNC programs on LinuxCNC's own motion controller (ctest label
`controller`, run serially: one LinuxCNC per machine).

A generated sine part (5 passes of 20 mm), `--method paper --feed-schedule`, posted for the
LinuxCNC preset (data/machines/linuxcnc-xyzac-trt.toml: TCP with M428/M429) in G94 and G93,
for the same machine in machine mode, for the B/C sample
(data/machines/linuxcnc-xyzbc-trt-sample.toml), and at the CL file's own feeds (no
`--feed-schedule`) for the A/C preset, runs on the controller with a copy of
LinuxCNC's sample xyzac-trt (or xyzbc-trt) configuration and a 50 mm tool (scripts/linuxcnc_controller.py; the run passes
`--gauge-length 50` so that the report's program time takes the same tool length for its
retracts). Asserted, for each program:
- it runs to its last line with no error (soft limits, joint following, interpreter);
- the commanded path passes every programmed point within the blend tolerance the program
  sets (G64 P0.01) plus a servo period's travel at 20 mm/s (0.02 mm);
- every joint's velocity stays within its MAX_VELOCITY (filter: central differences of the
  commanded joint positions over 10 servo periods, 10 ms) with 1.5 % for the controller's
  own blends (two G0 blocks of a linearised rapid overlap in time as LinuxCNC blends them:
  20.2 mm/s against 20 measured in machine mode);
- the controller's time from the end of the first retract to the end is within 3 % of the
  report's `gcode.time_s`.
- every joint's acceleration stays within its MAX_ACCELERATION (the same filter, 0.5 %), except
  where the report predicts it (gcode.tcp_joint_peaks covers it within 2 %) and warns of it
  (tcp_joint_limit): in tcp mode LinuxCNC limits the accelerations
  of the program's axes, not of the joints, and no F word changes how hard it accelerates.
- the warning's remedy works: the sample configuration with every [AXIS_*] MAX_ACCELERATION at
  the share the report of the first program gives (gcode.tcp_axis_accel_scale), imported by
  `taxopt machine --from-linuxcnc-ini` (which then reads the joints' own limits), posts the
  same part with no tcp_joint_limit warning, and on the controller so configured every joint
  stays within its MAX_ACCELERATION (0.5 %).

By default (ctest label `controller`) the A/C tcp G94 program, the same part on LinuxCNC's
head-head bridge mill (its 5axiskins sample, data/machines/linuxcnc-5axis-bridgemill.toml:
the head swings the tip about its pivot, 250 mm plus the tool's 50) and the remedy run (about 5
minutes); `--set sine-more` (label `long`, TAXOPT_LONG=1) the machine-mode, G93, B/C and
programmed-feed programs (about 7 minutes).

With `--set real` (ctest label `long`, run when TAXOPT_LONG=1) the same runs
and checks for the real CL files that fit the sample machine's travel (Creo's profilfraesen,
CATIA's peening file) and the bundled demo (data/demo), tcp mode, each on both samples (A/C
and B/C), and the demo on the A/C sample with its axes' accelerations at its report's share,
`--method paper --feed-schedule` (about 95 minutes); `--set demo` the demo alone. The others
leave its travel and taxopt refuses them: NX's variable-axis ball mill at its approach (the
spindle at Z 132 mm against 120 with the 50 mm tool; written anyway, the controller stopped
there), the other NX file and Amorim's at their points.

With `--set index` (ctest label `long`) real files with index moves, each at the work offset
that puts it within the sample's travel (the controller's G54 set to it before the run): NX's
multi-operation file cut to six operations that turn between them, on the bridge mill;
Amorim's wall with holes (a 90 deg turn inside an operation) on the bridge mill;
and the demo on the bridge mill (about 60 minutes).

Each program prints a row of the table in docs/feed-schedule.md "On LinuxCNC's controller".

    test_controller.py TAXOPT_EXE SOURCE_DIR [--set sine|sine-more|real|demo|index]
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from real_files import real_flags, real_path  # noqa: E402

# The real files that fit the samples, with the suite's options (tests/real_files.py) and tool
# lengths of 50 mm in the file's unit.
REAL = [(name, ["--gauge-length", "50"] + real_flags(name))
        for name in ("creopost-profilfraesen.ncl", "peening-catia-multax.aptsource")]


def index_cases(src, work, demo):
    """Real files with index moves on LinuxCNC's samples, each with the work offset that puts
    it within the travel (as a shop sets G54), and the demo on the head-head bridge mill: NX's
    multi-operation file cut to six operations that turn the table or head between them (B or
    A -82.875 to 82.875 and C by 90 deg; the file is CC0-1.0, the slice made here from the
    project's copy) on the bridge mill (on the A/C sample no work offset fits it: tilted 83 deg
    at C 90 and C -90 its operations need the spindle above Z's travel at X offsets that
    exclude each other; at Z -100 the controller stopped at the first, line 250, "would exceed
    joint 2's positive limit", and taxopt refuses it there), and Amorim's wall with holes,
    which turns its table by 90 deg inside an operation (about 30 minutes), on the bridge
    mill."""
    bridgemill = os.path.join(src, "data/machines/linuxcnc-5axis-bridgemill.toml")
    preset = os.path.join(src, "data/machines/linuxcnc-xyzac-trt.toml")
    real = os.path.join(src, "tests", "data", "real")
    lines = open(os.path.join(real, "mech491-project2-multiop.cls")).read().split("\n")
    ops, start = {}, None
    for k, l in enumerate(lines):
        if l.startswith("TOOL PATH/"):
            start = k
        elif l.startswith("END-OF-PATH") and start is not None:
            ops[lines[start].split("/")[1].split(",")[0]] = lines[start:k + 1]
    keep = ["POCKETING_SLOT1", "POCKETING_SLOT2"] + [
        "VARIABLE_AXIS_GUIDING_CURVES_1" + "_COPY" * n for n in range(1, 5)]
    sliced = os.path.join(work, "mech491-multiop-index-slice.cls")
    with open(sliced, "w") as f:
        f.write("\n".join(sum((ops[n] for n in keep), [])) + "\n")
    nx = ["--in", sliced, "--gauge-length", "1.9685", "--spindle-rpm", "1000", "--tool-number",
          "1", "--work-offset", "0,0,-100"]
    return [
        ("mech491-project2-multiop.cls, six operations, bridge mill, work offset Z -100",
         nx + ["--machine", bridgemill], "bridgemill", 1.0),
        ("amorim-wall-holes.apt, bridge mill, work offset Z -150",
         ["--in", os.path.join(real, "amorim-wall-holes.apt"), "--machine", bridgemill,
          "--skip-record", "CUTCOM", "--gauge-length", "50", "--work-offset", "0,0,-150"],
         "bridgemill", 1.0),
        ("demo, bridge mill", demo + ["--machine", bridgemill], "bridgemill", 1.0),
    ]


def remedy_case(exe, src, work, label, common, preset):
    """The "[AXIS_*] accelerations at the report's share" case of the program `label` posts
    with `common`: (name, arguments, kins, share), or a failure text."""
    report = os.path.join(work, "share.json")
    r = subprocess.run([exe] + common + ["--machine", preset, "--method", "paper", "-q",
                                         "--feed-schedule", "--report", report,
                                         "--work-offset", "0,0,0"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        return "the share's run: taxopt exit %d: %s" % (r.returncode, r.stderr)
    share = json.load(open(report))["gcode"].get("tcp_axis_accel_scale")
    if not share or not 0.0 < share < 1.0:
        return "the %s program's report gives no share of the axes' accelerations: %s" % (
            label, share)
    sys.path.insert(0, os.path.join(src, "scripts"))
    import linuxcnc_controller
    sample, ini_name, _ = linuxcnc_controller.SAMPLES["xyzac"]
    folder = os.path.join(work, "scaled-sample-" + label)
    shutil.copytree(sample, folder)
    ini = os.path.join(folder, ini_name)
    with open(ini) as f:
        lines = linuxcnc_controller.scaled_ini_lines(f.read().split("\n"), share)
    with open(ini, "w") as f:
        f.write("\n".join(lines))
    machine = os.path.join(work, "scaled-%s.toml" % label)
    r = subprocess.run([exe, "machine", "--from-linuxcnc-ini", ini, "--out", machine],
                       capture_output=True, text=True)
    if r.returncode != 0 or "joint_max_accel_mm_s2 = 300" not in open(machine).read():
        return "the scaled sample's import: exit %d: %s" % (r.returncode, r.stderr)
    return ("%s, A/C, tcp, G94, [AXIS_*] accelerations at %.3f" % (label, share),
            common + ["--machine", machine], "xyzac", share)


def cases(exe, src, work, which):
    """(name, taxopt arguments, kinematics, [AXIS_*] acceleration share) of every program to
    run, and the failures met making them."""
    preset = os.path.join(src, "data/machines/linuxcnc-xyzac-trt.toml")
    bc = os.path.join(src, "data/machines/linuxcnc-xyzbc-trt-sample.toml")
    bridgemill = os.path.join(src, "data/machines/linuxcnc-5axis-bridgemill.toml")
    demo = ["--in", os.path.join(src, "data/demo/sine.cls"), "--part",
            os.path.join(src, "data/demo/sine.stl"), "--gauge-length", "50"]
    if which == "index":
        return index_cases(src, work, demo), []
    demos = [("demo, A/C", demo + ["--machine", preset], "xyzac", 1.0),
             ("demo, B/C", demo + ["--machine", bc], "xyzbc", 1.0)]
    remedy = remedy_case(exe, src, work, "demo", demo, preset)
    failures = [remedy] if isinstance(remedy, str) else []
    if not failures:
        demos.append(remedy)
    if which == "demo":
        return demos, failures
    if which == "real":
        real = os.path.join(src, "tests", "data", "real")  # the project's copies
        out = []
        for name, extra in REAL:
            path = real_path(real, name, work)
            out.append((name, ["--in", path, "--machine", preset] + extra, "xyzac", 1.0))
            out.append((name + ", B/C", ["--in", path, "--machine", bc] + extra, "xyzbc", 1.0))
        return out + demos, failures
    cls, stl = os.path.join(work, "g.cls"), os.path.join(work, "g.stl")
    subprocess.run([exe, "generate", "--width", "3", "--length", "20", "--out-cls", cls,
                    "--out-mesh", stl], check=True, capture_output=True)
    machine_mode = os.path.join(work, "machine-mode.toml")
    with open(preset) as f, open(machine_mode, "w") as g:
        g.write(f.read().replace('mode = "tcp"', 'mode = "machine"'))
    inverse_time = os.path.join(work, "inverse-time.toml")
    with open(preset) as f, open(inverse_time, "w") as g:
        g.write(f.read().replace('feed_mode = "units-per-minute"', 'feed_mode = "inverse-time"'))
    common = ["--in", cls, "--part", stl, "--gauge-length", "50"]
    more = [("sine, A/C, machine mode, G94", common + ["--machine", machine_mode], "xyzac", 1.0),
            ("sine, A/C, tcp, G93", common + ["--machine", inverse_time], "xyzac", 1.0),
            ("sine, B/C, tcp, G94", common + ["--machine", bc], "xyzbc", 1.0),
            ("sine, A/C, tcp, G94, programmed feeds",
             common + ["--machine", preset, "--no-schedule"], "xyzac", 1.0)]
    if which == "sine-more":
        return more, []
    out = [("sine, A/C, tcp, G94", common + ["--machine", preset], "xyzac", 1.0),
           ("sine, B/C head-head (bridge mill), tcp, G94", common + ["--machine", bridgemill],
            "bridgemill", 1.0)]
    remedy = remedy_case(exe, src, work, "sine", common, preset)
    if isinstance(remedy, str):
        return out, [remedy]
    return out + [remedy], []


def main():
    exe, src = sys.argv[1], sys.argv[2]
    which = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == "--set" else "sine"
    if which in ("real", "demo", "sine-more", "index") and \
            os.environ.get("TAXOPT_LONG") != "1":
        print("skipped: the real files and the demo on the controller take about 95 minutes, "
              "the sine in its other modes about 7; TAXOPT_LONG=1 runs them")
        return 77
    work = tempfile.mkdtemp(prefix="taxopt-controller-test-")
    rows = []
    programs, failures = cases(exe, src, work, which)
    for k, (name, args, kins, share) in enumerate(programs):
        ngc, report = os.path.join(work, "%d.ngc" % k), os.path.join(work, "%d.json" % k)
        # Scheduled feeds unless the case says --no-schedule (the CL file's feeds, which
        # taxopt verifies at the machine's limits and refuses where they exceed them).
        schedule = [] if "--no-schedule" in args else ["--feed-schedule"]
        args = [a for a in args if a != "--no-schedule"]
        # LinuxCNC's sample simulations start with G54 at zero: the work offset the travel
        # check holds every block with, unless the case sets one (then the controller's G54
        # is set to it before the run).
        offset = "0,0,0"
        if "--work-offset" in args:
            at = args.index("--work-offset")
            offset, args = args[at + 1], args[:at] + args[at + 2:]
        r = subprocess.run([exe] + args + ["--method", "paper", "-q", "--gcode", ngc,
                                           "--report", report, "--work-offset", offset]
                           + schedule,
                           capture_output=True, text=True)
        if r.returncode != 0:
            failures.append("%s: taxopt exit %d: %s" % (name, r.returncode, r.stderr))
            continue
        out = os.path.join(work, "%d-controller.json" % k)
        c = subprocess.run(["/usr/bin/python3", os.path.join(src, "scripts/linuxcnc_controller.py"),
                            "--ngc", ngc, "--kins", kins, "--points", "--json", out,
                            "--timeout", "2400", "--axis-accel-scale", repr(share),
                            "--work-offset", offset],
                           capture_output=True, text=True)
        if not os.path.exists(out):
            failures.append("%s: the controller run gave no summary: %s" % (name, c.stderr[-2000:]))
            continue
        s = json.load(open(out))
        rep = json.load(open(report))
        predicted, from_line = rep["gcode"]["time_s"], rep["gcode"]["time_from_line"]
        measured = sum(t for line, t in s.get("line_s", {}).items() if int(line) > from_line)
        print("== %s" % name)
        print("controller: ran to end %s, %.2f s moving, points passed within %.4f mm / %.3f deg"
              ", %d samples lost by the sampler's reader"
              % (s["ran_to_end"], s.get("move_s", 0), s.get("point_miss_mm", -1),
                 s.get("point_miss_deg", -1), s.get("lost_samples", 0)))
        print("program time after line %d: controller %.2f s, report %.2f s (%+.2f %%)"
              % (from_line, measured, predicted, 100.0 * (predicted - measured) / measured
                 if measured > 0 else float("nan")))
        joints = s.get("joints", {})
        for j, p in sorted(joints.items()):
            print("joint %s: velocity %.3f of %s (line %s), acceleration %.1f of %s (line %s); %s"
                  % (j, p["max_velocity"], p["limit_velocity"], p["velocity_line"],
                     p["max_accel"], p["limit_accel"], p["accel_line"], s["filter"]))
            if p["limit_velocity"] and p["max_velocity"] > 1.015 * p["limit_velocity"]:
                failures.append("%s: joint %s at %.3f/s against its %g (line %s)"
                                % (name, j, p["max_velocity"], p["limit_velocity"],
                                   p["velocity_line"]))
        # Accelerations: LinuxCNC accelerates the program's axes at their limits, and where it
        # plans with TCP on the joints may pass theirs. Every such overshoot must be covered by
        # the report's prediction (gcode.tcp_joint_peaks, within 2 %) and warned of
        # (tcp_joint_limit); anywhere else a joint past its limit fails.
        names = ["X", "Y", "Z", "A" if kins == "xyzac" else "B", "C"]
        tcp_peaks = rep["gcode"].get("tcp_joint_peaks") or {}
        warned = any(f["code"] == "tcp_joint_limit" for f in rep["findings"])
        if share != 1.0 and warned:
            failures.append("%s: the axes' accelerations at the report's share still warn: %s"
                            % (name, [f["message"] for f in rep["findings"]
                                      if f["code"] == "tcp_joint_limit"]))
        worst_predicted = 0.0
        for j, p in sorted(joints.items()):
            pred = tcp_peaks.get(names[int(j)], {})
            if p["limit_accel"]:
                worst_predicted = max(worst_predicted,
                                      pred.get("accel_per_s2", 0.0) / p["limit_accel"])
            if not p["limit_accel"] or p["max_accel"] <= 1.005 * p["limit_accel"]:
                continue
            # The report's peak is exact on rapids, on a chain's last feed block and on a first
            # one that turns A or C or goes on into one that does (LinuxCNC blends those
            # parabolically, at half the acceleration); a bound on a first block of X Y Z
            # alone: it must cover what was measured.
            if not (pred and warned and pred["accel_per_s2"] >= 0.98 * p["max_accel"]):
                failures.append("%s: joint %s accelerated at %.1f against its %g (line %s), "
                                "not as the report predicts (%s)"
                                % (name, names[int(j)], p["max_accel"], p["limit_accel"],
                                   p["accel_line"], pred or "nothing"))
            else:
                print("joint %s past its acceleration limit as predicted and warned: %.2f "
                      "predicted, %.2f measured, line %d"
                      % (names[int(j)], pred["accel_per_s2"], p["max_accel"], p["accel_line"]))
        if not measured > 0 or abs(predicted - measured) > 0.03 * measured:
            failures.append("%s: the controller took %.2f s, the report says %.2f s"
                            % (name, measured, predicted))
        if not s["ran_to_end"] or s["errors"]:
            failures.append("%s: did not run to its end: %s" % (name, s["errors"]))
        if s.get("last_line", 0) < s.get("program_lines", 1) - 2:
            failures.append("%s: stopped at line %s of %s" % (name, s.get("last_line"),
                                                               s.get("program_lines")))
        if not s.get("points") or s.get("point_miss_mm", 1e9) > 0.01 + 0.02:
            failures.append("%s: a point missed by %s mm" % (name, s.get("point_miss_mm")))
        ratio = lambda key, lim: max((p[key] / p[lim] for p in joints.values() if p.get(lim)),
                                     default=float("nan"))
        rows.append("| %s | %.2f | %.2f | %+.1f %% | %.3f | %.3f | %.3f | %.3f | %.2f |"
                    % (name, predicted, measured, 100.0 * (predicted - measured) / measured
                       if measured > 0 else float("nan"), ratio("max_velocity", "limit_velocity"),
                       ratio("max_accel", "limit_accel"), worst_predicted,
                       s.get("point_miss_mm", -1), s.get("point_miss_deg", -1)))
    print("\n| program | report s | controller s | difference | joint velocity / limit "
          "| joint acceleration / limit | predicted (tcp) / limit | point off, mm "
          "| point off, deg |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(r)
    for f in failures:
        print("FAILED: " + f)
    shutil.rmtree(work, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
