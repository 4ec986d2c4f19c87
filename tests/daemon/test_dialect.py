"""test_dialect.py: the daemon's G-code settings. A daemon started with
`--dialect fanuc` runs a Fanuc program (O number line, decimal points: "X50"
would be 0.05 mm), and so does a job whose options say "dialect": "fanuc" on a
daemon left at linuxcnc (with "calculator_input": true, "X50" is 50 mm); one
started with `--subroutine-path DIR` runs a LinuxCNC
program whose o<slot> call is found in DIR. Each cuts one slot whose volume
is computed here in closed form: a 6 mm flat end mill 2 mm deep from
(10,20) to (50,20): (40 * 6 + pi * 3^2) * 2 mm3. A dialect the daemon does
not know stops its start, and a job naming one is refused (400). POST
/v1/check of each job finds what a reading of the program gives: it never
starts the spindle (no M3), so its one finding is a spindle_off_cut error
2 mm deep (the slot's depth) from the plunge to the slot's end (the Fanuc
file's lines 7-8 after %, O1000, G21, T1, Z5. and X10. Y20.; lines 2-3 of
the LinuxCNC subroutine file slot.ngc).
Usage: test_dialect.py FREPMILLD FREPMILL"""
import json
import math
import os
import subprocess
import sys
import tempfile

from daemon_util import COARSE, Daemon, check, curl_json, submit, wait_state

# Instrumented (sanitizer build): 0.2 mm. Most of an instrumented job's time
# goes to meshing the whole stock for the viewer (its uncut state and its
# final one), which scales with the stock's surface in voxels.
VOXEL = 0.2 if COARSE else 0.1
STOCK = "box:0,0,-10,60,40,0"
TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6,
                                   "flute_length": 20, "length": 40}]}
SLOT = (40 * 6 + math.pi * 3 ** 2) * 2
FANUC = ("%\nO1000 (SLOT)\nG21 G17 G40 G80 G90\nT1 M06\nG00 Z5.\nG00 X10. Y20.\n"
         "G01 Z-2. F300.\nX50. F600.\nG00 Z5.\nM30\n%\n")
# the same program without decimal points: millimetres only with calculator input
FANUC_CALCULATOR = FANUC.replace(".", "")
LINUXCNC_MAIN = "G21 G17 G90\nT1 M6\nG00 Z5\nG00 X10 Y20\no<slot> call\nM2\n"
LINUXCNC_SUB = "o<slot> sub\nG01 Z-2 F300\nG01 X50 F600\nG00 Z5\no<slot> endsub\nM2\n"


def run(frepmilld, state, flags, program, tmp, what, lines, options=None):
    d = Daemon(frepmilld, state, "--workers", "1", *flags)
    try:
        job = {"stock": STOCK, "voxel": VOXEL, "tools": TOOLS, "program": {"gcode": program}}
        if options:
            job["options"] = options
            bad = dict(job, options=dict(options, dialect="haas"))
            code, body = curl_json("-X", "POST", "-H", "Content-Type: application/json",
                                   "--data-binary", json.dumps(bad), d.url + "/v1/jobs")
            check(code == 400 and "options.dialect" in json.dumps(body),
                  "%s: a job naming dialect haas is refused (%d, %s)" % (what, code, body))
        job_id = submit(d.url, job, tmp)
        status = wait_state(d.url, job_id, ("done", "failed", "cancelled"), 300)
        check(status["state"] == "done", "%s: done (%s)" % (what, status.get("error")))
        removed = status["removed_volume_mm3"]
        # 0.5%: the tolerance of test_simulate's closed forms (at 0.1 mm voxels).
        check(abs(removed - SLOT) <= 0.005 * SLOT,
              "%s: removed %.2f mm3 = closed form %.2f" % (what, removed, SLOT))
        # POST /v1/check reads the program with the same settings (in the
        # other dialect, or without the folder, it is an error: 400)
        code, body = curl_json("-X", "POST", "--data-binary", json.dumps(job),
                               d.url + "/v1/check")
        found = body.get("findings") if code == 200 and body else None
        check(isinstance(found, list) and len(found) == 1 and found[0]["kind"] == "spindle_off_cut"
              and found[0]["severity"] == "error"
              and (found[0]["line"], found[0]["last_line"]) == lines
              and abs(found[0]["penetration_mm"] - 2.0) <= 0.25 and body["errors"] == 1,
              "%s: POST /v1/check reads it too: one spindle_off_cut error 2 mm deep at lines %d-%d "
              "(%d, %s)" % (what, lines[0], lines[1], code, body))
    finally:
        rc = d.stop()
        if rc != 0:
            print(d.read_log()[-6000:])
    check(rc == 0, "the daemon stopped cleanly")


def main():
    frepmilld = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="fm-dialect-") as tmp:
        subs = os.path.join(tmp, "subs")
        os.mkdir(subs)
        with open(os.path.join(subs, "slot.ngc"), "w") as f:
            f.write(LINUXCNC_SUB)
        run(frepmilld, os.path.join(tmp, "a"), ["--dialect", "fanuc"], FANUC, tmp,
            "--dialect fanuc: a Fanuc program", (7, 8))
        run(frepmilld, os.path.join(tmp, "a2"), [], FANUC_CALCULATOR, tmp,
            "options.dialect fanuc on a linuxcnc daemon", (7, 8),
            {"dialect": "fanuc", "calculator_input": True})
        run(frepmilld, os.path.join(tmp, "b"), ["--subroutine-path", subs], LINUXCNC_MAIN, tmp,
            "--subroutine-path: o<slot> call found in the configured folder", (2, 3))
        out = subprocess.run([frepmilld, "--dialect", "haas", "--state-dir",
                              os.path.join(tmp, "c")], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, timeout=30)
        check(out.returncode != 0 and b"expected linuxcnc or fanuc" in out.stderr,
              "--dialect haas stops the start (%s)" % out.stderr.decode().strip())


if __name__ == "__main__":
    main()
