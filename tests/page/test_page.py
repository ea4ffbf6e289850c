#!/usr/bin/env python3
"""taxopt's HTML page (--html) in a real browser: headless Chromium, with the network off.

usage: test_page.py TAXOPT SOURCE_DIR [--set pages|big] [--update-screenshot]

  pages  the demo's page (taxopt demo) and a real CL file's page with a part: the SOLIDWORKS
         CAM file amorim-interface-glue.apt, its 3-axis ball-end finish's part derived from
         the file itself (derived_part.py). Loaded in Chromium in a network namespace with no
         network (unshare -rn): no console message but the page's own ready line, no script
         error, the canvas draws (pixels that are not the background, the part alone among
         them), the page's data agree with the report (points, colliding points and moves,
         the peaks of omega and a, before and after), the screenshot is not blank.
         --update-screenshot copies the demo's screenshot to docs/images/taxopt-page-demo.png.
  big    the page of a 102,084-point run: its size and its load time are bounded, and it says
         that it is decimated.

The page reports what it drew in its console line "taxopt-page-ready {json}" (apps/taxopt/support/html_page.js).
"""
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FAILURES = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        FAILURES.append(what)


def run(cmd, **kw):
    print("$ " + " ".join(cmd), flush=True)
    return subprocess.run(cmd, text=True, capture_output=True, **kw)


