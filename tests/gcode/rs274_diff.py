#!/usr/bin/env python3
"""rs274_diff.py: differential test of `frepmill motions` against LinuxCNC's
standalone interpreter `rs274 -g` (Debian's linuxcnc-uspace).

rs274 prints canonical calls (STRAIGHT_TRAVERSE, STRAIGHT_FEED, ARC_FEED,
RIGID_TAP, NURBS_FEED, DWELL, MESSAGE) with positions in the active program
coordinate system and units, and announces offsets with SET_G5X_OFFSET /
SET_G92_OFFSET / SET_XY_ROTATION and units with USE_LENGTH_UNITS. This
script converts those to machine millimetres and compares every motion's
kind, end point, arc centre, axis and turns, and the rotary axes A, B, C
(degrees, with their G5x and G92 offsets), with frepmill's JSON lines
within the precision rs274 prints (4 decimals of program units), and the
texts of (debug,...) and (msg,...) comments in order. rs274 prints no
geometry for NURBS_FEED (G5, G5.1, G5.2/G5.3): those are compared by kind
(frepmill's exact "param" motion) and the motions after them by position.

usage: rs274_diff.py FREPMILL [--linuxcnc-examples DIR [--min-examples N]] [--tools TABLE_MM.tbl]
                     [--subroutine-path DIR] [PROGRAM ...]

--linuxcnc-examples runs every LinuxCNC example program in DIR (the list
NCFILES below says, for each, the tool table it needs or why it is not
compared; a program in DIR that the list does not know fails the test, so
that the list stays complete). With --min-examples N, fewer than N example
programs compared (an emptied or partial folder) fails. PROGRAMs use TABLE (or NAME.tbl next to the
program when there is one). Tool tables are in mm; rs274 gets them converted
to its machine unit, inches.

Exit 0 when all agree, 1 on a difference. When rs274 or the example folder
is missing: exit 77 (skipped) with a message, or 1 when the environment has
CI=true or CI=1 (CI never skips; tests/support/fm_skip.py).
"""
import atexit
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from fm_skip import in_ci  # noqa: E402  (the tests' skip rule: CI=true or CI=1)

SKIP = 77
CALL = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$")
HERE = os.path.dirname(os.path.abspath(__file__))
TABLES = os.path.join(HERE, "ncfiles")


def run_all(tools=None, ini=None):
    return {"tools": tools, "ini": ini}


def excluded(reason):
    return {"excluded": reason}


# Every program at the top of LinuxCNC's ncfiles folder. Tool tables are in
# tests/gcode/ncfiles (mm); None means rs274's built-in table (sim.tbl).
LATHE = "lathe program (G7/G8 diameter mode, G70-G72/G76 lathe cycles or lathe tool orientations)"
PROBE = "probes (G38.x): rs274's probe stub returns a fixed result, not a contact"
NCFILES = {
    "3D_Chips.ngc": run_all(),
    "3dtest.ngc": run_all(),
    "arcspiral.ngc": run_all(),
    "b-index.ngc": run_all(),
    "cds.ngc": run_all(),
    "comp-g1.ngc": run_all("comp_1in.tbl"),
    "comp.ngc": run_all(),
    "comp311.ngc": run_all("comp_1in.tbl"),
    "comp311_2.ngc": run_all("comp_1in.tbl"),
    "cone.ngc": excluded("moves the W axis, which rs274 refuses (\"Bad character 'w' used\": its "
                         "machine is XYZABC); a 5-axis program for issue 17"),
    "daisy.ngc": run_all(),
    "factorial.ngc": run_all(),
    "flowsnake.ngc": run_all(),
    "g20sub.ngc": run_all(),
    "g76.ngc": excluded(LATHE + "; also rs274 refuses its G41 entry move with its tools"),
    "g881.ngc": run_all(),
    "g881min.ngc": run_all(),
    "g882.ngc": run_all(),
    "gmoccapy_2_tools_with_cutter_radius_compensation.ngc": run_all(),
    "gridprobe.ngc": excluded(PROBE),
    "hole-circle.ngc": run_all(),
    "increment.ngc": excluded("a subroutine file without M2 or %: rs274 refuses to run it alone "
                              "(\"File ended with no percent sign or program end\")"),
    "lathe-g76.ngc": excluded(LATHE),
    "lathe_g70_71_demo.ngc": excluded(LATHE),
    "lathe_g7x_face_boring.ngc": excluded(LATHE),
    "lathe_g7x_quadrants.ngc": excluded(LATHE),
    "lathe_pawn.ngc": excluded(LATHE),
    "lathecomp.ngc": excluded(LATHE),
    "m250.ngc": run_all(),
    "m61demo.ngc": run_all(),
    "m6demo.ngc": run_all(),
    "m6remap.ngc": run_all(),
    "m70m72-demo.ngc": run_all(),
    "m73-demo.ngc": run_all(),
    "m75.ngc": run_all(),
    "m76.ngc": run_all(),
    "mmount.ngc": run_all("mmount.tbl"),
    "nestedcall.ngc": excluded("rs274 refuses it: 'O<g20sub> callsub' is not an O-word keyword"),
    "offsets.ngc": run_all("tools_1_to_4.tbl"),
    "plasmatest.ngc": run_all(),
    "polar.ngc": run_all(),
    "probe-hole.ngc": excluded(PROBE + "; also a subroutine file without M2 or %"),
    "retval.ngc": run_all(),
    "roparams.ngc": run_all(),
    "skeleton.ngc": run_all(),
    "smartprobe.ngc": excluded(PROBE),
    "spiral.ngc": run_all(),
    "systems.ngc": run_all(),
    "testm6fail.ngc": run_all(),
    "threading.ngc": run_all(),
    "tool-length-probe.ngc": excluded(PROBE + "; rs274 also stops at it (\"Start point too close "
                                      "to probe point\")"),
    "toplevel.ngc": run_all(),
    "tort.ngc": run_all(),
    "touchoff.ngc": run_all(),
    "useful-subroutines.ngc": run_all(),
    "x-trim.ngc": excluded(PROBE + " (through touchoff.ngc, found on the subroutine path)"),
}
# Sub-folders hold subroutine libraries for GUIs, remapping and probing
# screens (called by a configured LinuxCNC, not programs of their own).
NCFOLDERS_REASON = "subroutine libraries of GUIs, remaps and probe screens, not programs"

