"""test_findings.py: one program and one machine file give one set of
findings everywhere: `frepmill check --machine`, `frepmill simulate --check
--machine`, a daemon job whose document carries the machine, and POST
/v1/check. Every member of every finding is compared, program time
included: the machine's rapid rate (1200 mm/min here, not the 5000 default)
times the rapids for all of them.

The program is tests/check/rapid_through.ngc: a rapid at Z-5 through the
block (line 6), after a rapid to X-10, outside the machine's X travel
(-5..100): a travel_limit finding at line 4. The time of the first contact
of line 6 is worked out by hand below.
Usage: test_findings.py FREPMILLD FREPMILL"""
import json
import math
import os
import subprocess
import sys
import tempfile
import time

from daemon_util import ROOT, Daemon, check, curl_json, submit, wait_state

CHECK_DIR = os.path.join(ROOT, "tests", "check")
PROGRAM = os.path.join(CHECK_DIR, "rapid_through.ngc")
TOOLS = os.path.join(CHECK_DIR, "tools.json")
STOCK = "box:0,0,-10,50,50,0"
RAPID = 1200.0
MACHINE = {"units": "mm", "name": "slow rapids",
           "limits": {"x": [-5, 100], "y": [-100, 100], "z": [-60, 40]},
           "rapid_rate": RAPID, "start": [0, 0, 30]}


def same(a, b, where):
    """Every member equal; numbers within 1e-6 (JSON printing rounds)."""
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            print("  %s: members %s vs %s" % (where, sorted(a), sorted(b)))
            return False
        return all(same(a[k], b[k], where + "." + k) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            print("  %s: %d vs %d entries" % (where, len(a), len(b)))
            return False
        return all(same(x, y, "%s[%d]" % (where, i)) for i, (x, y) in enumerate(zip(a, b)))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and \
            not isinstance(a, bool) and not isinstance(b, bool):
        if abs(a - b) <= 1e-6 * max(1.0, abs(a)):
            return True
        print("  %s: %r vs %r" % (where, a, b))
        return False
    if a != b:
        print("  %s: %r vs %r" % (where, a, b))
    return a == b


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory(prefix="fm-findings-") as tmp:
        t0 = time.time()
        machine = os.path.join(tmp, "machine.json")
        with open(machine, "w") as f:
            json.dump(MACHINE, f)
        out = subprocess.run([frepmill, "check", PROGRAM, "--stock", STOCK, "--tools", TOOLS,
                              "--machine", machine], stdout=subprocess.PIPE,
                             stderr=subprocess.DEVNULL, timeout=300)
        check(out.returncode == 1, "frepmill check --machine exits 1 (findings)")
        ref = json.loads(out.stdout)["findings"]
        kinds = [(f["kind"], f["line"]) for f in ref]
        check(("travel_limit", 4) in kinds and ("rapid_into_stock", 6) in kinds,
              "frepmill check finds the travel limit at line 4 and the rapid into the stock at "
              "line 6 (%s)" % kinds)
        # Line 6 starts at (-10, 25, -5) after rapids from the machine's
        # start (0, 0, 30), where the interpreter starts too (issue 34; it
        # used to time the first rapid from the origin): Z10 (20 mm), X-10
        # Y25 (sqrt(10^2 + 25^2)), Z-5 (15 mm); the 6 mm tool's side meets
        # the block (x = 0) after 10 - 3 mm more. At 1200 mm/min (the default
        # 5000 would give less than a quarter of it):
        path = 20 + math.hypot(10, 25) + 15 + (10 - 3)
        expect = path / RAPID * 60.0
        rapid = [f for f in ref if f["kind"] == "rapid_into_stock"][0]
        check(abs(rapid["time_s"] - expect) <= 0.5 / RAPID * 60.0,
              "its first contact is at t = %.3f s (by hand %.3f s at the machine's rapid rate)" %
              (rapid["time_s"], expect))

        report = os.path.join(tmp, "simulate.json")
        subprocess.run([frepmill, "simulate", PROGRAM, "--stock", STOCK, "--tools", TOOLS,
                        "--voxel", "0.5", "--check", "--machine", machine, "--report", report],
                       check=True, timeout=300, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        with open(report) as f:
            sim = json.load(f)
        check(same(sim["findings"], ref, "simulate"),
              "frepmill simulate --check --machine gives frepmill check's findings")
        # All rapids, from the machine's start: 20 + sqrt(10^2 + 25^2) + 15 +
        # 70 + 15 mm.
        total = (20 + math.hypot(10, 25) + 15 + 70 + 15) / RAPID * 60.0
        check(abs(sim["program_time_s"] - total) < 1e-6,
              "the simulation is timed at the machine's rapid rate too (%.4f s, by hand %.4f s)" %
              (sim["program_time_s"], total))

        with open(PROGRAM) as f:
            program = f.read()
        with open(TOOLS) as f:
            tools = json.load(f)
        job = {"stock": STOCK, "voxel": 0.5, "tools": tools, "program": {"gcode": program},
               "machine": dict(MACHINE), "options": {"name": "findings"}}
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1")
        try:
            job_id = submit(d.url, job, tmp)
            status = wait_state(d.url, job_id, ("done", "failed"), 300)
            check(status["state"] == "done" and abs(status["program_time_s"] - total) < 1e-6,
                  "the daemon's job is done, timed like the CLI's (%.4f s)" %
                  status["program_time_s"])
            check(same(status["findings"], ref, "daemon job"),
                  "the daemon's job gives frepmill check's findings")
            path_json = os.path.join(tmp, "check.json")
            with open(path_json, "w") as f:
                json.dump(job, f)
            code, body = curl_json("-X", "POST", "--data-binary", "@" + path_json,
                                   d.url + "/v1/check")
            check(code == 200 and same(body["findings"], ref, "POST /v1/check"),
                  "POST /v1/check gives frepmill check's findings")
            code, tp = curl_json(d.url + "/v1/jobs/%s/toolpath" % job_id)
            last = tp["motions"][-1]
            check(code == 200 and abs(last[3] - status["program_time_s"]) < 1e-3,
                  "the toolpath's rapids are timed at the machine's rate too")
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")
        print("test_findings: %.1f s" % (time.time() - t0))


if __name__ == "__main__":
    main()
