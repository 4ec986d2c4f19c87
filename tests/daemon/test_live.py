"""test_live.py: Modbus live mode of frepmilld. A Node client from the npm
registry (modbus-serial, installed by deploy/install-deps.sh test) switches live mode on and writes a short sequence
of tool positions down into the stock, along it and back up; the daemon
cuts a live job's stock. The removed volume it reports (HTTP status and
Modbus registers 17-18) must match `frepmill simulate` of the same moves
written as G-code, within voxel tolerance, and the closed form of the slot.
Usage: test_live.py FREPMILLD FREPMILL"""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

from daemon_util import ROOT, Daemon, check, curl_json, modbus_port, skip

MODBUS_DIR = os.path.join(ROOT, "tests", "modbus")
STOCK = "box:0,0,-10,60,60,0"
VOXEL = 0.25
TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6,
                                   "flute_length": 20, "length": 40}]}
# Above the stock, down 2 mm, along X for 40 mm, then along Y for 10 mm, up.
MOVES = [(10, 30, 5), (10, 30, -2), (50, 30, -2), (50, 40, -2), (50, 40, 5)]
DEPTH, RADIUS = 2.0, 3.0


def need_node_client():
    """Skip (or, with CI=true, fail) without node or the Node Modbus client,
    which deploy/install-deps.sh test installs: the test never downloads."""
    if not shutil.which("node"):
        skip("node is not installed (Debian package nodejs)")
    if not os.path.exists(os.path.join(MODBUS_DIR, "node_modules", "modbus-serial", "package.json")):
        skip("tests/modbus/node_modules/modbus-serial is missing (deploy/install-deps.sh test installs it)")


def client(port, *steps):
    env = dict(os.environ, NODE_PATH=os.path.join(MODBUS_DIR, "node_modules"))
    out = subprocess.run(["node", os.path.join(os.path.dirname(__file__), "live_client.js"),
                          str(port), *steps], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         env=env, timeout=60)
    if out.returncode != 0:
        raise RuntimeError("live_client: %s" % out.stderr.decode())
    return out.stdout.decode().splitlines()


def gcode_of(moves):
    lines = ["G21 G90 G94", "T1 M6", "G0 X%g Y%g Z%g" % moves[0]]
    lines += ["G1 X%g Y%g Z%g F1000" % m for m in moves[1:]]
    return "\n".join(lines + ["M2", ""])