INIS = {}


def rot(x, y, deg):
    t = math.radians(deg)
    return x * math.cos(t) - y * math.sin(t), x * math.sin(t) + y * math.cos(t)


# rs274 keeps its tool table in $HOME/.tool.mmap (LinuxCNC's tooldata_mmap):
# two rs274 processes with one HOME (this test beside another checkout's, or
# a developer's LinuxCNC) overwrite each other's tools ("Requested tool 4
# not found" on offsets.ngc, seen twice). Each run of this script gets a
# HOME of its own.
RS274_HOME = None


def rs274_env():
    global RS274_HOME
    if RS274_HOME is None:
        RS274_HOME = tempfile.mkdtemp(prefix="fm-rs274-home-")
        atexit.register(shutil.rmtree, RS274_HOME, True)
    return dict(os.environ, HOME=RS274_HOME)


def rs274_run(program, tbl_inch, ini_path):
    cmd = ["rs274", "-g"]
    if tbl_inch:
        cmd += ["-t", tbl_inch]
    if ini_path:
        cmd += ["-i", ini_path]
    cmd.append(program)
    # M0/M1 wait for a key press: feed it newlines
    res = subprocess.run(cmd, input="\n" * 1000, capture_output=True, text=True, timeout=300,
                         cwd=os.path.dirname(os.path.abspath(program)), env=rs274_env())
    unit = 1.0
    g5x = [0.0, 0.0, 0.0]
    g92 = [0.0, 0.0, 0.0]
    rotation = 0.0
    g5x_abc = [0.0, 0.0, 0.0]
    g92_abc = [0.0, 0.0, 0.0]
    plane = "XY"
    pos = [0.0, 0.0, 0.0]  # machine mm of the last point
    out, messages = [], []

    def mach(p):
        x, y = rot(p[0] * unit + g92[0], p[1] * unit + g92[1], rotation)
        return [x + g5x[0], y + g5x[1], p[2] * unit + g92[2] + g5x[2]]

    def abc(v):
        # degrees: no unit conversion
        return [v[i] + g5x_abc[i] + g92_abc[i] for i in range(3)]

    for line in res.stdout.splitlines():
        m = CALL.match(line)
        if not m:
            continue
        name, args = m.group(1), m.group(2)
        if name == "MESSAGE":
            messages.append(args[1:-1] if args.startswith('"') and args.endswith('"') else args)
            continue
        if name == "USE_LENGTH_UNITS":
            unit = 25.4 if "INCHES" in args else 1.0
            continue
        if name == "SELECT_PLANE":
            plane = args.replace("CANON_PLANE_", "")
            continue
        nums = [float(v) for v in re.findall(r"[-+]?\d+\.\d+|[-+]?\d+", args)]
        if name == "SET_G5X_OFFSET":
            g5x = [v * unit for v in nums[1:4]]
            g5x_abc = nums[4:7]
        elif name == "SET_G92_OFFSET":
            g92 = [v * unit for v in nums[0:3]]
            g92_abc = nums[3:6]
        elif name == "SET_XY_ROTATION":
            rotation = nums[0]
        elif name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED"):
            end = mach(nums[0:3])
            out.append({"kind": "rapid" if name == "STRAIGHT_TRAVERSE" else "line", "end": end,
                        "rotary": abc(nums[3:6]), "tol": 3e-4 * unit})
            pos = end
        elif name == "RIGID_TAP":
            # in to the point, then out to where it started
            start = pos
            out.append({"kind": "line", "end": mach(nums[0:3]), "tol": 3e-4 * unit})
            out.append({"kind": "line", "end": start, "tol": 3e-4 * unit})
        elif name == "NURBS_FEED":
            out.append({"kind": "param", "tol": 3e-4 * unit})
            pos = None
        elif name == "ARC_FEED":
            e1, e2, c1, c2, turns, ax = nums[0:6]
            if plane == "XY":
                endp, cen, axis = [e1, e2, ax], [c1, c2, 0.0], 2
            elif plane == "YZ":
                endp, cen, axis = [ax, e1, e2], [0.0, c1, c2], 0
            else:  # XZ: first axis is Z
                endp, cen, axis = [e2, ax, e1], [c2, 0.0, c1], 1
            end = mach(endp)
            cen_m = mach(cen)
            cen_m[axis] = pos[axis] if pos else float("nan")
            out.append({"kind": "arc", "end": end, "center": cen_m, "turns": int(turns),
                        "axis": "xyz"[axis], "rotary": abc(nums[6:9]), "tol": 3e-4 * unit})
            pos = end
        elif name == "DWELL":
            out.append({"kind": "dwell", "seconds": nums[0], "tol": 3e-4 * unit})
    errors = [l for l in res.stderr.splitlines() if l.strip() and "executing" not in l]
    return out, messages, errors