def png_pixels(path):
    """(width, height, rows of RGB(A) bytes) of an 8-bit, non-interlaced PNG."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and interlace == 0 and colour in (2, 6), "PNG kind not read here"
            channels = 4 if colour == 6 else 3
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - channels] if x >= channels else 0
            b = prev[x]
            c = prev[x - channels] if x >= channels else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, channels, rows


def load_page(page, shot, budget_ms=20000):
    """Loads the page in headless Chromium with no network; returns (state, console lines, s)."""
    cmd = [CHROMIUM, "--headless=new", "--no-sandbox", "--enable-unsafe-swiftshader",
           "--use-angle=swiftshader", "--enable-logging=stderr", "--v=0",
           "--virtual-time-budget=%d" % budget_ms, "--window-size=1400,2400",
           "--user-data-dir=" + tempfile.mkdtemp(prefix="taxopt-chromium-"),
           "--screenshot=" + shot, "file://" + os.path.abspath(page)]
    # No network: a network namespace of its own (only a loopback, down). Where the kernel
    # refuses one, no test of "works offline" is possible: that fails, it is not skipped.
    net_off = run(["unshare", "-rn", "true"]).returncode == 0
    check(net_off, "a network namespace without network (unshare -rn) is available")
    if net_off:
        cmd = ["unshare", "-rn"] + cmd
    t0 = time.monotonic()
    r = run(cmd, timeout=300)
    seconds = time.monotonic() - t0
    console = [l for l in r.stderr.splitlines() if ":CONSOLE" in l and "source: file://" in l]
    state = None
    for l in console:
        m = re.search(r'"taxopt-page-ready (\{.*\})", source', l)
        if m:
            state = json.loads(m.group(1))
    check(r.returncode == 0, "chromium exits 0 (%d)" % r.returncode)
    return state, console, seconds


def check_page(name, page, report_path, out_dir, screenshot_copy=None):
    report = json.load(open(report_path))
    html = open(page, encoding="utf-8").read()
    check(not re.search(r'(src|href)\s*=\s*["\']?(https?:|//)', html, re.I),
          name + ": the page loads nothing from a network (no src/href to http)")
    shot = os.path.join(out_dir, name + "-page.png")
    state, console, seconds = load_page(page, shot)
    check(state is not None, name + ": the page ran to its end (its ready line is on the console)")
    if state is None:
        print("\n".join(console))
        return None
    others = [l for l in console if "taxopt-page-ready" not in l]
    check(not others and not state["errors"],
          name + ": no console message or script error (%s)" % (others + state["errors"])[:3])
    ops = report["operations"]
    check(state["operations"] == len(ops), name + ": operations %d" % state["operations"])
    check(state["points"] == sum(o["points"] for o in ops),
          name + ": points %d = the report's" % state["points"])
    colliding = sum(o["after"]["colliding_points"] or 0 for o in ops)
    moves = sum(max(0, o["verification"].get("colliding_moves") or 0) for o in ops)
    check(state["colliding_points"] == colliding,
          name + ": colliding points %d = the report's %d" % (state["colliding_points"], colliding))
    check(state["colliding_moves"] == moves,
          name + ": colliding moves %d = the report's %d" % (state["colliding_moves"], moves))
    for key, side, field in (("peak_accel_after", "after", "max_accel_deg_s2"),
                             ("peak_accel_before", "before", "max_accel_deg_s2"),
                             ("peak_omega_after", "after", "max_omega_deg_s"),
                             ("peak_omega_before", "before", "max_omega_deg_s")):
        want = max(o[side][field] for o in ops)
        # The page keeps 3 decimals, and every stride's peak (html_page.cpp).
        check(abs(state[key] - want) <= 1e-3 + 1e-9 * want,
              "%s: %s %.4f = the report's %.4f" % (name, key, state[key], want))
    check(state["charts"] == 5, name + ": five plots drawn")
    # No axis label, tick or legend over a plot's title (the pointer's legend lay over the next
    # plot's title); counted over the titles and every text of the plots.
    check(state["plot_texts"] > 5 and state["label_title_overlaps"] == 0,
          name + ": %d plot texts over a plot title (of %d titles and tick labels)"
          % (state["label_title_overlaps"], state["plot_texts"]))
    marked = [m for m in state["marker_counts"] if state["marker_counts"][m]]
    if marked:
        first = state["first_marker"] or {}
        text = first.get("text", "")
        check("CL line " in text and "deg apart" in text and any(k in text for k in marked),
              name + ": a marker shows its CL line, marks and axes: " + text.splitlines()[0]
              if text else name + ": a marker shows nothing")
        check(first.get("selected_row", -1) >= 0, name + ": the plots point at the marker's point")
    frac_part = state["part_pixels"] / state["canvas_pixels"]
    frac_all = state["drawn_pixels"] / state["canvas_pixels"]
    check(frac_part > 0.02, name + ": the part alone covers %.1f %% of the canvas" % (100 * frac_part))
    check(frac_all > frac_part, name + ": toolpath, axes and markers add to it (%.1f %%)" % (100 * frac_all))
    width, height, channels, rows = png_pixels(shot)
    colours = set()
    non_white = 0
    for y in range(0, height, 7):
        row = rows[y]
        for x in range(0, width, 7):
            px = row[x * channels:x * channels + 3]
            colours.add(px)
            non_white += px != b"\xff\xff\xff"
    samples = ((height + 6) // 7) * ((width + 6) // 7)
    check(len(colours) > 200 and non_white > 0.1 * samples,
          name + ": the screenshot is not blank (%d colours, %.0f %% not white)"
          % (len(colours), 100.0 * non_white / samples))
    if screenshot_copy:
        shutil.copyfile(shot, screenshot_copy)
        print("screenshot copied to " + screenshot_copy)
    print("%s: loaded in %.1f s, %d bytes" % (name, seconds, os.path.getsize(page)))
    state["seconds"] = seconds
    return state


def main():
    taxopt, source = sys.argv[1], sys.argv[2]
    which = sys.argv[sys.argv.index("--set") + 1] if "--set" in sys.argv else "pages"
    update = "--update-screenshot" in sys.argv
    if not CHROMIUM:
        print("FAIL chromium is not installed (scripts/setup.sh installs it)")
        return 1
    out = tempfile.mkdtemp(prefix="taxopt-page-")
    real = os.path.join(source, "tests", "data", "real")
    if which == "pages":
        demo = os.path.join(out, "demo")
        r = run([taxopt, "demo", "--out", demo, "-q"])
        check(r.returncode == 0, "taxopt demo exits 0: " + r.stderr[-300:])
        copy = os.path.join(source, "docs", "images", "taxopt-page-demo.png") if update else None
        check_page("demo", os.path.join(demo, "demo.html"), os.path.join(demo, "report.json"), out, copy)

        # A real CL file with a part: SOLIDWORKS CAM's 3-axis ball-end finish (lines 163-6364,
        # a 14 mm ball) of amorim-interface-glue.apt, the part derived from its feed points on a
        # 0.5 mm grid. The grid's chordal error near a ball's rim reaches 0.16 mm (measured:
        # the contact check's "cuts 0.163 mm" at --contact-tolerance 0.15): the tolerances say so.
        cl = os.path.join(real, "amorim-interface-glue.apt")
        stl = os.path.join(out, "interface-glue-finish.stl")
        r = run([sys.executable, os.path.join(source, "tests", "page", "derived_part.py"), cl,
                 "163", "6364", "7", "0.5", stl])
        check(r.returncode == 0, "derived part: " + r.stdout.strip() + r.stderr[-300:])
        page, rep = os.path.join(out, "real.html"), os.path.join(out, "real.json")
        r = run([taxopt, "--in", cl, "--skip-record", "INSERT", "--skip-record", "CUTCOM",
                 "--part", stl, "--contact-tolerance", "0.25", "--part-tolerance", "0.25",
                 "--html", page, "--report", rep, "-q"])
        check(r.returncode == 0, "taxopt on the real file with its part exits 0: " + r.stderr[-400:])
        state = check_page("real", page, rep, out)
        if state:
            check(state["mesh_triangles"] > 1000, "real: the part is on the page")
    else:
        d = os.path.join(out, "big")
        os.makedirs(d)
        cls, stl = os.path.join(d, "big.cls"), os.path.join(d, "big.stl")
        r = run([taxopt, "generate", "--out-cls", cls, "--out-mesh", stl, "--width", "100",
                 "--length", "400", "--chord-error", "0.01", "--scallop", "0.012"])
        check(r.returncode == 0, "generate exits 0")
        page, rep = os.path.join(d, "big.html"), os.path.join(d, "big.json")
        # --method none keeps the vertical axes, whose shank hits the sine's flanks: exit 1, and
        # --force writes the page with its ~16,000 markers (what the page is for).
        t0 = time.monotonic()
        r = run([taxopt, "--in", cls, "--part", stl, "--method", "none", "--html", page,
                 "--report", rep, "-q", "--force"])
        write_s = time.monotonic() - t0
        check(r.returncode == 1, "taxopt --force on the big run exits 1 (collisions)")
        report = json.load(open(rep))
        points = sum(o["points"] for o in report["operations"])
        size = os.path.getsize(page)
        check(points > 100000, "the run has %d points" % points)
        check(size < 16 * 2**20, "the page is %.1f MB (bound 16 MB)" % (size / 2**20))
        state = check_page("big", page, rep, out)
        if state:
            check(state["plotted_points"] < 0.25 * points,
                  "big: %d of %d points plotted" % (state["plotted_points"], points))
            check("decimated" in state["note"], "big: the page says it is decimated: " + state["note"])
            check(state["load_ms"] < 15000, "big: the page's script ran in %.1f s (bound 15 s)"
                  % (state["load_ms"] / 1000))
            check(state["seconds"] < 60, "big: Chromium started, loaded and shot it in %.1f s "
                  "(bound 60 s)" % state["seconds"])
        print("| points | page MB | taxopt run s | page script s |")
        print("|---|---|---|---|")
        print("| %d | %.1f | %.1f | %.1f |" % (points, size / 2**20, write_s,
                                              (state or {}).get("load_ms", 0) / 1000))
    if FAILURES:
        print("%d checks failed" % len(FAILURES))
        return 1
    shutil.rmtree(out, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
