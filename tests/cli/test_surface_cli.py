"""test_surface_cli.py: frepmill options the README lists, each against values
computed here by hand:

- `frepmill eval` (README, docs/hf.md): a sphere's value, gradient and
  interval enclosure, a second object picked by --model, a parameter set by
  --param, through HyperFun's sphere R^2 - |x - c|^2 and the R-function
  intersection f1 + f2 - sqrt(f1^2 + f2^2) (docs/hf.md); bad input exits 2
  or 4;
- `--dialect` for motions, check and simulate (docs/gcode.md): a Fanuc
  WHILE ... DO1 / END1 loop with #1 and a word without a decimal point
  (Y5000 is 5 mm) gives the hand-listed motions and the slot's volume under
  fanuc, and under linuxcnc an error at the WHILE line, exit 2;
- `--design` and `--tolerance` (README's deviation picture, docs/simulate.md):
  a 1.5 mm deep slot across a block whose design is the block faced 1 mm
  down: a gouge 0.5 mm deep of 40 x 6 x 0.5 = 120 mm^3 blamed on the slot's
  line (6, not the plunge outside the block) and tool, excess 1 mm thick of 40 x 4 x 1 = 160 mm^3 in two regions
  either side of the slot; a tolerance of 0.6 mm hides the gouge but not the
  excess, one of 1.2 mm both (no region, and the deepest deviations stay 0.5
  and 1 mm: at tolerances above the stock's band the inside of the 1 mm
  excess was reported as two regions 1.75 mm deep);
- `check --clearance` (docs/check.md): a plunge that brings the holder
  (40 mm above the tip) to 3 mm over the stock is clean by default and with
  --clearance 2, a holder warning (penetration 0) first when the tip is at
  z = 4 - 40 with --clearance 4; 1 mm into the stock it is an error of 1 mm.
Usage: test_surface_cli.py FREPMILL"""
import json
import math
import os
import sys
import tempfile

from cli_util import check, run, summary, write_box_stl

HF = """ball(x[3], a[1])
{
  array center[3];
  center = [1, 2, 3];
  ball = hfSphere(x, center, 2);
}
shell(x[3], a[1])
{
  array center[3];
  center = [1, 2, 3];
  shell = hfSphere(x, center, a[1]) & -hfSphere(x, center, 1);
}
"""

FANUC = """O1000
G21 G90
T1 M6
S1000 M3
G0 X0. Y5000 Z5.
G1 Z-1. F300.
#1=1
WHILE [#1 LE 3] DO1
G1 X[#1*10.]
#1=#1+1
END1
G0 Z5.
M30
"""

TOOLS = {"units": "mm", "tools": [
    {"number": 1, "shape": "flat", "diameter": 6, "flute_length": 40, "length": 40,
     "holder": [{"diameter": 20, "length": 30}]}]}


def r_intersection(f1, f2):
    return f1 + f2 - math.sqrt(f1 * f1 + f2 * f2)