def frepmill_run(frepmill, program, tbl_mm, subpath):
    cmd = [frepmill, "motions", program, "--messages"]
    if tbl_mm:
        cmd += ["--tools", tbl_mm]
    if subpath:
        cmd += ["--subroutine-path", subpath]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if res.returncode != 0:
        return None, None, res.stderr.strip()
    motions, messages = [], []
    for l in res.stdout.splitlines():
        if not l.strip():
            continue
        o = json.loads(l)
        if o.get("kind") == "message":
            messages.append(o["text"])
        else:
            motions.append(o)
    return motions, messages, ""


def compare(ref, got, ref_msgs, got_msgs):
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
        if r["kind"] == "param":
            continue
        if any(abs(a - b) > tol for a, b in zip(r["end"], g["end"])):
            problems.append("%s: end rs274 %s, frepmill %s" % (where, r["end"], g["end"]))
        g_abc = g.get("rotary", [0.0, 0.0, 0.0])
        if "rotary" in r and any(abs(a - b) > 3e-4 for a, b in zip(r["rotary"], g_abc)):
            problems.append("%s: A B C rs274 %s, frepmill %s" % (where, r["rotary"], g_abc))
        if r["kind"] == "arc":
            if r["turns"] != g["turns"] or r["axis"] != g["axis"]:
                problems.append("%s: turns/axis rs274 %d %s, frepmill %d %s"
                                % (where, r["turns"], r["axis"], g["turns"], g["axis"]))
            if any(not abs(a - b) <= tol for a, b in zip(r["center"], g["center"])):
                problems.append("%s: centre rs274 %s, frepmill %s" % (where, r["center"], g["center"]))
        if len(problems) > 10:
            break
    if ref_msgs != got_msgs:
        for k in range(max(len(ref_msgs), len(got_msgs))):
            a = ref_msgs[k] if k < len(ref_msgs) else None
            b = got_msgs[k] if k < len(got_msgs) else None
            if a != b:
                problems.append("message %d: rs274 %r, frepmill %r" % (k, a, b))
                break
        if len(ref_msgs) != len(got_msgs):
            problems.append("message count: rs274 %d, frepmill %d" % (len(ref_msgs), len(got_msgs)))
    return problems


def inch_table(tbl_mm, tmpdir):
    """rs274's tool table is in its machine unit, inches. A fresh copy for
    every run: rs274 writes the table back after G10 L1 and tool changes."""
    fd, out = tempfile.mkstemp(suffix=".tbl", dir=tmpdir)
    os.close(fd)
    with open(tbl_mm) as f, open(out, "w") as o:
        for line in f:
            body, sep, comment = line.partition(";")
            words = []
            for w in body.split():
                if w[0] in "ZXYD":
                    w = "%s%.8f" % (w[0], float(w[1:]) / 25.4)
                words.append(w)
            if words:
                o.write(" ".join(words) + (" ;" + comment if sep else "\n"))
    return out


