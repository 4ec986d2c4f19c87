#!/usr/bin/env python3
"""bench_cam.py: frepmill simulate on programs written by CAM systems, with CAMotics' camsim beside it when its
binary is given (issue 37). Prints figures; never a test, not registered with ctest.

Cases (bench/cam/README.md says how each program was written):
  the six programs of bench/cam/ (FreeCAD 0.20 Path: a pocket raster with a 1 mm flat, adaptive clearing, a plate's
  outline, holes and bore, a V-carved text; LinuxCNC image-to-gcode: a cameo raster finish with a 1 mm flat, a 3D
  relief with a 3 mm ball) at each --voxel (default 0.2 mm);
  issue 37's two earlier camsim cases: LinuxCNC's 3D_Chips.ngc (read where linuxcnc-uspace installs it, never
  copied) at 0.2 mm with a 25 mm ball, and the demo's 300-move pocket (deploy/demo/pocket.ngc, 284 motions: zigzag,
  contour, helical entry, circular pocket, four drilled holes, chamfer) at 0.1 mm.

Each row: the program's lines, frepmill's motions, wall and CPU seconds (user + sys) and peak RSS of the process
(from /usr/bin/time -v), the removed volume (the report's removed_volume_mm3). With camsim (--camsim PATH or
FM_CAMSIM=PATH) each case is also run as `camsim --threads 2 --resolution VOXEL PROJECT.camotics OUT.stl` in the
same run, on a CAMotics project written for the same stock, tools and resolution, and the row gets camsim's wall
and RSS and the ratios (ours faster by Nx = camsim wall / ours, leaner by Nx = camsim RSS / ours).

Usage (from the repository root, after a release build):
  bench/cam/bench_cam.py [--voxel MM]... [--camsim PATH] [--frepmill PATH] [--only NAME]... [--keep DIR]
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
CHIPS = "/usr/share/linuxcnc/ncfiles/3D_Chips.ngc"

# frepmill's tools (bench/cam/tools.json, deploy/demo/tools.json) as CAMotics models them: CAMotics' shapes are
# cylindrical, ballnose (a ball under a cylinder: "length" is the cylinder, the flutes reach length + radius),
# conical and snubnose (a cone with a flat tip); it has no drill point, so a drill is its cylinder (flat bottom).
CAMOTICS_TOOLS = {
    "bench/cam": {
        1: {"shape": "cylindrical", "diameter": 1, "length": 4, "description": "1 mm flat"},
        2: {"shape": "cylindrical", "diameter": 4, "length": 12, "description": "4 mm flat"},
        3: {"shape": "cylindrical", "diameter": 5, "length": 30, "description": "5 mm drill (flat bottom)"},
        4: {"shape": "cylindrical", "diameter": 6, "length": 20, "description": "6 mm flat"},
        # 60 degrees included, 0.2 mm tip: the cone from the tip to the full diameter is (3 - 0.1) / tan 30 high
        5: {"shape": "snubnose", "diameter": 6, "snub_diameter": 0.2, "length": 5.0229, "description": "60 deg V-bit"},
        6: {"shape": "ballnose", "diameter": 3, "length": 10.5, "description": "3 mm ball"},
    },
    "demo": {
        1: {"shape": "cylindrical", "diameter": 6, "length": 20, "description": "6 mm flat"},
        2: {"shape": "cylindrical", "diameter": 5, "length": 30, "description": "5 mm drill (flat bottom)"},
        # 90 degrees included, 0.2 mm tip
        3: {"shape": "snubnose", "diameter": 6, "snub_diameter": 0.2, "length": 2.9, "description": "90 deg V-bit"},
    },
    # issue 37's 3D_Chips case: a 25 mm ball whose flutes reach 52.5 mm (CAMotics: 40 mm of cylinder above it)
    "chips": {1: {"shape": "ballnose", "diameter": 25, "length": 40, "description": "25 mm ball"}},
}
CHIPS_TOOLS = {"units": "mm", "tools": [
    {"number": 1, "shape": "ball", "diameter": 25, "flute_length": 52.5, "length": 80, "shank_diameter": 25,
     "center_cutting": True, "comment": "25 mm ball as in bench/cam's CAMotics project"}]}

# name, program (relative to the repository root, or absolute), stock box, tools key, the tool in the spindle at
# the start (programs without M6), fixed voxel (None: every --voxel)
CASES = [
    ("freecad_pocket_raster", "bench/cam/freecad_pocket_raster.ngc", (0, 0, -10, 70, 62, 0), "bench/cam", None, None),
    ("freecad_adaptive", "bench/cam/freecad_adaptive.ngc", (0, 0, -15, 90, 70, 0), "bench/cam", None, None),
    ("freecad_plate_outline", "bench/cam/freecad_plate_outline.ngc", (0, 0, -10, 100, 60, 0), "bench/cam", None, None),
    ("freecad_vcarve_text", "bench/cam/freecad_vcarve_text.ngc", (0, 0, -8, 110, 36, 0), "bench/cam", None, None),
    ("i2g_cameo_raster_1mm", "bench/cam/i2g_cameo_raster_1mm.ngc", (0, 0, -4, 57, 44, 0), "bench/cam", 1, None),
    ("i2g_relief_ball3", "bench/cam/i2g_relief_ball3.ngc", (0, 0, -9, 84, 64, 0), "bench/cam", 6, None),
    ("3D_Chips", CHIPS, (-50, -50, -50, 50, 50, 0), "chips", None, 0.2),
    ("demo pocket", "deploy/demo/pocket.ngc", (0, 0, -30, 100, 60, 0), "demo", None, 0.1),
]


def parse_time_v(text):
    """Wall s, CPU s (user + sys) and peak RSS in MB from /usr/bin/time -v's report."""
    def field(name):
        m = re.search(r"^\s*" + re.escape(name) + r":\s*(\S+)\s*$", text, re.M)
        if not m:
            raise ValueError("/usr/bin/time -v printed no '%s'" % name)
        return m.group(1)
    wall = 0.0
    for part in field("Elapsed (wall clock) time (h:mm:ss or m:ss)").split(":"):
        wall = wall * 60 + float(part)
    cpu = float(field("User time (seconds)")) + float(field("System time (seconds)"))
    rss_mb = int(field("Maximum resident set size (kbytes)")) / 1024.0
    return wall, cpu, rss_mb