def eval_tests(frepmill, tmp):
    model = os.path.join(tmp, "model.hf")
    with open(model, "w") as f:
        f.write(HF)
    # ball: f = 4 - |p - c|^2, grad -2 (p - c)
    rc, out, err = run(frepmill, "eval", model, "1", "2", "3.5", "--model", "ball", "--grad")
    lines = out.split("\n")
    check(rc == 0 and abs(float(lines[0]) - 3.75) < 1e-12, "eval ball at (1, 2, 3.5): 4 - 0.25 = 3.75 (%r)" % out)
    grad = [float(v) for v in lines[1].split()[1:]] if len(lines) > 1 and lines[1].startswith("grad") else []
    check(len(grad) == 4 and max(abs(a - b) for a, b in zip(grad, (0, 0, -1, 0))) < 1e-12,
          "eval --grad: (0, 0, -1, 0) (%s)" % grad)
    # Over [0,1]^3: |p - c|^2 in [0+1+4, 1+4+9] = [5, 14], so f in [-10, -1];
    # an enclosure contains that (interval arithmetic on separable squares is exact).
    rc, out, err = run(frepmill, "eval", model, "0", "0", "0", "--model", "ball", "--interval",
                       "0", "1", "0", "1", "0", "1")
    lines = out.split("\n")
    iv = [float(v) for v in lines[1].split()[1:]] if len(lines) > 1 and lines[1].startswith("interval") else []
    check(rc == 0 and float(lines[0]) == -10 and len(iv) == 2 and iv[0] <= -10 and iv[1] >= -1
          and iv[0] >= -10 - 1e-9 and iv[1] <= -1 + 1e-9, "eval --interval over [0,1]^3: [-10, -1] (%s)" % iv)
    # shell (the last object, the default): R-intersection of a1^2 - d2 and d2 - 1
    for a1, p in ((0, (1, 2, 4.5)), (3, (1, 2, 4.5)), (3, (1, 2, 3.5))):
        d2 = sum((a - b) ** 2 for a, b in zip(p, (1, 2, 3)))
        want = r_intersection(a1 * a1 - d2, d2 - 1)
        args = [frepmill, "eval", model, *map(str, p)] + (["--param", "a1=%g" % a1] if a1 else [])
        rc, out, err = run(*args)
        got = float(out.split("\n")[0]) if rc == 0 and out else float("nan")
        check(abs(got - want) < 1e-9, "eval shell at %s with a1 = %g: %.9f (hand: %.9f)" % (p, a1, got, want))
    # d f / d z at (1, 2, 3.5), a1 = 3: chain rule through the R-function
    f1, f2 = 9 - 0.25, 0.25 - 1
    s = math.hypot(f1, f2)
    want = (1 - f1 / s) * -1.0 + (1 - f2 / s) * 1.0
    rc, out, err = run(frepmill, "eval", model, "1", "2", "3.5", "--param", "a1=3", "--grad")
    lines = out.split("\n")
    grad = [float(v) for v in lines[1].split()[1:]] if len(lines) > 1 and lines[1].startswith("grad") else []
    check(len(grad) == 4 and abs(grad[2] - want) < 1e-9 and abs(grad[0]) < 1e-12,
          "eval shell --grad: df/dz %.9f (hand: %.9f)" % (grad[2] if grad else float("nan"), want))
    rc, out, err = run(frepmill, "eval", os.path.join(tmp, "missing.hf"), "0", "0", "0")
    check(rc == 4 and "missing.hf" in err, "eval of a missing file: exit 4, names it (%d)" % rc)
    rc, out, err = run(frepmill, "eval", model, "0", "0")
    check(rc == 2 and "usage" in err, "eval without Z: exit 2 and the usage (%d)" % rc)
    rc, out, err = run(frepmill, "eval", model, "0", "0", "0", "--model", "cube")
    check(rc != 0 and "cube" in err, "eval --model of an unknown object: refused, names it (%d %r)" % (rc, err))


