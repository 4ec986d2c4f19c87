"""test_trunnion_cli.py: the README's 5-axis example, examples/trunnion_5axis.ngc
on examples/trunnion_machine.json (AC trunnion, TCP), end to end through the
CLI, each figure computed here from the program text:

- `frepmill motions`: 14 motions; every tip position is the program's X Y Z
  (TCP), the rotary angles are the program's A and C, the tool axis in the
  workpiece frame is (sin A sin C, sin A cos C, cos A) (A tilts about X,
  C turns about Z, both carried by the table), the C turns keep the tip
  still, and each feed move takes length / F (mm/min, deg/min) of program
  time;
- `frepmill check`: no findings (exit 0);
- `frepmill simulate` (the README's command): the removed volume equals the
  closed form of the chamfer, the tool's end face plane n.(p - tip) + (z + 2)
  = 0 swept along the square of half-side 28 with the normal n turning
  through each corner's quadrant: depth D(x, y) + 2 where D is the signed
  distance from (x, y) to that square (Euclidean in the corner quadrants,
  so the corners are cones), integrated over the 60 x 60 top:
    ring inside the square:    8 * int_0^2 u (u + 26) du = 8 (8/3 + 52)
    four edge bands outside:   4 * 56 * int_2^4 u du     = 4 * 56 * 6
    four corner quadrants:     4 * (8 * (sqrt 2 + ln(1 + sqrt 2)) / 3 + 2 * 4)
  = 1837.82 mm^3. Square corners instead of cones would remove 3.15 mm^3
  less; the tolerance (0.9 mm^3, 0.05%) tells them apart, and is ten times
  what the 0.2 mm grid misses on these planes and cones.
Usage: test_trunnion_cli.py FREPMILL"""
import json
import math
import os
import subprocess
import sys
import tempfile

from cli_util import ROOT, check, summary

EX = os.path.join(ROOT, "examples")
PROGRAM = os.path.join(EX, "trunnion_5axis.ngc")
MACHINE = os.path.join(EX, "trunnion_machine.json")
ARGS = ["--tools", os.path.join(EX, "rotary_tools.json"), "--machine", MACHINE]
STOCK = "box:-30,-30,-20,30,30,0"


def near(a, b, tol=1e-4):
    return all(abs(x - y) <= tol for x, y in zip(a, b)) and len(a) == len(b)


def closed_form_volume():
    ring = 8 * (8.0 / 3 + 52)
    bands = 4 * 56 * 6.0
    corner = 8 * (math.sqrt(2) + math.log(1 + math.sqrt(2))) / 3 + 2 * 4
    return ring + bands + 4 * corner


def main():
    frepmill = sys.argv[1]
    # The program, move by move, as written: (kind, X, Y, Z, A, C, F). The
    # interpreter starts where the machine file's "start" puts the tool, as
    # the check does (docs/simulate.md, "The machine's state at the start").
    moves = [("rapid", 0, 0, 60, 0, 0, 0), ("rapid", 0, 0, 60, 45, 0, 0),
             ("rapid", -45, 28, 40, 45, 0, 0), ("rapid", -45, 28, -2, 45, 0, 0),
             ("line", 28, 28, -2, 45, 0, 600), ("line", 28, 28, -2, 45, 90, 1800),
             ("line", 28, -28, -2, 45, 90, 600), ("line", 28, -28, -2, 45, 180, 1800),
             ("line", -28, -28, -2, 45, 180, 600), ("line", -28, -28, -2, 45, 270, 1800),
             ("line", -28, 28, -2, 45, 270, 600), ("line", -28, 28, -2, 45, 360, 1800),
             ("rapid", -28, 28, 60, 45, 360, 0), ("rapid", -28, 28, 60, 0, 0, 0)]
    out = subprocess.run([frepmill, "motions", PROGRAM, *ARGS], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, timeout=120)
    check(out.returncode == 0, "frepmill motions: exit 0 (%s)" % out.stderr.decode().strip()[-200:])
    motions = [json.loads(line) for line in out.stdout.decode().splitlines() if line.strip()]
    check(len(motions) == len(moves), "%d motions, one per move of the program (%d)" % (len(motions), len(moves)))
    with open(MACHINE) as f:
        prev = tuple(json.load(f).get("start", (0, 0, 0))) + (0, 0)
    for m, (kind, x, y, z, a, c, f) in zip(motions, moves):
        i = m["index"]
        ok = m["kind"] == kind and near(m["start"], prev[:3]) and near(m["end"], (x, y, z))
        ok = ok and near(m["rotary"][:1] + m["rotary"][2:], (a, c)) and m["tcp"] == 1
        ra, rc = math.radians(a), math.radians(c)
        axis = (math.sin(ra) * math.sin(rc), math.sin(ra) * math.cos(rc), math.cos(ra))
        ok = ok and near(m["tool_axis"][1], axis, 1e-5)
        if kind == "line":
            length = math.dist(prev[:3], (x, y, z))
            turn = abs(c - prev[4]) + abs(a - prev[3])
            want = 60.0 * (length if length > 0 else turn) / f
            ok = ok and abs((m["t"][1] - m["t"][0]) - want) <= 1e-6
        check(ok, "motion %d (line %d): %s to (%g, %g, %g) at A%g C%g, tool axis (%.4f, %.4f, %.4f)%s" %
              (i, m["line"], kind, x, y, z, a, c, *axis,
               ", %.2f s" % (m["t"][1] - m["t"][0]) if kind == "line" else ""))
        prev = (x, y, z, a, c)

    out = subprocess.run([frepmill, "check", PROGRAM, "--stock", STOCK, *ARGS], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, timeout=300)
    findings = json.loads(out.stdout) if out.stdout.strip() else None
    check(out.returncode == 0 and findings and findings["findings"] == [] and findings["errors"] == 0,
          "frepmill check: exit %d, no findings" % out.returncode)

    with tempfile.TemporaryDirectory(prefix="fm-trunnion-") as tmp:
        report = os.path.join(tmp, "report.json")
        out = subprocess.run([frepmill, "simulate", PROGRAM, "--stock", STOCK, *ARGS, "--voxel", "0.2",
                              "--report", report, "--png", os.path.join(tmp, "chamfer.png")],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=600)
        check(out.returncode == 0, "frepmill simulate: exit 0 (%s)" % out.stderr.decode().strip()[-300:])
        with open(report) as f:
            rep = json.load(f)
        want = closed_form_volume()
        check(abs(want - 1837.82) < 0.01, "closed form %.3f mm^3" % want)
        check(abs(rep["removed_volume_mm3"] - want) <= 0.0005 * want,
              "removed %.2f mm^3, closed form %.2f mm^3 (tolerance %.2f)" %
              (rep["removed_volume_mm3"], want, 0.0005 * want))
        check(abs(rep["initial_volume_mm3"] - 72000.0) <= 1e-6 * 72000, "initial volume 60 x 60 x 20")
        check(rep["motions"] == len(moves) and rep.get("voxels_uncertain") == 0,
              "report: %d motions, no uncertain voxel" % rep["motions"])
        check(os.path.getsize(os.path.join(tmp, "chamfer.png")) > 0, "the picture was written")
    return summary("test_trunnion_cli")


if __name__ == "__main__":
    sys.exit(main())
