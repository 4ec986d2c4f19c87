"""test_cycle_times.py: the controller's time everywhere (docs/plan.md):
`frepmill time`, `frepmill motions`' cycle_t, the report's cycle_times and
top_blocks, simulate's progress lines and the daemon's status and toolpath
all give the planned times of one program, and these are the closed forms.

The program runs in exact stop (G61.1: every move starts and ends at rest),
so each move is a trapezoid of its own: a move of length L at feed v with
acceleration a that reaches v takes L/v + v/a; one too short to reach it
(L < v^2/a) takes 2 sqrt(L/a). The tool change adds its tool_change_s to
the first motion after it. Per tool, per operation and per block the
breakdown must sum to the total, and each part must be its closed form.
Usage: test_cycle_times.py FREPMILLD FREPMILL"""
import json
import math
import os
import subprocess
import sys
import tempfile

from daemon_util import Daemon, check, curl_json, submit, wait_state

A = 500.0  # mm/s^2 on every axis
TOOL_CHANGE = 4.0
MACHINE = {"name": "closed forms",
           "dynamics": {"axes": {k: {"max_velocity": 100, "max_acceleration": A} for k in "xyz"},
                        "tool_change_s": TOOL_CHANGE}}
PROGRAM = "\n".join([
    "G21 G90 G61.1",
    "T1 M6",
    "G1 X100 F1200",  # line 3: 100 mm at 20 mm/s
    "G1 Y50",         # line 4: 50 mm at 20 mm/s
    "T2 M6",
    "G1 X110 F600",   # line 6: 10 mm at 10 mm/s (after the tool change)
    "G1 X110.1",      # line 7: 0.1 mm, too short to reach 10 mm/s (needs 0.2 mm)
    "M2", ""])
TOOLS = {"units": "mm", "tools": [
    {"number": 1, "shape": "flat", "diameter": 6, "flute_length": 20, "length": 40},
    {"number": 2, "shape": "flat", "diameter": 4, "flute_length": 20, "length": 40}]}
STOCK = "box:0,-10,-20,120,60,-5"


def trapezoid(length, v):
    """Rest to rest at most v with acceleration A."""
    if length >= v * v / A:
        return length / v + v / A
    return 2 * math.sqrt(length / A)


# (line, tool, planned s, feed-only s) of each move, by hand
MOVES = [(3, 1, trapezoid(100, 20), 100 / 20.0),
         (4, 1, trapezoid(50, 20), 50 / 20.0),
         (6, 2, TOOL_CHANGE + trapezoid(10, 10), 10 / 10.0),
         (7, 2, trapezoid(0.1, 10), 0.1 / 10.0)]
TOTAL = sum(m[2] for m in MOVES)
FEED_TOTAL = sum(m[3] for m in MOVES)


def near(a, b, tol=1e-6):
    return a is not None and abs(a - b) <= tol


def by_hand(tool):
    return (sum(m[2] for m in MOVES if m[1] == tool), sum(m[3] for m in MOVES if m[1] == tool))


def check_breakdown(ct, where):
    """Per tool, operation and block: each part its closed form, the sum the total."""
    tools = {t["tool"]: t for t in ct["tools"]}
    check(set(tools) == {1, 2} and all(near(tools[k]["time_s"], by_hand(k)[0]) and
                                       near(tools[k]["feed_only_s"], by_hand(k)[1]) for k in (1, 2)),
          "%s: per tool %s, by hand %s" % (where, ct["tools"], [by_hand(1), by_hand(2)]))
    ops = ct["operations"]
    check(len(ops) == 2 and ct["operation_count"] == 2 and
          [(o["tool"], o["first_line"], o["last_line"]) for o in ops] == [(1, 3, 4), (2, 6, 7)] and
          all(near(o["time_s"], by_hand(o["tool"])[0]) for o in ops) and
          near(ops[0]["t0"], 0) and near(ops[0]["t1"], ops[1]["t0"]) and near(ops[1]["t1"], TOTAL),
          "%s: two operations, tool 1 on lines 3-4 then tool 2 on 6-7, back to back" % where)
    blocks = {b["line"]: b for b in ct["blocks"]}
    check(set(blocks) == {3, 4, 6, 7} and
          all(near(blocks[m[0]]["time_s"], m[2]) and near(blocks[m[0]]["feed_only_s"], m[3])
              for m in MOVES),
          "%s: each block its trapezoid (%s)" % (where, ct["blocks"]))
    check(ct["blocks"] == sorted(ct["blocks"], key=lambda b: -b["time_s"]),
          "%s: the slowest block first" % where)
    for part in ("tools", "operations", "blocks"):
        s = sum(x["time_s"] for x in ct[part])
        f = sum(x["feed_only_s"] for x in ct[part])
        check(near(s, TOTAL) and near(f, FEED_TOTAL),
              "%s: %s sum to %.6f s (feed-only %.6f s), the total %.6f s (%.6f s)" %
              (where, part, s, f, TOTAL, FEED_TOTAL))


