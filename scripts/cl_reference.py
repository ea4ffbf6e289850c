#!/usr/bin/env python3
"""Independent reading of the real CL files, for the test that no motion is dropped.

For each file it counts the motion records (GOTO, FROM, GODLTA, GOHOME), the arc records
(CIRCLE, and Fusion's MOVARC, whose sweep is written: ANGLE deg counter-clockwise about its axis),
and measures the length of the path the file means, in mm: straight moves between points,
arcs by their own geometry with each arc's sense taken from the straight moves before and
after it (tangent continuity) and, where those do not decide, from the CAM system's
documented sense; drilling cycles expanded as docs/cl-files.md states. It shares no code with
taxopt's reader (src/cl/).

    python3 scripts/cl_reference.py tests/data/real/*.cls ... > tests/data/real/reference.tsv
"""
import math
import sys


def logical_records(text):
    lines = text.replace("\r\n", "\n").split("\n")
    if lines and lines[0].startswith("\ufeff"):
        lines[0] = lines[0][1:]
    i, out, comments = 0, [], []
    while i < len(lines):
        s = lines[i].strip()
        if s.startswith("$$"):
            comments.append(s)
            while s.endswith("$") and len(s) > 2 and i + 1 < len(lines):
                i += 1
                s = lines[i].strip()
                comments.append(s)
            i += 1
            continue
        code, piece = "", lines[i]
        while True:
            c = piece.find("$$")
            if c >= 0:
                piece = piece[:c]
            t = piece.rstrip()
            if t.endswith("$"):
                code += t[:-1]
                i += 1
                piece = lines[i]
                continue
            code += piece
            break
        code = code.strip()
        if code:
            if "/" in code:
                head, args = code.split("/", 1)
            else:
                head, args = (code.split(None, 1) + [""])[:2]
            head = " ".join(head.split()).upper()
            out.append((head, [a.strip() for a in args.split(",")] if args.strip() else []))
        i += 1
    return out, comments


def number(s):
    try:
        return float(s)
    except ValueError:
        return None


def sub(a, b):
    return [a[k] - b[k] for k in range(3)]


def add(a, b):
    return [a[k] + b[k] for k in range(3)]


def mul(a, s):
    return [x * s for x in a]


def dot(a, b):
    return sum(a[k] * b[k] for k in range(3))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def norm(a):
    return math.sqrt(dot(a, a))


def dialect_clockwise(records, comments):
    text = " ".join(c.upper() for c in comments) + " " + " ".join(h for h, _ in records)
    if "FFCAM" in text or "MAKINO" in text:
        return True
    heads = {h for h, _ in records}
    return bool(heads & {"TOOL PATH", "TLDATA", "END-OF-PATH", "MSYS"})


