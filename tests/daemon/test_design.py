"""test_design.py: the job document's "design" (the intended part) through the
daemon. The design is an STL built here: a 40 x 40 x 5 mm block with a 20 x 20
mm pocket 1 mm deep. The program cuts that pocket 1.2 mm deep with a 6 mm flat
end mill (a raster and a contour pass whose tool centres stay 3 mm inside the
pocket's walls, so the walls are the design's and only the floor is 0.2 mm too
deep). The job's report (and /report) carries "design" with max_gouge_mm = 0.2
within half a voxel, the gouge in the pocket; a design naming a file on the
server is refused (400 bad_design), an open one (a pocket wall left out) fails
its job saying where its open edges are; options.stop_at stops after a line and
options.tolerance reaches the comparison (the default is half a voxel, 0.05).
Usage: test_design.py FREPMILLD FREPMILL"""
import base64
import json
import os
import struct
import sys
import tempfile

from daemon_util import Daemon, check, curl_json, submit, wait_state

VOXEL = 0.1
STOCK = "box:0,0,-5,40,40,0"
TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6,
                                   "flute_length": 20, "length": 40}]}
DESIGN_FLOOR = -1.0
CUT_FLOOR = -1.2
PROGRAM = """G21 G17 G90
T1 M6
G00 Z5
G00 X13 Y13
G01 Z%.3f F300
G01 X27 F600
G01 Y17
G01 X13
G01 Y21
G01 X27
G01 Y25
G01 X13
G01 Y27
G01 X27
G01 Y13
G01 X13
G01 Y27
G00 Z5
M2
""" % CUT_FLOOR
STOP_LINE = 7  # "G01 Y17": the job ends before "G01 X13"


def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def quad(tris, a, b, c, d, normal):
    """Two triangles of the planar quad a b c d, wound so that their normal is
    the given outward one."""
    n = cross(sub(b, a), sub(c, a))
    if sum(n[i] * normal[i] for i in range(3)) < 0:
        a, b, c, d = d, c, b, a
    tris.append((normal, a, b, c))
    tris.append((normal, a, c, d))


def pocket_block_stl(open_wall=False):
    """Binary STL of [0,40]^2 x [-5,0] minus the pocket [10,30]^2 x [-1,0]:
    closed, every edge shared by two triangles; open_wall leaves out the
    pocket's last wall (its four edges then bound one triangle each)."""
    t = []
    z0, z1, zf = -5.0, 0.0, DESIGN_FLOOR
    quad(t, [0, 0, z0], [40, 0, z0], [40, 40, z0], [0, 40, z0], [0, 0, -1])
    quad(t, [0, 0, z0], [40, 0, z0], [40, 0, z1], [0, 0, z1], [0, -1, 0])
    quad(t, [40, 0, z0], [40, 40, z0], [40, 40, z1], [40, 0, z1], [1, 0, 0])
    quad(t, [40, 40, z0], [0, 40, z0], [0, 40, z1], [40, 40, z1], [0, 1, 0])
    quad(t, [0, 40, z0], [0, 0, z0], [0, 0, z1], [0, 40, z1], [-1, 0, 0])
    # the top: a ring of four trapezoids around the pocket's mouth
    quad(t, [0, 0, z1], [40, 0, z1], [30, 10, z1], [10, 10, z1], [0, 0, 1])
    quad(t, [40, 0, z1], [40, 40, z1], [30, 30, z1], [30, 10, z1], [0, 0, 1])
    quad(t, [40, 40, z1], [0, 40, z1], [10, 30, z1], [30, 30, z1], [0, 0, 1])
    quad(t, [0, 40, z1], [0, 0, z1], [10, 10, z1], [10, 30, z1], [0, 0, 1])
    # the pocket: its floor and walls face into the pocket
    quad(t, [10, 10, zf], [30, 10, zf], [30, 30, zf], [10, 30, zf], [0, 0, 1])
    quad(t, [10, 10, zf], [30, 10, zf], [30, 10, z1], [10, 10, z1], [0, 1, 0])
    quad(t, [30, 10, zf], [30, 30, zf], [30, 30, z1], [30, 10, z1], [-1, 0, 0])
    quad(t, [30, 30, zf], [10, 30, zf], [10, 30, z1], [30, 30, z1], [0, -1, 0])
    if not open_wall:
        quad(t, [10, 30, zf], [10, 10, zf], [10, 10, z1], [10, 30, z1], [1, 0, 0])
    out = bytearray(b"frepmill test design: a block with a pocket".ljust(80, b" "))
    out += struct.pack("<I", len(t))
    for n, a, b, c in t:
        out += struct.pack("<12fH", *n, *a, *b, *c, 0)
    return bytes(out)


