"""test_start_state.py: the machine's state at the start (issue 34): where the
tool tip stands and which tool the spindle holds before the first block.

- No tool in the spindle: a grbl-style program (no T, no M6) and one with T1
  but no M6 (as CAMotics' heart.ngc), with a table of two tools (so the
  one-tool default does not apply). `frepmill check` gives an error finding
  no_tool at the first feed into the stock (its line) and exits 1;
  `frepmill simulate` removes nothing, warns on stderr naming
  FILE:LINE and --initial-tool, exits 0 (its warnings do not change the exit
  status; docs/simulate.md) and its report carries "no_tool".
- With --initial-tool 1 (and the machine file's initial_tool, and the job
  document's options.initial_tool over HTTP) the same programs cut their
  slot: a 6 mm flat end mill 2 mm deep along 40 mm, a stadium,
  D (2 R L + pi R^2) (closed form); check is clean. A one-tool table cuts
  with its tool by default. A tool not in the table is refused (exit 2).
- The start: a 4-axis bar (radius 20 along X through the origin, A turns it)
  with the machine's start above it at (0, 0, 50): the first rapid goes from
  there, over the bar, and simulate removes only the plunge's closed-form
  volume (a 6 mm disc 5 mm below the top, integrated here numerically);
  check finds nothing. Without a start both begin at the origin, inside the
  bar: check's rapid_into_stock on the first rapid's line, and simulate cuts
  the bar there too (the same start for both).
Usage: test_start_state.py FREPMILLD FREPMILL"""
import json
import math
import os
import subprocess
import sys
import tempfile

from daemon_util import COARSE, INSTRUMENTED, Daemon, check, curl_json, submit, wait_state

VOXEL = 0.2 if COARSE else 0.1
R = 3.0
LENGTH = 40.0
DEPTH = 2.0
SLOT = DEPTH * (2 * R * LENGTH + math.pi * R ** 2)
TOL = 3e-3  # relative: flat-bottomed cuts at 0.1 mm (DESIGN.md's bar is 0.5%)
STOCK = "box:0,0,-10,60,50,0"
TWO_TOOLS = {"units": "mm", "tools": [
    {"number": 1, "shape": "flat", "diameter": 2 * R, "flute_length": 20, "length": 40},
    {"number": 2, "shape": "ball", "diameter": 4, "flute_length": 20, "length": 40}]}
ONE_TOOL = {"units": "mm", "tools": [TWO_TOOLS["tools"][0]]}
SLOT_LINES = ["G0 Z5", "G0 X10 Y20", "G1 Z%g F300" % -DEPTH, "G1 X%g F600" % (10 + LENGTH),
              "G0 Z5", "M2"]
# name: (program, line of the first feed into the stock)
PROGRAMS = {
    "grbl": ("\n".join(["G21 G90 G17", "M3 S10000"] + SLOT_LINES) + "\n", 5),
    "heart": ("\n".join(["G21 G90 G17", "T1", "M3 S10000"] + SLOT_LINES) + "\n", 6),
}
WAIT_S = 600 if INSTRUMENTED else 300