def reference(path):
    records, comments = logical_records(open(path, encoding="latin-1").read())
    default_cw = dialect_clockwise(records, comments)
    units = 1.0
    for h, a in records:
        if h in ("UNITS", "UNIT"):
            units = 25.4 if a and a[0].upper().startswith("IN") else 1.0
            break
        if h == "FEDRAT" and any(x.upper() in ("IPM", "IPR") for x in a):
            units = 25.4
    # Items: ("p", point) or ("arc", centre, axis, turns).
    items, axis, home, cycle = [], [0.0, 0.0, 1.0], None, None
    motions = circles = 0
    pending = None
    for h, a in records:
        if h in ("GOTO", "FROM"):
            v = [number(x) * units for x in a[:3]]
            if len(a) == 6:
                axis = [number(x) for x in a[3:6]]
                n = norm(axis)
                axis = [x / n for x in axis]
            motions += 1
            if h == "FROM":
                home = v
            if pending:
                items.append(pending)
                pending = None
            if cycle and h == "GOTO":
                depth, rapto, rtrcto, first, nxt = cycle
                clear = max(rtrcto, rapto)
                seq = [add(v, mul(axis, clear)), add(v, mul(axis, rapto))]
                reached = 0.0
                while reached < depth - 1e-9:
                    step = first if reached == 0.0 else nxt
                    new = min(depth, reached + step)
                    if reached > 0.0:
                        # back to the rapid plane, down to 0.254 mm above the depth reached
                        # (LinuxCNC 2.9's G83_RAPID_DELTA, as taxopt's reader)
                        back = max(reached - 0.254, -rapto)
                        seq += [add(v, mul(axis, rapto)), sub(v, mul(axis, back))]
                    seq.append(sub(v, mul(axis, new)))
                    reached = new
                seq.append(add(v, mul(axis, clear)))
                items += [("p", q) for q in seq]
            else:
                items.append(("p", v))
        elif h == "GOHOME":
            motions += 1
            items.append(("p", home))
        elif h == "GODLTA":
            motions += 1
            last = [it for it in items if it[0] == "p"][-1][1]
            d = [number(x) * units for x in a]
            items.append(("p", add(last, d if len(d) == 3 else mul(axis, d[0]))))
        elif h == "CIRCLE":
            circles += 1
            v = []
            for x in a:
                if number(x) is None:
                    break
                v.append(number(x))
            turns = 1
            if "TIMES" in [x.upper() for x in a]:
                turns = int(number(a[[x.upper() for x in a].index("TIMES") + 1]))
            n = norm(v[3:6])
            pending = ("arc", mul(v[:3], units), [x / n for x in v[3:6]], turns)
        elif h == "MOVARC":
            # Fusion / HSM: xc,yc,zc,i,j,k,r,ANGLE,deg -- ANGLE deg counter-clockwise about (i,j,k).
            circles += 1
            v = [number(x) for x in a[:7]]
            n = norm(v[3:6])
            pending = ("arc", mul(v[:3], units), [x / n for x in v[3:6]], 1,
                       math.radians(number(a[8])))
        elif h == "CYCLE":
            kind = a[0].upper()
            if kind == "OFF":
                cycle = None
            elif kind not in ("INIT", "ON"):
                kv = {}
                k = 1
                while k < len(a):
                    if k + 1 < len(a) and number(a[k + 1]) is not None:
                        kv[a[k].upper()] = number(a[k + 1])
                        k += 2
                    else:
                        k += 1
                depth = kv["FEDTO"] * units
                first = kv.get("1STPECK", 0.0) * units or depth
                nxt = kv.get("SUBPECK", 0.0) * units or first
                if kind not in ("DEEP", "DEEP2", "BRKCHP"):
                    first = nxt = depth
                cycle = (depth, kv.get("RAPTO", 0.0) * units, kv.get("RTRCTO", 0.0) * units,
                         first, nxt)
        elif h in ("NURBS", "KNOT", "CNTRL"):
            raise SystemExit(path + ": NURBS not measured by this script")
    # Walk: points and arcs between them.
    length, prev = 0.0, None
    for i, it in enumerate(items):
        if it[0] != "p":
            continue
        if prev is not None and items[i - 1][0] == "arc":
            c, n, turns = items[i - 1][1:4]
            given = items[i - 1][4] if len(items[i - 1]) > 4 else None
            s, e = prev, it[1]
            sp, ep = sub(s, c), sub(e, c)
            hs, he = dot(sp, n), dot(ep, n)
            sp, ep = sub(sp, mul(n, hs)), sub(ep, mul(n, he))
            ccw = math.atan2(dot(cross(sp, ep), n), dot(sp, ep)) % (2 * math.pi)
            if ccw < 1e-9:
                ccw = 2 * math.pi

            def vote(move, radial):
                mp = sub(move, mul(n, dot(move, n)))
                t = cross(n, radial)
                if norm(move) < 1e-9 or norm(mp) < 0.5 * norm(move) or norm(t) < 1e-9:
                    return 0
                cosine = dot(mp, t) / (norm(mp) * norm(t))
                # a corner (more than 5 deg off the tangent) says nothing of the sense
                return 0 if abs(cosine) < 0.99619 else (1 if cosine > 0 else -1)

            votes = []
            if i >= 3 and items[i - 2][0] == "p" and items[i - 3][0] == "p":
                votes.append(vote(sub(s, items[i - 3][1]), sp))
            if i + 1 < len(items) and items[i + 1][0] == "p":
                votes.append(vote(sub(items[i + 1][1], e), ep))
            votes = [x for x in votes if x]
            if votes and all(x == votes[0] for x in votes):
                clockwise = votes[0] < 0
            else:
                clockwise = default_cw
            sweep = (2 * math.pi - ccw if ccw < 2 * math.pi - 1e-12 else ccw) if clockwise else ccw
            sweep += 2 * math.pi * (turns - 1)
            if given is not None:
                sweep = given  # MOVARC writes its sweep
            r = 0.5 * (norm(sp) + norm(ep))
            length += math.hypot(sweep * r, he - hs)
        elif prev is not None:
            length += norm(sub(it[1], prev))
        prev = it[1]
    return motions, circles, length


if __name__ == "__main__":
    print("file\tmotion_records\tcircles\tpath_mm")
    for f in sys.argv[1:]:
        m, c, length = reference(f)
        print(f"{f.split('/')[-1]}\t{m}\t{c}\t{length:.3f}")