def missing(what):
    if in_ci():
        print("FAIL: %s (CI never skips)" % what)
        return 1
    print("SKIP: %s" % what)
    return SKIP


def main():
    args = sys.argv[1:]
    opts = {"--tools": None, "--linuxcnc-examples": None, "--subroutine-path": None, "--min-examples": None}
    for k in list(opts):
        if k in args:
            i = args.index(k)
            if i + 1 >= len(args):
                print(__doc__)
                return 2
            opts[k] = args[i + 1] if k == "--min-examples" else os.path.abspath(args[i + 1])
            del args[i:i + 2]
    if not args:
        print(__doc__)
        return 2
    frepmill, programs = args[0], args[1:]
    if not shutil.which("rs274"):
        return missing("rs274 not found (install Debian's linuxcnc-uspace)")
    ncdir = opts["--linuxcnc-examples"]
    if ncdir and not os.path.isdir(ncdir):
        return missing("LinuxCNC's example folder %s not found (linuxcnc-uspace)" % ncdir)
    gone = [p for p in programs if not os.path.exists(p)]
    if gone:
        print("FAIL: missing programs: %s" % ", ".join(gone))
        return 1

    # (program, tool table mm or None, ini text or None, subroutine path or None)
    jobs = []
    failed = 0
    if ncdir:
        present = sorted(f for f in os.listdir(ncdir) if f.endswith(".ngc"))
        unknown = [f for f in present if f not in NCFILES]
        if unknown:
            print("FAIL: example programs the list NCFILES does not classify: %s" % ", ".join(unknown))
            failed += 1
        for f in present:
            entry = NCFILES.get(f)
            if not entry:
                continue
            if "excluded" in entry:
                print("excluded %s: %s" % (f, entry["excluded"]))
                continue
            tbl = os.path.join(TABLES, entry["tools"] or "sim.tbl")
            ini = INIS.get(entry["ini"]) if entry["ini"] else None
            jobs.append((os.path.join(ncdir, f), tbl, ini, ncdir))
        absent = [f for f in NCFILES if f not in present]
        if absent:
            print("note: listed examples not installed here: %s" % ", ".join(absent))
        subdirs = sorted(d for d in os.listdir(ncdir) if os.path.isdir(os.path.join(ncdir, d)))
        print("not compared: the sub-folders %s (%s)" % (", ".join(subdirs), NCFOLDERS_REASON))
    for p in programs:
        p = os.path.abspath(p)
        own = os.path.splitext(p)[0] + ".tbl"
        jobs.append((p, own if os.path.exists(own) else opts["--tools"], None,
                     opts["--subroutine-path"]))

    tmpdir = tempfile.mkdtemp()
    try:
        total = examples = 0
        for program, tbl, ini_text, subpath in jobs:
            ini = None
            if ini_text or subpath:
                ini = os.path.join(tmpdir, "rs274.ini")
                with open(ini, "w") as o:
                    o.write(ini_text or "")
                    if subpath:
                        o.write("[RS274NGC]\nSUBROUTINE_PATH = %s\n" % subpath)
            ref, ref_msgs, errors = rs274_run(program, inch_table(tbl, tmpdir) if tbl else None, ini)
            got, got_msgs, err = frepmill_run(frepmill, program, tbl, subpath)
            name = os.path.basename(program)
            if errors:
                print("FAIL %s: rs274 reported: %s" % (name, "; ".join(errors[:3])))
                failed += 1
                continue
            if got is None:
                print("FAIL %s: frepmill failed: %s" % (name, err))
                failed += 1
                continue
            problems = compare(ref, got, ref_msgs, got_msgs)
            total += len(ref)
            if ncdir and os.path.dirname(program) == ncdir:
                examples += 1
            if problems:
                failed += 1
                print("FAIL %s (%d rs274 motions):" % (name, len(ref)))
                for pr in problems[:10]:
                    print("   " + pr)
            else:
                print("ok   %s: %d motions, %d messages agree" % (name, len(ref), len(ref_msgs)))
        print("%d programs, %d motions compared, %d failed" % (len(jobs), total, failed))
        if ncdir:
            print("%d LinuxCNC example programs compared" % examples)
        if opts["--min-examples"] is not None and examples < int(opts["--min-examples"]):
            print("FAIL: %d LinuxCNC example programs compared, fewer than --min-examples %s" %
                  (examples, opts["--min-examples"]))
            failed += 1
        return 1 if failed else 0
    finally:
        shutil.rmtree(tmpdir)


if __name__ == "__main__":
    sys.exit(main())
