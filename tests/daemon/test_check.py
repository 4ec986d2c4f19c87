"""test_check.py: the collision check in frepmilld (and `frepmill simulate
--check`). POST /v1/check and a job's status carry the findings `frepmill
check` prints for the same inputs
(a rapid through the stock at line 6 of tests/check/rapid_through.ngc, and
an STL clamp, sent base64, in its path); the Modbus status registers show
the finding count (23), the first finding's line (24-25) and the collision
alarm (bit 5 of register 1). Also the size limit and option errors.
Usage: test_check.py FREPMILLD FREPMILL"""
import base64
import json
import os
import struct
import subprocess
import sys
import tempfile
import time

from daemon_util import modbus_read, ROOT, Daemon, check, curl_json, modbus_port, submit, wait_state

CHECK_DIR = os.path.join(ROOT, "tests", "check")
STOCK = "box:0,0,-10,50,50,0"
# The rapid "G0 X60" at Z-5 is on line 6 of the program: counted by hand.
RAPID_LINE = 6


def box_stl(lo, hi):
    """A closed binary STL box, 12 outward triangles, written here."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
         (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    quads = [((0, 3, 2, 1), (0, 0, -1)), ((4, 5, 6, 7), (0, 0, 1)), ((0, 1, 5, 4), (0, -1, 0)),
             ((2, 3, 7, 6), (0, 1, 0)), ((1, 2, 6, 5), (1, 0, 0)), ((3, 0, 4, 7), (-1, 0, 0))]
    tris = []
    for (a, b, c, d), n in quads:
        tris += [(n, v[a], v[b], v[c]), (n, v[a], v[c], v[d])]
    out = bytearray(b"frepmill test clamp".ljust(80, b"\0"))
    out += struct.pack("<I", len(tris))
    for n, a, b, c in tris:
        out += struct.pack("<12fH", *n, *a, *b, *c, 0)
    return bytes(out)


def cli_check(frepmill, tmp, fixtures=()):
    args = [frepmill, "check", os.path.join(CHECK_DIR, "rapid_through.ngc"), "--stock", STOCK,
            "--tools", os.path.join(CHECK_DIR, "tools.json")]
    for f in fixtures:
        args += ["--fixture", f]
    out = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, timeout=300)
    check(out.returncode == 1, "frepmill check exits 1 (findings)")
    return json.loads(out.stdout)["findings"]


def same_findings(a, b):
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        for k in ("kind", "severity", "part", "line", "block", "last_line", "motions"):
            if x.get(k) != y.get(k):
                return False
        if abs(x["penetration_mm"] - y["penetration_mm"]) > 1e-6:
            return False
        for k in ("position", "contact"):
            if any(abs(p - q) > 1e-6 for p, q in zip(x[k], y[k])):
                return False
    return True


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory(prefix="fm-check-") as tmp:
        clamp = os.path.join(tmp, "clamp.stl")
        stl = box_stl((20, 20, 0), (30, 30, 15))
        with open(clamp, "wb") as f:
            f.write(stl)
        t0 = time.time()
        ref = cli_check(frepmill, tmp)
        ref_fix = cli_check(frepmill, tmp, [clamp])
        check(any(f["kind"] == "rapid_into_stock" and f["line"] == RAPID_LINE for f in ref),
              "the CLI finds the rapid into the stock at line %d" % RAPID_LINE)
        check(any(f["kind"] == "fixture_contact" for f in ref_fix),
              "the CLI finds the clamp in the rapid's path")
        report = os.path.join(tmp, "simulate.json")
        subprocess.run([frepmill, "simulate", os.path.join(CHECK_DIR, "rapid_through.ngc"),
                        "--stock", STOCK, "--tools", os.path.join(CHECK_DIR, "tools.json"),
                        "--voxel", "0.5", "--check", "--fixture", clamp, "--report", report],
                       check=True, timeout=300, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        with open(report) as f:
            check(same_findings(json.load(f)["findings"], ref_fix),
                  "frepmill simulate --check reports the findings of frepmill check")

        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1",
                   "--modbus-listen", "127.0.0.1:0")
        try:
            with open(os.path.join(CHECK_DIR, "rapid_through.ngc")) as f:
                program = f.read()
            with open(os.path.join(CHECK_DIR, "tools.json")) as f:
                tools = json.load(f)
            job = {"stock": STOCK, "voxel": 0.5, "tools": tools, "program": {"gcode": program},
                   "options": {"name": "rapid"}}
            path = os.path.join(tmp, "check.json")
            with open(path, "w") as f:
                json.dump(job, f)
            code, body = curl_json("-X", "POST", "--data-binary", "@" + path, d.url + "/v1/check")
            check(code == 200 and same_findings(body["findings"], ref),
                  "POST /v1/check gives the CLI's findings (%d, %s)" % (code, body))
            check(body["errors"] == sum(f["severity"] == "error" for f in ref),
                  "POST /v1/check counts the errors")

            job_fix = dict(job, fixtures=[{"stl_base64": base64.b64encode(stl).decode(),
                                           "name": "clamp"}])
            with open(path, "w") as f:
                json.dump(job_fix, f)
            code, body = curl_json("-X", "POST", "--data-binary", "@" + path, d.url + "/v1/check")
            check(code == 200 and same_findings(body["findings"], ref_fix),
                  "with an STL clamp (base64) POST /v1/check gives the CLI's findings")
            check(not [n for n in os.listdir(os.path.join(tmp, "state")) if n.startswith("check-")],
                  "the check's temporary folder is gone")

            big = dict(job, program={"gcode": "G0 X1\n" * 50000})
            with open(path, "w") as f:
                json.dump(big, f)
            code, body = curl_json("-X", "POST", "--data-binary", "@" + path, d.url + "/v1/check")
            check(code == 413 and body["error"]["code"] == "check_too_large",
                  "a program over the synchronous limit is 413 check_too_large")
            bad = dict(job, options={"check": {"clearence": 1}})
            with open(path, "w") as f:
                json.dump(bad, f)
            code, body = curl_json("-X", "POST", "--data-binary", "@" + path, d.url + "/v1/check")
            check(code == 400 and body["error"]["code"] == "unknown_key",
                  "a misspelt check option is 400 unknown_key")
            code, body = curl_json("-X", "POST", "-H", "Content-Type: application/json",
                                   "--data-binary", "@" + path, d.url + "/v1/jobs")
            check(code == 400 and body["error"]["code"] == "unknown_key",
                  "... and refused at job submission too")

            job_id = submit(d.url, job_fix, tmp)
            status = wait_state(d.url, job_id, ("done", "failed"), 300)
            check(status["state"] == "done" and same_findings(status["findings"], ref_fix),
                  "a job's status carries the CLI's findings")
            port = modbus_port(d)
            regs = modbus_read(port, 0, 29)
            errors = sum(f["severity"] == "error" for f in ref_fix)
            check(regs[23] == len(ref_fix), "register 23 = %d findings" % len(ref_fix))
            check((regs[24] << 16 | regs[25]) == ref_fix[0]["line"],
                  "registers 24-25 = line %d of the first finding" % ref_fix[0]["line"])
            check(bool(regs[1] & 0x20) == (errors > 0), "collision alarm bit 5 set on errors")
            check(regs[1] & 0x08, "done bit set")

            clean = dict(job, program={"gcode": "G21 G90\nG0 Z10\nG0 X-10 Y25\nM2\n"},
                         options={"check": False})
            job_id = submit(d.url, clean, tmp)
            status = wait_state(d.url, job_id, ("done", "failed"), 300)
            regs = modbus_read(port, 0, 29)
            check(status["findings"] == [] and regs[23] == 0 and not regs[1] & 0x20,
                  "a job with options.check false has no findings and no alarm")
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")
        print("test_check: %.1f s" % (time.time() - t0))


if __name__ == "__main__":
    main()
