#!/usr/bin/env python3
"""make_pocket.py: writes pocket.ngc, the bundled demo program: a 100x60x30 mm
block (top at Z0, corner at the origin) with a rectangular pocket cleared by
zigzag passes after a helical entry, a finishing contour with rounded
corners, a circular pocket cut by a helix and spiral arcs, four G81 holes
and a V-bit chamfer line. Three tools (see tools.json). Run it again after
changing a dimension: python3 make_pocket.py > pocket.ngc"""

out = []
def emit(s):
    out.append(s)

def f(v):
    return ("%.4f" % v).rstrip("0").rstrip(".")

emit("%")
emit("(frepmill demo: pocket, contour, circular pocket, holes, chamfer)")
emit("(stock: box 0,0,-30 to 100,60,0; tools.json: T1 6 mm flat, T2 5 mm drill, T3 90 deg V-bit)")
emit("G21 G90 G17 G94 G40 G49 G54")
emit("T1 M6")
emit("S12000 M3")
emit("G0 Z10")

# Rectangular pocket x 10..60, y 10..50, depth 6 in three levels of 2 mm.
r = 3.0
x0, x1, y0, y1 = 10.0 + r, 60.0 - r, 10.0 + r, 50.0 - r
cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
step = 1.0
emit("(rectangular pocket: helical entry, zigzag clearing)")
emit("G0 X%s Y%s" % (f(cx + 2), f(cy)))
emit("G0 Z1")
z = 0.0
for level in range(3):
    znew = z - 2.0
    # Helical entry: one turn of radius 2 about the pocket centre.
    emit("G3 X%s Y%s Z%s I-2 J0 F600" % (f(cx + 2), f(cy), f(znew)))
    emit("G1 X%s Y%s F1000" % (f(x0), f(y0)))
    y = y0
    direction = 1
    while True:
        emit("G1 X%s" % f(x1 if direction > 0 else x0))
        if y + step > y1 + 1e-9:
            break
        y = min(y + step, y1)
        emit("G1 Y%s" % f(y))
        direction = -direction
    emit("G0 Z%s" % f(znew + 1))
    emit("G0 X%s Y%s" % (f(cx + 2), f(cy)))
    z = znew

# Finishing contour of the rectangle with 4 mm corner arcs (climb, G3 inside).
emit("(finishing contour)")
rc = 4.0
emit("G0 X%s Y%s" % (f(x0 + rc), f(y0)))
emit("G1 Z-6 F300")
emit("G1 X%s F800" % f(x1 - rc))
emit("G3 X%s Y%s I0 J%s" % (f(x1), f(y0 + rc), f(rc)))
emit("G1 Y%s" % f(y1 - rc))
emit("G3 X%s Y%s I%s J0" % (f(x1 - rc), f(y1), f(-rc)))
emit("G1 X%s" % f(x0 + rc))
emit("G3 X%s Y%s I0 J%s" % (f(x0), f(y1 - rc), f(-rc)))
emit("G1 Y%s" % f(y0 + rc))
emit("G3 X%s Y%s I%s J0" % (f(x0 + rc), f(y0), f(rc)))
emit("G0 Z10")

# Circular pocket at (80, 30), radius 12, depth 8: helix down at r = 2, then
# full circles spiralling out.
pcx, pcy = 80.0, 30.0
emit("(circular pocket: helix, then full circles stepping out)")
emit("G0 X%s Y%s" % (f(pcx + 2), f(pcy)))
emit("G0 Z1")
emit("G3 X%s Y%s Z-8 I-2 J0 P4 F500" % (f(pcx + 2), f(pcy)))
rad = 2.0
while rad < 12.0 - r - 1e-9:
    rad = min(rad + 1.5, 12.0 - r)
    emit("G1 X%s Y%s F900" % (f(pcx + rad), f(pcy)))
    emit("G3 X%s Y%s I%s J0" % (f(pcx + rad), f(pcy), f(-rad)))
emit("G0 Z10")

# Outside profile step along the front edge: a 3 mm deep, 8 mm wide ledge cut in
# passes along X (feeds in G91 incremental mode).
emit("(front ledge in incremental passes)")
emit("G0 X-5 Y1")
emit("G1 Z-3 F300")
for i in range(3):
    emit("G91 G1 X110 F1200")
    emit("G1 Y2")
    emit("G1 X-110")
    emit("G1 Y%s" % f(0.5 if i < 2 else 0))
    emit("G90")
emit("G0 Z10")

emit("T2 M6")
emit("S3000 M3")
emit("(four drilled holes)")
emit("G0 Z10")
emit("G98 G81 X5 Y55 Z-12 R2 F200")
emit("X95")
emit("Y15")
emit("X5 Y15")
emit("G80")
emit("G0 Z10")

emit("T3 M6")
emit("S15000 M3")
emit("(chamfer line along the back edge)")
emit("G0 X5 Y58 Z2")
emit("G1 Z-1 F300")
emit("G1 X95 F1000")
emit("G0 Z10")
emit("M5")
emit("M30")
emit("%")
print("\n".join(out))