def main():
    frepmilld = sys.argv[1]
    design = {"stl_base64": base64.b64encode(pocket_block_stl()).decode()}
    job = {"stock": STOCK, "voxel": VOXEL, "tools": TOOLS, "program": {"gcode": PROGRAM},
           "design": design, "options": {"check": False}}
    with tempfile.TemporaryDirectory(prefix="fm-design-") as tmp:
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1")
        try:
            bad = dict(job, design="/etc/passwd.stl")
            code, body = curl_json("-X", "POST", "-H", "Content-Type: application/json",
                                   "--data-binary", json.dumps(bad), d.url + "/v1/jobs")
            check(code == 400 and body.get("error", {}).get("code") == "bad_design",
                  "a design naming a server file is refused (%d, %s)" % (code, body))

            # an open surface is no part: refused with its open edges, not
            # compared as the band's shell
            leaky = dict(job, design={"stl_base64": base64.b64encode(
                pocket_block_stl(open_wall=True)).decode()})
            job_id = submit(d.url, leaky, tmp)
            status = wait_state(d.url, job_id, ("done", "failed", "cancelled"), 600)
            msg = (status.get("error") or {}).get("message", "")
            # about the box's centre (20, 20, -2.5) the triangles enclose the
            # part, 40 x 40 x 5 - 20 x 20 x 1, and the missing wall's pyramid
            # (20 x 1 mm at 10 mm): it no longer takes 200 / 3 off
            enclosed = "enclose %.1f mm^3" % (40 * 40 * 5 - 20 * 20 * 1 + 20 * 1 * 10 / 3)
            check(status["state"] == "failed"
                  and "is not a closed surface: 4 of its edges bound one triangle only" in msg
                  and enclosed in msg,
                  "an open design fails its job with its open edges and volume (%s: %s)"
                  % (status["state"], msg))

            job_id = submit(d.url, job, tmp)
            status = wait_state(d.url, job_id, ("done", "failed", "cancelled"), 600)
            check(status["state"] == "done", "the job is done (%s)" % status.get("error"))
            code, rep = curl_json(d.url + "/v1/jobs/%s/report" % job_id)
            check(code == 200 and "design" in rep, "the report has \"design\" (%d)" % code)
            dev = rep["design"]
            want = DESIGN_FLOOR - CUT_FLOOR
            check(abs(dev["max_gouge_mm"] - want) <= VOXEL / 2,
                  "max_gouge_mm %.3f = %.1f within half a voxel" % (dev["max_gouge_mm"], want))
            g = dev["gouges"][0]
            x, y, z = g["position"]
            check(10 <= x <= 30 and 10 <= y <= 30 and CUT_FLOOR - VOXEL <= z <= DESIGN_FLOOR + VOXEL,
                  "the deepest gouge is on the pocket's floor (%.2f, %.2f, %.2f)" % (x, y, z))

            stopped = dict(job, options={"check": False, "stop_at": STOP_LINE,
                                         "tolerance": 0.08})
            job_id = submit(d.url, stopped, tmp)
            status = wait_state(d.url, job_id, ("done", "failed", "cancelled"), 600)
            check(status["state"] == "done", "the stopped job is done (%s)" % status.get("error"))
            code, rep = curl_json(d.url + "/v1/jobs/%s/report" % job_id)
            check(code == 200 and rep.get("stopped_at_line") == STOP_LINE,
                  "options.stop_at %d: the report says stopped_at_line %s"
                  % (STOP_LINE, rep.get("stopped_at_line")))
            check(abs(rep["design"]["tolerance_mm"] - 0.08) < 1e-9,
                  "options.tolerance reaches the comparison (%s)" % rep["design"]["tolerance_mm"])
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")


if __name__ == "__main__":
    main()
