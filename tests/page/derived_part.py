#!/usr/bin/env python3
"""The surface a real 3-axis ball-end finish cut, as a part mesh (binary STL).

The real CL files come without their parts. For a 3-axis ball-end finish the machined surface
follows from the file alone: with a vertical tool, the ball and the shank above it remove
everything above the ball's lower hemisphere within its footprint, at every point (a rapid's
ball is in the air, so it bounds the part from above too). The part is the height field
h(x, y) = min over the balls over (x, y) of (centre z - sqrt(R^2 - d^2)), sampled on a grid:
no grid node is inside a ball, and the ball at a point that touches the surface touches a node.
Between the nodes the triangles are chords: near a ball's rim, where its lower hemisphere turns
vertical, a chord reaches into the ball by up to f'' step^2 / 8 with f'' = R^2 / (R^2 - d^2)^1.5
(measured for amorim-interface-glue.apt, R 7 mm, step 0.5 mm: 0.163 mm, the contact check's
"the ball cuts 0.163 mm into the part" at --contact-tolerance 0.15). A user of the mesh gives
that tolerance. Where no ball passed, the field is 10 steps below the lowest ball's bottom (a
cliff down, away from the balls). A tilted axis would move the centre (tip + R axis), but the
footprint argument needs a vertical tool: 5-axis files are not for this script (the NX
variable-axis file's approach gave 0.64 mm at a 0.5 mm grid).

usage: derived_part.py CL_FILE FIRST_LINE LAST_LINE RADIUS STEP OUT.stl
(the ball operation's records are the lines FIRST_LINE..LAST_LINE, 1-based; RADIUS and STEP in
the CL file's units, which the STL keeps: taxopt reads a part in the CL file's units).
"""
import math
import struct
import sys


def ball_centres(path, first, last, radius):
    """The ball centres of the points: tip + R axis (a GOTO with 3 numbers keeps the axis)."""
    centres = []
    axis = (0.0, 0.0, 1.0)
    with open(path, encoding="latin-1") as f:
        for number, line in enumerate(f, 1):
            if number < first or number > last:
                continue
            word = line.strip().upper()
            if word.startswith("GOTO/"):
                values = [float(v) for v in word[5:].split(",")[:6]]
                if len(values) == 6:
                    axis = tuple(values[3:])
                # A rapid's ball is in the air: it bounds the part from above as a feed ball does.
                centres.append([values[q] + radius * axis[q] for q in range(3)])
    return centres


def main():
    path, first, last, radius, step, out = sys.argv[1:7]
    first, last, radius, step = int(first), int(last), float(radius), float(step)
    tips = ball_centres(path, first, last, radius)
    if not tips:
        sys.exit("no point in lines %d..%d of %s" % (first, last, path))
    xs = [p[0] for p in tips]
    ys = [p[1] for p in tips]
    x0, y0 = min(xs) - radius, min(ys) - radius
    nx = int(math.ceil((max(xs) + radius - x0) / step)) + 1
    ny = int(math.ceil((max(ys) + radius - y0) / step)) + 1
    floor = min(p[2] for p in tips) - radius - 10.0 * step
    h = [[None] * ny for _ in range(nx)]
    cells = int(math.ceil(radius / step))
    for x, y, cz in tips:
        i0, j0 = int(round((x - x0) / step)), int(round((y - y0) / step))
        for i in range(max(0, i0 - cells), min(nx, i0 + cells + 1)):
            dx = x0 + i * step - x
            for j in range(max(0, j0 - cells), min(ny, j0 + cells + 1)):
                dy = y0 + j * step - y
                d2 = dx * dx + dy * dy
                if d2 < radius * radius:
                    v = cz - math.sqrt(radius * radius - d2)
                    if h[i][j] is None or v < h[i][j]:
                        h[i][j] = v
    h = [[floor if v is None else v for v in column] for column in h]
    triangles = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a = (x0 + i * step, y0 + j * step, h[i][j])
            b = (x0 + (i + 1) * step, y0 + j * step, h[i + 1][j])
            c = (x0 + (i + 1) * step, y0 + (j + 1) * step, h[i + 1][j + 1])
            d = (x0 + i * step, y0 + (j + 1) * step, h[i][j + 1])
            triangles += [(a, b, c), (a, c, d)]
    with open(out, "wb") as f:
        f.write(b"taxopt derived part".ljust(80, b" "))
        f.write(struct.pack("<I", len(triangles)))
        for t in triangles:
            f.write(struct.pack("<3f", 0.0, 0.0, 0.0))
            for v in t:
                f.write(struct.pack("<3f", *v))
            f.write(b"\0\0")
    print("%d points, %d x %d grid, %d triangles" % (len(tips), nx, ny, len(triangles)))


if __name__ == "__main__":
    main()