def dialect_tests(frepmill, tmp, tools):
    program = os.path.join(tmp, "O1000.nc")
    with open(program, "w") as f:
        f.write(FANUC)
    rc, out, err = run(frepmill, "motions", program, "--dialect", "fanuc")
    motions = [json.loads(line) for line in out.splitlines() if line.strip()] if rc == 0 else []
    want = [("rapid", 5, (0, 5, 5)), ("line", 6, (0, 5, -1)), ("line", 9, (10, 5, -1)),
            ("line", 9, (20, 5, -1)), ("line", 9, (30, 5, -1)), ("rapid", 12, (30, 5, 5))]
    got = [(m["kind"], m["line"], tuple(round(v, 6) for v in m["end"])) for m in motions]
    check(rc == 0 and got == want, "motions --dialect fanuc: the loop's three passes (%s)" % got)
    for command in ("motions", "check", "simulate"):
        args = [frepmill, command, program, "--dialect", "linuxcnc"]
        if command != "motions":
            args += ["--stock", "box:0,0,-10,40,10,0", "--tools", tools]
        rc, out, err = run(*args)
        check(rc == 2 and (program + ":1:") in err,
              "%s --dialect linuxcnc: exit 2 at the Fanuc O word, line 1 (%d %r)" % (command, rc, err.strip()[:160]))
    # without O1000 LinuxCNC stops at the WHILE (line 8 of the file, 7 here)
    body = os.path.join(tmp, "loop.ngc")
    with open(body, "w") as f:
        f.write(FANUC.split("\n", 1)[1])
    rc, out, err = run(frepmill, "motions", body, "--dialect", "linuxcnc")
    check(rc == 2 and (body + ":7:") in err, "motions --dialect linuxcnc: exit 2 at WHILE, line 7 (%r)" %
          err.strip()[:160])
    rc, out, err = run(frepmill, "motions", body)
    check(rc == 2 and (body + ":7:") in err, "motions without --dialect is LinuxCNC: exit 2 at line 7")
    rc, out, err = run(frepmill, "check", program, "--dialect", "fanuc", "--stock", "box:0,0,-10,40,10,0",
                       "--tools", tools)
    report = json.loads(out) if rc in (0, 1) and out.strip() else None
    check(rc == 0 and report and report["findings"] == [], "check --dialect fanuc: clean, exit 0 (%d)" % rc)
    # The slot: tool centre from x = 0 to 30 at y = 5, 1 mm deep, 6 mm wide:
    # 30 x 6 x 1 plus the half disc beyond x = 30 (the one at x = 0 is
    # outside the block).
    rep_path = os.path.join(tmp, "fanuc.json")
    rc, out, err = run(frepmill, "simulate", program, "--dialect", "fanuc", "--stock", "box:0,0,-10,40,10,0",
                       "--tools", tools, "--voxel", "0.1", "--report", rep_path)
    want = 30 * 6 * 1 + math.pi * 9 / 2
    if check(rc == 0, "simulate --dialect fanuc: exit 0 (%r)" % err.strip()[-200:]):
        with open(rep_path) as f:
            removed = json.load(f)["removed_volume_mm3"]
        check(abs(removed - want) <= 0.005 * want,
              "simulate --dialect fanuc removed %.2f mm^3, slot %.2f mm^3 (0.5%%)" % (removed, want))


def design_tests(frepmill, tmp, tools):
    program = os.path.join(tmp, "slot.ngc")
    with open(program, "w") as f:
        f.write("G21 G90\nT1 M6\nS1000 M3\nG0 X-5 Y5 Z5\nG1 Z-1.5 F300\nG1 X45\nG0 Z5\nM2\n")
    design = os.path.join(tmp, "faced.stl")
    write_box_stl(design, (0, 0, -10), (40, 10, -1))
    voxel = 0.25
    for tol in (0.1, 0.6, 1.2):
        rep_path = os.path.join(tmp, "design%g.json" % tol)
        png = os.path.join(tmp, "deviation%g.png" % tol)
        rc, out, err = run(frepmill, "simulate", program, "--stock", "box:0,0,-10,40,10,0", "--tools", tools,
                           "--voxel", str(voxel), "--design", design, "--tolerance", str(tol),
                           "--color", "deviation", "--png", png, "--report", rep_path)
        if not check(rc == 0, "simulate --design --tolerance %g: exit 0 (%r)" % (tol, err.strip()[-200:])):
            continue
        with open(rep_path) as f:
            rep = json.load(f)
        d = rep.get("design") or {}
        check(abs(rep["removed_volume_mm3"] - 360) <= 0.01 * 360, "removed 40 x 6 x 1.5 = 360 mm^3 (%.2f)" %
              rep["removed_volume_mm3"])
        check(d.get("tolerance_mm") == tol, "design.tolerance_mm is --tolerance %g" % tol)
        # docs/simulate.md: the deepest deviations within half a voxel
        check(abs(d.get("max_gouge_mm", 0) - 0.5) <= voxel / 2, "max gouge 0.5 mm (%s)" % d.get("max_gouge_mm"))
        check(abs(d.get("max_excess_mm", 0) - 1.0) <= voxel / 2, "max excess 1.0 mm (%s)" % d.get("max_excess_mm"))
        check(abs(d.get("gouge_volume_mm3", 0) - 120) <= 0.01 * 120,
              "gouge volume 40 x 6 x 0.5 = 120 mm^3 (%s)" % d.get("gouge_volume_mm3"))
        check(abs(d.get("excess_volume_mm3", 0) - 160) <= 0.01 * 160,
              "excess volume 40 x 4 x 1 = 160 mm^3 (%s)" % d.get("excess_volume_mm3"))
        if tol < 0.5:
            g = d.get("gouges") or [{}]
            check(d.get("gouge_regions") == 1 and g[0].get("line") == 6 and g[0].get("tool") == 1
                  and abs(g[0].get("depth_mm", 0) - 0.5) <= voxel / 2,
                  "tolerance %g: one gouge region, 0.5 mm deep, blamed on the slot's line 6 and tool 1 (%s)" % (tol, g[0]))
        else:
            check(d.get("gouge_regions") == 0 and d.get("gouges") == [],
                  "tolerance %g: the 0.5 mm gouge is within it, no region" % tol)
        check(os.path.exists(png) and os.path.getsize(png) > 0, "the deviation picture was written")
        ex = d.get("excess") or []
        ys = sorted(e["position"][1] for e in ex)
        if tol > 1.0:
            check(d.get("excess_regions") == 0 and ex == [],
                  "tolerance %g: the 1 mm excess is within it, no region (%s)" % (tol, ex))
            continue
        check(d.get("excess_regions") == 2 and len(ys) == 2 and 0 <= ys[0] <= 2 and 8 <= ys[1] <= 10
              and all(abs(e["depth_mm"] - 1.0) <= voxel / 2 for e in ex),
              "tolerance %g: two excess regions 1 mm thick, either side of the slot (y %s)" % (tol, ys))


