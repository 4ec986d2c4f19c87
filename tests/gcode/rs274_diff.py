#!/usr/bin/env python3
"""rs274_diff.py: differential test of `frepmill motions` against LinuxCNC's
standalone interpreter `rs274 -g`.

rs274 prints canonical calls (STRAIGHT_TRAVERSE, STRAIGHT_FEED, ARC_FEED,
DWELL) with positions in the active program coordinate system and units, and
announces offsets with SET_G5X_OFFSET / SET_G92_OFFSET and units with
USE_LENGTH_UNITS. This script converts those to machine millimetres and
compares every motion's kind, end point, arc centre and turns with frepmill's
JSON lines, within the precision rs274 prints (4 decimals of program units).

usage: rs274_diff.py FREPMILL PROGRAM [PROGRAM...] [--tools TABLE_MM.tbl]
Exit 0 when all agree, 1 on a difference, 77 (skip) when rs274 or a LinuxCNC
example program is missing.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

SKIP = 77
CALL = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$")


def rs274_motions(program, tbl_inch):
    cmd = ["rs274", "-g"]
    if tbl_inch:
        cmd += ["-t", tbl_inch]
    cmd.append(program)
    # M0/M1 wait for a key press: feed it a newline
    res = subprocess.run(cmd, input="\n" * 1000, capture_output=True, text=True, timeout=300)
    unit = 1.0
    g5x = [0.0, 0.0, 0.0]
    g92 = [0.0, 0.0, 0.0]
    plane = "XY"
    pos = None  # machine mm of the last point
    out = []
    for line in res.stdout.splitlines():
        m = CALL.match(line)
        if not m:
            continue
        name, args = m.group(1), m.group(2)
        if name == "USE_LENGTH_UNITS":
            unit = 25.4 if "INCHES" in args else 1.0
            continue
        if name == "SELECT_PLANE":
            plane = args.replace("CANON_PLANE_", "")
            continue
        nums = [float(v) for v in re.findall(r"[-+]?\d+\.\d+|[-+]?\d+", args)]
        if name == "SET_G5X_OFFSET":
            g5x = [v * unit for v in nums[1:4]]
            continue
        if name == "SET_G92_OFFSET":
            g92 = [v * unit for v in nums[0:3]]
            continue

        def mach(p):
            return [p[i] * unit + g5x[i] + g92[i] for i in range(3)]

        if name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED"):
            end = mach(nums[0:3])
            out.append({"kind": "rapid" if name == "STRAIGHT_TRAVERSE" else "line", "end": end,
                        "tol": 3e-4 * unit})
            pos = end
        elif name == "ARC_FEED":
            e1, e2, c1, c2, rot, ax = nums[0:6]
            if plane == "XY":
                endp, cen, axis = [e1, e2, ax], [c1, c2, None], 2
            elif plane == "YZ":
                endp, cen, axis = [ax, e1, e2], [None, c1, c2], 0
            else:  # XZ: first axis is Z
                endp, cen, axis = [e2, ax, e1], [c2, None, c1], 1
            end = mach(endp)
            cen_m = [None if cen[i] is None else cen[i] * unit + g5x[i] + g92[i] for i in range(3)]
            cen_m[axis] = pos[axis] if pos else 0.0
            out.append({"kind": "arc", "end": end, "center": cen_m, "turns": int(rot),
                        "axis": "xyz"[axis], "tol": 3e-4 * unit})
            pos = end
        elif name == "DWELL":
            out.append({"kind": "dwell", "seconds": nums[0], "tol": 3e-4 * unit})
    errors = [l for l in res.stderr.splitlines() if l.strip() and "executing" not in l]
    return out, errors, res.stdout


def frepmill_motions(frepmill, program, tbl_mm):
    cmd = [frepmill, "motions", program]
    if tbl_mm:
        cmd += ["--tools", tbl_mm]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if res.returncode != 0:
        return None, res.stderr.strip()
    return [json.loads(l) for l in res.stdout.splitlines() if l.strip()], ""


def compare(program, ref, got):
    problems = []
    if len(ref) != len(got):
        problems.append("motion count: rs274 %d, frepmill %d" % (len(ref), len(got)))
    for i, (r, g) in enumerate(zip(ref, got)):
        where = "motion %d (frepmill line %s)" % (i, g.get("line"))
        if r["kind"] != g["kind"]:
            problems.append("%s: kind rs274 %s, frepmill %s" % (where, r["kind"], g["kind"]))
            break
        tol = r["tol"]
        if r["kind"] == "dwell":
            dt = g["t"][1] - g["t"][0]
            if abs(dt - r["seconds"]) > 1e-3:
                problems.append("%s: dwell rs274 %g s, frepmill %g s" % (where, r["seconds"], dt))
            continue
        if any(abs(a - b) > tol for a, b in zip(r["end"], g["end"])):
            problems.append("%s: end rs274 %s, frepmill %s" % (where, r["end"], g["end"]))
        if r["kind"] == "arc":
            if r["turns"] != g["turns"] or r["axis"] != g["axis"]:
                problems.append("%s: turns/axis rs274 %d %s, frepmill %d %s"
                                % (where, r["turns"], r["axis"], g["turns"], g["axis"]))
            if any(abs(a - b) > tol for a, b in zip(r["center"], g["center"])):
                problems.append("%s: centre rs274 %s, frepmill %s" % (where, r["center"], g["center"]))
        if len(problems) > 10:
            break
    return problems


def main():
    args = sys.argv[1:]
    tbl_mm = None
    if "--tools" in args:
        k = args.index("--tools")
        tbl_mm = os.path.abspath(args[k + 1])
        del args[k:k + 2]
    if len(args) < 2:
        print(__doc__)
        return 2
    frepmill, programs = args[0], args[1:]
    if not shutil.which("rs274"):
        print("SKIP: rs274 not found (install Debian's linuxcnc-uspace)")
        return SKIP
    missing = [p for p in programs if not os.path.exists(p)]
    if missing:
        print("SKIP: missing programs: %s" % ", ".join(missing))
        return SKIP
    tbl_inch = None
    tmpdir = tempfile.mkdtemp()
    try:
        if tbl_mm:
            # rs274's tool table is in its machine units, inches
            tbl_inch = os.path.join(tmpdir, "tools-inch.tbl")
            with open(tbl_mm) as f, open(tbl_inch, "w") as o:
                for line in f:
                    body, sep, comment = line.partition(";")
                    words = []
                    for w in body.split():
                        if w[0] in "ZXY":
                            w = "%s%.6f" % (w[0], float(w[1:]) / 25.4)
                        words.append(w)
                    o.write(" ".join(words) + (" ;" + comment if sep else "\n"))
        failed = 0
        total = 0
        for p in programs:
            ref, errors, raw = rs274_motions(p, tbl_inch)
            got, err = frepmill_motions(frepmill, p, tbl_mm)
            if errors:
                print("FAIL %s: rs274 reported: %s" % (p, "; ".join(errors[:3])))
                failed += 1
                continue
            if got is None:
                print("FAIL %s: frepmill failed: %s" % (p, err))
                failed += 1
                continue
            problems = compare(p, ref, got)
            total += len(ref)
            if problems:
                failed += 1
                print("FAIL %s (%d rs274 motions):" % (p, len(ref)))
                for pr in problems[:10]:
                    print("   " + pr)
            else:
                print("ok   %s: %d motions agree" % (p, len(ref)))
        print("%d programs, %d motions compared, %d failed" % (len(programs), total, failed))
        return 1 if failed else 0
    finally:
        shutil.rmtree(tmpdir)


if __name__ == "__main__":
    sys.exit(main())