def run(*args):
    return subprocess.run(list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=300)


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory(prefix="fm-cycle-") as tmp:
        machine = os.path.join(tmp, "machine.json")
        program = os.path.join(tmp, "p.ngc")
        tools = os.path.join(tmp, "tools.json")
        for path, text in ((machine, json.dumps(MACHINE)), (program, PROGRAM),
                           (tools, json.dumps(TOOLS))):
            with open(path, "w") as f:
                f.write(text)

        # frepmill time
        out = run(frepmill, "time", program, "--machine", machine, "--json")
        check(out.returncode == 0, "frepmill time runs (%s)" % out.stderr.strip())
        timed = json.loads(out.stdout)
        check(near(timed["cycle_time_s"], TOTAL) and near(timed["feed_only_s"], FEED_TOTAL),
              "time: cycle time %.6f s, by hand %.6f s; feed-only %.6f s" %
              (timed["cycle_time_s"], TOTAL, FEED_TOTAL))
        check_breakdown(timed, "time")

        # frepmill motions: t feed-only as before, cycle_t the planned times
        out = run(frepmill, "motions", program, "--machine", machine)
        check(out.returncode == 0, "frepmill motions --machine runs")
        motions = [json.loads(l) for l in out.stdout.splitlines()]
        moves = [m for m in motions if m["kind"] == "line"]
        check(len(moves) == len(MOVES) and
              all(near(m["cycle_t"][1] - m["cycle_t"][0], h[2]) and m["line"] == h[0] and
                  near(m["t"][1] - m["t"][0], h[3]) for m, h in zip(moves, MOVES)),
              "motions: each move's cycle_t spans its trapezoid and t its feed-only time")
        ends = [m["cycle_t"] for m in motions]
        check(all(a[0] <= a[1] for a in ends) and
              all(near(b[0], a[1]) for a, b in zip(ends, ends[1:])) and near(ends[0][0], 0),
              "motions: cycle_t monotone, each motion starting where the one before ends")
        check(near(ends[-1][1], timed["cycle_time_s"]),
              "motions: the last end %.6f s is time's cycle_time_s" % ends[-1][1])
        out = run(frepmill, "motions", program)
        plain = [json.loads(l) for l in out.stdout.splitlines()]
        check(all(m["cycle_t"] == m["t"] for m in plain),
              "motions without dynamics: cycle_t is the feed-only t")
        out = run(frepmill, "motions", program, "--machine", machine, "--skip", "2")
        skipped = [json.loads(l) for l in out.stdout.splitlines()]
        check([m["cycle_t"] for m in skipped] == [m["cycle_t"] for m in motions[2:]],
              "motions --skip 2: the same planned times from motion 2 on")

        # frepmill simulate: the report and the progress lines
        report = os.path.join(tmp, "r.json")
        out = run(frepmill, "simulate", program, "--stock", STOCK, "--tools", tools, "--voxel", "1",
                  "--machine", machine, "--report", report, "--progress")
        check(out.returncode == 0, "simulate runs (%s)" % out.stderr.strip()[-300:])
        with open(report) as f:
            rep = json.load(f)
        check(near(rep["cycle_time_s"], TOTAL) and rep["cycle_time_planned"] and
              near(rep["program_time_s"], FEED_TOTAL),
              "report: cycle_time_s %.6f s planned, program_time_s feed-only" % rep["cycle_time_s"])
        check_breakdown(rep["cycle_times"], "report")
        top = {b["line"]: b for b in rep["top_blocks"]}
        check(3 in top and near(top[3]["t0"], 0) and near(top[3]["t1"], MOVES[0][2]),
              "report: top_blocks' line 3 spans the planned [0, %.4f] s" % MOVES[0][2])
        progress = [l for l in out.stderr.splitlines() if l.startswith("progress")]
        check(progress and all(l.endswith(" planned") for l in progress) and
              "%.1f/%.1f s planned" % (TOTAL, TOTAL) in progress[-1],
              "simulate --progress: in planned time (%s)" % (progress[-1:] or ["none"]))
        check("as planned (feed-only %.1f s)" % FEED_TOTAL in out.stderr,
              "simulate's summary gives the planned time, feed-only beside")
        out = run(frepmill, "simulate", program, "--stock", STOCK, "--tools", tools, "--voxel", "1",
                  "--progress")
        progress = [l for l in out.stderr.splitlines() if l.startswith("progress")]
        check(progress and all(l.endswith(" feed-only") for l in progress),
              "simulate --progress without dynamics: labelled feed-only")

        # the daemon: status and toolpath in the controller's time
        job = {"stock": STOCK, "voxel": 1, "tools": TOOLS, "program": {"gcode": PROGRAM},
               "machine": MACHINE, "options": {"name": "cycle times"}}
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1")
        try:
            job_id = submit(d.url, job, tmp)
            status = wait_state(d.url, job_id, ("done", "failed"), 300)
            code, drep = curl_json(d.url + "/v1/jobs/%s/report" % job_id)
            check(status["state"] == "done" and code == 200 and
                  near(status["program_time_s"], drep["cycle_time_s"]) and
                  near(status["program_time_s"], TOTAL),
                  "status program_time_s %.6f s is the report's cycle_time_s %.6f s" %
                  (status["program_time_s"], drep.get("cycle_time_s", -1)))
            check(status["program_time_planned"] is True and
                  near(status["program_time_total_s"], TOTAL) and
                  near(status["feed_only_total_s"], FEED_TOTAL),
                  "status: program_time_planned, its total and the feed-only total beside")
            code, tp = curl_json(d.url + "/v1/jobs/%s/toolpath" % job_id)
            check(code == 200 and near(tp["motions"][-1][3], TOTAL, 1e-3),
                  "the toolpath (the viewer's timeline) ends at the planned %.4f s" % TOTAL)
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")


if __name__ == "__main__":
    main()