def timed(cmd, cwd):
    """Runs cmd under /usr/bin/time -v; returns (exit status, wall, cpu, rss_mb, its own stderr's tail)."""
    proc = subprocess.run(["/usr/bin/time", "-v"] + cmd, cwd=cwd, stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True)
    err = proc.stderr
    cut = err.find("\tCommand being timed:")
    wall, cpu, rss = parse_time_v(err[cut:] if cut >= 0 else err)
    own = (err[:cut] if cut >= 0 else "").strip().splitlines()
    return proc.returncode, wall, cpu, rss, own[-3:]


def count_lines(path):
    with open(path, "rb") as f:
        return sum(1 for _ in f)


def camotics_project(folder, program, box, tools_key, initial_tool, voxel):
    """A CAMotics project (its JSON .camotics form) for the same program, stock box, tools and resolution."""
    tools = {}
    if initial_tool is not None:
        # a program without M6 (image-to-gcode's): the only tool, as 0 and 1 whichever CAMotics starts with
        only = dict(CAMOTICS_TOOLS[tools_key][initial_tool], units="metric")
        tools = {"0": only, "1": only}
    else:
        for number, tool in CAMOTICS_TOOLS[tools_key].items():
            tools[str(number)] = dict(tool, units="metric")
    link = os.path.join(folder, "program.ngc")  # the program itself, not a copy
    os.symlink(os.path.abspath(program), link)
    project = {"units": "metric", "resolution-mode": "manual", "resolution": voxel, "tools": tools,
               "workpiece": {"automatic": False, "margin": 0,
                             "bounds": {"min": list(box[:3]), "max": list(box[3:])}},
               "files": ["program.ngc"]}
    path = os.path.join(folder, "project.camotics")
    with open(path, "w") as f:
        json.dump(project, f, indent=1)
    return path


