"""test_live_mapped.py: live mode from an SHDR adapter with every kind of
mapping: X/Y/Z, the rotary axes A and C of an AC trunnion (live_machine),
the tool, the program line and the spindle speed. The test writes the
stream: each line one instant of the machine, with the data items
Xm|Ym|Zm|Am|Cm|Tn|Ln|Sp.

The table (C, about Z through the origin) is turned to 90 degrees before the
tool plunges at machine X10 Y0 from Z20 to Z-5 and back. A positive joint
turns the table right-handed about +Z, so machine (10, 0) is the workpiece
point turned back by 90 degrees: (0, -10). The block box:-5,-15,-10,5,-5,0
holds that point and not (10, 0) nor (0, 10) (the table not turned, or
turned the wrong way): the hole is pi * 3^2 * 5 mm^3 only if the joints
move the tool. Then, with the tool at Z20, X goes to 310, beyond the
machine file's travel (a travel_limit finding, an error: its line is the
stream's), and back while the table turns to A-20 C45 (well clear of the
block) on line 15.
The live job's status and the agent's current document (validated with
xmllint) show the stream's last line, angles and speed, and the finding as
a FAULT with the stream's line as its native code.
Usage: test_live_mapped.py FREPMILLD MTCONNECT_DATA"""
import json
import math
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "daemon"))
from daemon_util import INSTRUMENTED, ROOT, Daemon, check, curl, skip  # noqa: E402
from test_live_shdr import Replay, live_status  # noqa: E402

NS = {"s": "urn:mtconnect.org:MTConnectStreams:2.7"}
BOX = (-5.0, -15.0, -10.0, 5.0, -5.0, 0.0)
RADIUS = 3.0
DEPTH = 5.0
TOOLS = {"units": "mm", "tools": [{"number": 3, "shape": "flat", "diameter": 2 * RADIUS,
                                   "flute_length": 30, "length": 40, "shank_diameter": 6}]}
# (X, Y, Z, A, C, tool, line, S): the machine's instants.
STREAM = [
    (10, 0, 20, 0, 90, 3, 10, 8000),
    (10, 0, -DEPTH, 0, 90, 3, 11, 8000),
    (10, 0, 20, 0, 90, 3, 12, 8000),
    (310, 0, 20, 0, 90, 3, 13, 8000),
    (10, 0, 20, 0, 45, 3, 14, 8000),
    (10, 0, 20, -20, 45, 3, 15, 9500),
]
MAP = "X=Xm,Y=Ym,Z=Zm,A=Am,C=Cm,tool=Tn,line=Ln,S=Sp"


def shdr_lines():
    out = [b"* shdrVersion: 2\n"]
    for k, (x, y, z, a, c, tool, line, rpm) in enumerate(STREAM):
        stamp = "2026-12-04T10:00:%02d.000000Z" % k
        out.append(("%s|Xm|%g|Ym|%g|Zm|%g|Am|%g|Cm|%g|Tn|%d|Ln|%d|Sp|%g\n" %
                    (stamp, x, y, z, a, c, tool, line, rpm)).encode())
    return b"".join(out)


class Adapter:
    """Sends the stream to the first connection, answers pings, keeps it open."""

    def __init__(self, data):
        self.data = data
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(4)
        self.port = self.sock.getsockname()[1]
        self.connections = 0
        self.pings = 0
        threading.Thread(target=self.serve, daemon=True).start()

    def serve(self):
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.connections += 1
            if self.connections == 1:
                conn.sendall(self.data)
            threading.Thread(target=self.answer, args=(conn,), daemon=True).start()

    answer = Replay.answer  # the pings answered with "* PONG 1000"


