"""test_live_check.py: live moves are collision-checked like a program's.
The tool's holder (20 mm across) sits 12 mm above the tip of a 6 mm cutter
with 10 mm of flute; a live plunge to Z-15 into the block (top at Z0) takes
the holder 3 mm into the stock: the live job reports a holder_contact error
finding (status, `finding` event) and the Modbus registers show it (23: the
finding count, 24-25: its line, bit 5 of register 1: the collision alarm).
A shallow move before it (flutes only) finds nothing.
Usage: test_live_check.py FREPMILLD FREPMILL"""
import json
import os
import sys
import tempfile
import time

import urllib.request

from daemon_util import Daemon, check, curl_json, modbus_port
from test_live import client, need_node_client

STOCK = "box:0,0,-20,60,60,0"
TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6,
                                   "flute_length": 10, "length": 12, "shank_diameter": 6,
                                   "holder": [{"diameter": 20, "length": 30}],
                                   "center_cutting": True}]}
SHALLOW = [(10, 30, 5), (10, 30, -2), (20, 30, -2), (20, 30, 5)]
# Move 5 (the first position only places the tool): the plunge to Z-15,
# whose holder face goes 15 - 12 = 3 mm below the top.
PLUNGE = [(40, 30, 5), (40, 30, -15)]
PLUNGE_MOVE = len(SHALLOW) - 1 + 2


def events(url, job_id, until, timeout=5):
    """The job's server-sent events from the first, until until(type, data)
    holds (or the timeout): [(type, data)]."""
    out, kind = [], None
    try:
        with urllib.request.urlopen(url + "/v1/jobs/%s/events" % job_id, timeout=timeout) as r:
            for raw in r:
                line = raw.decode().rstrip("\n")
                if line.startswith("event: "):
                    kind = line[7:]
                elif line.startswith("data: ") and kind:
                    out.append((kind, line[6:]))
                    if until(kind, line[6:]):
                        break
    except OSError:
        pass
    return out


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    need_node_client()
    with tempfile.TemporaryDirectory(prefix="fm-live-check-") as tmp:
        t0 = time.time()
        tools = os.path.join(tmp, "tools.json")
        with open(tools, "w") as f:
            json.dump(TOOLS, f)
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1",
                   "--modbus-listen", "127.0.0.1:0", "--modbus-live", "yes",
                   "--live-stock", STOCK, "--live-tools", tools, "--live-voxel", "0.25")
        try:
            port = modbus_port(d)
            client(port, "on", *["%g,%g,%g,1" % m for m in SHALLOW])
            code, listing = curl_json(d.url + "/v1/jobs")
            job_id = [j for j in listing["jobs"] if j.get("name") == "live"][0]["id"]
            deadline = time.time() + 60
            while time.time() < deadline:
                code, status = curl_json(d.url + "/v1/jobs/" + job_id)
                if status["motions_done"] >= len(SHALLOW) - 1:
                    break
                time.sleep(0.1)
            regs = list(map(int, client(port, "read")[0].split()[1:]))
            check(status["findings"] == [] and regs[23] == 0 and not regs[1] & 0x20,
                  "the shallow moves (flutes only) give no finding and no alarm %s" %
                  status["findings"])

            client(port, *["%g,%g,%g,1" % m for m in PLUNGE])
            # lib/check is slow on this plunge today (about 50 s on the
            # loaded machine; issue 14 makes it fast): a generous wait.
            deadline = time.time() + 300
            while time.time() < deadline:
                code, status = curl_json(d.url + "/v1/jobs/" + job_id)
                if status["motions_done"] >= PLUNGE_MOVE and status["findings"]:
                    break
                time.sleep(0.1)
            holder = [f for f in status["findings"] if f["part"] == "holder"]
            check(holder and holder[0]["severity"] == "error" and holder[0]["line"] == PLUNGE_MOVE,
                  "the plunge (move %d) gives a holder error finding: %s" %
                  (PLUNGE_MOVE, status["findings"]))
            regs = list(map(int, client(port, "read")[0].split()[1:]))
            check(regs[23] == len(status["findings"]) and regs[23] >= 1,
                  "register 23 counts the findings (%d)" % regs[23])
            check((regs[24] << 16 | regs[25]) == status["findings"][0]["line"],
                  "registers 24-25 hold the first finding's move (%d)" % status["findings"][0]["line"])
            check(regs[1] & 0x20, "the collision alarm (bit 5 of register 1) is set")
            def holder_event(kind, data):
                return kind == "finding" and json.loads(data)["part"] == "holder"
            check(any(holder_event(*e) for e in events(d.url, job_id, holder_event)),
                  "the finding came as a server-sent event too")
            client(port, "off")
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")
        print("test_live_check: %.1f s" % (time.time() - t0))


if __name__ == "__main__":
    main()