def clearance_tests(frepmill, tmp, tools):
    stock = "box:0,0,-50,40,40,0"
    results = {}
    for depth in (37, 41):
        program = os.path.join(tmp, "plunge%d.ngc" % depth)
        with open(program, "w") as f:
            f.write("G21 G90\nT1 M6\nS1000 M3\nG0 X20 Y20 Z10\nG1 Z-%d F300\nG0 Z10\nM2\n" % depth)
        for clearance in (None, 2, 4):
            args = [frepmill, "check", program, "--stock", stock, "--tools", tools]
            if clearance is not None:
                args += ["--clearance", str(clearance)]
            rc, out, err = run(*args)
            results[(depth, clearance)] = (rc, json.loads(out) if out.strip() else None)
    # 37 deep: the holder's bottom at 40 - 37 = 3 mm over the stock
    for clearance in (None, 2):
        rc, rep = results[(37, clearance)]
        check(rc == 0 and rep and rep["findings"] == [],
              "holder 3 mm over the stock, clearance %s: clean (exit %d)" % (clearance or "default 1 mm", rc))
    rc, rep = results[(37, 4)]
    f = (rep or {}).get("findings") or [{}]
    check(rc == 1 and len(f) == 1 and f[0].get("kind") == "holder_contact" and f[0].get("severity") == "warning"
          and f[0].get("penetration_mm") == 0 and f[0].get("line") == 5
          and abs(f[0]["position"][2] - (4 - 40)) <= 0.5,
          "--clearance 4: a holder warning at line 5, first at tip z = -36 (%s)" % f[0])
    for clearance in (None, 2, 4):
        rc, rep = results[(41, clearance)]
        f = (rep or {}).get("findings") or [{}]
        check(rc == 1 and f[0].get("kind") == "holder_contact" and f[0].get("severity") == "error"
              and abs(f[0].get("penetration_mm", 0) - 1.0) <= 0.5,
              "holder 1 mm into the stock, clearance %s: an error of 1 mm (%s)" % (clearance, f[0].get("penetration_mm")))


def main():
    frepmill = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="fm-surface-") as tmp:
        tools = os.path.join(tmp, "tools.json")
        with open(tools, "w") as f:
            json.dump(TOOLS, f)
        eval_tests(frepmill, tmp)
        dialect_tests(frepmill, tmp, tools)
        design_tests(frepmill, tmp, tools)
        clearance_tests(frepmill, tmp, tools)
    return summary("test_surface_cli")


if __name__ == "__main__":
    sys.exit(main())