def main():
    frepmilld, data = sys.argv[1], sys.argv[2]
    schema = os.path.join(data, "schemas", "MTConnectStreams_2.7_1.0.xsd")
    if not os.path.exists(schema):
        skip("the MTConnect schemas are missing (%s; cmake -DFM_MTCONNECT_DATA=...)" % data)
    # The closed form's premise: the plunge's workpiece point is in the
    # block with the tool's radius around it, the unturned and mis-turned
    # points are not.
    x, y = STREAM[1][0], STREAM[1][1]
    c = math.radians(STREAM[1][4])
    hole = (math.cos(c) * x + math.sin(c) * y, -math.sin(c) * x + math.cos(c) * y)

    def inside(p):
        return BOX[0] + RADIUS <= p[0] <= BOX[3] - RADIUS and BOX[1] + RADIUS <= p[1] <= BOX[4] - RADIUS

    check(inside(hole) and not inside((x, y)) and not inside((-hole[0], -hole[1])),
          "the hole at the workpiece's (%.3f, %.3f) lies in the block, the unturned and mis-turned ones "
          "do not" % hole)
    expect = math.pi * RADIUS ** 2 * DEPTH
    last = STREAM[-1]
    machine = os.path.join(ROOT, "tests", "check", "corpus_machine", "trunnion.json")
    with open(machine) as f:
        x_travel = json.load(f)["limits"]["x"]
    beyond = [p[6] for p in STREAM if not x_travel[0] <= p[0] <= x_travel[1]]
    adapter = Adapter(shdr_lines())
    with tempfile.TemporaryDirectory(prefix="fm-live-mapped-") as tmp:
        tools = os.path.join(tmp, "tools.json")
        with open(tools, "w") as f:
            json.dump(TOOLS, f)
        d = Daemon(frepmilld, os.path.join(tmp, "state"),
                   "--live-source", "shdr://127.0.0.1:%d" % adapter.port, "--live-map", MAP,
                   "--live-machine", machine, "--mtconnect-machine", machine,
                   "--live-stock", "box:%g,%g,%g,%g,%g,%g" % BOX, "--live-tools", tools,
                   "--live-voxel", "0.1", "--live-feed", "2000")
        try:
            deadline = time.time() + (600 if INSTRUMENTED else 120)
            status, steady = None, 0
            while time.time() < deadline:
                status = live_status(d.url)
                if status and status.get("line") == last[6] and status.get("motions_done") == len(STREAM) - 1:
                    steady += 1
                    if steady >= 3:
                        break
                time.sleep(0.3)
            check(status is not None and status.get("line") == last[6],
                  "the live job's line is the stream's last, %d (%s)" % (last[6], status and status.get("line")))
            removed = status["removed_volume_mm3"]
            check(abs(removed - expect) <= 0.01 * expect,
                  "removed %.3f mm^3 within 1%% of pi r^2 h = %.3f: the hole at the turned table's point" %
                  (removed, expect))
            check(status.get("rotary") == {"A": float(last[3]), "C": float(last[4])},
                  "the live job's joints are the stream's last (%s)" % status.get("rotary"))
            check(status.get("tool") == last[5], "the live job's tool is the stream's (%s)" % status.get("tool"))
            travel = sorted({f["line"] for f in status["findings"] if f["kind"] == "travel_limit"})
            check(beyond and travel == beyond,
                  "the travel_limit finding is on the stream's line %s beyond X %s (%s)" % (beyond, x_travel, travel))

            code, body = curl(d.url + "/mtconnect/current")
            check(code == 200, "current answers 200")
            path = os.path.join(tmp, "current.xml")
            with open(path, "wb") as f:
                f.write(body)
            out = subprocess.run(["xmllint", "--noout", "--schema", schema, path], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, timeout=120)
            check(out.returncode == 0, "current validates (%s)" % out.stderr.decode(errors="replace")[:500])
            cur = ET.fromstring(body)

            def value(tag, item):
                return cur.find(".//s:%s[@dataItemId='%s']" % (tag, item), NS).text

            got = {"line": value("LineNumber", "line"), "A": value("Angle", "Apos"), "C": value("Angle", "Cpos"),
                   "S": value("RotaryVelocity", "Srpm"), "tool": value("ToolNumber", "tool"),
                   "X": value("Position", "Xpos"), "Z": value("Position", "Zpos")}
            want = {"line": "%d" % last[6], "A": "%.4f" % last[3], "C": "%.4f" % last[4], "S": "%.1f" % last[7],
                    "tool": "%d" % last[5], "X": "%.4f" % last[0], "Z": "%.4f" % last[2]}
            check(got == want, "the agent shows the stream's last line, angles, speed, tool and position (%s)" % got)
            faults = sorted({int(f.get("nativeCode")) for f in cur.findall(".//s:Fault", NS)
                             if f.get("type") == "MOTION_PROGRAM"})
            check(faults == beyond, "the agent's MOTION_PROGRAM faults are at the stream's line %s (%s)" %
                  (beyond, faults))
            check("skipped" not in d.read_log(), "no line of the stream was skipped")
        finally:
            d.stop()


if __name__ == "__main__":
    main()