def run_case(args, case, voxel, work):
    name, program, box, tools_key, initial_tool, _ = case
    program = program if os.path.isabs(program) else os.path.join(ROOT, program)
    row = {"name": name, "voxel": voxel}
    if not os.path.exists(program):
        row["skipped"] = "%s not found" % program
        return row
    folder = tempfile.mkdtemp(prefix="case-", dir=work)
    if tools_key == "chips":
        tools = os.path.join(folder, "tools.json")
        with open(tools, "w") as f:
            json.dump(CHIPS_TOOLS, f)
    elif tools_key == "demo":
        tools = os.path.join(ROOT, "deploy", "demo", "tools.json")
    else:
        tools = os.path.join(HERE, "tools.json")
    report = os.path.join(folder, "report.json")
    cmd = [args.frepmill, "simulate", program, "--stock", "box:" + ",".join("%g" % v for v in box),
           "--tools", tools, "--voxel", "%g" % voxel, "--report", report]
    if initial_tool is not None:
        cmd += ["--initial-tool", str(initial_tool)]
    status, wall, cpu, rss, tail = timed(cmd, ROOT)
    if status != 0:
        row["error"] = "frepmill exit %d: %s" % (status, " | ".join(tail))
        return row
    with open(report) as f:
        rep = json.load(f)
    row.update(lines=count_lines(program), motions=rep["motions"], wall=wall, cpu=cpu, rss=rss,
               removed=rep["removed_volume_mm3"], uncertain=rep.get("voxels_uncertain", 0))
    if args.camsim:
        project = camotics_project(folder, program, box, tools_key, initial_tool, voxel)
        stl = os.path.join(folder, "camsim.stl")
        status, cwall, ccpu, crss, ctail = timed(
            [args.camsim, "--threads", "2", "--resolution", "%g" % voxel, project, stl], folder)
        if status != 0:
            row["camsim_error"] = "camsim exit %d: %s" % (status, " | ".join(ctail))
        else:
            row.update(camsim_wall=cwall, camsim_cpu=ccpu, camsim_rss=crss)
    if not args.keep:
        shutil.rmtree(folder, ignore_errors=True)
    return row


def print_row(row, camsim):
    head = "| %s | %g |" % (row["name"], row["voxel"])
    if "skipped" in row or "error" in row:
        print(head + " %s |" % row.get("skipped", row.get("error")))
        return
    line = head + " %d | %d | %.2f | %.2f | %.0f | %.1f | %d |" % (
        row["lines"], row["motions"], row["wall"], row["cpu"], row["rss"], row["removed"], row["uncertain"])
    if camsim:
        if "camsim_error" in row:
            line += " %s | | | |" % row["camsim_error"]
        else:
            line += " %.2f | %.0f | %.1fx | %.1fx |" % (row["camsim_wall"], row["camsim_rss"],
                                                       row["camsim_wall"] / row["wall"],
                                                       row["camsim_rss"] / row["rss"])
    print(line, flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--voxel", type=float, action="append", help="voxel edge in mm (repeatable; default 0.2)")
    ap.add_argument("--camsim", default=os.environ.get("FM_CAMSIM"), help="CAMotics' camsim (or FM_CAMSIM)")
    ap.add_argument("--frepmill", default=os.path.join(ROOT, "build", "release", "daemon", "frepmill"))
    ap.add_argument("--only", action="append", help="run only this case (repeatable)")
    ap.add_argument("--keep", help="keep each case's reports and CAMotics project in this folder")
    args = ap.parse_args()
    voxels = args.voxel or [0.2]
    if not os.access(args.frepmill, os.X_OK):
        sys.exit("bench_cam: %s is not an executable: build it (cmake --build build/release --target frepmill) "
                 "or give --frepmill" % args.frepmill)
    if args.camsim and not os.access(args.camsim, os.X_OK):
        sys.exit("bench_cam: camsim %s is not an executable" % args.camsim)
    work = args.keep or tempfile.mkdtemp(prefix="bench_cam-")
    os.makedirs(work, exist_ok=True)

    cols = "| program | voxel mm | lines | motions | wall s | CPU s | peak RSS MB | removed mm3 | uncertain |"
    rule = "|---|---|---|---|---|---|---|---|---|"
    if args.camsim:
        cols += " camsim wall s | camsim RSS MB | ours faster | ours leaner |"
        rule += "---|---|---|---|"
    print(cols)
    print(rule, flush=True)
    for case in CASES:
        if args.only and case[0] not in args.only:
            continue
        for voxel in ([case[5]] if case[5] else voxels):
            print_row(run_case(args, case, voxel, work), bool(args.camsim))
    if not args.camsim:
        print("\ncamsim was not given (--camsim PATH or FM_CAMSIM=PATH): frepmill's figures only.")
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