def run(frepmill, *args):
    out = subprocess.run([frepmill, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         timeout=WAIT_S)
    return out.returncode, out.stdout.decode(errors="replace"), out.stderr.decode(errors="replace")


def near(value, want, rel=TOL):
    return value is not None and abs(value - want) <= rel * abs(want)


def simulate(frepmill, tmp, name, *args):
    report = os.path.join(tmp, name + ".report.json")
    code, _, err = run(frepmill, "simulate", *args, "--voxel", str(VOXEL), "--report", report)
    rep = None
    if os.path.exists(report):
        with open(report) as f:
            rep = json.load(f)
    return code, err, rep


def no_tool_findings(text):
    return [f for f in json.loads(text)["findings"] if f["kind"] == "no_tool"]


def plunge_into_bar(r_tool, bar_r, z):
    """The volume a flat tool of radius r_tool plunged to height z on the
    axis of a bar of radius bar_r along X removes: the bar above z over the
    tool's disc, integral of 2 sqrt(r^2 - y^2) (sqrt(R^2 - y^2) - z) dy
    (midpoint rule, converged far below the grid's error)."""
    n = 200000
    h = 2 * r_tool / n
    total = 0.0
    for i in range(n):
        y = -r_tool + (i + 0.5) * h
        total += 2 * math.sqrt(r_tool ** 2 - y * y) * (math.sqrt(bar_r ** 2 - y * y) - z) * h
    return total


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


def cli_no_tool(frepmill, tmp, tools2, tools1):
    for name, (program, line) in PROGRAMS.items():
        path = write(os.path.join(tmp, name + ".ngc"), program)
        # no tool in the spindle, a table of two tools
        code, err, rep = simulate(frepmill, tmp, name, path, "--stock", STOCK, "--tools", tools2)
        check(code == 0, "%s: simulate without a tool exits 0 (a warning): %d" % (name, code))
        want = "warning: %s:%d: a feed motion with no tool in the spindle goes into the stock" % \
            (path, line)
        check(want in err and "--initial-tool N" in err,
              "%s: simulate warns at %s:%d and names --initial-tool (%s)" % (name, path, line,
                                                                             err.strip()))
        check(rep is not None and rep["removed_volume_mm3"] == 0,
              "%s: nothing is cut without a tool" % name)
        check(rep is not None and rep["no_tool"] is not None and rep["no_tool"]["line"] == line
              and rep["no_tool"]["motions"] == 2,
              "%s: the report's no_tool is at line %d, 2 motions (%s)" %
              (name, line, rep and rep.get("no_tool")))
        code, out, err = run(frepmill, "check", path, "--stock", STOCK, "--tools", tools2)
        found = no_tool_findings(out) if out.strip() else []
        check(code == 1 and len(found) == 1 and found[0]["line"] == line and
              found[0]["severity"] == "error" and found[0]["last_line"] == line + 1,
              "%s: check exits 1 with one no_tool error at line %d-%d (%s)" %
              (name, line, line + 1, found))
        check("%s:%d: no tool in the spindle" % (path, line) in err and "--initial-tool N" in err,
              "%s: check's summary says where and how to fix it" % name)
        # the tool in the spindle at the start: the slot's closed form
        code, err, rep = simulate(frepmill, tmp, name + "_t1", path, "--stock", STOCK, "--tools",
                                  tools2, "--initial-tool", "1")
        check(code == 0 and near(rep["removed_volume_mm3"], SLOT) and rep["no_tool"] is None
              and "no tool" not in err,
              "%s --initial-tool 1: removes %.3f mm3 (closed form %.3f), no warning" %
              (name, rep["removed_volume_mm3"] if rep else -1, SLOT))
        code, out, err = run(frepmill, "check", path, "--stock", STOCK, "--tools", tools2,
                             "--initial-tool", "1")
        check(code == 0, "%s: check --initial-tool 1 is clean (%s)" % (name, err.strip()))
        # the machine file's initial_tool
        machine = write(os.path.join(tmp, "tool1.json"), '{"units": "mm", "initial_tool": 1}\n')
        code, err, rep = simulate(frepmill, tmp, name + "_m", path, "--stock", STOCK, "--tools",
                                  tools2, "--machine", machine)
        check(code == 0 and near(rep["removed_volume_mm3"], SLOT),
              "%s: the machine's initial_tool 1 cuts the slot" % name)
        # --initial-tool wins over the machine's
        code, err, rep = simulate(frepmill, tmp, name + "_m2", path, "--stock", STOCK, "--tools",
                                  tools2, "--machine", machine, "--initial-tool", "2")
        check(code == 0 and rep["tools"][0]["tool"] == 2,
              "%s: --initial-tool 2 wins over the machine's 1" % name)
        # a one-tool table: its tool by default
        code, err, rep = simulate(frepmill, tmp, name + "_one", path, "--stock", STOCK, "--tools",
                                  tools1)
        check(code == 0 and near(rep["removed_volume_mm3"], SLOT) and rep["no_tool"] is None,
              "%s: a one-tool table cuts with its tool" % name)
        code, out, err = run(frepmill, "check", path, "--stock", STOCK, "--tools", tools1)
        check(code == 0, "%s: check with a one-tool table is clean" % name)
    # a tool the table does not have
    path = os.path.join(tmp, "grbl.ngc")
    code, _, err = run(frepmill, "simulate", path, "--stock", STOCK, "--tools", tools2,
                       "--initial-tool", "3")
    check(code == 2 and "tool 3 is not in the tool table" in err,
          "--initial-tool 3 is refused: %d %s" % (code, err.strip()))
    code, out, _ = run(frepmill, "motions", path, "--tools", tools2, "--initial-tool", "1")
    first = json.loads(out.splitlines()[0]) if out else {}
    check(code == 0 and first.get("tool") == 1, "motions --initial-tool 1: the motions carry tool 1")


def cli_bar(frepmill, tmp, tools1):
    bar = write(os.path.join(tmp, "bar.hf"),
                "bar(x[3], a[1])\n{\n  r_alpha = 1;\n"
                "  bar = (20 - sqrt(x[2]^2 + x[3]^2)) & (x[1] + 50) & (50 - x[1]);\n}\n")
    rotary = '"rotary": [{"axis": "a", "around": [1, 0, 0], "carries": "table"}]'
    above = write(os.path.join(tmp, "above.json"),
                  '{"units": "mm", "start": [0, 0, 50], %s}\n' % rotary)
    origin = write(os.path.join(tmp, "origin.json"), '{"units": "mm", %s}\n' % rotary)
    # line 4: the first rapid, from the start to above the bar; line 6 plunges
    program = write(os.path.join(tmp, "bar.ngc"),
                    "G21 G90 G17\nT1 M6\nS10000 M3\nG0 X10 Y0 Z30\nG0 X30 A0\nG1 Z15 F300\n"
                    "G0 Z50\nM30\n")
    want = plunge_into_bar(R, 20.0, 15.0)
    code, err, rep = simulate(frepmill, tmp, "bar", program, "--stock", bar, "--tools", tools1,
                              "--machine", above)
    check(code == 0 and near(rep["removed_volume_mm3"], want, 5e-3),
          "bar, start above: the first rapid cuts nothing, %.3f mm3 removed (the plunge: %.3f)" %
          (rep["removed_volume_mm3"] if rep else -1, want))
    code, out, err = run(frepmill, "check", program, "--stock", bar, "--tools", tools1,
                         "--machine", above)
    check(code == 0 and json.loads(out)["findings"] == [],
          "bar, start above: check finds nothing (%s)" % err.strip())
    code, out, _ = run(frepmill, "motions", program, "--tools", tools1, "--machine", above)
    first = json.loads(out.splitlines()[0]) if out else {}
    check(first.get("line") == 4 and first.get("start") == [0, 0, 50],
          "motions --machine: the first rapid starts at the machine's start (%s)" %
          first.get("start"))
    # no start: the origin, inside the bar, for both
    code, err, rep = simulate(frepmill, tmp, "bar0", program, "--stock", bar, "--tools", tools1,
                              "--machine", origin)
    check(code == 0 and rep["removed_volume_mm3"] > want + 100,
          "bar, start at the origin: simulate cuts the bar on the first rapid (%.1f mm3)" %
          (rep["removed_volume_mm3"] if rep else -1))
    code, out, err = run(frepmill, "check", program, "--stock", bar, "--tools", tools1,
                         "--machine", origin)
    kinds = [(f["kind"], f["line"]) for f in json.loads(out)["findings"]] if out.strip() else []
    check(code == 1 and ("rapid_into_stock", 4) in kinds,
          "bar, start at the origin: check's rapid_into_stock on line 4 (%s)" % kinds)


def http(frepmilld, tmp):
    d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1")
    try:
        for name, (program, line) in PROGRAMS.items():
            doc = {"stock": STOCK, "voxel": VOXEL, "tools": TWO_TOOLS,
                   "program": {"gcode": program}, "options": {"name": name}}
            job = submit(d.url, doc, tmp)
            doc["options"]["initial_tool"] = 1
            job_t1 = submit(d.url, doc, tmp)
            for job_id in (job, job_t1):
                status = wait_state(d.url, job_id, ("done", "failed", "cancelled"), WAIT_S)
                check(status["state"] == "done", "HTTP %s: job %s done" % (name, job_id))
            _, rep = curl_json(d.url + "/v1/jobs/%s/report" % job)
            check(rep["removed_volume_mm3"] == 0 and rep["no_tool"]["line"] == line and
                  [f["line"] for f in rep["findings"] if f["kind"] == "no_tool"] == [line],
                  "HTTP %s without a tool: no_tool at line %d in the report and its findings" %
                  (name, line))
            _, rep = curl_json(d.url + "/v1/jobs/%s/report" % job_t1)
            check(near(rep["removed_volume_mm3"], SLOT) and rep["no_tool"] is None and
                  rep["findings"] == [],
                  "HTTP %s with options.initial_tool 1: %.3f mm3 (closed form %.3f), no findings"
                  % (name, rep["removed_volume_mm3"], SLOT))
        doc["options"]["initial_tool"] = 3
        path = write(os.path.join(tmp, "bad.json"), json.dumps(doc))
        code, body = curl_json("-X", "POST", "-H", "Content-Type: application/json",
                               "--data-binary", "@" + path, d.url + "/v1/jobs")
        check(code == 400 and "options.initial_tool 3" in json.dumps(body),
              "HTTP: options.initial_tool 3 is refused (%d %s)" % (code, body))
    finally:
        d.stop()


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory(prefix="fm-start-") as tmp:
        tools2 = write(os.path.join(tmp, "tools2.json"), json.dumps(TWO_TOOLS))
        tools1 = write(os.path.join(tmp, "tools1.json"), json.dumps(ONE_TOOL))
        cli_no_tool(frepmill, tmp, tools2, tools1)
        cli_bar(frepmill, tmp, tools1)
        http(frepmilld, tmp)
    print("test_start_state: all passed")


if __name__ == "__main__":
    main()