def simulate_moves(frepmill, tmp, tool_table, moves, stock, voxel):
    """The moves as G-code through `frepmill simulate`: (the tool table's
    path in tmp, for the daemon too; the removed volume)."""
    tools = os.path.join(tmp, "tools.json")
    with open(tools, "w") as f:
        json.dump(tool_table, f)
    program = os.path.join(tmp, "moves.ngc")
    with open(program, "w") as f:
        f.write(gcode_of(moves))
    report = os.path.join(tmp, "report.json")
    subprocess.run([frepmill, "simulate", program, "--stock", stock, "--tools", tools,
                    "--voxel", str(voxel), "--report", report], check=True, timeout=300,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(report) as f:
        return tools, json.load(f)["removed_volume_mm3"]


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    need_node_client()
    with tempfile.TemporaryDirectory(prefix="fm-live-") as tmp:
        t0 = time.time()
        tools, cli_removed = simulate_moves(frepmill, tmp, TOOLS, MOVES, STOCK, VOXEL)
        # The slot by hand: two stadiums of width 2R (40 and 10 mm between
        # their cap centres), each 2R L + pi R^2, meeting at a right-angled
        # corner where they overlap in the corner disc plus the R x R square
        # inside the corner less its quarter disc; depth DEPTH.
        r2 = RADIUS ** 2
        closed = DEPTH * (2 * RADIUS * (40 + 10) + 2 * math.pi * r2 -
                          (math.pi * r2 + r2 - math.pi * r2 / 4))

        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1",
                   "--modbus-listen", "127.0.0.1:0", "--modbus-live", "yes",
                   "--live-stock", STOCK, "--live-tools", tools, "--live-voxel", str(VOXEL),
                   "--publish-interval-s", "0.1")
        try:
            port = modbus_port(d)
            out = client(port, "on", *["%g,%g,%g,1" % m for m in MOVES])
            check(out[0] == "live on" and len(out) == 1 + len(MOVES),
                  "the client switched live mode on and wrote %d positions" % len(MOVES))
            code, listing = curl_json(d.url + "/v1/jobs")
            live = [j for j in listing["jobs"] if j.get("name") == "live"]
            check(code == 200 and len(live) == 1, "a live job is listed")
            job_id = live[0]["id"]
            deadline = time.time() + 60
            while time.time() < deadline:
                code, status = curl_json(d.url + "/v1/jobs/" + job_id)
                if status["motions_done"] == len(MOVES) - 1:
                    break
                time.sleep(0.1)
            check(status["motions_done"] == len(MOVES) - 1 and status["state"] == "running",
                  "the live job cut %d moves and keeps running" % (len(MOVES) - 1))
            removed = status["removed_volume_mm3"]
            tol = 0.01 * closed
            check(abs(removed - cli_removed) <= tol,
                  "live removed %.2f mm3 = frepmill simulate's %.2f within %.1f" %
                  (removed, cli_removed, tol))
            check(abs(removed - closed) <= tol,
                  "live removed %.2f mm3 = closed form %.2f within %.1f" % (removed, closed, tol))
            check(status["position"] == list(map(float, MOVES[-1])) and status["tool"] == 1,
                  "the status shows the last position and the tool")
            regs = client(port, "read")
            words = list(map(int, regs[0].split()[1:]))
            floats = list(map(float, regs[1].split()[1:]))
            check(words[1] & 0x40 and words[1] & 0x02, "status bits: live mode and running")
            check(abs(floats[4] - removed) <= 1e-3 * removed + 0.01,
                  "registers 17-18 show the removed volume (%.2f)" % floats[4])
            check(all(abs(floats[i] - MOVES[-1][i]) < 1e-4 for i in range(3)),
                  "registers 9-14 show the last position")
            code, chunks = curl_json(d.url + "/v1/jobs/%s/chunks" % job_id)
            check(code == 200 and chunks["chunks"], "the live job's mesh chunks are published")

            out = client(port, "off")
            deadline = time.time() + 30
            while time.time() < deadline:
                code, status = curl_json(d.url + "/v1/jobs/" + job_id)
                if status["state"] == "done":
                    break
                time.sleep(0.1)
            check(status["state"] == "done", "live mode off ends the live job")
            # With live mode off a position only stages registers: nothing
            # is cut. The position lies in the stock beside the slot (it
            # would cut if it reached a job), and the check lasts 2 s, twenty
            # publish intervals, far longer than the live job took to cut
            # and publish each of its moves above: a delayed cut would show.
            regs = client(port, "30,10,-2,1", "read")
            words = list(map(int, regs[1].split()[1:]))
            floats = list(map(float, regs[2].split()[1:]))
            check(all(abs(floats[i] - MOVES[-1][i]) < 1e-4 for i in range(3)),
                  "registers 9-14 still show the last live position, not the staged one")
            cut_later = []
            deadline = time.time() + 2.0
            while time.time() < deadline:
                code, after = curl_json(d.url + "/v1/jobs/" + job_id)
                code, listing = curl_json(d.url + "/v1/jobs")
                if (after["motions_done"] != len(MOVES) - 1 or after["removed_volume_mm3"] != removed
                        or len(listing["jobs"]) != 1):
                    cut_later.append((after["motions_done"], after["removed_volume_mm3"],
                                      len(listing["jobs"])))
                time.sleep(0.1)
            check(not cut_later and after["state"] == "done",
                  "a position in the stock written with live mode off cuts nothing within 2 s, "
                  "and starts no job (%s)" % cut_later[:3])
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(not words[1] & 0x40, "live bit clear after live mode off")
        check(rc == 0, "the daemon stopped cleanly")
        print("test_live: %.1f s" % (time.time() - t0))


if __name__ == "__main__":
    main()
