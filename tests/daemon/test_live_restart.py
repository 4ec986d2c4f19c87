"""test_live_restart.py: a live job survives SIGKILL. Live mode cuts a slot
from controller positions (Modbus, modbus-serial from npm); the daemon is
killed with SIGKILL while the live job runs (the last positions written
just before the kill, perhaps not yet cut); a restarted daemon resumes the
same live job from its snapshot and journal, and the controller's next
positions cut on into that stock. In the end the job has removed what
`frepmill simulate` removes for all the moves written as G-code.
The journal is read back as a daemon from before the line and the joints
were journaled wrote it: its lines "X Y Z TOOL LINE A B C" are cut to
"X Y Z TOOL" while the daemon is down.
Usage: test_live_restart.py FREPMILLD FREPMILL"""
import os
import signal
import sys
import tempfile
import time

from daemon_util import Daemon, check, curl_json, modbus_port
from test_live import client, need_node_client, simulate_moves

STOCK = "box:0,0,-10,60,60,0"
VOXEL = 0.25
TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6,
                                   "flute_length": 20, "length": 40}]}
# Before the kill: down 2 mm, 30 mm along X, and the last two positions
# written just before SIGKILL. After the restart: on along Y, and up.
BEFORE = [(10, 20, 5), (10, 20, -2), (40, 20, -2), (40, 30, -2), (45, 30, -2)]
AFTER = [(45, 45, -2), (20, 45, -2), (20, 45, 5)]


def live_job(d):
    code, listing = curl_json(d.url + "/v1/jobs")
    live = [j for j in listing["jobs"] if j.get("name") == "live"]
    return live[-1] if code == 200 and live else None


def wait_moves(d, job_id, moves, timeout=60):
    deadline = time.time() + timeout
    status = None
    while time.time() < deadline:
        code, status = curl_json(d.url + "/v1/jobs/" + job_id)
        if code == 200 and status["motions_done"] >= moves:
            return status
        time.sleep(0.1)
    raise RuntimeError("job %s did not reach %d moves: %s" % (job_id, moves, status))


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    need_node_client()
    with tempfile.TemporaryDirectory(prefix="fm-live-restart-") as tmp:
        t0 = time.time()
        tools, cli_removed = simulate_moves(frepmill, tmp, TOOLS, BEFORE + AFTER, STOCK, VOXEL)

        state = os.path.join(tmp, "state")
        args = ["--workers", "1", "--modbus-listen", "127.0.0.1:0", "--modbus-live", "yes",
                "--live-stock", STOCK, "--live-tools", tools, "--live-voxel", str(VOXEL),
                "--snapshot-interval-s", "0.2", "--publish-interval-s", "0.1"]
        d = Daemon(frepmilld, state, *args)
        try:
            port = modbus_port(d)
            client(port, "on", *["%g,%g,%g,1" % m for m in BEFORE[:3]])
            job = live_job(d)
            check(job is not None, "live mode on made a live job")
            job_id = job["id"]
            before = wait_moves(d, job_id, 2)
            time.sleep(0.5)  # a snapshot at move 2 or later
            client(port, *["%g,%g,%g,1" % m for m in BEFORE[3:]])
            d.stop(sig=signal.SIGKILL)
            check(d.proc.returncode == -signal.SIGKILL, "the daemon was killed (SIGKILL) while "
                  "the live job ran (%d moves cut, %.1f mm3)" %
                  (before["motions_done"], before["removed_volume_mm3"]))
        finally:
            if d.proc.poll() is None:
                d.stop(sig=signal.SIGKILL)

        journals = [os.path.join(top, "live.journal") for top, _, files in os.walk(state)
                    if "live.journal" in files]
        check(len(journals) == 1, "the live job has its journal (%s)" % journals)
        with open(journals[0]) as f:
            lines = f.read().splitlines()
        written = [tuple(float(v) for v in line.split()[:3]) for line in lines]
        check(written == [tuple(map(float, m)) for m in BEFORE] and
              all(len(line.split()) == 8 and line.split()[4:] == ["0", "nan", "nan", "nan"] for line in lines),
              "the journal holds the positions written, each with tool, no line and no joints (%s)" % lines)
        with open(journals[0], "w") as f:
            f.write("".join(" ".join(line.split()[:4]) + "\n" for line in lines))

        d = Daemon(frepmilld, state, *args)
        try:
            port = modbus_port(d)
            job = live_job(d)
            check(job is not None and job["id"] == job_id,
                  "after the restart the live job %s is there again" % job_id)
            status = wait_moves(d, job_id, len(BEFORE) - 1)
            check(status["state"] == "running",
                  "it resumed: %d moves (every position written before the kill, from the "
                  "snapshot and the journal), state %s" % (status["motions_done"],
                                                          status["state"]))
            regs = client(port, "read")
            words = list(map(int, regs[0].split()[1:]))
            check(words[1] & 0x40, "register 1 shows live mode on (bit 6)")
            client(port, "on", *["%g,%g,%g,1" % m for m in AFTER])
            status = wait_moves(d, job_id, len(BEFORE) + len(AFTER) - 1)
            removed = status["removed_volume_mm3"]
            tol = 0.002 * cli_removed
            check(abs(removed - cli_removed) <= tol,
                  "the live job removed %.2f mm3 in all = frepmill simulate's %.2f for the same "
                  "moves (within %.2f): it continued with its stock" % (removed, cli_removed, tol))
            check(status["position"] == list(map(float, AFTER[-1])),
                  "the status shows the last position")
            client(port, "off")
            deadline = time.time() + 30
            while time.time() < deadline:
                code, status = curl_json(d.url + "/v1/jobs/" + job_id)
                if status["state"] == "done":
                    break
                time.sleep(0.1)
            check(status["state"] == "done", "live mode off ends the live job")
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")
        print("test_live_restart: %.1f s" % (time.time() - t0))


if __name__ == "__main__":
    main()
